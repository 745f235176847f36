//! # Placement comparisons and budget sweeps (`probekit eval --plot`)
//!
//! Each measured configuration goes the way a user's file goes: the
//! evaluated file's recipe with another placement, baked by [`Bake::run`]
//! (placement, capture, assembly and blend data), evaluated as `probekit
//! eval` evaluates a file (the runtime's [`Probes`], [`predict`]) on the
//! same points and ground truth ([`metrics`]).
//!
//! A sweep maps a probe budget `B` to each method's own knob
//! ([`placement_for_budget`]) and reports the probe count each actually
//! produced: `grid` ≈ `B` cells (those inside geometry moved out by the
//! virtual offset, as `probekit bake` does), `adaptive` budget `B`,
//! `spawn-and-merge` an initial grid of `B/2` growing to at most `B`,
//! `gradient-ascent` an initial grid of `B` (merging, dark clustering and
//! leak prevention change the count).

use super::{Bake, PipelineError};
use crate::eval::{mean_luminance, metrics, predict, Metrics};
use crate::plot::{line_chart_log, PlotError};
use crate::progress::Progress;
use crate::recipe::{CellVisibility, Placement, Recipe};
use crate::scene::Scene;
use crate::trace::free_space::EvalPoint;
use glam::Vec3;
use probekit_runtime::{BlendOverrides, LoadError, LoadOptions, Probes, QueryError};
use std::path::Path;
use thiserror::Error;

/// The methods a sweep runs, in plot order.
pub const SWEEP_METHODS: [&str; 4] = ["grid", "adaptive", "spawn-and-merge", "gradient-ascent"];

/// Why one placement + bake + evaluation failed.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SweepError {
    /// An unknown method name.
    #[error(
        "unknown placement method `{0}` (expected grid, adaptive, spawn-and-merge or \
         gradient-ascent)"
    )]
    UnknownMethod(String),
    /// The bake failed.
    #[error(transparent)]
    Bake(#[from] PipelineError),
    /// The cloud could not be loaded for queries.
    #[error(transparent)]
    Load(#[from] LoadError),
    /// The cloud could not be queried.
    #[error(transparent)]
    Query(#[from] QueryError),
}

/// The placement `name` configured for about `budget` probes (see the
/// module docs); the other parameters are the method's defaults.
pub fn placement_for_budget(name: &str, budget: usize) -> Result<Placement, SweepError> {
    let mut p =
        Placement::defaults_of(name).ok_or_else(|| SweepError::UnknownMethod(name.into()))?;
    let at_least_8 = budget.max(8);
    match &mut p {
        Placement::Grid { budget: b, .. } => *b = Some(budget),
        Placement::Adaptive {
            budget: b,
            tolerance,
            ..
        } => {
            *b = at_least_8;
            // The sweep measures the budget, not the tolerance.
            *tolerance = 0.0;
        }
        Placement::SpawnAndMerge {
            budget: b, initial, ..
        } => {
            *b = at_least_8;
            *initial = Some((budget / 2).max(8));
        }
        Placement::GradientAscent { budget: b, .. } => *b = at_least_8,
        Placement::Manual { .. } => return Err(SweepError::UnknownMethod(name.into())),
    }
    Ok(p)
}

/// One measured point of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepRow {
    /// Placement method name.
    pub method: String,
    /// The budget asked for.
    pub budget: usize,
    /// Probes the method actually produced.
    pub probes: usize,
    /// Error figures on the sweep's points.
    pub metrics: Metrics,
}

impl SweepRow {
    /// `{"method","budget","probes","rel_rmse","p95_rel_error","leaks"}`.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "method": self.method,
            "budget": self.budget,
            "probes": self.probes,
            "rel_rmse": self.metrics.rel_rmse,
            "p95_rel_error": self.metrics.p95_rel_error,
            "leaks": self.metrics.leaks,
        })
    }
}

