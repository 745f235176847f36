//! The probe-weight fit: per training point a Gram matrix of the blend's
//! errors, and cyclic coordinate descent on the log-weights (the objective
//! of [`super`]).

use super::training::TrainingSet;
use super::{BlendFitError, BlendFitSettings, FittedBlend, LOG_WEIGHT_MAX, LOG_WEIGHT_MIN};
use glam::Vec3;
use probekit_runtime::cloud::{ProbeCloud, WalkState};
use probekit_runtime::format::RuntimeLights;
use probekit_sh::convolve::clamped_cosine_band;
use rayon::prelude::*;

/// Step sizes of the coordinate-descent sweeps, in `t`.
const SWEEP_STEPS: [f32; 6] = [1.0, 0.5, 0.25, 0.25, 0.125, 0.0625];

/// One training point as the fit sees it: the cell's probes, their blend
/// weights without probe weights (normalized), and the Gram matrix of the
/// probes' irradiance errors `G_kl = ⟨C_k − E, C_l − E⟩` (band-weighted SH
/// inner product), divided by the point's squared relative-error scale.
#[derive(Clone)]
pub(super) struct Row {
    probes: [u32; 4],
    w: [f32; 4],
    /// Upper triangle of `G` (00 01 02 03 11 12 13 22 23 33), already scaled.
    g: [f64; 10],
}

impl Row {
    /// Scaled squared error of the blend with per-probe factors `f`.
    pub(super) fn error(&self, f: [f64; 4]) -> f64 {
        let mut a = [0.0f64; 4];
        let mut sum = 0.0;
        for k in 0..4 {
            a[k] = self.w[k] as f64 * f[k];
            sum += a[k];
        }
        if sum <= 0.0 {
            return 0.0;
        }
        let a = a.map(|x| x / sum);
        let g = &self.g;
        a[0] * a[0] * g[0]
            + a[1] * a[1] * g[4]
            + a[2] * a[2] * g[7]
            + a[3] * a[3] * g[9]
            + 2.0
                * (a[0] * (a[1] * g[1] + a[2] * g[2] + a[3] * g[3])
                    + a[1] * (a[2] * g[5] + a[3] * g[6])
                    + a[2] * a[3] * g[8])
    }
}

/// Fits one weight per probe of `cloud` to the training points (see the
/// module docs for the objective); `cloud` blends as it is set up
/// (visibility, cell bits, brightness), except for probe weights it may
/// already have, which are ignored. Returns `s_i = e^{t_i}`, one per probe,
/// in `[e^`[`LOG_WEIGHT_MIN`]`, e^`[`LOG_WEIGHT_MAX`]`]`; a probe no
/// training point blends keeps 1. Deterministic.
pub fn fit_probe_weights(
    cloud: &ProbeCloud,
    training: &TrainingSet,
    fit: &BlendFitSettings,
) -> Result<Vec<f32>, BlendFitError> {
    check(cloud, training, fit)?;
    Ok(fit_weights(cloud, training, fit).weights)
}

/// The input checks of [`fit_probe_weights`] and [`fit_blend`].
pub(super) fn check(
    cloud: &ProbeCloud,
    training: &TrainingSet,
    fit: &BlendFitSettings,
) -> Result<(), BlendFitError> {
    if training.positions.len() != training.sh.len() {
        return Err(BlendFitError::Mismatch(
            "training positions and SH differ in count",
        ));
    }
    fit.validate()?;
    let n = cloud.coeffs_per_probe();
    if training.sh.iter().any(|s| s.coeffs().len() < n) {
        return Err(BlendFitError::Mismatch(
            "a training point has fewer SH bands than the cloud",
        ));
    }
    if !training.excluded.is_empty() && training.excluded.len() != training.positions.len() {
        return Err(BlendFitError::Mismatch(
            "training points and their excluded direct light differ in count",
        ));
    }
    if (training.lights.as_ref()).is_some_and(|l| l.occlusion.probe_count() != cloud.probe_count())
    {
        return Err(BlendFitError::Mismatch(
            "the run-time lights' occlusion table has another probe count than the cloud",
        ));
    }
    Ok(())
}

