//! [`Probes`]: any `.probes` file (a cloud, a volume or rigs only) behind
//! one query shape.

mod error;
mod lights;
mod options;
mod query;

pub use error::{LoadError, QueryError};
pub use options::{BlendOverrides, LoadOptions};
pub use query::{Cell, Query};

use crate::cloud::visibility::MAX_SHARPNESS;
use crate::cloud::{ProbeCloud, WalkState};
use crate::format::{FormatError, L1Mode, ProbeFile, ProbeFileKind, Relighter, Rig, RuntimeLight};
use crate::prelude::*;
use crate::rig::{RigState, SphereTable, SplitRig};
use crate::volume::{Interp, Volume, VolumeError};
use alloc::sync::Arc;
use glam::Vec3;
use probekit_sh::MAX_COEFFS;
#[cfg(feature = "std")]
use std::path::Path;

/// Radiance SH of bands 0–2 (L2), 9 RGB coefficients indexed
/// `l(l+1) + m`, linear RGB, the crate's conventions.
pub type Sh = [[f32; 3]; 9];

/// A loaded `.probes` file ready for queries: a probe cloud, an irradiance
/// volume, or a file of rigs only, all queried the same way. Position
/// queries take `&self` and the handle is `Sync`: share one between
/// threads, give each moving object its own [`ObjectState`]. Only
/// [`Probes::update_rig`] takes `&mut self`; objects that share a rig each
/// clone its [`RigState`] ([`Probes::rig`]) and update their own. No query
/// allocates.
#[derive(Clone, Debug)]
pub struct Probes {
    source: Source,
    kind: ProbeFileKind,
    /// SH order of the stored coefficients.
    order: u32,
    /// The L1 evaluation in effect (linear unless the order is 2).
    l1_mode: L1Mode,
    rigs: Vec<RigState>,
    /// The file's rigs as stored (names, sample points, transition tables).
    rig_data: Vec<Rig>,
    /// The sphere-light table split rigs share; built when the file has
    /// rigs.
    sphere_table: Option<Arc<SphereTable>>,
    /// Lights evaluated at run time and the probes' occlusion of them.
    lights: Option<lights::LightTerm>,
}

/// What answers position queries.
#[derive(Clone, Debug)]
enum Source {
    Cloud(Box<ProbeCloud>),
    Volume(Box<Volume>, Interp),
    /// A rigs-only file.
    None,
}

/// The per-object state of queries: for a cloud, the tetrahedron the last
/// query ended in, so that the next query of the same object (a few
/// centimetres away) walks a step or two instead of searching; nothing for
/// a volume. 12 bytes; create one per moving object (or per thread for
/// unrelated points) with [`ObjectState::new`] and keep it. Any state works
/// with any [`Probes`]: a state from another file only costs a search.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ObjectState {
    walk: WalkState,
}

impl ObjectState {
    /// A fresh state: the first query searches from the cloud's start grid.
    pub const fn new() -> Self {
        Self {
            walk: WalkState::new(),
        }
    }
}

impl Probes {
    /// Loads a file from its bytes (checked completely first: a corrupt,
    /// truncated or unsupported file is a [`LoadError::Format`]).
    pub fn from_bytes(bytes: &[u8], options: LoadOptions) -> Result<Self, LoadError> {
        Self::build(&ProbeFile::from_bytes(bytes)?, options)
    }

    /// Loads the file at `path` (needs the `std` feature).
    #[cfg(feature = "std")]
    pub fn load(path: impl AsRef<Path>, options: LoadOptions) -> Result<Self, LoadError> {
        Self::build(&ProbeFile::load(path)?, options)
    }

    /// Builds the query structures of a parsed file: a cloud's mesh and
    /// blend data, or a volume's grid or octree, and its rigs. A file of
    /// kind rig answers rig queries only (position queries are
    /// [`QueryError::NoProbes`]).
    ///
    /// The file is checked first ([`ProbeFile::validate`], what the reader
    /// guarantees of a file read from bytes), so a file built or edited in
    /// memory is refused rather than queried out of bounds.
    pub fn from_file(file: &ProbeFile, options: LoadOptions) -> Result<Self, LoadError> {
        file.validate()?;
        Self::build(file, options)
    }

