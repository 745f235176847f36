use super::orphans::by_pocket_coverage;
use super::*;
use crate::delaunay::tetrahedralize;
use crate::scene::Scene;
use crate::trace::free_space::*;
use crate::trace::Tracer;

fn fast_settings() -> CaptureSettings {
    CaptureSettings {
        samples: 64,
        bounces: 1,
        ..Default::default()
    }
}

#[test]
fn grid_points_cover_box_at_cell_centres() {
    let b = Aabb::new(Vec3::ZERO, Vec3::new(8.0, 3.0, 4.0));
    let p = grid_points(&b, Some(1.0), None).unwrap();
    assert_eq!(p.len(), 8 * 3 * 4);
    assert!(p.contains(&Vec3::new(0.5, 0.5, 0.5)));
    assert!(grid_points(&b, None, Some(3)).is_err());
    assert!(grid_points(&b, Some(-1.0), None).is_err());
}

/// `auto` light shells place both ways and keep exactly the `off` or the
/// `on` placement: the one with the lower held-out error, which it reports;
/// with no positional light in the box it is `off` and places once.
#[test]
fn auto_light_shells_keep_the_placement_with_the_lower_held_out_error() {
    let timed = |scene: &Scene, light_shells| {
        let baker = Baker::new(scene).unwrap();
        let m = PlacementMethod::Adaptive {
            budget: 32,
            tolerance: 0.0,
            light_shells,
        };
        let (p, phases) = place_timed(
            &baker,
            scene.bake_box(),
            &m,
            &fast_settings(),
            &|_, _, _| {},
        )
        .unwrap();
        let pool = phases.iter().find(|p| p.phase == "pool").unwrap().rays;
        (p, pool)
    };
    let run = |scene: &Scene, light_shells| timed(scene, light_shells).0;
    let scene = Scene::builtin_demo();
    let (off, off_pool) = timed(&scene, LightShells::Off);
    let (on, on_pool) = timed(&scene, LightShells::On);
    let (auto, auto_pool) = timed(&scene, LightShells::Auto);
    // Auto captures the pool once, with the shells: the rays of `on`'s.
    assert_eq!(auto_pool, on_pool);
    assert!(off_pool < on_pool);
    assert_ne!(
        off.positions, on.positions,
        "the shells change the placement"
    );
    assert_eq!(off.stats.held_out_error, None);
    assert!(!off.stats.light_shells && on.stats.light_shells);
    let [e_off, e_on] = auto.stats.held_out_error.unwrap();
    assert!(e_off.is_finite() && e_on.is_finite() && e_off > 0.0 && e_on > 0.0);
    let kept = if e_on < e_off { &on } else { &off };
    assert_eq!(auto.positions, kept.positions);
    assert_eq!(auto.captured, kept.captured);
    assert_eq!(auto.stats.light_shells, e_on < e_off);
    // Both placements and the held-out points, the shared pool once.
    assert!(auto.stats.captures > on.stats.captures);
    assert!(auto.stats.captures > off.stats.captures);
    // The points of free space it captured, the held-out ones among them,
    // for the probe-weight fit; none is a probe.
    assert!(auto.free_points.len() > kept.free_points.len());
    assert!(auto
        .free_points
        .iter()
        .all(|(p, _)| !auto.positions.contains(p)));
    // The sun alone offers no shell: auto is off, placed once.
    let mut sunlit = Scene::builtin_demo();
    sunlit
        .lights
        .retain(|l| l.kind == crate::scene::LightKind::Directional);
    let (a, o) = (
        run(&sunlit, LightShells::Auto),
        run(&sunlit, LightShells::Off),
    );
    assert_eq!(a, o);
    assert_eq!(a.stats.held_out_error, None);
}

#[test]
fn light_shell_modes_round_trip_their_names() {
    for m in [LightShells::Off, LightShells::On, LightShells::Auto] {
        assert_eq!(LightShells::from_name(m.name()), Some(m));
    }
    assert_eq!(LightShells::from_name("yes"), None);
    assert_eq!(LightShells::default(), LightShells::Auto);
}

