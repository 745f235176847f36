//! The runtime's split rig, loaded from the bytes of the baker's rig file,
//! against the baker's own evaluation (what `probekit rig` reports): the car
//! among the demo rig lights at several translations, per vertex, within
//! 1e-4 of the mesh's largest irradiance. The file carries everything the
//! split needs (fitting matrix, transition table, bounding radius); the
//! engine passes only its lights, the target and the white level.

use glam::{Affine3A, Vec3};
use probekit::rig::fit::rig_file;
use probekit::rig::lights::rig_demo_lights;
use probekit::rig::mesh::car;
use probekit::rig::run::{run, RunConfig};
use probekit::rig::split::{exact_irradiance, white_level};
use probekit_runtime::{LoadOptions, Probes};

#[test]
fn the_runtime_split_rig_equals_the_bakers_evaluation() {
    let mesh = car();
    let lights = rig_demo_lights();
    let mut zones = Vec::new();
    // Every light per vertex at the origin; lights in the transition band
    // and through the rig at the others (with the box's circumscribed
    // sphere instead of the recorded radius, the last one is 1.7e-4 off).
    for at in [
        Vec3::ZERO,
        Vec3::new(4.0, 0.0, 3.0),
        Vec3::new(1.5, 0.0, -1.0),
        Vec3::new(-4.0, 0.0, -1.0),
    ] {
        let cfg = RunConfig {
            at,
            samples: 256,
            ..RunConfig::default()
        };
        let report = run(&mesh, "car", &lights, None, &cfg, false).unwrap();
        let white = white_level(&exact_irradiance(&mesh, at, &lights)).max(f32::MIN_POSITIVE);
        let bytes = rig_file(std::slice::from_ref(&report.fitted))
            .to_bytes()
            .unwrap();
        let probes = Probes::from_bytes(&bytes, LoadOptions::default()).unwrap();
        let mut rig = probes.split_rig(0).unwrap();
        rig.update(
            Affine3A::from_translation(at),
            &lights,
            cfg.target_grey,
            white,
        )
        .unwrap();
        let mut worst = 0.0f32;
        let mut largest = 0.0f32;
        for ((p, n), want) in mesh.positions.iter().zip(&mesh.normals).zip(&report.approx) {
            let got = rig.irradiance(*p, *n);
            worst = worst.max((got - *want).abs().max_element());
            largest = largest.max(want.max_element());
        }
        assert!(largest > 0.0, "at {at}: no light");
        zones.extend(report.zones.iter().map(|z| format!("{z:?}")));
        assert!(
            worst <= 1e-4 * largest,
            "at {at} (zones {:?}): |runtime − baker| up to {worst:e}, largest {largest:e}",
            report.zones
        );
    }
    for zone in ["Analytic", "Transition", "Rig"] {
        assert!(
            zones.iter().any(|z| z.starts_with(zone)),
            "no light in the {zone} zone: {zones:?}"
        );
    }
}
