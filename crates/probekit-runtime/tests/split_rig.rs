//! The rig with the near/transition/rig split at run time, against closed
//! forms and a symmetry:
//!
//! * near lights are evaluated exactly: a point light near the object adds
//!   `I·max(0, n·ω)/d²`, and a directional light (always in the rig, whose
//!   gradient model reproduces its constant SH exactly) adds the L2
//!   clamped-cosine series `E (1/4 + t/2 + 5/32 (3t² − 1))`;
//! * moving and rotating the object and its lights together changes no
//!   vertex's irradiance (in the object's frame);
//! * bad transforms and rig indices are typed errors.

mod common;

use common::Rng;
use glam::{Affine3A, Quat, Vec3};
use probekit_runtime::format::{Rig, RigModel, Transition};
use probekit_runtime::rig::{rig_weights, Light, RigError, SphereTable, SplitRig, MAX_WEIGHTS};
use std::sync::Arc;

const ORDER: u32 = 3;

/// A gradient rig over [−1, 1]³ with seven samples (centre and ±axes), its
/// fitting matrix the least-squares pseudo-inverse of the design matrix
/// (normal equations solved here), and a falling transition table.
fn rig() -> Rig {
    let (lo, hi) = (Vec3::splat(-1.0), Vec3::ONE);
    let samples = vec![
        Vec3::ZERO,
        Vec3::X * 0.8,
        -Vec3::X * 0.8,
        Vec3::Y * 0.8,
        -Vec3::Y * 0.8,
        Vec3::Z * 0.8,
        -Vec3::Z * 0.8,
    ];
    let n = samples.len();
    let mut d = vec![[0.0f64; 4]; n];
    for (row, &s) in d.iter_mut().zip(&samples) {
        let mut w = [(0u32, 0.0f32); MAX_WEIGHTS];
        let m = rig_weights(RigModel::Gradient, lo, hi, s, &mut w);
        for &(k, wk) in &w[..m] {
            row[k as usize] += wk as f64;
        }
    }
    // (DᵀD)⁻¹ Dᵀ by Gauss–Jordan on [DᵀD | Dᵀ].
    let mut a = vec![vec![0.0f64; 4 + n]; 4];
    for i in 0..4 {
        for j in 0..4 {
            a[i][j] = (0..n).map(|r| d[r][i] * d[r][j]).sum();
        }
        for r in 0..n {
            a[i][4 + r] = d[r][i];
        }
    }
    for c in 0..4 {
        let p = (c..4)
            .max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))
            .unwrap();
        a.swap(c, p);
        let v = a[c][c];
        for x in a[c].iter_mut() {
            *x /= v;
        }
        for r in 0..4 {
            if r != c {
                let f = a[r][c];
                let row_c = a[c].clone();
                for (x, y) in a[r].iter_mut().zip(row_c) {
                    *x -= f * y;
                }
            }
        }
    }
    let fitting = (0..4)
        .flat_map(|k| (0..n).map(|r| a[k][4 + r] as f32).collect::<Vec<_>>())
        .collect();
    Rig {
        name: "ball".into(),
        model: RigModel::Gradient,
        order: ORDER,
        bbox_min: lo,
        bbox_max: hi,
        bounding_radius: 0.0,
        samples,
        fitting,
        transitions: (0..12)
            .map(|i| {
                let x = 1.1 * 1.4f32.powi(i);
                Transition {
                    distance: x,
                    error: 300.0 / (x * x),
                }
            })
            .collect(),
    }
}

fn split() -> SplitRig {
    SplitRig::new(&rig(), Arc::new(SphereTable::default())).unwrap()
}

fn close(a: Vec3, b: Vec3, rel: f32) -> bool {
    (a - b).abs().max_element() <= rel * b.abs().max_element().max(1e-3)
}

