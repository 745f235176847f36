//! Cell visibility: for every tetrahedron (and hull face) of a probe cloud and
//! each of its probes, which points of the cell the probe can see, sampled on
//! a lattice and interpolated piecewise linearly.
//!
//! Distance moments ([`super::visibility`]) judge a point by the depth a probe
//! saw in its direction, averaged over an octahedral texel; where a wall's
//! edge or a grazing wall lies inside the texel the average is far from the
//! depth along the one ray that matters, and a probe behind a corner keeps
//! half its weight. Cell visibility answers the question the blend asks —
//! *does probe `i` of this cell see this point of this cell?* — by tracing
//! it at bake time on a lattice of points of the cell:
//!
//! * The lattice of subdivision `k` holds the points whose barycentric
//!   coordinates in the cell are multiples of `1/k` (the vertices of the
//!   edgewise subdivision of the cell into `k³` tetrahedra, or `k²` triangles
//!   on a hull face): `(k+1)(k+2)(k+3)/6` points per tetrahedron,
//!   `(k+1)(k+2)/2` per hull face.
//! * For each vertex `v` of the cell and each lattice point `q`, one bit: the
//!   segment from probe `v` to `q` crosses no surface.
//! * At run time the point's barycentric coordinates pick the sub-simplex of
//!   the Freudenthal–Kuhn triangulation that contains it (Freudenthal, "Simplizialzerlegungen
//!   von beschränkter Flachheit", Annals of Math. 43, 1942; the edgewise
//!   subdivision of Edelsbrunner & Grayson, "Edgewise Subdivision of a
//!   Simplex", DCG 24, 2000), and each vertex's visibility `c_v(p)` is the
//!   linear interpolation of its bits at the sub-simplex's four lattice
//!   points.
//!
//! The edgewise subdivision of a triangle does not depend on the order of
//! its vertices, the lattice points of a face are the same points in both
//! cells that share it (computed in the same order, see [`lattice_position`])
//! and a vertex not on the face has barycentric weight 0 there, so the
//! blended lighting stays continuous across cell faces, hull faces included.
//!
//! # Storage and bit order
//! A cell's record is `vertices · lattice_len` bits, vertex-major (all
//! lattice points of the cell's vertex 0, then vertex 1, …), least
//! significant bit first, padded with zero bits to whole bytes
//! ([`record_bytes`]). Lattice points are numbered by their cumulative
//! barycentric numerators: with integer numerators `n_0 … n_3` (sum `k`) of
//! the cell's vertices in their stored order, `c_1 = n_0`, `c_2 = n_0 + n_1`,
//! `c_3 = n_0 + n_1 + n_2` (so `c_1 ≤ c_2 ≤ c_3 ≤ k`) and the index is
//! `T(c_3) + T₂(c_2) + c_1` with the tetrahedral numbers
//! `T(m) = m(m+1)(m+2)/6` and triangular numbers `T₂(m) = m(m+1)/2`; a hull
//! face uses `T₂(c_2) + c_1` with `c_1 = n_0`, `c_2 = n_0 + n_1`.

use crate::math;
use crate::prelude::*;
use glam::Vec3;

/// Largest lattice subdivision a file may hold.
pub const MAX_CELL_SUBDIVISION: u32 = 8;

/// Default lattice subdivision: 20 points per tetrahedron, 10 bytes per
/// tetrahedron (about 65 bytes per probe on a Delaunay cloud).
pub const DEFAULT_CELL_SUBDIVISION: u32 = 3;

/// Lattice points of a cell with `vertices` corners (3: hull face, 4:
/// tetrahedron) at subdivision `k`.
pub const fn lattice_len(vertices: usize, k: u32) -> usize {
    let k = k as usize;
    if vertices == 3 {
        (k + 1) * (k + 2) / 2
    } else {
        (k + 1) * (k + 2) * (k + 3) / 6
    }
}

/// Bytes of one cell's record: `vertices · lattice_len` bits rounded up.
pub const fn record_bytes(vertices: usize, k: u32) -> usize {
    (vertices * lattice_len(vertices, k)).div_ceil(8)
}

const fn tri(m: u32) -> usize {
    (m as usize) * (m as usize + 1) / 2
}

const fn tetra(m: u32) -> usize {
    (m as usize) * (m as usize + 1) * (m as usize + 2) / 6
}

