//! What a cloud's blend uses beyond its probes, baked into a file as
//! `probekit bake` stores it: distance moments (`VISM`,
//! [`super::visibility`]), cell visibility (`CVSP`,
//! [`super::cell_visibility`]) and, fitted to training points with both in
//! place, per-probe blend weights (`PWGT`, [`super::blend_fit`]).
//!
//! `probekit bake`, `probekit eval --compare grid` (the grid gets what the
//! evaluated file has) and the `--plot` sweep all go through
//! [`VisibilityBake::bake_into`], so a cloud compared or plotted blends
//! exactly as a baked one; [`VisibilityBake::fit_weights_into`] then fits the
//! probe weights.

use super::blend_fit::{
    capture_training_points, fit_blend, BlendFitError, BlendFitSettings, TrainingSet,
};
use super::cell_planes::bake_file_cell_planes;
use super::cell_visibility::{bake_file_cell_visibility, CellLattice, CellVisibilityError};
use super::visibility::{bake_distance_moments, VisibilityError, VisibilitySettings};
use crate::capture::{Baker, CaptureSettings};
use crate::format::Parts;
use crate::progress::{Clock, PhaseTime};
use crate::trace::Tracer;
use probekit_runtime::cloud::ProbeCloud;
use probekit_runtime::format::{CloudBlend, ProbeFile};
use thiserror::Error;

