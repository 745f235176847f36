use super::*;
use crate::capture::{Baker, CaptureSettings, ReferenceSettings};
use crate::delaunay::tetrahedralize;
use crate::placement::{grid_points, place, LightShells, PlacementMethod};
use crate::query::{blends_hidden_probes, outside_hull};
use crate::scene::{Aabb, Scene};
use crate::trace::free_space::*;
use crate::trace::Tracer;
use glam::Vec3;
use probekit_sh::ShRgb;

#[test]
fn metrics_match_hand_computation() {
    let truth = [Vec3::splat(1.0), Vec3::splat(2.0)];
    let pred = [Vec3::splat(1.0), Vec3::splat(10.0)];
    let m = metrics(&pred, &truth, mean_luminance(&truth));
    // se = 3·8² = 192, st = 3 + 12 = 15.
    assert!((m.rel_rmse - (192.0f32 / 15.0).sqrt()).abs() < 1e-5);
    assert_eq!(m.leaks, 1);
    assert_eq!(m.points, 2);
}

/// The worst points come largest first with shares of the summed squared
/// error, and taking them out leaves exactly the rest of `rel_rmse²`:
/// `metrics` of the remaining points (an independent sum) times their share
/// of `Σ |E_true|²` equals `(1 − Σ share) · rel_rmse²`.
#[test]
fn worst_points_carry_their_share_of_the_error() {
    let truth = [
        Vec3::splat(1.0),
        Vec3::splat(2.0),
        Vec3::new(3.0, 0.0, 1.0),
        Vec3::splat(0.5),
        Vec3::ZERO,
    ];
    let pred = [
        Vec3::splat(1.5),
        Vec3::splat(10.0),
        Vec3::new(3.0, 4.0, 1.0),
        Vec3::splat(0.5),
        Vec3::new(0.0, 4.0, 0.0),
    ];
    // Squared errors 0.75, 192, 16, 0, 16; sum 224.75.
    let w = worst_points(&pred, &truth, 3);
    assert_eq!(
        w.iter().map(|p| p.index).collect::<Vec<_>>(),
        vec![1, 2, 4],
        "ties by index"
    );
    assert!((w[0].share - 192.0 / 224.75).abs() < 1e-6);
    assert!((w[1].share - 16.0 / 224.75).abs() < 1e-6);
    let all: f32 = worst_points(&pred, &truth, 10)
        .iter()
        .map(|p| p.share)
        .sum();
    assert!((all - 1.0).abs() < 1e-6);
    assert_eq!(worst_points(&pred, &truth, 10).len(), 5);
    let mean = mean_luminance(&truth);
    let full = metrics(&pred, &truth, mean).rel_rmse;
    let rest = [0usize, 3];
    let (rp, rt): (Vec<Vec3>, Vec<Vec3>) = rest.iter().map(|&i| (pred[i], truth[i])).unzip();
    let st = |t: &[Vec3]| t.iter().map(|v| v.length_squared()).sum::<f32>();
    let left = metrics(&rp, &rt, mean).rel_rmse.powi(2) * st(&rt) / st(&truth);
    let shares: f32 = w.iter().map(|p| p.share).sum();
    assert!(
        (left - (1.0 - shares) * full * full).abs() < 1e-5,
        "{left} vs {}",
        (1.0 - shares) * full * full
    );
    // No error at all: nothing to show.
    assert!(worst_points(&truth, &truth, 3).is_empty());
}

/// Error of a cloud at `positions` captured with `s`, on fixed eval points.
fn cloud_error(
    baker: &Baker,
    positions: &[Vec3],
    s: &CaptureSettings,
    pts: &[EvalPoint],
    truth: &[Vec3],
) -> Metrics {
    let sh: Vec<ShRgb> = baker
        .capture_many(positions, 0, s, &|_, _| {})
        .unwrap()
        .into_iter()
        .map(|r| r.sh)
        .collect();
    let mesh = tetrahedralize(positions)
        .unwrap()
        .to_tet_mesh(positions)
        .unwrap();
    let pred = interpolate_cloud(&mesh, &sh, pts);
    metrics(&pred, truth, mean_luminance(truth))
}

