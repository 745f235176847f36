//! Building uniform and adaptive irradiance volumes (seed 001).

use super::source::{Captured, VolumeSource};
use super::VolumeBuildError;
use crate::format::{lattice_pos, lattice_step};
use crate::format::{
    layout::{NONE, VALIDITY_INVALID, VALIDITY_VIRTUAL_OFFSET},
    Coefficients, Gradients, Octree, OctreeNode, ProbeFile, ProbeFileKind, Validity, VolumeGrid,
};
use glam::Vec3;
use std::collections::HashMap;

/// How per-sample SH gradients are obtained.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GradientMode {
    /// No gradients stored.
    None,
    /// Central differences from 6 extra captures at `±step` along each axis
    /// (seed 001: "project 6 additional irradiance functions").
    Central {
        /// Offset in metres; 0 or less = [`DEFAULT_STEP_FRACTION`] of the
        /// finest cell edge.
        step: f32,
    },
    /// The source's closed form ([`VolumeSource::analytic_gradients`]).
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

/// Adaptive octree settings (seed 001 "Adaptive Subdivision": min and max
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
    /// prediction test) say so. `max_depth` or more = the seed's rule (every
    /// cell touching a wall down to the finest level, which spends most of
    /// an interior's samples on walls the light field is smooth across).
    pub geometry_depth: u32,
    /// Cells that contain part of an emitter (an emissive surface or a
    /// positional light, [`VolumeSource::contains_emitter`]) split down to
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
    /// combined, [`Captured::std_error`]), so Monte Carlo noise alone does
    /// not refine. 0 = compare raw misses (the original criterion).
    pub noise_k: f32,
    /// After pruning, split leaves until leaves that share a point differ
    /// by at most one level (2:1 balance). The run-time blend lets a leaf's
    /// corner kernels reach one leaf size into its neighbours, so a coarse
    /// leaf next to much finer ones smears its far-away samples over them;
    /// balance bounds that reach to twice the fine size.
    pub balance: bool,
    /// Root cells per axis: the box is first cut into this grid and each
    /// root cell is an octree (a forest, format 1.3); depths count from the
    /// root cells. `None` = [`near_cubic_roots`] of the box; `Some([1, 1,
    /// 1])` = the seed's single octree over the whole box, whose cells copy
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

/// Relative SH distance used by every threshold: `‖a − b‖₂ / (|DC(ref)| + ε)`
/// over all RGB coefficients, `ε` = 1e-4.
pub fn relative_difference(a: &[Vec3], b: &[Vec3], reference: &[Vec3]) -> f32 {
    let d: f32 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).length_squared())
        .sum();
    d.sqrt() / (reference[0].length() + 1e-4)
}

fn check_box(min: Vec3, max: Vec3) -> Result<(), VolumeBuildError> {
    // A box given inverted is refused too (`Aabb::new` would reorder it).
    Ok(crate::scene::Aabb { min, max }.check_bake_box()?)
}

/// Uniform grid with `resolution` probes per axis (each ≥ 2) over the box,
/// probes at cell corners (seed 001 "Uniform Volume Subdivision").
pub fn build_uniform(
    src: &dyn VolumeSource,
    common: &CommonSettings,
    resolution: [u32; 3],
) -> Result<(ProbeFile, BuildStats), VolumeBuildError> {
    check_box(common.min, common.max)?;
    if resolution.iter().any(|&r| r < 2) {
        return Err(VolumeBuildError::BadResolution(resolution));
    }
    let total = resolution.iter().map(|&r| r as u64).product::<u64>();
    if total > 1 << 26 {
        return Err(VolumeBuildError::TooLarge(total));
    }
    let [rx, ry, rz] = resolution.map(|r| r as usize);
    let size = common.max - common.min;
    let mut points = Vec::with_capacity(rx * ry * rz);
    for k in 0..rz {
        for j in 0..ry {
            for i in 0..rx {
                let f = Vec3::new(
                    i as f32 / (rx - 1) as f32,
                    j as f32 / (ry - 1) as f32,
                    k as f32 / (rz - 1) as f32,
                );
                points.push(common.min + f * size);
            }
        }
    }
    let caps = src.capture(&points);
    let mut stats = BuildStats {
        captures: points.len(),
        samples: points.len(),
        leaves: (rx - 1) * (ry - 1) * (rz - 1),
        dilated: 0,
    };
    // Neighbours: the 26 surrounding grid points.
    let idx = |i: usize, j: usize, k: usize| i + rx * (j + ry * k);
    let mut nbrs: Vec<Vec<u32>> = vec![Vec::new(); points.len()];
    for k in 0..rz {
        for j in 0..ry {
            for i in 0..rx {
                for dk in -1i64..=1 {
                    for dj in -1i64..=1 {
                        for di in -1i64..=1 {
                            let (a, b, c) = (i as i64 + di, j as i64 + dj, k as i64 + dk);
                            if (di, dj, dk) == (0, 0, 0)
                                || a < 0
                                || b < 0
                                || c < 0
                                || a >= rx as i64
                                || b >= ry as i64
                                || c >= rz as i64
                            {
                                continue;
                            }
                            nbrs[idx(i, j, k)].push(idx(a as usize, b as usize, c as usize) as u32);
                        }
                    }
                }
            }
        }
    }
    let cell = size / (Vec3::new(rx as f32, ry as f32, rz as f32) - 1.0);
    finish(
        src,
        common,
        points,
        caps,
        &nbrs,
        cell.min_element(),
        &mut stats,
        |f| {
            f.grid = Some(VolumeGrid {
                min: common.min,
                max: common.max,
                resolution,
            })
        },
    )
    .map(|f| (f, stats))
}

