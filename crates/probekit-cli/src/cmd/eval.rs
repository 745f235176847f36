//! `probekit eval PROBES --scene SCENE [--points N] [--seed S] [--json]`:
//! error of a probe cloud against path-traced ground truth at random
//! free-space points of the bake box (`probekit::eval`).
//! Works on clouds and volumes alike (the runtime's `Probes`).
//!
//! `--compare grid` also bakes (in-process, with the capture settings the
//! file's metadata records) a uniform grid with the file's probe count over
//! the scene's bake box and reports its figures under `"compare":{"grid":..}`
//! (with the distance moments and cell visibility the file has, baked for
//! the grid with the same settings, and the same query-time flags);
//! `--plot FILE.png [--budgets 50,100,200,400]` runs a placement sweep
//! (`probekit::pipeline::sweep`) on the same points and ground truth (every
//! swept cloud with the file's kinds of visibility data and the same
//! query-time flags), draws rel. RMSE against probe count (log-log) and
//! reports it under `"sweep"`. `--worst K` lists the K points that carry the
//! most squared error, worst first, with their shares of it (under
//! `"worst"`, for the grid too).

use super::util::{load_probes, scene_for_file};
use anyhow::{bail, Context, Result};
use clap::Args;
use glam::Vec3;
use probekit::capture::{Baker, ReferenceSettings};
use probekit::eval::{evaluate, predict, reference_with_progress};
use probekit::pipeline::sweep::{plot_sweep, sweep, without_overridden_blend_data, SWEEP_METHODS};
use probekit::pipeline::Bake;
use probekit::recipe::{BakeRecord, Placement};
use probekit::scene::Aabb;
use probekit::trace::free_space::sample_points;
use probekit_runtime::{LoadOptions, Probes};
use std::path::PathBuf;

/// Arguments of `probekit eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// A cloud or volume `.probes` file.
    pub probes: PathBuf,
    /// Scene file or `builtin:NAME` (default: the scene the file was baked
    /// from, as it records it).
    #[arg(long)]
    pub scene: Option<String>,
    /// Evaluate against a scene whose lighting differs from the scene the
    /// file was baked from (refused otherwise: the figures would measure
    /// the probes against another scene's light).
    #[arg(long)]
    pub allow_other_scene: bool,
    /// Evaluation points.
    #[arg(long, default_value_t = 2000)]
    pub points: usize,
    /// Seed of the evaluation points.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Box `MINX,MINY,MINZ,MAXX,MAXY,MAXZ` (metres) to sample points in;
    /// default the scene's `[bake] box`.
    #[arg(long = "box", value_delimiter = ',', allow_hyphen_values = true)]
    pub bbox: Option<Vec<f32>>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Volumes: interpolation; clouds: blend overrides for diagnosis.
    #[command(flatten)]
    pub load: super::load_args::LoadArgs,
    /// Also evaluate a uniform `grid` with the same probe count.
    #[arg(long)]
    pub compare: Option<String>,
    /// Run a placement sweep over `--budgets` and draw it to this PNG.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Probe budgets of the sweep (default 50,100,200,400; `--plot` only).
    #[arg(long, value_delimiter = ',')]
    pub budgets: Option<Vec<usize>>,
    /// Methods of the sweep (default grid, adaptive, spawn-merge,
    /// gradient-ascent; `--plot` only).
    #[arg(long, value_delimiter = ',')]
    pub methods: Option<Vec<String>>,
    /// Receiver samples per probe for the `--compare`/`--plot` bakes
    /// (default: as the file's metadata records).
    #[arg(long)]
    pub samples: Option<u32>,
    /// Also list the K points with the largest squared error, worst first,
    /// under `"worst"`: position, normal, true and predicted irradiance, the
    /// share of the summed squared error (of `rel_rmse²`) each carries, and
    /// the regions that hold it. A few points next to a small bright light
    /// can carry most of `rel_rmse`.
    #[arg(long, default_value_t = 0)]
    pub worst: usize,
}

/// The sweep's budgets when `--plot` is given without `--budgets`.
const DEFAULT_BUDGETS: [usize; 4] = [50, 100, 200, 400];

/// Refuses flags that would be ignored: the sweep's `--budgets` and
/// `--methods` without `--plot`, `--samples` with neither `--compare` nor
/// `--plot` (it sets their bakes' samples), no evaluation points, and a
/// `--compare` other than `grid` (before the ground truth is traced).
fn check_flags(a: &EvalArgs) -> Result<()> {
    if a.plot.is_none() {
        if a.budgets.is_some() {
            bail!("--budgets sets the sweep of --plot FILE.png; give --plot too");
        }
        if a.methods.is_some() {
            bail!("--methods sets the sweep of --plot FILE.png; give --plot too");
        }
    }
    if a.samples.is_some() && a.plot.is_none() && a.compare.is_none() {
        bail!("--samples sets the bakes of --compare and --plot; give one of them too");
    }
    if a.points == 0 {
        bail!("--points 0: expected at least one evaluation point");
    }
    if let Some(o) = a.compare.as_deref().filter(|&o| o != "grid") {
        bail!("--compare {o}: expected grid");
    }
    Ok(())
}

