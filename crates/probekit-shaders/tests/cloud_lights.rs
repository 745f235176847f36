//! The run-time light term of `shaders/probekit_cloud.wgsl` against
//! `probekit_runtime::Probes` on a real file: a small grid cloud of
//! builtin:demo baked in-process with the light split, its sphere light and
//! sun plus an added point, spot and disk light all left to run time (the
//! bake writes the lights and each probe's 8-bit occlusion of them), saved
//! and loaded back, packed by `pack_cloud_file` and queried on a CPU Vulkan
//! adapter (Mesa lavapipe) at random points and points near each light.
//! Prints `SKIPPED: no wgpu adapter` and returns when no adapter exists.
//!
//! The shader evaluates each light with `pk_light_irradiance`, the rig's
//! evaluation: `rig::Light::irradiance` **with the sphere table** (a sphere
//! through the 128² table, a disk as the sphere of equal projected area and
//! radiance in it). `Probes::irradiance` uses `Light::irradiance(p, n,
//! None)`: the exact horizon-clipped sphere and a 64-gon disk. So:
//! * the light term and `pk_cloud_irradiance` are compared with the
//!   runtime's arithmetic done with the table — `Probes::sh_irradiance` +
//!   `Σ_l Probes::light_occlusion_l · Light::irradiance(p, n, Some(table))`
//!   — to 2e-4 of `Σ_l I_l/d_l²` (the light irradiance scale of
//!   rig_shader.rs, whose bound for a spot's penumbra, 2e-4, is the
//!   largest) plus the SH scale; the occlusion blend to 1e-4 (four weights,
//!   each to 2e-5 as in runtime.rs, times fractions ≤ 1);
//! * against `Probes::irradiance` itself the difference must be within that
//!   tolerance plus `Σ_l v_l·|E_l(table) − E_l(exact)|`, the table's
//!   approximation, which the test prints per kind;
//! * the SH part (`pk_cloud_sh_irradiance`) against `Probes::sh_irradiance`
//!   to 5e-5 as in runtime.rs, and an L1 copy of the file in
//!   `L1Mode::Zh3Hallucinated` (`pk_cloud_irradiance_zh3`) to 5e-4.

mod common;

use common::{adapter_or_skip, Buffers, Gpu, Report, Rng, MODE_CLOUD};
use glam::Vec3;
use probekit::pipeline::Bake;
use probekit::recipe::{Placement, Recipe};
use probekit::scene::{Light as SceneLight, LightKind, LightMode, Scene};
use probekit_runtime::cloud::WalkState;
use probekit_runtime::format::{Codec, Coefficients, L1Mode, ProbeFile, RuntimeLight};
use probekit_runtime::rig::{Light, SphereTable};
use probekit_runtime::sh::codec::encode_l1;
use probekit_runtime::{LoadOptions, ObjectState, ProbeCloud, Probes};
use probekit_shaders::layout::{cell_code, pack_cloud_file, pack_sphere_table, CLOUD_HULL};
use probekit_shaders::{CHECK_IN_FLOATS, CHECK_OUT_FLOATS};

/// Tolerance of the light term over `Σ I/d²` (see the module docs).
const LIGHT_TOLERANCE: f32 = 2e-4;
/// Tolerance of a blended visible fraction.
const OCCLUSION_TOLERANCE: f32 = 1e-4;

/// builtin:demo with every light at run time: its sphere light and sun,
/// and a point light in room B, a spot in room A's alcove and a disk on
/// room B's ceiling.
fn scene() -> Scene {
    let mut scene = Scene::builtin_demo();
    for l in &mut scene.lights {
        l.mode = LightMode::Runtime;
    }
    let base = scene.lights[0].clone();
    scene.lights.extend([
        SceneLight {
            kind: LightKind::Point,
            position: Vec3::new(6.2, 1.8, 3.0),
            direction: Vec3::NEG_Y,
            color: Vec3::new(0.9, 1.0, 0.8),
            intensity: 15.0,
            radius: 0.0,
            group: Some("point".into()),
            ..base.clone()
        },
        SceneLight {
            kind: LightKind::Spot,
            position: Vec3::new(0.8, 2.7, 2.9),
            direction: Vec3::new(0.3, -1.0, 0.1).normalize(),
            color: Vec3::new(1.0, 0.9, 0.7),
            intensity: 30.0,
            radius: 0.0,
            inner_angle: 20f32.to_radians(),
            outer_angle: 45f32.to_radians(),
            group: Some("spot".into()),
            ..base.clone()
        },
        SceneLight {
            kind: LightKind::Disk,
            position: Vec3::new(5.5, 2.9, 1.2),
            direction: Vec3::NEG_Y,
            color: Vec3::new(0.8, 0.9, 1.0),
            intensity: 20.0,
            radius: 0.25,
            group: Some("disk".into()),
            ..base
        },
    ]);
    scene
}

