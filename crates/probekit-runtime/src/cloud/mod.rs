//! Probe-cloud queries: which probes light a point, and with what weights.
//!
//! A [`TetMesh`] holds the probe positions and their Delaunay tetrahedra (as
//! produced by the baker's `probekit::delaunay::tetrahedralize`), each with its
//! four neighbours and a precomputed [`BaryMatrix`] (after Cupisz,
//! GDC 2012: "a 3×3 matrix … 9 extra floats per tetrahedron").
//!
//! # Point location
//! [`TetMesh::locate`] walks from the tetrahedron cached in a per-object
//! [`WalkState`]: compute the barycentric coordinates of `p`; if none is below
//! `-INSIDE_TOLERANCE` the point is inside, otherwise step through the face
//! opposite the most negative coordinate (Cupisz, "traversal"). Guards
//! against cycles (possible on faces/edges under rounding):
//!
//! 1. a warm walk longer than [`JUMP_AFTER_STEPS`] restarts from the coarse
//!    start grid (jump-and-walk; a cold [`WalkState`] starts there directly);
//! 2. after [`CYCLE_GUARD_STEPS`] more steps the walk becomes a *remembering
//!    stochastic walk* (Devillers, Pion & Teillaud, "Walking in a
//!    triangulation", 2002): a random face among those with a negative
//!    coordinate, never straight back;
//! 3. if that too exceeds its budget, the best tetrahedron seen (largest
//!    minimum coordinate) is returned — the point is then on a shared
//!    face/edge up to rounding, where all candidates give the same weights.
//!
//! # Outside the convex hull: closest-point outer cells
//! A point outside the probes' convex hull is lit by the probes of the hull
//! feature (face, edge or vertex) closest to it: the weights are the
//! barycentric coordinates of the closest hull point `q` in its hull triangle.
//! The projection onto a convex set is continuous (1-Lipschitz), and on the
//! hull the tetrahedron's barycentric coordinates equal those of its hull
//! face, so interpolated lighting is **continuous across the hull** and
//! everywhere outside it; far away it is constant along the outward normal
//! cone, like Unity's extruded outer cells but without their extrapolation
//! (no negative weights, no blow-up). `q` is found by a descent over hull
//! triangles from the face the tetrahedron walk exited through; hull-face
//! adjacency is precomputed. On a convex polytope the local minimum of the
//! distance is global, so the descent stops at the true closest point.
//!
//! Probes keep a clearance from surfaces, so the band along a room's walls,
//! floor and ceiling is outside the hull, and a hull face over it may join
//! probes of different rooms: there the face's cell visibility is what keeps
//! the far room's light out. On the demo scene at a budget of 121 probes,
//! about a fifth of the free space is outside the hull (one placement) and
//! it holds about a quarter of the leaks (twenty placements; probekit's
//! `eval` reports them as `leaks_outside_hull`; BENCHMARKS.md, "Leaks in
//! sight given a share of each insertion batch").
//!
//! # Cost
//! Queries never allocate. `TetMesh::new` builds the hull adjacency and the
//! start grid once (`O(n)`).

use crate::collections::map_with_capacity;
use crate::prelude::*;
use glam::Vec3;
use thiserror::Error;
use walk::StartGrid;

pub mod cell_visibility;
#[cfg(feature = "write")]
pub mod directional;
#[cfg(not(feature = "write"))]
#[allow(dead_code)]
pub(crate) mod directional;
mod hull;
pub mod probes;
mod topology;
pub mod visibility;
mod walk;

pub use cell_visibility::{CellPlanes, CellVisibility};
pub use probes::{
    ProbeCloud, ProbeCloudError, HIDDEN_MASS_FLOOR, MAX_BRIGHTNESS_EXPONENT, PROBE_WEIGHT_RANGE,
};
// Connectivity for meshes given without it (feature `write`: the baker,
// tools and tests).
#[cfg(feature = "write")]
pub use topology::{face_neighbors, lattice_tets};
pub use visibility::VisibilityMaps;

/// Neighbour marker for a face on the convex hull, as in the baker's output.
pub const HULL: u32 = u32::MAX;

