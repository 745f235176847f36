//! Valve's ambient cube: six irradiance values along ±X, ±Y, ±Z blended by the
//! squared normal components (McTaggart, *Half-Life 2 / Valve Source
//! Shading*, GDC 2004; Mitchell, McTaggart, Green, *Shading in Valve's Source
//! Engine*, SIGGRAPH 2006 course; described in Pettineo, *SG Series Part 1*,
//! seed 002).
//!
//! `E(n) ≈ Σ_i n_i²·face(i, sign n_i)` for unit `n` (the weights sum to 1, so
//! a constant irradiance is exact).
//!
//! ## Least-squares fits
//!
//! Write the reconstruction as `Σ_k F_k·b_k(n)` with `b_k(n) = n_i²` on the
//! half-space of face `k` and 0 elsewhere. The fit minimising
//! `∫_S² |Σ_k F_k b_k(n) − E(n)|² dn` solves `G·F = r` with the Gram matrix
//! (closed form; the tests check it by quadrature)
//! `G_kk = ∫_{n_i>0} n_i⁴ = 2π/5`, `G_kk' = 0` for opposite faces and
//! `∫_{n_i>0, n_j>0} n_i² n_j² = π/15` otherwise, and
//! `r_k = ∫ b_k E = Σ_lm Â_l·L_lm·∫ b_k Y_lm` for SH radiance `L_lm`. The
//! moments `∫ b_k Y_lm` are computed once (for all 64 coefficients of 8
//! bands) by a product Gauss–Legendre (12 nodes in `cos θ` about the face axis)
//! × uniform (32 nodes in φ) rule over the face's hemisphere, which is exact
//! for these polynomials (degree ≤ 9).

// Index loops over colour channels and SH coefficients read like the formulas.
#![allow(clippy::needless_range_loop)]

use crate::basis::{eval_basis_f64, num_coeffs, MAX_COEFFS, MAX_ORDER};
use crate::convolve::clamped_cosine_band;
#[cfg(not(feature = "std"))]
use crate::math::FloatMath;
use crate::numeric::{gauss_legendre, solve_dense};
use alloc::boxed::Box;
use glam::{DVec3, Vec3};
use once_cell::race::OnceBox;

/// Valve's ambient cube: irradiance (not divided by π, linear RGB) for the
/// six axis directions, in the order +X, −X, +Y, −Y, +Z, −Z (seed 002).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AmbientCube {
    /// Irradiance along +X, −X, +Y, −Y, +Z, −Z.
    pub faces: [Vec3; 6],
}

/// Index of the face for axis `i` (0 = X, 1 = Y, 2 = Z) and sign.
#[inline]
fn face_index(axis: usize, negative: bool) -> usize {
    2 * axis + negative as usize
}

/// The six blending weights `b_k(n)` for unit `n` (they sum to `|n|²`).
#[inline]
pub fn ambient_cube_weights(n: Vec3) -> [f32; 6] {
    let mut w = [0.0f32; 6];
    for i in 0..3 {
        w[face_index(i, n[i] < 0.0)] = n[i] * n[i];
    }
    w
}

fn weights_f64(n: DVec3) -> [f64; 6] {
    let mut w = [0.0f64; 6];
    for i in 0..3 {
        w[face_index(i, n[i] < 0.0)] = n[i] * n[i];
    }
    w
}

/// The closed-form Gram matrix `G_kk' = ∫ b_k b_k'` (module docs).
fn gram() -> [f64; 36] {
    use core::f64::consts::PI;
    let mut g = [0.0f64; 36];
    for k in 0..6 {
        for j in 0..6 {
            g[k * 6 + j] = if k == j {
                2.0 * PI / 5.0
            } else if k / 2 == j / 2 {
                0.0
            } else {
                PI / 15.0
            };
        }
    }
    g
}

/// `∫ b_k Y_j` for the six faces and all 64 SH coefficients (module docs).
fn moments() -> &'static [[f64; MAX_COEFFS]; 6] {
    static M: OnceBox<[[f64; MAX_COEFFS]; 6]> = OnceBox::new();
    M.get_or_init(|| {
        let nodes = gauss_legendre(12, 0.0, 1.0);
        let nphi = 32;
        let mut m = [[0.0f64; MAX_COEFFS]; 6];
        let mut y = [0.0f64; MAX_COEFFS];
        for (k, row) in m.iter_mut().enumerate() {
            let mut e = DVec3::ZERO;
            e[k / 2] = if k % 2 == 0 { 1.0 } else { -1.0 };
            let t1 = DVec3::new(e.y.abs() + e.z.abs(), e.x.abs(), 0.0).normalize();
            let t1 = (t1 - e * t1.dot(e)).normalize();
            let t2 = e.cross(t1);
            for &(u, wu) in &nodes {
                let s = (1.0 - u * u).max(0.0).sqrt();
                for p in 0..nphi {
                    let phi = 2.0 * core::f64::consts::PI * p as f64 / nphi as f64;
                    let d = e * u + (t1 * phi.cos() + t2 * phi.sin()) * s;
                    eval_basis_f64(MAX_ORDER, d, &mut y);
                    let w = wu * 2.0 * core::f64::consts::PI / nphi as f64 * u * u;
                    for (r, yj) in row.iter_mut().zip(y.iter()) {
                        *r += w * yj;
                    }
                }
            }
        }
        Box::new(m)
    })
}

