//! Serialization: the exact inverse of the reader. Deterministic — the
//! bytes depend only on the [`ProbeFile`]'s contents (fixed section order,
//! zero padding, no timestamps), so two bakes with equal content are
//! byte-identical and shards can be compared with `cmp`.
//!
//! File IO (temporary file, fsync, rename) lives in the baking library's
//! `probekit::format::write_probe_file`; this module only makes bytes, so
//! an engine-side tool can also write files.

use super::error::FormatError;
use super::layout::{
    self, entry, header, pad16, SectionId, ENTRY_LEN, HEADER_LEN, SECTION_HEADER_LEN,
    VERSION_MAJOR, VERSION_MINOR,
};
use super::{
    crc32, AxisModel, CloudBlend, CloudFile, ProbeFile, ProbeSet, Rig, RigModel, RuntimeLights,
    VolumeFile, VolumeStructure,
};
use crate::prelude::*;
use alloc::collections::BTreeMap;
use glam::Vec3;

/// Builds one section: a 16-byte header of four `u32`, then arrays each
/// zero-padded to a multiple of 16 bytes.
#[derive(Clone, Debug)]
pub struct SectionBuilder {
    buf: Vec<u8>,
}

impl SectionBuilder {
    /// Starts a section with its four header words.
    pub fn new(header: [u32; 4]) -> Self {
        let mut buf = Vec::new();
        for w in header {
            buf.extend_from_slice(&w.to_le_bytes());
        }
        Self { buf }
    }

    /// Appends raw bytes (no padding; call [`SectionBuilder::pad`] after an array).
    pub fn bytes(&mut self, b: &[u8]) -> &mut Self {
        self.buf.extend_from_slice(b);
        self
    }

    /// Appends little-endian `u32`s.
    pub fn u32s(&mut self, v: impl IntoIterator<Item = u32>) -> &mut Self {
        for w in v {
            self.buf.extend_from_slice(&w.to_le_bytes());
        }
        self
    }

    /// Appends little-endian `f32`s.
    pub fn f32s(&mut self, v: impl IntoIterator<Item = f32>) -> &mut Self {
        self.u32s(v.into_iter().map(f32::to_bits))
    }

    /// Appends `Vec3`s as packed `f32x3`.
    pub fn vec3s<'a>(&mut self, v: impl IntoIterator<Item = &'a Vec3>) -> &mut Self {
        self.f32s(v.into_iter().flat_map(|p| p.to_array()))
    }

    /// Zero-pads to a multiple of 16 bytes (ends an array).
    pub fn pad(&mut self) -> &mut Self {
        let target = pad16(self.buf.len()).unwrap_or(self.buf.len());
        self.buf.resize(target, 0);
        self
    }

    /// The finished section (padded).
    pub fn finish(mut self) -> Vec<u8> {
        self.pad();
        self.buf
    }
}

/// Lays out a file from finished sections, in the order given: header,
/// table, then the sections back to back (each already a multiple of 16
/// bytes, so each starts 16-aligned). Low level: no validation of section
/// contents; for tools and tests that craft files (e.g. a newer `minor`).
pub fn assemble_file(
    kind: u32,
    minor: u16,
    flags: u32,
    sections: &[(SectionId, Vec<u8>)],
) -> Vec<u8> {
    let table_end = HEADER_LEN + sections.len() * ENTRY_LEN;
    let total: usize = table_end + sections.iter().map(|(_, b)| b.len()).sum::<usize>();
    let mut out = vec![0u8; table_end];
    out.reserve(total - table_end);
    out[header::MAGIC..header::MAGIC + 8].copy_from_slice(&layout::MAGIC);
    out[header::MAJOR..header::MAJOR + 2].copy_from_slice(&VERSION_MAJOR.to_le_bytes());
    out[header::MINOR..header::MINOR + 2].copy_from_slice(&minor.to_le_bytes());
    out[header::KIND..header::KIND + 4].copy_from_slice(&kind.to_le_bytes());
    out[header::FLAGS..header::FLAGS + 4].copy_from_slice(&flags.to_le_bytes());
    out[header::SECTION_COUNT..header::SECTION_COUNT + 4]
        .copy_from_slice(&(sections.len() as u32).to_le_bytes());
    out[header::FILE_LEN..header::FILE_LEN + 8].copy_from_slice(&(total as u64).to_le_bytes());
    let mut offset = table_end as u64;
    for (k, (id, bytes)) in sections.iter().enumerate() {
        let e = HEADER_LEN + k * ENTRY_LEN;
        out[e + entry::ID..e + entry::ID + 4].copy_from_slice(&id.0.to_le_bytes());
        out[e + entry::OFFSET..e + entry::OFFSET + 8].copy_from_slice(&offset.to_le_bytes());
        out[e + entry::LENGTH..e + entry::LENGTH + 8]
            .copy_from_slice(&(bytes.len() as u64).to_le_bytes());
        out[e + entry::CRC..e + entry::CRC + 4].copy_from_slice(&crc32(bytes).to_le_bytes());
        offset += bytes.len() as u64;
    }
    let mut crc = super::Crc32::new();
    crc.update(&out[..header::CRC]);
    crc.update(&out[HEADER_LEN..table_end]);
    let c = crc.finish();
    out[header::CRC..header::CRC + 4].copy_from_slice(&c.to_le_bytes());
    for (_, bytes) in sections {
        out.extend_from_slice(bytes);
    }
    out
}

