//! Fitted per-probe blend weights (`PWGT`): each probe of a cloud gets a
//! weight `s_i > 0` that multiplies its blend weight before the
//! renormalization ([`ProbeCloud::set_probe_weights`](probekit_runtime::cloud::ProbeCloud::set_probe_weights)), fitted so that the
//! cloud predicts the light at path-traced *training points* better.
//!
//! **Why.** Visibility (distance moments, cell bits) drops the probes that
//! do not see a point. What is left are leaks *in sight*: a probe standing in
//! a doorway sees a lit corridor and carries its light into the dark closet
//! behind the wall's edge, though it sees the point (`leak_diag` column (e):
//! 27 of the 30 closet leaks of 525-probe demo clouds). A global rule — divide
//! by brightness, [`ProbeCloud::set_brightness_weighting`](probekit_runtime::cloud::ProbeCloud::set_brightness_weighting) — removes them but
//! flattens the gradients next to lights everywhere; a weight per probe,
//! fitted to data, lowers the doorway probe and leaves the others alone.
//!
//! **The blend stays what the runtime and shaders do**: a convex
//! combination of SH, continuous across faces (on a face the fourth probe's
//! barycentric weight is 0, so per-probe factors agree on both sides) and
//! exact for a constant field; it costs one multiply per probe per query.
//! This is our own method, not from a paper; the closest published idea is
//! DDGI's per-probe "probe relocation/state" (Majercik et al. 2021), which
//! switches probes off rather than weighting them.
//!
//! **Training points** ([`capture_training_set`]): `points_per_probe × P`
//! points in free space (at least 1 cm from surfaces), from their own seed
//! stream: half drawn like `probekit eval`'s (uniform in the bake box), half
//! uniform in tetrahedra chosen uniformly, so that every cell, the small
//! ones next to lights included, has evidence; captured as radiance SH with
//! the bake's light transport at [`BlendFitSettings::samples`].
//!
//! **Objective** ([`fit_probe_weights`]), over the training points `j`:
//!
//! ```text
//! J(t) = (1/N) Σ_j ‖Ê_j(s) − E_j‖² · ( 1/(‖E_j‖ + 0.01·mean_k ‖E_k‖)²  +  β/mean_k ‖E_k‖² )  +  ρ Σ_i t_i²
//! s_i = e^{t_i}
//! ```
//!
//! `‖·‖` is the root-mean-square over all normals of the irradiance of the
//! SH (`Σ_lm A_l² |c_lm|²`, `A_l` the clamped-cosine band factors, over 4π),
//! `Ê_j(s)` the blend with weights `s` and `E_j` the captured point. The
//! first term is the squared *relative* error, so every point counts alike
//! and a dark closet's points weigh as much as the bright ones next to a
//! light (the floor is `probekit eval`'s, 1 % of the mean); the second,
//! weighted by `β` ([`BlendFitSettings::absolute_weight`]), is the squared
//! error relative to the mean, what `rel_rmse` measures, so that fixing the
//! dark points does not cost the bright ones. `ρ`
//! ([`BlendFitSettings::regularization`]) keeps probes without evidence at a
//! weight of one. The minimizer is cyclic coordinate descent on `t_i` over a shrinking
//! grid of steps (9 trial values per probe and sweep), `t_i ∈
//! [`[`LOG_WEIGHT_MIN`]`, `[`LOG_WEIGHT_MAX`]`]`; each trial re-evaluates
//! only the points whose cell holds the probe, from a 4 × 4 Gram matrix per
//! point (the squared error is a quadratic form in the normalized weights).
//! Sequential and deterministic.
//!
//! **With run-time lights** ([`TrainingSet::lights`]): a file that leaves
//! small lights to an exact run-time term is fitted on the answer a query
//! gives, not on its SH part: each probe's prediction at a point is its SH
//! plus each run-time light's radiance SH there
//! ([`probekit_runtime::rig::Light::add_sh`]) times the probe's visible
//! fraction of it, and the truth is the point's SH part plus the direct light
//! of those lights its capture reported apart ([`TrainingSet::excluded`]).
//! Each point's weight in the objective (the scales above) still comes from
//! its SH part: scaled by the combined light, the points beside a lamp
//! would count for little and the objective would lean on its relative
//! term. Measured (default demo bake, 6 000 points of three seeds): 0.071
//! against 0.073 fitted on the SH part; FZK-Haus adaptive ~500: 0.082 both;
//! scaled by the combined light, 0.074 and 0.087.
//!
//! **The brightness exponent** ([`fit_blend`]): the weights can be fitted
//! for a blend that also divides each probe's weight by its mean
//! brightness to the power `α` ([`ProbeCloud::set_brightness_weighting`](probekit_runtime::cloud::ProbeCloud::set_brightness_weighting):
//! in a cell where one probe sees light the others do not, it counts
//! less). `probekit bake` fits them for `α` = 0, 0.5 and 1
//! ([`BRIGHTNESS_CHOICES`]) and keeps the exponent whose fits predict
//! held-out training points best under the same objective (two-fold
//! cross-validation), among those that do not raise the held-out absolute
//! error by more than 1 % ([`BRIGHTNESS_ABSOLUTE_TOLERANCE`]), and stores it
//! with the weights.
//!
//! Measured in BENCHMARKS.md ("Fitted probe weights", "The brightness
//! exponent, fitted with the probe weights").

