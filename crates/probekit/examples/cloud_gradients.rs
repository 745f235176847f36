//! Per-probe SH gradients for a cloud, measured: each probe of a baked
//! cloud is captured six more times at `±h` along the axes (same random
//! numbers on both sides, the file's own capture settings and light
//! split, virtual offset off), and the central differences give the
//! gradient of its SH part. A query extrapolates each of the blend's
//! probes to the point to first order (Tatarchuk 2005, after Annen et al.
//! 2004): `E_i(n) + ∇E_i(n)·δ_i`, the step `δ_i = p − p_i` shortened to at
//! most `--limit`, the result clamped to `[0, cap·E_i(n)]` per channel,
//! and adds the blend of those changes to the file's combined answer.
//!
//! ```text
//! cargo run --release -p probekit --example cloud_gradients -- SCENE \
//!     [--points 2000] [--seeds 1,2,3] [--h 0.02] [--limit 0.1] [--cap 2] FILE.probes...
//! ```
//!
//! Prints per file the plain figures and the figures with gradients, with
//! the file's bytes and the bytes the gradients would add (three times the
//! stored coefficients of each probe, in the file's codec).

use glam::Vec3;
use probekit::capture::Baker;
use probekit::eval::metrics;
use probekit::format::ProbeFile;
use probekit::pipeline::lights::LightSplit;
use probekit::recipe::BakeRecord;
use probekit::scene::Scene;
use probekit_runtime::{LoadOptions, ObjectState, Probes};
use rayon::prelude::*;
use std::error::Error;
use std::path::Path;

mod common;
use common::{arg, eval_seeds, EvalSet};

/// The gradients of every probe's SH part: `[d/dx, d/dy, d/dz]`, each
/// `order²` RGB coefficients.
fn gradients(
    scene: &Scene,
    file: &ProbeFile,
    h: f32,
) -> Result<Vec<[Vec<Vec3>; 3]>, Box<dyn Error>> {
    let record = BakeRecord::from_json(file.metadata()).ok_or("the file has no bake record")?;
    let recipe = record.recipe;
    let split = LightSplit::new(scene, &recipe.lights, recipe.capture.indirect_only);
    let mut baker = Baker::new(scene)?;
    if !split.candidates.is_empty() {
        baker.set_light_groups(&split.capture_groups)?;
    }
    let mut s = recipe.placement_capture();
    s.exclude_direct = split.excluded_groups(&recipe.lights.runtime_indices());
    s.validity.virtual_offset = false;
    let axes = [Vec3::X, Vec3::Y, Vec3::Z];
    file.positions()
        .par_iter()
        .enumerate()
        .map(|(i, &p)| {
            let mut g: [Vec<Vec3>; 3] = Default::default();
            for (k, a) in axes.iter().enumerate() {
                let plus = baker.capture(p + *a * h, i as u64, &s)?.sh.into_coeffs();
                let minus = baker.capture(p - *a * h, i as u64, &s)?.sh.into_coeffs();
                g[k] = plus
                    .iter()
                    .zip(&minus)
                    .map(|(a, b)| (*a - *b) / (2.0 * h))
                    .collect();
            }
            Ok(g)
        })
        .collect::<Result<_, probekit::capture::BakeError>>()
        .map_err(Into::into)
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let h: f32 = arg(&args, "--h", 0.02);
    let limit: f32 = arg(&args, "--limit", 0.1);
    let cap: f32 = arg(&args, "--cap", 2.0);
    let points: usize = arg(&args, "--points", 2000);
    let seeds: String = arg(&args, "--seeds", "1".to_string());
    let mut rest = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if a.starts_with("--") {
            it.next();
        } else {
            rest.push(a.clone());
        }
    }
    let (scene_name, files) = rest
        .split_first()
        .ok_or("usage: cloud_gradients SCENE FILE...")?;
    let scene = Scene::load(Path::new(scene_name))?;
    let eval_baker = Baker::new(&scene)?;
    let EvalSet {
        points: pts,
        truth,
        mean,
    } = eval_seeds(&eval_baker, &scene, points, &seeds)?;
    for f in files {
        let file = ProbeFile::load(f)?;
        let probes = Probes::from_file(&file, LoadOptions::default())?;
        let cloud = probes.cloud().ok_or("not a cloud")?;
        let t = std::time::Instant::now();
        let grads = gradients(&scene, &file, h)?;
        let capture_s = t.elapsed().as_secs_f32();
        let positions = file.positions();
        let mut state = ObjectState::new();
        let (mut plain, mut with) = (Vec::new(), Vec::new());
        for q in &pts {
            let e = Vec3::from(probes.irradiance(&mut state, q.position, q.normal)?);
            let blend = probes.query(&mut state, q.position)?;
            let mut delta = Vec3::ZERO;
            for (&i, &w) in blend.probes.iter().zip(&blend.weights).take(4) {
                if w == 0.0 {
                    continue;
                }
                let i = i as usize;
                let mut step = q.position - positions[i];
                if step.length() > limit {
                    step *= limit / step.length();
                }
                let e_i = probekit_sh::irradiance(cloud.probe_sh(i), q.normal);
                let slope: Vec3 = (0..3)
                    .map(|k| probekit_sh::irradiance(&grads[i][k], q.normal) * step[k])
                    .sum();
                let moved = (e_i + slope).clamp(Vec3::ZERO, e_i.max(Vec3::ZERO) * cap);
                delta += (moved - e_i) * w;
            }
            plain.push(e);
            with.push((e + delta).max(Vec3::ZERO));
        }
        let a = metrics(&plain, &truth, mean);
        let b = metrics(&with, &truth, mean);
        let coef_bytes = match file.probes() {
            Some(set) => set.coefficients.probe_bytes(0).map_or(0, |b| b.len()),
            None => 0,
        };
        let bytes = std::fs::metadata(f)?.len();
        println!(
            "{f}: probes={} bytes={bytes} +grad_bytes={} | plain rel_rmse={:.3} p95={:.2} leaks={} | gradients rel_rmse={:.3} p95={:.2} leaks={} | capture {capture_s:.0} s",
            file.probe_count(),
            3 * coef_bytes * file.probe_count(),
            a.rel_rmse,
            a.p95_rel_error,
            a.leaks,
            b.rel_rmse,
            b.p95_rel_error,
            b.leaks,
        );
    }
    Ok(())
}