#[test]
fn adaptive_beats_grid_at_equal_probe_count() {
    let scene = Scene::builtin_demo();
    let baker = Baker::new(&scene).unwrap();
    let s = CaptureSettings {
        samples: 128,
        bounces: 1,
        ..Default::default()
    };
    let m = PlacementMethod::Adaptive {
        budget: 96,
        tolerance: 0.0,
        light_shells: LightShells::Off,
    };
    let a = place(&baker, scene.bake_box(), &m, &s, &|_, _, _| {}).unwrap();
    let g = grid_points(&scene.bake_box(), None, Some(a.positions.len())).unwrap();
    let g: Vec<Vec3> = g
        .into_iter()
        .filter(|p| !inside_geometry(baker.tracer(), *p))
        .collect();
    let pts = sample_points(baker.tracer(), &scene.bake_box(), 150, 7);
    let rs = ReferenceSettings {
        relative_precision: 0.05,
        min_samples: 256,
        max_samples: 2048,
        bounces: 1,
        ..Default::default()
    };
    let truth = reference(&baker, &pts, &rs).unwrap();
    let ea = cloud_error(&baker, &a.positions, &s, &pts, &truth);
    let eg = cloud_error(&baker, &g, &s, &pts, &truth);
    eprintln!(
        "adaptive {} probes {ea:?}; grid {} probes {eg:?}",
        a.positions.len(),
        g.len()
    );
    assert!(g.len() >= a.positions.len() * 8 / 10);
    assert!(ea.rel_rmse < eg.rel_rmse, "adaptive {ea:?} grid {eg:?}");
}

/// `reference_cached` reads a cache file of the right length as is, and
/// ignores one of the wrong length: then it computes exactly what
/// `reference` at 3 % computes, writes it, and reads it back next time.
#[test]
fn reference_cache_round_trips_and_rejects_a_wrong_length() {
    let scene = Scene::builtin_demo();
    let baker = Baker::new(&scene).unwrap();
    let pts = sample_points(baker.tracer(), &scene.bake_box(), 3, 5);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("truth.bin");
    let fake: Vec<u8> = (0..pts.len() * 3)
        .flat_map(|i| (i as f32 + 0.5).to_le_bytes())
        .collect();
    std::fs::write(&path, &fake).unwrap();
    let read = reference_cached(&baker, &pts, &path).unwrap();
    for (i, v) in read.iter().enumerate() {
        let k = 3.0 * i as f32;
        assert_eq!(*v, Vec3::new(k + 0.5, k + 1.5, k + 2.5));
    }
    std::fs::write(&path, &fake[..fake.len() - 4]).unwrap();
    let computed = reference_cached(&baker, &pts, &path).unwrap();
    let rs = ReferenceSettings {
        relative_precision: 0.03,
        ..Default::default()
    };
    assert_eq!(computed, reference(&baker, &pts, &rs).unwrap());
    assert_eq!(std::fs::read(&path).unwrap().len(), 12 * pts.len());
    assert_eq!(reference_cached(&baker, &pts, &path).unwrap(), computed);
}

/// The cache file is keyed by the points themselves: the same points give
/// the same file; another seed, count, moved point or turned normal (what a
/// change to the sampler would give under the same seed) another; another
/// scene another.
#[test]
fn reference_cache_path_is_keyed_by_the_points() {
    let scene = Scene::builtin_demo();
    let baker = Baker::new(&scene).unwrap();
    let h = scene.lighting_hash();
    let pts = sample_points(baker.tracer(), &scene.bake_box(), 20, 5);
    let path = reference_cache_path(h, &pts);
    assert_eq!(path, reference_cache_path(h, &pts.clone()));
    let other_seed = sample_points(baker.tracer(), &scene.bake_box(), 20, 6);
    let fewer = &pts[..19];
    let mut moved = pts.clone();
    moved[7].position.x += 1e-3;
    let mut turned = pts.clone();
    turned[3].normal = -turned[3].normal;
    let mut seen = vec![path.clone()];
    for p in [
        reference_cache_path(h, &other_seed),
        reference_cache_path(h, fewer),
        reference_cache_path(h, &moved),
        reference_cache_path(h, &turned),
        reference_cache_path(h ^ 1, &pts),
    ] {
        assert!(!seen.contains(&p), "{p:?}");
        seen.push(p);
    }
    assert!(path.starts_with(std::env::temp_dir()));
}

