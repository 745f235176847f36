//! Analytic lights projected into **radiance** SH, as seen from a receiving
//! point `p`.
//!
//! Conventions (crate root): real SH of `order` bands, index `l*(l+1)+m`,
//! directions point **from `p` towards the light**; the coefficients hold
//! radiance, so irradiance comes from [`crate::convolve::irradiance`]
//! (clamped-cosine convolution, not divided by π). Every function *overwrites*
//! `out[..order²]`; sum several lights yourself.
//!
//! Units follow the scene format (glTF `KHR_lights_punctual`, without the 683
//! lm/W factor, i.e. radiometric):
//!
//! | light | parameter | unit | radiance seen from `p` |
//! |---|---|---|---|
//! | directional | `color_lux` | irradiance on a plane perpendicular to the light (W/m²) | delta of `E` |
//! | point, spot | `intensity` | radiant intensity (W/sr, "candela") | delta of `E = I/d²` |
//! | sphere | `intensity` | radiant intensity of the whole sphere (W/sr) | uniform cap, `L = I/(π r²)` |
//! | disk | `intensity` | radiant intensity along the normal (W/sr) | one-sided Lambertian, `L = I/(π r²)` |
//! | cone | `radiance` | radiance (W/(m²·sr)) | uniform cap |
//!
//! A delta of irradiance `E` from direction `ω₀` has SH coefficients
//! `c_lm = E·Y_lm(ω₀)` (Sloan, *Stupid Spherical Harmonics (SH) Tricks*, GDC
//! 2008, §"Directional lights").
//!
//! A uniform spherical cap of half-angle `α` and radiance `L` about axis `a`
//! (the cone, and the sphere light with `sin α = r/d`) has
//! `c_lm = L·A_l(α)·Y_lm(a)` with the per-band factor
//! `A_l(α) = 2π ∫_{cos α}^{1} P_l(x) dx`, i.e.
//! `A_0 = 2π(1 − cos α)` and, for `l ≥ 1`,
//! `A_l = 2π (P_{l−1}(cos α) − P_{l+1}(cos α))/(2l+1) = 2π sin²α · P_l'(cos α)/(l(l+1))`
//! (the second form uses `(1−x²)P_l' = l(l+1)(P_{l−1} − P_{l+1})/(2l+1)` and has no
//! cancellation for small caps). These are the zonal coefficients of Yuan,
//! Nowrouzezahrai & Sloan, *Irradiance Rigs* (JGT 2011), appendix A1, which
//! lists `A_0..A_5` for `sin α = r/d` ("including the per-band scaling"); in this
//! crate's ZH convention ([`crate::zonal`]) the zonal coefficient is
//! `z_l = sqrt((2l+1)/(4π))·L·A_l`.
//!
//! Sub-modules: [`sphere`] (sphere light, its spatial gradient and the exact
//! horizon-clipped irradiance) and [`disk`] (disk light by quadrature).

pub mod basis_gradient;
pub mod disk;
pub mod sphere;

pub use basis_gradient::eval_basis_tangent_gradient;
pub use disk::disk_light_sh;
pub use sphere::{
    sphere_light_irradiance_horizon_clipped, sphere_light_sh, sphere_light_sh_and_gradient,
    sphere_light_sh_gradient, sphere_light_zh,
};

use crate::basis::{eval_basis, eval_l2, num_coeffs, MAX_COEFFS, MAX_ORDER};
#[cfg(not(feature = "std"))]
use crate::math::FloatMath;
use core::f64::consts::PI;
use glam::Vec3;

/// Checks `order` and the output length; the crate's convention is to panic on
/// these programming errors (as [`crate::basis::eval_basis`] does).
#[inline]
pub(crate) fn check_order(order: usize, out_len: usize) {
    assert!(
        (1..=MAX_ORDER).contains(&order),
        "SH order {order} outside 1..={MAX_ORDER}"
    );
    assert!(
        out_len >= num_coeffs(order),
        "output holds {out_len} coefficients, order {order} needs {}",
        num_coeffs(order)
    );
}

