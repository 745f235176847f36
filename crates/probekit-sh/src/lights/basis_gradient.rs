//! The SH basis together with its gradient on the unit sphere, needed to
//! differentiate a zonal lobe whose axis moves (the lateral terms of the
//! sphere light's spatial gradient).
//!
//! For each basis function we differentiate a smooth extension `f_lm(x, y, z)`
//! to ℝ³ — the same expression the recurrence of [`crate::basis`] evaluates,
//! `K·P̃_l^m(z)·Re/Im (x + iy)^m` (Cartesian polynomials `eval_l2` for L2) — and
//! keep the tangential part `(I − d dᵀ)∇f`, which is the surface gradient of
//! `Y_lm` whatever the extension. Derivatives used:
//! `∂/∂x (x+iy)^m = m (x+iy)^{m−1}`, `∂/∂y (x+iy)^m = i m (x+iy)^{m−1}`, and the
//! z-derivative of the associated-Legendre recurrence
//! `P̃_l = ((2l−1) z P̃_{l−1} − (l+m−1) P̃_{l−2})/(l−m)` differentiated term by term.

use crate::basis::{
    eval_l2, normalization, num_coeffs, MAX_COEFFS, MAX_ORDER, Y1, Y2_A, Y2_B, Y2_C,
};
use glam::Vec3;

