//! The light sets of rig scenes: the built-in demo and cost-test lights,
//! and a loaded scene's analytic lights as rig lights with warnings for
//! what a rig does not model. The lights themselves and their evaluation
//! are [`crate::lights`].

use crate::lights::{from_scene_light, Light};
use crate::scene::Scene;
use glam::Vec3;

/// `builtin:rig-demo`: eight sphere lights placed around an object near the
/// origin, at a spread of distances (1.5–9 m from the origin), heights,
/// sizes and colours, none aimed at any particular rig. Positions are
/// world coordinates; use `--at` to move the object among them.
pub fn rig_demo_lights() -> Vec<Light> {
    let s = |p: [f32; 3], r: f32, c: [f32; 3], i: f32| Light::Sphere {
        position: Vec3::from(p),
        radius: r,
        intensity: Vec3::from(c) * i,
    };
    vec![
        // A warm key light, high and to the front right.
        s([4.0, 5.0, 3.0], 0.5, [1.0, 0.9, 0.75], 60.0),
        // A cool fill far to the left.
        s([-8.0, 3.0, -2.0], 1.0, [0.6, 0.7, 1.0], 90.0),
        // A lamp post near the rear, across the width.
        s([-2.5, 2.6, 2.2], 0.15, [1.0, 0.8, 0.5], 8.0),
        // A small bright light low beside the front wheel.
        s([2.6, 0.5, -1.6], 0.1, [1.0, 0.3, 0.2], 2.5),
        // Overhead, above the cabin.
        s([0.5, 4.0, -0.3], 0.3, [0.9, 1.0, 0.9], 12.0),
        // Far behind, low.
        s([-2.0, 1.0, -9.0], 0.6, [0.8, 0.8, 1.0], 50.0),
        // Sideways, mid distance, at the width axis.
        s([0.0, 1.2, 4.0], 0.25, [1.0, 1.0, 1.0], 10.0),
        // Ahead, far.
        s([9.0, 2.0, 1.0], 0.8, [1.0, 0.95, 0.9], 70.0),
    ]
}

/// A scene like the paper's demo (Yuan, Nowrouzezahrai & Sloan 2011, §4): a 6 × 3 × 6 m room around an
/// object at the origin with 4 primary sphere lights, 8 small bright sphere
/// lights and 192 disk lights on the walls and floor (red left wall, green
/// right wall) standing in for bounced light.
pub fn paper_cost_lights() -> Vec<Light> {
    let mut v = Vec::new();
    for (k, p) in [
        [2.0, 2.6, 2.0],
        [-2.0, 2.6, 2.0],
        [2.0, 2.6, -2.0],
        [-2.0, 2.6, -2.0],
    ]
    .iter()
    .enumerate()
    {
        v.push(Light::Sphere {
            position: Vec3::from(*p),
            radius: 0.2,
            intensity: Vec3::splat(15.0 + k as f32),
        });
    }
    for k in 0..8 {
        let a = std::f32::consts::TAU * k as f32 / 8.0;
        v.push(Light::Sphere {
            position: Vec3::new(1.2 * a.cos(), 0.4 + 0.18 * k as f32, 1.2 * a.sin()),
            radius: 0.03,
            intensity: Vec3::new(1.0, 0.7, 0.4) * 1.5,
        });
    }
    // 192 disks: 48 on the floor, 36 on each of the four walls.
    let disk = |p: Vec3, d: Vec3, c: Vec3| Light::Disk {
        position: p,
        direction: d,
        radius: 0.25,
        intensity: c * 0.4,
    };
    for i in 0..8 {
        for j in 0..6 {
            let p = Vec3::new(
                -2.6 + 5.2 * i as f32 / 7.0,
                0.0,
                -2.5 + 5.0 * j as f32 / 5.0,
            );
            v.push(disk(p, Vec3::Y, Vec3::splat(0.8)));
        }
    }
    for (axis, sign, colour) in [
        (0usize, -1.0f32, Vec3::new(0.9, 0.2, 0.2)),
        (0, 1.0, Vec3::new(0.2, 0.9, 0.2)),
        (2, -1.0, Vec3::splat(0.8)),
        (2, 1.0, Vec3::splat(0.8)),
    ] {
        for i in 0..9 {
            for j in 0..4 {
                let mut p = Vec3::new(0.0, 0.3 + 2.4 * j as f32 / 3.0, 0.0);
                let t = -2.6 + 5.2 * i as f32 / 8.0;
                p[axis] = 3.0 * sign;
                p[2 - axis] = t;
                let mut d = Vec3::ZERO;
                d[axis] = -sign;
                v.push(disk(p, d, colour));
            }
        }
    }
    v
}

