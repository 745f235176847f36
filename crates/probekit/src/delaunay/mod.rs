//! Probe clouds: exact 3D Delaunay tetrahedralization of probe positions.
//!
//! [`tetrahedralize`] is an incremental Bowyer–Watson construction
//! (Bowyer 1981, Watson 1981 — seed 003 §"Delaunay tessellation") in the style
//! of CGAL's `Delaunay_triangulation_3`:
//!
//! * **Point at infinity.** The convex hull is closed by *infinite cells*
//!   `(a, b, c, ∞)`, one per hull face, so a point outside the current hull is
//!   located and inserted exactly like one inside; no bounding box or extra
//!   probes are added (unlike seed 003, which encloses the cloud in a box).
//! * **Spatial sort.** Points are inserted in BRIO order (Amenta, Choi & Rote,
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

pub mod predicates;

use crate::sampling::SampleRng;
use glam::Vec3;
use predicates::{InSphere, Kernel, Orientation, P3};
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

/// Sorts indices by exact position and keeps the lowest index of each group.
fn merge_duplicates(pts: &[P3]) -> (Vec<u32>, Vec<(u32, u32)>) {
    let mut idx: Vec<u32> = (0..pts.len() as u32).collect();
    let key = |i: u32| {
        let p = pts[i as usize];
        (p[0].to_bits(), p[1].to_bits(), p[2].to_bits(), i)
    };
    idx.sort_unstable_by_key(|&i| key(i));
    let mut unique = Vec::with_capacity(pts.len());
    let mut merged = Vec::new();
    let mut g = 0;
    while g < idx.len() {
        let kept = idx[g];
        let mut h = g + 1;
        while h < idx.len() && pts[idx[h] as usize] == pts[kept as usize] {
            merged.push((idx[h], kept));
            h += 1;
        }
        unique.push(kept);
        g = h;
    }
    merged.sort_unstable();
    (unique, merged)
}

/// Spreads the low 21 bits of `v` so that two zero bits follow each bit.
fn spread3(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | (x << 32)) & 0x1f00000000ffff;
    x = (x | (x << 16)) & 0x1f0000ff0000ff;
    x = (x | (x << 8)) & 0x100f00f00f00f00f;
    x = (x | (x << 4)) & 0x10c30c30c30c30c3;
    x = (x | (x << 2)) & 0x1249249249249249;
    x
}

/// BRIO insertion order: seeded shuffle, rounds of doubling size, each sorted
/// by Morton code (21 bits per axis over the bounding box).
fn brio_order(pts: &[P3], mut order: Vec<u32>) -> Vec<u32> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &i in &order {
        for k in 0..3 {
            lo[k] = lo[k].min(pts[i as usize][k]);
            hi[k] = hi[k].max(pts[i as usize][k]);
        }
    }
    let scale: [f64; 3] = std::array::from_fn(|k| {
        let ext = hi[k] - lo[k];
        if ext > 0.0 {
            ((1u64 << 21) - 1) as f64 / ext
        } else {
            0.0
        }
    });
    let morton = |i: u32| {
        let p = pts[i as usize];
        let q = |k: usize| ((p[k] - lo[k]) * scale[k]) as u64;
        spread3(q(0)) | (spread3(q(1)) << 1) | (spread3(q(2)) << 2)
    };
    let mut rng = SampleRng::from_state(0x005E_ED0F_B810);
    for i in (1..order.len()).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        order.swap(i, j);
    }
    // Round boundaries from the end: the last round holds half the points.
    const FIRST_ROUND: usize = 64;
    let mut bounds = vec![order.len()];
    let mut end = order.len();
    while end > FIRST_ROUND {
        end /= 2;
        bounds.push(end);
    }
    bounds.push(0);
    bounds.reverse();
    let mut sorted = Vec::with_capacity(order.len());
    for w in bounds.windows(2) {
        let round: Vec<(u64, u32)> = order[w[0]..w[1]].iter().map(|&i| (morton(i), i)).collect();
        sorted.extend(bucket_sort_by_key(round, 63).into_iter().map(|(_, i)| i));
    }
    sorted
}

