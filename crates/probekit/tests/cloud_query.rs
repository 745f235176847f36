//! Baker → runtime: random Delaunay clouds from `delaunay::tetrahedralize`
//! queried through `probekit_runtime::cloud::TetMesh`, checked against brute
//! force (containment over all tetrahedra, closest point over all hull faces).

use glam::{DVec3, Vec3};
use probekit::delaunay::{bench_points, tetrahedralize};
use probekit_runtime::cloud::{Location, TetMesh, WalkState, INSIDE_TOLERANCE};
use proptest::prelude::*;

fn mesh(points: &[Vec3]) -> TetMesh {
    tetrahedralize(points).unwrap().to_tet_mesh(points).unwrap()
}

fn vol(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    (b - a).cross(c - a).dot(d - a)
}

/// Relative barycentric coordinates from signed volumes in f64 (independent
/// of the runtime's f32 matrices).
fn bary64(m: &TetMesh, t: usize, p: Vec3) -> [f64; 4] {
    let q = m.tets()[t].map(|i| m.positions()[i as usize].as_dvec3());
    let total = vol(q[0], q[1], q[2], q[3]);
    std::array::from_fn(|i| {
        let mut r = q;
        r[i] = p.as_dvec3();
        vol(r[0], r[1], r[2], r[3]) / total
    })
}

/// Closest point on the convex hull by brute force over all faces without a
/// neighbour (distance only).
fn hull_distance(m: &TetMesh, p: Vec3) -> f64 {
    let mut best = f64::INFINITY;
    for (t, v) in m.tets().iter().enumerate() {
        for i in 0..4 {
            if m.neighbor(t as u32, i).is_some() {
                continue;
            }
            let f: Vec<DVec3> = (0..4)
                .filter(|&k| k != i)
                .map(|k| m.positions()[v[k] as usize].as_dvec3())
                .collect();
            best = best.min(point_triangle_distance(p.as_dvec3(), f[0], f[1], f[2]));
        }
    }
    best
}

/// Point–triangle distance by dense sampling refinement-free formula: the
/// minimum over the plane projection (if inside) and the three edges.
fn point_triangle_distance(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let n = (b - a).cross(c - a).normalize();
    let proj = p - n * n.dot(p - a);
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|&(u, v)| (v - u).cross(proj - u).dot(n) >= 0.0);
    let seg = |u: DVec3, v: DVec3| {
        let t = ((p - u).dot(v - u) / (v - u).length_squared()).clamp(0.0, 1.0);
        (p - (u + (v - u) * t)).length()
    };
    if inside {
        (p - proj).length()
    } else {
        seg(a, b).min(seg(b, c)).min(seg(c, a))
    }
}

#[test]
fn random_cloud_queries_match_brute_force() {
    let pts = bench_points::uniform(800, 11);
    let m = mesh(&pts);
    let queries = bench_points::uniform(1500, 12);
    let mut s = WalkState::new();
    for &q in &queries {
        let p = q * 1.4 - Vec3::splat(0.2); // some outside the hull
        match m.locate(p, &mut s) {
            Location::Inside { tet, weights } => {
                let b = bary64(&m, tet as usize, p);
                assert!(b.iter().all(|&x| x >= -1e-4), "{b:?}");
                for i in 0..4 {
                    assert!(
                        (b[i] - weights[i] as f64).abs() < 1e-3,
                        "{b:?} vs {weights:?}"
                    );
                }
                let rec: Vec3 = (0..4)
                    .map(|i| m.positions()[m.tets()[tet as usize][i] as usize] * weights[i])
                    .sum();
                assert!((rec - p).length() < 1e-4);
                assert!(weights.iter().all(|&w| w >= -INSIDE_TOLERANCE));
            }
            Location::Outside { closest, .. } => {
                // Really outside: no tetrahedron contains p.
                assert!((0..m.tets().len()).all(|t| bary64(&m, t, p).iter().any(|&x| x < 1e-6)));
                let d = (p - closest).length() as f64;
                let b = hull_distance(&m, p);
                assert!((d - b).abs() < 1e-4 * (1.0 + b), "{d} vs {b}");
            }
        }
    }
}

