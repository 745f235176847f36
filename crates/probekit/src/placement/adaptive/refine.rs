//! The refine/decimate loop: greedy insertion of the worst pool points with
//! spawned candidates around them, decimation by removal cost, and the
//! farthest-point seed set.

use super::scoring::{energy, sq_error, LEAK_SHARE};
use super::{has_clearance, Adaptive, Scores, PROBE_CLEARANCE};
use crate::delaunay::tetrahedralize;
use crate::placement::PlacementError;
use crate::progress::Progress;
use crate::sampling::SampleRng;
use crate::trace::free_space::segment_clear;
use crate::trace::Ray;
use glam::Vec3;
use probekit_runtime::cloud::WalkState;
use probekit_sh::ShRgb;
use rayon::prelude::*;

/// New candidates spawned around each inserted probe.
const SPAWN: usize = 4;

impl Adaptive<'_, '_, '_> {
    pub(super) fn push_pool(&mut self, i: usize) {
        self.pool.probe[i] = Some(self.st.positions.len());
        self.origin.push(Some(i));
        self.st.positions.push(self.pool.pos[i]);
        self.st.sh.push(self.pool.sh[i].clone());
    }

    /// Inserts up to `count` of the worst pool points, spaced out: first up
    /// to [`LEAK_SHARE`] of `count` among those that fail the leak test, then
    /// the rest by rank.
    pub(super) fn insert_worst(&mut self, s: &Scores, count: usize) -> usize {
        let leak_count = ((LEAK_SHARE * count as f32).ceil() as usize).min(count);
        self.insert_ranked(s, leak_count, count)
    }

    /// Inserts, spaced out, up to `leak_count` leaking pool points by rank,
    /// then more by rank while fewer than `count` are chosen (none when
    /// `count` is 0: leaks only).
    pub(super) fn insert_ranked(&mut self, s: &Scores, leak_count: usize, count: usize) -> usize {
        let mut order: Vec<usize> = (0..s.err.len())
            .filter(|&i| self.pool.probe[i].is_none() && s.rank[i] > 0.0)
            .collect();
        order.sort_by(|&a, &b| s.rank[b].total_cmp(&s.rank[a]).then(a.cmp(&b)));
        let leaking: Vec<usize> = order.iter().copied().filter(|&i| s.leak[i]).collect();
        let mut chosen: Vec<usize> = Vec::with_capacity(count);
        for (limit, list) in [(leak_count, &leaking), (count, &order)] {
            for &i in list {
                if chosen.len() >= limit {
                    break;
                }
                let p = self.pool.pos[i];
                let r = 0.5 * s.near[i];
                if chosen
                    .iter()
                    .all(|&c| c != i && self.pool.pos[c].distance_squared(p) >= r * r)
                {
                    chosen.push(i);
                }
            }
        }
        for &i in &chosen {
            self.push_pool(i);
        }
        chosen.len()
    }

    /// Refines the pool around newly inserted probes: [`SPAWN`] candidates at
    /// half the distance to the nearest other probe, in jittered tetrahedral
    /// directions, captured now. Where the lighting needed a probe, finer
    /// candidates follow.
    pub(super) fn spawn_candidates(
        &mut self,
        s: &Scores,
        inserted: &[usize],
    ) -> Result<(), PlacementError> {
        const DIRS: [[f32; 3]; 4] = [
            [1.0, 1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
        ];
        self.st.lap("scoring");
        let tracer = self.st.baker.tracer();
        let mut cands = Vec::with_capacity(SPAWN * inserted.len());
        for &i in inserted {
            let r = 0.5 * s.near[i];
            if r.is_nan() || r <= 2.0 * PROBE_CLEARANCE {
                continue;
            }
            let mut rng = SampleRng::new(
                self.st.settings.seed,
                0x5350_574e,
                (self.pool.pos.len() + i) as u64,
            );
            for d in DIRS.iter().take(SPAWN) {
                let j = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
                let dir = (Vec3::from(*d).normalize() + 0.5 * j).normalize_or_zero();
                // Onto the layers along the box's faces (`snap_to_layer`).
                let o = self.pool.pos[i];
                cands.push((o, self.st.snap_point(o + r * dir)));
            }
        }
        let n = cands.len();
        // In the bake box and seen from the probe it refines: a candidate
        // behind a wall (or outside the building, beyond an outer wall)
        // does not refine this probe's neighbourhood, and one outside sees
        // the sky and sun (BENCHMARKS.md, "Placement against uniform grids").
        let bbox = self.bbox;
        let cands: Vec<Vec3> = cands
            .into_par_iter()
            .filter_map(|(o, p)| {
                let (dir, r) = ((p - o).normalize_or_zero(), p.distance(o));
                (dir != Vec3::ZERO
                    && bbox.contains(p)
                    && tracer
                        .closest_hit(&Ray::new(o, dir), r + PROBE_CLEARANCE)
                        .is_none()
                    && has_clearance(tracer, p))
                .then_some(p)
            })
            .collect();
        self.st.stats.rejected_inside += n - cands.len();
        // They keep the clearance: captured in free space.
        let first = self.st.next_index;
        let captured = self.st.capture_free(&cands, first)?;
        self.st.next_index += cands.len();
        let captured = captured.into_iter().flatten();
        for (p, sh) in captured.filter(|(p, _)| bbox.contains(*p)) {
            self.pool.energy.push(energy(&self.w, &sh));
            self.pool.pos.push(p);
            self.pool.sh.push(sh);
            self.pool.probe.push(None);
        }
        self.st.lap("candidates");
        Ok(())
    }

    /// Greedy insertion until `target` probes or the tolerance is met;
    /// returns `true` when the tolerance was met.
    pub(super) fn refine_to(
        &mut self,
        target: usize,
        tolerance: f32,
        progress: Progress<'_>,
        budget: usize,
    ) -> Result<bool, PlacementError> {
        let r = self.refine_rounds(target, tolerance, progress, budget);
        self.st.lap("scoring");
        r
    }

    /// The rounds of [`Self::refine_to`].
    fn refine_rounds(
        &mut self,
        target: usize,
        tolerance: f32,
        progress: Progress<'_>,
        budget: usize,
    ) -> Result<bool, PlacementError> {
        while self.st.positions.len() < target {
            self.st.stats.rounds += 1;
            let Some(s) = self.score()? else {
                return Ok(false);
            };
            let e = self.rel_rmse(&s);
            self.st.stats.last_mean_error = Some(e);
            if e <= tolerance {
                return Ok(true);
            }
            let n = self.st.positions.len();
            let batch = (n / 10).max(1).min(target - n);
            let first = self.st.positions.len();
            if self.insert_worst(&s, batch) == 0 {
                return Ok(false);
            }
            let inserted: Vec<usize> = self.origin[first..].iter().flatten().copied().collect();
            self.spawn_candidates(&s, &inserted)?;
            progress("adaptive", self.st.positions.len(), budget);
        }
        Ok(false)
    }

    /// Removes up to `count` cheap probes (an independent set of pool
    /// probes; see the module docs). Returns how many were removed.
    pub(super) fn decimate(&mut self, count: usize) -> Result<usize, PlacementError> {
        let pos = &self.st.positions;
        let tri = tetrahedralize(pos)?;
        let n = pos.len();
        let mut star: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (t, v) in tri.tets.iter().enumerate() {
            for &k in v {
                star[k as usize].push(t as u32);
            }
        }
        let tet_volume = |t: u32| -> f32 {
            let v = tri.tets[t as usize].map(|k| pos[k as usize]);
            ((v[1] - v[0]).cross(v[2] - v[0]).dot(v[3] - v[0]) / 6.0).abs()
        };
        let costs: Vec<(f32, usize)> = (0..n)
            .into_par_iter()
            .map(|j| {
                if self.origin[j].is_none() || star[j].is_empty() {
                    return (f32::INFINITY, j);
                }
                let mut link: Vec<u32> = star[j]
                    .iter()
                    .flat_map(|&t| tri.tets[t as usize])
                    .filter(|&k| k as usize != j)
                    .collect();
                link.sort_unstable();
                link.dedup();
                let lp: Vec<Vec3> = link.iter().map(|&k| pos[k as usize]).collect();
                let Ok(local) = tetrahedralize(&lp) else {
                    return (f32::INFINITY, j);
                };
                let Ok(mesh) = local.to_tet_mesh(&lp) else {
                    return (f32::INFINITY, j);
                };
                let (idx, wt) = mesh.weights_at(pos[j], &mut WalkState::new());
                let mut pred = ShRgb::zeros(self.st.sh[j].order());
                for k in 0..4 {
                    if wt[k] != 0.0 {
                        pred.add_scaled(&self.st.sh[link[idx[k] as usize] as usize], wt[k]);
                    }
                }
                let vol: f32 = star[j].iter().map(|&t| tet_volume(t)).sum();
                (sq_error(&self.w, &pred, &self.st.sh[j]) * vol, j)
            })
            .collect();
        let mut order = costs;
        order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut locked = vec![false; n];
        let mut remove = vec![false; n];
        let mut removed = 0;
        for (c, j) in order {
            if removed >= count || !c.is_finite() {
                break;
            }
            if locked[j] {
                continue;
            }
            remove[j] = true;
            removed += 1;
            for &t in &star[j] {
                for k in tri.tets[t as usize] {
                    locked[k as usize] = true;
                }
            }
        }
        // Compact the probe arrays, keeping the pool's back-references right.
        let st = &mut *self.st;
        let mut keep = 0;
        for (j, &gone) in remove.iter().enumerate() {
            if gone {
                if let Some(i) = self.origin[j] {
                    self.pool.probe[i] = None;
                }
                continue;
            }
            st.positions.swap(keep, j);
            st.sh.swap(keep, j);
            self.origin.swap(keep, j);
            if let Some(i) = self.origin[keep] {
                self.pool.probe[i] = Some(keep);
            }
            keep += 1;
        }
        st.positions.truncate(keep);
        st.sh.truncate(keep);
        self.origin.truncate(keep);
        st.lap("decimation");
        Ok(removed)
    }
}

