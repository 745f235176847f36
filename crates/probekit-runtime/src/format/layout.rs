//! Constants of the `.probes` layout shared by the reader (here) and the
//! writer (`probekit::format`). The byte-by-byte specification is
//! `docs/file-format.md`; field offsets below are pinned by tests.

use crate::prelude::*;
use core::fmt;

/// The first 8 bytes of every `.probes` file.
pub const MAGIC: [u8; 8] = *b"PROBEKIT";
/// Major version written and read. A file with another major is refused:
/// an older one ([`FormatError::OlderVersion`](super::FormatError::OlderVersion),
/// every 1.x file: bake it again) or a newer one
/// ([`FormatError::UnsupportedVersion`](super::FormatError::UnsupportedVersion)).
pub const VERSION_MAJOR: u16 = 2;
/// Minor version written. A reader loads files of a larger minor of the
/// same major and skips their unknown sections. 2.1 adds the run-time
/// lights (`LITE`) and the probes' occlusion of them (`OCCL`); a 2.0 reader
/// skips both and answers with the SH part alone.
pub const VERSION_MINOR: u16 = 1;

/// Bits of the header's flags word holding the intended evaluation of L1
/// (order-2) coefficients: 0 linear, 1 hallucinated ZH3; 2 and 3 are
/// reserved (a reader refuses them in a file of a minor it knows, and reads
/// them as linear in a newer one). The other flag bits are not defined
/// (written 0, ignored).
pub const FLAGS_L1_MODE: u32 = 0b11;

/// Octree root grid `[rx, ry, rz]` as the `OCTC` header words
/// `w2 = (rx − 1) | (ry − 1) << 16`, `w3 = rz − 1` (so zeros read as one
/// root). `None` if an axis is outside `1..=65536`.
pub fn pack_roots(r: [u32; 3]) -> Option<[u32; 2]> {
    if r.iter().any(|&v| v == 0 || v > 65536) {
        return None;
    }
    Some([(r[0] - 1) | ((r[1] - 1) << 16), r[2] - 1])
}

/// Inverse of [`pack_roots`]; `None` if `w3 ≥ 65536`.
pub fn unpack_roots(w2: u32, w3: u32) -> Option<[u32; 3]> {
    (w3 < 65536).then(|| [(w2 & 0xffff) + 1, (w2 >> 16) + 1, w3 + 1])
}
/// Bytes in the fixed file header.
pub const HEADER_LEN: usize = 48;
/// Bytes in one section-table entry.
pub const ENTRY_LEN: usize = 32;
/// Every section starts at a multiple of this, and every array inside a
/// section starts at a multiple of this relative to the section start, so a
/// loader can reinterpret an aligned buffer as `&[f32]`/`&[u32]` without
/// copying (16 also suits SIMD and GPU upload).
pub const ALIGN: usize = 16;
/// Bytes in the fixed header that starts every section.
pub const SECTION_HEADER_LEN: usize = 16;
/// Bytes in one rig record header.
pub const RIG_HEADER_LEN: usize = 80;
/// Bytes in one run-time light record (`LITE`).
pub const RUNTIME_LIGHT_LEN: usize = 64;
/// Most run-time lights a file holds (a light index is one byte in `OCCL`).
pub const MAX_RUNTIME_LIGHTS: usize = 255;
/// Bytes in one light-group record header (`LGRP`).
pub const GROUP_HEADER_LEN: usize = 16;
/// "No element": hull neighbour, leaf node's children, face without a tetrahedron.
pub const NONE: u32 = u32::MAX;

/// Validity flag: the probe lies inside geometry (or sees too many back faces).
pub const VALIDITY_INVALID: u32 = 1 << 0;
/// Validity flag: the probe was moved out of geometry (virtual offset) before capture.
pub const VALIDITY_VIRTUAL_OFFSET: u32 = 1 << 1;

/// Rounds `n` up to a multiple of [`ALIGN`]; `None` on overflow.
pub const fn pad16(n: usize) -> Option<usize> {
    match n.checked_add(ALIGN - 1) {
        Some(v) => Some(v & !(ALIGN - 1)),
        None => None,
    }
}

