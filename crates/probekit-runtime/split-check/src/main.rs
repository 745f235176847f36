//! The runtime's `SplitRig` against the baker's `rig` evaluation on the
//! car among the demo rig lights (README.md): prints the largest per-vertex
//! difference relative to the largest irradiance, and exits 1 above 1e-4.

use glam::{Affine3A, Vec3};
use probekit::rig::lights::{rig_demo_lights, Light as BLight, SphereTable as BTable};
use probekit::rig::mesh::car;
use probekit::rig::run::{run, RunConfig};
use probekit::rig::split;
use probekit_runtime::rig::{Light, SphereTable, SplitRig};
use std::sync::Arc;

fn conv(l: &BLight) -> Light {
    match *l {
        BLight::Sphere {
            position,
            radius,
            intensity,
        } => Light::Sphere {
            position,
            radius,
            intensity,
        },
        BLight::Point {
            position,
            intensity,
        } => Light::Point {
            position,
            intensity,
        },
        BLight::Spot {
            position,
            direction,
            inner_deg,
            outer_deg,
            intensity,
        } => Light::Spot {
            position,
            direction,
            inner_deg,
            outer_deg,
            intensity,
        },
        BLight::Disk {
            position,
            direction,
            radius,
            intensity,
        } => Light::Disk {
            position,
            direction,
            radius,
            intensity,
        },
        BLight::Directional {
            direction,
            irradiance,
        } => Light::Directional {
            direction,
            irradiance,
        },
    }
}

fn main() {
    let mesh = car();
    let lights = rig_demo_lights();
    let rl: Vec<Light> = lights.iter().map(conv).collect();
    // Lights one by one: the same exact irradiance and SH.
    let bt = BTable::default();
    let rt = SphereTable::default();
    let mut worst_light = 0.0f32;
    for (b, r) in lights.iter().zip(&rl) {
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            let a = b.irradiance(*p, *n, Some(&bt));
            let c = r.irradiance(*p, *n, Some(&rt));
            worst_light = worst_light.max((a - c).abs().max_element());
        }
    }
    println!("light irradiance max |diff| = {worst_light:e}");
    for at in [
        Vec3::ZERO,
        Vec3::new(0.7, 0.0, -0.4),
        Vec3::new(-2.0, 0.1, 1.5),
        Vec3::new(4.0, 0.0, 3.0),
    ] {
        let cfg = RunConfig {
            at,
            samples: 256,
            ..Default::default()
        };
        let report = run(&mesh, "car", &lights, None, &cfg, false).unwrap();
        let exact = split::exact_irradiance(&mesh, at, &lights);
        let white = split::white_level(&exact).max(f32::MIN_POSITIVE);
        let (c, radius) = mesh.bounding_sphere();
        let mut s = SplitRig::new(&report.fitted.rig, Arc::new(SphereTable::default()))
            .unwrap()
            .with_bounding_sphere(c, radius)
            .unwrap();
        s.update(Affine3A::from_translation(at), &rl, cfg.target_grey, white)
            .unwrap();
        let mut worst = 0.0f32;
        let mut largest = 0.0f32;
        for ((p, n), a) in mesh.positions.iter().zip(&mesh.normals).zip(&report.approx) {
            let e = s.irradiance(*p, *n);
            worst = worst.max((e - *a).abs().max_element());
            largest = largest.max(a.max_element());
        }
        println!("at {at}: zones {:?}\n  max |runtime - baker| = {worst:e}, largest {largest:e}, ratio {:e}", report.zones, worst / largest);
        if !(worst <= 1e-4 * largest) {
            println!("FAIL: above 1e-4 of the largest irradiance");
            std::process::exit(1);
        }
    }
    if worst_light != 0.0 {
        println!("FAIL: the two light implementations differ");
        std::process::exit(1);
    }
}