/// A small grid cloud (a budget of 48 probes), quick capture, every light
/// of [`scene`] at run time.
fn bake() -> ProbeFile {
    let scene = scene();
    let mut r = Recipe::default();
    r.capture.samples = 64;
    r.capture.bounces = 1;
    r.blend.fit.points_per_probe = 8;
    r.blend.fit.samples = 32;
    r.placement = Placement::Grid {
        budget: Some(48),
        cell: None,
    };
    r.lights.split = true;
    r.lights.max_per_probe = 8;
    let bake = Bake::new(&scene, "builtin:demo", &r).expect("recipe");
    let file = bake.run(&|_, _, _| {}).expect("cloud bake").file;
    // As an engine gets it: written and read back.
    ProbeFile::from_bytes(&file.to_bytes().unwrap()).unwrap()
}

/// `file` with its coefficients in the 13-byte L1 codec.
fn as_l1(file: &ProbeFile) -> ProbeFile {
    let c = &file.probes().unwrap().coefficients;
    let n = (c.order * c.order) as usize;
    let mut data = Vec::new();
    for p in c.to_f32().unwrap().chunks_exact(n) {
        data.extend_from_slice(&encode_l1(&[p[0], p[1], p[2], p[3]]));
    }
    let mut out = file.clone();
    out.probes_mut().unwrap().coefficients = Coefficients {
        codec: Codec::L1Q13,
        order: 2,
        data,
    };
    out
}

/// `I/d²` of `light` at `p` (`d` at least the radius; a directional
/// light's irradiance): the irradiance it gives a surface facing it.
fn light_scale(light: &Light, p: Vec3) -> f32 {
    match *light {
        Light::Directional { irradiance, .. } => irradiance.max_element(),
        Light::Sphere { intensity, .. }
        | Light::Point { intensity, .. }
        | Light::Spot { intensity, .. }
        | Light::Disk { intensity, .. } => {
            let d2 = light.position().unwrap().distance_squared(p);
            intensity.max_element() / d2.max(light.radius() * light.radius())
        }
    }
}

fn kind_index(light: &Light) -> usize {
    match light {
        Light::Sphere { .. } => 0,
        Light::Point { .. } => 1,
        Light::Spot { .. } => 2,
        Light::Disk { .. } => 3,
        Light::Directional { .. } => 4,
    }
}

/// Random points in the interior grown by 30 cm, and points 0.2–1.5 m from
/// each light with a position; each with a unit normal.
fn points(lights: &[RuntimeLight]) -> Vec<(Vec3, Vec3)> {
    let mut rng = Rng(0x119b_c10d);
    let mut v = Vec::new();
    for _ in 0..128 {
        let p = Vec3::new(
            rng.range(-0.3, 8.3),
            rng.range(-0.3, 3.3),
            rng.range(-0.3, 4.3),
        );
        v.push((p, rng.unit()));
    }
    for l in lights {
        if let Some(c) = l.light.position() {
            for _ in 0..32 {
                v.push((c + rng.unit() * rng.range(0.2, 1.5), rng.unit()));
            }
        }
    }
    v
}

/// The check kernel's input: p, n, the runtime's cell.
fn input(points: &[(Vec3, Vec3)], cells: &[u32]) -> Vec<f32> {
    let mut v = vec![0.0f32; points.len() * CHECK_IN_FLOATS];
    for (i, ((p, n), code)) in points.iter().zip(cells).enumerate() {
        let a = &mut v[i * CHECK_IN_FLOATS..];
        a[0..3].copy_from_slice(&p.to_array());
        a[3..6].copy_from_slice(&n.to_array());
        a[6] = (code & !CLOUD_HULL) as f32;
        a[7] = (code >> 31) as f32;
    }
    v
}

