//! [`ProbeFile`]: what a `.probes` file holds, one kind of contents each —
//! a probe cloud ([`CloudFile`]), an irradiance volume ([`VolumeFile`]) or
//! irradiance rigs alone ([`RigFile`]) — so each kind carries exactly the
//! data it has.
//!
//! Clouds and volumes share their probes ([`ProbeSet`]: positions, radiance
//! SH and how L1 SH is evaluated, validity, light groups); every kind may
//! carry irradiance rigs and carries its bake metadata. A cloud's optional
//! blend data (distance moments, cell visibility and occluder planes,
//! fitted probe weights and their brightness exponents) is one
//! [`CloudBlend`].

use super::{
    Coefficients, FormatError, Gradients, L1Mode, LightGroup, Octree, OuterCells, ProbeFileKind,
    Rig, RuntimeLights, TetSection, Validity, VolumeGrid,
};
use crate::cloud::{CellPlanes, CellVisibility};
use crate::format::DistanceMoments;
use crate::prelude::*;
use glam::Vec3;

/// The probes of a cloud or a volume: where they are and the light they
/// captured.
#[derive(Clone, Debug, PartialEq)]
pub struct ProbeSet {
    /// Probe (or volume sample) positions, metres, world space.
    pub positions: Vec<Vec3>,
    /// Radiance SH per probe, one per position.
    pub coefficients: Coefficients,
    /// How the coefficients are meant to be evaluated when they are L1
    /// (order 2), stored in the header's flags
    /// ([`super::layout::FLAGS_L1_MODE`]). Anything but `Linear` needs
    /// order-2 coefficients.
    pub l1_mode: L1Mode,
    /// Capture validity per probe (`VALD`; `None`: no section).
    pub validity: Option<Vec<Validity>>,
    /// Radiance SH per light group, for run-time relighting (empty: no
    /// `LGRP` section). Each holds one entry per probe, in the order of
    /// `positions`, at the order of `coefficients`; names unique. See
    /// [`ProbeFile::relit`] and [`super::Relighter`].
    pub groups: Vec<LightGroup>,
    /// Lights an engine evaluates at run time, whose direct light the SH
    /// leaves out, and each probe's occlusion of them (`LITE` and `OCCL`;
    /// `None`: every light is in the SH). See [`super::RuntimeLights`].
    pub runtime_lights: Option<RuntimeLights>,
}

impl ProbeSet {
    /// `positions` with `coefficients` (one per position), evaluated
    /// linearly, without validity or light groups.
    pub fn new(positions: Vec<Vec3>, coefficients: Coefficients) -> Self {
        Self {
            positions,
            coefficients,
            l1_mode: L1Mode::Linear,
            validity: None,
            groups: Vec::new(),
            runtime_lights: None,
        }
    }
}

/// A cloud's optional blend data: what weights each probe of the enclosing
/// cell beyond its barycentric coordinate. [`Default`] is none of it (the
/// plain barycentric blend).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CloudBlend {
    /// Per-probe distance moments for visibility-aware blending (`VISM`;
    /// `None`: no section).
    pub distance_moments: Option<DistanceMoments>,
    /// Per-cell lattice visibility bits of the tetrahedra and hull faces
    /// (`CVSP`; `None`: no section).
    pub cell_visibility: Option<CellVisibility>,
    /// Occluder planes of tetrahedra (`CPLN`), a refinement of
    /// `cell_visibility` for cells one flat wall cuts; only with
    /// `cell_visibility`. See [`crate::cloud::CellPlanes`].
    pub cell_planes: Option<CellPlanes>,
    /// Fitted per-probe blend weights (`PWGT`; one per probe, each in
    /// [`crate::cloud::PROBE_WEIGHT_RANGE`]; `None`: every probe weighs 1).
    /// See [`crate::cloud::ProbeCloud::probe_weights`].
    pub probe_weights: Option<Vec<f32>>,
    /// Brightness exponent `α` the probe weights were fitted with and the
    /// cloud blends with ([`crate::cloud::ProbeCloud::brightness_weighting`]),
    /// stored in `PWGT`'s header word `w1` (0: the plain blend). In
    /// `0..=`[`crate::cloud::MAX_BRIGHTNESS_EXPONENT`]; non-zero only with
    /// `probe_weights`.
    pub brightness_exponent: f32,
    /// Directional brightness exponent `γ` the cloud blends with on top of
    /// the probe weights
    /// ([`crate::cloud::ProbeCloud::directional_brightness`]), stored in
    /// `PWGT`'s header word `w2` (0: no directional blend). Same range and
    /// rule as `brightness_exponent`.
    pub directional_exponent: f32,
}