fn count(n: usize, what: &'static str) -> Result<u32, FormatError> {
    u32::try_from(n).map_err(|_| FormatError::Unrepresentable(what))
}

fn axis_words(a: AxisModel) -> (u32, u32) {
    match a {
        AxisModel::Constant => (0, 1),
        AxisModel::Gradient => (1, 2),
        AxisModel::Lattice(n) => (2, n),
    }
}

/// Encodes every present section of `f`, in the writer's fixed order.
pub(super) fn encode_sections(f: &ProbeFile) -> Result<Vec<(SectionId, Vec<u8>)>, FormatError> {
    let mut out = Vec::new();
    let (cloud, volume) = (f.as_cloud(), f.as_volume());
    if let Some(p) = f.probes() {
        encode_probes(p, &mut out)?;
    }
    if let Some(c) = cloud {
        encode_mesh(c, &mut out)?;
    }
    if let Some(v) = volume {
        encode_volume(v, &mut out)?;
    }
    if !f.rigs().is_empty() {
        out.push((SectionId::RIGS, encode_rigs(f.rigs())?));
    }
    if let Some(p) = f.probes().filter(|p| !p.groups.is_empty()) {
        out.push((SectionId::LIGHT_GROUPS, encode_groups(p)?));
    }
    if let Some(l) = f.probes().and_then(|p| p.runtime_lights.as_ref()) {
        encode_runtime_lights(l, &mut out)?;
    }
    if let Some(c) = cloud {
        encode_blend(&c.blend, &mut out)?;
    }
    let metadata = f.metadata();
    let mut s = SectionBuilder::new([count(metadata.len(), "metadata")?, 0, 0, 0]);
    s.bytes(metadata.as_bytes());
    out.push((SectionId::METADATA, s.finish()));

    debug_assert!(out
        .iter()
        .all(|(_, b)| b.len() % 16 == 0 && b.len() >= SECTION_HEADER_LEN));
    Ok(out)
}

type Sections = Vec<(SectionId, Vec<u8>)>;

/// `POSN`, `COEF` and `VALD`.
fn encode_probes(p: &ProbeSet, out: &mut Sections) -> Result<(), FormatError> {
    let probes = count(p.positions.len(), "more than u32::MAX probes")?;
    let mut s = SectionBuilder::new([probes, 0, 0, 0]);
    s.vec3s(&p.positions);
    out.push((SectionId::POSITIONS, s.finish()));

    let c = &p.coefficients;
    let stride = c.stride();
    let mut s = SectionBuilder::new([
        c.codec.id(),
        c.order,
        count(c.len(), "more than u32::MAX probes")?,
        stride as u32,
    ]);
    s.bytes(&c.data);
    out.push((SectionId::COEFFICIENTS, s.finish()));

    if let Some(v) = &p.validity {
        let mut s = SectionBuilder::new([count(v.len(), "validity")?, 0, 0, 0]);
        s.u32s(v.iter().flat_map(|v| [v.value.to_bits(), v.flags]));
        out.push((SectionId::VALIDITY, s.finish()));
    }
    Ok(())
}

/// `TETS` and `OUTR`.
fn encode_mesh(c: &CloudFile, out: &mut Sections) -> Result<(), FormatError> {
    if let Some(t) = &c.tetrahedra {
        let mut s = SectionBuilder::new([count(t.vertices.len(), "tetrahedra")?, 0, 0, 0]);
        s.u32s(t.vertices.iter().flatten().copied()).pad();
        s.u32s(t.neighbours.iter().flatten().copied()).pad();
        s.f32s(t.barycentric.iter().flatten().flatten().copied());
        out.push((SectionId::TETRAHEDRA, s.finish()));
    }
    if let Some(o) = &c.outer {
        let mut s = SectionBuilder::new([count(o.vertices.len(), "hull faces")?, 0, 0, 0]);
        s.u32s(o.vertices.iter().flatten().copied()).pad();
        s.u32s(o.adjacent.iter().flatten().copied()).pad();
        s.f32s(o.planes.iter().flatten().copied()).pad();
        s.u32s(o.tetrahedra.iter().copied());
        out.push((SectionId::OUTER, s.finish()));
    }
    Ok(())
}

