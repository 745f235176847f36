//! Assembling a baked probe cloud as a [`ProbeFile`]: Delaunay tetrahedra with
//! neighbours and barycentric matrices (the `TETS` section), encoded radiance
//! SH, the capture's validity, light groups and `META` JSON. Above the
//! capture and the Delaunay code, which it takes its inputs from.

use super::{encode_coefficients, FormatError, ProbeFile};
use crate::capture::Validity;
use crate::delaunay::{tetrahedralize, DelaunayError, HULL};
use crate::format::Parts;
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
            .map(|n| n.map(|x| if x == HULL { NONE } else { x }))
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

/// A complete probe-cloud file: tetrahedralizes `positions` (metres),
/// stores their radiance SH (`sh`, all of one order) in `codec`, the
/// validity (see [`file_validity`]) and `metadata` (the `META` text: a
/// bake's record as JSON). Deterministic: equal inputs give equal bytes.
pub fn cloud_file(
    positions: &[Vec3],
    sh: &[ShRgb],
    validity: &[FileValidity],
    codec: Codec,
    metadata: &str,
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
    file.probe_set_mut().coefficients = coefficients;
    file.cloud_mut().tetrahedra = Some(tet_section(positions, &t.tets, &t.neighbors));
    file.probe_set_mut().validity = Some(validity.to_vec());
    *file.metadata_mut() = metadata.to_string();
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
    file.groups()
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
    cloud_file(positions, sh, &validity, Codec::F32, "").expect("test cloud")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::capture::tests::{
        assert_close, group_probe_points, mean_se, quick, red, two_group_room,
    };
    use crate::capture::{bake_points, BakeOutput, CaptureSettings};

    #[test]
    fn barycentric_matrices_reproduce_vertices() {
        let pts = crate::delaunay::bench_points::uniform(40, 3);
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

    /// A stored cloud file of a bake, with its light groups (as `bake --groups`).
    fn cloud_with_groups(out: &BakeOutput) -> ProbeFile {
        let validity: Vec<_> = out.validity.iter().map(file_validity).collect();
        let mut f =
            cloud_file(&out.captured_positions, &out.sh, &validity, Codec::F32, "").unwrap();
        f.probe_set_mut().groups =
            light_groups(&out.groups, out.settings.order, Codec::F32).unwrap();
        f
    }

    fn query_cloud(f: &ProbeFile, q: &[(Vec3, Vec3)]) -> Vec<f64> {
        let cloud = probekit_runtime::ProbeCloud::from_file(f).unwrap();
        let mut st = probekit_runtime::cloud::WalkState::new();
        q.iter()
            .flat_map(|&(p, n)| cloud.irradiance(p, n, &mut st).to_array())
            .map(f64::from)
            .collect()
    }

    /// `bake --groups`: (a) the groups sum to the total (and the
    /// indirect-only groups to the indirect light); (b) group `a` equals a bake
    /// of light `a` alone; (c) relighting the stored file at run time (group `b`
    /// × 0, and × an RGB factor) equals querying bakes of the scene with light
    /// `b` removed / recoloured by that factor; (d) the file round-trips. Each
    /// over several seeds, within 5 standard errors of the per-seed differences
    /// plus a float floor (delta light `b` draws no random numbers, so the
    /// differences are in fact at float-rounding level).
    #[test]
    fn light_groups_sum_to_the_total_and_relight_like_rebaked_scenes() {
        let (pts, queries) = group_probe_points();
        let scale = Vec3::new(2.0, 0.5, 0.0);
        let (both, only_a, recoloured) = (
            two_group_room(Vec3::ONE),
            two_group_room(Vec3::ZERO),
            two_group_room(scale),
        );
        let mut d_group = Vec::new();
        let mut d_zero = Vec::new();
        let mut d_scaled = Vec::new();
        let mut magnitude = 0.0f64;
        for seed in 1..=4 {
            let s = CaptureSettings {
                groups: true,
                split_direct: true,
                ..quick(256, 2, 3, seed)
            };
            let out = bake_points(&both, &pts, &s, &|_, _| {}).unwrap();
            let names: Vec<&str> = out.groups.iter().map(|g| g.0.as_str()).collect();
            assert_eq!(names, ["a", "b"]);
            // (a) Σ groups = total, Σ indirect groups = indirect, per coefficient.
            for i in 0..pts.len() {
                let ind = &out.indirect.as_ref().unwrap()[i];
                for k in 0..9 {
                    let total = out.sh[i].coeffs()[k];
                    let sum = out.groups[0].1[i].coeffs()[k] + out.groups[1].1[i].coeffs()[k];
                    assert!(
                        (sum - total).abs().max_element()
                            <= 1e-5 * (1.0 + total.abs().max_element())
                    );
                    let isum = out.groups_indirect[0].1[i].coeffs()[k]
                        + out.groups_indirect[1].1[i].coeffs()[k];
                    let want = ind.coeffs()[k];
                    assert!(
                        (isum - want).abs().max_element()
                            <= 1e-5 * (1.0 + want.abs().max_element())
                    );
                }
            }
            // (b) group a vs the bake of light a alone.
            let alone = bake_points(&only_a, &pts, &s, &|_, _| {}).unwrap();
            d_group.push(
                out.groups[0]
                    .1
                    .iter()
                    .zip(&alone.sh)
                    .flat_map(|(g, t)| red(g).into_iter().zip(red(t)).map(|(x, y)| x - y))
                    .collect::<Vec<f64>>(),
            );
            magnitude = magnitude.max(red(&alone.sh[0])[0].abs());
            // (d) the stored file round-trips, groups included.
            let file = cloud_with_groups(&out);
            let bytes = file.to_bytes().unwrap();
            assert_eq!(ProbeFile::from_bytes(&bytes).unwrap(), file);
            // (c) run-time relighting vs rebaked scenes, through the runtime query.
            let mut zero = file.clone();
            zero.probe_set_mut().coefficients = file.relit(&[("b", Vec3::ZERO)]).unwrap();
            let mut scaled = file.clone();
            scaled.probe_set_mut().coefficients = file.relit(&[("b", scale)]).unwrap();
            let s_plain = CaptureSettings {
                ..quick(256, 2, 3, seed)
            };
            let alone_plain = bake_points(&only_a, &pts, &s_plain, &|_, _| {}).unwrap();
            let recol = bake_points(&recoloured, &pts, &s_plain, &|_, _| {}).unwrap();
            let diff = |a: Vec<f64>, b: Vec<f64>| a.iter().zip(&b).map(|(x, y)| x - y).collect();
            d_zero.push(diff(
                query_cloud(&zero, &queries),
                query_cloud(&cloud_with_groups(&alone_plain), &queries),
            ));
            d_scaled.push(diff(
                query_cloud(&scaled, &queries),
                query_cloud(&cloud_with_groups(&recol), &queries),
            ));
        }
        assert!(magnitude > 0.05, "the test scene is lit: {magnitude}");
        let zeros = |n: usize| vec![0.0; n];
        let floor = 1e-4 * magnitude.max(1.0);
        let worst = |d: &[Vec<f64>]| d.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
        eprintln!(
            "light groups: largest |difference| over seeds: group a vs a alone {:.3e}, \
             b×0 vs b removed {:.3e}, b×rgb vs b recoloured {:.3e} (DC of a alone {magnitude:.3})",
            worst(&d_group),
            worst(&d_zero),
            worst(&d_scaled)
        );
        let (m, se) = mean_se(&d_group);
        assert_close(&m, &se, &zeros(m.len()), floor, "group a vs light a alone");
        let (m, se) = mean_se(&d_zero);
        assert_close(&m, &se, &zeros(m.len()), floor, "b × 0 vs light b removed");
        let (m, se) = mean_se(&d_scaled);
        assert_close(
            &m,
            &se,
            &zeros(m.len()),
            floor,
            "b × rgb vs light b recoloured",
        );
    }
}
