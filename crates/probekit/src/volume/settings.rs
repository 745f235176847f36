//! Build settings of irradiance volumes: the common ones, the adaptive
//! octree's, gradients, the root grid, and what a build reports.

use super::VolumeBuildError;
use glam::Vec3;

/// How per-sample SH gradients are obtained.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GradientMode {
    /// No gradients stored.
    None,
    /// Central differences from 6 extra captures at `±step` along each axis
    /// (Tatarchuk 2005: "project 6 additional irradiance functions").
    Central {
        /// Offset in metres; 0 or less = [`DEFAULT_STEP_FRACTION`] of the
        /// finest cell edge.
        step: f32,
    },
    /// The source's closed form ([`VolumeSource::analytic_gradients`](super::VolumeSource::analytic_gradients)).
    Analytic,
}

/// Default central-difference offset, as a fraction of the finest cell
/// edge. A path-traced capture is noisy and the difference divides its
/// noise by `2·step`, so the offset is a trade between that noise and the
/// truncation error of the slope. Half a cell measures the slope over the
/// scale the interpolation spans: on the demo (five seeds pooled,
/// BENCHMARKS.md "Gradient step") tricubic interpolation then has 0.53× the
/// trilinear rel_rmse of the same samples, against 3.2× at 5 % of a cell;
/// a whole cell reaches through walls from samples next to them.
pub const DEFAULT_STEP_FRACTION: f32 = 0.5;

/// Settings shared by both builders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CommonSettings {
    /// Box minimum (metres).
    pub min: Vec3,
    /// Box maximum (metres).
    pub max: Vec3,
    /// Gradient capture.
    pub gradients: GradientMode,
    /// Samples with validity below this are invalid and dilated.
    pub validity_threshold: f32,
}

/// Adaptive octree settings (Tatarchuk 2005, "Adaptive Subdivision": min and max
/// level and one threshold per heuristic; `None` disables a heuristic).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveSettings {
    /// Box, gradients, validity.
    pub common: CommonSettings,
    /// Cells shallower than this are always subdivided.
    pub min_depth: u32,
    /// Cells at this depth are never subdivided, except by the emitter rule
    /// ([`Self::emitter_depth`], which may exceed it); both ≤ 20.
    pub max_depth: u32,
    /// Subdivide cells that contain geometry (Greger et al. 1998).
    pub geometry: bool,
    /// Geometry alone splits only cells shallower than this; deeper cells
    /// that contain geometry split only if the other heuristics (the
    /// prediction test) say so. `max_depth` or more = Tatarchuk's rule (every
    /// cell touching a wall down to the finest level, which spends most of
    /// an interior's samples on walls the light field is smooth across).
    pub geometry_depth: u32,
    /// Cells that contain part of an emitter (an emissive surface or a
    /// positional light, [`VolumeSource::contains_emitter`](super::VolumeSource::contains_emitter)) split down to
    /// this depth, and pruning does not collapse them; it may be deeper
    /// than `max_depth`, which then bounds every other rule. Next to an area
    /// light the irradiance changes within centimetres (ten times from 30 to
    /// 3 cm under the Cornell box's ceiling quad), where the prediction
    /// test, fed by noisy captures, refines or prunes by chance; 2:1
    /// balance then grades the cells around the finest ones. 0 = off (seed
    /// 001 has no such rule; its geometry rule refines every wall instead).
    pub emitter_depth: u32,
    /// Subdivide when the cell's largest edge exceeds `factor ×` the
    /// smallest harmonic mean of scene depth at its corners (Pharr 2004).
    pub depth_factor: Option<f32>,
    /// Subdivide when `max |Δv| / (|DC| + ε)` along a cell edge, i.e. the
    /// relative SH gradient times the cell size, exceeds this.
    pub gradient_threshold: Option<f32>,
    /// Subdivide when trilinear prediction from the parent's corners misses
    /// a child corner's captured SH by more than this (relative, as above).
    pub prediction_tolerance: Option<f32>,
    /// After sampling, collapse a cell whose children are leaves and whose
    /// children's samples the parent predicts within this (relative).
    pub prune_tolerance: Option<f32>,
    /// Floor of the denominator of the prediction and prune tolerances, as
    /// a fraction of the mean DC magnitude of the samples at `min_depth`:
    /// misses are measured relative to `max(|DC local|, floor × mean)`, so
    /// a dark corner (a closet) is not refined to chase differences that
    /// are large relative to its own tiny light but invisible against the
    /// scene's (which is how `probekit eval` normalises its error). 0 =
    /// purely local (the original criterion).
    pub relative_floor: f32,
    /// Noise-aware prediction and pruning: a child point counts as missed
    /// only by what its miss exceeds `noise_k ×` the standard error of the
    /// miss (the point's and the interpolated corners' capture errors
    /// combined, [`Captured::std_error`](super::Captured::std_error)), so Monte Carlo noise alone does
    /// not refine. 0 = compare raw misses (the original criterion).
    pub noise_k: f32,
    /// After pruning, split leaves until leaves that share a point differ
    /// by at most one level (2:1 balance). The run-time blend lets a leaf's
    /// corner kernels reach one leaf size into its neighbours, so a coarse
    /// leaf next to much finer ones smears its far-away samples over them;
    /// balance bounds that reach to twice the fine size.
    pub balance: bool,
    /// Root cells per axis: the box is first cut into this grid and each
    /// root cell is an octree (a forest); depths count from the
    /// root cells. `None` = [`near_cubic_roots`] of the box; `Some([1, 1,
    /// 1])` = Tatarchuk's single octree over the whole box, whose cells copy
    /// the box's aspect ratio.
    pub roots: Option<[u32; 3]>,
}

/// The coarsest grid of root cells that keeps them near-cubic: for `m` =
/// 1, 2, 3, 4 the cell edge `e = (smallest extent) / m`, `r_a =
/// max(1, round(extent_a / e))` roots per axis; the first `m` whose cells'
/// longest / shortest edge is at most 1.25 wins, else the most cubic of the
/// four. An 8 × 3 × 4 m room gets 5 × 2 × 3 roots of 1.6 × 1.5 × 1.33 m
/// (a single root's cells there are 2.7 : 1); a cube gets one root.
pub fn near_cubic_roots(min: Vec3, max: Vec3) -> Result<[u32; 3], VolumeBuildError> {
    check_box(min, max)?;
    let ext = max - min;
    let mut best = ([1u32; 3], f32::INFINITY);
    for m in 1..=4u32 {
        let e = ext.min_element() / m as f32;
        let r = ext
            .to_array()
            .map(|x| ((x / e).round() as u32).clamp(1, 4096));
        let cell = ext / Vec3::new(r[0] as f32, r[1] as f32, r[2] as f32);
        let aspect = cell.max_element() / cell.min_element();
        if aspect <= 1.25 {
            return Ok(r);
        }
        if aspect < best.1 {
            best = (r, aspect);
        }
    }
    Ok(best.0)
}

/// Counters of a build.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BuildStats {
    /// Points captured in total (samples, prediction probes, gradient probes).
    pub captures: usize,
    /// Samples stored.
    pub samples: usize,
    /// Leaves (cells).
    pub leaves: usize,
    /// Samples replaced by dilation.
    pub dilated: usize,
}

pub(super) fn check_box(min: Vec3, max: Vec3) -> Result<(), VolumeBuildError> {
    // A box given inverted is refused too (`Aabb::new` would reorder it).
    Ok(crate::scene::Aabb { min, max }.check_bake_box()?)
}
