//! Valve's ambient cube: six irradiance values along ±X, ±Y, ±Z blended by the
//! squared normal components (McTaggart, *Half-Life 2 / Valve Source
//! Shading*, GDC 2004; Mitchell, McTaggart, Green, *Shading in Valve's Source
//! Engine*, SIGGRAPH 2006 course; described in Pettineo, *SG Series Part 1*).
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
//! for these polynomials (degree ≤ 9). The same problem restricted to
//! non-negative faces (for unsigned texture formats) is solved exactly as a
//! small non-negative least-squares problem
//! ([`AmbientCube::fit_from_sh_nonnegative`]).

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
/// six axis directions, in the order +X, −X, +Y, −Y, +Z, −Z (McTaggart 2004).
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
    /// McTaggart 2004). Linear in the faces; a constant cube gives a constant.
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
        let r = sh_moments(radiance_sh);
        let mut faces = [Vec3::ZERO; 6];
        for (ch, mut rc) in r.into_iter().enumerate() {
            let mut g = gram();
            solve_dense(6, &mut g, &mut rc);
            for k in 0..6 {
                faces[k][ch] = rc[k] as f32;
            }
        }
        AmbientCube { faces }
    }

    /// The least-squares ambient cube of [`Self::fit_from_sh`] under the
    /// constraint that every face is ≥ 0 (what an unsigned texture format
    /// such as RGB9E5 can hold): per channel, minimises `∫_S² |E_cube −
    /// E_sh|²` over non-negative faces. The unconstrained fit goes negative
    /// opposite a strong light (its overshoot on the side faces is paid back
    /// there); clamping it to 0 is feasible but no longer optimal, this is.
    /// Equal to [`Self::fit_from_sh`] when that has no negative face.
    ///
    /// Solved exactly as a 6-variable non-negative least-squares problem
    /// (Lawson & Hanson, *Solving Least Squares Problems*, 1974, ch. 23):
    /// the optimum is the unique point satisfying the KKT conditions — the
    /// free faces solve the Gram system restricted to them and are ≥ 0, the
    /// faces held at 0 have a gradient `G·F − r ≥ 0` — found by trying the
    /// 64 sets of held faces, fewest first.
    pub fn fit_from_sh_nonnegative(radiance_sh: &[Vec3]) -> AmbientCube {
        let r = sh_moments(radiance_sh);
        let g = gram();
        let mut faces = [Vec3::ZERO; 6];
        for (ch, rc) in r.iter().enumerate() {
            let f = nonnegative_solve(&g, rc);
            for k in 0..6 {
                faces[k][ch] = f[k] as f32;
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

/// `r_k = ∫ b_k E_sh` per channel (module docs) for radiance SH `radiance_sh`
/// (its largest square number of coefficients, at most 64).
fn sh_moments(radiance_sh: &[Vec3]) -> [[f64; 6]; 3] {
    let mut order = 0;
    while order < MAX_ORDER && num_coeffs(order + 1) <= radiance_sh.len() {
        order += 1;
    }
    let m = moments();
    let mut r = [[0.0f64; 6]; 3];
    for (ch, rc) in r.iter_mut().enumerate() {
        for (k, rk) in rc.iter_mut().enumerate() {
            for l in 0..order {
                let a = clamped_cosine_band(l);
                for j in l * l..(l + 1) * (l + 1) {
                    *rk += a * radiance_sh[j][ch] as f64 * m[k][j];
                }
            }
        }
    }
    r
}

/// The sets of held (zero) faces as bit masks, fewest held first (then by
/// mask value).
fn held_sets() -> impl Iterator<Item = u8> {
    (0..=6u32).flat_map(|held| (0u8..64).filter(move |m| m.count_ones() == held))
}

/// `argmin_{F ≥ 0} Fᵀ G F − 2 rᵀ F` for the 6×6 Gram matrix `g`
/// ([`AmbientCube::fit_from_sh_nonnegative`]): the first set of held faces
/// whose restricted solution is feasible and whose held faces have a
/// non-negative gradient. Zero if rounding defeats every set (not seen).
fn nonnegative_solve(g: &[f64; 36], r: &[f64; 6]) -> [f64; 6] {
    let scale = r.iter().fold(0.0f64, |a, x| a.max(x.abs())).max(1e-300);
    let tol = 1e-12 * scale;
    for held in held_sets() {
        let mut free = [0usize; 6];
        let mut m = 0;
        for k in (0..6).filter(|k| held >> k & 1 == 0) {
            free[m] = k;
            m += 1;
        }
        let mut a = [0.0f64; 36];
        let mut b = [0.0f64; 6];
        for i in 0..m {
            b[i] = r[free[i]];
            for j in 0..m {
                a[i * m + j] = g[free[i] * 6 + free[j]];
            }
        }
        solve_dense(m, &mut a[..m * m], &mut b[..m]);
        if b[..m].iter().any(|&x| x < -tol) {
            continue;
        }
        let mut f = [0.0f64; 6];
        for i in 0..m {
            f[free[i]] = b[i].max(0.0);
        }
        let kkt = (0..6).filter(|k| held >> k & 1 == 1).all(|k| {
            let grad: f64 = (0..6).map(|j| g[k * 6 + j] * f[j]).sum::<f64>() - r[k];
            grad >= -tol
        });
        if kkt {
            return f;
        }
    }
    [0.0; 6]
}

/// Free-function form of [`AmbientCube::fit_from_sh`].
pub fn fit_from_sh(radiance_sh: &[Vec3]) -> AmbientCube {
    AmbientCube::fit_from_sh(radiance_sh)
}

/// Free-function form of [`AmbientCube::fit_from_sh_nonnegative`].
pub fn fit_from_sh_nonnegative(radiance_sh: &[Vec3]) -> AmbientCube {
    AmbientCube::fit_from_sh_nonnegative(radiance_sh)
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
    /// Radiance SH (3 bands) of a small bright light along `d` over a dim
    /// uniform sky: the unconstrained fit goes negative opposite it.
    fn light_sh(d: Vec3) -> Vec<Vec3> {
        let mut y = [0.0f32; 9];
        crate::basis::eval_basis(3, d.normalize(), &mut y);
        let mut sh: Vec<Vec3> = y.iter().map(|&v| Vec3::new(8.0, 6.0, 4.0) * v).collect();
        sh[0] += Vec3::splat(0.05) / Y00;
        sh
    }

    /// The non-negative fit equals projected coordinate descent on a dense
    /// sphere sampling of the same objective (an independent solver), has
    /// no negative face, and beats the clamped unconstrained fit; with no
    /// negative face to fix it is the unconstrained fit.
    #[test]
    fn nonnegative_fit_matches_dense_projected_descent() {
        let normals: Vec<Vec3> = fibonacci_sphere(20_000)
            .iter()
            .map(|d| d.as_vec3())
            .collect();
        let b: Vec<[f64; 6]> = normals.iter().map(|n| weights_f64(n.as_dvec3())).collect();
        for d in [
            Vec3::new(1.0, 0.3, -0.2),
            Vec3::new(-0.1, -1.0, 0.05),
            Vec3::ONE,
        ] {
            let sh = light_sh(d);
            let ls = AmbientCube::fit_from_sh(&sh);
            assert!(
                ls.faces.iter().any(|f| f.min_element() < 0.0),
                "{d}: {ls:?}"
            );
            let nn = AmbientCube::fit_from_sh_nonnegative(&sh);
            let e: Vec<Vec3> = normals.iter().map(|n| irradiance(&sh, *n)).collect();
            let cost = |c: &AmbientCube| -> f64 {
                normals
                    .iter()
                    .zip(&e)
                    .map(|(n, ei)| (c.irradiance(*n) - *ei).as_dvec3().length_squared())
                    .sum()
            };
            for ch in 0..3 {
                // Projected coordinate descent from 0 on Σ_i (Σ_k F_k b_k(n_i) − E_i)².
                let mut h = [0.0f64; 36];
                let mut rhs = [0.0f64; 6];
                for (bi, ei) in b.iter().zip(&e) {
                    for k in 0..6 {
                        rhs[k] += bi[k] * ei[ch] as f64;
                        for j in 0..6 {
                            h[k * 6 + j] += bi[k] * bi[j];
                        }
                    }
                }
                let mut f = [0.0f64; 6];
                for _ in 0..2000 {
                    for k in 0..6 {
                        let grad: f64 = (0..6).map(|j| h[k * 6 + j] * f[j]).sum::<f64>() - rhs[k];
                        f[k] = (f[k] - grad / h[k * 6 + k]).max(0.0);
                    }
                }
                let top = f.iter().fold(0.0f64, |a, x| a.max(*x));
                for k in 0..6 {
                    assert!(nn.faces[k][ch] >= 0.0);
                    assert!(
                        (nn.faces[k][ch] as f64 - f[k]).abs() < 3e-3 * top,
                        "{d} ch {ch} face {k}: {} vs {}",
                        nn.faces[k][ch],
                        f[k]
                    );
                }
            }
            let clamped = AmbientCube {
                faces: ls.faces.map(|f| f.max(Vec3::ZERO)),
            };
            assert!(cost(&nn) < cost(&clamped), "{d}");
        }
        let sh = test_sh();
        let ls = AmbientCube::fit_from_sh(&sh);
        assert!(ls.faces.iter().all(|f| f.min_element() > 0.0));
        assert_eq!(AmbientCube::fit_from_sh_nonnegative(&sh), ls);
        let dark = AmbientCube::fit_from_sh_nonnegative(&[-Vec3::ONE]);
        assert_eq!(dark, AmbientCube::default());
    }
}