/// A probe cloud: probes, usually tetrahedralized, and the data that
/// weights their blend.
#[derive(Clone, Debug, PartialEq)]
pub struct CloudFile {
    /// The probes.
    pub probes: ProbeSet,
    /// Tetrahedralization (`TETS`; `None` for a shard part of a sharded
    /// bake, which the merge tetrahedralizes).
    pub tetrahedra: Option<TetSection>,
    /// Outer cells: the hull faces outside points are extrapolated from
    /// (`OUTR`).
    pub outer: Option<OuterCells>,
    /// Optional blend data.
    pub blend: CloudBlend,
    /// Irradiance rigs carried along (empty: no `RIGS` section).
    pub rigs: Vec<Rig>,
    /// Bake metadata, UTF-8 (JSON by convention: the bake record; never a
    /// wall-clock time).
    pub metadata: String,
}

/// How a volume's samples are arranged.
#[derive(Clone, Debug, PartialEq)]
pub enum VolumeStructure {
    /// A uniform grid (`GRID`).
    Uniform(VolumeGrid),
    /// An adaptive octree, or a forest of them (`OCTC`).
    Adaptive(Octree),
}

/// An irradiance volume: samples on a uniform grid or an adaptive octree.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeFile {
    /// The samples.
    pub probes: ProbeSet,
    /// Their grid or octree.
    pub structure: VolumeStructure,
    /// Spatial SH gradients per sample (`GRAD`; `None`: no section).
    pub gradients: Option<Gradients>,
    /// Irradiance rigs carried along (empty: no `RIGS` section).
    pub rigs: Vec<Rig>,
    /// Bake metadata, UTF-8 (as [`CloudFile::metadata`]).
    pub metadata: String,
}

/// Irradiance rigs without probes.
#[derive(Clone, Debug, PartialEq)]
pub struct RigFile {
    /// The rigs (at least one).
    pub rigs: Vec<Rig>,
    /// Bake metadata, UTF-8 (as [`CloudFile::metadata`]).
    pub metadata: String,
}

/// Everything a `.probes` file holds, decoded and validated: a cloud, a
/// volume or rigs.
// One value per loaded file, never stored in bulk: the rigs variant being
// smaller than the cloud's costs nothing worth a box.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum ProbeFile {
    /// A probe cloud (kind 0).
    Cloud(CloudFile),
    /// An irradiance volume (kind 1).
    Volume(VolumeFile),
    /// Irradiance rigs alone (kind 2).
    Rigs(RigFile),
}

impl CloudFile {
    /// A cloud of `probes` with nothing else: no tetrahedra, blend data,
    /// rigs or metadata.
    pub fn new(probes: ProbeSet) -> Self {
        Self {
            probes,
            tetrahedra: None,
            outer: None,
            blend: CloudBlend::default(),
            rigs: Vec::new(),
            metadata: String::new(),
        }
    }
}

impl VolumeFile {
    /// A volume of `probes` arranged by `structure`, without gradients,
    /// rigs or metadata.
    pub fn new(probes: ProbeSet, structure: VolumeStructure) -> Self {
        Self {
            probes,
            structure,
            gradients: None,
            rigs: Vec::new(),
            metadata: String::new(),
        }
    }

    /// The octree of an adaptive volume.
    pub fn octree(&self) -> Option<&Octree> {
        match &self.structure {
            VolumeStructure::Adaptive(o) => Some(o),
            VolumeStructure::Uniform(_) => None,
        }
    }

    /// The grid of a uniform volume.
    pub fn grid(&self) -> Option<&VolumeGrid> {
        match &self.structure {
            VolumeStructure::Uniform(g) => Some(g),
            VolumeStructure::Adaptive(_) => None,
        }
    }
}

