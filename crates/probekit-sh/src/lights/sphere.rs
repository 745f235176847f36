//! Spherical area lights: zonal coefficients (Yuan, Nowrouzezahrai & Sloan,
//! *Irradiance Rigs*, JGT 2011, appendix A1), their full spatial gradient
//! (A2 along the light direction plus the lateral terms from the moving
//! lobe axis), and the exact horizon-clipped irradiance.
//!
//! A sphere of radius `r` and radiant intensity `I` (W/sr, the same in every
//! direction) has uniform radiance `L = I/(π r²)`. Seen from a point at
//! distance `d > r` from its centre it covers a cap of half-angle
//! `α = asin(r/d)` about `a = (center − p)/d`, so
//! `c_lm = L·A_l(α)·Y_lm(a)` (cap factors in [`crate::lights`]).
//! Writing `s = r/d`, `c = cos α = sqrt(1 − s²)` and `A_l = s²·B_l(c)` with
//! `B_0 = 2π/(1 + c)`, `B_l = 2π P_l'(c)/(l(l+1))`, this is
//! `c_lm = I/(π d²) · B_l(c) · Y_lm(a)`: no division by `r`, so `r → 0` is
//! exactly the point light `I/d²`.
//!
//! **Inside the sphere** (`d ≤ r`) the receiver is taken to see the sphere's
//! radiance in every direction: `c_00 = 4π·L·Y_00`, all other coefficients
//! and the gradient zero. This is discontinuous at the surface, where the
//! outside formula gives a hemisphere (`A_0 = 2π`).
//!
//! **Gradient.** With `F_l(d) = L·A_l(α(d))`, `c_lm(p) = F_l(d)·Y_lm(a)`,
//! `∂d/∂p = −a` and `∂a/∂p = −(I − a aᵀ)/d`:
//!
//! `∇_p c_lm = −F_l'(d)·Y_lm(a)·a − (F_l(d)/d)·∇_S Y_lm(a)`,
//!
//! where `∇_S` is the surface gradient of the basis
//! ([`super::eval_basis_tangent_gradient`]) and, since `dA_l/dc = −2π P_l(c)`
//! and `dc/dd = s²/(d c)`, `F_l'(d) = −2 I P_l(c)/(d³ c)`. The first term is the
//! paper's A2 (which lists `−F_l'/L` for `l = 0..5`); the second is the lateral
//! part the paper computes with forward differences. `F_l'` grows as `1/c`
//! when `p` approaches the surface (`c → 0`).

use super::{basis_fast, cap_band_factors, check_order, eval_basis_tangent_gradient, zero};
use crate::basis::{num_coeffs, MAX_COEFFS, MAX_ORDER, Y00};
#[cfg(not(feature = "std"))]
use crate::math::FloatMath;
use alloc::vec;
use alloc::vec::Vec;
use core::f64::consts::PI;
use glam::{DVec3, Vec3};

/// Zonal-harmonic coefficients (this crate's convention: coefficient of
/// `Y_l0` about the light axis, as taken by [`crate::zonal::zh_to_sh`]) of a
/// sphere light of uniform `radiance` `L`, radius `radius`, centre at
/// `distance` from the receiver: `z_l = sqrt((2l+1)/(4π))·L·A_l` with the
/// closed-form cap factors `A_l` of *Irradiance Rigs* appendix A1 (generalised
/// to any band by Legendre integrals; see [`crate::lights`]).
///
/// Returns `order` coefficients. A non-positive or non-finite radius gives
/// zeros; `distance ≤ radius` (inside) gives the full sphere, `z_0 = √(4π)·L`.
///
/// # Panics
/// If `order` is not in `1..=MAX_ORDER`.
pub fn sphere_light_zh(order: usize, radius: f32, distance: f32, radiance: f32) -> Vec<f32> {
    check_order(order, num_coeffs(order));
    let mut z = vec![0.0f32; order];
    let (r, d) = (radius as f64, distance.abs() as f64);
    if !(r > 0.0 && r.is_finite() && d.is_finite()) {
        return z;
    }
    if d <= r {
        z[0] = ((4.0 * PI).sqrt() * radiance as f64) as f32;
        return z;
    }
    let s2 = (r / d).powi(2);
    let c = ((d - r) * (d + r)).sqrt() / d;
    let a = cap_band_factors(order, c, s2);
    for (l, zl) in z.iter_mut().enumerate() {
        *zl = (((2 * l + 1) as f64 / (4.0 * PI)).sqrt() * radiance as f64 * a[l]) as f32;
    }
    z
}

