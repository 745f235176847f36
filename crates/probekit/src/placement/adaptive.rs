//! # `adaptive` placement: greedy refinement and decimation against a captured pool
//!
//! The evaluation (`placement::eval`, `probekit eval`) asks how well the
//! interpolated irradiance matches the truth at random points of free space.
//! `adaptive` optimises that directly, on a *pool* of its own points (never
//! the evaluation's: a different random stream):
//!
//! 1. **Pool.** About `4 × budget` points, jittered-stratified over the bake
//!    box, kept when in free space (not inside geometry, no surface within
//!    [`PROBE_CLEARANCE`]), captured at the placement sample count. The pool
//!    is both the candidate set and the validation set. Around every
//!    positional light it adds shells of candidates at geometrically growing
//!    distances ([`light_shells`]), where the `1/d²` fall-off needs probes
//!    closer together than a uniform pool offers.
//! 2. **Seed set.** `budget / 8` pool points by farthest-point sampling, so
//!    the coarse cloud spans the free space, including its corners.
//! 3. **Greedy insertion.** Tetrahedralize the probes, interpolate at every
//!    pool point that is not a probe, and score it by the squared irradiance
//!    error averaged over all normals, which for radiance SH `L` and the
//!    clamped-cosine band factors `A_l` (Ramamoorthi & Hanrahan 2001) is
//!    exactly `(1/4π) Σ_lm A_l² |ΔL_lm|²` (orthonormality of the basis) — the
//!    same quantity `rel_rmse` averages — plus a small relative term for dark
//!    regions, weighted by the local probe spacing. The worst points are
//!    inserted, a batch of `probes / 10` per round, each at least half its
//!    distance to the nearest probe from the others of the batch, and four
//!    new candidates are captured around each at half that distance, so the
//!    pool refines where the lighting needs probes.
//! 4. **Leak prevention** (seed 003, see [`super`]) with a tenth of the
//!    budget kept in reserve, then insertion up to the budget.
//! 5. **Decimation and swap.** A probe's removal cost is the error of
//!    predicting its own SH from its Delaunay link (its neighbours,
//!    tetrahedralized without it) times the volume of its star (the region
//!    whose interpolation it touches). The cheapest tenth — an independent
//!    set, so the estimates stay valid — is removed and as many pool points
//!    re-inserted by error; two such rounds.
//!
//! It stops early when the estimated relative RMSE over the pool
//! (`sqrt(Σ err / Σ mean-square irradiance)`, the definition of
//! `rel_rmse`) is below the tolerance. The captured pool is noisy (placement
//! samples), which only limits how fine the error ranking can be.

use super::{LeakSettings, PlacementError, State};
use crate::bake::sampling::SampleRng;
use crate::cloud::tetrahedralize;
use crate::scene::{Aabb, Light, LightKind};
use glam::Vec3;
use probekit_runtime::cloud::WalkState;
use probekit_sh::convolve::clamped_cosine_band;
use probekit_sh::project::fibonacci_point;
use probekit_sh::ShRgb;
use rayon::prelude::*;

/// No probe or pool point closer than this to a surface, metres.
pub const PROBE_CLEARANCE: f32 = 0.05;

/// Pool points per unit of budget.
const POOL_FACTOR: usize = 4;

/// Weight of the relative error in the ranking (see [`Adaptive::score`]).
const RELATIVE_WEIGHT: f32 = 0.05;

/// The ranking multiplies each point's error by `d^SPACING_EXPONENT`, `d`
/// its distance to the nearest probe of its tetrahedron: a point far from
/// probes stands for more volume than one next to them (`d³` would be the
/// volume itself). Measured on builtin:demo (docs/bench/placement.md): 1.5
/// beat 0 and 3 at 500 probes and tied at 2000.
const SPACING_EXPONENT: f32 = 1.5;

/// Directions per shell of [`light_shells`].
const LIGHT_SHELL_DIRECTIONS: usize = 24;

/// Ratio of successive shell radii in [`light_shells`].
const LIGHT_SHELL_RATIO: f32 = 1.6;

/// Largest shell radius in [`light_shells`], metres.
const LIGHT_SHELL_MAX: f32 = 2.5;

/// New candidates spawned around each inserted probe.
const SPAWN: usize = 4;

