//! The brightness exponent chosen with the weights (two-fold
//! cross-validation over [`BRIGHTNESS_CHOICES`]), and the fit of a whole
//! cloud file.

use super::training::{capture_training_set, TrainingSet};
use super::weights::{check, descend, factors, fit_weights, rows, solve, Row};
use super::{BlendFitError, BlendFitSettings};
use crate::capture::{Baker, CaptureSettings};
use crate::scene::Aabb;
use probekit_runtime::cloud::{ProbeCloud, MAX_BRIGHTNESS_EXPONENT};
use rayon::prelude::*;

/// Brightness exponents [`fit_blend`] chooses from by default (`probekit
/// bake --brightness-weight auto`): the plain blend, and the blends between
/// it and the harmonic mean ([`ProbeCloud::set_brightness_weighting`]).
pub const BRIGHTNESS_CHOICES: [f32; 3] = [0.0, 0.5, 1.0];

/// The directional brightness exponent `γ` `probekit bake` stores with the
/// weights by default ([`ProbeCloud::set_directional_brightness`]): applied
/// on top of weights fitted for the blend without it, a deliberate bias
/// against leaks. Measured on builtin:demo (BENCHMARKS.md, "Directional
/// brightness"): at ~500 probes it removes the closet leaks of all five
/// placements, and rel_rmse falls 1 %; 0.25 left one closet leak, 1 raised
/// rel_rmse. Weights fitted *for* the directional blend (the fit's error
/// per direction) brought the leaks back — the fit raises the doorway
/// probes again until its objective, which counts no leaks, is at its
/// minimum — so it is not part of the fit.
pub const DEFAULT_DIRECTIONAL: f32 = 0.5;

/// A fitted blend: the brightness exponent `α` the cloud should blend with
/// and the probe weights fitted for it.
#[derive(Clone, Debug, PartialEq)]
pub struct FittedBlend {
    /// Probe weights `s_i`, one per probe (see [`fit_probe_weights`](super::fit_probe_weights)).
    pub weights: Vec<f32>,
    /// The brightness exponent `α` they were fitted with
    /// ([`ProbeCloud::set_brightness_weighting`]).
    pub brightness: f32,
    /// The directional brightness exponent `γ` the cloud blends with on top
    /// of them ([`BlendFitSettings::directional`], not fitted for).
    pub directional: f32,
    /// How the exponent was chosen: with several to choose from, its
    /// two-fold cross-validated score (mean scaled squared error of held-out
    /// training points, [`fit_blend`]); with one, the objective `J` at the
    /// fitted weights (see the module docs: that error plus the
    /// regularization); 0 without training points.
    pub objective: f64,
}

/// Most an exponent may raise the held-out absolute error (what `rel_rmse`
/// measures) over the lowest of the candidates' and still be chosen by
/// [`fit_blend`]: 1 %.
pub const BRIGHTNESS_ABSOLUTE_TOLERANCE: f64 = 0.01;

