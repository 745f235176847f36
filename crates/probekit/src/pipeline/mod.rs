//! # The bake pipeline: place → capture → blend data → assemble
//!
//! One way to bake, for every caller (`probekit bake`, `merge`, `eval
//! --compare`, the sweeps, the examples): a [`Bake`] holds a scene, the
//! resolved [`Recipe`] and the ray tracer; its stages run in order —
//!
//! 1. [`Bake::place`]: the probe positions (grid, manual, adaptive,
//!    spawn-and-merge, gradient ascent; one grid sizing rule,
//!    [`crate::placement::grid_resolution`]);
//! 2. [`Bake::capture`]: each probe's radiance SH and validity by the path
//!    tracer, all probes or one shard's slice;
//! 3. [`Bake::assemble`]: the file — Delaunay tetrahedra, coefficients in
//!    the recipe's codec, light groups, the [`BakeRecord`] — or a shard part;
//! 4. [`Bake::blend_data`]: distance moments, cell visibility, occluder
//!    planes and fitted probe weights, per the recipe's `[blend]`.
//!
//! [`Bake::run`] runs them all; [`Bake::run_part`] bakes one shard into a
//! part file and [`merge`] joins the parts into the file a single machine
//! writes, byte for byte. [`bake_volume`] is the pipeline of an irradiance
//! volume. Each stage reports progress as `(phase, done, total)` and, in
//! the [`BakeReport`], its wall and CPU seconds and the rays it traced
//! ([`PhaseTime`]): `load` (the tracer; the caller may add the scene's
//! loading, [`Bake::with_load_time`]), `placement` (with its sub-phases),
//! `capture`, `assembly`, `distance moments`, `cell visibility` and
//! `weight fit`.

pub mod lights;
#[cfg(test)]
mod lights_tests;
mod merge;
mod positions;
pub mod sweep;
#[cfg(test)]
mod tests;
mod volume;

pub use merge::{merge, SCATTERED_SUFFIX};
pub use positions::read_positions;
pub use volume::{bake_volume, bake_volume_from, VolumeReport};

use crate::blend::blend_fit::TrainingSet;
use crate::blend::visibility_bake::VisibilityBakeError;
use crate::capture::{BakeError, BakeOutput, Baker, CaptureSettings};
use crate::format::cloud::{cloud_file, file_validity, light_groups, CloudFileError};
use crate::format::Parts;
use crate::format::{Codec, FormatError, ProbeFile};
use crate::placement::{grid_points, PlacementError};
use crate::progress::{Clock, PhaseTime, Progress};
use crate::recipe::{BakeRecord, Part, Placement, PlacementReport, Recipe, RecipeError};
use crate::scene::{Aabb, BakeBoxError, Scene};
use glam::Vec3;
use probekit_sh::ShRgb;
use serde::Serialize;
use thiserror::Error;

