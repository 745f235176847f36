//! The run-time light split through the whole pipeline: the file's answer
//! against independent captures, K per probe, the recorded choice, a sealed
//! room, and a sharded bake's merge.

use super::*;
use crate::capture::tests::{box_tris, light, material, scene_of, two_group_room};
use crate::recipe::{Recipe, ResolvedMode};
use crate::scene::{LightKind, LightMode};
use probekit_runtime::{LoadOptions, ObjectState, Probes};

/// A grid bake of `scene` with few samples and no blend data.
fn grid_recipe(budget: usize) -> Recipe {
    let mut r = Recipe {
        placement: Placement::Grid {
            budget: Some(budget),
            cell: None,
        },
        blend: crate::recipe::Blend::none(),
        ..Recipe::default()
    };
    r.capture.samples = 256;
    r.capture.bounces = 1;
    r.lights.decision_points = 200;
    // Inside the test rooms (the scenes hold a speck far away).
    r.bake_box = Some([[-1.9, 0.1, -1.9], [1.9, 2.4, 1.9]]);
    r
}

fn bake(scene: &Scene, recipe: &Recipe) -> Baked {
    Bake::new(scene, "test", recipe)
        .unwrap()
        .run(&|_, _, _| {})
        .unwrap()
}

/// With both lights run-time, the file's SH is the capture less their
/// direct light, and its answer at a point is close to a dense reference
/// capture of all light there (the split loses nothing); the groups sum
/// to the SH and the record holds the choice.
#[test]
fn run_time_lights_leave_the_sh_and_come_back_in_the_answer() {
    let mut scene = two_group_room(Vec3::ONE);
    for l in &mut scene.lights {
        l.mode = LightMode::Runtime;
    }
    let mut recipe = grid_recipe(27);
    recipe.capture.groups = true;
    let baked = bake(&scene, &recipe);
    let f = &baked.file;
    let rl = f.probes().unwrap().runtime_lights.as_ref().unwrap();
    assert_eq!(rl.lights.len(), 2);
    assert_eq!(
        baked.report.lights.as_ref().unwrap().runtime,
        vec![0, 1],
        "{:?}",
        baked.report.lights
    );
    let record = crate::recipe::BakeRecord::from_json(f.metadata()).unwrap();
    assert_eq!(
        record.recipe.lights.resolved,
        [ResolvedMode::Runtime, ResolvedMode::Runtime]
    );
    // Groups under the scene's names, summing to the stored SH.
    let names: Vec<&str> = f.group_names().collect();
    assert!(names.contains(&"a") && names.contains(&"b"), "{names:?}");
    let total = f.probe_set().coefficients.to_f32().unwrap();
    let mut sum = vec![Vec3::ZERO; total.len()];
    for g in f.groups() {
        for (s, c) in sum.iter_mut().zip(g.coefficients.to_f32().unwrap()) {
            *s += c;
        }
    }
    for (s, t) in sum.iter().zip(&total) {
        assert!((*s - *t).length() < 1e-3 * (1.0 + t.length()), "{s} vs {t}");
    }
    // The answer against a reference capture at points in the room.
    let probes = Probes::from_file(f, LoadOptions::default()).unwrap();
    let baker = crate::capture::Baker::new(&scene).unwrap();
    let rs = crate::capture::ReferenceSettings {
        relative_precision: 0.02,
        max_samples: 16_384,
        bounces: 1,
        ..Default::default()
    };
    let mut st = ObjectState::new();
    let (mut se, mut st2, mut added) = (0.0f64, 0.0f64, 0);
    for (k, (p, n)) in [
        (Vec3::new(0.0, 1.2, 0.0), Vec3::Y),
        (
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(0.0, 1.0, 0.5).normalize(),
        ),
        (Vec3::new(1.2, 0.8, -0.5), Vec3::X),
        (
            Vec3::new(-0.5, 1.5, 1.0),
            Vec3::new(1.0, 0.5, -1.0).normalize(),
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let truth = baker
            .reference_irradiance(p, n, k as u64, &rs)
            .unwrap()
            .irradiance;
        let got = Vec3::from(probes.irradiance(&mut st, p, n).unwrap());
        let sh = Vec3::from(probes.sh_irradiance(&mut st, p, n).unwrap());
        assert!(got.x >= sh.x, "the lights take light away at {p}");
        added += usize::from(got.x > 1.05 * sh.x);
        se += (got - truth).length_squared() as f64;
        st2 += truth.length_squared() as f64;
    }
    assert!(added >= 2, "the lights add light at {added} points");
    let rel = (se / st2).sqrt();
    assert!(rel < 0.25, "relative error {rel}");
}

/// Three run-time point lights in one room with K = 2: the weakest is
/// demoted to baked, whole; its light is in the SH; the report says so.
#[test]
fn more_than_k_lights_at_a_probe_demote_the_weakest_whole() {
    let mut lights = Vec::new();
    for (x, i) in [(-1.0f32, 8.0f32), (0.0, 6.0), (1.0, 0.5)] {
        let mut l = light(
            LightKind::Point,
            Vec3::new(x, 2.0, 0.0),
            Vec3::NEG_Y,
            i,
            0.0,
        );
        l.mode = LightMode::Runtime;
        lights.push(l);
    }
    let scene = scene_of(
        vec![box_tris(
            Vec3::new(-2.0, 0.0, -2.0),
            Vec3::new(2.0, 2.5, 2.0),
            true,
            0,
        )],
        vec![material(0.5, 0.0)],
        lights,
        Vec3::ZERO,
    );
    let mut recipe = grid_recipe(27);
    recipe.lights.max_per_probe = 2;
    let baked = bake(&scene, &recipe);
    let report = baked.report.lights.clone().unwrap();
    assert_eq!(report.demoted, vec![2], "{report:?}");
    assert_eq!(report.runtime, vec![0, 1]);
    let f = &baked.file;
    let rl = f.probes().unwrap().runtime_lights.as_ref().unwrap();
    assert_eq!(rl.lights.len(), 2);
    assert!(rl.occlusion.counts().iter().all(|&c| c <= 2));
    // The demoted light's direct light is back in the SH: the SH part now
    // holds more than the all-run-time capture would (at a probe right
    // under it).
    let mut all = recipe.clone();
    all.lights.max_per_probe = 3;
    let three = bake(&scene, &all);
    let p = Vec3::new(1.0, 1.0, 0.0);
    let sh = |f: &ProbeFile| {
        let pr = Probes::from_file(f, LoadOptions::default()).unwrap();
        Vec3::from(
            pr.sh_irradiance(&mut ObjectState::new(), p, Vec3::Y)
                .unwrap(),
        )
    };
    assert!(
        sh(f).x > sh(&three.file).x + 0.05,
        "{} vs {}",
        sh(f),
        sh(&three.file)
    );
    // Both answers agree: demoting moves light, it does not lose it.
    let e = |f: &ProbeFile| {
        let pr = Probes::from_file(f, LoadOptions::default()).unwrap();
        Vec3::from(pr.irradiance(&mut ObjectState::new(), p, Vec3::Y).unwrap())
    };
    let (a, b) = (e(f), e(&three.file));
    assert!((a - b).length() < 0.15 * b.length(), "{a} vs {b}");
    // Baking again from the recorded recipe makes the same choice, same bytes.
    assert_eq!(
        crate::recipe::BakeRecord::from_json(f.metadata())
            .unwrap()
            .recipe
            .lights
            .resolved,
        [
            ResolvedMode::Runtime,
            ResolvedMode::Runtime,
            ResolvedMode::Demoted
        ]
    );
    let record = crate::recipe::BakeRecord::from_json(f.metadata()).unwrap();
    let again = bake(&scene, &record.recipe);
    assert_eq!(again.file.to_bytes().unwrap(), f.to_bytes().unwrap());
}

/// A sealed room beside a lit one: nothing of the run-time lamp reaches it,
/// neither through the SH nor through the occlusion.
#[test]
fn a_sealed_room_beside_a_lit_one_stays_dark() {
    let mut lamp = light(
        LightKind::Sphere,
        Vec3::new(-1.0, 1.5, 0.0),
        Vec3::NEG_Y,
        20.0,
        0.1,
    );
    lamp.mode = LightMode::Runtime;
    let scene = scene_of(
        vec![
            box_tris(
                Vec3::new(-2.0, 0.0, -1.0),
                Vec3::new(0.0, 2.5, 1.0),
                true,
                0,
            ),
            box_tris(Vec3::new(0.1, 0.0, -1.0), Vec3::new(2.1, 2.5, 1.0), true, 0),
        ],
        vec![material(0.6, 0.0)],
        vec![lamp],
        Vec3::ZERO,
    );
    let mut recipe = grid_recipe(64);
    recipe.bake_box = Some([[-1.9, 0.1, -0.9], [2.0, 2.4, 0.9]]);
    let baked = bake(&scene, &recipe);
    let probes = Probes::from_file(&baked.file, LoadOptions::default()).unwrap();
    assert_eq!(probes.runtime_lights().len(), 1);
    let mut st = ObjectState::new();
    let lit = Vec3::from(
        probes
            .irradiance(&mut st, Vec3::new(-1.0, 0.5, 0.0), Vec3::Y)
            .unwrap(),
    );
    assert!(lit.x > 1.0, "{lit}");
    let mut occ = [0.0f32];
    for p in [Vec3::new(1.5, 1.2, 0.0), Vec3::new(1.9, 2.0, 0.5)] {
        probes.light_occlusion(&mut st, p, &mut occ).unwrap();
        let e = Vec3::from(probes.irradiance(&mut st, p, Vec3::NEG_X).unwrap());
        // The grid's cells straddle the wall: the blend reaches lit probes,
        // so only the occlusion keeps the sealed side dark.
        assert!(
            e.max_element() < 0.02 * lit.x,
            "{p}: {e} (occlusion {})",
            occ[0]
        );
    }
}

/// A sharded bake splits lights in the merge, over all probes: two parts
/// (each carrying its candidates' scattered light apart) merge to the
/// bytes a single machine writes — with `auto` lights decided on held-out
/// points, with and without light groups, with the default blend data
/// (the weight fit on the combined answer included). Merging without the
/// scene is an error that says to give it.
#[test]
fn a_sharded_bake_splits_lights_in_the_merge_to_the_same_bytes() {
    let scene = two_group_room(Vec3::ONE);
    for groups in [false, true] {
        let mut recipe = grid_recipe(27);
        recipe.blend = Recipe::default().blend;
        recipe.blend.fit.points_per_probe = 2;
        recipe.capture.groups = groups;
        let whole = bake(&scene, &recipe);
        assert!(whole.file.probes().unwrap().runtime_lights.is_some());
        assert!(whole.file.cloud().blend.probe_weights.is_some());
        let b = Bake::new(&scene, "test", &recipe).unwrap();
        let parts: Vec<(String, ProbeFile)> = (0..2)
            .map(|k| {
                (
                    format!("part{k}"),
                    b.run_part(k, 2, &|_, _, _| {}).unwrap().file,
                )
            })
            .collect();
        let merged = merge(&parts, Some((&scene, "test")), &|_, _, _| {}).unwrap();
        assert_eq!(
            merged.to_bytes().unwrap(),
            whole.file.to_bytes().unwrap(),
            "groups {groups}"
        );
        let e = merge(&parts, None, &|_, _, _| {}).unwrap_err().to_string();
        assert!(e.contains("give the scene"), "{e}");
    }
}

/// A uniform volume splits lights as a cloud does: the file holds the
/// run-time lights with each sample's occlusion, the SH part leaves their
/// direct light out, and the answer comes back close to a reference
/// capture.
#[test]
fn a_volume_splits_run_time_lights_too() {
    let mut scene = two_group_room(Vec3::ONE);
    for l in &mut scene.lights {
        l.mode = LightMode::Runtime;
    }
    let mut recipe = grid_recipe(27);
    recipe.volume.layout = crate::recipe::VolumeLayout::Uniform {
        cell: None,
        resolution: Some([4, 3, 4]),
    };
    let (file, _) = crate::pipeline::bake_volume(&scene, "test", &recipe, &|_, _, _| {}).unwrap();
    let rl = file.probes().unwrap().runtime_lights.as_ref().unwrap();
    assert_eq!(rl.lights.len(), 2);
    assert_eq!(rl.occlusion.probe_count(), 48);
    let record = crate::recipe::BakeRecord::from_json(file.metadata()).unwrap();
    assert_eq!(
        record.recipe.lights.resolved,
        [ResolvedMode::Runtime, ResolvedMode::Runtime]
    );
    let probes = Probes::from_file(&file, LoadOptions::default()).unwrap();
    let baker = crate::capture::Baker::new(&scene).unwrap();
    let rs = crate::capture::ReferenceSettings {
        relative_precision: 0.02,
        max_samples: 16_384,
        bounces: 1,
        ..Default::default()
    };
    let mut st = ObjectState::new();
    let (p, n) = (
        Vec3::new(-0.6, 1.0, 0.2),
        Vec3::new(-0.2, 1.0, 0.1).normalize(),
    );
    let truth = baker.reference_irradiance(p, n, 3, &rs).unwrap().irradiance;
    let got = Vec3::from(probes.irradiance(&mut st, p, n).unwrap());
    let sh = Vec3::from(probes.sh_irradiance(&mut st, p, n).unwrap());
    assert!(got.x > 1.2 * sh.x, "{got} vs SH part {sh}");
    assert!(
        (got - truth).length() < 0.25 * truth.length(),
        "{got} vs {truth}"
    );
}
