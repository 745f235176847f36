//! Rotation of SH coefficients.
//!
//! Rotating a function `f` on the sphere by a rotation matrix `R` gives
//! `f_R(d) = f(Rᵀ d)` (a lobe pointing along `a` ends up pointing along
//! `R a`). SH of band `l` map to band `l`, so the rotation of coefficients is
//! block-diagonal: `c'_l = D_l(R) · c_l`, with `D_l` an orthogonal
//! `(2l+1)×(2l+1)` matrix, `D(R₂R₁) = D(R₂)D(R₁)` and `D(Rᵀ) = D(R)ᵀ`.
//!
//! - [`ShRotation`]: any order up to [`MAX_ORDER`] by the recurrences of
//!   Ivanic & Ruedenberg, *Rotation Matrices for Real Spherical Harmonics.
//!   Direct Determination by Recursion*, J. Phys. Chem. 100 (1996) 6342, with
//!   the corrections of the 1998 errata (J. Phys. Chem. A 102, 9099): band `l`
//!   is built from band `l−1` and band 1. Their real SH carry no
//!   Condon–Shortley phase; ours (Sloan's) do, which multiplies `Y_lm` by
//!   `(−1)^m`, so our blocks are theirs conjugated by `diag((−1)^m)`:
//!   `D_ours[m][n] = (−1)^(m+n) D_IR[m][n]`. Built in f64, stored in f32.
//! - [`rotate_l1`], [`rotate_l2`]: allocation-free fast paths. Band 1 is a
//!   linear function `a·d`, rotated as the vector `R a`. Band 2 is a
//!   traceless quadratic form `dᵀ Q d`, rotated as `R Q Rᵀ`: the five
//!   coefficients are turned into `Q`, conjugated and read back — exact, no
//!   recurrence, no tables.

use crate::basis::{num_coeffs, order_from_len, MAX_ORDER, Y2_A, Y2_B, Y2_C};
use crate::coeffs::ShRgb;
#[cfg(not(feature = "std"))]
use crate::math::FloatMath;
use glam::{DMat3, Mat3, Vec3};

/// Offset of band `l`'s block in the packed storage: `Σ_{k<l} (2k+1)² = l(2l−1)(2l+1)/3`.
const fn band_offset(l: usize) -> usize {
    if l == 0 {
        0
    } else {
        l * (2 * l - 1) * (2 * l + 1) / 3
    }
}

/// Packed size of all blocks up to [`MAX_ORDER`] bands (680).
const PACKED: usize = band_offset(MAX_ORDER);

/// Largest block side, `2·MAX_ORDER − 1`.
const SIDE: usize = 2 * MAX_ORDER - 1;

/// The block-diagonal rotation of SH coefficients of up to `order` bands for
/// one rotation matrix: `c'_l = D_l · c_l`, so that the rotated coefficients
/// reconstruct `f(Rᵀ d)` (module docs; Ivanic–Ruedenberg recurrences).
/// Holds its blocks inline (no heap): build once per rotation, apply to
/// many probes.
#[derive(Clone, Debug)]
pub struct ShRotation {
    order: usize,
    blocks: [f32; PACKED],
}

/// Band-1 block in the Ivanic–Ruedenberg (no Condon–Shortley phase) basis,
/// `m = −1, 0, 1 ↔ y, z, x`: `R1[i][j] = R[axis(i)][axis(j)]`.
fn band1_ir(m: &DMat3) -> [[f64; 3]; 3] {
    const AXIS: [usize; 3] = [1, 2, 0];
    let mut r = [[0.0; 3]; 3];
    for (i, row) in r.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            // glam is column-major: col(j)[i] = M_ij.
            *v = m.col(AXIS[j])[AXIS[i]];
        }
    }
    r
}