/// Sorts `(key, value)` pairs by key, then value, for keys below `2^bits`:
/// one counting-sort pass on the top 12 key bits, then a comparison sort of
/// each (small, cache-resident) bucket. Same order as `sort_unstable` on the
/// pairs, about twice as fast on the builder's ~7 tets per point.
fn bucket_sort_by_key(a: Vec<(u64, u32)>, bits: u32) -> Vec<(u64, u32)> {
    const TOP: u32 = 12;
    let shift = bits.saturating_sub(TOP);
    let bucket = |k: u64| (k >> shift) as usize & ((1 << TOP) - 1);
    let mut start = vec![0usize; (1 << TOP) + 1];
    for &(k, _) in &a {
        start[bucket(k) + 1] += 1;
    }
    for i in 0..1 << TOP {
        start[i + 1] += start[i];
    }
    let mut next = start.clone();
    let mut b = vec![(0u64, 0u32); a.len()];
    for &e in &a {
        let d = bucket(e.0);
        b[next[d]] = e;
        next[d] += 1;
    }
    for w in start.windows(2) {
        b[w[0]..w[1]].sort_unstable();
    }
    b
}

/// The point at infinity.
const INF: u32 = u32::MAX;
/// Marks a cell slot on the free list.
const FREE: u32 = u32::MAX - 1;

/// `FACE[k]`: the face opposite vertex `k`, ordered so that `(f0, f1, f2, v_k)`
/// is an even permutation of the cell, i.e. `v_k` lies on its positive side.
const FACE: [[usize; 3]; 4] = [[3, 2, 1], [2, 3, 0], [1, 0, 3], [0, 1, 2]];

/// One cell of the triangulation under construction.
#[derive(Clone, Copy)]
struct Cell {
    /// Vertices (`INF` for the point at infinity, `FREE` on the free list).
    v: [u32; 4],
    /// Neighbour opposite each vertex.
    n: [u32; 4],
    /// Cavity mark: `2·gen` in conflict, `2·gen + 1` tested and not.
    stamp: u32,
}

struct Builder<'a> {
    /// Points in insertion order; cells refer to them by this position.
    pts: &'a [P3],
    /// Input index (perturbation rank) of each point of `pts`.
    rank: &'a [u32],
    /// Predicates specialised to `pts` (lattice detection, see [`Kernel`]).
    kernel: Kernel,
    /// Vertices, neighbours and cavity mark together (36 bytes): the flood
    /// reads a neighbour's mark and, if untested, its vertices from one record.
    cells: Vec<Cell>,
    /// Current insertion's generation for [`Cell::stamp`].
    gen: u32,
    free: Vec<u32>,
    hint: u32,
    rng: SampleRng,
    // Scratch reused across insertions (no allocation per point in steady state).
    stack: Vec<u32>,
    cavity: Vec<u32>,
    faces: Vec<([u32; 3], u32, u8)>,
    edge_table: Vec<(u64, u32, u8)>,
    edge_used: Vec<usize>,
    /// Largest cavity boundary (vertices) linked by [`Builder::fill_local`];
    /// larger ones use the edge hash table ([`Builder::fill_hashed`]).
    local_link_max: usize,
    /// Most cell slots ([`MAX_CELLS`]; tests lower it to reach the error).
    max_cells: usize,
    /// Per point (and one slot for the point at infinity): its number on the
    /// current cavity boundary, or [`NO_ID`].
    local_id: Vec<u32>,
    /// The slots numbered in `local_id` (one spare entry, see `fill_local`).
    boundary: Vec<u32>,
    /// `link[a·nv + b]`: the new cell on the directed boundary edge `a → b`.
    link: Vec<u32>,
    /// New cells of this insertion with the local numbers of their base face.
    new_cells: Vec<[u32; 4]>,
}

