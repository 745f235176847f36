//! [`ProbeCloud`]: a loaded probe cloud answering "radiance SH / irradiance
//! at this point" by blending the four probes of the enclosing tetrahedron
//! with their barycentric weights (seed 003, after Cupisz, GDC 2012), or the
//! closest hull triangle's probes outside the hull (see [`super`]). When the
//! file holds distance moments (`VISM`), each weight is multiplied by the
//! probe's Chebyshev visibility of the point and the four renormalized
//! ([`super::visibility`]; DDGI, Majercik et al. 2019), so probes behind a
//! wall stop leaking their light.

use super::cell_visibility::{CellPlanes, CellVisibility};
use super::directional::{self, DirectionTable, DIRECTIONS};
use super::visibility::VisibilityMaps;
use super::{CloudError, Location, TetMesh, WalkState};
use crate::format::{FormatError, ProbeFile};
use crate::prelude::*;
use glam::Vec3;
use thiserror::Error;

/// Why a [`ProbeCloud`] cannot be built from a file.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ProbeCloudError {
    /// The file has no `TETS` section (e.g. a volume, or a shard part).
    #[error("the file has no tetrahedra (not a probe cloud, or an unmerged shard part)")]
    NoTetrahedra,
    /// The distance moments do not match the probes.
    #[error("the visibility maps cover {maps} probes, the cloud has {probes}")]
    VisibilityMismatch {
        /// Probes with a map.
        maps: usize,
        /// Probes of the cloud.
        probes: usize,
    },
    /// The cell visibility bits do not match the tetrahedral mesh.
    #[error(
        "the cell visibility covers {tets} tetrahedra and {hull_faces} hull faces, \
         the mesh has {mesh_tets} and {mesh_hull_faces}"
    )]
    CellVisibilityMismatch {
        /// Tetrahedra with a record.
        tets: usize,
        /// Hull faces with a record.
        hull_faces: usize,
        /// Tetrahedra of the mesh.
        mesh_tets: usize,
        /// Hull faces of the mesh.
        mesh_hull_faces: usize,
    },
    /// The occluder planes do not match the tetrahedral mesh.
    #[error("the cell planes cover {tets} tetrahedra, the mesh has {mesh_tets}")]
    CellPlanesMismatch {
        /// Tetrahedra the planes are for.
        tets: usize,
        /// Tetrahedra of the mesh.
        mesh_tets: usize,
    },
    /// The brightness exponent is not a number in `0..=`[`MAX_BRIGHTNESS_EXPONENT`].
    #[error("brightness exponent {0}: expected 0 to 4")]
    BrightnessExponent(f32),
    /// The fitted probe weights do not cover the probes, or one is outside
    /// [`PROBE_WEIGHT_RANGE`] (or not a number).
    #[error("probe weights: {count} given for {probes} probes, or probe {index}'s weight {value} is outside 1e-6..=1e6")]
    ProbeWeights {
        /// Weights given.
        count: usize,
        /// Probes of the cloud.
        probes: usize,
        /// First probe whose weight is out of range (0 when the count is wrong).
        index: usize,
        /// Its weight (NaN when the count is wrong).
        value: f32,
    },
    /// The coefficients could not be decoded.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// The tetrahedra are invalid.
    #[error(transparent)]
    Cloud(#[from] CloudError),
}

/// Probe positions, tetrahedra and decoded radiance SH (linear RGB, f32),
/// and optionally per-probe [`VisibilityMaps`] that weight the blend.
#[derive(Debug, Clone)]
pub struct ProbeCloud {
    mesh: TetMesh,
    coeffs: Vec<Vec3>,
    order: u32,
    visibility: Option<VisibilityMaps>,
    visibility_on: bool,
    cells: Option<CellVisibility>,
    /// Occluder planes refining `cells` ([`ProbeCloud::set_cell_planes`]);
    /// boxed, so a cloud without them stays small.
    planes: Option<Box<CellPlanes>>,
    cells_on: bool,
    /// Brightness exponent `α` of [`ProbeCloud::set_brightness_weighting`]
    /// (0: off).
    brightness: f32,
    /// Each probe's `Ē_i` for the brightness weighting: the luminance of
    /// its DC coefficient as built (relighting through
    /// [`ProbeCloud::coefficients_mut`] keeps the blend, so it stays linear).
    luminance: Vec<f32>,
    /// Directional brightness exponent `γ` of
    /// [`ProbeCloud::set_directional_brightness`] (0: off).
    directional: f32,
    /// What the directional blend needs (boxed: ~1 KB of tables).
    directional_data: Box<DirectionalData>,
    /// Fitted per-probe blend weights ([`ProbeCloud::set_probe_weights`]).
    probe_weights: Option<Vec<f32>>,
    probe_weights_on: bool,
}