mod exponent;
#[cfg(test)]
mod tests;
mod training;
mod weights;

pub use exponent::{
    fit_blend, fit_file_probe_weights, FittedBlend, BRIGHTNESS_ABSOLUTE_TOLERANCE,
    BRIGHTNESS_CHOICES, DEFAULT_DIRECTIONAL,
};
pub use training::{capture_training_points, capture_training_set, TrainingSet};
pub use weights::fit_probe_weights;

use crate::capture::BakeError;
use probekit_runtime::cloud::{ProbeCloudError, MAX_BRIGHTNESS_EXPONENT};
use thiserror::Error;

/// Smallest fitted log-weight `t_i` (`s_i = e^t ≈ 9·10⁻⁴`).
pub const LOG_WEIGHT_MIN: f32 = -7.0;

/// Largest fitted log-weight `t_i` (`s_i = e^t ≈ 20`).
pub const LOG_WEIGHT_MAX: f32 = 3.0;

/// Training points per probe by default (the recipe's
/// `blend.fit.points_per_probe`): with 32, and with the 128 samples of
/// the fit before stratified light samples, the demo's default bake and
/// its 500-probe grid had no lower `rel_rmse` (BENCHMARKS.md, "Where a
/// bake's time goes").
pub const DEFAULT_POINTS_PER_PROBE: u32 = 16;

/// Samples per training point by default (the recipe's
/// `blend.fit.samples`; see [`DEFAULT_POINTS_PER_PROBE`]).
pub const DEFAULT_FIT_SAMPLES: u32 = 64;

/// Default `ρ` of the objective (see the module docs).
pub const DEFAULT_REGULARIZATION: f32 = 1e-5;

/// Default `β` of the objective (see the module docs).
pub const DEFAULT_ABSOLUTE_WEIGHT: f32 = 1.0;

/// How to fit probe weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlendFitSettings {
    /// Training points per probe (≥ 1).
    pub points_per_probe: u32,
    /// Path-traced samples per training point (≥ 1).
    pub samples: u32,
    /// `ρ` of the objective (≥ 0, finite).
    pub regularization: f32,
    /// `β` of the objective (≥ 0, finite): the weight of the absolute
    /// squared error (relative to the mean squared irradiance) beside the
    /// relative one.
    pub absolute_weight: f32,
    /// Seed of the training points' positions (their capture uses the
    /// capture settings' seed).
    pub seed: u64,
    /// Brightness exponent `α` to fit the weights for
    /// ([`ProbeCloud::set_brightness_weighting`](probekit_runtime::cloud::ProbeCloud::set_brightness_weighting), `0..=4`); `None` (the
    /// default, `probekit bake --brightness-weight auto`): choose one of
    /// [`BRIGHTNESS_CHOICES`] by cross-validation ([`fit_blend`]).
    pub brightness: Option<f32>,
    /// Directional brightness exponent `γ` the cloud blends with on top of
    /// the fitted weights ([`ProbeCloud::set_directional_brightness`](probekit_runtime::cloud::ProbeCloud::set_directional_brightness),
    /// `0..=4`; default [`DEFAULT_DIRECTIONAL`]). Not fitted for: see
    /// [`DEFAULT_DIRECTIONAL`].
    pub directional: f32,
}

impl BlendFitSettings {
    /// The defaults with `seed`.
    pub fn new(seed: u64) -> Self {
        Self {
            points_per_probe: DEFAULT_POINTS_PER_PROBE,
            samples: DEFAULT_FIT_SAMPLES,
            regularization: DEFAULT_REGULARIZATION,
            absolute_weight: DEFAULT_ABSOLUTE_WEIGHT,
            seed,
            brightness: None,
            directional: DEFAULT_DIRECTIONAL,
        }
    }

