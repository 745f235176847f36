//! Querying a baked file: which kind of file it is (a probe cloud or an
//! irradiance volume) and how its irradiance and SH are read at points
//! ([`Predictor`]), the barycentric SH blend, and what a cloud's blend does
//! at given points (outside the hull, weight on probes hidden by geometry).

use crate::trace::free_space::{segment_clear, EvalPoint};
use crate::trace::Tracer;
use glam::Vec3;
use probekit_runtime::cloud::WalkState;
use probekit_runtime::{Interp, ProbeCloud, ProbeCloudError, ProbeFile, Volume, VolumeError};
use probekit_sh::ShRgb;
use thiserror::Error;

/// Why a baked file cannot be evaluated.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum PredictError {
    /// The file is a cloud whose tetrahedra or coefficients are unusable.
    #[error(transparent)]
    Cloud(#[from] ProbeCloudError),
    /// The file is a volume that cannot be sampled.
    #[error(transparent)]
    Volume(#[from] VolumeError),
}

/// A baked file ready to answer irradiance queries, whatever its kind: a
/// probe cloud (tetrahedral blend, outer cells outside the hull) or an
/// irradiance volume (uniform or octree, with the chosen interpolation).
/// `probekit query`, `probekit eval` and the renderer all go through it, so
/// clouds and volumes are measured the same way.
#[derive(Clone, Debug)]
// One per loaded file, never in bulk: boxing the cloud would only add an
// indirection to every query.
#[allow(clippy::large_enum_variant)]
pub enum Predictor {
    /// A probe cloud.
    Cloud(ProbeCloud),
    /// An irradiance volume and how to interpolate it.
    Volume(Volume, Interp),
}

impl Predictor {
    /// A cloud when the file has tetrahedra, otherwise a volume sampled with
    /// `interp` (ignored for clouds).
    pub fn from_file(file: &ProbeFile, interp: Interp) -> Result<Self, PredictError> {
        Ok(if file.tetrahedra.is_some() {
            Predictor::Cloud(ProbeCloud::from_file(file)?)
        } else {
            Predictor::Volume(Volume::from_file(file)?, interp)
        })
    }

    /// Irradiance `E(n)` (not divided by π) at `p` for unit normal `n`;
    /// `state` caches the cloud walk between coherent queries.
    pub fn irradiance(
        &self,
        p: Vec3,
        n: Vec3,
        state: &mut WalkState,
    ) -> Result<Vec3, PredictError> {
        Ok(match self {
            Predictor::Cloud(c) => c.irradiance(p, n, state),
            Predictor::Volume(v, i) => v.irradiance(p, n, *i)?,
        })
    }

    /// SH order (bands) of the file's coefficients.
    pub fn order(&self) -> usize {
        match self {
            Predictor::Cloud(c) => c.order() as usize,
            Predictor::Volume(v, _) => v.order(),
        }
    }

    /// Interpolated radiance SH at `p` into `out[..order²]` (`out` must hold
    /// at least `order²` coefficients); `state` caches the cloud walk.
    pub fn sh_at(
        &self,
        p: Vec3,
        state: &mut WalkState,
        out: &mut [Vec3],
    ) -> Result<(), PredictError> {
        match self {
            Predictor::Cloud(c) => c.sh_at(p, state, out),
            Predictor::Volume(v, i) => v.sample_sh(p, *i, out)?,
        }
        Ok(())
    }

    /// [`blends_hidden_probes`] for a probe cloud; `None` for a volume.
    pub fn blends_hidden_probes(&self, tracer: &Tracer, points: &[EvalPoint]) -> Option<Vec<bool>> {
        match self {
            Predictor::Cloud(c) => Some(blends_hidden_probes(c, tracer, points)),
            Predictor::Volume(..) => None,
        }
    }

    /// [`outside_hull`] for a probe cloud; `None` for a volume.
    pub fn outside_hull(&self, points: &[EvalPoint]) -> Option<Vec<bool>> {
        match self {
            Predictor::Cloud(c) => Some(outside_hull(c, points)),
            Predictor::Volume(..) => None,
        }
    }

    /// Irradiance at every point, in order.
    pub fn predict(&self, points: &[EvalPoint]) -> Result<Vec<Vec3>, PredictError> {
        let mut st = WalkState::new();
        points
            .iter()
            .map(|p| self.irradiance(p.position, p.normal, &mut st))
            .collect()
    }
}

/// Order-`order` radiance SH blended from the probes `idx` of `sh` with the
/// barycentric weights `w`, in vertex order; vertices of weight 0 (and
/// indices past `sh`) are skipped.
pub(crate) fn blend_sh(sh: &[ShRgb], idx: [u32; 4], w: [f32; 4], order: usize) -> ShRgb {
    let mut acc = ShRgb::zeros(order);
    for k in 0..4 {
        if w[k] != 0.0 {
            if let Some(s) = sh.get(idx[k] as usize) {
                acc.add_scaled(s, w[k]);
            }
        }
    }
    acc
}

/// Whether each point lies outside the convex hull of `cloud`'s probes, in
/// order: it is lit from the outer cell of the closest hull face
/// ([`probekit_runtime::cloud::Location::Outside`]). Probes keep a
/// clearance from surfaces, so the band between a room's walls, floor or
/// ceiling and its outermost probes is such a region; a hull face there
/// can reach past an inner wall (a closet's floor corner lit from a face
/// between probes in the rooms around it: BENCHMARKS.md, "Leaks in sight
/// given a share").
pub fn outside_hull(cloud: &ProbeCloud, points: &[EvalPoint]) -> Vec<bool> {
    let mut st = WalkState::new();
    points
        .iter()
        .map(|p| {
            matches!(
                cloud.mesh().locate(p.position, &mut st),
                probekit_runtime::cloud::Location::Outside { .. }
            )
        })
        .collect()
}

/// Whether each point's blend in `cloud` gives weight to a probe that
/// geometry hides from it (the segment from the point to the probe is
/// blocked, [`crate::trace::free_space::segment_clear`]; the weights of
/// [`ProbeCloud::weights_at`], whose positive ones the directional blend
/// keeps), in order: a leak at such a point is light from behind a wall; one
/// elsewhere is an error of interpolating light in sight (a gradient next to
/// a lamp, say).
pub fn blends_hidden_probes(
    cloud: &ProbeCloud,
    tracer: &Tracer,
    points: &[EvalPoint],
) -> Vec<bool> {
    let pos = cloud.mesh().positions();
    let mut st = WalkState::new();
    points
        .iter()
        .map(|p| {
            let (idx, w) = cloud.weights_at(p.position, &mut st);
            (0..4).any(|k| w[k] > 0.0 && !segment_clear(tracer, p.position, pos[idx[k] as usize]))
        })
        .collect()
}