const EMPTY_EDGE: u64 = u64::MAX;
/// [`Builder::local_id`] of a point not on the current cavity boundary.
const NO_ID: u32 = u32::MAX;
/// Default [`Builder::local_link_max`]: a 64 × 64 table (16 KiB) at most.
/// Random points' cavities have ~16 boundary vertices.
const LOCAL_LINK_MAX: usize = 64;

impl<'a> Builder<'a> {
    fn new(pts: &'a [P3], rank: &'a [u32], local_link_max: usize, max_cells: usize) -> Self {
        let cap = pts.len() * 7 + 16;
        Builder {
            pts,
            rank,
            kernel: Kernel::for_points(pts),
            cells: Vec::with_capacity(cap),
            gen: 0,
            free: Vec::new(),
            hint: 0,
            rng: SampleRng::from_state(0xD1CE),
            stack: Vec::new(),
            cavity: Vec::new(),
            faces: Vec::new(),
            edge_table: vec![(EMPTY_EDGE, 0, 0); 256],
            edge_used: Vec::new(),
            local_link_max,
            max_cells,
            local_id: vec![NO_ID; pts.len() + 1],
            boundary: vec![0; local_link_max + 1],
            link: Vec::new(),
            new_cells: Vec::new(),
        }
    }

    #[inline(always)]
    fn p(&self, v: u32) -> &P3 {
        &self.pts[v as usize]
    }

    /// Picks a non-degenerate first tetrahedron from the first points and
    /// returns the remaining points in insertion order.
    fn init(&mut self) -> Result<Vec<u32>, DelaunayError> {
        let order: Vec<u32> = (0..self.pts.len() as u32).collect();
        let a = order[0];
        let b = order[1];
        let ic = (2..order.len())
            .find(|&i| !predicates::collinear(self.p(a), self.p(b), self.p(order[i])))
            .ok_or(DelaunayError::Collinear)?;
        let c = order[ic];
        let id = (2..order.len())
            .find(|&i| {
                predicates::orient3d(self.p(a), self.p(b), self.p(c), self.p(order[i]))
                    != Orientation::Zero
            })
            .ok_or(DelaunayError::Coplanar)?;
        let d = order[id];
        let (a, b) = match predicates::orient3d(self.p(a), self.p(b), self.p(c), self.p(d)) {
            Orientation::Positive => (a, b),
            _ => (b, a),
        };
        let fin = [a, b, c, d];
        self.cells.push(Cell {
            v: fin,
            n: [HULL; 4],
            stamp: 0,
        });
        for face in &FACE {
            let f = face.map(|i| fin[i]);
            self.cells.push(Cell {
                v: [f[1], f[0], f[2], INF],
                n: [HULL; 4],
                stamp: 0,
            });
        }
        for s in 0..5 {
            for t in 0..5 {
                if s == t {
                    continue;
                }
                let (cs, ct) = (self.cells[s].v, self.cells[t].v);
                let missing: Vec<usize> = (0..4).filter(|&i| !ct.contains(&cs[i])).collect();
                if missing.len() == 1 {
                    self.cells[s].n[missing[0]] = t as u32;
                }
            }
        }
        self.hint = 0;
        Ok(order
            .iter()
            .enumerate()
            .filter(|&(i, _)| i != 0 && i != 1 && i != ic && i != id)
            .map(|(_, &v)| v)
            .collect())
    }

    /// Asks the CPU to start loading cell `c`'s record (no effect on results).
    /// The flood stalls on each new neighbour record otherwise; a record is 36
    /// bytes and may straddle two cache lines, so both ends are requested.
    #[inline(always)]
    fn prefetch_cell(&self, c: u32) {
        #[cfg(target_arch = "x86_64")]
        if let Some(cell) = self.cells.get(c as usize) {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            let p = (cell as *const Cell).cast::<i8>();
            // SAFETY: a prefetch never faults and changes no memory; `p` and
            // `p + 35` lie inside the live record `cell` (36 bytes).
            #[allow(unused_unsafe)]
            unsafe {
                _mm_prefetch(p, _MM_HINT_T0);
                _mm_prefetch(p.wrapping_add(std::mem::size_of::<Cell>() - 1), _MM_HINT_T0);
            }
        }
    }

