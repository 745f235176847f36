//! Small numerical helpers shared by the basis fits (private to the crate):
//! spherical point sets, Gauss–Legendre nodes, a dense linear solver and a
//! 3×3 symmetric eigen-solver. Everything in f64, deterministic.

// Index loops over colour channels and SH coefficients read like the formulas.
#![allow(clippy::needless_range_loop)]

#[cfg(not(feature = "std"))]
use crate::math::FloatMath;
use alloc::vec::Vec;
use glam::DVec3;

#[cfg(test)]
/// `n` points of the spherical Fibonacci lattice (equal-area, golden-angle
/// spiral; Swinbank & Purser 2006), each standing for `4π/n` steradians.
pub(crate) fn fibonacci_sphere(n: usize) -> Vec<DVec3> {
    (0..n)
        .map(|i| crate::project::fibonacci_point_f64(i, n))
        .collect()
}

/// `n` Fibonacci points on the upper hemisphere `z > 0`, each standing for
/// `2π/n` steradians.
pub(crate) fn fibonacci_hemisphere(n: usize) -> Vec<DVec3> {
    let ga = core::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = ga * i as f64;
            DVec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// Gauss–Legendre nodes and weights on `[a, b]` with `n` points (exact for
/// polynomials of degree `2n − 1`), by Newton iteration on `P_n`.
pub(crate) fn gauss_legendre(n: usize, a: f64, b: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        // Tricomi's initial guess for the i-th root of P_n.
        let mut x = (core::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0f64, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            // p1 = P_n(x), p0 = P_{n-1}(x)
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        out.push((0.5 * (b - a) * x + 0.5 * (b + a), 0.5 * (b - a) * w));
    }
    out
}

/// Solves the dense `n × n` system `a · x = b` (row-major `a`) in place by
/// Gaussian elimination with partial pivoting. A (numerically) zero pivot
/// leaves that unknown at 0 instead of dividing by zero; callers that can be
/// singular regularise first.
pub(crate) fn solve_dense(n: usize, a: &mut [f64], b: &mut [f64]) {
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&i, &j| a[i * n + col].abs().total_cmp(&a[j * n + col].abs()))
            .unwrap_or(col);
        if piv != col {
            for k in 0..n {
                a.swap(col * n + k, piv * n + k);
            }
            b.swap(col, piv);
        }
        let p = a[col * n + col];
        if p.abs() < 1e-300 {
            continue;
        }
        for r in col + 1..n {
            let f = a[r * n + col] / p;
            if f != 0.0 {
                for k in col..n {
                    a[r * n + k] -= f * a[col * n + k];
                }
                b[r] -= f * b[col];
            }
        }
    }
    for col in (0..n).rev() {
        let p = a[col * n + col];
        let mut s = b[col];
        for k in col + 1..n {
            s -= a[col * n + k] * b[k];
        }
        b[col] = if p.abs() < 1e-300 { 0.0 } else { s / p };
    }
}

/// Eigenvectors of a symmetric 3×3 matrix (cyclic Jacobi rotations); returns
/// `(eigenvalues, eigenvectors)` with eigenvector `k` in column `k`.
pub(crate) fn symmetric_eigen3(m: [[f64; 3]; 3]) -> ([f64; 3], [DVec3; 3]) {
    let mut a = m;
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..50 {
        let off = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
        if off < 1e-30 {
            break;
        }
        for (p, q) in [(0usize, 1usize), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-300 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // A ← Jᵀ A J with J the rotation in the (p, q) plane.
            for k in 0..3 {
                let akp = a[k][p];
                let akq = a[k][q];
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let apk = a[p][k];
                let aqk = a[q][k];
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in v.iter_mut() {
                let vp = row[p];
                let vq = row[q];
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let vecs = [0, 1, 2].map(|k| DVec3::new(v[0][k], v[1][k], v[2][k]));
    ([a[0][0], a[1][1], a[2][2]], vecs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        let nodes = gauss_legendre(6, 0.0, 1.0);
        for deg in 0..12 {
            let s: f64 = nodes.iter().map(|(x, w)| w * x.powi(deg)).sum();
            assert!(
                (s - 1.0 / (deg as f64 + 1.0)).abs() < 1e-13,
                "degree {deg}: {s}"
            );
        }
    }

    #[test]
    fn solve_dense_recovers_known_solution() {
        let a0 = [4.0, 1.0, 2.0, 0.5, 3.0, -1.0, 2.0, 1.0, 5.0];
        let x = [1.0, -2.0, 0.25];
        let mut b: Vec<f64> = (0..3)
            .map(|r| (0..3).map(|k| a0[r * 3 + k] * x[k]).sum())
            .collect();
        let mut a = a0.to_vec();
        solve_dense(3, &mut a, &mut b);
        for k in 0..3 {
            assert!((b[k] - x[k]).abs() < 1e-12);
        }
    }

    #[test]
    fn eigen_satisfies_definition() {
        let m = [[2.0, -0.7, 0.3], [-0.7, -1.0, 0.9], [0.3, 0.9, 0.5]];
        let (vals, vecs) = symmetric_eigen3(m);
        for k in 0..3 {
            let v = vecs[k];
            let mv = DVec3::new(
                m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
                m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z,
            );
            assert!((mv - v * vals[k]).length() < 1e-10);
            assert!((v.length() - 1.0).abs() < 1e-12);
        }
    }
}
