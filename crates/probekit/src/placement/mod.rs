//! # Probe placement
//!
//! Where to put the probes of a cloud: a uniform `grid`, `manual` positions, or
//! `adaptive` (ours, the default): start from a coarse grid, then repeatedly
//! capture candidate points and insert those where the barycentric
//! interpolation of the current probes disagrees most with the captured
//! lighting, until a probe budget or a relative-error tolerance is met.
//!
//! Every method ends with **leak prevention** ([`leak_points`], after Cupisz,
//! "Light probe interpolation using tetrahedral tessellations", GDC 2012, and
//! Sukys 2014, "Light probe cloud generation for games"): every tetrahedron edge
//! is ray-traced in both directions; where it crosses geometry, a probe is
//! inserted on each side near the hit, offset along the surface normal by a
//! fraction of the edge length (hits nearly parallel to the surface are
//! skipped, new probes keep a minimum distance from existing ones), and the
//! points are re-tetrahedralized; this repeats a few times. Interpolation
//! across a wall is then confined to a thin band around it.
//!
//! Beyond that, `adaptive` also fills **orphan pockets**
//! ([`orphan_points`]): a wall's end or a closet's corner can reach into a
//! tetrahedron without crossing any of its edges, so the edge test adds
//! nothing there, and the free space behind it sees none of the
//! tetrahedron's four probes; a probe goes into each such pocket.
//!
//! No placed probe is inside geometry: candidates are rejected by a
//! first-hit back-face vote ([`inside_geometry`]), and captures whose
//! validity says invalid are dropped.

mod adaptive;
pub mod gradient_ascent;
mod grid;
mod leaks;
mod orphans;
pub mod spawn_merge;

pub(crate) use adaptive::held_out_points;
pub use adaptive::PROBE_CLEARANCE;
pub use grid::{grid_points, grid_resolution, MIN_GRID};
pub use leaks::{crossing_extent, leak_points, tet_edges, LeakSettings};
pub use orphans::{orphan_points, ORPHAN_COVER_RADIUS, ORPHAN_SPACING};

use crate::capture::{BakeError, Baker, CaptureSettings};
use crate::delaunay::DelaunayError;
use crate::progress::{Clock, PhaseTime, Progress};
use crate::scene::{Aabb, BakeBoxError};
use crate::trace::free_space::inside_geometry;
use glam::Vec3;
use probekit_sh::ShRgb;
use thiserror::Error;

/// The most probes any placement may be asked for (a grid's cell count, an
/// adaptive or spawn-and-merge budget, a gradient-ascent initial grid, a
/// manual positions file): larger requests are refused before any work, so
/// memory stays bounded by the request. 5 M probes at L2 f32 are 540 MB of
/// coefficients alone.
pub const MAX_PROBES: usize = 5_000_000;

/// Receiver samples per probe used while placing (captures are reused by the
/// bake when its own sample count is not larger).
pub const PLACEMENT_SAMPLES: u32 = 256;

/// How to place probes.
#[derive(Clone, Debug, PartialEq)]
pub enum PlacementMethod {
    /// Uniform grid over the bake box: cell size in metres, or about `budget`
    /// probes (one of them; cell wins when both are given). Cell centres are
    /// used, so no probe lies on the box faces.
    Grid {
        /// Cell edge length, metres.
        cell: Option<f32>,
        /// Approximate number of probes.
        budget: Option<usize>,
    },
    /// Given positions (metres), kept as they are except those inside geometry.
    Manual(Vec<Vec3>),
    /// Error-driven refinement (see the module docs).
    Adaptive {
        /// Most probes to place: a hard cap, the final leak-prevention and
        /// orphan-pocket probes included.
        budget: usize,
        /// Stop when the mean relative irradiance error at the candidates of a
        /// round falls below this (e.g. 0.05).
        tolerance: f32,
        /// Whether to add shells of candidates around positional lights
        /// (the `adaptive` placement module docs); see [`LightShells`].
        light_shells: LightShells,
    },
    /// Spawn-and-merge placement (Sukys 2014; [`spawn_merge`]).
    SpawnMerge(spawn_merge::SpawnMergeParams),
    /// Gradient-ascent placement (Sukys 2014; [`gradient_ascent`]).
    GradientAscent(gradient_ascent::GradientAscentParams),
}

