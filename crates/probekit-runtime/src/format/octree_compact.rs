//! The octree section `OCTC`: an adaptive
//! volume's octree as one bit per node, its corners found by position.
//!
//! An explicit node list would spend 40 bytes per node plus 8 `u32` corner
//! indices per leaf (~72 bytes per leaf, a third of an adaptive volume file).
//! The octrees the builder makes are regular: breadth-first node order with
//! the 8 children of a node consecutive, every node box an octant of its
//! parent on a lattice of `roots·2^max_depth` cells per axis over the box,
//! leaves listing exactly their 8 corner samples, and each corner sample at
//! the lattice position `min + q·step` ([`lattice_pos`], [`lattice_step`]:
//! computed in `f32` exactly as the builder does, by calling them). Such a
//! tree is fully described by the root box, `max_depth` and one "has
//! children" bit per node; the reader rebuilds the boxes and finds each leaf
//! corner by its position's bits among the probe positions. The writer
//! refuses an octree whose encoding does not decode to the very same
//! [`Octree`], so what a reader sees is always what was written.
//!
//! Layout (`docs/file-format.md`, *`OCTC`*): header `w0` node count `N`,
//! `w1` max depth `D ≤ 20`, `w2`/`w3` the root grid (
//! [`super::layout::pack_roots`]); arrays: `f32[6]` box min and max;
//! `ceil(N/8)` bytes of child bits, bit `i % 8` of byte `i / 8` set when
//! node `i` has children.
//!
//! A forest of `R = rx·ry·rz` roots is the same thing on a lattice of
//! `r_a·2^D` cells per axis: the first `R` nodes are the roots, root
//! `(i, j, k)` (index `i + rx·(j + ry·k)`) at lattice corner
//! `(i, j, k)·2^D`, and `N = R + 8 × (nodes with children)`.

use super::error::FormatError;
use super::layout::{SectionId, NONE};
use super::{Octree, OctreeNode};
use crate::prelude::*;
use alloc::collections::BTreeMap;
use glam::Vec3;

/// Deepest level `OCTC` accepts (lattice coordinates stay below `2^20`).
pub const MAX_DEPTH: u32 = 20;

/// A decoded-but-not-expanded `OCTC` section.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Compact {
    /// Root box minimum.
    pub min: Vec3,
    /// Root box maximum.
    pub max: Vec3,
    /// Deepest level of the lattice.
    pub max_depth: u32,
    /// Node count.
    pub nodes: u32,
    /// Root grid (x, y, z), each ≥ 1.
    pub roots: [u32; 3],
    /// Child bits, LSB first.
    pub bits: Vec<u8>,
}

fn invalid(element: usize, reason: &'static str) -> FormatError {
    FormatError::InvalidValue {
        id: SectionId::OCTREE,
        element: element as u64,
        reason,
    }
}

fn topology(element: usize, reason: &'static str) -> FormatError {
    FormatError::InvalidTopology {
        id: SectionId::OCTREE,
        element: element as u64,
        reason,
    }
}

/// Lattice step `(max − min) / cells` per axis, the builder's formula.
pub fn lattice_step(min: Vec3, max: Vec3, cells: [u32; 3]) -> Vec3 {
    (max - min) / Vec3::new(cells[0] as f32, cells[1] as f32, cells[2] as f32)
}

/// Lattice position `min + q·step`, the builder's formula.
pub fn lattice_pos(min: Vec3, step: Vec3, q: [u32; 3]) -> Vec3 {
    min + Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) * step
}

fn key(p: Vec3) -> [u32; 3] {
    // +0.0 folds −0.0 into +0.0.
    p.to_array().map(|v| (v + 0.0).to_bits())
}

