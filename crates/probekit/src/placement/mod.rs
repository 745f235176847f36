//! # Probe placement
//!
//! Where to put the probes of a cloud: a uniform `grid`, `manual` positions, or
//! `adaptive` (ours, the default): start from a coarse grid, then repeatedly
//! capture candidate points and insert those where the barycentric
//! interpolation of the current probes disagrees most with the captured
//! lighting, until a probe budget or a relative-error tolerance is met.
//!
//! Every method ends with **leak prevention** after seed 003 (Cupisz, "Light
//! probe interpolation using tetrahedral tessellations", GDC 2012, and the
//! placement paper summarised in `shared/seeds/003_*`): every tetrahedron edge
//! is ray-traced in both directions; where it crosses geometry, a probe is
//! inserted on each side near the hit, offset along the surface normal by a
//! fraction of the edge length (hits nearly parallel to the surface are
//! skipped, new probes keep a minimum distance from existing ones), and the
//! points are re-tetrahedralized; this repeats a few times. Interpolation
//! across a wall is then confined to a thin band around it.
//!
//! Beyond seed 003, `adaptive` also fills **orphan pockets**
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
pub mod spawn_merge;

pub use adaptive::PROBE_CLEARANCE;

use crate::capture::{BakeError, Baker, CaptureSettings};
use crate::delaunay::{tetrahedralize, DelaunayError};
use crate::progress::Progress;
use crate::scene::{Aabb, BakeBoxError};
use crate::trace::free_space::{inside_geometry, is_open, push_off_surfaces, segment_clear};
use crate::trace::{Ray, Tracer};
use glam::Vec3;
use probekit_sh::ShRgb;
use rayon::prelude::*;
use std::collections::BTreeSet;
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
    /// Seed 003's spawn-and-merge placement ([`spawn_merge`]).
    SpawnMerge(spawn_merge::SpawnMergeParams),
    /// Seed 003's gradient-ascent placement ([`gradient_ascent`]).
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
    /// Costs about 2.5× the placement time of `Off`, plus the held-out
    /// captures (at least 4096). The default.
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
    /// Pool points that still fail issue 5's leak test (interpolated
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
}

/// Leak-prevention parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeakSettings {
    /// Passes of trace–insert–retetrahedralize.
    pub iterations: u32,
    /// Offset of an inserted probe from the hit, as a fraction of the edge length.
    pub offset_fraction: f32,
    /// Offset bounds, metres.
    pub min_offset: f32,
    /// Largest offset, metres.
    pub max_offset: f32,
    /// Hits with `|cos(edge, normal)|` below this are skipped (surface-parallel).
    pub min_cos: f32,
    /// No new probe closer than this fraction of the offset to another probe.
    pub min_distance_fraction: f32,
}

impl Default for LeakSettings {
    fn default() -> Self {
        Self {
            iterations: 2,
            offset_fraction: 0.1,
            min_offset: 0.05,
            max_offset: 0.4,
            min_cos: 0.2,
            min_distance_fraction: 0.8,
        }
    }
}

/// The smallest grid: 2 cells per axis.
pub const MIN_GRID: usize = 8;

/// Cells per axis of the cell-centred grid over `b` with cells of edge
/// `cell` metres (when given), else about `budget` cells: cell edge
/// `∛(V / budget)`, each axis `round(extent / edge)`, at least 2. The one
/// sizing rule of every grid placement (`bake`, the sweeps, `eval
/// --compare grid`). Refuses a flat or empty box, a budget below
/// [`MIN_GRID`] (rather than baking 8 probes for `--grid 1`), a
/// non-positive cell and grids above [`MAX_PROBES`].
pub fn grid_resolution(
    b: &Aabb,
    cell: Option<f32>,
    budget: Option<usize>,
) -> Result<[usize; 3], PlacementError> {
    b.check_bake_box()?;
    let size = b.size();
    let cell = match (cell, budget) {
        (Some(c), _) if c.is_finite() && c > 0.0 => c,
        (Some(c), _) => {
            return Err(PlacementError::BadParameter(format!(
                "grid cell {c} must be a positive length in metres"
            )))
        }
        (None, Some(n)) if n >= MIN_GRID => (size.x * size.y * size.z / n as f32).cbrt(),
        (None, Some(n)) => {
            return Err(PlacementError::BadParameter(format!(
                "grid of {n} probes: a grid has at least 2 probes per axis, {MIN_GRID} in all"
            )))
        }
        (None, None) => {
            return Err(PlacementError::BadParameter(
                "grid needs a cell size or a budget".into(),
            ))
        }
    };
    // `as` saturates, so a tiny cell gives a huge count, refused below.
    let dims = size
        .to_array()
        .map(|s| ((s / cell).round() as usize).max(2));
    let count = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    match count {
        Some(n) if n <= MAX_PROBES => Ok(dims),
        _ => Err(PlacementError::TooMany {
            what: format!("grid of {}×{}×{}", dims[0], dims[1], dims[2]),
            count: count.unwrap_or(usize::MAX),
        }),
    }
}

