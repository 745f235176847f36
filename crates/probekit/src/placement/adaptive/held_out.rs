//! Held-out error: the relative RMSE of two placements at stratified
//! held-out points, to choose between placing with and without light
//! shells.

use super::has_clearance;
use super::pool::jittered;
use super::scoring::{band_weights, energy, scoring_weights, sq_error};
use crate::delaunay::tetrahedralize;
use crate::placement::{PlacementError, State};
use crate::query::blend_sh;
use crate::sampling::hash3;
use crate::scene::{Aabb, Light, LightKind};
use glam::Vec3;
use probekit_runtime::cloud::{TetMesh, WalkState};
use probekit_sh::ShRgb;
use rayon::prelude::*;

/// Seed salt of the held-out points of [`held_out_errors`].
const HELD_OUT_SALT: u64 = 0x0048_454c_444f_5554;

/// First capture index of the held-out points: far above any probe's or
/// candidate's, so their random numbers are their own.
const HELD_OUT_FIRST_INDEX: usize = 1 << 40;

/// Radius, metres, of the ball around each positional light in which
/// [`held_out_points`] samples more densely.
const HELD_OUT_LIGHT_RADIUS: f32 = 1.0;

/// Share of the held-out points that go into the balls around lights
/// (split evenly between the lights) when the scene has any.
const HELD_OUT_LIGHT_SHARE: f32 = 0.5;

/// Fewest held-out points [`held_out_errors`] draws (before those without
/// clearance are dropped); above it, `2·budget`, up to [`HELD_OUT_MAX`].
/// With 512 (the old floor) one duplex placement at ~500 scored its
/// shell-less twin 0.71 against 0.86 with shells, and 4096 points scored
/// them 0.80 against 0.80 and chose the shells, which were far better
/// (0.67 against 0.93 on 13 000 evaluation points; BENCHMARKS.md, "Away
/// from the lamps"): at 64 points per lamp the choice was noise. Costs
/// about 3 600 more captures at small budgets.
const HELD_OUT_MIN: usize = 4096;

/// Most held-out points [`held_out_errors`] draws.
const HELD_OUT_MAX: usize = 8192;

/// About `n` held-out points in `bbox` with their volume weights (m³ each
/// stands for), stratified: with positional lights in the scene, half of the
/// points lie in balls of [`HELD_OUT_LIGHT_RADIUS`] around them and half
/// in the rest of the box, each stratum jittered-uniform (a point in the
/// overlap of two balls belongs to the first). The weighted sums over the
/// points estimate integrals over the box exactly as uniform points would
/// (each stratum's weight is its sampling volume over its point count), with
/// far less variance where the error is concentrated: next to a light a
/// few points decide the relative RMSE, and a uniform set of a few hundred
/// points holds none or one of them, so with it the comparison of two
/// placements was close to a coin flip (BENCHMARKS.md, "Held-out points
/// near the lights"). Points are not yet checked for free space.
pub(crate) fn held_out_points(
    lights: &[Light],
    bbox: &Aabb,
    n: usize,
    seed: u64,
) -> Vec<(Vec3, f32)> {
    let centres: Vec<Vec3> = lights
        .iter()
        .filter(|l| l.kind != LightKind::Directional && l.position.is_finite())
        .map(|l| l.position)
        .filter(|&c| {
            // The ball reaches into the box.
            c.clamp(bbox.min, bbox.max).distance(c) < HELD_OUT_LIGHT_RADIUS
        })
        .collect();
    let r = HELD_OUT_LIGHT_RADIUS;
    let in_ball = |p: Vec3, upto: usize| {
        centres[..upto]
            .iter()
            .any(|c| c.distance_squared(p) < r * r)
    };
    let n_balls = if centres.is_empty() {
        0
    } else {
        (HELD_OUT_LIGHT_SHARE * n as f32) as usize
    };
    let mut out = Vec::with_capacity(n + n_balls);
    let uniform = jittered(bbox, n - n_balls, seed, None);
    let size = bbox.size();
    let w = size.x * size.y * size.z / uniform.len().max(1) as f32;
    out.extend(
        uniform
            .into_iter()
            .filter(|&p| !in_ball(p, centres.len()))
            .map(|p| (p, w)),
    );
    for (j, &c) in centres.iter().enumerate() {
        let cube = Aabb::new(c - Vec3::splat(r), c + Vec3::splat(r));
        let pts = jittered(&cube, n_balls / centres.len(), seed ^ (j as u64 + 1), None);
        let w = (2.0 * r).powi(3) / pts.len().max(1) as f32;
        out.extend(
            pts.into_iter()
                .filter(|&p| c.distance_squared(p) < r * r && !in_ball(p, j) && bbox.contains(p))
                .map(|p| (p, w)),
        );
    }
    out
}