#[test]
fn adaptive_places_no_probe_inside_and_is_deterministic() {
    let scene = Scene::builtin_demo();
    let baker = Baker::new(&scene).unwrap();
    let m = PlacementMethod::Adaptive {
        budget: 48,
        tolerance: 0.0,
        // Exercises the light shells too: they must obey the same rules.
        light_shells: LightShells::On,
    };
    let a = place(
        &baker,
        scene.bake_box(),
        &m,
        &fast_settings(),
        &|_, _, _| {},
    )
    .unwrap();
    let b = place(
        &baker,
        scene.bake_box(),
        &m,
        &fast_settings(),
        &|_, _, _| {},
    )
    .unwrap();
    assert_eq!(a, b);
    // The budget is a hard cap (the last leak and orphan passes included).
    assert!(
        a.positions.len() >= 40 && a.positions.len() <= 48,
        "{}",
        a.positions.len()
    );
    assert_eq!(a.captured.as_ref().unwrap().len(), a.positions.len());
    let tracer = baker.tracer();
    for p in &a.positions {
        assert!(!inside_geometry(tracer, *p), "{p}");
        // Not outside the building either (where a probe sees the sun).
        assert!(scene.bake_box().contains(*p), "{p}");
        assert!(a.positions.iter().filter(|q| *q == p).count() == 1);
    }
    // Grid drops the points inside the walls and pillars.
    let g = PlacementMethod::Grid {
        cell: Some(0.3),
        budget: None,
    };
    let g = place(
        &baker,
        scene.bake_box(),
        &g,
        &fast_settings(),
        &|_, _, _| {},
    )
    .unwrap();
    assert!(g.stats.rejected_inside > 0);
    assert!(g.positions.iter().all(|p| !inside_geometry(tracer, *p)));
}

#[test]
fn leak_fix_puts_probes_on_both_sides_of_the_wall() {
    let scene = Scene::builtin_demo();
    let tracer = Tracer::new(&scene);
    // Two layers of probes 1.2 m either side of the divider (x 3.85..4.15), z < 2.8.
    let mut pts = Vec::new();
    for x in [2.8f32, 5.2] {
        for y in [0.6f32, 2.2] {
            for z in [0.5f32, 1.5, 2.4] {
                pts.push(Vec3::new(x, y, z));
            }
        }
    }
    let ls = LeakSettings::default();
    let (n0, e0) = crossing_extent(&tracer, &pts).unwrap();
    assert!(n0 > 0);
    let new = leak_points(&tracer, &pts, &ls).unwrap();
    let west = new.iter().filter(|p| p.x < 3.85 && p.x > 3.3).count();
    let east = new.iter().filter(|p| p.x > 4.15 && p.x < 4.7).count();
    assert!(west > 0 && east > 0, "{new:?}");
    assert!(new.iter().all(|p| !inside_geometry(&tracer, *p)));
    let mut all = pts.clone();
    all.extend(new);
    let (n1, e1) = crossing_extent(&tracer, &all).unwrap();
    // Mean free extent per crossing edge shrinks: interpolation across the
    // wall is confined to a band near it.
    let (m0, m1) = (e0 / n0 as f32, e1 / n1 as f32);
    assert!(m1 < 0.7 * m0, "mean crossing extent {m0} -> {m1}");
}