/// Whether adaptive placement offers candidates on shells around positional
/// lights (the `adaptive` module docs). Shells lower the error near small
/// bright lights but draw probes from the rest of the scene; which way wins
/// depends on the scene and the budget (BENCHMARKS.md, "Light shells"), so
/// the default, [`LightShells::Auto`], tries both.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightShells {
    /// No shell candidates.
    Off,
    /// Shell candidates around every positional light in the bake box.
    On,
    /// Place both ways (when the box holds a positional light) and keep the
    /// placement whose interpolation (barycentric; where probes hidden from
    /// a point hold most of its weight, only those it sees, as placement
    /// scores its candidates) has the lower relative RMSE at held-out
    /// points: about `2·budget` (4096 to 8192) jittered points in free
    /// space of the box, half of them in 1 m balls
    /// around the positional lights and weighted by the volume each stands
    /// for (a stratified estimate of the same error with far less variance,
    /// `adaptive::held_out_points`), captured like the pool but with their
    /// own random numbers and never offered as candidates.
    /// The candidate pool is captured once for both placements; the
    /// held-out points are captured at half the pool's samples, in rounds
    /// until the choice is clear, and become training points of the probe
    /// weights, which need no capture of their own for that half. The
    /// default.
    #[default]
    Auto,
}

impl LightShells {
    /// The names `off`, `on`, `auto`.
    pub fn name(self) -> &'static str {
        match self {
            LightShells::Off => "off",
            LightShells::On => "on",
            LightShells::Auto => "auto",
        }
    }

    /// Parses [`LightShells::name`].
    pub fn from_name(s: &str) -> Option<Self> {
        match s {
            "off" => Some(LightShells::Off),
            "on" => Some(LightShells::On),
            "auto" => Some(LightShells::Auto),
            _ => None,
        }
    }
}

impl PlacementMethod {
    /// Refuses a request above [`MAX_PROBES`] (a grid counted by
    /// [`grid_resolution`] over `bake_box`).
    pub fn check_size(&self, bake_box: &Aabb) -> Result<(), PlacementError> {
        let (what, count) = match self {
            PlacementMethod::Grid { cell, budget } => {
                grid_resolution(bake_box, *cell, *budget)?;
                return Ok(());
            }
            PlacementMethod::Manual(p) => ("manual positions:", p.len()),
            PlacementMethod::Adaptive { budget, .. } => ("adaptive budget", *budget),
            PlacementMethod::SpawnMerge(p) => {
                ("spawn-and-merge budget", p.max_probes.max(p.initial))
            }
            PlacementMethod::GradientAscent(p) => ("gradient-ascent initial grid", p.initial),
        };
        if count > MAX_PROBES {
            return Err(PlacementError::TooMany {
                what: what.into(),
                count,
            });
        }
        Ok(())
    }

    /// Short name as used on the command line (`grid`, `manual`, `adaptive`, ...).
    pub fn name(&self) -> &'static str {
        match self {
            PlacementMethod::Grid { .. } => "grid",
            PlacementMethod::Manual(_) => "manual",
            PlacementMethod::Adaptive { .. } => "adaptive",
            PlacementMethod::SpawnMerge(_) => "spawn-merge",
            PlacementMethod::GradientAscent(_) => "gradient-ascent",
        }
    }
}

