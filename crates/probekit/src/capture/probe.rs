//! The path tracer: incoming radiance at a point, projected into SH
//! ([`Baker::capture`]), and ground-truth irradiance ([`Baker::reference_irradiance`]).
//!
//! ## Estimator
//! For a receiver at `x` (a probe: the whole sphere; a reference point: the
//! hemisphere about its normal) we estimate `∫ L(x, ω) K(ω) dω` with the
//! kernel `K = Y_lm` (SH projection) or `K = max(0, n·ω)` (irradiance).
//! Three kinds of samples, combined without double counting:
//! - **Delta lights** (point, spot, directional) are added once, exactly:
//!   the radiance of a delta light is `E δ(ω − ω_l)`, so its SH is
//!   `E·T·Y_lm(ω_l)` with `E = I/d²` (× the glTF spot ramp) or lux, and `T`
//!   the shadow ray's transmittance.
//! - **Receiver directions** `ω_i` (uniform sphere for probes, cosine
//!   hemisphere for the reference; R2 low-discrepancy with a per-receiver
//!   Cranley–Patterson rotation) start a path. What the path returns is
//!   `L(x, ω_i)/p(ω_i)`; emitters it hits are weighted by the power heuristic
//!   against light sampling (Veach & Guibas 1995).
//! - **Light samples** at `x` (sphere and disk lights, emissive triangles, an
//!   environment map) with the complementary MIS weight.
//!
//! At every surface vertex (Lambertian, albedo `ρ`) the path does next-event
//! estimation to every light (delta lights exactly, area lights and the
//! environment map with MIS against the cosine BSDF sample), then continues
//! by cosine sampling (throughput × ρ). A *bounce* is one scattering event:
//! with `bounces = B` the last vertex that scatters is the B-th, so a furnace
//! of emission `Le` and albedo `a` gives `Le·Σ_{k=0..B} a^k`. Russian
//! roulette (survival = max throughput component, ≤ 0.95, unbiased) starts
//! after [`CaptureSettings::russian_roulette_depth`] scattering events.
//! A surface of opacity `α < 1` is crossed straight with probability `1 − α`
//! (path rays) and attenuates shadow rays by `1 − α` (the tracer's
//! transmittance), so in expectation both pass `1 − α` of the light.
//! Emissive triangles emit on both sides (as [`Scene::emission`] says);
//! disk lights on the side their `direction` points to.
//!
//! **Direct** light is what reaches `x` from an emitter with no scattering
//! in between (crossing glass is not scattering); **indirect** is the rest
//! (Sukys 2014, §3.1.2 "Light decoupling"). Every contribution is also
//! attributed to the light group of the emitter it came from.
//!
//! ## Determinism
//! Sample `i` of receiver `k` draws its random numbers from
//! `SampleRng::new(seed, k, i)` and its direction from R2 point `i`; samples
//! are summed in f64 in chunks of [`CHUNK`] in a fixed order, so results are
//! bit-identical for any thread count and any sharding.

use super::emitters::Emitters;
use super::validity::{HitStats, Validity, ValiditySettings};
use super::BakeError;
use crate::env::EnvMap;
use crate::sampling::{
    power_heuristic, r2_point, sample_cosine_hemisphere, sample_uniform_sphere, Frame, SampleRng,
    INV_FOUR_PI,
};
use crate::scene::Scene;
use crate::trace::{offset_ray_origin, Hit, Ray, Tracer, SHADOW_EPSILON};
use glam::{DVec3, Vec2, Vec3};
use probekit_sh::{eval_basis, num_coeffs, ShRgb, MAX_COEFFS, MAX_ORDER};
use rayon::prelude::*;
use std::f32::consts::PI;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Samples per parallel work item; sums inside a chunk and across chunks run
/// in a fixed order, so the split never changes the result.
pub const CHUNK: u32 = 256;

/// Most consecutive transparent surfaces a path crosses before it is cut
/// (a guard against pathological stacks of glass; each crossing is unbiased).
const MAX_CROSSINGS: u32 = 64;

/// Stream index (per receiver) reserved for the R2 rotation of the capture directions.
const STREAM_ROTATION: u64 = u64::MAX;
/// Salt mixed into the seed for reference-irradiance streams, so a reference
/// point and a probe with the same index draw independent numbers.
const REFERENCE_SALT: u64 = 0x5245_4645_5245_4e43;

/// How to capture one probe.
#[derive(Clone, Debug, PartialEq)]
pub struct CaptureSettings {
    /// Receiver directions per probe (default 4096).
    pub samples: u32,
    /// Scattering events per path (default 3); 0 captures emitters only.
    pub bounces: u32,
    /// SH bands of the result, 1..=8 (default 3, i.e. L2).
    pub order: usize,
    /// Random seed (default 1).
    pub seed: u64,
    /// Scattering events before Russian roulette starts (default 3).
    pub russian_roulette_depth: u32,
    /// Also return direct and indirect light separately.
    pub split_direct: bool,
    /// Also return one SH per light group.
    pub groups: bool,
    /// Light groups ([`Baker::group_names`]) whose *direct* light the
    /// capture leaves out of [`CaptureResult::sh`]: what reaches the probe
    /// from their emitters without scattering. Their light scattered by
    /// surfaces stays in. For small lights that a runtime evaluates
    /// analytically (their `1/d²` fall-off is what interpolating probes
    /// misses most: BENCHMARKS.md, "Analytic near lights"), so that the
    /// probes hold only the rest. `direct`, `indirect` and the per-group SH
    /// still report all light. Empty by default; every name must be a group
    /// of the scene.
    pub exclude_direct: Vec<String>,
    /// Probe validity and virtual offset.
    pub validity: ValiditySettings,
}

