//! Constants of the `.probes` layout shared by the reader (here) and the
//! writer (`probekit::format`). The byte-by-byte specification is
//! `docs/file-format.md`; field offsets below are pinned by tests.

use crate::prelude::*;
use core::fmt;

/// The first 8 bytes of every `.probes` file.
pub const MAGIC: [u8; 8] = *b"PROBEKIT";
/// Major version written and read. A file with a larger major is refused.
pub const VERSION_MAJOR: u16 = 1;
/// Newest minor version this reader knows (1.1 added `LGRP`, light
/// groups; 1.2 added `OCTC`, the compact octree; 1.3 added `VISM`, per-probe
/// distance moments for visibility-aware blending; 1.4 added `CVIS`, per-cell
/// lattice visibility; 1.5 added `CVSP`, the same bits stored sparse; 1.6
/// added `PWGT`, fitted per-probe blend weights; 1.7 added `CPLN`, occluder
/// planes of cells; 1.8 stores the brightness exponent the weights were
/// fitted with in `PWGT`'s header word `w1`, [`MINOR_BRIGHTNESS`]; 1.9 the
/// directional brightness exponent in `w2`, [`MINOR_DIRECTIONAL`]; 1.10
/// the intended evaluation of L1 coefficients in the header's flags,
/// [`MINOR_L1_MODE`]; 1.11 a rig's bounding radius in its record header,
/// [`MINOR_RIG_RADIUS`]). Files with a larger minor load; their unknown
/// sections are skipped. The writer writes the lowest minor that holds the file's
/// sections ([`minor_for_sections`]): 0 without `LGRP`, so a 1.0 reader
/// reads every file that does not use 1.1 additions, byte for byte as before.
pub const VERSION_MINOR: u16 = 11;

/// Minor version that stores a rig's bounding radius
/// ([`crate::format::Rig::bounding_radius`]) in the record header's first
/// reserved word (a reader of 1.10 or older ignores it and measures light
/// distances from the box's circumscribed sphere).
pub const MINOR_RIG_RADIUS: u16 = 11;

/// Minor version that stores a non-zero brightness exponent in `PWGT`'s
/// header word `w1` (a reader of 1.6 or 1.7 ignores the word and blends
/// without it).
pub const MINOR_BRIGHTNESS: u16 = 8;

/// Minor version that stores a non-zero directional brightness exponent in
/// `PWGT`'s header word `w2` (a reader of 1.6 to 1.8 ignores the word and
/// blends without it).
pub const MINOR_DIRECTIONAL: u16 = 9;

/// Minor version that stores a non-linear intended evaluation of L1
/// coefficients ([`crate::L1Mode`]) in the header's flags,
/// [`FLAGS_L1_MODE`] (a reader of 1.0 to 1.9 ignores the flags and
/// evaluates the L1 coefficients linearly).
pub const MINOR_L1_MODE: u16 = 10;

/// Bits of the header's flags word holding the intended evaluation of L1
/// (order-2) coefficients: 0 linear, 1 hallucinated ZH3; 2 and 3 are
/// reserved (a reader refuses them in a file of a minor it knows, and reads
/// them as linear in a newer one). The other flag bits are not defined
/// (written 0, ignored).
pub const FLAGS_L1_MODE: u32 = 0b11;

/// Minor version that introduced octree forests (root grids other than
/// 1 × 1 × 1 in the `OCTR`/`OCTC` header words `w2`, `w3`).
pub const MINOR_FOREST: u16 = 3;

/// Octree root grid `[rx, ry, rz]` as the `OCTR`/`OCTC` header words
/// `w2 = (rx − 1) | (ry − 1) << 16`, `w3 = rz − 1` (so the zeros of files
/// before 1.3 read as one root). `None` if an axis is outside `1..=65536`.
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

