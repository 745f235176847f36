//! `probekit bake` and `probekit merge`: argument parsing, progress and
//! printing around [`probekit::pipeline`], which does the work.
//!
//! The bake's settings are a [`probekit::recipe::Recipe`], resolved from
//! layers: the defaults, the scene's `[bake]` table, `--recipe FILE`, this
//! command's options, then `--set KEY=VALUE`.

use super::recipe_args::{CaptureArgs, RecipeArgs};
use super::util::{check_outputs, load_probes, load_scene};
use anyhow::{anyhow, Context, Result};
use clap::{Args, ValueEnum};
use probekit::format::{write_probe_file, ProbeFile};
use probekit::pipeline::{Bake, Baked};
use probekit::progress::Clock;
use std::path::PathBuf;
use toml::Value;

/// A placement method on the command line (`manual` is `--positions`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PlacementArg {
    /// Error-driven refinement with leak and light-shell probes (the default).
    Adaptive,
    /// A uniform grid over the bake box.
    Grid,
    /// Spawn-and-merge placement (Sukys 2014).
    #[value(alias = "spawn-merge")]
    SpawnAndMerge,
    /// Gradient-ascent placement (Sukys 2014).
    GradientAscent,
}

/// A coefficient codec on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum CodecArg {
    /// 32-bit floats, lossless.
    F32,
    /// 16-bit floats.
    F16,
    /// Ratio-quantized L1, 13 bytes per probe.
    L1,
    /// Stored ZH3, 16 bytes per probe (decoded to L2).
    Zh3,
    /// Ratio-quantized L2, 28 bytes per probe.
    L2,
}

/// The name of a `ValueEnum` value, as typed.
pub fn value_name<T: ValueEnum>(v: &T) -> String {
    v.to_possible_value()
        .map(|p| p.get_name().to_string())
        .unwrap_or_default()
}

/// Arguments of `probekit bake`.
#[derive(Debug, Args)]
pub struct BakeArgs {
    /// Scene file (`.toml`, `.gltf`, `.glb`, `.obj`) or `builtin:demo`.
    #[arg(default_value = "builtin:demo")]
    pub scene: String,
    /// Output probe file (a part file with `--shard`); default: named after
    /// the scene in the current folder (`builtin:demo` → `demo.probes`).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Where the probes go.
    #[arg(long, value_enum, help_heading = "Placement")]
    pub placement: Option<PlacementArg>,
    /// Probe budget: the most probes of adaptive placement, the approximate
    /// count of a grid, the cap of spawn-and-merge, the initial grid of
    /// gradient ascent (default 256).
    #[arg(long, help_heading = "Placement")]
    pub budget: Option<usize>,
    /// Place probes at the positions of a CSV file (`x,y,z` per row, metres).
    #[arg(
        long,
        value_name = "FILE.csv",
        conflicts_with = "placement",
        help_heading = "Placement"
    )]
    pub positions: Option<PathBuf>,
    /// Samples, order and seed.
    #[command(flatten)]
    pub capture: CaptureArgs,
    /// Coefficient codec (default f32).
    #[arg(long, value_enum, help_heading = "Capture")]
    pub codec: Option<CodecArg>,
    /// Recipe file, keys and printing.
    #[command(flatten)]
    pub recipe: RecipeArgs,
    /// Bake only shard I of N (`I/N`, I from 0) into a part file for `merge`.
    #[arg(long, value_name = "I/N", help_heading = "Output")]
    pub shard: Option<String>,
    /// Also write a picture of the result (probes beside path-traced truth);
    /// the default demo bake writes `demo.png` beside `demo.probes`.
    #[arg(
        long,
        value_name = "FILE.png",
        conflicts_with = "shard",
        help_heading = "Output"
    )]
    pub render: Option<PathBuf>,
    /// Print the report as JSON, with `phases`: wall and CPU seconds and
    /// rays traced per phase (load, placement and its steps, capture,
    /// light split, assembly, distance moments, cell visibility, weight
    /// fit, picture), and `lights`: which lights run at run time.
    #[arg(long, help_heading = "Output")]
    pub json: bool,
}

