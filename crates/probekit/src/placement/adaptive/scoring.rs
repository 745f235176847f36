//! Scoring the pool: the squared irradiance error of the interpolation at
//! every pool point (with the blend the baked cloud's visibility would use),
//! its ranking weight, and the leak test.

use super::Adaptive;
use crate::delaunay::tetrahedralize;
use crate::placement::PlacementError;
use crate::query::blend_sh;
use crate::trace::free_space::segment_clear;
use glam::Vec3;
use probekit_runtime::cloud::WalkState;
use probekit_sh::convolve::clamped_cosine_band;
use probekit_sh::ShRgb;
use rayon::prelude::*;

/// Weight of the relative error in the ranking (see [`Adaptive::score`]).
const RELATIVE_WEIGHT: f32 = 0.05;

/// The ranking multiplies each point's error by `d^SPACING_EXPONENT`, `d`
/// its distance to the nearest probe of its tetrahedron: a point far from
/// probes stands for more volume than one next to them (`d³` would be the
/// volume itself). Measured on builtin:demo (BENCHMARKS.md, "Placement against uniform grids"): 1.5
/// beat 0 and 3 at 500 probes and tied at 2000.
const SPACING_EXPONENT: f32 = 1.5;

/// Share of each insertion batch reserved for pool points that leak through
/// geometry (fail the leak test [`leaks`] while blending a probe hidden
/// behind a surface), ahead of the error ranking. Measured on builtin:demo
/// (BENCHMARKS.md, "Placement against uniform grids"): 0.5 beat 0 at 66, 125 and 256 probes.
pub(super) const LEAK_SHARE: f32 = 0.5;

/// The normals the pool's leak test checks: the 6 axes, 12 face diagonals
/// and 8 cube diagonals.
pub(super) fn leak_normals() -> Vec<Vec3> {
    let mut out = Vec::with_capacity(26);
    for x in -1i32..=1 {
        for y in -1i32..=1 {
            for z in -1i32..=1 {
                if (x, y, z) != (0, 0, 0) {
                    out.push(Vec3::new(x as f32, y as f32, z as f32).normalize());
                }
            }
        }
    }
    out
}

/// Relative luminance (Rec. 709 weights), as `probekit eval` uses it.
pub(super) fn luminance(v: Vec3) -> f32 {
    probekit_sh::LUMINANCE.dot(v)
}

/// Mean over all unit normals of the irradiance luminance of radiance SH
/// `a`: `(1/4π) ∮ E(n) dn = A_0 Y_00 L_00 = (√π / 2) L_00` (only band 0
/// survives the average).
pub(super) fn mean_irradiance_luminance(a: &ShRgb) -> f32 {
    0.5 * std::f32::consts::PI.sqrt() * luminance(a.coeffs()[0])
}

/// The leak test of `probekit eval`, at a pool point for each of `normals`: true when the
/// interpolated irradiance `pred` has a luminance above 4× the captured
/// one's plus `floor` (1 % of the mean luminance) for some normal — the test
/// `probekit eval` applies to its points (`eval::metrics`).
pub(super) fn leaks(pred: &ShRgb, captured: &ShRgb, normals: &[Vec3], floor: f32) -> bool {
    normals
        .iter()
        .any(|&n| luminance(pred.irradiance(n)) > 4.0 * luminance(captured.irradiance(n)) + floor)
}

/// `A_l²` per coefficient index, for the mean-square irradiance.
pub(super) fn band_weights(order: usize) -> Vec<f32> {
    let mut w = Vec::with_capacity(order * order);
    for l in 0..order {
        let a = clamped_cosine_band(l) as f32;
        w.extend(std::iter::repeat(a * a).take(2 * l + 1));
    }
    w
}

/// `Σ_c w_c |a_c − b_c|²`: 4π × the mean over normals of the squared
/// irradiance difference (see the module docs).
pub(super) fn sq_error(w: &[f32], a: &ShRgb, b: &ShRgb) -> f32 {
    a.coeffs()
        .iter()
        .zip(b.coeffs())
        .zip(w)
        .map(|((x, y), w)| w * (*x - *y).length_squared())
        .sum()
}

/// `Σ_c w_c |a_c|²`.
pub(super) fn energy(w: &[f32], a: &ShRgb) -> f32 {
    a.coeffs()
        .iter()
        .zip(w)
        .map(|(x, w)| w * x.length_squared())
        .sum()
}

/// Per pool point: squared error of the current interpolation (0 for probes),
/// its ranking weight, the distance to the nearest vertex of its
/// tetrahedron, and whether it leaks through geometry: it fails the leak
/// test ([`leaks`]) and a vertex it blends is hidden from it by a surface.
pub(super) struct Scores {
    pub(super) err: Vec<f32>,
    pub(super) rank: Vec<f32>,
    pub(super) near: Vec<f32>,
    pub(super) leak: Vec<bool>,
}

/// The share of a point's barycentric weight that must be on probes it
/// sees for placement to score it with the plain blend; below it, with the
/// visible one ([`scoring_weights`]). Measured on the duplex, FZK-Haus, the
/// demo and the Cornell box against 1 (always the visible blend), 0 (always
/// the plain one, the earlier code) and three other mixes (BENCHMARKS.md,
/// "Scoring with visibility").
const VISIBLE_MASS: f32 = 0.5;

