//! Irradiance volumes (Tatarchuk 2005, *Irradiance Volumes for Games*,
//! after Greger et al. 1998): a uniform grid or an adaptive octree of
//! radiance-SH samples with optional SH gradients, baked from any
//! [`VolumeSource`] and written as a `.probes` file of kind volume.
//!
//! Queries live in `probekit_runtime::volume` (re-exported here as
//! [`Volume`] and [`Interp`]) so engines get them without the baker.

mod baker_source;
#[cfg(test)]
mod baker_tests;
pub mod export;
mod finish;
mod lattice;
mod octree;
mod report;
mod settings;
mod source;
#[cfg(test)]
mod tests;
mod uniform;

pub use baker_source::{position_key, triangle_box_overlap, BakerSource};
pub use finish::{dilate, relative_difference, truncate_gradients};
pub use octree::build_adaptive;
pub use probekit_runtime::volume::{Interp, Volume, VolumeError};
pub use report::{depth_rows, plot_depths, DepthRow};
pub use settings::{
    near_cubic_roots, AdaptiveSettings, BuildStats, CommonSettings, GradientMode,
    DEFAULT_STEP_FRACTION,
};
pub use source::{Captured, LightsDemo, Slab, SphereLight, VolumeSource};
pub use uniform::{build_uniform, resolution_for_cell};

use crate::format::FormatError;

/// Why a volume cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum VolumeBuildError {
    /// The box is empty, inverted, flat or not finite
    /// ([`crate::scene::Aabb::check_bake_box`]).
    #[error(transparent)]
    BadBox(#[from] crate::scene::BakeBoxError),
    /// A resolution axis below 2.
    #[error("resolution {0:?}: every axis needs at least 2 probes")]
    BadResolution([u32; 3]),
    /// A cell size that is not a positive number.
    #[error("cell size {0} is not a positive number")]
    BadCell(f32),
    /// Depth limits out of order or above 20 (the second is the deepest of
    /// the maximum and emitter depths).
    #[error("depths min {0} / max {1}: need min <= max <= 20")]
    BadDepth(u32, u32),
    /// A root grid axis outside 1..=65536, more than 2^20 roots, or roots ×
    /// 2^max_depth above 2^24 cells per axis.
    #[error("root grid {0:?}: need 1..=65536 roots per axis, at most 2^20 in all, and roots × 2^max-depth <= 2^24")]
    BadRoots([u32; 3]),
    /// Too many samples requested.
    #[error("{0} samples per axis or in total is too many")]
    TooLarge(u64),
    /// Every sample is invalid (nothing to dilate from).
    #[error("no valid sample to dilate from")]
    NoValidSamples,
    /// The source returned SH of another order than it declared, or
    /// non-finite gradients.
    #[error("the capture source returned data of the wrong size or non-finite values")]
    SourceOrder,
    /// A gradient order of 0 ([`truncate_gradients`]).
    #[error("gradient order {0}: need at least 1 band")]
    BadGradientOrder(u32),
    /// `GradientMode::Analytic` with a source that has no closed form.
    #[error("the source has no closed-form gradients; use central differences")]
    NoAnalyticGradients,
    /// The file could not be assembled.
    #[error(transparent)]
    Format(#[from] FormatError),
}

/// The `inspect --json` summary of a volume file:
/// `{"probes":P,"leaves":L,"resolution":[x,y,z]|null,"roots":[x,y,z]|null,
/// "max_depth":D,"basis":"sh<order>/<codec>","gradients":bool,"bytes":B,
/// "bytes_by_section":{...}}` (`probes` = samples, as for clouds;
/// `resolution` for a uniform grid, `roots` and `max_depth` for an octree).
pub fn inspect_json(file: &crate::format::ProbeFile) -> Result<serde_json::Value, VolumeError> {
    let v = Volume::from_file(file)?;
    let (codec, gradients) = file.as_volume().map_or(("f32", false), |f| {
        (f.probes.coefficients.codec.name(), f.gradients.is_some())
    });
    let by = file.bytes_by_section()?;
    let bytes: u64 = by.values().sum();
    Ok(serde_json::json!({
        "kind": "volume",
        "probes": file.positions().len(),
        "leaves": v.leaf_count(),
        "resolution": v.grid_resolution(),
        "roots": v.root_grid(),
        "max_depth": v.max_depth(),
        "basis": format!("sh{}/{}", v.order(), codec),
        "gradients": gradients,
        "bytes": bytes,
        "bytes_by_section": by,
    }))
}