/// Cell-centred uniform grid over `b` sized by [`grid_resolution`], x
/// fastest, then y, then z. No point lies on the box faces.
pub fn grid_points(
    b: &Aabb,
    cell: Option<f32>,
    budget: Option<usize>,
) -> Result<Vec<Vec3>, PlacementError> {
    let [nx, ny, nz] = grid_resolution(b, cell, budget)?;
    let size = b.size();
    let mut out = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let f = Vec3::new(
                    (i as f32 + 0.5) / nx as f32,
                    (j as f32 + 0.5) / ny as f32,
                    (k as f32 + 0.5) / nz as f32,
                );
                out.push(b.min + f * size);
            }
        }
    }
    Ok(out)
}

/// Unique edges of tetrahedra, as sorted index pairs in increasing order.
pub fn tet_edges(tets: &[[u32; 4]]) -> Vec<(u32, u32)> {
    let mut set = BTreeSet::new();
    for t in tets {
        for i in 0..4 {
            for j in i + 1..4 {
                let (a, b) = (t[i].min(t[j]), t[i].max(t[j]));
                set.insert((a, b));
            }
        }
    }
    set.into_iter().collect()
}

/// Number of tetrahedron edges of the Delaunay tetrahedralization of
/// `points` that cross geometry, and their crossing extent: for each such
/// edge, the free length on both sides over which interpolation spans the
/// surface (distance from each end point to the first surface seen from it),
/// summed, in metres. Leak prevention shrinks the extent.
pub fn crossing_extent(tracer: &Tracer, points: &[Vec3]) -> Result<(usize, f32), PlacementError> {
    let tri = tetrahedralize(points)?;
    let mut count = 0;
    let mut extent = 0.0f64;
    for (a, b) in tet_edges(&tri.tets) {
        let (pa, pb) = (points[a as usize], points[b as usize]);
        let d = pb - pa;
        let len = d.length();
        if len <= 0.0 {
            continue;
        }
        let dir = d / len;
        if let Some(h) = tracer.closest_hit(&Ray::new(pa, dir), len) {
            count += 1;
            let back = tracer
                .closest_hit(&Ray::new(pb, -dir), len)
                .map_or(len - h.t, |h2| h2.t);
            extent += (h.t + back) as f64;
        }
    }
    Ok((count, extent as f32))
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
}

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

    /// Up to `passes` rounds of [`orphan_points`] (inside `bounds`), at most
    /// `limit` probes added in all; returns how many.
    fn fix_orphans(
        &mut self,
        clearance: f32,
        passes: u32,
        limit: usize,
        bounds: &Aabb,
    ) -> Result<usize, PlacementError> {
        let mut added = 0;
        for _ in 0..passes {
            if added >= limit {
                break;
            }
            let mut new = orphan_points(self.baker.tracer(), &self.positions, clearance)?;
            new.retain(|p| bounds.contains(*p));
            let got = self.admit(new, |p| bounds.contains(*p), limit - added)?;
            if got == 0 {
                break;
            }
            added += got;
            self.stats.orphan_probes += got;
        }
        Ok(added)
    }

    /// Snaps `new` onto the box layers, keeps those in free space, captures
    /// them and adds up to `room` of the valid captures for which `inside`
    /// holds as probes; returns how many.
    fn admit(
        &mut self,
        new: Vec<Vec3>,
        inside: impl Fn(&Vec3) -> bool,
        room: usize,
    ) -> Result<usize, PlacementError> {
        let new = self.snap(new);
        let new = self.filter_free(new);
        let mut got = self.capture(&new)?;
        got.retain(|(p, _)| inside(p));
        got.truncate(room);
        let n = got.len();
        self.add(got);
        Ok(n)
    }

    /// One or more passes of leak prevention; at most `limit` probes added.
    fn fix_leaks(&mut self, ls: &LeakSettings, limit: usize) -> Result<(), PlacementError> {
        self.fix_leaks_within(ls, limit, None)
    }

    /// [`Self::fix_leaks`], keeping only probes inside `bounds` (when given):
    /// the far side of an edge that crosses an outer wall is outside the
    /// building, where a probe sees the sky and sun, and the virtual offset
    /// can push a capture through a thin wall.
    fn fix_leaks_within(
        &mut self,
        ls: &LeakSettings,
        limit: usize,
        bounds: Option<&Aabb>,
    ) -> Result<(), PlacementError> {
        let inside = |p: &Vec3| bounds.map_or(true, |b| b.contains(*p));
        let mut added_total = 0;
        for _ in 0..ls.iterations {
            if added_total >= limit {
                break;
            }
            let mut new = leak_points(self.baker.tracer(), &self.positions, ls)?;
            let n = new.len();
            new.retain(inside);
            self.stats.rejected_inside += n - new.len();
            if new.is_empty() {
                break;
            }
            let got = self.admit(new, inside, limit - added_total)?;
            added_total += got;
            self.stats.leak_probes += got;
        }
        Ok(())
    }
}

