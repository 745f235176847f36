//! The incremental Bowyer–Watson builder: cells with the point at infinity,
//! location by a visibility walk, cavities by exact in-sphere tests, and
//! the re-linking of the new cells (see [`super`] for the method).

use super::order::{bucket_sort_by_key, spread3};
use super::predicates::{self, InSphere, Kernel, Orientation, P3};
use super::{DelaunayError, HULL};
use crate::sampling::SampleRng;

/// The point at infinity.
pub(super) const INF: u32 = u32::MAX;

/// Marks a cell slot on the free list.
pub(super) const FREE: u32 = u32::MAX - 1;

/// `FACE[k]`: the face opposite vertex `k`, ordered so that `(f0, f1, f2, v_k)`
/// is an even permutation of the cell, i.e. `v_k` lies on its positive side.
pub(super) const FACE: [[usize; 3]; 4] = [[3, 2, 1], [2, 3, 0], [1, 0, 3], [0, 1, 2]];

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

pub(super) struct Builder<'a> {
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
pub(super) const LOCAL_LINK_MAX: usize = 64;

impl<'a> Builder<'a> {
    pub(super) fn new(
        pts: &'a [P3],
        rank: &'a [u32],
        local_link_max: usize,
        max_cells: usize,
    ) -> Self {
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
    pub(super) fn init(&mut self) -> Result<Vec<u32>, DelaunayError> {
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

    pub(super) fn insert(&mut self, p: u32) -> Result<(), DelaunayError> {
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
    pub(super) fn finish(self) -> (Vec<[u32; 4]>, Vec<[u32; 4]>) {
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
