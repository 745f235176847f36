//! Whole-bake tests of the pipeline: the phase report, and the same bytes
//! for any thread count.

use super::*;
use crate::recipe::Recipe;

/// A quick default-shaped bake of the demo: adaptive placement with
/// `auto` light shells and every kind of blend data, few samples.
fn quick_recipe() -> Recipe {
    let mut r = Recipe {
        placement: Placement::Adaptive {
            budget: 24,
            tolerance: 0.0,
            light_shells: crate::recipe::LightShellsName::Auto,
        },
        ..Recipe::default()
    };
    r.capture.samples = 32;
    r.capture.bounces = 1;
    r.capture.validity.pre_pass_rays = 32;
    r.blend.fit.points_per_probe = 4;
    r.blend.fit.samples = 16;
    r
}

/// The bake in a pool of `threads` threads.
fn bake_with(threads: usize, scene: &Scene, recipe: &Recipe) -> Baked {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| {
            Bake::new(scene, "builtin:demo", recipe)
                .unwrap()
                .run(&|_, _, _| {})
                .unwrap()
        })
}

/// One and two threads give the same file, byte for byte, and the same
/// rays in every phase; the report names every phase in order, with
/// placement's sub-phases, and the rays of the phases that trace add up to
/// the tracer's count.
#[test]
fn bake_is_the_same_for_one_and_two_threads_and_reports_its_phases() {
    let scene = Scene::builtin_demo();
    let recipe = quick_recipe();
    let (a, b) = (bake_with(1, &scene, &recipe), bake_with(2, &scene, &recipe));
    assert_eq!(a.file.to_bytes().unwrap(), b.file.to_bytes().unwrap());
    let names: Vec<&str> = a.report.phases.iter().map(|p| p.phase.as_str()).collect();
    assert_eq!(
        names,
        [
            "load",
            "placement",
            "capture",
            "light split",
            "assembly",
            "distance moments",
            "cell visibility",
            "weight fit"
        ]
    );
    let rays = |r: &BakeReport| -> Vec<(String, u64)> {
        let mut out = Vec::new();
        for p in &r.phases {
            out.push((p.phase.clone(), p.rays));
            for q in &p.phases {
                out.push((format!("{}/{}", p.phase, q.phase), q.rays));
            }
        }
        out
    };
    assert_eq!(rays(&a.report), rays(&b.report));
    let get = |name: &str| a.report.phases.iter().find(|p| p.phase == name).unwrap();
    for traced in [
        "placement",
        "capture",
        "distance moments",
        "cell visibility",
    ] {
        assert!(get(traced).rays > 0, "{traced}: {:?}", get(traced));
    }
    assert_eq!(get("load").rays, 0);
    assert_eq!(get("assembly").rays, 0);
    let placement = get("placement");
    let sub: Vec<&str> = placement.phases.iter().map(|p| p.phase.as_str()).collect();
    for s in ["pool", "scoring", "candidates", "leaks", "held-out"] {
        assert!(sub.contains(&s), "{s} missing from {sub:?}");
    }
    // Sub-phases split their phase: no more rays or seconds than it.
    for p in &a.report.phases {
        let rays: u64 = p.phases.iter().map(|q| q.rays).sum();
        let wall: f64 = p.phases.iter().map(|q| q.wall_seconds).sum();
        assert!(rays <= p.rays, "{p:?}");
        assert!(wall <= p.wall_seconds + 1e-6, "{p:?}");
        assert!(p.wall_seconds >= 0.0 && p.cpu_seconds >= 0.0);
    }
    let json = serde_json::to_value(&a.report).unwrap();
    assert!(json["phases"][1]["cpu_seconds"].is_number());
    assert!(json["phases"][1]["phases"].is_array());
}