impl ProbeFile {
    /// A cloud of `positions` with lossless `f32` coefficients of SH
    /// `order` (`order²` per position) and nothing else.
    pub fn cloud(positions: Vec<Vec3>, order: u32, coeffs: &[Vec3]) -> Result<Self, FormatError> {
        let coefficients = Coefficients::from_f32(order, coeffs)?;
        Ok(Self::Cloud(CloudFile::new(ProbeSet::new(
            positions,
            coefficients,
        ))))
    }

    /// What the file holds.
    pub fn kind(&self) -> ProbeFileKind {
        match self {
            Self::Cloud(_) => ProbeFileKind::Cloud,
            Self::Volume(_) => ProbeFileKind::Volume,
            Self::Rigs(_) => ProbeFileKind::Rig,
        }
    }

    /// The probes of a cloud or volume; `None` for rigs.
    pub fn probes(&self) -> Option<&ProbeSet> {
        match self {
            Self::Cloud(c) => Some(&c.probes),
            Self::Volume(v) => Some(&v.probes),
            Self::Rigs(_) => None,
        }
    }

    /// [`ProbeFile::probes`], mutable.
    pub fn probes_mut(&mut self) -> Option<&mut ProbeSet> {
        match self {
            Self::Cloud(c) => Some(&mut c.probes),
            Self::Volume(v) => Some(&mut v.probes),
            Self::Rigs(_) => None,
        }
    }

    /// Probe (volume sample) positions, metres; empty for rigs.
    pub fn positions(&self) -> &[Vec3] {
        self.probes().map_or(&[], |p| &p.positions)
    }

    /// Number of probes (volume samples); 0 for rigs.
    pub fn probe_count(&self) -> usize {
        self.positions().len()
    }

    /// The cloud, if the file is one.
    pub fn as_cloud(&self) -> Option<&CloudFile> {
        match self {
            Self::Cloud(c) => Some(c),
            _ => None,
        }
    }

    /// [`ProbeFile::as_cloud`], mutable.
    pub fn as_cloud_mut(&mut self) -> Option<&mut CloudFile> {
        match self {
            Self::Cloud(c) => Some(c),
            _ => None,
        }
    }

    /// The volume, if the file is one.
    pub fn as_volume(&self) -> Option<&VolumeFile> {
        match self {
            Self::Volume(v) => Some(v),
            _ => None,
        }
    }

    /// [`ProbeFile::as_volume`], mutable.
    pub fn as_volume_mut(&mut self) -> Option<&mut VolumeFile> {
        match self {
            Self::Volume(v) => Some(v),
            _ => None,
        }
    }

    /// The irradiance rigs (of any kind of file).
    pub fn rigs(&self) -> &[Rig] {
        match self {
            Self::Cloud(c) => &c.rigs,
            Self::Volume(v) => &v.rigs,
            Self::Rigs(r) => &r.rigs,
        }
    }

    /// [`ProbeFile::rigs`], mutable.
    pub fn rigs_mut(&mut self) -> &mut Vec<Rig> {
        match self {
            Self::Cloud(c) => &mut c.rigs,
            Self::Volume(v) => &mut v.rigs,
            Self::Rigs(r) => &mut r.rigs,
        }
    }

    /// Bake metadata, UTF-8 (JSON by convention).
    pub fn metadata(&self) -> &str {
        match self {
            Self::Cloud(c) => &c.metadata,
            Self::Volume(v) => &v.metadata,
            Self::Rigs(r) => &r.metadata,
        }
    }

    /// [`ProbeFile::metadata`], mutable.
    pub fn metadata_mut(&mut self) -> &mut String {
        match self {
            Self::Cloud(c) => &mut c.metadata,
            Self::Volume(v) => &mut v.metadata,
            Self::Rigs(r) => &mut r.metadata,
        }
    }

    /// How L1 coefficients are meant to be evaluated ([`L1Mode::Linear`]
    /// for rigs).
    pub fn l1_mode(&self) -> L1Mode {
        self.probes().map_or(L1Mode::Linear, |p| p.l1_mode)
    }
}
