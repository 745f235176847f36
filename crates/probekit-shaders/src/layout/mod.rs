//! The GPU buffers the WGSL library reads, and packers that fill them from
//! loaded probe files (`docs/shaders.md`, "Buffers", gives every layout).
//!
//! * [`pack_cloud`]: a [`ProbeCloud`](probekit_runtime::ProbeCloud) — positions, coefficients,
//!   tetrahedra, hull faces, distance moments (`VISM`), cell visibility
//!   (`CVSP`) and occluder planes (`CPLN`), fitted probe weights with the
//!   brightness and directional exponents (`PWGT`), the per-probe
//!   luminances the runtime precomputes, and a start grid for the GPU walk —
//!   into the one `u32` buffer `pk_cloud` of `shaders/probekit_cloud.wgsl`;
//!   [`pack_cloud_with_lights`] (and [`pack_cloud_file`]) add a file's
//!   run-time lights (`LITE`) and each probe's 8-bit occlusion of them
//!   (`OCCL`).
//! * [`pack_volume_grid`]: a uniform volume into the `PkVolumeGrid` uniform,
//!   `pk_sh_coeffs` and `pk_sh_gradients` of `shaders/probekit_buffers.wgsl`.
//! * [`pack_bricks`]: the textures of a brick-atlas export into the one
//!   `u32` buffer `pk_bricks` of `shaders/probekit_bricks.wgsl`.
//! * [`pack_split_rig`]: a runtime [`SplitRig`](probekit_runtime::rig::SplitRig)
//!   after its per-frame update — model, box, current parameters, near
//!   lights with their shares — into `pk_rig` of `shaders/probekit_rig.wgsl`.
//! * [`pack_rig_light`]: one light record, the layout rigs and clouds share
//!   (`shaders/probekit_lights.wgsl`); [`pack_sphere_table`]: the
//!   sphere-light table into `pk_sphere_table`, which the light evaluation
//!   of both reads.
//!
//! Buffers are little-endian `u32` words (`f32` values as their bits);
//! [`words_to_bytes`] gives the bytes to upload.

mod bricks;
mod cloud;
mod lights;
mod rig;
mod volume;

pub use bricks::{pack_bricks, BrickAtlas, BrickEncoding, BRICKS_HEADER, BRICKS_HEADER_WORDS};
pub use cloud::{
    cell_code, pack_cloud, pack_cloud_file, pack_cloud_with_lights, PackedCloud, CLOUD_FLAG_CELLS,
    CLOUD_FLAG_PROBE_WEIGHTS, CLOUD_FLAG_VISIBILITY, CLOUD_HEADER, CLOUD_HEADER_WORDS, CLOUD_HULL,
    CLOUD_HULL_WORDS, CLOUD_NONE, CLOUD_TET_WORDS,
};
pub use lights::{
    light_occlusion_words, pack_rig_light, pack_sphere_table, LIGHT_CODES, RIG_LIGHT_WORDS,
};
pub use rig::{pack_split_rig, RIG_CODES, RIG_HEADER, RIG_HEADER_WORDS, RIG_MAX_ORDER};
pub use volume::{pack_volume_grid, PackedVolumeGrid, VOLUME_GRADIENT_FLOATS, VOLUME_PROBE_FLOATS};

use probekit_runtime::cloud::ProbeCloudError;
use probekit_runtime::{FormatError, VolumeError};
use thiserror::Error;

/// Why a packer refuses its input.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum LayoutError {
    /// The file is not a probe cloud the runtime accepts.
    #[error(transparent)]
    Cloud(#[from] ProbeCloudError),
    /// The file is not a volume the runtime accepts.
    #[error(transparent)]
    Volume(#[from] VolumeError),
    /// The coefficients could not be decoded.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// A uniform-volume packer was given an octree (or a volume without a
    /// grid).
    #[error("not a uniform volume (no GRID section)")]
    NotAGrid,
    /// The buffer would exceed the 32-bit word offsets the shaders use.
    #[error("the {what} buffer would hold {words} words, more than 2^31")]
    TooLarge {
        /// Which buffer.
        what: &'static str,
        /// Words it would hold.
        words: usize,
    },
    /// The mesh's hull faces do not match its tetrahedra's hull faces in
    /// order (the runtime's numbering changed).
    #[error("hull face {face} does not match the tetrahedron face that owns it")]
    HullOrder {
        /// The hull face.
        face: usize,
    },
    /// A brick atlas whose sizes do not agree.
    #[error("brick atlas: {0}")]
    Bricks(String),
    /// A rig of more SH bands than the shader evaluates
    /// ([`RIG_MAX_ORDER`]).
    #[error("rig of SH order {order}; the shaders evaluate at most order 3 (L2)")]
    RigOrder {
        /// The rig's order (bands).
        order: usize,
    },
    /// Run-time lights whose occlusion table has another number of probes
    /// than the cloud.
    #[error("run-time light occlusion of {rows} probes for a cloud of {probes}")]
    LightOcclusion {
        /// The cloud's probes.
        probes: usize,
        /// The occlusion table's probes.
        rows: usize,
    },
}

/// The little-endian bytes of `words` (what to upload as a storage buffer).
pub fn words_to_bytes(words: &[u32]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// The little-endian bytes of `floats`.
pub fn floats_to_bytes(floats: &[f32]) -> Vec<u8> {
    floats.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// Checks that `words` words fit the shaders' 31-bit offsets.
fn check_size(what: &'static str, words: usize) -> Result<(), LayoutError> {
    if words >= 1 << 31 {
        return Err(LayoutError::TooLarge { what, words });
    }
    Ok(())
}