/// The lights of a loaded scene as rig lights, with what was left out.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneLights {
    /// The converted analytic lights, in scene order.
    pub lights: Vec<Light>,
    /// One line per thing the rig does not model (emissive triangles, the
    /// environment, degenerate lights), for the caller to print.
    pub warnings: Vec<String>,
    /// The scene's lighting hash ([`Scene::lighting_hash_hex`]) when the
    /// lights came from a loaded scene (not a built-in light set), to check
    /// a probe file against.
    pub lighting_hash: Option<String>,
}

/// All analytic lights of `scene` as rig lights ([`from_scene_light`]).
/// Emissive triangles and the environment are not rig lights: they are
/// left out with a warning each (bake them into a probe file and pass it
/// as a [`super::source::ProbeSource`] instead).
pub fn lights_from_scene(scene: &Scene) -> SceneLights {
    let name = scene.source.display();
    let mut out = SceneLights {
        lighting_hash: Some(scene.lighting_hash_hex()),
        ..SceneLights::default()
    };
    for (i, l) in scene.lights.iter().enumerate() {
        match from_scene_light(l) {
            Some(r) => out.lights.push(r),
            None => out.warnings.push(format!(
                "{name}: light {i} ({:?}) has radius ≤ 0; ignored",
                l.kind
            )),
        }
    }
    if !scene.emissive_triangles.is_empty() {
        out.warnings.push(format!(
            "{name}: {} emissive triangle(s) ignored (rigs take analytic lights and baked probes)",
            scene.emissive_triangles.len()
        ));
    }
    let env = &scene.environment;
    if env.map.is_some() || (env.color * env.intensity).max_element() > 0.0 {
        out.warnings.push(format!(
            "{name}: environment ignored (rigs take analytic lights and baked probes)"
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::LightKind;

    /// Legendre coefficients `a_l = (2l+1)/2 ∫₋₁¹ max(0,t) P_l(t) dt` of the
    /// clamped cosine for l = 0, 1, 2, by a midpoint rule (independent of
    /// the SH code): the L2 irradiance of a delta light of irradiance E is
    /// `E·Σ a_l P_l(n·l)` (addition theorem).
    fn clamped_cosine_legendre() -> [f64; 3] {
        let m = 200_000;
        let p = |l: usize, x: f64| match l {
            0 => 1.0,
            1 => x,
            _ => 0.5 * (3.0 * x * x - 1.0),
        };
        std::array::from_fn(|l| {
            let mut acc = 0.0;
            for i in 0..m {
                let x = -1.0 + 2.0 * (i as f64 + 0.5) / m as f64;
                acc += x.max(0.0) * p(l, x);
            }
            (2 * l + 1) as f64 / 2.0 * acc * 2.0 / m as f64
        })
    }

    /// A directional light through any rig gives, at
    /// every vertex, the L2 irradiance of a delta, `E·Σ a_l P_l(n·l)` with
    /// the clamped cosine's Legendre coefficients integrated numerically
    /// here; its exact irradiance is `E·max(0, n·l)`; it is always in the
    /// rig zone; and a directional-only scene's rig error is exactly the L2
    /// truncation error (computed here from the two formulas).
    #[test]
    fn directional_light_rig_is_l2_truncation_only() {
        let dir = Vec3::new(0.3, -1.0, 0.45).normalize();
        let e = Vec3::new(2.0, 1.5, 1.0);
        let sun = Light::Directional {
            direction: dir,
            irradiance: e,
        };
        assert_eq!(sun.position(), None);
        let car = crate::rig::mesh::car();
        let at = Vec3::new(3.0, 0.0, -1.0);
        let a = clamped_cosine_legendre();
        let l2 = |t: f64| a[0] + a[1] * t + a[2] * 0.5 * (3.0 * t * t - 1.0);
        let mut want = Vec::new();
        let mut exact = Vec::new();
        for n in &car.normals {
            let t = n.dot(-dir) as f64;
            want.push(e * l2(t) as f32);
            exact.push(e * t.max(0.0) as f32);
            assert_eq!(
                sun.irradiance(Vec3::ZERO, *n, None),
                e * n.dot(-dir).max(0.0)
            );
        }
        for spec in ["constant", "gradient", "mixed:l3,g,c"] {
            let cfg = crate::rig::run::RunConfig {
                spec: spec.parse().unwrap(),
                at,
                samples: 64,
                ..Default::default()
            };
            let r = crate::rig::run::run(&car, "car", &[sun], None, &cfg, false).unwrap();
            assert_eq!(r.zone_counts(), (0, 0, 1), "{spec}");
            for (i, (got, w)) in r.approx.iter().zip(&want).enumerate() {
                assert!(
                    (*got - *w).abs().max_element() < 1e-4 * e.x,
                    "{spec} vertex {i}: {got} vs {w}"
                );
            }
            for (x, w) in r.exact.iter().zip(&exact) {
                assert!((*x - *w).abs().max_element() < 1e-6);
            }
            let trunc = crate::rig::split::error_stats(&want, &exact, None);
            assert!(
                (r.stats.rel_rmse - trunc.rel_rmse).abs() < 1e-4,
                "{spec}: {:?} vs truncation {:?}",
                r.stats,
                trunc
            );
            assert!(r.stats_vs_sh.rel_rmse < 1e-5, "{:?}", r.stats_vs_sh);
        }
    }

    /// Scene lights convert kind by kind (intensity × colour, angles in
    /// degrees); the demo's sun becomes a directional light and its sky a
    /// warning.
    #[test]
    fn scene_lights_convert() {
        let s = crate::scene::Scene::builtin_demo();
        let l = lights_from_scene(&s);
        assert_eq!(l.lights.len(), s.lights.len());
        assert!(l
            .lights
            .iter()
            .any(|x| matches!(x, Light::Directional { .. })));
        assert!(l.lights.iter().any(|x| matches!(x, Light::Sphere { .. })));
        assert!(
            l.warnings.iter().any(|w| w.contains("environment")),
            "{:?}",
            l.warnings
        );
        let spot = crate::scene::Light {
            kind: LightKind::Spot,
            position: Vec3::ONE,
            direction: Vec3::NEG_Y,
            color: Vec3::new(1.0, 0.5, 0.25),
            intensity: 8.0,
            radius: 0.0,
            inner_angle: 0.25,
            outer_angle: 0.5,
            group: None,
            mode: crate::scene::LightMode::Auto,
            angular_diameter: 0.0,
        };
        let Some(Light::Spot {
            inner_deg,
            outer_deg,
            intensity,
            ..
        }) = from_scene_light(&spot)
        else {
            panic!("spot expected")
        };
        assert!((inner_deg - 0.25f32.to_degrees()).abs() < 1e-5);
        assert!((outer_deg - 0.5f32.to_degrees()).abs() < 1e-5);
        assert_eq!(intensity, Vec3::new(8.0, 4.0, 2.0));
        let bad = crate::scene::Light {
            kind: LightKind::Sphere,
            ..spot
        };
        assert_eq!(from_scene_light(&bad), None);
    }
}
