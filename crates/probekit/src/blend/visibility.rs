//! Baking per-probe distance moments (the `VISM` section) for
//! visibility-aware blending of a probe cloud at run time
//! ([`probekit_runtime::cloud::visibility`]; DDGI, Majercik et al.,
//! "Dynamic Diffuse Global Illumination with Ray-Traced Irradiance Fields",
//! JCGT 8(2), 2019).
//!
//! For each probe and each texel of its `S × S` octahedral map (orientation
//! in [`probekit_runtime::cloud::visibility`]: +Y at the centre), a
//! `k × k` grid of jittered points of the texel's **map area** is decoded
//! to directions and traced from the probe ([`Tracer::closest_hit`]); the
//! texel stores the mean distance `μ` and mean squared distance `μ2` to the
//! first surface, each ray's distance clamped to `max_distance` (a ray that
//! escapes counts as `max_distance`). So `μ` is the average over the texel's
//! map area (not its solid angle; the octahedral map's area distortion is
//! below a factor 2 and the run-time filter is bilinear in map space too).
//! Any surface counts, whatever its opacity.
//!
//! Deterministic: the jitter of ray `r` of texel `t` of a probe at position
//! `x` comes from a counter-based generator keyed by `(seed, hash(x),
//! t·k² + r)`, and probes are baked in parallel into their own slots, so the
//! bytes depend neither on the thread count nor on how the probes are split
//! into shards.

use crate::sampling::{hash3, SampleRng};
use crate::trace::{Ray, Tracer};
use glam::{Vec2, Vec3};
use probekit_runtime::cloud::visibility::{oct_decode, oct_texel_center};
use probekit_runtime::format::{DistanceMoments, MAX_VISIBILITY_RESOLUTION};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use thiserror::Error;

/// Default texels per side of each probe's map (`S`).
pub const DEFAULT_RESOLUTION: u32 = 8;
/// Default rays per texel side (`k`; `k²` rays per texel).
pub const DEFAULT_RAYS_PER_SIDE: u32 = 4;
/// Random stream of the jitter (distinct from capture's streams).
const STREAM: u64 = 0x7669_736d; // "vism"

/// How to bake distance moments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VisibilitySettings {
    /// Texels per side of each probe's octahedral map, `1..=64`.
    pub resolution: u32,
    /// Jittered rays per texel side (`k² ` rays per texel), at least 1.
    pub rays_per_side: u32,
    /// Distance clamp in metres (finite, > 0); e.g. the bake box diagonal.
    pub max_distance: f32,
    /// Seed of the ray jitter (the bake seed).
    pub seed: u64,
}

impl VisibilitySettings {
    /// Default resolution and rays, `max_distance` and `seed` as given.
    pub fn new(max_distance: f32, seed: u64) -> Self {
        Self {
            resolution: DEFAULT_RESOLUTION,
            rays_per_side: DEFAULT_RAYS_PER_SIDE,
            max_distance,
            seed,
        }
    }

    /// The settings as a JSON object for the bake metadata. `max_distance`
    /// is written as the shortest decimal of the `f32` (so the metadata
    /// reads back and re-serializes to the same text, as `merge` needs).
    pub fn to_json(&self) -> serde_json::Value {
        let max: f64 = self.max_distance.to_string().parse().unwrap_or(0.0);
        serde_json::json!({
            "resolution": self.resolution,
            "rays_per_texel": self.rays_per_side * self.rays_per_side,
            "max_distance": max,
        })
    }
}

/// Why distance moments cannot be baked.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum VisibilityError {
    /// Resolution outside `1..=64`.
    #[error("visibility map resolution {0} is outside 1..=64")]
    Resolution(u32),
    /// Zero rays per texel.
    #[error("visibility rays per texel side must be at least 1")]
    NoRays,
    /// Max distance not finite and positive.
    #[error("visibility max distance {0} is not a positive finite number")]
    MaxDistance(f32),
    /// A probe position is NaN or infinite.
    #[error("probe {0} has a non-finite position")]
    NonFinitePosition(usize),
}

