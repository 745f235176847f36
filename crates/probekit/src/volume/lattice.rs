//! The adaptive octree's lattice at maximum depth, which captures each
//! lattice point at most once, and the cells' corner and child points.

use super::source::{Captured, VolumeSource};
use crate::format::lattice_pos;
use glam::Vec3;
use std::collections::HashMap;

#[derive(Clone, Copy, Debug)]
pub(super) struct Cell {
    pub(super) lo: [u32; 3],
    pub(super) depth: u32,
    pub(super) first_child: usize,
}

pub(super) const NO_CHILD: usize = usize::MAX;

/// Lattice at max depth: captures each lattice point at most once.
pub(super) struct Lattice<'a> {
    pub(super) src: &'a dyn VolumeSource,
    pub(super) min: Vec3,
    pub(super) step: Vec3,
    /// Lattice cells per axis (`roots · 2^max_depth`).
    pub(super) cells: [u32; 3],
    pub(super) index: HashMap<[u32; 3], usize>,
    pub(super) keys: Vec<[u32; 3]>,
    pub(super) caps: Vec<Captured>,
    pub(super) captures: usize,
}

impl Lattice<'_> {
    pub(super) fn pos(&self, q: [u32; 3]) -> Vec3 {
        lattice_pos(self.min, self.step, q)
    }

    /// Captures every not yet captured point of `qs` in one batch.
    pub(super) fn ensure(&mut self, qs: &[[u32; 3]]) {
        let mut new = Vec::new();
        for q in qs {
            if !self.index.contains_key(q) {
                self.index.insert(*q, self.keys.len() + new.len());
                new.push(*q);
            }
        }
        if new.is_empty() {
            return;
        }
        let pts: Vec<Vec3> = new.iter().map(|q| self.pos(*q)).collect();
        self.captures += pts.len();
        self.caps.extend(self.src.capture(&pts));
        self.keys.extend(new);
    }

    pub(super) fn sh(&self, q: [u32; 3]) -> &[Vec3] {
        self.cap(q).sh.coeffs()
    }

    pub(super) fn cap(&self, q: [u32; 3]) -> &Captured {
        &self.caps[self.index[&q]]
    }
}

pub(super) fn corners(lo: [u32; 3], s: u32) -> [[u32; 3]; 8] {
    std::array::from_fn(|c| {
        [
            lo[0] + s * (c as u32 & 1),
            lo[1] + s * ((c as u32 >> 1) & 1),
            lo[2] + s * ((c as u32 >> 2) & 1),
        ]
    })
}

/// The 27 lattice points of a cell's children, with trilinear weights of the
/// parent's corners.
pub(super) fn child_points(lo: [u32; 3], s: u32) -> Vec<([u32; 3], [f32; 8])> {
    let h = s / 2;
    let mut out = Vec::with_capacity(27);
    for k in 0..3u32 {
        for j in 0..3u32 {
            for i in 0..3u32 {
                let f = [i as f32 * 0.5, j as f32 * 0.5, k as f32 * 0.5];
                let w = std::array::from_fn(|c| {
                    (0..3)
                        .map(|a| if (c >> a) & 1 == 1 { f[a] } else { 1.0 - f[a] })
                        .product()
                });
                out.push(([lo[0] + i * h, lo[1] + j * h, lo[2] + k * h], w));
            }
        }
    }
    out
}
