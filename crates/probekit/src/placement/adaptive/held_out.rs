//! Held-out error: the relative RMSE of two placements at stratified
//! held-out points, to choose between placing with and without light
//! shells.

use super::has_clearance;
use super::pool::jittered;
use super::scoring::{band_weights, energy, scoring_weights, sq_error};
use crate::delaunay::tetrahedralize;
use crate::placement::{PlacementError, State};
use crate::query::blend_sh;
use crate::scene::{Aabb, Light, LightKind};
use glam::Vec3;
use probekit_runtime::cloud::WalkState;
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
pub(super) fn held_out_points(
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

/// The relative RMSE (`sqrt(Σ err / Σ mean-square irradiance)`, as
/// [`Adaptive::rel_rmse`]) of the interpolation of each placement in
/// `candidates` (barycentric, or with the vertices hidden from the point
/// dropped where they hold most of its weight: [`scoring_weights`]) at
/// held-out points: about `2·budget` ([`HELD_OUT_MIN`] to [`HELD_OUT_MAX`])
/// points of [`held_out_points`] in free space of `bbox` (as the pool, with
/// [`PROBE_CLEARANCE`](super::PROBE_CLEARANCE)), each sum weighted by the volume its point
/// stands for, captured with `st`'s settings and their own random numbers.
/// A placement whose tetrahedra the runtime rejects scores infinity.
/// Also returns the captured held-out points (position, SH): points of free
/// space, training points for the probe-weight fit.
pub(in crate::placement) fn held_out_errors(
    st: &mut State,
    bbox: &Aabb,
    budget: usize,
    candidates: [&State; 2],
) -> Result<([f32; 2], Vec<(Vec3, ShRgb)>), PlacementError> {
    let tracer = st.baker.tracer();
    let pts: Vec<(Vec3, f32)> = held_out_points(
        &st.baker.scene().lights,
        bbox,
        (2 * budget).clamp(HELD_OUT_MIN, HELD_OUT_MAX),
        st.settings.seed ^ HELD_OUT_SALT,
    )
    .into_par_iter()
    .filter(|(p, _)| has_clearance(tracer, *p))
    .collect();
    let at: Vec<Vec3> = pts.iter().map(|(p, _)| *p).collect();
    // (point, volume weight, captured SH), in free space of the box.
    let captured: Vec<(Vec3, f32, ShRgb)> = st
        .capture_free(&at, HELD_OUT_FIRST_INDEX)?
        .into_iter()
        .zip(&pts)
        .filter_map(|(c, &(_, w))| c.map(|(p, sh)| (p, w, sh)))
        .filter(|(p, _, _)| bbox.contains(*p))
        .collect();
    let order = captured.first().map_or(1, |c| c.2.order());
    let w = band_weights(order);
    let total: f64 = captured
        .iter()
        .map(|(_, v, s)| *v as f64 * energy(&w, s) as f64)
        .sum();
    let mut out = [f32::INFINITY; 2];
    for (o, c) in out.iter_mut().zip(candidates) {
        let tri = tetrahedralize(&c.positions)?;
        let Ok(mesh) = tri.to_tet_mesh(&c.positions) else {
            continue;
        };
        // Per-chunk sums collected in order, then added in order: the same
        // bits for any thread count.
        const CHUNK: usize = 256;
        let parts: Vec<f64> = captured
            .par_chunks(CHUNK)
            .map(|chunk| {
                let mut ws = WalkState::new();
                chunk
                    .iter()
                    .map(|(p, v, cap)| {
                        let (idx, wt) = mesh.weights_at(*p, &mut ws);
                        let (vw, _) = scoring_weights(tracer, &c.positions, *p, idx, wt);
                        let pred = blend_sh(&c.sh, idx, vw, cap.order());
                        *v as f64 * sq_error(&w, &pred, cap) as f64
                    })
                    .sum::<f64>()
            })
            .collect();
        let err: f64 = parts.iter().sum();
        if total > 0.0 {
            *o = (err / total).sqrt() as f32;
        }
    }
    let points = captured.into_iter().map(|(p, _, sh)| (p, sh)).collect();
    Ok((out, points))
}
