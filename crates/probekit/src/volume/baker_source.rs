//! The path tracer as a [`VolumeSource`]: volumes of any scene the loader
//! accepts, captured by [`Baker`] with the same estimator, validity and
//! virtual offset as the probe cloud, so volumes and clouds are captured
//! and evaluated the same way.
//!
//! - **Random numbers** are keyed by the sample's *position* (a hash of its
//!   f32 bits, see [`position_key`]), not by its place in a batch, so a
//!   sample captures the same SH whatever the octree builder batches with it
//!   and whatever the thread count (determinism).
//! - **Virtual offset**: the baker moves a probe that sees mostly back faces
//!   out of the geometry and captures there; the volume keeps the sample at
//!   its corner (interpolation needs it there) and the builder flags it
//!   `VALIDITY_VIRTUAL_OFFSET`. A sample still invalid after the offset, or
//!   moved farther than [`BakerSource::with_max_offset`] (a corner on a
//!   wall pushed through to the other side would light the room with the
//!   outside), is reported invalid and dilated by the builder.
//! - **Central gradients** capture `p ± h eᵢ` with the random numbers of `p`
//!   (common random numbers), so the difference measures the change of the
//!   light field rather than Monte Carlo noise divided by `2h`.
//! - **Geometry heuristic**: exact triangle/box overlap (separating-axis
//!   test, Akenine-Möller 2001) over a uniform grid of triangle bins, on
//!   the cell shrunk by 10⁻³ of its size (geometry only on a face does not count).
//! - **Depth heuristic**: the harmonic mean of first-hit distances over
//!   [`BakerSource::depth_rays`] spherical-Fibonacci rays (Tatarchuk 2005, slide
//!   "Harmonic Mean of Scene Depth"; misses count `1/∞ = 0`).

use super::source::{central_difference, central_points, Captured, VolumeSource};
use crate::capture::{BakeError, Baker, CaptureSettings};
use crate::progress::{Clock, PhaseTime, Progress};
use crate::scene::{Aabb, LightKind, Scene};
use crate::sh::compare::spherical_fibonacci;
use crate::trace::Ray;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// A [`VolumeSource`] that path-traces a [`Scene`] with [`Baker`].
pub struct BakerSource<'s> {
    baker: Baker<'s>,
    settings: CaptureSettings,
    /// The scene's triangles, binned.
    bins: TriangleBins,
    /// The scene's emissive triangles, binned: a cell's emitter test reads
    /// only the triangles of the bins it overlaps.
    emissive: TriangleBins,
    /// Boxes of its positional lights (their radius around the position).
    light_boxes: Vec<Aabb>,
    /// Rays per point of the harmonic-mean-depth heuristic (default 64).
    pub depth_rays: usize,
    dirs: Vec<Vec3>,
    requested: AtomicUsize,
    done: AtomicUsize,
    progress: Option<Progress<'s>>,
    error: Mutex<Option<BakeError>>,
    /// Time and rays spent in capture batches, summed.
    capture_time: Mutex<PhaseTime>,
    max_offset: f32,
}

/// A 64-bit key of a position's bits (SplitMix64 finaliser over x, y, z):
/// the probe index the baker keys its random numbers with.
pub fn position_key(p: Vec3) -> u64 {
    use crate::sampling::{mix64, SPLITMIX_GAMMA};
    let mut h = SPLITMIX_GAMMA;
    for v in p.to_array() {
        // +0.0 folds −0.0 into +0.0: the same point, the same key.
        h ^= (v + 0.0).to_bits() as u64;
        h = mix64(h.wrapping_add(SPLITMIX_GAMMA));
    }
    h
}

impl<'s> BakerSource<'s> {
    /// Prepares the tracer and lights of `scene`; checks `settings`.
    pub fn new(scene: &'s Scene, settings: CaptureSettings) -> Result<Self, BakeError> {
        settings.validate()?;
        let baker = Baker::new(scene)?;
        Ok(Self {
            baker,
            settings,
            bins: TriangleBins::new(scene.triangles.iter().map(|t| t.positions).collect()),
            emissive: TriangleBins::new(
                scene
                    .emissive_triangles
                    .iter()
                    .filter_map(|e| scene.triangles.get(e.triangle as usize))
                    .map(|t| t.positions)
                    .collect(),
            ),
            light_boxes: light_boxes(scene),
            depth_rays: 64,
            dirs: spherical_fibonacci(64),
            requested: AtomicUsize::new(0),
            done: AtomicUsize::new(0),
            progress: None,
            error: Mutex::new(None),
            capture_time: Mutex::new(PhaseTime::zero("capture")),
            max_offset: f32::INFINITY,
        })
    }

