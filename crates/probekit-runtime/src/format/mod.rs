//! The `.probes` file: one versioned little-endian binary format for probe
//! clouds, irradiance volumes and irradiance rigs.
//!
//! The byte-by-byte specification, for engines writing their own loader, is
//! `docs/file-format.md`. In short: a 48-byte header (magic `PROBEKIT`,
//! major/minor version, kind, flags, section count, file length, CRC-32 of
//! header and table), a table of 32-byte section entries (id, offset,
//! length, CRC-32), then sections, each starting on a 16-byte boundary with
//! a 16-byte section header followed by arrays that each start 16-aligned.
//!
//! [`ProbeFile::from_bytes`] checks everything before trusting anything:
//! bounds with checked arithmetic, checksums, counts against lengths (no
//! allocation larger than the file), index ranges, finiteness. It never
//! panics on any input (fuzzed: `fuzz/` and `tests/fuzz_reader.rs`).
//!
//! [`ProbeFile::to_bytes`] is the inverse, deterministic (same
//! [`ProbeFile`] → same bytes). The baking library (`probekit::format`)
//! adds codec encoding and atomic file writing.

mod codec;
mod contents;
mod crc;
mod error;
mod groups;
#[cfg(feature = "write")]
pub mod layout;
#[cfg(not(feature = "write"))]
#[allow(dead_code)]
pub(crate) mod layout;
mod lights;
mod octree_compact;
mod read;
mod validate;
mod visibility;
mod write;

pub use codec::{Codec, Coefficients};
pub use contents::{
    CloudBlend, CloudFile, ProbeFile, ProbeSet, RigFile, VolumeFile, VolumeStructure,
};
pub use error::FormatError;
pub use groups::{LightGroup, Relighter};
pub use layout::SectionId;
pub use lights::{quantize_occlusion, LightOcclusion, RuntimeLight, RuntimeLights};
pub use visibility::{DistanceMoments, MAX_VISIBILITY_RESOLUTION};

// The byte-level reading and writing the baker and tools use (feature
// `write`); an engine loads through `ProbeFile::from_bytes` or `crate::Probes`.
#[cfg(feature = "write")]
pub use codec::{f16_is_non_finite, f16_to_f32};
#[cfg(feature = "write")]
pub use crc::{crc32, Crc32};
#[cfg(not(feature = "write"))]
use crc::{crc32, Crc32};
#[cfg(feature = "write")]
pub use octree_compact::{lattice_pos, lattice_step};
#[cfg(feature = "write")]
pub use read::{file_bytes_by_section, read_sections, FileHeader, RawSection};
#[cfg(feature = "write")]
pub use write::{assemble_file, SectionBuilder};

use crate::prelude::*;
use glam::Vec3;
#[cfg(feature = "std")]
use std::path::Path;

/// What a file holds; decides which sections it must and may hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ProbeFileKind {
    /// A probe cloud (positions, coefficients, usually tetrahedra). Id 0.
    Cloud,
    /// An irradiance volume: uniform (`GRID`) or adaptive (`OCTC`). Id 1.
    Volume,
    /// Irradiance rigs (`RIGS`) without probes. Id 2.
    Rig,
}

impl ProbeFileKind {
    /// Id stored in the header.
    pub const fn id(self) -> u32 {
        match self {
            Self::Cloud => 0,
            Self::Volume => 1,
            Self::Rig => 2,
        }
    }

    /// The kind with header id `id`.
    pub fn from_id(id: u32) -> Result<Self, FormatError> {
        match id {
            0 => Ok(Self::Cloud),
            1 => Ok(Self::Volume),
            2 => Ok(Self::Rig),
            _ => Err(FormatError::UnknownKind(id)),
        }
    }

    /// `"cloud"`, `"volume"` or `"rig"`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Cloud => "cloud",
            Self::Volume => "volume",
            Self::Rig => "rig",
        }
    }
}

/// How the coefficients of an L1 file (SH order 2: the 13-byte `l1` codec,
/// or `f32`/`f16` at order 2) are turned into irradiance. The file states
/// its intent (the header's flags), and [`crate::LoadOptions::l1_mode`] can override it.
/// Files of any other order ignore it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum L1Mode {
    /// The L1 radiance SH as they are: irradiance is the clamped-cosine
    /// convolution of bands 0 and 1 (Ramamoorthi & Hanrahan 2001).
    #[default]
    Linear,
    /// Hallucinated ZH3 (Roughton et al., "ZH3: Quadratic Zonal Harmonics",
    /// I3D 2024): the L1 coefficients are blended as usual, then a zonal
    /// band-2 lobe about the blended luminance axis is derived from them
    /// ([`probekit_sh::zh3::zh3_hallucinate`]), so the result has the
    /// sharper falloff of L2 for the storage of L1.
    Zh3Hallucinated,
}

