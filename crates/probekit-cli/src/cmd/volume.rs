//! `probekit volume SCENE -o OUT.probes (--uniform (--cell SIZE | --resolution X,Y,Z)
//! | --adaptive --min-depth A --max-depth B [--roots X,Y,Z] [--tolerance T]
//! [--noise-k K] [--geometry-depth G] [--balance]) [--gradients central|analytic]
//! [--box MINX,MINY,MINZ,MAXX,MAXY,MAXZ] [--order N] [--samples N] [--bounces B]
//! [--seed S] [--plot FILE.png] [--json]`.
//!
//! Bakes an irradiance volume (seed 001) through `probekit::volume`. SCENE
//! is any scene the loader accepts (`builtin:demo`, `.toml`, `.gltf`/`.glb`,
//! `.obj`), captured by the path tracer (`probekit::volume::BakerSource`,
//! the same capture, validity and virtual offset as `bake`), or
//! `builtin:lights-demo` (analytic sphere lights behind a slab, with
//! closed-form gradients).

use super::bake::capture_settings;
use super::util::load_scene;
use anyhow::{bail, Context, Result};
use clap::Args;
use glam::Vec3;
use probekit::format::settings::settings_json;
use probekit::format::{write_probe_file, BakeMetadata, Placement};
use probekit::volume::{
    build_adaptive, build_uniform, inspect_json, plot_depths, resolution_for_cell,
    truncate_gradients, AdaptiveSettings, BakerSource, CommonSettings, GradientMode, LightsDemo,
    VolumeSource,
};
use std::path::PathBuf;

/// The options that only the adaptive octree reads (clap ids: the field
/// names), refused with `--uniform`.
const ADAPTIVE_ONLY: [&str; 13] = [
    "min_depth",
    "max_depth",
    "roots",
    "tolerance",
    "prune",
    "relative_floor",
    "geometry",
    "geometry_depth",
    "emitter_depth",
    "noise_k",
    "balance",
    "depth_factor",
    "gradient_threshold",
];

