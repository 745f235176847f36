//! Tests of the tetrahedralization against exact invariants (sanity_check) and
//! independent counts (Euler characteristic, known grid/volume facts).

use super::order::bucket_sort_by_key;
use super::*;
use proptest::prelude::*;

fn check(points: &[Vec3]) -> Tetrahedralization {
    let t = tetrahedralize(points).expect("tetrahedralize");
    t.sanity_check(points).expect("sanity");
    t
}

/// Euler characteristic of a triangulated 3-ball: V − E + F − T = 1,
/// computed from the tets alone (an independent topological check).
fn euler(t: &Tetrahedralization) -> i64 {
    use std::collections::HashSet;
    let mut vs = HashSet::new();
    let mut es = HashSet::new();
    let mut fs = HashSet::new();
    for v in &t.tets {
        let mut s = *v;
        s.sort_unstable();
        for a in 0..4 {
            vs.insert(s[a]);
            for b in a + 1..4 {
                es.insert((s[a], s[b]));
                for c in b + 1..4 {
                    fs.insert((s[a], s[b], s[c]));
                }
            }
        }
    }
    vs.len() as i64 - es.len() as i64 + fs.len() as i64 - t.tets.len() as i64
}

#[test]
fn single_tetrahedron() {
    let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
    let t = check(&p);
    assert_eq!(t.tets.len(), 1);
    assert_eq!(t.neighbors[0], [HULL; 4]);
}

#[test]
fn cube_corners_give_five_or_six_tets_of_total_volume_one() {
    let p = bench_points::grid(2);
    let t = check(&p);
    // Any triangulation of a cube without interior vertices has 5 or 6 tets.
    assert!(t.tets.len() == 5 || t.tets.len() == 6, "{}", t.tets.len());
    assert_eq!(euler(&t), 1);
}

#[test]
fn regular_grids_are_exact() {
    for k in [3, 4, 7] {
        let p = bench_points::grid(k);
        let t = check(&p);
        assert_eq!(euler(&t), 1);
        // Volume of the grid's hull is (k-1)^3: checked exactly by the sum of
        // integer-coordinate tet volumes (each 6·vol is an integer).
        let vol6: i64 = t
            .tets
            .iter()
            .map(|v| {
                let q = v.map(|i| p[i as usize].as_dvec3());
                (q[1] - q[0]).cross(q[2] - q[0]).dot(q[3] - q[0]) as i64
            })
            .sum();
        assert_eq!(vol6, 6 * ((k - 1) as i64).pow(3));
    }
}

#[test]
fn shuffled_scaled_grid_with_duplicates() {
    let mut p: Vec<Vec3> = bench_points::grid(5)
        .iter()
        .map(|v| *v * 0.1 + Vec3::splat(-3.3))
        .collect();
    p.push(p[7]);
    p.push(p[0]);
    p.push(p[7]);
    let t = check(&p);
    let n = 125;
    assert_eq!(t.merged_duplicates, vec![(n, 7), (n + 1, 0), (n + 2, 7)]);
}

/// The points with integer coordinates on the sphere x²+y²+z² = 25: all
/// co-spherical, so every insphere test among them is a tie.
fn sphere_of_radius_5() -> Vec<Vec3> {
    let mut p = Vec::new();
    for x in -5i32..=5 {
        for y in -5i32..=5 {
            for z in -5i32..=5 {
                if x * x + y * y + z * z == 25 {
                    p.push(Vec3::new(x as f32, y as f32, z as f32));
                }
            }
        }
    }
    p
}

#[test]
fn cospherical_points_on_a_sphere() {
    let p = sphere_of_radius_5();
    assert!(p.len() > 20);
    let t = check(&p);
    assert_eq!(euler(&t), 1);
}

#[test]
fn local_and_hashed_linking_agree() {
    // `tetrahedralize` links small cavities through a dense table of local
    // vertex numbers and large ones through the edge hash table; with the
    // table disabled every cavity takes the hashed path: same output.
    let sphere = sphere_of_radius_5();
    for p in [
        bench_points::uniform(3000, 7),
        bench_points::grid(9),
        sphere,
    ] {
        let local = tetrahedralize(&p).unwrap();
        let hashed = tetrahedralize_with(&p, 0, MAX_CELLS).unwrap();
        hashed.sanity_check(&p).unwrap();
        assert_eq!(local, hashed);
    }
}

