//! Sections any kind of file may hold: positions, coefficients, validity,
//! light groups and metadata.

use super::{bytes_for, pod_vec, u32_at, vec3s, Sec};
use crate::format::codec::{Codec, Coefficients};
use crate::format::error::FormatError;
use crate::format::layout::{GROUP_HEADER_LEN, SECTION_HEADER_LEN};
use crate::format::{LightGroup, Validity};
use crate::prelude::*;
use glam::Vec3;

pub(super) fn parse_positions(s: &Sec<'_>) -> Result<Vec<Vec3>, FormatError> {
    let [count, ..] = s.header()?;
    let [data] = s.arrays([bytes_for(count, 12)])?;
    Ok(vec3s(data))
}

pub(super) fn parse_coefficients(s: &Sec<'_>) -> Result<Coefficients, FormatError> {
    let [codec, order, count, stride] = s.header()?;
    let codec = codec_for(codec, order, stride)?;
    let [data] = s.arrays([bytes_for(count, stride as usize)])?;
    Ok(Coefficients {
        codec,
        order,
        data: data.to_vec(),
    })
}

pub(super) fn parse_validity(s: &Sec<'_>) -> Result<Vec<Validity>, FormatError> {
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

pub(super) fn parse_groups(s: &Sec<'_>) -> Result<Vec<LightGroup>, FormatError> {
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

pub(super) fn parse_metadata(s: &Sec<'_>) -> Result<String, FormatError> {
    let [len, ..] = s.header()?;
    let [text] = s.arrays([Some(len as usize)])?;
    core::str::from_utf8(text)
        .map(str::to_string)
        .map_err(|_| FormatError::InvalidUtf8(s.id))
}