/// Internal neighbour encoding: hull faces are `HULL_BIT | hull face index`.
const HULL_BIT: u32 = 1 << 31;

/// A point is inside a tetrahedron when no barycentric coordinate is below
/// `-INSIDE_TOLERANCE`: rounding in `f32` makes points on a shared face come
/// out slightly negative on both sides; without a tolerance the walk would
/// bounce between them.
pub const INSIDE_TOLERANCE: f32 = 1e-5;

/// A warm walk taking more steps than this jumps to the start grid (the object
/// teleported; the grid is closer than the cached tetrahedron).
pub const JUMP_AFTER_STEPS: u32 = 48;

/// Steps of the deterministic (most-negative-coordinate) walk before it is
/// considered cycling and replaced by the remembering stochastic walk.
pub const CYCLE_GUARD_STEPS: u32 = 4096;

/// Why a [`TetMesh`] cannot be built.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum CloudError {
    /// No tetrahedra.
    #[error("the probe cloud has no tetrahedra")]
    Empty,
    /// `tets` and `neighbors` differ in length.
    #[error("{tets} tetrahedra but {neighbors} neighbour entries")]
    LengthMismatch {
        /// Number of tetrahedra.
        tets: usize,
        /// Number of neighbour entries.
        neighbors: usize,
    },
    /// Too many tetrahedra for the 31-bit index space.
    #[error("too many tetrahedra: {0}")]
    TooManyTets(usize),
    /// A probe position is NaN or infinite.
    #[error("probe {index} has a non-finite position")]
    NonFinitePosition {
        /// Probe index.
        index: usize,
    },
    /// A tetrahedron names a probe that does not exist.
    #[error("tetrahedron {tet} references probe {probe}, but there are only {count}")]
    VertexOutOfRange {
        /// Tetrahedron index.
        tet: usize,
        /// Offending probe index.
        probe: u32,
        /// Number of probes.
        count: usize,
    },
    /// A neighbour index is neither a tetrahedron nor [`HULL`].
    #[error("tetrahedron {tet} has neighbour {neighbor} out of range")]
    NeighborOutOfRange {
        /// Tetrahedron index.
        tet: usize,
        /// Offending neighbour.
        neighbor: u32,
    },
    /// Neighbours do not point back at each other or do not share the face.
    #[error("tetrahedron {tet}: neighbour across face {face} is inconsistent")]
    NeighborMismatch {
        /// Tetrahedron index.
        tet: usize,
        /// Local face (opposite vertex `face`).
        face: usize,
    },
    /// A tetrahedron has zero volume, or a barycentric matrix that overflows `f32`.
    #[error("tetrahedron {tet} is degenerate (zero volume)")]
    DegenerateTet {
        /// Tetrahedron index.
        tet: usize,
    },
    /// The hull faces do not form a closed surface.
    #[error("the convex hull is not closed (edge {a}–{b})")]
    HullNotClosed {
        /// First probe of the offending edge.
        a: u32,
        /// Second probe of the offending edge.
        b: u32,
    },
}

/// World → barycentric map of one tetrahedron `(v0, v1, v2, v3)`:
/// `(λ0, λ1, λ2) = rows · (p − origin)`, `λ3 = 1 − λ0 − λ1 − λ2`, with
/// `origin = v3` and `rows` the inverse of the matrix with columns
/// `v0 − v3, v1 − v3, v2 − v3` (computed in `f64`, stored in `f32`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaryMatrix {
    /// Rows of the inverse edge matrix.
    pub rows: [Vec3; 3],
    /// The fourth vertex `v3`.
    pub origin: Vec3,
}

impl BaryMatrix {
    /// Barycentric coordinates of `p` (sum to 1; all ≥ 0 inside).
    #[inline(always)]
    pub fn coords(&self, p: Vec3) -> [f32; 4] {
        let d = p - self.origin;
        let l0 = self.rows[0].dot(d);
        let l1 = self.rows[1].dot(d);
        let l2 = self.rows[2].dot(d);
        [l0, l1, l2, 1.0 - l0 - l1 - l2]
    }
}

