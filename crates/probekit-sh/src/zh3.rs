//! ZH3: linear SH plus one oriented quadratic zonal harmonic (Roughton,
//! Sloan, Silvennoinen, Iwanicki, Drobot, *ZH3: Quadratic Zonal Harmonics*,
//! I3D 2024).
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

/// Stored ZH3 of linear-RGB **radiance** (Roughton et al.): the L1 coefficients, one
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
    /// before interpolating: ZH3 is non-linear when the axes differ (Roughton et al.,
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
    /// L1 irradiance plus `(π/4)·z·Y2,0(axis·n)` per channel (Roughton et al.,
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
/// shared ZH3 axis of Roughton et al. (`zonalAxis` in `SHHallucinateZH3Irradiance`).
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
/// `sqrt(4π/5)·Σ_m c2,m·Y2,m(axis)` (module docs; Roughton et al., "To compute the
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
/// axis' zonal function (Roughton et al., "use the same axis for all three channels").
pub fn fit_zh3_shared(l2: &[Vec3; 9]) -> Zh3 {
    let a = shared_axis(&l1_of(l2));
    fit_with_axes(l2, [a; 3])
}

/// Stored ZH3 with an axis per channel, each from that channel's own L1
/// vector (Roughton et al., "we orient it along the linear SH vector"); a channel
/// without a band-1 vector falls back to [`shared_axis`].
pub fn fit_zh3_per_channel(l2: &[Vec3; 9]) -> Zh3 {
    let l1 = l1_of(l2);
    let fallback = shared_axis(&l1);
    let axes = [0, 1, 2].map(|ch| l1_vector(&l1, ch).try_normalize().unwrap_or(fallback));
    fit_with_axes(l2, axes)
}

/// Colour-channel weights of the shared-axis solve; the error is weighted the
/// same way (Roughton et al.: "make sure the error function uses the same weights").
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
/// error against the L2 irradiance over the whole sphere (Roughton et al., "solving
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
/// luminance axis (Roughton et al., `SHHallucinateZH3Irradiance`, curve fit of §3.4.3;
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
/// SH by hallucinated ZH3 (Roughton et al., `SHHallucinateZH3Irradiance`; coefficient
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
mod tests;