/// Probes per axis for a cell size: `ceil(extent / cell) + 1`, at least 2.
pub fn resolution_for_cell(min: Vec3, max: Vec3, cell: f32) -> Result<[u32; 3], VolumeBuildError> {
    check_box(min, max)?;
    if !(cell.is_finite() && cell > 0.0) {
        return Err(VolumeBuildError::BadCell(cell));
    }
    let ext = max - min;
    let mut r = [0u32; 3];
    for a in 0..3 {
        let n = (ext[a] / cell).ceil();
        if n > 4096.0 {
            return Err(VolumeBuildError::TooLarge(n as u64));
        }
        r[a] = (n as u32).max(1) + 1;
    }
    Ok(r)
}

#[derive(Clone, Copy, Debug)]
struct Cell {
    lo: [u32; 3],
    depth: u32,
    first_child: usize,
}

const NO_CHILD: usize = usize::MAX;

/// Lattice at max depth: captures each lattice point at most once.
struct Lattice<'a> {
    src: &'a dyn VolumeSource,
    min: Vec3,
    step: Vec3,
    /// Lattice cells per axis (`roots · 2^max_depth`).
    cells: [u32; 3],
    index: HashMap<[u32; 3], usize>,
    keys: Vec<[u32; 3]>,
    caps: Vec<Captured>,
    captures: usize,
}

impl Lattice<'_> {
    fn pos(&self, q: [u32; 3]) -> Vec3 {
        lattice_pos(self.min, self.step, q)
    }

    /// Captures every not yet captured point of `qs` in one batch.
    fn ensure(&mut self, qs: &[[u32; 3]]) {
        let mut new = Vec::new();
        for q in qs {
            if !self.index.contains_key(q) {
                self.index.insert(*q, self.keys.len() + new.len());
                new.push(*q);
            }
        }
        if new.is_empty() {
            return;
        }
        let pts: Vec<Vec3> = new.iter().map(|q| self.pos(*q)).collect();
        self.captures += pts.len();
        self.caps.extend(self.src.capture(&pts));
        self.keys.extend(new);
    }

    fn sh(&self, q: [u32; 3]) -> &[Vec3] {
        self.cap(q).sh.coeffs()
    }

    fn cap(&self, q: [u32; 3]) -> &Captured {
        &self.caps[self.index[&q]]
    }
}

fn corners(lo: [u32; 3], s: u32) -> [[u32; 3]; 8] {
    std::array::from_fn(|c| {
        [
            lo[0] + s * (c as u32 & 1),
            lo[1] + s * ((c as u32 >> 1) & 1),
            lo[2] + s * ((c as u32 >> 2) & 1),
        ]
    })
}

/// The 27 lattice points of a cell's children, with trilinear weights of the
/// parent's corners.
fn child_points(lo: [u32; 3], s: u32) -> Vec<([u32; 3], [f32; 8])> {
    let h = s / 2;
    let mut out = Vec::with_capacity(27);
    for k in 0..3u32 {
        for j in 0..3u32 {
            for i in 0..3u32 {
                let f = [i as f32 * 0.5, j as f32 * 0.5, k as f32 * 0.5];
                let w = std::array::from_fn(|c| {
                    (0..3)
                        .map(|a| if (c >> a) & 1 == 1 { f[a] } else { 1.0 - f[a] })
                        .product()
                });
                out.push(([lo[0] + i * h, lo[1] + j * h, lo[2] + k * h], w));
            }
        }
    }
    out
}

