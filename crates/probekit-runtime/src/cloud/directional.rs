//! Directional brightness: the blend of a cloud cell done per direction, so
//! that a probe bright only *towards* something (a doorway probe seeing a
//! lit corridor through a closet's gap) counts less for the normals that
//! face it, and the result is still one radiance SH per point.
//!
//! **What.** With exponent `γ > 0` ([`super::ProbeCloud::set_directional_brightness`]),
//! for each of the twelve directions `d` of [`directions`] (the vertices of
//! an icosahedron) every probe `i` of the cell gets the weight
//! `w_i(d) = w_i · f_i(d) / Σ_k w_k · f_k(d)`: `w_i` the cloud's blend
//! weight at the point (barycentric × visibility × fitted probe weight ×
//! mean brightness), and `f_i(d) = (L_i(d) / (t·r(d)))^−γ` for a probe
//! brighter than `t` = [`DIRECTIONAL_RATIO`] times the cell's weighted
//! harmonic mean `r(d)`, 1 otherwise ([`factors`]); `L_i(d)` the luminance
//! of the probe's irradiance for normal `d` as the cloud was built (floored
//! at 10⁻³ of the cell's brightest for that direction). The blended irradiance
//! `E(d) = Σ_i w_i(d) E_i(d)` at the twelve directions is projected back to
//! SH bands 0–2 with equal quadrature weights `4π/12` and divided by the
//! clamped-cosine band factors, giving radiance SH. Bands above 2 (whose
//! irradiance is 0 or tiny: `A_3 = 0`, `A_4 = −π/24`) keep the plain blend.
//!
//! **Why twelve points.** The icosahedron's vertices are a spherical
//! 5-design (Delsarte, Goethals & Seidel, "Spherical codes and designs",
//! 1977): equal-weight quadrature over them integrates every polynomial of
//! degree ≤ 5 exactly, so the product of two functions of bands ≤ 2 (degree
//! 4) too. The projection of an irradiance of bands ≤ 2 is therefore exact:
//! at `γ = 0`, or where no probe of the cell stands out by more than `t`
//! in any direction, the result is the plain blend, up to rounding.
//!
//! **Properties.** Per direction a convex combination, so a constant field
//! is kept and the blend is continuous in the point wherever the weights
//! are (on a face the fourth probe's weight is 0 in every direction).
//! `L_i(d)` is baked, like the mean brightness, so a cloud relit in place
//! blends as built and the relit irradiance stays linear in the group
//! scales.
//!
//! **Cost.** Where every factor of a direction is 1 its blend is the plain
//! one, and the projection of the plain blend's irradiance is the plain
//! blend of the SH (the 5-design property). So a query blends the SH
//! plainly and adds, for the directions where some probe stands out only,
//! the projection of that direction's change (`DirectionTable::correct`).
//! Whether a direction has a factor below 1 needs no division or power:
//! with `ρ_k = 1/L_k(d)` (per probe, as built) and `m = min_k ρ_k`, the
//! floored `1/l_k` is `min(ρ_k, 10³·m)` and some probe exceeds
//! `t·r(d)` exactly when `Σ_k w_k·min(ρ_k, 10³·m) > t·Σ_k w_k·m`; four
//! directions are tested at once.
//!
//! Our own method, measured in BENCHMARKS.md ("Directional brightness");
//! the per-direction weighting is in the spirit of DDGI's per-direction
//! visibility (Majercik et al. 2019), applied to brightness.

use glam::{Vec3, Vec4};

/// Number of quadrature directions ([`directions`]).
pub const DIRECTIONS: usize = 12;

/// Highest SH band the directional blend projects (bands 0–2, 9
/// coefficients); higher bands keep the plain blend.
pub const DIRECTIONAL_COEFFS: usize = 9;

