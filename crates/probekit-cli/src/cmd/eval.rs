//! `probekit eval PROBES --scene SCENE [--points N] [--seed S] [--json]`:
//! error of a probe cloud against path-traced ground truth at random
//! free-space points of the bake box (`probekit::placement::eval`).
//! Not done yet: `--box`, `--compare grid`, `--plot`, volume files.

use anyhow::{bail, Context, Result};
use clap::Args;
use probekit::bake::{Baker, ReferenceSettings};
use probekit::format::ProbeFile;
use probekit::placement::eval::{
    interpolate_cloud, mean_luminance, metrics, reference, sample_points, Metrics,
};
use probekit::scene::Scene;
use probekit_sh::ShRgb;
use std::path::PathBuf;

/// Arguments of `probekit eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// A cloud `.probes` file.
    pub probes: PathBuf,
    /// Scene file or `builtin:demo`.
    #[arg(long)]
    pub scene: PathBuf,
    /// Evaluation points.
    #[arg(long, default_value_t = 2000)]
    pub points: usize,
    /// Seed of the evaluation points.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

fn to_json(m: &Metrics) -> serde_json::Value {
    serde_json::json!({"points": m.points, "rel_rmse": m.rel_rmse, "p95_rel_error": m.p95_rel_error, "leaks": m.leaks})
}

/// Runs `probekit eval`.
pub fn run(a: &EvalArgs) -> Result<()> {
    let name = a.probes.display().to_string();
    let file = ProbeFile::load(&a.probes).with_context(|| name.clone())?;
    let Some(tets) = file.tetrahedra.as_ref() else {
        bail!("{name}: not a probe cloud (no tetrahedra)");
    };
    let tri = probekit::cloud::Tetrahedralization {
        tets: tets.vertices.clone(),
        neighbors: tets.neighbours.clone(),
        merged_duplicates: Vec::new(),
    };
    let mesh = tri
        .to_tet_mesh(&file.positions)
        .with_context(|| name.clone())?;
    let coeffs = file.coefficients.to_f32().with_context(|| name.clone())?;
    let per = file.coefficients.coeffs_per_probe();
    let sh: Vec<ShRgb> = coeffs
        .chunks(per)
        .map(|c| ShRgb::from_coeffs(c.to_vec()).context("coefficients are not a whole SH order"))
        .collect::<Result<_>>()
        .with_context(|| name.clone())?;
    let scene = Scene::load(&a.scene).with_context(|| a.scene.display().to_string())?;
    let baker = Baker::new(&scene).with_context(|| a.scene.display().to_string())?;
    let pts = sample_points(baker.tracer(), &scene.bake_box(), a.points, a.seed);
    let rs = ReferenceSettings {
        relative_precision: 0.03,
        ..Default::default()
    };
    let truth = reference(&baker, &pts, &rs).with_context(|| a.scene.display().to_string())?;
    let pred = interpolate_cloud(&mesh, &sh, &pts);
    let mean = mean_luminance(&truth);
    let all = metrics(&pred, &truth, mean);
    let mut out = to_json(&all);
    out["probes"] = file.positions.len().into();
    let mut regions = serde_json::Map::new();
    for r in &scene.regions {
        let bb = r.aabb();
        let idx: Vec<usize> = (0..pts.len())
            .filter(|&i| bb.contains(pts[i].position))
            .collect();
        let p: Vec<_> = idx.iter().map(|&i| pred[i]).collect();
        let t: Vec<_> = idx.iter().map(|&i| truth[i]).collect();
        regions.insert(r.name.clone(), to_json(&metrics(&p, &t, mean)));
    }
    out["regions"] = regions.into();
    if a.json {
        println!("{out}");
    } else {
        println!("{}", serde_json::to_string_pretty(&out)?);
    }
    Ok(())
}