/// How prediction misses are measured: irradiance-weighted SH distance
/// (each band scaled by `Â_l / π`, the clamped-cosine convolution, so by
/// Parseval the distance is the L2 norm over the sphere of the irradiance
/// difference / π and L2 noise counts a quarter) relative to
/// `max(|DC(prediction)|, floor)`.
///
/// With `noise_k > 0` the miss at a point is reduced by `noise_k × σ`, where
/// `σ² = ν(q) + Σ_c w_c² ν(c)` is the variance of the miss from capture
/// noise alone (independent captures: the point's own and the parent
/// corners' weighted by their trilinear weights), `ν = Σ_k band_k² |se_k|²`
/// the same weighted norm of a capture's standard errors.
struct MissScale {
    band: Vec<f32>,
    floor: f32,
    noise_k: f32,
}

impl MissScale {
    fn new(order: usize, noise_k: f32) -> Self {
        let mut band = Vec::with_capacity(order * order);
        for l in 0..order {
            let w = (probekit_sh::clamped_cosine_band(l) / std::f64::consts::PI) as f32;
            band.extend(std::iter::repeat(w).take(2 * l + 1));
        }
        Self {
            band,
            floor: 0.0,
            noise_k,
        }
    }

    /// Weighted squared norm `ν` of a capture's standard errors (0 if none).
    fn noise2(&self, c: &Captured) -> f32 {
        c.std_error.as_ref().map_or(0.0, |se| {
            se.iter()
                .zip(&self.band)
                .map(|(e, w)| (*e * *w).length_squared())
                .sum()
        })
    }

    /// Relative miss, less `noise_k` standard errors (`noise2` = `σ²`).
    fn miss(&self, pred: &[Vec3], actual: &[Vec3], noise2: f32) -> f32 {
        let d: f32 = pred
            .iter()
            .zip(actual)
            .zip(&self.band)
            .map(|((x, y), w)| ((*x - *y) * *w).length_squared())
            .sum();
        let excess = (d.sqrt() - self.noise_k * noise2.max(0.0).sqrt()).max(0.0);
        excess / (pred[0].length().max(self.floor) + 1e-4)
    }
}

/// Largest relative (noise-discounted) miss of trilinear prediction from
/// the parent's corners over the 27 child lattice points (all must be
/// captured; the 8 corners themselves miss by 0).
fn prediction_error(lat: &Lattice, lo: [u32; 3], s: u32, n: usize, scale: &MissScale) -> f32 {
    let cs = corners(lo, s);
    let corner_noise: [f32; 8] = cs.map(|c| scale.noise2(lat.cap(c)));
    let mut pred = vec![Vec3::ZERO; n];
    let mut worst = 0.0f32;
    for (q, w) in child_points(lo, s) {
        pred.fill(Vec3::ZERO);
        let mut noise2 = scale.noise2(lat.cap(q));
        for ((c, wc), nc) in cs.iter().zip(w).zip(corner_noise) {
            for (p, v) in pred.iter_mut().zip(lat.sh(*c)) {
                *p += *v * wc;
            }
            noise2 += wc * wc * nc;
        }
        if w.contains(&1.0) {
            continue; // a parent corner: predicted exactly
        }
        worst = worst.max(scale.miss(&pred, lat.sh(q), noise2));
    }
    worst
}