    /// Calls `f("capture", done, requested)` after every capture (from
    /// worker threads): `done` points captured of the `requested` so far
    /// (the octree builder asks for captures level by level, so the total
    /// grows).
    pub fn with_progress(mut self, f: Progress<'s>) -> Self {
        self.progress = Some(f);
        self
    }

    /// Rays per point of [`VolumeSource::depth_harmonic_mean`] (≥ 1).
    pub fn with_depth_rays(mut self, n: usize) -> Self {
        self.depth_rays = n.max(1);
        self.dirs = spherical_fibonacci(self.depth_rays);
        self
    }

    /// Longest accepted virtual offset (metres, default unlimited): a sample
    /// moved farther is reported invalid (validity 0) so the builder dilates
    /// it from its neighbours instead. The CLI uses a quarter of the finest
    /// cell edge.
    pub fn with_max_offset(mut self, metres: f32) -> Self {
        self.max_offset = if metres >= 0.0 { metres } else { f32::INFINITY };
        self
    }

    /// Puts the scene's lights in `light_groups` (one name per light) for
    /// the captures ([`Baker::set_light_groups`]): with the settings'
    /// `exclude_direct`, how a volume leaves run-time lights' direct light
    /// out.
    pub fn with_light_groups(mut self, light_groups: &[String]) -> Result<Self, BakeError> {
        self.baker.set_light_groups(light_groups)?;
        Ok(self)
    }

    /// The baker behind the captures.
    pub fn baker(&self) -> &Baker<'s> {
        &self.baker
    }

    /// The capture settings.
    pub fn settings(&self) -> &CaptureSettings {
        &self.settings
    }

    /// The builder threshold matching the baker's validity test: a sample is
    /// valid when its back-face fraction is at most the baker's
    /// `backface_threshold`, i.e. `1 − fraction ≥ 1 − threshold`.
    pub fn validity_threshold(&self) -> f32 {
        1.0 - self.settings.validity.backface_threshold
    }

    /// Points captured so far (every call of `capture`, including
    /// gradient probes).
    pub fn captures(&self) -> usize {
        self.done.load(Ordering::Relaxed)
    }

    /// The tracer's ray count so far (every query of this source's
    /// tracer: captures, depth rays).
    pub fn rays(&self) -> u64 {
        self.baker.tracer().rays()
    }

    /// Wall and CPU seconds and rays spent in capture batches so far,
    /// summed (phase `capture`).
    pub fn capture_time(&self) -> PhaseTime {
        self.capture_time
            .lock()
            .map(|t| t.clone())
            .unwrap_or_else(|_| PhaseTime::zero("capture"))
    }

    /// The first capture error (a non-finite point), if any; captures that
    /// failed return black, invalid samples until then.
    pub fn take_error(&self) -> Option<BakeError> {
        self.error.lock().map(|mut e| e.take()).unwrap_or(None)
    }

    fn capture_keyed(&self, points: &[Vec3], keys: &[u64]) -> Vec<Captured> {
        let mut clock = Clock::new(self.rays());
        let out = self.capture_batch(points, keys);
        let t = clock.lap("capture", self.rays()).clone();
        if let Ok(mut sum) = self.capture_time.lock() {
            sum.add(&t);
        }
        out
    }

    fn capture_batch(&self, points: &[Vec3], keys: &[u64]) -> Vec<Captured> {
        let total = self.requested.fetch_add(points.len(), Ordering::Relaxed) + points.len();
        let n = self.settings.order * self.settings.order;
        let thr = self.validity_threshold();
        points
            .par_iter()
            .zip(keys)
            .map(|(p, k)| {
                let r = self.baker.capture_with_error(*p, *k, &self.settings);
                let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
                if let Some(f) = self.progress {
                    f("capture", done, total);
                }
                match r {
                    Ok((r, se)) if r.validity.offset.length() > self.max_offset => Captured {
                        sh: r.sh,
                        validity: 0.0,
                        virtual_offset: false,
                        std_error: se,
                    },
                    Ok((r, se)) => {
                        let v = 1.0 - r.validity.backface_fraction;
                        // Keep the builder's threshold test identical to the baker's.
                        let validity = if r.validity.valid {
                            v.max(thr)
                        } else if v >= thr {
                            thr * 0.999
                        } else {
                            v
                        };
                        Captured {
                            sh: r.sh,
                            validity,
                            virtual_offset: r.validity.offset_applied,
                            std_error: se,
                        }
                    }
                    Err(e) => {
                        if let Ok(mut slot) = self.error.lock() {
                            slot.get_or_insert(e);
                        }
                        Captured {
                            sh: crate::sh::ShRgb::zeros(self.settings.order),
                            validity: 0.0,
                            virtual_offset: false,
                            std_error: None,
                        }
                    }
                }
            })
            .inspect(|c| debug_assert_eq!(c.sh.coeffs().len(), n))
            .collect()
    }
}

