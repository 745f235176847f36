//! `probekit eval` for many probe files on one ground truth: the reference
//! irradiance (the expensive part) is computed once (and cached in the
//! temporary directory for later runs) and reused, so an
//! error-against-memory table over several clouds and volumes costs one
//! reference pass.
//!
//! ```text
//! cargo run --release -p probekit --example eval_many -- SCENE \
//!     [--points 2000] [--seed 1 | --seeds 1,2,3] [--interp trilinear] FILE.probes...
//! ```
//!
//! Prints one line per file: probes, file bytes, `rel_rmse`,
//! `p95_rel_error` and leaks, the figures `probekit eval` reports (same
//! sample points for the same scene, point count and seed). With `--seeds`
//! the point sets of all the seeds are pooled into one evaluation (figures
//! over all their points, the leak floor from the pooled mean), and each
//! seed's own `rel_rmse` follows in brackets: one 2000-point set can be
//! decided by a handful of points next to a light. Each file is queried
//! through [`probekit_runtime::Probes`], loaded with `--interp` (volumes).

use glam::Vec3;
use probekit::capture::Baker;
use probekit::eval::metrics;
use probekit::format::ProbeFile;
use probekit::scene::Scene;
use probekit::volume::Interp;
use probekit_runtime::{LoadOptions, ObjectState, Probes};
use std::error::Error;
use std::path::Path;

mod common;
use common::{eval_set, pooled, seed_list, EvalSet};

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut scene = None;
    let (mut points, mut seeds, mut interp) = (2000usize, vec![1u64], Interp::Trilinear);
    let mut files = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--points" => points = value()?.parse()?,
            "--seed" => seeds = vec![value()?.parse()?],
            "--seeds" => seeds = seed_list(value()?)?,
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
    let sets: Vec<EvalSet> = seeds
        .iter()
        .map(|&s| eval_set(&baker, &scene, points, s))
        .collect::<Result<_, _>>()?;
    let EvalSet {
        points: pts,
        truth,
        mean,
    } = pooled(&sets);
    eprintln!(
        "reference at {} points in {:.1} s",
        pts.len(),
        t.elapsed().as_secs_f32()
    );
    let mut options = LoadOptions::default();
    options.interpolation = interp;
    for f in &files {
        let file = ProbeFile::load(f)?;
        let probes = Probes::from_file(&file, options)?;
        let mut state = ObjectState::new();
        let pred = pts
            .iter()
            .map(|p| {
                Ok(Vec3::from(
                    probes.irradiance(&mut state, p.position, p.normal)?,
                ))
            })
            .collect::<Result<Vec<_>, Box<dyn Error>>>()?;
        let m = metrics(&pred, &truth, mean);
        let per_seed: Vec<String> = if sets.len() > 1 {
            let mut at = 0;
            sets.iter()
                .map(|s| {
                    let n = s.points.len();
                    let r = metrics(&pred[at..at + n], &s.truth, s.mean).rel_rmse;
                    at += n;
                    format!("{r:.3}")
                })
                .collect()
        } else {
            Vec::new()
        };
        println!(
            "{f}: probes={} bytes={} rel_rmse={:.3} p95={:.2} leaks={}{}",
            file.probe_count(),
            std::fs::metadata(f)?.len(),
            m.rel_rmse,
            m.p95_rel_error,
            m.leaks,
            if per_seed.is_empty() {
                String::new()
            } else {
                format!(" [{}]", per_seed.join(" "))
            }
        );
    }
    Ok(())
}