/// Adaptive octree (seed 001 "Adaptive Octree Subdivision"): cells split by
/// the enabled heuristics between `min_depth` and `max_depth`, then
/// redundant children are pruned. Corner samples live on the lattice of the
/// finest level and are captured once however many cells share them.
pub fn build_adaptive(
    src: &dyn VolumeSource,
    s: &AdaptiveSettings,
) -> Result<(ProbeFile, BuildStats), VolumeBuildError> {
    let common = &s.common;
    check_box(common.min, common.max)?;
    // The emitter rule may go below `max_depth` (its cells alone).
    let finest_depth = s.max_depth.max(s.emitter_depth);
    if finest_depth > 20 || s.min_depth > s.max_depth {
        return Err(VolumeBuildError::BadDepth(s.min_depth, finest_depth));
    }
    let n = src.order() * src.order();
    let roots = match s.roots {
        Some(r) => r,
        None => near_cubic_roots(common.min, common.max)?,
    };
    // Edge of a depth-0 (root) cell in lattice units.
    let full = 1u32 << finest_depth;
    let lattice_cells = roots.map(|r| r as u64 * full as u64);
    let root_total: u64 = roots.iter().map(|&r| r as u64).product();
    if roots.iter().any(|&r| r == 0 || r > 65536)
        || root_total > 1 << 20
        || lattice_cells.iter().any(|&c| c > 1 << 24)
    {
        return Err(VolumeBuildError::BadRoots(roots));
    }
    let lattice_cells = lattice_cells.map(|c| c as u32);
    let mut lat = Lattice {
        src,
        min: common.min,
        step: lattice_step(common.min, common.max, lattice_cells),
        cells: lattice_cells,
        index: HashMap::new(),
        keys: Vec::new(),
        caps: Vec::new(),
        captures: 0,
    };
    let mut cells = Vec::new();
    for k in 0..roots[2] {
        for j in 0..roots[1] {
            for i in 0..roots[0] {
                cells.push(Cell {
                    lo: [i * full, j * full, k * full],
                    depth: 0,
                    first_child: NO_CHILD,
                });
            }
        }
    }
    let root_count = cells.len();
    let mut frontier: Vec<usize> = (0..root_count).collect();
    let mut depth_cache: HashMap<[u32; 3], f32> = HashMap::new();
    let mut scale = MissScale::new(src.order(), s.noise_k.max(0.0));
    while !frontier.is_empty() {
        let depth = cells[frontier[0]].depth;
        let size = full >> depth;
        let qs: Vec<[u32; 3]> = frontier
            .iter()
            .flat_map(|&c| corners(cells[c].lo, size))
            .collect();
        lat.ensure(&qs);
        if depth == s.min_depth.min(s.max_depth) && s.relative_floor > 0.0 {
            // Mean DC over the valid samples of the min-depth lattice.
            let valid: Vec<f32> = lat
                .caps
                .iter()
                .filter(|c| c.validity >= common.validity_threshold)
                .map(|c| c.sh.coeffs()[0].length())
                .collect();
            if !valid.is_empty() {
                scale.floor = s.relative_floor * valid.iter().sum::<f32>() / valid.len() as f32;
            }
        }
        if depth == finest_depth {
            break;
        }
        let mut split = vec![false; frontier.len()];
        let mut undecided = Vec::new();
        for (fi, &ci) in frontier.iter().enumerate() {
            let c = cells[ci];
            let cmin = lat.pos(c.lo);
            let cmax = lat.pos([c.lo[0] + size, c.lo[1] + size, c.lo[2] + size]);
            let edge = (cmax - cmin).max_element();
            if depth >= s.max_depth {
                // Below `max_depth` only the emitter rule splits.
                split[fi] = emitter_cell(src, s, depth, cmin, cmax);
                continue;
            }
            let cs = corners(c.lo, size);
            let mut yes = depth < s.min_depth
                || (s.geometry && depth < s.geometry_depth && src.contains_geometry(cmin, cmax))
                || emitter_cell(src, s, depth, cmin, cmax);
            if !yes {
                if let Some(f) = s.depth_factor {
                    let hm = cs
                        .iter()
                        .map(|q| {
                            *depth_cache
                                .entry(*q)
                                .or_insert_with(|| src.depth_harmonic_mean(lat.pos(*q)))
                        })
                        .fold(f32::INFINITY, f32::min);
                    yes = edge > f * hm;
                }
            }
            if !yes {
                if let Some(t) = s.gradient_threshold {
                    // Along the 12 edges: (corner, corner with one bit set).
                    let worst = (0..8)
                        .flat_map(|a| (0..3).map(move |b| (a, b)))
                        .filter(|(a, b)| (a >> b) & 1 == 0)
                        .map(|(a, b)| {
                            let (va, vb) = (lat.sh(cs[a]), lat.sh(cs[a | (1 << b)]));
                            relative_difference(va, vb, va)
                        })
                        .fold(0.0f32, f32::max);
                    yes = worst > t;
                }
            }
            split[fi] = yes;
            if !yes && s.prediction_tolerance.is_some() {
                undecided.push(fi);
            }
        }
        if let Some(tol) = s.prediction_tolerance {
            let qs: Vec<[u32; 3]> = undecided
                .iter()
                .flat_map(|&fi| {
                    child_points(cells[frontier[fi]].lo, size)
                        .into_iter()
                        .map(|(q, _)| q)
                })
                .collect();
            lat.ensure(&qs);
            for &fi in &undecided {
                split[fi] = prediction_error(&lat, cells[frontier[fi]].lo, size, n, &scale) > tol;
            }
        }
        let mut next = Vec::new();
        for (fi, &ci) in frontier.iter().enumerate() {
            if !split[fi] {
                continue;
            }
            let c = cells[ci];
            let first = cells.len();
            cells[ci].first_child = first;
            for k in 0..8u32 {
                let h = size / 2;
                cells.push(Cell {
                    lo: [
                        c.lo[0] + h * (k & 1),
                        c.lo[1] + h * ((k >> 1) & 1),
                        c.lo[2] + h * ((k >> 2) & 1),
                    ],
                    depth: depth + 1,
                    first_child: NO_CHILD,
                });
                next.push(first + k as usize);
            }
        }
        frontier = next;
    }
    // Prune bottom-up (children are created after parents).
    if let Some(tol) = s.prune_tolerance {
        for ci in (0..cells.len()).rev() {
            let c = cells[ci];
            if c.first_child == NO_CHILD || c.depth < s.min_depth {
                continue;
            }
            let all_leaves = (0..8).all(|k| cells[c.first_child + k].first_child == NO_CHILD);
            let size = full >> c.depth;
            let kept = || {
                let hi = [c.lo[0] + size, c.lo[1] + size, c.lo[2] + size];
                emitter_cell(src, s, c.depth, lat.pos(c.lo), lat.pos(hi))
            };
            if all_leaves && !kept() && prediction_error(&lat, c.lo, size, n, &scale) <= tol {
                cells[ci].first_child = NO_CHILD;
            }
        }
    }
    if s.balance {
        balance_cells(&mut cells, &mut lat, full);
    }
    // Emit reachable nodes breadth-first (roots first); keep only samples
    // used by leaves.
    let mut order: Vec<usize> = (0..root_count).collect();
    let mut new_first = Vec::new();
    let mut i = 0;
    while i < order.len() {
        let c = cells[order[i]];
        if c.first_child != NO_CHILD {
            new_first.push((i, order.len()));
            order.extend((0..8).map(|k| c.first_child + k));
        }
        i += 1;
    }
    let mut sample_of: HashMap<usize, u32> = HashMap::new();
    let mut keep: Vec<usize> = Vec::new();
    let mut nodes = Vec::with_capacity(order.len());
    let mut lists = Vec::new();
    let mut leaf_corners: Vec<[u32; 8]> = Vec::new();
    for &ci in &order {
        let c = cells[ci];
        let size = full >> c.depth;
        let cs = corners(c.lo, size);
        let mut node = OctreeNode {
            min: lat.pos(c.lo),
            max: lat.pos(cs[7]),
            first_child: NONE,
            depth: c.depth,
            sample_offset: 0,
            sample_count: 0,
        };
        if c.first_child == NO_CHILD {
            node.sample_offset = lists.len() as u32;
            node.sample_count = 8;
            let mut lc = [0u32; 8];
            for (k, q) in cs.iter().enumerate() {
                let li = lat.index[q];
                let si = *sample_of.entry(li).or_insert_with(|| {
                    keep.push(li);
                    (keep.len() - 1) as u32
                });
                lists.push(si);
                lc[k] = si;
            }
            leaf_corners.push(lc);
        }
        nodes.push(node);
    }
    for (pos, first) in new_first {
        nodes[pos].first_child = first as u32;
    }
    let points: Vec<Vec3> = keep.iter().map(|&li| lat.pos(lat.keys[li])).collect();
    let caps: Vec<Captured> = keep.iter().map(|&li| lat.caps[li].clone()).collect();
    // Neighbours for dilation: the other corners of every leaf a sample is on.
    let mut nbrs: Vec<Vec<u32>> = vec![Vec::new(); points.len()];
    for lc in &leaf_corners {
        for &a in lc {
            for &b in lc {
                if a != b && !nbrs[a as usize].contains(&b) {
                    nbrs[a as usize].push(b);
                }
            }
        }
    }
    let mut stats = BuildStats {
        captures: lat.captures,
        samples: points.len(),
        leaves: leaf_corners.len(),
        dilated: 0,
    };
    let finest = lat.step.min_element();
    let file = finish(src, common, points, caps, &nbrs, finest, &mut stats, |f| {
        f.octree = Some(Octree {
            nodes,
            samples: lists,
            roots,
        })
    })?;
    Ok((file, stats))
}