/// What a receiver sees of a sphere light, in the factored form of the module docs.
enum View {
    /// Nothing (degenerate input).
    Nothing,
    /// Inside the sphere: constant radiance `L` (per channel) in every direction.
    Inside(Vec3),
    /// Outside: unit axis `a`, distance `d`, `F_l = I/(π d²)·B_l` and `F_l'(d)`.
    Outside {
        axis: Vec3,
        d: f32,
        f: [Vec3; MAX_ORDER],
        df: [Vec3; MAX_ORDER],
    },
}

fn view(order: usize, p: Vec3, center: Vec3, radius: f32, intensity: Vec3, grad: bool) -> View {
    let r = if radius.is_finite() && radius > 0.0 {
        radius as f64
    } else {
        0.0
    };
    let w = (center - p).as_dvec3();
    let d = w.length();
    if !d.is_finite() {
        return View::Nothing;
    }
    if d <= r {
        if r > 0.0 {
            return View::Inside(intensity / (core::f32::consts::PI * (r * r) as f32));
        }
        return View::Nothing; // p at a zero-radius light: undefined
    }
    let axis: DVec3 = w / d;
    let c = ((d - r) * (d + r)).sqrt() / d;
    let mut f = [Vec3::ZERO; MAX_ORDER];
    let mut df = [Vec3::ZERO; MAX_ORDER];
    if order <= 3 {
        // L1/L2 fast path, the same factors in closed form (P_1' = 1, P_2' = 3c):
        // F = I/d²·[2/(1+c), 1, c],  F' = −2I/d³·[1/c, 1, (3c² − 1)/(2c)].
        let inv_d2 = (1.0 / (d * d)) as f32;
        let cf = c as f32;
        f[0] = intensity * (2.0 * inv_d2 / (1.0 + cf));
        f[1] = intensity * inv_d2;
        f[2] = intensity * (inv_d2 * cf);
        if grad {
            let g = (-2.0 / (d * d * d)) as f32;
            df[0] = intensity * (g / cf);
            df[1] = intensity * g;
            df[2] = intensity * (g * (3.0 * cf * cf - 1.0) / (2.0 * cf));
        }
        return View::Outside {
            axis: axis.as_vec3(),
            d: d as f32,
            f,
            df,
        };
    }
    // B_l = A_l / sin²α: the cap factors with sin²α = 1 (c > 0 here).
    let b = cap_band_factors(order, c, 1.0);
    let k = 1.0 / (PI * d * d);
    for l in 0..order {
        f[l] = intensity * (k * b[l]) as f32;
    }
    if grad {
        // F_l'(d) = −2 I P_l(c) / (d³ c), Legendre values by Bonnet's recurrence.
        let g = -2.0 / (d * d * d * c);
        let (mut p0, mut p1) = (1.0f64, c);
        for (l, dfl) in df.iter_mut().enumerate().take(order) {
            let pl = match l {
                0 => 1.0,
                1 => c,
                _ => {
                    let p2 = ((2 * l - 1) as f64 * c * p1 - (l - 1) as f64 * p0) / l as f64;
                    p0 = p1;
                    p1 = p2;
                    p2
                }
            };
            *dfl = intensity * (g * pl) as f32;
        }
    }
    View::Outside {
        axis: axis.as_vec3(),
        d: d as f32,
        f,
        df,
    }
}

