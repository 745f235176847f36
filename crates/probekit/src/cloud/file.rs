//! Writing a baked probe cloud as a [`ProbeFile`]: Delaunay tetrahedra with
//! neighbours and barycentric matrices (the `TETS` section), encoded radiance
//! SH, validity and `META` JSON.

use super::{tetrahedralize, DelaunayError};
use crate::capture::{CaptureSettings, Validity};
use crate::format::{encode_coefficients, BakeMetadata, FormatError, ProbeFile};
use glam::{DMat3, DVec3, Vec3};
use probekit_runtime::format::layout::{NONE, VALIDITY_INVALID, VALIDITY_VIRTUAL_OFFSET};
use probekit_runtime::format::{Codec, LightGroup, TetSection, Validity as FileValidity};
use probekit_sh::ShRgb;
use thiserror::Error;

/// Why a cloud file cannot be built.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum CloudFileError {
    /// The positions cannot be tetrahedralized.
    #[error("tetrahedralizing the probes: {0}")]
    Delaunay(#[from] DelaunayError),
    /// The coefficients cannot be encoded.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// Inputs of different lengths or SH orders.
    #[error("{0}")]
    Mismatch(String),
}

/// The `TETS` section for tetrahedra over `points`: vertices, neighbours
/// (`NONE` on the hull) and the row-major 3×4 world→barycentric matrix of
/// each tetrahedron (`b_i = M_i·(x, y, z, 1)` for vertices 0..3; `b_3 = 1 −
/// Σ`), i.e. the inverse of `[v0 − v3, v1 − v3, v2 − v3]` applied to `p − v3`,
/// computed in f64.
pub fn tet_section(points: &[Vec3], tets: &[[u32; 4]], neighbors: &[[u32; 4]]) -> TetSection {
    let barycentric = tets
        .iter()
        .map(|t| {
            let v = t.map(|i| points[i as usize].as_dvec3());
            let m = DMat3::from_cols(v[0] - v[3], v[1] - v[3], v[2] - v[3]).inverse();
            let off = -(m * v[3]);
            let row = |i: usize| -> [f32; 4] {
                let r: DVec3 = m.row(i);
                [r.x as f32, r.y as f32, r.z as f32, off[i] as f32]
            };
            [row(0), row(1), row(2)]
        })
        .collect();
    TetSection {
        vertices: tets.to_vec(),
        neighbours: neighbors
            .iter()
            .map(|n| n.map(|x| if x == super::HULL { NONE } else { x }))
            .collect(),
        barycentric,
    }
}

/// Per-probe validity as stored: `value` = 1 − back-face fraction, flags
/// invalid / moved by the virtual offset.
pub fn file_validity(v: &Validity) -> FileValidity {
    let mut flags = 0;
    if !v.valid {
        flags |= VALIDITY_INVALID;
    }
    if v.offset_applied {
        flags |= VALIDITY_VIRTUAL_OFFSET;
    }
    FileValidity {
        value: 1.0 - v.backface_fraction,
        flags,
    }
}

/// The bake settings as the `settings` object of [`BakeMetadata`].
pub fn settings_json(s: &CaptureSettings, codec: Codec) -> serde_json::Value {
    serde_json::json!({
        "samples": s.samples,
        "bounces": s.bounces,
        "order": s.order,
        "seed": s.seed,
        "russian_roulette_depth": s.russian_roulette_depth,
        "split_direct": s.split_direct,
        "groups": s.groups,
        "backface_threshold": s.validity.backface_threshold,
        "virtual_offset": s.validity.virtual_offset,
        "offset_margin": s.validity.offset_margin,
        "pre_pass_rays": s.validity.pre_pass_rays,
        "max_offset_steps": s.validity.max_offset_steps,
        "codec": codec.name(),
    })
}

