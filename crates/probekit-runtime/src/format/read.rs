//! The reader: header and section table first (bounds, alignment, overlap,
//! checksums), then each section's payload (counts against lengths before
//! any allocation), then [`validate`](super::validate) for cross-section
//! invariants. Every offset and size is computed with checked arithmetic.

use super::codec::{Codec, Coefficients};
use super::crc::{crc32, Crc32};
use super::error::FormatError;
use super::layout::{
    self, entry, header, pad16, SectionId, ALIGN, ENTRY_LEN, GROUP_HEADER_LEN, HEADER_LEN,
    OCTREE_NODE_LEN, RIG_HEADER_LEN, SECTION_HEADER_LEN, VERSION_MAJOR, VERSION_MINOR,
};
use super::{
    AxisModel, Gradients, LightGroup, Octree, OctreeNode, OuterCells, ProbeFile, ProbeFileKind,
    Rig, RigModel, TetSection, Transition, Validity, VolumeGrid,
};
use crate::cloud::cell_visibility::{
    plane_has_unit_normal, record_bytes, record_has_padding, records_len, stored_counts,
    CellPlanes, CellVisibility, MAX_CELL_SUBDIVISION,
};
use crate::prelude::*;
use alloc::collections::BTreeMap;
use bytemuck::Pod;
use glam::Vec3;

/// The decoded fixed header of a `.probes` file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FileHeader {
    /// Major version (equal to [`VERSION_MAJOR`] once accepted).
    pub major: u16,
    /// Minor version (may exceed [`VERSION_MINOR`]).
    pub minor: u16,
    /// Raw kind id (see [`ProbeFileKind::from_id`]).
    pub kind: u32,
    /// Header flags (none defined in 1.0).
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

fn parse_positions(s: &Sec<'_>) -> Result<Vec<Vec3>, FormatError> {
    let [count, ..] = s.header()?;
    let [data] = s.arrays([bytes_for(count, 12)])?;
    Ok(vec3s(data))
}

fn parse_coefficients(s: &Sec<'_>) -> Result<Coefficients, FormatError> {
    let [codec, order, count, stride] = s.header()?;
    let codec = Codec::from_id(codec)?;
    match codec.stride(order) {
        Some(expected) if expected == stride as usize => {}
        _ => {
            return Err(FormatError::CodecOrderMismatch {
                codec: codec.name(),
                order,
                stride,
            })
        }
    }
    let [data] = s.arrays([bytes_for(count, stride as usize)])?;
    Ok(Coefficients {
        codec,
        order,
        data: data.to_vec(),
    })
}

fn parse_validity(s: &Sec<'_>) -> Result<Vec<Validity>, FormatError> {
    let [count, ..] = s.header()?;
    let [data] = s.arrays([bytes_for(count, 8)])?;
    Ok(pod_vec::<[u32; 2]>(data)
        .into_iter()
        .map(|[v, flags]| Validity {
            value: f32::from_bits(v),
            flags,
        })
        .collect())
}

fn parse_tetrahedra(s: &Sec<'_>) -> Result<TetSection, FormatError> {
    let [count, ..] = s.header()?;
    let [v, n, m] = s.arrays([
        bytes_for(count, 16),
        bytes_for(count, 16),
        bytes_for(count, 48),
    ])?;
    Ok(TetSection {
        vertices: pod_vec(v),
        neighbours: pod_vec(n),
        barycentric: pod_vec(m),
    })
}

fn parse_outer(s: &Sec<'_>) -> Result<OuterCells, FormatError> {
    let [count, ..] = s.header()?;
    let [v, a, p, t] = s.arrays([
        bytes_for(count, 12),
        bytes_for(count, 12),
        bytes_for(count, 16),
        bytes_for(count, 4),
    ])?;
    Ok(OuterCells {
        vertices: pod_vec(v),
        adjacent: pod_vec(a),
        planes: pod_vec(p),
        tetrahedra: pod_vec(t),
    })
}

