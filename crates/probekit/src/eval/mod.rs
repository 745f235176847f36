//! # Evaluating probe sets against path-traced ground truth
//!
//! Sample points in free space of a bake box (not inside geometry, not within
//! 1 cm of a surface) with random unit normals
//! ([`sample_points`](crate::trace::free_space::sample_points)), compute
//! reference irradiance with [`Baker::reference_irradiance`], and compare an
//! interpolation (a baked file loaded as the runtime's
//! [`Probes`], queried by [`predict`]).
//! Placement comparisons and budget sweeps are [`crate::pipeline::sweep`].
//!
//! Metrics (RGB irradiance `E`, not divided by π):
//! * `rel_rmse = sqrt(mean |E_pred − E_true|²) / sqrt(mean |E_true|²)` (normalised RMSE);
//! * `p95_rel_error`: 95th percentile of `|E_pred − E_true| / (|E_true| + 0.01·mean|E_true|)`;
//! * `leaks`: points whose interpolated luminance exceeds 4× the true
//!   luminance plus 1 % of the mean true luminance;
//! * `leaks_through_geometry` (clouds): those leaks whose blend gives weight
//!   to a probe that geometry hides from the point
//!   ([`blends_hidden_probes`](crate::query::blends_hidden_probes)) — light from behind a wall, as
//!   against an error of interpolating light in sight;
//! * `points_outside_hull` and `leaks_outside_hull` (clouds,
//!   [`outside_hull`](crate::query::outside_hull)): the points outside the probes' convex hull, lit
//!   from its outer cells, and the leaks among them;
//! * `unlit_points` and `leaks_unlit` ([`unlit_points`]): the points whose
//!   true irradiance is exactly 0 — sealed voids inside walls and between
//!   floor slabs, which the free-space test cannot tell from rooms — and
//!   the leaks among them (counted in `leaks` too).

#[cfg(test)]
mod tests;

mod report;
use crate::capture::{BakeError, Baker, ReferenceSettings};
use crate::query::blend_sh;
use crate::scene::Region;
use crate::trace::free_space::EvalPoint;
use glam::Vec3;
use probekit_runtime::cloud::{TetMesh, WalkState};
use probekit_runtime::{Probes, QueryError};
use probekit_sh::ShRgb;
pub use report::{evaluate, BlendProbe, EvalReport, RegionReport, WorstReport};

/// The irradiance of `probes` at every point for its normal, in order,
/// through the runtime's batched query (one `ObjectState` for the batch):
/// what an engine shows there.
pub fn predict(probes: &Probes, points: &[EvalPoint]) -> Result<Vec<Vec3>, QueryError> {
    let pairs: Vec<(Vec3, Vec3)> = points.iter().map(|p| (p.position, p.normal)).collect();
    let e = crate::query::irradiance_at(probes, &pairs)?;
    Ok(e.into_iter().map(Vec3::from_array).collect())
}

/// Reference irradiance at each point (index = row number).
pub fn reference(
    baker: &Baker,
    points: &[EvalPoint],
    s: &ReferenceSettings,
) -> Result<Vec<Vec3>, BakeError> {
    reference_with_progress(baker, points, s, &|_, _| {})
}

/// [`reference()`], calling `progress(done, total)` after each point (the
/// points run in order, each in parallel over its sample batches).
pub fn reference_with_progress(
    baker: &Baker,
    points: &[EvalPoint],
    s: &ReferenceSettings,
    progress: &dyn Fn(usize, usize),
) -> Result<Vec<Vec3>, BakeError> {
    points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let e = baker.reference_irradiance(p.position, p.normal, i as u64, s)?;
            progress(i + 1, points.len());
            Ok(e.irradiance)
        })
        .collect()
}