/// Whether the emitter rule splits (and keeps split) the cell `[min, max]`
/// at `depth` ([`AdaptiveSettings::emitter_depth`]).
fn emitter_cell(
    src: &dyn VolumeSource,
    s: &AdaptiveSettings,
    depth: u32,
    min: Vec3,
    max: Vec3,
) -> bool {
    depth < s.emitter_depth && src.contains_emitter(min, max)
}

/// Splits leaves until any two leaves sharing a point (face, edge or
/// corner neighbours) differ by at most one level; captures new corners.
fn balance_cells(cells: &mut Vec<Cell>, lat: &mut Lattice, full: u32) {
    loop {
        let by_pos: HashMap<(u32, [u32; 3]), usize> = cells
            .iter()
            .enumerate()
            .map(|(i, c)| ((c.depth, c.lo), i))
            .collect();
        let is_leaf = |i: usize| cells[i].first_child == NO_CHILD;
        let mut split = Vec::new();
        for (i, c) in cells.iter().enumerate() {
            if !is_leaf(i) {
                continue;
            }
            let size = full >> c.depth;
            let mut must = false;
            'nb: for dz in -1i64..=1 {
                for dy in -1i64..=1 {
                    for dx in -1i64..=1 {
                        let q = [dx, dy, dz];
                        let lo: Option<Vec<u32>> = (0..3)
                            .map(|a| {
                                let v = c.lo[a] as i64 + q[a] * size as i64;
                                (v >= 0 && v < lat.cells[a] as i64).then_some(v as u32)
                            })
                            .collect();
                        let Some(lo) = lo else { continue };
                        let Some(&j) = by_pos.get(&(c.depth, [lo[0], lo[1], lo[2]])) else {
                            continue;
                        };
                        if !is_leaf(j) && (0..8).any(|k| !is_leaf(cells[j].first_child + k)) {
                            must = true;
                            break 'nb;
                        }
                    }
                }
            }
            if must {
                split.push(i);
            }
        }
        if split.is_empty() {
            return;
        }
        let mut qs = Vec::new();
        for &i in &split {
            let c = cells[i];
            let h = (full >> c.depth) / 2;
            cells[i].first_child = cells.len();
            for k in 0..8u32 {
                let lo = [
                    c.lo[0] + h * (k & 1),
                    c.lo[1] + h * ((k >> 1) & 1),
                    c.lo[2] + h * ((k >> 2) & 1),
                ];
                qs.extend(corners(lo, h));
                cells.push(Cell {
                    lo,
                    depth: c.depth + 1,
                    first_child: NO_CHILD,
                });
            }
        }
        lat.ensure(&qs);
    }
}

