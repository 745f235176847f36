//! The pipeline of an irradiance volume: a uniform grid or an octree of
//! captured samples, with gradients, as the recipe's `[volume]` says.

use super::lights::LightSplit;
use super::PipelineError;
use crate::capture::CaptureSettings;
use crate::format::Parts;
use crate::format::ProbeFile;
use crate::progress::{Clock, PhaseTime, Progress};
use crate::recipe::{BakeRecord, GradientModeName, Recipe, VolumeSettings};
use crate::scene::{Aabb, Scene};
use crate::volume::{
    build_adaptive, build_uniform, truncate_gradients, BakerSource, BuildStats, VolumeSource,
};
use glam::Vec3;
use probekit_sh::ShRgb;
use serde::Serialize;

/// What a volume bake produced, in numbers.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VolumeReport {
    /// Samples stored.
    pub samples: usize,
    /// Leaves (cells).
    pub leaves: usize,
    /// Points captured (samples, prediction and gradient probes).
    pub captures: usize,
    /// Samples replaced by dilation.
    pub dilated: usize,
    /// Wall and CPU seconds and rays per stage: `load` (the tracer, with
    /// the caller's scene loading where it adds it), `build` (the grid or
    /// octree, with its sub-phases `capture`, the path tracing, and
    /// `refinement`, the rest) and `assembly` (the file).
    pub phases: Vec<PhaseTime>,
}

/// Bakes the volume `recipe` describes over `scene` (named `scene_name`,
/// which the file records): captured by the path tracer with the same
/// capture, validity and virtual offset as a cloud's probes; a virtual
/// offset may move a sample at most a quarter of the finest cell, so it
/// stays in its cell.
pub fn bake_volume(
    scene: &Scene,
    scene_name: &str,
    recipe: &Recipe,
    progress: Progress<'_>,
) -> Result<(ProbeFile, VolumeReport), PipelineError> {
    recipe.validate()?;
    if recipe.volume.gradients.mode == GradientModeName::Analytic {
        return Err(PipelineError::Recipe(crate::recipe::RecipeError::Value {
            layer: String::new(),
            key: "volume.gradients.mode".into(),
            message: "\"analytic\" needs a source with closed-form lights (builtin:lights-demo); \
                      path-traced scenes use \"central\""
                .into(),
        }));
    }
    let bake_box = recipe.bake_box_in(scene);
    bake_box.check_bake_box()?;
    let mut recipe = recipe.resolved_for(scene);
    let mut clock = Clock::new(0);
    // The run-time light split: candidates left out of every capture.
    let split = LightSplit::new(scene, &recipe.lights, recipe.capture.indirect_only);
    let mut settings = recipe.capture_settings();
    settings.exclude_direct = split.excluded_groups(&split.candidates);
    let mut src = BakerSource::new(scene, settings)?
        .with_progress(progress)
        .with_max_offset(0.25 * recipe.finest_volume_cell(&bake_box));
    if !split.candidates.is_empty() {
        src = src.with_light_groups(&split.capture_groups)?;
    }
    let load = clock.lap("load", src.rays()).clone();
    let record = BakeRecord::new(scene_name, scene, recipe.clone());
    let threshold = src.validity_threshold();
    let built = bake_volume_from(&src, &bake_box, &recipe, threshold, record);
    if let Some(e) = src.take_error() {
        return Err(e.into());
    }
    let (mut file, mut report) = built?;
    if !split.candidates.is_empty() {
        let mut clock = Clock::new(src.rays());
        split_volume_lights(&src, &split, &mut recipe, &bake_box, &mut file)?;
        report
            .phases
            .push(clock.lap("light split", src.rays()).clone());
    }
    // The build's rays and its capture sub-phase, from the tracer.
    let capture = src.capture_time();
    if let Some(build) = report.phases.iter_mut().find(|p| p.phase == "build") {
        build.rays = src.rays();
        let mut rest = build.clone();
        rest.phase = "refinement".into();
        rest.wall_seconds = (rest.wall_seconds - capture.wall_seconds).max(0.0);
        rest.cpu_seconds = (rest.cpu_seconds - capture.cpu_seconds).max(0.0);
        rest.rays = rest.rays.saturating_sub(capture.rays);
        build.phases = vec![capture, rest];
    }
    report.phases.insert(0, load);
    Ok((file, report))
}