/// `A_l²` per coefficient index, for the mean-square irradiance.
fn band_weights(order: usize) -> Vec<f32> {
    let mut w = Vec::with_capacity(order * order);
    for l in 0..order {
        let a = clamped_cosine_band(l) as f32;
        w.extend(std::iter::repeat(a * a).take(2 * l + 1));
    }
    w
}

/// `Σ_c w_c |a_c − b_c|²`: 4π × the mean over normals of the squared
/// irradiance difference (see the module docs).
fn sq_error(w: &[f32], a: &ShRgb, b: &ShRgb) -> f32 {
    a.coeffs()
        .iter()
        .zip(b.coeffs())
        .zip(w)
        .map(|((x, y), w)| w * (*x - *y).length_squared())
        .sum()
}

/// `Σ_c w_c |a_c|²`.
fn energy(w: &[f32], a: &ShRgb) -> f32 {
    a.coeffs()
        .iter()
        .zip(w)
        .map(|(x, w)| w * x.length_squared())
        .sum()
}

/// About `n` points jittered in the cells of a grid over `b` (seeded).
fn jittered(b: &Aabb, n: usize, seed: u64) -> Vec<Vec3> {
    let size = b.size();
    let cell = (size.x * size.y * size.z / n.max(1) as f32).cbrt();
    let dims = (size / cell).ceil().max(Vec3::ONE);
    let (nx, ny, nz) = (dims.x as usize, dims.y as usize, dims.z as usize);
    let mut out = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let idx = (i + nx * (j + ny * k)) as u64;
                let mut rng = SampleRng::new(seed, 0x504f_4f4c, idx);
                let u = Vec3::new(
                    (i as f32 + rng.next_f32()) / nx as f32,
                    (j as f32 + rng.next_f32()) / ny as f32,
                    (k as f32 + rng.next_f32()) / nz as f32,
                );
                out.push(b.min + u * size);
            }
        }
    }
    out
}

/// Shells of candidates around each positional light (point, spot, sphere,
/// disk): [`LIGHT_SHELL_DIRECTIONS`] spherical-Fibonacci directions at
/// distances growing geometrically by [`LIGHT_SHELL_RATIO`] from just outside
/// the light to [`LIGHT_SHELL_MAX`]. Direct light falls off as `1/d²`, so the
/// probe spacing that keeps linear interpolation's error even grows in
/// proportion to the distance from the light; a uniform pool is far too sparse
/// near a light to offer such positions. They are only candidates: the greedy
/// ranking decides which become probes.
fn light_shells(lights: &[Light], bbox: &Aabb, max_radius: f32) -> Vec<Vec3> {
    let mut out = Vec::new();
    for (li, l) in lights.iter().enumerate() {
        if l.kind == LightKind::Directional || !l.position.is_finite() {
            continue;
        }
        let mut r = (3.0 * l.radius)
            .max(l.radius + 2.0 * PROBE_CLEARANCE)
            .max(0.3);
        let mut shell = 0usize;
        while r <= max_radius {
            // A different rotation per shell, so shells do not line up.
            let rot = glam::Quat::from_rotation_y(2.399_963 * (shell + li) as f32);
            for k in 0..LIGHT_SHELL_DIRECTIONS {
                let d = rot * fibonacci_point(k, LIGHT_SHELL_DIRECTIONS);
                let p = l.position + r * d;
                if bbox.contains(p) {
                    out.push(p);
                }
            }
            r *= LIGHT_SHELL_RATIO;
            shell += 1;
        }
    }
    out
}

/// Candidate pool and which of its points are probes.
struct Pool {
    pos: Vec<Vec3>,
    sh: Vec<ShRgb>,
    energy: Vec<f32>,
    /// Index into the probes, when this pool point is one.
    probe: Vec<Option<usize>>,
}

/// Adaptive state: the placement state plus, per probe, its pool index.
struct Adaptive<'s, 'a, 'b> {
    st: &'s mut State<'a, 'b>,
    pool: Pool,
    origin: Vec<Option<usize>>,
    w: Vec<f32>,
}

/// Per pool point: squared error of the current interpolation (0 for probes)
/// and the distance to the nearest vertex of its tetrahedron.
struct Scores {
    err: Vec<f32>,
    rank: Vec<f32>,
    near: Vec<f32>,
}

