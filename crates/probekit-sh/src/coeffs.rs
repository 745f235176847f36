//! [`ShRgb`]: linear-RGB radiance SH of any order up to [`MAX_ORDER`] bands.

use crate::basis::{eval_basis, num_coeffs, order_from_len, MAX_COEFFS, MAX_ORDER};
use crate::convolve;
use alloc::vec;
use alloc::vec::Vec;
use glam::Vec3;

/// Linear-RGB **radiance** spherical harmonics of `order` bands (`order²`
/// coefficients, index `l*(l+1)+m`, conventions at the crate root).
///
/// Stored coefficients are always radiance; irradiance comes from
/// [`ShRgb::irradiance`] (clamped-cosine convolution, not divided by π).
#[derive(Clone, Debug, PartialEq)]
pub struct ShRgb {
    order: usize,
    coeffs: Vec<Vec3>,
}

impl ShRgb {
    /// All-zero SH of `order` bands.
    ///
    /// # Panics
    /// If `order` is 0 or greater than [`MAX_ORDER`].
    pub fn zeros(order: usize) -> Self {
        assert!(
            (1..=MAX_ORDER).contains(&order),
            "SH order {order} outside 1..={MAX_ORDER}"
        );
        Self {
            order,
            coeffs: vec![Vec3::ZERO; num_coeffs(order)],
        }
    }

    /// Wraps coefficients; `None` unless their count is a perfect square ≤ 64.
    pub fn from_coeffs(coeffs: Vec<Vec3>) -> Option<Self> {
        order_from_len(coeffs.len()).map(|order| Self { order, coeffs })
    }

    /// Number of bands.
    pub fn order(&self) -> usize {
        self.order
    }

    /// The coefficients, index `l*(l+1)+m`.
    pub fn coeffs(&self) -> &[Vec3] {
        &self.coeffs
    }

    /// Mutable coefficients.
    pub fn coeffs_mut(&mut self) -> &mut [Vec3] {
        &mut self.coeffs
    }

    /// Consumes into the coefficient vector.
    pub fn into_coeffs(self) -> Vec<Vec3> {
        self.coeffs
    }

    /// Accumulates one Monte Carlo / quadrature sample of radiance `value`
    /// arriving from unit direction `dir` with weight `weight` (solid angle
    /// over pdf): `c_lm += weight · value · Y_lm(dir)`.
    pub fn add_sample(&mut self, dir: Vec3, value: Vec3, weight: f32) {
        let mut b = [0.0f32; MAX_COEFFS];
        eval_basis(self.order, dir, &mut b);
        let v = value * weight;
        for (c, y) in self.coeffs.iter_mut().zip(b.iter()) {
            *c += v * *y;
        }
    }

    /// Reconstructed radiance `Σ c_lm Y_lm(dir)` at unit direction `dir`.
    pub fn eval(&self, dir: Vec3) -> Vec3 {
        convolve::eval_sh(&self.coeffs, dir)
    }

    /// Irradiance `E(n) = ∫ L(ω) max(0, n·ω) dω` (not divided by π) for unit normal `n`.
    pub fn irradiance(&self, n: Vec3) -> Vec3 {
        convolve::irradiance(&self.coeffs, n)
    }

    /// A copy truncated (or zero-padded) to `order` bands.
    pub fn with_order(&self, order: usize) -> Self {
        let mut out = Self::zeros(order);
        let n = out.coeffs.len().min(self.coeffs.len());
        out.coeffs[..n].copy_from_slice(&self.coeffs[..n]);
        out
    }

    /// Multiplies every coefficient by `s`.
    pub fn scale(&mut self, s: f32) {
        for c in &mut self.coeffs {
            *c *= s;
        }
    }

    /// Adds `w · other` (orders must match).
    ///
    /// # Panics
    /// If the orders differ.
    pub fn add_scaled(&mut self, other: &ShRgb, w: f32) {
        assert_eq!(self.order, other.order, "SH orders differ");
        for (a, b) in self.coeffs.iter_mut().zip(&other.coeffs) {
            *a += *b * w;
        }
    }

    /// One colour channel (0 = R, 1 = G, 2 = B) as scalar coefficients.
    pub fn channel(&self, ch: usize) -> Vec<f32> {
        self.coeffs.iter().map(|c| c[ch]).collect()
    }

    /// Rec. 709 luminance of each coefficient (`0.2126 R + 0.7152 G + 0.0722 B`).
    pub fn luminance(&self) -> Vec<f32> {
        self.coeffs.iter().map(|c| c.dot(LUMINANCE)).collect()
    }
}

/// Rec. 709 / sRGB-primaries luminance weights for linear RGB.
pub const LUMINANCE: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

#[cfg(test)]
mod tests {
    use super::*;

    /// Projecting a band-limited function by quadrature and reconstructing it
    /// gives the same function (projection is exact for band-limited input).
    #[test]
    fn project_reconstruct_band_limited() {
        let truth = ShRgb::from_coeffs(
            (0..16)
                .map(|i| Vec3::new((i as f32 * 0.7).cos(), 0.2, -0.1 * i as f32))
                .collect(),
        )
        .unwrap();
        let n = 60_000;
        let ga = std::f32::consts::PI * (3.0 - 5f32.sqrt());
        let mut p = ShRgb::zeros(4);
        for i in 0..n {
            let z = 1.0 - (2.0 * i as f32 + 1.0) / n as f32;
            let r = (1.0 - z * z).sqrt();
            let phi = ga * i as f32;
            let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            p.add_sample(d, truth.eval(d), 4.0 * std::f32::consts::PI / n as f32);
        }
        for (a, b) in p.coeffs().iter().zip(truth.coeffs()) {
            assert!((*a - *b).length() < 2e-3, "{a} vs {b}");
        }
    }
}
