//! `shaders/probekit_rig.wgsl` against the runtime's `SplitRig` on a rig
//! the baker fits: the car among the demo rig lights plus a point, a spot,
//! a disk and a directional light, at placements where lights fall in all
//! three zones (per vertex, cross-faded, rig), per vertex; and every light
//! kind's exact irradiance and the sphere table's lookup on random inputs.
//!
//! Tolerances (f32 on both sides; WGSL allows 2.5 ULP for division and
//! square roots and may fuse multiply-adds, Rust rounds each operation):
//! * a light's irradiance is a few dozen operations from its inputs, each
//!   off by a few ULP (≈ 1e-7 relative). Sphere and disk go through the
//!   128² table: an error δ in `cos θ` moves the lookup by 63.5·δ cells,
//!   and an entry changes by at most π/63.5 per cell (π over half the
//!   table), so by at most π·δ — again a few ULP of `I/d²`, the irradiance
//!   the light gives a surface facing it. A spot's attenuation
//!   `clamp(cos·scale + offset)` loses up to `scale·ULP` (scale ≤ 1000 for
//!   a hard cone): 1e-4 of `I/d²` in the penumbra. So 2e-6 of `I/d²` for
//!   every kind and 2e-4 in a spot's penumbra; the table lookup itself to
//!   1e-6 of π.
//! * the rig's irradiance sums 4–8 weighted parameters and 9 SH terms whose
//!   magnitudes may exceed the result (cancellation between the DC and
//!   band-1 terms on the shadowed side), plus up to a dozen near lights: 1e-5
//!   of the mesh's largest irradiance (the unit the baker-vs-runtime test of
//!   crates/probekit uses, there at 1e-4).

mod common;

use common::{adapter_or_skip, Buffers, Gpu, Report, Rng, MODE_LIGHT, MODE_RIG};
use glam::{Affine3A, Quat, Vec3};
use probekit::rig::fit::rig_file;
use probekit::rig::lights::rig_demo_lights;
use probekit::rig::mesh::car;
use probekit::rig::run::{run, RunConfig};
use probekit::rig::split::{exact_irradiance, white_level};
use probekit::rig::RigSpec;
use probekit_runtime::format::AxisModel;
use probekit_runtime::rig::{Light, SphereTable, SplitRig};
use probekit_runtime::{LoadOptions, Probes};
use probekit_shaders::layout::{
    pack_rig_light, pack_sphere_table, pack_split_rig, RIG_LIGHT_WORDS,
};
use probekit_shaders::{CHECK_IN_FLOATS, CHECK_OUT_FLOATS};

/// Largest |GPU − CPU| of the rig's irradiance per vertex, over the mesh's
/// largest irradiance (see the module docs).
const RIG_TOLERANCE: f32 = 1e-5;
/// Largest |GPU − CPU| of one light's irradiance over `I/d²`.
const LIGHT_TOLERANCE: f32 = 2e-6;
/// The same in a spot's penumbra (the attenuation's scale amplifies the
/// rounding of the cosine).
const PENUMBRA_TOLERANCE: f32 = 2e-4;

/// The demo lights and one light of every other kind, placed so that each
/// is near the car at some placement of [`placements`].
fn lights() -> Vec<Light> {
    let mut l = rig_demo_lights();
    l.extend([
        Light::Point {
            position: Vec3::new(-1.0, 2.2, 1.6),
            intensity: Vec3::new(3.0, 2.5, 2.0),
        },
        Light::Spot {
            position: Vec3::new(0.3, 3.2, -0.4),
            direction: Vec3::new(0.1, -1.0, 0.15).normalize(),
            inner_deg: 20.0,
            outer_deg: 35.0,
            intensity: Vec3::new(25.0, 22.0, 18.0),
        },
        Light::Disk {
            position: Vec3::new(-3.6, 0.9, -0.6),
            direction: Vec3::new(1.0, -0.2, 0.1).normalize(),
            radius: 0.4,
            intensity: Vec3::new(4.0, 6.0, 8.0),
        },
        Light::Directional {
            direction: Vec3::new(0.3, -1.0, 0.2).normalize(),
            irradiance: Vec3::new(0.6, 0.55, 0.5),
        },
    ]);
    l
}

/// Where the car is placed: the baker test's translations (every zone
/// occurs), and a rotated one (directions taken into the object frame).
fn placements() -> Vec<Affine3A> {
    let mut v: Vec<Affine3A> = [
        Vec3::ZERO,
        Vec3::new(4.0, 0.0, 3.0),
        Vec3::new(1.5, 0.0, -1.0),
        Vec3::new(-4.0, 0.0, -1.0),
    ]
    .into_iter()
    .map(Affine3A::from_translation)
    .collect();
    v.push(Affine3A::from_rotation_translation(
        Quat::from_rotation_y(0.6),
        Vec3::new(-1.0, 0.0, 0.5),
    ));
    v
}