/// One triangle of the convex hull, wound counter-clockwise seen from outside.
#[derive(Clone, Copy, Debug, PartialEq)]
struct HullFace {
    probes: [u32; 3],
    /// `adjacent[k]`: hull face across the edge opposite local vertex `k`.
    adjacent: [u32; 3],
    /// The tetrahedron owning this face.
    tet: u32,
}

/// Per-object walk cache: the last tetrahedron (and hull face) found, plus
/// the state of the stochastic fallback. Start with [`WalkState::new`] (cold).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WalkState {
    tet: u32,
    hull_face: u32,
    rng: u32,
}

impl Default for WalkState {
    fn default() -> Self {
        Self::new()
    }
}

impl WalkState {
    /// A cold state: the first query starts from the coarse start grid.
    pub const fn new() -> Self {
        WalkState {
            tet: u32::MAX,
            hull_face: u32::MAX,
            rng: 0x9E37_79B9,
        }
    }

    /// The tetrahedron the last query ended in (`None` when cold).
    pub fn last_tet(&self) -> Option<u32> {
        (self.tet != u32::MAX).then_some(self.tet)
    }

    fn next_random(&mut self) -> u32 {
        // xorshift32
        let mut x = self.rng;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.rng = x;
        x
    }
}

/// Result of locating a point in the probe cloud.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Location {
    /// Inside (or on the boundary of) tetrahedron `tet`; `weights[i]` belongs
    /// to probe `tets[tet][i]` (barycentric coordinates, sum 1; may be
    /// slightly below 0, at least `-INSIDE_TOLERANCE`, through rounding).
    Inside {
        /// Tetrahedron index.
        tet: u32,
        /// Barycentric coordinates.
        weights: [f32; 4],
    },
    /// Outside the convex hull: lit by the closest hull point `closest`, which
    /// lies in hull triangle `probes` with barycentric `weights` (≥ 0, sum 1;
    /// zero on the vertices of the triangle not in the closest feature).
    Outside {
        /// Index of the hull triangle.
        hull_face: u32,
        /// Probes of that triangle.
        probes: [u32; 3],
        /// Weights of those probes.
        weights: [f32; 3],
        /// The closest point of the convex hull to the query.
        closest: Vec3,
    },
}

/// Per-tetrahedron data the walk reads at each step, packed into one 64-byte
/// cache line (a cold walk step is one memory access, not three).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
struct WalkRecord {
    bary: BaryMatrix,
    /// Neighbour opposite each vertex; hull faces encoded `HULL_BIT | face`.
    links: [u32; 4],
}

const _: () = assert!(core::mem::size_of::<WalkRecord>() == 64);

/// Probe positions with their tetrahedralization, ready for queries.
#[derive(Clone, Debug, PartialEq)]
pub struct TetMesh {
    positions: Vec<Vec3>,
    tets: Vec<[u32; 4]>,
    /// What the walk reads per step, one cache line per tetrahedron.
    walk: Vec<WalkRecord>,
    hull: Vec<HullFace>,
    grid: StartGrid,
}

/// `FACE[k]`: local vertices of the face opposite `k`, wound so that vertex
/// `k` of a positively oriented tetrahedron lies on its positive side.
const FACE: [[usize; 3]; 4] = [[3, 2, 1], [2, 3, 0], [1, 0, 3], [0, 1, 2]];

