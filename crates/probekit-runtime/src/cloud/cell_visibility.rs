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
//! record and those records only (the file's `CVSP` section, format 1.5;
//! `docs/file-format.md`).

use crate::math;
use crate::prelude::*;
use glam::Vec3;

/// Largest lattice subdivision a file may hold.
pub const MAX_CELL_SUBDIVISION: u32 = 8;

/// Default lattice subdivision, and the smallest `probekit bake` picks
/// from the cell size (`--cell-visibility auto`; coarse clouds get up to
/// [`MAX_CELL_SUBDIVISION`]): 35 points per tetrahedron, 18 bytes per
/// tetrahedron that is not clear (sparse storage; on a 525-probe adaptive
/// cloud of builtin:demo about 27 % of the tetrahedra, some 25 bytes per
/// probe in all). Measured (BENCHMARKS.md, "Sparse cell visibility"): at
/// `k` = 3 the interpolated bits let a bright probe behind a doorway's edge
/// keep weight at closet points it cannot see; from `k` = 4 the closet
/// leaks left are those an exact per-point segment test leaves too.
pub const DEFAULT_CELL_SUBDIVISION: u32 = 4;

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

/// Bit of corner `v` at lattice point `l` in a record with `vertices`
/// corners at subdivision `k`: `v · lattice_len + l` (least significant bit
/// of each byte first).
pub const fn record_bit_index(vertices: usize, k: u32, v: usize, l: usize) -> usize {
    v * lattice_len(vertices, k) + l
}

/// One cell's record with the bit of corner `v` at lattice point `l` set
/// where `sees(v, l)` (padding bits clear): what the baker writes and what
/// [`CellVisibility::new`] takes per cell. `sees` is called in bit order,
/// corner-major, so a seeded generator inside it gives the same record on
/// every run.
pub fn record_from(vertices: usize, k: u32, mut sees: impl FnMut(usize, usize) -> bool) -> Vec<u8> {
    let mut out = vec![0u8; record_bytes(vertices, k)];
    for v in 0..vertices {
        for l in 0..lattice_len(vertices, k) {
            if sees(v, l) {
                set_bit(&mut out, record_bit_index(vertices, k, v, l));
            }
        }
    }
    out
}

