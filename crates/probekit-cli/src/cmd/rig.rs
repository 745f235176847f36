//! `probekit rig MESH --scene SCENE [--probes BAKED] --rig SPEC --at x,y,z
//! [--json] ...`: fits an irradiance rig (Yuan, Nowrouzezahrai & Sloan 2011) to a mesh placed at a
//! point among the scene's lights and a baked probe file, splits the lights
//! into analytic / transition / rig zones, and reports the per-vertex error
//! against the exact lighting and the cost of a frame.

use anyhow::{anyhow, Context};
use clap::{Args, ValueEnum};
use glam::Vec3;
use probekit::query::Predictor;
use probekit::rig::render::{comparison_figure, zones_figure, Column};
use probekit::rig::run::{load_lights, load_mesh, run as run_rig, RunConfig, RunReport};
use probekit::rig::source::ProbeSource;
use probekit::rig::{RigSetupError, RigSpec};
use probekit_runtime::Interp;
use std::path::{Path, PathBuf};

/// On or off.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Switch {
    /// On.
    On,
    /// Off.
    Off,
}

/// Arguments of `probekit rig`.
#[derive(Args, Debug)]
pub struct RigArgs {
    /// The mesh: builtin:car, builtin:character, or an .obj/.gltf/.glb/.toml
    /// file (all its meshes merged, in its own coordinates).
    pub mesh: String,
    /// The analytic lights: builtin:rig-demo, builtin:paper-cost, or any
    /// scene (builtin:demo, .toml, .gltf, .glb, .obj; emissive triangles
    /// and the environment are ignored with a warning). Optional with --probes.
    #[arg(long)]
    pub scene: Option<String>,
    /// A baked .probes cloud or volume: its SH at the rig's sample points is
    /// added to the lights (use a `bake --indirect-only` file with the same
    /// scene's lights, or a full bake alone, to avoid counting direct light twice).
    #[arg(long)]
    pub probes: Option<PathBuf>,
    /// Volume interpolation for --probes: trilinear (default), taylor,
    /// tricubic, idw, leaf-trilinear. Refused without --probes or with a
    /// probe cloud (it interpolates by its tetrahedra).
    #[arg(long, requires = "probes")]
    pub interp: Option<String>,
    /// Use --probes with a --scene whose lighting differs from the scene
    /// the file was baked from (refused otherwise).
    #[arg(long, requires = "probes")]
    pub allow_other_scene: bool,
    /// Rig type: constant, gradient, lattice:NXxNYxNZ or mixed:X,Y,Z (c, g, lN per axis).
    #[arg(long)]
    pub rig: String,
    /// Where the mesh's origin is placed, x,y,z (metres).
    #[arg(long, default_value = "0,0,0", allow_hyphen_values = true)]
    pub at: String,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Analytic/rig split (off: every light through the rig).
    #[arg(long, value_enum, default_value = "on")]
    pub split: Switch,
    /// Sample points on the mesh.
    #[arg(long, default_value_t = 512)]
    pub samples: usize,
    /// SH order (bands; 3 = L2).
    #[arg(long, default_value_t = 3)]
    pub order: usize,
    /// White level (reflected radiance) for grey levels; default: the
    /// largest exact reflected radiance over the mesh.
    #[arg(long)]
    pub white: Option<f32>,
    /// Target error of the split, grey levels.
    #[arg(long, default_value_t = 1.0)]
    pub target: f32,
    /// Write the comparison picture (all rig types + exact, error heat
    /// maps) here, and the zone picture beside it as STEM_zones.png (STEM: this
    /// file's name without its extension).
    #[arg(long)]
    pub render: Option<PathBuf>,
    /// Write the fitted rig (sample points, fitting matrix, transition
    /// table) as a rig-only .probes file.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// The `--json` line: the rig, its error, its light zones and its cost per
/// frame (whether a baked file was used is the caller's to know).
fn json(spec: &RigSpec, r: &RunReport) -> String {
    let (a, t, g) = r.zone_counts();
    serde_json::json!({
        "rig": spec.to_string(),
        "parameters": spec.parameter_count(),
        "samples": r.fitted.rig.samples.len(),
        "rel_rmse": r.stats.rel_rmse,
        "max_error_grey_levels": r.stats.max_grey,
        "lights": {"analytic": a, "transition": t, "rig": g},
        "ns_per_frame": r.ns_per_frame.round() as u64,
    })
    .to_string()
}

fn kind_name(p: &ProbeSource) -> &'static str {
    match p.predictor() {
        Predictor::Cloud(_) => "cloud",
        Predictor::Volume(..) => "volume",
    }
}