impl TetMesh {
    /// Builds the query structure from probe positions (metres), tetrahedra
    /// (probe indices, either orientation) and neighbours (`neighbors[t][i]`
    /// opposite vertex `i`, [`HULL`] on the convex hull), validating all of
    /// them: indices in range, neighbour symmetry, non-degenerate
    /// tetrahedra, a closed hull.
    ///
    /// The tetrahedra must fill a **convex** region (as a Delaunay
    /// tetrahedralization does): the walk treats leaving through a hull face
    /// as being outside, and the outer-cell descent relies on convexity.
    /// Convexity itself is not checked.
    pub fn new(
        positions: Vec<Vec3>,
        tets: Vec<[u32; 4]>,
        neighbors: Vec<[u32; 4]>,
    ) -> Result<Self, CloudError> {
        if tets.is_empty() {
            return Err(CloudError::Empty);
        }
        if tets.len() != neighbors.len() {
            return Err(CloudError::LengthMismatch {
                tets: tets.len(),
                neighbors: neighbors.len(),
            });
        }
        if tets.len() >= HULL_BIT as usize {
            return Err(CloudError::TooManyTets(tets.len()));
        }
        if let Some(index) = positions.iter().position(|p| !p.is_finite()) {
            return Err(CloudError::NonFinitePosition { index });
        }
        let count = positions.len();
        let mut bary = Vec::with_capacity(tets.len());
        let mut positive = Vec::with_capacity(tets.len());
        for (t, v) in tets.iter().enumerate() {
            for &probe in v {
                if probe as usize >= count {
                    return Err(CloudError::VertexOutOfRange {
                        tet: t,
                        probe,
                        count,
                    });
                }
            }
            let q = v.map(|i| positions[i as usize].as_dvec3());
            let (e0, e1, e2) = (q[0] - q[3], q[1] - q[3], q[2] - q[3]);
            let det = e0.dot(e1.cross(e2));
            // Only a flat tetrahedron is refused: an exact Delaunay
            // tetrahedralization of near-co-planar probes (leak-prevention
            // probes offset by the same distance from one wall) legitimately
            // holds slivers whose volume is tiny but positive, and a query
            // point rarely falls inside one.
            // Rows of the inverse of [e0 e1 e2] are the cross products / det.
            let rows = [e1.cross(e2) / det, e2.cross(e0) / det, e0.cross(e1) / det];
            if det.is_nan() || det == 0.0 || !rows.iter().all(|r| r.as_vec3().is_finite()) {
                return Err(CloudError::DegenerateTet { tet: t });
            }
            bary.push(BaryMatrix {
                rows: rows.map(|r| r.as_vec3()),
                origin: q[3].as_vec3(),
            });
            positive.push(det < 0.0);
        }
        // Neighbour validation.
        let sorted_face = |t: usize, i: usize| {
            let v = tets[t];
            let mut f = [v[(i + 1) % 4], v[(i + 2) % 4], v[(i + 3) % 4]];
            f.sort_unstable();
            f
        };
        let mut links = neighbors.clone();
        let mut hull = Vec::new();
        for t in 0..tets.len() {
            for i in 0..4 {
                let u = neighbors[t][i];
                if u == HULL {
                    let f = FACE[i].map(|k| tets[t][k]);
                    // For a positive tet (det[b-a,c-a,d-a] > 0, i.e. our
                    // `det < 0` with columns relative to v3), FACE[i] has the
                    // tet on its positive side; reverse it to face outwards.
                    let outward = if positive[t] { [f[1], f[0], f[2]] } else { f };
                    links[t][i] = HULL_BIT | hull.len() as u32;
                    hull.push(HullFace {
                        probes: outward,
                        adjacent: [u32::MAX; 3],
                        tet: t as u32,
                    });
                    continue;
                }
                if u as usize >= tets.len() {
                    return Err(CloudError::NeighborOutOfRange {
                        tet: t,
                        neighbor: u,
                    });
                }
                let back = (0..4).find(|&j| neighbors[u as usize][j] == t as u32);
                match back {
                    Some(j) if sorted_face(t, i) == sorted_face(u as usize, j) => {}
                    _ => return Err(CloudError::NeighborMismatch { tet: t, face: i }),
                }
            }
        }
        // Hull adjacency by matching each directed edge with its reverse.
        let mut edges = map_with_capacity(hull.len() * 3);
        for (h, f) in hull.iter().enumerate() {
            for k in 0..3 {
                let e = (f.probes[(k + 1) % 3], f.probes[(k + 2) % 3]);
                if edges.insert(e, (h as u32, k)).is_some() {
                    return Err(CloudError::HullNotClosed { a: e.0, b: e.1 });
                }
            }
        }
        for face in &mut hull {
            for k in 0..3 {
                let f = face.probes;
                let (a, b) = (f[(k + 1) % 3], f[(k + 2) % 3]);
                match edges.get(&(b, a)) {
                    Some(&(g, _)) => face.adjacent[k] = g,
                    None => return Err(CloudError::HullNotClosed { a, b }),
                }
            }
        }
        let mut mesh = TetMesh {
            positions,
            tets,
            walk: bary
                .into_iter()
                .zip(links)
                .map(|(bary, links)| WalkRecord { bary, links })
                .collect(),
            hull,
            grid: StartGrid {
                origin: Vec3::ZERO,
                cells_per_metre: Vec3::ZERO,
                dims: [1, 1, 1],
                tets: vec![0],
            },
        };
        mesh.grid = mesh.build_start_grid();
        Ok(mesh)
    }