/// The basis at unit `d` into `b[..order²]`, through the L2 fast path when `order ≤ 3`.
#[inline]
pub(crate) fn basis_fast(order: usize, d: Vec3, b: &mut [f32; MAX_COEFFS]) {
    if order <= 3 {
        let f = eval_l2(d);
        b[..9].copy_from_slice(&f);
    } else {
        eval_basis(order, d, b);
    }
}

/// Writes `c_lm = weight · Y_lm(dir)` (a delta) into `out[..order²]`; `dir` unit.
#[inline]
fn delta_sh(order: usize, dir: Vec3, weight: Vec3, out: &mut [Vec3]) {
    let mut b = [0.0f32; MAX_COEFFS];
    basis_fast(order, dir, &mut b);
    for (o, y) in out[..num_coeffs(order)].iter_mut().zip(b.iter()) {
        *o = weight * *y;
    }
}

/// Zeroes `out[..order²]`.
#[inline]
pub(crate) fn zero(order: usize, out: &mut [Vec3]) {
    for o in &mut out[..num_coeffs(order)] {
        *o = Vec3::ZERO;
    }
}

/// Per-band cap factors `A_l(α) = 2π ∫_{cos α}^1 P_l(x) dx` for `l < order`, in f64,
/// from `cos α` and `sin² α` (both given so callers can compute them without
/// cancellation). See the module docs for the formula and its source.
pub(crate) fn cap_band_factors(order: usize, cos_a: f64, sin2_a: f64) -> [f64; MAX_ORDER] {
    let mut a = [0.0f64; MAX_ORDER];
    // 1 − cos α without cancellation for small caps.
    let one_minus_cos = if cos_a > 0.0 {
        sin2_a / (1.0 + cos_a)
    } else {
        1.0 - cos_a
    };
    a[0] = 2.0 * PI * one_minus_cos;
    // P_l'(x) by P'_{l+1} = P'_{l−1} + (2l+1) P_l, with P_l by Bonnet's recurrence.
    let x = cos_a;
    let (mut p_prev, mut p) = (1.0f64, x); // P_0, P_1
    let (mut dp_prev, mut dp) = (0.0f64, 1.0f64); // P_0', P_1'
    for (l, al) in a.iter_mut().enumerate().take(order).skip(1) {
        *al = 2.0 * PI * sin2_a * dp / (l * (l + 1)) as f64;
        let p_next = ((2 * l + 1) as f64 * x * p - l as f64 * p_prev) / (l + 1) as f64;
        let dp_next = dp_prev + (2 * l + 1) as f64 * p;
        p_prev = p;
        p = p_next;
        dp_prev = dp;
        dp = dp_next;
    }
    a
}

/// A directional light (sun) as a delta of irradiance in radiance SH:
/// `c_lm = E·Y_lm(dir_to_light)`, written to `out[..order²]`.
///
/// `dir_to_light` points from the receiver towards the light (normalised here;
/// a zero or non-finite vector gives all-zero output). `color_lux` is the
/// irradiance on a plane perpendicular to the light, per RGB channel (glTF
/// `KHR_lights_punctual` directional intensity × colour, radiometric).
/// Source: Sloan, *Stupid SH Tricks* (GDC 2008), directional lights.
///
/// # Panics
/// If `order` is not in `1..=MAX_ORDER` or `out` is shorter than `order²`.
pub fn directional_sh(order: usize, dir_to_light: Vec3, color_lux: Vec3, out: &mut [Vec3]) {
    check_order(order, out.len());
    match dir_to_light.try_normalize() {
        Some(d) => delta_sh(order, d, color_lux, out),
        None => zero(order, out),
    }
}