impl ShRotation {
    /// Builds the rotation of `order` bands for the rotation matrix `m`
    /// (orthonormal, determinant +1; glam's column-major `Mat3`, acting on
    /// column vectors). Ivanic–Ruedenberg recurrences in f64 (module docs).
    ///
    /// # Panics
    /// If `order` is 0 or greater than [`MAX_ORDER`].
    pub fn new(order: usize, m: Mat3) -> Self {
        assert!(
            (1..=MAX_ORDER).contains(&order),
            "SH order {order} outside 1..={MAX_ORDER}"
        );
        let md = m.as_dmat3();
        let r1 = band1_ir(&md);
        let mut blocks = [0.0f32; PACKED];
        blocks[0] = 1.0;
        // prev: band l-1 in the IR basis, index [(a + l-1) * SIDE + (b + l-1)].
        let mut prev = [0.0f64; SIDE * SIDE];
        let mut cur = [0.0f64; SIDE * SIDE];
        if order > 1 {
            for i in 0..3 {
                for j in 0..3 {
                    prev[i * SIDE + j] = r1[i][j];
                }
            }
            store(&mut blocks, 1, &prev);
        }
        for l in 2..order {
            let li = l as i32;
            let pl = li - 1; // previous band
            let pget = |a: i32, b: i32| prev[((a + pl) as usize) * SIDE + (b + pl) as usize];
            let r = |i: i32, j: i32| r1[(i + 1) as usize][(j + 1) as usize];
            // P(i, a, b) of Ivanic–Ruedenberg (table 2).
            let p = |i: i32, a: i32, b: i32| -> f64 {
                if b == li {
                    r(i, 1) * pget(a, pl) - r(i, -1) * pget(a, -pl)
                } else if b == -li {
                    r(i, 1) * pget(a, -pl) + r(i, -1) * pget(a, pl)
                } else {
                    r(i, 0) * pget(a, b)
                }
            };
            for m in -li..=li {
                for n in -li..=li {
                    let am = m.abs();
                    let d = if n.abs() < li {
                        ((li + n) * (li - n)) as f64
                    } else {
                        (2 * li * (2 * li - 1)) as f64
                    };
                    let d0 = if m == 0 { 1.0 } else { 0.0 };
                    let u = (((li + m) * (li - m)) as f64 / d).sqrt();
                    let v = 0.5
                        * ((1.0 + d0) * ((li + am - 1) * (li + am)) as f64 / d).sqrt()
                        * (1.0 - 2.0 * d0);
                    let w = -0.5 * (((li - am - 1) * (li - am)) as f64 / d).sqrt() * (1.0 - d0);
                    let mut val = 0.0;
                    if u != 0.0 {
                        val += u * p(0, m, n);
                    }
                    if v != 0.0 {
                        let vv = if m == 0 {
                            p(1, 1, n) + p(-1, -1, n)
                        } else if m > 0 {
                            let d1: f64 = if m == 1 { 1.0 } else { 0.0 };
                            p(1, m - 1, n) * (1.0 + d1).sqrt() - p(-1, -m + 1, n) * (1.0 - d1)
                        } else {
                            let d1: f64 = if m == -1 { 1.0 } else { 0.0 };
                            p(1, m + 1, n) * (1.0 - d1) + p(-1, -m - 1, n) * (1.0 + d1).sqrt()
                        };
                        val += v * vv;
                    }
                    if w != 0.0 {
                        let ww = if m > 0 {
                            p(1, m + 1, n) + p(-1, -m - 1, n)
                        } else {
                            p(1, m - 1, n) - p(-1, -m + 1, n)
                        };
                        val += w * ww;
                    }
                    cur[((m + li) as usize) * SIDE + (n + li) as usize] = val;
                }
            }
            store(&mut blocks, l, &cur);
            core::mem::swap(&mut prev, &mut cur);
        }
        Self { order, blocks }
    }

    /// Number of bands this rotation covers.
    pub fn order(&self) -> usize {
        self.order
    }

    /// The `(2l+1)×(2l+1)` block of band `l`, row-major, rows and columns
    /// ordered `m = −l..=l`, in our (Condon–Shortley) convention:
    /// `c'_{l,m} = Σ_n block[(m+l)(2l+1) + (n+l)] · c_{l,n}`.
    ///
    /// # Panics
    /// If `l >= self.order()`.
    pub fn band_matrix(&self, l: usize) -> &[f32] {
        assert!(
            l < self.order,
            "band {l} outside the rotation's {} bands",
            self.order
        );
        let s = 2 * l + 1;
        &self.blocks[band_offset(l)..band_offset(l) + s * s]
    }