/// Arguments of `probekit volume`.
#[derive(Debug, Args)]
pub struct VolumeArgs {
    /// Scene file (`.toml`, `.gltf`, `.glb`, `.obj`), `builtin:demo`, or
    /// `builtin:lights-demo` (analytic sphere lights, closed-form gradients).
    pub scene: String,
    /// Output `.probes` file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Uniform grid, probes at cell corners. The adaptive octree's options
    /// are refused with it rather than ignored.
    #[arg(long, conflicts_with = "adaptive", conflicts_with_all = ADAPTIVE_ONLY)]
    pub uniform: bool,
    /// Cell size in metres (uniform).
    #[arg(long, conflicts_with = "resolution")]
    pub cell: Option<f32>,
    /// Probes per axis `X,Y,Z` (uniform).
    #[arg(long, value_delimiter = ',')]
    pub resolution: Option<Vec<u32>>,
    /// Adaptive octree. `--cell` and `--resolution` (the uniform grid's)
    /// are refused with it rather than ignored.
    #[arg(long, conflicts_with_all = ["cell", "resolution"])]
    pub adaptive: bool,
    /// Cells shallower than this always subdivide (adaptive).
    #[arg(long, default_value_t = 1)]
    pub min_depth: u32,
    /// Deepest level below the root cells (adaptive, ≤ 20). Root cells are
    /// near-cubic (an 8 × 3 × 4 m room gets 1.5 m roots), so the default 4
    /// gives finest cells of about 0.1 m there, where a light needs them.
    #[arg(long, default_value_t = 4)]
    pub max_depth: u32,
    /// Root cells per axis `X,Y,Z` (adaptive): the box is cut into this
    /// grid and each root cell is an octree; depths count from the root
    /// cells. Default: the coarsest near-cubic grid (`1,1,1` = one octree
    /// over the whole box, the seed's layout, whose cells copy the box's
    /// aspect ratio).
    #[arg(long, value_delimiter = ',')]
    pub roots: Option<Vec<u32>>,
    /// Relative trilinear-prediction tolerance for subdivision (adaptive;
    /// see BENCHMARKS.md for the error / memory trade-off of 0.25–1.5).
    #[arg(long, default_value_t = 1.0)]
    pub tolerance: f32,
    /// Relative tolerance under which children are pruned (adaptive).
    #[arg(long, default_value_t = 0.1)]
    pub prune: f32,
    /// Tolerances are relative to max(local DC, this × the mean DC of the
    /// min-depth samples), so dark corners are not over-refined (adaptive;
    /// 0 = purely local). The default 4 makes the tolerance nearly absolute,
    /// which is what `eval`'s rel_rmse rewards (memory goes to bright,
    /// fast-changing light); 0.5 spends memory on dark corners too, for a
    /// p95 relative error like a uniform grid's at about twice the memory
    /// (BENCHMARKS.md, "five seeds").
    #[arg(long, default_value_t = 4.0)]
    pub relative_floor: f32,
    /// Subdivide cells that intersect scene geometry (adaptive; `false` to disable).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub geometry: bool,
    /// Geometry alone splits cells only above this depth; deeper cells
    /// touching geometry split only on a significant prediction miss
    /// (adaptive; `--geometry-depth` = `--max-depth` is the seed's rule,
    /// which spends most samples on walls).
    #[arg(long, default_value_t = 2)]
    pub geometry_depth: u32,
    /// Cells that contain part of an emitter (emissive triangle, or a
    /// positional light's ball) split down to this depth and are not pruned
    /// (adaptive; default `--max-depth`; 0 = off): the near field of an area
    /// light changes within centimetres. It may exceed `--max-depth`: only
    /// emitter cells go deeper (`--emitter-depth 5` at the default depth 4
    /// is the Cornell box's recipe, BENCHMARKS.md).
    #[arg(long)]
    pub emitter_depth: Option<u32>,
    /// A prediction miss counts only by what it exceeds this many standard
    /// errors of the capture noise (batch means over 256-sample chunks;
    /// adaptive; 0 = raw misses, the old criterion).
    #[arg(long, default_value_t = 2.0)]
    pub noise_k: f32,
    /// 2:1-balance the octree (leaves sharing a point differ by at most one
    /// level) so coarse leaves do not blend into much finer ones (adaptive;
    /// on by default, `--balance false` to turn off).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set,
          num_args = 0..=1, default_missing_value = "true")]
    pub balance: bool,
    /// Subdivide when the cell's edge exceeds this × the harmonic mean of
    /// scene depth at its corners (adaptive; 0, the default, disables: at 1
    /// it refines nearly every cell of an interior, see BENCHMARKS).
    #[arg(long, default_value_t = 0.0)]
    pub depth_factor: f32,
    /// Subdivide when the relative SH change along a cell edge exceeds this
    /// (adaptive; off by default).
    #[arg(long)]
    pub gradient_threshold: Option<f32>,
    /// Store SH gradients: `central` (6 extra captures per sample, any
    /// scene) or `analytic` (closed form; only `builtin:lights-demo`).
    #[arg(long)]
    pub gradients: Option<String>,
    /// Offset of the central differences, metres (`--gradients central`;
    /// default half the finest cell edge: noise against truncation, see
    /// BENCHMARKS.md "Gradient step").
    #[arg(long)]
    pub gradient_step: Option<f32>,
    /// Store the gradients of the first N bands only (default: all of
    /// `--order`); the others are interpolated trilinearly. 1 = the DC term's
    /// gradient, 3 RGB vectors per sample instead of 27 for L2.
    #[arg(long)]
    pub gradient_order: Option<u32>,
    /// Box `MINX,MINY,MINZ,MAXX,MAXY,MAXZ` (metres); default the scene's `[bake] box`.
    #[arg(long = "box", value_delimiter = ',', allow_hyphen_values = true)]
    pub bbox: Option<Vec<f32>>,
    /// SH bands (1..=8).
    #[arg(long, default_value_t = 3)]
    pub order: usize,
    /// Receiver directions per sample (path-traced scenes; default the
    /// scene's `[bake] samples`, else 1024).
    #[arg(long)]
    pub samples: Option<u32>,
    /// Scattering events per path (path-traced scenes).
    #[arg(long)]
    pub bounces: Option<u32>,
    /// Random seed (path-traced scenes).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Write a PNG of leaves and samples per octree depth (log scale) — where
    /// the adaptive octree spent its samples; a uniform grid is one depth.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Print `inspect --json`-style statistics (plus `captures`, `dilated`).
    #[arg(long)]
    pub json: bool,
}