/// `OCTC` or `GRID`, and `GRAD`.
fn encode_volume(v: &VolumeFile, out: &mut Sections) -> Result<(), FormatError> {
    match &v.structure {
        VolumeStructure::Adaptive(o) => {
            // One bit per node: only a regular octree (every one the volume
            // builder makes) has this encoding.
            let c = super::octree_compact::encode(o, &v.probes.positions).ok_or(
                FormatError::Unrepresentable(
                    "an octree that is not regular (breadth-first, octant children on the root lattice, leaves listing exactly their 8 corner probes)",
                ),
            )?;
            let [w2, w3] = roots_words(c.roots)?;
            let mut s = SectionBuilder::new([c.nodes, c.max_depth, w2, w3]);
            s.vec3s([&c.min, &c.max]).pad();
            s.bytes(&c.bits);
            out.push((SectionId::OCTREE, s.finish()));
        }
        VolumeStructure::Uniform(g) => {
            let [rx, ry, rz] = g.resolution;
            let mut s = SectionBuilder::new([rx, ry, rz, 0]);
            s.vec3s([&g.min, &g.max]);
            out.push((SectionId::GRID, s.finish()));
        }
    }
    if let Some(g) = &v.gradients {
        let per = 3 * (g.order * g.order) as usize;
        let n = g.data.len().checked_div(per).unwrap_or(0);
        let mut s = SectionBuilder::new([g.order, count(n, "gradients")?, 0, 0]);
        s.vec3s(&g.data);
        out.push((SectionId::GRADIENTS, s.finish()));
    }
    Ok(())
}

/// `RIGS`.
fn encode_rigs(rigs: &[Rig]) -> Result<Vec<u8>, FormatError> {
    let mut s = SectionBuilder::new([count(rigs.len(), "rigs")?, 0, 0, 0]);
    for r in rigs {
        let (kind, axes) = match r.model {
            RigModel::Constant => (0, [AxisModel::Constant; 3]),
            RigModel::Gradient => (1, [AxisModel::Constant; 3]),
            RigModel::Tensor(a) => (2, a),
        };
        let w = axes.map(axis_words);
        let (models, counts) = if kind == 2 {
            ([w[0].0, w[1].0, w[2].0], [w[0].1, w[1].1, w[2].1])
        } else {
            ([0; 3], [1; 3])
        };
        let params = r
            .model
            .parameter_count()
            .ok_or(FormatError::Unrepresentable("rig parameter count"))?;
        s.u32s([kind]).u32s(models).u32s(counts).u32s([
            r.order,
            count(r.samples.len(), "rig samples")?,
            params,
            count(r.transitions.len(), "rig transitions")?,
            count(r.name.len(), "rig name")?,
        ]);
        s.vec3s([&r.bbox_min, &r.bbox_max])
            .u32s([r.bounding_radius.to_bits(), 0]);
        s.bytes(r.name.as_bytes()).pad();
        s.vec3s(&r.samples).pad();
        s.f32s(r.fitting.iter().copied()).pad();
        s.f32s(r.transitions.iter().flat_map(|t| [t.distance, t.error]))
            .pad();
    }
    Ok(s.finish())
}

/// `LGRP`.
fn encode_groups(p: &ProbeSet) -> Result<Vec<u8>, FormatError> {
    let probes = count(p.positions.len(), "more than u32::MAX probes")?;
    let mut s = SectionBuilder::new([count(p.groups.len(), "light groups")?, probes, 0, 0]);
    for g in &p.groups {
        let c = &g.coefficients;
        s.u32s([
            c.codec.id(),
            c.order,
            c.stride() as u32,
            count(g.name.len(), "light group name")?,
        ]);
        s.bytes(g.name.as_bytes()).pad();
        s.bytes(&c.data).pad();
    }
    Ok(s.finish())
}

