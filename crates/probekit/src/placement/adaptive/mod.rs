//! # `adaptive` placement: greedy refinement and decimation against a captured pool
//!
//! The evaluation (`eval`, `probekit eval`) asks how well the
//! interpolated irradiance matches the truth at random points of free space.
//! `adaptive` optimises that directly, on a *pool* of its own points (never
//! the evaluation's: a different random stream):
//!
//! 1. **Pool.** About `4 × budget` points, jittered-stratified over the bake
//!    box, kept when in free space (not inside geometry, no surface within
//!    [`PROBE_CLEARANCE`], up to [`CLEARANCE_TOLERANCE`]), captured at the
//!    placement sample count without the virtual offset (they have
//!    clearance), once for both placements of `auto` light shells
//!    ([`capture_pool`]); the outermost layer sits just inside the box's
//!    faces ([`BOUNDARY_SNAP`]), its points exactly co-planar
//!    ([`super::snap_to_layer`]).
//!    The pool is both the candidate set and the validation set. Nothing
//!    outside the bake box is ever a candidate or a probe (through a thin
//!    outer wall a probe sees the sun and sky, and interpolation spreads that
//!    indoors). Along emissive surfaces it adds layers of points 5, 12.5
//!    and 25 cm off them ([`emitter_layers`]): next to an area light the
//!    irradiance changes within centimetres, and a probe may come closer to
//!    an emitter than to other surfaces ([`EMITTER_CLEARANCE`]), so that the
//!    box layer runs on under a ceiling light. With light shells
//!    ([`super::LightShells`]), around every positional light
//!    it adds shells of candidates at geometrically growing distances
//!    ([`light_shells`]), where the `1/d²` fall-off needs probes closer
//!    together than a uniform pool offers, from a quarter of the budget's
//!    mean probe spacing out ([`LIGHT_SHELL_INNER`]). Whether they help
//!    depends on the scene and the budget; by default
//!    ([`super::LightShells::Auto`]) the whole placement runs with and
//!    without them and keeps the one with the lower error at held-out
//!    points ([`held_out_errors`]), stratified so that the lights'
//!    neighbourhoods, where a few points decide the error, are sampled
//!    densely ([`held_out_points`]).
//! 2. **Seed set.** `budget / 8` pool points by farthest-point sampling, so
//!    the coarse cloud spans the free space, including its corners; a point
//!    hidden from a chosen one counts four times as far from it, so closets
//!    and rooms behind walls get seeds of their own.
//! 3. **Greedy insertion.** Tetrahedralize the probes, interpolate at every
//!    pool point that is not a probe — where most of its weight is on
//!    vertices hidden from it, blending only those it sees, as the baked
//!    cloud's cell visibility will ([`scoring_weights`]) — and score it by
//!    the squared irradiance
//!    error averaged over all normals, which for radiance SH `L` and the
//!    clamped-cosine band factors `A_l` (Ramamoorthi & Hanrahan 2001) is
//!    exactly `(1/4π) Σ_lm A_l² |ΔL_lm|²` (orthonormality of the basis) — the
//!    same quantity `rel_rmse` averages — plus a small relative term for dark
//!    regions, weighted by the local probe spacing. The worst points are
//!    inserted, a batch of `probes / 10` per round, each at least half its
//!    distance to the nearest probe from the others of the batch, and four
//!    new candidates are captured around each at half that distance (inside
//!    the box and in sight of it), so the pool refines where the lighting
//!    needs probes. Up to [`LEAK_SHARE`] of each batch goes first to pool
//!    points that leak through geometry: they fail the leak test of `probekit eval`
//!    (interpolated irradiance above 4× the captured one plus 1 % of the
//!    mean, for one of 26 normals) and blend a probe that a surface hides
//!    from them (a tetrahedron or hull face reaching through a wall).
//! 4. **Leak prevention** (Sukys 2014; see [`super`]) with a tenth of the
//!    budget kept in reserve, then insertion up to the budget (less the
//!    allowances of step 6).
//! 5. **Decimation and swap.** A probe's removal cost is the error of
//!    predicting its own SH from its Delaunay link (its neighbours,
//!    tetrahedralized without it) times the volume of its star (the region
//!    whose interpolation it touches). The cheapest tenth — an independent
//!    set, so the estimates stay valid — is removed and as many pool points
//!    re-inserted by error; two such rounds.
//! 6. A last leak-prevention pass, then pool points that still leak, within
//!    a twentieth of the budget; before the pool points, probes for
//!    pockets of free space that see none of their tetrahedron's probes
//!    (behind a wall's end or a closet's corner, which crosses no edge:
//!    [`super::orphan_points`], largest pocket first), within another
//!    twentieth (what they leave goes to the leaking pool points). Both
//!    allowances are kept out of steps 3–5, so the budget is a hard cap: a
//!    placement never has more probes than it.
//!
//! It stops early when the estimated relative RMSE over the pool
//! (`sqrt(Σ err / Σ mean-square irradiance)`, the definition of
//! `rel_rmse`) is below the tolerance. The captured pool is noisy (placement
//! samples), which only limits how fine the error ranking can be.