fn parse_box(a: &VolumeArgs, default: (Vec3, Vec3)) -> Result<(Vec3, Vec3)> {
    match &a.bbox {
        None => Ok(default),
        Some(b) if b.len() == 6 => Ok((Vec3::new(b[0], b[1], b[2]), Vec3::new(b[3], b[4], b[5]))),
        Some(_) => bail!(
            "{}: --box needs 6 numbers MINX,MINY,MINZ,MAXX,MAXY,MAXZ",
            a.scene
        ),
    }
}

fn resolution(a: &VolumeArgs, min: Vec3, max: Vec3) -> Result<[u32; 3]> {
    Ok(match (&a.resolution, a.cell) {
        (Some(r), _) if r.len() == 3 => [r[0], r[1], r[2]],
        (Some(_), _) => bail!("{}: --resolution needs 3 numbers X,Y,Z", a.scene),
        (None, Some(c)) => resolution_for_cell(min, max, c).with_context(|| a.scene.clone())?,
        (None, None) => bail!("{}: --uniform needs --cell or --resolution", a.scene),
    })
}

/// The gradient mode of `--gradients`, `--gradient-step` and
/// `--gradient-order`, checked before any scene is loaded.
fn gradient_mode(a: &VolumeArgs) -> Result<GradientMode> {
    if a.gradient_step.is_some() && a.gradients.as_deref() != Some("central") {
        bail!("{}: --gradient-step needs --gradients central", a.scene);
    }
    if a.gradient_order.is_some() && a.gradients.is_none() {
        bail!("{}: --gradient-order needs --gradients", a.scene);
    }
    if a.gradient_order
        .is_some_and(|g| g == 0 || g as usize > a.order)
    {
        bail!(
            "{}: --gradient-order must be in 1..=--order ({})",
            a.scene,
            a.order
        );
    }
    Ok(match a.gradients.as_deref() {
        None => GradientMode::None,
        Some("central") => match a.gradient_step {
            Some(h) if !(h.is_finite() && h > 0.0) => {
                bail!(
                    "{}: --gradient-step {h}: need a positive length in metres",
                    a.scene
                )
            }
            h => GradientMode::Central {
                step: h.unwrap_or(0.0),
            },
        },
        Some("analytic") => GradientMode::Analytic,
        Some(o) => bail!("{}: --gradients {o}: expected central or analytic", a.scene),
    })
}

