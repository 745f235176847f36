//! Invariants of a [`ProbeFile`] that span sections: counts agree, indices
//! stay in range, topology is consistent, floats are finite, and the kind's
//! required sections are present. Shared by the reader (after parsing) and
//! the writer (before writing). Linear time, no allocation beyond one
//! `bool` per octree node.

use super::codec::check_finite;
use super::error::FormatError;
use super::layout::{SectionId, NONE};
use super::{CloudBlend, CloudFile, ProbeFile, ProbeSet, Rig, VolumeFile};
use crate::prelude::*;
use glam::Vec3;

fn non_finite(id: SectionId, element: usize) -> FormatError {
    FormatError::NonFinite {
        id,
        element: element as u64,
    }
}

fn out_of_range(id: SectionId, element: usize, value: u32, limit: usize) -> FormatError {
    FormatError::IndexOutOfRange {
        id,
        element: element as u64,
        value: value as u64,
        limit: limit as u64,
    }
}

fn topology(id: SectionId, element: usize, reason: &'static str) -> FormatError {
    FormatError::InvalidTopology {
        id,
        element: element as u64,
        reason,
    }
}

fn count_mismatch(id: SectionId, expected: usize, actual: usize) -> FormatError {
    FormatError::CountMismatch {
        id,
        expected: expected as u64,
        actual: actual as u64,
    }
}

fn check_box(id: SectionId, element: usize, min: Vec3, max: Vec3) -> Result<(), FormatError> {
    if !min.is_finite() || !max.is_finite() {
        return Err(non_finite(id, element));
    }
    if min.cmpgt(max).any() {
        return Err(FormatError::InvalidValue {
            id,
            element: element as u64,
            reason: "box minimum exceeds maximum",
        });
    }
    Ok(())
}

fn distinct<const N: usize>(v: &[u32; N]) -> bool {
    (0..N).all(|i| (i + 1..N).all(|j| v[i] != v[j]))
}

pub(super) fn validate(f: &ProbeFile) -> Result<(), FormatError> {
    match f {
        ProbeFile::Cloud(c) => {
            validate_probes(&c.probes)?;
            validate_cloud(c)?;
            validate_rigs(&c.rigs)
        }
        ProbeFile::Volume(v) => {
            validate_probes(&v.probes)?;
            validate_volume(v)?;
            validate_rigs(&v.rigs)
        }
        ProbeFile::Rigs(r) => {
            if r.rigs.is_empty() {
                return Err(FormatError::MissingSection(SectionId::RIGS));
            }
            validate_rigs(&r.rigs)
        }
    }
}

/// Positions, coefficients, validity and light groups.
fn validate_probes(p: &ProbeSet) -> Result<(), FormatError> {
    let probes = p.positions.len();
    if u32::try_from(probes).is_err() {
        return Err(FormatError::Unrepresentable("more than u32::MAX probes"));
    }
    for (i, p) in p.positions.iter().enumerate() {
        if !p.is_finite() {
            return Err(non_finite(SectionId::POSITIONS, i));
        }
    }

    // Coefficients.
    let c = &p.coefficients;
    let stride = c
        .codec
        .stride(c.order)
        .ok_or(FormatError::CodecOrderMismatch {
            codec: c.codec.name(),
            order: c.order,
            stride: 0,
        })?;
    if c.data.len() % stride != 0 {
        return Err(FormatError::SectionSize {
            id: SectionId::COEFFICIENTS,
            expected: (c.data.len() / stride * stride) as u64,
            actual: c.data.len() as u64,
        });
    }
    if c.len() != probes {
        return Err(count_mismatch(SectionId::COEFFICIENTS, probes, c.len()));
    }
    check_finite(c)?;
    if p.l1_mode != super::L1Mode::Linear && c.order != 2 {
        return Err(FormatError::InvalidValue {
            id: SectionId::COEFFICIENTS,
            element: 0,
            reason: "an L1 evaluation other than linear needs order-2 (L1) coefficients",
        });
    }

    if let Some(v) = &p.validity {
        if v.len() != probes {
            return Err(count_mismatch(SectionId::VALIDITY, probes, v.len()));
        }
        if let Some(i) = v.iter().position(|v| !v.value.is_finite()) {
            return Err(non_finite(SectionId::VALIDITY, i));
        }
    }

    if let Some(l) = &p.runtime_lights {
        l.validate(probes)?;
    }

    // Light groups: one SH per probe each, at the coefficients' order.
    for (k, g) in p.groups.iter().enumerate() {
        let id = SectionId::LIGHT_GROUPS;
        let bad = |reason| FormatError::InvalidValue {
            id,
            element: k as u64,
            reason,
        };
        if g.name.is_empty() {
            return Err(bad("light group without a name"));
        }
        if u32::try_from(g.name.len()).is_err() {
            return Err(FormatError::Unrepresentable(
                "light group name longer than u32::MAX bytes",
            ));
        }
        if p.groups[..k].iter().any(|h| h.name == g.name) {
            return Err(bad("two light groups share a name"));
        }
        let gc = &g.coefficients;
        let stride = gc
            .codec
            .stride(gc.order)
            .ok_or(FormatError::CodecOrderMismatch {
                codec: gc.codec.name(),
                order: gc.order,
                stride: 0,
            })?;
        if gc.order != c.order {
            return Err(bad("light group SH order differs from the coefficients'"));
        }
        if gc.data.len() % stride != 0 || gc.len() != probes {
            return Err(count_mismatch(id, probes, gc.data.len() / stride));
        }
        check_finite(gc).map_err(|e| match e {
            FormatError::NonFinite { .. } => non_finite(id, k),
            e => e,
        })?;
    }

    Ok(())
}

