//! [`ProbeCloud`]: a loaded probe cloud answering "radiance SH / irradiance
//! at this point" by blending the four probes of the enclosing tetrahedron
//! with their barycentric weights (after Cupisz, GDC 2012), or the closest
//! hull triangle's probes outside the hull (see [`super`]). When the
//! file holds distance moments (`VISM`), each weight is multiplied by the
//! probe's Chebyshev visibility of the point and the four renormalized
//! ([`super::visibility`]; DDGI, Majercik et al. 2019), so probes behind a
//! wall stop leaking their light.

// The blend weights at a point, and the brightness, directional and
// fitted-weight factors they apply.
mod blend;
mod factors;

use super::cell_visibility::{CellPlanes, CellVisibility};
use super::directional::{self, DirectionTable};
use super::visibility::VisibilityMaps;
use super::{CloudError, TetMesh, WalkState};
use crate::format::{FormatError, ProbeFile};
use crate::prelude::*;
use glam::{Vec3, Vec4};
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
    /// Each probe's `Ē_i^−α` for the current `α` (+∞ where `Ē_i ≤ 0`);
    /// empty at `α = 0`.
    brightness_pow: Vec<f32>,
    /// `(10⁻³)^−α`: the brightness floor's factor relative to the cell's
    /// brightest probe's.
    brightness_floor: f32,
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
    /// Each probe's `1/L_i(d)` (+∞ where `L_i(d) ≤ 0`), `L_i(d)` the
    /// luminance of its irradiance for the twelve directions of
    /// [`directional::directions`] as built (like `ProbeCloud::luminance`),
    /// four directions to a vector.
    reciprocal_luminance: Vec<[Vec4; 3]>,
}

/// The range a fitted probe weight ([`ProbeCloud::probe_weights`], the
/// file's `PWGT` section) must lie in: positive, finite, and far enough from
/// 0 and infinity that four of them times the other factors neither
/// underflow nor overflow an `f32` sum.
pub const PROBE_WEIGHT_RANGE: core::ops::RangeInclusive<f32> = 1e-6..=1e6;