/// Runs every method of `methods` at every budget of `budgets`: `recipe`
/// with that placement, baked over `scene` (named `scene_name`) by the
/// pipeline, loaded with the caller's load options (`options`: the blend
/// overrides of the evaluated file's queries), evaluated on `points`
/// against `truth`. A configuration
/// that fails is reported to `on_error(method, budget, error)` and left
/// out; the rest go on. Rows are in method-then-budget order.
#[allow(clippy::too_many_arguments)]
pub fn sweep(
    scene: &Scene,
    scene_name: &str,
    recipe: &Recipe,
    methods: &[&str],
    budgets: &[usize],
    options: &LoadOptions,
    points: &[EvalPoint],
    truth: &[Vec3],
    on_error: &mut dyn FnMut(&str, usize, &SweepError),
    progress: Progress<'_>,
) -> Vec<SweepRow> {
    let mean = mean_luminance(truth);
    let mut rows = Vec::new();
    for &m in methods {
        for &b in budgets {
            let step =
                |phase: &str, done, total| progress(&format!("{m} {b}: {phase}"), done, total);
            let r = placement_for_budget(m, b).and_then(|placement| {
                let r = Recipe {
                    placement,
                    ..recipe.clone()
                };
                let file = Bake::new(scene, scene_name, &r)?.run(&step)?.file;
                let pred = predict(&Probes::from_file(&file, *options)?, points)?;
                Ok((
                    r.placement.method(),
                    file.positions().len(),
                    metrics(&pred, truth, mean),
                ))
            });
            match r {
                Ok((method, probes, metrics)) => rows.push(SweepRow {
                    method: method.into(),
                    budget: b,
                    probes,
                    metrics,
                }),
                Err(e) => on_error(m, b, &e),
            }
        }
    }
    rows
}

/// Leaves out of `recipe`'s blend data what `overrides` switch off (distance
/// moments, cell visibility, probe weights), so that a sweep's clouds carry
/// the blend data the evaluated file's queries use; the overrides
/// themselves still apply at load ([`sweep`]'s `options`).
pub fn without_overridden_blend_data(recipe: &mut Recipe, overrides: &BlendOverrides) {
    let blend = &mut recipe.blend;
    if overrides.distance_moments == Some(false) {
        blend.distance_moments = 0;
    }
    if overrides.cell_visibility == Some(false) {
        blend.cell_visibility = CellVisibility::Subdivision(0);
    }
    if overrides.probe_weights == Some(false) {
        blend.probe_weights = false;
    }
}

