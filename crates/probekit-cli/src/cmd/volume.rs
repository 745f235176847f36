//! `probekit volume`: an irradiance volume (a uniform grid or an adaptive
//! octree, with gradients) baked by [`probekit::pipeline::bake_volume`].
//!
//! SCENE is any scene the loader accepts, captured by the path tracer, or
//! `builtin:lights-demo` (analytic sphere lights behind a slab, with
//! closed-form gradients). The settings are the recipe's `[volume]` and
//! `[capture]` sections, layered like `bake`'s.

use super::bake::value_name;
use super::recipe_args::{CaptureArgs, RecipeArgs};
use super::util::{check_outputs, load_scene};
use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use probekit::format::write_probe_file;
use probekit::pipeline::{bake_volume, bake_volume_from};
use probekit::progress::Clock;
use probekit::recipe::{BakeRecord, RecipeLayers};
use probekit::volume::{inspect_json, plot_depths, LightsDemo};
use std::path::PathBuf;
use toml::Value;

/// The analytic scene of closed-form sphere lights.
const LIGHTS_DEMO: &str = "builtin:lights-demo";

/// The layout of a volume on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum LayoutArg {
    /// Probes at the corners of a uniform grid (`--cell` or `--resolution`).
    Uniform,
    /// An adaptive octree, refined where interpolation mispredicts light.
    Octree,
}

/// How gradients are stored, on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum GradientsArg {
    /// No gradients (trilinear interpolation).
    None,
    /// Central differences of 6 extra captures per sample (any scene).
    Central,
    /// Closed form (only `builtin:lights-demo`).
    Analytic,
}

/// Arguments of `probekit volume`.
#[derive(Debug, Args)]
pub struct VolumeArgs {
    /// Scene file (`.toml`, `.gltf`, `.glb`, `.obj`), `builtin:demo`, or
    /// `builtin:lights-demo` (analytic sphere lights, closed-form gradients).
    pub scene: String,
    /// Output `.probes` file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Uniform grid or adaptive octree (default: octree; uniform when
    /// `--cell` or `--resolution` is given).
    #[arg(long, value_enum, help_heading = "Layout")]
    pub layout: Option<LayoutArg>,
    /// Cell edge of a uniform grid, metres.
    #[arg(long, conflicts_with = "resolution", help_heading = "Layout")]
    pub cell: Option<f32>,
    /// Probes per axis of a uniform grid, `X,Y,Z`.
    #[arg(long, value_delimiter = ',', help_heading = "Layout")]
    pub resolution: Option<Vec<u32>>,
    /// Deepest level of an octree below its root cells (default 4).
    #[arg(long, help_heading = "Layout")]
    pub max_depth: Option<u32>,
    /// Per-sample SH gradients, for Taylor or tricubic interpolation.
    #[arg(long, value_enum, help_heading = "Layout")]
    pub gradients: Option<GradientsArg>,
    /// Samples, order and seed.
    #[command(flatten)]
    pub capture: CaptureArgs,
    /// Recipe file, keys and printing.
    #[command(flatten)]
    pub recipe: RecipeArgs,
    /// Also write a PNG of leaves and samples per octree depth (where the
    /// octree spent its samples).
    #[arg(long, value_name = "FILE.png", help_heading = "Output")]
    pub plot: Option<PathBuf>,
    /// Print the statistics as JSON (`inspect --json`'s, plus `captures`,
    /// `dilated` and `phases`: wall and CPU seconds and rays traced per
    /// phase: load, build with its capture and refinement, assembly).
    #[arg(long, help_heading = "Output")]
    pub json: bool,
}

impl VolumeArgs {
    /// The recipe keys this command's options set.
    fn flag_layer(&self) -> Vec<(&'static str, Value)> {
        let int = |v: u64| Value::Integer(v as i64);
        let mut keys = Vec::new();
        let sized = self.cell.is_some() || self.resolution.is_some();
        match self.layout {
            Some(l) => keys.push(("volume.method", Value::String(value_name(&l)))),
            None if sized => keys.push(("volume.method", Value::String("uniform".into()))),
            None => {}
        }
        if let Some(c) = self.cell {
            keys.push(("volume.cell", Value::Float(c.into())));
        }
        if let Some(r) = &self.resolution {
            let r = r.iter().map(|&x| int(x.into())).collect();
            keys.push(("volume.resolution", Value::Array(r)));
        }
        if let Some(d) = self.max_depth {
            keys.push(("volume.max_depth", int(d.into())));
        }
        if let Some(g) = self.gradients {
            keys.push(("volume.gradients.mode", Value::String(value_name(&g))));
        }
        self.capture.push_keys(&mut keys);
        keys
    }
}

/// Runs `probekit volume`.
pub fn run(a: &VolumeArgs) -> Result<()> {
    if !a.recipe.print_recipe {
        check_outputs(&[Some(&a.output), a.plot.as_deref()])?;
    }
    let progress = crate::progress::Progress::new();
    let mut clock = Clock::new(0);
    let (file, mut report) = if a.scene == LIGHTS_DEMO {
        let mut layers = RecipeLayers::new();
        let (lo, hi) = LightsDemo::demo_box();
        let bx = Value::try_from([lo.to_array(), hi.to_array()])?;
        layers.push_value(LIGHTS_DEMO, "box", bx);
        let recipe = a.recipe.resolve_layers(layers, a.flag_layer())?;
        if a.recipe.print_recipe {
            print!("{}", recipe.to_toml());
            return Ok(());
        }
        let src = LightsDemo::demo(recipe.capture.order);
        let record = BakeRecord::without_scene(LIGHTS_DEMO, recipe.clone());
        bake_volume_from(&src, &recipe.recorded_box(), &recipe, 0.5, record)
    } else {
        let scene = load_scene(&a.scene)?;
        let recipe = a.recipe.resolve(&a.scene, &scene, a.flag_layer())?;
        if a.recipe.print_recipe {
            print!("{}", recipe.resolved_for(&scene).to_toml());
            return Ok(());
        }
        clock.lap("load", 0);
        bake_volume(&scene, &a.scene, &recipe, &progress.callback())
    }
    .with_context(|| a.scene.clone())?;
    progress.finish();
    // The scene's loading joins the bake's `load` phase (the tracer).
    if let (Some(l), Some(scene_load)) = (
        report.phases.iter_mut().find(|p| p.phase == "load"),
        clock.phases().first(),
    ) {
        l.add(scene_load);
    }
    let out = a.output.display().to_string();
    write_probe_file(&a.output, &file).with_context(|| out.clone())?;
    if let Some(p) = &a.plot {
        let title = format!("{}: leaves and samples per depth", a.scene);
        plot_depths(&file, p, &title)?;
    }
    if a.json {
        let mut j = inspect_json(&file).with_context(|| out.clone())?;
        j["captures"] = report.captures.into();
        j["dilated"] = report.dilated.into();
        j["phases"] = serde_json::to_value(&report.phases)?;
        println!("{j}");
    } else {
        println!(
            "{out}: {} samples, {} leaves, {} captures, {} dilated",
            report.samples, report.leaves, report.captures, report.dilated
        );
    }
    Ok(())
}