/// Radiance SH at `p` of a spherical light of radius `radius` centred at
/// `center` with radiant intensity `intensity` (W/sr per RGB channel; radiance
/// `I/(π r²)`), written to `out[..order²]`: the zonal coefficients of
/// *Irradiance Rigs* appendix A1 rotated to the light direction (module docs).
///
/// A radius of 0 (or negative / non-finite) is the point-light limit `I/d²`.
/// `p` inside the sphere (`|center − p| ≤ radius`) sees the full sphere of
/// radiance (band 0 only). `p` at the centre of a zero-radius light, or
/// non-finite positions, give zeros.
///
/// # Panics
/// If `order` is not in `1..=MAX_ORDER` or `out` is shorter than `order²`.
pub fn sphere_light_sh(
    order: usize,
    p: Vec3,
    center: Vec3,
    radius: f32,
    intensity: Vec3,
    out: &mut [Vec3],
) {
    check_order(order, out.len());
    match view(order, p, center, radius, intensity, false) {
        View::Nothing => zero(order, out),
        View::Inside(l) => {
            zero(order, out);
            out[0] = l * (4.0 * core::f32::consts::PI * Y00);
        }
        View::Outside { axis, f, .. } => {
            let mut b = [0.0f32; MAX_COEFFS];
            basis_fast(order, axis, &mut b);
            for (l, fl) in f.iter().enumerate().take(order) {
                for i in l * l..(l + 1) * (l + 1) {
                    out[i] = *fl * b[i];
                }
            }
        }
    }
}

/// [`sphere_light_sh`] together with its full spatial gradient with respect
/// to the receiver position `p`: `grad[i][j] = ∂c_i/∂p_j` (`j` = x, y, z; each an
/// RGB triple), for `i < order²`. Units: radiance per metre.
///
/// The gradient is analytic (module docs): the along-axis term is the
/// derivative of the A1 zonal coefficients with respect to distance
/// (*Irradiance Rigs* A2, for every band), the lateral terms differentiate the
/// rotation of the zonal lobe through the surface gradient of the basis.
/// Inside the sphere and for degenerate input the gradient is zero; a radius of
/// 0 gives the gradient of the point light [`super::point_sh`]. The
/// first-order model `c(p + δ) ≈ c(p) + Σ_j δ_j·grad[·][j]` is what the
/// gradient rig of *Irradiance Rigs* §2.1 stores.
///
/// # Panics
/// If `order` is not in `1..=MAX_ORDER` or a slice is shorter than `order²`.
pub fn sphere_light_sh_and_gradient(
    order: usize,
    p: Vec3,
    center: Vec3,
    radius: f32,
    intensity: Vec3,
    value: &mut [Vec3],
    grad: &mut [[Vec3; 3]],
) {
    check_order(order, value.len());
    check_order(order, grad.len());
    let n = num_coeffs(order);
    match view(order, p, center, radius, intensity, true) {
        View::Nothing => {
            zero(order, value);
            grad[..n].fill([Vec3::ZERO; 3]);
        }
        View::Inside(l) => {
            zero(order, value);
            value[0] = l * (4.0 * core::f32::consts::PI * Y00);
            grad[..n].fill([Vec3::ZERO; 3]);
        }
        View::Outside { axis, d, f, df } => {
            let mut y = [0.0f32; MAX_COEFFS];
            let mut gs = [Vec3::ZERO; MAX_COEFFS];
            eval_basis_tangent_gradient(order, axis, &mut y, &mut gs);
            for l in 0..order {
                let radial = -df[l];
                let lateral = -f[l] / d;
                for i in l * l..(l + 1) * (l + 1) {
                    value[i] = f[l] * y[i];
                    let ra = axis * y[i];
                    let g = gs[i];
                    grad[i] = [
                        radial * ra.x + lateral * g.x,
                        radial * ra.y + lateral * g.y,
                        radial * ra.z + lateral * g.z,
                    ];
                }
            }
        }
    }
}

/// The full spatial gradient of [`sphere_light_sh`] alone; see
/// [`sphere_light_sh_and_gradient`] for the layout (`out[i][j] = ∂c_i/∂p_j`)
/// and the method.
///
/// # Panics
/// If `order` is not in `1..=MAX_ORDER` or `out` is shorter than `order²`.
pub fn sphere_light_sh_gradient(
    order: usize,
    p: Vec3,
    center: Vec3,
    radius: f32,
    intensity: Vec3,
    out: &mut [[Vec3; 3]],
) {
    let mut value = [Vec3::ZERO; MAX_COEFFS];
    sphere_light_sh_and_gradient(order, p, center, radius, intensity, &mut value, out);
}

