//! Adaptive volumes: an octree refined where the trilinear prediction of
//! the children misses the captured lighting (Tatarchuk 2005, "Irradiance
//! Volumes for Games", adaptive subdivision), balanced and written as a file.

use super::finish::{finish, relative_difference};
use super::lattice::{child_points, corners, Cell, Lattice, NO_CHILD};
use super::settings::{check_box, near_cubic_roots, AdaptiveSettings, BuildStats};
use super::source::{Captured, VolumeSource};
use super::VolumeBuildError;
use crate::format::lattice_step;
use crate::format::{layout::NONE, Octree, OctreeNode, ProbeFile, VolumeStructure};
use glam::Vec3;
use std::collections::HashMap;

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

/// Adaptive octree (Tatarchuk 2005, "Adaptive Octree Subdivision"): cells split by
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
    let structure = VolumeStructure::Adaptive(Octree {
        nodes,
        samples: lists,
        roots,
    });
    let file = finish(
        src, common, points, caps, &nbrs, finest, &mut stats, structure,
    )?;
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