/// Whether corner `v` sees lattice point `l` in a record with `vertices`
/// corners at `k` (the bit [`record_from`] sets).
pub fn record_sees(record: &[u8], vertices: usize, k: u32, v: usize, l: usize) -> bool {
    bit(record, record_bit_index(vertices, k, v, l))
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

/// Bit `i` of `bytes`, least significant bit of each byte first (the order
/// of records and masks).
fn bit(bytes: &[u8], i: usize) -> bool {
    bytes[i >> 3] >> (i & 7) & 1 != 0
}

/// Sets bit `i` of `bytes` (the order of [`bit`]).
fn set_bit(bytes: &mut [u8], i: usize) {
    bytes[i >> 3] |= 1 << (i & 7);
}

/// Whether every used bit of a record with `vertices` corners at `k` is set.
fn record_is_clear(record: &[u8], vertices: usize, k: u32) -> bool {
    let used = vertices * lattice_len(vertices, k);
    (0..used).all(|i| bit(record, i))
}

/// Whether any padding bit (past the `vertices · lattice_len` used ones) of
/// a record with `vertices` corners at subdivision `k` is set; a canonical
/// record has none.
pub fn record_has_padding(record: &[u8], vertices: usize, k: u32) -> bool {
    let used = vertices * lattice_len(vertices, k);
    (used..record.len() * 8).any(|i| bit(record, i))
}

/// Bytes of `tets` tetrahedron records and `hull_faces` hull-face records at
/// subdivision `k` (dense: every cell; sparse: the stored ones); `None` on
/// overflow.
pub fn records_len(k: u32, tets: usize, hull_faces: usize) -> Option<usize> {
    tets.checked_mul(record_bytes(4, k))?
        .checked_add(hull_faces.checked_mul(record_bytes(3, k))?)
}

/// Cells whose bit is set in a sparse `mask` (see
/// [`CellVisibility::from_sparse`]): among the `tets` tetrahedra, and among
/// the `hull_faces` hull faces after them. `mask` must hold
/// `tets + hull_faces` bits.
pub fn stored_counts(mask: &[u8], tets: usize, hull_faces: usize) -> (usize, usize) {
    let count = |r: core::ops::Range<usize>| r.filter(|&i| bit(mask, i)).count();
    (count(0..tets), count(tets..tets + hull_faces))
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

/// Largest deviation from 1 of the length of a stored plane normal.
pub const PLANE_NORMAL_TOLERANCE: f32 = 1e-3;

/// Whether plane `[n_x, n_y, n_z, d]` has a unit normal: its length within
/// [`PLANE_NORMAL_TOLERANCE`] of 1 (the rule of [`CellPlanes::new`] and of
/// the `CPLN` reader).
pub fn plane_has_unit_normal(p: &[f32; 4]) -> bool {
    (Vec3::new(p[0], p[1], p[2]).length() - 1.0).abs() <= PLANE_NORMAL_TOLERANCE
}

/// Occluder planes of tetrahedra (the file's `CPLN` section, format 1.7): a
/// refinement of the lattice bits for cells that one flat wall cuts.
///
/// A lattice point is a cell's finest unit of visibility: between lattice
/// points the bits are interpolated, so a point a few centimetres from a wall
/// still gives a probe behind it part of its weight (at `k` = 8 in a 2 m cell
/// the points are 25 cm apart). Most cells that geometry cuts are cut by one
/// wall, floor or ceiling slab, and there the exact answer is a plane: a
/// corner sees the point when both lie on the same side of the wall's
/// mid-plane. The bake (`probekit::cloud::cell_visibility::bake_cell_planes`)
/// stores a plane only for a cell where every blocked segment of its lattice
/// hits surfaces parallel to one plane, no corner lies inside the wall's
/// slab, and the plane reproduces every lattice bit and an exact segment test
/// at extra random points of the cell; a wall that ends inside the cell (a
/// doorway's edge) fails that test and keeps the lattice.
///
/// At run time a tetrahedron with a plane `n·x = d` gives corner `v` the
/// visibility `c_v(p) = 1` if `n·p − d` and `n·x_v − d` have the same sign
/// (zero counts as positive), else 0, in place of the interpolated bits.
/// The step lies on the wall's mid-plane, inside the wall; where a planed
/// cell meets a lattice cell, the two agree at the lattice points of their
/// shared face and differ between them only within a lattice spacing of the
/// wall, where the lattice cell lets some light through.
#[derive(Clone, Debug, PartialEq)]
pub struct CellPlanes {
    /// Tetrahedra with a plane, strictly increasing.
    tets: Vec<u32>,
    /// Their planes `[n_x, n_y, n_z, d]`: unit normal, offset in metres.
    planes: Vec<[f32; 4]>,
    /// Per tetrahedron of the mesh: index into `planes` plus one, 0 for none.
    lookup: Vec<u32>,
}

impl CellPlanes {
    /// Planes of a mesh with `tet_count` tetrahedra: `tets` strictly
    /// increasing and below `tet_count`, `planes` one per entry with a finite
    /// unit normal (length within [`PLANE_NORMAL_TOLERANCE`] of 1) and a
    /// finite offset. `None` otherwise.
    pub fn new(tet_count: usize, tets: Vec<u32>, planes: Vec<[f32; 4]>) -> Option<Self> {
        if tets.len() != planes.len() || tet_count > u32::MAX as usize {
            return None;
        }
        if tets.windows(2).any(|w| w[0] >= w[1])
            || tets.last().is_some_and(|&t| t as usize >= tet_count)
        {
            return None;
        }
        let valid = |p: &[f32; 4]| p.iter().all(|c| c.is_finite()) && plane_has_unit_normal(p);
        if !planes.iter().all(valid) {
            return None;
        }
        let mut lookup = vec![0u32; tet_count];
        for (i, &t) in tets.iter().enumerate() {
            lookup[t as usize] = i as u32 + 1;
        }
        Some(Self {
            tets,
            planes,
            lookup,
        })
    }

    /// Tetrahedra of the mesh the planes belong to.
    pub fn tet_count(&self) -> usize {
        self.lookup.len()
    }

    /// Number of planes (tetrahedra that have one).
    pub fn len(&self) -> usize {
        self.tets.len()
    }

    /// Whether no tetrahedron has a plane.
    pub fn is_empty(&self) -> bool {
        self.tets.is_empty()
    }

    /// The tetrahedra with a plane, increasing.
    pub fn tets(&self) -> &[u32] {
        &self.tets
    }

    /// Their planes `[n_x, n_y, n_z, d]` (`n·x = d`), in the order of
    /// [`CellPlanes::tets`].
    pub fn planes(&self) -> &[[f32; 4]] {
        &self.planes
    }

    /// Tetrahedron `tet`'s plane, `None` if it has none or is out of range.
    pub fn plane(&self, tet: u32) -> Option<[f32; 4]> {
        match self.lookup.get(tet as usize) {
            Some(&i) if i > 0 => Some(self.planes[i as usize - 1]),
            _ => None,
        }
    }

    /// Visibility of each of `corners` from `p` through `plane` (see the
    /// type docs): 1 where the corner lies on `p`'s side, else 0.
    pub fn visibility<const N: usize>(plane: [f32; 4], p: Vec3, corners: &[Vec3; N]) -> [f32; N] {
        let n = Vec3::new(plane[0], plane[1], plane[2]);
        let side = |x: Vec3| n.dot(x) - plane[3] >= 0.0;
        let s = side(p);
        core::array::from_fn(|v| if side(corners[v]) == s { 1.0 } else { 0.0 })
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
}