/// The directional blend's data of a [`ProbeCloud`].
#[derive(Debug, Clone)]
struct DirectionalData {
    /// The constant tables.
    table: DirectionTable,
    /// Each probe's `L_i(d)`: the luminance of its irradiance for the twelve
    /// directions of [`directional::directions`], as built (like
    /// `ProbeCloud::luminance`).
    luminance: Vec<[f32; DIRECTIONS]>,
}

/// The range a fitted probe weight ([`ProbeCloud::set_probe_weights`], the
/// file's `PWGT` section) must lie in: positive, finite, and far enough from
/// 0 and infinity that four of them times the other factors neither
/// underflow nor overflow an `f32` sum.
pub const PROBE_WEIGHT_RANGE: core::ops::RangeInclusive<f32> = 1e-6..=1e6;

/// Largest brightness exponent [`ProbeCloud::set_brightness_weighting`]
/// accepts.
pub const MAX_BRIGHTNESS_EXPONENT: f32 = 4.0;

/// The share of a point's barycentric weight that cell visibility must
/// leave in sight (`Σ_i b_i·c_i`) for [`ProbeCloud::weights_at`] to
/// renormalize over the visible probes alone; below it the blend moves
/// linearly towards the cell's darkest probe, which it reaches at 0.
/// Measured at 0.1 and 0.25 on the demo and at 0.1 on the duplex apartment
/// and FZK-Haus (probekit's BENCHMARKS.md, "Hidden-cell fallback").
pub const HIDDEN_MASS_FLOOR: f32 = 0.1;

impl ProbeCloud {
    /// Builds a cloud from a loaded file: its positions, its `TETS` vertices
    /// and neighbours (via [`TetMesh::new`], which validates them) and its
    /// coefficients decoded to f32 (`order²` per probe), and its distance
    /// moments (`VISM`) when present, which switch visibility weighting on,
    /// its cell visibility and occluder planes (`CVSP`, `CPLN`), and its
    /// fitted probe weights with the brightness exponents they were fitted
    /// for (`PWGT`).
    pub fn from_file(file: &ProbeFile) -> Result<Self, ProbeCloudError> {
        let mesh = Self::mesh_from_file(file)?;
        let mut cloud = Self::new(mesh, file.coefficients.order, file.coefficients.to_f32()?)?;
        if let Some(m) = &file.visibility {
            let maps = VisibilityMaps::from_moments(m).ok_or(FormatError::InvalidValue {
                id: crate::format::SectionId::VISIBILITY,
                element: 0,
                reason: "visibility map resolution is zero",
            })?;
            cloud.set_visibility_maps(Some(maps))?;
        }
        if let Some(c) = &file.cell_visibility {
            cloud.set_cell_visibility_bits(Some(c.clone()))?;
        }
        if let Some(p) = &file.cell_planes {
            cloud.set_cell_planes(Some(p.clone()))?;
        }
        if let Some(w) = &file.probe_weights {
            cloud.set_probe_weights(Some(w.clone()))?;
            cloud.set_brightness_weighting(file.brightness_exponent)?;
            cloud.set_directional_brightness(file.directional_exponent)?;
        }
        Ok(cloud)
    }

    /// The tetrahedral mesh a cloud file stores: its positions and its `TETS`
    /// vertices and neighbours, validated by [`TetMesh::new`].
    pub fn mesh_from_file(file: &ProbeFile) -> Result<TetMesh, ProbeCloudError> {
        let tets = file
            .tetrahedra
            .as_ref()
            .ok_or(ProbeCloudError::NoTetrahedra)?;
        Ok(TetMesh::new(
            file.positions.clone(),
            tets.vertices.clone(),
            tets.neighbours.clone(),
        )?)
    }

    /// Builds a cloud from a mesh and `order²` radiance SH coefficients per
    /// probe of the mesh.
    pub fn new(mesh: TetMesh, order: u32, coeffs: Vec<Vec3>) -> Result<Self, ProbeCloudError> {
        let n = (order * order) as usize;
        if order == 0 || coeffs.len() != n * mesh.positions().len() {
            return Err(FormatError::Unrepresentable(
                "coefficient count does not match probes × order²",
            )
            .into());
        }
        let luminance = coeffs
            .chunks_exact(n)
            .map(|c| probekit_sh::LUMINANCE.dot(c[0]))
            .collect();
        let table = DirectionTable::new();
        let luminance_d = coeffs.chunks_exact(n).map(|c| table.luminance(c)).collect();
        Ok(Self {
            directional: 0.0,
            directional_data: Box::new(DirectionalData {
                table,
                luminance: luminance_d,
            }),
            mesh,
            coeffs,
            order,
            luminance,
            visibility: None,
            visibility_on: true,
            cells: None,
            planes: None,
            cells_on: true,
            brightness: 0.0,
            probe_weights: None,
            probe_weights_on: true,
        })
    }

