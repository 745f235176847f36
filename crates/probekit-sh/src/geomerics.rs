//! Geomerics' non-negative irradiance reconstruction from L1 radiance SH
//! (Graham Hazel / Geomerics, "Reconstructing diffuse lighting from spherical
//! harmonic data", reference implementation in Probulator; described in
//! Pettineo, *SG Series Part 1*, and cited as \[Joseph15\] in Roughton et al.,
//! *ZH3: Quadratic Zonal Harmonics*, I3D 2024).
//!
//! ## Normalisation
//!
//! For one colour channel with radiance coefficients `c0..c3` (crate
//! conventions), the band-1 part of the radiance is `Y1·(v·ω)` with
//! `v = (−c3, −c1, c2)` in xyz (because `Y1,-1 = −Y1·y`, `Y1,0 = Y1·z`,
//! `Y1,1 = −Y1·x`). The linear irradiance is
//! `E_lin(n) = π·Y00·c0 + (2π/3)·Y1·(v·n)`.
//!
//! - `R0 = π·Y00·c0`: the mean of `E` over the sphere (constant sky `L` gives `πL`).
//! - `|R1|/R0 = |v|/(√3·c0)`: the linear moment of `E_lin` relative to `R0` is
//!   `(2π/3)·Y1·|v| / (π·Y00·c0) = 2|v|/(√3·c0)`, and the model below has
//!   linear moment `2·|R1|/R0` for small `|R1|/R0`, so they agree to first
//!   order. For a non-negative radiance `|v| ≤ √3·c0` (a single delta attains
//!   it), so the ratio lies in `[0, 1]`; it is clamped there for other input.
//! - `R̂1 = v/|v|`, `q = ½(1 + R̂1·n)`, `p = 1 + 2|R1|/R0`,
//!   `a = (1 − |R1|/R0)/(1 + |R1|/R0)`, and
//!   `E(n) = R0·(a + (1 − a)(p + 1)·q^p)`.
//!
//! Because the mean of `(p + 1)·q^p` over the sphere is 1, `E` keeps the mean
//! irradiance `R0` exactly, is non-negative whenever `c0 ≥ 0`, and does not keep
//! the linear moment for strong directionality (it over-brightens; Sloan & Silvennoinen 2020, as cited by Roughton et al. 2024).

// Index loops over colour channels and SH coefficients read like the formulas.
#![allow(clippy::needless_range_loop)]

use crate::basis::Y00;
#[cfg(not(feature = "std"))]
use crate::math::FloatMath;
use glam::Vec3;

/// Irradiance `E(n)` (not divided by π) for unit normal `n` from L1
/// **radiance** SH `c`, by the Geomerics non-negative reconstruction, each
/// colour channel separately with its own direction (module docs give the
/// formula and normalisation; source: Hazel/Geomerics via Probulator,
/// normalised so `E` keeps the mean irradiance `R0`).
///
/// A channel with `c0 ≤ 0` (or non-finite) gives 0; a channel without a
/// band-1 vector gives its mean irradiance `π·Y00·c0`. Never NaN for finite input.
pub fn irradiance_geomerics_l1(c: &[Vec3; 4], n: Vec3) -> Vec3 {
    let mut out = [0.0f32; 3];
    for (ch, o) in out.iter_mut().enumerate() {
        let v = Vec3::new(-c[3][ch], -c[1][ch], c[2][ch]);
        *o = geomerics_channel(c[0][ch], v, n);
    }
    Vec3::from(out)
}

