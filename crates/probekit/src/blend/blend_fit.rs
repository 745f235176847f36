//! Fitted per-probe blend weights (`PWGT`): each probe of a cloud gets a
//! weight `s_i > 0` that multiplies its blend weight before the
//! renormalization ([`ProbeCloud::set_probe_weights`]), fitted so that the
//! cloud predicts the light at path-traced *training points* better.
//!
//! **Why.** Visibility (distance moments, cell bits) drops the probes that
//! do not see a point. What is left are leaks *in sight*: a probe standing in
//! a doorway sees a lit corridor and carries its light into the dark closet
//! behind the wall's edge, though it sees the point (`leak_diag` column (e):
//! 27 of the 30 closet leaks of 525-probe demo clouds). A global rule — divide
//! by brightness, [`ProbeCloud::set_brightness_weighting`] — removes them but
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
//! **The brightness exponent** ([`fit_blend`]): the weights can be fitted
//! for a blend that also divides each probe's weight by its mean
//! brightness to the power `α` ([`ProbeCloud::set_brightness_weighting`]:
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

use crate::capture::{BakeError, Baker, CaptureSettings};
use crate::sampling::SampleRng;
use crate::scene::Aabb;
use crate::trace::free_space::{is_free, sample_points, SURFACE_CLEARANCE};
use glam::Vec3;
use probekit_runtime::cloud::{
    ProbeCloud, ProbeCloudError, TetMesh, WalkState, MAX_BRIGHTNESS_EXPONENT,
};
use probekit_sh::convolve::clamped_cosine_band;
use probekit_sh::ShRgb;
use thiserror::Error;

/// Smallest fitted log-weight `t_i` (`s_i = e^t ≈ 9·10⁻⁴`).
pub const LOG_WEIGHT_MIN: f32 = -7.0;
/// Largest fitted log-weight `t_i` (`s_i = e^t ≈ 20`).
pub const LOG_WEIGHT_MAX: f32 = 3.0;
/// Training points per probe by default.
pub const DEFAULT_POINTS_PER_PROBE: u32 = 32;
/// Samples per training point by default.
pub const DEFAULT_FIT_SAMPLES: u32 = 128;
/// Default `ρ` of the objective (see the module docs).
pub const DEFAULT_REGULARIZATION: f32 = 1e-5;
/// Default `β` of the objective (see the module docs).
pub const DEFAULT_ABSOLUTE_WEIGHT: f32 = 1.0;
/// Seed stream of the training points (`"wfit"`), apart from `probekit
/// eval`'s points of the same seed.
const TRAINING_STREAM: u64 = 0x7766_6974;
/// Stream of the per-cell training points' random numbers.
const CELL_STREAM: u64 = 0x6365_6c6c; // "cell"
/// Capture index of the first training point: far above any probe's, so
/// training points never share a probe's random numbers.
const TRAINING_INDEX: usize = 1 << 32;
/// Step sizes of the coordinate-descent sweeps, in `t`.
const SWEEP_STEPS: [f32; 6] = [1.0, 0.5, 0.25, 0.25, 0.125, 0.0625];

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
    /// ([`ProbeCloud::set_brightness_weighting`], `0..=4`); `None` (the
    /// default, `probekit bake --brightness-weight auto`): choose one of
    /// [`BRIGHTNESS_CHOICES`] by cross-validation ([`fit_blend`]).
    pub brightness: Option<f32>,
    /// Directional brightness exponent `γ` the cloud blends with on top of
    /// the fitted weights ([`ProbeCloud::set_directional_brightness`],
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

/// Captured training points: positions (metres) and their radiance SH.
#[derive(Clone, Debug, PartialEq)]
pub struct TrainingSet {
    /// Where each point was captured.
    pub positions: Vec<Vec3>,
    /// Radiance SH at each point (all light, or indirect only, as the cloud
    /// stores).
    pub sh: Vec<ShRgb>,
}

