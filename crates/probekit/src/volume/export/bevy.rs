//! Bevy's irradiance volume ([`export_bevy`]).
//!
//! Targets Bevy `0.20.0-dev` (bevyengine/bevy commit 4805ca7, August 2026):
//! `crates/bevy_pbr/src/light_probe/irradiance_volume.rs` (the layout),
//! `irradiance_volume.wesl` lines 53–76 (the sampling),
//! `crates/bevy_camera/src/camera.rs` (`Exposure`) and
//! `crates/bevy_light/src/probe.rs` (`IrradianceVolume`, `LightProbe`).
//!
//! # Layout
//! A 3D texture of `Rx × 2Ry × 3Rz` texels holding one Valve ambient cube
//! per voxel: face `S` of voxel `(x, y, z)` at `(x, y + Ry·[S negative], z +
//! Rz·axis(S))`. (The shader adds half the height for a *negative* normal
//! component; the Rust module's prose table states the opposite; we follow
//! the shader.) Format `E5B9G9R9_UFLOAT_PACK32`, as Bevy's own example
//! asset.
//!
//! # Values
//! Bevy computes `Σ N_a²·face(a, sign N_a)` and multiplies it by the diffuse
//! colour and the volume's `intensity`, with no `1/π`, so a texel stores
//! `E/π` of its face direction (the Lambertian outgoing radiance for albedo
//! 1), in the scene's radiance units. The faces are
//! `probekit_sh::ambient_cube::fit_from_sh_nonnegative` of the runtime's
//! radiance SH at the voxel's point: the least-squares ambient cube of the
//! irradiance over the sphere among cubes with no negative face, RGB9E5
//! being unsigned. (The unconstrained fit goes negative opposite a strong
//! light; clamping it to 0 would no longer be the best cube Bevy can hold.)
//!
//! # Where the voxels are
//! Bevy maps the unit cube centred at the origin through the `LightProbe`'s
//! `Transform`, samples voxel `i` at its centre `(i + ½)/R` of the cube, and
//! clamps to the outermost centres (the half-texel clamp). Voxel `i` holds
//! the point `min + i/(R − 1)·(max − min)` — on a uniform volume at its own
//! resolution, probe `i` itself — and the transform's scale is `(max −
//! min)·R/(R − 1)` about the box centre, so that Bevy's voxel centre `i`
//! lands there: `centre + ((i + ½)/R − ½)·(max − min)·R/(R − 1) = min +
//! i/(R − 1)·(max − min)`. Bevy's trilinear filtering between voxel centres
//! then blends the probes' cubes with the runtime's trilinear weights
//! (which equals the cube of the blended SH wherever no face is held at 0,
//! the fit being linear in the SH there), and the half-voxel band of the
//! cube beyond the box holds the box's faces, as the runtime clamps
//! queries to the box.
//!
//! An octree is written on the uniform lattice of its finest level,
//! `roots·2^d + 1` voxels per axis ([`BevyLattice::OctreeLevel`]): its
//! points are the octree's own samples wherever the leaves are that fine,
//! and the runtime's continuous query elsewhere. Trilinear filtering of that
//! lattice reproduces the query exactly inside a leaf whose neighbours share
//! its size (a trilinear function stays trilinear on a finer lattice) and
//! differs from it around coarse/fine transitions. A lattice of more than
//! [`BEVY_MAX_DEFAULT_VOXELS`] voxels, or over 2048 texels on a side
//! (wgpu's default `max_texture_dimension_3d`), takes the finest depth that
//! fits.
//!
//! # Intensity and exposure
//! Bevy multiplies every lit colour by the camera's exposure `2^−EV100 /
//! 1.2` ([`bevy_exposure`]; `Exposure::default()` is EV100 9.7,
//! [`BEVY_DEFAULT_EV100`]) before tone mapping, and
//! `IrradianceVolume::default()` has `intensity` 0. Intensity 1 keeps
//! probekit's units (its lights are plain radiance numbers, as Bevy's
//! `cd/m²`), right when the Bevy scene's lights and exposure share them;
//! [`bevy_intensity_for_exposure`] `= 1.2·2^EV100` (≈ 998 at the default
//! exposure) shows the baked radiance on screen at its probekit value. The
//! sidecar carries both, under names that say which is which.

