//! Tests of the cell-visibility lattice, its interpolation and storage.

use super::lattice::lattice_index;
use super::*;
use glam::Vec3;
use proptest::prelude::*;

/// Barycentric numerators → the lattice point's barycentric coordinates.
fn bary_of(n: &[u32; 4], k: u32) -> [f32; 4] {
    n.map(|v| v as f32 / k as f32)
}

#[test]
fn lattice_indices_enumerate_every_point_once_in_order() {
    for vertices in [3, 4] {
        for k in 1..=MAX_CELL_SUBDIVISION {
            let pts = lattice_numerators(vertices, k);
            assert_eq!(pts.len(), lattice_len(vertices, k));
            for (i, n) in pts.iter().enumerate() {
                assert_eq!(n.iter().sum::<u32>(), k);
                let c = [n[0], n[0] + n[1], n[0] + n[1] + n[2]];
                assert_eq!(lattice_index(vertices, c), i, "{vertices} {k} {n:?}");
            }
        }
    }
}

#[test]
fn kuhn_weights_reproduce_the_lattice_point_at_lattice_points() {
    for vertices in [3usize, 4] {
        for k in 1..=5 {
            for (i, n) in lattice_numerators(vertices, k).iter().enumerate() {
                let b = bary_of(n, k);
                let (idx, w) = kuhn_weights(&b[..vertices], k);
                let got: f32 = (0..4).filter(|&j| idx[j] == i).map(|j| w[j]).sum();
                assert!(
                    (got - 1.0).abs() < 1e-5,
                    "{vertices} {k} {n:?}: {idx:?} {w:?}"
                );
            }
        }
    }
}

proptest! {
    /// Piecewise-linear interpolation reproduces any affine function of
    /// the position exactly: the sub-simplex's weights are barycentric
    /// coordinates of the point in it (checked against the lattice
    /// points' own coordinates, an independent reconstruction).
    #[test]
    fn kuhn_weights_are_barycentric_in_the_sub_simplex(
        raw in prop::array::uniform4(0.0f32..1.0),
        k in 1u32..=MAX_CELL_SUBDIVISION,
        tri in any::<bool>(),
    ) {
        let vertices = if tri { 3 } else { 4 };
        let s: f32 = raw[..vertices].iter().sum::<f32>().max(1e-3);
        let mut b = [0.0f32; 4];
        for j in 0..vertices { b[j] = raw[j] / s; }
        let (idx, w) = kuhn_weights(&b[..vertices], k);
        let pts = lattice_numerators(vertices, k);
        prop_assert!(w.iter().all(|&x| x >= -1e-6));
        prop_assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        let mut rec = [0.0f32; 4];
        for j in 0..vertices {
            let lb = bary_of(&pts[idx[j]], k);
            for (r, l) in rec.iter_mut().zip(lb) { *r += w[j] * l; }
        }
        for j in 0..vertices {
            prop_assert!((rec[j] - b[j]).abs() < 1e-4, "{b:?} -> {rec:?}");
        }
    }

    /// On a face of a tetrahedron (one coordinate 0) the interpolation
    /// only uses lattice points of that face, with the weights the hull
    /// face (triangle) interpolation gives the same point — the
    /// continuity argument of the module docs.
    #[test]
    fn tetrahedron_faces_interpolate_like_triangles(
        raw in prop::array::uniform3(0.0f32..1.0),
        k in 1u32..=MAX_CELL_SUBDIVISION,
        missing in 0usize..4,
    ) {
        let s: f32 = raw.iter().sum::<f32>().max(1e-3);
        let tri_b = raw.map(|x| x / s);
        let mut b = [0.0f32; 4];
        let mut j = 0;
        for (v, x) in b.iter_mut().enumerate() {
            if v != missing { *x = tri_b[j]; j += 1; }
        }
        // Both as maps from face-lattice numerators to weights.
        let pts4 = lattice_numerators(4, k);
        let pts3 = lattice_numerators(3, k);
        let (i4, w4) = kuhn_weights(&b, k);
        let (i3, w3) = kuhn_weights(&tri_b, k);
        let mut m4: Vec<([u32; 3], f32)> = Vec::new();
        for j in 0..4 {
            if w4[j] <= 1e-6 { continue; }
            let n = pts4[i4[j]];
            prop_assert_eq!(n[missing], 0, "a point off the face has weight");
            let mut f = [0u32; 3];
            let mut t = 0;
            for (v, &x) in n.iter().enumerate() { if v != missing { f[t] = x; t += 1; } }
            m4.push((f, w4[j]));
        }
        for j in 0..3 {
            if w3[j] <= 1e-6 { continue; }
            let n = pts3[i3[j]];
            let f = [n[0], n[1], n[2]];
            let got: f32 = m4.iter().filter(|(g, _)| *g == f).map(|(_, w)| *w).sum();
            prop_assert!((got - w3[j]).abs() < 1e-4, "{f:?}: {got} vs {}", w3[j]);
        }
    }
}