/// Exact irradiance `E = ∫_cap max(0, n·ω) dω` from a uniform spherical cap of
/// **unit radiance** with half-angle `α` (`sin_alpha = sin α = r/d` for a
/// sphere light), for a plane whose normal makes angle `θ` with the cap's
/// axis (`normal_cos = cos θ`), including the case where the horizon clips the
/// cap. Multiply by the radiance `L = I/(π r²)`; not divided by π (crate
/// convention).
///
/// - cap fully above the horizon (`cos²θ > sin²α`, `cos θ > 0`): `E = π sin²α cos θ`;
/// - fully below: `0`;
/// - partly hidden: with `x = cot α`, `y = −x cot θ`, `q = sin θ·sqrt(1 − y²)`,
///   `E = (cos θ·acos y − x·q)·sin²α + atan(q/x)`.
///
/// This is the differential-area-to-sphere form factor (Snyder, *Area Light
/// Sources for Real-Time Graphics*, MSR-TR-96-11, 1996; in the form of
/// Lagarde & de Rousiers, *Moving Frostbite to PBR*, SIGGRAPH 2014 course,
/// §4.7.2, eq. for `illuminanceSphereOrDisk`), times π. Arguments are clamped:
/// `normal_cos` to `[−1, 1]`, `sin_alpha` to `[0, 1]` (1 is a hemisphere; a
/// receiver inside a sphere light sees the whole sphere, `E = π`, which is not
/// a cap). Evaluated in f64. The rig code tabulates it over `(cos θ, r/d)`.
pub fn sphere_light_irradiance_horizon_clipped(normal_cos: f32, sin_alpha: f32) -> f32 {
    let ct = if normal_cos.is_nan() {
        0.0
    } else {
        (normal_cos as f64).clamp(-1.0, 1.0)
    };
    let s = if sin_alpha.is_nan() {
        0.0
    } else {
        (sin_alpha as f64).clamp(0.0, 1.0)
    };
    let s2 = s * s;
    if s2 == 0.0 {
        return 0.0;
    }
    if ct * ct >= s2 {
        return (PI * s2 * ct.max(0.0)) as f32;
    }
    let st = (1.0 - ct * ct).sqrt(); // > 0 because ct² < s² ≤ 1
    let x = (1.0 - s2).sqrt() / s; // cot α
    let y = (-x * ct / st).clamp(-1.0, 1.0);
    let q = st * (1.0 - y * y).sqrt();
    let e = (ct * y.acos() - x * q) * s2 + q.atan2(x);
    e.max(0.0) as f32
}

#[cfg(test)]
mod tests {
    use super::super::point_sh;
    use super::super::testutil::*;
    use super::*;
    use crate::convolve::irradiance;

    fn chan(out: &[Vec3], ch: usize) -> Vec<f64> {
        out.iter().map(|v| v[ch] as f64).collect()
    }

    /// The sphere light against brute-force projection of its radiance over the
    /// cap it subtends, and the ZH against the same.
    #[test]
    fn sphere_matches_brute_force() {
        let i = Vec3::new(3.0, 1.0, 0.25);
        let center = Vec3::new(0.4, 1.5, -0.7);
        for &(r, order, p) in &[
            (0.3f32, 3usize, Vec3::new(2.0, 0.0, 1.0)),
            (1.0, 5, Vec3::new(0.0, 0.0, 0.0)),
            (0.9, 8, Vec3::new(0.5, 2.4, -0.6)),
        ] {
            let mut out = vec![Vec3::ZERO; num_coeffs(order)];
            sphere_light_sh(order, p, center, r, i, &mut out);
            let w = (center - p).as_dvec3();
            let d = w.length();
            let ca = (1.0 - (r as f64 / d).powi(2)).sqrt();
            let l = 1.0 / (PI * (r as f64).powi(2));
            let reference = project_cap(order, w / d, ca, 200_000, |_| l);
            for ch in 0..3 {
                let rf: Vec<f64> = reference.iter().map(|v| v * i[ch] as f64).collect();
                let e = rel_err(&chan(&out, ch), &rf);
                assert!(e < 1e-4, "r {r} order {order} ch {ch}: {e}");
            }
            // ZH, rotated with the zonal module, reproduces the same SH.
            let zh = sphere_light_zh(order, r, d as f32, l as f32);
            let mut rot = vec![0.0f32; num_coeffs(order)];
            crate::zonal::zh_to_sh(&zh, (w / d).as_vec3(), &mut rot);
            let rot: Vec<f64> = rot.iter().map(|v| *v as f64).collect();
            assert!(rel_err(&rot, &reference) < 1e-4);
        }
    }