impl BakeArgs {
    /// The recipe keys this command's options set.
    fn flag_layer(&self) -> Vec<(&'static str, Value)> {
        let int = |v: u64| Value::Integer(v as i64);
        let mut keys = Vec::new();
        if let Some(m) = self.placement {
            keys.push(("placement.method", Value::String(value_name(&m))));
        }
        if let Some(p) = &self.positions {
            keys.push(("placement.method", Value::String("manual".into())));
            let path = p.display().to_string();
            keys.push(("placement.positions", Value::String(path)));
        }
        if let Some(b) = self.budget {
            keys.push(("placement.budget", int(b as u64)));
        }
        self.capture.push_keys(&mut keys);
        if let Some(c) = self.codec {
            keys.push(("codec", Value::String(value_name(&c))));
        }
        keys
    }
}

/// Arguments of `probekit merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Part files written by `bake --shard I/N`.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// Output probe file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// The scene the parts were baked from (file or `builtin:NAME`; default:
    /// the scene the parts recorded): needed for cell visibility and probe
    /// weights, which depend on all probes and are baked here.
    #[arg(long)]
    pub scene: Option<String>,
}

/// Parses `I/N`.
fn parse_shard(s: &str) -> Result<(usize, usize)> {
    let bad = || anyhow!("--shard {s}: expected I/N with 0 ≤ I < N");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (i, n): (usize, usize) = (
        i.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if n == 0 || i >= n {
        return Err(bad());
    }
    Ok((i, n))
}

/// Runs `probekit bake`.
pub fn run(a: &BakeArgs) -> Result<()> {
    let shard = a.shard.as_deref().map(parse_shard).transpose()?;
    let output = a
        .output
        .clone()
        .unwrap_or_else(|| super::util::output_named_after(&a.scene, "probes"));
    if !a.recipe.print_recipe {
        check_outputs(&[Some(&output), a.render.as_deref()])?;
    }
    let progress = crate::progress::Progress::new();
    // The scene's loading joins the bake's `load` phase (no progress line:
    // an error in the recipe must stay the only line on stderr).
    let mut clock = Clock::new(0);
    let scene = load_scene(&a.scene)?;
    let recipe = a.recipe.resolve(&a.scene, &scene, a.flag_layer())?;
    if a.recipe.print_recipe {
        print!("{}", recipe.resolved_for(&scene).to_toml());
        return Ok(());
    }
    let outname = output.display().to_string();
    let scene_load = clock.lap("load", 0).clone();
    let bake = Bake::new(&scene, &a.scene, &recipe)
        .with_context(|| a.scene.clone())?
        .with_load_time(&scene_load);
    let callback = progress.callback();
    let Baked { file, mut report } = match shard {
        Some((i, n)) => bake.run_part(i, n, &callback),
        None => bake.run(&callback),
    }
    .with_context(|| a.scene.clone())?;
    progress.finish();
    write_probe_file(&output, &file).with_context(|| outname.clone())?;
    warn_unused_probes(&outname, &file);
    // README's first command, `probekit bake`, also draws its picture.
    let default_demo =
        a.scene == probekit::scene::BUILTIN_DEMO && a.output.is_none() && a.shard.is_none();
    let picture = a
        .render
        .clone()
        .or_else(|| default_demo.then(|| output.with_extension("png")));
    if let Some(png) = &picture {
        clock.restart(0);
        let rs = super::render::bake_settings(&file, &scene);
        super::render::render_to_png(&scene, &file, &rs, png, &outname)?;
        // The picture is not part of the bake, but of the command's time.
        report.phases.push(clock.lap("picture", 0).clone());
    }
    if a.json {
        let mut v = serde_json::to_value(&report)?;
        v["output"] = outname.into();
        println!("{v}");
    } else {
        let part = report
            .shard
            .map_or(String::new(), |[i, n]| format!(", shard {i}/{n}"));
        println!(
            "{outname}: {} probes ({} invalid), {} bytes{part}",
            report.probes, report.invalid, report.bytes
        );
        if let Some(l) = &report.lights {
            println!("{}", light_split_line(&scene, l));
        }
    }
    Ok(())
}

/// One line on the run-time light split: which lights run at run time,
/// which `auto` lights stayed baked and which were demoted.
fn light_split_line(
    scene: &probekit::scene::Scene,
    l: &probekit::pipeline::lights::LightSplitReport,
) -> String {
    let names = |v: &[usize]| -> String {
        let n: Vec<String> = v
            .iter()
            .map(|&i| {
                let light = &scene.lights[i];
                match &light.group {
                    Some(g) => format!("light {} ({g})", i + 1),
                    None => format!("light {}", i + 1),
                }
            })
            .collect();
        n.join(", ")
    };
    let mut line = if l.runtime.is_empty() {
        "every light baked into the probes".to_string()
    } else {
        format!(
            "run-time lights: {} ({} occlusion entries)",
            names(&l.runtime),
            l.occlusion_entries
        )
    };
    if !l.kept_baked.is_empty() {
        line += &format!(
            "; kept baked (baking wins on held-out points): {}",
            names(&l.kept_baked)
        );
    }
    if !l.demoted.is_empty() {
        line += &format!(
            "; demoted to baked (more than {} run-time lights reach a probe): {}",
            l.max_per_probe,
            names(&l.demoted)
        );
    }
    line
}

/// Tells on stderr which probes share a position with an earlier one: the
/// tetrahedralization merged them ([`probekit::delaunay::unused_probes`]), so
/// they are stored but no query reaches them.
fn warn_unused_probes(outname: &str, file: &ProbeFile) {
    let Some(t) = file.as_cloud().and_then(|c| c.tetrahedra.as_ref()) else {
        return;
    };
    let unused = probekit::delaunay::unused_probes(file.positions().len(), &t.vertices);
    if let Some(&first) = unused.first() {
        let p = file.positions()[first as usize];
        eprintln!(
            "warning: {outname}: {} probe(s) share a position with another and take no part in \
             the tetrahedra (first: probe {first} at {}, {}, {})",
            unused.len(),
            p.x,
            p.y,
            p.z
        );
    }
}

/// Runs `probekit merge`.
pub fn merge(a: &MergeArgs) -> Result<()> {
    check_outputs(&[Some(&a.output)])?;
    let progress = crate::progress::Progress::new();
    let mut parts = Vec::with_capacity(a.parts.len());
    for p in &a.parts {
        parts.push((p.display().to_string(), load_probes(p)?));
    }
    let head = &parts[0];
    let record = probekit::recipe::BakeRecord::from_json(head.1.metadata())
        .ok_or_else(|| anyhow!("{}: not a shard part (no bake record)", head.0))?;
    let kinds = (record.recipe).visibility_bake(&record.recipe.recorded_box(), true);
    let needs_scene = kinds.cell_subdivision.is_some() || kinds.probe_weights.is_some();
    // The scene given, else the one the parts recorded.
    let scene = match (&a.scene, needs_scene) {
        (_, false) => None,
        (Some(s), true) => Some((load_scene(s)?, s.clone())),
        (None, true) if record.scene.is_empty() => {
            return Err(anyhow!(
                "{}: baked with cell visibility or probe weights, which merge bakes over all \
                 probes, and the part records no scene: pass --scene",
                head.0
            ))
        }
        (None, true) => Some((load_scene(&record.scene)?, record.scene.clone())),
    };
    let out = a.output.display().to_string();
    let file = probekit::pipeline::merge(
        &parts,
        scene.as_ref().map(|(s, n)| (s, n.as_str())),
        &progress.callback(),
    )
    .with_context(|| out.clone())?;
    progress.finish();
    write_probe_file(&a.output, &file).with_context(|| out.clone())?;
    println!(
        "{out}: {} probes from {} parts",
        file.positions().len(),
        parts.len()
    );
    Ok(())
}