/// The root grid of an `OCTR`/`OCTC` header (`w2`, `w3`).
fn parse_roots(id: SectionId, w2: u32, w3: u32) -> Result<[u32; 3], FormatError> {
    super::layout::unpack_roots(w2, w3).ok_or(FormatError::InvalidValue {
        id,
        element: 0,
        reason: "octree root grid axis outside 1..=65536",
    })
}

fn parse_octree(s: &Sec<'_>) -> Result<Octree, FormatError> {
    let [nodes, samples, w2, w3] = s.header()?;
    let roots = parse_roots(SectionId::OCTREE, w2, w3)?;
    let [n, sm] = s.arrays([bytes_for(nodes, OCTREE_NODE_LEN), bytes_for(samples, 4)])?;
    let nodes = pod_vec::<[u32; 10]>(n)
        .into_iter()
        .map(|w| {
            let f = |k: usize| f32::from_bits(w[k]);
            OctreeNode {
                min: Vec3::new(f(0), f(1), f(2)),
                max: Vec3::new(f(3), f(4), f(5)),
                first_child: w[6],
                depth: w[7],
                sample_offset: w[8],
                sample_count: w[9],
            }
        })
        .collect();
    Ok(Octree {
        nodes,
        samples: pod_vec(sm),
        roots,
    })
}

fn parse_octree_compact(s: &Sec<'_>) -> Result<super::octree_compact::Compact, FormatError> {
    let [nodes, max_depth, w2, w3] = s.header()?;
    let roots = parse_roots(SectionId::OCTREE_COMPACT, w2, w3)?;
    let bits_len = (nodes as usize).div_ceil(8);
    let [b, bits] = s.arrays([Some(24), Some(bits_len)])?;
    let b = pod_vec::<[f32; 6]>(b);
    let b = b.first().ok_or(s.size_error(48))?;
    Ok(super::octree_compact::Compact {
        min: Vec3::new(b[0], b[1], b[2]),
        max: Vec3::new(b[3], b[4], b[5]),
        max_depth,
        nodes,
        roots,
        bits: bits.to_vec(),
    })
}

fn parse_grid(s: &Sec<'_>) -> Result<VolumeGrid, FormatError> {
    let [rx, ry, rz, _] = s.header()?;
    let [b] = s.arrays([Some(24)])?;
    let b = pod_vec::<[f32; 6]>(b);
    let b = b.first().ok_or(s.size_error(48))?;
    Ok(VolumeGrid {
        min: Vec3::new(b[0], b[1], b[2]),
        max: Vec3::new(b[3], b[4], b[5]),
        resolution: [rx, ry, rz],
    })
}

fn parse_gradients(s: &Sec<'_>) -> Result<Gradients, FormatError> {
    let [order, count, ..] = s.header()?;
    if order == 0 || order as usize > probekit_sh::MAX_ORDER {
        return Err(FormatError::InvalidValue {
            id: s.id,
            element: 0,
            reason: "gradient SH order outside 1..=8",
        });
    }
    let per_probe = 3 * 12 * (order * order) as usize;
    let [data] = s.arrays([bytes_for(count, per_probe)])?;
    Ok(Gradients {
        order,
        data: vec3s(data),
    })
}

fn parse_axis(model: u32, count: u32, id: SectionId, rig: u64) -> Result<AxisModel, FormatError> {
    let bad = |reason| FormatError::InvalidValue {
        id,
        element: rig,
        reason,
    };
    match (model, count) {
        (0, 1) => Ok(AxisModel::Constant),
        (1, 2) => Ok(AxisModel::Gradient),
        (2, n) if n >= 1 => Ok(AxisModel::Lattice(n)),
        (0..=2, _) => Err(bad("rig axis count does not match its model")),
        _ => Err(bad("unknown rig axis model")),
    }
}