    /// [`Probes::from_file`] of a file known to be valid (read and checked).
    fn build(file: &ProbeFile, options: LoadOptions) -> Result<Self, LoadError> {
        let source = match file.kind() {
            ProbeFileKind::Volume => {
                let volume = Volume::from_file(file)?;
                let interp = options.interpolation;
                if interp.needs_gradients() && !volume.has_gradients() {
                    return Err(VolumeError::NoGradients(interp).into());
                }
                Source::Volume(Box::new(volume), interp)
            }
            ProbeFileKind::Rig => Source::None,
            _ => Source::Cloud(Box::new(cloud_with(file, &options)?)),
        };
        let mut rigs = Vec::with_capacity(file.rigs().len());
        for (index, rig) in file.rigs().iter().enumerate() {
            rigs.push(RigState::new(rig).map_err(|source| LoadError::Rig { index, source })?);
        }
        // A rigs file has no probes: the SH order of its (first) rig.
        let order = match file.probes() {
            Some(p) => p.coefficients.order,
            None => file.rigs().first().map_or(1, |r| r.order),
        };
        Ok(Self {
            source,
            kind: file.kind(),
            order,
            l1_mode: match order {
                2 => options.l1_mode.unwrap_or(file.l1_mode()),
                _ => L1Mode::Linear,
            },
            rigs,
            rig_data: file.rigs().to_vec(),
            sphere_table: (!file.rigs().is_empty()).then(|| Arc::new(SphereTable::default())),
            lights: file.probes().and_then(lights::LightTerm::new),
        })
    }

    /// What the file is: a cloud, a volume or rigs.
    pub fn kind(&self) -> ProbeFileKind {
        self.kind
    }

    /// Number of probes (volume samples); 0 for a rigs-only file.
    pub fn probe_count(&self) -> usize {
        match &self.source {
            Source::Cloud(c) => c.probe_count(),
            Source::Volume(v, _) => v.sample_count(),
            Source::None => 0,
        }
    }

    /// SH order (bands) of the stored coefficients: 2 for L1, 3 for L2.
    pub fn order(&self) -> u32 {
        self.order
    }

    /// How the coefficients become irradiance: the option or the file's
    /// mode for L1 files, [`L1Mode::Linear`] for every other order.
    pub fn l1_mode(&self) -> L1Mode {
        self.l1_mode
    }

    /// The volume's interpolation; `None` for a cloud or a rigs-only file.
    pub fn interpolation(&self) -> Option<Interp> {
        match &self.source {
            Source::Volume(_, i) => Some(*i),
            _ => None,
        }
    }

    /// The cloud behind the queries, for diagnostics (`None` for a volume
    /// or a rigs-only file).
    pub fn cloud(&self) -> Option<&ProbeCloud> {
        match &self.source {
            Source::Cloud(c) => Some(c),
            _ => None,
        }
    }

    /// The volume behind the queries, for diagnostics (`None` for a cloud
    /// or a rigs-only file).
    pub fn volume(&self) -> Option<&Volume> {
        match &self.source {
            Source::Volume(v, _) => Some(v),
            _ => None,
        }
    }

    /// Radiance SH at `position` (metres, world space), bands 0–2: the
    /// stored L2; an L1 file's four coefficients with band 2 zero, or, in
    /// [`L1Mode::Zh3Hallucinated`], with the hallucinated zonal lobe
    /// expanded to band 2; higher orders' first nine. For shading many
    /// pixels of one object: query once, evaluate the SH per pixel.
    pub fn sh_at(&self, state: &mut ObjectState, position: Vec3) -> Result<Sh, QueryError> {
        self.has_probes()?;
        query::check_position(position, 0)?;
        let mut sh = [Vec3::ZERO; 9];
        self.sample_l2(state, position, &mut sh)?;
        Ok(sh.map(|c| c.to_array()))
    }