impl Default for CaptureSettings {
    fn default() -> Self {
        Self {
            samples: 4096,
            bounces: 3,
            order: 3,
            seed: 1,
            russian_roulette_depth: 3,
            split_direct: false,
            groups: false,
            exclude_direct: Vec::new(),
            validity: ValiditySettings::default(),
        }
    }
}

impl CaptureSettings {
    /// Defaults overridden by a scene file's `[bake]` table.
    pub fn from_scene(scene: &Scene) -> Self {
        let mut s = Self::default();
        if let Some(n) = scene.bake.samples {
            s.samples = n;
        }
        if let Some(b) = scene.bake.bounces {
            s.bounces = b;
        }
        if let Some(seed) = scene.bake.seed {
            s.seed = seed;
        }
        s
    }

    /// Checks the bounds: `samples ≥ 1`, `order` in 1..=8, finite validity settings.
    pub fn validate(&self) -> Result<(), BakeError> {
        if self.samples == 0 {
            return Err(BakeError::BadSettings("samples must be at least 1".into()));
        }
        if !(1..=MAX_ORDER).contains(&self.order) {
            return Err(BakeError::BadSettings(format!(
                "SH order {} outside 1..={MAX_ORDER}",
                self.order
            )));
        }
        self.validity.validate()
    }
}

/// What [`Baker::capture`] returns for one probe. All SH are radiance SH.
#[derive(Clone, Debug, PartialEq)]
pub struct CaptureResult {
    /// Where the probe was captured: the requested point plus `validity.offset`.
    pub position: Vec3,
    /// Incoming radiance, all light.
    pub sh: ShRgb,
    /// Direct light only (emitters seen without scattering), if requested.
    pub direct: Option<ShRgb>,
    /// Indirect light only (all light less `direct`), if requested.
    pub indirect: Option<ShRgb>,
    /// Per light group `(name, radiance SH)`, sorted by name, if requested.
    pub groups: Vec<(String, ShRgb)>,
    /// Per light group indirect light only, same names and order as
    /// `groups`, if both `groups` and `split_direct` were requested (what
    /// `bake --groups --indirect-only` stores: it sums to `indirect`).
    pub groups_indirect: Vec<(String, ShRgb)>,
    /// Validity measures.
    pub validity: Validity,
}

/// How [`Baker::reference_irradiance`] decides it is done.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceSettings {
    /// Stop once the standard error of the luminance is below this fraction
    /// of the estimate (default 0.01).
    pub relative_precision: f32,
    /// At least this many samples (default 1024).
    pub min_samples: u32,
    /// At most this many samples (default 262 144).
    pub max_samples: u32,
    /// Scattering events per path (default 3).
    pub bounces: u32,
    /// Scattering events before Russian roulette (default 3).
    pub russian_roulette_depth: u32,
    /// Random seed (default 1).
    pub seed: u64,
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        Self {
            relative_precision: 0.01,
            min_samples: 1024,
            max_samples: 1 << 18,
            bounces: 3,
            russian_roulette_depth: 3,
            seed: 1,
        }
    }
}

/// Ground-truth irradiance at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceResult {
    /// `E(n) = ∫ L(ω) max(0, n·ω) dω` (not divided by π), linear RGB.
    pub irradiance: Vec3,
    /// Standard error of `irradiance` per channel (from batch means).
    pub std_error: Vec3,
    /// Samples used.
    pub samples: u32,
}

/// The receiver's sampling of directions.
#[derive(Clone, Copy)]
enum Receiver {
    /// Uniform over the sphere (probe capture).
    Sphere,
    /// Cosine-weighted about a normal (irradiance).
    Cosine(Frame),
}

impl Receiver {
    fn sample(&self, u: Vec2) -> Vec3 {
        match self {
            Receiver::Sphere => sample_uniform_sphere(u),
            Receiver::Cosine(f) => f.to_world(sample_cosine_hemisphere(u)).normalize(),
        }
    }
    fn pdf(&self, d: Vec3) -> f32 {
        match self {
            Receiver::Sphere => INV_FOUR_PI,
            Receiver::Cosine(f) => f.z.dot(d).max(0.0) / PI,
        }
    }
}

/// Path-tracing context for one scene: its tracer and prepared lights.
pub struct Baker<'s> {
    scene: &'s Scene,
    tracer: Tracer<'s>,
    emitters: Emitters,
}

/// Per-path parameters.
#[derive(Clone, Copy)]
struct PathParams {
    bounces: u32,
    rr_depth: u32,
}

/// f64 accumulators: `slots × coefficients`, slot = `2·group + (indirect as usize)`.
struct Accum {
    ncoef: usize,
    data: Vec<DVec3>,
}

