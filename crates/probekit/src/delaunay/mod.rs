//! Exact 3D Delaunay tetrahedralization of probe positions: the structure
//! of a probe cloud. Imports only the sampling RNG (for the insertion order).
//!
//! [`tetrahedralize`] is an incremental Bowyer–Watson construction
//! (Bowyer 1981, Watson 1981; as in Sukys 2014, "Light probe cloud generation
//! for games", §"Delaunay tessellation") in the style
//! of CGAL's `Delaunay_triangulation_3`:
//!
//! * **Point at infinity.** The convex hull is closed by *infinite cells*
//!   `(a, b, c, ∞)`, one per hull face, so a point outside the current hull is
//!   located and inserted exactly like one inside; no bounding box or extra
//!   probes are added (unlike Sukys 2014, which encloses the cloud in a box).
//! * **Spatial sort.** Points are inserted in BRIO order (`order.rs`; Amenta, Choi & Rote,
//!   "Incremental constructions con BRIO", 2003): a seeded shuffle split into
//!   rounds of doubling size, each round sorted along a Morton (Z-order) curve,
//!   so consecutive points are close and the location walk is short.
//! * **Location** is a stochastic visibility walk (Devillers, Pion & Teillaud,
//!   "Walking in a triangulation", 2002) from the last created cell.
//! * **Exactness.** Every decision is an exact predicate from
//!   [`predicates`] (a [`predicates::Kernel`] for the point set: static and
//!   semi-static floating-point filters, then an exact `f64`/`i128` lattice
//!   evaluation or Shewchuk's adaptive orient3d/insphere via the `robust`
//!   crate), and co-spherical ties — every cube of a regular grid — are broken
//!   by the symbolic lifting perturbation of Devillers & Teillaud (2011), so the
//!   result is the unique Delaunay triangulation of the perturbed points: no
//!   zero-volume tetrahedron, whatever the degeneracy. Perturbation ranks are
//!   the input indices, so the output does not depend on insertion order.
//! * **Memory.** The builder numbers points in insertion order and keeps
//!   each cell's vertices, neighbours and cavity mark in one record, so that
//!   the cells and points touched by one insertion share cache lines.
//! * **Duplicates** (bit-identical positions, `-0.0 == 0.0`) are merged before
//!   insertion: the lowest index is kept and the pair is reported in
//!   [`Tetrahedralization::merged_duplicates`].
//!
//! The result converts to the runtime's [`probekit_runtime::cloud::TetMesh`]
//! with [`Tetrahedralization::to_tet_mesh`].

mod builder;
mod order;
pub mod predicates;

use builder::{Builder, FACE, LOCAL_LINK_MAX};
use glam::Vec3;
use order::{brio_order, merge_duplicates};
use predicates::{InSphere, Orientation, P3};
use thiserror::Error;

/// Why a point set cannot be tetrahedralized.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum DelaunayError {
    /// A coordinate is NaN or infinite.
    #[error("probe {index} has a non-finite position {position:?}")]
    NonFinite {
        /// Index of the offending point in the input.
        index: usize,
        /// Its coordinates.
        position: [f32; 3],
    },
    /// Fewer than four distinct points (after merging duplicates).
    #[error("need at least 4 distinct probe positions, got {distinct}")]
    TooFewPoints {
        /// Number of distinct positions.
        distinct: usize,
    },
    /// All points lie on one line.
    #[error("all probe positions are co-linear: no volume to tetrahedralize")]
    Collinear,
    /// All points lie in one plane.
    #[error("all probe positions are co-planar: no volume to tetrahedralize")]
    Coplanar,
    /// More points than 32-bit indices can address.
    #[error("too many probes: {count} (at most {max})")]
    TooManyPoints {
        /// Number of points given.
        count: usize,
        /// Largest supported count.
        max: usize,
    },
    /// The tetrahedralization needs more cells than 32-bit cell indices can
    /// address (about 6.7 cells per point in general position, so some
    /// 600 M points; far fewer in degenerate configurations, where the cell
    /// count can grow quadratically).
    #[error("too many tetrahedra: the probes need more than {max} cells")]
    TooManyCells {
        /// Largest supported number of cell slots.
        max: usize,
    },
}

/// Largest number of input points: indices are `u32`, with two values reserved
/// as markers (point at infinity, free cell).
pub const MAX_POINTS: usize = (u32::MAX - 2) as usize;

/// Most cell slots the builder may hold: slot indices stay below the
/// builder's `FREE` and `HULL` markers (`u32::MAX - 1`, `u32::MAX`).
const MAX_CELLS: usize = (u32::MAX - 2) as usize;

