//! Probe validity: is a probe inside geometry, and how far is the geometry?
//!
//! Measured on the capture's own receiver rays (first surface each meets):
//! - **back-face fraction**: rays whose first hit is a back face, over all
//!   rays. A probe inside a wall or a closed object sees mostly back faces.
//!   Where the scene flagged a triangle as inconsistently wound
//!   ([`crate::scene::Scene::winding_consistent`]), front/back says nothing,
//!   so that ray is judged by parity instead: the crossings out to infinity
//!   are counted, and an odd count means the probe is enclosed.
//!   (Parity assumes closed surfaces; an open, single-sided wall hit on an
//!   inconsistently wound triangle counts as one crossing.)
//! - **harmonic mean distance** `N / Σ 1/dᵢ` over all `N` rays, misses
//!   contributing `1/∞ = 0` (Tatarchuk 2005, "Irradiance Volumes for Games",
//!   slide "Harmonic Mean of Scene Depth"): a scale of how far lighting can
//!   be extrapolated from the probe.
//! - **nearest distance**: the smallest hit distance.
//!
//! **Virtual offset**: a probe whose back-face fraction exceeds the
//! threshold is moved straight across the face of its nearest back-face hit
//! (along the face's normal) to `margin` beyond its plane, re-tested (a
//! cheap pre-pass of [`ValiditySettings::pre_pass_rays`] rays, up to
//! [`ValiditySettings::max_offset_steps`] moves), then captured there and
//! flagged. Where two solids touch (a wall's top against the ceiling slab)
//! those moves can go from one into the other and back; a probe still in
//! geometry after them leaves the solid it started in straight across one
//! of its faces, the nearest whose far side the pre-pass finds free
//! (`Baker::exits`). Only such probes move differently: a probe the moves
//! free is where they leave it.

use super::probe::STREAM_ROTATION;
use super::{BakeError, Baker};
use crate::sampling::{r2_point, sample_uniform_sphere, SampleRng};
use crate::trace::{Hit, Ray};
use glam::Vec3;

/// Most surface crossings the parity test follows before giving up.
pub const MAX_PARITY_CROSSINGS: u32 = 32;

/// Validity thresholds and the virtual offset.
#[derive(Clone, Debug, PartialEq)]
pub struct ValiditySettings {
    /// A probe is invalid when more than this fraction of its rays hit back
    /// faces (default 0.25).
    pub backface_threshold: f32,
    /// Move invalid probes out of geometry before capturing (default true).
    pub virtual_offset: bool,
    /// Distance beyond the back face to move to, metres (default 0.02).
    pub offset_margin: f32,
    /// Rays of the validity pre-pass that decides the offset (default 256).
    pub pre_pass_rays: u32,
    /// Most offset moves per probe (default 3).
    pub max_offset_steps: u32,
}

impl Default for ValiditySettings {
    fn default() -> Self {
        Self {
            backface_threshold: 0.25,
            virtual_offset: true,
            offset_margin: 0.02,
            pre_pass_rays: 256,
            max_offset_steps: 3,
        }
    }
}

impl ValiditySettings {
    /// Whether rays with these statistics find their origin outside
    /// geometry: a back-face fraction at most the threshold.
    pub(crate) fn accepts(&self, st: &HitStats) -> bool {
        st.backface_fraction() <= self.backface_threshold
    }

    /// Checks the bounds: threshold in [0, 1], margin finite and ≥ 0, rays ≥ 1.
    pub fn validate(&self) -> Result<(), BakeError> {
        if !(0.0..=1.0).contains(&self.backface_threshold) {
            return Err(BakeError::BadSettings(format!(
                "back-face threshold {} outside [0, 1]",
                self.backface_threshold
            )));
        }
        if !(self.offset_margin.is_finite() && self.offset_margin >= 0.0) {
            return Err(BakeError::BadSettings(format!(
                "virtual offset margin {} must be finite and ≥ 0",
                self.offset_margin
            )));
        }
        if self.virtual_offset && self.pre_pass_rays == 0 {
            return Err(BakeError::BadSettings(
                "virtual offset needs at least one pre-pass ray".into(),
            ));
        }
        Ok(())
    }
}

/// Validity of one captured probe (measured at its final position).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Validity {
    /// Fraction of receiver rays whose first hit is a back face (0..1).
    pub backface_fraction: f32,
    /// Harmonic mean of hit distances over all rays, metres (∞ if nothing is hit).
    pub harmonic_mean_distance: f32,
    /// Distance to the nearest surface hit, metres (∞ if nothing is hit).
    pub nearest_distance: f32,
    /// `backface_fraction ≤ threshold` at the final position.
    pub valid: bool,
    /// Displacement applied by the virtual offset (zero if none).
    pub offset: Vec3,
    /// True when the probe was moved by the virtual offset.
    pub offset_applied: bool,
}

/// First-hit statistics over a set of rays.
#[derive(Clone, Debug)]
pub(crate) struct HitStats {
    pub rays: u32,
    pub hits: u32,
    pub back: u32,
    pub inv_dist_sum: f64,
    pub min_dist: f32,
    /// The nearest back-face hit (by distance along its ray).
    pub nearest_back: Option<BackHit>,
}

