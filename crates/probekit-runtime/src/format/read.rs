//! The reader: header and section table first (bounds, alignment, overlap,
//! checksums), then each section's payload (counts against lengths before
//! any allocation), then [`validate`](super::validate) for cross-section
//! invariants. Every offset and size is computed with checked arithmetic.

mod cloud;
mod lights;
mod probes;
mod rig;
mod volume;

use super::crc::{crc32, Crc32};
use super::error::FormatError;
use super::layout::{
    self, entry, header, pad16, SectionId, ALIGN, ENTRY_LEN, HEADER_LEN, SECTION_HEADER_LEN,
    VERSION_MAJOR, VERSION_MINOR,
};
use super::{ProbeFile, ProbeFileKind};
use crate::prelude::*;
use alloc::collections::BTreeMap;
use bytemuck::Pod;
use cloud::{
    build_cell_planes, parse_cell_planes, parse_cell_visibility, parse_outer, parse_probe_weights,
    parse_tetrahedra, parse_visibility,
};
use glam::Vec3;
use probes::{parse_coefficients, parse_groups, parse_metadata, parse_positions, parse_validity};
use rig::parse_rigs;
use volume::{parse_gradients, parse_grid, parse_octree};

/// The decoded fixed header of a `.probes` file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FileHeader {
    /// Major version (equal to [`VERSION_MAJOR`] once accepted).
    pub major: u16,
    /// Minor version (may exceed [`VERSION_MINOR`]).
    pub minor: u16,
    /// Raw kind id (see [`ProbeFileKind::from_id`]).
    pub kind: u32,
    /// Header flags (bits 0–1: [`layout::FLAGS_L1_MODE`]).
    pub flags: u32,
}

/// One section whose bounds, alignment and checksum have been verified,
/// borrowing the file's bytes. An engine that maps files can cast
/// `bytes[16..]` arrays directly when `bytes` is 16-aligned in memory.
#[derive(Clone, Copy, Debug)]
pub struct RawSection<'a> {
    /// Section id.
    pub id: SectionId,
    /// Offset of the section from the start of the file.
    pub offset: u64,
    /// The section's bytes (section header included).
    pub bytes: &'a [u8],
}

fn truncated(needed: usize, len: usize) -> FormatError {
    FormatError::Truncated {
        needed: needed as u64,
        len: len as u64,
    }
}

fn u16_at(b: &[u8], o: usize) -> Option<u16> {
    Some(u16::from_le_bytes(
        b.get(o..o.checked_add(2)?)?.try_into().ok()?,
    ))
}

fn u32_at(b: &[u8], o: usize) -> Option<u32> {
    Some(u32::from_le_bytes(
        b.get(o..o.checked_add(4)?)?.try_into().ok()?,
    ))
}

fn u64_at(b: &[u8], o: usize) -> Option<u64> {
    Some(u64::from_le_bytes(
        b.get(o..o.checked_add(8)?)?.try_into().ok()?,
    ))
}