/// Factor on the distance between two pool points that cannot see each
/// other, in the seed set's farthest-point sampling ([`farthest_points`]).
const OCCLUDED_DISTANCE_FACTOR: f32 = 4.0;

/// Farthest-point sampling of `k` pool points, starting from the one
/// nearest the box's minimum corner. With a tracer, a point hidden from a
/// chosen one (a surface on the segment between them) counts
/// [`OCCLUDED_DISTANCE_FACTOR`] times as far from it, so rooms and closets
/// behind walls get seeds of their own even when they are close in space.
pub(super) fn farthest_points(
    pos: &[Vec3],
    start: Vec3,
    k: usize,
    tracer: Option<&crate::trace::Tracer<'_>>,
) -> Vec<usize> {
    if pos.is_empty() {
        return Vec::new();
    }
    let first = (0..pos.len())
        .min_by(|&a, &b| {
            pos[a]
                .distance_squared(start)
                .total_cmp(&pos[b].distance_squared(start))
                .then(a.cmp(&b))
        })
        .unwrap_or(0);
    let mut d = vec![f32::INFINITY; pos.len()];
    let mut out = Vec::new();
    let mut next = first;
    loop {
        out.push(next);
        let c = pos[next];
        d.par_iter_mut().zip(pos).for_each(|(dj, p)| {
            let e = p.distance_squared(c);
            if e < *dj {
                let hidden = tracer.is_some_and(|t| !segment_clear(t, c, *p));
                let f = if hidden {
                    OCCLUDED_DISTANCE_FACTOR * OCCLUDED_DISTANCE_FACTOR
                } else {
                    1.0
                };
                *dj = dj.min(e * f);
            }
        });
        if out.len() >= k.min(pos.len()) {
            break;
        }
        let (i, _) = d
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))
            .unwrap_or((0, &0.0));
        if d[i] <= 0.0 {
            break;
        }
        next = i;
    }
    out
}