    /// Attaches (or with `None` removes) per-probe visibility maps; they
    /// must cover exactly the cloud's probes.
    pub fn set_visibility_maps(
        &mut self,
        maps: Option<VisibilityMaps>,
    ) -> Result<(), ProbeCloudError> {
        if let Some(m) = &maps {
            if m.probe_count() != self.probe_count() {
                return Err(ProbeCloudError::VisibilityMismatch {
                    maps: m.probe_count(),
                    probes: self.probe_count(),
                });
            }
        }
        self.visibility = maps;
        Ok(())
    }

    /// The visibility maps, if the cloud has them (whether or not weighting
    /// is switched on).
    pub fn visibility_maps(&self) -> Option<&VisibilityMaps> {
        self.visibility.as_ref()
    }

    /// The visibility maps, writable (to tune bias, sharpness, variance).
    pub fn visibility_maps_mut(&mut self) -> Option<&mut VisibilityMaps> {
        self.visibility.as_mut()
    }

    /// Switches visibility weighting on (the default) or off for every
    /// query; without maps it has no effect.
    pub fn set_visibility(&mut self, on: bool) {
        self.visibility_on = on;
    }

    /// True when queries apply visibility weighting (maps present and on).
    pub fn visibility_enabled(&self) -> bool {
        self.visibility_on && self.visibility.is_some()
    }

    /// Attaches (or with `None` removes) per-cell visibility bits
    /// ([`super::cell_visibility`]); they must cover exactly the mesh's
    /// tetrahedra and hull faces, in its order.
    pub fn set_cell_visibility_bits(
        &mut self,
        cells: Option<CellVisibility>,
    ) -> Result<(), ProbeCloudError> {
        if let Some(c) = &cells {
            if c.tet_count() != self.mesh.tets().len()
                || c.hull_face_count() != self.mesh.hull_face_count()
            {
                return Err(ProbeCloudError::CellVisibilityMismatch {
                    tets: c.tet_count(),
                    hull_faces: c.hull_face_count(),
                    mesh_tets: self.mesh.tets().len(),
                    mesh_hull_faces: self.mesh.hull_face_count(),
                });
            }
        }
        self.cells = cells;
        Ok(())
    }

    /// The cell visibility bits, if the cloud has them (whether or not
    /// weighting by them is switched on).
    pub fn cell_visibility_bits(&self) -> Option<&CellVisibility> {
        self.cells.as_ref()
    }

    /// Attaches (or with `None` removes) occluder planes
    /// ([`super::cell_visibility::CellPlanes`]): in a tetrahedron with a
    /// plane, cell visibility is the plane's side test in place of the
    /// interpolated bits. They must be for exactly the mesh's tetrahedra.
    /// Like the bits, they apply while cell-visibility weighting is on.
    pub fn set_cell_planes(&mut self, planes: Option<CellPlanes>) -> Result<(), ProbeCloudError> {
        if let Some(p) = &planes {
            if p.tet_count() != self.mesh.tets().len() {
                return Err(ProbeCloudError::CellPlanesMismatch {
                    tets: p.tet_count(),
                    mesh_tets: self.mesh.tets().len(),
                });
            }
        }
        self.planes = planes.map(Box::new);
        Ok(())
    }

    /// The occluder planes, if the cloud has them.
    pub fn cell_planes(&self) -> Option<&CellPlanes> {
        self.planes.as_deref()
    }

    /// Switches cell-visibility weighting on (the default) or off; without
    /// bits or planes it has no effect. Independent of [`ProbeCloud::set_visibility`].
    pub fn set_cell_visibility(&mut self, on: bool) {
        self.cells_on = on;
    }

    /// True when queries apply cell-visibility weighting (bits or planes
    /// present, and on).
    pub fn cell_visibility_enabled(&self) -> bool {
        self.cells_on && (self.cells.is_some() || self.planes.is_some())
    }

    /// Sets the distance bias of the visibility test in metres (default
    /// [`super::visibility::DEFAULT_VISIBILITY_BIAS`]); no effect without maps.
    pub fn set_visibility_bias(&mut self, bias: f32) {
        if let Some(m) = &mut self.visibility {
            m.set_bias(bias);
        }
    }