/// Adaptive probes along the bake box's faces are exactly co-planar, so the
/// cloud's convex hull has no sliver tetrahedra along them: before
/// `snap_to_layer`, 19 of the 44 hull faces on the layers of this placement
/// belonged to tetrahedra flatter than 10⁻⁶ (probes a few ulps off the
/// layer). Such hull triangles, metres long, skipped the
/// probes next to a query point outside the hull and lit it through the
/// dividing wall.
#[test]
fn adaptive_hull_has_no_sliver_tetrahedra_along_the_layers() {
    let scene = Scene::builtin_demo();
    let baker = Baker::new(&scene).unwrap();
    let m = PlacementMethod::Adaptive {
        budget: 64,
        tolerance: 0.0,
        light_shells: LightShells::Off,
    };
    let bbox = scene.bake_box();
    let a = place(&baker, bbox, &m, &fast_settings(), &|_, _, _| {}).unwrap();
    let snap = Vec3::splat(adaptive::BOUNDARY_SNAP);
    let layer = Aabb::new(bbox.min + snap, bbox.max - snap);
    let planes: Vec<(usize, f32)> = (0..3)
        .flat_map(|k| [(k, layer.min[k]), (k, layer.max[k])])
        .collect();
    for p in &a.positions {
        for &(k, c) in &planes {
            let d = (p[k] - c).abs();
            assert!(d == 0.0 || d > LAYER_SNAP, "{p} is {d} m off a layer");
        }
    }
    let t = crate::delaunay::tetrahedralize(&a.positions).unwrap();
    let (mut on_layers, mut slivers) = (0, 0);
    for (v, nb) in t.tets.iter().zip(&t.neighbors) {
        let q = v.map(|i| a.positions[i as usize]);
        for (i, &n) in nb.iter().enumerate() {
            if n != probekit_runtime::cloud::HULL {
                continue;
            }
            // The hull face is the one opposite vertex i.
            let face: Vec<Vec3> = (0..4).filter(|&j| j != i).map(|j| q[j]).collect();
            let on = |&(k, c): &(usize, f32)| face.iter().all(|p| (p[k] - c).abs() < 1e-3);
            if planes.iter().any(on) {
                on_layers += 1;
                if crate::delaunay::flatness(q) < crate::delaunay::SLIVER_FLATNESS {
                    slivers += 1;
                }
            }
        }
    }
    assert!(on_layers > 20, "{on_layers}");
    assert_eq!(slivers, 0, "of {on_layers} hull faces on the layers");
}

#[test]
fn snap_to_layer_moves_only_points_near_or_beyond_a_face() {
    let layer = Aabb::new(Vec3::splat(0.06), Vec3::new(7.94, 2.94, 3.94));
    let inside = Vec3::new(1.0, 1.5, 2.0);
    assert_eq!(snap_to_layer(inside, &layer), inside);
    // Within LAYER_SNAP inside a face, on it, and beyond it: onto the face.
    for z in [0.06 + 0.9 * LAYER_SNAP, 0.06, 0.059_999_995, 0.01] {
        let q = snap_to_layer(Vec3::new(1.0, 1.5, z), &layer);
        assert_eq!(q, Vec3::new(1.0, 1.5, 0.06), "{z}");
    }
    let q = snap_to_layer(Vec3::new(7.95, 2.9395, 0.06 + 1.1 * LAYER_SNAP), &layer);
    assert_eq!(q, Vec3::new(7.94, 2.94, 0.06 + 1.1 * LAYER_SNAP));
}

/// Points of the demo's closet (x 0..1.2, z 0..1.0, reached through a gap
/// at x < 0.5 in its front wall), jittered, 5 cm off its walls.
fn closet_points(n: usize) -> Vec<Vec3> {
    let mut rng = crate::sampling::SampleRng::new(7, 0x434c, 0);
    (0..n)
        .map(|_| {
            Vec3::new(
                0.05 + 1.1 * rng.next_f32(),
                0.05 + 2.9 * rng.next_f32(),
                0.05 + 0.9 * rng.next_f32(),
            )
        })
        .collect()
}

/// Share of `pts` whose Delaunay cell of `probes` has all four probes hidden
/// by geometry (segment tests), counted independently of `orphan_points`'
/// lattice: by locating each point with the run time's walk.
fn orphaned_share(tracer: &Tracer, probes: &[Vec3], pts: &[Vec3]) -> f32 {
    use crate::trace::free_space::segment_clear;
    let mesh = tetrahedralize(probes).unwrap().to_tet_mesh(probes).unwrap();
    let mut ws = probekit_runtime::cloud::WalkState::new();
    let mut orphaned = 0;
    for &p in pts {
        let (idx, w) = mesh.weights_at(p, &mut ws);
        if (0..4)
            .filter(|&k| w[k] > 0.0)
            .all(|k| !segment_clear(tracer, p, probes[idx[k] as usize]))
        {
            orphaned += 1;
        }
    }
    orphaned as f32 / pts.len() as f32
}

