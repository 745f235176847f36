//! Tests of the query on Freudenthal (Kuhn) triangulations of grids — valid,
//! maximally degenerate (co-spherical) tetrahedralizations built here without
//! the baker. Random Delaunay clouds are tested in `probekit/tests/cloud_query.rs`.

use super::*;
use glam::DVec3;
use std::collections::HashMap;

#[test]
fn face_neighbors_rejects_a_face_shared_three_times() {
    let t = [[0, 1, 2, 3], [0, 1, 2, 4], [0, 1, 2, 5]];
    assert!(matches!(
        face_neighbors(&t),
        Err(CloudError::NeighborMismatch { tet: 2, .. })
    ));
}

/// [`lattice_tets`] against a brute-force check on a 3 × 4 × 2 lattice of
/// unit spacing: each tetrahedron has exactly a sixth of a cube's volume
/// (so their count fills the box), every random point of the box lies in
/// exactly one of them, no lattice point lies inside a circumsphere
/// (Delaunay), and the faces match across
/// cubes (each boundary square gives two hull faces, no face is shared by
/// three).
#[test]
fn lattice_tets_tile_the_box_once() {
    let dims = [3u32, 4, 2];
    let tets = lattice_tets(dims);
    assert_eq!(tets.len(), 6 * 2 * 3);
    let coord = |i: u32| {
        let (x, y, z) = (
            i % dims[0],
            (i / dims[0]) % dims[1],
            i / (dims[0] * dims[1]),
        );
        [x as f64, y as f64, z as f64]
    };
    // Six times the signed volume (exact here: small integers in f64).
    let det = |a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]| {
        let e = |q: [f64; 3]| [q[0] - a[0], q[1] - a[1], q[2] - a[2]];
        let (u, v, w) = (e(b), e(c), e(d));
        u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
            + u[2] * (v[0] * w[1] - v[1] * w[0])
    };
    let corners: Vec<[[f64; 3]; 4]> = tets.iter().map(|t| t.map(coord)).collect();
    assert!(corners
        .iter()
        .all(|v| det(v[0], v[1], v[2], v[3]).abs() == 1.0));
    let mut rng = Lcg(7);
    for _ in 0..2000 {
        let p = [2.0, 3.0, 1.0].map(|s| s * rng.f() as f64);
        let inside = corners
            .iter()
            .filter(|v| {
                let full = det(v[0], v[1], v[2], v[3]);
                [
                    det(p, v[1], v[2], v[3]),
                    det(v[0], p, v[2], v[3]),
                    det(v[0], v[1], p, v[3]),
                    det(v[0], v[1], v[2], p),
                ]
                .iter()
                .all(|&s| s / full > 0.0)
            })
            .count();
        assert_eq!(inside, 1, "{p:?}");
    }
    // Delaunay: no lattice point strictly inside a circumsphere (centre by
    // Cramer's rule on 2(v_k − v_0)·c = |v_k|² − |v_0|²).
    let all: Vec<[f64; 3]> = (0..dims.iter().product::<u32>()).map(coord).collect();
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    for v in &corners {
        let rows: [[f64; 3]; 3] =
            core::array::from_fn(|k| core::array::from_fn(|i| 2.0 * (v[k + 1][i] - v[0][i])));
        let rhs: [f64; 3] = core::array::from_fn(|k| dot(v[k + 1], v[k + 1]) - dot(v[0], v[0]));
        let cols = |r: [[f64; 3]; 3]| -> [[f64; 3]; 3] {
            core::array::from_fn(|i| core::array::from_fn(|k| r[k][i]))
        };
        let d3 = |c: [[f64; 3]; 3]| det([0.0; 3], c[0], c[1], c[2]);
        let a = cols(rows);
        let centre: [f64; 3] = core::array::from_fn(|i| {
            let mut m = a;
            m[i] = rhs;
            d3(m) / d3(a)
        });
        let d2 = |q: [f64; 3]| dot(q, q) - 2.0 * dot(q, centre) + dot(centre, centre);
        // The cube's centre: the middle of its main diagonal, v_0 to v_3.
        assert!((0..3).all(|i| (centre[i] - 0.5 * (v[0][i] + v[3][i])).abs() < 1e-12));
        let r2 = d2(v[0]);
        assert!(all.iter().all(|&q| d2(q) >= r2 - 1e-9), "{v:?}");
    }
    let n = face_neighbors(&tets).unwrap();
    let hull = n.iter().flatten().filter(|&&t| t == HULL).count();
    assert_eq!(hull, 2 * 2 * (2 * 3 + 2 + 3));
    assert!(lattice_tets([1, 4, 4]).is_empty());
}

/// Kuhn triangulation of a `k³` lattice (spacing `h`, origin `o`, optional
/// per-point jitter function): 6 tetrahedra per cube, one per axis order.
pub(crate) fn kuhn(
    k: u32,
    h: f32,
    o: Vec3,
    jitter: &dyn Fn(u32) -> Vec3,
) -> (Vec<Vec3>, Vec<[u32; 4]>, Vec<[u32; 4]>) {
    let id = |x: u32, y: u32, z: u32| (z * k + y) * k + x;
    let mut pos = Vec::new();
    for z in 0..k {
        for y in 0..k {
            for x in 0..k {
                pos.push(o + h * Vec3::new(x as f32, y as f32, z as f32) + jitter(id(x, y, z)));
            }
        }
    }
    let tets = lattice_tets([k; 3]);
    let nbrs = neighbours(&tets);
    (pos, tets, nbrs)
}