impl Adaptive<'_, '_, '_> {
    fn push_pool(&mut self, i: usize) {
        self.pool.probe[i] = Some(self.st.positions.len());
        self.origin.push(Some(i));
        self.st.positions.push(self.pool.pos[i]);
        self.st.sh.push(self.pool.sh[i].clone());
    }

    /// Interpolation error at every pool point.
    fn score(&self) -> Result<Option<Scores>, PlacementError> {
        let tri = tetrahedralize(&self.st.positions)?;
        // The f32 runtime mesh may reject a sliver the exact
        // tetrahedralization keeps; then refinement stops with what it has.
        let Ok(mesh) = tri.to_tet_mesh(&self.st.positions) else {
            return Ok(None);
        };
        const CHUNK: usize = 256;
        let n = self.pool.pos.len();
        let parts: Vec<Vec<(f32, f32)>> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut ws = WalkState::new();
                (c * CHUNK..((c + 1) * CHUNK).min(n))
                    .map(|i| {
                        if self.pool.probe[i].is_some() {
                            return (0.0, 0.0);
                        }
                        let p = self.pool.pos[i];
                        let (idx, wt) = mesh.weights_at(p, &mut ws);
                        let mut pred = ShRgb::zeros(self.pool.sh[i].order());
                        let mut near = f32::INFINITY;
                        for k in 0..4 {
                            let q = self.st.positions[idx[k] as usize];
                            near = near.min(q.distance(p));
                            if wt[k] != 0.0 {
                                pred.add_scaled(&self.st.sh[idx[k] as usize], wt[k]);
                            }
                        }
                        (sq_error(&self.w, &pred, &self.pool.sh[i]), near)
                    })
                    .collect()
            })
            .collect();
        let (err, near): (Vec<f32>, Vec<f32>) = parts.into_iter().flatten().unzip();
        // Rank by the absolute error plus a relative part, so dark regions
        // (where a leak is a large relative error of little energy) are not
        // starved by the bright ones, weighted by the volume the point
        // stands for ([`SPACING_EXPONENT`]).
        let mean = self.pool.energy.iter().map(|&e| e as f64).sum::<f64>()
            / self.pool.energy.len().max(1) as f64;
        let mean = mean as f32;
        let rank = err
            .iter()
            .zip(&self.pool.energy)
            .zip(&near)
            .map(|((&e, &en), &d)| {
                e * (1.0 + RELATIVE_WEIGHT * mean / (en + 1e-4 * mean + 1e-30))
                    * d.powf(SPACING_EXPONENT)
            })
            .collect();
        Ok(Some(Scores { err, rank, near }))
    }

    /// Estimated relative RMSE over the pool points that are not probes.
    fn rel_rmse(&self, s: &Scores) -> f32 {
        let (mut e, mut t) = (0.0f64, 0.0f64);
        for i in 0..s.err.len() {
            if self.pool.probe[i].is_none() {
                e += s.err[i] as f64;
                t += self.pool.energy[i] as f64;
            }
        }
        if t > 0.0 {
            (e / t).sqrt() as f32
        } else {
            0.0
        }
    }

    /// Inserts up to `count` of the worst pool points, spaced out.
    fn insert_worst(&mut self, s: &Scores, count: usize) -> usize {
        let mut order: Vec<usize> = (0..s.err.len())
            .filter(|&i| self.pool.probe[i].is_none() && s.rank[i] > 0.0)
            .collect();
        order.sort_by(|&a, &b| s.rank[b].total_cmp(&s.rank[a]).then(a.cmp(&b)));
        let mut chosen: Vec<usize> = Vec::with_capacity(count);
        for i in order {
            if chosen.len() >= count {
                break;
            }
            let p = self.pool.pos[i];
            let r = 0.5 * s.near[i];
            if chosen
                .iter()
                .all(|&c| self.pool.pos[c].distance_squared(p) >= r * r)
            {
                chosen.push(i);
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
    fn spawn_candidates(&mut self, s: &Scores, inserted: &[usize]) -> Result<(), PlacementError> {
        const DIRS: [[f32; 3]; 4] = [
            [1.0, 1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
        ];
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
                cands.push(self.pool.pos[i] + r * dir);
            }
        }
        let n = cands.len();
        let cands: Vec<Vec3> = cands
            .into_par_iter()
            .filter(|p| super::is_free(tracer, *p, PROBE_CLEARANCE))
            .collect();
        self.st.stats.rejected_inside += n - cands.len();
        for (p, sh) in self.st.capture(&cands)? {
            self.pool.energy.push(energy(&self.w, &sh));
            self.pool.pos.push(p);
            self.pool.sh.push(sh);
            self.pool.probe.push(None);
        }
        Ok(())
    }

    /// Greedy insertion until `target` probes or the tolerance is met;
    /// returns `true` when the tolerance was met.
    fn refine_to(
        &mut self,
        target: usize,
        tolerance: f32,
        progress: &(dyn Fn(&str, usize, usize) + Sync),
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
    fn decimate(&mut self, count: usize) -> Result<usize, PlacementError> {
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
        Ok(removed)
    }
}

/// Farthest-point sampling of `k` pool points, starting from the one
/// nearest the box's minimum corner.
fn farthest_points(pos: &[Vec3], start: Vec3, k: usize) -> Vec<usize> {
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
    let mut d: Vec<f32> = pos.iter().map(|p| p.distance_squared(pos[first])).collect();
    let mut out = vec![first];
    while out.len() < k.min(pos.len()) {
        let (i, _) = d
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))
            .unwrap_or((0, &0.0));
        if d[i] <= 0.0 {
            break;
        }
        out.push(i);
        for (j, dj) in d.iter_mut().enumerate() {
            *dj = dj.min(pos[j].distance_squared(pos[i]));
        }
    }
    out
}