/// Draws `rel_rmse` against probe count, one line per method (in first-seen
/// order), both axes log10, with [`crate::plot`]. Rows with a non-positive
/// error are left out (a log axis cannot show them).
pub fn plot_sweep(path: impl AsRef<Path>, title: &str, rows: &[SweepRow]) -> Result<(), PlotError> {
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for r in rows {
        if !(r.metrics.rel_rmse > 0.0 && r.probes > 0) {
            continue;
        }
        let pt = (r.probes as f64, r.metrics.rel_rmse as f64);
        match series.iter_mut().find(|s| s.0 == r.method) {
            Some(s) => s.1.push(pt),
            None => series.push((r.method.clone(), vec![pt])),
        }
    }
    for s in &mut series {
        s.1.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    line_chart_log(path, title, &series, "probes", "rel. RMSE", true, true)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::capture::{Baker, ReferenceSettings};
    use crate::eval::reference;
    use crate::placement::grid_points;
    use crate::recipe::{Blend, Fit};
    use crate::scene::demo::box_triangles;
    use crate::scene::{Aabb, Light, LightKind, Material};
    use crate::trace::free_space::{inside_geometry, sample_points};

    /// A sun-lit room corner: floor slab and one wall, sky light.
    fn scene() -> Scene {
        let floor = box_triangles(Vec3::new(-1.0, -0.2, -1.0), Vec3::new(5.0, 0.0, 4.0), 0);
        let wall = box_triangles(Vec3::new(2.0, 0.0, -1.0), Vec3::new(2.2, 1.5, 2.0), 0);
        let sun = Light {
            kind: LightKind::Directional,
            position: Vec3::ZERO,
            direction: Vec3::new(1.0, -1.0, 0.3).normalize(),
            color: Vec3::ONE,
            intensity: 3.0,
            radius: 0.0,
            inner_angle: 0.0,
            outer_angle: 0.0,
            group: None,
            mode: crate::scene::LightMode::Auto,
            angular_diameter: 0.0,
        };
        let mut s = Scene::from_triangles(
            "corner",
            vec![("floor".into(), floor), ("wall".into(), wall)],
            vec![Material::default()],
            vec![sun],
        )
        .unwrap();
        s.environment.color = Vec3::splat(0.2);
        s.bake.r#box = Some(Aabb::new(
            Vec3::new(0.0, 0.05, 0.0),
            Vec3::new(4.0, 2.0, 3.0),
        ));
        s
    }

    #[test]
    fn unknown_method_is_an_error() {
        assert!(placement_for_budget("nope", 10).is_err());
        assert!(placement_for_budget("manual", 10).is_err());
    }

    #[test]
    fn sweep_draws_a_png_and_reports_consistent_rows() {
        let scene = scene();
        let baker = Baker::new(&scene).unwrap();
        let mut recipe = Recipe::default();
        recipe.capture.samples = 16;
        recipe.capture.bounces = 1;
        recipe.blend = Blend::none();
        let pts = sample_points(baker.tracer(), &scene.bake_box(), 40, 3);
        let rs = ReferenceSettings {
            relative_precision: 0.2,
            min_samples: 64,
            max_samples: 256,
            bounces: 1,
            ..Default::default()
        };
        let truth = reference(&baker, &pts, &rs).unwrap();
        let mut failures = Vec::new();
        let phases = std::sync::Mutex::new(std::collections::BTreeSet::new());
        let budgets = [16usize, 32];
        let rows = sweep(
            &scene,
            "corner",
            &recipe,
            &SWEEP_METHODS,
            &budgets,
            &LoadOptions::default(),
            &pts,
            &truth,
            &mut |m, b, e| failures.push(format!("{m} {b}: {e}")),
            &|phase, done, total| {
                assert!(done <= total, "{phase}: {done} of {total}");
                phases.lock().unwrap().insert(phase.to_string());
            },
        );
        assert_eq!(rows.len() + failures.len(), 8, "{failures:?}");
        // Every configuration that ran reported its captures, named by
        // method and budget.
        let phases = phases.into_inner().unwrap();
        for r in &rows {
            let p = format!("{} {}: capture", r.method, r.budget);
            assert!(phases.contains(&p), "{p} missing from {phases:?}");
        }
        for m in SWEEP_METHODS {
            assert!(rows.iter().any(|r| r.method == m), "{m}: {failures:?}");
        }
        for r in &rows {
            assert!(r.probes >= 4, "{r:?}");
            assert_eq!(r.metrics.points, pts.len());
            assert!(r.metrics.rel_rmse.is_finite() && r.metrics.rel_rmse >= 0.0);
            let j = r.to_json();
            assert_eq!(j["method"], r.method.as_str());
            assert_eq!(j["probes"], r.probes);
            assert_eq!(j["budget"], r.budget);
            assert_eq!(j["leaks"], r.metrics.leaks);
            assert!((j["rel_rmse"].as_f64().unwrap() - r.metrics.rel_rmse as f64).abs() < 1e-6);
        }
        // The grid rows hold exactly the free grid cells (independent count).
        for r in rows.iter().filter(|r| r.method == "grid") {
            let free = grid_points(&scene.bake_box(), None, Some(r.budget))
                .unwrap()
                .into_iter()
                .filter(|q| !inside_geometry(baker.tracer(), *q))
                .count();
            assert_eq!(r.probes, free);
        }
        // With blend data and a query setting the grid row changes, and it
        // carries the recipe's blend data into the swept files.
        recipe.blend = Blend {
            distance_moments: 4,
            cell_visibility: CellVisibility::Subdivision(2),
            occluder_planes: true,
            probe_weights: true,
            fit: Fit {
                points_per_probe: 2,
                samples: 8,
                ..Fit::default()
            },
            ..Blend::default()
        };
        let mut biased = LoadOptions::default();
        biased.blend.visibility_bias = Some(0.1);
        let grid = sweep(
            &scene,
            "corner",
            &recipe,
            &["grid"],
            &[32],
            &biased,
            &pts,
            &truth,
            &mut |m, b, e| panic!("{m} {b}: {e}"),
            &|_, _, _| {},
        );
        let plain = rows.iter().find(|r| r.method == "grid" && r.budget == 32);
        assert_eq!(plain.map(|r| r.probes), Some(grid[0].probes));
        assert_ne!(plain.map(|r| r.metrics), Some(grid[0].metrics));
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("sweep.png");
        plot_sweep(&png, "sweep", &rows).unwrap();
        let bytes = std::fs::read(&png).unwrap();
        assert!(bytes.len() > 1000);
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    }
}