    /// Irradiance `E(n)` at `position` for the surface normal `normal` (any
    /// non-zero length; normalized here), linear RGB, not divided by π
    /// (divide by π for outgoing radiance of a white Lambertian surface).
    /// All stored bands are used; an L1 file in
    /// [`L1Mode::Zh3Hallucinated`] adds the hallucinated zonal lobe. A file
    /// with run-time lights adds, per light, its exact unoccluded
    /// irradiance times the probes' visible fractions of it blended with
    /// the SH's weights ([`crate::format::RuntimeLights`]): the whole light
    /// of the scene. An engine drawing those lights itself asks for
    /// [`Probes::sh_irradiance`] and [`Probes::light_occlusion`] instead.
    pub fn irradiance(
        &self,
        state: &mut ObjectState,
        position: Vec3,
        normal: Vec3,
    ) -> Result<[f32; 3], QueryError> {
        self.irradiance_at(state, position, normal, 0, true)
    }

    /// The SH part of [`Probes::irradiance`]: without the run-time lights'
    /// direct light (equal to it for a file without run-time lights).
    pub fn sh_irradiance(
        &self,
        state: &mut ObjectState,
        position: Vec3,
        normal: Vec3,
    ) -> Result<[f32; 3], QueryError> {
        self.irradiance_at(state, position, normal, 0, false)
    }

    /// The lights the file leaves to run time (empty if none): the SH holds
    /// everything else, their bounce light included.
    pub fn runtime_lights(&self) -> &[RuntimeLight] {
        self.lights.as_ref().map_or(&[], |l| l.lights())
    }

    /// Each run-time light's visible fraction at `position`, in `[0, 1]`:
    /// the probes' stored fractions blended with the SH's weights, in the
    /// order of [`Probes::runtime_lights`], into `out[..count]`. For an
    /// engine that evaluates those lights itself: their unoccluded
    /// irradiance times this is what [`Probes::irradiance`] adds to the SH
    /// part (or use it to dim the engine's own shadowed light where the
    /// probes see none). `out` shorter than the light count is a
    /// [`QueryError::LengthMismatch`].
    pub fn light_occlusion(
        &self,
        state: &mut ObjectState,
        position: Vec3,
        out: &mut [f32],
    ) -> Result<(), QueryError> {
        self.has_probes()?;
        query::check_position(position, 0)?;
        let count = self.runtime_lights().len();
        if out.len() < count {
            return Err(QueryError::LengthMismatch {
                positions: 1,
                normals: count,
                results: out.len(),
            });
        }
        if let Some(t) = &self.lights {
            let (p, w) = self.blend_weights(state, position);
            t.occlusion_into(&p, &w, &mut out[..count]);
        }
        Ok(())
    }

    /// [`Probes::sh_at`] for every point of `positions`, in order, sharing
    /// `state` (a coherent batch, such as one object's vertices, walks
    /// little); `out` must have the same length.
    pub fn sh_at_many(
        &self,
        state: &mut ObjectState,
        positions: &[Vec3],
        out: &mut [Sh],
    ) -> Result<(), QueryError> {
        if out.len() != positions.len() {
            return Err(QueryError::LengthMismatch {
                positions: positions.len(),
                normals: positions.len(),
                results: out.len(),
            });
        }
        if !positions.is_empty() {
            self.has_probes()?;
        }
        for (index, (&p, o)) in positions.iter().zip(out).enumerate() {
            query::check_position(p, index)?;
            let mut sh = [Vec3::ZERO; 9];
            self.sample_l2(state, p, &mut sh)?;
            *o = sh.map(|c| c.to_array());
        }
        Ok(())
    }

    /// [`Probes::irradiance`] for every `(position, normal)` pair, in order,
    /// sharing `state`; the three slices must have the same length.
    pub fn irradiance_many(
        &self,
        state: &mut ObjectState,
        positions: &[Vec3],
        normals: &[Vec3],
        out: &mut [[f32; 3]],
    ) -> Result<(), QueryError> {
        if normals.len() != positions.len() || out.len() != positions.len() {
            return Err(QueryError::LengthMismatch {
                positions: positions.len(),
                normals: normals.len(),
                results: out.len(),
            });
        }
        for (index, ((&p, &n), o)) in positions.iter().zip(normals).zip(out).enumerate() {
            *o = self.irradiance_at(state, p, n, index, true)?;
        }
        Ok(())
    }

