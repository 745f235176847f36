//! # Placement comparisons and budget sweeps (`probekit eval --compare`, `--plot`)
//!
//! Each measured configuration goes the way a user's file goes: place probes
//! ([`place`]), bake the placed positions with the full capture settings
//! (fresh captures, probe indices from 0, as `probekit bake` does), build the
//! cloud file in memory ([`cloud_file`]) and evaluate it through the same
//! [`Predictor`] as `probekit eval` on the same points and ground truth
//! ([`metrics`]).
//!
//! A sweep maps a probe budget `B` to each method's own knob
//! ([`method_for_budget`]) and reports the probe count each actually
//! produced: `grid` ≈ `B` cells (minus those inside geometry), `adaptive`
//! budget `B`, `spawn-merge` an initial grid of `B/2` growing to at most `B`,
//! `gradient-ascent` an initial grid of `B` (merging, dark clustering and
//! leak prevention change the count).
//!
//! Every swept cloud gets the visibility data the caller asks for
//! ([`VisibilityBake`]; `probekit eval --plot` passes what the evaluated
//! file has) and its predictor the caller's query settings, so the curves
//! blend as the evaluated file does.

use super::{mean_luminance, metrics, Metrics};
use crate::blend::visibility_bake::{VisibilityBake, VisibilityBakeError};
use crate::capture::{BakeError, Baker, CaptureSettings};
use crate::format::cloud::{cloud_file, file_validity, CloudFileError};
use crate::format::settings::settings_json;
use crate::format::{BakeMetadata, Codec, Placement as PlacementMeta, ProbeFile};
use crate::placement::gradient_ascent::GradientAscentParams;
use crate::placement::spawn_merge::SpawnMergeParams;
use crate::placement::{place, LightShells, PlacementError, PlacementMethod};
use crate::plot::{line_chart_log, PlotError};
use crate::progress::Progress;
use crate::query::{PredictError, Predictor};
use crate::scene::Aabb;
use crate::trace::free_space::EvalPoint;
use glam::Vec3;
use probekit_runtime::Interp;
use std::path::Path;
use thiserror::Error;

/// The methods a sweep runs, in plot order.
pub const SWEEP_METHODS: [&str; 4] = ["grid", "adaptive", "spawn-merge", "gradient-ascent"];