/// Verifies the header and the section table and returns the sections in
/// table order. Checks, in order: length ≥ header, magic, major version,
/// table inside the file, file length field, header CRC, then per entry:
/// alignment, bounds, duplicates, CRC, and finally that no two sections overlap.
pub fn read_sections(bytes: &[u8]) -> Result<(FileHeader, Vec<RawSection<'_>>), FormatError> {
    let len = bytes.len();
    if len < HEADER_LEN {
        // Still say "bad magic" for short non-probe files.
        if bytes.len() >= 8 && bytes[..8] != layout::MAGIC {
            return Err(FormatError::BadMagic);
        }
        return Err(truncated(HEADER_LEN, len));
    }
    if bytes[header::MAGIC..header::MAGIC + 8] != layout::MAGIC {
        return Err(FormatError::BadMagic);
    }
    let major = u16_at(bytes, header::MAJOR).ok_or(truncated(HEADER_LEN, len))?;
    let minor = u16_at(bytes, header::MINOR).ok_or(truncated(HEADER_LEN, len))?;
    if (1..VERSION_MAJOR).contains(&major) {
        return Err(FormatError::OlderVersion {
            major,
            minor,
            supported: VERSION_MAJOR,
        });
    }
    if major != VERSION_MAJOR {
        return Err(FormatError::UnsupportedVersion {
            major,
            minor,
            supported: VERSION_MAJOR,
        });
    }
    let word = |o: usize| u32_at(bytes, o).ok_or(truncated(HEADER_LEN, len));
    let kind = word(header::KIND)?;
    let flags = word(header::FLAGS)?;
    let count = word(header::SECTION_COUNT)? as usize;
    let declared_len = u64_at(bytes, header::FILE_LEN).ok_or(truncated(HEADER_LEN, len))?;
    let stored_crc = word(header::CRC)?;

    let table_end = count
        .checked_mul(ENTRY_LEN)
        .and_then(|t| t.checked_add(HEADER_LEN))
        .ok_or(FormatError::CountOverflow(SectionId::HEADER))?;
    if table_end > len {
        return Err(truncated(table_end, len));
    }
    if declared_len > len as u64 {
        return Err(FormatError::Truncated {
            needed: declared_len,
            len: len as u64,
        });
    }
    if declared_len != len as u64 {
        return Err(FormatError::LengthMismatch {
            declared: declared_len,
            actual: len as u64,
        });
    }
    let mut crc = Crc32::new();
    crc.update(&bytes[..header::CRC]);
    crc.update(&bytes[HEADER_LEN..table_end]);
    if crc.finish() != stored_crc {
        return Err(FormatError::ChecksumMismatch {
            what: "header".into(),
            stored: stored_crc,
            computed: crc.finish(),
        });
    }

    let mut sections: Vec<RawSection<'_>> = Vec::with_capacity(count);
    for k in 0..count {
        let e = HEADER_LEN + k * ENTRY_LEN;
        let id = SectionId(u32_at(bytes, e + entry::ID).ok_or(truncated(table_end, len))?);
        let offset = u64_at(bytes, e + entry::OFFSET).ok_or(truncated(table_end, len))?;
        let length = u64_at(bytes, e + entry::LENGTH).ok_or(truncated(table_end, len))?;
        let stored = u32_at(bytes, e + entry::CRC).ok_or(truncated(table_end, len))?;
        if offset % ALIGN as u64 != 0 || length % ALIGN as u64 != 0 {
            return Err(FormatError::SectionMisaligned { id, offset });
        }
        let end = offset.checked_add(length);
        let out_of_bounds = FormatError::SectionOutOfBounds { id, offset, length };
        let end = match end {
            Some(end) if offset >= table_end as u64 && end <= len as u64 => end,
            _ => return Err(out_of_bounds),
        };
        if sections.iter().any(|s| s.id == id) {
            return Err(FormatError::DuplicateSection(id));
        }
        // In bounds of a slice of `len` bytes, so the casts are lossless.
        let data = &bytes[offset as usize..end as usize];
        let computed = crc32(data);
        if computed != stored {
            return Err(FormatError::ChecksumMismatch {
                what: id.to_string(),
                stored,
                computed,
            });
        }
        sections.push(RawSection {
            id,
            offset,
            bytes: data,
        });
    }
    let mut by_offset: Vec<&RawSection<'_>> = sections.iter().collect();
    by_offset.sort_by_key(|s| (s.offset, s.id));
    for w in by_offset.windows(2) {
        if w[0].offset + w[0].bytes.len() as u64 > w[1].offset {
            return Err(FormatError::SectionOverlap {
                first: w[0].id,
                second: w[1].id,
            });
        }
    }
    Ok((
        FileHeader {
            major,
            minor,
            kind,
            flags,
        },
        sections,
    ))
}