    /// Inside the sphere: the whole sphere at radiance L.
    #[test]
    fn inside_sees_full_sphere() {
        let mut out = vec![Vec3::ZERO; 9];
        let i = Vec3::splat(2.0);
        sphere_light_sh(3, Vec3::new(0.1, 0.0, 0.0), Vec3::ZERO, 0.5, i, &mut out);
        let l = 2.0 / (std::f32::consts::PI * 0.25);
        // Irradiance of a constant sky of radiance L is πL for any normal.
        let e = irradiance(&out, Vec3::new(0.0, 0.6, 0.8));
        assert!((e.x - std::f32::consts::PI * l).abs() < 1e-4 * e.x);
        assert!(out[1..].iter().all(|c| *c == Vec3::ZERO));
        let zh = sphere_light_zh(3, 0.5, 0.2, l);
        assert!((zh[0] - (4.0 * std::f32::consts::PI).sqrt() * l).abs() < 1e-4);
        assert_eq!(&zh[1..], &[0.0, 0.0]);
    }

    /// A tiny sphere far away is a point light with the same intensity; radius 0 is exactly one.
    #[test]
    fn point_light_limit() {
        let order = 4;
        let p = Vec3::new(0.0, 0.5, 0.0);
        let c = Vec3::new(6.0, 3.0, -8.0);
        let i = Vec3::new(100.0, 50.0, 10.0);
        let mut s = vec![Vec3::ZERO; 16];
        let mut q = vec![Vec3::ZERO; 16];
        point_sh(order, p, c, i, &mut q);
        sphere_light_sh(order, p, c, 0.01, i, &mut s);
        for (a, b) in s.iter().zip(&q) {
            assert!((*a - *b).length() < 1e-5 * q[0].length(), "{a} vs {b}");
        }
        sphere_light_sh(order, p, c, 0.0, i, &mut s);
        for (a, b) in s.iter().zip(&q) {
            assert!((*a - *b).length() < 1e-6 * q[0].length());
        }
        // Radius 0 also gives the point light's gradient: central differences of point_sh.
        let mut g = vec![[Vec3::ZERO; 3]; 16];
        sphere_light_sh_gradient(order, p, c, 0.0, i, &mut g);
        let h = 1e-2;
        let (mut a, mut b) = (vec![Vec3::ZERO; 16], vec![Vec3::ZERO; 16]);
        let gmax = g
            .iter()
            .flat_map(|x| x.iter().map(|v| v.abs().max_element()))
            .fold(0.0f32, f32::max);
        for (j, e) in [Vec3::X, Vec3::Y, Vec3::Z].into_iter().enumerate() {
            point_sh(order, p + e * h, c, i, &mut a);
            point_sh(order, p - e * h, c, i, &mut b);
            for k in 0..16 {
                let fd = (a[k] - b[k]) / (2.0 * h);
                assert!(
                    (fd - g[k][j]).abs().max_element() < 1e-3 * gmax,
                    "{k} {j}: {fd} vs {}",
                    g[k][j]
                );
            }
        }
    }

