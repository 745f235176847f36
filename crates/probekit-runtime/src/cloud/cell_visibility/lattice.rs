//! The lattice of a `k`-subdivided cell: its points, their numbering (see
//! the parent module's docs, "Storage and bit order") and positions, and
//! the Freudenthal–Kuhn sub-simplex holding a point, whose barycentric
//! weights interpolate the lattice bits.

#![cfg_attr(not(feature = "write"), allow(dead_code))]

use crate::math;
use crate::prelude::*;
use glam::Vec3;

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

const fn tri(m: u32) -> usize {
    (m as usize) * (m as usize + 1) / 2
}

const fn tetra(m: u32) -> usize {
    (m as usize) * (m as usize + 1) * (m as usize + 2) / 6
}

/// Index of the lattice point with cumulative numerators `c` (`c[0] ≤ c[1]
/// ≤ c[2]`; `c[2]` unused for hull faces) in a cell with `vertices` corners.
pub(super) fn lattice_index(vertices: usize, c: [u32; 3]) -> usize {
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