/// Receiver samples per held-out point (at most the placement's): half
/// the pool's. The choice compares two placements' errors at the same
/// points, to which a point's capture noise adds the same variance, so the
/// noise enters the difference only through a cross term; and the error
/// is decided by the points next to the lamps, where stratified light
/// samples leave a quarter of the noise of independent ones at the same
/// count (`capture::stratified_tests`). Measured on the demo's default
/// bake (BENCHMARKS.md, "Where a bake's time goes").
const HELD_OUT_SAMPLES: u32 = 128;

/// Captured points of free space: (position, radiance SH).
type FreePoints = Vec<(Vec3, ShRgb)>;

/// Held-out points captured per round of [`held_out_errors`].
const HELD_OUT_ROUND: usize = 1024;

/// [`held_out_errors`] stops once the two placements' weighted squared
/// errors differ by this many standard errors of the difference.
const HELD_OUT_DECISIVE: f64 = 3.0;

/// The relative RMSE (`sqrt(Σ err / Σ mean-square irradiance)`, as
/// [`Adaptive::rel_rmse`]) of the interpolation of each placement in
/// `candidates` (barycentric, or with the vertices hidden from the point
/// dropped where they hold most of its weight: [`scoring_weights`]) at
/// held-out points of [`held_out_points`] in free space of `bbox` (as the
/// pool, with [`PROBE_CLEARANCE`](super::PROBE_CLEARANCE)), each sum
/// weighted by the volume its point stands for, captured with `st`'s
/// settings and their own random numbers. A placement whose tetrahedra the
/// runtime rejects scores infinity.
///
/// The points (about `2·budget`, [`HELD_OUT_MIN`] to [`HELD_OUT_MAX`]) are
/// visited in a fixed shuffled order, so every prefix is a random subset of
/// the stratified set (the volume weights then change by one common
/// factor, which the ratio cancels), and captured [`HELD_OUT_ROUND`] at a
/// time: it stops once the difference of the two placements' weighted
/// squared errors exceeds [`HELD_OUT_DECISIVE`] standard errors of that
/// difference (estimated from the points' paired differences), a measured
/// target instead of a fixed count; when they stay that close, all points
/// are used. Also returns the captured held-out points (position, SH):
/// points of free space, training points for the probe-weight fit.
pub(in crate::placement) fn held_out_errors(
    st: &mut State,
    bbox: &Aabb,
    budget: usize,
    candidates: [&State; 2],
) -> Result<([f32; 2], FreePoints), PlacementError> {
    let tracer = st.baker.tracer();
    let salt = st.settings.seed ^ HELD_OUT_SALT;
    let mut pts: Vec<(Vec3, f32)> = held_out_points(
        &st.baker.scene().lights,
        bbox,
        (2 * budget).clamp(HELD_OUT_MIN, HELD_OUT_MAX),
        salt,
    )
    .into_par_iter()
    .filter(|(p, _)| has_clearance(tracer, *p))
    .collect();
    // A fixed shuffle: sorted by a hash of the point's place in the list.
    let mut keyed: Vec<(u64, (Vec3, f32))> = pts
        .drain(..)
        .enumerate()
        .map(|(i, p)| (hash3(salt, 0x5348_5546, i as u64), p))
        .collect();
    keyed.sort_by_key(|k| k.0);
    let pts: Vec<(Vec3, f32)> = keyed.into_iter().map(|k| k.1).collect();
    let meshes: Vec<Option<TetMesh>> = candidates
        .iter()
        .map(|c| {
            let tri = tetrahedralize(&c.positions)?;
            Ok(tri.to_tet_mesh(&c.positions).ok())
        })
        .collect::<Result<_, PlacementError>>()?;
    // Per captured point: its volume-weighted energy and the two errors.
    let mut rows: Vec<(f64, [f64; 2])> = Vec::new();
    let mut captured_points = Vec::new();
    let mut w: Option<Vec<f32>> = None;
    let mut at = 0;
    while at < pts.len() {
        let end = (at + HELD_OUT_ROUND).min(pts.len());
        let round: Vec<Vec3> = pts[at..end].iter().map(|(p, _)| *p).collect();
        // (point, volume weight, captured SH), in free space of the box.
        let samples = st.settings.samples;
        st.settings.samples = samples.min(HELD_OUT_SAMPLES);
        let captured = st.capture_free(&round, HELD_OUT_FIRST_INDEX + at);
        st.settings.samples = samples;
        let captured: Vec<(Vec3, f32, ShRgb)> = captured?
            .into_iter()
            .zip(&pts[at..end])
            .filter_map(|(c, &(_, v))| c.map(|(p, sh)| (p, v, sh)))
            .filter(|(p, _, _)| bbox.contains(*p))
            .collect();
        at = end;
        let Some(first) = captured.first() else {
            continue;
        };
        let w = w.get_or_insert_with(|| band_weights(first.2.order()));
        // Per-chunk rows collected in order: the same for any thread count.
        const CHUNK: usize = 256;
        let part: Vec<(f64, [f64; 2])> = captured
            .par_chunks(CHUNK)
            .flat_map_iter(|chunk| {
                let mut ws = [WalkState::new(), WalkState::new()];
                chunk
                    .iter()
                    .map(|(p, v, cap)| {
                        let e = core::array::from_fn(|k| {
                            let Some(mesh) = &meshes[k] else {
                                return 0.0;
                            };
                            let c = candidates[k];
                            let (idx, wt) = mesh.weights_at(*p, &mut ws[k]);
                            let (vw, _) = scoring_weights(tracer, &c.positions, *p, idx, wt);
                            let pred = blend_sh(&c.sh, idx, vw, cap.order());
                            *v as f64 * sq_error(w, &pred, cap) as f64
                        });
                        (*v as f64 * energy(w, cap) as f64, e)
                    })
                    .collect::<Vec<_>>()
            })
            .collect();
        rows.extend(part);
        captured_points.extend(captured.into_iter().map(|(p, _, sh)| (p, sh)));
        if meshes.iter().any(Option::is_none) || decisive(&rows) {
            break;
        }
    }
    let total: f64 = rows.iter().map(|r| r.0).sum();
    let mut out = [f32::INFINITY; 2];
    for (k, o) in out.iter_mut().enumerate() {
        if meshes[k].is_some() && total > 0.0 {
            let err: f64 = rows.iter().map(|r| r.1[k]).sum();
            *o = (err / total).sqrt() as f32;
        }
    }
    Ok((out, captured_points))
}