/// Tetrahedra, outer cells and blend data.
fn validate_cloud(c: &CloudFile) -> Result<(), FormatError> {
    let probes = c.probes.positions.len();
    // Tetrahedra.
    let tets = c.tetrahedra.as_ref().map_or(0, |t| t.vertices.len());
    if let Some(t) = &c.tetrahedra {
        let id = SectionId::TETRAHEDRA;
        if t.neighbours.len() != tets || t.barycentric.len() != tets {
            return Err(count_mismatch(
                id,
                tets,
                t.neighbours.len().min(t.barycentric.len()),
            ));
        }
        for (k, v) in t.vertices.iter().enumerate() {
            if let Some(&bad) = v.iter().find(|&&i| i as usize >= probes) {
                return Err(out_of_range(id, k, bad, probes));
            }
            if !distinct(v) {
                return Err(topology(id, k, "tetrahedron repeats a vertex"));
            }
        }
        for (k, n) in t.neighbours.iter().enumerate() {
            for &m in n {
                if m == NONE {
                    continue;
                }
                if m as usize >= tets {
                    return Err(out_of_range(id, k, m, tets));
                }
                if m as usize == k {
                    return Err(topology(id, k, "tetrahedron is its own neighbour"));
                }
                if !t.neighbours[m as usize].contains(&(k as u32)) {
                    return Err(topology(id, k, "neighbour relation is not symmetric"));
                }
            }
        }
        for (k, m) in t.barycentric.iter().enumerate() {
            if !m.iter().flatten().all(|x| x.is_finite()) {
                return Err(non_finite(id, k));
            }
        }
    }

    // Outer cells.
    if let Some(o) = &c.outer {
        let id = SectionId::OUTER;
        let faces = o.vertices.len();
        if o.adjacent.len() != faces || o.planes.len() != faces || o.tetrahedra.len() != faces {
            return Err(count_mismatch(
                id,
                faces,
                o.adjacent.len().min(o.planes.len()).min(o.tetrahedra.len()),
            ));
        }
        for k in 0..faces {
            let v = &o.vertices[k];
            if let Some(&bad) = v.iter().find(|&&i| i as usize >= probes) {
                return Err(out_of_range(id, k, bad, probes));
            }
            if !distinct(v) {
                return Err(topology(id, k, "hull face repeats a vertex"));
            }
            for &a in &o.adjacent[k] {
                if a as usize >= faces {
                    return Err(out_of_range(id, k, a, faces));
                }
                if a as usize == k {
                    return Err(topology(id, k, "hull face is adjacent to itself"));
                }
            }
            let t = o.tetrahedra[k];
            if t != NONE && t as usize >= tets {
                return Err(out_of_range(id, k, t, tets));
            }
            if !o.planes[k].iter().all(|x| x.is_finite()) {
                return Err(non_finite(id, k));
            }
        }
    }

    validate_blend(c, &c.blend, probes)
}