    /// Sets the brightness exponent `α` (0, the default, switches it off):
    /// each probe's blend weight is divided by `Ē_i^α`, `Ē_i` the
    /// luminance of its mean irradiance (its DC coefficient) as the cloud
    /// was built — a cloud relit in place ([`ProbeCloud::coefficients_mut`])
    /// keeps the blend of its baked light, so relighting stays linear —
    /// floored at 10⁻³ of the brightest probe of the cell, then the weights
    /// are renormalized. A file's probe weights carry the exponent they were
    /// fitted for ([`ProbeCloud::from_file`]). The blend stays a convex combination of the probes'
    /// SH, continuous in `p`, and exact for a constant field; at `α = 1`
    /// the blended mean irradiance is the weighted *harmonic* mean of the
    /// probes' `(Σ b_i/Ē_i)⁻¹`, at most `Ē_j / b_j` for every probe `j`: one bright probe
    /// (one that sees light the point does not, e.g. on a doorway's lit
    /// side next to a dark closet) no longer dominates a dark cell. The
    /// price is a low bias in strong gradients next to lights.
    /// Measured on builtin:demo (BENCHMARKS.md, "Brightness-weighted
    /// blending"): `α = 1` removes the closet and wall leaks of adaptive
    /// clouds from ~500 probes on, for 13 % (525 probes) to 50 % (2100)
    /// more rel_rmse; `α = 0.5` is between. Our own measure, not from a
    /// paper. Errors on a value outside `0..=`[`MAX_BRIGHTNESS_EXPONENT`]
    /// or not a number.
    pub fn set_brightness_weighting(&mut self, alpha: f32) -> Result<(), ProbeCloudError> {
        if !(0.0..=MAX_BRIGHTNESS_EXPONENT).contains(&alpha) {
            return Err(ProbeCloudError::BrightnessExponent(alpha));
        }
        self.brightness = alpha;
        Ok(())
    }

    /// The brightness exponent (0: off; see
    /// [`ProbeCloud::set_brightness_weighting`]).
    pub fn brightness_weighting(&self) -> f32 {
        self.brightness
    }

    /// Sets the directional brightness exponent `γ` (0, the default,
    /// switches it off): [`ProbeCloud::sh_at`] blends the cell per direction,
    /// the weight of each probe more than [`super::directional::DIRECTIONAL_RATIO`]
    /// times brighter *for that direction* than the cell (its weighted
    /// harmonic mean) divided by the excess to the power `γ` (luminances as
    /// the cloud was built, so relighting stays linear), and projects the
    /// twelve directions' blends back to SH ([`super::directional`]). Where the mean brightness
    /// ([`ProbeCloud::set_brightness_weighting`]) damps a probe that is
    /// bright on average, this damps a probe bright only towards one side —
    /// a doorway probe seeing a lit corridor, next to a dark closet — for the
    /// normals facing that side. Still one radiance SH per point, a convex
    /// blend per direction, exact for a constant field, and the plain blend
    /// at `γ = 0`. A file's probe weights carry the exponent they were fitted
    /// for and the directional one ([`ProbeCloud::from_file`]). Errors on a
    /// value outside `0..=`[`MAX_BRIGHTNESS_EXPONENT`] or not a number.
    pub fn set_directional_brightness(&mut self, gamma: f32) -> Result<(), ProbeCloudError> {
        if !(0.0..=MAX_BRIGHTNESS_EXPONENT).contains(&gamma) {
            return Err(ProbeCloudError::BrightnessExponent(gamma));
        }
        self.directional = gamma;
        Ok(())
    }

    /// The directional brightness exponent (0: off; see
    /// [`ProbeCloud::set_directional_brightness`]).
    pub fn directional_brightness(&self) -> f32 {
        self.directional
    }

    /// Attaches (or with `None` removes) fitted per-probe blend weights
    /// `s_i`, one per probe, each in [`PROBE_WEIGHT_RANGE`]: probe `i`'s
    /// blend weight is multiplied by `s_i` before the renormalization of
    /// [`ProbeCloud::weights_at`]. The blend stays a convex combination of
    /// the probes' SH, exact for a constant field, and continuous: on a
    /// face the fourth probe's barycentric weight is 0, so both cells blend
    /// the face's three probes alike. `probekit bake` fits them to path-traced
    /// points (`probekit::cloud::blend_fit`, the file's `PWGT` section), so
    /// that a probe whose light should not reach its neighbours' space — one
    /// standing in a doorway, seeing a lit corridor, beside a dark closet —
    /// counts less. All weights 1 is the plain blend.
    pub fn set_probe_weights(&mut self, weights: Option<Vec<f32>>) -> Result<(), ProbeCloudError> {
        if let Some(w) = &weights {
            let bad = (w.len() != self.probe_count())
                .then_some((0, f32::NAN))
                .or_else(|| {
                    w.iter()
                        .position(|x| !PROBE_WEIGHT_RANGE.contains(x))
                        .map(|i| (i, w[i]))
                });
            if let Some((index, value)) = bad {
                return Err(ProbeCloudError::ProbeWeights {
                    count: w.len(),
                    probes: self.probe_count(),
                    index,
                    value,
                });
            }
        }
        self.probe_weights = weights;
        Ok(())
    }