fn parse_rigs(s: &Sec<'_>) -> Result<Vec<Rig>, FormatError> {
    let [count, ..] = s.header()?;
    // Every record takes at least RIG_HEADER_LEN bytes: bound the capacity.
    let mut rigs = Vec::with_capacity((count as usize).min(s.bytes.len() / RIG_HEADER_LEN));
    let mut pos = SECTION_HEADER_LEN;
    for r in 0..count as u64 {
        let w = |k: usize| {
            pos.checked_add(4 * k)
                .and_then(|o| u32_at(s.bytes, o))
                .ok_or(FormatError::SectionSize {
                    id: s.id,
                    expected: (pos + RIG_HEADER_LEN) as u64,
                    actual: s.bytes.len() as u64,
                })
        };
        let mut h = [0u32; RIG_HEADER_LEN / 4];
        for (k, slot) in h.iter_mut().enumerate() {
            *slot = w(k)?;
        }
        let model = match h[0] {
            0 => RigModel::Constant,
            1 => RigModel::Gradient,
            2 => RigModel::Tensor([
                parse_axis(h[1], h[4], s.id, r)?,
                parse_axis(h[2], h[5], s.id, r)?,
                parse_axis(h[3], h[6], s.id, r)?,
            ]),
            _ => {
                return Err(FormatError::InvalidValue {
                    id: s.id,
                    element: r,
                    reason: "unknown rig model",
                })
            }
        };
        let order = h[7];
        let samples = h[8];
        let params = h[9];
        let transitions = h[10];
        let name_len = h[11];
        if order == 0 || order as usize > probekit_sh::MAX_ORDER {
            return Err(FormatError::InvalidValue {
                id: s.id,
                element: r,
                reason: "rig SH order outside 1..=8",
            });
        }
        if model.parameter_count() != Some(params) {
            return Err(FormatError::InvalidValue {
                id: s.id,
                element: r,
                reason: "rig parameter count does not match its model",
            });
        }
        let f = |k: usize| f32::from_bits(h[k]);
        let bbox_min = Vec3::new(f(12), f(13), f(14));
        let bbox_max = Vec3::new(f(15), f(16), f(17));
        let start = pos + RIG_HEADER_LEN;
        let sizes = [
            Some(name_len as usize),
            bytes_for(samples, 12),
            bytes_for(params, 4).and_then(|p| p.checked_mul(samples as usize)),
            bytes_for(transitions, 8),
        ];
        let ([name, pts, fit, tr], end) = s.arrays_at(start, sizes, false)?;
        let name = s.name(name)?;
        rigs.push(Rig {
            name,
            model,
            order,
            bbox_min,
            bbox_max,
            samples: vec3s(pts),
            fitting: pod_vec(fit),
            transitions: pod_vec::<[f32; 2]>(tr)
                .into_iter()
                .map(|[distance, error]| Transition { distance, error })
                .collect(),
        });
        pos = end;
    }
    if pos != s.bytes.len() {
        return Err(s.size_error(pos as u64));
    }
    Ok(rigs)
}

/// Checks a codec id, order and stride read from a file against each other.
fn codec_for(codec: u32, order: u32, stride: u32) -> Result<Codec, FormatError> {
    let codec = Codec::from_id(codec)?;
    match codec.stride(order) {
        Some(expected) if expected == stride as usize => Ok(codec),
        _ => Err(FormatError::CodecOrderMismatch {
            codec: codec.name(),
            order,
            stride,
        }),
    }
}