/// Distance moments, cell visibility, probe weights and occluder planes.
fn validate_blend(c: &CloudFile, b: &CloudBlend, probes: usize) -> Result<(), FormatError> {
    // Distance moments: one octahedral map per probe.
    if let Some(v) = &b.distance_moments {
        v.validate(probes)?;
    }

    // Cell visibility: one cell per tetrahedron (hull faces are
    // counted against the mesh when a `ProbeCloud` is built).
    if let Some(cells) = &b.cell_visibility {
        let id = SectionId::CELL_VISIBILITY;
        let tets = c
            .tetrahedra
            .as_ref()
            .ok_or(FormatError::MissingSection(SectionId::TETRAHEDRA))?;
        if cells.tet_count() != tets.vertices.len() {
            return Err(count_mismatch(id, tets.vertices.len(), cells.tet_count()));
        }
        if let Some(k) = cells.first_noncanonical() {
            return Err(FormatError::InvalidValue {
                id,
                element: k as u64,
                reason: "cell visibility: a record with padding bits set, a stored record that is clear, or mask padding bits set",
            });
        }
    }

    // Fitted probe weights: one per probe of a cloud, each in range.
    if let Some(w) = &b.probe_weights {
        let id = SectionId::PROBE_WEIGHTS;
        if w.len() != probes {
            return Err(count_mismatch(id, probes, w.len()));
        }
        if let Some(k) = w
            .iter()
            .position(|x| !crate::cloud::PROBE_WEIGHT_RANGE.contains(x))
        {
            return Err(FormatError::InvalidValue {
                id,
                element: k as u64,
                reason: "probe weight outside 1e-6..=1e6 or not a number",
            });
        }
    }
    // Brightness exponent: in range, and only beside probe weights
    // (it is stored in their header).
    if !(0.0..=crate::cloud::MAX_BRIGHTNESS_EXPONENT).contains(&b.brightness_exponent) {
        return Err(FormatError::InvalidValue {
            id: SectionId::PROBE_WEIGHTS,
            element: 0,
            reason: "brightness exponent (header word w1) outside 0..=4 or not a number",
        });
    }
    if b.brightness_exponent != 0.0 && b.probe_weights.is_none() {
        return Err(FormatError::Unrepresentable(
            "a brightness exponent is stored with probe weights (PWGT) only",
        ));
    }
    // Directional brightness exponent: the same rules, header word w2.
    if !(0.0..=crate::cloud::MAX_BRIGHTNESS_EXPONENT).contains(&b.directional_exponent) {
        return Err(FormatError::InvalidValue {
            id: SectionId::PROBE_WEIGHTS,
            element: 0,
            reason:
                "directional brightness exponent (header word w2) outside 0..=4 or not a number",
        });
    }
    if b.directional_exponent != 0.0 && b.probe_weights.is_none() {
        return Err(FormatError::Unrepresentable(
            "a directional brightness exponent is stored with probe weights (PWGT) only",
        ));
    }

    // Occluder planes: a cloud's, refining its cell visibility, one
    // lookup entry per tetrahedron (the planes themselves are checked by
    // `CellPlanes::new`).
    if let Some(planes) = &b.cell_planes {
        check_cell_planes_context(c, planes.tet_count())?;
    }

    Ok(())
}

/// Octree or grid, and gradients.
fn validate_volume(v: &VolumeFile) -> Result<(), FormatError> {
    let probes = v.probes.positions.len();
    // Octree.
    if let Some(o) = v.octree() {
        let id = SectionId::OCTREE;
        let n = o.nodes.len();
        if n == 0 {
            return Err(FormatError::InvalidValue {
                id,
                element: 0,
                reason: "octree without a root node",
            });
        }
        let roots = o.root_count();
        if o.roots.contains(&0) || roots > n {
            return Err(FormatError::InvalidValue {
                id,
                element: 0,
                reason: "octree root grid empty or larger than the node count",
            });
        }
        let mut has_parent = vec![false; n];
        for (k, node) in o.nodes.iter().enumerate() {
            check_box(id, k, node.min, node.max)?;
            if node.first_child != NONE {
                let c = node.first_child as usize;
                // Children after their parent: the tree is acyclic by construction.
                if c <= k || c.checked_add(8).map_or(true, |e| e > n) {
                    return Err(out_of_range(id, k, node.first_child, n));
                }
                for p in &mut has_parent[c..c + 8] {
                    if *p {
                        return Err(topology(id, k, "octree node has two parents"));
                    }
                    *p = true;
                }
            }
            let start = node.sample_offset as usize;
            let end = start.checked_add(node.sample_count as usize);
            let list =
                end.and_then(|e| o.samples.get(start..e))
                    .ok_or(FormatError::IndexOutOfRange {
                        id,
                        element: k as u64,
                        value: node.sample_offset as u64 + node.sample_count as u64,
                        limit: o.samples.len() as u64,
                    })?;
            if let Some(&bad) = list.iter().find(|&&s| s as usize >= probes) {
                return Err(out_of_range(id, k, bad, probes));
            }
            if node.first_child == NONE && list.len() < 8 {
                return Err(topology(
                    id,
                    k,
                    "octree leaf lists fewer than 8 corner samples",
                ));
            }
        }
        if let Some(k) = has_parent[..roots].iter().position(|p| *p) {
            return Err(topology(id, k, "octree root node has a parent"));
        }
        if let Some(k) = has_parent.iter().skip(roots).position(|p| !p) {
            return Err(topology(
                id,
                k + roots,
                "octree node unreachable from the root",
            ));
        }
    }

    // Grid.
    if let Some(g) = v.grid() {
        let id = SectionId::GRID;
        check_box(id, 0, g.min, g.max)?;
        if g.resolution.contains(&0) {
            return Err(FormatError::InvalidValue {
                id,
                element: 0,
                reason: "grid resolution has a zero axis",
            });
        }
        let total = g
            .resolution
            .iter()
            .try_fold(1u64, |a, &r| a.checked_mul(r as u64));
        if total != Some(probes as u64) {
            return Err(FormatError::CountMismatch {
                id,
                expected: probes as u64,
                actual: total.unwrap_or(u64::MAX),
            });
        }
    }

    if let Some(g) = &v.gradients {
        let id = SectionId::GRADIENTS;
        if g.order == 0 || g.order as usize > probekit_sh::MAX_ORDER {
            return Err(FormatError::InvalidValue {
                id,
                element: 0,
                reason: "gradient SH order outside 1..=8",
            });
        }
        let per = 3 * (g.order * g.order) as usize;
        if g.data.len() % per != 0 || g.data.len() / per != probes {
            return Err(count_mismatch(id, probes, g.data.len() / per));
        }
        if let Some(i) = g.data.iter().position(|v| !v.is_finite()) {
            return Err(non_finite(id, i / per));
        }
    }

    Ok(())
}