    /// The fitted probe weights, if the cloud has them (whether or not they
    /// are switched on).
    pub fn probe_weights(&self) -> Option<&[f32]> {
        self.probe_weights.as_deref()
    }

    /// Switches the fitted probe weights on (the default) or off; without
    /// weights it has no effect.
    pub fn set_probe_weighting(&mut self, on: bool) {
        self.probe_weights_on = on;
    }

    /// True when queries apply fitted probe weights (present and on).
    pub fn probe_weighting_enabled(&self) -> bool {
        self.probe_weights_on && self.probe_weights.is_some()
    }

    /// `s_i·Ē_i^−α` for the cell's probes with a non-zero weight in `bary`:
    /// the fitted probe weight (1 when absent or off) times the brightness
    /// factor (1 when off or when no probe is bright); 1 in unused slots.
    fn probe_factors(&self, probes: &[u32; 4], bary: &[f32; 4]) -> [f32; 4] {
        let mut f = self.brightness_factors(probes, bary);
        if let Some(s) = self
            .probe_weights
            .as_ref()
            .filter(|_| self.probe_weights_on)
        {
            for k in 0..4 {
                if bary[k] != 0.0 {
                    f[k] *= s[probes[k] as usize];
                }
            }
        }
        f
    }

    /// `Ē_i^−α` for the cell's probes with a non-zero weight in `bary`
    /// (1 elsewhere, and everywhere when off or when no probe is bright).
    fn brightness_factors(&self, probes: &[u32; 4], bary: &[f32; 4]) -> [f32; 4] {
        let mut f = [1.0f32; 4];
        if self.brightness <= 0.0 {
            return f;
        }
        let lum = |k: usize| self.luminance[probes[k] as usize];
        let e: [f32; 4] = core::array::from_fn(|k| if bary[k] != 0.0 { lum(k) } else { 0.0 });
        let top = e.iter().copied().fold(0.0f32, f32::max);
        if !(top > 0.0 && top.is_finite()) {
            return f;
        }
        for k in 0..4 {
            if bary[k] != 0.0 {
                f[k] = crate::math::powf(e[k].max(1e-3 * top), -self.brightness);
            }
        }
        f
    }