#[test]
fn delaunay_grid_queries_terminate_and_reproduce_linear_functions() {
    let pts: Vec<Vec3> = bench_points::grid(6).iter().map(|v| *v * 0.5).collect();
    let m = mesh(&pts);
    let f = |x: Vec3| 2.0 * x.x - x.y + 4.0 * x.z - 0.5;
    let mut s = WalkState::new();
    for &q in &bench_points::uniform(2000, 13) {
        let p = q * 2.5;
        let (idx, w) = m.weights_at(p, &mut s);
        let v: f32 = (0..4)
            .map(|i| w[i] * f(m.positions()[idx[i] as usize]))
            .sum();
        assert!((v - f(p)).abs() < 1e-4);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn weights_reproduce_points_in_random_clouds(
        cloud in proptest::collection::vec((-5f32..5.0, -5f32..5.0, -5f32..5.0), 8..120),
        queries in proptest::collection::vec((-7f32..7.0, -7f32..7.0, -7f32..7.0), 1..40),
    ) {
        let pts: Vec<Vec3> = cloud.iter().map(|&(x, y, z)| Vec3::new(x, y, z)).collect();
        let Ok(t) = tetrahedralize(&pts) else { return Ok(()) };
        let m = t.to_tet_mesh(&pts).unwrap();
        let mut s = WalkState::new();
        for &(x, y, z) in &queries {
            let p = Vec3::new(x, y, z);
            let (idx, w) = m.weights_at(p, &mut s);
            prop_assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-4);
            if let Location::Inside { .. } = m.locate(p, &mut WalkState::new()) {
                let rec: Vec3 = (0..4).map(|i| m.positions()[idx[i] as usize] * w[i]).sum();
                prop_assert!((rec - p).length() < 1e-3 * (1.0 + p.length()), "{} vs {}", rec, p);
            } else {
                prop_assert!(w.iter().all(|&x| x >= 0.0));
                let b = hull_distance(&m, p);
                let rec: Vec3 = (0..4).map(|i| m.positions()[idx[i] as usize] * w[i]).sum();
                prop_assert!(((rec - p).length() as f64 - b).abs() < 1e-3 * (1.0 + b));
            }
        }
    }
}

/// Interpolated payload (a fixed non-linear function of the probe index) at `p`.
fn payload(m: &TetMesh, p: Vec3, s: &mut WalkState) -> f32 {
    let (idx, w) = m.weights_at(p, s);
    (0..4).map(|i| w[i] * (idx[i] as f32 * 0.731).sin()).sum()
}

/// Continuity on `[t0, t1]` along `o + t·dir`: bisect towards the half with
/// the larger difference until the interval is ~1e-6 m wide. A continuous
/// (possibly steep, e.g. in a thin tetrahedron) payload's difference shrinks
/// with the interval; a jump's does not.
fn assert_no_jump(m: &TetMesh, o: Vec3, dir: Vec3, t0: f32, t1: f32, s: &mut WalkState) {
    let (mut lo, mut hi) = (t0, t1);
    let (mut vlo, mut vhi) = (payload(m, o + dir * lo, s), payload(m, o + dir * hi, s));
    while hi - lo > 2e-6 {
        let mid = 0.5 * (lo + hi);
        let vm = payload(m, o + dir * mid, s);
        if (vm - vlo).abs() > (vhi - vm).abs() {
            (hi, vhi) = (mid, vm);
        } else {
            (lo, vlo) = (mid, vm);
        }
    }
    assert!(
        (vhi - vlo).abs() < 0.01,
        "jump {vlo} -> {vhi} near {}",
        o + dir * lo
    );
}

#[test]
fn lighting_is_continuous_across_and_outside_the_hull_of_a_random_cloud() {
    let pts = bench_points::uniform(300, 21);
    let m = mesh(&pts);
    let dirs = bench_points::uniform(200, 22);
    let origins = bench_points::uniform(200, 23);
    let eps = 1e-4f32;
    let mut crossings = 0;
    for (o, d) in origins.iter().zip(&dirs) {
        let dir = (*d - Vec3::splat(0.5)).normalize_or(Vec3::X);
        let mut s = WalkState::new();
        let inside = |x: Vec3, s: &mut WalkState| matches!(m.locate(x, s), Location::Inside { .. });
        // March the line from far outside to far outside in small steps: the
        // payload must never jump (outer cells included: edge and vertex
        // regions of the hull), and at each hull crossing, found by
        // bisection, the values on both sides agree.
        let mut t = -2.0f32;
        let mut prev = payload(&m, *o + dir * t, &mut s);
        let mut prev_in = inside(*o + dir * t, &mut s);
        while t < 2.0 {
            let t1 = t + 1e-3;
            let x1 = *o + dir * t1;
            let v = payload(&m, x1, &mut s);
            if (v - prev).abs() >= 0.05 {
                assert_no_jump(&m, *o, dir, t, t1, &mut s);
            }
            let now_in = inside(x1, &mut s);
            if now_in != prev_in {
                crossings += 1;
                let (mut lo, mut hi) = (t, t1);
                for _ in 0..30 {
                    let mid = 0.5 * (lo + hi);
                    if inside(*o + dir * mid, &mut s) == prev_in {
                        lo = mid
                    } else {
                        hi = mid
                    }
                }
                let mid = 0.5 * (lo + hi);
                assert_no_jump(&m, *o, dir, mid - eps, mid + eps, &mut s);
            }
            prev = v;
            prev_in = now_in;
            t = t1;
        }
    }
    assert!(crossings >= 200, "{crossings}");
}