/// Why placement failed.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum PlacementError {
    /// The method exists in the interface but has no implementation yet.
    #[error("placement method `{0}` is not implemented yet")]
    NotImplemented(&'static str),
    /// A parameter is out of range.
    #[error("bad placement parameter: {0}")]
    BadParameter(String),
    /// Capturing failed.
    #[error(transparent)]
    Bake(#[from] BakeError),
    /// The probes could not be tetrahedralized (e.g. fewer than 4, co-planar).
    #[error(transparent)]
    Delaunay(#[from] DelaunayError),
    /// The bake box cannot hold probes (no geometry and no `[bake] box`, or flat).
    #[error(transparent)]
    BakeBox(#[from] BakeBoxError),
    /// More probes asked for than [`MAX_PROBES`].
    #[error("{what} {count} is above the limit of {MAX_PROBES} probes")]
    TooMany {
        /// What was asked for (`adaptive budget`, `grid of 300×300×300`, ...).
        what: String,
        /// How many probes that is.
        count: usize,
    },
}

/// What placement did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlacementStats {
    /// Method name.
    pub method: String,
    /// Refinement rounds run (adaptive).
    pub rounds: u32,
    /// Probes captured during placement, candidates included.
    pub captures: usize,
    /// Candidate points rejected as inside geometry or invalid.
    pub rejected_inside: usize,
    /// Probes inserted by leak prevention.
    pub leak_probes: usize,
    /// Probes inserted for pockets of free space that see none of their
    /// tetrahedron's probes ([`orphan_points`]; adaptive).
    pub orphan_probes: usize,
    /// Crossing extent before leak prevention (see [`crossing_extent`]), metres.
    pub crossing_before: f32,
    /// Crossing extent after leak prevention, metres.
    pub crossing_after: f32,
    /// Mean relative error at the last round's candidates (adaptive).
    pub last_mean_error: Option<f32>,
    /// Pool points that still fail the leak test of `probekit eval` (interpolated
    /// irradiance above 4× the captured one plus 1 % of the pool's mean, for
    /// one of 26 normals) when adaptive placement ends; `None` for the other
    /// methods.
    pub leaking_pool_points: Option<usize>,
    /// [`LightShells::Auto`]: the held-out relative RMSE of the placement
    /// without and with light shells (the lower one was kept); `None`
    /// otherwise.
    pub held_out_error: Option<[f32; 2]>,
    /// Whether the kept adaptive placement used light shells.
    pub light_shells: bool,
}

/// Result of [`place`].
#[derive(Clone, Debug, PartialEq)]
pub struct Placement {
    /// Probe positions, metres.
    pub positions: Vec<Vec3>,
    /// Radiance SH captured during placement at [`PLACEMENT_SAMPLES`] (or the
    /// settings' count if lower), one per position; `Some` only when the
    /// settings' sample count is not above what placement used, so the bake
    /// can reuse them.
    pub captured: Option<Vec<ShRgb>>,
    /// What happened.
    pub stats: PlacementStats,
    /// Points in free space of the bake box that placement captured (with
    /// the settings' light transport at its sample count) and that are
    /// not probes: adaptive placement's candidate pool and, for
    /// [`LightShells::Auto`], its held-out points; empty for the other
    /// methods. Each is (position, radiance SH, all light), what a
    /// training point of the probe-weight fit is
    /// (`blend::blend_fit::capture_training_set`).
    pub free_points: Vec<(Vec3, ShRgb)>,
}

/// Probes so far: positions, captured SH, and the next capture index.
#[derive(Clone)]
struct State<'a, 'b> {
    baker: &'a Baker<'b>,
    settings: CaptureSettings,
    positions: Vec<Vec3>,
    sh: Vec<ShRgb>,
    next_index: usize,
    stats: PlacementStats,
    /// The layer box of [`snap_to_layer`], when the method keeps its probes
    /// on layers along the bake box's faces (`adaptive`).
    layer: Option<Aabb>,
    /// Times the sub-phases (adaptive: pool, scoring, candidates, leaks, …).
    clock: Clock,
    /// See [`Placement::free_points`].
    free_points: Vec<(Vec3, ShRgb)>,
}

/// Fewest candidates [`State::admit`] captures in one batch: enough for
/// every thread of a small machine to have work.
const ADMIT_BATCH_MIN: usize = 16;

/// Points within this distance (metres) of a face of the layer box, or beyond
/// it, are moved onto it ([`snap_to_layer`]).
pub const LAYER_SNAP: f32 = 0.001;

/// `p` with each coordinate within [`LAYER_SNAP`] of a face of `layer`, or
/// outside it, set to that face's coordinate exactly.
///
/// Why: the probes along a face of the bake box form a face of their convex
/// hull, and a point outside the hull is lit by the hull triangle closest to
/// it. When those probes are co-planar only up to rounding (a leak-prevention
/// probe 5·10⁻⁷ m off the layer, `1.2 × 0.05` rounded one ulp away from a
/// layer computed another way), the exact Delaunay tetrahedralization is
/// right to make them sliver tetrahedra, and the hull then has triangles
/// metres long that skip the probes next to a query point — through a wall
/// (BENCHMARKS.md, "Hull slivers"). Exactly co-planar probes give a planar
/// hull triangulated in the plane. The tolerance is small (1 mm) so that
/// layers placed on purpose near a face (the emitter layers under a ceiling
/// light) stay where they are.
pub fn snap_to_layer(p: Vec3, layer: &Aabb) -> Vec3 {
    let mut q = p;
    for a in 0..3 {
        if q[a] <= layer.min[a] + LAYER_SNAP {
            q[a] = layer.min[a];
        } else if q[a] >= layer.max[a] - LAYER_SNAP {
            q[a] = layer.max[a];
        }
    }
    q
}

impl State<'_, '_> {
    /// Ends the sub-phase `phase` (see [`Clock::lap`]).
    fn lap(&mut self, phase: &str) {
        let rays = self.baker.tracer().rays();
        self.clock.lap(phase, rays);
    }

    /// `pts` moved onto the layer box's faces ([`snap_to_layer`]) when the
    /// method has one; unchanged otherwise.
    fn snap(&self, mut pts: Vec<Vec3>) -> Vec<Vec3> {
        for p in &mut pts {
            *p = self.snap_point(*p);
        }
        pts
    }

    /// [`Self::snap`] of one point.
    fn snap_point(&self, p: Vec3) -> Vec3 {
        self.layer.as_ref().map_or(p, |l| snap_to_layer(p, l))
    }

    /// Captures `points` (already filtered for inside-geometry); returns the
    /// valid ones as (position, SH).
    fn capture(&mut self, points: &[Vec3]) -> Result<Vec<(Vec3, ShRgb)>, PlacementError> {
        let out = self.capture_numbered(points, self.next_index)?;
        self.next_index += points.len();
        Ok(out.into_iter().flatten().collect())
    }

    /// Captures `points` as capture indices `first..` (which choose their
    /// random numbers) without advancing [`Self::next_index`]; per point,
    /// its (position, SH) when the capture is valid and not inside
    /// geometry, else `None` (counted in `rejected_inside`).
    fn capture_numbered(
        &mut self,
        points: &[Vec3],
        first: usize,
    ) -> Result<Vec<Option<(Vec3, ShRgb)>>, PlacementError> {
        let res = self
            .baker
            .capture_many(points, first, &self.settings, &|_, _| {})?;
        self.stats.captures += points.len();
        let mut out = Vec::with_capacity(res.len());
        for r in res {
            if r.validity.valid && !inside_geometry(self.baker.tracer(), r.position) {
                out.push(Some((r.position, r.sh)));
            } else {
                self.stats.rejected_inside += 1;
                out.push(None);
            }
        }
        Ok(out)
    }

    /// [`Self::capture_numbered`] of points already known to keep a
    /// clearance from every surface (`adaptive`'s `has_clearance`): without
    /// the virtual offset, whose pre-pass would trace its rays only to
    /// leave them where they are; one that sees mostly back faces all the
    /// same comes back invalid and is dropped, not moved.
    fn capture_free(
        &mut self,
        points: &[Vec3],
        first: usize,
    ) -> Result<Vec<Option<(Vec3, ShRgb)>>, PlacementError> {
        let offset = self.settings.validity.virtual_offset;
        self.settings.validity.virtual_offset = false;
        let out = self.capture_numbered(points, first);
        self.settings.validity.virtual_offset = offset;
        out
    }

    fn filter_free(&mut self, pts: Vec<Vec3>) -> Vec<Vec3> {
        let tracer = self.baker.tracer();
        let n = pts.len();
        let out: Vec<Vec3> = pts
            .into_iter()
            .filter(|p| !inside_geometry(tracer, *p))
            .collect();
        self.stats.rejected_inside += n - out.len();
        out
    }

    fn add(&mut self, v: Vec<(Vec3, ShRgb)>) {
        for (p, s) in v {
            self.positions.push(p);
            self.sh.push(s);
        }
    }

    /// Snaps `new` onto the box layers, keeps those in free space, and
    /// adds as probes the first `room` of them (in order) whose capture is
    /// valid and for which `inside` holds; returns how many. Captures in
    /// batches of about what is still wanted, so the candidates beyond the
    /// last one admitted are never captured: each point keeps the capture
    /// index it has in `new`, so the probes are those of capturing them
    /// all and keeping the first `room`.
    fn admit(
        &mut self,
        new: Vec<Vec3>,
        inside: impl Fn(&Vec3) -> bool,
        room: usize,
    ) -> Result<usize, PlacementError> {
        let new = self.snap(new);
        let new = self.filter_free(new);
        let first = self.next_index;
        self.next_index += new.len();
        let mut got = Vec::new();
        let mut at = 0;
        while got.len() < room && at < new.len() {
            // What is still wanted, a quarter more for captures that come
            // back invalid, and enough to keep the threads busy.
            let want = room - got.len();
            let end = (at + want + want / 4 + ADMIT_BATCH_MIN).min(new.len());
            for c in self.capture_numbered(&new[at..end], first + at)? {
                match c {
                    Some(c) if got.len() < room && inside(&c.0) => got.push(c),
                    _ => {}
                }
            }
            at = end;
        }
        let n = got.len();
        self.add(got);
        Ok(n)
    }
}

/// Places probes in `bake_box` with `method`. Captures during placement use
/// `settings` with the sample count lowered to [`PLACEMENT_SAMPLES`].
/// `progress(phase, done, total)` reports each phase. Deterministic for a
/// given scene, method and settings (any thread count).
pub fn place(
    baker: &Baker,
    bake_box: Aabb,
    method: &PlacementMethod,
    settings: &CaptureSettings,
    progress: Progress<'_>,
) -> Result<Placement, PlacementError> {
    place_timed(baker, bake_box, method, settings, progress).map(|p| p.0)
}

/// [`place`], and the time of its sub-phases (wall and CPU seconds, rays;
/// adaptive placement's `pool`, `seed set`, `scoring`, `candidates`,
/// `leaks`, `decimation`, `orphans` and, for [`LightShells::Auto`],
/// `held-out`, each summed over both placements).
pub fn place_timed(
    baker: &Baker,
    bake_box: Aabb,
    method: &PlacementMethod,
    settings: &CaptureSettings,
    progress: Progress<'_>,
) -> Result<(Placement, Vec<PhaseTime>), PlacementError> {
    settings.validate()?;
    // Before any work: a box that can hold probes, and a request that
    // bounds the memory it takes.
    bake_box.check_bake_box()?;
    method.check_size(&bake_box)?;
    let mut cs = settings.clone();
    cs.samples = cs.samples.min(PLACEMENT_SAMPLES);
    let reusable = settings.samples <= PLACEMENT_SAMPLES;
    let mut st = State {
        baker,
        settings: cs,
        positions: Vec::new(),
        sh: Vec::new(),
        next_index: 0,
        stats: PlacementStats {
            method: method.name().into(),
            ..Default::default()
        },
        layer: None,
        clock: Clock::new(baker.tracer().rays()),
        free_points: Vec::new(),
    };
    let ls = LeakSettings::default();
    match method {
        PlacementMethod::SpawnMerge(p) => {
            spawn_merge::spawn_merge(&mut st, &bake_box, p, &ls, progress)?
        }
        PlacementMethod::GradientAscent(p) => {
            gradient_ascent::gradient_ascent(&mut st, &bake_box, p, &ls, progress)?;
        }
        PlacementMethod::Grid { cell, budget } => {
            let pts = grid_points(&bake_box, *cell, *budget)?;
            return Ok(fixed_positions(st, pts, "grid", progress));
        }
        PlacementMethod::Manual(p) => {
            if let Some(i) = p.iter().position(|q| !q.is_finite()) {
                return Err(PlacementError::BadParameter(format!(
                    "manual position {i} is not finite"
                )));
            }
            return Ok(fixed_positions(st, p.clone(), "manual", progress));
        }
        PlacementMethod::Adaptive {
            budget,
            tolerance,
            light_shells,
        } => {
            if *budget < 8 {
                return Err(PlacementError::BadParameter(format!(
                    "adaptive budget {budget} must be ≥ 8"
                )));
            }
            if !(tolerance.is_finite() && *tolerance >= 0.0) {
                return Err(PlacementError::BadParameter(format!(
                    "tolerance {tolerance} must be ≥ 0"
                )));
            }
            // Auto places twice only where some light offers shells, from
            // one captured pool.
            if *light_shells == LightShells::Auto
                && adaptive::has_shell_lights(baker.scene(), &bake_box)
            {
                let pool = adaptive::capture_pool(&mut st, &bake_box, *budget, true, progress)?;
                let pool_captures = st.stats.captures;
                let mut plain = st.clone();
                adaptive::adaptive(
                    &mut plain, &bake_box, *budget, *tolerance, &pool, false, &ls, progress,
                )?;
                // The second run's phases say so (a progress bar restarts).
                let shelled_progress =
                    |phase: &str, done, total| progress(&format!("{phase}+shells"), done, total);
                let mut shelled = st.clone();
                // Its clock goes on from the first run's.
                shelled.clock = plain.clock.clone();
                adaptive::adaptive(
                    &mut shelled,
                    &bake_box,
                    *budget,
                    *tolerance,
                    &pool,
                    true,
                    &ls,
                    &shelled_progress,
                )?;
                progress("held-out", 0, 1);
                st.clock = shelled.clock.clone();
                let (e, held_out) =
                    adaptive::held_out_errors(&mut st, &bake_box, *budget, [&plain, &shelled])?;
                st.lap("held-out");
                progress("held-out", 1, 1);
                // The pool was captured once, for both.
                let captures = plain.stats.captures + shelled.stats.captures + st.stats.captures
                    - 2 * pool_captures;
                let clock = st.clock.clone();
                st = if e[1] < e[0] { shelled } else { plain };
                st.clock = clock;
                st.stats.captures = captures;
                st.stats.held_out_error = Some(e);
                st.free_points.extend(held_out);
            } else {
                let shells = *light_shells == LightShells::On;
                let pool = adaptive::capture_pool(&mut st, &bake_box, *budget, shells, progress)?;
                adaptive::adaptive(
                    &mut st, &bake_box, *budget, *tolerance, &pool, shells, &ls, progress,
                )?;
            }
        }
    }
    let captured = reusable.then(|| st.sh.clone());
    let phases = st.clock.take_phases();
    Ok((
        Placement {
            positions: st.positions,
            captured,
            stats: st.stats,
            free_points: st.free_points,
        },
        phases,
    ))
}

/// The placement of given positions (a grid's or a manual list): those in
/// free space, with no captures and no timed sub-phases.
fn fixed_positions(
    mut st: State,
    pts: Vec<Vec3>,
    method: &str,
    progress: Progress<'_>,
) -> (Placement, Vec<PhaseTime>) {
    let positions = st.filter_free(pts);
    progress(method, positions.len(), positions.len());
    let placement = Placement {
        positions,
        captured: None,
        stats: st.stats,
        free_points: Vec::new(),
    };
    (placement, Vec::new())
}

#[cfg(test)]
mod tests;