/// Runs `probekit rig`.
pub fn run(a: RigArgs) -> anyhow::Result<()> {
    super::util::check_outputs(&[a.out.as_deref(), a.render.as_deref()])?;
    let spec: RigSpec = a.rig.parse().map_err(|e| anyhow!("--rig: {e}"))?;
    let at = super::util::parse_vec3(&a.at, "--at")?;
    // The loader's errors name the file already; validation errors do not.
    let mesh = load_mesh(&a.mesh).map_err(|e| match e {
        RigSetupError::Scene(_) | RigSetupError::UnknownBuiltin(_) => anyhow!("{e}"),
        e => anyhow!("{}: {e}", a.mesh),
    })?;
    let lights = match &a.scene {
        Some(s) => {
            let l = load_lights(s)?;
            if let (Some(p), Some(hash)) = (&a.probes, &l.lighting_hash) {
                let file = super::util::load_probes(p)?;
                let name = p.display().to_string();
                if let Err(e) = probekit::format::check_scene_hash(&file.metadata, &name, hash, s) {
                    if !a.allow_other_scene {
                        return Err(e.into());
                    }
                    eprintln!("warning: {e}");
                }
            }
            for w in &l.warnings {
                eprintln!("warning: {w}");
            }
            l.lights
        }
        None if a.probes.is_some() => Vec::new(),
        None => return Err(anyhow!("rig needs --scene, --probes or both")),
    };
    let name = a.interp.as_deref().unwrap_or("trilinear");
    let interp = Interp::from_name(name).ok_or_else(|| {
        anyhow!("--interp {name}: expected trilinear, taylor, tricubic, idw or leaf-trilinear")
    })?;
    let probes = match &a.probes {
        Some(p) => {
            let source = ProbeSource::load(p)?;
            if let (Some(i), true) = (&a.interp, source.is_cloud()) {
                return Err(super::util::interp_on_cloud(i))
                    .with_context(|| p.display().to_string());
            }
            Some(
                source
                    .with_interp(interp)
                    .map_err(|e| anyhow!("{}: {e}", p.display()))?,
            )
        }
        None => None,
    };
    if let Some(w) = a.white {
        if !(w > 0.0 && w.is_finite()) {
            return Err(anyhow!("--white {w}: must be a positive number"));
        }
    }
    let cfg = RunConfig {
        spec,
        at,
        split: a.split == Switch::On,
        samples: a.samples,
        order: a.order,
        white: a.white,
        target_grey: a.target,
        ..RunConfig::default()
    };
    let report = run_rig(&mesh, &a.mesh, &lights, probes.as_ref(), &cfg, true)
        .with_context(|| a.mesh.clone())?;
    if a.json {
        println!("{}", json(&spec, &report));
    } else {
        let (an, tr, rg) = report.zone_counts();
        println!(
            "rig {spec} on {} at {at}: {} SH vectors, {} samples",
            a.mesh,
            spec.parameter_count(),
            report.fitted.rig.samples.len()
        );
        println!(
            "  lights: {an} analytic, {tr} transition, {rg} rig (of {})",
            lights.len()
        );
        if let (Some(p), Some(src)) = (&a.probes, &probes) {
            println!(
                "  baked {} {} (order {}) through the rig",
                kind_name(src),
                p.display(),
                src.order()
            );
        }
        println!(
            "  per-vertex error vs exact: rel RMSE {:.4}, max {:.2} grey levels (white {:.4})",
            report.stats.rel_rmse, report.stats.max_grey, report.stats.l_white
        );
        println!(
            "  spatial error vs per-vertex SH of the same lights: rel RMSE {:.4}, max {:.2} grey levels",
            report.stats_vs_sh.rel_rmse, report.stats_vs_sh.max_grey
        );
        if !report.thresholds.is_empty() {
            let t: Vec<String> = report
                .fitted
                .rig
                .transitions
                .iter()
                .map(|t| format!("{:.2}:{:.3}", t.distance, t.error))
                .collect();
            println!(
                "  error table (distance/R : grey levels, unitized light): {}",
                t.join(" ")
            );
            let (c, r) = mesh.bounding_sphere();
            for (i, (l, th)) in lights.iter().zip(&report.thresholds).enumerate() {
                let x = l
                    .position()
                    .map_or(f32::INFINITY, |p| p.distance(c + at) / r);
                println!(
                    "  light {i}: at {x:.2} R, transition at {th:.2} R, {:?}",
                    report.zones[i]
                );
            }
        }
        println!(
            "  frame: {:.0} ns (rig update + per-vertex), brute-force analytic {:.0} ns, ratio {:.2}",
            report.ns_per_frame,
            report.ns_brute_force,
            report.ns_brute_force / report.ns_per_frame.max(1.0)
        );
    }
    if let Some(out) = &a.out {
        let bytes = probekit::rig::fit::rig_file(std::slice::from_ref(&report.fitted))
            .to_bytes()
            .map_err(|e| anyhow!("{}: {e}", out.display()))?;
        std::fs::write(out, bytes).map_err(|e| anyhow!("{}: cannot write: {e}", out.display()))?;
    }
    if let Some(out) = &a.render {
        render(out, &mesh, &lights, probes.as_ref(), &cfg, &report)?;
    }
    Ok(())
}

