//! Sections of a probe cloud: its tetrahedra and outer cells, and what
//! weights its blend: distance moments, cell visibility, occluder planes
//! and fitted probe weights.

use super::{bytes_for, pod_vec, Sec};
use crate::cloud::cell_visibility::{
    plane_has_unit_normal, records_len, stored_counts, CellPlanes, CellVisibility,
    MAX_CELL_SUBDIVISION,
};
use crate::format::error::FormatError;
use crate::format::layout::{SectionId, SECTION_HEADER_LEN};
use crate::format::{
    validate, CloudFile, DistanceMoments, OuterCells, TetSection, MAX_VISIBILITY_RESOLUTION,
};
use crate::prelude::*;

pub(super) fn parse_tetrahedra(s: &Sec<'_>) -> Result<TetSection, FormatError> {
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

pub(super) fn parse_outer(s: &Sec<'_>) -> Result<OuterCells, FormatError> {
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

pub(super) fn parse_visibility(s: &Sec<'_>) -> Result<DistanceMoments, FormatError> {
    let [count, resolution, max_bits, _] = s.header()?;
    if resolution == 0 || resolution > MAX_VISIBILITY_RESOLUTION {
        return Err(FormatError::InvalidValue {
            id: s.id,
            element: 0,
            reason: "visibility map resolution outside 1..=64",
        });
    }
    let per_probe = 4 * (resolution as usize) * (resolution as usize);
    let [data] = s.arrays([bytes_for(count, per_probe)])?;
    Ok(DistanceMoments {
        resolution,
        max_distance: f32::from_bits(max_bits),
        data: data
            .chunks_exact(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]))
            .collect(),
    })
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

/// `CVSP`: a mask of one bit per cell, then the records of the cells whose
/// bit is set.
pub(super) fn parse_cell_visibility(s: &Sec<'_>) -> Result<CellVisibility, FormatError> {
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

/// `PWGT`: one little-endian `f32` per probe, the brightness exponent as
/// `f32` bits in header word `w1` and the directional one in `w2` (all
/// range checked by [`validate`]).
pub(super) fn parse_probe_weights(s: &Sec<'_>) -> Result<(Vec<f32>, f32, f32), FormatError> {
    let [count, alpha, beta, _] = s.header()?;
    let [data] = s.arrays([bytes_for(count, 4)])?;
    let w = data
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    Ok((w, f32::from_bits(alpha), f32::from_bits(beta)))
}

/// A `CPLN` section as stored, its arrays checked against the section
/// length only: the mesh's tetrahedron count (header `w0`), the tetrahedra
/// with a plane and their planes `[n_x, n_y, n_z, d]`. [`build_cell_planes`]
/// turns it into a [`CellPlanes`] once the whole file is parsed: the
/// planes' lookup table has one entry per tetrahedron, so `tet_count` must
/// first be checked against `TETS` (a section that may come later).
pub(super) struct RawCellPlanes {
    tet_count: u32,
    tets: Vec<u32>,
    planes: Vec<[f32; 4]>,
}

/// `CPLN`: header `tet_count, count`; `count × u32` tetrahedron
/// indices, then `count × f32[4]` planes, each array padded to 16.
pub(super) fn parse_cell_planes(s: &Sec<'_>) -> Result<RawCellPlanes, FormatError> {
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

/// Builds the planes of a `CPLN` section once `cloud` holds every other
/// section: where they may stand first
/// ([`validate::check_cell_planes_context`]: cell visibility present,
/// `tet_count` equal to `TETS`'s count), then each entry.
pub(super) fn build_cell_planes(
    cloud: &CloudFile,
    raw: RawCellPlanes,
) -> Result<CellPlanes, FormatError> {
    validate::check_cell_planes_context(cloud, raw.tet_count as usize)?;
    if let Some(e) = first_bad_cell_plane(&raw) {
        return Err(e);
    }
    CellPlanes::new(raw.tet_count as usize, raw.tets, raw.planes).ok_or(FormatError::InvalidValue {
        id: SectionId::CELL_PLANES,
        element: 0,
        reason: "cell planes refused",
    })
}