/// A section identifier: four ASCII bytes read as a little-endian `u32`
/// (so `POSN` is the bytes `50 4F 53 4E`, shown in hex dumps as-is).
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SectionId(pub u32);

impl SectionId {
    /// Probe positions.
    pub const POSITIONS: Self = Self::from_fourcc(*b"POSN");
    /// SH coefficients in a codec.
    pub const COEFFICIENTS: Self = Self::from_fourcc(*b"COEF");
    /// Per-probe validity and flags.
    pub const VALIDITY: Self = Self::from_fourcc(*b"VALD");
    /// Tetrahedra: vertices, neighbours, barycentric matrices.
    pub const TETRAHEDRA: Self = Self::from_fourcc(*b"TETS");
    /// Outer cells: the hull-face table.
    pub const OUTER: Self = Self::from_fourcc(*b"OUTR");
    /// The octree of an adaptive volume, compactly: one child bit per node,
    /// leaf corners found by position among the probes.
    pub const OCTREE: Self = Self::from_fourcc(*b"OCTC");
    /// Uniform volume grid: box and resolution.
    pub const GRID: Self = Self::from_fourcc(*b"GRID");
    /// Per-probe SH gradients.
    pub const GRADIENTS: Self = Self::from_fourcc(*b"GRAD");
    /// Irradiance rigs.
    pub const RIGS: Self = Self::from_fourcc(*b"RIGS");
    /// Bake metadata (UTF-8 JSON).
    pub const METADATA: Self = Self::from_fourcc(*b"META");
    /// Per-light-group radiance SH, for run-time relighting.
    pub const LIGHT_GROUPS: Self = Self::from_fourcc(*b"LGRP");
    /// Per-probe distance moments on an octahedral map, for
    /// visibility-aware blending of a probe cloud.
    pub const VISIBILITY: Self = Self::from_fourcc(*b"VISM");
    /// Per-cell lattice visibility bits of a probe cloud, stored sparse: a
    /// mask of the cells with a record, then their records; clear cells
    /// (every probe sees every lattice point) have none
    /// ([`crate::cloud::CellVisibility`]).
    pub const CELL_VISIBILITY: Self = Self::from_fourcc(*b"CVSP");
    /// Fitted per-probe blend weights of a cloud, one `f32` per probe
    /// ([`crate::cloud::ProbeCloud::probe_weights`]), with the brightness
    /// exponents the cloud blends with in the section header.
    pub const PROBE_WEIGHTS: Self = Self::from_fourcc(*b"PWGT");
    /// Occluder planes of some tetrahedra of a cloud, refining its cell
    /// visibility where one flat wall cuts the cell: the mesh's tetrahedron
    /// count, the increasing indices of the tetrahedra with a plane, then
    /// one plane `[n_x, n_y, n_z, d]` each
    /// ([`crate::cloud::CellPlanes`]). Only with `CVSP`.
    pub const CELL_PLANES: Self = Self::from_fourcc(*b"CPLN");
    /// Lights an engine evaluates at run time (the probes' SH leaves out
    /// their direct light): one 64-byte record each, then their light-group
    /// names ([`super::RuntimeLights`]).
    pub const RUNTIME_LIGHTS: Self = Self::from_fourcc(*b"LITE");
    /// Each probe's occlusion of the run-time lights, 8 bits per light that
    /// reaches it, stored sparse: a count per probe, then `(light, value)`
    /// byte pairs ([`super::LightOcclusion`]). Only with `LITE`.
    pub const LIGHT_OCCLUSION: Self = Self::from_fourcc(*b"OCCL");
    /// Pseudo-id naming the file header in errors and size tables.
    pub const HEADER: Self = Self::from_fourcc(*b"HEAD");