/// The weights placement scores a point `p` of the cell `idx` with, and
/// whether a vertex of positive barycentric weight `wt` is hidden from `p`
/// by a surface ([`segment_clear`]). Where the hidden vertices hold more
/// than `1 − `[`VISIBLE_MASS`] of the weight, the baked cloud's cell
/// visibility gives them 0 and scales the rest up by more than 2×
/// (`ProbeCloud::weights_at`), so those are the weights: `wt` with the
/// hidden vertices at 0, renormalized. In a room whose other probes are
/// behind walls the plain blend dilutes a probe next to a lamp with dark
/// ones and looks right, while the baked cloud gives that probe the whole
/// weight and over-lights the room several times; scored with the plain
/// blend, placement never saw it. Elsewhere (the hidden vertices hold half
/// the weight or less, or all of it) it is `wt`: the baked lattice or plane
/// can let part of a hidden probe's light through next to a wall, and
/// always scoring the visible blend lost near the lamps of FZK-Haus. Where
/// all of it is hidden the baked cloud gives the whole weight to the
/// cell's darkest probe (`ProbeCloud::weights_at`); scoring that fallback
/// (with the cell's visible corners of weight 0 first) here instead of `wt`
/// was measured and lost on the duplex and FZK-Haus at ~500 (BENCHMARKS.md,
/// "Hidden-cell fallback").
pub(super) fn scoring_weights(
    tracer: &crate::trace::Tracer<'_>,
    positions: &[Vec3],
    p: Vec3,
    idx: [u32; 4],
    wt: [f32; 4],
) -> ([f32; 4], bool) {
    let mut vw = wt;
    let mut hidden = false;
    for k in 0..4 {
        if wt[k] > 0.0 {
            if let Some(&q) = positions.get(idx[k] as usize) {
                if !segment_clear(tracer, p, q) {
                    vw[k] = 0.0;
                    hidden = true;
                }
            }
        }
    }
    let sum: f32 = vw.iter().sum();
    let total: f32 = wt.iter().sum();
    if hidden && sum > 0.0 && sum.is_finite() && sum < VISIBLE_MASS * total {
        (vw.map(|x| x / sum), true)
    } else {
        (wt, hidden)
    }
}

impl Adaptive<'_, '_, '_> {
    /// Interpolation error at every pool point.
    pub(super) fn score(&self) -> Result<Option<Scores>, PlacementError> {
        let tri = tetrahedralize(&self.st.positions)?;
        // The f32 runtime mesh may reject a sliver the exact
        // tetrahedralization keeps; then refinement stops with what it has.
        let Ok(mesh) = tri.to_tet_mesh(&self.st.positions) else {
            return Ok(None);
        };
        const CHUNK: usize = 256;
        let tracer = self.st.baker.tracer();
        let n = self.pool.pos.len();
        let parts: Vec<Vec<(f32, f32, bool)>> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut ws = WalkState::new();
                (c * CHUNK..((c + 1) * CHUNK).min(n))
                    .map(|i| {
                        if self.pool.probe[i].is_some() {
                            return (0.0, 0.0, false);
                        }
                        let p = self.pool.pos[i];
                        let (idx, wt) = mesh.weights_at(p, &mut ws);
                        let cap = &self.pool.sh[i];
                        let (vw, hidden) = scoring_weights(tracer, &self.st.positions, p, idx, wt);
                        let pred = blend_sh(&self.st.sh, idx, vw, cap.order());
                        let near = idx
                            .iter()
                            .map(|&v| self.st.positions[v as usize].distance(p))
                            .fold(f32::INFINITY, f32::min);
                        // A leak through geometry: some vertex it blends is
                        // out of sight (behind a wall), and the plain blend
                        // leaks. The plain blend, not the scored one: the
                        // baked cloud's cell visibility is a lattice
                        // (or a plane) that can let part of such a probe's
                        // weight through next to the wall.
                        // Where the scored weights are the plain ones,
                        // `pred` is that blend already.
                        let leak = hidden && {
                            let plain;
                            let blended = if vw == wt {
                                &pred
                            } else {
                                plain = blend_sh(&self.st.sh, idx, wt, cap.order());
                                &plain
                            };
                            leaks(blended, cap, &self.normals, self.floor)
                        };
                        (sq_error(&self.w, &pred, cap), near, leak)
                    })
                    .collect()
            })
            .collect();
        let mut err = Vec::with_capacity(n);
        let mut near = Vec::with_capacity(n);
        let mut leak = Vec::with_capacity(n);
        for (e, d, l) in parts.into_iter().flatten() {
            err.push(e);
            near.push(d);
            leak.push(l);
        }
        // Rank by the absolute error plus a relative part, so dark regions
        // (where a leak is a large relative error of little energy) are not
        // starved by the bright ones, weighted by the volume the point
        // stands for ([`SPACING_EXPONENT`]).
        let mean = self.pool.energy.iter().map(|&e| e as f64).sum::<f64>()
            / self.pool.energy.len().max(1) as f64;
        let mean = mean as f32;
        let rank = err
            .iter()
            .zip(&self.pool.energy)
            .zip(&near)
            .map(|((&e, &en), &d)| {
                e * (1.0 + RELATIVE_WEIGHT * mean / (en + 1e-4 * mean + 1e-30))
                    * d.powf(SPACING_EXPONENT)
            })
            .collect();
        Ok(Some(Scores {
            err,
            rank,
            near,
            leak,
        }))
    }

    /// Estimated relative RMSE over the pool points that are not probes.
    pub(super) fn rel_rmse(&self, s: &Scores) -> f32 {
        let (mut e, mut t) = (0.0f64, 0.0f64);
        for i in 0..s.err.len() {
            if self.pool.probe[i].is_none() {
                e += s.err[i] as f64;
                t += self.pool.energy[i] as f64;
            }
        }
        if t > 0.0 {
            (e / t).sqrt() as f32
        } else {
            0.0
        }
    }
}