/// Past the cell limit the builder stops with an error instead of letting a
/// 32-bit cell index wrap; at or above the count it needs, the output is the
/// same as without a limit.
#[test]
fn too_many_cells_is_an_error() {
    let p = bench_points::uniform(500, 3);
    let full = tetrahedralize(&p).unwrap();
    // The finite cells, as many again for the infinite ones, and as many
    // again as slack for the free list.
    let needed = 3 * full.tets.len();
    assert_eq!(
        tetrahedralize_with(&p, LOCAL_LINK_MAX, 100),
        Err(DelaunayError::TooManyCells { max: 100 })
    );
    assert_eq!(tetrahedralize_with(&p, LOCAL_LINK_MAX, needed), Ok(full));
}

#[test]
fn coplanar_and_collinear_subsets() {
    // A plane of grid points, a line of points, plus two apexes.
    let mut p = Vec::new();
    for i in 0..6 {
        for j in 0..6 {
            p.push(Vec3::new(i as f32, j as f32, 0.0));
        }
    }
    for i in 0..10 {
        p.push(Vec3::new(0.5 * i as f32, 0.5 * i as f32, 2.0));
    }
    p.push(Vec3::new(2.5, 2.5, -3.0));
    check(&p);
}

#[test]
fn degenerate_inputs_are_typed_errors() {
    assert_eq!(
        tetrahedralize(&[Vec3::ZERO, Vec3::X, Vec3::Y]),
        Err(DelaunayError::TooFewPoints { distinct: 3 })
    );
    assert_eq!(
        tetrahedralize(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Y, Vec3::X]),
        Err(DelaunayError::TooFewPoints { distinct: 3 })
    );
    let line: Vec<Vec3> = (0..10).map(|i| Vec3::splat(i as f32)).collect();
    assert_eq!(tetrahedralize(&line), Err(DelaunayError::Collinear));
    let plane: Vec<Vec3> = bench_points::grid(3)
        .iter()
        .map(|v| Vec3::new(v.x, v.y, 1.0))
        .collect();
    assert_eq!(tetrahedralize(&plane), Err(DelaunayError::Coplanar));
    let mut nan = bench_points::grid(2);
    nan[5].y = f32::NAN;
    assert!(matches!(
        tetrahedralize(&nan),
        Err(DelaunayError::NonFinite { index: 5, .. })
    ));
    nan[5].y = f32::INFINITY;
    assert!(matches!(
        tetrahedralize(&nan),
        Err(DelaunayError::NonFinite { index: 5, .. })
    ));
}

#[test]
fn random_points_and_output_independent_of_input_order() {
    let p = bench_points::uniform(3000, 7);
    let t = check(&p);
    assert_eq!(euler(&t), 1);
    // Reversing the input changes ranks; the set of tets must still be the
    // unique Delaunay triangulation (random points are in general position).
    let rev: Vec<Vec3> = p.iter().rev().copied().collect();
    let t2 = check(&rev);
    let canon = |t: &Tetrahedralization, map: &dyn Fn(u32) -> u32| {
        let mut v: Vec<[u32; 4]> = t
            .tets
            .iter()
            .map(|v| {
                let mut s = v.map(map);
                s.sort_unstable();
                s
            })
            .collect();
        v.sort_unstable();
        v
    };
    let n = p.len() as u32;
    assert_eq!(canon(&t, &|i| i), canon(&t2, &|i| n - 1 - i));
}