/// The twelve unit directions of the directional blend: the vertices of a
/// regular icosahedron, `(0, ±1, ±φ)`, `(±1, ±φ, 0)`, `(±φ, 0, ±1)`
/// normalized (`φ` the golden ratio), in that order with the first sign
/// outermost. A spherical 5-design (see the module docs).
pub fn directions() -> [Vec3; DIRECTIONS] {
    let phi = (1.0 + crate::math::sqrt(5.0)) / 2.0;
    let mut out = [Vec3::ZERO; DIRECTIONS];
    let mut i = 0;
    for s1 in [-1.0f32, 1.0] {
        for s2 in [-1.0f32, 1.0] {
            out[i] = Vec3::new(0.0, s1, s2 * phi).normalize();
            out[i + 1] = Vec3::new(s1, s2 * phi, 0.0).normalize();
            out[i + 2] = Vec3::new(s2 * phi, 0.0, s1).normalize();
            i += 3;
        }
    }
    out
}

/// The constant tables of the directional blend: for each direction `d` of
/// [`directions`] and coefficient `c < 9`, `A_l·Y_c(d)` (a radiance SH's
/// irradiance at `d`) and `(4π/12)·Y_c(d)/A_l` (the projection of an
/// irradiance sampled at the directions back to radiance SH); `A_l` the
/// clamped-cosine band factors π, 2π/3, π/4.
#[derive(Debug, Clone)]
pub struct DirectionTable {
    irradiance: [[f32; DIRECTIONAL_COEFFS]; DIRECTIONS],
    projection: [[f32; DIRECTIONAL_COEFFS]; DIRECTIONS],
}

impl Default for DirectionTable {
    fn default() -> Self {
        Self::new()
    }
}

impl DirectionTable {
    /// Builds the tables (about a hundred basis evaluations).
    pub fn new() -> Self {
        let mut irradiance = [[0.0; DIRECTIONAL_COEFFS]; DIRECTIONS];
        let mut projection = [[0.0; DIRECTIONAL_COEFFS]; DIRECTIONS];
        let w = 4.0 * core::f32::consts::PI / DIRECTIONS as f32;
        for (d, dir) in directions().into_iter().enumerate() {
            let y = probekit_sh::basis::eval_l2(dir);
            for c in 0..DIRECTIONAL_COEFFS {
                let a = band_factor(c);
                irradiance[d][c] = a * y[c];
                projection[d][c] = w * y[c] / a;
            }
        }
        Self {
            irradiance,
            projection,
        }
    }

    /// Irradiance (not divided by π) of radiance SH `coeffs` (its bands ≤ 2)
    /// for each of the twelve directions.
    pub fn irradiance(&self, coeffs: &[Vec3]) -> [Vec3; DIRECTIONS] {
        let m = coeffs.len().min(DIRECTIONAL_COEFFS);
        core::array::from_fn(|d| {
            let t = &self.irradiance[d];
            (0..m).fold(Vec3::ZERO, |e, c| e + coeffs[c] * t[c])
        })
    }

    /// Luminance ([`probekit_sh::LUMINANCE`]) of [`Self::irradiance`].
    pub fn luminance(&self, coeffs: &[Vec3]) -> [f32; DIRECTIONS] {
        self.irradiance(coeffs)
            .map(|e| probekit_sh::LUMINANCE.dot(e))
    }