/// A complete probe-cloud file: tetrahedralizes `positions` (metres),
/// stores their radiance SH (`sh`, all of one order) in `codec`, the
/// validity (see [`file_validity`]) and `metadata` as JSON. Deterministic: equal inputs give equal
/// bytes.
pub fn cloud_file(
    positions: &[Vec3],
    sh: &[ShRgb],
    validity: &[FileValidity],
    codec: Codec,
    metadata: &BakeMetadata,
) -> Result<ProbeFile, CloudFileError> {
    if sh.len() != positions.len() || validity.len() != positions.len() {
        return Err(CloudFileError::Mismatch(format!(
            "{} positions, {} SH, {} validity entries",
            positions.len(),
            sh.len(),
            validity.len()
        )));
    }
    let order = sh.first().map_or(1, |s| s.order());
    if sh.iter().any(|s| s.order() != order) {
        return Err(CloudFileError::Mismatch(
            "probes of different SH orders".into(),
        ));
    }
    let t = tetrahedralize(positions)?;
    let flat: Vec<Vec3> = sh.iter().flat_map(|s| s.coeffs().iter().copied()).collect();
    let coefficients = encode_coefficients(codec, order as u32, &flat)?;
    let mut file = ProbeFile::cloud(positions.to_vec(), 1, &vec![Vec3::ZERO; positions.len()])?;
    file.coefficients = coefficients;
    file.tetrahedra = Some(tet_section(positions, &t.tets, &t.neighbors));
    file.validity = Some(validity.to_vec());
    file.metadata = metadata.to_json();
    file.validate()?;
    Ok(file)
}

/// The `LGRP` light groups of a bake: each `(name, radiance SH per probe)`
/// (e.g. [`crate::capture::BakeOutput::groups`]), every SH of `order` bands,
/// encoded in `codec`, in the order given. Set them as [`ProbeFile::groups`]; the file's validation then
/// checks probe counts, orders and names. Deterministic like [`cloud_file`].
pub fn light_groups(
    groups: &[(String, Vec<ShRgb>)],
    order: usize,
    codec: Codec,
) -> Result<Vec<LightGroup>, CloudFileError> {
    groups
        .iter()
        .map(|(name, sh)| {
            if sh.iter().any(|s| s.order() != order) {
                return Err(CloudFileError::Mismatch(format!(
                    "light group {name}: SH of an order other than {order}"
                )));
            }
            let flat: Vec<Vec3> = sh.iter().flat_map(|s| s.coeffs().iter().copied()).collect();
            Ok(LightGroup {
                name: name.clone(),
                coefficients: encode_coefficients(codec, order as u32, &flat)?,
            })
        })
        .collect()
}

/// Decodes a file's light groups back to `(name, radiance SH per probe)`
/// (the inverse of [`light_groups`] for `f32`; what `merge` reads from parts).
pub fn decode_light_groups(file: &ProbeFile) -> Result<Vec<(String, Vec<ShRgb>)>, CloudFileError> {
    file.groups
        .iter()
        .map(|g| {
            let n = g.coefficients.coeffs_per_probe().max(1);
            let flat = g.coefficients.to_f32()?;
            let sh = flat
                .chunks(n)
                .map(|c| {
                    ShRgb::from_coeffs(c.to_vec()).ok_or_else(|| {
                        CloudFileError::Mismatch(format!("light group {}: bad SH order", g.name))
                    })
                })
                .collect::<Result<Vec<_>, _>>()?;
            Ok((g.name.clone(), sh))
        })
        .collect()
}

/// A cloud file of `positions` and `sh` (f32, every probe valid, placement
/// `manual`), for tests.
#[cfg(test)]
pub(crate) fn test_cloud_file(positions: &[Vec3], sh: &[ShRgb]) -> ProbeFile {
    let validity = vec![
        FileValidity {
            value: 1.0,
            flags: 0
        };
        positions.len()
    ];
    let meta = BakeMetadata::new(
        "0".into(),
        crate::format::Placement {
            method: "manual".into(),
            parameters: serde_json::json!({}),
        },
        serde_json::json!({}),
    );
    cloud_file(positions, sh, &validity, Codec::F32, &meta).expect("test cloud")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barycentric_matrices_reproduce_vertices() {
        let pts = super::super::bench_points::uniform(40, 3);
        let t = tetrahedralize(&pts).unwrap();
        let s = tet_section(&pts, &t.tets, &t.neighbors);
        for (tet, m) in s.vertices.iter().zip(&s.barycentric) {
            for (j, &vi) in tet.iter().enumerate() {
                let p = pts[vi as usize];
                let b: Vec<f32> = (0..3)
                    .map(|i| m[i][0] * p.x + m[i][1] * p.y + m[i][2] * p.z + m[i][3])
                    .collect();
                let b3 = 1.0 - b[0] - b[1] - b[2];
                let all = [b[0], b[1], b[2], b3];
                for (k, w) in all.iter().enumerate() {
                    let want = if k == j { 1.0 } else { 0.0 };
                    assert!((w - want).abs() < 1e-3, "{w} vs {want}");
                }
            }
        }
    }
}