#[test]
fn interpolation_reads_each_vertex_bits() {
    // k = 1: the lattice is the corners. Vertex v sees corner j iff v ≤ j.
    let k = 1;
    let pts = lattice_numerators(4, k);
    let rec = record_from(4, k, |v, i| {
        let corner = pts[i].iter().position(|&x| x == 1).unwrap();
        v <= corner
    });
    let cv = CellVisibility::new(k, 1, 0, rec).unwrap();
    let b = [0.1, 0.2, 0.3, 0.4];
    let c = cv.tet(0, &b);
    // Vertex v's visibility is the barycentric mass of corners j ≥ v.
    for v in 0..4 {
        let want: f32 = b[v..].iter().sum();
        assert!((c[v] - want).abs() < 1e-5, "{v}: {} vs {want}", c[v]);
    }
    assert_eq!(cv.tet(7, &b), [1.0; 4]);
    assert!(CellVisibility::new(0, 1, 0, vec![0; 1]).is_none());
    assert!(CellVisibility::new(1, 2, 0, vec![0; 1]).is_none());
}

/// Reads corner `v`'s interpolated bit straight from a dense record.
fn dense_value(record: &[u8], vertices: usize, k: u32, bary: &[f32], v: usize) -> f32 {
    let (idx, w) = kuhn_weights(bary, k);
    (0..vertices)
        .filter(|&j| w[j] > 0.0 && record_sees(record, vertices, k, v, idx[j]))
        .map(|j| w[j])
        .sum()
}

proptest! {
    /// Sparse storage answers every cell as its dense record does
    /// (clear cells 1 everywhere), across many 64-cell rank blocks, and
    /// gives the dense records back.
    #[test]
    fn sparse_storage_answers_like_the_dense_records(
        seed in any::<u64>(),
        k in 1u32..=4,
        tets in 0usize..300,
        hull in 0usize..90,
        raw in prop::array::uniform4(0.01f32..1.0),
    ) {
        let mut state = seed | 1;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut dense = Vec::new();
        let mut clear = 0;
        for (n, count) in [(4usize, tets), (3, hull)] {
            for _ in 0..count {
                let all = next() % 2 == 0;
                clear += usize::from(all);
                dense.extend(record_from(n, k, |_, _| all || next() % 4 != 0));
            }
        }
        let cv = CellVisibility::new(k, tets, hull, dense.clone()).unwrap();
        prop_assert!(cv.record_count() <= tets + hull - clear);
        prop_assert_eq!(cv.first_noncanonical(), None);
        prop_assert_eq!(cv.to_dense(), dense.clone());
        let s: f32 = raw.iter().sum();
        let b4 = raw.map(|x| x / s);
        let s3: f32 = raw[..3].iter().sum();
        let b3 = [raw[0] / s3, raw[1] / s3, raw[2] / s3];
        let (rb4, rb3) = (record_bytes(4, k), record_bytes(3, k));
        for t in 0..tets {
            let rec = &dense[t * rb4..(t + 1) * rb4];
            let got = cv.tet(t as u32, &b4);
            for (v, &g) in got.iter().enumerate() {
                // A clear cell is exactly 1; its all-ones record sums
                // the Kuhn weights, 1 up to rounding.
                let want = dense_value(rec, 4, k, &b4, v);
                prop_assert!((g - want).abs() <= 1e-6, "tet {} v {}: {} {}", t, v, g, want);
            }
        }
        for h in 0..hull {
            let at = tets * rb4 + h * rb3;
            let rec = &dense[at..at + rb3];
            let got = cv.hull_face(h as u32, &b3);
            for (v, &g) in got.iter().enumerate() {
                let want = dense_value(rec, 3, k, &b3, v);
                prop_assert!((g - want).abs() <= 1e-6, "face {} v {}: {} {}", h, v, g, want);
            }
        }
    }
}

#[test]
fn shared_face_points_are_bit_identical_in_both_cells() {
    let pos = [
        Vec3::new(0.1, 0.2, 0.3),
        Vec3::new(1.7, -0.4, 0.9),
        Vec3::new(0.3, 2.1, -1.3),
        Vec3::new(-0.8, 0.5, 1.1),
        Vec3::new(0.9, 0.9, 0.9),
    ];
    // Cells [0,1,2,3] and [4,2,1,0] share face {0,1,2}, listed in other orders.
    let a = [0u32, 1, 2, 3];
    let b = [4u32, 2, 1, 0];
    let k = 5;
    for n in lattice_numerators(4, k).iter().filter(|n| n[3] == 0) {
        // The same barycentric point expressed in b's vertex order.
        let nb = [0, n[2], n[1], n[0]];
        let pa = lattice_position(&a, &pos, n, k);
        let pb = lattice_position(&b, &pos, &nb, k);
        assert_eq!(
            pa.to_array().map(f32::to_bits),
            pb.to_array().map(f32::to_bits)
        );
    }
}