    /// The exponents the fit chooses from: the fixed one, or
    /// [`BRIGHTNESS_CHOICES`].
    pub fn exponents(&self) -> Vec<f32> {
        self.brightness
            .map_or(BRIGHTNESS_CHOICES.to_vec(), |a| vec![a])
    }

    /// The settings as `probekit bake` records them in the metadata.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "points_per_probe": self.points_per_probe,
            "samples": self.samples,
            "regularization": self.regularization,
            "absolute_weight": self.absolute_weight,
            "seed": self.seed,
            "brightness": self.brightness.map_or(serde_json::json!("auto"), |a| serde_json::json!(a)),
            "directional": self.directional,
        })
    }

    /// Settings as [`BlendFitSettings::to_json`] wrote them, each field
    /// falling back to `fallback`'s when absent or out of range.
    pub fn from_json(v: &serde_json::Value, fallback: &Self) -> Self {
        let u32_of = |k: &str| {
            v[k].as_u64()
                .filter(|&x| x > 0 && x <= u32::MAX as u64)
                .map(|x| x as u32)
        };
        Self {
            points_per_probe: u32_of("points_per_probe").unwrap_or(fallback.points_per_probe),
            samples: u32_of("samples").unwrap_or(fallback.samples),
            regularization: v["regularization"]
                .as_f64()
                .map(|x| x as f32)
                .filter(|x| *x >= 0.0 && x.is_finite())
                .unwrap_or(fallback.regularization),
            absolute_weight: v["absolute_weight"]
                .as_f64()
                .map(|x| x as f32)
                .filter(|x| *x >= 0.0 && x.is_finite())
                .unwrap_or(fallback.absolute_weight),
            seed: v["seed"].as_u64().unwrap_or(fallback.seed),
            brightness: match &v["brightness"] {
                serde_json::Value::String(a) if a == "auto" => None,
                x => x
                    .as_f64()
                    .map(|x| x as f32)
                    .filter(|x| (0.0..=MAX_BRIGHTNESS_EXPONENT).contains(x))
                    .map_or(fallback.brightness, Some),
            },
            directional: v["directional"]
                .as_f64()
                .map(|x| x as f32)
                .filter(|x| (0.0..=MAX_BRIGHTNESS_EXPONENT).contains(x))
                .unwrap_or(fallback.directional),
        }
    }

    fn validate(&self) -> Result<(), BlendFitError> {
        if self.points_per_probe == 0 {
            return Err(BlendFitError::Settings(
                "points per probe must be at least 1",
            ));
        }
        if self.samples == 0 {
            return Err(BlendFitError::Settings("samples must be at least 1"));
        }
        if !(self.regularization >= 0.0 && self.regularization.is_finite()) {
            return Err(BlendFitError::Settings(
                "regularization must be a finite number ≥ 0",
            ));
        }
        if !(self.absolute_weight >= 0.0 && self.absolute_weight.is_finite()) {
            return Err(BlendFitError::Settings(
                "absolute weight must be a finite number ≥ 0",
            ));
        }
        if self
            .brightness
            .is_some_and(|a| !(0.0..=MAX_BRIGHTNESS_EXPONENT).contains(&a))
        {
            return Err(BlendFitError::Settings(
                "brightness exponent must lie in 0 to 4",
            ));
        }
        if !(0.0..=MAX_BRIGHTNESS_EXPONENT).contains(&self.directional) {
            return Err(BlendFitError::Settings(
                "directional brightness exponent must lie in 0 to 4",
            ));
        }
        Ok(())
    }
}

/// Why probe weights cannot be fitted.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum BlendFitError {
    /// A setting is out of range.
    #[error("probe weight fit: {0}")]
    Settings(&'static str),
    /// Capturing the training points failed.
    #[error("probe weight fit: training points: {0}")]
    Capture(#[from] BakeError),
    /// The cloud cannot be built from the file.
    #[error("probe weight fit: {0}")]
    Cloud(#[from] ProbeCloudError),
    /// Training positions and SH differ in count, or an SH's order differs
    /// from the cloud's.
    #[error("probe weight fit: {0}")]
    Mismatch(&'static str),
    /// No training point fell in free space of the bake box.
    #[error("probe weight fit: no training point in free space of the bake box")]
    NoTrainingPoints,
}
