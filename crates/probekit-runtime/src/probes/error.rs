//! Why a [`crate::Probes`] cannot be loaded ([`LoadError`]) or a query
//! answered ([`QueryError`]).

use crate::cloud::ProbeCloudError;
use crate::format::FormatError;
use crate::rig::RigError;
use crate::volume::VolumeError;
use thiserror::Error;

/// Why a file cannot be loaded as [`crate::Probes`].
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum LoadError {
    /// The bytes are not a valid `.probes` file (or the path cannot be
    /// read): truncated, corrupt, a format version this reader does not
    /// know, inconsistent sections.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// The cloud cannot be built: no tetrahedra (an unmerged shard part),
    /// an invalid mesh, blend data that does not match it, or a blend
    /// override out of range.
    #[error(transparent)]
    Cloud(#[from] ProbeCloudError),
    /// The volume cannot be built, or the chosen interpolation needs
    /// gradients it does not have.
    #[error(transparent)]
    Volume(#[from] VolumeError),
    /// Rig `index` of the file cannot be used.
    #[error("rig {index}: {source}")]
    Rig {
        /// The rig's index in the file.
        index: usize,
        /// What is wrong with it.
        source: RigError,
    },
    /// [`crate::BlendOverrides::visibility_bias`] is not finite.
    #[error("visibility bias {0}: expected a finite distance in metres")]
    VisibilityBias(f32),
    /// [`crate::BlendOverrides::visibility_sharpness`] is above 16.
    #[error("visibility sharpness {0}: expected 0 to 16")]
    VisibilitySharpness(u32),
}

/// Why a query was refused. Queries never panic; every bad input is one of
/// these. In a batch, `index` is the position of the first bad query (0 for
/// a single query); the results before it are written, the rest untouched.
#[derive(Clone, Copy, Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum QueryError {
    /// The file holds no probes to sample (a rigs-only file).
    #[error("the file holds no probes (rigs only): nothing to sample")]
    NoProbes,
    /// A position is NaN or infinite.
    #[error("query {index}: the position is not finite")]
    NonFinitePosition {
        /// Index of the query in its batch.
        index: usize,
    },
    /// A normal is NaN or infinite.
    #[error("query {index}: the normal is not finite")]
    NonFiniteNormal {
        /// Index of the query in its batch.
        index: usize,
    },
    /// A normal is zero (or too short to normalize).
    #[error("query {index}: the normal has zero length")]
    ZeroNormal {
        /// Index of the query in its batch.
        index: usize,
    },
    /// The slices of a batch differ in length.
    #[error(
        "batch of {positions} positions with {normals} normals and room for {results} results"
    )]
    LengthMismatch {
        /// Positions given.
        positions: usize,
        /// Normals given (equal to `positions` for SH batches).
        normals: usize,
        /// Results the output slice holds.
        results: usize,
    },
    /// There is no rig with that index.
    #[error("rig {index} does not exist: the file has {count} rigs")]
    NoSuchRig {
        /// The index asked for.
        index: usize,
        /// Rigs in the file.
        count: usize,
    },
    /// A rig update got samples of the wrong shape.
    #[error(transparent)]
    Rig(#[from] RigError),
}
