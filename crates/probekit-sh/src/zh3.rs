//! ZH3: linear SH plus one oriented quadratic zonal harmonic (Roughton,
//! Sloan, Silvennoinen, Iwanicki, Drobot, *ZH3: Quadratic Zonal Harmonics*,
//! I3D 2024 — seed 004).
//!
//! A [`Zh3`] holds the four L1 radiance coefficients (RGB) and, per colour
//! channel, one coefficient `z` of the band-2 zonal harmonic `Y2,0` rotated to
//! a unit axis `a`: the band-2 radiance is `z·Y2,0(a·ω)`, whose SH
//! coefficients are `sqrt(4π/5)·z·Y2,m(a)` ([`crate::zonal::zh_to_sh`]).
//!
//! ## Projection onto an axis
//!
//! `u(a) = sqrt(4π/5)·(Y2,−2(a), …, Y2,2(a))` is a **unit** vector in the
//! 5-dimensional band-2 space (addition theorem: `Σ_m Y2,m(a)² = 5/(4π)`), so
//! the least-squares zonal coefficient of band-2 coefficients `c2` is
//! `z = u(a)·c2 = sqrt(4π/5)·Σ_m c2,m·Y2,m(a)` ([`zonal_projection`]). (The
//! talk's slide says "scale by 4π/5"; with our orthonormal basis the scale that
//! reproduces zonal signals exactly is `sqrt(4π/5)`, and the tests check that.)
//!
//! ## Irradiance error and the axis solve
//!
//! ZH3 keeps L1 exactly, so against the L2 irradiance only band 2 differs.
//! By orthonormality the squared irradiance error integrated over the sphere
//! is, per channel, exactly `(π/4)²·|c2 − z·u(a)|²`, and with the optimal
//! `z` it is `(π/4)²·(|c2|² − (u(a)·c2)²)` — closed form, no quadrature
//! ([`weighted_irradiance_error`], [`zh3_axis_error`]). The solved shared axis
//! maximises `F(a) = Σ_ch w_ch·(u(a)·c2_ch)²`: a quartic on the unit sphere.
//! We maximise it by Riemannian Newton ascent (exact Hessian, gradient step
//! where the Hessian is not negative definite, Armijo backtracking,
//! retraction `a ← normalize(a + ξ)`), in f64, started from the luminance
//! axis and, to escape poor local optima, also from the weighted L1 axis, each
//! channel's L1 axis and the eigenvectors of each channel's (and the
//! weighted sum's) band-2 quadratic form (a band-2 function restricted to the
//! sphere is `aᵀ M a` with `M` symmetric); the best end point wins. It is not
//! BFGS (the talk uses BFGS): the problem is two-dimensional with a cheap
//! exact Hessian, and the multi-start matters more than the local method. The
//! result is never worse than the luminance axis, and a test checks it
//! against a 20 000-axis brute-force search.

// Index loops over colour channels and SH coefficients read like the formulas.
#![allow(clippy::needless_range_loop)]

use crate::basis::{eval_l2, Y2_A, Y2_B, Y2_C};
use crate::coeffs::LUMINANCE;
use crate::convolve::irradiance_l1;
#[cfg(not(feature = "std"))]
use crate::math::FloatMath;
use crate::numeric::symmetric_eigen3;
use crate::zonal::zh_to_sh;
use alloc::vec;
use alloc::vec::Vec;
use glam::{DMat3, DVec3, Vec3};

/// Stored ZH3 of linear-RGB **radiance** (seed 004): the L1 coefficients, one
/// zonal band-2 coefficient per channel and the unit axis of each channel's
/// zonal lobe (all three equal for the shared-axis variants).
///
/// Band-2 radiance of channel `k` is `zonal[k]·Y2,0(axes[k]·ω)`
/// (`Y2,0(t) = sqrt(5/(16π))·(3t² − 1)`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Zh3 {
    /// L1 radiance coefficients, index `l*(l+1)+m`, crate conventions.
    pub l1: [Vec3; 4],
    /// Zonal band-2 coefficient per colour channel (R, G, B).
    pub zonal: Vec3,
    /// Unit zonal axis per colour channel (R, G, B).
    pub axes: [Vec3; 3],
}

impl Zh3 {
    /// Expands to L2 radiance SH (9 coefficients) by rotating each channel's
    /// zonal lobe to its axis ([`zh_to_sh`], Sloan's ZH rotation). Expand
    /// before interpolating: ZH3 is non-linear when the axes differ (seed 004,
    /// "Stored vs. hallucinated ZH3").
    pub fn to_l2(&self) -> [Vec3; 9] {
        let mut out = [Vec3::ZERO; 9];
        out[..4].copy_from_slice(&self.l1);
        for ch in 0..3 {
            let mut c = [0.0f32; 9];
            zh_to_sh(&[0.0, 0.0, self.zonal[ch]], self.axes[ch], &mut c);
            for i in 4..9 {
                out[i][ch] = c[i];
            }
        }
        out
    }