/// Draws `count` training points in free space of `bake_box` (seeded by
/// `fit.seed`) and captures them with `capture` at `fit.samples` samples:
/// all light, or indirect light only when `capture.split_direct` (the
/// convention of [`crate::placement::sweep::bake_cloud`]: what `bake
/// --indirect-only` stores). Half are uniform in the box, as `probekit eval`'s points; the
/// other half are uniform in tetrahedra of `mesh` chosen uniformly (not by
/// volume), so every cell has evidence and small cells — where adaptive
/// placement packed probes, next to lights — are sampled densely: a fit that
/// only saw uniform points could shift weight onto a probe beside a light
/// where no point would show the overshoot. `progress(done, total)` counts
/// points. Deterministic (any thread count).
pub fn capture_training_set(
    baker: &Baker,
    bake_box: &Aabb,
    mesh: &TetMesh,
    count: usize,
    capture: &CaptureSettings,
    fit: &BlendFitSettings,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<TrainingSet, BlendFitError> {
    fit.validate()?;
    let seed = fit.seed ^ TRAINING_STREAM;
    let uniform = count.div_ceil(2);
    let mut pts: Vec<Vec3> = sample_points(baker.tracer(), bake_box, uniform, seed)
        .into_iter()
        .map(|p| p.position)
        .collect();
    let tets = mesh.tets();
    let pos = mesh.positions();
    let want = count - uniform;
    let mut tries = 0u64;
    let mut cell_points = 0;
    while !tets.is_empty() && cell_points < want && tries < 200 * want as u64 + 1000 {
        let mut rng = SampleRng::new(seed, CELL_STREAM, tries);
        tries += 1;
        let t = &tets[((rng.next_f32() * tets.len() as f32) as usize).min(tets.len() - 1)];
        // Uniform in the simplex: the gaps of three sorted uniforms.
        let mut u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
        u.sort_by(f32::total_cmp);
        let b = [u[0], u[1] - u[0], u[2] - u[1], 1.0 - u[2]];
        let p = (0..4).fold(Vec3::ZERO, |acc, k| acc + b[k] * pos[t[k] as usize]);
        if bake_box.contains(p) && is_free(baker.tracer(), p, SURFACE_CLEARANCE) {
            pts.push(p);
            cell_points += 1;
        }
    }
    if pts.is_empty() {
        return Err(BlendFitError::NoTrainingPoints);
    }
    let mut s = capture.clone();
    s.samples = fit.samples;
    s.groups = false;
    let rs = baker.capture_many(&pts, TRAINING_INDEX, &s, progress)?;
    let (positions, sh) = rs
        .into_iter()
        .map(|r| {
            let sh = match (capture.split_direct, r.indirect) {
                (true, Some(ind)) => ind,
                _ => r.sh,
            };
            (r.position, sh)
        })
        .unzip();
    Ok(TrainingSet { positions, sh })
}

/// One training point as the fit sees it: the cell's probes, their blend
/// weights without probe weights (normalized), and the Gram matrix of the
/// probes' irradiance errors `G_kl = ⟨C_k − E, C_l − E⟩` (band-weighted SH
/// inner product), divided by the point's squared relative-error scale.
#[derive(Clone)]
struct Row {
    probes: [u32; 4],
    w: [f32; 4],
    /// Upper triangle of `G` (00 01 02 03 11 12 13 22 23 33), already scaled.
    g: [f64; 10],
}

impl Row {
    /// Scaled squared error of the blend with per-probe factors `f`.
    fn error(&self, f: [f64; 4]) -> f64 {
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
fn check(
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
    Ok(())
}

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
    /// Probe weights `s_i`, one per probe (see [`fit_probe_weights`]).
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
/// ([`DEFAULT_DIRECTIONAL`]). Errors as [`fit_probe_weights`], and
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
    // Per exponent: its rows, held-out objective score, held-out absolute score.
    let mut candidates = Vec::with_capacity(exponents.len());
    for &alpha in exponents {
        let (rows, to_absolute) = rows(&with(alpha)?, training, beta);
        let fold = |k: usize| -> Vec<f64> {
            let part: Vec<Row> = rows.iter().skip(k).step_by(2).cloned().collect();
            descend(&part, nprobes, rho)
                .iter()
                .map(|&x| (x as f64).exp())
                .collect()
        };
        let (even, odd) = (fold(0), fold(1));
        // Weights fitted on one fold score the other; a row's error is
        // linear in its Gram matrix, so the absolute score rescales it.
        let (mut objective, mut absolute) = (0.0, 0.0);
        for (j, r) in rows.iter().enumerate() {
            let e = r.error(factors(r, if j % 2 == 0 { &odd } else { &even }));
            objective += e;
            absolute += e * to_absolute[j];
        }
        candidates.push((rows, objective / n, absolute / n));
    }
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

/// [`fit_probe_weights`] after validation, with the objective, for the
/// exponent `cloud` is set to.
fn fit_weights(cloud: &ProbeCloud, training: &TrainingSet, fit: &BlendFitSettings) -> FittedBlend {
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
fn solve(rows: &[Row], nprobes: usize, rho: f64) -> (Vec<f32>, f64) {
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
fn rows(cloud: &ProbeCloud, training: &TrainingSet, beta: f64) -> (Vec<Row>, Vec<f64>) {
    let n = cloud.coeffs_per_probe();
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
    let mut ws = WalkState::new();
    let mut rows = Vec::with_capacity(training.positions.len());
    let mut to_absolute = Vec::with_capacity(training.positions.len());
    for (j, p) in training.positions.iter().enumerate() {
        let (probes, w) = plain.weights_at(*p, &mut ws);
        let e = truth(j);
        let scale = 1.0 / (norm(e) + floor).powi(2).max(1e-30) + beta / mean_square;
        to_absolute.push(1.0 / mean_square / scale);
        let d: [Vec<Vec3>; 4] = core::array::from_fn(|k| {
            if w[k] > 0.0 {
                let c = plain.probe_sh(probes[k] as usize);
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
        rows.push(Row { probes, w, g });
    }
    (rows, to_absolute)
}

/// Per-slot factors of `r` for probe weights `s`.
fn factors(r: &Row, s: &[f64]) -> [f64; 4] {
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
fn descend(rows: &[Row], nprobes: usize, rho: f64) -> Vec<f32> {
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

/// Fits the blend of a cloud file: builds its [`ProbeCloud`] (with the
/// visibility data it holds), captures `fit.points_per_probe ×` probes
/// training points ([`capture_training_set`]) and fits probe weights for
/// `fit.brightness`, or for each of [`BRIGHTNESS_CHOICES`] keeping the best
/// ([`fit_blend`]). `probekit bake` stores the result as the file's `PWGT`
/// section: the weights, and the exponent in its header.
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
    let training =
        capture_training_set(baker, bake_box, cloud.mesh(), count, capture, fit, progress)?;
    fit_blend(&cloud, &training, fit, &fit.exponents())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::delaunay::tetrahedralize;

    /// Seeded uniform points in `[lo, hi]³` (the crate's sampler).
    struct Lcg(crate::sampling::SampleRng);
    impl Lcg {
        fn new(seed: u64) -> Self {
            Self(crate::sampling::SampleRng::new(seed, 0, 0))
        }
        fn v(&mut self, lo: f32, hi: f32) -> Vec3 {
            let r = &mut self.0;
            Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * (hi - lo) + Vec3::splat(lo)
        }
    }

    /// The default settings with regularization `rho`.
    fn settings(rho: f32) -> BlendFitSettings {
        BlendFitSettings {
            regularization: rho,
            ..BlendFitSettings::new(1)
        }
    }

    /// L2 SH of a uniform grey sky of radiance `dc / Y00`.
    fn grey(dc: f32) -> ShRgb {
        let mut c = vec![Vec3::ZERO; 9];
        c[0] = Vec3::splat(dc);
        ShRgb::from_coeffs(c).unwrap()
    }

    /// A 4 × 4 × 4 lattice (1 m) whose probe `bright` has 50× the others'
    /// light.
    fn outlier_cloud(bright: usize) -> ProbeCloud {
        let mut pos = Vec::new();
        for z in 0..4 {
            for y in 0..4 {
                for x in 0..4 {
                    pos.push(Vec3::new(x as f32, y as f32, z as f32));
                }
            }
        }
        let mesh = tetrahedralize(&pos).unwrap().to_tet_mesh(&pos).unwrap();
        let coeffs = (0..pos.len())
            .flat_map(|i| grey(if i == bright { 50.0 } else { 1.0 }).coeffs().to_vec())
            .collect();
        ProbeCloud::new(mesh, 3, coeffs).unwrap()
    }

    /// Independent relative error of the cloud at `p` against a constant
    /// field `truth`: the RMS over 200 Fibonacci-sphere normals of the
    /// irradiance difference, over the RMS of the true irradiance.
    fn sphere_rel_error(cloud: &ProbeCloud, p: Vec3, truth: &ShRgb) -> f32 {
        let (se, st) = sphere_errors(cloud, p, truth);
        (se / st).sqrt() as f32
    }

    /// A probe that sees light its neighbourhood does not (50× brighter
    /// than a field that is constant everywhere) is weighted down to the
    /// floor, the others stay near 1, and the independently measured
    /// error at fresh points falls more than tenfold.
    #[test]
    fn an_outlier_probe_is_weighted_down_and_the_error_falls() {
        let bright = 21; // (1, 1, 1): interior
        let cloud = outlier_cloud(bright);
        let mut g = Lcg::new(1);
        let truth = grey(1.0);
        let training = TrainingSet {
            positions: (0..800).map(|_| g.v(0.05, 2.95)).collect(),
            sh: vec![truth.clone(); 800],
        };
        let w = fit_probe_weights(&cloud, &training, &settings(1e-5)).unwrap();
        assert_eq!(w.len(), 64);
        assert!(w[bright] < (LOG_WEIGHT_MIN + 1.0).exp(), "{}", w[bright]);
        let mut others: Vec<f32> = (0..64).filter(|&i| i != bright).map(|i| w[i]).collect();
        others.sort_by(f32::total_cmp);
        assert!((0.8..1.25).contains(&others[31]), "median {}", others[31]);
        let mut fitted = cloud.clone();
        fitted.set_probe_weights(Some(w)).unwrap();
        let test: Vec<Vec3> = (0..300).map(|_| g.v(0.05, 2.95)).collect();
        let mean = |c: &ProbeCloud| {
            test.iter()
                .map(|&p| sphere_rel_error(c, p, &truth))
                .sum::<f32>()
                / test.len() as f32
        };
        let (before, after) = (mean(&cloud), mean(&fitted));
        assert!(after < 0.1 * before, "{before} → {after}");
    }

    /// A very large `ρ` keeps every weight at exactly 1; the fit is
    /// deterministic; bad input is a typed error.
    #[test]
    fn regularization_determinism_and_bad_input() {
        let cloud = outlier_cloud(5);
        let mut g = Lcg::new(2);
        let training = TrainingSet {
            positions: (0..200).map(|_| g.v(0.05, 2.95)).collect(),
            sh: vec![grey(1.0); 200],
        };
        assert_eq!(
            fit_probe_weights(&cloud, &training, &settings(1e9)).unwrap(),
            vec![1.0; 64]
        );
        let a = fit_probe_weights(&cloud, &training, &settings(1e-4)).unwrap();
        assert_eq!(
            a,
            fit_probe_weights(&cloud, &training, &settings(1e-4)).unwrap()
        );
        // Weights the cloud already has are ignored, and so is a
        // directional exponent in `fit_blend` (not fitted for).
        let mut weighted = cloud.clone();
        weighted.set_probe_weights(Some(vec![7.0; 64])).unwrap();
        assert_eq!(
            fit_probe_weights(&weighted, &training, &settings(1e-4)).unwrap(),
            a
        );
        weighted.set_directional_brightness(2.0).unwrap();
        let d = BlendFitSettings {
            directional: 0.75,
            ..settings(1e-4)
        };
        let f = fit_blend(&weighted, &training, &d, &[0.0]).unwrap();
        assert_eq!((f.weights, f.directional), (a.clone(), 0.75));
        for bad in [-0.5, f32::NAN, 4.5] {
            let s = BlendFitSettings {
                directional: bad,
                ..settings(1e-4)
            };
            assert!(matches!(
                fit_probe_weights(&cloud, &training, &s),
                Err(BlendFitError::Settings(_))
            ));
        }
        // The settings' JSON round trip, the exponents included.
        let j = BlendFitSettings {
            brightness: Some(0.5),
            directional: 0.75,
            ..settings(1e-4)
        };
        assert_eq!(BlendFitSettings::from_json(&j.to_json(), &settings(1.0)), j);
        let mut short = training.clone();
        short.sh.pop();
        assert!(matches!(
            fit_probe_weights(&cloud, &short, &settings(1e-4)),
            Err(BlendFitError::Mismatch(_))
        ));
        let mut l1 = training.clone();
        l1.sh[3] = ShRgb::zeros(2);
        assert!(matches!(
            fit_probe_weights(&cloud, &l1, &settings(1e-4)),
            Err(BlendFitError::Mismatch(_))
        ));
        for bad in [-1.0, f32::NAN, f32::INFINITY] {
            assert!(matches!(
                fit_probe_weights(&cloud, &training, &settings(bad)),
                Err(BlendFitError::Settings(_))
            ));
            let beta = BlendFitSettings {
                absolute_weight: bad,
                ..settings(1e-4)
            };
            assert!(matches!(
                fit_probe_weights(&cloud, &training, &beta),
                Err(BlendFitError::Settings(_))
            ));
        }
        let empty = TrainingSet {
            positions: vec![],
            sh: vec![],
        };
        assert_eq!(
            fit_probe_weights(&cloud, &empty, &settings(1e-4)).unwrap(),
            vec![1.0; 64]
        );
    }

    /// L2 SH of a sky whose radiance is `dc / Y00` (uniform) plus a linear
    /// lobe `z` along +z: irradiance changes with the normal, so a blend is
    /// judged on every band.
    fn lobed(dc: f32, z: f32) -> ShRgb {
        let mut c = vec![Vec3::ZERO; 9];
        c[0] = Vec3::splat(dc);
        c[2] = Vec3::splat(z);
        ShRgb::from_coeffs(c).unwrap()
    }

    /// The lattice of [`outlier_cloud`] holding `field(position)` at each
    /// probe, 50× that at probe `outlier`.
    fn field_cloud(field: &dyn Fn(Vec3) -> ShRgb, outlier: Option<usize>) -> ProbeCloud {
        let c = outlier_cloud(0);
        let coeffs = c
            .mesh()
            .positions()
            .iter()
            .enumerate()
            .flat_map(|(i, &p)| {
                let k = if Some(i) == outlier { 50.0 } else { 1.0 };
                field(p).coeffs().iter().map(|&x| x * k).collect::<Vec<_>>()
            })
            .collect();
        ProbeCloud::new(c.mesh().clone(), 3, coeffs).unwrap()
    }

    /// Mean squared irradiance error and mean squared true irradiance over
    /// 200 Fibonacci-sphere normals at `p` (RGB lengths).
    fn sphere_errors(cloud: &ProbeCloud, p: Vec3, truth: &ShRgb) -> (f64, f64) {
        let mut ws = WalkState::new();
        let (mut se, mut st) = (0.0f64, 0.0f64);
        let n = 200;
        for i in 0..n {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - z * z).sqrt();
            let phi = i as f32 * 2.399_963;
            let d = Vec3::new(r * phi.cos(), z, r * phi.sin());
            let t = truth.irradiance(d);
            se += (cloud.irradiance(p, d, &mut ws) - t).length_squared() as f64;
            st += t.length_squared() as f64;
        }
        (se / n as f64, st / n as f64)
    }

    /// The exponent is chosen by the data, and checked against an
    /// independent measure of both criteria (relative-plus-absolute and
    /// absolute squared errors integrated over 200 normals at fresh points,
    /// not the fit's Gram matrices), for every exponent refitted:
    /// * a field linear in space (what barycentric blending reproduces
    ///   exactly) keeps the plain blend;
    /// * one outlier probe 50× brighter than the constant field around it
    ///   (a doorway probe seeing light the cell does not), weights held at 1
    ///   by a huge `ρ`, gets an exponent > 0: lower error on both criteria;
    /// * a bright ramp meeting a dark region between two probe layers, weights
    ///   held at 1: an exponent > 0 lowers the relative error of the dark
    ///   points, but raises the absolute one far beyond the tolerance, so
    ///   the plain blend is kept.
    ///
    /// In each case the choice is the one the rule makes on the measured
    /// errors.
    #[test]
    fn fit_blend_chooses_the_exponent_the_data_asks_for() {
        let linear = |p: Vec3| lobed(1.0 + 2.0 * p.x, 0.5 + 0.25 * p.y);
        let constant = |_: Vec3| lobed(1.0, 0.4);
        let ramp_then_dark = |p: Vec3| {
            if p.x < 1.5 {
                lobed(10.0 + 40.0 * p.x, 4.0 + 16.0 * p.x)
            } else {
                lobed(1.0, 0.4)
            }
        };
        let mut g = Lcg::new(5);
        type Field<'a> = &'a dyn Fn(Vec3) -> ShRgb;
        let cases: [(&str, Field, Option<usize>, f32, bool); 3] = [
            ("linear", &linear, None, 1e-5, true),
            ("outlier", &constant, Some(21), 1e9, false),
            ("ramp then dark", &ramp_then_dark, None, 1e9, true),
        ];
        for (name, field, outlier, rho, plain_wins) in cases {
            let cloud = field_cloud(field, outlier);
            let pts: Vec<Vec3> = (0..600).map(|_| g.v(0.05, 2.95)).collect();
            let training = TrainingSet {
                sh: pts.iter().map(|&p| field(p)).collect(),
                positions: pts,
            };
            let fit = settings(rho);
            let chosen = fit_blend(&cloud, &training, &fit, &BRIGHTNESS_CHOICES).unwrap();
            assert_eq!(chosen.weights.len(), 64);
            assert_eq!(chosen.brightness == 0.0, plain_wins, "{name}: {chosen:?}");
            let test: Vec<Vec3> = (0..300).map(|_| g.v(0.05, 2.95)).collect();
            let beta = fit.absolute_weight as f64;
            let measured = |alpha: f32| {
                let f = fit_blend(&cloud, &training, &fit, &[alpha]).unwrap();
                assert_eq!(f.brightness, alpha);
                let mut c = cloud.clone();
                c.set_brightness_weighting(alpha).unwrap();
                c.set_probe_weights(Some(f.weights)).unwrap();
                let e: Vec<(f64, f64)> = test
                    .iter()
                    .map(|&p| sphere_errors(&c, p, &field(p)))
                    .collect();
                let k = e.len() as f64;
                let mean = e.iter().map(|x| x.1.sqrt()).sum::<f64>() / k;
                let mean_square = e.iter().map(|x| x.1).sum::<f64>() / k;
                let objective = e
                    .iter()
                    .map(|&(se, st)| {
                        se / (st.sqrt() + 0.01 * mean).powi(2) + beta * se / mean_square
                    })
                    .sum::<f64>()
                    / k;
                let absolute = e.iter().map(|x| x.0).sum::<f64>() / k / mean_square;
                (objective, absolute)
            };
            let m = BRIGHTNESS_CHOICES.map(measured);
            let lowest = m.iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
            let rule = (0..m.len())
                .filter(|&i| m[i].1 <= lowest * (1.0 + BRIGHTNESS_ABSOLUTE_TOLERANCE))
                .min_by(|&a, &b| m[a].0.total_cmp(&m[b].0))
                .unwrap();
            assert_eq!(
                BRIGHTNESS_CHOICES[rule], chosen.brightness,
                "{name}: measured (objective, absolute) {m:?}"
            );
            if name == "ramp then dark" {
                // The objective alone would have taken an exponent > 0.
                assert!(m[2].0 < m[0].0 && m[2].1 > 1.1 * m[0].1, "{m:?}");
            }
        }
        // Bad input: no exponent, or one out of range.
        let cloud = outlier_cloud(3);
        let t = TrainingSet {
            positions: vec![Vec3::ONE],
            sh: vec![grey(1.0)],
        };
        for bad in [&[][..], &[5.0], &[f32::NAN]] {
            assert!(matches!(
                fit_blend(&cloud, &t, &settings(1e-5), bad),
                Err(BlendFitError::Settings(_))
            ));
        }
    }

    /// On the demo scene: training points are captured in free space and
    /// fitted, deterministically, to weights in range, not all 1; bad
    /// settings are refused before any work.
    #[test]
    fn fits_a_small_cloud_of_the_demo_scene() {
        let scene = crate::scene::Scene::load(std::path::Path::new("builtin:demo")).unwrap();
        let baker = Baker::new(&scene).unwrap();
        let b = scene.bake_box();
        let mut pos = Vec::new();
        for i in 0..4 {
            for j in 0..3 {
                for k in 0..3 {
                    let t = Vec3::new(i as f32 + 0.5, j as f32 + 0.5, k as f32 + 0.5)
                        / Vec3::new(4.0, 3.0, 3.0);
                    let p = b.min + t * (b.max - b.min);
                    if !crate::trace::free_space::inside_geometry(baker.tracer(), p) {
                        pos.push(p);
                    }
                }
            }
        }
        let mut cs = CaptureSettings::from_scene(&scene);
        cs.samples = 16;
        let sh: Vec<ShRgb> = baker
            .capture_many(&pos, 0, &cs, &|_, _| {})
            .unwrap()
            .into_iter()
            .map(|r| r.sh)
            .collect();
        let file = crate::format::cloud::test_cloud_file(&pos, &sh);
        let fit = BlendFitSettings {
            points_per_probe: 4,
            samples: 16,
            ..BlendFitSettings::new(9)
        };
        let run = || fit_file_probe_weights(&baker, &file, &b, &cs, &fit, &|_, _| {});
        let fitted = run().unwrap();
        assert!(BRIGHTNESS_CHOICES.contains(&fitted.brightness));
        assert_eq!(fitted.directional, DEFAULT_DIRECTIONAL);
        let w = fitted.weights.clone();
        assert_eq!(w.len(), pos.len());
        assert!(w
            .iter()
            .all(|x| probekit_runtime::cloud::PROBE_WEIGHT_RANGE.contains(x)));
        assert!(w.iter().any(|&x| x != 1.0));
        assert_eq!(fitted, run().unwrap());
        // A fixed exponent is kept.
        let fixed = BlendFitSettings {
            brightness: Some(0.25),
            ..fit
        };
        let f = fit_file_probe_weights(&baker, &file, &b, &cs, &fixed, &|_, _| {}).unwrap();
        assert_eq!(f.brightness, 0.25);
        let cloud = ProbeCloud::from_file(&file).unwrap();
        let t = capture_training_set(&baker, &b, cloud.mesh(), 50, &cs, &fit, &|_, _| {}).unwrap();
        assert_eq!(t.positions.len(), 50);
        assert!(t.positions.iter().all(|p| b.contains(*p)));
        for bad in [
            BlendFitSettings {
                points_per_probe: 0,
                ..fit
            },
            BlendFitSettings { samples: 0, ..fit },
            BlendFitSettings {
                regularization: -1.0,
                ..fit
            },
            BlendFitSettings {
                brightness: Some(4.5),
                ..fit
            },
        ] {
            assert!(matches!(
                fit_file_probe_weights(&baker, &file, &b, &cs, &bad, &|_, _| {}),
                Err(BlendFitError::Settings(_))
            ));
        }
    }
}