impl VolumeSource for BakerSource<'_> {
    fn order(&self) -> usize {
        self.settings.order
    }

    fn capture(&self, points: &[Vec3]) -> Vec<Captured> {
        let keys: Vec<u64> = points.iter().map(|p| position_key(*p)).collect();
        self.capture_keyed(points, &keys)
    }

    /// Captures `p ± h eᵢ` with the random numbers of `p` (common random
    /// numbers), then differences.
    fn central_gradients(&self, points: &[Vec3], step: f32) -> Vec<Vec3> {
        let probe = central_points(points, step);
        let keys: Vec<u64> = points
            .iter()
            .flat_map(|p| std::iter::repeat(position_key(*p)).take(6))
            .collect();
        let caps = self.capture_keyed(&probe, &keys);
        central_difference(&caps, self.settings.order, step)
    }

    /// Geometry strictly inside the cell: the box is shrunk by 10⁻³ of its
    /// size first, so a wall lying exactly on a cell face (the usual case
    /// for a bake box fitted to a room's interior) does not refine every
    /// boundary cell — it causes no discontinuity inside the cell.
    fn contains_geometry(&self, min: Vec3, max: Vec3) -> bool {
        let pad = (max - min) * 1e-3;
        self.bins.overlaps(min + pad, max - pad)
    }

    /// An emissive triangle (exact overlap test) or a positional light's
    /// box overlaps the cell.
    fn contains_emitter(&self, min: Vec3, max: Vec3) -> bool {
        let cell = Aabb { min, max };
        self.light_boxes.iter().any(|b| b.overlaps(&cell)) || self.emissive.overlaps(min, max)
    }

    fn depth_harmonic_mean(&self, p: Vec3) -> f32 {
        let inv: f64 = self
            .dirs
            .iter()
            .map(|d| {
                self.baker
                    .tracer()
                    .closest_hit(&Ray::new(p, *d), f32::INFINITY)
                    .map_or(0.0, |h| 1.0 / (h.t.max(1e-6) as f64))
            })
            .sum();
        if inv > 0.0 {
            (self.dirs.len() as f64 / inv) as f32
        } else {
            f32::INFINITY
        }
    }
}

/// Boxes of `scene`'s point, spot, sphere and disk lights: their radius
/// around their position (directional lights have no position).
fn light_boxes(scene: &Scene) -> Vec<Aabb> {
    scene
        .lights
        .iter()
        .filter(|l| l.kind != LightKind::Directional && l.position.is_finite())
        .map(|l| {
            let r = Vec3::splat(l.radius.max(0.0));
            Aabb::new(l.position - r, l.position + r)
        })
        .collect()
}

/// Triangles binned by their boxes into a uniform grid over their bounds
/// (about 32 bins along the longest axis): the scene's, for the geometry
/// test, and its emissive ones, for the emitter test.
struct TriangleBins {
    tris: Vec<[Vec3; 3]>,
    min: Vec3,
    cell: Vec3,
    res: [usize; 3],
    bins: Vec<Vec<u32>>,
}