/// Evaluates the basis of `order` bands at unit direction `d` into
/// `values[..order²]` and its **tangential** (surface) gradient into
/// `grads[..order²]`: `grads[i]·t` is the rate of change of `Y_i` when `d`
/// moves along a unit tangent `t` (`grads[i]·d = 0`).
///
/// Orders ≤ 3 use hand-written derivatives of the L2 Cartesian polynomials
/// (Sloan, *Stupid SH Tricks*, appendix A2); higher orders differentiate the
/// f64 associated-Legendre recurrence (see the module docs).
///
/// # Panics
/// If `order` is not in `1..=MAX_ORDER`, or either slice is shorter than `order²`.
pub fn eval_basis_tangent_gradient(order: usize, d: Vec3, values: &mut [f32], grads: &mut [Vec3]) {
    assert!(
        (1..=MAX_ORDER).contains(&order),
        "SH order {order} outside 1..={MAX_ORDER}"
    );
    let n = num_coeffs(order);
    assert!(
        values.len() >= n && grads.len() >= n,
        "output slices too short"
    );
    if order <= 3 {
        let v = eval_l2(d);
        values[..n].copy_from_slice(&v[..n]);
        let (x, y, z) = (d.x, d.y, d.z);
        let g = [
            Vec3::ZERO,
            Vec3::new(0.0, -Y1, 0.0),
            Vec3::new(0.0, 0.0, Y1),
            Vec3::new(-Y1, 0.0, 0.0),
            Vec3::new(y, x, 0.0) * Y2_A,
            Vec3::new(0.0, z, y) * -Y2_A,
            Vec3::new(0.0, 0.0, 6.0 * z) * Y2_B,
            Vec3::new(z, 0.0, x) * -Y2_A,
            Vec3::new(2.0 * x, -2.0 * y, 0.0) * Y2_C,
        ];
        for (o, gi) in grads[..n].iter_mut().zip(g.iter()) {
            *o = *gi - d * gi.dot(d);
        }
        return;
    }
    let dd = d.as_dvec3();
    let (x, y, z) = (dd.x, dd.y, dd.z);
    let mut cm = [0.0f64; MAX_ORDER];
    let mut sm = [0.0f64; MAX_ORDER];
    cm[0] = 1.0;
    for m in 1..order {
        cm[m] = x * cm[m - 1] - y * sm[m - 1];
        sm[m] = x * sm[m - 1] + y * cm[m - 1];
    }
    let sqrt2 = core::f64::consts::SQRT_2;
    let mut vals = [0.0f64; MAX_COEFFS];
    let mut grd = [glam::DVec3::ZERO; MAX_COEFFS];
    for m in 0..order {
        let mut pmm = 1.0f64;
        for k in 0..m {
            pmm *= -((2 * k + 1) as f64);
        }
        let (mut p2, mut p1) = (0.0f64, pmm); // P̃_{l-2}, P̃_{l-1}
        let (mut dp2, mut dp1) = (0.0f64, 0.0f64); // their z-derivatives
        for l in m..order {
            let (p, dp) = if l == m {
                (pmm, 0.0)
            } else if l == m + 1 {
                (z * (2 * m + 1) as f64 * pmm, (2 * m + 1) as f64 * pmm)
            } else {
                let a = (2 * l - 1) as f64;
                let b = (l + m - 1) as f64;
                let c = (l - m) as f64;
                (
                    (a * z * p1 - b * p2) / c,
                    (a * (p1 + z * dp1) - b * dp2) / c,
                )
            };
            if l > m {
                p2 = p1;
                p1 = p;
                dp2 = dp1;
                dp1 = dp;
            }
            let k = normalization(l, m as i32);
            if m == 0 {
                let i = l * (l + 1);
                vals[i] = k * p;
                grd[i] = glam::DVec3::new(0.0, 0.0, k * dp);
            } else {
                let mf = m as f64;
                let s = sqrt2 * k;
                let ip = l * (l + 1) + m;
                let im = l * (l + 1) - m;
                vals[ip] = s * p * cm[m];
                vals[im] = s * p * sm[m];
                grd[ip] = glam::DVec3::new(
                    s * p * mf * cm[m - 1],
                    -s * p * mf * sm[m - 1],
                    s * dp * cm[m],
                );
                grd[im] = glam::DVec3::new(
                    s * p * mf * sm[m - 1],
                    s * p * mf * cm[m - 1],
                    s * dp * sm[m],
                );
            }
        }
    }
    for i in 0..n {
        values[i] = vals[i] as f32;
        let g = grd[i] - dd * grd[i].dot(dd);
        grads[i] = g.as_vec3();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::eval_basis_f64;
    use glam::DVec3;

    /// Values equal the basis; tangential gradients equal central differences of
    /// the (independently tested) basis along two tangent great circles.
    #[test]
    fn gradient_matches_central_differences() {
        let dirs = [
            Vec3::new(0.3, -0.5, 0.81),
            Vec3::new(-0.9, 0.1, 0.2),
            Vec3::new(0.05, 0.02, -1.0),
            Vec3::new(0.6, 0.6, -0.5),
        ];
        for order in [2usize, 3, 4, 8] {
            for d in dirs {
                let d = d.normalize();
                let mut v = [0.0f32; MAX_COEFFS];
                let mut g = [Vec3::ZERO; MAX_COEFFS];
                eval_basis_tangent_gradient(order, d, &mut v, &mut g);
                let dd = d.as_dvec3();
                let mut y0 = [0.0f64; MAX_COEFFS];
                eval_basis_f64(order, dd, &mut y0);
                let t1 = dd.any_orthonormal_vector();
                let t2 = dd.cross(t1);
                for t in [t1, t2] {
                    let h = 1e-5;
                    let rot = |a: f64| -> DVec3 { dd * a.cos() + t * a.sin() };
                    let mut yp = [0.0f64; MAX_COEFFS];
                    let mut ym = [0.0f64; MAX_COEFFS];
                    eval_basis_f64(order, rot(h), &mut yp);
                    eval_basis_f64(order, rot(-h), &mut ym);
                    for i in 0..num_coeffs(order) {
                        assert!((v[i] as f64 - y0[i]).abs() < 1e-5);
                        let fd = (yp[i] - ym[i]) / (2.0 * h);
                        let an = g[i].as_dvec3().dot(t);
                        assert!(
                            (fd - an).abs() < 1e-4 * (1.0 + fd.abs()),
                            "order {order} i {i} d {d}: fd {fd} analytic {an}"
                        );
                    }
                }
                for gi in &g[..num_coeffs(order)] {
                    assert!(gi.dot(d).abs() < 1e-5);
                }
            }
        }
    }
}
