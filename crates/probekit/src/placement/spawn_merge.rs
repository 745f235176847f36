//! # Spawn-and-merge placement (Sukys 2014, §3.1.1)
//!
//! After Sukys, "Light probe cloud generation for games" (2014: "Spawn and
//! merge", "Light probe sampling", "Contrast of spherical harmonics"):
//!
//! 1. fill the bake box with a uniform grid of probes and capture them;
//! 2. for every pair of neighbouring probes (the edges of the Delaunay
//!    tetrahedralization of the current probes) compute the *contrast* of
//!    their captured lighting;
//! 3. **merge** pairs that are close (shorter than `merge_distance`) and
//!    similar (contrast ≤ `contrast`) into one probe at their midpoint;
//!    **spawn** a probe at the midpoint of pairs that are not too far apart
//!    (≤ `spawn_distance`), not too close (each half ≥ `min_distance`) and
//!    contrasting (contrast > `contrast`);
//! 4. capture the new probes and repeat until an iteration changes nothing,
//!    `max_iterations` is reached or the probe count reaches `max_probes`.
//!
//! Contrast: the irradiance luminance `I(d)` of each probe's radiance SH
//! (clamped-cosine convolution, [`ShRgb::irradiance`]) is sampled in 6 (±axes)
//! or 26 (the directions to the 26 neighbours of a cube cell: 6 faces, 12
//! edges, 8 corners — Sukys's "pairs of the six directions" plus its "20
//! additional directions") directions; per direction the contrast of two
//! probes is `|I_a − I_b| / (I_a + I_b + floor)` (bounded in `[0, 1]`; the
//! floor, 2 % of the mean sampled luminance over all probes, keeps Monte
//! Carlo noise in unlit areas from reading as contrast). Two probes are
//! *different* when any direction's contrast exceeds the threshold and
//! *similar* otherwise (Sukys's "if any of these values rise above or all
//! of these values fall below the given contrast threshold").
//!
//! Merges never join probes whose connecting segment crosses geometry, and
//! no probe is placed inside geometry (midpoints inside are skipped). Each
//! probe takes part in at most one merge per iteration; the count never
//! drops below 8. Leak prevention runs at the end, as for every method.

use super::{crossing_extent, grid_points, tet_edges, LeakSettings, PlacementError, State};
use crate::delaunay::tetrahedralize;
use crate::progress::Progress;
use crate::scene::Aabb;
use crate::trace::Ray;
use glam::Vec3;
use probekit_sh::ShRgb;

/// How many directions the SH are sampled in (Sukys 2014, §3.1.3 "Light probe sampling").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Directions {
    /// ±X, ±Y, ±Z.
    Six,
    /// The directions to the 26 neighbours of a cube cell (faces, edges, corners).
    TwentySix,
}

impl Directions {
    /// From a count: 6 or 26.
    pub fn from_count(n: u32) -> Result<Self, PlacementError> {
        match n {
            6 => Ok(Directions::Six),
            26 => Ok(Directions::TwentySix),
            _ => Err(PlacementError::BadParameter(format!(
                "directions {n}: expected 6 or 26"
            ))),
        }
    }

    /// The count: 6 or 26.
    pub fn count(self) -> u32 {
        match self {
            Directions::Six => 6,
            Directions::TwentySix => 26,
        }
    }

    /// The unit directions, in a fixed order.
    pub fn vectors(self) -> Vec<Vec3> {
        let mut out = Vec::with_capacity(26);
        for x in -1i32..=1 {
            for y in -1i32..=1 {
                for z in -1i32..=1 {
                    let nz = (x != 0) as u32 + (y != 0) as u32 + (z != 0) as u32;
                    let keep = match self {
                        Directions::Six => nz == 1,
                        Directions::TwentySix => nz >= 1,
                    };
                    if keep {
                        out.push(Vec3::new(x as f32, y as f32, z as f32).normalize());
                    }
                }
            }
        }
        out
    }
}