/// Neighbour marker for a face on the convex hull.
pub const HULL: u32 = u32::MAX;

/// A Delaunay tetrahedralization of a set of points.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Tetrahedralization {
    /// Tetrahedra as indices into the input points, positively oriented
    /// (`det[b − a, c − a, d − a] > 0`, see [`predicates::Orientation`]).
    pub tets: Vec<[u32; 4]>,
    /// `neighbors[t][i]` is the tetrahedron sharing the face opposite vertex
    /// `i` of `tets[t]`, or [`HULL`] (`u32::MAX`) on the convex hull.
    pub neighbors: Vec<[u32; 4]>,
    /// Duplicate positions that were merged: `(dropped, kept)` input indices,
    /// sorted by `dropped`. A dropped index appears in no tetrahedron.
    pub merged_duplicates: Vec<(u32, u32)>,
}

/// Computes the Delaunay tetrahedralization of `points` (metres, any frame).
///
/// Exact on degenerate input (see the module docs). Errors: any NaN/infinite
/// coordinate, fewer than 4 distinct points, all points co-linear or co-planar,
/// more than [`MAX_POINTS`] points.
pub fn tetrahedralize(points: &[Vec3]) -> Result<Tetrahedralization, DelaunayError> {
    tetrahedralize_with(points, LOCAL_LINK_MAX, MAX_CELLS)
}

/// [`tetrahedralize`] with a given [`Builder::local_link_max`] (tests use 0 to
/// check that the hashed linking gives the same output) and cell limit
/// (tests lower it to reach [`DelaunayError::TooManyCells`]).
fn tetrahedralize_with(
    points: &[Vec3],
    local_link_max: usize,
    max_cells: usize,
) -> Result<Tetrahedralization, DelaunayError> {
    if points.len() > MAX_POINTS {
        return Err(DelaunayError::TooManyPoints {
            count: points.len(),
            max: MAX_POINTS,
        });
    }
    for (index, p) in points.iter().enumerate() {
        if !p.is_finite() {
            return Err(DelaunayError::NonFinite {
                index,
                position: p.to_array(),
            });
        }
    }
    // `+ 0.0` turns -0.0 into +0.0 so that equal positions have equal bits.
    let pts: Vec<P3> = points
        .iter()
        .map(|p| [p.x as f64 + 0.0, p.y as f64 + 0.0, p.z as f64 + 0.0])
        .collect();
    let (unique, merged_duplicates) = merge_duplicates(&pts);
    if unique.len() < 4 {
        return Err(DelaunayError::TooFewPoints {
            distinct: unique.len(),
        });
    }
    // The builder numbers points in insertion order, so that the points of
    // nearby cells are nearby in memory; `order` maps back to input indices,
    // which stay the perturbation ranks.
    let order = brio_order(&pts, unique);
    let sorted: Vec<P3> = order.iter().map(|&i| pts[i as usize]).collect();
    let mut builder = Builder::new(&sorted, &order, local_link_max, max_cells);
    let rest = builder.init()?;
    for &v in &rest {
        builder.insert(v)?;
    }
    let (tets, neighbors) = builder.finish();
    Ok(Tetrahedralization {
        tets,
        neighbors,
        merged_duplicates,
    })
}

/// `6·volume / (longest edge)³` of the tetrahedron `p`, in `f64` from the
/// `f32` positions: 0 for a flat one, `√2 ≈ 1.41` for a regular one.
pub fn flatness(p: [Vec3; 4]) -> f64 {
    let q = p.map(|v| v.as_dvec3());
    let vol6 = (q[1] - q[0]).cross(q[2] - q[0]).dot(q[3] - q[0]).abs();
    let mut longest = 0.0f64;
    for i in 0..4 {
        for j in i + 1..4 {
            longest = longest.max(q[i].distance(q[j]));
        }
    }
    if longest > 0.0 {
        vol6 / longest.powi(3)
    } else {
        0.0
    }
}

/// [`flatness`] under which [`hull_slivers`] counts a tetrahedron.
pub const SLIVER_FLATNESS: f64 = 1e-6;