    /// Rotates RGB coefficients: `out = D · coeffs`. `coeffs.len()` may be
    /// any perfect square up to `order²` (fewer bands than the rotation is
    /// fine). No allocation.
    ///
    /// # Panics
    /// If `coeffs.len()` is not a perfect square `≤ order²`, or `out` is shorter.
    pub fn apply(&self, coeffs: &[Vec3], out: &mut [Vec3]) {
        let bands = self.bands_of(coeffs.len());
        for l in 0..bands {
            let s = 2 * l + 1;
            let blk = self.band_matrix(l);
            let base = l * l;
            for i in 0..s {
                let row = &blk[i * s..(i + 1) * s];
                let mut acc = Vec3::ZERO;
                for (r, c) in row.iter().zip(&coeffs[base..base + s]) {
                    acc += *c * *r;
                }
                out[base + i] = acc;
            }
        }
    }

    /// Rotates scalar coefficients: `out = D · coeffs`. No allocation.
    ///
    /// # Panics
    /// If `coeffs.len()` is not a perfect square `≤ order²`, or `out` is shorter.
    pub fn apply_scalar(&self, coeffs: &[f32], out: &mut [f32]) {
        let bands = self.bands_of(coeffs.len());
        for l in 0..bands {
            let s = 2 * l + 1;
            let blk = self.band_matrix(l);
            let base = l * l;
            for i in 0..s {
                let row = &blk[i * s..(i + 1) * s];
                out[base + i] = row
                    .iter()
                    .zip(&coeffs[base..base + s])
                    .map(|(r, c)| r * c)
                    .sum();
            }
        }
    }

    /// Returns `sh` rotated (allocates the result; use [`ShRotation::apply`]
    /// on a hot path).
    ///
    /// # Panics
    /// If `sh` has more bands than this rotation.
    pub fn rotate_sh(&self, sh: &ShRgb) -> ShRgb {
        let mut out = ShRgb::zeros(sh.order());
        self.apply(sh.coeffs(), out.coeffs_mut());
        out
    }

    fn bands_of(&self, len: usize) -> usize {
        match order_from_len(len) {
            Some(b) if b <= self.order => b,
            _ => panic!(
                "{len} coefficients do not fit a rotation of {} bands ({} coefficients)",
                self.order,
                num_coeffs(self.order)
            ),
        }
    }
}

/// Stores band `l` of `ir` (IR basis, SIDE-strided) into the packed blocks
/// with the Condon–Shortley sign change `(−1)^(m+n)`.
fn store(blocks: &mut [f32; PACKED], l: usize, ir: &[f64; SIDE * SIDE]) {
    let s = 2 * l + 1;
    let off = band_offset(l);
    for i in 0..s {
        for j in 0..s {
            let sign = if (i + j) % 2 == 0 { 1.0 } else { -1.0 };
            // m + n = (i - l) + (j - l) has the parity of i + j.
            blocks[off + i * s + j] = (sign * ir[i * SIDE + j]) as f32;
        }
    }
}

/// Rotates L1 RGB radiance SH (4 coefficients) by the rotation matrix `m`
/// (`f(Rᵀ d)`, module docs). Band 1 `c₁Y₁₋₁ + c₂Y₁₀ + c₃Y₁₁ = Y1·(a·d)` with
/// `a = (−c₃, −c₁, c₂)`, rotated as `R a`. No allocation.
#[inline]
pub fn rotate_l1(m: Mat3, c: &[Vec3; 4]) -> [Vec3; 4] {
    let b = rotate_band1(&m, [c[1], c[2], c[3]]);
    [c[0], b[0], b[1], b[2]]
}

#[inline]
fn rotate_band1(m: &Mat3, c: [Vec3; 3]) -> [Vec3; 3] {
    // a = (x, y, z) components of the linear function, per channel.
    let a = [-c[2], -c[0], c[1]];
    let (c0, c1, c2) = (m.x_axis, m.y_axis, m.z_axis);
    // (R a)_i = Σ_j R_ij a_j, R_ij = col j, row i.
    let ra = |i: usize| a[0] * c0[i] + a[1] * c1[i] + a[2] * c2[i];
    let (x, y, z) = (ra(0), ra(1), ra(2));
    [-y, z, -x]
}