/// Points leak prevention would insert for the Delaunay tetrahedralization of
/// `points` (one pass; see the module docs), in a deterministic order.
pub fn leak_points(
    tracer: &Tracer,
    points: &[Vec3],
    ls: &LeakSettings,
) -> Result<Vec<Vec3>, PlacementError> {
    let tri = tetrahedralize(points)?;
    let mut cands = Vec::new();
    for (a, b) in tet_edges(&tri.tets) {
        let (pa, pb) = (points[a as usize], points[b as usize]);
        let d = pb - pa;
        let len = d.length();
        if len <= 1e-6 {
            continue;
        }
        let dir = d / len;
        let off = (ls.offset_fraction * len).clamp(ls.min_offset, ls.max_offset);
        for (o, dd) in [(pa, dir), (pb, -dir)] {
            if let Some(h) = tracer.closest_hit(&Ray::new(o, dd), len) {
                let n = h.facing_normal();
                if n.dot(dd).abs() < ls.min_cos {
                    continue;
                }
                // Not beyond the probe the ray started from.
                let o2 = off.min(0.5 * h.t);
                cands.push((h.point + n * o2, o2));
            }
        }
    }
    Ok(spaced(
        points,
        cands
            .into_iter()
            .map(|(p, o)| (p, ls.min_distance_fraction * o)),
        ls.max_offset,
    ))
}

/// The candidates `(p, r)` kept in order when no existing point of `points`
/// and no candidate kept before lies within `r` of `p` (a spatial hash of
/// cell `cell`, which must be at least the largest `r`); non-finite ones are
/// dropped.
fn spaced(points: &[Vec3], cands: impl Iterator<Item = (Vec3, f32)>, cell: f32) -> Vec<Vec3> {
    let cell = cell.max(1e-3);
    let key = |p: Vec3| {
        let q = (p / cell).floor();
        (q.x as i64, q.y as i64, q.z as i64)
    };
    let mut hash: std::collections::HashMap<(i64, i64, i64), Vec<Vec3>> = Default::default();
    for &p in points {
        hash.entry(key(p)).or_default().push(p);
    }
    let mut out = Vec::new();
    for (p, r) in cands {
        if !p.is_finite() {
            continue;
        }
        let k = key(p);
        let mut near = false;
        'n: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(v) = hash.get(&(k.0 + dx, k.1 + dy, k.2 + dz)) {
                        if v.iter().any(|q| q.distance_squared(p) < r * r) {
                            near = true;
                            break 'n;
                        }
                    }
                }
            }
        }
        if !near {
            hash.entry(k).or_default().push(p);
            out.push(p);
        }
    }
    out
}

/// Spacing of the points [`orphan_points`] tests in each tetrahedron,
/// metres.
pub const ORPHAN_SPACING: f32 = 0.1;

