//! Zonal harmonics (ZH): functions symmetric about an axis, stored as one
//! coefficient per band (the coefficient of `Y_l0` when the axis is +Z), and
//! their rotation to any axis (Sloan, *Stupid SH Tricks*, §"Zonal Harmonics":
//! `c_lm = sqrt(4π/(2l+1)) · z_l · Y_lm(axis)`).

use crate::basis::{eval_basis, num_coeffs, MAX_COEFFS};
#[cfg(not(feature = "std"))]
use crate::math::FloatMath;
use glam::Vec3;

/// Rotates zonal coefficients `zh` (one per band, `zh.len()` bands) to unit
/// `axis`, writing `zh.len()²` SH coefficients into `out`.
///
/// # Panics
/// If `zh` is empty or longer than [`crate::MAX_ORDER`], or `out` is too short.
pub fn zh_to_sh(zh: &[f32], axis: Vec3, out: &mut [f32]) {
    let order = zh.len();
    let mut b = [0.0f32; MAX_COEFFS];
    eval_basis(order, axis, &mut b);
    for (l, z) in zh.iter().enumerate() {
        let f = (4.0 * core::f32::consts::PI / (2 * l + 1) as f32).sqrt() * z;
        for i in l * l..(l + 1) * (l + 1) {
            out[i] = f * b[i];
        }
    }
    debug_assert!(out.len() >= num_coeffs(order));
}

/// Evaluates a zonal function with coefficients `zh` (about +Z) at `cos θ`,
/// where θ is the angle from its axis: `Σ z_l Y_l0(θ)`, Legendre recurrence.
pub fn eval_zonal(zh: &[f32], cos_theta: f32) -> f32 {
    let x = cos_theta as f64;
    let (mut p0, mut p1) = (1.0f64, x);
    let mut sum = 0.0f64;
    for (l, z) in zh.iter().enumerate() {
        let p = match l {
            0 => 1.0,
            1 => x,
            _ => {
                let p2 = ((2 * l - 1) as f64 * x * p1 - (l - 1) as f64 * p0) / l as f64;
                p0 = p1;
                p1 = p2;
                p2
            }
        };
        let k = ((2 * l + 1) as f64 / (4.0 * core::f64::consts::PI)).sqrt();
        sum += *z as f64 * k * p;
    }
    sum as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::convolve::eval_sh;

    #[test]
    fn rotated_zh_matches_direct_legendre() {
        let zh = [0.7f32, -0.4, 0.25, 0.1, -0.05, 0.02, 0.01, -0.01];
        let axis = Vec3::new(0.3, -0.5, 0.81).normalize();
        let mut c = [0.0f32; 64];
        zh_to_sh(&zh, axis, &mut c);
        let coeffs: Vec<Vec3> = c.iter().map(|v| Vec3::splat(*v)).collect();
        for i in 0..50 {
            let t = i as f32 * 0.37;
            let d = Vec3::new(
                t.cos() * (t * 0.3).sin(),
                (t * 0.3).cos(),
                t.sin() * (t * 0.3).sin(),
            )
            .normalize();
            let a = eval_sh(&coeffs, d).x;
            let b = eval_zonal(&zh, axis.dot(d));
            assert!((a - b).abs() < 1e-4, "{a} vs {b}");
        }
    }
}