/// One channel: DC coefficient `c0`, band-1 vector `v = (−c3, −c1, c2)`.
fn geomerics_channel(c0: f32, v: Vec3, n: Vec3) -> f32 {
    if c0.is_nan() || c0 <= 0.0 || !c0.is_finite() {
        return 0.0;
    }
    let r0 = core::f32::consts::PI * Y00 * c0;
    let len = v.length();
    if len.is_nan() || len <= 0.0 || !len.is_finite() {
        return r0;
    }
    let ratio = (len / (3f32.sqrt() * c0)).clamp(0.0, 1.0);
    let dir = v / len;
    let q = (0.5 * (1.0 + dir.dot(n))).clamp(0.0, 1.0);
    let p = 1.0 + 2.0 * ratio;
    let a = (1.0 - ratio) / (1.0 + ratio);
    r0 * (a + (1.0 - a) * (p + 1.0) * q.powf(p))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::Y1;
    use crate::convolve::irradiance_l1;
    use crate::numeric::fibonacci_sphere;
    use proptest::prelude::*;

    #[test]
    fn constant_environment_is_exact() {
        let l = Vec3::new(0.5, 1.0, 2.0);
        let c = [l / Y00, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
        for d in fibonacci_sphere(64) {
            let e = irradiance_geomerics_l1(&c, d.as_vec3());
            assert!((e - l * std::f32::consts::PI).length() < 1e-5, "{e}");
        }
    }

    /// The mean of the reconstruction over the sphere (quadrature) is the mean
    /// irradiance `π·Y00·c0`, even for strongly directional input.
    #[test]
    fn mean_irradiance_preserved_by_quadrature() {
        let dirs = fibonacci_sphere(40_000);
        let c = [
            Vec3::new(1.0, 2.0, 0.5),
            Vec3::new(0.3, -0.9, 0.2),
            Vec3::new(-0.5, 1.5, 0.1),
            Vec3::new(0.8, 0.4, -0.6),
        ];
        let mut mean = glam::DVec3::ZERO;
        for d in &dirs {
            mean += irradiance_geomerics_l1(&c, d.as_vec3()).as_dvec3();
        }
        mean /= dirs.len() as f64;
        let expect = c[0].as_dvec3() * (std::f64::consts::PI * Y00 as f64);
        assert!(
            (mean - expect).length() < 2e-3 * expect.length(),
            "{mean} vs {expect}"
        );
    }

    /// Weak directionality: the reconstruction matches the linear (Ramamoorthi–
    /// Hanrahan) L1 irradiance to first order — the difference shrinks like ε².
    #[test]
    fn first_order_matches_linear_irradiance() {
        let base = Vec3::new(1.0, 0.7, 1.3);
        let dirv = [
            Vec3::new(0.4, -0.2, 0.7),
            Vec3::new(-0.3, 0.5, 0.1),
            Vec3::new(0.2, 0.2, -0.6),
        ];
        for n in fibonacci_sphere(50) {
            let n = n.as_vec3();
            let err = |eps: f32| {
                let c = [base, dirv[0] * eps, dirv[1] * eps, dirv[2] * eps];
                (irradiance_geomerics_l1(&c, n) - irradiance_l1(&c, n)).abs()
            };
            let (e1, e2) = (err(0.02), err(0.01));
            // The linear term agrees: what is left is second order.
            for ch in 0..3 {
                assert!(e1[ch] < 0.02, "eps 0.02 error {}", e1[ch]);
                assert!(
                    e2[ch] <= 0.3 * e1[ch] + 1e-5,
                    "not quadratic: {} then {}",
                    e1[ch],
                    e2[ch]
                );
            }
        }
    }

    /// A single delta light (the extreme non-negative signal, ratio 1) is
    /// reconstructed as `R0·4·q³`: zero opposite the light and exactly the
    /// true irradiance 1 facing it (`4π·Y00² = 1`).
    #[test]
    fn delta_light_is_non_negative_and_dark_behind() {
        let d = Vec3::new(0.2, 0.9, -0.3).normalize();
        // Radiance coefficients of a unit delta towards d: Y_lm(d).
        let c = [
            Vec3::splat(Y00),
            Vec3::splat(-Y1 * d.y),
            Vec3::splat(Y1 * d.z),
            Vec3::splat(-Y1 * d.x),
        ];
        let e = irradiance_geomerics_l1(&c, -d);
        assert!(e.max_element().abs() < 1e-5);
        let e = irradiance_geomerics_l1(&c, d);
        assert!((e.x - 1.0).abs() < 1e-5, "{e}");
    }

    proptest! {
        #[test]
        fn non_negative_and_finite(
            c0 in prop::array::uniform3(-1.0f32..5.0),
            c1 in prop::array::uniform3(-5.0f32..5.0),
            c2 in prop::array::uniform3(-5.0f32..5.0),
            c3 in prop::array::uniform3(-5.0f32..5.0),
            nx in -1.0f32..1.0, ny in -1.0f32..1.0, nz in -1.0f32..1.0,
        ) {
            let n = Vec3::new(nx, ny, nz).try_normalize().unwrap_or(Vec3::Y);
            let c = [Vec3::from(c0), Vec3::from(c1), Vec3::from(c2), Vec3::from(c3)];
            let e = irradiance_geomerics_l1(&c, n);
            prop_assert!(e.is_finite());
            prop_assert!(e.min_element() >= 0.0);
        }
    }
}