fn parse_groups(s: &Sec<'_>) -> Result<Vec<LightGroup>, FormatError> {
    let [count, probes, ..] = s.header()?;
    // Every record takes at least GROUP_HEADER_LEN bytes: bound the capacity.
    let mut groups = Vec::with_capacity((count as usize).min(s.bytes.len() / GROUP_HEADER_LEN));
    let mut pos = SECTION_HEADER_LEN;
    for _ in 0..count {
        let w = |k: usize| {
            pos.checked_add(4 * k)
                .and_then(|o| u32_at(s.bytes, o))
                .ok_or(FormatError::SectionSize {
                    id: s.id,
                    expected: (pos + GROUP_HEADER_LEN) as u64,
                    actual: s.bytes.len() as u64,
                })
        };
        let (codec, order, stride, name_len) = (w(0)?, w(1)?, w(2)?, w(3)?);
        let codec = codec_for(codec, order, stride)?;
        let start = pos + GROUP_HEADER_LEN;
        let sizes = [Some(name_len as usize), bytes_for(probes, stride as usize)];
        let ([name, data], end) = s.arrays_at(start, sizes, false)?;
        let name = s.name(name)?;
        groups.push(LightGroup {
            name,
            coefficients: Coefficients {
                codec,
                order,
                data: data.to_vec(),
            },
        });
        pos = end;
    }
    if pos != s.bytes.len() {
        return Err(s.size_error(pos as u64));
    }
    Ok(groups)
}

fn parse_visibility(s: &Sec<'_>) -> Result<super::DistanceMoments, FormatError> {
    let [count, resolution, max_bits, _] = s.header()?;
    if resolution == 0 || resolution > super::MAX_VISIBILITY_RESOLUTION {
        return Err(FormatError::InvalidValue {
            id: s.id,
            element: 0,
            reason: "visibility map resolution outside 1..=64",
        });
    }
    let per_probe = 4 * (resolution as usize) * (resolution as usize);
    let [data] = s.arrays([bytes_for(count, per_probe)])?;
    Ok(super::DistanceMoments {
        resolution,
        max_distance: f32::from_bits(max_bits),
        data: data
            .chunks_exact(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]))
            .collect(),
    })
}

fn parse_cell_visibility(s: &Sec<'_>) -> Result<CellVisibility, FormatError> {
    let [tets, faces, k, _] = s.header()?;
    check_subdivision(s, k)?;
    let [data] = s.arrays([records_len(k, tets as usize, faces as usize)])?;
    // Padding bits are checked here: the sparse form drops clear records.
    let padded = |rec: &[u8], vertices: usize| record_has_padding(rec, vertices, k);
    let (t, h) = data.split_at(tets as usize * record_bytes(4, k));
    let bad = t
        .chunks_exact(record_bytes(4, k))
        .position(|r| padded(r, 4))
        .or_else(|| {
            h.chunks_exact(record_bytes(3, k))
                .position(|r| padded(r, 3))
                .map(|i| tets as usize + i)
        });
    if let Some(element) = bad {
        return Err(FormatError::InvalidValue {
            id: s.id,
            element: element as u64,
            reason: "cell visibility record has padding bits set",
        });
    }
    CellVisibility::new(k, tets as usize, faces as usize, data.to_vec())
        .ok_or(FormatError::CountOverflow(s.id))
}

fn check_subdivision(s: &Sec<'_>, k: u32) -> Result<(), FormatError> {
    if (1..=MAX_CELL_SUBDIVISION).contains(&k) {
        Ok(())
    } else {
        Err(FormatError::InvalidValue {
            id: s.id,
            element: 0,
            reason: "cell visibility subdivision outside 1..=8",
        })
    }
}

/// `CVSP` (1.5): a mask of one bit per cell, then the records of the cells
/// whose bit is set.
fn parse_cell_visibility_sparse(s: &Sec<'_>) -> Result<CellVisibility, FormatError> {
    let [tets, faces, k, _] = s.header()?;
    check_subdivision(s, k)?;
    let cells = (tets as usize).checked_add(faces as usize);
    let ([mask], end) = s.arrays_at(SECTION_HEADER_LEN, [cells.map(|c| c.div_ceil(8))], false)?;
    let (t, h) = stored_counts(mask, tets as usize, faces as usize);
    let ([records], _) = s.arrays_at(end, [records_len(k, t, h)], true)?;
    CellVisibility::from_sparse(
        k,
        tets as usize,
        faces as usize,
        mask.to_vec(),
        records.to_vec(),
    )
    .ok_or(FormatError::CountOverflow(s.id))
}