    /// Blend weights at `p`: the barycentric weights `b_i` of
    /// [`TetMesh::weights_at`] (tetrahedron or outer cell), times each
    /// probe's cell visibility `c_i(p)` ([`super::cell_visibility`]: the
    /// tetrahedron's occluder plane where it has one, else its bits) and
    /// Chebyshev visibility `v_i(p)` ([`super::visibility`]) where present
    /// and on, and the factor `f_i = s_i·Ē_i^−α`: the fitted probe weight
    /// `s_i` ([`ProbeCloud::set_probe_weights`]) when present and on, and the
    /// brightness factor when [`ProbeCloud::set_brightness_weighting`] is
    /// on; renormalized:
    /// `b_i·c_i·v_i·f_i / Σ_j b_j·c_j·v_j·f_j`. Where cell visibility hides
    /// every probe of positive barycentric weight from `p` (a pocket behind
    /// a wall's end or a closet's corner), the plain weights would bring in
    /// the light of the wall's far side, so the weight is 1 on the cell's
    /// darkest probe (lowest `Ē_i` of its three or four, the first on a
    /// tie) and 0 elsewhere: a dim pocket rather than a leak (probekit's
    /// BENCHMARKS.md, "Hidden-cell fallback"; the cell's corners of weight
    /// 0 that its bits call visible were tried first and measured worse,
    /// the bits being too coarse there). Where some of it is in sight but
    /// less than [`HIDDEN_MASS_FLOOR`] (`m = Σ_i b_i·c_i` below it), the
    /// renormalized weights `r` would hand the whole weight to the few
    /// probes the bits let through, often partly hidden ones next to the
    /// wall; the weights are then `t·r + (1 − t)·d` with `t = m / floor` and
    /// `d` the darkest probe's, so they reach the fallback continuously as
    /// `m` goes to 0. Where the sum is 0 for another reason (Chebyshev
    /// visibility or the factors) it falls back to `b_i·v_i·f_i`, then
    /// `b_i·f_i`, then `b_i`. Unused slots have weight 0. No allocation.
    pub fn weights_at(&self, p: Vec3, state: &mut WalkState) -> ([u32; 4], [f32; 4]) {
        let maps = self.visibility.as_ref().filter(|_| self.visibility_on);
        let cells = self.cells.as_ref().filter(|_| self.cells_on);
        let planes = self.planes.as_deref().filter(|_| self.cells_on);
        if maps.is_none()
            && cells.is_none()
            && planes.is_none()
            && self.brightness <= 0.0
            && !self.probe_weighting_enabled()
        {
            return self.mesh.weights_at(p, state);
        }
        let (probes, bary, c, used) = match self.mesh.locate(p, state) {
            Location::Inside { tet, weights } => {
                let probes = self.mesh.tets()[tet as usize];
                let c = match planes.and_then(|pl| pl.plane(tet)) {
                    Some(plane) => {
                        let pos = self.mesh.positions();
                        CellPlanes::visibility(plane, p, &probes.map(|i| pos[i as usize]))
                    }
                    None => cells.map_or([1.0; 4], |c| c.tet(tet, &weights)),
                };
                (probes, weights, c, 4)
            }
            Location::Outside {
                hull_face,
                probes,
                weights,
                ..
            } => (
                [probes[0], probes[1], probes[2], 0],
                [weights[0], weights[1], weights[2], 0.0],
                cells.map_or([1.0; 4], |c| {
                    let v = c.hull_face(hull_face, &weights);
                    [v[0], v[1], v[2], 1.0]
                }),
                3,
            ),
        };
        let mut v = [1.0f32; 4];
        if let Some(maps) = maps {
            let pos = self.mesh.positions();
            for k in 0..4 {
                if bary[k] != 0.0 {
                    let i = probes[k] as usize;
                    v[k] = maps.visibility(i, pos[i], p);
                }
            }
        }
        let normalized = |w: [f32; 4]| {
            let sum: f32 = w.iter().sum();
            (sum.is_finite() && sum > 0.0).then(|| w.map(|x| x / sum))
        };
        let f = self.probe_factors(&probes, &bary);
        let bcv = core::array::from_fn(|k| bary[k] * c[k] * v[k] * f[k]);
        // The barycentric weight cell visibility leaves in sight. At 0 it
        // hides every probe of positive weight from `p` (a pocket behind a
        // wall's end, a corner beyond the hull): the plain blend would carry
        // the far side's light in, so the cell's darkest probe alone instead.
        let has_cells = cells.is_some() || planes.is_some();
        let mass: f32 = (0..used).map(|k| bary[k] * c[k]).sum();
        let all_hidden = has_cells && mass == 0.0;
        let darkest = || {
            let lum = |k: usize| self.luminance[probes[k] as usize];
            let k = (0..used).min_by(|&a, &b| lum(a).total_cmp(&lum(b)).then(a.cmp(&b)))?;
            let mut w = [0.0; 4];
            w[k] = 1.0;
            Some(w)
        };
        // Little of the weight in sight: renormalizing would hand it all to
        // the few (often partly hidden) probes the bits let through; blend
        // towards the darkest probe instead, reaching it continuously as the
        // visible mass goes to 0.
        let r = normalized(bcv);
        if has_cells && mass > 0.0 && mass < HIDDEN_MASS_FLOOR {
            if let (Some(r), Some(d)) = (r, darkest()) {
                let t = mass / HIDDEN_MASS_FLOOR;
                return (
                    probes,
                    core::array::from_fn(|k| t * r[k] + (1.0 - t) * d[k]),
                );
            }
        }
        let w = r
            .or_else(|| all_hidden.then(darkest).flatten())
            .or_else(|| normalized(core::array::from_fn(|k| bary[k] * v[k] * f[k])))
            .or_else(|| normalized(core::array::from_fn(|k| bary[k] * f[k])))
            .unwrap_or(bary);
        (probes, w)
    }

    /// The tetrahedral mesh.
    pub fn mesh(&self) -> &TetMesh {
        &self.mesh
    }

    /// SH bands per probe.
    pub fn order(&self) -> u32 {
        self.order
    }

    /// Coefficients per probe (`order²`).
    pub fn coeffs_per_probe(&self) -> usize {
        (self.order * self.order) as usize
    }

    /// Number of probes.
    pub fn probe_count(&self) -> usize {
        self.mesh.positions().len()
    }

    /// Every probe's radiance SH (`order²` per probe, probe after probe),
    /// writable: an engine relights a loaded cloud in place with
    /// [`crate::format::Relighter::relight_into`], no allocation. The blend
    /// weights do not change (the brightness weighting keeps the baked
    /// light's `Ē_i`), so the relit irradiance is linear in the group scales.
    pub fn coefficients_mut(&mut self) -> &mut [Vec3] {
        &mut self.coeffs
    }

    /// The radiance SH of probe `i` (`order²` coefficients).
    pub fn probe_sh(&self, i: usize) -> &[Vec3] {
        let n = self.coeffs_per_probe();
        &self.coeffs[i * n..(i + 1) * n]
    }