impl AmbientCube {
    /// Irradiance for unit normal `n`: `Σ_i n_i²·face(i, sign n_i)` (Valve,
    /// seed 002). Linear in the faces; a constant cube gives a constant.
    pub fn irradiance(&self, n: Vec3) -> Vec3 {
        let w = ambient_cube_weights(n);
        self.faces
            .iter()
            .zip(w.iter())
            .fold(Vec3::ZERO, |acc, (f, w)| acc + *f * *w)
    }

    /// Least-squares ambient cube of the irradiance of **radiance** SH
    /// `radiance_sh` (any order up to 8 bands; `len` should be a perfect
    /// square — extra coefficients beyond the largest square ≤ 64 are
    /// ignored), minimising `∫_S² |E_cube − E_sh|²` over the whole sphere with
    /// the closed-form Gram matrix and exact moments of the module docs.
    pub fn fit_from_sh(radiance_sh: &[Vec3]) -> AmbientCube {
        let mut order = 0;
        while order < MAX_ORDER && num_coeffs(order + 1) <= radiance_sh.len() {
            order += 1;
        }
        let m = moments();
        let mut faces = [Vec3::ZERO; 6];
        for ch in 0..3 {
            let mut r = [0.0f64; 6];
            for (k, rk) in r.iter_mut().enumerate() {
                for l in 0..order {
                    let a = clamped_cosine_band(l);
                    for j in l * l..(l + 1) * (l + 1) {
                        *rk += a * radiance_sh[j][ch] as f64 * m[k][j];
                    }
                }
            }
            let mut g = gram();
            solve_dense(6, &mut g, &mut r);
            for k in 0..6 {
                faces[k][ch] = r[k] as f32;
            }
        }
        AmbientCube { faces }
    }

    /// Least-squares ambient cube of irradiance samples: `irradiance[i]` seen
    /// at unit normal `normals[i]`, all samples weighted equally (pass normals
    /// spread uniformly over the sphere to approximate the sphere integral).
    /// Normal equations in f64 with a ridge of `1e-9 × mean diagonal`, so a
    /// face no sample sees comes out 0 instead of failing. Extra entries of
    /// the longer slice are ignored.
    pub fn fit_from_samples(normals: &[Vec3], irradiance: &[Vec3]) -> AmbientCube {
        let mut ata = [0.0f64; 36];
        let mut atb = [[0.0f64; 6]; 3];
        for (n, e) in normals.iter().zip(irradiance) {
            let w = weights_f64(n.as_dvec3());
            for k in 0..6 {
                if w[k] == 0.0 {
                    continue;
                }
                for j in 0..6 {
                    ata[k * 6 + j] += w[k] * w[j];
                }
                for ch in 0..3 {
                    atb[ch][k] += w[k] * e[ch] as f64;
                }
            }
        }
        let ridge = 1e-9 * (0..6).map(|k| ata[k * 7]).sum::<f64>() / 6.0;
        for k in 0..6 {
            ata[k * 7] += ridge;
        }
        let mut faces = [Vec3::ZERO; 6];
        for (ch, b) in atb.iter_mut().enumerate() {
            let mut a = ata;
            solve_dense(6, &mut a, b);
            for k in 0..6 {
                faces[k][ch] = b[k] as f32;
            }
        }
        AmbientCube { faces }
    }
}

/// Free-function form of [`AmbientCube::fit_from_sh`].
pub fn fit_from_sh(radiance_sh: &[Vec3]) -> AmbientCube {
    AmbientCube::fit_from_sh(radiance_sh)
}