/// [`fit_probe_weights`] after validation, with the objective, for the
/// exponent `cloud` is set to.
pub(super) fn fit_weights(
    cloud: &ProbeCloud,
    training: &TrainingSet,
    fit: &BlendFitSettings,
) -> FittedBlend {
    let nprobes = cloud.probe_count();
    if training.positions.is_empty() {
        return FittedBlend {
            weights: vec![1.0; nprobes],
            brightness: cloud.brightness_weighting(),
            directional: fit.directional,
            objective: 0.0,
        };
    }
    let (rows, _) = rows(cloud, training, fit.absolute_weight as f64);
    let (t, objective) = solve(&rows, nprobes, fit.regularization as f64);
    FittedBlend {
        weights: t.iter().map(|&x| x.exp()).collect(),
        brightness: cloud.brightness_weighting(),
        directional: fit.directional,
        objective,
    }
}

/// [`descend`] on `rows`, with the objective `J` at its result: the rows'
/// mean error plus `rho Σ t_i²`.
pub(super) fn solve(rows: &[Row], nprobes: usize, rho: f64) -> (Vec<f32>, f64) {
    let t = descend(rows, nprobes, rho);
    let s: Vec<f64> = t.iter().map(|&x| (x as f64).exp()).collect();
    let objective = rows.iter().map(|r| r.error(factors(r, &s))).sum::<f64>() / rows.len() as f64
        + rho * t.iter().map(|&x| (x as f64).powi(2)).sum::<f64>();
    (t, objective)
}

/// The training points as [`Row`]s of `cloud`'s plain blend (probe weights
/// off), each point's Gram matrix scaled by its relative-error scale plus
/// `beta` over the mean squared irradiance (see the module docs); and per
/// row, the factor that turns its error into the absolute error alone (the
/// inverse mean squared irradiance over the row's scale).
pub(super) fn rows(cloud: &ProbeCloud, training: &TrainingSet, beta: f64) -> (Vec<Row>, Vec<f64>) {
    let n = cloud.coeffs_per_probe();
    let order = (n as f64).sqrt() as usize;
    let mut plain = cloud.clone();
    plain.set_probe_weighting(false);
    // A_l² per coefficient.
    let band: Vec<f64> = (0..n)
        .map(|c| {
            let l = (c as f64).sqrt() as usize;
            clamped_cosine_band(l).powi(2)
        })
        .collect();
    let norm = |v: &[Vec3]| -> f64 {
        v.iter()
            .zip(&band)
            .map(|(x, b)| b * x.length_squared() as f64)
            .sum::<f64>()
            .sqrt()
    };
    // The cloud's bands of each training point (a codec may store fewer).
    let truth = |j: usize| &training.sh[j].coeffs()[..n];
    let count = training.sh.len() as f64;
    let mean = (0..training.sh.len()).map(|j| norm(truth(j))).sum::<f64>() / count;
    let mean_square = ((0..training.sh.len())
        .map(|j| norm(truth(j)).powi(2))
        .sum::<f64>()
        / count)
        .max(1e-30);
    let floor = 0.01 * mean;
    // Each point's row on its own: in parallel, chunks in order.
    let row = |j: usize, p: Vec3, ws: &mut WalkState| -> (Row, f64) {
        let (probes, w) = plain.weights_at(p, ws);
        let scale = 1.0 / (norm(truth(j)) + floor).powi(2).max(1e-30) + beta / mean_square;
        // What the prediction is compared with: with the run-time lights,
        // the light the capture left out too.
        let e: Vec<Vec3> = match (training.lights.as_ref(), training.excluded.get(j)) {
            (Some(_), Some(x)) => truth(j)
                .iter()
                .zip(x.coeffs())
                .map(|(a, b)| *a + *b)
                .collect(),
            _ => truth(j).to_vec(),
        };
        let e = &e[..];
        let d: [Vec<Vec3>; 4] = core::array::from_fn(|k| {
            if w[k] > 0.0 {
                let i = probes[k] as usize;
                let mut c = plain.probe_sh(i).to_vec();
                add_runtime_lights(training.lights.as_ref(), i, p, order, &mut c);
                c.iter().zip(e).map(|(a, b)| *a - *b).collect()
            } else {
                vec![Vec3::ZERO; n]
            }
        });
        let dot = |a: &[Vec3], b: &[Vec3]| -> f64 {
            a.iter()
                .zip(b)
                .zip(&band)
                .map(|((x, y), bw)| bw * x.dot(*y) as f64)
                .sum::<f64>()
                * scale
        };
        let mut g = [0.0f64; 10];
        let mut i = 0;
        for k in 0..4 {
            for l in k..4 {
                g[i] = dot(&d[k], &d[l]);
                i += 1;
            }
        }
        (Row { probes, w, g }, 1.0 / mean_square / scale)
    };
    const CHUNK: usize = 256;
    training
        .positions
        .par_chunks(CHUNK)
        .enumerate()
        .flat_map_iter(|(c, pts)| {
            let mut ws = WalkState::new();
            pts.iter()
                .enumerate()
                .map(|(k, p)| row(c * CHUNK + k, *p, &mut ws))
                .collect::<Vec<_>>()
        })
        .unzip()
}

