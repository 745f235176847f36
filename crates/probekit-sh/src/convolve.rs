//! Convolution with zonal kernels, in particular the clamped cosine that turns
//! radiance SH into irradiance (Ramamoorthi & Hanrahan, *An Efficient
//! Representation for Irradiance Environment Maps*, SIGGRAPH 2001).
//!
//! Irradiance here is `E(n) = ∫ L(ω) max(0, n·ω) dω`, **not** divided by π.
//! For radiance coefficients `L_lm`, `E_lm = Â_l · L_lm` with
//! `Â_0 = π`, `Â_1 = 2π/3`, `Â_2 = π/4`, `Â_3 = 0`, `Â_4 = −π/24`, …

use crate::basis::{eval_basis, num_coeffs, order_from_len, MAX_COEFFS};
#[cfg(not(feature = "std"))]
use crate::math::FloatMath;
use alloc::vec::Vec;
use glam::Vec3;

/// The clamped-cosine convolution factor `Â_l` for band `l` (Ramamoorthi &
/// Hanrahan 2001, eq. 8 and 9), in f64: multiply band-`l` radiance coefficients
/// by it to get irradiance coefficients.
pub fn clamped_cosine_band(l: usize) -> f64 {
    use core::f64::consts::PI;
    match l {
        0 => PI,
        1 => 2.0 * PI / 3.0,
        _ if l % 2 == 1 => 0.0,
        _ => {
            // 2π (-1)^{l/2-1} / ((l+2)(l-1)) · l! / (2^l ((l/2)!)²)
            let half = l / 2;
            let sign = if (half - 1) % 2 == 0 { 1.0 } else { -1.0 };
            // l! / (2^l (l/2)!²) = binomial(l, l/2) / 2^l, computed stably
            let mut c = 1.0f64;
            for k in 1..=half {
                c *= (half + k) as f64 / k as f64;
            }
            c /= 2f64.powi(l as i32);
            2.0 * PI * sign / (((l + 2) * (l - 1)) as f64) * c
        }
    }
}

/// Funk–Hecke factor for convolving with a zonal kernel given by its zonal
/// coefficients `z_l` (coefficients of `Y_l0` of a kernel symmetric about +Z):
/// band `l` of the result is `sqrt(4π/(2l+1)) · z_l` times band `l` of the input.
pub fn zonal_band_factor(l: usize, z_l: f64) -> f64 {
    (4.0 * core::f64::consts::PI / (2 * l + 1) as f64).sqrt() * z_l
}

/// Multiplies every coefficient of band `l` by `scales[l]`, in place.
/// `coeffs.len()` must be a perfect square; bands past `scales.len()` are zeroed.
pub fn scale_bands(coeffs: &mut [Vec3], scales: &[f32]) {
    let order = order_from_len(coeffs.len()).expect("coefficient count must be a perfect square");
    for l in 0..order {
        let s = scales.get(l).copied().unwrap_or(0.0);
        for c in &mut coeffs[l * l..(l + 1) * (l + 1)] {
            *c *= s;
        }
    }
}

/// Turns radiance SH into irradiance SH in place (band `l` times `Â_l`).
pub fn radiance_to_irradiance(coeffs: &mut [Vec3]) {
    let order = order_from_len(coeffs.len()).expect("coefficient count must be a perfect square");
    let scales: Vec<f32> = (0..order).map(|l| clamped_cosine_band(l) as f32).collect();
    scale_bands(coeffs, &scales);
}

/// Evaluates a reconstruction `Σ c_lm Y_lm(d)` of SH coefficients of any order
/// (`coeffs.len()` a perfect square ≤ 64) at unit direction `d`. No allocation.
pub fn eval_sh(coeffs: &[Vec3], d: Vec3) -> Vec3 {
    let order = order_from_len(coeffs.len()).expect("coefficient count must be a perfect square");
    let mut b = [0.0f32; MAX_COEFFS];
    eval_basis(order, d, &mut b);
    coeffs
        .iter()
        .zip(b.iter())
        .fold(Vec3::ZERO, |acc, (c, y)| acc + *c * *y)
}

/// Irradiance `E(n)` (not divided by π) for unit normal `n` from **radiance**
/// SH of any order. No allocation.
pub fn irradiance(coeffs: &[Vec3], n: Vec3) -> Vec3 {
    let order = order_from_len(coeffs.len()).expect("coefficient count must be a perfect square");
    let mut b = [0.0f32; MAX_COEFFS];
    eval_basis(order, n, &mut b);
    let mut e = Vec3::ZERO;
    for l in 0..order {
        let a = clamped_cosine_band(l) as f32;
        for i in l * l..(l + 1) * (l + 1) {
            e += coeffs[i] * (b[i] * a);
        }
    }
    e
}

