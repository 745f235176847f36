//! The tetrahedron walk of [`TetMesh::locate`]: the coarse start grid of
//! jump-and-walk, the deterministic walk through the face opposite the
//! most negative barycentric coordinate (Cupisz, GDC 2012, "traversal"),
//! and the remembering stochastic walk it falls back to on a cycle
//! (Devillers, Pion & Teillaud, "Walking in a triangulation", 2002).

use super::{TetMesh, WalkState, CYCLE_GUARD_STEPS, HULL_BIT, INSIDE_TOLERANCE, JUMP_AFTER_STEPS};
use crate::math;
use crate::prelude::*;
use glam::Vec3;

/// Uniform grid of start tetrahedra over the probes' bounding box.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct StartGrid {
    pub(super) origin: Vec3,
    pub(super) cells_per_metre: Vec3,
    pub(super) dims: [u32; 3],
    pub(super) tets: Vec<u32>,
}

impl StartGrid {
    #[inline]
    pub(super) fn start(&self, p: Vec3) -> u32 {
        let c = ((p - self.origin) * self.cells_per_metre).floor();
        let ix = (c.x.max(0.0) as u32).min(self.dims[0] - 1);
        let iy = (c.y.max(0.0) as u32).min(self.dims[1] - 1);
        let iz = (c.z.max(0.0) as u32).min(self.dims[2] - 1);
        self.tets[((iz * self.dims[1] + iy) * self.dims[0] + ix) as usize]
    }
}

impl TetMesh {
    /// About one start cell per 4 probes, at most 64³ cells; each cell holds
    /// the tetrahedron found at its centre (walking cell to cell).
    pub(super) fn build_start_grid(&self) -> StartGrid {
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for t in &self.tets {
            for &v in t {
                lo = lo.min(self.positions[v as usize]);
                hi = hi.max(self.positions[v as usize]);
            }
        }
        let ext = (hi - lo).max(Vec3::splat(1e-6));
        let target = (self.positions.len() as f32 / 4.0).clamp(1.0, 64.0 * 64.0 * 64.0);
        let cell = math::cbrt(ext.x * ext.y * ext.z / target);
        let dims = (ext / cell).ceil().clamp(Vec3::ONE, Vec3::splat(64.0));
        let dims = [dims.x as u32, dims.y as u32, dims.z as u32];
        let cells_per_metre = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) / ext;
        let mut grid = StartGrid {
            origin: lo,
            cells_per_metre,
            dims,
            tets: Vec::new(),
        };
        let mut state = WalkState {
            tet: 0,
            ..WalkState::new()
        };
        for iz in 0..dims[2] {
            for iy in 0..dims[1] {
                for ix in 0..dims[0] {
                    let c =
                        lo + (Vec3::new(ix as f32, iy as f32, iz as f32) + 0.5) / cells_per_metre;
                    let tet = self.walk(c, state.tet, false, &mut state).0;
                    state.tet = tet;
                    grid.tets.push(tet);
                }
            }
        }
        grid
    }

    /// The tetrahedron walk. Returns `(tet, coords, exit_face)`: `exit_face`
    /// is the local face through which `p` left the hull (`None` if inside).
    pub(super) fn walk(
        &self,
        p: Vec3,
        start: u32,
        warm: bool,
        state: &mut WalkState,
    ) -> (u32, [f32; 4], Option<usize>) {
        let mut t = start;
        let mut budget = if warm {
            JUMP_AFTER_STEPS
        } else {
            CYCLE_GUARD_STEPS
        };
        let mut jumped = !warm;
        loop {
            let l = self.walk[t as usize].bary.coords(p);
            let mut i = 0;
            for k in 1..4 {
                if l[k] < l[i] {
                    i = k;
                }
            }
            if l[i] >= -INSIDE_TOLERANCE {
                return (t, l, None);
            }
            let n = self.walk[t as usize].links[i];
            if n & HULL_BIT != 0 {
                return (t, l, Some(i));
            }
            t = n;
            budget -= 1;
            if budget == 0 {
                if !jumped {
                    jumped = true;
                    t = self.grid.start(p);
                    budget = CYCLE_GUARD_STEPS;
                } else {
                    return self.stochastic_walk(p, t, state);
                }
            }
        }
    }

    /// Remembering stochastic walk (Devillers, Pion & Teillaud 2002): a random
    /// face among those with a negative coordinate, never the one just crossed.
    #[cold]
    fn stochastic_walk(
        &self,
        p: Vec3,
        start: u32,
        state: &mut WalkState,
    ) -> (u32, [f32; 4], Option<usize>) {
        let mut t = start;
        let mut prev = u32::MAX;
        let mut best = (t, self.walk[t as usize].bary.coords(p));
        let budget = 4 * self.tets.len() as u64 + 64;
        for _ in 0..budget {
            let l = self.walk[t as usize].bary.coords(p);
            let min = l.iter().copied().fold(f32::INFINITY, f32::min);
            if min > best.1.iter().copied().fold(f32::INFINITY, f32::min) {
                best = (t, l);
            }
            if min >= -INSIDE_TOLERANCE {
                return (t, l, None);
            }
            let r = state.next_random() as usize;
            let mut moved = false;
            for j in 0..4 {
                let i = (r + j) & 3;
                let n = self.walk[t as usize].links[i];
                if l[i] >= -INSIDE_TOLERANCE || n == prev {
                    continue;
                }
                if n & HULL_BIT != 0 {
                    return (t, l, Some(i));
                }
                prev = t;
                t = n;
                moved = true;
                break;
            }
            if !moved {
                // Only the face we came through is negative: p is on it up to rounding.
                return (t, l, None);
            }
        }
        (best.0, best.1, None)
    }
}