    /// Irradiance from the sphere light against brute-force cosine integration:
    /// the exact horizon-clipped function to 1e-5; SH irradiance within the
    /// truncation error of the clamped cosine (order 8: 2 %, L2: 5 % of `πL sin²α`).
    #[test]
    fn irradiance_matches_numerical_integration() {
        let center = Vec3::new(0.0, 0.0, 2.0);
        let (r, i) = (1.2f32, Vec3::splat(5.0));
        let p = Vec3::ZERO;
        let mut sh3 = vec![Vec3::ZERO; 9];
        let mut sh8 = vec![Vec3::ZERO; 64];
        sphere_light_sh(3, p, center, r, i, &mut sh3);
        sphere_light_sh(8, p, center, r, i, &mut sh8);
        let d = 2.0f64;
        let s = r as f64 / d;
        let ca = (1.0 - s * s).sqrt();
        let l = 5.0 / (PI * (r as f64).powi(2));
        for deg in [0.0f64, 20.0, 45.0, 70.0, 90.0, 110.0, 125.0, 140.0] {
            let th = deg.to_radians();
            let n = DVec3::new(th.sin(), 0.0, th.cos());
            let e_ref = l * integrate_cap(DVec3::Z, ca, 400_000, |w| n.dot(w).max(0.0));
            let e_exact =
                l * sphere_light_irradiance_horizon_clipped(th.cos() as f32, s as f32) as f64;
            let scale = PI * l * s * s;
            assert!(
                (e_exact - e_ref).abs() < 1e-5 * scale,
                "{deg}°: exact {e_exact} vs numerical {e_ref}"
            );
            let e8 = irradiance(&sh8, n.as_vec3()).x as f64;
            assert!(
                (e8 - e_ref).abs() < 0.02 * scale,
                "{deg}°: L7 {e8} vs {e_ref}"
            );
            // L2 keeps the clamped cosine only to band 2: a few per cent here.
            let e3 = irradiance(&sh3, n.as_vec3()).x as f64;
            assert!(
                (e3 - e_ref).abs() < 0.05 * scale,
                "{deg}°: L2 {e3} vs {e_ref}"
            );
        }
    }

    /// The horizon-clipped formula against numerical integration for many
    /// partly hidden caps (and the fully visible / hidden limits).
    #[test]
    fn horizon_clipped_matches_numerical() {
        for &s in &[0.05f64, 0.3, 0.6, 0.9, 0.99, 1.0] {
            let ca = (1.0 - s * s).sqrt();
            let a = s.asin();
            for k in 0..=12 {
                // θ from π/2 − α − 0.05 to π/2 + α + 0.05 (clipped span and both sides).
                let th = (PI / 2.0 - a - 0.05 + (2.0 * a + 0.1) * k as f64 / 12.0).clamp(0.0, PI);
                let n = DVec3::new(th.sin(), 0.0, th.cos());
                let e_ref = integrate_cap(DVec3::Z, ca, 300_000, |w| n.dot(w).max(0.0));
                let e = sphere_light_irradiance_horizon_clipped(th.cos() as f32, s as f32) as f64;
                assert!(
                    (e - e_ref).abs() < 2e-5 * (PI * s * s),
                    "s {s} θ {th}: {e} vs {e_ref}"
                );
            }
        }
        assert_eq!(sphere_light_irradiance_horizon_clipped(0.5, 0.0), 0.0);
        assert_eq!(
            sphere_light_irradiance_horizon_clipped(f32::NAN, 0.5),
            sphere_light_irradiance_horizon_clipped(0.0, 0.5)
        );
    }