/// Adds to probe `i`'s SH `c` what the runtime adds for it at `p`: each
/// run-time light's radiance SH at `p` times the probe's visible fraction
/// of it (the combined answer of [`TrainingSet::lights`]).
fn add_runtime_lights(
    lights: Option<&RuntimeLights>,
    i: usize,
    p: Vec3,
    order: usize,
    c: &mut [Vec3],
) {
    let Some(rl) = lights else { return };
    for &[l, v] in rl.occlusion.probe(i) {
        if let Some(light) = rl.lights.get(l as usize) {
            light.light.add_sh(order, p, v as f32 / 255.0, c);
        }
    }
}

/// Per-slot factors of `r` for probe weights `s`.
pub(super) fn factors(r: &Row, s: &[f64]) -> [f64; 4] {
    core::array::from_fn(|k| {
        if r.w[k] > 0.0 {
            s[r.probes[k] as usize]
        } else {
            1.0
        }
    })
}

/// Cyclic coordinate descent on `t`: minimizes the rows' mean error plus
/// `rho Σ t_i²` (see the module docs).
pub(super) fn descend(rows: &[Row], nprobes: usize, rho: f64) -> Vec<f32> {
    // Points by probe (CSR), for the local re-evaluation.
    let mut start = vec![0usize; nprobes + 1];
    for r in rows {
        for k in 0..4 {
            if r.w[k] > 0.0 {
                start[r.probes[k] as usize + 1] += 1;
            }
        }
    }
    for i in 0..nprobes {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut members = vec![0u32; start[nprobes]];
    for (j, r) in rows.iter().enumerate() {
        for k in 0..4 {
            if r.w[k] > 0.0 {
                let i = r.probes[k] as usize;
                members[fill[i]] = j as u32;
                fill[i] += 1;
            }
        }
    }
    // Σ errors + rho·N·Σ t²: the mean error's minimizer.
    let rho = rho * rows.len() as f64;
    let mut t = vec![0.0f32; nprobes];
    let mut s = vec![1.0f64; nprobes];
    for step in SWEEP_STEPS {
        for i in 0..nprobes {
            let mine = &members[start[i]..start[i + 1]];
            if mine.is_empty() {
                continue;
            }
            let t0 = t[i];
            let mut best = (f64::INFINITY, t0);
            for k in -4i32..=4 {
                let ti = (t0 + k as f32 * step).clamp(LOG_WEIGHT_MIN, LOG_WEIGHT_MAX);
                s[i] = (ti as f64).exp();
                let c = mine
                    .iter()
                    .map(|&j| {
                        let r = &rows[j as usize];
                        r.error(factors(r, &s))
                    })
                    .sum::<f64>()
                    + rho * (ti as f64).powi(2);
                if c < best.0 {
                    best = (c, ti);
                }
            }
            t[i] = best.1;
            s[i] = (best.1 as f64).exp();
        }
    }
    t
}