/// Tetrahedra with a face on the convex hull ([`probekit_runtime::cloud::HULL`]
/// neighbour) whose [`flatness`] is below [`SLIVER_FLATNESS`]: probes
/// co-planar with a hull face only up to rounding. The exact
/// tetrahedralization is right to keep them, but their hull triangles can
/// reach metres past the probes next to a query point outside the hull,
/// which is then lit from far-away probes, even through a wall
/// (BENCHMARKS.md, "Hull slivers"; adaptive placement avoids them with
/// `placement::snap_to_layer`). `tets` and `neighbours` as in a file's
/// `TETS` section; indices out of range are skipped.
pub fn hull_slivers(positions: &[Vec3], tets: &[[u32; 4]], neighbours: &[[u32; 4]]) -> usize {
    tets.iter()
        .zip(neighbours)
        .filter(|(_, n)| n.contains(&probekit_runtime::cloud::HULL))
        .filter_map(|(v, _)| {
            let p = |k: usize| positions.get(v[k] as usize).copied();
            Some(flatness([p(0)?, p(1)?, p(2)?, p(3)?]))
        })
        .filter(|&f| f < SLIVER_FLATNESS)
        .count()
}

/// Probes (indices below `probe_count`) that no tetrahedron of `tets`
/// uses, in increasing order. In a Delaunay tetrahedralization every
/// distinct position is a vertex, so for [`tetrahedralize`]'s output these
/// are exactly the duplicates it merged
/// ([`Tetrahedralization::merged_duplicates`]): a query never reaches them.
/// `probekit bake` warns about them and `probekit inspect` counts them.
/// Indices out of range are skipped.
pub fn unused_probes(probe_count: usize, tets: &[[u32; 4]]) -> Vec<u32> {
    let mut used = vec![false; probe_count];
    for &i in tets.iter().flatten() {
        if let Some(u) = used.get_mut(i as usize) {
            *u = true;
        }
    }
    (0..probe_count as u32)
        .filter(|&i| !used[i as usize])
        .collect()
}

impl Tetrahedralization {
    /// Builds the runtime query structure for these tetrahedra over `points`
    /// (the same slice given to [`tetrahedralize`]).
    pub fn to_tet_mesh(
        &self,
        points: &[Vec3],
    ) -> Result<probekit_runtime::cloud::TetMesh, probekit_runtime::cloud::CloudError> {
        probekit_runtime::cloud::TetMesh::new(
            points.to_vec(),
            self.tets.clone(),
            self.neighbors.clone(),
        )
    }