    /// Interpolated radiance SH at `p` into `out` (its first
    /// `min(out.len(), order²)` coefficients): the blend of
    /// [`ProbeCloud::weights_at`] (visibility-weighted when on), done per
    /// direction for bands ≤ 2 when directional brightness is on
    /// ([`ProbeCloud::set_directional_brightness`]). No allocation.
    pub fn sh_at(&self, p: Vec3, state: &mut WalkState, out: &mut [Vec3]) {
        let n = self.coeffs_per_probe();
        let m = out.len().min(n);
        out.iter_mut().for_each(|c| *c = Vec3::ZERO);
        let (probes, weights) = self.weights_at(p, state);
        // The directional blend writes bands ≤ 2 itself; the plain blend
        // fills the rest.
        let first = if self.directional > 0.0 {
            self.directional_blend(&probes, &weights, &mut out[..m]);
            m.min(directional::DIRECTIONAL_COEFFS)
        } else {
            0
        };
        for (&i, &w) in probes.iter().zip(&weights) {
            if w == 0.0 {
                continue;
            }
            let src = &self.coeffs[i as usize * n + first..i as usize * n + m];
            for (o, c) in out[first..m].iter_mut().zip(src) {
                *o += *c * w;
            }
        }
    }

    /// Overwrites bands ≤ 2 of `out` with the directional blend of the cell
    /// `probes` with blend weights `weights` (see [`super::directional`]).
    fn directional_blend(&self, probes: &[u32; 4], weights: &[f32; 4], out: &mut [Vec3]) {
        let active = weights.map(|w| w > 0.0);
        let data = &self.directional_data;
        let lum = probes.map(|i| &data.luminance[i as usize]);
        let f = directional::factors(lum, *weights, self.directional);
        let e: [[Vec3; DIRECTIONS]; 4] = core::array::from_fn(|k| {
            if active[k] {
                data.table.irradiance(self.probe_sh(probes[k] as usize))
            } else {
                [Vec3::ZERO; DIRECTIONS]
            }
        });
        let blended: [Vec3; DIRECTIONS] = core::array::from_fn(|d| {
            let (mut sum, mut acc) = (0.0f32, Vec3::ZERO);
            for k in 0..4 {
                if active[k] {
                    let u = weights[k] * f[d][k];
                    sum += u;
                    acc += e[k][d] * u;
                }
            }
            if sum > 0.0 && sum.is_finite() {
                acc / sum
            } else {
                (0..4).fold(Vec3::ZERO, |a, k| a + e[k][d] * weights[k])
            }
        });
        data.table.project(&blended, out);
    }

    /// Irradiance `E(n)` (not divided by π) at `p` for unit normal `n`: the
    /// clamped-cosine convolution ([`probekit_sh::irradiance`]) of the
    /// blended radiance SH. No allocation.
    pub fn irradiance(&self, p: Vec3, n: Vec3, state: &mut WalkState) -> Vec3 {
        let mut buf = [Vec3::ZERO; probekit_sh::MAX_COEFFS];
        let k = self.coeffs_per_probe();
        self.sh_at(p, state, &mut buf[..k]);
        probekit_sh::irradiance(&buf[..k], n)
    }

