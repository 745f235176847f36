//! Sections of an irradiance volume: the uniform grid, the adaptive
//! octree and the SH gradients.

use super::{bytes_for, pod_vec, vec3s, Sec};
use crate::format::error::FormatError;
use crate::format::layout::{unpack_roots, SectionId};
use crate::format::octree_compact::Compact;
use crate::format::{Gradients, VolumeGrid};
use glam::Vec3;

/// The root grid of an `OCTC` header (`w2`, `w3`).
fn parse_roots(id: SectionId, w2: u32, w3: u32) -> Result<[u32; 3], FormatError> {
    unpack_roots(w2, w3).ok_or(FormatError::InvalidValue {
        id,
        element: 0,
        reason: "octree root grid axis outside 1..=65536",
    })
}

/// `OCTC`: the compact octree, expanded against the positions once the
/// whole file is read ([`Compact::expand`]).
pub(super) fn parse_octree(s: &Sec<'_>) -> Result<Compact, FormatError> {
    let [nodes, max_depth, w2, w3] = s.header()?;
    let roots = parse_roots(SectionId::OCTREE, w2, w3)?;
    let bits_len = (nodes as usize).div_ceil(8);
    let [b, bits] = s.arrays([Some(24), Some(bits_len)])?;
    let b = pod_vec::<[f32; 6]>(b);
    let b = b.first().ok_or(s.size_error(48))?;
    Ok(Compact {
        min: Vec3::new(b[0], b[1], b[2]),
        max: Vec3::new(b[3], b[4], b[5]),
        max_depth,
        nodes,
        roots,
        bits: bits.to_vec(),
    })
}

pub(super) fn parse_grid(s: &Sec<'_>) -> Result<VolumeGrid, FormatError> {
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

pub(super) fn parse_gradients(s: &Sec<'_>) -> Result<Gradients, FormatError> {
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