/// Bytes per section of a file, keyed by section name (`"positions"`,
/// `"coefficients"`, ..., `"header"` for header plus table, unknown ids by
/// their four-character code). For files written by `probekit` the values
/// sum to the file length. This is `bytes_by_section` in `inspect --json`.
#[cfg_attr(not(feature = "write"), allow(dead_code))]
pub fn file_bytes_by_section(bytes: &[u8]) -> Result<BTreeMap<String, u64>, FormatError> {
    let (_, sections) = read_sections(bytes)?;
    let mut map = BTreeMap::new();
    map.insert(
        "header".to_string(),
        (HEADER_LEN + sections.len() * ENTRY_LEN) as u64,
    );
    for s in &sections {
        *map.entry(s.id.to_string()).or_insert(0) += s.bytes.len() as u64;
    }
    Ok(map)
}

/// A section being decoded: its id and bytes.
struct Sec<'a> {
    id: SectionId,
    bytes: &'a [u8],
}

impl<'a> Sec<'a> {
    /// The four `u32` words of the section header.
    fn header(&self) -> Result<[u32; 4], FormatError> {
        let w = |k: usize| u32_at(self.bytes, 4 * k);
        match (w(0), w(1), w(2), w(3)) {
            (Some(a), Some(b), Some(c), Some(d)) => Ok([a, b, c, d]),
            _ => Err(self.size_error(SECTION_HEADER_LEN as u64)),
        }
    }

    fn size_error(&self, expected: u64) -> FormatError {
        FormatError::SectionSize {
            id: self.id,
            expected,
            actual: self.bytes.len() as u64,
        }
    }

    /// Splits the payload after the section header into arrays of the given
    /// byte sizes, each padded to 16; the section must be exactly that long.
    fn arrays<const N: usize>(
        &self,
        sizes: [Option<usize>; N],
    ) -> Result<[&'a [u8]; N], FormatError> {
        Ok(self.arrays_at(SECTION_HEADER_LEN, sizes, true)?.0)
    }