/// Whether the rows' summed squared errors of the two placements differ by
/// more than [`HELD_OUT_DECISIVE`] standard errors of the sum of the
/// paired differences (`√n` times their sample standard deviation).
fn decisive(rows: &[(f64, [f64; 2])]) -> bool {
    let n = rows.len() as f64;
    if rows.len() < 2 {
        return false;
    }
    let d: Vec<f64> = rows.iter().map(|r| r.1[0] - r.1[1]).collect();
    let sum: f64 = d.iter().sum();
    let mean = sum / n;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    sum.abs() > HELD_OUT_DECISIVE * (n * var).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stopping rule against its definition: a clear, consistent
    /// difference decides; noise around zero does not.
    #[test]
    fn a_consistent_difference_decides_and_noise_does_not() {
        let clear: Vec<(f64, [f64; 2])> = (0..100)
            .map(|i| (1.0, [1.0 + 0.01 * (i % 7) as f64, 0.5]))
            .collect();
        assert!(decisive(&clear));
        let noise: Vec<(f64, [f64; 2])> = (0..100)
            .map(|i| (1.0, [1.0 + if i % 2 == 0 { 0.3 } else { -0.3 }, 1.0]))
            .collect();
        assert!(!decisive(&noise));
        assert!(!decisive(&clear[..1]));
        // By hand: differences 1, 3 (sum 4, sd √2, SE 2): 2 SE, not 3.
        assert!(!decisive(&[(1.0, [2.0, 1.0]), (1.0, [4.0, 1.0])]));
        // 1, 1.1, 0.9: sum 3, sd 0.1, SE 0.173: 17 SE.
        assert!(decisive(&[
            (1.0, [2.0, 1.0]),
            (1.0, [2.1, 1.0]),
            (1.0, [1.9, 1.0])
        ]));
    }
}