/// Rotates L2 RGB radiance SH (9 coefficients) by the rotation matrix `m`
/// (`f(Rᵀ d)`, module docs). Band 2 is the traceless quadratic form `dᵀQd`
/// built from the five coefficients (Sloan's L2 constants, [`crate::eval_l2`]),
/// rotated as `R Q Rᵀ` and read back. Exact; no allocation.
#[inline]
pub fn rotate_l2(m: Mat3, c: &[Vec3; 9]) -> [Vec3; 9] {
    let b1 = rotate_band1(&m, [c[1], c[2], c[3]]);
    // Q from band 2 (unit sphere: 3z² − 1 = 2z² − x² − y²):
    // c4·A·xy − c5·A·yz + c6·B(2z² − x² − y²) − c7·A·xz + c8·C(x² − y²).
    let qxx = c[8] * Y2_C - c[6] * Y2_B;
    let qyy = -c[8] * Y2_C - c[6] * Y2_B;
    let qzz = c[6] * (2.0 * Y2_B);
    let qxy = c[4] * (0.5 * Y2_A);
    let qyz = c[5] * (-0.5 * Y2_A);
    let qxz = c[7] * (-0.5 * Y2_A);
    let q = [[qxx, qxy, qxz], [qxy, qyy, qyz], [qxz, qyz, qzz]];
    // R_ij
    let r = |i: usize, j: usize| m.col(j)[i];
    // P = Q Rᵀ: P_ij = Σ_k Q_ik R_jk
    let mut p = [[Vec3::ZERO; 3]; 3];
    for (i, prow) in p.iter_mut().enumerate() {
        for (j, pij) in prow.iter_mut().enumerate() {
            *pij = q[i][0] * r(j, 0) + q[i][1] * r(j, 1) + q[i][2] * r(j, 2);
        }
    }
    // Q' = R P, only the six entries needed.
    let qp = |i: usize, j: usize| p[0][j] * r(i, 0) + p[1][j] * r(i, 1) + p[2][j] * r(i, 2);
    let (xx, yy, zz) = (qp(0, 0), qp(1, 1), qp(2, 2));
    let (xy, yz, xz) = (qp(0, 1), qp(1, 2), qp(0, 2));
    [
        c[0],
        b1[0],
        b1[1],
        b1[2],
        xy * (2.0 / Y2_A),
        yz * (-2.0 / Y2_A),
        zz * (0.5 / Y2_B),
        xz * (-2.0 / Y2_A),
        (xx - yy) * (0.5 / Y2_C),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::convolve::eval_sh;
    use crate::project::fibonacci_sphere;
    use glam::{EulerRot, Quat};
    use proptest::prelude::*;

    fn test_coeffs(order: usize, seed: f32) -> Vec<Vec3> {
        (0..num_coeffs(order))
            .map(|i| {
                let t = i as f32 + seed;
                Vec3::new(
                    (t * 1.3).sin(),
                    (t * 0.7 + 1.0).cos(),
                    0.5 * (t * 2.1).sin(),
                )
            })
            .collect()
    }

    fn rot(a: f32, b: f32, c: f32) -> Mat3 {
        Mat3::from_quat(Quat::from_euler(EulerRot::ZYX, a, b, c))
    }

    /// Rotation against re-projection: project g(d) = f(Rᵀd) by dense
    /// Fibonacci quadrature with ShRgb::add_sample, compare with D·c.
    #[test]
    fn rotation_matches_reprojection() {
        let n = 40_000;
        let dirs = fibonacci_sphere(n);
        let w = 4.0 * std::f32::consts::PI / n as f32;
        for (order, m) in [
            (3usize, rot(0.3, -1.1, 2.0)),
            (5, rot(-2.5, 0.4, 0.9)),
            (8, rot(1.7, 2.9, -0.6)),
        ] {
            let c = test_coeffs(order, order as f32);
            let mut proj = ShRgb::zeros(order);
            for d in &dirs {
                proj.add_sample(*d, eval_sh(&c, m.transpose() * *d), w);
            }
            let r = ShRotation::new(order, m);
            let mut out = vec![Vec3::ZERO; c.len()];
            r.apply(&c, &mut out);
            for (i, (a, b)) in out.iter().zip(proj.coeffs()).enumerate() {
                assert!(
                    (*a - *b).length() < 3e-3,
                    "order {order} coeff {i}: {a} vs {b}"
                );
            }
        }
    }

    /// A lobe's peak follows the rotation: a zonal lobe about +Z rotated by R
    /// reaches its maximum at R·Z (direct evaluation, not re-projection).
    #[test]
    fn zonal_lobe_points_along_rotated_axis() {
        let m = rot(0.8, 0.5, -1.2);
        let order = 4;
        let mut y = [0.0f32; 64];
        crate::basis::eval_basis(order, Vec3::Z, &mut y);
        // A band-limited delta at +Z.
        let c: Vec<Vec3> = y[..16].iter().map(|v| Vec3::splat(*v)).collect();
        let mut out = vec![Vec3::ZERO; 16];
        ShRotation::new(order, m).apply(&c, &mut out);
        let axis = m * Vec3::Z;
        let peak = eval_sh(&out, axis).x;
        for d in fibonacci_sphere(2000) {
            assert!(eval_sh(&out, d).x <= peak + 1e-4);
        }
        // And the rotated function equals the original at Rᵀd everywhere.
        for d in fibonacci_sphere(200) {
            let a = eval_sh(&out, d);
            let b = eval_sh(&c, m.transpose() * d);
            assert!((a - b).length() < 1e-4);
        }
    }

    /// Rotation about +Z by α mixes each (m, −m) pair by the angle mα: the
    /// closed form a' = a cos mα − b sin mα, b' = a sin mα + b cos mα.
    #[test]
    fn z_rotation_closed_form() {
        let alpha = 0.77f32;
        let m = Mat3::from_rotation_z(alpha);
        let order = MAX_ORDER;
        let c = test_coeffs(order, 0.3);
        let mut out = vec![Vec3::ZERO; c.len()];
        ShRotation::new(order, m).apply(&c, &mut out);
        for l in 0..order {
            let i0 = l * (l + 1);
            assert!((out[i0] - c[i0]).length() < 1e-5);
            for mm in 1..=l {
                let (a, b) = (c[i0 + mm], c[i0 - mm]);
                let (s, co) = (mm as f32 * alpha).sin_cos();
                let ea = a * co - b * s;
                let eb = a * s + b * co;
                assert!((out[i0 + mm] - ea).length() < 1e-5, "l {l} m {mm}");
                assert!((out[i0 - mm] - eb).length() < 1e-5, "l {l} m -{mm}");
            }
        }
    }

    /// Rotating zonal coefficients about +Z agrees with the independent
    /// zonal-rotation formula `c_lm = sqrt(4π/(2l+1)) z_l Y_lm(R·Z)`.
    #[test]
    fn agrees_with_zonal_rotation() {
        let zh = [0.9f32, -0.5, 0.3, 0.2, -0.1, 0.05, 0.02, -0.01];
        let m = rot(-0.4, 1.3, 0.25);
        let mut on_z = [0.0f32; 64];
        crate::zonal::zh_to_sh(&zh, Vec3::Z, &mut on_z);
        let mut want = [0.0f32; 64];
        crate::zonal::zh_to_sh(&zh, m * Vec3::Z, &mut want);
        let mut got = [0.0f32; 64];
        ShRotation::new(8, m).apply_scalar(&on_z, &mut got);
        for i in 0..64 {
            assert!(
                (got[i] - want[i]).abs() < 1e-5,
                "{i}: {} vs {}",
                got[i],
                want[i]
            );
        }
        let sh = ShRgb::from_coeffs(on_z.iter().map(|v| Vec3::splat(*v)).collect()).unwrap();
        let r = ShRotation::new(8, m).rotate_sh(&sh);
        assert!((r.coeffs()[5].x - want[5]).abs() < 1e-5);
    }

    #[test]
    fn band_matrix_shapes() {
        let r = ShRotation::new(4, rot(0.1, 0.2, 0.3));
        assert_eq!(r.order(), 4);
        for l in 0..4 {
            assert_eq!(r.band_matrix(l).len(), (2 * l + 1) * (2 * l + 1));
        }
        assert_eq!(r.band_matrix(0), &[1.0]);
    }

    fn arb_rot() -> impl Strategy<Value = Mat3> {
        (-3.2f32..3.2, -3.2f32..3.2, -3.2f32..3.2).prop_map(|(a, b, c)| rot(a, b, c))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn fast_paths_match_general(m in arb_rot(), seed in 0.0f32..10.0) {
            let c = test_coeffs(3, seed);
            let mut g = vec![Vec3::ZERO; 9];
            ShRotation::new(3, m).apply(&c, &mut g);
            let f2 = rotate_l2(m, &c.clone().try_into().unwrap());
            for i in 0..9 {
                prop_assert!((f2[i] - g[i]).length() < 2e-5, "L2 {}: {} vs {}", i, f2[i], g[i]);
            }
            let f1 = rotate_l1(m, &c[..4].try_into().unwrap());
            for i in 0..4 {
                prop_assert!((f1[i] - g[i]).length() < 2e-5);
            }
        }

        /// Fast L2 path against direct evaluation: f_R(d) = f(Rᵀd).
        #[test]
        fn fast_l2_rotates_the_function(m in arb_rot(), seed in 0.0f32..10.0) {
            let c: [Vec3; 9] = test_coeffs(3, seed).try_into().unwrap();
            let r = rotate_l2(m, &c);
            for d in fibonacci_sphere(50) {
                let a = eval_sh(&r, d);
                let b = eval_sh(&c, m.transpose() * d);
                prop_assert!((a - b).length() < 1e-4);
            }
        }

        #[test]
        fn preserves_band_energy(m in arb_rot(), seed in 0.0f32..10.0) {
            let order = MAX_ORDER;
            let c: Vec<f32> = test_coeffs(order, seed).iter().map(|v| v.x).collect();
            let mut out = vec![0.0f32; c.len()];
            ShRotation::new(order, m).apply_scalar(&c, &mut out);
            for l in 0..order {
                let e0: f32 = c[l * l..(l + 1) * (l + 1)].iter().map(|v| v * v).sum();
                let e1: f32 = out[l * l..(l + 1) * (l + 1)].iter().map(|v| v * v).sum();
                prop_assert!((e0 - e1).abs() < 1e-4 * (1.0 + e0), "band {}: {} vs {}", l, e0, e1);
            }
        }

        #[test]
        fn composes(m1 in arb_rot(), m2 in arb_rot(), seed in 0.0f32..10.0) {
            let order = 6;
            let c = test_coeffs(order, seed);
            let mut a = vec![Vec3::ZERO; c.len()];
            let mut b = vec![Vec3::ZERO; c.len()];
            ShRotation::new(order, m1).apply(&c, &mut a);
            ShRotation::new(order, m2).apply(&a.clone(), &mut b);
            let mut d = vec![Vec3::ZERO; c.len()];
            ShRotation::new(order, m2 * m1).apply(&c, &mut d);
            for i in 0..c.len() {
                prop_assert!((b[i] - d[i]).length() < 1e-4, "{}: {} vs {}", i, b[i], d[i]);
            }
        }

        #[test]
        fn inverse_round_trips(m in arb_rot(), seed in 0.0f32..10.0) {
            let order = MAX_ORDER;
            let c = test_coeffs(order, seed);
            let mut a = vec![Vec3::ZERO; c.len()];
            let mut b = vec![Vec3::ZERO; c.len()];
            ShRotation::new(order, m).apply(&c, &mut a);
            ShRotation::new(order, m.transpose()).apply(&a, &mut b);
            for i in 0..c.len() {
                prop_assert!((b[i] - c[i]).length() < 1e-4);
            }
            // Block of Rᵀ is the transpose of the block of R.
            let r = ShRotation::new(order, m);
            let rt = ShRotation::new(order, m.transpose());
            for l in 0..order {
                let s = 2 * l + 1;
                let (p, q) = (r.band_matrix(l), rt.band_matrix(l));
                for i in 0..s {
                    for j in 0..s {
                        prop_assert!((p[i * s + j] - q[j * s + i]).abs() < 1e-5);
                    }
                }
            }
        }

        #[test]
        fn identity_is_identity(order in 1usize..=MAX_ORDER, seed in 0.0f32..10.0) {
            let c = test_coeffs(order, seed);
            let mut a = vec![Vec3::ZERO; c.len()];
            ShRotation::new(order, Mat3::IDENTITY).apply(&c, &mut a);
            for i in 0..c.len() {
                prop_assert!((a[i] - c[i]).length() < 1e-6);
            }
        }
    }
}