/// A point light at `light_pos` seen from `p`: a delta of irradiance
/// `E = I/d²` from the direction of the light, `c_lm = E·Y_lm((light_pos − p)/d)`.
///
/// `intensity` is the radiant intensity per RGB channel (W/sr; glTF candela ×
/// colour without the 683 factor). When `p` coincides with the light (or
/// the input is not finite) the irradiance is undefined and the output is
/// all zeros.
///
/// # Panics
/// If `order` is not in `1..=MAX_ORDER` or `out` is shorter than `order²`.
pub fn point_sh(order: usize, p: Vec3, light_pos: Vec3, intensity: Vec3, out: &mut [Vec3]) {
    check_order(order, out.len());
    let w = light_pos - p;
    let d2 = w.length_squared();
    match w.try_normalize() {
        Some(dir) if d2 > 0.0 && d2.is_finite() => delta_sh(order, dir, intensity / d2, out),
        _ => zero(order, out),
    }
}

/// The angular attenuation of a glTF `KHR_lights_punctual` spot light, so that
/// probekit matches glTF viewers:
///
/// `scale = 1 / max(0.001, cos inner − cos outer)`, `offset = −cos outer · scale`,
/// `t = clamp(cd·scale + offset, 0, 1)`, attenuation `= t²`,
///
/// where `cd = cos` of the angle between the spot's axis (the way light
/// travels) and the direction from the light to the receiver. It is 1 inside
/// the inner cone, 0 outside the outer cone, and falls off as the square of a
/// linear ramp in `cos` in between. Source: the `KHR_lights_punctual`
/// specification, "Inner and Outer Cone Angles" (Khronos, 2018).
pub fn spot_attenuation(cos_to_receiver: f32, inner_rad: f32, outer_rad: f32) -> f32 {
    let [scale, offset] = spot_scale_offset(inner_rad, outer_rad);
    let t = (cos_to_receiver * scale + offset).clamp(0.0, 1.0);
    t * t
}

/// The `[scale, offset]` of [`spot_attenuation`] for cone half-angles
/// `inner_rad` and `outer_rad` (radians): what a shader needs to apply the
/// same attenuation, `t = clamp(cd·scale + offset, 0, 1)`, `t²`.
pub fn spot_scale_offset(inner_rad: f32, outer_rad: f32) -> [f32; 2] {
    let (ci, co) = (inner_rad.cos(), outer_rad.cos());
    let scale = 1.0 / (ci - co).max(0.001);
    [scale, -co * scale]
}

/// A spot light: a point light at `light_pos` whose intensity is multiplied by
/// the glTF spot attenuation ([`spot_attenuation`]).
///
/// `light_dir` is the spot's axis, the way light travels (normalised here);
/// `inner_deg`/`outer_deg` are the glTF cone half-angles in **degrees**
/// (`0 ≤ inner < outer ≤ 90` in glTF; other values still give the formula's
/// result). `intensity` is the on-axis radiant intensity (W/sr). A zero
/// `light_dir`, or `p` at the light, gives all-zero output.
///
/// # Panics
/// If `order` is not in `1..=MAX_ORDER` or `out` is shorter than `order²`.
#[allow(clippy::too_many_arguments)]
pub fn spot_sh(
    order: usize,
    p: Vec3,
    light_pos: Vec3,
    light_dir: Vec3,
    inner_deg: f32,
    outer_deg: f32,
    intensity: Vec3,
    out: &mut [Vec3],
) {
    check_order(order, out.len());
    let (Some(axis), Some(to_receiver)) =
        (light_dir.try_normalize(), (p - light_pos).try_normalize())
    else {
        zero(order, out);
        return;
    };
    let att = spot_attenuation(
        axis.dot(to_receiver),
        inner_deg.to_radians(),
        outer_deg.to_radians(),
    );
    point_sh(order, p, light_pos, intensity * att, out);
}