pub(crate) fn neighbours(tets: &[[u32; 4]]) -> Vec<[u32; 4]> {
    face_neighbors(tets).unwrap()
}

fn grid_mesh(k: u32) -> TetMesh {
    let (p, t, n) = kuhn(k, 1.0, Vec3::ZERO, &|_| Vec3::ZERO);
    let m = TetMesh::new(p, t.clone(), n.clone()).unwrap();
    // Round trip of the stored topology.
    assert_eq!(m.tets(), &t[..]);
    assert_eq!(m.neighbors().collect::<Vec<_>>(), n);
    m
}

/// Tiny deterministic generator for test points.
struct Lcg(u64);
impl Lcg {
    fn f(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn v(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.f(), self.f(), self.f()) * (hi - lo) + Vec3::splat(lo)
    }
}

/// Independent containment test: exact-ish f64 signed volumes.
fn contains(m: &TetMesh, t: usize, p: Vec3) -> bool {
    let q = m.tets[t].map(|i| m.positions[i as usize].as_dvec3());
    let p = p.as_dvec3();
    let vol = |a: DVec3, b: DVec3, c: DVec3, d: DVec3| (b - a).cross(c - a).dot(d - a);
    let total = vol(q[0], q[1], q[2], q[3]);
    (0..4).all(|i| {
        let mut r = q;
        r[i] = p;
        vol(r[0], r[1], r[2], r[3]) / total >= -1e-5
    })
}

#[test]
fn weights_reproduce_position_and_sum_to_one() {
    let m = grid_mesh(6);
    let mut rng = Lcg(1);
    let mut s = WalkState::new();
    for _ in 0..2000 {
        let p = rng.v(0.0, 5.0);
        let (idx, w) = m.weights_at(p, &mut s);
        let sum: f32 = w.iter().sum();
        let rec: Vec3 = (0..4).map(|i| m.positions[idx[i] as usize] * w[i]).sum();
        assert!((sum - 1.0).abs() < 1e-5, "{sum}");
        assert!((rec - p).length() < 1e-5, "{rec} vs {p}");
        assert!(w.iter().all(|&x| x >= -INSIDE_TOLERANCE));
    }
}

#[test]
fn walk_finds_the_containing_tet_cold_and_warm() {
    let m = grid_mesh(7);
    let mut rng = Lcg(2);
    let mut warm = WalkState::new();
    for _ in 0..1000 {
        let p = rng.v(0.0, 6.0);
        for s in [&mut WalkState::new(), &mut warm] {
            match m.locate(p, s) {
                Location::Inside { tet, .. } => assert!(contains(&m, tet as usize, p)),
                o => panic!("{p} inside the grid located as {o:?}"),
            }
        }
        // Brute force agrees that some tet contains p.
        assert!((0..m.tets.len()).any(|t| contains(&m, t, p)));
    }
}

#[test]
fn walk_terminates_from_every_start_on_degenerate_grid() {
    // Points on lattice vertices, edges and faces: the worst case for cycles.
    let m = grid_mesh(4);
    let mut rng = Lcg(3);
    let pts: Vec<Vec3> = (0..40)
        .map(|i| {
            let v = (rng.v(0.0, 3.0) * 2.0).round() * 0.5;
            if i % 3 == 0 {
                v.round()
            } else {
                v
            }
        })
        .collect();
    for start in 0..m.tets.len() as u32 {
        for &p in &pts {
            let mut s = WalkState {
                tet: start,
                ..WalkState::new()
            };
            match m.locate(p, &mut s) {
                Location::Inside { tet, .. } => assert!(contains(&m, tet as usize, p)),
                o => panic!("{o:?}"),
            }
        }
    }
}

#[test]
fn linear_functions_are_reproduced_exactly() {
    let (p, t, n) = kuhn(5, 0.7, Vec3::new(-1.0, 2.0, 0.5), &|i| {
        // Small deterministic jitter keeps the Kuhn triangulation valid.
        let h = (i.wrapping_mul(2654435761) >> 8) as f32 / (1u32 << 24) as f32;
        Vec3::new(h - 0.5, (h * 7.0).fract() - 0.5, (h * 13.0).fract() - 0.5) * 0.1
    });
    let m = TetMesh::new(p, t, n).unwrap();
    let f = |x: Vec3| 3.0 * x.x - 2.0 * x.y + 0.5 * x.z + 1.25;
    let mut rng = Lcg(4);
    let mut s = WalkState::new();
    for _ in 0..2000 {
        let x = rng.v(-0.9, 1.6) + Vec3::new(0.0, 3.0, 1.5);
        let (idx, w) = m.weights_at(x, &mut s);
        if let Location::Inside { .. } = m.locate(x, &mut s.clone()) {
            let v: f32 = (0..4).map(|i| w[i] * f(m.positions[idx[i] as usize])).sum();
            assert!((v - f(x)).abs() < 1e-4, "{v} vs {}", f(x));
        }
    }
}

/// Brute-force closest point over all hull triangles.
fn brute_closest(m: &TetMesh, p: Vec3) -> f32 {
    (0..m.hull.len() as u32)
        .map(|h| (p.as_dvec3() - m.closest_in_face(p, h).1).length() as f32)
        .fold(f32::INFINITY, f32::min)
}