/// The lowest minor version whose section set includes every id in `ids`:
/// 7 if `CPLN` ([`SectionId::CELL_PLANES`]) is present, else
/// 6 if `PWGT` ([`SectionId::PROBE_WEIGHTS`]) is present, else
/// 5 if `CVSP` ([`SectionId::CELL_VISIBILITY_SPARSE`]) is present, else
/// 4 if `CVIS` ([`SectionId::CELL_VISIBILITY`]) is present, else
/// 3 if `VISM` ([`SectionId::VISIBILITY`]) is present, else 2 if `OCTC`
/// ([`SectionId::OCTREE_COMPACT`]) is, else 1 if `LGRP`
/// ([`SectionId::LIGHT_GROUPS`]) is, else 0.
pub fn minor_for_sections(ids: impl IntoIterator<Item = SectionId>) -> u16 {
    ids.into_iter()
        .map(|id| match id {
            SectionId::CELL_PLANES => 7,
            SectionId::PROBE_WEIGHTS => 6,
            SectionId::CELL_VISIBILITY_SPARSE => 5,
            SectionId::CELL_VISIBILITY => 4,
            SectionId::VISIBILITY => 3,
            SectionId::OCTREE_COMPACT => 2,
            SectionId::LIGHT_GROUPS => 1,
            _ => 0,
        })
        .max()
        .unwrap_or(0)
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
/// Bytes in one octree node record.
pub const OCTREE_NODE_LEN: usize = 40;
/// Bytes in one rig record header.
pub const RIG_HEADER_LEN: usize = 80;
/// Bytes in one light-group record header (`LGRP`, format 1.1).
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
    /// Octree nodes and their sample lists (adaptive volumes).
    pub const OCTREE: Self = Self::from_fourcc(*b"OCTR");
    /// The same octree compactly: one child bit per node, corners found by
    /// position (format 1.2; the writer's choice for regular octrees).
    pub const OCTREE_COMPACT: Self = Self::from_fourcc(*b"OCTC");
    /// Uniform volume grid: box and resolution.
    pub const GRID: Self = Self::from_fourcc(*b"GRID");
    /// Per-probe SH gradients.
    pub const GRADIENTS: Self = Self::from_fourcc(*b"GRAD");
    /// Irradiance rigs.
    pub const RIGS: Self = Self::from_fourcc(*b"RIGS");
    /// Bake metadata (UTF-8 JSON).
    pub const METADATA: Self = Self::from_fourcc(*b"META");
    /// Per-light-group radiance SH, for run-time relighting (format 1.1).
    pub const LIGHT_GROUPS: Self = Self::from_fourcc(*b"LGRP");
    /// Per-probe distance moments on an octahedral map, for
    /// visibility-aware blending of a probe cloud (format 1.3).
    pub const VISIBILITY: Self = Self::from_fourcc(*b"VISM");
    /// Per-cell lattice visibility bits of a probe cloud (format 1.4;
    /// [`crate::cloud::cell_visibility`]).
    pub const CELL_VISIBILITY: Self = Self::from_fourcc(*b"CVIS");
    /// The same bits stored sparse: a mask of the cells with a record, then
    /// their records; clear cells (every probe sees every lattice point)
    /// have none (format 1.5; [`crate::cloud::CellVisibility`]). The writer
    /// writes this form; a file holds at most one of `CVIS` and `CVSP`.
    pub const CELL_VISIBILITY_SPARSE: Self = Self::from_fourcc(*b"CVSP");
    /// Fitted per-probe blend weights of a cloud, one `f32` per probe
    /// (format 1.6; [`crate::cloud::ProbeCloud::probe_weights`]).
    pub const PROBE_WEIGHTS: Self = Self::from_fourcc(*b"PWGT");
    /// Occluder planes of some tetrahedra of a cloud, refining its cell
    /// visibility where one flat wall cuts the cell: the mesh's tetrahedron
    /// count, the increasing indices of the tetrahedra with a plane, then
    /// one plane `[n_x, n_y, n_z, d]` each (format 1.7;
    /// [`crate::cloud::CellPlanes`]). Only with `CVSP`/`CVIS`.
    pub const CELL_PLANES: Self = Self::from_fourcc(*b"CPLN");
    /// Pseudo-id naming the file header in errors and size tables.
    pub const HEADER: Self = Self::from_fourcc(*b"HEAD");

    /// Every section this version knows, in the order the writer emits them.
    pub const KNOWN: [Self; 17] = [
        Self::POSITIONS,
        Self::COEFFICIENTS,
        Self::VALIDITY,
        Self::TETRAHEDRA,
        Self::OUTER,
        Self::OCTREE,
        Self::OCTREE_COMPACT,
        Self::GRID,
        Self::GRADIENTS,
        Self::RIGS,
        Self::LIGHT_GROUPS,
        Self::VISIBILITY,
        Self::CELL_VISIBILITY,
        Self::CELL_VISIBILITY_SPARSE,
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
            Self::OCTREE_COMPACT => "octree",
            Self::GRID => "grid",
            Self::GRADIENTS => "gradients",
            Self::RIGS => "rigs",
            Self::METADATA => "metadata",
            Self::LIGHT_GROUPS => "light_groups",
            Self::VISIBILITY => "visibility",
            Self::CELL_VISIBILITY => "cell_visibility",
            Self::CELL_VISIBILITY_SPARSE => "cell_visibility",
            Self::PROBE_WEIGHTS => "probe_weights",
            Self::CELL_PLANES => "cell_planes",
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
    /// ([`super::FLAGS_L1_MODE`], format 1.10); the other bits are not
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