impl VisibilitySettings {
    fn check(&self) -> Result<(), VisibilityError> {
        if self.resolution == 0 || self.resolution > MAX_VISIBILITY_RESOLUTION {
            return Err(VisibilityError::Resolution(self.resolution));
        }
        if self.rays_per_side == 0 {
            return Err(VisibilityError::NoRays);
        }
        if !(self.max_distance.is_finite() && self.max_distance > 0.0) {
            return Err(VisibilityError::MaxDistance(self.max_distance));
        }
        Ok(())
    }
}

/// The `[μ, μ2]` (metres, m²) of every texel of the map of a probe at
/// `position`, row-major (see the module docs). Deterministic in
/// `(settings, position)`.
pub fn probe_moments(tracer: &Tracer<'_>, position: Vec3, s: &VisibilitySettings) -> Vec<[f32; 2]> {
    let key = hash3(
        position.x.to_bits() as u64,
        position.y.to_bits() as u64,
        position.z.to_bits() as u64,
    ) ^ STREAM;
    let res = s.resolution;
    let k = s.rays_per_side;
    let texel = 2.0 / res as f32;
    let mut out = Vec::with_capacity((res * res) as usize);
    for row in 0..res {
        for col in 0..res {
            let t = (row * res + col) as u64;
            let corner = oct_texel_center(res, col, row) - Vec2::splat(0.5 * texel);
            let (mut m1, mut m2) = (0.0f64, 0.0f64);
            for r in 0..k * k {
                let mut rng = SampleRng::new(s.seed, key, t * (k * k) as u64 + r as u64);
                let j = rng.next_2d();
                let cell = Vec2::new((r % k) as f32 + j.x, (r / k) as f32 + j.y) / k as f32;
                let dir = oct_decode(corner + cell * texel);
                let ray = Ray::new(position, dir);
                let d = tracer
                    .closest_hit(&ray, s.max_distance)
                    .map_or(s.max_distance, |h| h.t.clamp(0.0, s.max_distance));
                m1 += d as f64;
                m2 += (d as f64) * (d as f64);
            }
            let n = (k * k) as f64;
            out.push([(m1 / n) as f32, (m2 / n) as f32]);
        }
    }
    out
}

