//! # Gradient-ascent placement (Sukys 2014, §3.1.2, after Chajdas, Weis and
//! Westermann, "Assisted environment map probe placement", SIGRAD 2011)
//!
//! 1. Fill the bake box with a uniform grid of probes and capture them.
//! 2. **Gradient field.** At each probe the irradiance luminance `I(d)` of its
//!    captured radiance SH is sampled in the 26 directions of
//!    [`Directions::TwentySix`] (seed §3.1.3: six directions "converged very
//!    slowly"); the gradient is Chajdas et al.'s sum of the directions
//!    weighted by their luminance, `g = (1/26) Σ_d d·I(d)` — it points to where
//!    the light comes from. (This is Sukys's sampling of one probe's SH,
//!    not a finite difference between neighbouring probes.)
//! 3. **Ascent.** Each probe moves by its step length along `g/|g|`
//!    (initial step `step` × the grid's cell edge) and is recaptured there.
//!    The move is **stepped back** (the probe returns to where it was and its
//!    step is halved — Sukys's "second order" ascent) when the new point
//!    is outside the bake box, inside geometry or invalid, *dark* (its mean
//!    sampled luminance below `dark_threshold` × the mean of the initial
//!    lit probes), or not brighter than before. The last condition goes
//!    beyond the seed (which only steps back from the dark): it makes every
//!    accepted move increase the captured irradiance, a monotone line search.
//!    A probe stops when its step falls below `min_step` × cell; the ascent
//!    stops when no probe moves or after `max_iterations`.
//! 4. With `indirect_only` (seed §3.1.2 "Light decoupling") the gradient and
//!    the dark/brighter tests use the indirect part of the capture
//!    ([`crate::capture::CaptureSettings::split_direct`]); the probes still store all light.
//! 5. Probes that converged onto each other (closer than `merge_fraction` ×
//!    cell) are merged, keeping the first (Chajdas et al.'s "potential
//!    probes" that traced to one point).
//! 6. **Dark probes** (initially dark: their gradient is zero) are not moved;
//!    they are replaced by the representatives of a k-means clustering of
//!    their positions (seed §3.1.3 "Completely unlit areas"): for each
//!    cluster the member probe nearest to the cluster mean, so each
//!    representative lies in the dark region and in free space. `k` is
//!    `dark_clusters`, or `⌈n_dark / 8⌉` (one per 2×2×2 block of grid cells).
//! 7. Leak prevention, as for every method.

use super::spawn_merge::{sampled_irradiance, Directions};
use super::{crossing_extent, grid_points, LeakSettings, PlacementError, State};
use crate::progress::Progress;
use crate::sampling::SampleRng;
use crate::scene::Aabb;
use glam::Vec3;
use probekit_sh::ShRgb;

/// Parameters of gradient-ascent placement.
#[derive(Clone, Debug, PartialEq)]
pub struct GradientAscentParams {
    /// Approximate probe count of the initial uniform grid over the bake box.
    pub initial: usize,
    /// Gradient from indirect light only (Sukys 2014, "Light decoupling").
    pub indirect_only: bool,
    /// Initial step, as a fraction of the grid's cell edge (default 0.5).
    pub step: f32,
    /// A probe stops once its step is below this fraction of the cell edge
    /// (default 0.05).
    pub min_step: f32,
    /// Most ascent iterations (default 8).
    pub max_iterations: u32,
    /// Dark: mean sampled irradiance luminance below this fraction of the
    /// mean over the lit initial probes (default 0.01).
    pub dark_threshold: f32,
    /// Number of k-means clusters replacing the dark probes; `None`: `⌈n/8⌉`.
    pub dark_clusters: Option<usize>,
    /// Probes closer than this fraction of the cell edge after the ascent
    /// are merged (default 0.25).
    pub merge_fraction: f32,
}

impl Default for GradientAscentParams {
    fn default() -> Self {
        Self {
            initial: 256,
            indirect_only: false,
            step: 0.5,
            min_step: 0.05,
            max_iterations: 8,
            dark_threshold: 0.01,
            dark_clusters: None,
            merge_fraction: 0.25,
        }
    }
}

