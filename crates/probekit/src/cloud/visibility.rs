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
//! Deterministic: the jitter of ray `r` of texel `t` of probe `p` comes from
//! a counter-based generator keyed by `(seed, p, t·k² + r)`, and probes are
//! baked in parallel into their own slots, so the bytes do not depend on the
//! thread count.

use crate::bake::sampling::SampleRng;
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

    /// The settings as a JSON object for the bake metadata.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "resolution": self.resolution,
            "rays_per_texel": self.rays_per_side * self.rays_per_side,
            "max_distance": self.max_distance,
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

/// The `[μ, μ2]` (metres, m²) of every texel of the map of probe `index` at
/// `position`, row-major (see the module docs). Deterministic in
/// `(settings, index)`.
pub fn probe_moments(
    tracer: &Tracer<'_>,
    position: Vec3,
    index: u64,
    s: &VisibilitySettings,
) -> Vec<[f32; 2]> {
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
                let mut rng = SampleRng::new(s.seed, STREAM ^ index, t * (k * k) as u64 + r as u64);
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
        .enumerate()
        .map(|(i, &p)| {
            let m = probe_moments(tracer, p, i as u64, settings);
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
