//! The rig lights against closed forms written out here:
//!
//! * a sphere light entirely above the horizon gives exactly the irradiance
//!   of a point light of the same intensity, `I cos θ / d²` (Snyder 1996);
//!   far away, a disk too;
//! * a disk on the axis of the receiver: `E = π L r² / (r² + h²)`;
//! * the L2 SH of a delta light (point, directional), convolved with the
//!   clamped cosine, is `E (1/4 + t/2 + 5/32 (3t² − 1))`, `t` the cosine
//!   between normal and light (Σ_m Y_lm(a) Y_lm(b) = (2l+1)/4π P_l(a·b),
//!   Â = π, 2π/3, π/4), evaluated with the basis written out below;
//! * the sphere table against the closed form it tabulates.

mod common;

use common::Rng;
use glam::Vec3;
use probekit_runtime::rig::{Light, SphereTable};
use probekit_runtime::sh::lights::sphere_light_irradiance_horizon_clipped;
use std::f32::consts::PI;

/// Real SH of bands 0–2, index `l(l+1)+m`, Condon–Shortley phase.
fn basis(d: Vec3) -> [f32; 9] {
    let c0 = 0.5 * (1.0 / PI).sqrt();
    let c1 = (3.0 / (4.0 * PI)).sqrt();
    let c2 = 0.5 * (15.0 / PI).sqrt();
    let (x, y, z) = (d.x, d.y, d.z);
    [
        c0,
        -c1 * y,
        c1 * z,
        -c1 * x,
        c2 * x * y,
        -c2 * y * z,
        0.25 * (5.0 / PI).sqrt() * (3.0 * z * z - 1.0),
        -c2 * x * z,
        0.25 * (15.0 / PI).sqrt() * (x * x - y * y),
    ]
}

fn sh_irradiance(sh: &[Vec3], n: Vec3) -> Vec3 {
    let y = basis(n);
    let a = [PI, 2.0 * PI / 3.0, 2.0 * PI / 3.0, 2.0 * PI / 3.0];
    sh.iter()
        .enumerate()
        .map(|(k, &c)| c * y[k] * a.get(k).copied().unwrap_or(PI / 4.0))
        .sum()
}

fn unit(rng: &mut Rng) -> Vec3 {
    rng.vec3().normalize_or(Vec3::Y)
}

fn close(a: Vec3, b: Vec3, rel: f32) -> bool {
    (a - b).abs().max_element() <= rel * b.abs().max_element().max(1e-6)
}

#[test]
fn a_sphere_above_the_horizon_is_a_point_light() {
    let mut rng = Rng(1);
    let mut checked = 0;
    for _ in 0..500 {
        let p = rng.vec3() * 3.0;
        let n = unit(&mut rng);
        let centre = p + unit(&mut rng) * (1.0 + 4.0 * rng.f32().abs());
        let radius = 0.05 + 0.4 * rng.f32().abs();
        let intensity = Vec3::new(2.0, 1.0, 0.5);
        let w = centre - p;
        let (d, ct) = (w.length(), n.dot(w.normalize()));
        if ct <= radius / d + 1e-3 {
            continue; // Partly or wholly below the horizon.
        }
        let sphere = Light::Sphere {
            position: centre,
            radius,
            intensity,
        };
        let want = intensity * ct / (d * d);
        assert!(close(sphere.irradiance(p, n, None), want, 1e-4), "{p} {n}");
        let point = Light::Point {
            position: centre,
            intensity,
        };
        assert!(close(point.irradiance(p, n, None), want, 1e-5));
        checked += 1;
    }
    assert!(checked > 100, "{checked}");
}

#[test]
fn a_disk_on_the_axis_has_the_closed_form() {
    for (r, h) in [(0.5f32, 1.0f32), (1.0, 0.3), (0.2, 4.0)] {
        let intensity = Vec3::splat(3.0);
        let disk = Light::Disk {
            position: Vec3::new(0.0, h, 0.0),
            direction: -Vec3::Y,
            radius: r,
            intensity,
        };
        let l = intensity / (PI * r * r);
        let want = l * (PI * r * r / (r * r + h * h));
        let got = disk.irradiance(Vec3::ZERO, Vec3::Y, None);
        assert!(close(got, want, 2e-3), "r {r} h {h}: {got} {want}");
        // Behind the disk: nothing.
        assert_eq!(
            disk.irradiance(Vec3::new(0.0, 2.0 * h, 0.0), -Vec3::Y, None),
            Vec3::ZERO
        );
    }
}