/// Largest brightness exponent a cloud blends with
/// ([`ProbeCloud::brightness_weighting`] and
/// [`ProbeCloud::directional_brightness`]; a file or a load override
/// beyond it is refused).
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
        let Some(file) = file.as_cloud() else {
            return Err(ProbeCloudError::NoTetrahedra);
        };
        let c = &file.probes.coefficients;
        let mut cloud = Self::new(mesh, c.order, c.to_f32()?)?;
        let b = &file.blend;
        if let Some(m) = &b.distance_moments {
            let maps = VisibilityMaps::from_moments(m).ok_or(FormatError::InvalidValue {
                id: crate::format::SectionId::VISIBILITY,
                element: 0,
                reason: "visibility map resolution is zero",
            })?;
            cloud.set_visibility_maps(Some(maps))?;
        }
        if let Some(c) = &b.cell_visibility {
            cloud.set_cell_visibility_bits(Some(c.clone()))?;
        }
        if let Some(p) = &b.cell_planes {
            cloud.set_cell_planes(Some(p.clone()))?;
        }
        if let Some(w) = &b.probe_weights {
            cloud.set_probe_weights(Some(w.clone()))?;
            cloud.set_brightness_weighting(b.brightness_exponent)?;
            cloud.set_directional_brightness(b.directional_exponent)?;
        }
        Ok(cloud)
    }

    /// The tetrahedral mesh a cloud file stores: its positions and its `TETS`
    /// vertices and neighbours, validated by [`TetMesh::new`].
    pub fn mesh_from_file(file: &ProbeFile) -> Result<TetMesh, ProbeCloudError> {
        let Some(file) = file.as_cloud() else {
            return Err(ProbeCloudError::NoTetrahedra);
        };
        let tets = file
            .tetrahedra
            .as_ref()
            .ok_or(ProbeCloudError::NoTetrahedra)?;
        Ok(TetMesh::new(
            file.probes.positions.clone(),
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
        let reciprocal_luminance = coeffs
            .chunks_exact(n)
            .map(|c| directional::reciprocal(&table.luminance(c)))
            .collect();
        Ok(Self {
            directional: 0.0,
            directional_data: Box::new(DirectionalData {
                table,
                reciprocal_luminance,
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
            brightness_pow: Vec::new(),
            brightness_floor: 1.0,
            probe_weights: None,
            probe_weights_on: true,
        })
    }

    baker_only! {
        /// Attaches (or with `None` removes) per-probe visibility maps; they
        /// must cover exactly the cloud's probes.
        fn set_visibility_maps(
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
    }

    /// The visibility maps, if the cloud has them (whether or not weighting
    /// is switched on).
    pub fn visibility_maps(&self) -> Option<&VisibilityMaps> {
        self.visibility.as_ref()
    }

    baker_only! {
        /// The visibility maps, writable (to tune bias, sharpness, variance).
        fn visibility_maps_mut(&mut self) -> Option<&mut VisibilityMaps> {
            self.visibility.as_mut()
        }
    }

    baker_only! {
        /// Switches visibility weighting on (the default) or off for every
        /// query; without maps it has no effect.
        fn set_visibility(&mut self, on: bool) {
            self.visibility_on = on;
        }
    }

    /// True when queries apply visibility weighting (maps present and on).
    pub fn visibility_enabled(&self) -> bool {
        self.visibility_on && self.visibility.is_some()
    }

    baker_only! {
        /// Attaches (or with `None` removes) per-cell visibility bits
        /// ([`super::cell_visibility`]); they must cover exactly the mesh's
        /// tetrahedra and hull faces, in its order.
        fn set_cell_visibility_bits(
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
    }

    /// The cell visibility bits, if the cloud has them (whether or not
    /// weighting by them is switched on).
    pub fn cell_visibility_bits(&self) -> Option<&CellVisibility> {
        self.cells.as_ref()
    }

    baker_only! {
        /// Attaches (or with `None` removes) occluder planes
        /// ([`super::cell_visibility::CellPlanes`]): in a tetrahedron with a
        /// plane, cell visibility is the plane's side test in place of the
        /// interpolated bits. They must be for exactly the mesh's tetrahedra.
        /// Like the bits, they apply while cell-visibility weighting is on.
        fn set_cell_planes(&mut self, planes: Option<CellPlanes>) -> Result<(), ProbeCloudError> {
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
    }

    /// The occluder planes, if the cloud has them.
    pub fn cell_planes(&self) -> Option<&CellPlanes> {
        self.planes.as_deref()
    }

    baker_only! {
        /// Switches cell-visibility weighting on (the default) or off; without
        /// bits or planes it has no effect. Independent of [`ProbeCloud::set_visibility`].
        fn set_cell_visibility(&mut self, on: bool) {
            self.cells_on = on;
        }
    }

    /// True when queries apply cell-visibility weighting (bits or planes
    /// present, and on).
    pub fn cell_visibility_enabled(&self) -> bool {
        self.cells_on && (self.cells.is_some() || self.planes.is_some())
    }

    baker_only! {
        /// Sets the distance bias of the visibility test in metres (default
        /// [`super::visibility::DEFAULT_VISIBILITY_BIAS`]); no effect without maps.
        fn set_visibility_bias(&mut self, bias: f32) {
            if let Some(m) = &mut self.visibility {
                m.set_bias(bias);
            }
        }
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

    baker_only! {
        /// Every probe's radiance SH (`order²` per probe, probe after probe),
        /// writable: an engine relights a loaded cloud in place with
        /// [`crate::format::Relighter::relight_into`], no allocation. The blend
        /// weights do not change (the brightness weighting keeps the baked
        /// light's `Ē_i`), so the relit irradiance is linear in the group scales.
        fn coefficients_mut(&mut self) -> &mut [Vec3] {
            &mut self.coeffs
        }
    }

    /// The radiance SH of probe `i` (`order²` coefficients).
    pub fn probe_sh(&self, i: usize) -> &[Vec3] {
        let n = self.coeffs_per_probe();
        &self.coeffs[i * n..(i + 1) * n]
    }

    /// Interpolated radiance SH at `p` into `out` (its first
    /// `min(out.len(), order²)` coefficients; the rest is zeroed): the blend
    /// of [`ProbeCloud::weights_at`] (visibility-weighted when on), done per
    /// direction for bands ≤ 2 when directional brightness is on
    /// ([`ProbeCloud::directional_brightness`]). No allocation.
    pub fn sh_at(&self, p: Vec3, state: &mut WalkState, out: &mut [Vec3]) {
        let (_, probes, weights) = self.blend_at(p, state);
        self.blend_sh(&probes, &weights, out);
    }

    /// The SH of blend weights `weights` of `probes` into `out` (see
    /// [`ProbeCloud::sh_at`]).
    pub(crate) fn blend_sh(&self, probes: &[u32; 4], weights: &[f32; 4], out: &mut [Vec3]) {
        let n = self.coeffs_per_probe();
        let m = out.len().min(n);
        out.fill(Vec3::ZERO);
        let out = &mut out[..m];
        // As flat `f32` arrays, which vectorize; fixed lengths for L1 and L2.
        let src: &[f32] = bytemuck::cast_slice(&self.coeffs);
        let flat: &mut [f32] = bytemuck::cast_slice_mut(out);
        let stride = 3 * n;
        match m {
            9 => flat.copy_from_slice(&blend_fixed::<27>(src, stride, probes, weights)),
            4 => flat.copy_from_slice(&blend_fixed::<12>(src, stride, probes, weights)),
            _ => {
                for (&i, &w) in probes.iter().zip(weights) {
                    if w != 0.0 {
                        let c = &src[i as usize * stride..][..flat.len()];
                        for (o, c) in flat.iter_mut().zip(c) {
                            *o += *c * w;
                        }
                    }
                }
            }
        }
        // The directional blend is the plain one wherever no probe of the
        // cell stands out in any direction; elsewhere it adds the difference
        // for the directions where one does.
        if self.directional > 0.0 {
            self.directional_correction(probes, weights, out);
        }
    }

    /// Irradiance `E(n)` (not divided by π) at `p` for unit normal `n`: the
    /// clamped-cosine convolution ([`probekit_sh::irradiance`]) of the
    /// blended radiance SH. No allocation.
    pub fn irradiance(&self, p: Vec3, n: Vec3, state: &mut WalkState) -> Vec3 {
        let k = self.coeffs_per_probe();
        if k <= 9 {
            let mut buf = [Vec3::ZERO; 9];
            self.sh_at(p, state, &mut buf[..k]);
            crate::eval::irradiance(&buf[..k], n)
        } else {
            let mut buf = [Vec3::ZERO; probekit_sh::MAX_COEFFS];
            self.sh_at(p, state, &mut buf[..k]);
            crate::eval::irradiance(&buf[..k], n)
        }
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

/// `Σ_k weights[k]·src[probes[k]·stride..][..L]` (slots of weight 0
/// skipped), accumulated in registers.
#[inline(always)]
fn blend_fixed<const L: usize>(
    src: &[f32],
    stride: usize,
    probes: &[u32; 4],
    weights: &[f32; 4],
) -> [f32; L] {
    let mut acc = [0.0f32; L];
    for (&i, &w) in probes.iter().zip(weights) {
        let start = i as usize * stride;
        let c = src
            .get(start..start + L)
            .and_then(|c| <&[f32; L]>::try_from(c).ok());
        if let (true, Some(c)) = (w != 0.0, c) {
            for j in 0..L {
                acc[j] += c[j] * w;
            }
        }
    }
    acc
}

#[cfg(test)]
mod tests;