    /// Irradiance `E(n)` (not divided by π) for unit normal `n`: the linear
    /// L1 irradiance plus `(π/4)·z·Y2,0(axis·n)` per channel (seed 004,
    /// `SHHallucinateZH3Irradiance`, with our unnormalised cosine kernel
    /// `π/4` in place of the talk's normalised `1/4`).
    pub fn irradiance(&self, n: Vec3) -> Vec3 {
        let t = Vec3::new(
            self.axes[0].dot(n),
            self.axes[1].dot(n),
            self.axes[2].dot(n),
        );
        irradiance_l1(&self.l1, n)
            + self.zonal * (3.0 * t * t - Vec3::ONE) * (core::f32::consts::FRAC_PI_4 * Y2_B)
    }
}

/// `Y2,0` as a function of the cosine to its axis: `sqrt(5/(16π))·(3t² − 1)`.
#[inline]
fn y20(t: f32) -> f32 {
    Y2_B * (3.0 * t * t - 1.0)
}

/// The band-1 vector of one colour channel in xyz: `(−c3, −c1, c2)`, so that
/// the band-1 radiance is `Y1·(v·ω)` (crate sign convention).
#[inline]
pub fn l1_vector(l1: &[Vec3; 4], channel: usize) -> Vec3 {
    Vec3::new(-l1[3][channel], -l1[1][channel], l1[2][channel])
}

/// The band-1 vector of the Rec. 709 luminance of `l1`, normalised: the
/// shared ZH3 axis of seed 004 (`zonalAxis` in `SHHallucinateZH3Irradiance`).
/// `None` when the luminance has no (finite, non-zero) band-1 vector.
pub fn luminance_axis(l1: &[Vec3; 4]) -> Option<Vec3> {
    weighted_axis(l1, LUMINANCE)
}

fn weighted_axis(l1: &[Vec3; 4], w: Vec3) -> Option<Vec3> {
    let v = Vec3::new(-l1[3].dot(w), -l1[1].dot(w), l1[2].dot(w));
    let len = v.length();
    (len > 1e-30 && len.is_finite()).then(|| v / len)
}

/// The shared axis used by [`fit_zh3_shared`] and the codec: the luminance
/// axis, or +Y (world up) when the luminance has no band-1 vector.
pub fn shared_axis(l1: &[Vec3; 4]) -> Vec3 {
    luminance_axis(l1).unwrap_or(Vec3::Y)
}

/// Least-squares zonal coefficient of band-2 coefficients `band2`
/// (`c2,−2..c2,2`, one channel) about unit `axis`:
/// `sqrt(4π/5)·Σ_m c2,m·Y2,m(axis)` (module docs; seed 004 "To compute the
/// ZH3 coefficient…").
pub fn zonal_projection(band2: &[f32; 5], axis: Vec3) -> f32 {
    let b = eval_l2(axis);
    let s: f32 = (0..5).map(|m| band2[m] * b[4 + m]).sum();
    (4.0 * core::f32::consts::PI / 5.0).sqrt() * s
}

fn band2(l2: &[Vec3; 9], ch: usize) -> [f32; 5] {
    [l2[4][ch], l2[5][ch], l2[6][ch], l2[7][ch], l2[8][ch]]
}

fn l1_of(l2: &[Vec3; 9]) -> [Vec3; 4] {
    [l2[0], l2[1], l2[2], l2[3]]
}

fn fit_with_axes(l2: &[Vec3; 9], axes: [Vec3; 3]) -> Zh3 {
    let mut zonal = Vec3::ZERO;
    for ch in 0..3 {
        zonal[ch] = zonal_projection(&band2(l2, ch), axes[ch]);
    }
    Zh3 {
        l1: l1_of(l2),
        zonal,
        axes,
    }
}

/// Stored ZH3 with a shared axis: the L1 luminance direction ([`shared_axis`]),
/// each channel's zonal coefficient the projection of its L2 band onto the
/// axis' zonal function (seed 004, "use the same axis for all three channels").
pub fn fit_zh3_shared(l2: &[Vec3; 9]) -> Zh3 {
    let a = shared_axis(&l1_of(l2));
    fit_with_axes(l2, [a; 3])
}