/// The reference irradiance `probekit eval` uses ([`reference()`] at 3 %
/// relative precision), read from `cache` when that file holds exactly one
/// RGB `f32` triple per point (little-endian), else computed and written
/// there (a failed write is ignored: the cache is only an optimisation).
/// The caller keys the file name by everything the truth depends on — see
/// [`reference_cache_path`].
pub fn reference_cached(
    baker: &Baker,
    points: &[EvalPoint],
    cache: &std::path::Path,
) -> Result<Vec<Vec3>, BakeError> {
    if let Ok(b) = std::fs::read(cache) {
        if b.len() == 12 * points.len() {
            return Ok(b
                .chunks_exact(12)
                .map(|c| {
                    let f = |k: usize| f32::from_le_bytes([c[k], c[k + 1], c[k + 2], c[k + 3]]);
                    Vec3::new(f(0), f(4), f(8))
                })
                .collect());
        }
    }
    let rs = ReferenceSettings {
        relative_precision: 0.03,
        ..Default::default()
    };
    let t = reference(baker, points, &rs)?;
    let bytes: Vec<u8> = t
        .iter()
        .flat_map(|v| v.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let _ = crate::format::write_atomic(cache, &bytes);
    Ok(t)
}

/// A cache file for [`reference_cached`] in the system's temporary
/// directory, keyed by the scene's content hash and a hash of the points
/// themselves (positions and normals, bit for bit) and of the reference
/// version ([`REFERENCE_VERSION`]): a change to how
/// [`sample_points`](crate::trace::free_space::sample_points) picks
/// points, or to the reference, gets a new file instead of another point
/// set's truth (a count and a seed alone do not tell).
pub fn reference_cache_path(scene_hash: u64, points: &[EvalPoint]) -> std::path::PathBuf {
    let mut h = crate::scene::Fnv1a::new();
    h.u32(REFERENCE_VERSION);
    h.u64(points.len() as u64);
    for p in points {
        h.vec3(p.position);
        h.vec3(p.normal);
    }
    std::env::temp_dir().join(format!(
        "probekit_truth_{scene_hash:016x}_{:016x}_{}.bin",
        h.0,
        points.len()
    ))
}

/// Bumped whenever [`reference_cached`]'s reference changes (precision,
/// integrator), so cached truth of an older one is not read.
pub const REFERENCE_VERSION: u32 = 1;

/// Error figures of a prediction against ground truth.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Metrics {
    /// Points evaluated.
    pub points: usize,
    /// Normalised RMSE (see the module docs).
    pub rel_rmse: f32,
    /// 95th percentile of the per-point relative error.
    pub p95_rel_error: f32,
    /// Leak count.
    pub leaks: usize,
}

fn lum(v: Vec3) -> f32 {
    probekit_sh::LUMINANCE.dot(v)
}

/// The luminance above which an interpolated irradiance counts as a leak
/// (module docs): 4× the true luminance of `truth` plus 1 % of
/// `mean_truth_lum`, the mean true luminance over the evaluated points.
pub fn leak_threshold(truth: Vec3, mean_truth_lum: f32) -> f32 {
    4.0 * lum(truth) + 0.01 * mean_truth_lum
}

/// Whether interpolated irradiance `pred` leaks against `truth`: its
/// luminance exceeds [`leak_threshold`].
pub fn is_leak(pred: Vec3, truth: Vec3, mean_truth_lum: f32) -> bool {
    lum(pred) > leak_threshold(truth, mean_truth_lum)
}

/// Metrics of `pred` against `truth`; `mean_truth_lum` is the mean true
/// luminance over all evaluated points (the leak floor uses it, also for a
/// region's subset).
pub fn metrics(pred: &[Vec3], truth: &[Vec3], mean_truth_lum: f32) -> Metrics {
    let n = pred.len().min(truth.len());
    if n == 0 {
        return Metrics {
            points: 0,
            rel_rmse: 0.0,
            p95_rel_error: 0.0,
            leaks: 0,
        };
    }
    let mean_abs = truth[..n].iter().map(|t| t.length() as f64).sum::<f64>() / n as f64;
    let (mut se, mut st) = (0.0f64, 0.0f64);
    let mut rel = Vec::with_capacity(n);
    let mut leaks = 0;
    for (p, t) in pred.iter().zip(truth).take(n) {
        se += (*p - *t).length_squared() as f64;
        st += t.length_squared() as f64;
        rel.push((*p - *t).length() / (t.length() + 0.01 * mean_abs as f32).max(1e-12));
        if is_leak(*p, *t, mean_truth_lum) {
            leaks += 1;
        }
    }
    rel.sort_by(f32::total_cmp);
    let k = ((0.95 * n as f32).ceil() as usize).clamp(1, n) - 1;
    Metrics {
        points: n,
        rel_rmse: if st > 0.0 {
            (se / st).sqrt() as f32
        } else {
            0.0
        },
        p95_rel_error: rel[k],
        leaks,
    }
}

/// One of the points that carry the most error ([`worst_points`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorstPoint {
    /// Index into the evaluated points.
    pub index: usize,
    /// Its share of the summed squared error `Σ |E_pred − E_true|²` over all
    /// points, in `0..=1`: the share of `rel_rmse²` it accounts for.
    pub share: f32,
}

/// The `k` points with the largest squared error `|E_pred − E_true|²` (RGB,
/// as `rel_rmse` sums it), largest first (ties: lower index first), with
/// their shares of the summed squared error. On a scene with small bright
/// lights a handful of points next to them can carry most of `rel_rmse`
/// (the duplex apartment: one point 35 cm from a sphere light held 43 % of
/// a grid's squared error, BENCHMARKS.md "The duplex at ~500"), which this
/// shows before one reads too much into a single figure. Empty when no
/// point has any error.
pub fn worst_points(pred: &[Vec3], truth: &[Vec3], k: usize) -> Vec<WorstPoint> {
    let n = pred.len().min(truth.len());
    let se: Vec<f64> = (0..n)
        .map(|i| (pred[i] - truth[i]).length_squared() as f64)
        .collect();
    let total: f64 = se.iter().sum();
    if !(total.is_finite() && total > 0.0) {
        return Vec::new();
    }
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&a, &b| se[b].total_cmp(&se[a]).then(a.cmp(&b)));
    idx.into_iter()
        .take(k)
        .map(|i| WorstPoint {
            index: i,
            share: (se[i] / total) as f32,
        })
        .collect()
}