mod held_out;
mod pool;
mod refine;
mod scoring;
#[cfg(test)]
mod tests;

pub(super) use held_out::held_out_errors;
pub(crate) use held_out::held_out_points;
pub(super) use pool::has_shell_lights;
#[cfg(test)]
pub(super) use pool::BOUNDARY_SNAP;

use super::{LeakSettings, PlacementError, State};
use crate::progress::Progress;
use crate::scene::Aabb;
use glam::Vec3;
use pool::{
    emitter_layers, jittered, layer_box, light_shells, Pool, LIGHT_SHELL_INNER, LIGHT_SHELL_MAX,
};
use probekit_sh::ShRgb;
use rayon::prelude::*;
use refine::farthest_points;
use scoring::{band_weights, leak_normals, mean_irradiance_luminance, Scores};

/// No probe or pool point closer than this to a surface, metres.
pub const PROBE_CLEARANCE: f32 = 0.05;

/// Pool points and spawned candidates keep [`PROBE_CLEARANCE`] from every
/// surface up to this much, metres. A point exactly at the clearance must
/// not be rejected by the rounding of a ray hit: the box layer under the
/// Cornell box's ceiling ([`layer_box`]) is exactly the clearance from it
/// (before, at 6 cm, it was exactly 5 cm under the light, and losing the
/// layer's points there left the probes' hull spanning over the light, so
/// points just under it were lit from the light's edge: BENCHMARKS.md,
/// "Hull slivers").
const CLEARANCE_TOLERANCE: f32 = 1e-3;

/// Pool points and candidates may come this close to an emissive surface
/// (metres), closer than [`PROBE_CLEARANCE`]. Next to an area light the
/// irradiance for normals facing it keeps growing over the last centimetres
/// (Cornell box: 52.8 about 2 cm under its light's middle, 47 at 5 cm), and points
/// between the probes' hull and the light take the nearest hull point's
/// value; the box layer ([`layer_box`]) must run on under a light that
/// hangs 1 cm below the ceiling, 4 cm above the layer, or the hull gets a
/// hole there. Twice the evaluation's 1 cm surface distance. Probes beyond
/// the box layer (closer to the light) are not allowed: they break the
/// hull's plane, and its faces from them to the room's corners lit points
/// under the light at an eighth of their truth (BENCHMARKS.md, "Box layer at
/// the clearance").
pub const EMITTER_CLEARANCE: f32 = 0.02;

/// Whether a pool point or candidate at `p` keeps [`PROBE_CLEARANCE`] from
/// every surface but an emissive one, and [`EMITTER_CLEARANCE`] from those
/// (both up to [`CLEARANCE_TOLERANCE`]), along the 26 rays of
/// [`super::is_free`], and is not inside geometry. A surface hidden behind
/// an emitter (the ceiling a light hangs under) is not seen.
pub(super) fn has_clearance(tracer: &crate::trace::Tracer, p: Vec3) -> bool {
    let scene = tracer.scene();
    crate::trace::free_space::is_free_of(tracer, p, PROBE_CLEARANCE - CLEARANCE_TOLERANCE, |h| {
        h.t < EMITTER_CLEARANCE - CLEARANCE_TOLERANCE
            || scene.emission(h.material, h.uv).max_element() <= 0.0
    })
}

/// Pool points per unit of budget.
const POOL_FACTOR: usize = 4;

/// Rounds of [`super::orphan_points`] at the end of adaptive placement.
const ORPHAN_PASSES: u32 = 2;

/// Adaptive state: the placement state plus, per probe, its pool index.
struct Adaptive<'s, 'a, 'b> {
    pub(super) st: &'s mut State<'a, 'b>,
    pub(super) pool: Pool,
    pub(super) origin: Vec<Option<usize>>,
    pub(super) w: Vec<f32>,
    /// The bake box: no probe or candidate outside it.
    pub(super) bbox: Aabb,
    /// Normals of the leak test ([`leak_normals`]).
    pub(super) normals: Vec<Vec3>,
    /// Leak floor: 1 % of the mean irradiance luminance of the initial pool.
    pub(super) floor: f32,
}