/// Index of the lattice point with cumulative numerators `c` (`c[0] ≤ c[1]
/// ≤ c[2]`; `c[2]` unused for hull faces) in a cell with `vertices` corners.
fn lattice_index(vertices: usize, c: [u32; 3]) -> usize {
    if vertices == 3 {
        tri(c[1]) + c[0] as usize
    } else {
        tetra(c[2]) + tri(c[1]) + c[0] as usize
    }
}

/// Barycentric numerators (summing to `k`) of every lattice point of a cell
/// with `vertices` corners, in index order (see the module docs); unused
/// fourth numerator 0 for hull faces.
pub fn lattice_numerators(vertices: usize, k: u32) -> Vec<[u32; 4]> {
    let mut out = Vec::with_capacity(lattice_len(vertices, k));
    if vertices == 3 {
        for c2 in 0..=k {
            for c1 in 0..=c2 {
                out.push([c1, c2 - c1, k - c2, 0]);
            }
        }
    } else {
        for c3 in 0..=k {
            for c2 in 0..=c3 {
                for c1 in 0..=c2 {
                    out.push([c1, c2 - c1, c3 - c2, k - c3]);
                }
            }
        }
    }
    out
}

/// Position of the lattice point with numerators `n` in the cell whose
/// corners are probes `probes` (3 or 4) at `positions`:
/// `Σ (n_i / k)·x_i`, summed in increasing probe index so that cells sharing
/// a face compute bit-identical points on it (terms with `n_i = 0` add an
/// exact zero).
pub fn lattice_position(probes: &[u32], positions: &[Vec3], n: &[u32; 4], k: u32) -> Vec3 {
    let mut order = [0usize, 1, 2, 3];
    let m = probes.len().min(4);
    order[..m].sort_unstable_by_key(|&i| probes[i]);
    let mut p = Vec3::ZERO;
    for &i in &order[..m] {
        p += positions[probes[i] as usize] * (n[i] as f32 / k as f32);
    }
    p
}

/// The Freudenthal–Kuhn sub-simplex of the `k`-subdivided cell that
/// contains the point with barycentric coordinates `bary` (3 or 4 entries,
/// clamped to the cell): its lattice indices and the point's barycentric
/// weights in it (unused fourth slot of a hull face: weight 0).
pub fn kuhn_weights(bary: &[f32], k: u32) -> ([usize; 4], [f32; 4]) {
    let vertices = bary.len().clamp(3, 4);
    let dim = vertices - 1;
    let kf = k.max(1) as f32;
    let top = k.max(1) - 1;
    // Cumulative coordinates, clamped and kept monotonic.
    let mut y = [0.0f32; 3];
    let mut acc = 0.0f32;
    let mut prev = 0.0f32;
    for j in 0..dim {
        acc += bary[j].max(0.0);
        let v = (acc * kf).clamp(prev, kf);
        y[j] = v;
        prev = v;
    }
    let mut base = [0u32; 3];
    let mut f = [0.0f32; 3];
    for j in 0..dim {
        let b = (math::floor(y[j]).max(0.0) as u32).min(top);
        base[j] = b;
        f[j] = (y[j] - b as f32).clamp(0.0, 1.0);
    }
    // Axes by decreasing fractional part; ties step the higher axis first,
    // which keeps the cumulative numerators ordered.
    let mut axes = [0usize, 1, 2];
    let axes = &mut axes[..dim];
    axes.sort_unstable_by(|&a, &b| {
        f[b].partial_cmp(&f[a])
            .unwrap_or(core::cmp::Ordering::Equal)
            .then(b.cmp(&a))
    });
    let mut idx = [0usize; 4];
    let mut w = [0.0f32; 4];
    let mut c = base;
    idx[0] = lattice_index(vertices, c);
    w[0] = 1.0 - f[axes[0]];
    for m in 0..dim {
        c[axes[m]] += 1;
        idx[m + 1] = lattice_index(vertices, c);
        w[m + 1] = if m + 1 < dim {
            f[axes[m]] - f[axes[m + 1]]
        } else {
            f[axes[m]]
        };
    }
    (idx, w)
}

/// Per-cell visibility bits of a probe cloud (see the module docs), ready to
/// weight the blend: `c_v(p)` for each corner of the cell containing `p`.
#[derive(Clone, Debug, PartialEq)]
pub struct CellVisibility {
    k: u32,
    tets: usize,
    hull_faces: usize,
    data: Vec<u8>,
}

