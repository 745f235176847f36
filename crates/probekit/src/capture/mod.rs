//! # Probe capture
//!
//! Monte Carlo path tracing of the incoming radiance at points, projected
//! into radiance SH (issue 4, "Capture"); probe validity and virtual offset;
//! ground-truth irradiance; deterministic parallel and sharded bakes.
//!
//! Entry points: [`bake_points`] (many probes, the CLI's `bake`),
//! [`Baker::capture`] (one probe, `capture`), [`Baker::reference_irradiance`]
//! (`reference`), [`shard_range`] (`bake --shard I/N`). The estimator is
//! described in [`capture`]; validity in [`validity`]; samplers in
//! [`crate::sampling`].

pub(crate) mod emitters;
pub mod probe;
pub mod validity;

#[cfg(test)]
mod tests;

pub use emitters::{DEFAULT_GROUP, EMISSIVE_GROUP, ENVIRONMENT_GROUP};
pub use probe::{Baker, CaptureResult, CaptureSettings, ReferenceResult, ReferenceSettings, CHUNK};
pub use validity::{Validity, ValiditySettings};

use crate::env::EnvError;
use crate::scene::Scene;
use glam::Vec3;
use probekit_sh::ShRgb;
use std::ops::Range;

/// What can go wrong in a capture.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BakeError {
    /// The scene's environment map could not be loaded.
    #[error("environment map: {0}")]
    EnvMap(#[from] EnvError),
    /// The scene's environment description is unusable.
    #[error("environment: {0}")]
    BadEnvironment(String),
    /// A light is unusable.
    #[error("light {index}: {message}")]
    BadLight {
        /// Index into the scene's lights.
        index: usize,
        /// What is wrong.
        message: String,
    },
    /// Settings out of bounds.
    #[error("invalid capture settings: {0}")]
    BadSettings(String),
    /// A probe or reference position (or normal) is NaN or infinite.
    #[error("position {index} is not finite: {position}")]
    NonFinitePosition {
        /// Global index of the point.
        index: usize,
        /// The position.
        position: Vec3,
    },
    /// `--shard I/N` with `N = 0` or `I ≥ N`.
    #[error("shard {shard} of {shards}: the shard index must be below the shard count, and the count at least 1")]
    BadShard {
        /// Shard index.
        shard: usize,
        /// Shard count.
        shards: usize,
    },
}

/// Everything a bake of a list of positions produces. Per-probe vectors are
/// in the order of the positions.
#[derive(Clone, Debug, PartialEq)]
pub struct BakeOutput {
    /// Global index of the first probe (non-zero for a shard).
    pub first_index: usize,
    /// The requested positions.
    pub positions: Vec<Vec3>,
    /// Where each probe was captured (requested position + virtual offset).
    pub captured_positions: Vec<Vec3>,
    /// Radiance SH per probe, all light.
    pub sh: Vec<ShRgb>,
    /// Direct light per probe (`settings.split_direct`).
    pub direct: Option<Vec<ShRgb>>,
    /// Indirect light per probe (`settings.split_direct`).
    pub indirect: Option<Vec<ShRgb>>,
    /// Per light group `(name, SH per probe)`, sorted by name (`settings.groups`).
    pub groups: Vec<(String, Vec<ShRgb>)>,
    /// Per light group indirect light, same names and order as `groups`
    /// (`settings.groups` and `settings.split_direct`).
    pub groups_indirect: Vec<(String, Vec<ShRgb>)>,
    /// Validity per probe.
    pub validity: Vec<Validity>,
    /// The settings used.
    pub settings: CaptureSettings,
}

impl BakeOutput {
    fn from_results(
        first_index: usize,
        positions: &[Vec3],
        results: Vec<CaptureResult>,
        settings: &CaptureSettings,
        group_names: Vec<String>,
    ) -> Self {
        let mut out = BakeOutput {
            first_index,
            positions: positions.to_vec(),
            captured_positions: Vec::with_capacity(results.len()),
            sh: Vec::with_capacity(results.len()),
            direct: settings.split_direct.then(Vec::new),
            indirect: settings.split_direct.then(Vec::new),
            groups: if settings.groups {
                group_names
                    .iter()
                    .map(|n| (n.clone(), Vec::new()))
                    .collect()
            } else {
                Vec::new()
            },
            groups_indirect: if settings.groups && settings.split_direct {
                group_names.into_iter().map(|n| (n, Vec::new())).collect()
            } else {
                Vec::new()
            },
            validity: Vec::with_capacity(results.len()),
            settings: settings.clone(),
        };
        for r in results {
            out.captured_positions.push(r.position);
            out.sh.push(r.sh);
            if let (Some(d), Some(v)) = (out.direct.as_mut(), r.direct) {
                d.push(v);
            }
            if let (Some(d), Some(v)) = (out.indirect.as_mut(), r.indirect) {
                d.push(v);
            }
            for ((_, dst), (_, v)) in out.groups.iter_mut().zip(r.groups) {
                dst.push(v);
            }
            for ((_, dst), (_, v)) in out.groups_indirect.iter_mut().zip(r.groups_indirect) {
                dst.push(v);
            }
            out.validity.push(r.validity);
        }
        out
    }