impl GradientAscentParams {
    /// Checks ranges: `initial ≥ 8`, `0 < min_step ≤ step`, thresholds finite and ≥ 0.
    pub fn validate(&self) -> Result<(), PlacementError> {
        let bad = |m: String| Err(PlacementError::BadParameter(m));
        if self.initial < 8 {
            return bad(format!(
                "gradient-ascent initial grid {} must be ≥ 8",
                self.initial
            ));
        }
        if !(self.step.is_finite() && self.min_step > 0.0 && self.min_step <= self.step) {
            return bad(format!(
                "gradient-ascent steps: need 0 < min step {} ≤ step {}",
                self.min_step, self.step
            ));
        }
        if !(self.dark_threshold.is_finite() && self.dark_threshold >= 0.0) {
            return bad(format!(
                "dark threshold {} must be ≥ 0",
                self.dark_threshold
            ));
        }
        if !(self.merge_fraction.is_finite() && self.merge_fraction >= 0.0) {
            return bad(format!(
                "merge fraction {} must be ≥ 0",
                self.merge_fraction
            ));
        }
        if self.dark_clusters == Some(0) {
            return bad("dark clusters must be ≥ 1".into());
        }
        Ok(())
    }

    /// Parameters as JSON for the probe file's placement metadata.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "initial": self.initial,
            "indirect_only": self.indirect_only,
            "step": self.step,
            "min_step": self.min_step,
            "max_iterations": self.max_iterations,
            "dark_threshold": self.dark_threshold,
            "dark_clusters": self.dark_clusters,
            "merge_fraction": self.merge_fraction,
            "directions": 26,
        })
    }
}

/// Chajdas et al.'s gradient from samples `lum[i]` of the irradiance
/// luminance in directions `dirs[i]`: `(1/N) Σ d_i·lum_i`.
pub fn sampled_gradient(lum: &[f32], dirs: &[Vec3]) -> Vec3 {
    let n = lum.len().min(dirs.len()).max(1) as f32;
    lum.iter().zip(dirs).map(|(l, d)| *d * *l).sum::<Vec3>() / n
}

/// Result of [`kmeans`].
#[derive(Clone, Debug, PartialEq)]
pub struct KMeans {
    /// Cluster means.
    pub centres: Vec<Vec3>,
    /// Cluster of each input point.
    pub assignment: Vec<usize>,
}

/// Lloyd's k-means of `points` into `min(k, n)` clusters, seeded
/// deterministically by farthest-point initialisation (first centre the
/// point nearest the mean of all points), at most `iterations` rounds;
/// ties go to the lower index. Empty input gives no clusters.
pub fn kmeans(points: &[Vec3], k: usize, iterations: u32) -> KMeans {
    let n = points.len();
    let k = k.min(n);
    if k == 0 {
        return KMeans {
            centres: Vec::new(),
            assignment: vec![0; n],
        };
    }
    let mean = points.iter().copied().sum::<Vec3>() / n as f32;
    let nearest = |c: &[Vec3], p: Vec3| -> (usize, f32) {
        let mut best = (0, f32::INFINITY);
        for (i, q) in c.iter().enumerate() {
            let d = q.distance_squared(p);
            if d < best.1 {
                best = (i, d);
            }
        }
        best
    };
    let first = nearest(points, mean).0;
    let mut centres = vec![points[first]];
    while centres.len() < k {
        let far = (0..n)
            .map(|i| (nearest(&centres, points[i]).1, i))
            .fold((-1.0f32, 0usize), |a, b| if b.0 > a.0 { b } else { a })
            .1;
        centres.push(points[far]);
    }
    let mut assignment = vec![usize::MAX; n];
    for _ in 0..iterations.max(1) {
        let mut changed = false;
        for (i, p) in points.iter().enumerate() {
            let c = nearest(&centres, *p).0;
            if assignment[i] != c {
                assignment[i] = c;
                changed = true;
            }
        }
        if !changed {
            break;
        }
        let mut sum = vec![(Vec3::ZERO, 0usize); k];
        for (p, &c) in points.iter().zip(&assignment) {
            sum[c].0 += *p;
            sum[c].1 += 1;
        }
        for (c, (s, m)) in centres.iter_mut().zip(sum) {
            if m > 0 {
                *c = s / m as f32;
            }
        }
    }
    KMeans {
        centres,
        assignment,
    }
}