use super::lattice::{lattice_resolution, texel_positions};
use super::{ExportError, Ktx2, TexelFormat};
use crate::sh::{ambient_cube::fit_from_sh_nonnegative, codec};
use crate::volume::{Interp, Volume};
use glam::Vec3;

/// Bevy's default camera exposure in EV100: `Exposure::EV100_BLENDER`, the
/// value of `Exposure::default()` (bevy_camera `camera.rs`).
pub const BEVY_DEFAULT_EV100: f32 = 9.7;

/// Most voxels [`export_bevy`] writes for an octree when no resolution is
/// given (2^21: 48 MiB of RGB9E5 texels).
pub const BEVY_MAX_DEFAULT_VOXELS: u64 = 1 << 21;

/// wgpu's default `max_texture_dimension_3d`, in texels.
const MAX_TEXTURE_SIDE: u64 = 2048;

/// Bevy's exposure scale at `ev100`: `2^−ev100 / 1.2`
/// (`Exposure::exposure`, after Filament's physically based camera).
/// Bevy multiplies every lit colour by it before tone mapping.
pub fn bevy_exposure(ev100: f32) -> f32 {
    (-ev100).exp2() / 1.2
}

/// The `IrradianceVolume::intensity` that shows the baked radiance on screen
/// at its probekit value under camera exposure `ev100`: `1 /
/// bevy_exposure(ev100) = 1.2 · 2^ev100` (≈ 998 at Bevy's default, EV100
/// 9.7; ≈ 1 at EV100 −0.26).
pub fn bevy_intensity_for_exposure(ev100: f32) -> f32 {
    1.2 * ev100.exp2()
}

/// What the voxels of a Bevy export hold (module docs, "Where the voxels
/// are").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BevyLattice {
    /// A uniform volume at its own resolution: voxel `i` is probe `i`.
    Probes,
    /// The uniform lattice of an octree's depth `depth` (`roots·2^depth + 1`
    /// voxels per axis): the octree's samples where its leaves are that
    /// fine, the runtime's query elsewhere.
    OctreeLevel {
        /// Lattice depth below the root cells.
        depth: u32,
        /// Whether `depth` is the octree's deepest level.
        finest: bool,
    },
    /// Any other resolution: every voxel is the runtime's trilinear query at
    /// its point.
    Resampled,
}

impl BevyLattice {
    /// What the voxels are, in words (sidecar and CLI).
    pub fn describe(&self) -> String {
        match self {
            Self::Probes => "the volume's probes (one voxel per probe)".to_string(),
            Self::OctreeLevel { depth, finest } => format!(
                "the octree's depth-{depth} lattice ({}): its samples where leaves are that fine, \
                 the runtime's trilinear query elsewhere",
                if *finest {
                    "its finest level"
                } else {
                    "coarser than its finest level, to fit the size limit"
                }
            ),
            Self::Resampled => {
                "resampled: the runtime's trilinear query at every voxel's point".to_string()
            }
        }
    }
}

/// What [`export_bevy`] produced.
#[derive(Clone, Debug)]
pub struct BevyExport {
    /// The voxel texture, `Rx × 2Ry × 3Rz` texels of RGB9E5.
    pub texture: Ktx2,
    /// The sidecar JSON: `format`, `bevy_version`, `resolution`, `box`,
    /// `lattice`, `voxels`, `light_probe_transform` (`translation`,
    /// `rotation` as a quaternion `[x, y, z, w]`, `scale`),
    /// `intensity_in_scene_units` (1), `intensity_for_bevy_default_exposure`,
    /// `bevy_default_exposure_ev100`, `intensity_rule`, `texel`.
    pub sidecar: serde_json::Value,
    /// Voxels per axis.
    pub resolution: [u32; 3],
    /// What the voxels hold.
    pub lattice: BevyLattice,
}