/// Subdivisions of a tetrahedron's lattice in [`orphan_points`], at most.
const ORPHAN_MAX_SUBDIVISION: u32 = 8;

/// Points that see none of the probes of their tetrahedron are looked for
/// this far from surfaces and more, metres: `probekit eval`'s points keep
/// 1 cm.
const ORPHAN_TEST_CLEARANCE: f32 = 0.01;

/// Probes for the pockets of free space that see none of the four probes
/// of their tetrahedron, for the Delaunay tetrahedralization of `points`,
/// in a deterministic order. In such a pocket every visibility-aware blend
/// has only hidden probes to choose from, so the light of the far side of a
/// wall is all it can give.
///
/// Seed 003's edge test ([`leak_points`]) finds a wall that crosses an
/// edge; a wall's *end* or a corner (a closet's, say) can reach into a
/// tetrahedron without crossing any of its edges, leaving such a pocket
/// behind it. In every tetrahedron, and on every face of the hull (beyond
/// which a point blends the face's three probes), this tests the points of
/// a barycentric lattice about [`ORPHAN_SPACING`] apart (at most 8
/// subdivisions of its longest edge) that are in open space ([`is_open`]) at
/// 1 cm from surfaces, as `probekit eval`'s points are: one whose segments
/// to all the cell's probes are blocked is pushed off nearby surfaces until
/// it keeps `clearance` (the probes' own; [`push_off_surfaces`]) and becomes
/// a candidate probe there, unless that fails or another probe or kept
/// candidate is within [`ORPHAN_SPACING`]. The candidates come largest
/// pocket first: ordered greedily by how many of the orphaned lattice points
/// each sees within [`ORPHAN_COVER_RADIUS`] that the ones before it do not.
pub fn orphan_points(
    tracer: &Tracer,
    points: &[Vec3],
    clearance: f32,
) -> Result<Vec<Vec3>, PlacementError> {
    use probekit_runtime::cloud::cell_visibility::{lattice_numerators, lattice_position};
    let tri = tetrahedralize(points)?;
    // The tetrahedra, and the hull's faces: outside the hull a point blends
    // the three probes of the face below it (the outer cells), so a face
    // point that sees none of those three is orphaned there.
    let mut cells: Vec<Vec<u32>> = tri.tets.iter().map(|t| t.to_vec()).collect();
    for (t, nb) in tri.tets.iter().zip(&tri.neighbors) {
        for i in (0..4).filter(|&i| nb[i] == crate::delaunay::HULL) {
            cells.push((0..4).filter(|&j| j != i).map(|j| t[j]).collect());
        }
    }
    let cands: Vec<(Vec3, Option<Vec3>)> = cells
        .par_iter()
        .flat_map_iter(|t| {
            let v: Vec<Vec3> = t.iter().map(|&k| points[k as usize]).collect();
            let longest = (0..v.len())
                .flat_map(|i| (i + 1..v.len()).map(move |j| (i, j)))
                .map(|(i, j)| v[i].distance(v[j]))
                .fold(0.0f32, f32::max);
            let k = ((longest / ORPHAN_SPACING).ceil() as u32).clamp(1, ORPHAN_MAX_SUBDIVISION);
            lattice_numerators(v.len(), k)
                .into_iter()
                .filter(|n| n.iter().all(|&c| c < k))
                .map(|n| lattice_position(t, points, &n, k))
                .filter(|&p| {
                    v.iter().all(|&q| !segment_clear(tracer, p, q))
                        && is_open(tracer, p, ORPHAN_TEST_CLEARANCE)
                })
                .map(|p| (p, push_off_surfaces(tracer, p, clearance)))
                .collect::<Vec<_>>()
        })
        .collect();
    let orphans: Vec<Vec3> = cands.iter().map(|c| c.0).collect();
    let spaced = spaced(
        points,
        cands
            .iter()
            .filter_map(|c| c.1)
            .map(|p| (p, ORPHAN_SPACING)),
        ORPHAN_SPACING,
    );
    Ok(by_pocket_coverage(tracer, spaced, &orphans))
}

/// How far a probe for an orphan pocket counts as serving an orphaned
/// point it sees, metres: [`orphan_points`] orders its candidates by them.
pub const ORPHAN_COVER_RADIUS: f32 = 1.0;

