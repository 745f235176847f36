//! # Probe capture
//!
//! Monte Carlo path tracing of the incoming radiance at points, projected
//! into radiance SH; probe validity and virtual offset; ground-truth
//! irradiance; deterministic parallel and sharded bakes.
//!
//! Entry points: [`bake_points`] (many probes, the CLI's `bake`),
//! [`Baker::capture`] (one probe, `capture`), [`Baker::reference_irradiance`]
//! (`reference`), [`shard_range`] (`bake --shard I/N`). Validity is described
//! in [`validity`]; samplers in [`crate::sampling`]. The estimator is
//! in the `integrator` module, probe capture in `probe`, ground truth in
//! `reference`.
//!
//! ## Estimator
//! For a receiver at `x` (a probe: the whole sphere; a reference point: the
//! hemisphere about its normal) we estimate `∫ L(x, ω) K(ω) dω` with the
//! kernel `K = Y_lm` (SH projection) or `K = max(0, n·ω)` (irradiance).
//! Three kinds of samples, combined without double counting:
//! - **Delta lights** (point, spot, directional) are added once, exactly:
//!   the radiance of a delta light is `E δ(ω − ω_l)`, so its SH is
//!   `E·T·Y_lm(ω_l)` with `E = I/d²` (× the glTF spot ramp) or lux, and `T`
//!   the shadow ray's transmittance.
//! - **Receiver directions** `ω_i` (uniform sphere for probes, cosine
//!   hemisphere for the reference; R2 low-discrepancy with a per-receiver
//!   Cranley–Patterson rotation) start a path. What the path returns is
//!   `L(x, ω_i)/p(ω_i)`; emitters it hits are weighted by the power heuristic
//!   against light sampling (Veach & Guibas 1995).
//! - **Light samples** at `x` (sphere and disk lights, emissive triangles, an
//!   environment map) with the complementary MIS weight; a probe's samples
//!   of each sphere or disk light and of the environment map are points of
//!   a scrambled Sobol' (0,2)-sequence ([`crate::sampling::sobol02_point`],
//!   one scramble per light and probe), stratified over its receiver
//!   samples like the directions.
//!
//! At every surface vertex (Lambertian, albedo `ρ`) the path does next-event
//! estimation to every light (delta lights exactly, area lights and the
//! environment map with MIS against the cosine BSDF sample), then continues
//! by cosine sampling (throughput × ρ). A *bounce* is one scattering event:
//! with `bounces = B` the last vertex that scatters is the B-th, so a furnace
//! of emission `Le` and albedo `a` gives `Le·Σ_{k=0..B} a^k`. Russian
//! roulette (survival = max throughput component, ≤ 0.95, unbiased) starts
//! after [`CaptureSettings::russian_roulette_depth`] scattering events.
//! A surface of opacity `α < 1` is crossed straight with probability `1 − α`
//! (path rays) and attenuates shadow rays by `1 − α` (the tracer's
//! transmittance), so in expectation both pass `1 − α` of the light.
//! Emissive triangles emit on both sides (as [`Scene::emission`] says);
//! disk lights on the side their `direction` points to.
//!
//! **Direct** light is what reaches `x` from an emitter with no scattering
//! in between (crossing glass is not scattering); **indirect** is the rest
//! (Sukys 2014, §3.1.2 "Light decoupling"). Every contribution is also
//! attributed to the light group of the emitter it came from.
//!
//! ## Determinism
//! Sample `i` of receiver `k` draws its random numbers from
//! `SampleRng::new(seed, k, i)` and its direction from R2 point `i`; samples
//! are summed in f64 in chunks of [`CHUNK`] in a fixed order, so results are
//! bit-identical for any thread count and any sharding.

pub(crate) mod emitters;
mod integrator;
pub mod occlusion;
mod probe;
mod reference;
pub mod validity;

#[cfg(test)]
mod stratified_tests;
#[cfg(test)]
pub(crate) mod tests;

pub use emitters::{DEFAULT_GROUP, EMISSIVE_GROUP, ENVIRONMENT_GROUP};
pub use occlusion::{visible_fraction, visible_fractions};
pub use probe::{CaptureResult, CaptureSettings, CHUNK};
pub use reference::{ReferenceResult, ReferenceSettings};
pub use validity::{Validity, ValiditySettings};