/// Uniform radiance `radiance` inside a cone (spherical cap) of half-angle
/// `half_angle` radians about unit `axis` (pointing from the receiver into the
/// cone), zero outside: `c_lm = L·A_l(α)·Y_lm(axis)` with the closed-form cap
/// factors of the module docs (integrals of Legendre polynomials,
/// `∫_{cos α}^1 P_l = (P_{l−1}(cos α) − P_{l+1}(cos α))/(2l+1)`).
///
/// `half_angle` is clamped to `[0, π]` (π is the whole sphere). A zero `axis`
/// or a NaN angle gives all-zero output.
///
/// # Panics
/// If `order` is not in `1..=MAX_ORDER` or `out` is shorter than `order²`.
pub fn cone_sh(order: usize, axis: Vec3, half_angle: f32, radiance: Vec3, out: &mut [Vec3]) {
    check_order(order, out.len());
    let Some(axis) = axis.try_normalize().filter(|_| !half_angle.is_nan()) else {
        zero(order, out);
        return;
    };
    let alpha = (half_angle as f64).clamp(0.0, PI);
    let a = if alpha >= PI {
        // sin²π rounds to ~1e-32, not 0: the whole sphere has only band 0.
        let mut full = [0.0; MAX_ORDER];
        full[0] = 4.0 * PI;
        full
    } else {
        cap_band_factors(order, alpha.cos(), alpha.sin().powi(2))
    };
    let mut b = [0.0f32; MAX_COEFFS];
    basis_fast(order, axis, &mut b);
    for (l, al) in a.iter().enumerate().take(order) {
        let f = radiance * *al as f32;
        for i in l * l..(l + 1) * (l + 1) {
            out[i] = f * b[i];
        }
    }
}

#[cfg(test)]
pub(crate) mod testutil {
    //! Brute-force references shared by the light tests: quadrature over a
    //! spherical cap of directions (golden-angle spiral, uniform in `cos θ`),
    //! which integrates any function of direction restricted to the cap.

    use crate::basis::{eval_basis_f64, num_coeffs, MAX_COEFFS};
    use glam::DVec3;

    /// An orthonormal frame `(t, b)` perpendicular to unit `n`.
    pub fn frame(n: DVec3) -> (DVec3, DVec3) {
        let t = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
        let t = (t - n * n.dot(t)).normalize();
        (t, n.cross(t))
    }

    /// `∫_{cap(axis, α)} f(ω) dω` for a scalar `f`, with `n` spiral points.
    pub fn integrate_cap(
        axis: DVec3,
        cos_alpha: f64,
        n: usize,
        mut f: impl FnMut(DVec3) -> f64,
    ) -> f64 {
        let (t, b) = frame(axis);
        let ga = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let w = 2.0 * std::f64::consts::PI * (1.0 - cos_alpha) / n as f64;
        let mut s = 0.0;
        for i in 0..n {
            let z = 1.0 - (1.0 - cos_alpha) * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let ph = ga * i as f64;
            let d = axis * z + t * (r * ph.cos()) + b * (r * ph.sin());
            s += f(d);
        }
        s * w
    }

    /// SH projection `∫_{cap} L(ω) Y_lm(ω) dω` of a scalar radiance `L` that is zero
    /// outside the cap (directions where `radiance` returns 0 contribute nothing).
    pub fn project_cap(
        order: usize,
        axis: DVec3,
        cos_alpha: f64,
        n: usize,
        radiance: impl Fn(DVec3) -> f64,
    ) -> Vec<f64> {
        let (t, b) = frame(axis);
        let ga = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let w = 2.0 * std::f64::consts::PI * (1.0 - cos_alpha) / n as f64;
        let mut out = vec![0.0; num_coeffs(order)];
        let mut y = [0.0f64; MAX_COEFFS];
        for i in 0..n {
            let z = 1.0 - (1.0 - cos_alpha) * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let ph = ga * i as f64;
            let d = axis * z + t * (r * ph.cos()) + b * (r * ph.sin());
            let l = radiance(d);
            if l != 0.0 {
                eval_basis_f64(order, d, &mut y);
                for (o, yi) in out.iter_mut().zip(y.iter()) {
                    *o += l * yi * w;
                }
            }
        }
        out
    }