/// Fast path: irradiance from L1 radiance SH (4 coefficients).
#[inline]
pub fn irradiance_l1(c: &[Vec3; 4], n: Vec3) -> Vec3 {
    use crate::basis::{Y00, Y1};
    const A0: f32 = core::f32::consts::PI;
    const A1: f32 = 2.0 * core::f32::consts::PI / 3.0;
    c[0] * (A0 * Y00) + (c[1] * -n.y + c[2] * n.z + c[3] * -n.x) * (A1 * Y1)
}

/// Fast path: irradiance from L2 radiance SH (9 coefficients).
#[inline]
pub fn irradiance_l2(c: &[Vec3; 9], n: Vec3) -> Vec3 {
    const A0: f32 = core::f32::consts::PI;
    const A1: f32 = 2.0 * core::f32::consts::PI / 3.0;
    const A2: f32 = core::f32::consts::PI / 4.0;
    let b = crate::basis::eval_l2(n);
    c[0] * (A0 * b[0])
        + (c[1] * b[1] + c[2] * b[2] + c[3] * b[3]) * A1
        + (c[4] * b[4] + c[5] * b[5] + c[6] * b[6] + c[7] * b[7] + c[8] * b[8]) * A2
}

/// Number of coefficients of L1 (4) and L2 (9), re-exported for readability.
pub const L1_COEFFS: usize = num_coeffs(2);
/// See [`L1_COEFFS`].
pub const L2_COEFFS: usize = num_coeffs(3);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::{eval_basis_f64, MAX_ORDER};
    use glam::DVec3;

    fn fib(n: usize) -> Vec<DVec3> {
        let ga = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
                let r = (1.0 - z * z).sqrt();
                DVec3::new(r * (ga * i as f64).cos(), r * (ga * i as f64).sin(), z)
            })
            .collect()
    }

    /// `Â_l` against direct numerical integration of the clamped cosine's
    /// zonal coefficients: `Â_l = sqrt(4π/(2l+1)) · ∫ max(0,cosθ) Y_l0 dω`.
    #[test]
    fn clamped_cosine_matches_quadrature() {
        let dirs = fib(200_000);
        let w = 4.0 * std::f64::consts::PI / dirs.len() as f64;
        let mut b = [0.0f64; 64];
        let mut z = [0.0f64; MAX_ORDER];
        for d in &dirs {
            eval_basis_f64(MAX_ORDER, *d, &mut b);
            let c = d.z.max(0.0);
            for (l, zl) in z.iter_mut().enumerate() {
                *zl += c * b[l * (l + 1)] * w;
            }
        }
        for (l, zl) in z.iter().enumerate() {
            let expect = zonal_band_factor(l, *zl);
            let got = clamped_cosine_band(l);
            assert!(
                (expect - got).abs() < 2e-4,
                "band {l}: quadrature {expect}, formula {got}"
            );
        }
        assert!((clamped_cosine_band(4) + std::f64::consts::PI / 24.0).abs() < 1e-12);
    }

    /// Irradiance of a band-limited radiance against brute-force cosine integration.
    #[test]
    fn irradiance_matches_brute_force() {
        let coeffs: Vec<Vec3> = (0..9)
            .map(|i| {
                Vec3::new(
                    1.0 / (1.0 + i as f32),
                    0.3 * (i as f32).sin(),
                    0.1 * i as f32,
                )
            })
            .collect();
        let dirs = fib(100_000);
        let w = 4.0 * std::f64::consts::PI / dirs.len() as f64;
        for n in fib(7) {
            let mut e = glam::DVec3::ZERO;
            for d in &dirs {
                let c = n.dot(*d);
                if c > 0.0 {
                    e += eval_sh(&coeffs, d.as_vec3()).as_dvec3() * c * w;
                }
            }
            let got = irradiance(&coeffs, n.as_vec3()).as_dvec3();
            assert!(
                (e - got).length() < 2e-3 * (1.0 + e.length()),
                "{e} vs {got}"
            );
            let arr: [Vec3; 9] = coeffs.clone().try_into().unwrap();
            let fast = irradiance_l2(&arr, n.as_vec3()).as_dvec3();
            assert!((fast - got).length() < 1e-5);
            let arr1: [Vec3; 4] = coeffs[..4].try_into().unwrap();
            let fast1 = irradiance_l1(&arr1, n.as_vec3());
            let slow1 = irradiance(&coeffs[..4], n.as_vec3());
            assert!((fast1 - slow1).length() < 1e-5);
        }
    }

    /// A constant sky of radiance 1 gives irradiance π for every normal.
    #[test]
    fn constant_sky_gives_pi() {
        let c = [
            Vec3::splat(1.0 / crate::basis::Y00),
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::ZERO,
        ];
        let e = irradiance_l1(&c, Vec3::new(0.3, 0.4, 0.866).normalize());
        assert!((e - Vec3::splat(std::f32::consts::PI)).length() < 1e-5);
    }
}