/// `PWGT` (1.6): one little-endian `f32` per probe, (1.8) the
/// brightness exponent as `f32` bits in header word `w1` and (1.9) the
/// directional one in `w2` (all range checked by [`super::validate`]).
fn parse_probe_weights(s: &Sec<'_>) -> Result<(Vec<f32>, f32, f32), FormatError> {
    let [count, alpha, beta, _] = s.header()?;
    let [data] = s.arrays([bytes_for(count, 4)])?;
    let w = data
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    Ok((w, f32::from_bits(alpha), f32::from_bits(beta)))
}

/// A `CPLN` section (1.7) as stored, its arrays checked against the section
/// length only: the mesh's tetrahedron count (header `w0`), the tetrahedra
/// with a plane and their planes `[n_x, n_y, n_z, d]`. [`build_cell_planes`]
/// turns it into a [`CellPlanes`] once the whole file is parsed: the
/// planes' lookup table has one entry per tetrahedron, so `tet_count` must
/// first be checked against `TETS` (a section that may come later).
struct RawCellPlanes {
    tet_count: u32,
    tets: Vec<u32>,
    planes: Vec<[f32; 4]>,
}

/// `CPLN` (1.7): header `tet_count, count`; `count × u32` tetrahedron
/// indices, then `count × f32[4]` planes, each array padded to 16.
fn parse_cell_planes(s: &Sec<'_>) -> Result<RawCellPlanes, FormatError> {
    let [tet_count, count, ..] = s.header()?;
    let [tets, planes] = s.arrays([bytes_for(count, 4), bytes_for(count, 16)])?;
    Ok(RawCellPlanes {
        tet_count,
        tets: pod_vec(tets),
        planes: pod_vec(planes),
    })
}

/// The first entry of `raw` that [`CellPlanes::new`] would refuse, as a
/// typed error naming it: an index not above the one before it (unsorted or
/// repeated), an index past the tetrahedra, a value that is not finite, or
/// a normal whose length is not within [`PLANE_NORMAL_TOLERANCE`](crate::cloud::cell_visibility::PLANE_NORMAL_TOLERANCE) of 1.
fn first_bad_cell_plane(raw: &RawCellPlanes) -> Option<FormatError> {
    let id = SectionId::CELL_PLANES;
    raw.tets
        .iter()
        .zip(&raw.planes)
        .enumerate()
        .find_map(|(i, (&t, p))| {
            let element = i as u64;
            let bad = |reason| FormatError::InvalidValue {
                id,
                element,
                reason,
            };
            if i > 0 && t <= raw.tets[i - 1] {
                Some(bad(
                    "cell plane tetrahedra not strictly increasing (unsorted or repeated index)",
                ))
            } else if t >= raw.tet_count {
                Some(FormatError::IndexOutOfRange {
                    id,
                    element,
                    value: t.into(),
                    limit: raw.tet_count.into(),
                })
            } else if !p.iter().all(|c| c.is_finite()) {
                Some(FormatError::NonFinite { id, element })
            } else if !plane_has_unit_normal(p) {
                Some(bad("cell plane normal not of unit length (tolerance 1e-3)"))
            } else {
                None
            }
        })
}

/// Builds the planes of a `CPLN` section once `file` holds every other
/// section: where they may stand first
/// ([`super::validate::check_cell_planes_context`]: a cloud with cell
/// visibility, `tet_count` equal to `TETS`'s count), then each entry.
fn build_cell_planes(file: &ProbeFile, raw: RawCellPlanes) -> Result<CellPlanes, FormatError> {
    super::validate::check_cell_planes_context(file, raw.tet_count as usize)?;
    if let Some(e) = first_bad_cell_plane(&raw) {
        return Err(e);
    }
    CellPlanes::new(raw.tet_count as usize, raw.tets, raw.planes).ok_or(FormatError::InvalidValue {
        id: SectionId::CELL_PLANES,
        element: 0,
        reason: "cell planes refused",
    })
}