    /// Largest `|a_i − b_i|` over all coefficients, divided by `|b_0|`.
    pub fn rel_err(a: &[f64], b: &[f64]) -> f64 {
        let m = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f64, f64::max);
        m / b[0].abs()
    }
}

#[cfg(test)]
mod tests {
    use super::testutil::*;
    use super::*;
    use glam::DVec3;

    fn chan(out: &[Vec3], ch: usize) -> Vec<f64> {
        out.iter().map(|v| v[ch] as f64).collect()
    }

    /// Cap factors against the explicit A1 list of *Irradiance Rigs* (l = 0..5,
    /// written in r and d), an independent algebraic form.
    #[test]
    fn cap_factors_match_irradiance_rigs_a1() {
        for &(r, d) in &[(0.1f64, 1.0f64), (0.5, 1.3), (1.0, 1.05), (0.001, 3.0)] {
            let s2 = r * r / (d * d);
            let c = (1.0 - s2).sqrt();
            let (r2, r4) = (r * r, r.powi(4));
            let (d2, d4, d6) = (d * d, d.powi(4), d.powi(6));
            let a1 = [
                2.0 * PI * (1.0 - c),
                PI * r2 / d2,
                PI * r2 * c / d2,
                PI * r2 / d2 - 5.0 * PI * r4 / (4.0 * d4),
                PI * r2 * (4.0 * d2 - 7.0 * r2) * c / (4.0 * d4),
                PI * r2 * (8.0 * d4 - 28.0 * d2 * r2 + 21.0 * r4) / (8.0 * d6),
            ];
            let got = cap_band_factors(6, c, s2);
            for l in 0..6 {
                assert!(
                    (got[l] - a1[l]).abs() <= 1e-9 * a1[0],
                    "r={r} d={d} l={l}: {} vs A1 {}",
                    got[l],
                    a1[l]
                );
            }
        }
    }

    /// Cone SH against brute-force projection over the cap, several axes, angles and orders.
    #[test]
    fn cone_matches_brute_force() {
        let radiance = Vec3::new(1.0, 2.0, 0.5);
        for &(alpha, order) in &[(0.05f32, 3usize), (0.4, 5), (1.2, 8), (2.5, 4)] {
            let axis = Vec3::new(0.3, -0.7, 0.5).normalize();
            let mut out = vec![Vec3::ZERO; num_coeffs(order)];
            cone_sh(order, axis, alpha, radiance, &mut out);
            let reference = project_cap(
                order,
                axis.as_dvec3(),
                (alpha as f64).cos(),
                200_000,
                |_| 1.0,
            );
            for ch in 0..3 {
                let r: Vec<f64> = reference.iter().map(|v| v * radiance[ch] as f64).collect();
                let e = rel_err(&chan(&out, ch), &r);
                assert!(e < 1e-4, "alpha {alpha} order {order} ch {ch}: rel err {e}");
            }
        }
        // Whole sphere: only band 0, 4π·L·Y00.
        let mut out = vec![Vec3::ZERO; 9];
        cone_sh(3, Vec3::Y, std::f32::consts::PI, Vec3::ONE, &mut out);
        assert!((out[0].x - (4.0 * std::f32::consts::PI * crate::basis::Y00)).abs() < 1e-5);
        assert!(out[1..].iter().all(|c| c.abs().max_element() < 1e-6));
    }