/// The probes kept back from the error-driven placement for its end, out of
/// `budget`: `(edge, orphan)` — a twentieth of the budget each (at least 4
/// and 2), for the last edge-leak pass and the pool points that still leak,
/// and for orphan pockets (what these leave goes to the leaking pool
/// points); together at most a fifth of the budget, so small budgets keep
/// most of theirs for the error-driven placement. Measured on
/// `builtin:demo` at a quarter of the ~500 and ~2000 grids (BENCHMARKS.md,
/// "A hard budget"): a fortieth for the pockets left closet leaks on two of
/// five placements, a twentieth none.
fn final_allowances(budget: usize) -> (usize, usize) {
    (
        (budget / 20).max(4).min(budget / 10),
        (budget / 20).max(2).min(budget / 10),
    )
}

/// Capture index of the first candidate captured after the pool (spawned
/// candidates, leak and orphan probes): above any pool's, and the same
/// with and without light shells, so [`LightShells::Auto`](super::LightShells::Auto)'s two
/// placements are those of `off` and `on`.
const AFTER_POOL_INDEX: usize = 1 << 30;

/// The captured candidate pool of a box: what every adaptive placement of
/// it shares (jittered points, emitter layers) and what one with light
/// shells adds. [`LightShells::Auto`](super::LightShells::Auto) captures it
/// once for both of its placements.
#[derive(Clone)]
pub(super) struct PoolCapture {
    /// (captured position, SH) of the jittered points and emitter layers,
    /// in the bake box.
    base: Vec<(Vec3, ShRgb)>,
    /// Those of the light shells (empty when not asked for).
    shells: Vec<(Vec3, ShRgb)>,
    /// Points of `base` and `shells` rejected (no clearance, invalid,
    /// inside geometry).
    rejected: [usize; 2],
}

/// Builds and captures the pool of adaptive placement in `bbox` for
/// `budget` (see the module docs), with light shells when `shells`: about
/// `4 × budget` jittered points with the box layer, layers along emissive
/// surfaces, then the shells; those without clearance dropped, the rest
/// captured in that order as capture indices `0..` (so the shared points
/// draw the same random numbers with and without shells), in free space
/// (no virtual offset: they have clearance), and those that come back
/// invalid, inside geometry or outside the box dropped.
pub(super) fn capture_pool(
    st: &mut State,
    bbox: &Aabb,
    budget: usize,
    shells: bool,
    progress: Progress<'_>,
) -> Result<PoolCapture, PlacementError> {
    let tracer = st.baker.tracer();
    st.layer = Some(layer_box(st.baker.scene(), bbox));
    let mut raw = jittered(
        bbox,
        (POOL_FACTOR * budget).clamp(512, 60_000),
        st.settings.seed,
        st.layer.as_ref(),
    );
    // Shells reach out to where the uniform pool is about as dense.
    let size = bbox.size();
    let spacing = (size.x * size.y * size.z / raw.len().max(1) as f32).cbrt();
    let limit = raw.len() / 4;
    raw.extend(emitter_layers(
        st.baker.scene(),
        bbox,
        spacing,
        st.settings.seed,
        limit,
    ));
    let nbase = raw.len();
    if shells {
        // The budget's mean probe spacing.
        let h = (size.x * size.y * size.z / budget.max(1) as f32).cbrt();
        raw.extend(light_shells(
            &st.baker.scene().lights,
            bbox,
            LIGHT_SHELL_INNER * h,
            (1.5 * spacing).min(LIGHT_SHELL_MAX),
        ));
    }
    let nshells = raw.len() - nbase;
    let kept: Vec<(usize, Vec3)> = st
        .snap(raw)
        .into_par_iter()
        .enumerate()
        .filter(|(_, p)| has_clearance(tracer, *p))
        .collect();
    let pts: Vec<Vec3> = kept.iter().map(|k| k.1).collect();
    progress("pool", 0, pts.len());
    // Rejections count per placement, from `rejected` (in `adaptive`).
    let rejected = st.stats.rejected_inside;
    let captured = st.capture_free(&pts, 0)?;
    st.stats.rejected_inside = rejected;
    st.next_index = st.next_index.max(AFTER_POOL_INDEX);
    progress("pool", pts.len(), pts.len());
    let mut pool = PoolCapture {
        base: Vec::new(),
        shells: Vec::new(),
        rejected: [nbase, nshells],
    };
    // The virtual offset may push a capture out of the box (through an
    // outer wall): drop those.
    for ((i, _), c) in kept.iter().zip(captured) {
        let Some((p, sh)) = c.filter(|(p, _)| bbox.contains(*p)) else {
            continue;
        };
        let part = usize::from(*i >= nbase);
        pool.rejected[part] -= 1;
        [&mut pool.base, &mut pool.shells][part].push((p, sh));
    }
    st.lap("pool");
    Ok(pool)
}