/// Dilation, gradients and file assembly shared by both builders.
#[allow(clippy::too_many_arguments)]
fn finish(
    src: &dyn VolumeSource,
    common: &CommonSettings,
    points: Vec<Vec3>,
    caps: Vec<Captured>,
    nbrs: &[Vec<u32>],
    finest_cell: f32,
    stats: &mut BuildStats,
    structure: impl FnOnce(&mut ProbeFile),
) -> Result<ProbeFile, VolumeBuildError> {
    let order = src.order();
    let n = order * order;
    let mut coeffs: Vec<Vec3> = Vec::with_capacity(points.len() * n);
    for c in &caps {
        if c.sh.coeffs().len() != n {
            return Err(VolumeBuildError::SourceOrder);
        }
        coeffs.extend_from_slice(c.sh.coeffs());
    }
    let valid: Vec<bool> = caps
        .iter()
        .map(|c| c.validity.is_finite() && c.validity >= common.validity_threshold)
        .collect();
    let weights: Vec<f32> = caps.iter().map(|c| c.validity.clamp(0.0, 1.0)).collect();
    stats.dilated = dilate(&mut coeffs, n, &valid, &weights, nbrs)?;
    let gradients = match common.gradients {
        GradientMode::None => None,
        GradientMode::Analytic => Some(
            src.analytic_gradients(&points)
                .ok_or(VolumeBuildError::NoAnalyticGradients)?,
        ),
        GradientMode::Central { step } => {
            let step = if step > 0.0 {
                step
            } else {
                DEFAULT_STEP_FRACTION * finest_cell
            };
            stats.captures += points.len() * 6;
            Some(src.central_gradients(&points, step))
        }
    };
    if let Some(g) = &gradients {
        if g.len() != points.len() * 3 * n || g.iter().any(|v| !v.is_finite()) {
            return Err(VolumeBuildError::SourceOrder);
        }
    }
    let validity = caps
        .iter()
        .zip(&valid)
        .map(|(c, &ok)| Validity {
            value: if c.validity.is_finite() {
                c.validity
            } else {
                0.0
            },
            flags: if ok { 0 } else { VALIDITY_INVALID }
                | if c.virtual_offset {
                    VALIDITY_VIRTUAL_OFFSET
                } else {
                    0
                },
        })
        .collect();
    let mut file = ProbeFile {
        positions: points,
        validity: Some(validity),
        gradients: gradients.map(|data| Gradients {
            order: order as u32,
            data,
        }),
        ..ProbeFile::new(
            ProbeFileKind::Volume,
            Coefficients::from_f32(order as u32, &coeffs)?,
        )
    };
    structure(&mut file);
    file.validate()?;
    Ok(file)
}

