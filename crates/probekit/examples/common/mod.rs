//! Helpers shared by the measurement examples (`mod common;` in each; not
//! every example uses every helper).
#![allow(dead_code)]

use glam::Vec3;
use probekit::capture::Baker;
use probekit::eval::{mean_luminance, reference_cache_path, reference_cached};
use probekit::scene::Scene;
use probekit::trace::free_space::{sample_points, EvalPoint};
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
    with_truth(baker, scene, pts)
}

/// `points` with their reference irradiance (cached in the temp folder,
/// keyed by scene and points) and its mean luminance.
pub fn with_truth(
    baker: &Baker,
    scene: &Scene,
    points: Vec<EvalPoint>,
) -> Result<EvalSet, Box<dyn Error>> {
    let truth = reference_cached(
        baker,
        &points,
        &reference_cache_path(scene.lighting_hash(), &points),
    )?;
    let mean = mean_luminance(&truth);
    Ok(EvalSet {
        points,
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

/// Extra evaluation points in balls around the scene's positional lights,
/// for a *stratified* estimate of the same population `rel_rmse` that
/// `probekit eval`'s uniform points estimate: on scenes with small lamps most
/// of `Σ|E|²` (and of the error) sits within a few tenths of a metre of
/// them, where a uniform set of thousands of points holds a handful.
///
/// Strata: each light's ball of `radius` (the part not in an earlier ball),
/// and the rest of the bake box. A ball's points are uniform in it and pass
/// `probekit eval`'s test (inside the box and
/// `trace::free_space::is_evaluation_point`); each stands for
/// `V_ball / draws` of free space. A uniform
/// point outside every ball stands for `V_box · f / n` (`f`: the box's free
/// fraction, from `free_draws` draws of the same test; `n`: the uniform
/// points); one inside a ball gets weight 0 (that stratum is the ball's
/// points). Weighted sums `Σ w·|Ê − E|²` and `Σ w·|E|²` estimate the
/// population's integrals, as the unweighted sums over uniform points do.
pub struct NearLights {
    /// The balls' points (all lights', in order) with their ground truth.
    pub set: EvalSet,
    /// Weight of each of `set`'s points (m³ of free space it stands for).
    pub weights: Vec<f32>,
    /// Stratum of each of `set`'s points: 1 + the light's index among the
    /// balls.
    pub stratum: Vec<u32>,
    /// Ball centres.
    pub centres: Vec<Vec3>,
    /// Ball radius, metres.
    pub radius: f32,
    /// Weight of a uniform point outside every ball.
    pub uniform_weight: f32,
}

impl NearLights {
    /// `n` points per positional light (sphere or point, centre inside the
    /// bake box) in balls of `radius`, beside a uniform set of
    /// `uniform_points` points.
    pub fn sample(
        baker: &Baker,
        scene: &Scene,
        uniform_points: usize,
        n: usize,
        radius: f32,
        seed: u64,
    ) -> Result<Self, Box<dyn Error>> {
        use probekit::sampling::{sample_uniform_sphere, SampleRng};
        use probekit::scene::LightKind;
        use probekit::trace::free_space::is_evaluation_point;
        let bbox = scene.bake_box();
        let free = |p: Vec3| bbox.contains(p) && is_evaluation_point(baker.tracer(), p);
        let centres: Vec<Vec3> = scene
            .lights
            .iter()
            .filter(|l| matches!(l.kind, LightKind::Sphere | LightKind::Point))
            .map(|l| l.position)
            .filter(|&c| bbox.contains(c))
            .collect();
        let v_ball = 4.0 / 3.0 * std::f32::consts::PI * radius.powi(3);
        let (mut points, mut weights, mut stratum) = (Vec::new(), Vec::new(), Vec::new());
        for (j, &c) in centres.iter().enumerate() {
            let (mut got, mut draws, mut tries) = (Vec::new(), 0u64, 0u64);
            while got.len() < n && tries < 1000 * n as u64 + 1000 {
                let mut rng = SampleRng::new(seed, 0x4e45_4152 + j as u64, tries);
                tries += 1;
                let u = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
                if u.length_squared() > 1.0 {
                    continue; // not in the ball: not a draw of it
                }
                draws += 1;
                let p = c + u * radius;
                let normal = sample_uniform_sphere(glam::Vec2::new(rng.next_f32(), rng.next_f32()));
                let earlier = centres[..j].iter().any(|&e| e.distance(p) < radius);
                if !earlier && free(p) {
                    got.push(EvalPoint {
                        position: p,
                        normal,
                    });
                }
            }
            let w = v_ball / draws.max(1) as f32;
            weights.extend(std::iter::repeat(w).take(got.len()));
            stratum.extend(std::iter::repeat(j as u32 + 1).take(got.len()));
            points.extend(got);
        }
        // The box's free fraction, from draws of its own stream.
        let size = bbox.size();
        let free_draws = 20_000u64;
        let hits = (0..free_draws)
            .filter(|&i| {
                let mut rng = SampleRng::new(seed, 0x4652_4545, i);
                free(bbox.min + Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * size)
            })
            .count();
        let f = hits as f32 / free_draws as f32;
        let uniform_weight = size.x * size.y * size.z * f / uniform_points.max(1) as f32;
        Ok(NearLights {
            set: with_truth(baker, scene, points)?,
            weights,
            stratum,
            centres,
            radius,
            uniform_weight,
        })
    }

    /// Weight of uniform point `p` (0 inside a ball).
    pub fn uniform_weight_at(&self, p: Vec3) -> f32 {
        if self.centres.iter().any(|&c| c.distance(p) < self.radius) {
            0.0
        } else {
            self.uniform_weight
        }
    }
}
