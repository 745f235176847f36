//! Projection helpers: the spherical Fibonacci point set and deterministic
//! quadrature projection of a function onto SH.
//!
//! The spherical Fibonacci set (González, *Measurement of areas on a sphere
//! using Fibonacci and latitude–longitude lattices*, Math. Geosci. 2010) puts
//! point `i` of `n` at `z = 1 − (2i + 1)/n`, `φ = i · π(3 − √5)` (the golden
//! angle), `d = (√(1−z²)·cos φ, √(1−z²)·sin φ, z)`. Every point stands for the
//! same solid angle `4π/n`, so `∫ f dω ≈ (4π/n) Σ f(dᵢ)`; for smooth
//! (band-limited) integrands the error falls off roughly as `1/n`.
//!
//! **This is the point set used across the crate's tests and numerical
//! searches** ([`crate::window::min_over_sphere`], the rotation and windowing
//! tests): use [`fibonacci_sphere`] or the allocation-free
//! [`fibonacci_point`] rather than writing another lattice.

use crate::basis::{eval_basis_f64, num_coeffs, MAX_COEFFS};
use crate::coeffs::ShRgb;
#[cfg(not(feature = "std"))]
use crate::math::FloatMath;
use alloc::vec::Vec;
use glam::{DVec3, Vec3};

/// The golden angle `π(3 − √5)` in radians.
const GOLDEN_ANGLE: f64 = 2.399_963_229_728_653;

/// Point `i` of the `n`-point spherical Fibonacci set, in f64 (see the module
/// docs for the formula). No allocation.
///
/// `i` should be `< n`; `n` must be non-zero.
#[inline]
pub fn fibonacci_point_f64(i: usize, n: usize) -> DVec3 {
    let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = GOLDEN_ANGLE * i as f64;
    let (s, c) = phi.sin_cos();
    DVec3::new(r * c, r * s, z)
}

/// Point `i` of the `n`-point spherical Fibonacci set (unit vector, f32).
/// No allocation.
#[inline]
pub fn fibonacci_point(i: usize, n: usize) -> Vec3 {
    fibonacci_point_f64(i, n).as_vec3()
}

/// The `n`-point spherical Fibonacci set: `n` unit directions of equal solid
/// angle `4π/n`, deterministic (module docs give the formula). The point set
/// shared by the crate's tests and numerical searches.
pub fn fibonacci_sphere(n: usize) -> Vec<Vec3> {
    (0..n).map(|i| fibonacci_point(i, n)).collect()
}

/// Projects the function `f` (radiance, linear RGB, of a unit direction) onto
/// `order` bands of SH by `samples`-point spherical Fibonacci quadrature:
/// `c_lm = (4π/n) Σ f(dᵢ) Y_lm(dᵢ)`, accumulated in f64. Deterministic: the
/// same `f` and `samples` give the same bits.
///
/// Exact up to quadrature error for band-limited `f`; for a map with sharp
/// features it is a Monte-Carlo-like estimate whose error falls with `samples`.
///
/// # Panics
/// If `order` is 0 or greater than [`crate::MAX_ORDER`], or `samples` is 0.
pub fn project_fn(order: usize, f: impl Fn(Vec3) -> Vec3, samples: usize) -> ShRgb {
    assert!(samples > 0, "project_fn needs at least one sample");
    let mut out = ShRgb::zeros(order);
    let nc = num_coeffs(order);
    let mut acc = [DVec3::ZERO; MAX_COEFFS];
    let mut b = [0.0f64; MAX_COEFFS];
    for i in 0..samples {
        let d = fibonacci_point_f64(i, samples);
        let v = f(d.as_vec3()).as_dvec3();
        eval_basis_f64(order, d, &mut b);
        for (a, y) in acc[..nc].iter_mut().zip(&b[..nc]) {
            *a += v * *y;
        }
    }
    let w = 4.0 * core::f64::consts::PI / samples as f64;
    for (c, a) in out.coeffs_mut().iter_mut().zip(&acc[..nc]) {
        *c = (*a * w).as_vec3();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::convolve::eval_sh;
    use proptest::prelude::*;

    #[test]
    fn points_are_unit_and_balanced() {
        let pts = fibonacci_sphere(5000);
        let mut mean = DVec3::ZERO;
        for p in &pts {
            assert!((p.length() - 1.0).abs() < 1e-6);
            mean += p.as_dvec3();
        }
        // An equal-area set has (almost) zero centroid.
        assert!((mean / 5000.0).length() < 1e-3, "{mean}");
        // Area check against an independent integral: the cap z > 0.5 has
        // solid angle 2π(1 − 0.5) = π, i.e. a quarter of the points.
        let cap = pts.iter().filter(|p| p.z > 0.5).count();
        assert!((cap as f64 / 5000.0 - 0.25).abs() < 1e-3);
    }

    /// The quadrature integrates a known polynomial: ∫ z² dω = 4π/3 and
    /// ∫ x²y² dω = 4π/15 (exact values from the moments of the sphere).
    #[test]
    fn quadrature_integrates_polynomials() {
        let n = 20_000;
        let w = 4.0 * std::f64::consts::PI / n as f64;
        let (mut a, mut b) = (0.0, 0.0);
        for i in 0..n {
            let d = fibonacci_point_f64(i, n);
            a += d.z * d.z * w;
            b += d.x * d.x * d.y * d.y * w;
        }
        let pi = std::f64::consts::PI;
        assert!((a - 4.0 * pi / 3.0).abs() < 1e-4, "{a}");
        assert!((b - 4.0 * pi / 15.0).abs() < 1e-4, "{b}");
    }

    #[test]
    fn project_constant() {
        let sh = project_fn(3, |_| Vec3::new(1.0, 2.0, 3.0), 4000);
        // ∫ c·Y00 dω = c · 4π · Y00 = c · 2√π.
        let k = 2.0 * std::f32::consts::PI.sqrt();
        assert!((sh.coeffs()[0] - Vec3::new(k, 2.0 * k, 3.0 * k)).length() < 1e-5);
        for c in &sh.coeffs()[1..] {
            assert!(c.length() < 1e-3 * k, "{c}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        /// Projecting a band-limited function (random coefficients, up to 5
        /// bands) reproduces its coefficients to quadrature accuracy.
        #[test]
        fn projection_of_band_limited_is_exact(
            order in 1usize..=5,
            raw in proptest::collection::vec(-1.0f32..1.0, 75),
        ) {
            let n = num_coeffs(order);
            let truth: Vec<Vec3> = (0..n)
                .map(|i| Vec3::new(raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]))
                .collect();
            let sh = project_fn(order, |d| eval_sh(&truth, d), 16_000);
            for (a, b) in sh.coeffs().iter().zip(&truth) {
                prop_assert!((*a - *b).abs().max_element() < 2e-3, "{} vs {}", a, b);
            }
        }
    }
}
