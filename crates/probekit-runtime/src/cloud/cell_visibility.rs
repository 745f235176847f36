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
//!
//! A cell whose every bit is 1 (*clear*: each corner sees the whole cell)
//! is not stored: [`CellVisibility`] keeps a mask of the cells with a
//! record and those records only (the file's `CVSP` section;
//! `docs/file-format.md`).

mod lattice;
mod planes;
mod records;

pub use planes::CellPlanes;

// What the baker needs to build the records (feature `write`).
#[cfg(feature = "write")]
pub use lattice::{kuhn_weights, lattice_len, lattice_numerators, lattice_position};
#[cfg(feature = "write")]
pub use planes::{plane_has_unit_normal, PLANE_NORMAL_TOLERANCE};
use records::{bit, record_is_clear, set_bit};
#[cfg(feature = "write")]
pub use records::{
    record_bit_index, record_bytes, record_from, record_has_padding, record_sees, records_len,
    stored_counts, DEFAULT_CELL_SUBDIVISION, MAX_CELL_SUBDIVISION,
};
#[cfg(not(feature = "write"))]
pub(crate) use {
    lattice::{kuhn_weights, lattice_len},
    planes::plane_has_unit_normal,
    records::{
        record_bytes, record_from, record_has_padding, records_len, stored_counts,
        MAX_CELL_SUBDIVISION,
    },
};

use crate::prelude::*;

/// Per-cell visibility bits of a probe cloud (see the module docs), ready to
/// weight the blend: `c_v(p)` for each corner of the cell containing `p`.
///
/// Stored sparse: most cells of a cloud lie in open space, where every
/// corner sees every lattice point (73 % of the tetrahedra of a 525-probe
/// adaptive cloud of builtin:demo). Such a *clear* cell has no record; a
/// mask holds one bit per cell (tetrahedra, then hull faces), set where the
/// cell has a record, and the records of the other cells follow in cell
/// order. A clear cell's corners all have `c_v = 1`, which is what its
/// lattice bits would interpolate to, so storage does not change the blend.
#[derive(Clone, Debug, PartialEq)]
pub struct CellVisibility {
    k: u32,
    tets: usize,
    hull_faces: usize,
    /// Bit `i` (least significant first) set: cell `i` has a record.
    mask: Vec<u8>,
    /// Set mask bits before each 64-cell block (rank directory).
    rank: Vec<u32>,
    /// Records of the tetrahedra with a mask bit, then of such hull faces.
    records: Vec<u8>,
    /// Tetrahedra with a record.
    tet_records: usize,
    /// Cells with a record.
    stored: usize,
}

impl CellVisibility {
    /// Wraps dense records: `tets` tetrahedron records of
    /// [`record_bytes`]`(4, k)` bytes, then `hull_faces` hull-face records of
    /// `record_bytes(3, k)` bytes, in the mesh's tetrahedron and hull-face
    /// order; records with every used bit set are dropped (see the type
    /// docs). `None` if `k` is outside `1..=`[`MAX_CELL_SUBDIVISION`] or the
    /// length does not match.
    pub fn new(k: u32, tets: usize, hull_faces: usize, data: Vec<u8>) -> Option<Self> {
        if !(1..=MAX_CELL_SUBDIVISION).contains(&k) {
            return None;
        }
        if data.len() != records_len(k, tets, hull_faces)? {
            return None;
        }
        let (rb4, rb3) = (record_bytes(4, k), record_bytes(3, k));
        let cells = tets.checked_add(hull_faces)?;
        let mut mask = vec![0u8; cells.div_ceil(8)];
        let mut records = Vec::new();
        let (t, h) = data.split_at(tets * rb4);
        let all = t
            .chunks_exact(rb4)
            .map(|r| (r, 4))
            .chain(h.chunks_exact(rb3).map(|r| (r, 3)));
        for (i, (r, vertices)) in all.enumerate() {
            if !record_is_clear(r, vertices, k) {
                set_bit(&mut mask, i);
                records.extend_from_slice(r);
            }
        }
        Self::from_sparse(k, tets, hull_faces, mask, records)
    }

