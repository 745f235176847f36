//! The real spherical-harmonic basis: indexing, the general recurrence and
//! hand-written L1/L2 fast paths.
//!
//! Conventions (see the crate root): real SH, coefficient index `l*(l+1)+m`,
//! Condon–Shortley phase as in Sloan, *Stupid Spherical Harmonics (SH) Tricks*
//! (GDC 2008), appendix A2: `Y1,-1 = -0.4886·y`, `Y1,0 = 0.4886·z`,
//! `Y1,1 = -0.4886·x`. The polar axis of the basis is therefore +Z even though
//! the world is +Y up; nothing in the basis depends on the up axis.
//!
//! An *order* is a number of bands: order `N` holds bands `l = 0..N`, that is
//! `N²` coefficients. L1 is order 2 (4 coefficients), L2 is order 3 (9).

#[cfg(not(feature = "std"))]
use crate::math::FloatMath;
use glam::Vec3;

/// The largest supported order (number of bands): 8, i.e. `l = 0..=7`, 64 coefficients.
///
/// Eight bands is well beyond what diffuse lighting needs (the clamped cosine
/// keeps 99.2 % of its energy in the first three); it bounds stack arrays.
pub const MAX_ORDER: usize = 8;

/// The largest number of coefficients, `MAX_ORDER²`.
pub const MAX_COEFFS: usize = MAX_ORDER * MAX_ORDER;

/// Number of coefficients of an order (number of bands): `order²`.
#[inline]
pub const fn num_coeffs(order: usize) -> usize {
    order * order
}

/// Flat index of coefficient `(l, m)`, `-l <= m <= l`: `l*(l+1)+m`.
#[inline]
pub const fn index(l: usize, m: i32) -> usize {
    ((l * (l + 1)) as i32 + m) as usize
}

/// The order (number of bands) whose coefficient count is `n`, if `n` is a perfect square
/// in `1..=MAX_COEFFS`.
pub fn order_from_len(n: usize) -> Option<usize> {
    (1..=MAX_ORDER).find(|&o| o * o == n)
}

/// `Y00 = 1 / (2√π)`.
pub const Y00: f32 = 0.282_094_8;
/// Magnitude of the band-1 constants, `√3 / (2√π)`.
pub const Y1: f32 = 0.488_602_5;
/// `√15 / (2√π)`: `Y2,-2`, `Y2,-1`, `Y2,1`.
pub const Y2_A: f32 = 1.092_548_5;
/// `√5 / (4√π)`: `Y2,0 = Y2_B·(3z² − 1)`.
pub const Y2_B: f32 = 0.315_391_57;
/// `√15 / (4√π)`: `Y2,2 = Y2_C·(x² − y²)`.
pub const Y2_C: f32 = 0.546_274_2;

/// The four L1 basis functions at unit direction `d`, fast path.
#[inline]
pub fn eval_l1(d: Vec3) -> [f32; 4] {
    [Y00, -Y1 * d.y, Y1 * d.z, -Y1 * d.x]
}

/// The nine L2 basis functions at unit direction `d`, fast path
/// (Sloan, *Stupid SH Tricks*, appendix A2, with the Condon–Shortley phase).
#[inline]
pub fn eval_l2(d: Vec3) -> [f32; 9] {
    let (x, y, z) = (d.x, d.y, d.z);
    [
        Y00,
        -Y1 * y,
        Y1 * z,
        -Y1 * x,
        Y2_A * x * y,
        -Y2_A * y * z,
        Y2_B * (3.0 * z * z - 1.0),
        -Y2_A * x * z,
        Y2_C * (x * x - y * y),
    ]
}

/// Normalisation `K_l^m = sqrt((2l+1)/(4π) · (l−|m|)!/(l+|m|)!)`, in f64.
pub fn normalization(l: usize, m: i32) -> f64 {
    let am = m.unsigned_abs() as usize;
    let mut ratio = 1.0f64; // (l-|m|)! / (l+|m|)!
    for k in (l - am + 1)..=(l + am) {
        ratio /= k as f64;
    }
    ((2 * l + 1) as f64 / (4.0 * core::f64::consts::PI) * ratio).sqrt()
}

/// Evaluates all basis functions of `order` bands at unit direction `d` into
/// `out[..order²]`, by the associated-Legendre recurrence in f64.
///
/// Uses `P̃_l^m(z) = P_l^m(z) / sin^m θ` (with the Condon–Shortley phase) and
/// `sin^m θ·cos mφ = Re (x + iy)^m`, `sin^m θ·sin mφ = Im (x + iy)^m`, so no
/// trigonometry is needed and the poles are exact.
///
/// # Panics
/// If `order` is 0 or greater than [`MAX_ORDER`], or `out` is shorter than `order²`.
pub fn eval_basis(order: usize, d: Vec3, out: &mut [f32]) {
    let mut tmp = [0.0f64; MAX_COEFFS];
    eval_basis_f64(order, d.as_dvec3(), &mut tmp);
    for (o, t) in out[..num_coeffs(order)].iter_mut().zip(tmp.iter()) {
        *o = *t as f32;
    }
}