/// Keeps only the first `order` bands of a volume's stored gradients (the
/// runtime interpolates the other bands trilinearly, under Taylor and
/// tricubic alike). Gradients cost `3·order²` RGB vectors per
/// sample, 3× the L2 coefficients themselves; most of the irradiance's
/// change is in the low bands (BENCHMARKS.md, "Gradient order"). A file
/// without gradients, or with `order` at least theirs, is left unchanged.
pub fn truncate_gradients(file: &mut ProbeFile, order: u32) -> Result<(), VolumeBuildError> {
    let Some(g) = &mut file.gradients else {
        return Ok(());
    };
    if order == 0 {
        return Err(VolumeBuildError::BadGradientOrder(order));
    }
    if order >= g.order {
        return Ok(());
    }
    let (old, new) = ((g.order * g.order) as usize, (order * order) as usize);
    if g.data.len() % old != 0 {
        return Err(VolumeBuildError::SourceOrder);
    }
    g.data = g
        .data
        .chunks_exact(old)
        .flat_map(|c| c[..new].iter().copied())
        .collect();
    g.order = order;
    file.validate()?;
    Ok(())
}

/// Replaces every invalid sample by the validity-weighted average of its
/// valid (or already dilated) neighbours, ring by ring (Jacobi order, so the
/// result does not depend on sample order). Dilated samples take part in
/// later rings with half the weight of their sources. Returns the number of
/// samples replaced; fails only if no sample is valid.
pub fn dilate(
    coeffs: &mut [Vec3],
    n: usize,
    valid: &[bool],
    validity: &[f32],
    nbrs: &[Vec<u32>],
) -> Result<usize, VolumeBuildError> {
    let count = valid.len();
    let mut known: Vec<Option<f32>> = (0..count)
        .map(|i| valid[i].then_some(validity[i].max(1e-3)))
        .collect();
    let todo = known.iter().filter(|k| k.is_none()).count();
    if todo == 0 {
        return Ok(0);
    }
    if todo == count {
        return Err(VolumeBuildError::NoValidSamples);
    }
    let mut replaced = 0;
    loop {
        let mut updates = Vec::new();
        for i in 0..count {
            if known[i].is_some() {
                continue;
            }
            let mut acc = vec![Vec3::ZERO; n];
            let mut wsum = 0.0f32;
            for &j in &nbrs[i] {
                if let Some(w) = known[j as usize] {
                    wsum += w;
                    for k in 0..n {
                        acc[k] += coeffs[j as usize * n + k] * w;
                    }
                }
            }
            if wsum > 0.0 {
                acc.iter_mut().for_each(|a| *a /= wsum);
                let w = 0.5 * wsum / nbrs[i].len().max(1) as f32;
                updates.push((i, acc, w));
            }
        }
        if updates.is_empty() {
            // Disconnected invalid samples: nothing reaches them.
            return Err(VolumeBuildError::NoValidSamples);
        }
        for (i, acc, w) in updates {
            coeffs[i * n..(i + 1) * n].copy_from_slice(&acc);
            known[i] = Some(w.max(1e-6));
            replaced += 1;
        }
        if replaced == todo {
            return Ok(replaced);
        }
    }
}