/// A back-face hit of a validity ray: the way out of the solid through the
/// face it met.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BackHit {
    /// Distance along the ray (metres).
    pub t: f32,
    /// Unit direction straight across the face: its outward normal; the
    /// ray's direction where the winding says nothing and parity judged it.
    pub way: Vec3,
    /// Distance from the ray's origin to the face's plane along `way`
    /// (metres).
    pub across: f32,
}

impl Default for HitStats {
    fn default() -> Self {
        Self {
            rays: 0,
            hits: 0,
            back: 0,
            inv_dist_sum: 0.0,
            min_dist: f32::INFINITY,
            nearest_back: None,
        }
    }
}

impl HitStats {
    /// Adds a hit at distance `t`, with the way out where it is a back face.
    pub fn add_hit(&mut self, t: f32, back: Option<BackHit>) {
        self.hits += 1;
        self.inv_dist_sum += 1.0 / (t.max(1e-6) as f64);
        self.min_dist = self.min_dist.min(t);
        if let Some(b) = back {
            self.back += 1;
            self.keep_nearest(b);
        }
    }

    /// Adds another set (fixed order keeps results deterministic).
    pub fn merge(&mut self, o: &HitStats) {
        self.rays += o.rays;
        self.hits += o.hits;
        self.back += o.back;
        self.inv_dist_sum += o.inv_dist_sum;
        self.min_dist = self.min_dist.min(o.min_dist);
        if let Some(b) = o.nearest_back {
            self.keep_nearest(b);
        }
    }

    /// `b` as the nearest back-face hit when it is nearer than the one held.
    fn keep_nearest(&mut self, b: BackHit) {
        if self.nearest_back.map_or(true, |n| b.t < n.t) {
            self.nearest_back = Some(b);
        }
    }

    pub fn backface_fraction(&self) -> f32 {
        if self.rays == 0 {
            0.0
        } else {
            self.back as f32 / self.rays as f32
        }
    }

    pub fn harmonic_mean(&self) -> f32 {
        if self.inv_dist_sum > 0.0 {
            (self.rays as f64 / self.inv_dist_sum) as f32
        } else {
            f32::INFINITY
        }
    }
}

impl Validity {
    pub(crate) fn from_stats(
        st: &HitStats,
        s: &ValiditySettings,
        offset: Vec3,
        pushed: bool,
    ) -> Self {
        Self {
            backface_fraction: st.backface_fraction(),
            harmonic_mean_distance: st.harmonic_mean(),
            nearest_distance: st.min_dist,
            valid: s.accepts(st),
            offset,
            offset_applied: pushed,
        }
    }
}

impl Baker<'_> {
    /// Validity bookkeeping for the first surface a receiver ray meets.
    pub(super) fn record_first_hit(&self, st: &mut HitStats, dir: Vec3, hit: Option<&Hit>) {
        st.rays += 1;
        let Some(h) = hit else { return };
        st.add_hit(h.t, self.back_hit(h, dir));
    }

    /// The way out where `h`, the first hit along unit `dir`, is a back
    /// face (the ray started inside a solid), `None` where it is a front one.
    fn back_hit(&self, h: &Hit, dir: Vec3) -> Option<BackHit> {
        if h.winding_consistent {
            let n = h.geometric_normal;
            (!h.front_face).then(|| BackHit {
                t: h.t,
                way: n,
                across: h.t * dir.dot(n).max(0.0),
            })
        } else {
            self.parity_inside(h, dir).then_some(BackHit {
                t: h.t,
                way: dir,
                across: h.t,
            })
        }
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

    /// Ways out of the geometry around `x`: the back faces the validity
    /// pre-pass's rays meet first.
    pub(crate) fn exits(&self, x: Vec3, probe_index: u64, seed: u64, rays: u32) -> Vec<BackHit> {
        let mut out = Vec::new();
        self.pre_pass(x, probe_index, seed, rays, |d, hit| {
            if let Some(b) = hit.and_then(|h| self.back_hit(h, d)) {
                out.push(b);
            }
        });
        out
    }

    /// First-hit statistics of the validity pre-pass's rays from `x`.
    pub(crate) fn hit_stats(&self, x: Vec3, probe_index: u64, seed: u64, rays: u32) -> HitStats {
        let mut st = HitStats::default();
        self.pre_pass(x, probe_index, seed, rays, |d, hit| {
            self.record_first_hit(&mut st, d, hit)
        });
        st
    }

    /// The validity pre-pass: `rays` R2 directions from `x` (rotated by the
    /// probe's own stream), each with its first hit, in order.
    fn pre_pass(
        &self,
        x: Vec3,
        probe_index: u64,
        seed: u64,
        rays: u32,
        mut f: impl FnMut(Vec3, Option<&Hit>),
    ) {
        let rot = SampleRng::new(seed, probe_index, STREAM_ROTATION - 1).next_2d();
        for i in 0..rays {
            let d = sample_uniform_sphere(r2_point(i as u64, rot));
            let hit = self.tracer.closest_hit(&Ray::new(x, d), f32::INFINITY);
            f(d, hit.as_ref());
        }
    }
}
