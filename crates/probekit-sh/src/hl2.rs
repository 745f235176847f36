//! The Half-Life 2 ("radiosity normal mapping") basis: three orthonormal
//! tangent-space directions, each storing one irradiance value (McTaggart,
//! *Half-Life 2 / Valve Source Shading*, GDC 2004; Mitchell, McTaggart,
//! Green, *Shading in Valve's Source Engine*, SIGGRAPH 2006; described in
//! Pettineo, *SG Series Part 1*).
//!
//! **Tangent space**: +Z is the surface normal, X the tangent, Y the
//! bitangent (this is the one place in probekit where +Z, not +Y, is "up").
//!
//! **Evaluation** (Source engine's `LightmappedGeneric` blend): with
//! `d_i = max(0, n·b_i)²`, `E(n) = Σ d_i·E_i / Σ d_i`. The weights sum to 1,
//! so a constant is reproduced exactly; for `n` on the upper hemisphere at
//! least one `d_i > 0` (the `b_i` sum to `(0, 0, √3)`), and for the rare
//! normal with all `d_i = 0` the mean of the three values is returned.
//!
//! **Projection**: [`project_hl2_point`] is Valve's bake (irradiance along
//! each basis direction). [`fit_hl2`] and [`fit_hl2_sh`] are least squares
//! against the irradiance over the **upper hemisphere** of tangent space
//! (`n_z ≥ 0`, where normal-mapped normals live), with a fixed Fibonacci
//! hemisphere quadrature of [`HL2_FIT_SAMPLES`] equal-area points; the Gram
//! matrix of the blend weights is precomputed once on that point set.

// Index loops over colour channels and SH coefficients read like the formulas.
#![allow(clippy::needless_range_loop)]

use crate::convolve::irradiance;
use crate::numeric::{fibonacci_hemisphere, solve_dense};
use alloc::boxed::Box;
use alloc::vec::Vec;
use glam::{DVec3, Mat3, Vec3};
use once_cell::race::OnceBox;

const S23: f32 = 0.816_496_6; // sqrt(2/3)
const S16: f32 = 0.408_248_3; // 1/sqrt(6)
const S12: f32 = core::f32::consts::FRAC_1_SQRT_2;
const S13: f32 = 0.577_350_26; // 1/sqrt(3)

/// The three HL2 basis directions in tangent space (+Z = surface normal):
/// `(√(2/3), 0, 1/√3)`, `(−1/√6, 1/√2, 1/√3)`, `(−1/√6, −1/√2, 1/√3)` —
/// orthonormal, each 54.7° from the normal (McTaggart 2004).
pub const HL2_BASIS: [Vec3; 3] = [
    Vec3::new(S23, 0.0, S13),
    Vec3::new(-S16, S12, S13),
    Vec3::new(-S16, -S12, S13),
];

/// Number of Fibonacci hemisphere points of the least-squares fits.
pub const HL2_FIT_SAMPLES: usize = 4096;

/// Blend weights of the three basis values for a unit tangent-space normal
/// (`max(0, n·b_i)²` normalised to sum 1; module docs).
pub fn hl2_weights(n_tangent: Vec3) -> [f32; 3] {
    let d = HL2_BASIS.map(|b| {
        let x = n_tangent.dot(b).max(0.0);
        x * x
    });
    let s = d[0] + d[1] + d[2];
    if s > 0.0 {
        d.map(|x| x / s)
    } else {
        [1.0 / 3.0; 3]
    }
}

fn weights_f64(n: DVec3) -> [f64; 3] {
    let d = HL2_BASIS.map(|b| {
        let x = n.dot(b.as_dvec3()).max(0.0);
        x * x
    });
    let s = d[0] + d[1] + d[2];
    if s > 0.0 {
        d.map(|x| x / s)
    } else {
        [1.0 / 3.0; 3]
    }
}

/// Irradiance for a unit tangent-space normal from the three HL2 values
/// (Source engine blend, module docs).
pub fn eval_hl2(values: &[Vec3; 3], n_tangent: Vec3) -> Vec3 {
    let w = hl2_weights(n_tangent);
    values[0] * w[0] + values[1] * w[1] + values[2] * w[2]
}

/// Valve's bake: the irradiance (not divided by π) of **radiance** SH
/// `radiance_sh` (world space, any order) along each basis direction
/// `world_from_tangent · b_i`.
pub fn project_hl2_point(radiance_sh: &[Vec3], world_from_tangent: Mat3) -> [Vec3; 3] {
    HL2_BASIS.map(|b| irradiance(radiance_sh, (world_from_tangent * b).normalize()))
}

struct FitTable {
    dirs: Vec<DVec3>,
    gram: [f64; 9],
}

fn table() -> &'static FitTable {
    static T: OnceBox<FitTable> = OnceBox::new();
    T.get_or_init(|| {
        let dirs = fibonacci_hemisphere(HL2_FIT_SAMPLES);
        let mut gram = [0.0f64; 9];
        for d in &dirs {
            let w = weights_f64(*d);
            for i in 0..3 {
                for j in 0..3 {
                    gram[i * 3 + j] += w[i] * w[j];
                }
            }
        }
        Box::new(FitTable { dirs, gram })
    })
}