impl TriangleBins {
    /// Bins `tris` on a grid of at most 32 cells along the longest axis of
    /// their bounding box (each triangle in every bin its box overlaps).
    fn new(tris: Vec<[Vec3; 3]>) -> Self {
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for t in &tris {
            for p in t {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
        if tris.is_empty() {
            return Self {
                tris,
                min: Vec3::ZERO,
                cell: Vec3::ONE,
                res: [1; 3],
                bins: vec![Vec::new()],
            };
        }
        let size = (hi - lo).max(Vec3::splat(1e-3));
        let longest = size.max_element();
        let res = size
            .to_array()
            .map(|s| ((s / longest * 32.0).ceil() as usize).clamp(1, 32));
        let cell = size / Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
        let mut bins = vec![Vec::new(); res[0] * res[1] * res[2]];
        let me = Self {
            tris: Vec::new(),
            min: lo,
            cell,
            res,
            bins: Vec::new(),
        };
        for (i, &[a, b, c]) in tris.iter().enumerate() {
            let (i0, i1) = me.range(a.min(b).min(c), a.max(b).max(c));
            for z in i0[2]..=i1[2] {
                for y in i0[1]..=i1[1] {
                    for x in i0[0]..=i1[0] {
                        bins[x + res[0] * (y + res[1] * z)].push(i as u32);
                    }
                }
            }
        }
        Self { tris, bins, ..me }
    }

    /// Bin index ranges (inclusive) covering `[lo, hi]`, clamped.
    fn range(&self, lo: Vec3, hi: Vec3) -> ([usize; 3], [usize; 3]) {
        let f = |p: Vec3| {
            let q = (p - self.min) / self.cell;
            std::array::from_fn(|a| (q[a].floor().max(0.0) as usize).min(self.res[a] - 1))
        };
        (f(lo), f(hi))
    }

    /// Whether any triangle intersects the closed box `[min, max]`
    /// ([`triangle_box_overlap`]).
    fn overlaps(&self, min: Vec3, max: Vec3) -> bool {
        if self.tris.is_empty() {
            return false;
        }
        let (i0, i1) = self.range(min, max);
        for z in i0[2]..=i1[2] {
            for y in i0[1]..=i1[1] {
                for x in i0[0]..=i1[0] {
                    for &t in &self.bins[x + self.res[0] * (y + self.res[1] * z)] {
                        if triangle_box_overlap(self.tris[t as usize], min, max) {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }
}

/// Whether triangle `tri` intersects the closed box `[min, max]`:
/// separating-axis test over the 3 box normals, the triangle normal and the
/// 9 edge cross products (Akenine-Möller, "Fast 3D Triangle-Box Overlap
/// Testing", 2001). Touching counts as overlap.
pub fn triangle_box_overlap(tri: [Vec3; 3], min: Vec3, max: Vec3) -> bool {
    let c = (min + max) * 0.5;
    let h = (max - min) * 0.5;
    let v = tri.map(|p| p - c);
    let separated = |axis: Vec3| -> bool {
        if axis.length_squared() < 1e-20 {
            return false;
        }
        let p = v.map(|q| q.dot(axis));
        let r = h.x * axis.x.abs() + h.y * axis.y.abs() + h.z * axis.z.abs();
        let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        lo > r || hi < -r
    };
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    for e in edges {
        for a in [Vec3::X, Vec3::Y, Vec3::Z] {
            if separated(a.cross(e)) {
                return false;
            }
        }
    }
    for a in [Vec3::X, Vec3::Y, Vec3::Z] {
        if separated(a) {
            return false;
        }
    }
    !separated(edges[0].cross(edges[1]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The binned test answers like testing every triangle, for boxes
        /// inside, across and outside the triangles' bounds.
        #[test]
        fn binned_overlap_equals_brute_force(
            raw in prop::collection::vec(prop::array::uniform9(-2.0f32..2.0), 0..40),
            boxes in prop::collection::vec(
                (prop::array::uniform3(-3.0f32..3.0), prop::array::uniform3(0.0f32..1.5)),
                1..40,
            ),
        ) {
            // Small triangles around random centres, so bins matter.
            let tris: Vec<[Vec3; 3]> = raw
                .iter()
                .map(|r| {
                    let c = Vec3::new(r[0], r[1], r[2]);
                    [c, c + 0.3 * Vec3::new(r[3], r[4], r[5]), c + 0.3 * Vec3::new(r[6], r[7], r[8])]
                })
                .collect();
            let bins = TriangleBins::new(tris.clone());
            for (lo, size) in &boxes {
                let min = Vec3::from(*lo);
                let max = min + Vec3::from(*size);
                let brute = tris.iter().any(|t| triangle_box_overlap(*t, min, max));
                prop_assert_eq!(bins.overlaps(min, max), brute, "{:?} {:?}", min, max);
            }
        }
    }
}