    /// Appends the next shard (its `first_index` must equal this one's end):
    /// the per-probe vectors are concatenated. Errors on a gap, an overlap,
    /// different settings or different groups.
    pub fn append(&mut self, next: BakeOutput) -> Result<(), BakeError> {
        let end = self.first_index + self.positions.len();
        if next.first_index != end {
            return Err(BakeError::BadSettings(format!(
                "shard starts at probe {} but the previous part ends at {end}",
                next.first_index
            )));
        }
        if next.settings != self.settings
            || next
                .groups
                .iter()
                .map(|g| &g.0)
                .ne(self.groups.iter().map(|g| &g.0))
        {
            return Err(BakeError::BadSettings(
                "parts were baked with different settings or light groups".into(),
            ));
        }
        self.positions.extend(next.positions);
        self.captured_positions.extend(next.captured_positions);
        self.sh.extend(next.sh);
        if let (Some(a), Some(b)) = (self.direct.as_mut(), next.direct) {
            a.extend(b);
        }
        if let (Some(a), Some(b)) = (self.indirect.as_mut(), next.indirect) {
            a.extend(b);
        }
        for ((_, a), (_, b)) in self.groups.iter_mut().zip(next.groups) {
            a.extend(b);
        }
        for ((_, a), (_, b)) in self.groups_indirect.iter_mut().zip(next.groups_indirect) {
            a.extend(b);
        }
        self.validity.extend(next.validity);
        Ok(())
    }
}

/// Bakes probes at `points` (global indices `0..points.len()`), in parallel,
/// calling `progress(done, total)` after each probe. Same bits for any thread
/// count.
pub fn bake_points(
    scene: &Scene,
    points: &[Vec3],
    settings: &CaptureSettings,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<BakeOutput, BakeError> {
    bake_points_from(scene, points, 0, settings, progress)
}

/// Like [`bake_points`] for a slice of a larger bake whose first point has
/// global index `first_index`: a probe's random numbers depend only on the
/// seed and its global index, so shards reproduce the unsharded bake exactly.
pub fn bake_points_from(
    scene: &Scene,
    points: &[Vec3],
    first_index: usize,
    settings: &CaptureSettings,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<BakeOutput, BakeError> {
    Baker::new(scene)?.bake_points_from(points, first_index, settings, progress)
}

impl Baker<'_> {
    /// [`bake_points_from`] with this baker's scene and BVH, so a caller
    /// that also places probes or bakes visibility data with the same
    /// baker builds the BVH once.
    pub fn bake_points_from(
        &self,
        points: &[Vec3],
        first_index: usize,
        settings: &CaptureSettings,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<BakeOutput, BakeError> {
        settings.validate()?;
        let results = self.capture_many(points, first_index, settings, progress)?;
        Ok(BakeOutput::from_results(
            first_index,
            points,
            results,
            settings,
            self.group_names(),
        ))
    }

    /// [`bake_shard`] with this baker (see [`Baker::bake_points_from`]).
    pub fn bake_shard(
        &self,
        all_points: &[Vec3],
        shard: usize,
        shards: usize,
        settings: &CaptureSettings,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<BakeOutput, BakeError> {
        let r = shard_range(all_points.len(), shard, shards)?;
        self.bake_points_from(&all_points[r.clone()], r.start, settings, progress)
    }
}

/// Bakes shard `shard` of `shards` of `all_points` (see [`shard_range`]).
pub fn bake_shard(
    scene: &Scene,
    all_points: &[Vec3],
    shard: usize,
    shards: usize,
    settings: &CaptureSettings,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<BakeOutput, BakeError> {
    Baker::new(scene)?.bake_shard(all_points, shard, shards, settings, progress)
}

/// The contiguous index range of shard `shard` (0-based) of `shards` over
/// `total` items: `[⌊total·shard/shards⌋, ⌊total·(shard+1)/shards⌋)`. The
/// shards partition `0..total` in order, sizes differing by at most one.
pub fn shard_range(total: usize, shard: usize, shards: usize) -> Result<Range<usize>, BakeError> {
    if shards == 0 || shard >= shards {
        return Err(BakeError::BadShard { shard, shards });
    }
    let at = |k: usize| (total as u128 * k as u128 / shards as u128) as usize;
    Ok(at(shard)..at(shard + 1))
}