impl Accum {
    fn new(slots: usize, ncoef: usize) -> Self {
        Self {
            ncoef,
            data: vec![DVec3::ZERO; slots * ncoef],
        }
    }
    fn add(&mut self, slot: usize, basis: &[f32], v: Vec3) {
        let v = v.as_dvec3();
        let row = &mut self.data[slot * self.ncoef..(slot + 1) * self.ncoef];
        for (c, y) in row.iter_mut().zip(basis) {
            *c += v * *y as f64;
        }
    }
    fn merge(&mut self, other: &Accum) {
        for (a, b) in self.data.iter_mut().zip(&other.data) {
            *a += *b;
        }
    }
}

fn slot(group: u16, direct: bool) -> usize {
    2 * group as usize + usize::from(!direct)
}

fn mis(a: f32, b: f32) -> f32 {
    power_heuristic(1.0, a, 1.0, b)
}

impl<'s> Baker<'s> {
    /// Builds the BVH, prepares the lights and loads the environment map.
    pub fn new(scene: &'s Scene) -> Result<Self, BakeError> {
        Self::with_tracer(scene, Tracer::new(scene))
    }

    /// Uses an already built tracer over `scene`.
    pub fn with_tracer(scene: &'s Scene, tracer: Tracer<'s>) -> Result<Self, BakeError> {
        Ok(Self {
            scene,
            tracer,
            emitters: Emitters::new(scene)?,
        })
    }

    /// Replaces the scene's environment by `map` × `intensity`, rotated by
    /// `rotation_y_degrees` about +Y (counter-clockwise seen from above), for
    /// callers that already hold the map in memory.
    pub fn set_environment_map(&mut self, map: &EnvMap, intensity: f32, rotation_y_degrees: f32) {
        self.emitters.env = Emitters::map_environment(map, intensity, rotation_y_degrees);
    }