#[test]
fn clustered_points_with_large_scale_range() {
    let mut p = bench_points::uniform(500, 3);
    p.extend(
        bench_points::uniform(500, 4)
            .iter()
            .map(|v| *v * 1e-4 + Vec3::splat(0.5)),
    );
    p.extend(bench_points::grid(3).iter().map(|v| *v * 1e3));
    check(&p);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn bucket_sort_matches_comparison_sort(
        keys in proptest::collection::vec((0u64..1 << 63, 0u8..4), 0..3000),
    ) {
        // Clustered keys (few buckets) and repeated keys (ties on the value).
        let pairs: Vec<(u64, u32)> = keys
            .iter()
            .enumerate()
            .map(|(i, &(k, mode))| match mode {
                0 => (k, i as u32),
                1 => (k & 0xff, i as u32),
                2 => (k >> 50, i as u32),
                _ => (7, i as u32),
            })
            .collect();
        let mut expect = pairs.clone();
        expect.sort_unstable();
        prop_assert_eq!(bucket_sort_by_key(pairs, 63), expect);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn random_small_integer_sets_are_valid(
        pts in proptest::collection::vec((0i8..4, 0i8..4, 0i8..4), 4..60)
    ) {
        // Tiny integer lattice: massive co-planarity, co-sphericity and duplicates.
        let p: Vec<Vec3> = pts.iter().map(|&(x, y, z)| Vec3::new(x as f32, y as f32, z as f32)).collect();
        match tetrahedralize(&p) {
            Ok(t) => {
                prop_assert_eq!(t.sanity_check(&p), Ok(()));
                prop_assert_eq!(euler(&t), 1);
                // Every distinct position is a vertex: the probes no
                // tetrahedron uses are the repeats of an earlier position
                // (brute force), which are the merged ones.
                let repeats: Vec<u32> = (0..p.len())
                    .filter(|&i| p[..i].contains(&p[i]))
                    .map(|i| i as u32)
                    .collect();
                let dropped: Vec<u32> = t.merged_duplicates.iter().map(|d| d.0).collect();
                prop_assert_eq!(&unused_probes(p.len(), &t.tets), &repeats);
                prop_assert_eq!(&dropped, &repeats);
            }
            Err(DelaunayError::TooFewPoints { .. } | DelaunayError::Collinear | DelaunayError::Coplanar) => {}
            Err(e) => prop_assert!(false, "{e}"),
        }
    }

    #[test]
    fn random_float_sets_are_valid(
        pts in proptest::collection::vec((-1e3f32..1e3, -1e3f32..1e3, -1e3f32..1e3), 4..200)
    ) {
        let p: Vec<Vec3> = pts.iter().map(|&(x, y, z)| Vec3::new(x, y, z)).collect();
        let t = tetrahedralize(&p).unwrap();
        prop_assert_eq!(t.sanity_check(&p), Ok(()));
    }
}

/// `flatness` against closed forms, and `hull_slivers` on a cube whose top
/// face has one corner a few ulps too high: the corner makes a sliver on
/// the hull, the exact cube none.
#[test]
fn flatness_and_hull_slivers() {
    let reg = [
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(1.0, -1.0, -1.0),
        Vec3::new(-1.0, 1.0, -1.0),
        Vec3::new(-1.0, -1.0, 1.0),
    ];
    // Regular tetrahedron of edge a: 6V = a³/√2.
    assert!((flatness(reg) - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12);
    let flat = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)];
    assert_eq!(flatness(flat), 0.0);
    let mut grid = Vec::new();
    for i in 0..4 {
        for j in 0..4 {
            for k in 0..4 {
                grid.push(Vec3::new(i as f32, j as f32, k as f32));
            }
        }
    }
    let t = check(&grid);
    assert_eq!(hull_slivers(&grid, &t.tets, &t.neighbors), 0);
    let mut bumped = grid.clone();
    // (1, 3, 1) on the top face, lifted by a few ulps.
    let top = bumped
        .iter()
        .position(|p| *p == Vec3::new(1.0, 3.0, 1.0))
        .unwrap();
    bumped[top].y = f32::from_bits(3.0f32.to_bits() + 4);
    let t = check(&bumped);
    assert!(hull_slivers(&bumped, &t.tets, &t.neighbors) > 0);
}