    /// The arrays of [`Self::arrays`] starting at `start` (a record inside
    /// the section when not `exact`), and the offset where the last one's
    /// padding ends (the next record's start).
    fn arrays_at<const N: usize>(
        &self,
        start: usize,
        sizes: [Option<usize>; N],
        exact: bool,
    ) -> Result<([&'a [u8]; N], usize), FormatError> {
        let mut offsets = [(0usize, 0usize); N];
        let mut pos = start;
        for (k, size) in sizes.into_iter().enumerate() {
            let size = size.ok_or(FormatError::CountOverflow(self.id))?;
            offsets[k] = (pos, size);
            pos = pad16(size)
                .and_then(|p| pos.checked_add(p))
                .ok_or(FormatError::CountOverflow(self.id))?;
        }
        let ok = if exact {
            pos == self.bytes.len()
        } else {
            pos <= self.bytes.len()
        };
        if !ok {
            return Err(self.size_error(pos as u64));
        }
        let mut out: [&'a [u8]; N] = [&[]; N];
        for (k, (o, s)) in offsets.into_iter().enumerate() {
            out[k] = &self.bytes[o..o + s];
        }
        Ok((out, pos))
    }

    /// A record's name as UTF-8.
    fn name(&self, bytes: &[u8]) -> Result<String, FormatError> {
        core::str::from_utf8(bytes)
            .map(|n| n.to_string())
            .map_err(|_| FormatError::InvalidUtf8(self.id))
    }
}

/// `count · size` in bytes, `None` on overflow.
fn bytes_for(count: u32, size: usize) -> Option<usize> {
    (count as usize).checked_mul(size)
}

/// Copies little-endian 4-byte-word arrays into `Vec<T>`, by a bytemuck cast
/// when `bytes` happens to be aligned for `T`, element by element otherwise.
/// `T` must consist of 4-byte words only (`u32`, `f32` and arrays of them).
fn pod_vec<T: Pod>(bytes: &[u8]) -> Vec<T> {
    let size = core::mem::size_of::<T>();
    #[allow(unused_mut)]
    let mut v: Vec<T> = match bytemuck::try_cast_slice::<u8, T>(bytes) {
        Ok(s) => s.to_vec(),
        Err(_) => bytes
            .chunks_exact(size)
            .map(bytemuck::pod_read_unaligned)
            .collect(),
    };
    #[cfg(target_endian = "big")]
    for w in bytemuck::cast_slice_mut::<T, u32>(&mut v) {
        *w = w.swap_bytes();
    }
    v
}

fn vec3s(bytes: &[u8]) -> Vec<Vec3> {
    pod_vec::<[f32; 3]>(bytes)
        .into_iter()
        .map(Vec3::from_array)
        .collect()
}

/// Whether a file of `kind` may hold section `id` (a known id).
fn belongs(kind: ProbeFileKind, id: SectionId) -> bool {
    match id {
        SectionId::RIGS | SectionId::METADATA => true,
        SectionId::POSITIONS
        | SectionId::COEFFICIENTS
        | SectionId::VALIDITY
        | SectionId::LIGHT_GROUPS
        | SectionId::RUNTIME_LIGHTS
        | SectionId::LIGHT_OCCLUSION => kind != ProbeFileKind::Rig,
        SectionId::OCTREE | SectionId::GRID | SectionId::GRADIENTS => kind == ProbeFileKind::Volume,
        _ => kind == ProbeFileKind::Cloud,
    }
}

/// Every known section of a file, decoded, before they are put together.
#[derive(Default)]
struct Decoded {
    positions: Option<Vec<Vec3>>,
    coefficients: Option<super::Coefficients>,
    validity: Option<Vec<super::Validity>>,
    groups: Vec<super::LightGroup>,
    runtime_lights: Option<Vec<super::RuntimeLight>>,
    occlusion: Option<(super::LightOcclusion, u32)>,
    tetrahedra: Option<super::TetSection>,
    outer: Option<super::OuterCells>,
    compact: Option<super::octree_compact::Compact>,
    grid: Option<super::VolumeGrid>,
    gradients: Option<super::Gradients>,
    moments: Option<super::DistanceMoments>,
    cells: Option<crate::cloud::CellVisibility>,
    planes: Option<cloud::RawCellPlanes>,
    weights: Option<(Vec<f32>, f32, f32)>,
    rigs: Vec<super::Rig>,
    metadata: String,
}

/// Parses and validates a whole file (see [`ProbeFile::from_bytes`]).
pub(super) fn parse(bytes: &[u8]) -> Result<ProbeFile, FormatError> {
    let (head, sections) = read_sections(bytes)?;
    let kind = ProbeFileKind::from_id(head.kind)?;
    let l1_mode = match super::L1Mode::from_flags(head.flags) {
        Some(mode) => mode,
        // A newer minor may define more modes: evaluate linearly.
        None if head.minor > VERSION_MINOR => super::L1Mode::Linear,
        None => {
            return Err(FormatError::InvalidValue {
                id: SectionId::HEADER,
                element: 0,
                reason: "header flags: reserved L1 evaluation mode (bits 0-1 are 2 or 3)",
            })
        }
    };
    let mut d = Decoded::default();
    for raw in &sections {
        let s = Sec {
            id: raw.id,
            bytes: raw.bytes,
        };
        if SectionId::KNOWN.contains(&raw.id) && !belongs(kind, raw.id) {
            return Err(FormatError::MisplacedSection {
                id: raw.id,
                kind: kind.name(),
            });
        }
        match raw.id {
            SectionId::POSITIONS => d.positions = Some(parse_positions(&s)?),
            SectionId::COEFFICIENTS => d.coefficients = Some(parse_coefficients(&s)?),
            SectionId::VALIDITY => d.validity = Some(parse_validity(&s)?),
            SectionId::TETRAHEDRA => d.tetrahedra = Some(parse_tetrahedra(&s)?),
            SectionId::OUTER => d.outer = Some(parse_outer(&s)?),
            SectionId::OCTREE => d.compact = Some(parse_octree(&s)?),
            SectionId::GRID => d.grid = Some(parse_grid(&s)?),
            SectionId::GRADIENTS => d.gradients = Some(parse_gradients(&s)?),
            SectionId::RIGS => d.rigs = parse_rigs(&s)?,
            SectionId::LIGHT_GROUPS => d.groups = parse_groups(&s)?,
            SectionId::RUNTIME_LIGHTS => d.runtime_lights = Some(lights::parse_runtime_lights(&s)?),
            SectionId::LIGHT_OCCLUSION => d.occlusion = Some(lights::parse_light_occlusion(&s)?),
            SectionId::VISIBILITY => d.moments = Some(parse_visibility(&s)?),
            SectionId::CELL_VISIBILITY => d.cells = Some(parse_cell_visibility(&s)?),
            SectionId::PROBE_WEIGHTS => d.weights = Some(parse_probe_weights(&s)?),
            SectionId::CELL_PLANES => d.planes = Some(parse_cell_planes(&s)?),
            SectionId::METADATA => d.metadata = parse_metadata(&s)?,
            id if head.minor > VERSION_MINOR => {
                // A newer minor version may add sections; skip them.
                let _ = id;
            }
            id => return Err(FormatError::UnknownSection(id)),
        }
    }
    let file = assemble(kind, l1_mode, d)?;
    file.validate()?;
    Ok(file)
}

/// The file of `kind` from its decoded sections: required ones present,
/// the octree expanded against the positions, the occluder planes checked
/// against the cloud they refine.
fn assemble(
    kind: ProbeFileKind,
    l1_mode: super::L1Mode,
    d: Decoded,
) -> Result<ProbeFile, FormatError> {
    if kind == ProbeFileKind::Rig {
        return Ok(ProbeFile::Rigs(super::RigFile {
            rigs: d.rigs,
            metadata: d.metadata,
        }));
    }
    let probes = super::ProbeSet {
        positions: d
            .positions
            .ok_or(FormatError::MissingSection(SectionId::POSITIONS))?,
        coefficients: d
            .coefficients
            .ok_or(FormatError::MissingSection(SectionId::COEFFICIENTS))?,
        l1_mode,
        validity: d.validity,
        groups: d.groups,
        runtime_lights: match (d.runtime_lights, d.occlusion) {
            (None, None) => None,
            (Some(lights), Some((occlusion, count))) => {
                if count as usize != lights.len() {
                    return Err(FormatError::CountMismatch {
                        id: SectionId::LIGHT_OCCLUSION,
                        expected: lights.len() as u64,
                        actual: u64::from(count),
                    });
                }
                Some(super::RuntimeLights { lights, occlusion })
            }
            (Some(_), None) => return Err(FormatError::MissingSection(SectionId::LIGHT_OCCLUSION)),
            (None, Some(_)) => return Err(FormatError::MissingSection(SectionId::RUNTIME_LIGHTS)),
        },
    };
    if kind == ProbeFileKind::Volume {
        let structure = match (d.grid, d.compact) {
            (Some(g), None) => super::VolumeStructure::Uniform(g),
            (None, Some(c)) => super::VolumeStructure::Adaptive(c.expand(&probes.positions)?),
            (None, None) => return Err(FormatError::MissingSection(SectionId::GRID)),
            (Some(_), Some(_)) => {
                return Err(FormatError::InvalidValue {
                    id: SectionId::GRID,
                    element: 0,
                    reason: "a volume holds GRID or OCTC, not both",
                })
            }
        };
        return Ok(ProbeFile::Volume(super::VolumeFile {
            probes,
            structure,
            gradients: d.gradients,
            rigs: d.rigs,
            metadata: d.metadata,
        }));
    }
    let (probe_weights, brightness_exponent, directional_exponent) = match d.weights {
        Some((w, a, b)) => (Some(w), a, b),
        None => (None, 0.0, 0.0),
    };
    let mut cloud = super::CloudFile {
        probes,
        tetrahedra: d.tetrahedra,
        outer: d.outer,
        blend: super::CloudBlend {
            distance_moments: d.moments,
            cell_visibility: d.cells,
            cell_planes: None,
            probe_weights,
            brightness_exponent,
            directional_exponent,
        },
        rigs: d.rigs,
        metadata: d.metadata,
    };
    if let Some(raw) = d.planes {
        cloud.blend.cell_planes = Some(build_cell_planes(&cloud, raw)?);
    }
    Ok(ProbeFile::Cloud(cloud))
}