fn parse_metadata(s: &Sec<'_>) -> Result<String, FormatError> {
    let [len, ..] = s.header()?;
    let [text] = s.arrays([Some(len as usize)])?;
    core::str::from_utf8(text)
        .map(str::to_string)
        .map_err(|_| FormatError::InvalidUtf8(s.id))
}

/// Parses and validates a whole file (see [`ProbeFile::from_bytes`]).
pub(super) fn parse(bytes: &[u8]) -> Result<ProbeFile, FormatError> {
    let (head, sections) = read_sections(bytes)?;
    let kind = ProbeFileKind::from_id(head.kind)?;
    let mut positions = None;
    let mut coefficients = None;
    let mut compact = None;
    let mut planes = None;
    let mut file = ProbeFile::new(kind, Coefficients::empty(1));
    for raw in &sections {
        let s = Sec {
            id: raw.id,
            bytes: raw.bytes,
        };
        match raw.id {
            SectionId::POSITIONS => positions = Some(parse_positions(&s)?),
            SectionId::COEFFICIENTS => coefficients = Some(parse_coefficients(&s)?),
            SectionId::VALIDITY => file.validity = Some(parse_validity(&s)?),
            SectionId::TETRAHEDRA => file.tetrahedra = Some(parse_tetrahedra(&s)?),
            SectionId::OUTER => file.outer = Some(parse_outer(&s)?),
            SectionId::OCTREE => file.octree = Some(parse_octree(&s)?),
            SectionId::OCTREE_COMPACT => compact = Some(parse_octree_compact(&s)?),
            SectionId::GRID => file.grid = Some(parse_grid(&s)?),
            SectionId::GRADIENTS => file.gradients = Some(parse_gradients(&s)?),
            SectionId::RIGS => file.rigs = parse_rigs(&s)?,
            SectionId::LIGHT_GROUPS => file.groups = parse_groups(&s)?,
            SectionId::VISIBILITY => file.visibility = Some(parse_visibility(&s)?),
            SectionId::CELL_VISIBILITY | SectionId::CELL_VISIBILITY_SPARSE => {
                if file.cell_visibility.is_some() {
                    return Err(FormatError::InvalidValue {
                        id: s.id,
                        element: 0,
                        reason: "both CVIS and CVSP: at most one cell visibility section",
                    });
                }
                file.cell_visibility = Some(if raw.id == SectionId::CELL_VISIBILITY {
                    parse_cell_visibility(&s)?
                } else {
                    parse_cell_visibility_sparse(&s)?
                });
            }
            SectionId::PROBE_WEIGHTS => {
                let (w, alpha, beta) = parse_probe_weights(&s)?;
                file.probe_weights = Some(w);
                file.brightness_exponent = alpha;
                file.directional_exponent = beta;
            }
            SectionId::CELL_PLANES => planes = Some(parse_cell_planes(&s)?),
            SectionId::METADATA => file.metadata = parse_metadata(&s)?,
            id if head.minor > VERSION_MINOR => {
                // A newer minor version may add sections; skip them.
                let _ = id;
            }
            id => return Err(FormatError::UnknownSection(id)),
        }
    }
    file.positions = positions.ok_or(FormatError::MissingSection(SectionId::POSITIONS))?;
    file.coefficients = coefficients.ok_or(FormatError::MissingSection(SectionId::COEFFICIENTS))?;
    if let Some(c) = compact {
        if file.octree.is_some() {
            return Err(FormatError::InvalidValue {
                id: SectionId::OCTREE_COMPACT,
                element: 0,
                reason: "a file holds OCTR or OCTC, not both",
            });
        }
        file.octree = Some(c.expand(&file.positions)?);
    }
    if let Some(raw) = planes {
        file.cell_planes = Some(build_cell_planes(&file, raw)?);
    }
    file.validate()?;
    Ok(file)
}