/// Irradiance luminance (Rec. 709 weights) of radiance SH `sh` in each of
/// `dirs` (E not divided by π).
pub fn sampled_irradiance(sh: &ShRgb, dirs: &[Vec3]) -> Vec<f32> {
    dirs.iter()
        .map(|d| probekit_sh::LUMINANCE.dot(sh.irradiance(*d)))
        .collect()
}

/// The sampled contrast of two probes (Sukys 2014): the largest per-direction
/// `|a − b| / (a + b + floor)` over paired samples `a`, `b` (see the module
/// docs); 0 for empty input. Negative samples (SH ringing) count as 0.
pub fn contrast(a: &[f32], b: &[f32], floor: f32) -> f32 {
    a.iter()
        .zip(b)
        .map(|(&x, &y)| {
            let (x, y) = (x.max(0.0), y.max(0.0));
            (x - y).abs() / (x + y + floor).max(f32::MIN_POSITIVE)
        })
        .fold(0.0, f32::max)
}

/// Parameters of spawn-and-merge placement (distances in metres).
#[derive(Clone, Debug, PartialEq)]
pub struct SpawnMergeParams {
    /// Approximate probe count of the initial uniform grid over the bake box.
    pub initial: usize,
    /// Contrast threshold in `(0, 1)` (see [`contrast`]); default 0.2.
    pub contrast: f32,
    /// Similar pairs shorter than this are merged; `None`: 1.05 × the
    /// initial grid's mean cell edge (so grid neighbours can merge).
    pub merge_distance: Option<f32>,
    /// Contrasting pairs longer than this spawn nothing; `None`: 2 × the
    /// initial cell edge.
    pub spawn_distance: Option<f32>,
    /// A spawned probe is at least this far from both ends (pairs shorter
    /// than twice this spawn nothing); `None`: ¼ of the initial cell edge.
    pub min_distance: Option<f32>,
    /// Sampling directions of the contrast.
    pub directions: Directions,
    /// Spawning stops at this many probes (leak prevention may add up to
    /// a tenth more, at least 4).
    pub max_probes: usize,
    /// Most spawn/merge iterations.
    pub max_iterations: u32,
}

impl Default for SpawnMergeParams {
    fn default() -> Self {
        Self {
            initial: 64,
            contrast: 0.2,
            merge_distance: None,
            spawn_distance: None,
            min_distance: None,
            directions: Directions::TwentySix,
            max_probes: 256,
            max_iterations: 8,
        }
    }
}

impl SpawnMergeParams {
    /// Checks ranges: `initial ≥ 8`, `max_probes ≥ 8`, contrast in `(0, 1)`,
    /// distances finite and positive.
    pub fn validate(&self) -> Result<(), PlacementError> {
        let bad = |m: String| Err(PlacementError::BadParameter(m));
        if self.initial < 8 {
            return bad(format!(
                "spawn-merge initial grid {} must be ≥ 8",
                self.initial
            ));
        }
        if self.max_probes < 8 {
            return bad(format!(
                "spawn-merge max probes {} must be ≥ 8",
                self.max_probes
            ));
        }
        if !(self.contrast > 0.0 && self.contrast < 1.0) {
            return bad(format!("contrast {} must be in (0, 1)", self.contrast));
        }
        for (n, v) in [
            ("merge distance", self.merge_distance),
            ("spawn distance", self.spawn_distance),
            ("min distance", self.min_distance),
        ] {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0) {
                    return bad(format!("{n} {v} must be > 0"));
                }
            }
        }
        Ok(())
    }

    /// Parameters as JSON for the probe file's placement metadata, with the
    /// derived distances resolved for `bake_box`.
    pub fn to_json(&self, bake_box: &Aabb) -> serde_json::Value {
        let (m, s, d) = self.distances(bake_box);
        serde_json::json!({
            "initial": self.initial,
            "contrast": self.contrast,
            "merge_distance": m,
            "spawn_distance": s,
            "min_distance": d,
            "directions": self.directions.count(),
            "max_probes": self.max_probes,
            "max_iterations": self.max_iterations,
        })
    }

    /// `(merge, spawn, min)` distances with the defaults resolved.
    pub fn distances(&self, bake_box: &Aabb) -> (f32, f32, f32) {
        let s = bake_box.size();
        let cell = (s.x * s.y * s.z / self.initial.max(1) as f32).cbrt();
        (
            self.merge_distance.unwrap_or(1.05 * cell),
            self.spawn_distance.unwrap_or(2.0 * cell),
            self.min_distance.unwrap_or(0.25 * cell),
        )
    }
}