#[test]
fn near_lights_are_exact_and_the_sun_goes_through_the_rig() {
    let mut s = split();
    let sun_dir = Vec3::new(0.3, -1.0, 0.2).normalize();
    let sun = Vec3::new(1.0, 0.9, 0.7);
    let lamp_at = Vec3::new(1.5, 1.2, -0.4);
    let lamp = Vec3::new(5.0, 4.0, 2.0);
    let lights = [
        Light::Directional {
            direction: sun_dir,
            irradiance: sun,
        },
        Light::Point {
            position: lamp_at,
            intensity: lamp,
        },
    ];
    // A tiny target: the lamp is per vertex (x* at the table's end).
    s.update(Affine3A::IDENTITY, &lights, 1e-6, 1.0).unwrap();
    let mut rng = Rng(31);
    for _ in 0..100 {
        let p = rng.vec3() * 0.9;
        let n = rng.vec3().normalize_or(Vec3::Y);
        let t = n.dot(-sun_dir);
        let series = 0.25 + 0.5 * t + 5.0 / 32.0 * (3.0 * t * t - 1.0);
        let w = lamp_at - p;
        let d2 = w.length_squared();
        let point = lamp * (n.dot(w).max(0.0) / (d2 * d2.sqrt()));
        let want = sun * series + point;
        let got = s.irradiance(p, n);
        assert!(close(got, want, 1e-4), "{p} {n}: {got} {want}");
    }
}

#[test]
fn moving_and_rotating_object_and_lights_together_changes_nothing() {
    let lights_obj = [
        Light::Sphere {
            position: Vec3::new(1.6, 0.3, 0.2),
            radius: 0.1,
            intensity: Vec3::new(3.0, 2.0, 1.0),
        },
        Light::Point {
            position: Vec3::new(-2.5, 1.0, 0.5),
            intensity: Vec3::splat(4.0),
        },
        Light::Spot {
            position: Vec3::new(0.0, 3.0, 0.0),
            direction: -Vec3::Y,
            inner_deg: 20.0,
            outer_deg: 35.0,
            intensity: Vec3::splat(6.0),
        },
        Light::Disk {
            position: Vec3::new(0.0, 0.0, -4.0),
            direction: Vec3::Z,
            radius: 0.5,
            intensity: Vec3::splat(2.0),
        },
        Light::Point {
            position: Vec3::new(30.0, 5.0, 0.0),
            intensity: Vec3::splat(500.0),
        },
        Light::Directional {
            direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
            irradiance: Vec3::ONE,
        },
    ];
    let mut rng = Rng(37);
    let verts: Vec<(Vec3, Vec3)> = (0..50)
        .map(|_| (rng.vec3() * 0.9, rng.vec3().normalize_or(Vec3::Y)))
        .collect();
    for target in [0.5f32, 2.0, 10.0] {
        let mut at_home = split();
        at_home
            .update(Affine3A::IDENTITY, &lights_obj, target, 1.0)
            .unwrap();
        for k in 0..5 {
            let rot = Quat::from_axis_angle(rng.vec3().normalize_or(Vec3::X), 3.0 * rng.f32());
            let t = rng.vec3() * 20.0 + Vec3::splat(k as f32);
            let world_from_object = Affine3A::from_rotation_translation(rot, t);
            let lights_world: Vec<Light> = lights_obj
                .iter()
                .map(|l| move_light(l, &world_from_object))
                .collect();
            let mut moved = split();
            moved
                .update(world_from_object, &lights_world, target, 1.0)
                .unwrap();
            for &(p, n) in &verts {
                let (a, b) = (moved.irradiance(p, n), at_home.irradiance(p, n));
                assert!(close(a, b, 2e-3), "target {target}, {p}: {a} {b}");
            }
        }
    }
}

/// `l` carried by the rigid transform `m`, written out per light kind.
fn move_light(l: &Light, m: &Affine3A) -> Light {
    let mut l = *l;
    match &mut l {
        Light::Sphere { position, .. } | Light::Point { position, .. } => {
            *position = m.transform_point3(*position)
        }
        Light::Spot {
            position,
            direction,
            ..
        }
        | Light::Disk {
            position,
            direction,
            ..
        } => {
            *position = m.transform_point3(*position);
            *direction = m.transform_vector3(*direction);
        }
        Light::Directional { direction, .. } => *direction = m.transform_vector3(*direction),
    }
    l
}

#[test]
fn bad_transforms_and_indices_are_errors() {
    let mut s = split();
    let lights = [Light::Point {
        position: Vec3::X * 3.0,
        intensity: Vec3::ONE,
    }];
    for bad in [
        Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0)),
        Affine3A::from_translation(Vec3::NAN),
    ] {
        assert_eq!(s.update(bad, &lights, 1.0, 1.0), Err(RigError::Transform));
    }
    // Degenerate targets and whites answer without panicking.
    s.update(Affine3A::IDENTITY, &lights, f32::NAN, 0.0)
        .unwrap();
    let _ = s.irradiance(Vec3::ZERO, Vec3::Y);
}