    /// Radiance SH at `position` with every stored band, for the baker and
    /// tools (feature `write`): the first `min(out.len(), order²)`
    /// coefficients of the file's order, the rest of `out` zeroed; no L1
    /// hallucination ([`Probes::sh_at`] gives an engine bands 0–2).
    #[cfg(feature = "write")]
    pub fn sh_all_bands_at(
        &self,
        state: &mut ObjectState,
        position: Vec3,
        out: &mut [Vec3],
    ) -> Result<(), QueryError> {
        self.has_probes()?;
        query::check_position(position, 0)?;
        let k = (self.order * self.order) as usize;
        let mut buf = [Vec3::ZERO; MAX_COEFFS];
        self.sample(state, position, &mut buf[..k])?;
        let m = out.len().min(k);
        out[..m].copy_from_slice(&buf[..m]);
        out[m..].fill(Vec3::ZERO);
        Ok(())
    }

    /// [`Probes::sh_at`] with what produced it: the cell the point was
    /// found in and the probes and weights of the blend (see [`Query`]).
    pub fn query(&self, state: &mut ObjectState, position: Vec3) -> Result<Query, QueryError> {
        self.has_probes()?;
        query::check_position(position, 0)?;
        let mut sh = [Vec3::ZERO; 9];
        let mut probes = [0u32; 8];
        let mut weights = [0.0f32; 8];
        let cell = match &self.source {
            Source::Cloud(c) => {
                let (cell, p4, w4) = c.blend_at(position, &mut state.walk);
                let k = c.coeffs_per_probe().min(9);
                c.blend_sh(&p4, &w4, &mut sh[..k]);
                probes[..4].copy_from_slice(&p4);
                weights[..4].copy_from_slice(&w4);
                cell
            }
            Source::Volume(v, _) => {
                let (cell, p8, w8) = v.cell_at(position);
                self.sample_l2(state, position, &mut sh)?;
                (probes, weights) = (p8, w8);
                Cell::VolumeCell(cell)
            }
            Source::None => return Err(QueryError::NoProbes),
        };
        if self.l1_mode == L1Mode::Zh3Hallucinated {
            sh = query::hallucinate(&sh);
        }
        Ok(Query {
            sh: sh.map(|c| c.to_array()),
            cell,
            probes,
            weights,
        })
    }

    /// Relights the probes in place for new light-group scales (one RGB
    /// scale per group of `relighter`, in its order: [`Relighter::scales_for`]
    /// turns names into them), as [`Relighter::relight_into`] computes them.
    /// `relighter` is built once from the same file ([`Relighter::new`]).
    /// A cloud keeps the blend of its baked light (its brightness
    /// weightings read the probes' brightness as loaded), so the relit
    /// irradiance is linear in the scales; a volume's gradients stay the
    /// baked ones. A run-time light scales with its group too (its exact
    /// term in [`Probes::irradiance`]; [`Probes::runtime_lights`] stays as
    /// baked, for an engine that draws the light itself and scales it).
    /// Errors (nothing changed): a relighter of another order
    /// or probe count, a scale count that is not the group count, a scale
    /// that is not finite. No allocation; a rigs-only file has nothing to
    /// relight.
    pub fn relight(&mut self, relighter: &Relighter, scales: &[Vec3]) -> Result<(), FormatError> {
        if relighter.order() != self.order {
            return Err(FormatError::Unrepresentable(
                "the relighter's SH order differs from the file's",
            ));
        }
        let coeffs: &mut [Vec3] = match &mut self.source {
            Source::Cloud(c) => c.coefficients_mut(),
            Source::Volume(v, _) => v.coefficients_mut(),
            Source::None => &mut [],
        };
        relighter.relight_into(scales, coeffs)?;
        if let Some(t) = &mut self.lights {
            t.set_group_scales(|g| {
                (relighter.group_index(g))
                    .and_then(|k| scales.get(k).copied())
                    .unwrap_or(Vec3::ONE)
            });
        }
        Ok(())
    }

    /// Number of rigs in the file.
    pub fn rig_count(&self) -> usize {
        self.rigs.len()
    }

    /// The index of the rig for mesh `name`, if the file has one.
    pub fn rig_index(&self, name: &str) -> Option<usize> {
        self.rig_data.iter().position(|r| r.name == name)
    }