/// Stored ZH3 with an axis per channel, each from that channel's own L1
/// vector (seed 004, "we orient it along the linear SH vector"); a channel
/// without a band-1 vector falls back to [`shared_axis`].
pub fn fit_zh3_per_channel(l2: &[Vec3; 9]) -> Zh3 {
    let l1 = l1_of(l2);
    let fallback = shared_axis(&l1);
    let axes = [0, 1, 2].map(|ch| l1_vector(&l1, ch).try_normalize().unwrap_or(fallback));
    fit_with_axes(l2, axes)
}

/// Colour-channel weights of the shared-axis solve; the error is weighted the
/// same way (seed 004: "make sure the error function uses the same weights").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AxisWeights {
    /// R, G and B count equally (weights 1, 1, 1).
    Equal,
    /// Rec. 709 luminance weights ([`LUMINANCE`]).
    Luminance,
}

impl AxisWeights {
    /// The per-channel weights.
    pub fn weights(self) -> Vec3 {
        match self {
            AxisWeights::Equal => Vec3::ONE,
            AxisWeights::Luminance => LUMINANCE,
        }
    }
}

/// Weighted squared irradiance error between two L2 radiance SH, integrated
/// over the sphere: `Σ_ch w_ch ∫ (E_a − E_b)² dω = Σ_ch w_ch Σ_lm Â_l²·Δc_lm²`
/// (exact by orthonormality; `Â_l = π, 2π/3, π/4`, Ramamoorthi & Hanrahan 2001).
pub fn weighted_irradiance_error(a: &[Vec3; 9], b: &[Vec3; 9], weights: Vec3) -> f64 {
    let al = [
        core::f64::consts::PI,
        2.0 * core::f64::consts::PI / 3.0,
        core::f64::consts::PI / 4.0,
    ];
    let w = weights.as_dvec3();
    let mut e = 0.0;
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        let l = if i == 0 {
            0
        } else if i < 4 {
            1
        } else {
            2
        };
        let d = x.as_dvec3() - y.as_dvec3();
        e += al[l] * al[l] * (d * d).dot(w);
    }
    e
}

/// Weighted squared irradiance error (over the sphere, against the L2
/// irradiance) of the shared-axis ZH3 with unit `axis` and optimal zonal
/// coefficients: `(π/4)²·Σ_ch w_ch (|c2|² − z_ch²)` (module docs).
pub fn zh3_axis_error(l2: &[Vec3; 9], axis: Vec3, w: AxisWeights) -> f64 {
    let wv = w.weights().as_dvec3();
    let mut e = 0.0;
    for ch in 0..3 {
        let b = band2(l2, ch);
        let n2: f64 = b.iter().map(|x| (*x as f64).powi(2)).sum();
        let z = zonal_projection_f64(&b, axis.as_dvec3());
        e += wv[ch] * (n2 - z * z);
    }
    (core::f64::consts::PI / 4.0).powi(2) * e
}

/// The band-2 function of one channel restricted to the unit sphere as a
/// quadratic form `aᵀ M a` (uses `3z² − 1 = 2z² − x² − y²` for `|a| = 1`).
fn band2_matrix(b: &[f64; 5]) -> [[f64; 3]; 3] {
    let (ya, yb, yc) = (Y2_A as f64, Y2_B as f64, Y2_C as f64);
    let m01 = 0.5 * ya * b[0];
    let m12 = -0.5 * ya * b[1];
    let m02 = -0.5 * ya * b[3];
    [
        [-yb * b[2] + yc * b[4], m01, m02],
        [m01, -yb * b[2] - yc * b[4], m12],
        [m02, m12, 2.0 * yb * b[2]],
    ]
}

fn mat_vec(m: &[[f64; 3]; 3], a: DVec3) -> DVec3 {
    DVec3::new(
        m[0][0] * a.x + m[0][1] * a.y + m[0][2] * a.z,
        m[1][0] * a.x + m[1][1] * a.y + m[1][2] * a.z,
        m[2][0] * a.x + m[2][1] * a.y + m[2][2] * a.z,
    )
}

fn zonal_projection_f64(band2: &[f32; 5], axis: DVec3) -> f64 {
    let b: [f64; 5] = band2.map(|x| x as f64);
    let m = band2_matrix(&b);
    let a = axis.normalize_or_zero();
    (4.0 * core::f64::consts::PI / 5.0).sqrt() * a.dot(mat_vec(&m, a))
}