/// Representatives of the k-means clusters of `points` (see [`kmeans`]):
/// per non-empty cluster, the member nearest to its mean, in cluster order.
/// Each representative is one of the input points.
pub fn cluster_representatives(points: &[Vec3], k: usize) -> Vec<Vec3> {
    let km = kmeans(points, k, 50);
    let mut best: Vec<Option<(f32, usize)>> = vec![None; km.centres.len()];
    for (i, (p, &c)) in points.iter().zip(&km.assignment).enumerate() {
        let d = p.distance_squared(km.centres[c]);
        if !matches!(best[c], Some(b) if b.0 <= d) {
            best[c] = Some((d, i));
        }
    }
    best.into_iter().flatten().map(|(_, i)| points[i]).collect()
}

/// One accepted move of a probe during the ascent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AscentMove {
    /// Probe index in the initial (lit) list.
    pub probe: usize,
    /// Position before, metres.
    pub from: Vec3,
    /// Position after, metres.
    pub to: Vec3,
    /// Mean sampled irradiance luminance of the field before.
    pub before: f32,
    /// The same after (greater than `before`).
    pub after: f32,
}

/// A probe during the ascent.
struct Walker {
    pos: Vec3,
    sh: ShRgb,
    lum: Vec<f32>,
    mag: f32,
    step: f32,
    active: bool,
}

/// One valid capture: `(captured position, all-light SH, field SH)`.
type Capture = (Vec3, ShRgb, ShRgb);

/// Captures `pts` returning `(captured position, all-light SH, field SH)` for
/// the valid ones (index into `pts`), the field being indirect light when
/// `indirect_only`.
fn capture_field(
    st: &mut State,
    pts: &[Vec3],
    indirect_only: bool,
) -> Result<Vec<Option<Capture>>, PlacementError> {
    let mut cs = st.settings.clone();
    cs.split_direct = indirect_only;
    let res = st.baker.capture_many(pts, st.next_index, &cs, &|_, _| {})?;
    st.next_index += pts.len();
    st.stats.captures += pts.len();
    let tracer = st.baker.tracer();
    Ok(res
        .into_iter()
        .map(|r| {
            if r.validity.valid && !crate::trace::free_space::inside_geometry(tracer, r.position) {
                let field = if indirect_only {
                    r.indirect.clone().unwrap_or_else(|| r.sh.clone())
                } else {
                    r.sh.clone()
                };
                Some((r.position, r.sh, field))
            } else {
                None
            }
        })
        .collect())
}

fn mean(v: &[f32]) -> f32 {
    v.iter().map(|x| x.max(0.0)).sum::<f32>() / v.len().max(1) as f32
}