    /// Adds to `out` (its first `min(out.len(), 9)` coefficients, radiance
    /// SH holding the plain blend `Σ_k w_k c_k`) the directional blend's
    /// departure from it: for each direction `d` where some probe's factor
    /// of [`factors`] is below 1, the projection of
    /// `Σ_k (u_k(d) − w_k/Σw)·E_k(d)`, `u_k(d)` the per-direction weights
    /// and `E_k(d)` probe `k`'s irradiance at `d` from its SH `sh[k]`.
    /// `recip[k]` is probe `k`'s [`reciprocal`] luminances, `weights` the
    /// blend weights (slots of weight ≤ 0 are unused and not read). No
    /// direction stands out: `out` is left as it is, the directional blend
    /// being then the plain one.
    pub(crate) fn correct(
        &self,
        recip: [&[Vec4; 3]; 4],
        sh: [&[Vec3]; 4],
        weights: &[f32; 4],
        gamma: f32,
        out: &mut [Vec3],
    ) {
        let used = weights.map(|w| w > 0.0);
        let w = weights.map(|x| if x > 0.0 { x } else { 0.0 });
        let total = w[0] + w[1] + w[2] + w[3];
        if gamma <= 0.0 || !(total > 0.0 && total.is_finite()) {
            return;
        }
        let tt = DIRECTIONAL_RATIO * total;
        // `j` also names the directions `4j..4j + 4` below.
        #[allow(clippy::needless_range_loop)]
        for j in 0..3 {
            let r: [Vec4; 4] =
                core::array::from_fn(|k| if used[k] { recip[k][j] } else { Vec4::INFINITY });
            // `m = 1/top`; the floored reciprocal luminances; `Σ w/l`.
            let m = r[0].min(r[1]).min(r[2].min(r[3]));
            let cap = m * RECIPROCAL_FLOOR;
            let l: [Vec4; 4] = core::array::from_fn(|k| r[k].min(cap));
            let inverse = l[0] * w[0] + l[1] * w[1] + l[2] * w[2] + l[3] * w[3];
            // A probe exceeds `t·r(d)` where `inverse > t·Σw·m` (false for
            // NaN: no used probe bright in that direction).
            let mask = inverse.cmpgt(m * tt).bitmask();
            if mask == 0 {
                continue;
            }
            for lane in 0..4 {
                if mask & (1 << lane) != 0 {
                    let d = 4 * j + lane;
                    let f: [f32; 4] = core::array::from_fn(|k| {
                        // `l_k / threshold = l_k·Σ(w/l) / (t·Σw)`.
                        let x = inverse[lane] / (tt * l[k][lane]);
                        if used[k] && x > 1.0 {
                            inverse_power(x, gamma)
                        } else {
                            1.0
                        }
                    });
                    self.correct_direction(d, &f, &w, total, sh, out);
                }
            }
        }
    }

    /// The change of direction `d` for factors `f` (see [`Self::correct`]).
    fn correct_direction(
        &self,
        d: usize,
        f: &[f32; 4],
        w: &[f32; 4],
        total: f32,
        sh: [&[Vec3]; 4],
        out: &mut [Vec3],
    ) {
        let s = w[0] * f[0] + w[1] * f[1] + w[2] * f[2] + w[3] * f[3];
        if !(s > 0.0 && s.is_finite()) {
            return;
        }
        let t = &self.irradiance[d];
        let mut delta = Vec3::ZERO;
        for k in 0..4 {
            let u = w[k] * f[k] / s - w[k] / total;
            if u != 0.0 {
                let c = sh[k];
                let m = c.len().min(DIRECTIONAL_COEFFS);
                let e = (0..m).fold(Vec3::ZERO, |e, i| e + c[i] * t[i]);
                delta += e * u;
            }
        }
        let m = out.len().min(DIRECTIONAL_COEFFS);
        for (c, o) in out[..m].iter_mut().enumerate() {
            *o += delta * self.projection[d][c];
        }
    }

    /// Radiance SH (the first `min(out.len(), 9)` coefficients of `out`,
    /// overwritten) whose irradiance is the projection of `e`, an
    /// irradiance sampled at the twelve directions. Exact for an irradiance
    /// of bands ≤ 2 (see the module docs).
    pub fn project(&self, e: &[Vec3; DIRECTIONS], out: &mut [Vec3]) {
        let m = out.len().min(DIRECTIONAL_COEFFS);
        for (c, o) in out[..m].iter_mut().enumerate() {
            *o = (0..DIRECTIONS).fold(Vec3::ZERO, |s, d| s + e[d] * self.projection[d][c]);
        }
    }
}

/// The clamped-cosine factor `A_l` of coefficient `c` (bands ≤ 2).
fn band_factor(c: usize) -> f32 {
    probekit_sh::clamped_cosine_band(if c == 0 {
        0
    } else if c < 4 {
        1
    } else {
        2
    }) as f32
}