/// The default resolution of `volume`'s Bevy export (module docs): a uniform
/// volume's own, an octree's finest lattice that fits the limits.
fn default_resolution(volume: &Volume) -> Result<([u32; 3], BevyLattice), ExportError> {
    let Some(roots) = volume.root_grid() else {
        let r = volume.grid_resolution().unwrap_or([2; 3]);
        return Ok((r, BevyLattice::Probes));
    };
    let finest = volume.max_depth();
    let side = |d: u32| roots.map(|r| ((r as u64) << d) + 1);
    let fits = |d: u32| {
        let [x, y, z] = side(d);
        x <= MAX_TEXTURE_SIDE
            && 2 * y <= MAX_TEXTURE_SIDE
            && 3 * z <= MAX_TEXTURE_SIDE
            && x * y * z <= BEVY_MAX_DEFAULT_VOXELS
    };
    let depth = (0..=finest.min(10)).rev().find(|&d| fits(d)).unwrap_or(0);
    Ok((
        lattice_resolution(volume, Some(depth))?,
        BevyLattice::OctreeLevel {
            depth,
            finest: depth == finest,
        },
    ))
}

/// What the voxels of an export of `volume` at `res` hold.
fn classify(volume: &Volume, res: [u32; 3]) -> BevyLattice {
    match (volume.grid_resolution(), volume.root_grid()) {
        (Some(g), _) if g == res => BevyLattice::Probes,
        (None, Some(roots)) => {
            let finest = volume.max_depth();
            (0..=finest.min(20))
                .find(|&d| (0..3).all(|a| ((roots[a] as u64) << d) + 1 == res[a] as u64))
                .map_or(BevyLattice::Resampled, |depth| BevyLattice::OctreeLevel {
                    depth,
                    finest: depth == finest,
                })
        }
        _ => BevyLattice::Resampled,
    }
}

/// Byte offset of face `face` (0..6 = +X, −X, +Y, −Y, +Z, −Z) of voxel
/// `[x, y, z]` in a texture of `res` voxels (module docs, "Layout").
fn face_offset(res: [usize; 3], [x, y, z]: [usize; 3], face: usize) -> usize {
    let [rx, ry, rz] = res;
    let (axis, neg) = (face / 2, face % 2 == 1);
    let (tx, ty, tz) = (x, y + if neg { ry } else { 0 }, z + axis * rz);
    4 * (tx + rx * (ty + 2 * ry * tz))
}

