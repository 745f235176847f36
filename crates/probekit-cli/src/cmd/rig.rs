//! `probekit rig MESH --scene SCENE [--probes BAKED] --rig SPEC --at x,y,z
//! [--json] ...`: fits an irradiance rig (Yuan, Nowrouzezahrai & Sloan 2011) to a mesh placed at a
//! point among the scene's lights and a baked probe file, splits the lights
//! into analytic / transition / rig zones, and reports the per-vertex error
//! against the exact lighting and the cost of a frame.

use anyhow::{anyhow, Context};
use clap::{Args, ValueEnum};
use probekit::query::QueryOptions;
use probekit::rig::report::RigReport;
use probekit::rig::run::{comparison_pictures, load_lights, load_mesh, run as run_rig, RunConfig};
use probekit::rig::source::ProbeSource;
use probekit::rig::{RigSetupError, RigSpec};
use std::path::PathBuf;

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
    let file = a
        .probes
        .as_deref()
        .map(super::util::load_probes)
        .transpose()?;
    let lights = match &a.scene {
        Some(s) => {
            let l = load_lights(s)?;
            if let (Some(p), Some(file), Some(hash)) = (&a.probes, &file, &l.lighting_hash) {
                let name = p.display().to_string();
                if let Err(e) = probekit::format::check_scene_hash(file.metadata(), &name, hash, s)
                {
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
    let probes = match (&a.probes, &file) {
        (Some(p), Some(file)) => {
            let options = QueryOptions::parse(a.interp.as_deref(), &[], &[])?;
            let options = options
                .load_options(file.kind())
                .with_context(|| p.display().to_string())?;
            let source = ProbeSource::from_file(file, options);
            Some(source.map_err(|e| anyhow!("{}: {e}", p.display()))?)
        }
        _ => None,
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
    let path = a.probes.as_ref().map(|p| p.display().to_string());
    let baked = path.as_deref().zip(probes.as_ref());
    let printed = RigReport::new(&spec, &a.mesh, &mesh, at, &lights, baked, &report);
    if a.json {
        println!("{}", serde_json::to_value(&printed)?);
    } else {
        print!("{printed}");
    }
    if let Some(out) = &a.out {
        let bytes = probekit::rig::fit::rig_file(std::slice::from_ref(&report.fitted))
            .to_bytes()
            .map_err(|e| anyhow!("{}: {e}", out.display()))?;
        std::fs::write(out, bytes).map_err(|e| anyhow!("{}: cannot write: {e}", out.display()))?;
    }
    if let Some(out) = &a.render {
        comparison_pictures(out, &mesh, &lights, probes.as_ref(), &cfg, &report)?;
    }
    Ok(())
}