fn render(
    out: &Path,
    mesh: &probekit::rig::mesh::Mesh,
    lights: &[probekit::lights::Light],
    probes: Option<&ProbeSource>,
    cfg: &RunConfig,
    report: &RunReport,
) -> anyhow::Result<()> {
    let mut specs: Vec<RigSpec> = [
        "constant",
        "gradient",
        "lattice:2x2x3",
        "lattice:3x2x2",
        "mixed:l3,g,c",
        "lattice:8x4x2",
    ]
    .iter()
    .map(|s| s.parse().expect("built-in spec"))
    .collect();
    if !specs.contains(&cfg.spec) {
        specs.push(cfg.spec);
    }
    let l_white = report.stats.l_white;
    let mut runs = Vec::new();
    for s in &specs {
        // Rigs are compared with each other with every light in the rig.
        let c = RunConfig {
            spec: *s,
            split: false,
            ..cfg.clone()
        };
        runs.push((s, run_rig(mesh, "mesh", lights, probes, &c, false)?));
    }
    let grey = |r: &RunReport| -> Vec<f32> {
        r.approx
            .iter()
            .zip(&r.exact)
            .map(|(x, e)| 255.0 * (*x - *e).abs().max_element() / std::f32::consts::PI / l_white)
            .collect()
    };
    let mut cols: Vec<Column> = runs
        .iter()
        .map(|(s, r)| Column {
            name: s.to_string(),
            irradiance: &r.approx,
            error_grey: Some(grey(r)),
        })
        .collect();
    cols.push(Column {
        name: "exact".into(),
        irradiance: &report.exact,
        error_grey: None,
    });
    comparison_figure(out, mesh, &cols, l_white, 64.0)?;
    let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("rig");
    let zones_path = out.with_file_name(format!("{stem}_zones.png"));
    let world = mesh.translated(cfg.at);
    // Directional lights have no position to draw.
    let lw: Vec<(Vec3, f32)> = lights
        .iter()
        .zip(&report.zones)
        .filter_map(|(l, z)| Some((l.position()?, z.rig_weight())))
        .collect();
    zones_figure(&zones_path, &world, &report.approx, l_white, &lw)?;
    Ok(())
}