/// Runs `probekit eval`.
pub fn run(a: &EvalArgs) -> Result<()> {
    let name = a.probes.display().to_string();
    let file = load_probes(&a.probes)?;
    check_flags(a)?;
    super::util::check_outputs(&[a.plot.as_deref()])?;
    let options = a.load.options(&[])?;
    let probes = options.load(&file).with_context(|| name.clone())?;
    // The clouds `--compare` and `--plot` bake, loaded with the evaluated
    // file's blend overrides (a volume has none).
    let mut cloud_options = LoadOptions::default();
    cloud_options.blend = options.blend;
    let (scene, scene_name) =
        scene_for_file(&file, &a.probes, a.scene.as_deref(), a.allow_other_scene)?;
    let baker = Baker::new(&scene).with_context(|| scene_name.clone())?;
    let bbox = match &a.bbox {
        None => scene.bake_box(),
        Some(b)
            if b.len() == 6
                && b.iter().all(|x| x.is_finite())
                && b[0] < b[3]
                && b[1] < b[4]
                && b[2] < b[5] =>
        {
            Aabb {
                min: Vec3::new(b[0], b[1], b[2]),
                max: Vec3::new(b[3], b[4], b[5]),
            }
        }
        Some(_) => bail!("--box: expected MINX,MINY,MINZ,MAXX,MAXY,MAXZ with min < max"),
    };
    bbox.check_bake_box().with_context(|| scene_name.clone())?;
    let pts = sample_points(baker.tracer(), &bbox, a.points, a.seed);
    if pts.is_empty() {
        bail!("{scene_name}: no free-space points in the box");
    }
    let rs = ReferenceSettings {
        relative_precision: 0.03,
        ..Default::default()
    };
    // One bar for the long phases: ground truth, the compared grid's bake,
    // the sweep's configurations (on stderr; cleared before the output).
    let bar = crate::progress::Progress::new();
    let progress = bar.callback();
    let truth = reference_with_progress(&baker, &pts, &rs, &|d, t| progress("ground truth", d, t))
        .with_context(|| scene_name.clone())?;
    let pred = predict(&probes, &pts).with_context(|| name.clone())?;
    let report = evaluate(
        &scene,
        &pts,
        &pred,
        &truth,
        baker.tracer(),
        a.worst,
        &probes,
    );
    let mut out = serde_json::to_value(report)?;
    // The recipe the file was baked with (the defaults for a file that
    // records none), with `--samples` for the bakes below.
    let mut recipe = BakeRecord::from_json(file.metadata())
        .map(|r| r.recipe)
        .unwrap_or_default();
    if let Some(n) = a.samples {
        recipe.capture.samples = n;
    }
    // `--compare grid` (the only comparison; checked by `check_flags`).
    if a.compare.is_some() {
        // The same recipe, placed on a grid of the file's probe count:
        // the grid gets the blend data the evaluated file has.
        recipe.placement = Placement::Grid {
            budget: Some(file.positions().len().max(8)),
            cell: None,
        };
        let ctx = || format!("{scene_name}: --compare grid");
        let step = |phase: &str, d, t| progress(&format!("grid: {phase}"), d, t);
        let g = Bake::new(&scene, &scene_name, &recipe)
            .and_then(|b| b.run(&step))
            .with_context(ctx)?
            .file;
        let grid = Probes::from_file(&g, cloud_options).with_context(ctx)?;
        let gp = predict(&grid, &pts).with_context(ctx)?;
        let gf = evaluate(&scene, &pts, &gp, &truth, baker.tracer(), a.worst, &grid);
        out["compare"] = serde_json::json!({ "grid": gf });
    }
    if let Some(plot) = &a.plot {
        let budgets = a.budgets.clone().unwrap_or(DEFAULT_BUDGETS.to_vec());
        if budgets.is_empty() || budgets.iter().any(|&b| b < 8) {
            bail!("--budgets: expected probe counts of at least 8");
        }
        let methods: Vec<&str> = match &a.methods {
            Some(m) => m.iter().map(String::as_str).collect(),
            None => SWEEP_METHODS.to_vec(),
        };
        // The swept clouds get the evaluated file's visibility data (less
        // what the overrides turn off) and its overrides, so the curves
        // blend as the file does.
        without_overridden_blend_data(&mut recipe, &options.blend);
        let rows = sweep(
            &scene,
            &scene_name,
            &recipe,
            &methods,
            &budgets,
            &cloud_options,
            &pts,
            &truth,
            &mut |m, b, e| eprintln!("{scene_name}: sweep: {m} at budget {b} failed, skipped: {e}"),
            &progress,
        );
        if rows.is_empty() {
            bail!("{scene_name}: every sweep configuration failed");
        }
        plot_sweep(plot, &format!("{scene_name}: error vs probes"), &rows)?;
        out["sweep"] = rows.iter().map(|r| r.to_json()).collect::<Vec<_>>().into();
        out["plot"] = plot.display().to_string().into();
    }
    bar.finish();
    if a.json {
        println!("{out}");
    } else {
        println!("{}", serde_json::to_string_pretty(&out)?);
    }
    Ok(())
}