    /// The scene.
    pub fn scene(&self) -> &'s Scene {
        self.scene
    }

    /// The tracer.
    pub fn tracer(&self) -> &Tracer<'s> {
        &self.tracer
    }

    /// Names of the light groups that hold at least one light, sorted: each
    /// light's `group` (or `"default"`), `"emissive"` for emissive triangles,
    /// `"environment"` for a non-black environment.
    pub fn group_names(&self) -> Vec<String> {
        self.present_groups()
            .into_iter()
            .map(|g| self.emitters.groups[g].clone())
            .collect()
    }

    /// Every name of `s.exclude_direct` is a light group of the scene.
    fn check_excluded(&self, s: &CaptureSettings) -> Result<(), BakeError> {
        if s.exclude_direct.is_empty() {
            return Ok(());
        }
        let names = self.group_names();
        match s.exclude_direct.iter().find(|n| !names.contains(n)) {
            None => Ok(()),
            Some(n) => Err(BakeError::BadSettings(format!(
                "exclude_direct: no light group `{n}` in the scene (groups: {})",
                names.join(", ")
            ))),
        }
    }

    fn present_groups(&self) -> Vec<usize> {
        let e = &self.emitters;
        let mut present = vec![false; e.groups.len()];
        for d in &e.delta {
            present[d.group() as usize] = true;
        }
        for s in &e.shapes {
            present[s.group as usize] = true;
        }
        if e.has_emissive_triangles() {
            present[e.emissive_group as usize] = true;
        }
        if !e.env.is_black() {
            present[e.env_group as usize] = true;
        }
        (0..present.len()).filter(|&g| present[g]).collect()
    }

    /// Transmittance from `from` along unit `wi` over `dist` (∞ allowed),
    /// including blocking by sphere/disk lights other than `except`.
    fn shadow(&self, from: Vec3, wi: Vec3, dist: f32, except: Option<usize>) -> Vec3 {
        for (k, s) in self.emitters.shapes.iter().enumerate() {
            if Some(k) == except {
                continue;
            }
            if let Some(t) = s.intersect(from, wi, 0.0) {
                if t < dist * (1.0 - SHADOW_EPSILON) {
                    return Vec3::ZERO;
                }
            }
        }
        let ray = Ray::new(from, wi);
        if dist.is_finite() {
            self.tracer
                .transmittance_ray(&ray, dist * (1.0 - SHADOW_EPSILON))
        } else {
            self.tracer.transmittance_ray(&ray, f32::INFINITY)
        }
    }

    /// Next-event estimation at a Lambertian vertex: `o` the offset point,
    /// `n` the facing normal, `f = throughput · ρ/π`. Calls `sink(value, group)`.
    fn nee_surface(
        &self,
        o: Vec3,
        n: Vec3,
        f: Vec3,
        rng: &mut SampleRng,
        sink: &mut impl FnMut(Vec3, u16),
    ) {
        let e = &self.emitters;
        for d in &e.delta {
            if let Some((wi, irr, dist)) = d.incident(o) {
                let cos = n.dot(wi);
                if cos > 0.0 {
                    let t = self.shadow(o, wi, dist, None);
                    if t != Vec3::ZERO {
                        sink(f * irr * t * cos, d.group());
                    }
                }
            }
        }
        for (k, s) in e.shapes.iter().enumerate() {
            if let Some(ls) = s.sample(o, rng.next_2d()) {
                let cos = n.dot(ls.wi);
                if cos > 0.0 && ls.pdf > 0.0 {
                    let t = self.shadow(o, ls.wi, ls.dist, Some(k));
                    if t != Vec3::ZERO {
                        let w = mis(ls.pdf, cos / PI);
                        sink(f * ls.radiance * t * (cos * w / ls.pdf), s.group);
                    }
                }
            }
        }
        if e.has_emissive_triangles() {
            let pick = rng.next_f32();
            if let Some((ls, _)) = e.sample_triangle(self.scene, o, pick, rng.next_2d()) {
                let cos = n.dot(ls.wi);
                if cos > 0.0 && ls.pdf > 0.0 && ls.radiance != Vec3::ZERO {
                    let t = self.shadow(o, ls.wi, ls.dist, None);
                    if t != Vec3::ZERO {
                        let w = mis(ls.pdf, cos / PI);
                        sink(f * ls.radiance * t * (cos * w / ls.pdf), e.emissive_group);
                    }
                }
            }
        }
        if e.env.is_sampled() {
            if let Some(ls) = e.env.sample(rng.next_2d()) {
                let cos = n.dot(ls.wi);
                if cos > 0.0 {
                    let t = self.shadow(o, ls.wi, f32::INFINITY, None);
                    if t != Vec3::ZERO {
                        let w = mis(ls.pdf, cos / PI);
                        sink(f * ls.radiance * t * (cos * w / ls.pdf), e.env_group);
                    }
                }
            }
        }
    }

    /// Light sampling at the receiver point `x` (no surface there). Calls
    /// `sink(direction, value, group)` with `value = L·T·w/pdf`.
    fn nee_receiver(
        &self,
        x: Vec3,
        recv: &Receiver,
        rng: &mut SampleRng,
        sink: &mut impl FnMut(Vec3, Vec3, u16),
    ) {
        let e = &self.emitters;
        for (k, s) in e.shapes.iter().enumerate() {
            if let Some(ls) = s.sample(x, rng.next_2d()) {
                let p0 = recv.pdf(ls.wi);
                if p0 > 0.0 && ls.pdf > 0.0 {
                    let t = self.shadow(x, ls.wi, ls.dist, Some(k));
                    if t != Vec3::ZERO {
                        let w = mis(ls.pdf, p0);
                        sink(ls.wi, ls.radiance * t * (w / ls.pdf), s.group);
                    }
                }
            }
        }
        if e.has_emissive_triangles() {
            let pick = rng.next_f32();
            if let Some((ls, _)) = e.sample_triangle(self.scene, x, pick, rng.next_2d()) {
                let p0 = recv.pdf(ls.wi);
                if p0 > 0.0 && ls.pdf > 0.0 && ls.radiance != Vec3::ZERO {
                    let t = self.shadow(x, ls.wi, ls.dist, None);
                    if t != Vec3::ZERO {
                        let w = mis(ls.pdf, p0);
                        sink(ls.wi, ls.radiance * t * (w / ls.pdf), e.emissive_group);
                    }
                }
            }
        }
        if e.env.is_sampled() {
            if let Some(ls) = e.env.sample(rng.next_2d()) {
                let p0 = recv.pdf(ls.wi);
                if p0 > 0.0 {
                    let t = self.shadow(x, ls.wi, f32::INFINITY, None);
                    if t != Vec3::ZERO {
                        let w = mis(ls.pdf, p0);
                        sink(ls.wi, ls.radiance * t * (w / ls.pdf), e.env_group);
                    }
                }
            }
        }
    }

    /// Delta lights seen from `x`: `(direction, irradiance·T, group)`.
    fn delta_at(&self, x: Vec3) -> Vec<(Vec3, Vec3, u16)> {
        let mut out = Vec::new();
        for d in &self.emitters.delta {
            if let Some((wi, irr, dist)) = d.incident(x) {
                let t = self.shadow(x, wi, dist, None);
                if t != Vec3::ZERO {
                    out.push((wi, irr * t, d.group()));
                }
            }
        }
        out
    }

    /// Follows one receiver direction: calls `sink(value, group, direct)` with
    /// value = (radiance contribution)/p0, already MIS-weighted. Records the
    /// first geometric hit into `stats` when given.
    #[allow(clippy::too_many_arguments)]
    fn trace_path(
        &self,
        x: Vec3,
        dir: Vec3,
        p0: f32,
        params: PathParams,
        rng: &mut SampleRng,
        mut stats: Option<&mut HitStats>,
        sink: &mut impl FnMut(Vec3, u16, bool),
    ) {
        let e = &self.emitters;
        let scene = self.scene;
        let mut ray = Ray::new(x, dir);
        let mut beta = Vec3::splat(1.0 / p0);
        let mut depth = 0u32;
        let mut prev_pdf = p0;
        let mut prev_point = x;
        let mut crossings = 0u32;
        loop {
            let hit = self.tracer.closest_hit(&ray, f32::INFINITY);
            if let Some(st) = stats.take() {
                self.record_first_hit(st, ray.direction, hit.as_ref());
            }
            let t_tri = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
            let mut shape_hit: Option<(usize, f32)> = None;
            for (k, s) in e.shapes.iter().enumerate() {
                if let Some(t) = s.intersect(ray.origin, ray.direction, 0.0) {
                    if t < t_tri && shape_hit.map_or(true, |(_, tb)| t < tb) {
                        shape_hit = Some((k, t));
                    }
                }
            }
            if let Some((k, t)) = shape_hit {
                let s = &e.shapes[k];
                let le = s.radiance_towards(ray.direction);
                if le != Vec3::ZERO {
                    let hp = ray.at(t);
                    let light_pdf = s.pdf(prev_point, ray.direction, (hp - prev_point).length());
                    let w = mis(prev_pdf, light_pdf);
                    sink(beta * le * w, s.group, depth == 0);
                }
                return;
            }
            let Some(h) = hit else {
                let le = e.env.radiance(ray.direction);
                if le != Vec3::ZERO {
                    let w = if e.env.is_sampled() {
                        mis(prev_pdf, e.env.pdf(ray.direction))
                    } else {
                        1.0
                    };
                    sink(beta * le * w, e.env_group, depth == 0);
                }
                return;
            };
            if h.opacity < 1.0 && rng.next_f32() >= h.opacity {
                crossings += 1;
                if crossings > MAX_CROSSINGS {
                    return;
                }
                ray = h.continue_ray(ray.direction);
                continue;
            }
            let le = scene.emission(h.material, h.uv);
            if le != Vec3::ZERO {
                let light_pdf = e.triangle_pdf(
                    scene,
                    h.triangle,
                    ray.direction,
                    (h.point - prev_point).length(),
                );
                let w = mis(prev_pdf, light_pdf);
                sink(beta * le * w, e.emissive_group, depth == 0);
            }
            if depth >= params.bounces {
                return;
            }
            let albedo = scene.albedo(h.material, h.uv);
            if albedo.max_element() <= 0.0 {
                return;
            }
            let n = h.facing_normal();
            let o = offset_ray_origin(h.point, n);
            let f = beta * albedo / PI;
            self.nee_surface(o, n, f, rng, &mut |v, g| sink(v, g, false));
            depth += 1;
            if depth > params.rr_depth {
                let q = beta.max_element().min(0.95);
                if q.is_nan() || q <= 0.0 || rng.next_f32() >= q {
                    return;
                }
                beta /= q;
            }
            let local = sample_cosine_hemisphere(rng.next_2d());
            if local.z <= 0.0 {
                return;
            }
            let wi = Frame::from_z(n).to_world(local).normalize();
            beta *= albedo;
            prev_pdf = local.z / PI;
            prev_point = o;
            ray = Ray::new(o, wi);
            crossings = 0;
        }
    }

    /// Validity bookkeeping for the first surface a receiver ray meets.
    fn record_first_hit(&self, st: &mut HitStats, dir: Vec3, hit: Option<&Hit>) {
        st.rays += 1;
        let Some(h) = hit else { return };
        let back = if h.winding_consistent {
            !h.front_face
        } else {
            self.parity_inside(h, dir)
        };
        st.add_hit(h.t, dir, back);
    }

    /// Winding-free inside test for a ray whose first hit is on an
    /// inconsistently wound triangle: counts every surface crossing out to
    /// infinity; an odd count means the ray started inside a closed surface.
    /// Gives up (says "outside") after [`super::validity::MAX_PARITY_CROSSINGS`].
    fn parity_inside(&self, first: &Hit, dir: Vec3) -> bool {
        let mut count = 1u32;
        let mut h = *first;
        for _ in 0..super::validity::MAX_PARITY_CROSSINGS {
            match self.tracer.closest_hit(&h.continue_ray(dir), f32::INFINITY) {
                Some(next) => {
                    count += 1;
                    h = next;
                }
                None => return count % 2 == 1,
            }
        }
        false
    }

    /// First-hit statistics of `rays` R2 directions from `x` (validity pre-pass).
    pub(crate) fn hit_stats(&self, x: Vec3, probe_index: u64, seed: u64, rays: u32) -> HitStats {
        let rot = SampleRng::new(seed, probe_index, STREAM_ROTATION - 1).next_2d();
        let mut st = HitStats::default();
        for i in 0..rays {
            let d = sample_uniform_sphere(r2_point(i as u64, rot));
            let hit = self.tracer.closest_hit(&Ray::new(x, d), f32::INFINITY);
            self.record_first_hit(&mut st, d, hit.as_ref());
        }
        st
    }

    /// One chunk of probe samples `[start, end)`.
    fn capture_chunk(
        &self,
        x: Vec3,
        probe_index: u64,
        s: &CaptureSettings,
        rot: Vec2,
        range: (u32, u32),
        slots: usize,
    ) -> (Accum, HitStats) {
        let ncoef = num_coeffs(s.order);
        let mut acc = Accum::new(slots, ncoef);
        let mut st = HitStats::default();
        let params = PathParams {
            bounces: s.bounces,
            rr_depth: s.russian_roulette_depth,
        };
        let recv = Receiver::Sphere;
        let mut basis = [0.0f32; MAX_COEFFS];
        let mut pending: Vec<(Vec3, u16, bool)> = Vec::with_capacity(8);
        for i in range.0..range.1 {
            let mut rng = SampleRng::new(s.seed, probe_index, i as u64);
            let dir = recv.sample(r2_point(i as u64, rot));
            pending.clear();
            self.trace_path(
                x,
                dir,
                INV_FOUR_PI,
                params,
                &mut rng,
                Some(&mut st),
                &mut |v, g, d| pending.push((v, g, d)),
            );
            if !pending.is_empty() {
                eval_basis(s.order, dir, &mut basis);
                for &(v, g, d) in &pending {
                    acc.add(slot(g, d), &basis[..ncoef], v);
                }
            }
            self.nee_receiver(x, &recv, &mut rng, &mut |wi, v, g| {
                eval_basis(s.order, wi, &mut basis);
                acc.add(slot(g, true), &basis[..ncoef], v);
            });
        }
        (acc, st)
    }

    /// Captures the radiance SH at `x` (no virtual offset), returning the
    /// per-slot sums (already divided by the sample count, delta lights
    /// added) and, with two chunks or more, the standard error of each
    /// coefficient (all slots summed) from the chunk means.
    fn capture_at(
        &self,
        x: Vec3,
        probe_index: u64,
        s: &CaptureSettings,
    ) -> (Accum, HitStats, Option<Vec<DVec3>>) {
        let slots = 2 * self.emitters.groups.len();
        let rot = SampleRng::new(s.seed, probe_index, STREAM_ROTATION).next_2d();
        let n = s.samples;
        let chunks: Vec<(u32, u32)> = (0..n.div_ceil(CHUNK))
            .map(|c| (c * CHUNK, ((c + 1) * CHUNK).min(n)))
            .collect();
        let parts: Vec<(Accum, HitStats)> = chunks
            .par_iter()
            .map(|&r| self.capture_chunk(x, probe_index, s, rot, r, slots))
            .collect();
        let ncoef = num_coeffs(s.order);
        let mut acc = Accum::new(slots, ncoef);
        let mut st = HitStats::default();
        for (a, h) in &parts {
            acc.merge(a);
            st.merge(h);
        }
        let se = (parts.len() >= 2).then(|| chunk_std_error(&parts, &chunks, ncoef));
        let inv_n = 1.0 / n as f64;
        for c in &mut acc.data {
            *c *= inv_n;
        }
        let mut basis = [0.0f32; MAX_COEFFS];
        for (wi, e, g) in self.delta_at(x) {
            eval_basis(s.order, wi, &mut basis);
            acc.add(slot(g, true), &basis[..ncoef], e);
        }
        (acc, st, se)
    }

    /// Captures probe number `probe_index` (its global index in the bake,
    /// which keys its random numbers) at `point`: incoming radiance SH, and
    /// optionally direct/indirect and per-group SH, with validity. An invalid
    /// probe (back-face fraction above the threshold) is pushed out by the
    /// virtual offset when enabled (see [`super::validity`]).
    pub fn capture(
        &self,
        point: Vec3,
        probe_index: u64,
        s: &CaptureSettings,
    ) -> Result<CaptureResult, BakeError> {
        self.capture_with_error(point, probe_index, s).map(|r| r.0)
    }

    /// [`Baker::capture`] plus the Monte Carlo standard error of each
    /// coefficient of `sh` (RGB, same layout), estimated by batch means
    /// over the [`CHUNK`]-sample chunks the capture sums anyway (standard
    /// error of the mean of the chunk means, chunks weighted equally). With
    /// the R2 sequence each chunk is itself stratified, so this tends to
    /// overstate the error of the whole capture (a conservative noise
    /// scale). `None` below two chunks (`samples ≤ CHUNK`). Same results
    /// for any thread count.
    pub fn capture_with_error(
        &self,
        point: Vec3,
        probe_index: u64,
        s: &CaptureSettings,
    ) -> Result<(CaptureResult, Option<Vec<Vec3>>), BakeError> {
        s.validate()?;
        self.check_excluded(s)?;
        let v = &s.validity;
        let (pos, pushed, in_light) = self.offset_position(point, probe_index, s)?;
        let (acc, st, se) = self.capture_at(pos, probe_index, s);
        let mut validity = Validity::from_stats(&st, v, pos - point, pushed);
        if in_light || self.scene.sphere_light_at(pos, 0.0).is_some() {
            validity.valid = false;
        }
        let se = se.map(|e| e.into_iter().map(|v| v.as_vec3()).collect());
        Ok((self.assemble(acc, s, pos, validity), se))
    }

    /// Where [`Baker::capture`] captures probe `probe_index` (its global
    /// index in the bake) requested at `point` (metres): `point` itself, or
    /// where the virtual offset moves it out of geometry or out of a sphere
    /// light (see [`super::validity`]). The same position, bit for bit, as
    /// [`CaptureResult::position`], for a small part of a capture's cost (the
    /// validity pre-pass only): a caller checks the captured set (e.g. that
    /// it can be tetrahedralized) before spending the capture on it.
    pub fn capture_position(
        &self,
        point: Vec3,
        probe_index: u64,
        s: &CaptureSettings,
    ) -> Result<Vec3, BakeError> {
        s.validate()?;
        Ok(self.offset_position(point, probe_index, s)?.0)
    }

    /// The virtual offset of [`Baker::capture_with_error`] for a finite
    /// `point` (else [`BakeError::NonFinitePosition`]): the capture
    /// position, whether the probe was moved, and whether it stays inside a
    /// sphere light (offset off).
    fn offset_position(
        &self,
        point: Vec3,
        probe_index: u64,
        s: &CaptureSettings,
    ) -> Result<(Vec3, bool, bool), BakeError> {
        if !point.is_finite() {
            return Err(BakeError::NonFinitePosition {
                index: probe_index as usize,
                position: point,
            });
        }
        let v = &s.validity;
        let mut pos = point;
        let mut pushed = false;
        if v.virtual_offset {
            for _ in 0..v.max_offset_steps {
                let st = self.hit_stats(pos, probe_index, s.seed, v.pre_pass_rays);
                if st.backface_fraction() <= v.backface_threshold {
                    break;
                }
                match st.nearest_back {
                    Some((t, d)) => {
                        pos += d * (t + v.offset_margin);
                        pushed = true;
                    }
                    None => break,
                }
            }
        }
        // A probe inside a sphere light sees the emitter over its whole
        // sphere (irradiance π·L_e, thousands of times the room's), which
        // interpolation would smear over every neighbouring tetrahedron:
        // push it radially out past the surface, or flag it invalid.
        let mut in_light = false;
        for _ in 0..4 {
            let Some(l) = self.scene.sphere_light_at(pos, v.offset_margin) else {
                break;
            };
            if !v.virtual_offset {
                in_light = true;
                break;
            }
            let d = (pos - l.position).try_normalize().unwrap_or(Vec3::Y);
            pos = l.position + d * (l.radius + v.offset_margin.max(0.5 * l.radius));
            pushed = true;
        }
        Ok((pos, pushed, in_light))
    }

    fn assemble(
        &self,
        acc: Accum,
        s: &CaptureSettings,
        pos: Vec3,
        validity: Validity,
    ) -> CaptureResult {
        let ncoef = acc.ncoef;
        let ngroups = self.emitters.groups.len();
        let sum_slots = |pred: &dyn Fn(usize) -> bool| -> ShRgb {
            let mut c = vec![DVec3::ZERO; ncoef];
            for sl in (0..2 * ngroups).filter(|&sl| pred(sl)) {
                for (a, b) in c.iter_mut().zip(&acc.data[sl * ncoef..(sl + 1) * ncoef]) {
                    *a += *b;
                }
            }
            ShRgb::from_coeffs(c.into_iter().map(|v| v.as_vec3()).collect())
                .expect("order² coefficients")
        };
        // Slot `2g` holds group g's direct light, `2g + 1` its scattered light.
        let excluded: Vec<usize> = (0..ngroups)
            .filter(|&g| s.exclude_direct.contains(&self.emitters.groups[g]))
            .collect();
        let sh = sum_slots(&|sl| !(sl % 2 == 0 && excluded.contains(&(sl / 2))));
        let (direct, indirect) = if s.split_direct {
            (
                Some(sum_slots(&|sl| sl % 2 == 0)),
                Some(sum_slots(&|sl| sl % 2 == 1)),
            )
        } else {
            (None, None)
        };
        let per_group = |indirect_only: bool| -> Vec<(String, ShRgb)> {
            self.present_groups()
                .into_iter()
                .map(|g| {
                    (
                        self.emitters.groups[g].clone(),
                        sum_slots(&|sl| sl / 2 == g && (!indirect_only || sl % 2 == 1)),
                    )
                })
                .collect()
        };
        let groups = if s.groups {
            per_group(false)
        } else {
            Vec::new()
        };
        let groups_indirect = if s.groups && s.split_direct {
            per_group(true)
        } else {
            Vec::new()
        };
        CaptureResult {
            position: pos,
            sh,
            direct,
            indirect,
            groups,
            groups_indirect,
            validity,
        }
    }

    /// Captures many probes in parallel (rayon, over probes and over sample
    /// chunks). `first_index` is the global index of `points[0]` (non-zero for
    /// a shard). `progress(done, total)` is called after each probe.
    /// Bit-identical for any thread count.
    pub fn capture_many(
        &self,
        points: &[Vec3],
        first_index: usize,
        s: &CaptureSettings,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<Vec<CaptureResult>, BakeError> {
        s.validate()?;
        self.check_excluded(s)?;
        if let Some(i) = points.iter().position(|p| !p.is_finite()) {
            return Err(BakeError::NonFinitePosition {
                index: first_index + i,
                position: points[i],
            });
        }
        let done = AtomicUsize::new(0);
        let total = points.len();
        points
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                let r = self.capture(*p, (first_index + i) as u64, s);
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
                r
            })
            .collect()
    }

    /// [`Baker::capture_position`] of every point, in parallel: where
    /// [`Baker::capture_many`] with the same arguments captures them (the
    /// bake's [`super::BakeOutput::captured_positions`]). Bit-identical for
    /// any thread count.
    pub fn capture_positions(
        &self,
        points: &[Vec3],
        first_index: usize,
        s: &CaptureSettings,
    ) -> Result<Vec<Vec3>, BakeError> {
        points
            .par_iter()
            .enumerate()
            .map(|(i, p)| self.capture_position(*p, (first_index + i) as u64, s))
            .collect()
    }

    /// Ground-truth irradiance `E(n) = ∫ L(ω) max(0, n·ω) dω` at `point` with
    /// unit `normal` (not divided by π), by cosine-weighted path tracing with
    /// the same light transport as [`Baker::capture`]. Samples run in batches
    /// of [`CHUNK`], eight batches at a time in parallel, until the standard
    /// error of the luminance (from batch means) is below
    /// `relative_precision` of the estimate, or `max_samples`. `index` keys
    /// the random numbers (use the point's row number).
    pub fn reference_irradiance(
        &self,
        point: Vec3,
        normal: Vec3,
        index: u64,
        s: &ReferenceSettings,
    ) -> Result<ReferenceResult, BakeError> {
        if !(point.is_finite() && normal.is_finite()) || normal.length_squared() < 1e-12 {
            return Err(BakeError::NonFinitePosition {
                index: index as usize,
                position: point,
            });
        }
        if s.max_samples == 0 || s.relative_precision.is_nan() || s.relative_precision < 0.0 {
            return Err(BakeError::BadSettings(
                "reference needs max_samples ≥ 1 and a relative precision ≥ 0".into(),
            ));
        }
        let n = normal.normalize();
        let frame = Frame::from_z(n);
        let recv = Receiver::Cosine(frame);
        let seed = s.seed ^ REFERENCE_SALT;
        let rot = SampleRng::new(seed, index, STREAM_ROTATION).next_2d();
        let params = PathParams {
            bounces: s.bounces,
            rr_depth: s.russian_roulette_depth,
        };
        let batch = |b: u32| -> DVec3 {
            let (lo, hi) = (b * CHUNK, ((b + 1) * CHUNK).min(s.max_samples));
            let mut sum = DVec3::ZERO;
            for i in lo..hi {
                let mut rng = SampleRng::new(seed, index, i as u64);
                let dir = recv.sample(r2_point(i as u64, rot));
                let p0 = recv.pdf(dir);
                if p0 > 0.0 {
                    let cos = n.dot(dir).max(0.0);
                    self.trace_path(point, dir, p0, params, &mut rng, None, &mut |v, _, _| {
                        sum += (v * cos).as_dvec3();
                    });
                }
                self.nee_receiver(point, &recv, &mut rng, &mut |wi, v, _| {
                    sum += (v * n.dot(wi).max(0.0)).as_dvec3();
                });
            }
            sum
        };
        let nbatches = s.max_samples.div_ceil(CHUNK);
        let mut sums: Vec<DVec3> = Vec::new();
        const ROUND: u32 = 8;
        let mut samples;
        loop {
            let b0 = sums.len() as u32;
            let b1 = (b0 + ROUND).min(nbatches);
            let round: Vec<DVec3> = (b0..b1).into_par_iter().map(batch).collect();
            sums.extend(round);
            samples = (sums.len() as u32 * CHUNK).min(s.max_samples);
            if sums.len() as u32 >= nbatches {
                break;
            }
            if samples >= s.min_samples && sums.len() >= 2 {
                let (mean, se) = batch_mean_se(&sums);
                let lum = |v: DVec3| v.dot(probekit_sh::LUMINANCE.as_dvec3());
                if lum(se) <= s.relative_precision as f64 * lum(mean).abs() {
                    break;
                }
            }
        }
        // Batches have CHUNK samples except possibly the last: weight by size.
        let total: DVec3 = sums.iter().copied().sum();
        let mean = total / samples as f64;
        let (_, se) = batch_mean_se(&sums);
        let mut e = mean;
        for (wi, irr, _) in self.delta_at(point) {
            e += (irr * n.dot(wi).max(0.0)).as_dvec3();
        }
        Ok(ReferenceResult {
            irradiance: e.as_vec3(),
            std_error: se.as_vec3(),
            samples,
        })
    }
}