/// Probes around the demo's closet and none in it, at each height `ys`: two
/// in the corridor (z 1.1..1.7) and two in room A east of the closet's side
/// wall.
fn around_the_closet(ys: &[f32]) -> Vec<Vec3> {
    ys.iter()
        .flat_map(|&y| {
            [
                Vec3::new(0.1, y, 1.4),
                Vec3::new(0.8, y, 1.4),
                Vec3::new(1.6, y, 0.06),
                Vec3::new(1.6, y, 0.9),
            ]
        })
        .collect()
}

/// A closet whose walls reach into tetrahedra of corridor and room probes
/// without crossing an edge into it: leak prevention's edge test adds nothing
/// there, part of the closet sees none of its cell's probes, and
/// `orphan_points` puts probes in the closet (in open space, off its
/// walls) after which no point of it is orphaned.
#[test]
fn orphan_points_fill_a_closet_that_no_edge_crosses() {
    let scene = Scene::builtin_demo();
    let tracer = Tracer::new(&scene);
    let probes = around_the_closet(&[0.5, 2.5]);
    let closet = closet_points(3000);
    let before = orphaned_share(&tracer, &probes, &closet);
    assert!(before > 0.02, "orphaned share before: {before}");
    let clearance = 0.049;
    let new = orphan_points(&tracer, &probes, clearance).unwrap();
    assert!(!new.is_empty());
    for p in &new {
        // In the closet, off its walls, and in open space.
        assert!(p.x < 1.2 - clearance && p.z < 1.0 - clearance, "{p}");
        assert!(is_free(&tracer, *p, clearance), "{p}");
    }
    // Spaced at least ORPHAN_SPACING from each other and the probes.
    for (i, p) in new.iter().enumerate() {
        for q in probes.iter().chain(&new[..i]) {
            assert!(p.distance(*q) >= ORPHAN_SPACING, "{p} {q}");
        }
    }
    let mut all = probes.clone();
    all.extend(&new);
    let after = orphaned_share(&tracer, &all, &closet);
    assert!(after < 0.1 * before, "orphaned share {before} -> {after}");
}

/// Orphan candidates come largest pocket first, counting only the orphaned
/// points a candidate sees within reach: a hand-made case in the demo with
/// 20 orphaned points in the closet and 3 in room B. A candidate in room B
/// (listed first) serves 3, one in the closet 20, and one in room A beside
/// the closet's side wall, 0.4 m from the closet's points but behind the
/// wall, none: it goes last.
#[test]
fn orphan_candidates_come_largest_pocket_first() {
    let scene = Scene::builtin_demo();
    let tracer = Tracer::new(&scene);
    let mut orphans: Vec<Vec3> = (0..20)
        .map(|i| Vec3::new(0.3 + 0.04 * i as f32, 1.5, 0.5))
        .collect();
    orphans.extend((0..3).map(|i| Vec3::new(6.0 + 0.1 * i as f32, 1.5, 3.0)));
    let room_b = Vec3::new(6.1, 1.2, 3.0);
    let closet = Vec3::new(0.7, 1.2, 0.5);
    let beside = Vec3::new(1.6, 1.5, 0.5);
    let order = by_pocket_coverage(&tracer, vec![beside, room_b, closet], &orphans);
    assert_eq!(order, vec![closet, room_b, beside]);
}

/// Below the hull's floor layer a point blends the three probes of the hull
/// face above it. Here the floor layer's probes all stand outside the
/// closet, and a probe high in the closet sees its floor from above: every
/// tetrahedron over the closet's floor has a probe the floor's points see,
/// but the hull face under them has none, so the orphan search must test
/// the hull's faces too, and it puts a probe on the closet's floor.
#[test]
fn orphan_points_cover_the_hull_faces() {
    let scene = Scene::builtin_demo();
    let tracer = Tracer::new(&scene);
    let mut probes = around_the_closet(&[0.06, 2.5]);
    probes.push(Vec3::new(0.6, 2.5, 0.5));
    let new = orphan_points(&tracer, &probes, 0.049).unwrap();
    assert!(
        new.iter().any(|p| p.x < 1.2 && p.z < 1.0 && p.y < 0.2),
        "{new:?}"
    );
}