/// `cands` reordered greedily by the orphaned points they serve: first the
/// candidate that sees (a clear segment, within [`ORPHAN_COVER_RADIUS`])
/// the most of `orphans`, then the one that sees the most of those left,
/// and so on (ties to the earlier candidate; those that serve none keep
/// their order at the end). An allowance of a few probes then goes to the
/// largest pockets first — a closet's floor rather than a sliver beside a
/// pillar — instead of to whichever cell came first.
fn by_pocket_coverage(tracer: &Tracer, cands: Vec<Vec3>, orphans: &[Vec3]) -> Vec<Vec3> {
    let r2 = ORPHAN_COVER_RADIUS * ORPHAN_COVER_RADIUS;
    let sees: Vec<Vec<u32>> = cands
        .par_iter()
        .map(|&c| {
            (0..orphans.len() as u32)
                .filter(|&i| {
                    let o = orphans[i as usize];
                    o.distance_squared(c) < r2 && segment_clear(tracer, c, o)
                })
                .collect()
        })
        .collect();
    // Lazy greedy: a candidate's gain only falls as points are served, so
    // a heap of stale gains (upper bounds) yields the exact greedy order
    // (highest gain, then lowest index) re-counting only the candidate on
    // top, instead of every candidate in every round.
    use std::cmp::Reverse;
    let mut served = vec![false; orphans.len()];
    let mut taken = vec![false; cands.len()];
    let mut out = Vec::with_capacity(cands.len());
    let mut heap: std::collections::BinaryHeap<(usize, Reverse<usize>)> = sees
        .iter()
        .enumerate()
        .map(|(k, s)| (s.len(), Reverse(k)))
        .collect();
    while let Some((stale, Reverse(k))) = heap.pop() {
        let gain = sees[k].iter().filter(|&&i| !served[i as usize]).count();
        if gain < stale {
            heap.push((gain, Reverse(k)));
            continue;
        }
        if gain == 0 {
            break;
        }
        taken[k] = true;
        for &i in &sees[k] {
            served[i as usize] = true;
        }
        out.push(cands[k]);
    }
    out.extend((0..cands.len()).filter(|&k| !taken[k]).map(|k| cands[k]));
    out
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
            let pts = st.filter_free(pts);
            progress("grid", pts.len(), pts.len());
            return Ok(Placement {
                positions: pts,
                captured: None,
                stats: st.stats,
            });
        }
        PlacementMethod::Manual(p) => {
            if let Some(i) = p.iter().position(|q| !q.is_finite()) {
                return Err(PlacementError::BadParameter(format!(
                    "manual position {i} is not finite"
                )));
            }
            let pts = st.filter_free(p.clone());
            progress("manual", pts.len(), pts.len());
            return Ok(Placement {
                positions: pts,
                captured: None,
                stats: st.stats,
            });
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
            // Auto places twice only where some light offers shells.
            if *light_shells == LightShells::Auto
                && adaptive::has_shell_lights(baker.scene(), &bake_box)
            {
                let mut plain = st.clone();
                adaptive::adaptive(
                    &mut plain, &bake_box, *budget, *tolerance, false, &ls, progress,
                )?;
                // The second run's phases say so (a progress bar restarts).
                let shelled_progress =
                    |phase: &str, done, total| progress(&format!("{phase}+shells"), done, total);
                let mut shelled = st.clone();
                adaptive::adaptive(
                    &mut shelled,
                    &bake_box,
                    *budget,
                    *tolerance,
                    true,
                    &ls,
                    &shelled_progress,
                )?;
                progress("held-out", 0, 1);
                let e = adaptive::held_out_errors(&mut st, &bake_box, *budget, [&plain, &shelled])?;
                progress("held-out", 1, 1);
                let captures = plain.stats.captures + shelled.stats.captures + st.stats.captures;
                st = if e[1] < e[0] { shelled } else { plain };
                st.stats.captures = captures;
                st.stats.held_out_error = Some(e);
            } else {
                let shells = *light_shells == LightShells::On;
                adaptive::adaptive(
                    &mut st, &bake_box, *budget, *tolerance, shells, &ls, progress,
                )?;
            }
        }
    }
    let captured = reusable.then(|| st.sh.clone());
    Ok(Placement {
        positions: st.positions,
        captured,
        stats: st.stats,
    })
}

#[cfg(test)]
mod tests;