/// `region_metrics` gives, per region, the metrics of exactly the points
/// inside its box (filtered here by hand), with the overall mean for the
/// leak threshold.
#[test]
fn region_metrics_match_hand_filtered_points() {
    use crate::scene::Region;
    let pts: Vec<EvalPoint> = (0..6)
        .map(|i| EvalPoint {
            position: Vec3::new(i as f32, 0.5, 0.5),
            normal: Vec3::Y,
        })
        .collect();
    let truth: Vec<Vec3> = (0..6).map(|i| Vec3::splat(1.0 + i as f32)).collect();
    let pred: Vec<Vec3> = [1.0, 9.0, 3.5, 4.0, 0.5, 6.0].map(Vec3::splat).to_vec();
    let regions = vec![
        Region {
            name: "low".into(),
            min: Vec3::new(-0.5, 0.0, 0.0),
            max: Vec3::new(2.5, 1.0, 1.0),
        },
        Region {
            name: "none".into(),
            min: Vec3::splat(10.0),
            max: Vec3::splat(11.0),
        },
    ];
    let mean = mean_luminance(&truth);
    let out = region_metrics(&regions, &pts, &pred, &truth, mean);
    assert_eq!(out.len(), 2);
    assert_eq!(out[0].0.name, "low");
    assert_eq!(out[0].1, metrics(&pred[..3], &truth[..3], mean));
    assert_eq!(out[0].1.points, 3);
    assert_eq!(out[0].1.leaks, 1, "9 against a truth of 2 is a leak");
    assert_eq!(out[1].1.points, 0);
}

/// `unlit_points` counts the points of exactly zero truth in every channel
/// (not a dim one, not one dark in a single channel) and the leaks among
/// them: with a mean true luminance of 1, any prediction above 0.01 there
/// (hand-computed).
#[test]
fn unlit_points_are_the_zero_truth_points_and_their_leaks() {
    let truth = [
        Vec3::ZERO,
        Vec3::ZERO,
        Vec3::ZERO,
        Vec3::splat(1e-6),
        Vec3::new(0.0, 0.0, 2.0),
    ];
    let pred = [
        Vec3::ZERO,
        Vec3::splat(0.005),
        Vec3::splat(0.02),
        Vec3::splat(1.0),
        Vec3::splat(1.0),
    ];
    // 0 and 0.005 stay under 4·0 + 0.01; 0.02 leaks.
    assert_eq!(unlit_points(&pred, &truth, 1.0), (3, 1));
    assert_eq!(unlit_points(&pred[..2], &truth[..2], 1.0), (2, 0));
    assert_eq!(unlit_points(&[], &[], 1.0), (0, 0));
}