/// Why a cloud's visibility data cannot be baked.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum VisibilityBakeError {
    /// The distance moments failed (settings or positions).
    #[error("distance moments: {0}")]
    Moments(#[from] VisibilityError),
    /// The cell visibility failed (subdivision, or the file's tetrahedra).
    #[error("cell visibility: {0}")]
    Cells(#[from] CellVisibilityError),
    /// The probe weight fit failed.
    #[error(transparent)]
    Weights(#[from] BlendFitError),
    /// Blend data belongs to a probe cloud; the file is another kind.
    #[error("blend data belongs to a probe cloud, not a {0} file")]
    NotACloud(&'static str),
}

/// Refuses a file that is not a cloud, so that its blend data can be set.
fn check_cloud(file: &ProbeFile) -> Result<(), VisibilityBakeError> {
    match file.as_cloud() {
        Some(_) => Ok(()),
        None => Err(VisibilityBakeError::NotACloud(file.kind().name())),
    }
}

/// Removes what the weight fit stores (probe weights and both brightness
/// exponents): it was fitted to the blend data a bake step replaces.
fn drop_fitted_weights(blend: &mut CloudBlend) {
    blend.probe_weights = None;
    blend.brightness_exponent = 0.0;
    blend.directional_exponent = 0.0;
}

/// Which visibility data to bake for a cloud.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VisibilityBake {
    /// Distance moments (`VISM`) with these settings; `None`: none.
    pub moments: Option<VisibilitySettings>,
    /// Cell visibility (`CVSP`) at this lattice subdivision (fixed, 1..=8,
    /// or from the cell size); `None`: none.
    pub cell_subdivision: Option<CellLattice>,
    /// Occluder planes (`CPLN`) for the cells one flat wall cuts, refining
    /// the cell visibility ([`super::cell_planes::bake_cell_planes`]);
    /// only with `cell_subdivision`.
    pub cell_planes: bool,
    /// Fitted probe weights (`PWGT`) with these settings; `None`: none.
    pub probe_weights: Option<BlendFitSettings>,
}

impl VisibilityBake {
    /// No visibility data: the cloud blends with plain barycentric weights.
    pub fn none() -> Self {
        Self {
            moments: None,
            cell_subdivision: None,
            cell_planes: false,
            probe_weights: None,
        }
    }

    /// The kinds `file` stores, with its settings: the moments' resolution
    /// and distance clamp (ray jitter from `seed`, default rays per texel),
    /// the cells' subdivision (chosen anew from the cell size where the
    /// metadata records `settings.cell_visibility` as `"auto"`), and probe
    /// weights fitted with the settings its metadata records
    /// (`settings.probe_weights`; the defaults with `seed` where absent). For a second cloud that should blend as `file`
    /// does (`eval --compare grid`, the `--plot` sweep).
    pub fn like(file: &ProbeFile, seed: u64) -> Self {
        let meta: serde_json::Value = serde_json::from_str(file.metadata()).unwrap_or_default();
        // A volume or rigs file blends without any of it.
        let none = CloudBlend::default();
        let b = file.as_cloud().map_or(&none, |c| &c.blend);
        Self {
            moments: b.distance_moments.as_ref().map(|v| VisibilitySettings {
                resolution: v.resolution,
                ..VisibilitySettings::new(v.max_distance, seed)
            }),
            cell_subdivision: b.cell_visibility.as_ref().map(|c| {
                match CellLattice::from_json(&meta["settings"]["cell_visibility"]) {
                    Some(CellLattice::Auto) => CellLattice::Auto,
                    _ => CellLattice::Fixed(c.subdivision()),
                }
            }),
            cell_planes: b.cell_planes.is_some(),
            // A file from before the exponent was fitted records none: it
            // blends with the one it stores (0).
            probe_weights: b.probe_weights.as_ref().map(|_| {
                BlendFitSettings::from_json(
                    &meta["settings"]["probe_weights"],
                    &BlendFitSettings {
                        brightness: Some(b.brightness_exponent),
                        directional: b.directional_exponent,
                        ..BlendFitSettings::new(seed)
                    },
                )
            }),
        }
    }

    /// Bakes the selected visibility kinds into `file` (a cloud with
    /// positions and, for the cells, tetrahedra), replacing what it had;
    /// kinds not selected are removed, and so are probe weights (fitted to
    /// the old blend: [`VisibilityBake::fit_weights_into`] fits them anew).
    /// `moments_progress(done, total)` counts probes,
    /// `cells_progress` cells and hull faces, then the cells whose planes
    /// are fitted. Deterministic (any thread
    /// count). The same as [`VisibilityBake::bake_moments_into`] then
    /// [`VisibilityBake::bake_cells_into`].
    pub fn bake_into(
        &self,
        tracer: &Tracer<'_>,
        file: &mut ProbeFile,
        moments_progress: &(dyn Fn(usize, usize) + Sync),
        cells_progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<(), VisibilityBakeError> {
        self.bake_moments_into(tracer, file, moments_progress)?;
        self.bake_cells_into(tracer, file, cells_progress)
    }

    /// The first half of [`VisibilityBake::bake_into`]: the distance
    /// moments (or none), and no probe weights. `progress(done, total)`
    /// counts probes.
    pub fn bake_moments_into(
        &self,
        tracer: &Tracer<'_>,
        file: &mut ProbeFile,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<(), VisibilityBakeError> {
        check_cloud(file)?;
        file.cloud_mut().blend.distance_moments = match &self.moments {
            Some(v) => Some(bake_distance_moments(
                tracer,
                file.positions(),
                v,
                progress,
            )?),
            None => None,
        };
        drop_fitted_weights(&mut file.cloud_mut().blend);
        Ok(())
    }

    /// The second half of [`VisibilityBake::bake_into`]: the cell
    /// visibility and occluder planes (or none), and no probe weights.
    /// `progress(done, total)` counts cells and hull faces, then the cells
    /// whose planes are fitted.
    pub fn bake_cells_into(
        &self,
        tracer: &Tracer<'_>,
        file: &mut ProbeFile,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<(), VisibilityBakeError> {
        check_cloud(file)?;
        file.cloud_mut().blend.cell_visibility = match self.cell_subdivision {
            Some(lattice) => Some(bake_file_cell_visibility(tracer, file, lattice, progress)?),
            None => None,
        };
        file.cloud_mut().blend.cell_planes = None;
        if self.cell_planes {
            file.cloud_mut().blend.cell_planes = bake_file_cell_planes(tracer, file, progress)?;
        }
        drop_fitted_weights(&mut file.cloud_mut().blend);
        Ok(())
    }

    /// After [`VisibilityBake::bake_into`]: fits probe weights to the blend
    /// `file` now has (as [`super::blend_fit::fit_file_probe_weights`]), training points captured
    /// with `capture` (indirect light only when `capture.split_direct`, as
    /// the bake stores), when selected; removes them otherwise.
    /// `captured`: training points already captured (a bake's placement
    /// captured them in free space; radiance SH as `file` stores it): they
    /// stand in for the half of the `points_per_probe ×` probes training
    /// points that [`super::blend_fit::capture_training_set`] draws uniformly in the box, and
    /// only the rest of those and the half in the cells are captured here
    /// ([`capture_training_points`]).
    /// When `file` has run-time lights, the fit predicts with the combined
    /// answer ([`TrainingSet::lights`]): `capture` and `captured` must then
    /// hold all light, the run-time lights' direct light included.
    /// `progress(done, total)` counts training points. Deterministic (any
    /// thread count). Returns the time of its steps (`training points`:
    /// their capture; `fit`), empty when there are no weights to fit.
    pub fn fit_weights_into(
        &self,
        baker: &Baker,
        capture: &CaptureSettings,
        file: &mut ProbeFile,
        captured: &TrainingSet,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<Vec<PhaseTime>, VisibilityBakeError> {
        check_cloud(file)?;
        drop_fitted_weights(&mut file.cloud_mut().blend);
        let Some(fit) = &self.probe_weights else {
            return Ok(Vec::new());
        };
        let rays = || baker.tracer().rays();
        let mut clock = Clock::new(rays());
        let cloud = ProbeCloud::from_file(file).map_err(BlendFitError::from)?;
        let count = (fit.points_per_probe as usize).saturating_mul(cloud.probe_count());
        // Half uniform in the box: the captured points stand in for them;
        // half in the cells, captured here.
        let uniform = count.div_ceil(2);
        let counts = [
            uniform.saturating_sub(captured.positions.len()),
            count - uniform,
        ];
        let mut training = captured.clone();
        let new = capture_training_points(
            baker,
            &baker.scene().bake_box(),
            cloud.mesh(),
            counts,
            capture,
            fit,
            progress,
        )?;
        training.positions.extend(new.positions);
        training.sh.extend(new.sh);
        training.excluded.extend(new.excluded);
        training.lights = file.probes().and_then(|p| p.runtime_lights.clone());
        if training.positions.is_empty() {
            return Err(BlendFitError::NoTrainingPoints.into());
        }
        clock.lap("training points", rays());
        let f = fit_blend(&cloud, &training, fit, &fit.exponents())?;
        clock.lap("fit", rays());
        file.cloud_mut().blend.probe_weights = Some(f.weights);
        file.cloud_mut().blend.brightness_exponent = f.brightness;
        file.cloud_mut().blend.directional_exponent = f.directional;
        Ok(clock.take_phases())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blend::cell_planes::{bake_cell_planes, CELL_PLANE_SEED};
    use crate::format::cloud::test_cloud_file;
    use glam::Vec3;
    use probekit_sh::ShRgb;

    /// `like` reproduces a file's kinds and settings, and `bake_into` gives
    /// the bytes the two bakers give on their own.
    #[test]
    fn like_then_bake_into_matches_the_separate_bakes() {
        let scene = crate::scene::tests_support::boxes_scene(&[(
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.3, 2.0, 2.0),
        )]);
        let tracer = Tracer::new(&scene);
        let mut pos = Vec::new();
        for i in 0..4 {
            for j in 0..3 {
                for k in 0..3 {
                    pos.push(Vec3::new(
                        -1.5 + i as f32,
                        0.3 + 0.7 * j as f32,
                        0.3 + 0.7 * k as f32,
                    ));
                }
            }
        }
        let mut a = test_cloud_file(&pos, &vec![ShRgb::zeros(2); pos.len()]);
        let vs = VisibilitySettings {
            resolution: 4,
            ..VisibilitySettings::new(5.0, 7)
        };
        let want = VisibilityBake {
            moments: Some(vs),
            cell_subdivision: Some(CellLattice::Fixed(2)),
            cell_planes: true,
            probe_weights: None,
        };
        a.cloud_mut().blend.probe_weights = Some(vec![2.0; pos.len()]);
        want.bake_into(&tracer, &mut a, &|_, _| {}, &|_, _| {})
            .unwrap();
        let moments = bake_distance_moments(&tracer, &pos, &vs, &|_, _| {}).unwrap();
        assert_eq!(a.cloud().blend.distance_moments.as_ref(), Some(&moments));
        let cells =
            bake_file_cell_visibility(&tracer, &a, CellLattice::Fixed(2), &|_, _| {}).unwrap();
        assert_eq!(a.cloud().blend.cell_visibility.as_ref(), Some(&cells));
        let mesh = probekit_runtime::cloud::ProbeCloud::mesh_from_file(&a).unwrap();
        let planes = bake_cell_planes(&tracer, &mesh, &cells, CELL_PLANE_SEED, &|_, _| {}).unwrap();
        assert!(!planes.is_empty());
        assert_eq!(a.cloud().blend.cell_planes.as_ref(), Some(&planes));
        // Weights fitted to the old blend are gone.
        assert!(a.cloud().blend.probe_weights.is_none());
        let like = VisibilityBake::like(&a, 7);
        assert_eq!(like.cell_subdivision, Some(CellLattice::Fixed(2)));
        assert!(like.cell_planes);
        assert_eq!(
            like.moments.map(|m| (m.resolution, m.max_distance)),
            Some((4, 5.0))
        );
        // `none` removes both.
        VisibilityBake::none()
            .bake_into(&tracer, &mut a, &|_, _| {}, &|_, _| {})
            .unwrap();
        assert!(
            a.cloud().blend.distance_moments.is_none()
                && a.cloud().blend.cell_visibility.is_none()
                && a.cloud().blend.cell_planes.is_none()
        );
        assert_eq!(VisibilityBake::like(&a, 7), VisibilityBake::none());
        // A bad subdivision is a typed error.
        let bad = VisibilityBake {
            moments: None,
            cell_subdivision: Some(CellLattice::Fixed(99)),
            cell_planes: true,
            probe_weights: None,
        };
        assert!(matches!(
            bad.bake_into(&tracer, &mut a, &|_, _| {}, &|_, _| {}),
            Err(VisibilityBakeError::Cells(_))
        ));
    }
}
