//! Ground truth: irradiance at a point for a normal by cosine-weighted
//! path tracing until a relative precision is reached
//! ([`Baker::reference_irradiance`]).

use super::integrator::{PathParams, Receiver};
use super::probe::{CHUNK, STREAM_ROTATION};
use super::{BakeError, Baker};
use crate::sampling::{r2_point, Frame, SampleRng};
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// Salt mixed into the seed for reference-irradiance streams, so a reference
/// point and a probe with the same index draw independent numbers.
const REFERENCE_SALT: u64 = 0x5245_4645_5245_4e43;

/// How [`Baker::reference_irradiance`] decides it is done.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceSettings {
    /// Stop once the standard error of the luminance is below this fraction
    /// of the estimate (default 0.01).
    pub relative_precision: f32,
    /// At least this many samples (default 1024).
    pub min_samples: u32,
    /// At most this many samples (default 262 144).
    pub max_samples: u32,
    /// Scattering events per path (default 3).
    pub bounces: u32,
    /// Scattering events before Russian roulette (default 3).
    pub russian_roulette_depth: u32,
    /// Random seed (default 1).
    pub seed: u64,
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        Self {
            relative_precision: 0.01,
            min_samples: 1024,
            max_samples: 1 << 18,
            bounces: 3,
            russian_roulette_depth: 3,
            seed: 1,
        }
    }
}

/// Ground-truth irradiance at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceResult {
    /// `E(n) = ∫ L(ω) max(0, n·ω) dω` (not divided by π), linear RGB.
    pub irradiance: Vec3,
    /// Standard error of `irradiance` per channel (from batch means).
    pub std_error: Vec3,
    /// Samples used.
    pub samples: u32,
}

impl Baker<'_> {
    /// Ground-truth irradiance `E(n) = ∫ L(ω) max(0, n·ω) dω` at `point` with
    /// unit `normal` (not divided by π), by cosine-weighted path tracing with
    /// the same light transport as [`Baker::capture`]. Samples run in batches
    /// of [`CHUNK`], eight batches at a time in parallel, until the standard
    /// error of the luminance (from batch means) is below
    /// `relative_precision` of the estimate, or `max_samples`. `index` keys
    /// the random numbers (use the point's row number).
    pub fn reference_irradiance(
        &self,
        point: Vec3,
        normal: Vec3,
        index: u64,
        s: &ReferenceSettings,
    ) -> Result<ReferenceResult, BakeError> {
        if !(point.is_finite() && normal.is_finite()) || normal.length_squared() < 1e-12 {
            return Err(BakeError::NonFinitePosition {
                index: index as usize,
                position: point,
            });
        }
        if s.max_samples == 0 || s.relative_precision.is_nan() || s.relative_precision < 0.0 {
            return Err(BakeError::BadSettings(
                "reference needs max_samples ≥ 1 and a relative precision ≥ 0".into(),
            ));
        }
        let n = normal.normalize();
        let frame = Frame::from_z(n);
        let recv = Receiver::Cosine(frame);
        let seed = s.seed ^ REFERENCE_SALT;
        let rot = SampleRng::new(seed, index, STREAM_ROTATION).next_2d();
        let params = PathParams {
            bounces: s.bounces,
            rr_depth: s.russian_roulette_depth,
        };
        let batch = |b: u32| -> DVec3 {
            let (lo, hi) = (b * CHUNK, ((b + 1) * CHUNK).min(s.max_samples));
            let mut sum = DVec3::ZERO;
            for i in lo..hi {
                let mut rng = SampleRng::new(seed, index, i as u64);
                let dir = recv.sample(r2_point(i as u64, rot));
                let p0 = recv.pdf(dir);
                if p0 > 0.0 {
                    let cos = n.dot(dir).max(0.0);
                    self.trace_path(
                        point,
                        dir,
                        p0,
                        params,
                        &mut rng,
                        None,
                        None,
                        &mut |v, _, _| {
                            sum += (v * cos).as_dvec3();
                        },
                    );
                }
                self.nee_receiver(point, &recv, &mut rng, None, &mut |wi, v, _| {
                    sum += (v * n.dot(wi).max(0.0)).as_dvec3();
                });
            }
            sum
        };
        let nbatches = s.max_samples.div_ceil(CHUNK);
        let mut sums: Vec<DVec3> = Vec::new();
        const ROUND: u32 = 8;
        let mut samples;
        loop {
            let b0 = sums.len() as u32;
            let b1 = (b0 + ROUND).min(nbatches);
            let round: Vec<DVec3> = (b0..b1).into_par_iter().map(batch).collect();
            sums.extend(round);
            samples = (sums.len() as u32 * CHUNK).min(s.max_samples);
            if sums.len() as u32 >= nbatches {
                break;
            }
            if samples >= s.min_samples && sums.len() >= 2 {
                let (mean, se) = batch_mean_se(&sums);
                let lum = |v: DVec3| v.dot(probekit_sh::LUMINANCE.as_dvec3());
                if lum(se) <= s.relative_precision as f64 * lum(mean).abs() {
                    break;
                }
            }
        }
        // Batches have CHUNK samples except possibly the last: weight by size.
        let total: DVec3 = sums.iter().copied().sum();
        let mean = total / samples as f64;
        let (_, se) = batch_mean_se(&sums);
        let mut e = mean;
        for (wi, irr, _) in self.delta_at(point) {
            e += (irr * n.dot(wi).max(0.0)).as_dvec3();
        }
        Ok(ReferenceResult {
            irradiance: e.as_vec3(),
            std_error: se.as_vec3(),
            samples,
        })
    }
}

/// Mean per sample and its standard error, from per-batch sums of [`CHUNK`]
/// samples each (the standard error of the mean of batch means).
fn batch_mean_se(sums: &[DVec3]) -> (DVec3, DVec3) {
    let k = sums.len() as f64;
    let means: Vec<DVec3> = sums.iter().map(|s| *s / CHUNK as f64).collect();
    let m = means.iter().copied().sum::<DVec3>() / k;
    if sums.len() < 2 {
        return (m, DVec3::splat(f64::INFINITY));
    }
    let var = means.iter().map(|x| (*x - m) * (*x - m)).sum::<DVec3>() / (k - 1.0);
    (m, (var / k).map(f64::sqrt))
}
