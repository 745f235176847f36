//! `probekit volume SCENE -o OUT.probes (--uniform (--cell SIZE | --resolution X,Y,Z)
//! | --adaptive --min-depth A --max-depth B) [--gradients central|analytic]
//! [--box MINX,MINY,MINZ,MAXX,MAXY,MAXZ] [--order N] [--json]`.
//!
//! Bakes an irradiance volume (seed 001) through `probekit::volume`. Until the
//! scene loader and path-traced capture land, SCENE must be
//! `builtin:lights-demo` (analytic sphere lights behind a slab).

use anyhow::{bail, Context, Result};
use clap::Args;
use glam::Vec3;
use probekit::format::write_probe_file;
use probekit::volume::{
    build_adaptive, build_uniform, inspect_json, resolution_for_cell, AdaptiveSettings,
    CommonSettings, GradientMode, LightsDemo, VolumeSource,
};
use std::path::PathBuf;

/// Arguments of `probekit volume`.
#[derive(Debug, Args)]
pub struct VolumeArgs {
    /// Scene to bake; for now only `builtin:lights-demo`.
    pub scene: String,
    /// Output `.probes` file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Uniform grid, probes at cell corners.
    #[arg(long, conflicts_with = "adaptive")]
    pub uniform: bool,
    /// Cell size in metres (uniform).
    #[arg(long, conflicts_with = "resolution")]
    pub cell: Option<f32>,
    /// Probes per axis `X,Y,Z` (uniform).
    #[arg(long, value_delimiter = ',')]
    pub resolution: Option<Vec<u32>>,
    /// Adaptive octree.
    #[arg(long)]
    pub adaptive: bool,
    /// Cells shallower than this always subdivide (adaptive).
    #[arg(long, default_value_t = 1)]
    pub min_depth: u32,
    /// Deepest level (adaptive, ≤ 20).
    #[arg(long, default_value_t = 4)]
    pub max_depth: u32,
    /// Relative trilinear-prediction tolerance for subdivision (adaptive).
    #[arg(long, default_value_t = 0.25)]
    pub tolerance: f32,
    /// Relative tolerance under which children are pruned (adaptive).
    #[arg(long, default_value_t = 0.1)]
    pub prune: f32,
    /// Store SH gradients: `central` (6 extra captures) or `analytic`.
    #[arg(long)]
    pub gradients: Option<String>,
    /// Box `MINX,MINY,MINZ,MAXX,MAXY,MAXZ` (metres); default the scene's.
    #[arg(long = "box", value_delimiter = ',')]
    pub bbox: Option<Vec<f32>>,
    /// SH bands (1..=8).
    #[arg(long, default_value_t = 3)]
    pub order: usize,
    /// Print `inspect --json`-style statistics.
    #[arg(long)]
    pub json: bool,
}

/// Runs `probekit volume`.
pub fn run(a: &VolumeArgs) -> Result<()> {
    if a.scene != "builtin:lights-demo" {
        bail!(
            "{}: unknown scene (only builtin:lights-demo until the scene loader lands)",
            a.scene
        );
    }
    if !(1..=probekit::sh::MAX_ORDER).contains(&a.order) {
        bail!(
            "{}: --order must be in 1..={}",
            a.scene,
            probekit::sh::MAX_ORDER
        );
    }
    let src = LightsDemo::demo(a.order);
    let (mut min, mut max) = LightsDemo::demo_box();
    if let Some(b) = &a.bbox {
        if b.len() != 6 {
            bail!(
                "{}: --box needs 6 numbers MINX,MINY,MINZ,MAXX,MAXY,MAXZ",
                a.scene
            );
        }
        min = Vec3::new(b[0], b[1], b[2]);
        max = Vec3::new(b[3], b[4], b[5]);
    }
    let gradients = match a.gradients.as_deref() {
        None => GradientMode::None,
        Some("central") => GradientMode::Central { step: 0.0 },
        Some("analytic") => GradientMode::Analytic,
        Some(o) => bail!("{}: --gradients {o}: expected central or analytic", a.scene),
    };
    let common = CommonSettings {
        min,
        max,
        gradients,
        validity_threshold: 0.5,
    };
    let src: &dyn VolumeSource = &src;
    let (file, stats) = if a.adaptive {
        build_adaptive(
            src,
            &AdaptiveSettings {
                common,
                min_depth: a.min_depth,
                max_depth: a.max_depth,
                geometry: true,
                depth_factor: Some(1.0),
                gradient_threshold: None,
                prediction_tolerance: Some(a.tolerance),
                prune_tolerance: Some(a.prune),
            },
        )
    } else if a.uniform {
        let res = match (&a.resolution, a.cell) {
            (Some(r), _) if r.len() == 3 => [r[0], r[1], r[2]],
            (Some(_), _) => bail!("{}: --resolution needs 3 numbers X,Y,Z", a.scene),
            (None, Some(c)) => resolution_for_cell(min, max, c).with_context(|| a.scene.clone())?,
            (None, None) => bail!("{}: --uniform needs --cell or --resolution", a.scene),
        };
        build_uniform(src, &common, res)
    } else {
        bail!("{}: choose --uniform or --adaptive", a.scene)
    }
    .with_context(|| a.scene.clone())?;
    write_probe_file(&a.output, &file).with_context(|| a.output.display().to_string())?;
    if a.json {
        let mut j = inspect_json(&file).with_context(|| a.output.display().to_string())?;
        j["captures"] = stats.captures.into();
        j["dilated"] = stats.dilated.into();
        println!("{j}");
    } else {
        println!(
            "{}: {} samples, {} leaves, {} captures, {} dilated",
            a.output.display(),
            stats.samples,
            stats.leaves,
            stats.captures,
            stats.dilated
        );
    }
    Ok(())
}