/// Why a bake failed. Each names what it could (a file, a key, a stage).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum PipelineError {
    /// The recipe is invalid.
    #[error(transparent)]
    Recipe(#[from] RecipeError),
    /// The bake box cannot hold probes.
    #[error(transparent)]
    BakeBox(#[from] BakeBoxError),
    /// Placement failed.
    #[error(transparent)]
    Placement(#[from] PlacementError),
    /// The capture failed.
    #[error(transparent)]
    Capture(#[from] BakeError),
    /// The file could not be assembled.
    #[error(transparent)]
    File(#[from] CloudFileError),
    /// The blend data could not be baked.
    #[error("visibility data and probe weights: {0}")]
    Blend(#[from] VisibilityBakeError),
    /// A file could not be encoded or checked.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// The volume could not be built.
    #[error(transparent)]
    Volume(#[from] crate::volume::VolumeBuildError),
    /// A positions file cannot be read or has a bad row.
    #[error("{path}: {message}")]
    Positions {
        /// The file.
        path: String,
        /// What is wrong (with the line).
        message: String,
    },
    /// Shard parts that do not make one bake.
    #[error("{0}")]
    Parts(String),
    /// A scene other than the one the parts were baked from.
    #[error(transparent)]
    SceneMismatch(#[from] crate::format::SceneMismatch),
}

/// Placed positions and what placement did.
#[derive(Clone, Debug)]
pub struct Placed {
    /// Probe positions, metres.
    pub positions: Vec<Vec3>,
    /// The report the file records.
    pub report: PlacementReport,
    /// The sub-phases of placement (adaptive: pool, scoring, candidates,
    /// leaks, …), for the [`BakeReport`].
    pub phases: Vec<PhaseTime>,
    /// Points of free space placement captured that are not probes
    /// ([`crate::placement::Placement::free_points`]).
    pub free_points: Vec<(Vec3, ShRgb)>,
}

/// What a bake produced, in numbers (serialised by `probekit bake --json`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BakeReport {
    /// Probes in the file (a part: in the part).
    pub probes: usize,
    /// Tetrahedra (0 for a part).
    pub tetrahedra: usize,
    /// Probes the capture flagged invalid.
    pub invalid: usize,
    /// File size in bytes.
    pub bytes: u64,
    /// Light group names.
    pub groups: Vec<String>,
    /// `[shard, shards]` of a part.
    pub shard: Option<[usize; 2]>,
    /// What placement did.
    pub placement: PlacementReport,
    /// Wall and CPU seconds and rays per stage, in order (see the module
    /// docs).
    pub phases: Vec<PhaseTime>,
    /// The run-time light split (`None`: every light baked).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lights: Option<lights::LightSplitReport>,
}

/// A finished bake: the file and its report.
#[derive(Clone, Debug)]
pub struct Baked {
    /// The probe file (or part), ready to write.
    pub file: ProbeFile,
    /// Its numbers.
    pub report: BakeReport,
}

/// One scene baked with one recipe (see the module docs).
pub struct Bake<'s> {
    scene: &'s Scene,
    scene_name: String,
    recipe: Recipe,
    bake_box: Aabb,
    baker: Baker<'s>,
    load: PhaseTime,
    /// The candidates of the run-time light split.
    split: lights::LightSplit,
}

impl<'s> Bake<'s> {
    /// Checks the recipe and the box it bakes in (before any work) and
    /// builds the ray tracer. `scene_name` is the scene as named, which
    /// the file records.
    pub fn new(scene: &'s Scene, scene_name: &str, recipe: &Recipe) -> Result<Self, PipelineError> {
        let mut clock = Clock::new(0);
        recipe.validate()?;
        let bake_box = recipe.bake_box_in(scene);
        bake_box.check_bake_box()?;
        recipe.placement_method(None).check_size(&bake_box)?;
        let resolved = &recipe.lights.resolved;
        if !resolved.is_empty() && resolved.len() != scene.lights.len() {
            return Err(RecipeError::Value {
                layer: String::new(),
                key: "lights.resolved".into(),
                message: format!(
                    "{} choices for the scene's {} lights: give one per light, or none",
                    resolved.len(),
                    scene.lights.len()
                ),
            }
            .into());
        }
        let split = lights::LightSplit::new(scene, &recipe.lights, recipe.capture.indirect_only);
        let mut baker = Baker::new(scene)?;
        if !split.candidates.is_empty() {
            baker.set_light_groups(&split.capture_groups)?;
        }
        let load = clock.lap("load", baker.tracer().rays()).clone();
        Ok(Bake {
            scene,
            scene_name: scene_name.to_string(),
            recipe: recipe.resolved_for(scene),
            bake_box,
            baker,
            load,
            split,
        })
    }

    /// Adds `scene_load` (the caller's loading of the scene, timed with a
    /// [`Clock`]) to the `load` phase this bake reports, which otherwise
    /// holds the building of the tracer only.
    pub fn with_load_time(mut self, scene_load: &PhaseTime) -> Self {
        let mut t = scene_load.clone();
        t.phase = self.load.phase.clone();
        self.load.add(&t);
        self
    }

    /// The tracer's ray count now (for [`Clock`]).
    fn rays(&self) -> u64 {
        self.baker.tracer().rays()
    }

    /// The resolved recipe (its box written out).
    pub fn recipe(&self) -> &Recipe {
        &self.recipe
    }

    /// The box probes go in.
    pub fn bake_box(&self) -> Aabb {
        self.bake_box
    }

    /// The ray tracer and capture over the scene.
    pub fn baker(&self) -> &Baker<'s> {
        &self.baker
    }

    /// The scene.
    pub fn scene(&self) -> &'s Scene {
        self.scene
    }

    /// The record a file of this bake stores.
    pub fn record(&self) -> BakeRecord {
        BakeRecord::new(&self.scene_name, self.scene, self.recipe.clone())
    }

    /// Stage 1: where the probes go. A manual placement's positions are
    /// checked where the capture will put them (the virtual offset moves
    /// probes out of geometry and lamps), before the capture: a set that
    /// spans no volume there is refused now rather than after the capture.
    pub fn place(&self, progress: Progress<'_>) -> Result<Placed, PipelineError> {
        let capture = self.placement_capture();
        let mut report = PlacementReport {
            count: 0,
            held_out_error: None,
            light_shells: None,
        };
        let mut phases = Vec::new();
        let mut free_points = Vec::new();
        let positions = match &self.recipe.placement {
            Placement::Grid { budget, cell } => {
                let n = budget.or(cell.is_none().then_some(Placement::DEFAULT_BUDGET));
                grid_points(&self.bake_box, *cell, n)?
            }
            Placement::Manual { positions } => {
                let pts = read_positions(positions)?;
                let flat =
                    |e: crate::delaunay::DelaunayError, why: &str| PipelineError::Positions {
                        path: positions.clone(),
                        message: format!("the probe positions cannot be tetrahedralized{why}: {e}"),
                    };
                crate::delaunay::tetrahedralize(&pts).map_err(|e| flat(e, ""))?;
                let captured = self.baker.capture_positions(&pts, 0, &capture)?;
                crate::delaunay::tetrahedralize(&captured).map_err(|e| {
                    flat(
                        e,
                        " once the virtual offset has moved the probes in geometry or in \
                         sphere lights out of them",
                    )
                })?;
                pts
            }
            _ => {
                let method = self.recipe.placement_method(None);
                let (placed, sub) = crate::placement::place_timed(
                    &self.baker,
                    self.bake_box,
                    &method,
                    &capture,
                    &|phase, d, t| progress(&format!("placement: {phase}"), d, t),
                )?;
                phases = sub;
                free_points = placed.free_points;
                if let Placement::Adaptive { .. } = self.recipe.placement {
                    report.held_out_error = placed.stats.held_out_error;
                    report.light_shells = Some(placed.stats.light_shells);
                }
                placed.positions
            }
        };
        report.count = positions.len();
        Ok(Placed {
            positions,
            report,
            phases,
            free_points,
        })
    }

    /// Stage 2: captures shard `shard` of `shards` of `positions` (`0, 1`:
    /// all of them). Each probe's random numbers depend on the seed and its
    /// global index only, so a shard's probes equal the whole bake's.
    pub fn capture(
        &self,
        positions: &[Vec3],
        shard: usize,
        shards: usize,
        progress: Progress<'_>,
    ) -> Result<BakeOutput, PipelineError> {
        let range = crate::capture::shard_range(positions.len(), shard, shards)?;
        let mut settings = self.recipe.capture_settings();
        if !self.split.candidates.is_empty() {
            // Every candidate's direct light left out and reported apart.
            settings.exclude_direct = self.split.excluded_groups(&self.split.candidates);
            settings.groups = true;
            settings.split_direct = true;
        }
        Ok(self
            .baker
            .bake_shard(positions, shard, shards, &settings, &|done, _| {
                progress("capture", done, range.len())
            })?)
    }

    /// Placement's capture settings: the probes' own, less the direct light
    /// of every candidate of the run-time light split.
    fn placement_capture(&self) -> CaptureSettings {
        let mut c = self.recipe.placement_capture();
        c.exclude_direct = self.split.excluded_groups(&self.split.candidates);
        c
    }

    /// The capture settings of the weight fit's training points for
    /// `file`: the probes' own, less the direct light of the lights its
    /// record says run at run time — the capture reports that light apart
    /// ([`TrainingSet::excluded`]), the fit adds it back to the truth.
    pub(crate) fn fit_capture(&self, file: &ProbeFile) -> CaptureSettings {
        let mut c = self.recipe.capture_settings();
        if let Some(r) = BakeRecord::from_json(file.metadata()) {
            let runtime = r.recipe.lights.runtime_indices();
            if runtime.iter().all(|&i| i < self.split.capture_groups.len()) {
                c.exclude_direct = self.split.excluded_groups(&runtime);
            }
        }
        c
    }

    /// Stage 3: the cloud file of a whole capture — tetrahedra,
    /// coefficients in the recipe's codec, light groups, validity — with
    /// `record` as its metadata.
    pub fn assemble(
        &self,
        out: &BakeOutput,
        record: &BakeRecord,
    ) -> Result<ProbeFile, PipelineError> {
        let (sh, groups) = stored(out, self.recipe.capture.indirect_only);
        let validity: Vec<_> = out.validity.iter().map(file_validity).collect();
        let codec = self.recipe.codec.codec();
        let mut f = cloud_file(
            &out.captured_positions,
            &sh,
            &validity,
            codec,
            &record.to_json(),
        )?;
        f.probe_set_mut().groups = light_groups(&groups, out.settings.order, codec)?;
        f.probe_set_mut().l1_mode = self.recipe.l1_evaluation.l1_mode();
        Ok(f)
    }

    /// Stage 3 of a shard: a part file without tetrahedra — the shard's
    /// captured positions, f32 SH, validity and light groups — whose record
    /// says which slice of `total` probes it holds. With run-time light
    /// candidates, the SH leaves their direct light out, the groups are the
    /// capture's (each candidate its own), and each candidate's scattered
    /// light follows under its group's name and [`SCATTERED_SUFFIX`]: what
    /// [`merge`] needs to split the lights over all probes.
    pub fn assemble_part(
        &self,
        out: &BakeOutput,
        record: &BakeRecord,
        shard: usize,
        shards: usize,
        total: usize,
    ) -> Result<ProbeFile, PipelineError> {
        let (sh, mut groups) = stored(out, self.recipe.capture.indirect_only);
        // The run-time light split is decided over all probes, in `merge`:
        // it needs each candidate's direct light apart, so its group's
        // scattered light goes along under a name of its own.
        for &i in &self.split.candidates {
            let name = &self.split.capture_groups[i];
            if let Some((_, g)) = out.groups_indirect.iter().find(|g| &g.0 == name) {
                groups.push((format!("{name}{SCATTERED_SUFFIX}"), g.clone()));
            }
        }
        let order = sh.first().map_or(out.settings.order, |s| s.order()) as u32;
        let flat: Vec<Vec3> = sh.iter().flat_map(|s| s.coeffs().iter().copied()).collect();
        let mut f = ProbeFile::cloud(out.captured_positions.clone(), order, &flat)?;
        f.probe_set_mut().validity = Some(out.validity.iter().map(file_validity).collect());
        f.probe_set_mut().groups = light_groups(&groups, out.settings.order, Codec::F32)?;
        let mut record = record.clone();
        record.part = Some(Part {
            shard,
            shards,
            first_index: out.first_index,
            count: out.positions.len(),
            total,
        });
        *f.metadata_mut() = record.to_json();
        Ok(f)
    }

    /// The training points of the probe-weight fit that `placed` already
    /// captured: its free-space points, when they hold what the fit needs
    /// (all light: not with `capture.indirect_only`, and not when a light
    /// is a run-time candidate, whose direct light placement leaves out).
    /// Empty otherwise, and for placements that capture none (grid,
    /// manual).
    pub fn captured_training(&self, placed: &Placed) -> TrainingSet {
        let settings = self.recipe.capture_settings();
        // Placement left out every candidate's direct light, which the fit
        // needs (it fits the combined answer): its points serve only when
        // there is no candidate.
        let (positions, sh) = if settings.split_direct || !self.split.candidates.is_empty() {
            (Vec::new(), Vec::new())
        } else {
            placed.free_points.iter().cloned().unzip()
        };
        TrainingSet {
            positions,
            sh,
            ..TrainingSet::default()
        }
    }

    /// Stage 4: the blend data the recipe asks for, baked into `file`.
    /// `whole`: false for a part, which gets only its probes' distance
    /// moments (the rest depends on every probe; `merge` bakes it).
    /// `captured`: training points of the weight fit already captured
    /// ([`Bake::captured_training`]). Laps `clock` after each kind:
    /// `distance moments`, `cell visibility` (occluder planes included),
    /// `weight fit` (with its sub-phases).
    pub fn blend_data(
        &self,
        file: &mut ProbeFile,
        whole: bool,
        captured: &TrainingSet,
        progress: Progress<'_>,
        clock: &mut Clock,
    ) -> Result<(), PipelineError> {
        let kinds = self.recipe.visibility_bake(&self.bake_box, whole);
        let tracer = self.baker.tracer();
        kinds.bake_moments_into(tracer, file, &|d, t| progress("distance moments", d, t))?;
        clock.lap("distance moments", self.rays());
        kinds.bake_cells_into(tracer, file, &|d, t| progress("cell visibility", d, t))?;
        clock.lap("cell visibility", self.rays());
        let sub = kinds.fit_weights_into(
            &self.baker,
            &self.fit_capture(file),
            file,
            captured,
            &|d, t| progress("weight fit", d, t),
        )?;
        clock.lap_with("weight fit", self.rays(), sub);
        Ok(())
    }

    /// The whole pipeline: the file a single machine writes.
    pub fn run(&self, progress: Progress<'_>) -> Result<Baked, PipelineError> {
        let mut clock = Clock::new(self.rays());
        let placed = self.place(progress)?;
        clock.lap_with("placement", self.rays(), placed.phases.clone());
        self.finish(&placed, progress, clock)
    }

    /// The stages after placement for `placed` positions (the sweeps place
    /// once and bake here); `clock` has timed what ran before.
    pub fn finish(
        &self,
        placed: &Placed,
        progress: Progress<'_>,
        mut clock: Clock,
    ) -> Result<Baked, PipelineError> {
        let out = self.capture(&placed.positions, 0, 1, progress)?;
        clock.lap("capture", self.rays());
        let mut record = self.record();
        record.placed = Some(placed.report.clone());
        let (out, mut split) = self.split_lights(out, &mut record, progress)?;
        if split.is_some() {
            clock.lap("light split", self.rays());
        }
        let mut file = self.assemble(&out, &record)?;
        if let Some((lights, _)) = split.as_mut() {
            file.probe_set_mut().runtime_lights = lights.take();
        }
        clock.lap("assembly", self.rays());
        let training = self.captured_training(placed);
        self.blend_data(&mut file, true, &training, progress, &mut clock)?;
        file.validate()?;
        let phases = self.phases(clock);
        let mut report = report(&file, &out, None, placed.report.clone(), phases)?;
        report.lights = split.map(|(_, r)| r);
        Ok(Baked { file, report })
    }

    /// The run-time light split of a whole capture (`lights` module):
    /// occlusion, the held-out choice, K per probe, the composed capture;
    /// the choice goes into `record`. Nothing to do without candidates.
    pub(crate) fn split_lights(
        &self,
        out: BakeOutput,
        record: &mut BakeRecord,
        progress: Progress<'_>,
    ) -> Result<SplitLights, PipelineError> {
        if self.split.candidates.is_empty() {
            return Ok((out, None));
        }
        progress("light split", 0, 1);
        let lights::Split {
            output,
            lights,
            resolved,
            report,
        } = lights::resolve(&self.baker, &self.split, &self.recipe, &self.bake_box, out)?;
        progress("light split", 1, 1);
        record.recipe.lights.resolved = resolved;
        Ok((output, Some((lights, report))))
    }

    /// Shard `shard` of `shards` as a part file for [`merge`]. Placement is
    /// deterministic, so every shard places the same probes and captures
    /// its slice. The run-time light split, which looks at every probe, is
    /// left to the merge ([`Bake::assemble_part`]).
    pub fn run_part(
        &self,
        shard: usize,
        shards: usize,
        progress: Progress<'_>,
    ) -> Result<Baked, PipelineError> {
        let mut clock = Clock::new(self.rays());
        let placed = self.place(progress)?;
        clock.lap_with("placement", self.rays(), placed.phases.clone());
        let out = self.capture(&placed.positions, shard, shards, progress)?;
        clock.lap("capture", self.rays());
        let mut record = self.record();
        record.placed = Some(placed.report.clone());
        let mut file = self.assemble_part(&out, &record, shard, shards, placed.positions.len())?;
        clock.lap("assembly", self.rays());
        let none = TrainingSet::default();
        self.blend_data(&mut file, false, &none, progress, &mut clock)?;
        file.validate()?;
        let phases = self.phases(clock);
        let report = report(
            &file,
            &out,
            Some([shard, shards]),
            placed.report.clone(),
            phases,
        )?;
        Ok(Baked { file, report })
    }

    /// The report's phases: `load`, then what `clock` timed.
    fn phases(&self, mut clock: Clock) -> Vec<PhaseTime> {
        let mut phases = vec![self.load.clone()];
        phases.extend(clock.take_phases());
        phases
    }
}

/// [`Bake::split_lights`]' result: the composed capture, and with a split
/// the file's run-time lights and what the split did.
type SplitLights = (
    BakeOutput,
    Option<(
        Option<probekit_runtime::format::RuntimeLights>,
        lights::LightSplitReport,
    )>,
);

/// The SH and light groups a bake stores: all light, or indirect only.
fn stored(out: &BakeOutput, indirect_only: bool) -> (Vec<ShRgb>, Vec<(String, Vec<ShRgb>)>) {
    if indirect_only {
        (
            out.indirect.clone().unwrap_or_else(|| out.sh.clone()),
            out.groups_indirect.clone(),
        )
    } else {
        (out.sh.clone(), out.groups.clone())
    }
}

/// The report of a finished file.
fn report(
    file: &ProbeFile,
    out: &BakeOutput,
    shard: Option<[usize; 2]>,
    placement: PlacementReport,
    phases: Vec<PhaseTime>,
) -> Result<BakeReport, PipelineError> {
    Ok(BakeReport {
        probes: file.positions().len(),
        tetrahedra: file
            .cloud()
            .tetrahedra
            .as_ref()
            .map_or(0, |t| t.vertices.len()),
        invalid: out.validity.iter().filter(|v| !v.valid).count(),
        bytes: file.bytes_by_section()?.values().sum(),
        groups: file.group_names().map(str::to_string).collect(),
        shard,
        placement,
        phases,
        lights: None,
    })
}

/// The capture settings a file's record says it was baked with (`None`
/// for a file without a record).
pub fn recorded_capture(file: &ProbeFile) -> Option<CaptureSettings> {
    BakeRecord::from_json(file.metadata()).map(|r| r.recipe.capture_settings())
}