/// Runs gradient ascent on `st` (empty on entry); returns the accepted moves.
pub(super) fn gradient_ascent(
    st: &mut State,
    bbox: &Aabb,
    p: &GradientAscentParams,
    ls: &LeakSettings,
    progress: Progress<'_>,
) -> Result<Vec<AscentMove>, PlacementError> {
    p.validate()?;
    let dirs = Directions::TwentySix.vectors();
    let size = bbox.size();
    let cell = (size.x * size.y * size.z / p.initial as f32).cbrt();
    let grid = grid_points(bbox, None, Some(p.initial))?;
    let grid = st.filter_free(grid);
    let got = capture_field(st, &grid, p.indirect_only)?;
    let mut walkers: Vec<Walker> = Vec::new();
    for (pos, sh, field) in got.into_iter().flatten() {
        let lum = sampled_irradiance(&field, &dirs);
        let mag = mean(&lum);
        walkers.push(Walker {
            pos,
            sh,
            lum,
            mag,
            step: p.step * cell,
            active: true,
        });
    }
    st.stats.rejected_inside += grid.len() - walkers.len();
    let all_mean = walkers.iter().map(|w| w.mag).sum::<f32>() / walkers.len().max(1) as f32;
    let dark_level = p.dark_threshold * all_mean;
    let (dark, mut lit): (Vec<Walker>, Vec<Walker>) = walkers
        .into_iter()
        .partition(|w| !(w.mag > dark_level && w.mag > 0.0));
    for w in &mut lit {
        if sampled_gradient(&w.lum, &dirs).length() <= 0.0 {
            w.active = false;
        }
    }
    let total = p.max_iterations as usize;
    let mut moves = Vec::new();
    let mut round = 0;
    while round < p.max_iterations {
        round += 1;
        let idx: Vec<usize> = (0..lit.len()).filter(|&i| lit[i].active).collect();
        if idx.is_empty() {
            break;
        }
        let mut props = Vec::with_capacity(idx.len());
        for &i in &idx {
            let w = &lit[i];
            let g = sampled_gradient(&w.lum, &dirs);
            props.push(w.pos + g.normalize_or_zero() * w.step);
        }
        // Outside the box or inside geometry: step back without capturing.
        let tracer = st.baker.tracer();
        let ok: Vec<bool> = props
            .iter()
            .map(|q| {
                q.cmpge(bbox.min).all()
                    && q.cmple(bbox.max).all()
                    && !crate::trace::free_space::inside_geometry(tracer, *q)
            })
            .collect();
        let to_capture: Vec<Vec3> = props
            .iter()
            .zip(&ok)
            .filter(|(_, k)| **k)
            .map(|(q, _)| *q)
            .collect();
        let mut got = capture_field(st, &to_capture, p.indirect_only)?.into_iter();
        let mut any_moved = false;
        for (j, &i) in idx.iter().enumerate() {
            let res = if ok[j] { got.next().flatten() } else { None };
            let w = &mut lit[i];
            let accepted = match res {
                Some((pos, sh, field)) => {
                    let lum = sampled_irradiance(&field, &dirs);
                    let mag = mean(&lum);
                    if mag > dark_level && mag > w.mag {
                        moves.push(AscentMove {
                            probe: i,
                            from: w.pos,
                            to: pos,
                            before: w.mag,
                            after: mag,
                        });
                        w.pos = pos;
                        w.sh = sh;
                        w.lum = lum;
                        w.mag = mag;
                        true
                    } else {
                        false
                    }
                }
                None => false,
            };
            if accepted {
                any_moved = true;
            } else {
                w.step *= 0.5;
                if w.step < p.min_step * cell {
                    w.active = false;
                }
            }
        }
        progress("gradient-ascent", round as usize, total);
        if !any_moved && lit.iter().all(|w| !w.active) {
            break;
        }
    }
    st.stats.rounds = round;
    // Merge probes that converged onto each other (keep the first).
    let r = p.merge_fraction * cell;
    let mut kept: Vec<Walker> = Vec::with_capacity(lit.len());
    for w in lit {
        if kept.iter().all(|k| k.pos.distance_squared(w.pos) >= r * r) {
            kept.push(w);
        }
    }
    for w in kept {
        st.positions.push(w.pos);
        st.sh.push(w.sh);
    }
    // Dark probes → k-means representatives.
    if !dark.is_empty() {
        let k = p.dark_clusters.unwrap_or(dark.len().div_ceil(8));
        let pts: Vec<Vec3> = dark.iter().map(|w| w.pos).collect();
        for rep in cluster_representatives(&pts, k) {
            if let Some(w) = dark.iter().find(|w| w.pos == rep) {
                st.positions.push(w.pos);
                st.sh.push(w.sh.clone());
            }
        }
    }
    if st.positions.len() < 4 {
        // Too few to tetrahedralize: fall back to spread-out initial points.
        let mut rng = SampleRng::new(st.settings.seed ^ 0x4741_5343, 0, 0);
        let extra: Vec<Vec3> = (0..8)
            .map(|_| bbox.min + Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * size)
            .collect();
        let extra = st.filter_free(extra);
        let got = st.capture(&extra)?;
        st.add(got);
    }
    let (_, before) = crossing_extent(st.baker.tracer(), &st.positions)?;
    st.stats.crossing_before = before;
    st.fix_leaks(ls, (p.initial / 10).max(4))?;
    let (_, after) = crossing_extent(st.baker.tracer(), &st.positions)?;
    st.stats.crossing_after = after;
    progress("leaks", st.positions.len(), st.positions.len());
    Ok(moves)
}

#[cfg(test)]
mod tests {
    use super::super::{place, PlacementMethod, PlacementStats};
    use super::*;
    use crate::capture::{Baker, CaptureSettings};
    use crate::scene::demo::box_triangles;
    use crate::scene::{Light, LightKind, Material, Scene};