/// The runtime's split rig of the car fitted by the baker (`spec`, 256
/// samples), loaded from the rig file's bytes as an engine would.
fn fitted_car(spec: RigSpec) -> (Probes, RunConfig) {
    let cfg = RunConfig {
        spec,
        samples: 256,
        ..RunConfig::default()
    };
    let report = run(&car(), "car", &rig_demo_lights(), None, &cfg, false).unwrap();
    let bytes = rig_file(std::slice::from_ref(&report.fitted))
        .to_bytes()
        .unwrap();
    (
        Probes::from_bytes(&bytes, LoadOptions::default()).unwrap(),
        cfg,
    )
}

#[test]
fn split_rig_matches_runtime() {
    let Some(adapter) = adapter_or_skip() else {
        return;
    };
    let gpu = Gpu::new(&adapter, "pk_check_rig");
    let mesh = car();
    let lights = lights();
    let mut zones = [0usize; 3];
    let mut near_kinds = [false; 4];
    for spec in [
        RigSpec::Gradient,
        RigSpec::Tensor {
            axes: [
                AxisModel::Lattice(3),
                AxisModel::Gradient,
                AxisModel::Constant,
            ],
            mixed: true,
        },
    ] {
        let (probes, cfg) = fitted_car(spec);
        // Every placement's rig in one buffer, each addressed by its first
        // word.
        let mut rigs: Vec<(SplitRig, u32, f32)> = Vec::new();
        let mut buffers = Buffers {
            sphere_table: pack_sphere_table(&SphereTable::default()),
            ..Buffers::default()
        };
        for m in placements() {
            let mut rig = probes.split_rig(0).unwrap();
            let at: Vec3 = m.translation.into();
            let white = white_level(&exact_irradiance(&mesh, at, &lights)).max(f32::MIN_POSITIVE);
            rig.update(m, &lights, cfg.target_grey, white).unwrap();
            assert_eq!(
                pack_sphere_table(rig.sphere_table()),
                buffers.sphere_table,
                "the runtime's table is the default one"
            );
            let in_near = rig.near_lights().len();
            zones[0] += rig.near_lights().iter().filter(|l| l.1 == 1.0).count();
            zones[1] += rig.near_lights().iter().filter(|l| l.1 < 1.0).count();
            zones[2] += lights.len() - in_near;
            for (l, _) in rig.near_lights() {
                match l {
                    Light::Sphere { .. } => near_kinds[0] = true,
                    Light::Point { .. } => near_kinds[1] = true,
                    Light::Spot { .. } => near_kinds[2] = true,
                    Light::Disk { .. } => near_kinds[3] = true,
                    Light::Directional { .. } => panic!("a directional light is never near"),
                }
            }
            let offset = buffers.rig.len() as u32;
            buffers.rig.extend(pack_split_rig(&rig).unwrap());
            let largest = mesh
                .positions
                .iter()
                .zip(&mesh.normals)
                .map(|(p, n)| rig.irradiance(*p, *n).max_element())
                .fold(0.0f32, f32::max);
            assert!(largest > 0.0);
            rigs.push((rig, offset, largest));
        }
        let mut input = Vec::new();
        for (_, offset, _) in &rigs {
            for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
                let mut case = [0.0f32; CHECK_IN_FLOATS];
                case[..3].copy_from_slice(&p.to_array());
                case[3..6].copy_from_slice(&n.to_array());
                case[6] = *offset as f32;
                input.extend(case);
            }
        }
        let out = gpu.run(MODE_RIG, &input, &buffers);
        let mut report = Report::default();
        let mut worst_vertex = 0.0f32;
        let vertices = mesh.positions.len();
        for (r, (rig, _, largest)) in rigs.iter().enumerate() {
            report.unit = *largest;
            for (v, (p, n)) in mesh.positions.iter().zip(&mesh.normals).enumerate() {
                let case = r * vertices + v;
                let o = &out[case * CHECK_OUT_FLOATS..][..33];
                let want = rig.irradiance(*p, *n);
                report.check("irradiance", case, &o[..3], &want.to_array(), RIG_TOLERANCE);
                let model = rig.state().irradiance(*p, *n);
                report.check(
                    "rig alone",
                    case,
                    &o[3..6],
                    &model.to_array(),
                    RIG_TOLERANCE,
                );
                let mut sh = [Vec3::ZERO; 9];
                rig.state().sh_at(*p, &mut sh);
                let sh: Vec<f32> = sh.iter().flat_map(|c| c.to_array()).collect();
                report.check("rig SH", case, &o[6..33], &sh, RIG_TOLERANCE);
                // Per vertex, relative to the vertex's own irradiance where
                // it is at least 1 % of the mesh's largest.
                if want.max_element() >= 0.01 * largest {
                    let d = (Vec3::from_slice(&o[..3]) - want).abs().max_element();
                    worst_vertex = worst_vertex.max(d / want.max_element());
                }
            }
        }
        println!(
            "{spec:?}: {} placements × {vertices} vertices; largest difference relative to \
             the vertex's own irradiance (≥ 1 % of the mesh's largest): {worst_vertex:.2e}",
            rigs.len()
        );
        report.finish(&format!("split rig {spec:?}"));
    }
    println!(
        "lights per vertex {}, cross-faded {}, rig {}",
        zones[0], zones[1], zones[2]
    );
    assert!(zones.iter().all(|&z| z > 0), "a zone is empty: {zones:?}");
    assert_eq!(
        near_kinds, [true; 4],
        "every light kind but directional is near at some placement (sphere, point, spot, disk)"
    );
}