/// `x^−γ` for `x > 0`: square roots for the common exponents, else
/// [`crate::math::pow`] (exp2 of a log2, no `powf`).
#[inline]
fn inverse_power(x: f32, gamma: f32) -> f32 {
    if gamma == 0.25 {
        1.0 / crate::math::sqrt(crate::math::sqrt(x))
    } else if gamma == 0.5 {
        1.0 / crate::math::sqrt(x)
    } else if gamma == 1.0 {
        1.0 / x
    } else {
        crate::math::pow(x, -gamma)
    }
}

/// The luminance floor of [`factors`] as a factor on the reciprocal of the
/// brightest: `1/(10⁻³·top)`.
const RECIPROCAL_FLOOR: f32 = 1e3;

/// `1/L(d)` of twelve directional luminances (+∞ where `L(d) ≤ 0`), four
/// directions to a vector: what [`DirectionTable::correct`] reads per probe.
pub(crate) fn reciprocal(lum: &[f32; DIRECTIONS]) -> [Vec4; 3] {
    core::array::from_fn(|j| {
        Vec4::from_array(core::array::from_fn(|l| {
            let x = lum[4 * j + l];
            if x > 0.0 {
                1.0 / x
            } else {
                f32::INFINITY
            }
        }))
    })
}

/// How much brighter than the cell (for a direction) a probe may be before
/// the directional blend damps it: `t` of [`factors`]. Measured on
/// builtin:demo (BENCHMARKS.md, "Directional brightness"): 3 keeps the
/// closet free of leaks at a third of the error cost of damping every
/// difference (`t` = 1).
pub const DIRECTIONAL_RATIO: f32 = 3.0;