    /// Checks every invariant of a Delaunay tetrahedralization of `points`
    /// with exact predicates, returning a description of the first violation:
    ///
    /// * indices in range, no tetrahedron uses a merged duplicate, every other
    ///   point is a vertex;
    /// * every tetrahedron positively oriented (hence none of zero volume);
    /// * neighbour symmetry: `neighbors[t][i] = u` implies `u` points back at
    ///   `t` and the two share exactly the face opposite `i`;
    /// * locally Delaunay: the vertex of each neighbour opposite the shared face
    ///   is not strictly inside the circumsphere (exact insphere; co-spherical
    ///   allowed) — with the above this implies the global empty-sphere property;
    /// * the hull (faces without neighbour) is closed: each directed hull edge
    ///   appears once and its reverse once; and convex at every edge (exact
    ///   orient3d), so a cavity left inside the mesh is caught;
    /// * the tetrahedra's volumes sum to the volume enclosed by the hull
    ///   (divergence theorem over hull faces; relative tolerance 1e-9 in `f64`).
    ///
    /// Used by the tests and fuzzing; O(n log n) and allocation-heavy — not for
    /// hot paths.
    pub fn sanity_check(&self, points: &[Vec3]) -> Result<(), String> {
        let pts: Vec<P3> = points.iter().map(|p| p.as_dvec3().to_array()).collect();
        let n = pts.len();
        if self.tets.len() != self.neighbors.len() {
            return Err("tets and neighbors differ in length".into());
        }
        for (t, v) in self.tets.iter().enumerate() {
            if let Some(&x) = v.iter().find(|&&x| x as usize >= n) {
                return Err(format!("tet {t} has vertex {x} out of range"));
            }
            let q = v.map(|x| &pts[x as usize]);
            if predicates::orient3d(q[0], q[1], q[2], q[3]) != Orientation::Positive {
                return Err(format!("tet {t} {v:?} is not positively oriented"));
            }
        }
        let dropped: std::collections::HashSet<u32> =
            self.merged_duplicates.iter().map(|&(d, _)| d).collect();
        let unused: std::collections::HashSet<u32> =
            unused_probes(n, &self.tets).into_iter().collect();
        if let Some(&i) = unused.symmetric_difference(&dropped).min() {
            return Err(if unused.contains(&i) {
                format!("point {i} is in no tetrahedron and not a merged duplicate")
            } else {
                format!("point {i} is a merged duplicate but a tetrahedron uses it")
            });
        }
        for &(d, k) in &self.merged_duplicates {
            if pts[d as usize] != pts[k as usize] || k >= d {
                return Err(format!("bad duplicate pair ({d}, {k})"));
            }
        }
        let mut hull_edges = std::collections::HashMap::new();
        let mut hull_volume6 = 0.0f64;
        let mut volume6 = 0.0f64;
        let mut scale = 0.0f64;
        for (t, v) in self.tets.iter().enumerate() {
            let q = v.map(|x| glam::DVec3::from_array(pts[x as usize]));
            let vol6 = (q[1] - q[0]).cross(q[2] - q[0]).dot(q[3] - q[0]);
            volume6 += vol6;
            scale += vol6.abs();
            for i in 0..4 {
                let f = FACE[i].map(|k| v[k]);
                let u = self.neighbors[t][i];
                if u == HULL {
                    // Outward face orientation is (f1, f0, f2).
                    let (a, b, c) = (f[1], f[0], f[2]);
                    for (e, opposite) in [((a, b), c), ((b, c), a), ((c, a), b)] {
                        if hull_edges.insert(e, opposite).is_some() {
                            return Err(format!("hull edge {e:?} used twice in one direction"));
                        }
                    }
                    let (pa, pb, pc) = (q[FACE[i][1]], q[FACE[i][0]], q[FACE[i][2]]);
                    hull_volume6 += pa.dot(pb.cross(pc));
                    continue;
                }
                let Some(w) = self.neighbors.get(u as usize) else {
                    return Err(format!("tet {t} neighbour {u} out of range"));
                };
                let Some(j) = (0..4).find(|&j| w[j] == t as u32) else {
                    return Err(format!("tet {t} -> {u} is not symmetric"));
                };
                let uv = self.tets[u as usize];
                let mut shared_a: Vec<u32> = f.to_vec();
                let mut shared_b: Vec<u32> = (0..4).filter(|&k| k != j).map(|k| uv[k]).collect();
                shared_a.sort_unstable();
                shared_b.sort_unstable();
                if shared_a != shared_b {
                    return Err(format!("tets {t} and {u} do not share the expected face"));
                }
                let opp = &pts[uv[j] as usize];
                let tq = v.map(|x| &pts[x as usize]);
                if predicates::insphere_exact(tq, opp) == Some(InSphere::Inside) {
                    return Err(format!(
                        "tet {t}: vertex {} of {u} is inside its circumsphere",
                        uv[j]
                    ));
                }
            }
        }
        for (&(a, b), &c) in &hull_edges {
            let Some(&d) = hull_edges.get(&(b, a)) else {
                return Err(format!("hull is open at edge ({a}, {b})"));
            };
            // Convex at every hull edge: the other face's far vertex is not
            // strictly outside this face (outward-wound faces have the
            // tetrahedra on their negative side). A closed, locally convex
            // surface is convex; a cavity inside the mesh is not.
            let q = [a, b, c, d].map(|x| &pts[x as usize]);
            if predicates::orient3d(q[0], q[1], q[2], q[3]) == Orientation::Positive {
                return Err(format!("hull is not convex at edge ({a}, {b})"));
            }
        }
        if (volume6 - hull_volume6).abs() > 1e-9 * scale.max(f64::MIN_POSITIVE) {
            return Err(format!(
                "volume {volume6} != hull volume {hull_volume6} (×6)"
            ));
        }
        Ok(())
    }
}

/// Deterministic point sets shared by the benchmark, the Qhull peer script's
/// point writer (`examples/delaunay_peer.rs`) and the tests.
pub mod bench_points {
    use crate::sampling::SampleRng;
    use glam::Vec3;

    /// `n` points uniform in the unit cube `[0, 1)³` from `seed`.
    pub fn uniform(n: usize, seed: u64) -> Vec<Vec3> {
        let mut rng = SampleRng::from_state(seed);
        let mut u = || rng.next_f32();
        (0..n).map(|_| Vec3::new(u(), u(), u())).collect()
    }

    /// The `k × k × k` regular grid with unit spacing (every cube co-spherical).
    pub fn grid(k: usize) -> Vec<Vec3> {
        let mut v = Vec::with_capacity(k * k * k);
        for z in 0..k {
            for y in 0..k {
                for x in 0..k {
                    v.push(Vec3::new(x as f32, y as f32, z as f32));
                }
            }
        }
        v
    }
}

#[cfg(test)]
mod tests;