    const LIGHT: Vec3 = Vec3::new(1.0, 1.5, 1.0);
    const PILLAR_MIN: Vec3 = Vec3::new(1.8, 0.0, 1.8);
    const PILLAR_MAX: Vec3 = Vec3::new(2.4, 3.0, 2.4);

    fn settings() -> CaptureSettings {
        CaptureSettings {
            samples: 16,
            bounces: 0,
            order: 3,
            ..Default::default()
        }
    }

    /// A point light at [`LIGHT`] in a 4 × 3 × 4 box, a pillar casting a
    /// shadow towards +x +z; black sky, direct light only.
    fn point_light_scene() -> Scene {
        let pillar = box_triangles(PILLAR_MIN, PILLAR_MAX, 0);
        let light = Light {
            kind: LightKind::Point,
            position: LIGHT,
            direction: Vec3::NEG_Y,
            color: Vec3::ONE,
            intensity: 10.0,
            radius: 0.0,
            inner_angle: 0.0,
            outer_angle: 0.0,
            group: None,
            mode: crate::scene::LightMode::Auto,
            angular_diameter: 0.0,
        };
        let mut s = Scene::from_triangles(
            "point-light",
            vec![("pillar".into(), pillar)],
            vec![Material::default()],
            vec![light],
        )
        .unwrap();
        s.bake.r#box = Some(Aabb::new(Vec3::ZERO, Vec3::new(4.0, 3.0, 4.0)));
        s
    }

    fn in_pillar(p: Vec3) -> bool {
        p.cmpgt(PILLAR_MIN).all() && p.cmplt(PILLAR_MAX).all()
    }