/// Chooses the brightness exponent `α` from `exponents` (each in
/// `0..=`[`probekit_runtime::cloud::MAX_BRIGHTNESS_EXPONENT`]) by two-fold
/// cross-validation, then fits probe weights for it on all training points.
/// For each `α`, weights are fitted on the even-numbered training points and
/// scored on the odd-numbered ones, and the other way round, twice: by the
/// module docs' objective (relative plus `β` times absolute squared error)
/// and by the absolute squared error alone (relative to the mean squared
/// irradiance: what `rel_rmse` measures). Of the exponents whose absolute
/// score is within [`BRIGHTNESS_ABSOLUTE_TOLERANCE`] of the lowest, the one
/// with the lowest objective score wins (ties: the first). Held-out scores,
/// not the fit's own objective: the harmonic blend, with more freedom to fit
/// the training points, would otherwise be chosen for fitting them rather
/// than for predicting the points between them. And the tolerance because
/// the objective's relative term can favour an exponent that fixes dark
/// points (leaks) at the cost of the bright ones: measured, on the demo the
/// exponents' absolute scores are within 1 % (mostly 0.5 %) and the
/// objective's choice (mostly `α` = 1) halves the closet leaks at ~500
/// probes; in the Cornell box `α` = 1 lowers the
/// objective by 1–4 % and raises `rel_rmse` by 1–3 %, which the tolerance
/// refuses. With one exponent, no cross-validation. `cloud`'s own exponents
/// and probe weights are ignored: the weights are fitted without directional
/// brightness, which `fit.directional` puts on top
/// ([`DEFAULT_DIRECTIONAL`]). Errors as [`fit_probe_weights`](super::fit_probe_weights), and
/// [`BlendFitError::Settings`] on an empty list or an exponent out of range.
/// Deterministic.
pub fn fit_blend(
    cloud: &ProbeCloud,
    training: &TrainingSet,
    fit: &BlendFitSettings,
    exponents: &[f32],
) -> Result<FittedBlend, BlendFitError> {
    if exponents.is_empty() {
        return Err(BlendFitError::Settings(
            "no brightness exponent to choose from",
        ));
    }
    if exponents
        .iter()
        .any(|a| !(0.0..=MAX_BRIGHTNESS_EXPONENT).contains(a))
    {
        return Err(BlendFitError::Settings(
            "brightness exponent must lie in 0 to 4",
        ));
    }
    check(cloud, training, fit)?;
    let with = |alpha: f32| -> Result<ProbeCloud, BlendFitError> {
        let mut c = cloud.clone();
        c.set_brightness_weighting(alpha)?;
        c.set_directional_brightness(0.0)?;
        Ok(c)
    };
    if exponents.len() == 1 || training.positions.len() < 2 {
        return Ok(fit_weights(&with(exponents[0])?, training, fit));
    }
    let beta = fit.absolute_weight as f64;
    let rho = fit.regularization as f64;
    let nprobes = cloud.probe_count();
    let n = training.positions.len() as f64;
    // Per exponent: its rows, held-out objective score, held-out absolute
    // score. The exponents and folds are independent descents, run in
    // parallel; each is sequential, so the result is the same for any
    // thread count.
    let candidates: Vec<(Vec<Row>, f64, f64)> = exponents
        .par_iter()
        .map(|&alpha| -> Result<_, BlendFitError> {
            let (rows, to_absolute) = rows(&with(alpha)?, training, beta);
            let fold = |k: usize| -> Vec<f64> {
                let part: Vec<Row> = rows.iter().skip(k).step_by(2).cloned().collect();
                descend(&part, nprobes, rho)
                    .iter()
                    .map(|&x| (x as f64).exp())
                    .collect()
            };
            let (even, odd) = rayon::join(|| fold(0), || fold(1));
            // Weights fitted on one fold score the other; a row's error is
            // linear in its Gram matrix, so the absolute score rescales it.
            let (mut objective, mut absolute) = (0.0, 0.0);
            for (j, r) in rows.iter().enumerate() {
                let e = r.error(factors(r, if j % 2 == 0 { &odd } else { &even }));
                objective += e;
                absolute += e * to_absolute[j];
            }
            Ok((rows, objective / n, absolute / n))
        })
        .collect::<Result<_, _>>()?;
    let mut candidates = candidates;
    let lowest = candidates.iter().map(|c| c.2).fold(f64::INFINITY, f64::min);
    let best = (0..candidates.len())
        .filter(|&i| candidates[i].2 <= lowest * (1.0 + BRIGHTNESS_ABSOLUTE_TOLERANCE))
        .min_by(|&a, &b| candidates[a].1.total_cmp(&candidates[b].1))
        .unwrap_or(0);
    let (rows, score, _) = candidates.swap_remove(best);
    let (t, _) = solve(&rows, nprobes, rho);
    Ok(FittedBlend {
        weights: t.iter().map(|&x| x.exp()).collect(),
        brightness: exponents[best],
        directional: fit.directional,
        objective: score,
    })
}

/// Fits the blend of a cloud file: builds its [`ProbeCloud`] (with the
/// visibility data it holds), captures `fit.points_per_probe ×` probes
/// training points ([`capture_training_set`]) and fits probe weights for
/// `fit.brightness`, or for each of [`BRIGHTNESS_CHOICES`] keeping the best
/// ([`fit_blend`]); with the file's run-time lights, on the combined answer
/// ([`TrainingSet::lights`]; `capture` must then capture all light).
/// `probekit bake` stores the result as the file's `PWGT` section: the
/// weights, and the exponent in its header.
pub fn fit_file_probe_weights(
    baker: &Baker,
    file: &probekit_runtime::format::ProbeFile,
    bake_box: &Aabb,
    capture: &CaptureSettings,
    fit: &BlendFitSettings,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<FittedBlend, BlendFitError> {
    fit.validate()?;
    let cloud = ProbeCloud::from_file(file)?;
    let count = (fit.points_per_probe as usize).saturating_mul(cloud.probe_count());
    let mut training =
        capture_training_set(baker, bake_box, cloud.mesh(), count, capture, fit, progress)?;
    training.lights = file.probes().and_then(|p| p.runtime_lights.clone());
    fit_blend(&cloud, &training, fit, &fit.exponents())
}