impl CellVisibility {
    /// Wraps `data`: `tets` tetrahedron records of [`record_bytes`]`(4, k)`
    /// bytes, then `hull_faces` hull-face records of `record_bytes(3, k)`
    /// bytes, in the mesh's tetrahedron and hull-face order. `None` if `k`
    /// is outside `1..=`[`MAX_CELL_SUBDIVISION`] or the length does not match.
    pub fn new(k: u32, tets: usize, hull_faces: usize, data: Vec<u8>) -> Option<Self> {
        if !(1..=MAX_CELL_SUBDIVISION).contains(&k) {
            return None;
        }
        let len = tets
            .checked_mul(record_bytes(4, k))?
            .checked_add(hull_faces.checked_mul(record_bytes(3, k))?)?;
        (data.len() == len).then_some(Self {
            k,
            tets,
            hull_faces,
            data,
        })
    }

    /// Lattice subdivision `k`.
    pub fn subdivision(&self) -> u32 {
        self.k
    }

    /// Tetrahedra covered.
    pub fn tet_count(&self) -> usize {
        self.tets
    }

    /// Hull faces covered.
    pub fn hull_face_count(&self) -> usize {
        self.hull_faces
    }

    /// The raw records (see [`CellVisibility::new`]).
    pub fn data(&self) -> &[u8] {
        &self.data
    }

    /// The index of the first record (tetrahedra first, then hull faces)
    /// whose padding bits are not all zero, if any; a canonical file has
    /// none.
    pub fn first_nonzero_padding(&self) -> Option<usize> {
        let rb4 = record_bytes(4, self.k);
        let rb3 = record_bytes(3, self.k);
        let used4 = 4 * lattice_len(4, self.k);
        let used3 = 3 * lattice_len(3, self.k);
        let dirty = |rec: &[u8], used: usize| {
            (used..rec.len() * 8).any(|bit| rec[bit >> 3] >> (bit & 7) & 1 != 0)
        };
        let (tets, hull) = self.data.split_at(self.tets * rb4);
        tets.chunks_exact(rb4)
            .position(|r| dirty(r, used4))
            .or_else(|| {
                hull.chunks_exact(rb3)
                    .position(|r| dirty(r, used3))
                    .map(|i| self.tets + i)
            })
    }

    fn interpolate<const N: usize>(&self, record: &[u8], bary: &[f32; N]) -> [f32; N] {
        let (idx, w) = kuhn_weights(bary, self.k);
        let len = lattice_len(N, self.k);
        let mut out = [0.0f32; N];
        for (v, o) in out.iter_mut().enumerate() {
            for j in 0..N {
                let bit = v * len + idx[j];
                if w[j] > 0.0 && record[bit >> 3] >> (bit & 7) & 1 != 0 {
                    *o += w[j];
                }
            }
        }
        out
    }

    /// Visibility `c_v(p) ∈ [0, 1]` of each corner of tetrahedron `tet` at
    /// the point with barycentric coordinates `bary` in it (all 1 if `tet`
    /// is out of range).
    pub fn tet(&self, tet: u32, bary: &[f32; 4]) -> [f32; 4] {
        let rb = record_bytes(4, self.k);
        let t = tet as usize;
        if t >= self.tets {
            return [1.0; 4];
        }
        self.interpolate(&self.data[t * rb..(t + 1) * rb], bary)
    }

    /// Visibility of each corner of hull face `face` at the point with
    /// barycentric coordinates `bary` on it (the closest hull point of a
    /// point outside the hull; all 1 if `face` is out of range).
    pub fn hull_face(&self, face: u32, bary: &[f32; 3]) -> [f32; 3] {
        let start = self.tets * record_bytes(4, self.k);
        let rb = record_bytes(3, self.k);
        let h = face as usize;
        if h >= self.hull_faces {
            return [1.0; 3];
        }
        self.interpolate(&self.data[start + h * rb..start + (h + 1) * rb], bary)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
        let len = lattice_len(4, k);
        let pts = lattice_numerators(4, k);
        let mut rec = vec![0u8; record_bytes(4, k)];
        for v in 0..4 {
            for (i, n) in pts.iter().enumerate() {
                let corner = n.iter().position(|&x| x == 1).unwrap();
                if v <= corner {
                    let bit = v * len + i;
                    rec[bit >> 3] |= 1 << (bit & 7);
                }
            }
        }
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
}