    /// Every section this version knows, in the order the writer emits them.
    pub const KNOWN: [Self; 17] = [
        Self::RUNTIME_LIGHTS,
        Self::LIGHT_OCCLUSION,
        Self::POSITIONS,
        Self::COEFFICIENTS,
        Self::VALIDITY,
        Self::TETRAHEDRA,
        Self::OUTER,
        Self::OCTREE,
        Self::GRID,
        Self::GRADIENTS,
        Self::RIGS,
        Self::LIGHT_GROUPS,
        Self::VISIBILITY,
        Self::CELL_VISIBILITY,
        Self::PROBE_WEIGHTS,
        Self::CELL_PLANES,
        Self::METADATA,
    ];

    /// The id of a four-character code.
    pub const fn from_fourcc(code: [u8; 4]) -> Self {
        Self(u32::from_le_bytes(code))
    }

    /// The four bytes of the id.
    pub const fn fourcc(self) -> [u8; 4] {
        self.0.to_le_bytes()
    }

    /// The snake_case name used in `bytes_by_section` tables and messages
    /// (`"positions"`, `"coefficients"`, ...); unknown ids give `None`.
    pub fn name(self) -> Option<&'static str> {
        Some(match self {
            Self::POSITIONS => "positions",
            Self::COEFFICIENTS => "coefficients",
            Self::VALIDITY => "validity",
            Self::TETRAHEDRA => "tetrahedra",
            Self::OUTER => "outer_cells",
            Self::OCTREE => "octree",
            Self::GRID => "grid",
            Self::GRADIENTS => "gradients",
            Self::RIGS => "rigs",
            Self::METADATA => "metadata",
            Self::LIGHT_GROUPS => "light_groups",
            Self::VISIBILITY => "visibility",
            Self::CELL_VISIBILITY => "cell_visibility",
            Self::PROBE_WEIGHTS => "probe_weights",
            Self::CELL_PLANES => "cell_planes",
            Self::RUNTIME_LIGHTS => "runtime_lights",
            Self::LIGHT_OCCLUSION => "light_occlusion",
            Self::HEADER => "header",
            _ => return None,
        })
    }
}

impl fmt::Display for SectionId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => f.write_str(n),
            None => {
                let b = self.fourcc();
                if b.iter().all(|c| c.is_ascii_graphic()) {
                    write!(f, "'{}'", String::from_utf8_lossy(&b))
                } else {
                    write!(f, "{:#010x}", self.0)
                }
            }
        }
    }
}

impl fmt::Debug for SectionId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "SectionId({self})")
    }
}

/// Byte offsets of the header fields (see `docs/file-format.md`).
pub mod header {
    /// `[u8; 8]` magic.
    pub const MAGIC: usize = 0;
    /// `u16` major version.
    pub const MAJOR: usize = 8;
    /// `u16` minor version.
    pub const MINOR: usize = 10;
    /// `u32` file kind (0 cloud, 1 volume, 2 rig).
    pub const KIND: usize = 12;
    /// `u32` flags: bits 0–1 the intended evaluation of L1 coefficients
    /// ([`super::FLAGS_L1_MODE`]); the other bits are not
    /// defined (written 0, ignored).
    pub const FLAGS: usize = 16;
    /// `u32` number of section-table entries.
    pub const SECTION_COUNT: usize = 20;
    /// `u64` total file length in bytes.
    pub const FILE_LEN: usize = 24;
    /// `u32` CRC-32 of bytes `0..32` followed by the whole section table.
    pub const CRC: usize = 32;
    /// Bytes `36..48` are reserved (written 0, ignored).
    pub const RESERVED: usize = 36;
}

/// Byte offsets inside one section-table entry.
pub mod entry {
    /// `u32` section id.
    pub const ID: usize = 0;
    /// `u32` reserved (written 0, ignored).
    pub const RESERVED0: usize = 4;
    /// `u64` offset of the section from the start of the file.
    pub const OFFSET: usize = 8;
    /// `u64` length of the section in bytes (a multiple of 16).
    pub const LENGTH: usize = 16;
    /// `u32` CRC-32 of the section's bytes.
    pub const CRC: usize = 24;
    /// `u32` reserved (written 0, ignored).
    pub const RESERVED1: usize = 28;
}