/// Runs spawn-and-merge on `st` (empty on entry).
pub(super) fn spawn_merge(
    st: &mut State,
    bbox: &Aabb,
    p: &SpawnMergeParams,
    ls: &LeakSettings,
    progress: Progress<'_>,
) -> Result<(), PlacementError> {
    p.validate()?;
    let (merge_d, spawn_d, min_d) = p.distances(bbox);
    let dirs = p.directions.vectors();
    let grid = grid_points(bbox, None, Some(p.initial))?;
    let grid = st.filter_free(grid);
    let got = st.capture(&grid)?;
    st.add(got);
    progress("spawn-merge", st.positions.len(), p.max_probes);
    let mut samples: Vec<Vec<f32>> = st.sh.iter().map(|s| sampled_irradiance(s, &dirs)).collect();
    let mut round = 0;
    while round < p.max_iterations {
        round += 1;
        if st.positions.len() < 4 {
            break;
        }
        let n = st.positions.len();
        let mean = samples.iter().flatten().map(|v| v.max(0.0)).sum::<f32>()
            / (n * dirs.len()).max(1) as f32;
        let floor = 0.02 * mean + 1e-12;
        let tri = tetrahedralize(&st.positions)?;
        let edges = tet_edges(&tri.tets);
        let tracer = st.baker.tracer();
        // (length, contrast, a, b)
        let mut merge: Vec<(f32, usize, usize)> = Vec::new();
        let mut spawn: Vec<(f32, usize, usize)> = Vec::new();
        for (a, b) in edges {
            let (a, b) = (a as usize, b as usize);
            let (pa, pb) = (st.positions[a], st.positions[b]);
            let d = pa.distance(pb);
            if d <= 1e-6 {
                continue;
            }
            let c = contrast(&samples[a], &samples[b], floor);
            if c <= p.contrast {
                if d < merge_d {
                    merge.push((d, a, b));
                }
            } else if d <= spawn_d && d >= 2.0 * min_d {
                spawn.push((c, a, b));
            }
        }
        // Merges: shortest first, each probe once, never across geometry.
        merge.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
        let mut used = vec![false; n];
        let mut removed = 0usize;
        let mut new_pts: Vec<Vec3> = Vec::new();
        for &(d, a, b) in &merge {
            if n - removed <= 8 {
                break;
            }
            if used[a] || used[b] {
                continue;
            }
            let (pa, pb) = (st.positions[a], st.positions[b]);
            if tracer
                .closest_hit(&Ray::new(pa, (pb - pa) / d), d)
                .is_some()
            {
                continue;
            }
            let mid = 0.5 * (pa + pb);
            if crate::trace::free_space::inside_geometry(tracer, mid) {
                continue;
            }
            used[a] = true;
            used[b] = true;
            removed += 2;
            new_pts.push(mid);
        }
        // Spawns: highest contrast first, up to the probe limit, spaced.
        spawn.sort_by(|x, y| y.0.total_cmp(&x.0).then((x.1, x.2).cmp(&(y.1, y.2))));
        let kept: Vec<Vec3> = (0..n)
            .filter(|&i| !used[i])
            .map(|i| st.positions[i])
            .collect();
        let room = p.max_probes.saturating_sub(kept.len() + new_pts.len());
        let mut spawned: Vec<Vec3> = Vec::new();
        for &(_, a, b) in &spawn {
            if spawned.len() >= room {
                break;
            }
            let mid = 0.5 * (st.positions[a] + st.positions[b]);
            let near = |q: &Vec3| q.distance_squared(mid) < min_d * min_d;
            if kept.iter().any(near) || new_pts.iter().any(near) || spawned.iter().any(near) {
                continue;
            }
            spawned.push(mid);
        }
        let spawned = st.filter_free(spawned);
        if new_pts.is_empty() && spawned.is_empty() {
            break;
        }
        new_pts.extend(spawned);
        let got = st.capture(&new_pts)?;
        // Rebuild the probe list: survivors, then the new captures.
        let mut positions = Vec::with_capacity(kept.len() + got.len());
        let mut sh = Vec::with_capacity(kept.len() + got.len());
        let mut smp = Vec::with_capacity(kept.len() + got.len());
        for i in 0..n {
            if !used[i] {
                positions.push(st.positions[i]);
                sh.push(st.sh[i].clone());
                smp.push(std::mem::take(&mut samples[i]));
            }
        }
        for (q, s) in got {
            smp.push(sampled_irradiance(&s, &dirs));
            positions.push(q);
            sh.push(s);
        }
        st.positions = positions;
        st.sh = sh;
        samples = smp;
        progress("spawn-merge", st.positions.len(), p.max_probes);
    }
    st.stats.rounds = round;
    let (_, before) = crossing_extent(st.baker.tracer(), &st.positions)?;
    st.stats.crossing_before = before;
    st.fix_leaks(ls, (p.max_probes / 10).max(4))?;
    let (_, after) = crossing_extent(st.baker.tracer(), &st.positions)?;
    st.stats.crossing_after = after;
    // The leak pass may add probes beyond `max_probes`: the bar ends full.
    let n = st.positions.len();
    progress("leaks", n, n.max(p.max_probes));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::{inside_geometry, place, PlacementMethod};
    use super::*;
    use crate::capture::{Baker, CaptureSettings};
    use crate::scene::demo::box_triangles;
    use crate::scene::{Light, LightKind, Material, Scene};

    fn settings(samples: u32) -> CaptureSettings {
        CaptureSettings {
            samples,
            bounces: 0,
            order: 3,
            ..Default::default()
        }
    }

    /// A sun shining straight down, a roof over `x > 3` (above the bake box
    /// 0..6 × 0..2.8 × 0..3): lit for x < 3, shadow for x > 3 — a sharp
    /// light boundary on the plane x = 3 in free space.
    fn shadow_edge_scene() -> Scene {
        let roof = box_triangles(Vec3::new(3.0, 3.0, -20.0), Vec3::new(30.0, 3.2, 20.0), 0);
        let sun = Light {
            kind: LightKind::Directional,
            position: Vec3::ZERO,
            direction: Vec3::NEG_Y,
            color: Vec3::ONE,
            intensity: 5.0,
            radius: 0.0,
            inner_angle: 0.0,
            outer_angle: 0.0,
            group: None,
            mode: crate::scene::LightMode::Auto,
            angular_diameter: 0.0,
        };
        let mut s = Scene::from_triangles(
            "shadow-edge",
            vec![("roof".into(), roof)],
            vec![Material::default()],
            vec![sun],
        )
        .unwrap();
        s.bake.r#box = Some(Aabb::new(Vec3::ZERO, Vec3::new(6.0, 2.8, 3.0)));
        s
    }

    #[test]
    fn direction_sets_are_unit_and_complete() {
        let six = Directions::Six.vectors();
        let all = Directions::TwentySix.vectors();
        assert_eq!((six.len(), all.len()), (6, 26));
        for d in &all {
            assert!((d.length() - 1.0).abs() < 1e-6);
        }
        // Symmetric sets: the vectors sum to zero, no duplicates.
        assert!(all.iter().copied().sum::<Vec3>().length() < 1e-5);
        for (i, a) in all.iter().enumerate() {
            assert!(all[i + 1..].iter().all(|b| a.distance(*b) > 0.1));
        }
        assert!(Directions::from_count(7).is_err());
    }

    #[test]
    fn contrast_is_bounded_and_symmetric() {
        let a = [1.0, 2.0, 0.0];
        let b = [1.0, 1.0, 0.0];
        // |2 − 1| / (2 + 1 + 0) = 1/3 in the second direction.
        assert!((contrast(&a, &b, 0.0) - 1.0 / 3.0).abs() < 1e-6);
        assert_eq!(contrast(&a, &b, 0.0), contrast(&b, &a, 0.0));
        assert_eq!(contrast(&a, &a, 0.0), 0.0);
        assert!((contrast(&[5.0], &[0.0], 0.0) - 1.0).abs() < 1e-6);
        // The floor damps contrast between dim values.
        assert!(contrast(&[0.02], &[0.01], 1.0) < 0.01);
    }

    #[test]
    fn spawn_merge_concentrates_probes_at_a_shadow_edge() {
        let scene = shadow_edge_scene();
        let baker = Baker::new(&scene).unwrap();
        let p = SpawnMergeParams {
            initial: 64,
            max_probes: 160,
            max_iterations: 6,
            ..Default::default()
        };
        let m = PlacementMethod::SpawnMerge(p.clone());
        let a = place(&baker, scene.bake_box(), &m, &settings(16), &|_, _, _| {}).unwrap();
        let b = place(&baker, scene.bake_box(), &m, &settings(16), &|_, _, _| {}).unwrap();
        assert_eq!(a, b, "deterministic");
        let n = a.positions.len();
        assert!((8..=160 + 16).contains(&n), "{n}");
        // The slab |x − 3| < 0.75 is a quarter of the box: a uniform set would
        // put ~25 % of its probes there.
        let near = a
            .positions
            .iter()
            .filter(|q| (q.x - 3.0).abs() < 0.75)
            .count();
        let frac = near as f32 / n as f32;
        eprintln!(
            "shadow edge: {near} of {n} probes within 0.75 m, stats {:?}",
            a.stats
        );
        assert!(frac > 0.45, "{near} of {n} probes near the edge");
        // Probe density near the edge is higher than far from it.
        let density_near = near as f32 / 1.5;
        let density_far = (n - near) as f32 / 4.5;
        assert!(
            density_near > 2.0 * density_far,
            "{density_near} {density_far}"
        );
        let tracer = baker.tracer();
        for q in &a.positions {
            assert!(scene.bake_box().contains(*q), "{q}");
            assert!(!inside_geometry(tracer, *q));
        }
        assert!(a.stats.rounds >= 1);
    }

    #[test]
    fn spawn_merge_merges_down_a_uniform_environment() {
        // Constant sky, no geometry nearby (one small box 1 km away).
        let far = box_triangles(Vec3::splat(1000.0), Vec3::splat(1000.5), 0);
        let mut scene = Scene::from_triangles(
            "uniform",
            vec![("far".into(), far)],
            vec![Material::default()],
            vec![],
        )
        .unwrap();
        scene.environment.color = Vec3::splat(0.7);
        scene.bake.r#box = Some(Aabb::new(Vec3::ZERO, Vec3::splat(4.0)));
        let baker = Baker::new(&scene).unwrap();
        for dirs in [Directions::Six, Directions::TwentySix] {
            let p = SpawnMergeParams {
                initial: 64,
                max_probes: 64,
                directions: dirs,
                ..Default::default()
            };
            let m = PlacementMethod::SpawnMerge(p);
            let a = place(&baker, scene.bake_box(), &m, &settings(256), &|_, _, _| {}).unwrap();
            let n = a.positions.len();
            eprintln!("uniform sky, {dirs:?}: 64 -> {n} probes");
            // 4×4×4 = 64 initial probes, all alike: merged down, nothing spawned.
            assert!((8..=24).contains(&n), "{dirs:?}: {n} probes");
            assert_eq!(a.stats.leak_probes, 0);
        }
    }

    #[test]
    fn bad_parameters_are_errors() {
        let scene = shadow_edge_scene();
        let baker = Baker::new(&scene).unwrap();
        for p in [
            SpawnMergeParams {
                contrast: 1.5,
                ..Default::default()
            },
            SpawnMergeParams {
                initial: 3,
                ..Default::default()
            },
            SpawnMergeParams {
                merge_distance: Some(f32::NAN),
                ..Default::default()
            },
        ] {
            let m = PlacementMethod::SpawnMerge(p);
            assert!(matches!(
                place(&baker, scene.bake_box(), &m, &settings(8), &|_, _, _| {}),
                Err(PlacementError::BadParameter(_))
            ));
        }
    }
}