/// [`eval_basis`] in f64, for reference integrals and fitting.
///
/// # Panics
/// If `order` is 0 or greater than [`MAX_ORDER`], or `out` is shorter than `order²`.
pub fn eval_basis_f64(order: usize, d: glam::DVec3, out: &mut [f64]) {
    assert!(
        (1..=MAX_ORDER).contains(&order),
        "SH order {order} outside 1..={MAX_ORDER}"
    );
    let out = &mut out[..num_coeffs(order)];
    let (x, y, z) = (d.x, d.y, d.z);
    // cm[m] = Re (x+iy)^m, sm[m] = Im (x+iy)^m
    let mut cm = [0.0f64; MAX_ORDER];
    let mut sm = [0.0f64; MAX_ORDER];
    cm[0] = 1.0;
    for m in 1..order {
        cm[m] = x * cm[m - 1] - y * sm[m - 1];
        sm[m] = x * sm[m - 1] + y * cm[m - 1];
    }
    let sqrt2 = core::f64::consts::SQRT_2;
    for m in 0..order {
        // P̃_m^m = (-1)^m (2m-1)!!
        let mut pmm = 1.0f64;
        for k in 0..m {
            pmm *= -((2 * k + 1) as f64);
        }
        let mut p_lm2 = 0.0f64; // P̃_{l-2}^m
        let mut p_lm1 = pmm; // P̃_{l-1}^m, starts as P̃_m^m
        for l in m..order {
            let p = if l == m {
                pmm
            } else if l == m + 1 {
                z * (2 * m + 1) as f64 * pmm
            } else {
                ((2 * l - 1) as f64 * z * p_lm1 - (l + m - 1) as f64 * p_lm2) / (l - m) as f64
            };
            if l > m {
                p_lm2 = p_lm1;
                p_lm1 = p;
            }
            let k = normalization(l, m as i32);
            if m == 0 {
                out[index(l, 0)] = k * p;
            } else {
                out[index(l, m as i32)] = sqrt2 * k * p * cm[m];
                out[index(l, -(m as i32))] = sqrt2 * k * p * sm[m];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fib_dirs(n: usize) -> Vec<Vec3> {
        let ga = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
                let r = (1.0 - z * z).sqrt();
                let phi = ga * i as f64;
                Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32)
            })
            .collect()
    }

    #[test]
    fn fast_paths_match_recurrence() {
        for d in fib_dirs(200) {
            let mut g = [0.0f32; 9];
            eval_basis(3, d, &mut g);
            let f = eval_l2(d);
            for i in 0..9 {
                assert!(
                    (g[i] - f[i]).abs() < 1e-5,
                    "coefficient {i}: {} vs {}",
                    g[i],
                    f[i]
                );
            }
            let f1 = eval_l1(d);
            for i in 0..4 {
                assert!((g[i] - f1[i]).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn sign_convention_matches_sloan() {
        let b = eval_l2(Vec3::Y);
        assert!(b[1] < 0.0 && (b[1] + Y1).abs() < 1e-6);
        let b = eval_l2(Vec3::Z);
        assert!(b[2] > 0.0);
        let b = eval_l2(Vec3::X);
        assert!(b[3] < 0.0);
    }

    /// Orthonormality by numerical integration over a dense Fibonacci sphere
    /// (an independent quadrature, not the recurrence itself).
    #[test]
    fn orthonormal_up_to_order_8() {
        let n = 40_000;
        let dirs = fib_dirs(n);
        let nc = MAX_COEFFS;
        let mut gram = vec![0.0f64; nc * nc];
        let mut b = [0.0f64; MAX_COEFFS];
        for d in &dirs {
            eval_basis_f64(MAX_ORDER, d.as_dvec3(), &mut b);
            for i in 0..nc {
                for j in 0..nc {
                    gram[i * nc + j] += b[i] * b[j];
                }
            }
        }
        let w = 4.0 * std::f64::consts::PI / n as f64;
        for i in 0..nc {
            for j in 0..nc {
                let v = gram[i * nc + j] * w;
                let e = if i == j { 1.0 } else { 0.0 };
                assert!((v - e).abs() < 2e-3, "<Y{i},Y{j}> = {v}");
            }
        }
    }

    #[test]
    fn order_from_len_roundtrip() {
        for o in 1..=MAX_ORDER {
            assert_eq!(order_from_len(num_coeffs(o)), Some(o));
        }
        assert_eq!(order_from_len(5), None);
        assert_eq!(order_from_len(81), None);
    }
}