/// The run-time light split of a built volume (`super::lights`): the
/// candidates' direct light at every sample from a capture of direct light
/// only, each sample's occlusion, the held-out choice and K per sample;
/// lights that end baked get their direct light back in the samples' SH
/// (their SH gradients, where the volume has them, keep the light it was
/// built with). The choice goes into the file's record.
fn split_volume_lights(
    src: &BakerSource<'_>,
    split: &LightSplit,
    recipe: &mut Recipe,
    bake_box: &Aabb,
    file: &mut ProbeFile,
) -> Result<(), PipelineError> {
    let baker = src.baker();
    let positions = file.positions().to_vec();
    let order = recipe.capture.order;
    let direct = CaptureSettings {
        bounces: 0,
        groups: true,
        split_direct: true,
        exclude_direct: Vec::new(),
        ..recipe.capture_settings()
    };
    let mut out = baker.bake_points_from(&positions, 0, &direct, &|_, _| {})?;
    let probes = file
        .probes()
        .ok_or(PipelineError::Parts("a volume without samples".into()))?;
    let coeffs = probes.coefficients.to_f32()?;
    let probes_order = probes.coefficients.order;
    let k = probes.coefficients.coeffs_per_probe();
    out.sh = coeffs
        .chunks(k)
        .map(|c| ShRgb::from_coeffs(c.to_vec()).unwrap_or_else(|| ShRgb::zeros(order)))
        .collect();
    out.captured_positions = positions;
    let mut no_groups = recipe.clone();
    no_groups.capture.groups = false;
    no_groups.capture.indirect_only = false;
    let s = super::lights::resolve(baker, split, &no_groups, bake_box, out)?;
    let flat: Vec<Vec3> = s
        .output
        .sh
        .iter()
        .flat_map(|c| c.coeffs().iter().copied())
        .collect();
    let codec = file.probe_set_mut().coefficients.codec;
    file.probe_set_mut().coefficients =
        crate::format::encode_coefficients(codec, probes_order, &flat)?;
    file.probe_set_mut().runtime_lights = s.lights;
    recipe.lights.resolved = s.resolved;
    if let Some(mut record) = BakeRecord::from_json(file.metadata()) {
        record.recipe.lights.resolved = recipe.lights.resolved.clone();
        *file.metadata_mut() = record.to_json();
    }
    file.validate()?;
    Ok(())
}

/// Bakes the volume `recipe` describes from any source (an analytic one,
/// `builtin:lights-demo`, or a [`BakerSource`]) over `bake_box`, samples
/// below `validity_threshold` dilated; `record` becomes the file's
/// metadata.
pub fn bake_volume_from(
    src: &dyn VolumeSource,
    bake_box: &Aabb,
    recipe: &Recipe,
    validity_threshold: f32,
    record: BakeRecord,
) -> Result<(ProbeFile, VolumeReport), PipelineError> {
    bake_box.check_bake_box()?;
    let mut clock = Clock::new(0);
    let (mut file, stats): (ProbeFile, BuildStats) = match recipe
        .volume_settings(bake_box, validity_threshold)?
    {
        VolumeSettings::Uniform { common, resolution } => build_uniform(src, &common, resolution)?,
        VolumeSettings::Octree(s) => build_adaptive(src, &s)?,
    };
    clock.lap("build", 0);
    if let Some(g) = recipe.volume.gradients.order {
        truncate_gradients(&mut file, g)?;
    }
    *file.metadata_mut() = record.to_json();
    file.probe_set_mut().l1_mode = recipe.l1_evaluation.l1_mode();
    file.validate()?;
    clock.lap("assembly", 0);
    Ok((
        file,
        VolumeReport {
            samples: stats.samples,
            leaves: stats.leaves,
            captures: stats.captures,
            dilated: stats.dilated,
            phases: clock.take_phases(),
        },
    ))
}
