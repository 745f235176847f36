//! Occluder planes: the exact side-of-the-wall test that replaces the
//! lattice bits in a tetrahedron one flat wall cuts.

use crate::prelude::*;
use glam::Vec3;

/// Largest deviation from 1 of the length of a stored plane normal.
pub const PLANE_NORMAL_TOLERANCE: f32 = 1e-3;

/// Whether plane `[n_x, n_y, n_z, d]` has a unit normal: its length within
/// [`PLANE_NORMAL_TOLERANCE`] of 1 (the rule of [`CellPlanes::new`] and of
/// the `CPLN` reader).
pub fn plane_has_unit_normal(p: &[f32; 4]) -> bool {
    (Vec3::new(p[0], p[1], p[2]).length() - 1.0).abs() <= PLANE_NORMAL_TOLERANCE
}

/// Occluder planes of tetrahedra (the file's `CPLN` section): a
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