/// Runs `probekit volume`.
pub fn run(a: &VolumeArgs) -> Result<()> {
    super::util::check_outputs(&[Some(&a.output), a.plot.as_deref()])?;
    if !(1..=probekit::sh::MAX_ORDER).contains(&a.order) {
        bail!(
            "{}: --order must be in 1..={}",
            a.scene,
            probekit::sh::MAX_ORDER
        );
    }
    if !a.uniform && !a.adaptive {
        bail!(
            "{}: choose a volume: --adaptive (an octree), or --uniform with --cell SIZE or \
             --resolution X,Y,Z",
            a.scene
        );
    }
    let gradients = gradient_mode(a)?;
    if a.scene == "builtin:lights-demo" {
        let src = LightsDemo::demo(a.order);
        let (min, max) = parse_box(a, LightsDemo::demo_box())?;
        return build_and_write(a, &src, gradients, min, max, 0.5, None, None);
    }
    if a.gradients.as_deref() == Some("analytic") {
        bail!(
            "{}: --gradients analytic needs a source with closed-form lights \
             (builtin:lights-demo); path-traced scenes use --gradients central",
            a.scene
        );
    }
    let scene = load_scene(&a.scene)?;
    let mut settings = capture_settings(&scene, a.samples, a.bounces, a.seed);
    settings.order = a.order;
    let settings_for_meta = settings.clone();
    let bb = scene.bake_box();
    let (min, max) = parse_box(a, (bb.min, bb.max))?;
    // Before any work: a box that can hold a volume (a scene without
    // geometry needs `--box` or a `[bake] box`).
    probekit::scene::Aabb { min, max }
        .check_bake_box()
        .with_context(|| a.scene.clone())?;
    let pb = std::sync::Arc::new(crate::progress::Progress::new());
    let bar = pb.clone();
    let src = BakerSource::new(&scene, settings)
        .with_context(|| a.scene.clone())?
        .with_progress(Box::new(move |done, requested| {
            bar.update("capture", done, requested)
        }));
    // A virtual offset longer than a quarter of the finest cell moves a
    // corner sample out of its cell (typically through a wall): dilate it.
    let size = max - min;
    let finest = if a.adaptive {
        let deepest = a.max_depth.max(a.emitter_depth.unwrap_or(0)).min(20);
        (size / (1u64 << deepest) as f32).min_element()
    } else {
        let r = resolution(a, min, max)?;
        (size / (Vec3::new(r[0] as f32, r[1] as f32, r[2] as f32) - 1.0).max(Vec3::ONE))
            .min_element()
    };
    let src = src.with_max_offset(0.25 * finest);
    let thr = src.validity_threshold();
    let meta = BakeMetadata::new(
        String::new(),
        Placement {
            method: if a.adaptive { "octree" } else { "uniform" }.into(),
            parameters: serde_json::Value::Null,
        },
        settings_json(&settings_for_meta, probekit::format::Codec::F32),
    )
    .with_scene(&a.scene, &scene);
    let r = build_and_write(a, &src, gradients, min, max, thr, Some(&pb), Some(meta));
    if let Some(e) = src.take_error() {
        bail!("{}: capture failed: {e}", a.scene);
    }
    r
}

#[allow(clippy::too_many_arguments)] // rewritten with the pipeline
fn build_and_write(
    a: &VolumeArgs,
    src: &dyn VolumeSource,
    gradients: GradientMode,
    min: Vec3,
    max: Vec3,
    validity_threshold: f32,
    pb: Option<&crate::progress::Progress>,
    meta: Option<BakeMetadata>,
) -> Result<()> {
    let common = CommonSettings {
        min,
        max,
        gradients,
        validity_threshold,
    };
    let built = if a.adaptive {
        build_adaptive(
            src,
            &AdaptiveSettings {
                common,
                min_depth: a.min_depth,
                max_depth: a.max_depth,
                geometry: a.geometry,
                depth_factor: (a.depth_factor > 0.0).then_some(a.depth_factor),
                gradient_threshold: a.gradient_threshold,
                prediction_tolerance: Some(a.tolerance),
                prune_tolerance: Some(a.prune),
                relative_floor: a.relative_floor,
                geometry_depth: a.geometry_depth,
                emitter_depth: a.emitter_depth.unwrap_or(a.max_depth),
                noise_k: a.noise_k,
                balance: a.balance,
                roots: match a.roots.as_deref() {
                    None => None,
                    Some(&[x, y, z]) => Some([x, y, z]),
                    Some(_) => bail!("{}: --roots needs X,Y,Z", a.scene),
                },
            },
        )
    } else if a.uniform {
        build_uniform(src, &common, resolution(a, min, max)?)
    } else {
        bail!("{}: choose --uniform or --adaptive", a.scene)
    };
    if let Some(pb) = pb {
        pb.finish();
    }
    let (mut file, stats) = built.with_context(|| a.scene.clone())?;
    if let Some(g) = a.gradient_order {
        truncate_gradients(&mut file, g).with_context(|| a.scene.clone())?;
    }
    if let Some(m) = meta {
        file.metadata = m.to_json();
    }
    write_probe_file(&a.output, &file).with_context(|| a.output.display().to_string())?;
    if let Some(p) = &a.plot {
        let title = format!("{}: leaves and samples per depth", a.scene);
        plot_depths(&file, p, &title)?;
    }
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