    /// Whether the segment from `p` to the light crosses the pillar (slab test).
    fn shadowed(p: Vec3) -> bool {
        let d = LIGHT - p;
        let (mut t0, mut t1) = (0.0f32, 1.0f32);
        for k in 0..3 {
            if d[k].abs() < 1e-9 {
                if p[k] < PILLAR_MIN[k] || p[k] > PILLAR_MAX[k] {
                    return false;
                }
                continue;
            }
            let (a, b) = ((PILLAR_MIN[k] - p[k]) / d[k], (PILLAR_MAX[k] - p[k]) / d[k]);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
        t0 < t1
    }

    #[test]
    fn accepted_moves_climb_towards_the_light() {
        let scene = point_light_scene();
        let baker = Baker::new(&scene).unwrap();
        let mut st = State {
            baker: &baker,
            settings: settings(),
            positions: Vec::new(),
            sh: Vec::new(),
            next_index: 0,
            stats: PlacementStats::default(),
            layer: None,
            clock: crate::progress::Clock::new(0),
            free_points: Vec::new(),
        };
        let p = GradientAscentParams {
            initial: 64,
            max_iterations: 6,
            ..Default::default()
        };
        let moves = gradient_ascent(
            &mut st,
            &scene.bake_box(),
            &p,
            &LeakSettings::default(),
            &|_, _, _| {},
        )
        .unwrap();
        assert!(moves.len() > 20, "{} moves", moves.len());
        for m in &moves {
            assert!(m.after > m.before);
            // Independent check: the point light's irradiance magnitude is
            // I/r² (both ends lit), so r must shrink. The 26-direction mean
            // is isotropic to about 1 %, hence the small allowance.
            let (r0, r1) = (m.from.distance(LIGHT), m.to.distance(LIGHT));
            assert!(r1 < r0 * 1.01, "{m:?}: r {r0} -> {r1}");
            assert!(!shadowed(m.to) && !in_pillar(m.to), "{m:?}");
        }
        let closer = moves
            .iter()
            .filter(|m| m.to.distance(LIGHT) < m.from.distance(LIGHT))
            .count();
        assert!(
            closer * 10 >= moves.len() * 9,
            "{closer} of {}",
            moves.len()
        );
        eprintln!(
            "point light: {} accepted moves, {closer} closer; {} probes at the end",
            moves.len(),
            st.positions.len()
        );
        for q in &st.positions {
            assert!(!in_pillar(*q), "{q}");
        }
        // Dark probes (in the pillar's shadow) are represented by ⌈n/8⌉
        // k-means representatives, each still in the shadow.
        let dark_after = st.positions.iter().filter(|q| shadowed(**q)).count();
        assert!(dark_after >= 1, "no shadowed probe kept");
        let g: Vec<Vec3> = grid_points(&scene.bake_box(), None, Some(64))
            .unwrap()
            .into_iter()
            .filter(|q| !in_pillar(*q))
            .collect();
        let dark_before = g.iter().filter(|q| shadowed(**q)).count();
        assert!(dark_before >= 2);
        // Leak probes may land in the shadow too; the representatives alone are ⌈n/8⌉.
        assert!(
            dark_after >= dark_before.div_ceil(8),
            "{dark_after} {dark_before}"
        );
    }

    #[test]
    fn placement_is_deterministic_and_never_inside() {
        let scene = point_light_scene();
        let baker = Baker::new(&scene).unwrap();
        for indirect_only in [false, true] {
            let m = PlacementMethod::GradientAscent(GradientAscentParams {
                initial: 48,
                max_iterations: 4,
                indirect_only,
                ..Default::default()
            });
            let mut s = settings();
            s.bounces = 1;
            let a = place(&baker, scene.bake_box(), &m, &s, &|_, _, _| {}).unwrap();
            let b = place(&baker, scene.bake_box(), &m, &s, &|_, _, _| {}).unwrap();
            assert_eq!(a, b);
            assert!(a.positions.len() >= 4);
            for q in &a.positions {
                assert!(!in_pillar(*q), "{q}");
                assert!(scene.bake_box().contains(*q), "{q}");
            }
        }
    }

    #[test]
    fn kmeans_is_a_lloyd_fixed_point_and_representatives_stay_in_the_region() {
        // An L-shaped dark region: x in 0..3, z in 0..1, plus x in 0..1, z in 1..3.
        let in_l = |p: Vec3| {
            (p.x >= 0.0 && p.x <= 3.0 && p.z >= 0.0 && p.z <= 1.0)
                || (p.x >= 0.0 && p.x <= 1.0 && p.z >= 0.0 && p.z <= 3.0)
        };
        let mut pts = Vec::new();
        for i in 0..12 {
            for k in 0..12 {
                for j in 0..2 {
                    let p = Vec3::new(
                        0.125 + 0.25 * i as f32,
                        0.5 + j as f32,
                        0.125 + 0.25 * k as f32,
                    );
                    if in_l(p) {
                        pts.push(p);
                    }
                }
            }
        }
        for k in [1usize, 3, 5] {
            let km = kmeans(&pts, k, 100);
            assert_eq!(km.centres.len(), k);
            // Brute-force check of Lloyd's conditions.
            for (p, &c) in pts.iter().zip(&km.assignment) {
                let d = p.distance_squared(km.centres[c]);
                for q in &km.centres {
                    assert!(d <= p.distance_squared(*q) + 1e-5);
                }
            }
            for (ci, c) in km.centres.iter().enumerate() {
                let members: Vec<Vec3> = pts
                    .iter()
                    .zip(&km.assignment)
                    .filter(|(_, &a)| a == ci)
                    .map(|(p, _)| *p)
                    .collect();
                assert!(!members.is_empty());
                let mean = members.iter().copied().sum::<Vec3>() / members.len() as f32;
                assert!(mean.distance(*c) < 1e-4, "{mean} {c}");
            }
            let reps = cluster_representatives(&pts, k);
            assert_eq!(reps.len(), k);
            for r in &reps {
                assert!(in_l(*r) && pts.contains(r), "{r}");
            }
        }
        assert!(kmeans(&[], 3, 10).centres.is_empty());
        assert_eq!(kmeans(&pts[..2], 5, 10).centres.len(), 2);
    }

    #[test]
    fn gradient_of_one_bright_direction_points_at_it() {
        let dirs = Directions::TwentySix.vectors();
        let lum: Vec<f32> = dirs.iter().map(|d| d.dot(Vec3::X).max(0.0)).collect();
        let g = sampled_gradient(&lum, &dirs);
        assert!(g.normalize().dot(Vec3::X) > 0.999, "{g}");
        assert!(sampled_gradient(&[1.0; 26], &dirs).length() < 1e-6);
    }
}