    /// A delta is the limit of a tiny cap with the same irradiance: project a
    /// 0.2° cap of radiance E/Ω by brute force and compare with the delta formula.
    #[test]
    fn point_and_directional_match_tiny_cap() {
        let order = 5;
        let alpha = 0.2f64.to_radians();
        let omega = 2.0 * PI * (1.0 - alpha.cos());
        let p = Vec3::new(0.5, 1.0, -2.0);
        let light = Vec3::new(2.0, 3.0, 1.0);
        let i = Vec3::new(10.0, 20.0, 5.0);
        let mut out = vec![Vec3::ZERO; 25];
        point_sh(order, p, light, i, &mut out);
        let w = (light - p).as_dvec3();
        let e = 20.0 / w.length_squared();
        let reference = project_cap(order, w.normalize(), alpha.cos(), 20_000, |_| e / omega);
        let err = rel_err(&chan(&out, 1), &reference);
        assert!(err < 1e-4, "point: {err}");

        let dir = Vec3::new(-0.2, 0.9, 0.3);
        directional_sh(order, dir, Vec3::splat(3.0), &mut out);
        let reference = project_cap(
            order,
            dir.as_dvec3().normalize(),
            alpha.cos(),
            20_000,
            |_| 3.0 / omega,
        );
        let err = rel_err(&chan(&out, 0), &reference);
        assert!(err < 1e-4, "directional: {err}");

        // Degenerate input gives zeros, not NaN or a panic.
        point_sh(order, p, p, i, &mut out);
        assert!(out.iter().all(|c| *c == Vec3::ZERO));
        directional_sh(order, Vec3::ZERO, i, &mut out);
        assert!(out.iter().all(|c| *c == Vec3::ZERO));
    }

    /// The spot is a point light scaled by the glTF curve: full inside the inner
    /// cone, zero outside the outer cone, (½)² halfway in cos between them, and
    /// monotonic in between.
    #[test]
    fn spot_follows_gltf_falloff() {
        let light = Vec3::new(0.0, 4.0, 0.0);
        let axis = -Vec3::Y;
        let i = Vec3::new(5.0, 5.0, 5.0);
        let (inner, outer) = (20.0f32, 40.0f32);
        let mut spot = vec![Vec3::ZERO; 9];
        let mut point = vec![Vec3::ZERO; 9];
        let at_angle = |deg: f32| light + Vec3::new(deg.to_radians().tan() * 4.0, -4.0, 0.0);
        // Inside the inner cone.
        let p = at_angle(10.0);
        spot_sh(3, p, light, axis, inner, outer, i, &mut spot);
        point_sh(3, p, light, i, &mut point);
        for (a, b) in spot.iter().zip(&point) {
            assert!((*a - *b).length() < 1e-6);
        }
        // Outside the outer cone.
        spot_sh(3, at_angle(41.0), light, axis, inner, outer, i, &mut spot);
        assert!(spot.iter().all(|c| *c == Vec3::ZERO));
        // Halfway in cos: attenuation 0.25.
        let (ci, co) = (inner.to_radians().cos(), outer.to_radians().cos());
        let mid = ((ci + co) / 2.0).acos().to_degrees();
        let p = at_angle(mid);
        spot_sh(3, p, light, axis, inner, outer, i, &mut spot);
        point_sh(3, p, light, i, &mut point);
        assert!(
            (spot[0].x / point[0].x - 0.25).abs() < 1e-3,
            "{}",
            spot[0].x / point[0].x
        );
        // Monotonic decrease across the ramp.
        let mut last = f32::INFINITY;
        for k in 0..=20 {
            let deg = inner + (outer - inner) * k as f32 / 20.0;
            let a = spot_attenuation(
                deg.to_radians().cos(),
                inner.to_radians(),
                outer.to_radians(),
            );
            assert!(a <= last + 1e-6 && (0.0..=1.0).contains(&a));
            last = a;
        }
    }

    /// Sanity of the brute-force helper itself: the cap quadrature gives the
    /// cap's solid angle for f = 1.
    #[test]
    fn cap_quadrature_solid_angle() {
        let s = integrate_cap(DVec3::Z, 0.5, 1000, |_| 1.0);
        assert!((s - PI).abs() < 1e-12);
    }
}
