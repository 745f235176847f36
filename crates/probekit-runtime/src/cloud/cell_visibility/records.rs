//! Cell records: their size, bit order and construction, and the sparse
//! mask's counts (the parent module's docs, "Storage and bit order").
#![cfg_attr(not(feature = "write"), allow(dead_code))]

use super::lattice_len;
use crate::prelude::*;

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
/// [`CellVisibility::new`](super::CellVisibility::new) takes per cell. `sees` is called in bit order,
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

/// Bit `i` of `bytes`, least significant bit of each byte first (the order
/// of records and masks).
pub(crate) fn bit(bytes: &[u8], i: usize) -> bool {
    bytes[i >> 3] >> (i & 7) & 1 != 0
}

/// Sets bit `i` of `bytes` (the order of [`bit`]).
pub(crate) fn set_bit(bytes: &mut [u8], i: usize) {
    bytes[i >> 3] |= 1 << (i & 7);
}

/// Whether every used bit of a record with `vertices` corners at `k` is set.
pub(crate) fn record_is_clear(record: &[u8], vertices: usize, k: u32) -> bool {
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
/// [`CellVisibility::from_sparse`](super::CellVisibility::from_sparse)): among the `tets` tetrahedra, and among
/// the `hull_faces` hull faces after them. `mask` must hold
/// `tets + hull_faces` bits.
pub fn stored_counts(mask: &[u8], tets: usize, hull_faces: usize) -> (usize, usize) {
    let count = |r: core::ops::Range<usize>| r.filter(|&i| bit(mask, i)).count();
    (count(0..tets), count(tets..tets + hull_faces))
}