/// Per-direction factors of a cell's four probes: `lum[k]` the probes'
/// directional luminances ([`DirectionTable::luminance`] of the baked SH),
/// `weights[k]` their blend weights (≥ 0; slots with 0 unused). For each
/// direction `d`, each used probe's luminance is floored at 10⁻³ of the
/// brightest used one, `r(d) = (Σ_k w_k / L_k(d))⁻¹ · Σ_k w_k` is the cell's
/// weighted harmonic mean luminance, and the factor is
/// `(max(L_k(d), t·r(d)) / (t·r(d)))^−γ` with `t` = [`DIRECTIONAL_RATIO`]:
/// 1 for a probe less than `t` times the cell's brightness in that
/// direction, `(t·r/L_k)^γ` for a brighter one. The harmonic mean follows the
/// dimmer probes (what a dark closet's cell is made of) and is continuous in
/// the weights, so a probe whose weight goes to 0 at a face changes nothing
/// there. A direction without a positive, finite brightest gets 1 for all,
/// as do unused slots and `γ ≤ 0`.
pub fn factors(
    lum: [&[f32; DIRECTIONS]; 4],
    weights: [f32; 4],
    gamma: f32,
) -> [[f32; 4]; DIRECTIONS] {
    let used = weights.map(|w| w > 0.0);
    let total: f32 = weights.iter().filter(|w| **w > 0.0).sum();
    core::array::from_fn(|d| {
        let top = (0..4)
            .filter(|&k| used[k])
            .map(|k| lum[k][d])
            .fold(0.0f32, f32::max);
        if !(top > 0.0 && top.is_finite()) || gamma <= 0.0 || !(total > 0.0 && total.is_finite()) {
            return [1.0; 4];
        }
        let l: [f32; 4] = core::array::from_fn(|k| lum[k][d].max(1e-3 * top));
        let inverse: f32 = (0..4).filter(|&k| used[k]).map(|k| weights[k] / l[k]).sum();
        let threshold = DIRECTIONAL_RATIO * total / inverse;
        core::array::from_fn(|k| {
            if used[k] && l[k] > threshold {
                inverse_power(l[k] / threshold, gamma)
            } else {
                1.0
            }
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sh(seed: u32) -> [Vec3; 9] {
        // Deterministic pseudo-random coefficients.
        let mut x = seed.wrapping_mul(2_654_435_761).wrapping_add(1);
        core::array::from_fn(|_| {
            let mut v = [0.0f32; 3];
            for c in &mut v {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                *c = (x % 2001) as f32 / 1000.0 - 1.0;
            }
            Vec3::from(v)
        })
    }

    /// The twelve directions are unit, distinct, and antipodal in pairs.
    #[test]
    fn directions_are_an_icosahedron() {
        let d = directions();
        for a in &d {
            assert!((a.length() - 1.0).abs() < 1e-6);
            assert!(d.iter().any(|b| (*a + *b).length() < 1e-6), "no antipode");
            // Five nearest neighbours at the icosahedron's edge angle.
            let near = d
                .iter()
                .filter(|b| (a.dot(**b) - 1.0 / 5f32.sqrt()).abs() < 1e-5)
                .count();
            assert_eq!(near, 5);
        }
    }

    /// The projection reproduces bands ≤ 2 exactly (the 5-design property),
    /// checked against the SH crate's own irradiance evaluation.
    #[test]
    fn projection_of_band_limited_irradiance_is_exact() {
        let t = DirectionTable::new();
        for seed in 0..20 {
            let c = sh(seed);
            let e = t.irradiance(&c);
            for (d, dir) in directions().into_iter().enumerate() {
                let want = probekit_sh::irradiance(&c, dir);
                assert!((e[d] - want).length() < 1e-4, "{d}: {:?} {want:?}", e[d]);
            }
            let mut back = [Vec3::ZERO; 9];
            t.project(&e, &mut back);
            for k in 0..9 {
                assert!((back[k] - c[k]).length() < 1e-4, "seed {seed} coeff {k}");
            }
        }
    }

    /// Factors against a direct computation of the rule: 1 at γ = 0, in
    /// unused slots and below the threshold; `(L / (t·r))^−γ` above it, `r`
    /// the weighted harmonic mean with floored luminances.
    #[test]
    fn factors_damp_probes_brighter_than_the_cell() {
        let mut lum = [[1.0f32; DIRECTIONS]; 4];
        lum[0] = [16.0; DIRECTIONS];
        lum[1] = [0.0; DIRECTIONS];
        lum[2][3] = -5.0;
        lum[3] = [1e6; DIRECTIONS];
        let refs = [&lum[0], &lum[1], &lum[2], &lum[3]];
        let w = [0.2f32, 0.3, 0.5, 0.0];
        assert_eq!(factors(refs, w, 0.0), [[1.0; 4]; DIRECTIONS]);
        for gamma in [0.25f32, 0.5, 0.7, 1.0] {
            let f = factors(refs, w, gamma);
            for (d, fd) in f.iter().enumerate() {
                // Floors at 10⁻³ of 16; slot 3 unused.
                let l = [16.0f32, 0.016, if d == 3 { 0.016 } else { 1.0 }];
                let r = 1.0 / (0.2 / l[0] + 0.3 / l[1] + 0.5 / l[2]);
                let t = DIRECTIONAL_RATIO * r;
                for k in 0..3 {
                    let want = if l[k] > t {
                        (l[k] / t).powf(-gamma)
                    } else {
                        1.0
                    };
                    assert!(
                        (fd[k] - want).abs() < 1e-5 * want,
                        "{d} {k}: {} {want}",
                        fd[k]
                    );
                }
                assert_eq!(fd[3], 1.0);
                assert!(fd[0] < 1.0 && fd[1] == 1.0);
            }
        }
        // Equal probes: no damping.
        let same = [[2.0f32; DIRECTIONS]; 4];
        let f = factors([&same[0], &same[1], &same[2], &same[3]], [0.25; 4], 1.0);
        assert_eq!(f, [[1.0; 4]; DIRECTIONS]);
    }
}
