//! The cell of a volume holding a point, for diagnostics: its index, its
//! eight corner samples and their trilinear weights in it.

use super::{find_leaf, Layout, Volume};
use crate::math;
use glam::Vec3;

impl Volume {
    /// The cell holding `p` (clamped to the box): for a uniform grid the
    /// cell index `i + (rx − 1)·(j + (ry − 1)·k)` (an axis of one probe
    /// counts as one cell), for an octree the leaf's node index; its eight
    /// corner samples in child bit order (bit 0 the +x corner, bit 1 +y,
    /// bit 2 +z; along an axis of one probe both corners are that probe)
    /// and their trilinear weights at `p` (summing to 1). On an octree the
    /// blend also reaches the samples of finer neighbours (module docs);
    /// these are the leaf's own corners.
    pub(crate) fn cell_at(&self, p: Vec3) -> (u32, [u32; 8], [f32; 8]) {
        let (bmin, bmax) = self.bounds();
        let p = p.clamp(bmin, bmax);
        let (index, corner, f) = match &self.layout {
            Layout::Grid { min, max, res } => {
                let mut i0 = [0u32; 3];
                let mut f = [0.0f32; 3];
                for a in 0..3 {
                    if res[a] < 2 {
                        continue;
                    }
                    let h = (max[a] - min[a]) / (res[a] - 1) as f32;
                    let x = if h > 0.0 { (p[a] - min[a]) / h } else { 0.0 };
                    i0[a] = (math::floor(x).max(0.0) as u32).min(res[a] - 2);
                    f[a] = (x - i0[a] as f32).clamp(0.0, 1.0);
                }
                let cells = res.map(|r| r.max(2) - 1);
                let index = i0[0] + cells[0] * (i0[1] + cells[1] * i0[2]);
                let corner: [u32; 8] = core::array::from_fn(|c| {
                    let at = |a: usize| i0[a] + ((c >> a) & 1) as u32 * (res[a] >= 2) as u32;
                    at(0) + res[0] * (at(1) + res[1] * at(2))
                });
                (index, corner, f)
            }
            Layout::Tree { nodes, roots, .. } => {
                let k = find_leaf(nodes, *roots, p);
                let leaf = &nodes[k];
                let ext = leaf.max - leaf.min;
                let f = [0, 1, 2].map(|a| {
                    if ext[a] > 0.0 {
                        ((p[a] - leaf.min[a]) / ext[a]).clamp(0.0, 1.0)
                    } else {
                        0.0
                    }
                });
                (k as u32, leaf.corners, f)
            }
        };
        let weights = core::array::from_fn(|c| {
            (0..3)
                .map(|a| if (c >> a) & 1 == 1 { f[a] } else { 1.0 - f[a] })
                .product()
        });
        (index, corner, weights)
    }
}