/// Every rig's model, counts and values.
fn validate_rigs(rigs: &[Rig]) -> Result<(), FormatError> {
    for (r, rig) in rigs.iter().enumerate() {
        let id = SectionId::RIGS;
        let bad = |reason| FormatError::InvalidValue {
            id,
            element: r as u64,
            reason,
        };
        if rig.order == 0 || rig.order as usize > probekit_sh::MAX_ORDER {
            return Err(bad("rig SH order outside 1..=8"));
        }
        let params = rig
            .model
            .parameter_count()
            .ok_or(bad("rig parameter count overflows"))?;
        if let super::RigModel::Tensor(axes) = rig.model {
            if axes.contains(&super::AxisModel::Lattice(0)) {
                return Err(bad("rig lattice with zero samples"));
            }
        }
        if u32::try_from(rig.samples.len()).is_err()
            || u32::try_from(rig.transitions.len()).is_err()
            || u32::try_from(rig.name.len()).is_err()
        {
            return Err(FormatError::Unrepresentable(
                "rig arrays longer than u32::MAX",
            ));
        }
        if Some(rig.fitting.len()) != (params as usize).checked_mul(rig.samples.len()) {
            return Err(bad("rig fitting matrix is not parameters × samples"));
        }
        check_box(id, r, rig.bbox_min, rig.bbox_max)?;
        if !(rig.bounding_radius.is_finite() && rig.bounding_radius >= 0.0) {
            return Err(bad("rig bounding radius is negative or not finite"));
        }
        if !rig.samples.iter().all(|p| p.is_finite())
            || !rig.fitting.iter().all(|x| x.is_finite())
            || !rig
                .transitions
                .iter()
                .all(|t| t.distance.is_finite() && t.error.is_finite())
        {
            return Err(non_finite(id, r));
        }
        if rig
            .transitions
            .windows(2)
            .any(|w| w[0].distance >= w[1].distance)
        {
            return Err(bad(
                "rig transition table not sorted by increasing distance",
            ));
        }
    }

    Ok(())
}

/// Whether occluder planes (`CPLN`) for a mesh of `tet_count`
/// tetrahedra may stand in cloud `c`: it has cell visibility, which the planes refine (`MissingSection`
/// naming `CVSP` otherwise), and `tet_count` equals the number of
/// tetrahedra in `TETS` (`MissingSection`, `CountMismatch`). Shared by
/// [`validate`] and the reader, which checks it before building a
/// [`crate::cloud::CellPlanes`] (its lookup table has `tet_count` entries,
/// so an unchecked count would allocate at an attacker's word).
pub(super) fn check_cell_planes_context(
    c: &CloudFile,
    tet_count: usize,
) -> Result<(), FormatError> {
    let id = SectionId::CELL_PLANES;
    if c.blend.cell_visibility.is_none() {
        return Err(FormatError::MissingSection(SectionId::CELL_VISIBILITY));
    }
    let tets = c
        .tetrahedra
        .as_ref()
        .ok_or(FormatError::MissingSection(SectionId::TETRAHEDRA))?;
    if tet_count != tets.vertices.len() {
        return Err(count_mismatch(id, tets.vertices.len(), tet_count));
    }
    Ok(())
}
