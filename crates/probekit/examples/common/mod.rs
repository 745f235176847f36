//! Helpers shared by the measurement examples (`mod common;` in each; not
//! every example uses every helper).
#![allow(dead_code)]

use glam::Vec3;
use probekit::bake::Baker;
use probekit::placement::eval::{
    mean_luminance, reference_cache_path, reference_cached, sample_points, EvalPoint,
};
use probekit::scene::Scene;
use std::error::Error;

/// The value after `name` in `args`, parsed, or `default` when it is
/// missing or does not parse.
pub fn arg<T: std::str::FromStr>(args: &[String], name: &str, default: T) -> T {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// `probekit eval`'s points with their ground truth.
#[derive(Clone)]
pub struct EvalSet {
    /// The points.
    pub points: Vec<EvalPoint>,
    /// Reference irradiance at each point (for its normal).
    pub truth: Vec<Vec3>,
    /// Mean luminance of `truth` (the leak floor's scale).
    pub mean: f32,
}

/// `probekit eval`'s `n` points of `seed` in the scene's bake box and their
/// reference irradiance (cached in the temp folder, keyed by scene and
/// points).
pub fn eval_set(
    baker: &Baker,
    scene: &Scene,
    n: usize,
    seed: u64,
) -> Result<EvalSet, Box<dyn Error>> {
    let pts = sample_points(baker.tracer(), &scene.bake_box(), n, seed);
    let truth = reference_cached(
        baker,
        &pts,
        &reference_cache_path(scene.content_hash(), &pts),
    )?;
    let mean = mean_luminance(&truth);
    Ok(EvalSet {
        points: pts,
        truth,
        mean,
    })
}

/// The point sets of several seeds as one evaluation: points and truth
/// concatenated in order, the mean (the leak floor's scale) over all of them.
pub fn pooled(sets: &[EvalSet]) -> EvalSet {
    let points: Vec<EvalPoint> = sets.iter().flat_map(|s| s.points.iter().copied()).collect();
    let truth: Vec<Vec3> = sets.iter().flat_map(|s| s.truth.iter().copied()).collect();
    let mean = mean_luminance(&truth);
    EvalSet {
        points,
        truth,
        mean,
    }
}

/// Seeds written comma-separated (`1,2,3`).
pub fn seed_list(seeds: &str) -> Result<Vec<u64>, std::num::ParseIntError> {
    seeds.split(',').map(|s| s.trim().parse()).collect()
}

/// `eval_set` of each seed in `seeds` (comma-separated), pooled.
pub fn eval_seeds(
    baker: &Baker,
    scene: &Scene,
    n: usize,
    seeds: &str,
) -> Result<EvalSet, Box<dyn Error>> {
    let sets = seed_list(seeds)?
        .into_iter()
        .map(|s| eval_set(baker, scene, n, s))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(pooled(&sets))
}