/// Leaks ([`is_leak`]) at the points flagged in `flags`: with the flags of
/// [`blends_hidden_probes`](crate::query::blends_hidden_probes) (the blend gives weight to a probe that
/// geometry hides from the point) the leaks through geometry, light that
/// comes through a wall, as against an error of interpolating light in
/// sight; with those of [`outside_hull`](crate::query::outside_hull) the leaks of points lit from the
/// hull's outer cells.
pub fn leaks_at(pred: &[Vec3], truth: &[Vec3], mean_truth_lum: f32, flags: &[bool]) -> usize {
    pred.iter()
        .zip(truth)
        .zip(flags)
        .filter(|((&p, &t), &f)| f && is_leak(p, t, mean_truth_lum))
        .count()
}

/// `(points, leaks)`: how many evaluation points have a true irradiance of
/// exactly 0 in every channel — no path of the reference reached a light
/// from them, which in a scene with lights or a sky means a sealed void (a
/// cavity inside a wall, the gap between a ceiling and the floor slab
/// above, modelled as separate closed boxes), free space to the
/// inside-geometry test but nowhere an object can be — and how many of them
/// leak ([`is_leak`]: there, any blend above 1 % of `mean_truth_lum`). The
/// duplex apartment has 858 such points of 13 000 (BENCHMARKS.md,
/// "Hidden-cell fallback"); these leaks are part of `leaks`.
pub fn unlit_points(pred: &[Vec3], truth: &[Vec3], mean_truth_lum: f32) -> (usize, usize) {
    let mut out = (0, 0);
    for (&p, &t) in pred.iter().zip(truth) {
        if t == Vec3::ZERO {
            out.0 += 1;
            if is_leak(p, t, mean_truth_lum) {
                out.1 += 1;
            }
        }
    }
    out
}

/// [`leaks_at`] the flagged points inside each region, in the regions'
/// order (as [`region_metrics`]; `flags` covers all points).
pub fn region_leaks_at(
    regions: &[Region],
    points: &[EvalPoint],
    pred: &[Vec3],
    truth: &[Vec3],
    mean_truth_lum: f32,
    flags: &[bool],
) -> Vec<usize> {
    regions
        .iter()
        .map(|r| {
            let bb = r.aabb();
            let inside: Vec<bool> = points
                .iter()
                .zip(flags)
                .map(|(p, &f)| f && bb.contains(p.position))
                .collect();
            leaks_at(pred, truth, mean_truth_lum, &inside)
        })
        .collect()
}

/// [`metrics`] of the points inside each region, in the regions' order;
/// the leak threshold still uses `mean_truth_lum`, the mean over all points,
/// so a region's leaks are the overall leaks that fall inside it.
pub fn region_metrics<'r>(
    regions: &'r [Region],
    points: &[EvalPoint],
    pred: &[Vec3],
    truth: &[Vec3],
    mean_truth_lum: f32,
) -> Vec<(&'r Region, Metrics)> {
    regions
        .iter()
        .map(|r| {
            let bb = r.aabb();
            let (p, t): (Vec<Vec3>, Vec<Vec3>) = points
                .iter()
                .zip(pred.iter().zip(truth))
                .filter(|(pt, _)| bb.contains(pt.position))
                .map(|(_, (&p, &t))| (p, t))
                .unzip();
            (r, metrics(&p, &t, mean_truth_lum))
        })
        .collect()
}

/// Mean luminance of `truth`.
pub fn mean_luminance(truth: &[Vec3]) -> f32 {
    if truth.is_empty() {
        0.0
    } else {
        truth.iter().map(|t| lum(*t)).sum::<f32>() / truth.len() as f32
    }
}

/// Interpolated irradiance of a probe cloud (radiance SH per probe, blended
/// with the mesh's barycentric weights, then convolved) at each point.
pub fn interpolate_cloud(mesh: &TetMesh, sh: &[ShRgb], points: &[EvalPoint]) -> Vec<Vec3> {
    let mut ws = WalkState::new();
    let order = sh.first().map_or(1, |s| s.order());
    points
        .iter()
        .map(|p| {
            let (idx, w) = mesh.weights_at(p.position, &mut ws);
            blend_sh(sh, idx, w, order).irradiance(p.normal)
        })
        .collect()
}
