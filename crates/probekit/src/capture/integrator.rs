//! The integrator: one receiver direction traced as a path with next-event
//! estimation and multiple importance sampling, light sampling at the
//! receiver, and the delta lights it sees (the estimator of [`super`]).

use super::validity::HitStats;
use super::Baker;
use crate::sampling::{
    mix64, power_heuristic, sample_cosine_hemisphere, sample_uniform_sphere, sobol02_point,
    sobol02_scramble, Frame, SampleRng, INV_FOUR_PI,
};
use crate::trace::{offset_ray_origin, Ray, SHADOW_EPSILON};
use glam::{DVec3, Vec2, Vec3};
use std::f32::consts::PI;

/// Most consecutive transparent surfaces a path crosses before it is cut
/// (a guard against pathological stacks of glass; each crossing is unbiased).
const MAX_CROSSINGS: u32 = 64;

/// The receiver's sampling of directions.
#[derive(Clone, Copy)]
pub(super) enum Receiver {
    /// Uniform over the sphere (probe capture).
    Sphere,
    /// Cosine-weighted about a normal (irradiance).
    Cosine(Frame),
}

impl Receiver {
    pub(super) fn sample(&self, u: Vec2) -> Vec3 {
        match self {
            Receiver::Sphere => sample_uniform_sphere(u),
            Receiver::Cosine(f) => f.to_world(sample_cosine_hemisphere(u)).normalize(),
        }
    }
    pub(super) fn pdf(&self, d: Vec3) -> f32 {
        match self {
            Receiver::Sphere => INV_FOUR_PI,
            Receiver::Cosine(f) => f.z.dot(d).max(0.0) / PI,
        }
    }
}

/// Per-path parameters.
#[derive(Clone, Copy)]
pub(super) struct PathParams {
    pub(super) bounces: u32,
    pub(super) rr_depth: u32,
}

/// f64 accumulators: `slots × coefficients`, slot = `2·group + (indirect as usize)`.
pub(super) struct Accum {
    pub(super) ncoef: usize,
    pub(super) data: Vec<DVec3>,
}

impl Accum {
    pub(super) fn new(slots: usize, ncoef: usize) -> Self {
        Self {
            ncoef,
            data: vec![DVec3::ZERO; slots * ncoef],
        }
    }
    pub(super) fn add(&mut self, slot: usize, basis: &[f32], v: Vec3) {
        let v = v.as_dvec3();
        let row = &mut self.data[slot * self.ncoef..(slot + 1) * self.ncoef];
        for (c, y) in row.iter_mut().zip(basis) {
            *c += v * *y as f64;
        }
    }
    pub(super) fn merge(&mut self, other: &Accum) {
        for (a, b) in self.data.iter_mut().zip(&other.data) {
            *a += *b;
        }
    }
}

pub(super) fn slot(group: u16, direct: bool) -> usize {
    2 * group as usize + usize::from(!direct)
}

fn mis(a: f32, b: f32) -> f32 {
    power_heuristic(1.0, a, 1.0, b)
}

impl Baker<'_> {
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
    /// With `stratified = Some((i, key))` the sphere/disk lights and the
    /// environment map draw their 2D sample as [`Baker::nee_receiver`] does.
    fn nee_surface(
        &self,
        o: Vec3,
        n: Vec3,
        f: Vec3,
        rng: &mut SampleRng,
        stratified: Option<(u32, u64)>,
        sink: &mut impl FnMut(Vec3, u16),
    ) {
        let e = &self.emitters;
        let u2 = |k: u64, rng: &mut SampleRng| match stratified {
            Some((i, key)) => sobol02_point(i, sobol02_scramble(key, k)),
            None => rng.next_2d(),
        };
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
            if let Some(ls) = s.sample(o, u2(k as u64, rng)) {
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
            if let Some(ls) = e.env.sample(u2(u64::MAX, rng)) {
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
    /// `sink(direction, value, group)` with `value = L·T·w/pdf`. With
    /// `stratified = Some((i, key))` the sphere/disk lights and the
    /// environment map draw their 2D sample from point `i` of a scrambled
    /// (0,2)-sequence ([`sobol02_point`], one scramble per light from
    /// `key`) instead of `rng`: over the receiver's samples `0..n` the
    /// light samples are stratified, which cuts the noise of the direct
    /// light from small lamps (one sample of the lamp per receiver
    /// direction) far below independent draws; each sample stays uniform,
    /// so the estimate stays unbiased.
    pub(super) fn nee_receiver(
        &self,
        x: Vec3,
        recv: &Receiver,
        rng: &mut SampleRng,
        stratified: Option<(u32, u64)>,
        sink: &mut impl FnMut(Vec3, Vec3, u16),
    ) {
        let e = &self.emitters;
        let u2 = |k: u64, rng: &mut SampleRng| match stratified {
            Some((i, key)) => sobol02_point(i, sobol02_scramble(key, k)),
            None => rng.next_2d(),
        };
        for (k, s) in e.shapes.iter().enumerate() {
            if let Some(ls) = s.sample(x, u2(k as u64, rng)) {
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
            if let Some(ls) = e.env.sample(u2(u64::MAX, rng)) {
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
    pub(super) fn delta_at(&self, x: Vec3) -> Vec<(Vec3, Vec3, u16)> {
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
    /// first geometric hit into `stats` when given. With `stratified =
    /// Some((i, key))` the first surface vertex draws its light samples and
    /// its next direction from point `i` of scrambled (0,2)-sequences
    /// (scrambles from `key`, apart from the receiver's): the light that
    /// reaches the probe after one bounce, most of the indirect light, is
    /// then stratified over the receiver's samples too.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn trace_path(
        &self,
        x: Vec3,
        dir: Vec3,
        p0: f32,
        params: PathParams,
        rng: &mut SampleRng,
        mut stats: Option<&mut HitStats>,
        stratified: Option<(u32, u64)>,
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
            // The first vertex's samples, stratified when asked.
            let first = stratified
                .filter(|_| depth == 0)
                .map(|(i, key)| (i, mix64(!key)));
            self.nee_surface(o, n, f, rng, first, &mut |v, g| sink(v, g, false));
            depth += 1;
            if depth > params.rr_depth {
                let q = beta.max_element().min(0.95);
                if q.is_nan() || q <= 0.0 || rng.next_f32() >= q {
                    return;
                }
                beta /= q;
            }
            let u = match first {
                Some((i, key)) => sobol02_point(i, sobol02_scramble(key, u64::MAX - 1)),
                None => rng.next_2d(),
            };
            let local = sample_cosine_hemisphere(u);
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
}
