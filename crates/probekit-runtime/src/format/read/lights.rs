//! `LITE` (run-time lights) and `OCCL` (the probes' occlusion of them).

use super::{bytes_for, pod_vec, Sec};
use crate::format::error::FormatError;
use crate::format::layout::{RUNTIME_LIGHT_LEN, SECTION_HEADER_LEN};
use crate::format::lights::{light_from_words, LightOcclusion, RuntimeLight};
use crate::prelude::*;

/// The lights of `LITE`: fixed 64-byte records, then their group names.
pub(super) fn parse_runtime_lights(s: &Sec<'_>) -> Result<Vec<RuntimeLight>, FormatError> {
    let [count, ..] = s.header()?;
    let [records] = s
        .arrays_at(
            SECTION_HEADER_LEN,
            [bytes_for(count, RUNTIME_LIGHT_LEN)],
            false,
        )?
        .0;
    let words: Vec<[u32; 16]> = pod_vec(records);
    let names_start = SECTION_HEADER_LEN + records.len();
    let name_total = words
        .iter()
        .try_fold(0usize, |a, w| a.checked_add(w[1] as usize))
        .ok_or(FormatError::CountOverflow(s.id))?;
    let ([names], _) = s.arrays_at(names_start, [Some(name_total)], true)?;
    let mut lights = Vec::with_capacity(words.len());
    let mut at = 0usize;
    for (k, w) in words.iter().enumerate() {
        let f: [f32; 13] = core::array::from_fn(|j| f32::from_bits(w[2 + j]));
        let light = light_from_words(w[0], &f).ok_or(FormatError::InvalidValue {
            id: s.id,
            element: k as u64,
            reason: "unknown run-time light kind",
        })?;
        let end = at + w[1] as usize;
        let group = s.name(&names[at..end])?;
        at = end;
        lights.push(RuntimeLight { light, group });
    }
    Ok(lights)
}

/// The sparse table of `OCCL`, and the light count its header names.
pub(super) fn parse_light_occlusion(s: &Sec<'_>) -> Result<(LightOcclusion, u32), FormatError> {
    let [probes, lights, entries, _] = s.header()?;
    let [counts, pairs] = s.arrays([Some(probes as usize), bytes_for(entries, 2)])?;
    let pairs: Vec<[u8; 2]> = pairs.chunks_exact(2).map(|p| [p[0], p[1]]).collect();
    Ok((LightOcclusion::from_parts(counts.to_vec(), pairs), lights))
}