/// Objective `F(a) = Σ w g(a)²` (g = band-2 value at a), its Euclidean
/// gradient `4 Σ w g M a` and Euclidean Hessian `Σ w (8 (Ma)(Ma)ᵀ + 4 g M)`.
fn objective(ms: &[[[f64; 3]; 3]; 3], w: DVec3, a: DVec3) -> (f64, DVec3, DMat3) {
    let mut f = 0.0;
    let mut grad = DVec3::ZERO;
    let mut hess = DMat3::ZERO;
    for ch in 0..3 {
        let ma = mat_vec(&ms[ch], a);
        let g = a.dot(ma);
        f += w[ch] * g * g;
        grad += ma * (4.0 * w[ch] * g);
        let m = DMat3::from_cols_array_2d(&ms[ch]);
        hess += outer(ma, ma) * (8.0 * w[ch]) + m * (4.0 * w[ch] * g);
    }
    (f, grad, hess)
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// Riemannian Newton ascent on the unit sphere (Absil, Mahony & Sepulchre,
/// *Optimization Algorithms on Matrix Manifolds*, 2008, §6: Riemannian
/// Hessian `P H P − (a·∇F) P`), falling back to the gradient where the Hessian
/// is not negative definite, with Armijo backtracking and the retraction
/// `a ← normalize(a + ξ)`. Monotone: `F` never decreases.
fn ascend(ms: &[[[f64; 3]; 3]; 3], w: DVec3, start: DVec3) -> (f64, DVec3) {
    let mut a = start.normalize();
    let (mut f, mut ge, mut he) = objective(ms, w, a);
    for _ in 0..60 {
        let rgrad = ge - a * ge.dot(a);
        // F is O(1) after scaling; a gradient of 1e-9 is at f64 round-off.
        if rgrad.length_squared() < 1e-18 {
            break;
        }
        let (e1, e2) = a.any_orthonormal_pair();
        let radial = a.dot(ge);
        let h11 = e1.dot(he * e1) - radial;
        let h22 = e2.dot(he * e2) - radial;
        let h12 = e1.dot(he * e2);
        let (g1, g2) = (e1.dot(rgrad), e2.dot(rgrad));
        let det = h11 * h22 - h12 * h12;
        let mut dir = rgrad;
        let mut t = 1.0 / (h11.abs() + h22.abs() + 2.0 * h12.abs()).max(1e-12);
        if det > 0.0 && h11 < 0.0 {
            // Newton: ξ = −H⁻¹ g (H negative definite, so ξ ascends).
            let x1 = -(h22 * g1 - h12 * g2) / det;
            let x2 = -(-h12 * g1 + h11 * g2) / det;
            dir = e1 * x1 + e2 * x2;
            t = 1.0;
        }
        let slope = dir.dot(rgrad);
        let mut accepted = false;
        for _ in 0..60 {
            let cand = (a + dir * t).normalize();
            let (fc, gc, hc) = objective(ms, w, cand);
            if fc >= f + 1e-4 * t * slope {
                accepted = fc > f;
                a = cand;
                f = fc;
                ge = gc;
                he = hc;
                break;
            }
            t *= 0.5;
        }
        if !accepted {
            break;
        }
    }
    (f, a)
}

/// Stored ZH3 with the shared axis that minimises the weighted irradiance
/// error against the L2 irradiance over the whole sphere (seed 004, "solving
/// for a new zonal axis"); error weights equal the axis weights `w`. The L1
/// coefficients are kept and each channel's zonal coefficient is the
/// projection onto the solved axis. Closed-form error and the optimiser
/// (multi-start Riemannian Newton ascent from the luminance axis) are in
/// the module docs. Deterministic.
pub fn solve_zh3_axis(l2: &[Vec3; 9], w: AxisWeights) -> Zh3 {
    let l1 = l1_of(l2);
    let start = shared_axis(&l1);
    let wv = w.weights().as_dvec3();
    let bands: [[f64; 5]; 3] = [0, 1, 2].map(|ch| band2(l2, ch).map(|x| x as f64));
    let scale = bands
        .iter()
        .flat_map(|b| b.iter())
        .fold(0.0f64, |m, x| m.max(x.abs()));
    if scale <= 0.0 || !scale.is_finite() {
        return fit_with_axes(l2, [start; 3]);
    }
    let ms = bands.map(|b| band2_matrix(&b.map(|x| x / scale)));
    let mut starts: Vec<DVec3> = vec![start.as_dvec3()];
    if let Some(a) = weighted_axis(&l1, w.weights()) {
        starts.push(a.as_dvec3());
    }
    for ch in 0..3 {
        if let Some(a) = l1_vector(&l1, ch).try_normalize() {
            starts.push(a.as_dvec3());
        }
        starts.extend(symmetric_eigen3(ms[ch]).1);
    }
    let mut sum = [[0.0f64; 3]; 3];
    for ch in 0..3 {
        for r in 0..3 {
            for c in 0..3 {
                sum[r][c] += wv[ch] * ms[ch][r][c];
            }
        }
    }
    starts.extend(symmetric_eigen3(sum).1);
    let mut best = ascend(&ms, wv, starts[0]);
    for s in &starts[1..] {
        let cand = ascend(&ms, wv, *s);
        if cand.0 > best.0 {
            best = cand;
        }
    }
    let axis = best.1.as_vec3().normalize();
    // Guard against f32 rounding making the solved axis (marginally) worse
    // than the start.
    let axis = if zh3_axis_error(l2, axis, w) <= zh3_axis_error(l2, start, w) {
        axis
    } else {
        start
    };
    fit_with_axes(l2, [axis; 3])
}

/// Hallucinated ZH3 as a [`Zh3`]: shared luminance axis from L1, and per
/// channel the zonal coefficient `c0·(0.08·r + 0.6·r²)` with
/// `r = |v·a| / c0`, `v` the channel's band-1 vector ([`l1_vector`]) and `a` the
/// luminance axis (seed 004, `SHHallucinateZH3Irradiance`, curve fit of §3.4.3;
/// `r` is the raw coefficient ratio, in `[0, √3]` for non-negative radiance).
/// Channels with `c0 ≤ 0`, or L1 whose luminance has no band-1 vector, get a
/// zonal coefficient of 0 (the talk's shader would divide by zero).
pub fn zh3_hallucinate(l1: &[Vec3; 4]) -> Zh3 {
    let mut zonal = Vec3::ZERO;
    let axis = luminance_axis(l1);
    if let Some(a) = axis {
        for ch in 0..3 {
            let c0 = l1[0][ch];
            if c0 > 0.0 && c0.is_finite() {
                let r = l1_vector(l1, ch).dot(a).abs() / c0;
                zonal[ch] = c0 * (0.08 * r + 0.6 * r * r);
            }
        }
    }
    Zh3 {
        l1: *l1,
        zonal,
        axes: [axis.unwrap_or(Vec3::Y); 3],
    }
}

/// Irradiance `E(n)` (not divided by π) for unit normal `n` from L1 radiance
/// SH by hallucinated ZH3 (seed 004, `SHHallucinateZH3Irradiance`; coefficient
/// as in [`zh3_hallucinate`]). Fast path with no intermediate struct; the
/// talk's `0.25` (normalised cosine kernel) is `π/4` here because our
/// irradiance is not divided by π.
pub fn zh3_hallucinated_irradiance(l1: &[Vec3; 4], n: Vec3) -> Vec3 {
    let mut e = irradiance_l1(l1, n);
    let Some(a) = luminance_axis(l1) else {
        return e;
    };
    let zh = y20(a.dot(n)) * core::f32::consts::FRAC_PI_4;
    // Per-channel v·a for all three channels at once: v = (−c3, −c1, c2).
    let c0 = l1[0];
    let r = (l1[2] * a.z - l1[3] * a.x - l1[1] * a.y).abs() / c0;
    let zonal = c0 * (0.08 * r + 0.6 * r * r);
    let valid = c0.cmpgt(Vec3::ZERO) & c0.is_finite_mask();
    e += Vec3::select(valid, zonal * zh, Vec3::ZERO);
    e
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::{Y00, Y1};
    use crate::convolve::{eval_sh, irradiance_l2};
    use crate::numeric::fibonacci_sphere;
    use proptest::prelude::*;

    fn unit(x: f32, y: f32, z: f32) -> Vec3 {
        Vec3::new(x, y, z).try_normalize().unwrap_or(Vec3::X)
    }

    /// L2 coefficients of a zonal signal about `axis` with per-channel zonal
    /// coefficients `z[l]`, built by evaluating the zonal function itself on a
    /// quadrature (not by `zh_to_sh`): project `Σ_l z_l Y_l0(axis·ω)`.
    fn zonal_signal_by_quadrature(axis: Vec3, z: [Vec3; 3]) -> [Vec3; 9] {
        let dirs = fibonacci_sphere(20_000);
        let w = 4.0 * std::f64::consts::PI / dirs.len() as f64;
        let mut c = [glam::DVec3::ZERO; 9];
        for d in &dirs {
            let t = axis.as_dvec3().dot(*d);
            let y = [
                0.5 / std::f64::consts::PI.sqrt(),
                (3.0 / (4.0 * std::f64::consts::PI)).sqrt() * t,
                (5.0 / (16.0 * std::f64::consts::PI)).sqrt() * (3.0 * t * t - 1.0),
            ];
            let f = z[0].as_dvec3() * y[0] + z[1].as_dvec3() * y[1] + z[2].as_dvec3() * y[2];
            let b = eval_l2(d.as_vec3());
            for i in 0..9 {
                c[i] += f * (b[i] as f64) * w;
            }
        }
        c.map(|v| v.as_vec3())
    }

    #[test]
    fn recovers_zonal_signal_built_by_quadrature() {
        let axis = unit(0.3, -0.8, 0.5);
        let z = [
            Vec3::new(2.0, 1.5, 1.0),
            Vec3::new(0.9, 0.6, -0.2),
            Vec3::new(0.4, -0.3, 0.25),
        ];
        let l2 = zonal_signal_by_quadrature(axis, z);
        for fit in [
            fit_zh3_shared(&l2),
            fit_zh3_per_channel(&l2),
            solve_zh3_axis(&l2, AxisWeights::Luminance),
            solve_zh3_axis(&l2, AxisWeights::Equal),
        ] {
            assert!(
                (fit.zonal - z[2]).length() < 2e-3,
                "{} vs {}",
                fit.zonal,
                z[2]
            );
            let back = fit.to_l2();
            for i in 0..9 {
                assert!((back[i] - l2[i]).length() < 2e-3, "coefficient {i}");
            }
        }
    }

    proptest! {
        /// ZH3 reproduces any zonal L2 signal exactly (random axis, random
        /// zonal coefficients; the luminance band-1 vector is kept away from 0
        /// so the axis is defined).
        #[test]
        fn reproduces_any_zonal_l2(
            ax in -1.0f32..1.0, ay in -1.0f32..1.0, az in -1.0f32..1.0,
            z0 in prop::array::uniform3(0.5f32..3.0),
            z1 in prop::array::uniform3(0.2f32..1.0),
            g1 in 1.0f32..2.0,
            s1 in prop::array::uniform3(prop::bool::ANY),
            z2 in prop::array::uniform3(-1.0f32..1.0),
        ) {
            let axis = unit(ax, ay, az);
            // Green dominates the luminance so its band-1 vector cannot cancel.
            let mut z1v = Vec3::from(z1);
            z1v.y = g1;
            for ch in [0, 2] { if s1[ch] { z1v[ch] = -z1v[ch]; } }
            let zh = [Vec3::from(z0), z1v, Vec3::from(z2)];
            let mut l2 = [Vec3::ZERO; 9];
            for ch in 0..3 {
                let mut c = [0.0f32; 9];
                zh_to_sh(&[zh[0][ch], zh[1][ch], zh[2][ch]], axis, &mut c);
                for i in 0..9 { l2[i][ch] = c[i]; }
            }
            for fit in [
                fit_zh3_shared(&l2),
                fit_zh3_per_channel(&l2),
                solve_zh3_axis(&l2, AxisWeights::Luminance),
                solve_zh3_axis(&l2, AxisWeights::Equal),
            ] {
                let back = fit.to_l2();
                for i in 0..9 {
                    prop_assert!((back[i] - l2[i]).length() < 1e-4, "coefficient {} {} vs {}", i, back[i], l2[i]);
                }
            }
        }
    }

    /// Without a band-1 vector the L1-derived axes are undefined (they fall
    /// back to +Y), but the solve still finds the zonal axis exactly.
    #[test]
    fn solve_recovers_zonal_signal_without_band1() {
        let axis = unit(0.6, -0.2, 0.77);
        let mut l2 = [Vec3::ZERO; 9];
        for (ch, z2) in [0.4f32, -0.3, 0.2].into_iter().enumerate() {
            let mut c = [0.0f32; 9];
            zh_to_sh(&[1.0, 0.0, z2], axis, &mut c);
            for i in 0..9 {
                l2[i][ch] = c[i];
            }
        }
        for w in [AxisWeights::Equal, AxisWeights::Luminance] {
            let back = solve_zh3_axis(&l2, w).to_l2();
            for i in 0..9 {
                assert!((back[i] - l2[i]).length() < 1e-5, "coefficient {i}");
            }
        }
        assert_eq!(fit_zh3_shared(&l2).axes[0], Vec3::Y);
    }

    /// ZH3 irradiance (fast path) against brute-force cosine integration of the
    /// ZH3 radiance reconstructed from its expansion.
    #[test]
    fn irradiance_matches_brute_force() {
        let zh = Zh3 {
            l1: [
                Vec3::new(1.0, 1.2, 0.9),
                Vec3::new(0.2, -0.1, 0.3),
                Vec3::new(-0.3, 0.2, 0.1),
                Vec3::new(0.1, 0.1, -0.2),
            ],
            zonal: Vec3::new(0.3, -0.2, 0.5),
            axes: [
                unit(1.0, 0.2, 0.0),
                unit(0.0, 1.0, 0.3),
                unit(-0.4, 0.1, 1.0),
            ],
        };
        let l2 = zh.to_l2();
        let dirs = fibonacci_sphere(60_000);
        let w = 4.0 * std::f64::consts::PI / dirs.len() as f64;
        for n in fibonacci_sphere(9) {
            let mut e = glam::DVec3::ZERO;
            for d in &dirs {
                let c = n.dot(*d);
                if c > 0.0 {
                    // radiance from the ZH3 definition, not from to_l2
                    let mut l = glam::DVec3::ZERO;
                    let b = eval_l2(d.as_vec3());
                    for i in 0..4 {
                        l += zh.l1[i].as_dvec3() * b[i] as f64;
                    }
                    for ch in 0..3 {
                        l[ch] += (zh.zonal[ch] * y20(zh.axes[ch].dot(d.as_vec3()))) as f64;
                    }
                    e += l * c * w;
                }
            }
            let got = zh.irradiance(n.as_vec3()).as_dvec3();
            assert!((got - e).length() < 3e-3, "{got} vs {e}");
            let via_l2 = irradiance_l2(&l2, n.as_vec3()).as_dvec3();
            assert!((got - via_l2).length() < 1e-4);
            let rad = eval_sh(&l2, n.as_vec3());
            assert!(rad.is_finite());
        }
    }

    /// Hallucinated ZH3 against an independent evaluation: the seed's formula
    /// written out by hand (luminance axis, ratio, curve fit) and expanded to
    /// L2 via `zh_to_sh`, evaluated with the L2 fast path.
    #[test]
    fn hallucinated_matches_independent_evaluation() {
        let l1 = [
            Vec3::new(1.2, 1.0, 0.8),
            Vec3::new(-0.3, -0.2, -0.1),
            Vec3::new(0.4, 0.5, 0.2),
            Vec3::new(0.1, -0.2, 0.05),
        ];
        // By hand: luminance vector, axis, ratios.
        let lum = |c: Vec3| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
        let lv = Vec3::new(-lum(l1[3]), -lum(l1[1]), lum(l1[2]));
        let axis = lv / lv.length();
        let mut l2 = [Vec3::ZERO; 9];
        l2[..4].copy_from_slice(&l1);
        for ch in 0..3 {
            let v = Vec3::new(-l1[3][ch], -l1[1][ch], l1[2][ch]);
            let r = (v.dot(axis)).abs() / l1[0][ch];
            let z = l1[0][ch] * (0.08 * r + 0.6 * r * r);
            let mut c = [0.0f32; 9];
            zh_to_sh(&[0.0, 0.0, z], axis, &mut c);
            for i in 4..9 {
                l2[i][ch] = c[i];
            }
        }
        for n in fibonacci_sphere(40) {
            let n = n.as_vec3();
            let a = zh3_hallucinated_irradiance(&l1, n);
            let b = irradiance_l2(&l2, n);
            assert!((a - b).length() < 1e-5, "{a} vs {b}");
            let c = zh3_hallucinate(&l1).irradiance(n);
            assert!((a - c).length() < 1e-5);
        }
    }

    #[test]
    fn hallucinated_handles_degenerate_input() {
        let flat = [Vec3::splat(1.0 / Y00), Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
        let e = zh3_hallucinated_irradiance(&flat, Vec3::Z);
        assert!((e - Vec3::splat(std::f32::consts::PI)).length() < 1e-5);
        let neg = [Vec3::splat(-1.0), Vec3::splat(0.2), Vec3::ZERO, Vec3::ZERO];
        assert!(zh3_hallucinated_irradiance(&neg, Vec3::Y).is_finite());
        // A delta: ratio r = √3 along the axis.
        let d = unit(0.2, 0.7, -0.4);
        let delta = [
            Vec3::splat(Y00),
            Vec3::splat(-Y1 * d.y),
            Vec3::splat(Y1 * d.z),
            Vec3::splat(-Y1 * d.x),
        ];
        let z = zh3_hallucinate(&delta).zonal.x;
        let r = 3f32.sqrt();
        assert!((z - Y00 * (0.08 * r + 0.6 * r * r)).abs() < 1e-5);
    }

    /// The closed-form error equals brute-force quadrature of the squared
    /// irradiance difference over the sphere.
    #[test]
    fn closed_form_error_matches_quadrature() {
        let l2 = random_l2(7);
        let zh = fit_zh3_shared(&l2);
        let w = Vec3::new(0.2126, 0.7152, 0.0722);
        let closed = weighted_irradiance_error(&zh.to_l2(), &l2, w);
        let closed2 = zh3_axis_error(&l2, zh.axes[0], AxisWeights::Luminance);
        let quad = quadrature_error(&zh, &l2, w);
        assert!(
            (closed - quad).abs() < 1e-3 * quad.max(1e-6),
            "{closed} vs {quad}"
        );
        assert!(
            (closed2 - quad).abs() < 1e-3 * quad.max(1e-6),
            "{closed2} vs {quad}"
        );
    }

    fn quadrature_error(zh: &Zh3, l2: &[Vec3; 9], w: Vec3) -> f64 {
        let dirs = fibonacci_sphere(20_000);
        let mut e = 0.0;
        for d in &dirs {
            let n = d.as_vec3();
            let diff = (zh.irradiance(n) - irradiance_l2(l2, n)).as_dvec3();
            e += (diff * diff).dot(w.as_dvec3());
        }
        e * 4.0 * std::f64::consts::PI / dirs.len() as f64
    }

    /// Deterministic pseudo-random L2 radiance of a non-negative-ish environment.
    fn random_l2(seed: u64) -> [Vec3; 9] {
        let mut s = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 33) as f64 / (1u64 << 31) as f64) as f32 * 2.0 - 1.0
        };
        let mut c = [Vec3::ZERO; 9];
        c[0] = Vec3::new(2.0 + next(), 2.0 + next(), 2.0 + next());
        for ci in c.iter_mut().skip(1) {
            *ci = Vec3::new(next(), next(), next()) * 0.8;
        }
        c
    }

    /// The solved axis is never worse than the shared luminance axis,
    /// measured by brute-force quadrature with the same weights.
    #[test]
    fn solved_axis_not_worse_than_shared_by_quadrature() {
        let mut strictly_better = 0;
        for seed in 0..12 {
            let l2 = random_l2(seed);
            let shared = fit_zh3_shared(&l2);
            for w in [AxisWeights::Equal, AxisWeights::Luminance] {
                let solved = solve_zh3_axis(&l2, w);
                let es = quadrature_error(&shared, &l2, w.weights());
                let ev = quadrature_error(&solved, &l2, w.weights());
                assert!(
                    ev <= es * (1.0 + 1e-3) + 1e-7,
                    "seed {seed}: solved {ev} > shared {es}"
                );
                if ev < 0.9 * es {
                    strictly_better += 1;
                }
                // The solved axis is a stationary point: nearby axes are not better.
                let a = solved.axes[0];
                let base = zh3_axis_error(&l2, a, w);
                for p in fibonacci_sphere(12) {
                    let b = (a + p.as_vec3() * 0.02).normalize();
                    assert!(zh3_axis_error(&l2, b, w) >= base - 1e-6 * (1.0 + base));
                }
            }
        }
        assert!(
            strictly_better > 0,
            "the solve never improved on the shared axis"
        );
    }

    /// The solved axis is the global optimum: no axis of a dense brute-force
    /// search (20 000 Fibonacci axes) has a lower closed-form error.
    #[test]
    fn solved_axis_matches_brute_force_search() {
        let axes: Vec<Vec3> = fibonacci_sphere(20_000)
            .iter()
            .map(|d| d.as_vec3())
            .collect();
        for seed in 20..26 {
            let l2 = random_l2(seed);
            for w in [AxisWeights::Equal, AxisWeights::Luminance] {
                let solved = zh3_axis_error(&l2, solve_zh3_axis(&l2, w).axes[0], w);
                let brute = axes
                    .iter()
                    .map(|a| zh3_axis_error(&l2, *a, w))
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    solved <= brute * (1.0 + 1e-4) + 1e-9,
                    "seed {seed}: solved {solved} > brute force {brute}"
                );
            }
        }
    }

    /// The quadratic form used by the solver equals the band-2 function.
    #[test]
    fn band2_matrix_matches_basis() {
        let b = [0.3f32, -0.7, 0.5, 0.2, -0.4];
        let m = band2_matrix(&b.map(|x| x as f64));
        for d in fibonacci_sphere(30) {
            let direct: f32 = (0..5).map(|k| b[k] * eval_l2(d.as_vec3())[4 + k]).sum();
            let quad = d.dot(mat_vec(&m, d));
            assert!((direct as f64 - quad).abs() < 1e-5);
        }
    }
}