#[test]
fn outside_points_use_the_closest_hull_point() {
    // A box (convex hull required: the mesh must tetrahedralize a convex set).
    let (p, t, n) = kuhn(5, 1.0, Vec3::ZERO, &|_| Vec3::ZERO);
    let p = p
        .into_iter()
        .map(|v| v * Vec3::new(1.0, 0.5, 2.0))
        .collect();
    let m = TetMesh::new(p, t, n).unwrap();
    let mut rng = Lcg(5);
    let mut s = WalkState::new();
    let mut outside = 0;
    for _ in 0..3000 {
        let p = rng.v(-6.0, 10.0);
        if let Location::Outside {
            probes,
            weights,
            closest,
            ..
        } = m.locate(p, &mut s)
        {
            outside += 1;
            let d = (p - closest).length();
            let b = brute_closest(&m, p);
            assert!(
                (d - b).abs() <= 1e-4 * (1.0 + b),
                "descent {d} vs brute force {b} at {p}"
            );
            let rec: Vec3 = (0..3)
                .map(|i| m.positions[probes[i] as usize] * weights[i])
                .sum();
            assert!((rec - closest).length() < 1e-4);
            assert!(weights.iter().all(|&w| w >= 0.0));
            assert!((weights.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        }
    }
    assert!(outside > 1000);
}

/// Interpolates a smooth-ish per-probe payload (a hash-free function of the
/// probe index, deliberately non-linear in position) at `p`.
fn payload_at(m: &TetMesh, p: Vec3, s: &mut WalkState) -> f32 {
    let (idx, w) = m.weights_at(p, s);
    (0..4).map(|i| w[i] * ((idx[i] as f32) * 0.37).sin()).sum()
}

#[test]
fn lighting_is_continuous_across_the_hull() {
    let m = grid_mesh(5);
    let mut rng = Lcg(6);
    let eps = 1e-4f32;
    for _ in 0..300 {
        // A random line through the box; march it in small steps and look for
        // jumps bigger than the Lipschitz bound (payload range 2 over ~eps).
        let a = rng.v(-3.0, 7.0);
        let dir = (rng.v(-1.0, 1.0)).normalize_or(Vec3::X);
        let mut s = WalkState::new();
        // Find hull crossings by bisection on inside/outside along the line.
        let inside = |x: Vec3, s: &mut WalkState| matches!(m.locate(x, s), Location::Inside { .. });
        let mut prev_t = -8.0f32;
        let mut prev_in = inside(a + dir * prev_t, &mut s);
        let mut t = prev_t;
        while t < 8.0 {
            t += 0.25;
            let now_in = inside(a + dir * t, &mut s);
            if now_in != prev_in {
                let (mut lo, mut hi) = (prev_t, t);
                for _ in 0..40 {
                    let mid = 0.5 * (lo + hi);
                    if inside(a + dir * mid, &mut s) == prev_in {
                        lo = mid
                    } else {
                        hi = mid
                    }
                }
                let x = a + dir * (0.5 * (lo + hi));
                let v0 = payload_at(&m, x - dir * eps, &mut s);
                let v1 = payload_at(&m, x + dir * eps, &mut s);
                // Weights are 1-Lipschitz-ish in units of 1/edge length (1 m);
                // a jump would be O(1).
                assert!((v0 - v1).abs() < 50.0 * eps, "jump {v0} -> {v1} at {x}");
                let w0 = m.weights_at(x - dir * eps, &mut s);
                let w1 = m.weights_at(x + dir * eps, &mut s);
                // Same blend: per-probe total weights agree to O(eps).
                let mut acc: HashMap<u32, f32> = HashMap::new();
                for i in 0..4 {
                    *acc.entry(w0.0[i]).or_default() += w0.1[i];
                    *acc.entry(w1.0[i]).or_default() -= w1.1[i];
                }
                assert!(acc.values().all(|d| d.abs() < 50.0 * eps), "{w0:?} {w1:?}");
            }
            prev_t = t;
            prev_in = now_in;
        }
    }
}

#[test]
fn coherent_batch_matches_cold_queries() {
    let m = grid_mesh(6);
    let pts: Vec<Vec3> = (0..500)
        .map(|i| Vec3::new(0.3 + i as f32 * 0.011, 2.5, 2.5 + (i as f32 * 0.1).sin()))
        .collect();
    let mut out = Vec::new();
    m.locate_many(&pts, &mut WalkState::new(), &mut out);
    assert_eq!(out.len(), pts.len());
    for (p, l) in pts.iter().zip(&out) {
        let (a, b) = (m.locate(*p, &mut WalkState::new()), *l);
        let w = |l: Location| match l {
            Location::Inside { tet, weights } => (0..4)
                .map(|i| m.positions[m.tets[tet as usize][i] as usize] * weights[i])
                .sum::<Vec3>(),
            Location::Outside { closest, .. } => closest,
        };
        assert!((w(a) - w(b)).length() < 1e-5, "{p}: {a:?} vs {b:?}");
    }
}

#[test]
fn invalid_meshes_are_typed_errors() {
    let (p, t, n) = kuhn(3, 1.0, Vec3::ZERO, &|_| Vec3::ZERO);
    assert_eq!(
        TetMesh::new(p.clone(), vec![], vec![]),
        Err(CloudError::Empty)
    );
    let mut bad = t.clone();
    bad[3][2] = 999;
    assert!(matches!(
        TetMesh::new(p.clone(), bad, n.clone()),
        Err(CloudError::VertexOutOfRange {
            tet: 3,
            probe: 999,
            ..
        })
    ));
    let mut bn = n.clone();
    let (i, _) = bn[0].iter().enumerate().find(|(_, &x)| x != HULL).unwrap();
    bn[0][i] = HULL;
    assert!(matches!(
        TetMesh::new(p.clone(), t.clone(), bn),
        Err(CloudError::NeighborMismatch { .. })
    ));
    let mut bn = n.clone();
    bn[1][0] = 12345;
    assert!(matches!(
        TetMesh::new(p.clone(), t.clone(), bn),
        Err(CloudError::NeighborOutOfRange { .. } | CloudError::NeighborMismatch { .. })
    ));
    let mut bp = p.clone();
    bp[4] = Vec3::new(f32::NAN, 0.0, 0.0);
    assert_eq!(
        TetMesh::new(bp, t.clone(), n.clone()),
        Err(CloudError::NonFinitePosition { index: 4 })
    );
    // A flat tetrahedron.
    let flat = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)];
    assert_eq!(
        TetMesh::new(flat, vec![[0, 1, 2, 3]], vec![[HULL; 4]]),
        Err(CloudError::DegenerateTet { tet: 0 })
    );
    assert!(matches!(
        TetMesh::new(p, t.clone(), n[..3].to_vec()),
        Err(CloudError::LengthMismatch { .. })
    ));
}

