//! Stratified light samples at the probe ([`crate::sampling::sobol02_point`])
//! against independent ones: the same mean, less noise.

use super::{Baker, CaptureSettings};
use crate::scene::demo::{SPHERE_LIGHT_POSITION, SPHERE_LIGHT_RADIUS};
use crate::scene::Scene;
use glam::Vec3;
use probekit_sh::convolve::clamped_cosine_band;
use probekit_sh::ShRgb;

/// Points of the demo's room A at `d` metres below-beside its lamp.
fn near_lamp(d: f32) -> Vec3 {
    SPHERE_LIGHT_POSITION + Vec3::new(-0.6, -0.8, 0.0).normalize() * d
}

/// `Σ_lm A_l² |c_lm|²` (luminance-free, all channels): 4π × the mean over
/// normals of the squared irradiance of `sh` (Ramamoorthi & Hanrahan 2001).
fn energy(a: &ShRgb, b: &ShRgb) -> f64 {
    a.coeffs()
        .iter()
        .zip(b.coeffs())
        .enumerate()
        .map(|(c, (x, y))| {
            let l = (c as f64).sqrt() as usize;
            clamped_cosine_band(l).powi(2) * (*x - *y).length_squared() as f64
        })
        .sum()
}

/// Over `seeds` captures of `x` at `samples`: the mean SH and the mean
/// squared irradiance deviation from it, relative to the mean's own
/// squared irradiance (the noise `probekit eval`'s `rel_rmse` would see).
fn noise(baker: &Baker, x: Vec3, samples: u32, seeds: u64) -> (ShRgb, f64) {
    let caps: Vec<ShRgb> = (1..=seeds)
        .map(|seed| {
            let s = CaptureSettings {
                samples,
                bounces: 2,
                seed,
                ..CaptureSettings::default()
            };
            baker.capture(x, 7, &s).unwrap().sh
        })
        .collect();
    let mut mean = ShRgb::zeros(3);
    for c in &caps {
        mean.add_scaled(c, 1.0 / seeds as f32);
    }
    let var = caps.iter().map(|c| energy(c, &mean)).sum::<f64>() / (seeds - 1) as f64;
    let zero = ShRgb::zeros(3);
    (mean.clone(), var / energy(&mean, &zero))
}

/// Near the demo's lamp, where its direct light dominates, stratified
/// samples agree with independent ones in the mean and have less than half
/// their variance at the same sample count; 2 m away, where light after a
/// bounce dominates, less than three quarters of it (measured: about 0.25
/// and 0.5, `measure_capture_noise_by_sample_count`).
#[test]
fn stratified_light_samples_cut_the_noise_near_a_lamp() {
    let scene = Scene::builtin_demo();
    let strat = Baker::new(&scene).unwrap();
    let mut indep = Baker::new(&scene).unwrap();
    indep.stratified_lights = false;
    for (d, most) in [(3.0 * SPHERE_LIGHT_RADIUS, 0.5), (2.0, 0.75)] {
        let x = near_lamp(d);
        let (ms, vs) = noise(&strat, x, 128, 24);
        let (mi, vi) = noise(&indep, x, 128, 24);
        // Means agree within a few standard errors of the independent one's.
        let diff = energy(&ms, &mi) / energy(&mi, &ShRgb::zeros(3));
        assert!(diff < 9.0 * vi / 24.0 + 1e-4, "{d} m: {diff} {vi}");
        assert!(vs < most * vi, "{d} m: stratified {vs} independent {vi}");
    }
}

/// The relative noise of captures at several sample counts, stratified and
/// independent, at points 0.3 to 2 m from the demo's lamp (run with
/// `--ignored --nocapture`; BENCHMARKS.md, "Where a bake's time goes").
#[test]
#[ignore]
fn measure_capture_noise_by_sample_count() {
    let scene = Scene::builtin_demo();
    let strat = Baker::new(&scene).unwrap();
    let mut indep = Baker::new(&scene).unwrap();
    indep.stratified_lights = false;
    for d in [0.3, 0.6, 1.0, 2.0] {
        let x = near_lamp(d);
        let mut row = format!("d = {d} m:");
        for n in [64, 128, 256, 512] {
            let (_, vs) = noise(&strat, x, n, 16);
            let (_, vi) = noise(&indep, x, n, 16);
            row += &format!("  {n}: strat {vs:.2e} indep {vi:.2e}");
        }
        println!("{row}");
    }
}