    /// Rig `index`: its sample points, its current parameters, its
    /// evaluation ([`RigState`]). Clone it to give an object its own rig
    /// state ([`RigState::update`] with SH sampled at its sample points,
    /// then [`RigState::irradiance`] per vertex, unit normals).
    pub fn rig(&self, index: usize) -> Result<&RigState, QueryError> {
        let count = self.rigs.len();
        self.rigs
            .get(index)
            .ok_or(QueryError::NoSuchRig { index, count })
    }

    /// A per-object rig with the near/transition/rig split for rig
    /// `index` ([`SplitRig`]): `update` it once per frame with the object's
    /// transform and the scene's lights, then ask `irradiance` per vertex.
    pub fn split_rig(&self, index: usize) -> Result<SplitRig, QueryError> {
        let count = self.rig_data.len();
        let (Some(rig), Some(table)) = (self.rig_data.get(index), self.sphere_table.as_ref())
        else {
            return Err(QueryError::NoSuchRig { index, count });
        };
        Ok(SplitRig::new(rig, table.clone())?)
    }

    /// Refits rig `index` to the radiance SH sampled at its sample points
    /// ([`RigState::update`]: `sample_sh` holds `order²` coefficients per
    /// sample point, in the rig's order); once per frame, before its
    /// queries.
    pub fn update_rig(&mut self, index: usize, sample_sh: &[Vec3]) -> Result<(), QueryError> {
        let count = self.rigs.len();
        let rig = self
            .rigs
            .get_mut(index)
            .ok_or(QueryError::NoSuchRig { index, count })?;
        Ok(rig.update(sample_sh)?)
    }

    /// Irradiance of rig `index` at `position` (the mesh's own coordinates,
    /// metres) for `normal` (any non-zero length), as [`Probes::irradiance`]
    /// (its current parameters: see [`Probes::update_rig`]).
    pub fn rig_irradiance(
        &self,
        index: usize,
        position: Vec3,
        normal: Vec3,
    ) -> Result<[f32; 3], QueryError> {
        let rig = self.rig(index)?;
        query::check_position(position, 0)?;
        let n = query::unit_normal(normal, 0)?;
        Ok(rig.irradiance(position, n).to_array())
    }

    /// One irradiance query, `index` its place in a batch (for errors);
    /// `with_lights`: add the run-time lights' term.
    fn irradiance_at(
        &self,
        state: &mut ObjectState,
        position: Vec3,
        normal: Vec3,
        index: usize,
        with_lights: bool,
    ) -> Result<[f32; 3], QueryError> {
        self.has_probes()?;
        query::check_position(position, index)?;
        let n = query::unit_normal(normal, index)?;
        let k = (self.order * self.order) as usize;
        let terms = self.lights.as_ref().filter(|_| with_lights);
        let e = if let Some(t) = terms {
            // One blend for the SH and the lights' occlusion.
            let mut buf = [Vec3::ZERO; MAX_COEFFS];
            let (probes, weights) = self.sample_weighted(state, position, &mut buf[..k]);
            let e = if k == 4 && self.l1_mode == L1Mode::Zh3Hallucinated {
                let l1: &[Vec3; 4] = buf[..4].try_into().unwrap_or(&[Vec3::ZERO; 4]);
                probekit_sh::zh3::zh3_hallucinated_irradiance(l1, n)
            } else {
                crate::eval::irradiance(&buf[..k], n)
            };
            e + t.irradiance(&probes, &weights, position, n)
        } else if k <= 9 {
            let mut buf = [Vec3::ZERO; 9];
            self.sample(state, position, &mut buf[..k])?;
            if self.l1_mode == L1Mode::Zh3Hallucinated {
                let l1: &[Vec3; 4] = buf[..4].try_into().unwrap_or(&[Vec3::ZERO; 4]);
                probekit_sh::zh3::zh3_hallucinated_irradiance(l1, n)
            } else {
                crate::eval::irradiance(&buf[..k], n)
            }
        } else {
            let mut buf = [Vec3::ZERO; MAX_COEFFS];
            self.sample(state, position, &mut buf[..k])?;
            crate::eval::irradiance(&buf[..k], n)
        };
        Ok(e.to_array())
    }