/// With a given bounding sphere, a light is per vertex exactly when the
/// transition distance measured from that sphere says so.
#[test]
fn a_given_bounding_sphere_decides_the_zones() {
    use probekit_runtime::rig::{rig_weight, transition_distance};
    let table = rig().transitions;
    let lamp_at = Vec3::new(2.0, 0.5, 0.0);
    let lamp = Light::Point {
        position: lamp_at,
        intensity: Vec3::splat(3.0),
    };
    let (p, n) = (Vec3::new(0.2, 0.1, 0.0), Vec3::X);
    let exact = {
        let w = lamp_at - p;
        Vec3::splat(3.0) * (n.dot(w) / w.length().powi(3))
    };
    for radius in [0.3f32, 0.9, 1.8] {
        let center = Vec3::new(0.1, 0.0, 0.0);
        let target = 2.0;
        let x_star = transition_distance(&table, &lamp, center, radius, 1.0, target);
        let share = 1.0 - rig_weight(lamp_at.distance(center) / radius, x_star);
        let mut s = split().with_bounding_sphere(center, radius).unwrap();
        s.update(Affine3A::IDENTITY, &[lamp], target, 1.0).unwrap();
        let rig_only = s.state().irradiance(p, n);
        let got = s.irradiance(p, n);
        assert!(
            close(got, rig_only + exact * share, 1e-5),
            "r {radius}: {got}"
        );
    }
    for (c, r) in [
        (Vec3::NAN, 1.0),
        (Vec3::ZERO, 0.0),
        (Vec3::ZERO, f32::INFINITY),
    ] {
        assert_eq!(
            split().with_bounding_sphere(c, r).err(),
            Some(RigError::BoundingBox)
        );
    }
}

/// What the accessors hand out (for packing the rig for a shader) is what
/// `irradiance` evaluates: the rig alone plus each near light, in the
/// object's frame, times its share, through the shared sphere table; the
/// shares lie in (0, 1]; a light wholly in the rig is left out; the state's
/// model and box are the file's.
#[test]
fn near_lights_and_table_rebuild_the_irradiance() {
    let lights = [
        Light::Sphere {
            position: Vec3::new(1.6, 0.3, 0.2),
            radius: 0.1,
            intensity: Vec3::new(3.0, 2.0, 1.0),
        },
        Light::Disk {
            position: Vec3::new(0.0, 0.0, -2.0),
            direction: Vec3::Z,
            radius: 0.5,
            intensity: Vec3::splat(2.0),
        },
        Light::Point {
            position: Vec3::new(40.0, 5.0, 0.0),
            intensity: Vec3::splat(50.0),
        },
        Light::Directional {
            direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
            irradiance: Vec3::ONE,
        },
    ];
    let mut s = split();
    assert!(s.near_lights().is_empty());
    assert_eq!(s.sphere_table().size(), 128);
    assert_eq!(s.sphere_table().values().len(), 128 * 128);
    let r = rig();
    assert_eq!(s.state().model(), r.model);
    assert_eq!(s.state().bounds(), (r.bbox_min, r.bbox_max));
    let m = Affine3A::from_rotation_translation(Quat::from_rotation_y(0.5), Vec3::X);
    s.update(m, &lights, 2.0, 1.0).unwrap();
    let near = s.near_lights();
    assert!(!near.is_empty() && near.len() < lights.len(), "{near:?}");
    assert!(near.iter().all(|(_, share)| *share > 0.0 && *share <= 1.0));
    // The first light, in the object's frame.
    let first = m.inverse().transform_point3(Vec3::new(1.6, 0.3, 0.2));
    assert!(near[0].0.position().unwrap().distance(first) < 1e-5);
    let mut rng = Rng(41);
    for _ in 0..50 {
        let p = rng.vec3() * 0.9;
        let n = rng.vec3().normalize_or(Vec3::Y);
        let mut want = s.state().irradiance(p, n);
        for (l, share) in near {
            want += l.irradiance(p, n, Some(s.sphere_table())) * *share;
        }
        assert_eq!(s.irradiance(p, n), want);
    }
}