use crate::env::{EnvError, EnvMap};
use crate::scene::Scene;
use crate::trace::Tracer;
use emitters::Emitters;
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

/// Path-tracing context for one scene: its tracer and prepared lights.
pub struct Baker<'s> {
    scene: &'s Scene,
    tracer: Tracer<'s>,
    emitters: Emitters,
    /// Light samples at a probe from a scrambled (0,2)-sequence (the
    /// default) or, for the tests that compare the two, independent draws.
    stratified_lights: bool,
}

impl<'s> Baker<'s> {
    /// Builds the BVH, prepares the lights and loads the environment map.
    pub fn new(scene: &'s Scene) -> Result<Self, BakeError> {
        Self::with_tracer(scene, Tracer::new(scene))
    }

    /// Uses an already built tracer over `scene`.
    pub fn with_tracer(scene: &'s Scene, tracer: Tracer<'s>) -> Result<Self, BakeError> {
        Ok(Self {
            scene,
            tracer,
            emitters: Emitters::new(scene)?,
            stratified_lights: true,
        })
    }

    /// Replaces the scene's environment by `map` × `intensity`, rotated by
    /// `rotation_y_degrees` about +Y (counter-clockwise seen from above), for
    /// callers that already hold the map in memory.
    pub fn set_environment_map(&mut self, map: &EnvMap, intensity: f32, rotation_y_degrees: f32) {
        self.emitters.env = Emitters::map_environment(map, intensity, rotation_y_degrees);
    }

    /// Puts light `i` of the scene in light group `light_groups[i]` for
    /// every capture after this (one name per light; emissive triangles
    /// and the environment keep their groups). The bake's run-time light
    /// split gives each candidate light a group of its own this way, so
    /// that a capture can leave its direct light out and report it apart.
    pub fn set_light_groups(&mut self, light_groups: &[String]) -> Result<(), BakeError> {
        if light_groups.len() != self.scene.lights.len() {
            return Err(BakeError::BadSettings(format!(
                "{} light group names for {} lights",
                light_groups.len(),
                self.scene.lights.len()
            )));
        }
        let env = std::mem::replace(&mut self.emitters.env, emitters::Environment::Black);
        self.emitters = Emitters::with_light_groups(self.scene, light_groups)?;
        self.emitters.env = env;
        Ok(())
    }

    /// The scene.
    pub fn scene(&self) -> &'s Scene {
        self.scene
    }

    /// The tracer.
    pub fn tracer(&self) -> &Tracer<'s> {
        &self.tracer
    }

    /// Names of the light groups that hold at least one light, sorted: each
    /// light's `group` (or `"default"`), `"emissive"` for emissive triangles,
    /// `"environment"` for a non-black environment.
    pub fn group_names(&self) -> Vec<String> {
        self.present_groups()
            .into_iter()
            .map(|g| self.emitters.groups[g].clone())
            .collect()
    }

    /// Every name of `s.exclude_direct` is a light group of the scene.
    fn check_excluded(&self, s: &CaptureSettings) -> Result<(), BakeError> {
        if s.exclude_direct.is_empty() {
            return Ok(());
        }
        let names = self.group_names();
        match s.exclude_direct.iter().find(|n| !names.contains(n)) {
            None => Ok(()),
            Some(n) => Err(BakeError::BadSettings(format!(
                "exclude_direct: no light group `{n}` in the scene (groups: {})",
                names.join(", ")
            ))),
        }
    }

    fn present_groups(&self) -> Vec<usize> {
        let e = &self.emitters;
        let mut present = vec![false; e.groups.len()];
        for d in &e.delta {
            present[d.group() as usize] = true;
        }
        for s in &e.shapes {
            present[s.group as usize] = true;
        }
        if e.has_emissive_triangles() {
            present[e.emissive_group as usize] = true;
        }
        if !e.env.is_black() {
            present[e.env_group as usize] = true;
        }
        (0..present.len()).filter(|&g| present[g]).collect()
    }
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