/// Least-squares HL2 values of an irradiance function of the tangent-space
/// normal, over the upper hemisphere (module docs: fixed Fibonacci quadrature
/// of [`HL2_FIT_SAMPLES`] points, equal weights).
pub fn fit_hl2(irradiance_of: impl Fn(Vec3) -> Vec3) -> [Vec3; 3] {
    let t = table();
    let mut rhs = [[0.0f64; 3]; 3];
    for d in &t.dirs {
        let w = weights_f64(*d);
        let e = irradiance_of(d.as_vec3()).as_dvec3();
        for ch in 0..3 {
            for i in 0..3 {
                rhs[ch][i] += w[i] * e[ch];
            }
        }
    }
    let mut out = [Vec3::ZERO; 3];
    for (ch, r) in rhs.iter_mut().enumerate() {
        let mut g = t.gram;
        solve_dense(3, &mut g, r);
        for i in 0..3 {
            out[i][ch] = r[i] as f32;
        }
    }
    out
}

/// Least-squares HL2 values of the irradiance of world-space **radiance** SH
/// `radiance_sh` (any order) for a surface whose tangent frame is
/// `world_from_tangent` (columns: tangent, bitangent, normal), over the upper
/// tangent hemisphere ([`fit_hl2`]).
pub fn fit_hl2_sh(radiance_sh: &[Vec3], world_from_tangent: Mat3) -> [Vec3; 3] {
    fit_hl2(|n| irradiance(radiance_sh, (world_from_tangent * n).normalize()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::Y00;

    #[test]
    fn basis_is_orthonormal_and_tilted_equally() {
        for i in 0..3 {
            for j in 0..3 {
                let d = HL2_BASIS[i].dot(HL2_BASIS[j]);
                let e = if i == j { 1.0 } else { 0.0 };
                assert!((d - e).abs() < 1e-6);
            }
            assert!((HL2_BASIS[i].z - 1.0 / 3f32.sqrt()).abs() < 1e-6);
        }
    }

    #[test]
    fn evaluation_reproduces_basis_values_and_constants() {
        let v = [Vec3::X, Vec3::Y, Vec3::Z];
        for i in 0..3 {
            assert!((eval_hl2(&v, HL2_BASIS[i]) - v[i]).length() < 1e-6);
        }
        let c = [Vec3::splat(2.0); 3];
        for n in fibonacci_hemisphere(100) {
            assert!((eval_hl2(&c, n.as_vec3()) - Vec3::splat(2.0)).length() < 1e-5);
        }
        assert!(eval_hl2(&v, -Vec3::Z).is_finite());
    }

    #[test]
    fn constant_environment_fit_is_exact() {
        let l = Vec3::new(0.2, 0.4, 0.8);
        let sh = [l / Y00, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
        let frame = Mat3::from_cols(Vec3::X, Vec3::Z, -Vec3::Y);
        for v in fit_hl2_sh(&sh, frame)
            .into_iter()
            .chain(project_hl2_point(&sh, frame))
        {
            assert!((v - l * std::f32::consts::PI).length() < 1e-4, "{v}");
        }
    }

    /// The fit against an independent least-squares solve on a different,
    /// random (stratified) hemisphere sampling, done here by explicit normal
    /// equations via Cramer's rule.
    #[test]
    fn fit_matches_independent_least_squares() {
        let sh: Vec<Vec3> = (0..9)
            .map(|i| {
                if i == 0 {
                    Vec3::new(3.0, 2.0, 2.5)
                } else {
                    Vec3::new(
                        (i as f32).sin(),
                        0.4 * (i as f32 * 2.1).cos(),
                        -0.1 * i as f32,
                    )
                }
            })
            .collect();
        let frame = Mat3::from_cols(Vec3::X, Vec3::Z, -Vec3::Y);
        let fit = fit_hl2_sh(&sh, frame);
        // Stratified random hemisphere (uniform in z and φ), LCG.
        let mut s: u64 = 12345;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut ata = [[0.0f64; 3]; 3];
        let mut atb = [DVec3::ZERO; 3];
        let m = 120;
        for a in 0..m {
            for b in 0..m {
                let z = (a as f64 + rnd()) / m as f64;
                let phi = 2.0 * std::f64::consts::PI * (b as f64 + rnd()) / m as f64;
                let r = (1.0 - z * z).sqrt();
                let n = DVec3::new(r * phi.cos(), r * phi.sin(), z);
                let w = weights_f64(n);
                let e = irradiance(&sh, frame * n.as_vec3()).as_dvec3();
                for i in 0..3 {
                    for j in 0..3 {
                        ata[i][j] += w[i] * w[j];
                    }
                    atb[i] += e * w[i];
                }
            }
        }
        let det3 = |m: [[f64; 3]; 3]| {
            m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
        };
        let d = det3(ata);
        for ch in 0..3 {
            for i in 0..3 {
                let mut mi = ata;
                for r in 0..3 {
                    mi[r][i] = atb[r][ch];
                }
                let x = det3(mi) / d;
                assert!(
                    (x - fit[i][ch] as f64).abs() < 5e-3 * (1.0 + x.abs()),
                    "value {i} channel {ch}: {x} vs {}",
                    fit[i][ch]
                );
            }
        }
    }
}