#[test]
fn cloud_runtime_lights_match_runtime() {
    let Some(adapter) = adapter_or_skip() else {
        return;
    };
    let gpu = Gpu::new(&adapter, "pk_check_cloud");
    let file = bake();
    let runtime = file
        .probes()
        .unwrap()
        .runtime_lights
        .clone()
        .expect("the bake leaves lights to run time");
    let lights = &runtime.lights;
    let mut kinds = [false; 5];
    for l in lights {
        kinds[kind_index(&l.light)] = true;
    }
    assert_eq!(kinds, [true; 5], "every light kind at run time");
    assert!(lights.len() <= 8, "the check kernel reports 8 occlusions");
    let dense = runtime.occlusion.to_dense(lights.len());
    let partial = dense.iter().filter(|&&v| v > 0.0 && v < 1.0).count();
    let zero = dense.iter().filter(|&&v| v == 0.0).count();
    println!(
        "cloud: {} probes, {} run-time lights; occlusion values: {zero} zero, {partial} partial, {} one",
        file.probe_count(),
        lights.len(),
        dense.len() - zero - partial
    );
    assert!(
        partial > 0 && zero > 0,
        "some probes see part of a light, some none"
    );

    let table = SphereTable::default();
    let cloud = ProbeCloud::from_file(&file).unwrap();
    let packed = pack_cloud_file(&file).unwrap();
    assert_eq!(packed.lights.len(), 16 * lights.len());
    let buffers = Buffers {
        cloud: packed.words,
        sphere_table: pack_sphere_table(&table),
        ..Default::default()
    };
    let probes = Probes::from_bytes(&file.to_bytes().unwrap(), LoadOptions::default()).unwrap();
    let l1_file = as_l1(&file);
    let mut zh3 = LoadOptions::default();
    zh3.l1_mode = Some(L1Mode::Zh3Hallucinated);
    let l1_probes = Probes::from_bytes(&l1_file.to_bytes().unwrap(), zh3).unwrap();
    let l1_buffers = Buffers {
        cloud: pack_cloud_file(&l1_file).unwrap().words,
        sphere_table: buffers.sphere_table.clone(),
        ..Default::default()
    };

    let pts = points(lights);
    let cells: Vec<u32> = pts
        .iter()
        .map(|(p, _)| cell_code(&cloud.mesh().locate(*p, &mut WalkState::new())))
        .collect();
    let out = gpu.run(MODE_CLOUD, &input(&pts, &cells), &buffers);
    let out_l1 = gpu.run(MODE_CLOUD, &input(&pts, &cells), &l1_buffers);
    let sh_unit = 1e-3
        * (0..cloud.probe_count())
            .map(|i| cloud.probe_sh(i)[0].abs().max_element())
            .fold(0.0f32, f32::max);

    let mut rep = Report::default();
    // Per kind: points lit by it, and the largest |table − exact| over I/d².
    let mut lit = [0usize; 5];
    let mut table_error = [0.0f32; 5];
    let mut worst_exact = 0.0f32;
    for (i, &(p, n)) in pts.iter().enumerate() {
        let o = &out[i * CHECK_OUT_FLOATS..][..CHECK_OUT_FLOATS];
        let mut st = ObjectState::new();
        let exact = Vec3::from(probes.irradiance(&mut st, p, n).unwrap());
        let sh = Vec3::from(probes.sh_irradiance(&mut st, p, n).unwrap());
        let mut occ = vec![0.0f32; lights.len()];
        probes.light_occlusion(&mut st, p, &mut occ).unwrap();
        // The runtime's light term (LightTerm::irradiance) with the table,
        // and how far the table is from the exact evaluation.
        let (mut term, mut table_off, mut scale) = (Vec3::ZERO, 0.0f32, 0.0f32);
        for (l, r) in lights.iter().enumerate() {
            let s = light_scale(&r.light, p);
            scale += s;
            if occ[l] > 0.0 {
                let et = r.light.irradiance(p, n, Some(&table));
                let ex = r.light.irradiance(p, n, None);
                term += occ[l] * et;
                let d = (et - ex).abs().max_element();
                table_off += occ[l] * d;
                let k = kind_index(&r.light);
                table_error[k] = table_error[k].max(d / s);
                if et.max_element() > 0.0 {
                    lit[k] += 1;
                }
            }
        }
        let with_table = sh + term;

        rep.unit = 0.0;
        rep.check("light count", i, &o[87..88], &[lights.len() as f32], 0.0);
        rep.unit = 1.0;
        let mut gpu_occ = o[79..79 + lights.len()].to_vec();
        gpu_occ.truncate(lights.len());
        rep.check(
            "pk_cloud_light_occlusion",
            i,
            &gpu_occ,
            &occ,
            OCCLUSION_TOLERANCE,
        );
        rep.unit = sh_unit;
        rep.check(
            "pk_cloud_sh_irradiance",
            i,
            &o[70..73],
            &sh.to_array(),
            5e-5,
        );
        rep.unit = scale;
        rep.check(
            "pk_cloud_lights_irradiance",
            i,
            &o[76..79],
            &term.to_array(),
            LIGHT_TOLERANCE,
        );
        rep.unit = sh_unit + scale;
        rep.check(
            "pk_cloud_irradiance (table)",
            i,
            &o[35..38],
            &with_table.to_array(),
            LIGHT_TOLERANCE,
        );
        // Against Probes::irradiance: within the tolerance plus the table's
        // approximation.
        let g = Vec3::from_slice(&o[35..38]);
        let bound = LIGHT_TOLERANCE * (rep.unit + exact.abs().max_element()) + table_off;
        let d = (g - exact).abs().max_element();
        worst_exact = worst_exact.max(d / (sh_unit + scale + exact.abs().max_element()));
        if d > bound * 1.0001 && rep.failures.len() < 20 {
            rep.failures.push(format!(
                "Probes::irradiance, case {i}: gpu {g} vs rust {exact}: {d:e} > {bound:e}"
            ));
        }

        // The L1 copy in ZH3 mode: the SH part by hallucinated ZH3, plus
        // the same light term.
        let o1 = &out_l1[i * CHECK_OUT_FLOATS..][..CHECK_OUT_FLOATS];
        let mut st = ObjectState::new();
        let e1 = l1_probes.irradiance(&mut st, p, n).unwrap();
        let sh1 = l1_probes.sh_irradiance(&mut st, p, n).unwrap();
        let mut occ1 = vec![0.0f32; lights.len()];
        l1_probes.light_occlusion(&mut st, p, &mut occ1).unwrap();
        let mut term1 = Vec3::ZERO;
        for (l, r) in lights.iter().enumerate() {
            if occ1[l] > 0.0 {
                term1 += occ1[l] * r.light.irradiance(p, n, Some(&table));
            }
        }
        rep.unit = sh_unit;
        rep.check("L1: pk_cloud_sh_irradiance_zh3", i, &o1[73..76], &sh1, 5e-4);
        rep.unit = sh_unit + scale;
        rep.check(
            "L1: pk_cloud_irradiance_zh3 (table)",
            i,
            &o1[38..41],
            &(Vec3::from(sh1) + term1).to_array(),
            LIGHT_TOLERANCE.max(5e-4),
        );
        let d1 = (Vec3::from_slice(&o1[38..41]) - Vec3::from(e1))
            .abs()
            .max_element();
        let bound1 = 5e-4 * (rep.unit + Vec3::from(e1).abs().max_element())
            + lights
                .iter()
                .enumerate()
                .map(|(l, r)| {
                    occ1[l]
                        * (r.light.irradiance(p, n, Some(&table)) - r.light.irradiance(p, n, None))
                            .abs()
                            .max_element()
                })
                .sum::<f32>();
        if d1 > bound1 * 1.0001 && rep.failures.len() < 20 {
            rep.failures.push(format!(
                "L1 Probes::irradiance, case {i}: {:?} vs {e1:?}: {d1:e} > {bound1:e}",
                &o1[38..41]
            ));
        }
    }
    let names = ["sphere", "point", "spot", "disk", "directional"];
    for k in 0..5 {
        println!(
            "{:>12}: lit at {:>3} of {} points; sphere-table evaluation vs exact: {:.2e} of I/d²",
            names[k],
            lit[k],
            pts.len(),
            table_error[k]
        );
    }
    println!(
        "pk_cloud_irradiance vs Probes::irradiance (exact lights): largest difference {worst_exact:.2e} \
         of the scale (SH unit + Σ I/d² + |E|)"
    );
    assert!(
        lit.iter().all(|&c| c > 0),
        "every light lights some point: {lit:?}"
    );
    rep.finish("cloud run-time lights");
}