/// Morton key of `p`'s 21-bit quantisation over `[lo, hi]`, interleaving one
/// bit at a time (x lowest) — written independently of the builder's `spread3`.
fn morton_bitwise(p: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> u64 {
    let top = ((1u64 << 21) - 1) as f64;
    let q: [u64; 3] = std::array::from_fn(|k| {
        let s = top / (hi[k] - lo[k]).max(f64::MIN_POSITIVE);
        (((p[k] - lo[k]) * s) as u64).min((1 << 21) - 1)
    });
    let mut key = 0u64;
    for bit in 0..21 {
        for (k, &qk) in q.iter().enumerate() {
            key |= ((qk >> bit) & 1) << (3 * bit + k);
        }
    }
    key
}

#[test]
fn output_tetrahedra_follow_the_morton_curve_of_their_centroids() {
    // `finish` sorts cells by the Morton code of their centroids and gathers
    // vertices and neighbours from the builder's records; recompute the keys
    // from the output alone and check their order (sanity_check, which
    // `check` runs, covers the neighbour renumbering).
    let mut shuffled = bench_points::grid(6);
    shuffled.reverse();
    shuffled.push(shuffled[3]); // a merged duplicate
    for p in [
        bench_points::uniform(3000, 9),
        bench_points::grid(6),
        shuffled,
    ] {
        let t = check(&p);
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for v in &p {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k] as f64);
                hi[k] = hi[k].max(v[k] as f64);
            }
        }
        let keys: Vec<u64> = t
            .tets
            .iter()
            .map(|v| {
                let c = std::array::from_fn(|k| {
                    v.iter().map(|&i| p[i as usize][k] as f64).sum::<f64>() * 0.25
                });
                morton_bitwise(c, lo, hi)
            })
            .collect();
        assert!(keys.windows(2).all(|w| w[0] <= w[1]), "not in Morton order");
        assert!(
            keys.first() < keys.last(),
            "keys all equal: the check is vacuous"
        );
    }
}

/// `sanity_check` is what the proptests lean on, so it must reject each kind
/// of broken output: every corruption of a valid tetrahedralization below
/// is caught, with the violation it names.
#[test]
fn sanity_check_rejects_each_corruption() {
    let p = bench_points::uniform(60, 3);
    let good = check(&p);
    let t0 = good.tets[0];
    let mut cases: Vec<(&str, Tetrahedralization, Vec<Vec3>)> = vec![
        (
            "out of range",
            {
                let mut t = good.clone();
                t.tets[0][2] = p.len() as u32;
                t
            },
            p.clone(),
        ),
        (
            "not positively oriented",
            {
                let mut t = good.clone();
                t.tets[0].swap(0, 1);
                t
            },
            p.clone(),
        ),
        (
            "in no tetrahedron and not a merged duplicate",
            good.clone(),
            {
                let mut q = p.clone();
                q.push(Vec3::splat(100.0));
                q
            },
        ),
        (
            "is a merged duplicate but a tetrahedron uses it",
            {
                let mut t = good.clone();
                t.merged_duplicates.push((t0[0], t0[1]));
                t
            },
            p.clone(),
        ),
        (
            "is not symmetric",
            {
                let mut t = good.clone();
                let u = *t.neighbors[0].iter().find(|&&u| u != HULL).unwrap();
                let back = (0..4).find(|&j| t.neighbors[u as usize][j] == 0).unwrap();
                t.neighbors[u as usize][back] = HULL;
                t
            },
            p.clone(),
        ),
        (
            "hull is not convex",
            {
                let mut t = good.clone();
                t.tets.pop();
                t.neighbors.pop();
                let last = t.tets.len() as u32;
                for n in t.neighbors.iter_mut().flatten() {
                    if *n == last {
                        *n = HULL;
                    }
                }
                t
            },
            p.clone(),
        ),
    ];
    // Two flat tetrahedra on either side of one triangle: valid in every
    // other respect, but each apex is inside the other's circumsphere (the
    // Delaunay mesh of these five points has three tetrahedra around the
    // apex–apex edge).
    let flat = vec![
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::new(0.3, 0.3, 0.05),
        Vec3::new(0.3, 0.3, -0.05),
    ];
    let two = Tetrahedralization {
        tets: vec![[0, 1, 2, 3], [1, 0, 2, 4]],
        neighbors: vec![[HULL, HULL, HULL, 1], [HULL, HULL, HULL, 0]],
        merged_duplicates: Vec::new(),
    };
    cases.push(("inside its circumsphere", two, flat.clone()));
    assert_eq!(check(&flat).tets.len(), 3);
    for (want, t, q) in cases {
        let err = t.sanity_check(&q).expect_err(want);
        assert!(err.contains(want), "{want}: {err}");
    }
}