    /// Wraps sparse storage (the `CVSP` section's arrays): `mask` of
    /// `ceil((tets + hull_faces)/8)` bytes, bit `i` set when cell `i`
    /// (tetrahedra, then hull faces) has a record, and `records`, the
    /// records of those cells in order ([`record_bytes`]`(4, k)` bytes for a
    /// tetrahedron, `record_bytes(3, k)` for a hull face). `None` if `k` is
    /// outside `1..=`[`MAX_CELL_SUBDIVISION`] or a length does not match.
    /// Canonical form (no padding bit set, no stored record clear) is
    /// checked by [`CellVisibility::first_noncanonical`].
    pub fn from_sparse(
        k: u32,
        tets: usize,
        hull_faces: usize,
        mask: Vec<u8>,
        records: Vec<u8>,
    ) -> Option<Self> {
        if !(1..=MAX_CELL_SUBDIVISION).contains(&k) {
            return None;
        }
        let cells = tets.checked_add(hull_faces)?;
        if mask.len() != cells.div_ceil(8) {
            return None;
        }
        let (tet_records, hull_records) = stored_counts(&mask, tets, hull_faces);
        if records.len() != records_len(k, tet_records, hull_records)? {
            return None;
        }
        let mut rank = Vec::with_capacity(cells.div_ceil(64));
        let mut count = 0u32;
        for block in mask.chunks(8) {
            rank.push(count);
            count += block.iter().map(|b| b.count_ones()).sum::<u32>();
        }
        Some(Self {
            k,
            tets,
            hull_faces,
            mask,
            rank,
            records,
            tet_records,
            stored: tet_records + hull_records,
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

    /// The mask (see [`CellVisibility::from_sparse`]).
    pub fn mask(&self) -> &[u8] {
        &self.mask
    }

    /// The stored records (see [`CellVisibility::from_sparse`]).
    pub fn records(&self) -> &[u8] {
        &self.records
    }

    /// Cells with a record (not clear).
    pub fn record_count(&self) -> usize {
        self.stored
    }

    /// The dense records of [`CellVisibility::new`], clear cells included.
    pub fn to_dense(&self) -> Vec<u8> {
        // A clear record per corner count: every used bit set.
        let clear = |vertices: usize| record_from(vertices, self.k, |_, _| true);
        let (clear4, clear3) = (clear(4), clear(3));
        let mut out = Vec::new();
        for i in 0..self.tets + self.hull_faces {
            let empty = if i < self.tets { &clear4 } else { &clear3 };
            out.extend_from_slice(self.record(i).unwrap_or(empty));
        }
        out
    }

    /// The index of the first cell (tetrahedra first, then hull faces) whose
    /// storage is not canonical, if any: a stored record with a padding bit
    /// set or with every used bit set (a clear cell has no record), or a
    /// mask padding bit set (reported as the cell count). A canonical file
    /// has none.
    pub fn first_noncanonical(&self) -> Option<usize> {
        let cells = self.tets + self.hull_faces;
        let bad = (0..cells).find(|&i| {
            let vertices = if i < self.tets { 4 } else { 3 };
            self.record(i).is_some_and(|r| {
                record_has_padding(r, vertices, self.k) || record_is_clear(r, vertices, self.k)
            })
        });
        bad.or_else(|| {
            (cells..self.mask.len() * 8)
                .any(|i| bit(&self.mask, i))
                .then_some(cells)
        })
    }

    /// Set mask bits before cell `i` (`i` < cell count).
    fn rank_of(&self, i: usize) -> usize {
        let block = i >> 6;
        let full: u32 = self.mask[block * 8..i >> 3]
            .iter()
            .map(|b| b.count_ones())
            .sum();
        let part = (self.mask[i >> 3] & ((1u8 << (i & 7)) - 1)).count_ones();
        (self.rank[block] + full + part) as usize
    }

    /// Cell `i`'s record (tetrahedra, then hull faces), `None` when clear.
    fn record(&self, i: usize) -> Option<&[u8]> {
        if !bit(&self.mask, i) {
            return None;
        }
        let r = self.rank_of(i);
        let (rb4, rb3) = (record_bytes(4, self.k), record_bytes(3, self.k));
        let start = if i < self.tets {
            r * rb4
        } else {
            self.tet_records * rb4 + (r - self.tet_records) * rb3
        };
        let len = if i < self.tets { rb4 } else { rb3 };
        Some(&self.records[start..start + len])
    }

    fn interpolate<const N: usize>(&self, record: &[u8], bary: &[f32; N]) -> [f32; N] {
        let (idx, w) = kuhn_weights(bary, self.k);
        let len = lattice_len(N, self.k);
        let mut out = [0.0f32; N];
        for (v, o) in out.iter_mut().enumerate() {
            for j in 0..N {
                if w[j] > 0.0 && bit(record, v * len + idx[j]) {
                    *o += w[j];
                }
            }
        }
        out
    }

    /// Visibility `c_v(p) ∈ [0, 1]` of each corner of tetrahedron `tet` at
    /// the point with barycentric coordinates `bary` in it (all 1 if the
    /// cell is clear or `tet` is out of range).
    pub fn tet(&self, tet: u32, bary: &[f32; 4]) -> [f32; 4] {
        let t = tet as usize;
        if t >= self.tets {
            return [1.0; 4];
        }
        self.record(t)
            .map_or([1.0; 4], |r| self.interpolate(r, bary))
    }

    /// Visibility of each corner of hull face `face` at the point with
    /// barycentric coordinates `bary` on it (the closest hull point of a
    /// point outside the hull; all 1 if the cell is clear or `face` is out
    /// of range).
    pub fn hull_face(&self, face: u32, bary: &[f32; 3]) -> [f32; 3] {
        let h = face as usize;
        if h >= self.hull_faces {
            return [1.0; 3];
        }
        self.record(self.tets + h)
            .map_or([1.0; 3], |r| self.interpolate(r, bary))
    }

    /// Whether tetrahedron `tet` has a record (some corner does not see some
    /// lattice point of it); `false` for a clear cell or one out of range.
    pub fn tet_has_record(&self, tet: u32) -> bool {
        (tet as usize) < self.tets && bit(&self.mask, tet as usize)
    }
}

#[cfg(test)]
mod tests;