/// Runs `adaptive` placement into `st` (see the module docs).
pub(super) fn adaptive(
    st: &mut State,
    bbox: &Aabb,
    budget: usize,
    tolerance: f32,
    ls: &LeakSettings,
    progress: &(dyn Fn(&str, usize, usize) + Sync),
) -> Result<(), PlacementError> {
    let tracer = st.baker.tracer();
    let raw = jittered(
        bbox,
        (POOL_FACTOR * budget).clamp(512, 60_000),
        st.settings.seed,
    );
    let mut raw = raw;
    // Shells reach out to where the uniform pool is about as dense.
    let size = bbox.size();
    let spacing = (size.x * size.y * size.z / raw.len().max(1) as f32).cbrt();
    raw.extend(light_shells(
        &st.baker.scene().lights,
        bbox,
        (1.5 * spacing).min(LIGHT_SHELL_MAX),
    ));
    let nraw = raw.len();
    let raw: Vec<Vec3> = raw
        .into_par_iter()
        .filter(|p| super::is_free(tracer, *p, PROBE_CLEARANCE))
        .collect();
    st.stats.rejected_inside += nraw - raw.len();
    progress("pool", 0, raw.len());
    let captured = st.capture(&raw)?;
    progress("pool", raw.len(), raw.len());
    let order = captured.first().map_or(1, |c| c.1.order());
    let w = band_weights(order);
    let (pos, sh): (Vec<Vec3>, Vec<ShRgb>) = captured.into_iter().unzip();
    let energy = sh.iter().map(|s| energy(&w, s)).collect();
    let n = pos.len();
    if n < 4 {
        return Err(PlacementError::BadParameter(format!(
            "only {n} free-space points in the bake box; need at least 4"
        )));
    }
    let mut a = Adaptive {
        st,
        pool: Pool {
            pos,
            sh,
            energy,
            probe: vec![None; n],
        },
        origin: Vec::new(),
        w,
    };
    for i in farthest_points(&a.pool.pos, bbox.min, (budget / 8).max(8)) {
        a.push_pool(i);
    }
    progress("adaptive", a.st.positions.len(), budget);
    let reserve = budget / 10;
    let mut done = a.refine_to(budget - reserve, tolerance, progress, budget)?;
    let (_, before) = super::crossing_extent(a.st.baker.tracer(), &a.st.positions)?;
    a.st.stats.crossing_before = before;
    let room = budget.saturating_sub(a.st.positions.len());
    a.st.fix_leaks(ls, room)?;
    a.origin.resize(a.st.positions.len(), None);
    if !done {
        done = a.refine_to(budget, tolerance, progress, budget)?;
    }
    if !done {
        for _ in 0..2 {
            let m = a.decimate((budget / 10).max(1))?;
            if m == 0 {
                break;
            }
            let target = a.st.positions.len() + m;
            if a.refine_to(target, tolerance, progress, budget)? {
                break;
            }
        }
    }
    // A last leak pass for the probes the swaps moved (may add a few percent
    // over the budget).
    a.st.fix_leaks(ls, (budget / 20).max(4))?;
    let (_, after) = super::crossing_extent(a.st.baker.tracer(), &a.st.positions)?;
    a.st.stats.crossing_after = after;
    progress("leaks", a.st.positions.len(), budget);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use probekit_sh::project::fibonacci_point;

    /// The closed form of the mean-square irradiance difference matches a
    /// dense average over normals of `|E_a(n) − E_b(n)|²` (× 4π).
    #[test]
    fn sq_error_is_mean_square_irradiance_difference() {
        let mut rng = SampleRng::new(3, 1, 2);
        let mut r = || rng.next_f32() * 2.0 - 1.0;
        let a = ShRgb::from_coeffs((0..9).map(|_| Vec3::new(r(), r(), r())).collect()).unwrap();
        let b = ShRgb::from_coeffs((0..9).map(|_| Vec3::new(r(), r(), r())).collect()).unwrap();
        let w = band_weights(3);
        let n = 40_000;
        let mut acc = 0.0f64;
        for i in 0..n {
            let d = fibonacci_point(i, n);
            acc += (a.irradiance(d) - b.irradiance(d)).length_squared() as f64;
        }
        let dense = 4.0 * std::f64::consts::PI * acc / n as f64;
        let closed = sq_error(&w, &a, &b) as f64;
        assert!(
            (dense - closed).abs() < 1e-3 * closed,
            "{dense} vs {closed}"
        );
    }

    /// Shell candidates lie at `r0·1.6^k` from the light (r0 = 0.3 m for a
    /// 0.1 m sphere), up to the cap, inside the box only; directional lights
    /// get none.
    #[test]
    fn light_shells_are_geometric_and_inside_the_box() {
        let sphere = Light {
            kind: LightKind::Sphere,
            position: Vec3::new(1.0, 2.9, 1.0),
            direction: Vec3::NEG_Y,
            color: Vec3::ONE,
            intensity: 10.0,
            radius: 0.1,
            inner_angle: 0.0,
            outer_angle: 0.0,
            group: None,
        };
        let sun = Light {
            kind: LightKind::Directional,
            ..sphere.clone()
        };
        let bbox = Aabb {
            min: Vec3::ZERO,
            max: Vec3::new(10.0, 3.0, 10.0),
        };
        let pts = light_shells(&[sphere.clone(), sun], &bbox, 1.0);
        // Radii 0.3, 0.48, 0.768 (≤ 1.0); the shell at 1.2288 is beyond the cap.
        let radii = [0.3f32, 0.48, 0.768];
        assert!(!pts.is_empty());
        for p in &pts {
            assert!(bbox.contains(*p));
            let d = p.distance(sphere.position);
            assert!(
                radii.iter().any(|r| (d - r).abs() < 1e-4),
                "distance {d} is not a shell radius"
            );
        }
        // The ceiling cuts each shell: points above y = 3 are dropped, so
        // fewer than 24 per shell, but the lower half is always there.
        for r in radii {
            let n = pts
                .iter()
                .filter(|p| (p.distance(sphere.position) - r).abs() < 1e-4)
                .count();
            assert!(
                (12..LIGHT_SHELL_DIRECTIONS).contains(&n),
                "shell {r}: {n} points"
            );
        }
    }

    #[test]
    fn farthest_points_spread_out() {
        let pts: Vec<Vec3> = (0..1000)
            .map(|i| {
                let mut r = SampleRng::new(1, 2, i);
                Vec3::new(r.next_f32(), r.next_f32(), r.next_f32())
            })
            .collect();
        let k = farthest_points(&pts, Vec3::ZERO, 8);
        assert_eq!(k.len(), 8);
        // 8 points by FPS in a unit cube are pairwise farther apart than
        // 0.5 (the cube's corners are 1 apart; random 8 would not be).
        for (x, &i) in k.iter().enumerate() {
            for &j in &k[x + 1..] {
                assert!(pts[i].distance(pts[j]) > 0.5);
            }
        }
    }
}