/// Bakes the `VISM` section for probes at `positions`: [`probe_moments`]
/// for each (in parallel), stored as binary16 fractions of `max_distance`
/// (`μ/max`, `μ2/max²`, rounded to nearest). `progress(done, total)` is
/// called as probes finish.
pub fn bake_distance_moments(
    tracer: &Tracer<'_>,
    positions: &[Vec3],
    settings: &VisibilitySettings,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<DistanceMoments, VisibilityError> {
    settings.check()?;
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(VisibilityError::NonFinitePosition(i));
    }
    let done = AtomicUsize::new(0);
    let total = positions.len();
    let maps: Vec<Vec<[f32; 2]>> = positions
        .par_iter()
        .map(|&p| {
            let m = probe_moments(tracer, p, settings);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            m
        })
        .collect();
    let max = settings.max_distance;
    let f16 = |x: f32| half::f16::from_f32(x.clamp(0.0, 1.0)).to_bits();
    let data = maps
        .iter()
        .flatten()
        .flat_map(|&[m1, m2]| [f16(m1 / max), f16(m2 / (max * max))])
        .collect();
    Ok(DistanceMoments {
        resolution: settings.resolution,
        max_distance: max,
        data,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::cloud::test_cloud_file;
    use crate::format::Parts;
    use crate::scene::Scene;
    use probekit_runtime::cloud::{ProbeCloud, VisibilityMaps, WalkState};
    use probekit_runtime::format::ProbeFile;
    use probekit_sh::ShRgb;

    /// Distance from `p` (inside) to the walls of box `[lo, hi]` along unit
    /// `d`: the analytic ray–plane intersection, no tracer.
    fn box_exit(p: Vec3, d: Vec3, lo: Vec3, hi: Vec3) -> f32 {
        let mut t = f32::INFINITY;
        for a in 0..3 {
            if d[a] > 1e-9 {
                t = t.min((hi[a] - p[a]) / d[a]);
            } else if d[a] < -1e-9 {
                t = t.min((lo[a] - p[a]) / d[a]);
            }
        }
        t
    }

    fn scene(boxes: &[(Vec3, Vec3)]) -> Scene {
        crate::scene::tests_support::boxes_scene(boxes)
    }

    #[test]
    fn moments_in_a_box_room_match_dense_analytic_sampling() {
        let (lo, hi) = (Vec3::ZERO, Vec3::new(4.0, 3.0, 5.0));
        let sc = scene(&[(lo, hi)]);
        let tracer = Tracer::new(&sc);
        let p = Vec3::new(1.1, 0.7, 3.4);
        let s = VisibilitySettings {
            resolution: 4,
            rays_per_side: 8,
            max_distance: 20.0,
            seed: 3,
        };
        let baked = probe_moments(&tracer, p, &s);
        let file = bake_distance_moments(&tracer, &[p], &s, &|_, _| {}).unwrap();
        let stored = file.decode();
        // Reference: a dense 32×32 midpoint grid over each texel's map area,
        // distances from the analytic planes.
        let n = 32;
        let texel = 2.0 / s.resolution as f32;
        for row in 0..s.resolution {
            for col in 0..s.resolution {
                let c0 = oct_texel_center(s.resolution, col, row) - Vec2::splat(0.5 * texel);
                let (mut m1, mut m2) = (0.0f64, 0.0f64);
                for j in 0..n {
                    for i in 0..n {
                        let e = c0 + Vec2::new(i as f32 + 0.5, j as f32 + 0.5) * texel / n as f32;
                        let t = box_exit(p, oct_decode(e), lo, hi) as f64;
                        m1 += t;
                        m2 += t * t;
                    }
                }
                let k = (row * s.resolution + col) as usize;
                let (r1, r2) = ((m1 / (n * n) as f64) as f32, (m2 / (n * n) as f64) as f32);
                for got in [baked[k], stored[k]] {
                    assert!(
                        (got[0] - r1).abs() <= 0.03 * r1 + 0.01,
                        "texel {k}: μ {} vs {r1}",
                        got[0]
                    );
                    assert!(
                        (got[1] - r2).abs() <= 0.06 * r2 + 0.02,
                        "texel {k}: μ2 {} vs {r2}",
                        got[1]
                    );
                }
            }
        }
        // Rays that escape count as max_distance: a probe outside all geometry.
        let far = probe_moments(&tracer, Vec3::new(100.0, 0.0, 0.0), &s);
        let (toward, away): (Vec<[f32; 2]>, Vec<[f32; 2]>) =
            far.iter().partition(|m| m[0] < s.max_distance);
        assert!(away.iter().all(|m| m[0] == 20.0 && m[1] == 400.0));
        assert!(toward.len() < far.len());
    }

    #[test]
    fn bake_is_deterministic_and_rejects_bad_settings() {
        let sc = scene(&[(Vec3::ZERO, Vec3::splat(3.0))]);
        let tracer = Tracer::new(&sc);
        let pts: Vec<Vec3> = (0..20)
            .map(|i| Vec3::splat(0.2 + 0.13 * i as f32))
            .collect();
        let s = VisibilitySettings::new(6.0, 9);
        let a = bake_distance_moments(&tracer, &pts, &s, &|_, _| {}).unwrap();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let b = one.install(|| bake_distance_moments(&tracer, &pts, &s, &|_, _| {}).unwrap());
        assert_eq!(a, b);
        // Split in two (as shards are): the same maps, concatenated.
        let c = bake_distance_moments(&tracer, &pts[..7], &s, &|_, _| {}).unwrap();
        let d = bake_distance_moments(&tracer, &pts[7..], &s, &|_, _| {}).unwrap();
        assert_eq!([c.data, d.data].concat(), a.data);
        let bad = |f: fn(&mut VisibilitySettings)| {
            let mut s = s;
            f(&mut s);
            bake_distance_moments(&tracer, &pts, &s, &|_, _| {})
        };
        assert_eq!(
            bad(|s| s.resolution = 0),
            Err(VisibilityError::Resolution(0))
        );
        assert_eq!(
            bad(|s| s.resolution = 65),
            Err(VisibilityError::Resolution(65))
        );
        assert_eq!(bad(|s| s.rays_per_side = 0), Err(VisibilityError::NoRays));
        assert!(matches!(
            bad(|s| s.max_distance = f32::NAN),
            Err(VisibilityError::MaxDistance(_))
        ));
        assert_eq!(
            bake_distance_moments(&tracer, &[Vec3::NAN], &s, &|_, _| {}),
            Err(VisibilityError::NonFinitePosition(0))
        );
    }

    /// Two rooms split by a 0.3 m wall at x ∈ [0, 0.3]: the lit room
    /// (x < 0) has probes of constant radiance 1, the sealed dark room
    /// (x > 0.3) probes of radiance 0 — its true irradiance is 0 (nothing
    /// reaches it). Tetrahedra reach across the wall.
    struct TwoRooms {
        cloud: ProbeCloud,
        file: ProbeFile,
    }

    fn two_rooms() -> TwoRooms {
        let room = (Vec3::new(-2.0, 0.0, 0.0), Vec3::new(2.3, 2.0, 2.0));
        let wall = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.3, 2.0, 2.0));
        let sc = scene(&[room, wall]);
        let tracer = Tracer::new(&sc);
        let mut pos = Vec::new();
        for x in [-1.5f32, -0.5, 0.8, 1.8] {
            for y in [0.4f32, 1.0, 1.6] {
                for z in [0.4f32, 1.0, 1.6] {
                    pos.push(Vec3::new(x, y, z));
                }
            }
        }
        let sh: Vec<ShRgb> = pos
            .iter()
            .map(|p| {
                let mut s = ShRgb::zeros(1);
                let lit = if p.x < 0.0 { 1.0 } else { 0.0 };
                s.coeffs_mut()[0] = Vec3::splat(lit);
                s
            })
            .collect();
        let mut file = test_cloud_file(&pos, &sh);
        let s = VisibilitySettings::new((room.1 - room.0).length(), 1);
        file.cloud_mut().blend.distance_moments =
            Some(bake_distance_moments(&tracer, &pos, &s, &|_, _| {}).unwrap());
        let file = ProbeFile::from_bytes(&file.to_bytes().unwrap()).unwrap();
        let cloud = ProbeCloud::from_file(&file).unwrap();
        TwoRooms { cloud, file }
    }

    #[test]
    fn the_dark_room_does_not_leak_with_visibility() {
        let TwoRooms { mut cloud, file } = two_rooms();
        assert!(cloud.visibility_enabled());
        let lit = cloud.irradiance(Vec3::new(-1.0, 1.0, 1.0), Vec3::X, &mut WalkState::new());
        assert!((lit.x - std::f32::consts::PI * 2.0 * 0.28209479).abs() < 1e-3 || lit.x > 0.5);
        let mut worst_on = 0.0f32;
        let mut worst_off = 0.0f32;
        let mut st = WalkState::new();
        // Points 1–9 cm from the wall in the dark room, normals facing it.
        for k in 0..50 {
            let f = k as f32 / 49.0;
            let p = Vec3::new(
                0.31 + 0.08 * f,
                0.3 + 1.4 * f,
                1.7 - 1.4 * (f * 7.0).fract(),
            );
            cloud.set_visibility(true);
            let on = cloud.irradiance(p, -Vec3::X, &mut st).x;
            cloud.set_visibility(false);
            let off = cloud.irradiance(p, -Vec3::X, &mut st).x;
            worst_on = worst_on.max(on / lit.x);
            worst_off = worst_off.max(off / lit.x);
        }
        // Truth is 0: without visibility a third of the lit room's light
        // leaks through; with it, below the eval's 1% leak threshold.
        assert!(worst_off > 0.2, "{worst_off}");
        assert!(worst_on < 0.01, "{worst_on}");
        // The lit side near the wall keeps its light (the wall does not
        // hide lit probes from points in front of it).
        cloud.set_visibility(true);
        let near = cloud
            .irradiance(Vec3::new(-0.05, 1.0, 1.0), Vec3::X, &mut st)
            .x;
        assert!(near > 0.5 * lit.x, "{near} vs {}", lit.x);
        // Turning visibility off gives the plain barycentric blend of the
        // mesh weights, computed here directly.
        cloud.set_visibility(false);
        let p = Vec3::new(0.35, 1.1, 0.9);
        let (idx, w) = cloud.mesh().weights_at(p, &mut WalkState::new());
        let direct: f32 = idx
            .iter()
            .zip(w)
            .map(|(&i, w)| w * file.probe_set().coefficients.to_f32().unwrap()[i as usize].x)
            .sum();
        let mut out = [Vec3::ZERO; 1];
        cloud.sh_at(p, &mut st, &mut out);
        assert!((out[0].x - direct).abs() < 1e-6);
    }

    #[test]
    fn lighting_stays_continuous_along_lines_with_visibility() {
        let TwoRooms { cloud, .. } = two_rooms();
        let mut rng = SampleRng::new(5, 0, 0);
        let mut st = WalkState::new();
        let max_jump = |a: Vec3, b: Vec3, steps: usize, st: &mut WalkState| {
            let mut prev = cloud.irradiance(a, Vec3::X, st).x;
            let mut worst = 0.0f32;
            for i in 1..=steps {
                let p = a.lerp(b, i as f32 / steps as f32);
                let e = cloud.irradiance(p, Vec3::X, st).x;
                worst = worst.max((e - prev).abs());
                prev = e;
            }
            worst
        };
        for _ in 0..6 {
            // Short segments (4 cm) crossing the wall's faces, somewhere in the rooms.
            let u = rng.next_2d();
            let c = Vec3::new(
                if rng.next_f32() < 0.5 { -0.02 } else { 0.32 },
                0.3 + 1.4 * u.x,
                0.3 + 1.4 * u.y,
            );
            let d = (Vec3::new(1.0, rng.next_f32() - 0.5, rng.next_f32() - 0.5)).normalize() * 0.02;
            let coarse = max_jump(c - d, c + d, 40, &mut st);
            let fine = max_jump(c - d, c + d, 400, &mut st);
            // Continuous (Lipschitz): ten times finer steps, at most a third
            // of the largest jump (a discontinuity keeps its jump).
            assert!(fine <= coarse / 3.0 + 1e-4, "coarse {coarse}, fine {fine}");
            assert!(coarse < 0.5, "{coarse}");
        }
    }

    #[test]
    fn maps_are_checked_against_the_cloud() {
        let TwoRooms { mut cloud, .. } = two_rooms();
        let n = cloud.probe_count();
        let short = VisibilityMaps::new(2, 5.0, vec![[1.0, 1.0]; 4 * (n - 1)]).unwrap();
        assert!(cloud.set_visibility_maps(Some(short)).is_err());
        assert!(VisibilityMaps::new(0, 5.0, vec![]).is_none());
        assert!(VisibilityMaps::new(2, 5.0, vec![[0.0, 0.0]; 5]).is_none());
        cloud.set_visibility_maps(None).unwrap();
        assert!(!cloud.visibility_enabled());
    }
}