    /// The along-axis derivative equals the explicit A2 list of *Irradiance Rigs*
    /// (l = 0..5): `∇c_lm · a = L·g_l·Y_lm(a)`.
    #[test]
    fn radial_gradient_matches_irradiance_rigs_a2() {
        let order = 6;
        let (r, i) = (0.7f32, Vec3::splat(2.0));
        let center = Vec3::new(1.0, 2.0, 3.0);
        let p = Vec3::new(0.2, 0.1, 0.3);
        let mut v = vec![Vec3::ZERO; 36];
        let mut g = vec![[Vec3::ZERO; 3]; 36];
        sphere_light_sh_and_gradient(order, p, center, r, i, &mut v, &mut g);
        let w = (center - p).as_dvec3();
        let d = w.length();
        let a = w / d;
        let rr = r as f64;
        let c = (1.0 - rr * rr / (d * d)).sqrt();
        let (r2, r4, r6) = (rr * rr, rr.powi(4), rr.powi(6));
        let (d2, d4) = (d * d, d.powi(4));
        let a2 = [
            2.0 * PI * r2 / (d.powi(3) * c),
            2.0 * PI * r2 / d.powi(3),
            (2.0 * d2 * PI * r2 - 3.0 * PI * r4) / (d.powi(5) * c),
            PI * (2.0 * d2 * r2 - 5.0 * r4) / d.powi(5),
            PI * (8.0 * d4 * r2 - 40.0 * d2 * r4 + 35.0 * r6) / (4.0 * d.powi(7) * c),
            PI * (8.0 * d4 * r2 - 56.0 * d2 * r4 + 63.0 * r6) / (4.0 * d.powi(7)),
        ];
        let l = 2.0 / (PI * r2);
        let mut y = [0.0f64; 64];
        crate::basis::eval_basis_f64(order, a, &mut y);
        let scale = l * a2[0] * y[0];
        for (band, g_band) in a2.iter().enumerate() {
            for idx in band * band..(band + 1) * (band + 1) {
                let along =
                    g[idx][0].x as f64 * a.x + g[idx][1].x as f64 * a.y + g[idx][2].x as f64 * a.z;
                // A2 is the derivative moving *towards* the light, i.e. along +a.
                let expect = l * g_band * y[idx];
                assert!(
                    (along - expect).abs() < 1e-4 * scale,
                    "l {band} i {idx}: {along} vs A2 {expect}"
                );
            }
        }
    }

    /// The whole gradient (along-axis and lateral) against central differences of
    /// `sphere_light_sh`, at several points near and far, for L2 and a higher order.
    #[test]
    fn full_gradient_matches_central_differences() {
        let (r, i) = (0.5f32, Vec3::new(4.0, 2.0, 1.0));
        let center = Vec3::new(0.3, 1.2, -0.4);
        let points = [
            Vec3::new(2.0, 0.5, 1.0),
            Vec3::new(0.3, 1.2, 0.35),  // 1.5 r from the centre
            Vec3::new(-3.0, -2.0, 4.0), // far
            Vec3::new(0.9, 1.9, -0.9),
        ];
        for order in [3usize, 6] {
            let n = num_coeffs(order);
            for p in points {
                let mut v = vec![Vec3::ZERO; n];
                let mut g = vec![[Vec3::ZERO; 3]; n];
                sphere_light_sh_and_gradient(order, p, center, r, i, &mut v, &mut g);
                let mut g2 = vec![[Vec3::ZERO; 3]; n];
                sphere_light_sh_gradient(order, p, center, r, i, &mut g2);
                assert_eq!(g, g2);
                let d = (center - p).length();
                let h = 2e-3 * (d - r);
                let gmax = g
                    .iter()
                    .flat_map(|c| c.iter().map(|v| v.abs().max_element()))
                    .fold(0.0f32, f32::max);
                let mut plus = vec![Vec3::ZERO; n];
                let mut minus = vec![Vec3::ZERO; n];
                for (j, e) in [Vec3::X, Vec3::Y, Vec3::Z].into_iter().enumerate() {
                    sphere_light_sh(order, p + e * h, center, r, i, &mut plus);
                    sphere_light_sh(order, p - e * h, center, r, i, &mut minus);
                    for k in 0..n {
                        let fd = (plus[k] - minus[k]) / (2.0 * h);
                        let diff = (fd - g[k][j]).abs().max_element();
                        assert!(
                            diff < 2e-3 * gmax,
                            "order {order} p {p} coeff {k} axis {j}: fd {fd} analytic {}",
                            g[k][j]
                        );
                    }
                }
            }
        }
        // Inside: zero gradient.
        let mut v = vec![Vec3::ZERO; 9];
        let mut g = vec![[Vec3::ZERO; 3]; 9];
        sphere_light_sh_and_gradient(3, center, center, r, i, &mut v, &mut g);
        assert!(g.iter().all(|c| *c == [Vec3::ZERO; 3]));
        assert!(v[0].x > 0.0);
    }