/// A random light of kind `k` (0 sphere … 4 directional) near the origin.
fn random_light(rng: &mut Rng, k: usize) -> Light {
    let position = Vec3::new(
        rng.range(-3.0, 3.0),
        rng.range(-3.0, 3.0),
        rng.range(-3.0, 3.0),
    );
    let intensity = Vec3::new(
        rng.range(0.1, 50.0),
        rng.range(0.1, 50.0),
        rng.range(0.1, 50.0),
    );
    match k {
        0 => Light::Sphere {
            position,
            radius: rng.range(0.05, 1.0),
            intensity,
        },
        1 => Light::Point {
            position,
            intensity,
        },
        2 => {
            let inner_deg = rng.range(0.0, 60.0);
            // Some hard cones (inner = outer: the 0.001 floor of the scale).
            let outer_deg = if rng.next_f32() < 0.2 {
                inner_deg
            } else {
                rng.range(inner_deg, 89.0)
            };
            Light::Spot {
                position,
                direction: rng.unit(),
                inner_deg,
                outer_deg,
                intensity,
            }
        }
        3 => Light::Disk {
            position,
            direction: rng.unit(),
            radius: rng.range(0.05, 1.0),
            intensity,
        },
        _ => Light::Directional {
            direction: rng.unit(),
            irradiance: intensity,
        },
    }
}

#[test]
fn light_kinds_match_runtime() {
    let Some(adapter) = adapter_or_skip() else {
        return;
    };
    let gpu = Gpu::new(&adapter, "pk_check_rig");
    let table = SphereTable::default();
    let mut rng = Rng(0x5eed_119b);
    let names = ["sphere", "point", "spot", "disk", "directional"];
    let mut lights = Vec::new();
    let mut buffers = Buffers {
        sphere_table: pack_sphere_table(&table),
        ..Buffers::default()
    };
    for k in 0..5 {
        for _ in 0..40 {
            let l = random_light(&mut rng, k);
            buffers.rig.extend(pack_rig_light(&l, rng.next_f32()));
            lights.push((k, l));
        }
    }
    let mut input = Vec::new();
    let mut cases = Vec::new();
    for _ in 0..4096 {
        let li = rng.below(lights.len());
        let (k, light) = lights[li];
        // Points around the light, some inside a sphere light, some behind
        // a disk, some in a spot's penumbra.
        let p = match light.position() {
            Some(c) => c + rng.unit() * rng.range(0.0, 4.0),
            None => rng.unit() * 3.0,
        };
        let n = rng.unit();
        let (cos_theta, sin_alpha) = (rng.range(-1.2, 1.2), rng.range(-0.2, 1.2));
        let mut case = [0.0f32; CHECK_IN_FLOATS];
        case[..3].copy_from_slice(&p.to_array());
        case[3..6].copy_from_slice(&n.to_array());
        case[6] = (li * RIG_LIGHT_WORDS) as f32;
        case[7] = cos_theta;
        case[8] = sin_alpha;
        input.extend(case);
        cases.push((k, light, p, n, cos_theta, sin_alpha));
    }
    let out = gpu.run(MODE_LIGHT, &input, &buffers);
    let mut report = Report::default();
    for (i, &(k, light, p, n, ct, sa)) in cases.iter().enumerate() {
        let o = &out[i * CHECK_OUT_FLOATS..][..4];
        let want = light.irradiance(p, n, Some(&table));
        // I/d²: what the light gives a surface facing it (sphere and disk:
        // exactly so outside them; a sphere's inside gives I/r²).
        let (intensity, d2) = match light {
            Light::Directional { irradiance, .. } => (irradiance, 1.0),
            _ => {
                let c = light.position().unwrap();
                let r = light.radius();
                let intensity = match light {
                    Light::Sphere { intensity, .. }
                    | Light::Point { intensity, .. }
                    | Light::Spot { intensity, .. }
                    | Light::Disk { intensity, .. } => intensity,
                    Light::Directional { .. } => unreachable!(),
                };
                (intensity, c.distance_squared(p).max(r * r))
            }
        };
        report.unit = intensity.max_element() / d2;
        let penumbra = match light {
            Light::Spot {
                position,
                direction,
                inner_deg,
                outer_deg,
                ..
            } => {
                let c = direction.dot((p - position).normalize());
                let (ci, co) = (inner_deg.to_radians().cos(), outer_deg.to_radians().cos());
                c > co - 1e-3 && c < ci + 1e-3
            }
            _ => false,
        };
        let (name, tol) = if penumbra {
            ("spot (penumbra)", PENUMBRA_TOLERANCE)
        } else {
            (names[k], LIGHT_TOLERANCE)
        };
        report.check(name, i, &o[..3], &want.to_array(), tol);
        report.unit = std::f32::consts::PI;
        report.check(
            "sphere table lookup",
            i,
            &o[3..4],
            &[table.lookup(ct, sa)],
            1e-6,
        );
    }
    report.finish("rig lights");
}