/// Free-function form of [`AmbientCube::fit_from_samples`].
pub fn fit_from_samples(normals: &[Vec3], irradiance: &[Vec3]) -> AmbientCube {
    AmbientCube::fit_from_samples(normals, irradiance)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::Y00;
    use crate::convolve::irradiance;
    use crate::numeric::fibonacci_sphere;

    fn test_sh() -> Vec<Vec3> {
        (0..16)
            .map(|i| {
                let f = i as f32;
                if i == 0 {
                    Vec3::new(3.0, 2.5, 2.0)
                } else {
                    Vec3::new((f * 0.9).sin(), (f * 1.7).cos() * 0.5, 0.3 - 0.05 * f)
                }
            })
            .collect()
    }

    #[test]
    fn gram_matches_quadrature() {
        let dirs = fibonacci_sphere(100_000);
        let w = 4.0 * std::f64::consts::PI / dirs.len() as f64;
        let mut g = [0.0f64; 36];
        for d in &dirs {
            let b = weights_f64(*d);
            for k in 0..6 {
                for j in 0..6 {
                    g[k * 6 + j] += b[k] * b[j] * w;
                }
            }
        }
        let exact = gram();
        for i in 0..36 {
            assert!(
                (g[i] - exact[i]).abs() < 1e-3,
                "{i}: {} vs {}",
                g[i],
                exact[i]
            );
        }
    }

    #[test]
    fn moments_match_quadrature() {
        let dirs = fibonacci_sphere(100_000);
        let w = 4.0 * std::f64::consts::PI / dirs.len() as f64;
        let mut m = [[0.0f64; 16]; 6];
        let mut y = [0.0f64; MAX_COEFFS];
        for d in &dirs {
            let b = weights_f64(*d);
            eval_basis_f64(4, *d, &mut y);
            for k in 0..6 {
                for j in 0..16 {
                    m[k][j] += b[k] * y[j] * w;
                }
            }
        }
        let exact = moments();
        for k in 0..6 {
            for j in 0..16 {
                assert!((m[k][j] - exact[k][j]).abs() < 1e-3, "{k},{j}");
            }
        }
    }

    /// The SH fit equals brute-force least squares on a dense sphere sampling,
    /// and the residual is orthogonal to every face's basis function
    /// (optimality checked by quadrature, independently of the solver).
    #[test]
    fn fit_from_sh_matches_dense_least_squares() {
        let sh = test_sh();
        let cube = AmbientCube::fit_from_sh(&sh);
        let normals: Vec<Vec3> = fibonacci_sphere(40_000)
            .iter()
            .map(|d| d.as_vec3())
            .collect();
        let e: Vec<Vec3> = normals.iter().map(|n| irradiance(&sh, *n)).collect();
        let brute = AmbientCube::fit_from_samples(&normals, &e);
        for k in 0..6 {
            assert!(
                (cube.faces[k] - brute.faces[k]).length() < 2e-3 * cube.faces[k].length().max(1.0),
                "face {k}: {} vs {}",
                cube.faces[k],
                brute.faces[k]
            );
        }
        let mut grad = [DVec3::ZERO; 6];
        for (n, ei) in normals.iter().zip(&e) {
            let r = (cube.irradiance(*n) - *ei).as_dvec3();
            let b = weights_f64(n.as_dvec3());
            for k in 0..6 {
                grad[k] += r * b[k];
            }
        }
        let scale: f64 = e.iter().map(|x| x.as_dvec3().length()).sum::<f64>();
        for g in grad {
            assert!(g.length() < 1e-3 * scale, "{g} vs {scale}");
        }
    }

    #[test]
    fn exact_cube_signal_recovered_from_samples() {
        let truth = AmbientCube {
            faces: [
                Vec3::new(1.0, 2.0, 3.0),
                Vec3::new(0.5, 0.1, 0.2),
                Vec3::new(4.0, 4.0, 3.0),
                Vec3::new(0.2, 0.3, 0.1),
                Vec3::new(1.5, 1.0, 0.5),
                Vec3::new(0.9, 0.8, 0.7),
            ],
        };
        let normals: Vec<Vec3> = fibonacci_sphere(500).iter().map(|d| d.as_vec3()).collect();
        let e: Vec<Vec3> = normals.iter().map(|n| truth.irradiance(*n)).collect();
        let fit = AmbientCube::fit_from_samples(&normals, &e);
        for k in 0..6 {
            assert!((fit.faces[k] - truth.faces[k]).length() < 1e-4);
        }
        // Faces of the cube are what the name says: irradiance along each axis.
        assert!((truth.irradiance(-Vec3::Y) - truth.faces[3]).length() < 1e-6);
    }

    #[test]
    fn constant_environment_is_exact() {
        let l = Vec3::new(0.3, 0.6, 0.9);
        let sh = vec![l / Y00, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
        let cube = AmbientCube::fit_from_sh(&sh);
        for f in cube.faces {
            assert!((f - l * std::f32::consts::PI).length() < 1e-5, "{f}");
        }
    }

    #[test]
    fn degenerate_samples_do_not_panic() {
        let c = AmbientCube::fit_from_samples(&[], &[]);
        assert_eq!(c, AmbientCube::default());
        let c = AmbientCube::fit_from_samples(&[Vec3::X, Vec3::X], &[Vec3::ONE, Vec3::ONE]);
        assert!((c.faces[0] - Vec3::ONE).length() < 1e-4);
        assert!(c.faces[1..].iter().all(|f| f.is_finite()));
        let c = AmbientCube::fit_from_sh(&[Vec3::ONE; 5]);
        assert!(c.faces.iter().all(|f| f.is_finite()));
    }
}