    /// Index of `c` in the neighbour list of `n`.
    #[inline(always)]
    fn back_index(&self, n: u32, c: u32) -> usize {
        let nb = &self.cells[n as usize].n;
        // Exactly one entry is c (the neighbour relation is symmetric and a
        // cell's four neighbours are distinct): sum index × match, branch-free
        // (a search loop mispredicts on the random position).
        debug_assert_eq!(nb.iter().filter(|&&x| x == c).count(), 1);
        usize::from(nb[1] == c) + 2 * usize::from(nb[2] == c) + 3 * usize::from(nb[3] == c)
    }

    /// A cell in conflict with `p`: walk to the cell containing it, or to the
    /// infinite cell beyond the hull face it lies outside of.
    fn locate(&mut self, p: u32) -> u32 {
        let mut c = self.hint;
        if self.cells[c as usize].v[0] == FREE {
            c = (0..self.cells.len() as u32)
                .find(|&i| self.cells[i as usize].v[0] != FREE)
                .unwrap();
        }
        if let Some(k) = self.cells[c as usize].v.iter().position(|&v| v == INF) {
            c = self.cells[c as usize].n[k];
        }
        let pp = *self.p(p);
        let mut prev = HULL;
        'walk: loop {
            let v = self.cells[c as usize].v;
            if v.contains(&INF) {
                return c;
            }
            let nb = self.cells[c as usize].n;
            // The next step (or the flood, if p is in c) reads one of the
            // neighbours: overlap its load with the orientation tests. (prev
            // is prefetched too: it is in cache, and a test would mispredict.)
            for n in nb {
                self.prefetch_cell(n);
            }
            let start = (self.rng.next_u64() & 3) as usize;
            // p is on the positive side of the face we came through (the one
            // with neighbour prev, at index `back`): visit the others in
            // the order start, start + 1, … (mod 4), skipping `back` by
            // index arithmetic rather than a test per face, whose outcome
            // (a random position) the branch predictor gets wrong.
            let (faces, skip) = if prev == HULL {
                (4, 4)
            } else {
                (3, self.back_index(c, prev).wrapping_sub(start) & 3)
            };
            for j in 0..faces {
                let i = (start + j + usize::from(j >= skip)) & 3;
                let n = nb[i];
                let mut q = [self.p(v[0]), self.p(v[1]), self.p(v[2]), self.p(v[3])];
                q[i] = &pp;
                if self.kernel.orient3d(q[0], q[1], q[2], q[3]) == Orientation::Negative {
                    prev = c;
                    c = n;
                    continue 'walk;
                }
            }
            return c;
        }
    }

    /// Does `p` lie in the (perturbed) circumsphere of cell `c`?
    fn conflict(&self, c: u32, p: u32) -> bool {
        let v = self.cells[c as usize].v;
        let pp = self.p(p);
        // Branch-free search for the point at infinity (at most one).
        let inf = v.map(|x| x == INF);
        if inf.contains(&true) {
            let k = inf.iter().position(|&b| b).unwrap_or(0);
            let f = FACE[k].map(|i| v[i]);
            // The finite cell across the hull face and the ranks are only
            // needed when p is co-planar with the face.
            let coplanar = || {
                let n = self.cells[c as usize].n[k];
                let inner = self.p(self.cells[n as usize].v[self.back_index(n, c)]);
                (
                    inner,
                    f.map(|x| self.rank[x as usize]),
                    self.rank[p as usize],
                )
            };
            self.kernel
                .in_infinite_cell([self.p(f[0]), self.p(f[1]), self.p(f[2])], pp, coplanar)
                == InSphere::Inside
        } else {
            let t = [self.p(v[0]), self.p(v[1]), self.p(v[2]), self.p(v[3])];
            match self.kernel.insphere(t, pp) {
                Some(s) => s == InSphere::Inside,
                None => {
                    let rt = v.map(|x| self.rank[x as usize]);
                    self.kernel.perturbed_tie(t, rt, pp, self.rank[p as usize]) == InSphere::Inside
                }
            }
        }
    }

    fn insert(&mut self, p: u32) -> Result<(), DelaunayError> {
        let start = self.locate(p);
        if self.gen >= (u32::MAX >> 1) - 1 {
            self.cells.iter_mut().for_each(|c| c.stamp = 0);
            self.gen = 0;
        }
        self.gen += 1;
        let (gin, gout) = (2 * self.gen, 2 * self.gen + 1);
        self.cavity_and_fill(p, start, gin, gout)
    }

    fn cavity_and_fill(
        &mut self,
        p: u32,
        start: u32,
        gin: u32,
        gout: u32,
    ) -> Result<(), DelaunayError> {
        let mut stack = std::mem::take(&mut self.stack);
        let mut cavity = std::mem::take(&mut self.cavity);
        // Boundary faces are copied out as found, before cavity slots are reused.
        let mut faces = std::mem::take(&mut self.faces);
        stack.clear();
        cavity.clear();
        faces.clear();
        self.cells[start as usize].stamp = gin;
        stack.push(start);
        while let Some(c) = stack.pop() {
            cavity.push(c);
            let cell = self.cells[c as usize];
            // Load the four neighbours' marks up front: independent cache
            // misses overlap instead of stalling one after the other. (A cell
            // has four distinct neighbours, so no mark changes in between.)
            let stamps = cell.n.map(|n| self.cells[n as usize].stamp);
            for (i, &n) in cell.n.iter().enumerate() {
                let s = stamps[i];
                if s == gin {
                    continue;
                }
                if s != gout {
                    if self.conflict(n, p) {
                        self.cells[n as usize].stamp = gin;
                        // n is popped next (DFS); start loading its neighbours'
                        // records (its own is in cache after the conflict test).
                        for m in self.cells[n as usize].n {
                            self.prefetch_cell(m);
                        }
                        stack.push(n);
                        continue;
                    }
                    self.cells[n as usize].stamp = gout;
                }
                let back = self.back_index(n, c) as u8;
                faces.push((FACE[i].map(|k| cell.v[k]), n, back));
            }
        }

        // Cell slots are u32 below the FREE and HULL markers: refuse before
        // an index would wrap (a bound, not an exact count: cavity slots and
        // the free list are reused first).
        if self.cells.len() + faces.len() > self.max_cells {
            return Err(DelaunayError::TooManyCells {
                max: self.max_cells,
            });
        }
        // The cavity's boundary is a triangulated sphere (the cavity is a
        // ball, star-shaped from p), so it has V = F/2 + 2 vertices.
        let boundary_vertices = faces.len() / 2 + 2;
        let (reuse, last) = if boundary_vertices <= self.local_link_max {
            self.fill_local(p, start, &faces, &cavity, boundary_vertices)
        } else {
            self.fill_hashed(p, start, &faces, &cavity)
        };
        // Cavity cells not reused go to the free list.
        for &c in &cavity[..reuse] {
            self.cells[c as usize].v = [FREE; 4];
            self.free.push(c);
        }
        self.hint = last;
        self.stack = stack;
        self.cavity = cavity;
        self.faces = faces;
        Ok(())
    }

    /// Slot for the next new cell: a cavity cell not yet reused, else one
    /// from the free list, else a new record.
    #[inline(always)]
    fn new_cell(&mut self, reuse: &mut usize, cavity: &[u32]) -> u32 {
        if *reuse > 0 {
            *reuse -= 1;
            cavity[*reuse]
        } else if let Some(s) = self.free.pop() {
            s
        } else {
            self.cells.push(Cell {
                v: [FREE; 4],
                n: [HULL; 4],
                stamp: 0,
            });
            (self.cells.len() - 1) as u32
        }
    }

    /// The new cell on boundary face `f` with apex `p` (vertex 3), linked
    /// both ways to `outside`, the cell across `f` (whose neighbour `back`
    /// was the cavity); its three faces through `p` are left for the caller
    /// to link. Shared by [`Builder::fill_local`] and
    /// [`Builder::fill_hashed`].
    #[inline(always)]
    fn open_cell(
        &mut self,
        p: u32,
        f: [u32; 3],
        outside: u32,
        back: u8,
        reuse: &mut usize,
        cavity: &[u32],
    ) -> u32 {
        let nc = self.new_cell(reuse, cavity);
        self.cells[nc as usize].v = [f[0], f[1], f[2], p];
        self.cells[nc as usize].n[3] = outside;
        self.cells[outside as usize].n[back as usize] = nc;
        nc
    }

    /// Joins each boundary face to `p` as a new cell, links it to the cell
    /// outside the face, and links the new cells to each other by local
    /// vertex numbering: the `nv` boundary vertices get numbers `0..nv`
    /// (through `local_id`, a per-point scratch array), and the new cell on
    /// the directed boundary edge `a → b` is stored at `link[a·nv + b]`. The
    /// boundary is a closed oriented surface, so the cell across the face
    /// `(a, b, p)` is the one stored at `link[b·nv + a]`, read in a second
    /// pass. No hashing, no probing and no "seen before?" branch (whose
    /// outcome the branch predictor cannot know), and no clearing: every
    /// entry read was written in this insertion.
    ///
    /// Returns the number of cavity cells not reused and the last new cell.
    fn fill_local(
        &mut self,
        p: u32,
        start: u32,
        faces: &[([u32; 3], u32, u8)],
        cavity: &[u32],
        nv: usize,
    ) -> (usize, u32) {
        let mut new_cells = std::mem::take(&mut self.new_cells);
        new_cells.clear();
        if self.link.len() < nv * nv {
            self.link.resize(nv * nv, 0);
        }
        // The point at infinity has the slot after the last point.
        let inf_slot = self.pts.len();
        let mut count = 0usize;
        let mut reuse = cavity.len();
        let mut last = start;
        for &(f, outside, back) in faces {
            let nc = self.open_cell(p, f, outside, back, &mut reuse, cavity);
            // Number the face's vertices, branch-free: a vertex seen for the
            // first time takes `count` (a branch on "fresh" would be hard to
            // predict).
            let mut id = [0u32; 3];
            for k in 0..3 {
                let slot = (f[k] as usize).min(inf_slot);
                let cur = self.local_id[slot];
                let fresh = cur == NO_ID;
                id[k] = if fresh { count as u32 } else { cur };
                self.local_id[slot] = id[k];
                self.boundary[count] = slot as u32;
                count += usize::from(fresh);
            }
            // Face j of the new cell (opposite f[j]) holds the directed edge
            // f[j+1] → f[j+2].
            for j in 0..3 {
                let (a, b) = (id[(j + 1) % 3] as usize, id[(j + 2) % 3] as usize);
                self.link[a * nv + b] = nc;
            }
            new_cells.push([nc, id[0], id[1], id[2]]);
            last = nc;
        }
        // Not a debug assertion: with more vertices than Euler's formula
        // allows, `link` entries would alias (wrong neighbours, not a crash).
        assert_eq!(count, nv, "cavity boundary is not a sphere");
        for &[nc, a, b, c] in &new_cells {
            let id = [a as usize, b as usize, c as usize];
            for j in 0..3 {
                let across = self.link[id[(j + 2) % 3] * nv + id[(j + 1) % 3]];
                self.cells[nc as usize].n[j] = across;
            }
        }
        for &slot in &self.boundary[..count] {
            self.local_id[slot as usize] = NO_ID;
        }
        self.new_cells = new_cells;
        (reuse, last)
    }

    /// [`Builder::fill_local`] for cavities with too many boundary vertices
    /// for a dense `nv × nv` table: the new cells are linked through a small
    /// linear-probing hash table of undirected edges instead.
    fn fill_hashed(
        &mut self,
        p: u32,
        start: u32,
        faces: &[([u32; 3], u32, u8)],
        cavity: &[u32],
    ) -> (usize, u32) {
        // Size the edge table: 3 half-edges per face, 2 per edge, load <= 1/4.
        let need = (faces.len() * 6).next_power_of_two().max(256);
        if self.edge_table.len() < need {
            self.edge_table = vec![(EMPTY_EDGE, 0, 0); need];
        }
        let mask = self.edge_table.len() - 1;
        let mut reuse = cavity.len();
        let mut last = start;
        for &(f, outside, back) in faces {
            let nc = self.open_cell(p, f, outside, back, &mut reuse, cavity);
            // Faces containing p: the one opposite f[j] holds edge (f[j+1], f[j+2]).
            for j in 0..3 {
                let (a, b) = (f[(j + 1) % 3], f[(j + 2) % 3]);
                let key = if a < b {
                    (a as u64) << 32 | b as u64
                } else {
                    (b as u64) << 32 | a as u64
                };
                let mut h = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32) as usize & mask;
                loop {
                    let e = self.edge_table[h];
                    if e.0 == key {
                        self.cells[nc as usize].n[j] = e.1;
                        self.cells[e.1 as usize].n[e.2 as usize] = nc;
                        break;
                    }
                    if e.0 == EMPTY_EDGE {
                        self.edge_table[h] = (key, nc, j as u8);
                        self.edge_used.push(h);
                        break;
                    }
                    h = (h + 1) & mask;
                }
            }
            last = nc;
        }
        for &h in &self.edge_used {
            self.edge_table[h].0 = EMPTY_EDGE;
        }
        self.edge_used.clear();
        (reuse, last)
    }

    /// The finite cells as output tetrahedra, ordered along a Morton curve of
    /// their centroids, so that neighbouring tetrahedra are close in memory
    /// (the runtime walk touches a few neighbours per query; scattered builder
    /// slots cost a cache miss per step), with vertices mapped from builder
    /// numbering to input indices (`rank`) and neighbours renumbered
    /// ([`HULL`] for infinite cells). Ties between equal Morton codes keep
    /// slot order.
    ///
    /// Reads the cells directly: one sort of `(key, slot)` and one pass that
    /// gathers each cell's vertices and neighbours from its record.
    fn finish(self) -> (Vec<[u32; 4]>, Vec<[u32; 4]>) {
        let pts = self.pts;
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in pts {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let scale: [f64; 3] = std::array::from_fn(|k| {
            ((1u64 << 21) - 1) as f64 / (hi[k] - lo[k]).max(f64::MIN_POSITIVE)
        });
        let keyed: Vec<(u64, u32)> = self
            .cells
            .iter()
            .enumerate()
            .filter(|(_, c)| c.v[0] != FREE && !c.v.contains(&INF))
            .map(|(slot, c)| {
                let q = |k: usize| {
                    let m = c.v.iter().map(|&i| pts[i as usize][k]).sum::<f64>() * 0.25;
                    (((m - lo[k]) * scale[k]) as u64).min((1 << 21) - 1)
                };
                (
                    spread3(q(0)) | (spread3(q(1)) << 1) | (spread3(q(2)) << 2),
                    slot as u32,
                )
            })
            .collect();
        let keyed = bucket_sort_by_key(keyed, 63);
        let mut new_of_old = vec![HULL; self.cells.len()];
        for (new, &(_, old)) in keyed.iter().enumerate() {
            new_of_old[old as usize] = new as u32;
        }
        let mut tets = Vec::with_capacity(keyed.len());
        let mut neighbors = Vec::with_capacity(keyed.len());
        // Records are read in output order, scattered over the slots: each a
        // likely cache miss unless requested some iterations ahead.
        const AHEAD: usize = 16;
        for (k, &(_, old)) in keyed.iter().enumerate() {
            if let Some(&(_, ahead)) = keyed.get(k + AHEAD) {
                self.prefetch_cell(ahead);
            }
            let c = &self.cells[old as usize];
            tets.push(c.v.map(|i| self.rank[i as usize]));
            neighbors.push(c.n.map(|n| new_of_old[n as usize]));
        }
        (tets, neighbors)
    }
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