impl L1Mode {
    /// The mode stored in a header's flags word ([`layout::FLAGS_L1_MODE`]
    /// bits); `None` for the reserved values 2 and 3.
    pub(crate) fn from_flags(flags: u32) -> Option<Self> {
        match flags & layout::FLAGS_L1_MODE {
            0 => Some(Self::Linear),
            1 => Some(Self::Zh3Hallucinated),
            _ => None,
        }
    }

    /// The header flag bits of this mode.
    pub(crate) const fn flags(self) -> u32 {
        match self {
            Self::Linear => 0,
            Self::Zh3Hallucinated => 1,
        }
    }
}

/// Capture validity of one probe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Validity {
    /// Fraction of the probe's capture rays that hit front faces or escaped
    /// (1 = fully valid), or whatever finite score the baker documents.
    pub value: f32,
    /// Bit set of [`layout::VALIDITY_INVALID`] and
    /// [`layout::VALIDITY_VIRTUAL_OFFSET`]; other bits are kept, not interpreted.
    pub flags: u32,
}

/// Tetrahedra of a probe cloud (structure of arrays, one entry per tetrahedron).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TetSection {
    /// The four probe indices of each tetrahedron.
    pub vertices: Vec<[u32; 4]>,
    /// `neighbours[t][i]` is the tetrahedron across the face opposite
    /// `vertices[t][i]`, or [`layout::NONE`] on the hull.
    pub neighbours: Vec<[u32; 4]>,
    /// Row-major 3×4 matrix `M` giving barycentric coordinates of point `p`:
    /// `b_i = M[i][0]·x + M[i][1]·y + M[i][2]·z + M[i][3]` for `i = 0..3`,
    /// `b_3 = 1 − b_0 − b_1 − b_2` (weights of `vertices[t][0..4]`).
    pub barycentric: Vec<[[f32; 4]; 3]>,
}

/// Outer cells: the table of convex-hull faces from which points outside the
/// hull are extrapolated (structure of arrays, one entry per hull face).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OuterCells {
    /// The three probe indices of each hull face, counter-clockwise seen
    /// from outside.
    pub vertices: Vec<[u32; 3]>,
    /// `adjacent[f][i]` is the hull face sharing the edge opposite
    /// `vertices[f][i]`.
    pub adjacent: Vec<[u32; 3]>,
    /// Face plane `(n, d)` with outward unit normal `n`: a point `p` is
    /// outside the face when `n·p + d > 0`.
    pub planes: Vec<[f32; 4]>,
    /// The tetrahedron owning each face, or [`layout::NONE`].
    pub tetrahedra: Vec<u32>,
}

/// One node of an adaptive volume's octree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OctreeNode {
    /// Box minimum corner (metres, world space).
    pub min: Vec3,
    /// Box maximum corner.
    pub max: Vec3,
    /// Index of the first of 8 consecutive children, or [`layout::NONE`] for
    /// a leaf. Child `k` covers the octant with bit 0 of `k` = +x half, bit 1
    /// = +y, bit 2 = +z. Children always come after their parent.
    pub first_child: u32,
    /// Depth (root = 0).
    pub depth: u32,
    /// First entry of this node's sample list in [`Octree::samples`].
    pub sample_offset: u32,
    /// Length of the sample list. For a leaf, the first 8 entries are its
    /// corners in the same bit order as children; further entries are
    /// samples of finer neighbours on its faces and edges.
    pub sample_count: u32,
}

/// An adaptive volume's octree — or a forest of octrees whose roots tile the
/// volume's box as a grid — : nodes (roots first) and the sample lists they
/// index (probe indices).
///
/// A single root cell copies the box's aspect ratio into every cell of the
/// tree (an 8 × 3 × 4 m room gives cells 2.7× longer in x than in y); a
/// grid of near-cubic roots keeps cells near-cubic at every depth, which is
/// what interpolation error and Tatarchuk's cell-size heuristics assume
/// (see `docs/file-format.md`).
#[derive(Clone, Debug, PartialEq)]
pub struct Octree {
    /// Nodes; nodes `0..roots[0]·roots[1]·roots[2]` are the roots (depth 0),
    /// root `(i, j, k)` at index `i + rx·(j + ry·k)`, in the same box order
    /// as [`VolumeGrid`] cells.
    pub nodes: Vec<OctreeNode>,
    /// Concatenated per-node sample lists: probe indices.
    pub samples: Vec<u32>,
    /// Root cells per axis (x, y, z), each ≥ 1; `[1, 1, 1]` is a single
    /// octree.
    pub roots: [u32; 3],
}

impl Default for Octree {
    fn default() -> Self {
        Self {
            nodes: Vec::new(),
            samples: Vec::new(),
            roots: [1, 1, 1],
        }
    }
}

impl Octree {
    /// Number of root nodes, `rx·ry·rz` (saturating).
    pub fn root_count(&self) -> usize {
        self.roots
            .iter()
            .fold(1usize, |a, &r| a.saturating_mul(r as usize))
    }