/// `LITE` and `OCCL`.
fn encode_runtime_lights(l: &RuntimeLights, out: &mut Sections) -> Result<(), FormatError> {
    let mut s = SectionBuilder::new([count(l.lights.len(), "run-time lights")?, 0, 0, 0]);
    for r in &l.lights {
        let (kind, words) = super::lights::light_words(&r.light);
        s.u32s([kind, count(r.group.len(), "light group name")?]);
        // -0.0 is written as 0.0 (equal contents, equal bytes).
        s.f32s(words.iter().map(|w| *w + 0.0)).u32s([0]);
    }
    for r in &l.lights {
        s.bytes(r.group.as_bytes());
    }
    s.pad();
    out.push((SectionId::RUNTIME_LIGHTS, s.finish()));
    let o = &l.occlusion;
    let mut s = SectionBuilder::new([
        count(o.probe_count(), "more than u32::MAX probes")?,
        count(l.lights.len(), "run-time lights")?,
        count(o.entries().len(), "occlusion entries")?,
        0,
    ]);
    s.bytes(o.counts()).pad();
    s.bytes(bytemuck::cast_slice(o.entries())).pad();
    out.push((SectionId::LIGHT_OCCLUSION, s.finish()));
    Ok(())
}

/// `VISM`, `CVSP`, `PWGT` and `CPLN`.
fn encode_blend(b: &CloudBlend, out: &mut Sections) -> Result<(), FormatError> {
    if let Some(v) = &b.distance_moments {
        let mut s = SectionBuilder::new([
            count(v.probe_count(), "visibility maps")?,
            v.resolution,
            v.max_distance.to_bits(),
            0,
        ]);
        for h in &v.data {
            s.bytes(&h.to_le_bytes());
        }
        out.push((SectionId::VISIBILITY, s.finish()));
    }
    if let Some(c) = &b.cell_visibility {
        let mut s = SectionBuilder::new([
            count(c.tet_count(), "cell visibility tetrahedra")?,
            count(c.hull_face_count(), "cell visibility hull faces")?,
            c.subdivision(),
            0,
        ]);
        s.bytes(c.mask()).pad().bytes(c.records());
        out.push((SectionId::CELL_VISIBILITY, s.finish()));
    }
    if let Some(w) = &b.probe_weights {
        // -0.0 is written as 0.0 (equal contents, equal bytes).
        let alpha = (b.brightness_exponent + 0.0).to_bits();
        let beta = (b.directional_exponent + 0.0).to_bits();
        let mut s = SectionBuilder::new([count(w.len(), "probe weights")?, alpha, beta, 0]);
        for x in w {
            s.bytes(&x.to_le_bytes());
        }
        out.push((SectionId::PROBE_WEIGHTS, s.finish()));
    }
    if let Some(p) = &b.cell_planes {
        let mut s = SectionBuilder::new([
            count(p.tet_count(), "cell plane tetrahedra")?,
            count(p.len(), "cell planes")?,
            0,
            0,
        ]);
        s.u32s(p.tets().iter().copied()).pad();
        s.f32s(p.planes().iter().flatten().copied());
        out.push((SectionId::CELL_PLANES, s.finish()));
    }
    Ok(())
}

/// Header words `w2`, `w3` of `OCTC` for a root grid.
fn roots_words(r: [u32; 3]) -> Result<[u32; 2], FormatError> {
    layout::pack_roots(r).ok_or(FormatError::InvalidValue {
        id: SectionId::OCTREE,
        element: 0,
        reason: "octree root grid axis outside 1..=65536",
    })
}

impl ProbeFile {
    /// Serializes the file (after [`ProbeFile::validate`]) as format
    /// [`VERSION_MAJOR`].[`VERSION_MINOR`]. Deterministic: equal contents
    /// give equal bytes. Refuses ([`FormatError::Unrepresentable`]) an
    /// octree that is not regular, which the compact `OCTC` encoding
    /// cannot hold.
    pub fn to_bytes(&self) -> Result<Vec<u8>, FormatError> {
        self.validate()?;
        let sections = encode_sections(self)?;
        Ok(assemble_file(
            self.kind().id(),
            VERSION_MINOR,
            self.l1_mode().flags(),
            &sections,
        ))
    }

    /// Bytes each section takes when written, keyed by section name, plus
    /// `"header"` (header and table). Sums to `to_bytes()?.len()`.
    pub fn bytes_by_section(&self) -> Result<BTreeMap<String, u64>, FormatError> {
        self.validate()?;
        let sections = encode_sections(self)?;
        let mut map = BTreeMap::new();
        map.insert(
            "header".to_string(),
            (HEADER_LEN + sections.len() * ENTRY_LEN) as u64,
        );
        for (id, b) in &sections {
            map.insert(id.to_string(), b.len() as u64);
        }
        Ok(map)
    }
}