    /// [`Self::irradiance`] for many `(point, normal)` pairs; `out` is cleared
    /// and refilled (allocates only to grow).
    pub fn irradiance_many(
        &self,
        points: &[Vec3],
        normals: &[Vec3],
        state: &mut WalkState,
        out: &mut Vec<Vec3>,
    ) {
        out.clear();
        out.extend(
            points
                .iter()
                .zip(normals)
                .map(|(&p, &n)| self.irradiance(p, n, state)),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::visibility::VisibilityMaps;
    use crate::cloud::HULL;

    /// Radiance SH that varies linearly with position: c_k(p) = a_k + B_k·p.
    fn field(p: Vec3, k: usize) -> Vec3 {
        let k = k as f32;
        Vec3::new(
            0.5 + 0.1 * k + p.x - 0.3 * p.y,
            1.0 - 0.2 * k + 0.7 * p.z,
            0.25 * k + p.x + p.y + p.z,
        )
    }

    /// Two tetrahedra sharing the face (1, 2, 3).
    fn cloud() -> ProbeCloud {
        let pos = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, Vec3::splat(1.0)];
        let tets = vec![[0, 1, 2, 3], [4, 3, 2, 1]];
        let neighbors = vec![[1, HULL, HULL, HULL], [0, HULL, HULL, HULL]];
        let mesh = TetMesh::new(pos.clone(), tets, neighbors).unwrap();
        let coeffs: Vec<Vec3> = pos
            .iter()
            .flat_map(|&p| (0..9).map(move |k| field(p, k)))
            .collect();
        ProbeCloud::new(mesh, 3, coeffs).unwrap()
    }

    #[test]
    fn reproduces_a_linear_field_inside() {
        let c = cloud();
        let mut st = WalkState::new();
        let mut out = [Vec3::ZERO; 9];
        for p in [
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(0.6, 0.6, 0.5),
            Vec3::new(0.25, 0.25, 0.25),
        ] {
            c.sh_at(p, &mut st, &mut out);
            for (k, o) in out.iter().enumerate() {
                assert!((*o - field(p, k)).abs().max_element() < 1e-5, "{p} {k}");
            }
            // Irradiance against a direct cosine-weighted sum over the sphere
            // of the exact field's SH (independent quadrature).
            let n = Vec3::new(0.3, 0.8, -0.52).normalize();
            let exact: Vec<Vec3> = (0..9).map(|k| field(p, k)).collect();
            let mut e = Vec3::ZERO;
            let m = 20_000;
            for i in 0..m {
                let d = probekit_sh::fibonacci_point(i, m);
                let cos = n.dot(d).max(0.0);
                e += probekit_sh::convolve::eval_sh(&exact, d) * cos;
            }
            e *= 4.0 * std::f32::consts::PI / m as f32;
            let got = c.irradiance(p, n, &mut st);
            assert!((got - e).abs().max_element() < 2e-2 * e.abs().max_element().max(1.0));
        }
    }

    #[test]
    fn outside_points_get_hull_values() {
        let c = cloud();
        let mut st = WalkState::new();
        let mut out = [Vec3::ZERO; 9];
        // Below the face z = 0: the closest hull point is (0.2, 0.3, 0).
        c.sh_at(Vec3::new(0.2, 0.3, -2.0), &mut st, &mut out);
        let q = Vec3::new(0.2, 0.3, 0.0);
        for (k, o) in out.iter().enumerate() {
            assert!((*o - field(q, k)).abs().max_element() < 1e-5);
        }
        // Far beyond vertex 0 along (-1,-1,-1): the vertex itself.
        c.sh_at(Vec3::splat(-5.0), &mut st, &mut out);
        for (k, o) in out.iter().enumerate() {
            assert!((*o - field(Vec3::ZERO, k)).abs().max_element() < 1e-5);
        }
    }

    #[test]
    fn visibility_weights_drop_probes_behind_walls_and_renormalize() {
        let mut c = cloud();
        let n = c.probe_count();
        let p = Vec3::new(0.3, 0.35, 0.3);
        let mut st = WalkState::new();
        let (idx, b) = c.mesh().weights_at(p, &mut st);
        // Open space (every first hit 100 m away): weights unchanged.
        let open = VisibilityMaps::new(2, 100.0, vec![[100.0, 10_000.0]; 4 * n]).unwrap();
        c.set_visibility_maps(Some(open)).unwrap();
        let (_, w) = c.weights_at(p, &mut st);
        assert_eq!(w, b);
        // Probe 1 (at +X) sees a surface 0.1 m away in every direction: it
        // no longer lights p (≈ 0.8 m away); the others keep their
        // barycentric ratios, renormalized.
        let mut m = vec![[100.0, 10_000.0]; 4 * n];
        for t in &mut m[4..8] {
            *t = [0.1, 0.01];
        }
        c.set_visibility_maps(Some(VisibilityMaps::new(2, 100.0, m).unwrap()))
            .unwrap();
        let (_, w) = c.weights_at(p, &mut st);
        let k1 = idx.iter().position(|&i| i == 1).unwrap();
        let rest: f32 = (0..4).filter(|&k| k != k1).map(|k| b[k]).sum();
        for k in 0..4 {
            let want = if k == k1 { 0.0 } else { b[k] / rest };
            assert!((w[k] - want).abs() < 1e-3, "{k}: {} vs {want}", w[k]);
        }
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        // Switched off: barycentric again; sh_at follows the weights.
        c.set_visibility(false);
        assert!(!c.visibility_enabled());
        assert_eq!(c.weights_at(p, &mut st).1, b);
        c.set_visibility(true);
        let mut out = [Vec3::ZERO; 9];
        c.sh_at(p, &mut st, &mut out);
        let want: Vec3 = (0..4).map(|k| c.probe_sh(idx[k] as usize)[0] * w[k]).sum();
        assert!((out[0] - want).length() < 1e-5);
    }

    #[test]
    fn files_without_tetrahedra_are_refused() {
        let f = ProbeFile::cloud(vec![Vec3::ZERO], 1, &[Vec3::ONE]).unwrap();
        assert!(matches!(
            ProbeCloud::from_file(&f),
            Err(ProbeCloudError::NoTetrahedra)
        ));
    }
}