/// Bevy's ambient-cube voxel texture of `volume` and its sidecar (module
/// docs): at `resolution` voxels per axis (at least 2 each), or by default
/// on the volume's probes (uniform) or its finest lattice (octree). The
/// sidecar's `light_probe_transform` puts Bevy's voxel centres on the
/// lattice points.
pub fn export_bevy(
    volume: &Volume,
    resolution: Option<[u32; 3]>,
) -> Result<BevyExport, ExportError> {
    let (resolution, lattice) = match resolution {
        Some(r) => (r, classify(volume, r)),
        None => default_resolution(volume)?,
    };
    if resolution.iter().map(|&r| r as u64).product::<u64>() > 1 << 24 {
        return Err(ExportError::TooLarge(resolution));
    }
    if resolution.iter().any(|&r| r < 2) {
        return Err(ExportError::BevyResolution(resolution));
    }
    let (min, max) = volume.bounds();
    let pts = texel_positions(min, max, resolution);
    let n = volume.coeffs_per_sample();
    let mut sh = vec![Vec3::ZERO; pts.len() * n];
    volume.sample_sh_batch(&pts, Interp::Trilinear, &mut sh)?;
    let res = resolution.map(|r| r as usize);
    let mut data = vec![0u8; res[0] * 2 * res[1] * 3 * res[2] * 4];
    for (t, coeffs) in sh.chunks_exact(n).enumerate() {
        let voxel = [t % res[0], (t / res[0]) % res[1], t / (res[0] * res[1])];
        let cube = fit_from_sh_nonnegative(coeffs);
        // AmbientCube faces: +X, −X, +Y, −Y, +Z, −Z.
        for (f, face) in cube.faces.iter().enumerate() {
            let o = face_offset(res, voxel, f);
            // Non-negative already; `max` only guards against −0.
            let e = (*face / std::f32::consts::PI).max(Vec3::ZERO);
            data[o..o + 4].copy_from_slice(&codec::encode_rgb9e5(e).to_le_bytes());
        }
    }
    let texture = Ktx2 {
        format: TexelFormat::Rgb9e5,
        size: [resolution[0], 2 * resolution[1], 3 * resolution[2]],
        kvd: vec![("KTXwriter".to_string(), "probekit".to_string())],
        data,
    };
    let r = Vec3::from_array(resolution.map(|r| r as f32));
    let scale = (max - min) * r / (r - 1.0);
    let at_default = bevy_intensity_for_exposure(BEVY_DEFAULT_EV100) as f64;
    let sidecar = serde_json::json!({
        "format": "probekit-bevy-irradiance-volume",
        "bevy_version": "0.20.0-dev (bevyengine/bevy 4805ca7)",
        "resolution": resolution,
        "box": {"min": min.to_array(), "max": max.to_array()},
        "lattice": lattice.describe(),
        "voxels": "voxel (i,j,k) holds the ambient cube at box.min + (i,j,k)/(resolution-1)*(box.max-box.min); light_probe_transform puts Bevy's voxel centres there",
        "light_probe_transform": {
            "translation": ((min + max) * 0.5).to_array(),
            "rotation": [0.0, 0.0, 0.0, 1.0],
            "scale": scale.to_array(),
            "note": "scale = (box.max-box.min)*R/(R-1), not the box size: the LightProbe cube reaches half a voxel beyond the box on each side, where Bevy holds the outermost voxels",
        },
        "intensity_in_scene_units": 1.0,
        "intensity_for_bevy_default_exposure": (at_default * 100.0).round() / 100.0,
        "bevy_default_exposure_ev100": BEVY_DEFAULT_EV100,
        "intensity_rule": "IrradianceVolume::intensity = 1.2 * 2^EV100 shows the baked radiance on screen at its probekit value (Bevy scales lit colour by its exposure 2^-EV100 / 1.2): intensity_for_bevy_default_exposure at Bevy's default EV100 9.7. intensity_in_scene_units (1) keeps probekit's units, right when the Bevy scene's lights and exposure use them too (EV100 -0.26 makes the two equal).",
        "texel": "E/pi per ambient-cube face (radiance units), RGB9E5",
    });
    Ok(BevyExport {
        texture,
        sidecar,
        resolution,
        lattice,
    })
}

/// Reads Bevy's texel for face `face` (0..6 = +X, −X, +Y, −Y, +Z, −Z) of
/// voxel `(x, y, z)` from an [`export_bevy`] texture: the inverse of its
/// layout, for tests and tools.
pub fn bevy_texel(tex: &Ktx2, voxel: [u32; 3], face: usize) -> Option<Vec3> {
    let [w, h2, d3] = tex.size;
    let res = [w as usize, h2 as usize / 2, d3 as usize / 3];
    let v = voxel.map(|v| v as usize);
    if face >= 6 || (0..3).any(|a| v[a] >= res[a]) {
        return None;
    }
    let o = face_offset(res, v, face);
    let b = tex.data.get(o..o + 4)?;
    Some(codec::decode_rgb9e5(u32::from_le_bytes(b.try_into().ok()?)))
}