    /// [`QueryError::NoProbes`] for a rigs-only file, checked before the
    /// input so that the kind of file is the first thing a caller learns.
    fn has_probes(&self) -> Result<(), QueryError> {
        match self.source {
            Source::None => Err(QueryError::NoProbes),
            _ => Ok(()),
        }
    }

    /// Bands 0–2 at `p` into `out` (see [`Probes::sh_at`]).
    fn sample_l2(
        &self,
        state: &mut ObjectState,
        p: Vec3,
        out: &mut [Vec3; 9],
    ) -> Result<(), QueryError> {
        let k = (self.order * self.order) as usize;
        if k <= 9 {
            self.sample(state, p, &mut out[..k])?;
        } else {
            let mut buf = [Vec3::ZERO; MAX_COEFFS];
            self.sample(state, p, &mut buf[..k])?;
            out.copy_from_slice(&buf[..9]);
        }
        if self.l1_mode == L1Mode::Zh3Hallucinated {
            *out = query::hallucinate(out);
        }
        Ok(())
    }

    /// The probes and weights of the blend at `p` (a cloud's four, a
    /// volume cell's eight corners; unused slots weigh 0).
    fn blend_weights(&self, state: &mut ObjectState, p: Vec3) -> ([u32; 8], [f32; 8]) {
        let (mut probes, mut weights) = ([0u32; 8], [0.0f32; 8]);
        match &self.source {
            Source::Cloud(c) => {
                let (_, p4, w4) = c.blend_at(p, &mut state.walk);
                probes[..4].copy_from_slice(&p4);
                weights[..4].copy_from_slice(&w4);
            }
            Source::Volume(v, _) => (_, probes, weights) = v.cell_at(p),
            Source::None => {}
        }
        (probes, weights)
    }

    /// [`Self::sample`] that also returns the blend's probes and weights
    /// (a cloud blends once for both).
    fn sample_weighted(
        &self,
        state: &mut ObjectState,
        p: Vec3,
        out: &mut [Vec3],
    ) -> ([u32; 8], [f32; 8]) {
        let (probes, weights) = self.blend_weights(state, p);
        match &self.source {
            Source::Cloud(c) => {
                // A cloud blends its first four.
                let p4 = [probes[0], probes[1], probes[2], probes[3]];
                let w4 = [weights[0], weights[1], weights[2], weights[3]];
                c.blend_sh(&p4, &w4, out);
            }
            Source::Volume(v, interp) => v.sample_into(p, *interp, out),
            Source::None => {}
        }
        (probes, weights)
    }

    /// The stored coefficients at `p` into `out` (`order²` long).
    fn sample(&self, state: &mut ObjectState, p: Vec3, out: &mut [Vec3]) -> Result<(), QueryError> {
        match &self.source {
            Source::Cloud(c) => c.sh_at(p, &mut state.walk, out),
            Source::Volume(v, interp) => v.sample_into(p, *interp, out),
            Source::None => return Err(QueryError::NoProbes),
        }
        Ok(())
    }
}

/// The cloud of `file` with `options`' blend overrides applied.
fn cloud_with(file: &ProbeFile, options: &LoadOptions) -> Result<ProbeCloud, LoadError> {
    let mut cloud = ProbeCloud::from_file(file)?;
    let b = &options.blend;
    if let Some(on) = b.distance_moments {
        cloud.set_visibility(on);
    }
    if let Some(on) = b.cell_visibility {
        cloud.set_cell_visibility(on);
    }
    if let Some(on) = b.probe_weights {
        cloud.set_probe_weighting(on);
    }
    if let Some(alpha) = b.brightness_exponent {
        cloud.set_brightness_weighting(alpha)?;
    }
    if let Some(gamma) = b.directional_exponent {
        cloud.set_directional_brightness(gamma)?;
    }
    if let Some(bias) = b.visibility_bias {
        if !bias.is_finite() {
            return Err(LoadError::VisibilityBias(bias));
        }
        cloud.set_visibility_bias(bias);
    }
    if let Some(k) = b.visibility_sharpness {
        if k > MAX_SHARPNESS {
            return Err(LoadError::VisibilitySharpness(k));
        }
        if let Some(maps) = cloud.visibility_maps_mut() {
            maps.set_sharpness(k);
        }
    }
    Ok(cloud)
}