/// `leaks_at` counts exactly the leaks at flagged points
/// (hand-computed), and `blends_hidden_probes` flags a point of room A
/// exactly when its plain blend reaches a probe beyond the dividing wall
/// (x 3.85..4.15, solid for z < 2.8; nothing else stands between these
/// probes and points): the side of the wall decides, an
/// independent test of the segment tests.
#[test]
fn leaks_through_geometry_are_the_leaks_whose_blend_reaches_behind_a_wall() {
    let truth = [Vec3::splat(1.0); 4];
    let pred = [
        Vec3::splat(10.0),
        Vec3::splat(10.0),
        Vec3::splat(1.5),
        Vec3::splat(10.0),
    ];
    let mean = mean_luminance(&truth);
    let hidden = [true, false, true, true];
    // Leaks at 0, 1 and 3; flagged among them: 0 and 3.
    assert_eq!(metrics(&pred, &truth, mean).leaks, 3);
    assert_eq!(leaks_at(&pred, &truth, mean, &hidden), 2);

    let scene = Scene::builtin_demo();
    let tracer = Tracer::new(&scene);
    let mut probes = Vec::new();
    // Room A east of the closet (x > 1.3) and room B; below the sphere
    // light (y 2.3..2.5), so only the wall can hide a probe.
    for x in [1.6f32, 3.0, 5.0, 7.0] {
        for y in [0.5f32, 2.0] {
            for z in [0.3f32, 1.4, 2.5] {
                probes.push(Vec3::new(x, y, z));
            }
        }
    }
    let mesh = tetrahedralize(&probes)
        .unwrap()
        .to_tet_mesh(&probes)
        .unwrap();
    let cloud =
        probekit_runtime::ProbeCloud::new(mesh.clone(), 1, vec![Vec3::ONE; probes.len()]).unwrap();
    let mut rng = crate::sampling::SampleRng::new(3, 0x4854, 0);
    let pts: Vec<EvalPoint> = (0..400)
        .map(|_| EvalPoint {
            position: Vec3::new(
                1.6 + 2.2 * rng.next_f32(),
                0.5 + 1.5 * rng.next_f32(),
                0.3 + 2.2 * rng.next_f32(),
            ),
            normal: Vec3::Y,
        })
        .collect();
    let flags = blends_hidden_probes(&cloud, &tracer, &pts);
    let mut ws = probekit_runtime::cloud::WalkState::new();
    let mut across = 0;
    for (p, &f) in pts.iter().zip(&flags) {
        let (idx, w) = mesh.weights_at(p.position, &mut ws);
        let expected = (0..4).any(|k| w[k] > 0.0 && probes[idx[k] as usize].x > 4.0);
        assert_eq!(f, expected, "{:?}", p.position);
        across += usize::from(expected);
    }
    // Cells between x = 3 and 5 straddle the wall: many points blend across.
    assert!(across > 40, "{across}");
}

/// `outside_hull` flags exactly the points outside the probes' box when the
/// probes are a lattice (its convex hull is its bounding box: an
/// independent test), and `leaks_at` with those flags counts the leaks
/// among them.
#[test]
fn outside_hull_flags_the_points_beyond_a_lattice_of_probes() {
    let mut probes = Vec::new();
    for x in [0.0f32, 1.0, 2.0] {
        for y in [0.0f32, 0.5] {
            for z in [0.0f32, 1.5, 3.0] {
                probes.push(Vec3::new(x, y, z));
            }
        }
    }
    let hull = Aabb::new(Vec3::ZERO, Vec3::new(2.0, 0.5, 3.0));
    let mesh = tetrahedralize(&probes)
        .unwrap()
        .to_tet_mesh(&probes)
        .unwrap();
    let cloud = probekit_runtime::ProbeCloud::new(mesh, 1, vec![Vec3::ONE; probes.len()]).unwrap();
    let mut rng = crate::sampling::SampleRng::new(5, 0x4855, 0);
    let pts: Vec<EvalPoint> = (0..600)
        .map(|_| EvalPoint {
            position: Vec3::new(
                -0.5 + 3.0 * rng.next_f32(),
                -0.5 + 1.5 * rng.next_f32(),
                -0.5 + 4.0 * rng.next_f32(),
            ),
            normal: Vec3::Y,
        })
        // Not within a hair of the hull, where rounding may go either way.
        .filter(|p| {
            let d = (p.position - hull.min)
                .min(hull.max - p.position)
                .abs()
                .min_element();
            d > 1e-4
        })
        .collect();
    let flags = outside_hull(&cloud, &pts);
    let mut outside = 0;
    for (p, &f) in pts.iter().zip(&flags) {
        assert_eq!(f, !hull.contains(p.position), "{:?}", p.position);
        outside += usize::from(f);
    }
    assert!(outside > 100 && outside < pts.len() - 50, "{outside}");
    // Every point leaks against a truth of 0.1 (blend 1): the flagged ones.
    let truth = vec![Vec3::splat(0.1); pts.len()];
    let pred = vec![Vec3::ONE; pts.len()];
    let mean = mean_luminance(&truth);
    assert_eq!(leaks_at(&pred, &truth, mean, &flags), outside);
}