    /// Probe positions.
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// Tetrahedra (probe indices).
    pub fn tets(&self) -> &[[u32; 4]] {
        &self.tets
    }

    /// Neighbour of tetrahedron `tet` across the face opposite local vertex
    /// `face`, `None` on the convex hull.
    pub fn neighbor(&self, tet: u32, face: usize) -> Option<u32> {
        let n = self.walk[tet as usize].links[face];
        (n & HULL_BIT == 0).then_some(n)
    }

    /// The neighbour table as given to [`TetMesh::new`] (`HULL` on the hull),
    /// e.g. for writing the mesh back to a file.
    pub fn neighbors(&self) -> impl ExactSizeIterator<Item = [u32; 4]> + '_ {
        self.walk
            .iter()
            .map(|r| r.links.map(|n| if n & HULL_BIT != 0 { HULL } else { n }))
    }

    /// Barycentric matrix of tetrahedron `tet`.
    pub fn bary(&self, tet: u32) -> &BaryMatrix {
        &self.walk[tet as usize].bary
    }

    /// Number of triangles on the convex hull.
    pub fn hull_face_count(&self) -> usize {
        self.hull.len()
    }

    /// The three probes of hull face `face` (the order of the weights
    /// [`Location::Outside`] gives for it), `None` if out of range.
    pub fn hull_face_probes(&self, face: u32) -> Option<[u32; 3]> {
        self.hull.get(face as usize).map(|h| h.probes)
    }

    /// Locates `p` (metres) starting from the tetrahedron cached in `state`
    /// (or the start grid when cold) and updates the cache. Never allocates.
    pub fn locate(&self, p: Vec3, state: &mut WalkState) -> Location {
        let warm = (state.tet as usize) < self.tets.len();
        let start = if warm { state.tet } else { self.grid.start(p) };
        let (tet, weights, exit) = self.walk(p, start, warm, state);
        state.tet = tet;
        match exit {
            None => Location::Inside { tet, weights },
            Some(face) => {
                let h = self.walk[tet as usize].links[face] & !HULL_BIT;
                let (hull_face, weights, closest) = self.closest_on_hull(p, h);
                state.hull_face = hull_face;
                Location::Outside {
                    hull_face,
                    probes: self.hull[hull_face as usize].probes,
                    weights,
                    closest,
                }
            }
        }
    }

    /// [`Self::locate`] for many points in order, sharing one walk state
    /// (coherent batches walk little). `out` is cleared and refilled; it only
    /// allocates when it must grow.
    pub fn locate_many(&self, points: &[Vec3], state: &mut WalkState, out: &mut Vec<Location>) {
        out.clear();
        out.extend(points.iter().map(|&p| self.locate(p, state)));
    }

    /// Interpolation weights at `p`: four probe indices and their weights
    /// (unused slots have weight 0 and probe index 0), summing to 1, to blend
    /// any per-probe payload (SH coefficients of any codec) linearly.
    pub fn weights_at(&self, p: Vec3, state: &mut WalkState) -> ([u32; 4], [f32; 4]) {
        match self.locate(p, state) {
            Location::Inside { tet, weights } => (self.tets[tet as usize], weights),
            Location::Outside {
                probes, weights, ..
            } => (
                [probes[0], probes[1], probes[2], 0],
                [weights[0], weights[1], weights[2], 0.0],
            ),
        }
    }
}

#[cfg(test)]
mod tests;
