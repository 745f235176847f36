//! Export of irradiance volumes as KTX2 3D textures for GPUs and for Bevy.
//!
//! * [`ktx2`]: the KTX2 container ([`Ktx2`], writer and reader).
//! * [`lattice`]: the dense export ([`export_ktx2`]): radiance SH on the
//!   uniform lattice of the volume's samples (an octree resampled at its
//!   finest level), in one of two encodings ([`Ktx2Encoding`]).
//! * [`bricks`]: an octree as a brick atlas plus an indirection texture
//!   ([`export_bricks`]), and [`export_auto`], the smaller of the two.
//! * [`bevy`]: Bevy's ambient-cube `IrradianceVolume` texture
//!   ([`export_bevy`]) with its `LightProbe` transform and the intensity
//!   that matches probekit's units.

pub mod bevy;
pub mod bricks;
pub mod ktx2;
pub mod lattice;

pub use bevy::{
    bevy_exposure, bevy_intensity_for_exposure, bevy_texel, export_bevy, BevyExport, BevyLattice,
    BEVY_DEFAULT_EV100,
};
pub use bricks::{export_auto, export_bricks, BRICK_CELLS};
pub use ktx2::{Ktx2, TexelFormat};
pub use lattice::{export_ktx2, Ktx2Encoding, Ktx2Export};

use super::VolumeError;
use std::path::{Path, PathBuf};

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The volume query failed.
    #[error(transparent)]
    Volume(#[from] VolumeError),
    /// Writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// Too many texels.
    #[error("resolution {0:?} is too large to export")]
    TooLarge([u32; 3]),
    /// A brick atlas was asked of a uniform volume (it has no octree).
    #[error("a brick atlas needs an octree volume; export a uniform volume with --format ktx2")]
    NotAnOctree,
    /// A malformed KTX2 file (reader).
    #[error("not a valid KTX2 file: {0}")]
    BadKtx2(&'static str),
    /// A Bevy voxel grid with fewer than 2 voxels on an axis (its voxels sit
    /// on the box's corners and faces, which takes 2 per axis).
    #[error("resolution {0:?}: a Bevy irradiance volume needs at least 2 voxels per axis")]
    BevyResolution([u32; 3]),
    /// The quantized encoding needs at least 2 bands.
    #[error("quantized export needs SH order >= 2")]
    OrderTooLow,
}

/// Writes an [`export_ktx2`] result into directory `dir` (created).
pub fn write_ktx2_export(export: &Ktx2Export, dir: &Path) -> Result<(), ExportError> {
    std::fs::create_dir_all(dir).map_err(|source| ExportError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    // Each file goes to a temporary name and is renamed into place, so an
    // interrupted export never leaves a half-written texture.
    let put = |p: PathBuf, bytes: &[u8]| {
        crate::format::write_atomic(&p, bytes).map_err(|e| match e {
            crate::format::WriteError::Io { path, source } => ExportError::Io { path, source },
            other => ExportError::Io {
                path: p.clone(),
                source: std::io::Error::other(other.to_string()),
            },
        })
    };
    for (name, t) in &export.textures {
        put(dir.join(name), &t.to_bytes())?;
    }
    let json = serde_json::to_string_pretty(&export.sidecar).expect("JSON value");
    put(dir.join("volume.json"), json.as_bytes())
}
