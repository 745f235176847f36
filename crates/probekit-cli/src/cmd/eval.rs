//! `probekit eval PROBES --scene SCENE [--points N] [--seed S] [--json]`:
//! error of a probe cloud against path-traced ground truth at random
//! free-space points of the bake box (`probekit::placement::eval`).
//! Works on clouds and volumes alike (`Predictor`).

use super::util::{load_probes, parse_interp};
use anyhow::{bail, Context, Result};
use clap::Args;
use glam::Vec3;
use probekit::bake::{Baker, ReferenceSettings};
use probekit::placement::eval::{
    mean_luminance, metrics, reference, sample_points, Metrics, Predictor,
};
use probekit::scene::{Aabb, Scene};
use std::path::PathBuf;

/// Arguments of `probekit eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// A cloud or volume `.probes` file.
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
    /// Box `MINX,MINY,MINZ,MAXX,MAXY,MAXZ` (metres) to sample points in;
    /// default the scene's `[bake] box`.
    #[arg(long = "box", value_delimiter = ',', allow_hyphen_values = true)]
    pub bbox: Option<Vec<f32>>,
    /// Volumes: trilinear (default), taylor or tricubic.
    #[arg(long, default_value = "trilinear")]
    pub interp: String,
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
    let file = load_probes(&a.probes)?;
    let predictor =
        Predictor::from_file(&file, parse_interp(&a.interp)?).with_context(|| name.clone())?;
    let scene = Scene::load(&a.scene).with_context(|| a.scene.display().to_string())?;
    let baker = Baker::new(&scene).with_context(|| a.scene.display().to_string())?;
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
    let pts = sample_points(baker.tracer(), &bbox, a.points, a.seed);
    if pts.is_empty() {
        bail!("{}: no free-space points in the box", a.scene.display());
    }
    let rs = ReferenceSettings {
        relative_precision: 0.03,
        ..Default::default()
    };
    let truth = reference(&baker, &pts, &rs).with_context(|| a.scene.display().to_string())?;
    let pred = predictor.predict(&pts).with_context(|| name.clone())?;
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
