//! `probekit eval` for many probe files on one ground truth: the reference
//! irradiance (the expensive part) is computed once (and cached in the
//! temporary directory for later runs) and reused, so an
//! error-against-memory table over several clouds and volumes costs one
//! reference pass.
//!
//! ```text
//! cargo run --release -p probekit --example eval_many -- SCENE \
//!     [--points 2000] [--seed 1] [--interp trilinear] FILE.probes...
//! ```
//!
//! Prints one line per file: probes, file bytes, `rel_rmse`,
//! `p95_rel_error` and leaks, the figures `probekit eval` reports (same
//! sample points for the same scene, point count and seed).

use probekit::bake::Baker;
use probekit::format::ProbeFile;
use probekit::placement::eval::{metrics, Predictor};
use probekit::scene::Scene;
use probekit::volume::Interp;
use std::error::Error;
use std::path::Path;

mod common;
use common::{eval_set, EvalSet};
fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut scene = None;
    let (mut points, mut seed, mut interp) = (2000usize, 1u64, Interp::Trilinear);
    let mut files = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--points" => points = value()?.parse()?,
            "--seed" => seed = value()?.parse()?,
            "--interp" => {
                let v = value()?;
                interp = Interp::from_name(v).ok_or(format!("--interp {v}: unknown"))?;
            }
            _ if scene.is_none() => scene = Some(a.clone()),
            _ => files.push(a.clone()),
        }
    }
    let scene = scene.ok_or("usage: eval_many SCENE [--points N] [--seed S] FILE...")?;
    let scene = Scene::load(Path::new(&scene))?;
    let baker = Baker::new(&scene)?;
    let t = std::time::Instant::now();
    let EvalSet {
        points: pts,
        truth,
        mean,
    } = eval_set(&baker, &scene, points, seed)?;
    eprintln!(
        "reference at {} points in {:.1} s",
        pts.len(),
        t.elapsed().as_secs_f32()
    );
    for f in &files {
        let file = ProbeFile::load(f)?;
        let pred = Predictor::from_file(&file, interp)?.predict(&pts)?;
        let m = metrics(&pred, &truth, mean);
        println!(
            "{f}: probes={} bytes={} rel_rmse={:.3} p95={:.2} leaks={}",
            file.positions.len(),
            std::fs::metadata(f)?.len(),
            m.rel_rmse,
            m.p95_rel_error,
            m.leaks
        );
    }
    Ok(())
}