    fn dir(theta: f32, phi: f32) -> Vec3 {
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.cos(),
            theta.sin() * phi.sin(),
        )
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

        /// A uniform sphere's vector irradiance equals a point source's (Newton's
        /// shell theorem for 1/r² fields), so band 1 of the sphere light equals
        /// band 1 of the point light of the same intensity, for any radius < d.
        #[test]
        fn band1_is_the_point_lights(
            th in 0.0f32..std::f32::consts::PI, ph in 0.0f32..std::f32::consts::TAU, r in 0.01f32..2.0, k in 1.02f32..30.0,
        ) {
            let p = Vec3::new(0.3, -0.2, 1.0);
            let center = p + dir(th, ph) * (r * k);
            let i = Vec3::new(1.0, 2.0, 3.0);
            let mut s = [Vec3::ZERO; 9];
            let mut q = [Vec3::ZERO; 9];
            sphere_light_sh(3, p, center, r, i, &mut s);
            point_sh(3, p, center, i, &mut q);
            for idx in 1..4 {
                proptest::prop_assert!((s[idx] - q[idx]).length() <= 2e-5 * q[0].length());
            }
        }

        /// The whole gradient against central differences at random receivers.
        #[test]
        fn gradient_matches_central_differences_random(
            th in 0.0f32..std::f32::consts::PI, ph in 0.0f32..std::f32::consts::TAU, r in 0.05f32..1.0, k in 1.2f32..20.0,
        ) {
            let p = Vec3::new(-0.5, 0.7, 0.2);
            let center = p + dir(th, ph) * (r * k);
            let i = Vec3::new(3.0, 1.0, 2.0);
            let mut v = [Vec3::ZERO; 16];
            let mut g = [[Vec3::ZERO; 3]; 16];
            sphere_light_sh_and_gradient(4, p, center, r, i, &mut v, &mut g);
            let gmax = g.iter().flat_map(|c| c.iter().map(|x| x.abs().max_element())).fold(0.0f32, f32::max);
            let h = 2e-3 * r * (k - 1.0);
            let mut a = [Vec3::ZERO; 16];
            let mut b = [Vec3::ZERO; 16];
            for (j, e) in [Vec3::X, Vec3::Y, Vec3::Z].into_iter().enumerate() {
                sphere_light_sh(4, p + e * h, center, r, i, &mut a);
                sphere_light_sh(4, p - e * h, center, r, i, &mut b);
                for idx in 0..16 {
                    let fd = (a[idx] - b[idx]) / (2.0 * h);
                    proptest::prop_assert!((fd - g[idx][j]).abs().max_element() <= 3e-3 * gmax,
                        "coeff {} axis {}: fd {} analytic {}", idx, j, fd, g[idx][j]);
                }
            }
        }

        /// Horizon-clipped irradiance: non-decreasing in cos θ, between 0 and the
        /// bounded by `π sin²α`, at least `π sin²α cos θ`, and equal to `π sin²α` head-on.
        #[test]
        fn horizon_clipped_monotone_and_bounded(s in 0.001f32..1.0, c0 in -1.0f32..1.0, dc in 0.0f32..0.5) {
            let c1 = (c0 + dc).min(1.0);
            let e0 = sphere_light_irradiance_horizon_clipped(c0, s);
            let e1 = sphere_light_irradiance_horizon_clipped(c1, s);
            let top = std::f32::consts::PI * s * s;
            proptest::prop_assert!(e0 >= 0.0 && e1 <= top * (1.0 + 1e-5));
            proptest::prop_assert!(e1 >= e0 - 1e-6 * top);
            // Clipping only ever adds light compared with the linear cosine (the
            // hidden part would have counted negatively).
            proptest::prop_assert!(e0 >= top * c0 - 1e-6 * top);
            let head_on = sphere_light_irradiance_horizon_clipped(1.0, s);
            proptest::prop_assert!((head_on - top).abs() <= 1e-5 * top);
        }
    }
}