#[test]
fn delta_lights_sh_convolve_to_the_clamped_cosine_series() {
    let mut rng = Rng(3);
    for _ in 0..100 {
        let p = rng.vec3() * 2.0;
        let n = unit(&mut rng);
        let to_light = unit(&mut rng);
        let d = 0.5 + 3.0 * rng.f32().abs();
        let intensity = Vec3::new(1.0, 2.0, 0.25);
        let t = n.dot(to_light);
        let series = 0.25 + 0.5 * t + 5.0 / 32.0 * (3.0 * t * t - 1.0);
        for (light, e) in [
            (
                Light::Point {
                    position: p + to_light * d,
                    intensity,
                },
                intensity / (d * d),
            ),
            (
                Light::Directional {
                    direction: -to_light,
                    irradiance: intensity,
                },
                intensity,
            ),
        ] {
            let mut sh = [Vec3::ZERO; 9];
            light.add_sh(3, p, 2.0, &mut sh);
            let got = sh_irradiance(&sh, n);
            assert!(close(got, e * (2.0 * series), 1e-4), "{light:?}: {got}");
        }
    }
}

#[test]
fn the_sphere_table_follows_its_closed_form() {
    let table = SphereTable::default();
    let mut rng = Rng(5);
    for _ in 0..2000 {
        let ct = rng.f32();
        let s = rng.f32().abs() * 0.95;
        let want = sphere_light_irradiance_horizon_clipped(ct, s);
        let got = table.lookup(ct, s);
        assert!((got - want).abs() <= 2e-3 * PI, "{ct} {s}: {got} {want}");
    }
    // Out of range and NaN arguments are clamped, not a panic.
    for (c, s) in [(f32::NAN, 0.5), (2.0, -1.0), (-5.0, f32::INFINITY)] {
        assert!(table.lookup(c, s).is_finite());
    }
}

#[test]
fn bad_sh_requests_write_nothing() {
    let light = Light::Point {
        position: Vec3::X,
        intensity: Vec3::ONE,
    };
    let mut short = [Vec3::ZERO; 3];
    light.add_sh(2, Vec3::ZERO, 1.0, &mut short);
    light.add_sh(0, Vec3::ZERO, 1.0, &mut short);
    let mut big = vec![Vec3::ZERO; 100];
    light.add_sh(9, Vec3::ZERO, 1.0, &mut big);
    assert!(short.iter().chain(&big).all(|c| *c == Vec3::ZERO));
}

/// The transition distance against a table whose `g` is computed here
/// from the point light's closed form (`E_near(x) = I/((x − 1)R)²`), a
/// linear scan for the bracket and interpolation in it.
#[test]
fn transition_distances_follow_the_table() {
    use probekit_runtime::format::Transition;
    use probekit_runtime::rig::{rig_weight, transition_distance, TRANSITION_BAND};
    let (center, radius) = (Vec3::new(0.5, 1.0, -0.5), 0.8f32);
    let distances: Vec<f32> = (0..16).map(|i| 1.1 * 1.3f32.powi(i)).collect();
    let table: Vec<Transition> = distances
        .iter()
        .map(|&x| Transition {
            distance: x,
            error: 40.0 / x,
        })
        .collect();
    let intensity = 2.0f32;
    let white = 0.05f32;
    let dir = Vec3::new(1.0, 2.0, -0.5).normalize();
    let light = Light::Point {
        position: center + dir * 5.0,
        intensity: Vec3::new(intensity, 0.5, 0.1),
    };
    let g = |t: &Transition| {
        let d = (t.distance - 1.0) * radius;
        t.error * (intensity / (d * d)) / PI / white
    };
    for target in [0.5f32, 1.0, 3.0, 20.0, 1e-6, 1e9] {
        let got = transition_distance(&table, &light, center, radius, white, target);
        let gs: Vec<f32> = table.iter().map(g).collect();
        let want = if gs[0] <= target {
            distances[0]
        } else if *gs.last().unwrap() > target {
            *distances.last().unwrap()
        } else {
            let i = gs.iter().position(|&v| v <= target).unwrap();
            let (g0, g1) = (gs[i - 1], gs[i]);
            distances[i - 1] + (g0 - target) / (g0 - g1) * (distances[i] - distances[i - 1])
        };
        assert!(
            (got - want).abs() <= 1e-4 * want,
            "target {target}: {got} {want}"
        );
    }
    // A directional light and an empty table: always the rig.
    let sun = Light::Directional {
        direction: -Vec3::Y,
        irradiance: Vec3::ONE,
    };
    assert_eq!(
        transition_distance(&table, &sun, center, radius, white, 1.0),
        0.0
    );
    assert_eq!(
        transition_distance(&[], &light, center, radius, white, 1.0),
        0.0
    );
    assert_eq!(rig_weight(f32::INFINITY, 0.0), 1.0);
    // The cross-fade.
    let xs = 2.0;
    assert_eq!(rig_weight(1.9, xs), 0.0);
    assert_eq!(rig_weight(xs, xs), 0.0);
    assert!((rig_weight(xs * (1.0 + TRANSITION_BAND) / 2.0, xs) - 0.5).abs() < 1e-6);
    assert_eq!(rig_weight(xs * TRANSITION_BAND, xs), 1.0);
    // Degenerate input is an answer, not a panic.
    let _ = transition_distance(&table, &light, center, 0.0, 0.0, f32::NAN);
}
