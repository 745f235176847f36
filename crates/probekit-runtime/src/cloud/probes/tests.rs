//! Tests of [`ProbeCloud`]'s blend on a two-tetrahedron mesh.

use super::*;
use crate::cloud::visibility::VisibilityMaps;
use crate::cloud::HULL;

/// Radiance SH that varies linearly with position: c_k(p) = a_k + B_k·p.
fn field(p: Vec3, k: usize) -> Vec3 {
    let k = k as f32;
    Vec3::new(
        0.5 + 0.1 * k + p.x - 0.3 * p.y,
        1.0 - 0.2 * k + 0.7 * p.z,
        0.25 * k + p.x + p.y + p.z,
    )
}

/// Two tetrahedra sharing the face (1, 2, 3).
fn cloud() -> ProbeCloud {
    let pos = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, Vec3::splat(1.0)];
    let tets = vec![[0, 1, 2, 3], [4, 3, 2, 1]];
    let neighbors = vec![[1, HULL, HULL, HULL], [0, HULL, HULL, HULL]];
    let mesh = TetMesh::new(pos.clone(), tets, neighbors).unwrap();
    let coeffs: Vec<Vec3> = pos
        .iter()
        .flat_map(|&p| (0..9).map(move |k| field(p, k)))
        .collect();
    ProbeCloud::new(mesh, 3, coeffs).unwrap()
}

#[test]
fn reproduces_a_linear_field_inside() {
    let c = cloud();
    let mut st = WalkState::new();
    let mut out = [Vec3::ZERO; 9];
    for p in [
        Vec3::new(0.1, 0.2, 0.3),
        Vec3::new(0.6, 0.6, 0.5),
        Vec3::new(0.25, 0.25, 0.25),
    ] {
        c.sh_at(p, &mut st, &mut out);
        for (k, o) in out.iter().enumerate() {
            assert!((*o - field(p, k)).abs().max_element() < 1e-5, "{p} {k}");
        }
        // Irradiance against a direct cosine-weighted sum over the sphere
        // of the exact field's SH (independent quadrature).
        let n = Vec3::new(0.3, 0.8, -0.52).normalize();
        let exact: Vec<Vec3> = (0..9).map(|k| field(p, k)).collect();
        let mut e = Vec3::ZERO;
        let m = 20_000;
        for i in 0..m {
            let d = probekit_sh::fibonacci_point(i, m);
            let cos = n.dot(d).max(0.0);
            e += probekit_sh::convolve::eval_sh(&exact, d) * cos;
        }
        e *= 4.0 * std::f32::consts::PI / m as f32;
        let got = c.irradiance(p, n, &mut st);
        assert!((got - e).abs().max_element() < 2e-2 * e.abs().max_element().max(1.0));
    }
}

#[test]
fn outside_points_get_hull_values() {
    let c = cloud();
    let mut st = WalkState::new();
    let mut out = [Vec3::ZERO; 9];
    // Below the face z = 0: the closest hull point is (0.2, 0.3, 0).
    c.sh_at(Vec3::new(0.2, 0.3, -2.0), &mut st, &mut out);
    let q = Vec3::new(0.2, 0.3, 0.0);
    for (k, o) in out.iter().enumerate() {
        assert!((*o - field(q, k)).abs().max_element() < 1e-5);
    }
    // Far beyond vertex 0 along (-1,-1,-1): the vertex itself.
    c.sh_at(Vec3::splat(-5.0), &mut st, &mut out);
    for (k, o) in out.iter().enumerate() {
        assert!((*o - field(Vec3::ZERO, k)).abs().max_element() < 1e-5);
    }
}

#[test]
fn visibility_weights_drop_probes_behind_walls_and_renormalize() {
    let mut c = cloud();
    let n = c.probe_count();
    let p = Vec3::new(0.3, 0.35, 0.3);
    let mut st = WalkState::new();
    let (idx, b) = c.mesh().weights_at(p, &mut st);
    // Open space (every first hit 100 m away): weights unchanged.
    let open = VisibilityMaps::new(2, 100.0, vec![[100.0, 10_000.0]; 4 * n]).unwrap();
    c.set_visibility_maps(Some(open)).unwrap();
    let (_, w) = c.weights_at(p, &mut st);
    assert_eq!(w, b);
    // Probe 1 (at +X) sees a surface 0.1 m away in every direction: it
    // no longer lights p (≈ 0.8 m away); the others keep their
    // barycentric ratios, renormalized.
    let mut m = vec![[100.0, 10_000.0]; 4 * n];
    for t in &mut m[4..8] {
        *t = [0.1, 0.01];
    }
    c.set_visibility_maps(Some(VisibilityMaps::new(2, 100.0, m).unwrap()))
        .unwrap();
    let (_, w) = c.weights_at(p, &mut st);
    let k1 = idx.iter().position(|&i| i == 1).unwrap();
    let rest: f32 = (0..4).filter(|&k| k != k1).map(|k| b[k]).sum();
    for k in 0..4 {
        let want = if k == k1 { 0.0 } else { b[k] / rest };
        assert!((w[k] - want).abs() < 1e-3, "{k}: {} vs {want}", w[k]);
    }
    assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
    // Switched off: barycentric again; sh_at follows the weights.
    c.set_visibility(false);
    assert!(!c.visibility_enabled());
    assert_eq!(c.weights_at(p, &mut st).1, b);
    c.set_visibility(true);
    let mut out = [Vec3::ZERO; 9];
    c.sh_at(p, &mut st, &mut out);
    let want: Vec3 = (0..4).map(|k| c.probe_sh(idx[k] as usize)[0] * w[k]).sum();
    assert!((out[0] - want).length() < 1e-5);
}

#[test]
fn files_without_tetrahedra_are_refused() {
    let f = ProbeFile::cloud(vec![Vec3::ZERO], 1, &[Vec3::ONE]).unwrap();
    assert!(matches!(
        ProbeCloud::from_file(&f),
        Err(ProbeCloudError::NoTetrahedra)
    ));
}