    /// Whether this is a forest (more than one root).
    pub fn is_forest(&self) -> bool {
        self.roots != [1, 1, 1]
    }
}

/// A uniform volume's grid: probes at the corners of `resolution − 1` cells
/// per axis, probe `(i, j, k)` at index `i + rx·(j + ry·k)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeGrid {
    /// Box minimum corner (metres, world space).
    pub min: Vec3,
    /// Box maximum corner.
    pub max: Vec3,
    /// Probes per axis (x, y, z), each at least 1.
    pub resolution: [u32; 3],
}

/// Spatial SH gradients per probe: `data[(p·3 + axis)·order² + c]` is
/// `∂ coefficient c / ∂ axis` (axis 0 = x, 1 = y, 2 = z) of probe `p`, per
/// metre, RGB.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Gradients {
    /// SH order of the gradients (may be lower than the coefficients').
    pub order: u32,
    /// `3·order²` vectors per probe.
    pub data: Vec<Vec3>,
}

/// Basis along one axis of a tensor-product rig (Yuan, Nowrouzezahrai & Sloan, *Irradiance Rigs*, JGT 2011).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AxisModel {
    /// `{1}`: one function.
    Constant,
    /// `{1, t}`: two functions.
    Gradient,
    /// `N` hat functions (N ≥ 1).
    Lattice(u32),
}

impl AxisModel {
    /// Number of basis functions along the axis.
    pub const fn count(self) -> u32 {
        match self {
            Self::Constant => 1,
            Self::Gradient => 2,
            Self::Lattice(n) => n,
        }
    }
}

/// A rig model M(p, c) over the mesh's bounding box (*Irradiance Rigs*, JGT 2011).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RigModel {
    /// One SH vector.
    Constant,
    /// One SH vector plus three gradient vectors (4 parameters).
    Gradient,
    /// Tensor product of one [`AxisModel`] per axis (lattice = all axes
    /// lattices; the paper's car is `[Lattice(3), Gradient, Constant]`).
    Tensor([AxisModel; 3]),
}

impl RigModel {
    /// Number of SH vectors the rig holds; `None` on overflow.
    pub fn parameter_count(self) -> Option<u32> {
        match self {
            Self::Constant => Some(1),
            Self::Gradient => Some(4),
            Self::Tensor(a) => a[0]
                .count()
                .checked_mul(a[1].count())?
                .checked_mul(a[2].count()),
        }
    }
}

/// One entry of a rig's analytic/rig transition table (*Irradiance Rigs* §3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transition {
    /// Light distance from the object's bounding-sphere centre, in
    /// bounding-sphere radii (`probekit::rig::split` writes these).
    pub distance: f32,
    /// Error in reflected radiance at that distance, in 8-bit grey levels,
    /// for a light normalised so that its reflected radiance at the
    /// bounding-sphere point nearest to it is white (the role of the paper's
    /// `N(r)`; `probekit::rig::split` module docs).
    pub error: f32,
}

/// A fitted irradiance rig for one mesh and rig type.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    /// Mesh name (UTF-8) the rig belongs to.
    pub name: String,
    /// The model.
    pub model: RigModel,
    /// SH order of the rig parameters and of the SH sampled at its points.
    pub order: u32,
    /// Mesh bounding box minimum (mesh coordinates, metres).
    pub bbox_min: Vec3,
    /// Mesh bounding box maximum.
    pub bbox_max: Vec3,
    /// Radius of the sphere, centred on the box centre, that holds every
    /// vertex of the mesh (metres): the sphere the rig's transition table
    /// measures light distances from (`probekit::rig::split`). 0 when
    /// unknown: readers then use the box's
    /// circumscribed sphere, half its diagonal.
    pub bounding_radius: f32,
    /// Sample points on the mesh surface (mesh coordinates).
    pub samples: Vec<Vec3>,
    /// Row-major `parameters × samples` fitting matrix `L = (MᵀM)⁻¹Mᵀ`:
    /// parameter `k` = Σ_j `L[k][j]` · SH(sample `j`), per coefficient and channel.
    pub fitting: Vec<f32>,
    /// Error against normalized light distance, by increasing distance.
    pub transitions: Vec<Transition>,
}

impl ProbeFile {
    /// Parses and validates a whole file. Never panics; every problem is a
    /// [`FormatError`].
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FormatError> {
        read::parse(bytes)
    }

    /// Reads and parses the file at `path` (needs the `std` feature).
    #[cfg(feature = "std")]
    pub fn load(path: impl AsRef<Path>) -> Result<Self, FormatError> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|source| FormatError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_bytes(&bytes)
    }

    /// Checks the invariants the reader guarantees (counts agree, indices in
    /// range, topology consistent, floats finite, kind's sections present).
    /// The writer calls this before writing, so no file it writes is refused.
    pub fn validate(&self) -> Result<(), FormatError> {
        validate::validate(self)
    }
}