impl Compact {
    /// Expands to the explicit octree, finding leaf corners among
    /// `positions` (the first probe with the corner's exact bits). Typed
    /// errors for every inconsistency; work is `O(N + P log P)`.
    pub fn expand(&self, positions: &[Vec3]) -> Result<Octree, FormatError> {
        let n = self.nodes as usize;
        if n == 0 {
            return Err(invalid(0, "octree without a root node"));
        }
        if self.max_depth > MAX_DEPTH {
            return Err(invalid(0, "compact octree deeper than 20 levels"));
        }
        if !(self.min.is_finite() && self.max.is_finite())
            || (0..3).any(|a| self.max[a] < self.min[a])
        {
            return Err(invalid(0, "box is not finite with min <= max"));
        }
        let bit = |i: usize| (self.bits[i / 8] >> (i % 8)) & 1 == 1;
        let parents = (0..n).filter(|&i| bit(i)).count();
        let [rx, ry, rz] = self.roots;
        let root_count = (rx as usize)
            .checked_mul(ry as usize)
            .and_then(|v| v.checked_mul(rz as usize))
            .filter(|&r| r >= 1 && r <= n)
            .ok_or(invalid(0, "root grid empty or larger than the node count"))?;
        if parents
            .checked_mul(8)
            .and_then(|c| c.checked_add(root_count))
            != Some(n)
        {
            return Err(invalid(
                0,
                "node count is not roots + 8 × nodes with children",
            ));
        }
        if (n..self.bits.len() * 8).any(bit) {
            return Err(invalid(n, "child bit set past the last node"));
        }
        let side = 1u32 << self.max_depth;
        // Lattice cells per axis (< 2^36 with 65536 roots and depth 20).
        let cells = self.roots.map(|r| r as u64 * side as u64);
        if cells.iter().any(|&c| c > 1 << 24) {
            return Err(invalid(
                0,
                "root grid × 2^depth exceeds 2^24 cells per axis",
            ));
        }
        let step = lattice_step(self.min, self.max, cells.map(|c| c as u32));
        let mut index: BTreeMap<[u32; 3], u32> = BTreeMap::new();
        for (i, p) in positions.iter().enumerate().rev() {
            index.insert(key(*p), i as u32);
        }
        // Lattice corner and depth of each node, filled as parents are met.
        let mut lo = vec![[0u32; 3]; n];
        let mut depth = vec![0u32; n];
        for (r, l) in lo.iter_mut().enumerate().take(root_count) {
            let (i, j, k) = (
                r % rx as usize,
                (r / rx as usize) % ry as usize,
                r / (rx * ry) as usize,
            );
            *l = [i as u32 * side, j as u32 * side, k as u32 * side];
        }
        let mut nodes = Vec::with_capacity(n);
        let mut samples = Vec::new();
        let mut next = root_count;
        for i in 0..n {
            if i >= next {
                // No earlier node claimed it: children must follow parents.
                return Err(topology(i, "octree node unreachable from the root"));
            }
            let size = side >> depth[i];
            let hi = lo[i].map(|v| v + size);
            let mut node = OctreeNode {
                min: lattice_pos(self.min, step, lo[i]),
                max: lattice_pos(self.min, step, hi),
                first_child: NONE,
                depth: depth[i],
                sample_offset: 0,
                sample_count: 0,
            };
            if bit(i) {
                if depth[i] >= self.max_depth {
                    return Err(topology(i, "octree node below max depth"));
                }
                node.first_child = next as u32;
                let h = size / 2;
                for k in 0..8u32 {
                    let c = next + k as usize;
                    lo[c] = [
                        lo[i][0] + h * (k & 1),
                        lo[i][1] + h * ((k >> 1) & 1),
                        lo[i][2] + h * ((k >> 2) & 1),
                    ];
                    depth[c] = depth[i] + 1;
                }
                next += 8;
            } else {
                node.sample_offset = samples.len() as u32;
                node.sample_count = 8;
                for k in 0..8u32 {
                    let q = [
                        lo[i][0] + size * (k & 1),
                        lo[i][1] + size * ((k >> 1) & 1),
                        lo[i][2] + size * ((k >> 2) & 1),
                    ];
                    let p = lattice_pos(self.min, step, q);
                    let s = index
                        .get(&key(p))
                        .ok_or(topology(i, "no probe at an octree leaf corner"))?;
                    samples.push(*s);
                }
            }
            nodes.push(node);
        }
        Ok(Octree {
            nodes,
            samples,
            roots: self.roots,
        })
    }
}

/// The compact encoding of `o`, if it has one that expands back to exactly
/// `o` with these `positions` (see the module docs); `None` otherwise.
pub(crate) fn encode(o: &Octree, positions: &[Vec3]) -> Option<Compact> {
    let root = o.nodes.first()?;
    let last_root = o.nodes.get(o.root_count().checked_sub(1)?)?;
    if root.depth != 0 || u32::try_from(o.nodes.len()).is_err() {
        return None;
    }
    let max_depth = o.nodes.iter().map(|n| n.depth).max()?;
    if max_depth > MAX_DEPTH {
        return None;
    }
    let mut bits = vec![0u8; o.nodes.len().div_ceil(8)];
    for (i, n) in o.nodes.iter().enumerate() {
        if n.first_child != NONE {
            bits[i / 8] |= 1 << (i % 8);
        }
    }
    let c = Compact {
        min: root.min,
        max: last_root.max,
        max_depth,
        nodes: o.nodes.len() as u32,
        roots: o.roots,
        bits,
    };
    match c.expand(positions) {
        Ok(back) if back == *o => Some(c),
        _ => None,
    }
}