/// Why one placement + bake + evaluation failed.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SweepError {
    /// An unknown method name.
    #[error(
        "unknown placement method `{0}` (expected grid, adaptive, spawn-merge or gradient-ascent)"
    )]
    UnknownMethod(String),
    /// Placement failed.
    #[error(transparent)]
    Placement(#[from] PlacementError),
    /// Capturing the placed probes failed.
    #[error(transparent)]
    Bake(#[from] BakeError),
    /// The cloud file could not be built.
    #[error(transparent)]
    Cloud(#[from] CloudFileError),
    /// The cloud's visibility data could not be baked.
    #[error(transparent)]
    Visibility(#[from] VisibilityBakeError),
    /// The cloud could not be evaluated.
    #[error(transparent)]
    Predict(#[from] PredictError),
}

/// The placement method `name` configured for about `budget` probes (see the
/// module docs).
pub fn method_for_budget(name: &str, budget: usize) -> Result<PlacementMethod, SweepError> {
    Ok(match name {
        "grid" => PlacementMethod::Grid {
            cell: None,
            budget: Some(budget),
        },
        "adaptive" => PlacementMethod::Adaptive {
            budget,
            tolerance: 0.0,
            light_shells: LightShells::default(),
        },
        "spawn-merge" => PlacementMethod::SpawnMerge(SpawnMergeParams {
            initial: (budget / 2).max(8),
            max_probes: budget.max(8),
            ..Default::default()
        }),
        "gradient-ascent" => PlacementMethod::GradientAscent(GradientAscentParams {
            initial: budget.max(8),
            ..Default::default()
        }),
        o => return Err(SweepError::UnknownMethod(o.into())),
    })
}

/// Places probes with `method` in `bake_box`, bakes them with `settings`
/// and returns the cloud file (coefficients in `codec`; placement metadata
/// names the method). `progress` hears placement's phases, then
/// `"capture"` per probe.
pub fn place_and_bake(
    baker: &Baker,
    bake_box: Aabb,
    method: &PlacementMethod,
    settings: &CaptureSettings,
    codec: Codec,
    progress: Progress<'_>,
) -> Result<ProbeFile, SweepError> {
    let placed = place(baker, bake_box, method, settings, progress)?;
    bake_cloud(
        baker,
        &placed.positions,
        settings,
        codec,
        method.name(),
        &|done, total| progress("capture", done, total),
    )
}

/// Bakes what `visibility` selects into `file` ([`VisibilityBake::bake_into`],
/// then [`VisibilityBake::fit_weights_into`]), telling `progress` the
/// phases `"visibility"`, `"cell visibility"` and `"probe weights"`.
pub fn bake_blend_data(
    baker: &Baker,
    visibility: &VisibilityBake,
    settings: &CaptureSettings,
    file: &mut ProbeFile,
    progress: Progress<'_>,
) -> Result<(), VisibilityBakeError> {
    visibility.bake_into(
        baker.tracer(),
        file,
        &|d, t| progress("visibility", d, t),
        &|d, t| progress("cell visibility", d, t),
    )?;
    visibility.fit_weights_into(baker, settings, file, &|d, t| {
        progress("probe weights", d, t)
    })
}

/// Bakes `positions` with `settings` (probe indices from 0) into an
/// in-memory cloud file, as `probekit bake` would write it;
/// `progress(done, total)` after each probe.
pub fn bake_cloud(
    baker: &Baker,
    positions: &[Vec3],
    settings: &CaptureSettings,
    codec: Codec,
    method: &str,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<ProbeFile, SweepError> {
    let res = baker.capture_many(positions, 0, settings, progress)?;
    let pos: Vec<Vec3> = res.iter().map(|r| r.position).collect();
    let sh: Vec<_> = res
        .iter()
        .map(|r| match (&r.indirect, settings.split_direct) {
            (Some(i), true) => i.clone(),
            _ => r.sh.clone(),
        })
        .collect();
    let validity: Vec<_> = res.iter().map(|r| file_validity(&r.validity)).collect();
    let meta = BakeMetadata::new(
        format!("{:016x}", baker.scene().lighting_hash()),
        PlacementMeta {
            method: method.into(),
            parameters: serde_json::json!({ "count": pos.len() }),
        },
        settings_json(settings, codec),
    );
    Ok(cloud_file(&pos, &sh, &validity, codec, &meta)?)
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

/// Runs every method of `methods` at every budget of `budgets`: place, bake
/// with `settings` (f32 coefficients), bake `visibility` into the cloud,
/// `configure` its predictor (query-time settings), evaluate on `points`
/// against `truth`. A configuration that fails is reported to
/// `on_error(method, budget, error)` and left out; the rest go on. Rows are
/// in method-then-budget order.
#[allow(clippy::too_many_arguments)]
pub fn sweep(
    baker: &Baker,
    bake_box: Aabb,
    methods: &[&str],
    budgets: &[usize],
    settings: &CaptureSettings,
    visibility: &VisibilityBake,
    configure: &dyn Fn(&mut Predictor),
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
            let r = method_for_budget(m, b)
                .and_then(|method| {
                    place_and_bake(baker, bake_box, &method, settings, Codec::F32, &step)
                })
                .and_then(|mut file| {
                    bake_blend_data(baker, visibility, settings, &mut file, &step)?;
                    let mut p = Predictor::from_file(&file, Interp::Trilinear)?;
                    configure(&mut p);
                    let pred = p.predict(points)?;
                    Ok((file.positions.len(), metrics(&pred, truth, mean)))
                });
            match r {
                Ok((probes, metrics)) => rows.push(SweepRow {
                    method: m.into(),
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
    use super::super::reference;
    use super::*;
    use crate::capture::ReferenceSettings;
    use crate::placement::grid_points;
    use crate::scene::demo::box_triangles;
    use crate::scene::{Light, LightKind, Material, Scene};
    use crate::trace::free_space::inside_geometry;
    use crate::trace::free_space::sample_points;

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
        assert!(method_for_budget("nope", 10).is_err());
    }

    #[test]
    fn sweep_draws_a_png_and_reports_consistent_rows() {
        let scene = scene();
        let baker = Baker::new(&scene).unwrap();
        let s = CaptureSettings {
            samples: 16,
            bounces: 1,
            order: 3,
            ..Default::default()
        };
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
            &baker,
            scene.bake_box(),
            &SWEEP_METHODS,
            &budgets,
            &s,
            &VisibilityBake::none(),
            &|_| {},
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
        assert!(rows.iter().any(|r| r.method == "grid"));
        assert!(
            rows.iter().any(|r| r.method == "spawn-merge"),
            "{failures:?}"
        );
        assert!(
            rows.iter().any(|r| r.method == "gradient-ascent"),
            "{failures:?}"
        );
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
        // With visibility data and a query setting: the grid row is what
        // the same file gives when baked and queried that way by hand, and
        // differs from the plain row.
        let vis = VisibilityBake {
            moments: Some(crate::blend::visibility::VisibilitySettings {
                resolution: 4,
                ..crate::blend::visibility::VisibilitySettings::new(10.0, 1)
            }),
            cell_subdivision: Some(crate::blend::cell_visibility::CellLattice::Fixed(2)),
            cell_planes: true,
            probe_weights: Some(crate::blend::blend_fit::BlendFitSettings {
                points_per_probe: 2,
                samples: 8,
                ..crate::blend::blend_fit::BlendFitSettings::new(3)
            }),
        };
        let configure = |p: &mut Predictor| {
            if let Predictor::Cloud(c) = p {
                c.set_visibility_bias(0.1);
            }
        };
        let grid = sweep(
            &baker,
            scene.bake_box(),
            &["grid"],
            &[32],
            &s,
            &vis,
            &configure,
            &pts,
            &truth,
            &mut |m, b, e| panic!("{m} {b}: {e}"),
            &|_, _, _| {},
        );
        let method = method_for_budget("grid", 32).unwrap();
        let mut f = place_and_bake(
            &baker,
            scene.bake_box(),
            &method,
            &s,
            Codec::F32,
            &|_, _, _| {},
        )
        .unwrap();
        assert!(f.visibility.is_none() && f.cell_visibility.is_none());
        vis.bake_into(baker.tracer(), &mut f, &|_, _| {}, &|_, _| {})
            .unwrap();
        vis.fit_weights_into(&baker, &s, &mut f, &|_, _| {})
            .unwrap();
        assert!(f.probe_weights.is_some());
        let mut p = Predictor::from_file(&f, Interp::Trilinear).unwrap();
        configure(&mut p);
        let by_hand = metrics(&p.predict(&pts).unwrap(), &truth, mean_luminance(&truth));
        assert_eq!(grid[0].metrics, by_hand);
        let plain = rows.iter().find(|r| r.method == "grid" && r.budget == 32);
        assert_ne!(plain.map(|r| r.metrics), Some(by_hand));
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("sweep.png");
        plot_sweep(&png, "sweep", &rows).unwrap();
        let bytes = std::fs::read(&png).unwrap();
        assert!(bytes.len() > 1000);
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    }
}
