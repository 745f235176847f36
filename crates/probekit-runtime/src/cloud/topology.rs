//! Connectivity of tetrahedralizations given without it: the neighbour
//! table of a list of tetrahedra, and the Kuhn tetrahedralization of a
//! regular lattice of probes.

#![cfg_attr(not(feature = "write"), allow(dead_code))]

use super::{CloudError, HULL};
use crate::collections::map_with_capacity;
use crate::prelude::*;

/// Neighbour table of a tetrahedralization given only its tetrahedra (as in
/// the JSON export): `result[t][i]` is the tetrahedron sharing the face
/// opposite vertex `i` of `tets[t]`, or [`HULL`]. Error if a face is shared by
/// more than two tetrahedra.
pub fn face_neighbors(tets: &[[u32; 4]]) -> Result<Vec<[u32; 4]>, CloudError> {
    let mut faces = map_with_capacity(tets.len() * 2);
    let mut n = vec![[HULL; 4]; tets.len()];
    for (t, v) in tets.iter().enumerate() {
        for i in 0..4 {
            let mut f = [v[(i + 1) % 4], v[(i + 2) % 4], v[(i + 3) % 4]];
            f.sort_unstable();
            match faces.get_mut(&f) {
                None => {
                    faces.insert(f, Some((t, i)));
                }
                Some(slot) => match slot.take() {
                    Some((u, j)) => {
                        n[t][i] = u as u32;
                        n[u][j] = t as u32;
                    }
                    None => return Err(CloudError::NeighborMismatch { tet: t, face: i }),
                },
            }
        }
    }
    Ok(n)
}

/// The Kuhn (Freudenthal) tetrahedralization of a regular lattice of
/// `dims[0] × dims[1] × dims[2]` points, indexed `x + dims[0]·(y + dims[1]·z)`
/// (x fastest, z slowest): every cube of the
/// lattice is split into the 6 tetrahedra around its main diagonal, one per
/// order of the three axes, each the path from the cube's lowest corner to
/// its highest that steps along one axis at a time. Every cube is split the
/// same way, so the faces match across cubes and the result is a
/// conforming mesh of the lattice's box (6·∏(dims − 1) tetrahedra, each of
/// a sixth of a cube's volume, in either orientation, which [`TetMesh::new`]
/// accepts). Each tetrahedron's circumsphere is its cube's, which holds no
/// other lattice point, so this is one of the lattice's many Delaunay
/// tetrahedralizations (every cube's corners are co-spherical; the baker's
/// symbolic perturbation may choose another): an engine with a uniform grid
/// of probes can query it as a cloud. Empty when a dimension is below 2.
///
/// [`TetMesh::new`]: super::TetMesh::new
pub fn lattice_tets(dims: [u32; 3]) -> Vec<[u32; 4]> {
    let [nx, ny, nz] = dims;
    if nx < 2 || ny < 2 || nz < 2 {
        return Vec::new();
    }
    const AXIS_ORDERS: [[usize; 3]; 6] = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let id = |c: [u32; 3]| c[0] + nx * (c[1] + ny * c[2]);
    let cubes = (nx - 1) as usize * (ny - 1) as usize * (nz - 1) as usize;
    let mut tets = Vec::with_capacity(6 * cubes);
    for z in 0..nz - 1 {
        for y in 0..ny - 1 {
            for x in 0..nx - 1 {
                for order in AXIS_ORDERS {
                    let mut c = [x, y, z];
                    let mut t = [id(c); 4];
                    for (j, &axis) in order.iter().enumerate() {
                        c[axis] += 1;
                        t[j + 1] = id(c);
                    }
                    tets.push(t);
                }
            }
        }
    }
    tets
}