/// Runs `adaptive` placement into `st` (see the module docs) from the
/// captured `pool`, with its light shells when `shells`. It places at most
/// `budget` probes. Leaves in `st.free_points` the pool points that are
/// not probes.
#[allow(clippy::too_many_arguments)]
pub(super) fn adaptive(
    st: &mut State,
    bbox: &Aabb,
    budget: usize,
    tolerance: f32,
    pool: &PoolCapture,
    shells: bool,
    ls: &LeakSettings,
    progress: Progress<'_>,
) -> Result<(), PlacementError> {
    st.stats.light_shells = shells;
    st.layer = Some(layer_box(st.baker.scene(), bbox));
    st.stats.rejected_inside += pool.rejected[0] + if shells { pool.rejected[1] } else { 0 };
    let parts = if shells {
        [&pool.base[..], &pool.shells[..]]
    } else {
        [&pool.base[..], &[][..]]
    };
    let (pos, sh): (Vec<Vec3>, Vec<ShRgb>) = parts.iter().flat_map(|p| p.iter().cloned()).unzip();
    let order = sh.first().map_or(1, |c| c.order());
    let w = band_weights(order);
    let floor =
        0.01 * sh.iter().map(mean_irradiance_luminance).sum::<f32>() / sh.len().max(1) as f32;
    let n = pos.len();
    if n < 4 {
        return Err(PlacementError::BadParameter(format!(
            "only {n} free-space points in the bake box; need at least 4"
        )));
    }
    let mut a = Adaptive {
        st,
        pool: Pool::new(pos, sh, &w),
        origin: Vec::new(),
        w,
        bbox: *bbox,
        normals: leak_normals(),
        floor,
    };
    let seeds = farthest_points(
        &a.pool.pos,
        bbox.min,
        (budget / 8).max(8),
        Some(a.st.baker.tracer()),
    );
    for i in seeds {
        a.push_pool(i);
    }
    a.st.lap("seed set");
    progress("adaptive", a.st.positions.len(), budget);
    // The budget is a hard cap: the last leak pass and the orphan pass get
    // allowances of their own, kept out of the error-driven placement.
    let (extra, orphans) = final_allowances(budget);
    let core = budget - extra - orphans;
    let reserve = core / 10;
    let mut done = a.refine_to(core - reserve, tolerance, progress, budget)?;
    let (_, before) = super::crossing_extent(a.st.baker.tracer(), &a.st.positions)?;
    a.st.stats.crossing_before = before;
    let room = core.saturating_sub(a.st.positions.len());
    a.st.fix_leaks_within(ls, room, Some(bbox))?;
    a.st.lap("leaks");
    a.origin.resize(a.st.positions.len(), None);
    if !done {
        done = a.refine_to(core, tolerance, progress, budget)?;
    }
    if !done {
        for _ in 0..2 {
            let m = a.decimate((core / 10).max(1))?;
            if m == 0 {
                break;
            }
            let target = a.st.positions.len() + m;
            if a.refine_to(target, tolerance, progress, budget)? {
                break;
            }
        }
    }
    // A last leak pass for the probes the swaps moved, then pool points that
    // still fail the leak test, within the same allowance.
    let before = a.st.positions.len();
    a.st.fix_leaks_within(ls, extra, Some(bbox))?;
    a.st.lap("leaks");
    let mut left = extra.saturating_sub(a.st.positions.len() - before);
    // Pockets behind a wall's end or corner that see none of their
    // tetrahedron's probes get one, within an allowance of their own: from
    // the edge test's allowance they would crowd out its probes. What they
    // leave goes to the pool points that still leak.
    let used = a.st.fix_orphans(
        PROBE_CLEARANCE - CLEARANCE_TOLERANCE,
        ORPHAN_PASSES,
        orphans,
        bbox,
    )?;
    a.st.lap("orphans");
    left += orphans - used;
    a.origin.resize(a.st.positions.len(), None);
    while let Some(s) = a.score()? {
        let leaking = s.leak.iter().filter(|&&l| l).count();
        a.st.stats.leaking_pool_points = Some(leaking);
        if leaking == 0 || left == 0 {
            break;
        }
        let k = a.insert_ranked(&s, left, 0);
        if k == 0 {
            break;
        }
        left -= k;
    }
    a.st.lap("scoring");
    let (_, after) = super::crossing_extent(a.st.baker.tracer(), &a.st.positions)?;
    a.st.stats.crossing_after = after;
    a.st.lap("leaks");
    a.st.free_points = (0..a.pool.pos.len())
        .filter(|&i| a.pool.probe[i].is_none())
        .map(|i| (a.pool.pos[i], a.pool.sh[i].clone()))
        .collect();
    progress("leaks", a.st.positions.len(), budget);
    Ok(())
}