/// A cloud on the `k` Kuhn grid, L1, with probe `i`'s DC radiance
/// `dc(i)` (grey) and pseudo-random higher bands.
fn grey_cloud(k: u32, dc: &dyn Fn(usize) -> f32) -> ProbeCloud {
    let mesh = grid_mesh(k);
    let mut g = Lcg(7);
    let coeffs: Vec<Vec3> = (0..mesh.positions().len())
        .flat_map(|i| {
            let mut c = vec![Vec3::splat(dc(i))];
            c.extend((0..3).map(|_| g.v(-0.1, 0.1)));
            c
        })
        .collect();
    ProbeCloud::new(mesh, 2, coeffs).unwrap()
}

/// Brightness weighting at α = 1 blends the probes' mean irradiance to the
/// weighted harmonic mean `(Σ b_i/Ē_i)⁻¹` (computed here from the
/// barycentric weights alone); at α = 0 the weights are barycentric, and
/// with equal probes they are barycentric whatever α.
#[test]
fn brightness_weighting_blends_the_harmonic_mean() {
    let dc = |i: usize| 0.05 + (i * 37 % 11) as f32;
    let mut cloud = grey_cloud(2, &dc);
    let mut g = Lcg(3);
    let mut ws = WalkState::new();
    for _ in 0..200 {
        let p = g.v(0.01, 1.99);
        let (idx, bary) = cloud.mesh().weights_at(p, &mut ws);
        cloud.set_brightness_weighting(0.0).unwrap();
        let (i0, w0) = cloud.weights_at(p, &mut ws);
        assert_eq!((i0, w0), (idx, bary));
        cloud.set_brightness_weighting(1.0).unwrap();
        let (i1, w1) = cloud.weights_at(p, &mut ws);
        assert_eq!(i1, idx);
        assert!((w1.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        let blended: f32 = (0..4).map(|k| w1[k] * dc(idx[k] as usize)).sum();
        let inv: f32 = (0..4)
            .filter(|&k| bary[k] > 0.0)
            .map(|k| bary[k] / dc(idx[k] as usize))
            .sum();
        assert!(
            (blended - 1.0 / inv).abs() <= 1e-4 * blended,
            "{p}: {blended} vs harmonic {}",
            1.0 / inv
        );
    }
    let mut same = grey_cloud(2, &|_| 2.0);
    same.set_brightness_weighting(2.5).unwrap();
    for _ in 0..50 {
        let p = g.v(0.01, 1.99);
        let (_, bary) = same.mesh().weights_at(p, &mut ws);
        let (_, w) = same.weights_at(p, &mut ws);
        for k in 0..4 {
            assert!((w[k] - bary[k]).abs() < 1e-5, "{p}: {w:?} vs {bary:?}");
        }
    }
}

/// A black probe (DC 0) is floored, not divided by: finite weights that sum
/// to 1; out-of-range exponents are typed errors and change nothing.
#[test]
fn brightness_weighting_floors_black_probes_and_refuses_bad_exponents() {
    let mut cloud = grey_cloud(2, &|i| if i % 2 == 0 { 0.0 } else { 1.0 });
    cloud.set_brightness_weighting(1.0).unwrap();
    let mut ws = WalkState::new();
    let mut g = Lcg(11);
    for _ in 0..100 {
        let (_, w) = cloud.weights_at(g.v(0.01, 1.99), &mut ws);
        assert!(w.iter().all(|x| x.is_finite() && *x >= 0.0), "{w:?}");
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5);
    }
    for bad in [-0.5, f32::NAN, 4.5, f32::INFINITY] {
        assert!(matches!(
            cloud.set_brightness_weighting(bad),
            Err(ProbeCloudError::BrightnessExponent(_))
        ));
        assert_eq!(cloud.brightness_weighting(), 1.0);
    }
}

/// Fitted probe weights: the blend is `b_i·s_i / Σ b_j·s_j` (checked
/// against the mesh's barycentric weights, summed here), all-ones weights
/// are the plain blend bit for bit, equal probes are reproduced whatever the
/// weights, the weights can be switched off, and bad weights are typed
/// errors that change nothing.
#[test]
fn probe_weights_multiply_the_barycentric_weights() {
    let dc = |i: usize| 0.5 + (i * 13 % 7) as f32;
    let mut cloud = grey_cloud(3, &dc);
    let n = cloud.probe_count();
    let s: Vec<f32> = (0..n).map(|i| 0.01 + (i * 29 % 17) as f32 * 0.7).collect();
    let mut g = Lcg(5);
    let mut ws = WalkState::new();
    let pts: Vec<Vec3> = (0..300).map(|_| g.v(0.01, 3.99)).collect();
    let plain: Vec<_> = pts.iter().map(|&p| cloud.weights_at(p, &mut ws)).collect();
    cloud.set_probe_weights(Some(vec![1.0; n])).unwrap();
    for (p, want) in pts.iter().zip(&plain) {
        assert_eq!(cloud.weights_at(*p, &mut ws), *want);
    }
    cloud.set_probe_weights(Some(s.clone())).unwrap();
    assert!(cloud.probe_weighting_enabled());
    for &p in &pts {
        let (idx, bary) = cloud.mesh().weights_at(p, &mut ws);
        let (i, w) = cloud.weights_at(p, &mut ws);
        assert_eq!(i, idx);
        let sum: f32 = (0..4).map(|k| bary[k] * s[idx[k] as usize]).sum();
        for k in 0..4 {
            let want = bary[k] * s[idx[k] as usize] / sum;
            assert!(
                (w[k] - want).abs() < 1e-5,
                "{p}: {w:?}, want slot {k} {want}"
            );
        }
    }
    cloud.set_probe_weighting(false);
    for (p, want) in pts.iter().zip(&plain) {
        assert_eq!(cloud.weights_at(*p, &mut ws), *want);
    }
    cloud.set_probe_weighting(true);
    // Equal probes are reproduced exactly, whatever the weights.
    let one = [
        Vec3::splat(2.0),
        Vec3::new(0.1, -0.2, 0.3),
        Vec3::splat(-0.05),
        Vec3::X,
    ];
    let mut same = ProbeCloud::new(grid_mesh(3), 2, one.repeat(n)).unwrap();
    same.set_probe_weights(Some(s.clone())).unwrap();
    for &p in &pts[..50] {
        for nrm in [Vec3::Y, -Vec3::X, Vec3::new(0.6, 0.0, 0.8)] {
            let want = probekit_sh::irradiance(&one, nrm);
            let e = same.irradiance(p, nrm, &mut ws);
            assert!((e - want).abs().max_element() < 1e-5, "{p}: {e} vs {want}");
        }
    }
    // Bad weights.
    for bad in [
        vec![1.0; n - 1],
        {
            let mut v = vec![1.0; n];
            v[3] = 0.0;
            v
        },
        {
            let mut v = vec![1.0; n];
            v[5] = f32::NAN;
            v
        },
        {
            let mut v = vec![1.0; n];
            v[0] = 2e6;
            v
        },
        {
            let mut v = vec![1.0; n];
            v[1] = -1.0;
            v
        },
    ] {
        assert!(matches!(
            cloud.set_probe_weights(Some(bad)),
            Err(ProbeCloudError::ProbeWeights { .. })
        ));
        assert_eq!(cloud.probe_weights(), Some(&s[..]));
    }
    cloud.set_probe_weights(None).unwrap();
    assert!(!cloud.probe_weighting_enabled());
}

/// With probe weights the blend is continuous across every interior face:
/// just inside either cell, the weights of the face's three probes agree
/// and the fourth's vanish.
#[test]
fn probe_weights_keep_the_blend_continuous_across_faces() {
    let mut cloud = grey_cloud(3, &|i| 1.0 + i as f32);
    let n = cloud.probe_count();
    cloud
        .set_probe_weights(Some((0..n).map(|i| 0.05 + (i * 7 % 5) as f32).collect()))
        .unwrap();
    let mesh = cloud.mesh().clone();
    let pos = mesh.positions();
    let mut g = Lcg(9);
    let mut ws = WalkState::new();
    let mut checked = 0;
    for (t, (tet, nb)) in mesh.tets().iter().zip(mesh.neighbors()).enumerate() {
        for (f, &n) in nb.iter().enumerate() {
            if n == HULL {
                continue;
            }
            let face: Vec<u32> = (0..4).filter(|&k| k != f).map(|k| tet[k]).collect();
            // A random point of the face, and its normal offset both ways.
            let (a, b) = (g.f(), g.f());
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let [p0, p1, p2] = [0, 1, 2].map(|k| pos[face[k] as usize]);
            let q = p0 + a * (p1 - p0) + b * (p2 - p0);
            let nrm = (p1 - p0).cross(p2 - p0).normalize() * 1e-4;
            let blend = |p: Vec3, ws: &mut WalkState| {
                let (i, w) = cloud.weights_at(p, ws);
                let mut m = HashMap::new();
                for k in 0..4 {
                    *m.entry(i[k]).or_insert(0.0f32) += w[k];
                }
                m
            };
            let (x, y) = (blend(q + nrm, &mut ws), blend(q - nrm, &mut ws));
            for v in &face {
                let (wx, wy) = (
                    x.get(v).copied().unwrap_or(0.0),
                    y.get(v).copied().unwrap_or(0.0),
                );
                assert!(
                    (wx - wy).abs() < 2e-3,
                    "tet {t} face {f} probe {v}: {wx} vs {wy}"
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 100, "{checked}");
}

/// A cloud on the `k` Kuhn grid, L2, probe `i`'s coefficients from `sh(i)`.
fn l2_cloud(k: u32, sh: &dyn Fn(usize, Vec3) -> [Vec3; 9]) -> ProbeCloud {
    let mesh = grid_mesh(k);
    let coeffs: Vec<Vec3> = mesh
        .positions()
        .iter()
        .enumerate()
        .flat_map(|(i, &p)| sh(i, p))
        .collect();
    ProbeCloud::new(mesh, 3, coeffs).unwrap()
}

/// Positive-irradiance L2 SH whose light comes more from `+x` the larger
/// `lobe` (pseudo-random small higher bands from `seed`).
fn lit_from_x(dc: f32, lobe: f32, seed: u64) -> [Vec3; 9] {
    let mut g = Lcg(seed);
    let mut c: [Vec3; 9] = core::array::from_fn(|_| g.v(-0.03, 0.03));
    c[0] = Vec3::new(dc, 0.9 * dc, 0.8 * dc);
    // Y1,1 = −0.4886·x: a negative coefficient brightens +x.
    c[3] = Vec3::splat(-lobe);
    c
}

/// Directional brightness, against an independent computation of its
/// definition: at the twelve icosahedron vertices (built here from `φ`),
/// each probe's irradiance (`probekit_sh::irradiance`), weights `w_k`
/// times `(L_k(d)/(t·r))^−γ` where a probe is brighter than `t` times the
/// cell's weighted harmonic mean `r`, renormalized, the blend projected with
/// `probekit_sh::basis::eval_basis` and divided by the band factors. Also:
/// `γ = 0` is the plain blend; equal probes are kept; an error on a bad
/// exponent.
#[test]
fn directional_brightness_blends_per_direction_and_projects() {
    let sh = |i: usize, p: Vec3| lit_from_x(1.0 + p.y, 0.2 + 0.6 * (i % 3) as f32, i as u64);
    let mut cloud = l2_cloud(3, &sh);
    let mut g = Lcg(21);
    let mut ws = WalkState::new();
    let pts: Vec<Vec3> = (0..60).map(|_| g.v(0.01, 1.99)).collect();
    let plain: Vec<[Vec3; 9]> = pts
        .iter()
        .map(|&p| {
            let mut o = [Vec3::ZERO; 9];
            cloud.sh_at(p, &mut ws, &mut o);
            o
        })
        .collect();
    for bad in [-0.1, f32::NAN, 4.5] {
        assert!(matches!(
            cloud.set_directional_brightness(bad),
            Err(ProbeCloudError::BrightnessExponent(_))
        ));
    }
    assert_eq!(cloud.directional_brightness(), 0.0);
    let phi = (1.0 + 5f64.sqrt()) / 2.0;
    let mut dirs = Vec::new();
    for a in [-1.0, 1.0] {
        for b in [-1.0, 1.0] {
            dirs.push(DVec3::new(0.0, a, b * phi).normalize().as_vec3());
            dirs.push(DVec3::new(a, b * phi, 0.0).normalize().as_vec3());
            dirs.push(DVec3::new(b * phi, 0.0, a).normalize().as_vec3());
        }
    }
    for gamma in [0.0f32, 0.25, 0.7] {
        cloud.set_directional_brightness(gamma).unwrap();
        for (j, &p) in pts.iter().enumerate() {
            let mut got = [Vec3::ZERO; 9];
            cloud.sh_at(p, &mut ws, &mut got);
            let (idx, w) = cloud.weights_at(p, &mut ws);
            let mut want = [Vec3::ZERO; 9];
            for &d in &dirs {
                let e: Vec<Vec3> = idx
                    .iter()
                    .map(|&i| probekit_sh::irradiance(cloud.probe_sh(i as usize), d))
                    .collect();
                let lum: Vec<f32> = e.iter().map(|x| probekit_sh::LUMINANCE.dot(*x)).collect();
                let top = (0..4)
                    .filter(|&k| w[k] > 0.0)
                    .map(|k| lum[k])
                    .fold(0.0, f32::max);
                let l: Vec<f32> = lum.iter().map(|x| x.max(1e-3 * top)).collect();
                let used: Vec<usize> = (0..4).filter(|&k| w[k] > 0.0).collect();
                let harmonic = used.iter().map(|&k| w[k]).sum::<f32>()
                    / used.iter().map(|&k| w[k] / l[k]).sum::<f32>();
                let t = directional::DIRECTIONAL_RATIO * harmonic;
                let u: Vec<f32> = (0..4)
                    .map(|k| {
                        w[k] * if l[k] > t {
                            (l[k] / t).powf(-gamma)
                        } else {
                            1.0
                        }
                    })
                    .collect();
                let sum: f32 = u.iter().sum();
                let blend: Vec3 = (0..4).map(|k| e[k] * (u[k] / sum)).sum();
                let mut y = [0.0f32; 9];
                probekit_sh::basis::eval_basis(3, d, &mut y);
                for c in 0..9 {
                    let l = if c == 0 {
                        0
                    } else if c < 4 {
                        1
                    } else {
                        2
                    };
                    let a = probekit_sh::clamped_cosine_band(l) as f32;
                    want[c] += blend * (y[c] * 4.0 * std::f32::consts::PI / 12.0 / a);
                }
            }
            for c in 0..9 {
                assert!(
                    (got[c] - want[c]).length() < 1e-4 * (1.0 + want[c].length()),
                    "γ {gamma} {p} coeff {c}: {:?} vs {:?}",
                    got[c],
                    want[c]
                );
                if gamma == 0.0 {
                    assert!((got[c] - plain[j][c]).length() < 1e-5);
                }
            }
        }
    }
    // Equal probes: the blend is that probe, whatever γ.
    let mut same = l2_cloud(3, &|_, _| lit_from_x(1.0, 0.7, 3));
    same.set_directional_brightness(1.0).unwrap();
    let want = lit_from_x(1.0, 0.7, 3);
    for &p in &pts {
        let mut o = [Vec3::ZERO; 9];
        same.sh_at(p, &mut ws, &mut o);
        for c in 0..9 {
            assert!((o[c] - want[c]).length() < 1e-5, "{p} {c}");
        }
    }
}

/// The leak it is for: a probe lit strongly from `+x` beside dark probes
/// (a doorway probe seeing a lit corridor). Directional brightness lowers
/// the blended irradiance facing `+x` far more than facing `−x`, where the
/// probes agree; relighting in place scales the blend linearly (the
/// directional brightness is the baked one), and the result is
/// continuous across every interior face.
#[test]
fn directional_brightness_damps_a_probe_bright_towards_one_side() {
    let bright = 13; // the centre probe (1, 1, 1) of the 3 × 3 × 3 grid
                     // Grey; facing −x the bright probe's irradiance equals the dark ones'
                     // (0.886·dc − 1.023·lobe = 0.266), facing +x it is 7.5× theirs.
    let sh = |i: usize, _: Vec3| {
        let mut c = [Vec3::ZERO; 9];
        if i == bright {
            c[0] = Vec3::splat(1.279);
            c[3] = Vec3::splat(-0.848);
        } else {
            c[0] = Vec3::splat(0.3);
        }
        c
    };
    let mut cloud = l2_cloud(3, &sh);
    assert_eq!(cloud.mesh().positions()[bright], Vec3::ONE);
    let mut ws = WalkState::new();
    // A point whose cell weighs the bright probe 0.3 (and two dark ones
    // 0.5 and 0.2).
    let p = Vec3::new(1.2, 1.7, 1.7);
    let e0 = [Vec3::X, -Vec3::X].map(|n| cloud.irradiance(p, n, &mut ws).x);
    cloud.set_directional_brightness(1.0).unwrap();
    let e1 = [Vec3::X, -Vec3::X].map(|n| cloud.irradiance(p, n, &mut ws).x);
    let drop = [0, 1].map(|k| (e0[k] - e1[k]) / e0[k]);
    assert!(
        drop[0] > 0.2 && drop[0] > 3.0 * drop[1].abs(),
        "{e0:?} → {e1:?}"
    );
    // Relit ×3 in place: ×3 out, same blend.
    let mut relit = cloud.clone();
    relit.coefficients_mut().iter_mut().for_each(|c| *c *= 3.0);
    for n in [Vec3::X, Vec3::Y, -Vec3::Z] {
        let (a, b) = (
            cloud.irradiance(p, n, &mut ws),
            relit.irradiance(p, n, &mut ws),
        );
        assert!((b - 3.0 * a).length() < 1e-4 * b.length(), "{a} {b}");
    }
    // Continuous across every interior face: just inside either cell, the
    // same SH (the fourth probe's weight, and with it its share of the
    // cell's harmonic mean, goes to 0 at the face).
    let mesh = cloud.mesh().clone();
    let pos = mesh.positions();
    let mut g = Lcg(4);
    let mut checked = 0;
    for (tet, nb) in mesh.tets().iter().zip(mesh.neighbors()) {
        for (f, &n) in nb.iter().enumerate() {
            if n == HULL {
                continue;
            }
            let face: Vec<Vec3> = (0..4)
                .filter(|&k| k != f)
                .map(|k| pos[tet[k] as usize])
                .collect();
            let (a, b) = (g.f(), g.f());
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let q = face[0] + a * (face[1] - face[0]) + b * (face[2] - face[0]);
            let off = (face[1] - face[0]).cross(face[2] - face[0]).normalize() * 1e-4;
            let mut x = [Vec3::ZERO; 9];
            let mut y = [Vec3::ZERO; 9];
            cloud.sh_at(q + off, &mut ws, &mut x);
            cloud.sh_at(q - off, &mut ws, &mut y);
            for c in 0..9 {
                assert!(
                    (x[c] - y[c]).length() < 2e-3 * (0.1 + x[0].length()),
                    "face {f} at {q}: coeff {c} {} vs {}",
                    x[c],
                    y[c]
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 50, "{checked}");
}

/// One tetrahedron (the unit corner), grey DC-only probes of radiance
/// `dc`, and cell visibility at `k` = 1 in which probe `i` sees the
/// lattice point of numerators `n` (1 at the cell's corner it stands on)
/// when `sees(i, n)`.
fn one_tet_with_visibility(dc: [f32; 4], sees: &dyn Fn(u32, [u32; 4]) -> bool) -> ProbeCloud {
    use super::cell_visibility::{lattice_numerators, record_from};
    let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
    let tets = vec![[0, 1, 2, 3]];
    let mesh = TetMesh::new(positions, tets.clone(), neighbours(&tets)).unwrap();
    let record = |probes: &[u32]| {
        let lattice = lattice_numerators(probes.len(), 1);
        record_from(probes.len(), 1, |v, j| sees(probes[v], lattice[j]))
    };
    let faces = mesh.hull_face_count();
    let mut data = record(&tets[0]);
    for h in 0..faces as u32 {
        data.extend(record(&mesh.hull_face_probes(h).unwrap()));
    }
    let cells = CellVisibility::new(1, 1, faces, data).unwrap();
    let coeffs = dc.iter().map(|&c| Vec3::splat(c)).collect();
    let mut cloud = ProbeCloud::new(mesh, 1, coeffs).unwrap();
    cloud.set_cell_visibility_bits(Some(cells)).unwrap();
    cloud
}

/// Where cell visibility hides every probe of positive weight, the blend
/// does not fall back to the plain weights (the light from behind the
/// wall) but to the cell's darkest probe alone: inside the tetrahedron
/// where no probe sees the point (probe 1, by construction); beyond the
/// hull where the closest point is on the edge of probes 0 and 1, both
/// hidden, even though the face's third probe sees the point (its bits are
/// too coarse to trust there); beyond the face of probes 1, 2 and 3, which
/// does not hold the darker probe 0 (an outer cell's unused slot, which
/// names probe 0, is never chosen). Where some probe of positive weight
/// sees the point, the visible ones are renormalized in their barycentric
/// proportions, as before.
#[test]
fn a_cell_that_hides_every_weighted_probe_falls_back_to_its_darkest_probe() {
    let mut ws = WalkState::new();
    let dark = one_tet_with_visibility([3.0, 1.0, 4.0, 2.0], &|_, _| false);
    let mut g = Lcg(11);
    for _ in 0..50 {
        let a = g.v(0.02, 0.3);
        let (idx, w) = dark.weights_at(a, &mut ws);
        assert_eq!(idx, [0, 1, 2, 3]);
        assert_eq!(w, [0.0, 1.0, 0.0, 0.0], "{a}");
    }
    let far = one_tet_with_visibility([3.0, 1.0, 4.0, 2.0], &|i, _| i >= 2);
    let p = Vec3::new(0.5, -1.0, -1.0);
    let (_, bary) = far.mesh().weights_at(p, &mut ws);
    let (idx, w) = far.weights_at(p, &mut ws);
    for k in 0..4 {
        if k < 3 && idx[k] < 2 {
            assert!((bary[k] - 0.5).abs() < 1e-5, "{idx:?} {bary:?}");
        }
        let expect = if k < 3 && idx[k] == 1 { 1.0 } else { 0.0 };
        assert_eq!(w[k], expect, "{idx:?} {w:?}");
    }
    // Probes 2 and 3 see an interior point: their barycentric shares.
    let q = Vec3::new(0.1, 0.2, 0.3);
    let (_, w) = far.weights_at(q, &mut ws);
    assert!(w[0] == 0.0 && w[1] == 0.0, "{w:?}");
    assert!(
        (w[2] - 0.4).abs() < 1e-5 && (w[3] - 0.6).abs() < 1e-5,
        "{w:?}"
    );
    // Beyond the slanted face (probes 1, 2, 3): probe 2 is its darkest.
    let slant = one_tet_with_visibility([0.5, 3.0, 2.0, 4.0], &|_, _| false);
    let (idx, w) = slant.weights_at(Vec3::splat(1.0), &mut ws);
    let mut face = [idx[0], idx[1], idx[2]];
    face.sort_unstable();
    assert_eq!(face, [1, 2, 3]);
    for k in 0..4 {
        let expect = if k < 3 && idx[k] == 2 { 1.0 } else { 0.0 };
        assert_eq!(w[k], expect, "{idx:?} {w:?}");
    }
}

/// Below [`HIDDEN_MASS_FLOOR`] of visible barycentric weight the blend moves
/// linearly from the renormalized visible probes to the darkest probe. Here
/// probe 3 sees only the lattice point at its own corner, so its cell
/// visibility at `k` = 1 is its barycentric weight `b₃` (= z in the unit
/// corner tetrahedron) and the visible mass `b₃²`; the others see nothing.
/// Against the closed form: `t = b₃² / floor` on probe 3 and `1 − t` on the
/// darkest, probe 1, below the floor, all on probe 3 above it — continuous
/// across the floor and into the fallback at z = 0.
#[test]
fn little_visible_weight_blends_towards_the_darkest_probe() {
    let cloud = one_tet_with_visibility([3.0, 1.0, 4.0, 2.0], &|i, n| i == 3 && n[3] == 1);
    let mut ws = WalkState::new();
    let mut last = None;
    for s in 1..=80 {
        let z = s as f32 * 0.008;
        let (idx, w) = cloud.weights_at(Vec3::new(0.1, 0.1, z), &mut ws);
        assert_eq!(idx, [0, 1, 2, 3]);
        let t = (z * z / HIDDEN_MASS_FLOOR).min(1.0);
        let expect = [0.0, 1.0 - t, 0.0, t];
        for k in 0..4 {
            assert!(
                (w[k] - expect[k]).abs() < 1e-4,
                "z {z}: {w:?} vs {expect:?}"
            );
        }
        // Steps of 0.008 in z move the weights by at most 2·0.64·0.008/0.1.
        if let Some(prev) = last.replace(w[3]) {
            assert!((w[3] - prev).abs() <= 0.11, "z {z}: jump {prev} → {}", w[3]);
        }
    }
}