/// Standard error of each coefficient (slots summed) of the mean of the
/// per-chunk means: `sqrt(Σ (m_c − m̄)² / (k (k − 1)))` per RGB channel.
fn chunk_std_error(parts: &[(Accum, HitStats)], chunks: &[(u32, u32)], ncoef: usize) -> Vec<DVec3> {
    let k = parts.len() as f64;
    let means: Vec<Vec<DVec3>> = parts
        .iter()
        .zip(chunks)
        .map(|((a, _), (lo, hi))| {
            let inv = 1.0 / (hi - lo).max(1) as f64;
            (0..ncoef)
                .map(|c| a.data.chunks_exact(ncoef).map(|row| row[c]).sum::<DVec3>() * inv)
                .collect()
        })
        .collect();
    (0..ncoef)
        .map(|c| {
            let m = means.iter().map(|v| v[c]).sum::<DVec3>() / k;
            let var = means.iter().map(|v| (v[c] - m) * (v[c] - m)).sum::<DVec3>() / (k - 1.0);
            (var / k).map(f64::sqrt)
        })
        .collect()
}

/// Mean per sample and its standard error, from per-batch sums of [`CHUNK`]
/// samples each (the standard error of the mean of batch means).
fn batch_mean_se(sums: &[DVec3]) -> (DVec3, DVec3) {
    let k = sums.len() as f64;
    let means: Vec<DVec3> = sums.iter().map(|s| *s / CHUNK as f64).collect();
    let m = means.iter().copied().sum::<DVec3>() / k;
    if sums.len() < 2 {
        return (m, DVec3::splat(f64::INFINITY));
    }
    let var = means.iter().map(|x| (*x - m) * (*x - m)).sum::<DVec3>() / (k - 1.0);
    (m, (var / k).map(f64::sqrt))
}
