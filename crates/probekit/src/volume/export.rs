//! Export of irradiance volumes as KTX2 3D textures for GPUs and for Bevy.
//!
//! The KTX2 container is written by hand after the *KTX File Format
//! Specification, version 2.0* (Khronos, <https://registry.khronos.org/KTX/specs/2.0/ktxspec.v2.html>):
//! 12-byte identifier, 9 header words (vkFormat, typeSize, width, height,
//! depth, layerCount = 0, faceCount = 1, levelCount = 1,
//! supercompressionScheme = 0), the index (DFD and KVD offsets/lengths, no
//! SGD), one level-index entry, the Data Format Descriptor (one basic block,
//! *Khronos Data Format Specification 1.3* §5: colour model RGBSDA, BT.709
//! primaries, linear transfer), key/value data (`KTXwriter`), then the level
//! data aligned to `lcm(texel size, 4)`. Texels are stored x fastest, then y,
//! then z.
//!
//! # Generic export ([`export_ktx2`])
//! Texel `(i, j, k)` is the volume's radiance SH at `min + (i, j, k) /
//! (R − 1) · (max − min)` (cell corners, as the volume's samples). A uniform
//! volume is written at its own resolution. An octree is resampled onto the
//! uniform lattice of its finest level (`roots·2^depth + 1` texels per axis,
//! `roots` the octree's root grid, [`Volume::root_grid`]) with
//! the runtime's continuous trilinear query — simple, but memory grows like
//! the finest level (`--layout dense`); [`export_bricks`] keeps the
//! octree's adaptivity instead, and [`export_auto`] (the CLI's default)
//! picks the smaller.
//!
//! # Brick atlas ([`export_bricks`])
//! The usual GPU form of an adaptive volume (a two-level sparse grid, as in
//! brick maps and Unreal's volumetric lightmaps): an **indirection texture**
//! of `N = roots·2^Di` texels per axis over the box, `Di = max_depth − 2`, and an
//! **atlas** of bricks of `(BRICK_CELLS + 1)³ = 5³` texels. A brick covers
//! one octree node: a node at depth `Di` whose leaves are finer (then its 5
//! texels per axis are exactly the finest lattice), or a leaf shallower than
//! `Di` (then it covers `2^level` indirection cells per axis, `level = Di −
//! depth`). Texels sit at the node's corners and at multiples of a quarter
//! of it, duplicated on faces shared with neighbouring bricks, so a
//! hardware trilinear fetch inside a brick needs no borders. Indirection
//! texel `(r, g, b, a)` (`R8G8B8A8_UINT`) = the brick's position in the
//! atlas (in bricks) and its `level`. Lookup for a point `p`: `g = (p −
//! min)/(max − min)·N`, `c = ⌊g⌋`, `(b, level) = indirection[c]`, `s =
//! 2^level`, `f = (g − ⌊c/s⌋·s)/s ∈ [0,1]³`, atlas texel coordinate `b·5 +
//! ½ + 4f` (divide by the atlas resolution for normalised coordinates).
//! Coefficients are encoded as in the generic export (one atlas texture per
//! group). Between a coarse brick and finer ones the faces agree at the
//! brick texels (both come from the continuous octree query) and differ by
//! the usual T-junction interpolation in between.
//!
//! * [`Ktx2Encoding::F16`]: the `3·order²` floats of a texel, ordered
//!   `c0.r, c0.g, c0.b, c1.r, …`, are cut into groups of 4, one
//!   `R16G16B16A16_SFLOAT` texture per group (last one zero-padded).
//! * [`Ktx2Encoding::Quantized`]: DC in an `E5B9G9R9_UFLOAT_PACK32` texture
//!   (`probekit_sh::codec::encode_rgb9e5`; negative DC clamps to 0), and for
//!   every higher coefficient `i` and channel the ratio `c_i / c_0` divided by
//!   the codec's bound `max(|lo|, |hi|)` of `probekit_sh::codec::ratio_range(i)`,
//!   in `R8G8B8A8_SNORM` textures (groups of 4, like F16). Decode
//!   `c_i = snorm · bound_i · c_0`.
//!
//! A JSON sidecar (`volume.json`) gives the box, the texture-to-world
//! transform, the resolution and the layout.
//!
//! # Bevy ([`export_bevy`])
//! Targets Bevy `0.20.0-dev` (bevyengine/bevy commit 4805ca7, August 2026;
//! `crates/bevy_pbr/src/light_probe/irradiance_volume.rs` and
//! `irradiance_volume.wesl`). Bevy's `IrradianceVolume` is a 3D texture of
//! `Rx × 2Ry × 3Rz` texels holding one Valve ambient cube per voxel: face
//! `S` of voxel `(x, y, z)` at `(x, y + Ry·[S negative], z + Rz·axis(S))`.
//! (The shader adds half the height for a *negative* normal component; the
//! module's prose table states the opposite; we follow the shader.) Bevy
//! maps a unit cube centred at the origin through the `LightProbe`'s
//! `Transform`, samples voxel centres `(i + ½)/R`, computes
//! `Σ N_a²·face` and multiplies by the diffuse colour and the volume's
//! `intensity` — so a texel stores `E/π` of the face direction (the
//! Lambertian outgoing radiance for albedo 1), in the scene's radiance units
//! (cd/m² with `intensity = 1`). Faces come from
//! `probekit_sh::ambient_cube::fit_from_sh` of the query at each voxel centre.
//! Format `E5B9G9R9_UFLOAT_PACK32`, as Bevy's own example asset.

use super::{Interp, Volume, VolumeError};
use crate::sh::{ambient_cube::fit_from_sh, codec};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The volume query failed.
    #[error(transparent)]
    Volume(#[from] VolumeError),
    /// Writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// Too many texels.
    #[error("resolution {0:?} is too large to export")]
    TooLarge([u32; 3]),
    /// A brick atlas was asked of a uniform volume (it has no octree).
    #[error("a brick atlas needs an octree volume; export a uniform volume with --format ktx2")]
    NotAnOctree,
    /// A malformed KTX2 file (reader).
    #[error("not a valid KTX2 file: {0}")]
    BadKtx2(&'static str),
    /// The quantized encoding needs at least 2 bands.
    #[error("quantized export needs SH order >= 2")]
    OrderTooLow,
}

/// A texel format this module writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelFormat {
    /// `VK_FORMAT_R16G16B16A16_SFLOAT` (97).
    Rgba16Float,
    /// `VK_FORMAT_R8G8B8A8_SNORM` (38).
    Rgba8Snorm,
    /// `VK_FORMAT_E5B9G9R9_UFLOAT_PACK32` (123).
    Rgb9e5,
    /// `VK_FORMAT_R8G8B8A8_UINT` (41): the brick atlas's indirection texture.
    Rgba8Uint,
}

impl TexelFormat {
    /// The Vulkan format number.
    pub const fn vk_format(self) -> u32 {
        match self {
            Self::Rgba16Float => 97,
            Self::Rgba8Snorm => 38,
            Self::Rgb9e5 => 123,
            Self::Rgba8Uint => 41,
        }
    }

    /// Bytes per texel.
    pub const fn texel_bytes(self) -> usize {
        match self {
            Self::Rgba16Float => 8,
            Self::Rgba8Snorm | Self::Rgb9e5 | Self::Rgba8Uint => 4,
        }
    }

    /// KTX2 `typeSize`.
    const fn type_size(self) -> u32 {
        match self {
            Self::Rgba16Float => 2,
            Self::Rgba8Snorm | Self::Rgba8Uint => 1,
            Self::Rgb9e5 => 4,
        }
    }

    fn from_vk(v: u32) -> Option<Self> {
        [
            Self::Rgba16Float,
            Self::Rgba8Snorm,
            Self::Rgb9e5,
            Self::Rgba8Uint,
        ]
        .into_iter()
        .find(|f| f.vk_format() == v)
    }

    /// DFD samples: (bitOffset, bitLength − 1, channelType, lower, upper).
    fn samples(self) -> Vec<(u16, u8, u8, u32, u32)> {
        match self {
            Self::Rgba16Float => [0u8, 1, 2, 15]
                .iter()
                .enumerate()
                .map(|(i, &ch)| (16 * i as u16, 15, ch | 0xC0, 0xBF80_0000, 0x3F80_0000))
                .collect(),
            Self::Rgba8Snorm => [0u8, 1, 2, 15]
                .iter()
                .enumerate()
                .map(|(i, &ch)| (8 * i as u16, 7, ch | 0x40, 0xFFFF_FF81, 0x7F))
                .collect(),
            Self::Rgba8Uint => [0u8, 1, 2, 15]
                .iter()
                .enumerate()
                .map(|(i, &ch)| (8 * i as u16, 7, ch, 0, 255))
                .collect(),
            Self::Rgb9e5 => (0..3u8)
                .flat_map(|c| [(9 * c as u16, 8, c, 0, 8448), (27, 4, c | 0x20, 15, 31)])
                .collect(),
        }
    }
}

/// One decoded KTX2 3D texture (single level, no layers, no faces).
#[derive(Clone, Debug, PartialEq)]
pub struct Ktx2 {
    /// Texel format.
    pub format: TexelFormat,
    /// Width, height, depth in texels.
    pub size: [u32; 3],
    /// Key/value pairs.
    pub kvd: Vec<(String, String)>,
    /// Texel bytes, x fastest, then y, then z.
    pub data: Vec<u8>,
}

const IDENTIFIER: [u8; 12] = [
    0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
];

fn align(n: usize, a: usize) -> usize {
    n.div_ceil(a) * a
}

impl Ktx2 {
    /// Serializes the texture as a KTX2 file (module docs).
    pub fn to_bytes(&self) -> Vec<u8> {
        let samples = self.format.samples();
        let block_size = 24 + 16 * samples.len();
        let mut dfd = Vec::new();
        dfd.extend_from_slice(&((4 + block_size) as u32).to_le_bytes());
        dfd.extend_from_slice(&0u32.to_le_bytes()); // vendor 0, type 0
        dfd.extend_from_slice(&2u16.to_le_bytes()); // version 1.3
        dfd.extend_from_slice(&(block_size as u16).to_le_bytes());
        dfd.extend_from_slice(&[1, 1, 1, 0]); // RGBSDA, BT709, linear, straight alpha
        dfd.extend_from_slice(&[0, 0, 0, 0]); // 1×1×1×1 block
        let mut planes = [0u8; 8];
        planes[0] = self.format.texel_bytes() as u8;
        dfd.extend_from_slice(&planes);
        for (off, len, ch, lo, hi) in samples {
            dfd.extend_from_slice(&off.to_le_bytes());
            dfd.extend_from_slice(&[len, ch, 0, 0, 0, 0]);
            dfd.extend_from_slice(&lo.to_le_bytes());
            dfd.extend_from_slice(&hi.to_le_bytes());
        }
        let mut kvd = Vec::new();
        for (k, v) in &self.kvd {
            let len = k.len() + 1 + v.len() + 1;
            kvd.extend_from_slice(&(len as u32).to_le_bytes());
            kvd.extend_from_slice(k.as_bytes());
            kvd.push(0);
            kvd.extend_from_slice(v.as_bytes());
            kvd.push(0);
            kvd.resize(align(kvd.len(), 4), 0);
        }
        let dfd_off = 12 + 36 + 32 + 24;
        let kvd_off = dfd_off + dfd.len();
        let data_off = align(kvd_off + kvd.len(), 8);
        let mut out = Vec::with_capacity(data_off + self.data.len());
        out.extend_from_slice(&IDENTIFIER);
        for w in [
            self.format.vk_format(),
            self.format.type_size(),
            self.size[0],
            self.size[1],
            self.size[2],
            0,
            1,
            1,
            0,
        ] {
            out.extend_from_slice(&w.to_le_bytes());
        }
        for w in [
            dfd_off as u32,
            dfd.len() as u32,
            kvd_off as u32,
            kvd.len() as u32,
        ] {
            out.extend_from_slice(&w.to_le_bytes());
        }
        out.extend_from_slice(&0u64.to_le_bytes());
        out.extend_from_slice(&0u64.to_le_bytes());
        for w in [
            data_off as u64,
            self.data.len() as u64,
            self.data.len() as u64,
        ] {
            out.extend_from_slice(&w.to_le_bytes());
        }
        out.extend_from_slice(&dfd);
        out.extend_from_slice(&kvd);
        out.resize(data_off, 0);
        out.extend_from_slice(&self.data);
        out
    }

    /// Parses a file written by [`Self::to_bytes`] (single-level 3D
    /// textures of the three formats); checks identifier, sizes, offsets and
    /// the DFD's format description.
    pub fn from_bytes(b: &[u8]) -> Result<Self, ExportError> {
        let bad = ExportError::BadKtx2;
        if b.len() < 104 || b[..12] != IDENTIFIER {
            return Err(bad("identifier or header"));
        }
        let u32_at = |o: usize| -> Result<u32, ExportError> {
            b.get(o..o + 4)
                .map(|s| u32::from_le_bytes(s.try_into().expect("4 bytes")))
                .ok_or(bad("truncated"))
        };
        let u64_at = |o: usize| -> Result<u64, ExportError> {
            b.get(o..o + 8)
                .map(|s| u64::from_le_bytes(s.try_into().expect("8 bytes")))
                .ok_or(bad("truncated"))
        };
        let format = TexelFormat::from_vk(u32_at(12)?).ok_or(bad("unsupported vkFormat"))?;
        if u32_at(16)? != format.type_size() {
            return Err(bad("typeSize"));
        }
        let size = [u32_at(20)?, u32_at(24)?, u32_at(28)?];
        if u32_at(32)? != 0 || u32_at(36)? != 1 || u32_at(40)? != 1 || u32_at(44)? != 0 {
            return Err(bad("layers, faces, levels or supercompression"));
        }
        let (dfd_off, dfd_len) = (u32_at(48)? as usize, u32_at(52)? as usize);
        let (kvd_off, kvd_len) = (u32_at(56)? as usize, u32_at(60)? as usize);
        let (lo, ll) = (u64_at(80)? as usize, u64_at(88)? as usize);
        let texels = size
            .iter()
            .try_fold(1usize, |a, &s| a.checked_mul(s as usize));
        if texels.and_then(|t| t.checked_mul(format.texel_bytes())) != Some(ll) {
            return Err(bad("level length"));
        }
        let dfd = b
            .get(dfd_off..dfd_off + dfd_len)
            .ok_or(bad("DFD out of range"))?;
        let samples = format.samples();
        if dfd.len() != 28 + 16 * samples.len() || dfd[12] != 1 || dfd[14] != 1 {
            return Err(bad("DFD"));
        }
        for (k, (off, len, ch, _, _)) in samples.iter().enumerate() {
            let s = &dfd[28 + 16 * k..];
            if u16::from_le_bytes([s[0], s[1]]) != *off || s[2] != *len || s[3] != *ch {
                return Err(bad("DFD sample"));
            }
        }
        let mut kvd = Vec::new();
        let mut p = kvd_off;
        let end = kvd_off + kvd_len;
        while p + 4 <= end {
            let len = u32_at(p)? as usize;
            let s = b.get(p + 4..p + 4 + len).ok_or(bad("KVD out of range"))?;
            let mut parts = s.split(|&c| c == 0);
            let k = parts.next().ok_or(bad("KVD key"))?;
            let v = parts.next().ok_or(bad("KVD value"))?;
            kvd.push((
                String::from_utf8_lossy(k).into_owned(),
                String::from_utf8_lossy(v).into_owned(),
            ));
            p = align(p + 4 + len, 4);
        }
        let data = b
            .get(lo..lo + ll)
            .ok_or(bad("level data out of range"))?
            .to_vec();
        Ok(Self {
            format,
            size,
            kvd,
            data,
        })
    }
}

/// How [`export_ktx2`] stores coefficients.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ktx2Encoding {
    /// RGBA16F textures of 4 floats each.
    F16,
    /// RGB9E5 DC plus RGBA8_SNORM ratio textures.
    Quantized,
}

/// What [`export_ktx2`] wrote.
#[derive(Clone, Debug)]
pub struct Ktx2Export {
    /// The textures, in sidecar order.
    pub textures: Vec<(String, Ktx2)>,
    /// The sidecar JSON.
    pub sidecar: serde_json::Value,
}

fn lattice_resolution(v: &Volume, finest: Option<u32>) -> Result<[u32; 3], ExportError> {
    let r = match finest {
        Some(d) => {
            let roots = v.root_grid().unwrap_or([1; 3]);
            let mut r = [0u32; 3];
            for a in 0..3 {
                let cells = (roots[a] as u64) << d.min(10);
                if cells >= 1 << 26 {
                    return Err(ExportError::TooLarge([cells as u32; 3]));
                }
                r[a] = cells as u32 + 1;
            }
            r
        }
        None => v.grid_resolution().unwrap_or([2; 3]),
    };
    if r.iter().map(|&x| x as u64).product::<u64>() > 1 << 26 {
        return Err(ExportError::TooLarge(r));
    }
    Ok(r)
}

fn texel_positions(min: Vec3, max: Vec3, r: [u32; 3], centres: bool) -> Vec<Vec3> {
    let mut out = Vec::new();
    for k in 0..r[2] {
        for j in 0..r[1] {
            for i in 0..r[0] {
                let q = [i, j, k];
                let f = Vec3::from_array(std::array::from_fn(|a| {
                    if centres {
                        (q[a] as f32 + 0.5) / r[a] as f32
                    } else if r[a] > 1 {
                        q[a] as f32 / (r[a] - 1) as f32
                    } else {
                        0.5
                    }
                }));
                out.push(min + f * (max - min));
            }
        }
    }
    out
}

/// Textures with their file names, in sidecar order.
type NamedTextures = Vec<(String, Ktx2)>;

/// Encodes `n` radiance SH coefficients per texel (texels x fastest, then
/// y, then z, `res` of them) as KTX2 textures per `encoding` (module docs);
/// returns the textures and, for [`Ktx2Encoding::Quantized`], the ratio
/// bound of each coefficient `i ≥ 1`.
fn encode_sh_textures(
    sh: &[Vec3],
    n: usize,
    res: [u32; 3],
    encoding: Ktx2Encoding,
) -> Result<(NamedTextures, Vec<f32>), ExportError> {
    let texels = sh.len() / n.max(1);
    let mut textures = Vec::new();
    let kvd = vec![("KTXwriter".to_string(), "probekit".to_string())];
    let mut bounds = Vec::new();
    match encoding {
        Ktx2Encoding::F16 => {
            let floats = 3 * n;
            for g in 0..floats.div_ceil(4) {
                let mut data = Vec::with_capacity(texels * 8);
                for t in 0..texels {
                    for c in 0..4 {
                        let f = 4 * g + c;
                        let x = if f < floats {
                            sh[t * n + f / 3][f % 3]
                        } else {
                            0.0
                        };
                        data.extend_from_slice(&half::f16::from_f32(x).to_bits().to_le_bytes());
                    }
                }
                textures.push((
                    format!("sh_f16_{g}.ktx2"),
                    Ktx2 {
                        format: TexelFormat::Rgba16Float,
                        size: res,
                        kvd: kvd.clone(),
                        data,
                    },
                ));
            }
        }
        Ktx2Encoding::Quantized => {
            if n < 4 {
                return Err(ExportError::OrderTooLow);
            }
            let mut dc = Vec::with_capacity(texels * 4);
            for t in 0..texels {
                dc.extend_from_slice(
                    &codec::encode_rgb9e5(sh[t * n].max(Vec3::ZERO)).to_le_bytes(),
                );
            }
            textures.push((
                "sh_dc_rgb9e5.ktx2".to_string(),
                Ktx2 {
                    format: TexelFormat::Rgb9e5,
                    size: res,
                    kvd: kvd.clone(),
                    data: dc,
                },
            ));
            bounds = (1..n)
                .map(|i| {
                    let (lo, hi) = codec::ratio_range(i.min(8));
                    lo.abs().max(hi.abs())
                })
                .collect::<Vec<f32>>();
            let floats = 3 * (n - 1);
            for g in 0..floats.div_ceil(4) {
                let mut data = Vec::with_capacity(texels * 4);
                for t in 0..texels {
                    let dcv = codec::decode_rgb9e5(codec::encode_rgb9e5(sh[t * n].max(Vec3::ZERO)));
                    for c in 0..4 {
                        let f = 4 * g + c;
                        let q = if f < floats {
                            let (i, ch) = (1 + f / 3, f % 3);
                            let r = if dcv[ch] > 0.0 {
                                sh[t * n + i][ch] / dcv[ch]
                            } else {
                                0.0
                            };
                            (r / bounds[i - 1]).clamp(-1.0, 1.0)
                        } else {
                            0.0
                        };
                        data.push(((q * 127.0).round() as i8) as u8);
                    }
                }
                textures.push((
                    format!("sh_ratio_snorm8_{g}.ktx2"),
                    Ktx2 {
                        format: TexelFormat::Rgba8Snorm,
                        size: res,
                        kvd: kvd.clone(),
                        data,
                    },
                ));
            }
        }
    }
    Ok((textures, bounds))
}

/// Adds the sidecar fields both KTX2 exports share: SH order, encoding,
/// coefficient layout, ratio bounds and the texture list.
fn with_coefficient_fields(
    mut sidecar: serde_json::Value,
    order: usize,
    encoding: Ktx2Encoding,
    bounds: &[f32],
    textures: &NamedTextures,
) -> serde_json::Value {
    let extra = serde_json::json!({
        "sh_order": order,
        "radiance": true,
        "encoding": match encoding { Ktx2Encoding::F16 => "f16", Ktx2Encoding::Quantized => "quantized" },
        "layout": match encoding {
            Ktx2Encoding::F16 => "floats c0.r,c0.g,c0.b,c1.r,... in groups of 4 per RGBA16F texture",
            Ktx2Encoding::Quantized => "DC in RGB9E5; then for i>=1, channel ch: ratio c_i.ch/c_0.ch / bound[i-1], groups of 4 per RGBA8_SNORM texture; c_i = snorm*bound*c_0",
        },
        "ratio_bounds": bounds,
        "textures": textures.iter().map(|(name, t)| serde_json::json!({"file": name, "vk_format": t.format.vk_format()})).collect::<Vec<_>>(),
    });
    if let (Some(m), serde_json::Value::Object(e)) = (sidecar.as_object_mut(), extra) {
        m.extend(e);
    }
    sidecar
}

/// Exports `volume` as KTX2 textures plus sidecar (module docs). A uniform
/// volume keeps its resolution; an octree is resampled at its finest level
/// (or at `octree_depth` if given; at most 10).
pub fn export_ktx2(
    volume: &Volume,
    encoding: Ktx2Encoding,
    octree_depth: Option<u32>,
) -> Result<Ktx2Export, ExportError> {
    let res = lattice_resolution(
        volume,
        if volume.grid_resolution().is_some() {
            None
        } else {
            octree_depth.or(Some(volume.max_depth()))
        },
    )?;
    let (min, max) = volume.bounds();
    let pts = texel_positions(min, max, res, false);
    let n = volume.coeffs_per_sample();
    let mut sh = vec![Vec3::ZERO; pts.len() * n];
    volume.sample_sh_batch(&pts, Interp::Trilinear, &mut sh)?;
    let (textures, bounds) = encode_sh_textures(&sh, n, res, encoding)?;
    let size = max - min;
    let sidecar = serde_json::json!({
        "format": "probekit-volume-ktx2",
        "box": {"min": min.to_array(), "max": max.to_array()},
        "resolution": res,
        "texel_positions": "corners: texel (i,j,k) at min + (i,j,k)/(R-1)*(max-min)",
        "texture_to_world": {
            "description": "world = min + uvw_corner * (max - min), with uvw_corner = (i,j,k)/(R-1); for hardware sampling use uvw = (0.5 + uvw_corner*(R-1))/R",
            "translation": min.to_array(),
            "scale": size.to_array(),
        },
    });
    Ok(Ktx2Export {
        sidecar: with_coefficient_fields(sidecar, volume.order(), encoding, &bounds, &textures),
        textures,
    })
}

/// Cells per axis of one brick of [`export_bricks`]; a brick holds
/// `(BRICK_CELLS + 1)³` texels (its faces are duplicated in its neighbours,
/// so hardware trilinear filtering inside a brick needs no border logic).
pub const BRICK_CELLS: u32 = 4;

/// Exports an octree volume as a **brick atlas** (module docs, "Brick
/// atlas"): bricks of `(BRICK_CELLS + 1)³` texels, one per octree node at
/// the indirection depth `Di = max_depth − 2` that has finer leaves and one
/// per shallower leaf, packed into atlas textures (encoded as
/// [`export_ktx2`] does), plus an `R8G8B8A8_UINT` indirection texture of
/// `roots·2^Di` texels per axis. Memory follows the octree's adaptivity instead of
/// its finest level. A uniform volume has no octree: use [`export_ktx2`].
pub fn export_bricks(volume: &Volume, encoding: Ktx2Encoding) -> Result<Ktx2Export, ExportError> {
    bricks_from_plan(volume, &plan_bricks(volume)?, encoding)
}

/// Which bricks an octree's atlas holds and where: the cheap half of
/// [`export_bricks`] (no sampling), enough to size the atlas.
struct BrickPlan {
    /// Indirection texels per axis (`roots · 2^Di`).
    cells: [u32; 3],
    /// Per brick: (level, node coordinates at depth `Di − level`).
    bricks: Vec<(u32, [u32; 3])>,
    /// Per indirection cell (x fastest): (brick, level).
    cell_brick: Vec<(u32, u32)>,
    /// Atlas size in bricks.
    atlas: [usize; 3],
    /// Atlas size in texels.
    res: [u32; 3],
}

fn plan_bricks(volume: &Volume) -> Result<BrickPlan, ExportError> {
    if volume.grid_resolution().is_some() {
        return Err(ExportError::NotAnOctree);
    }
    let depth = volume.max_depth();
    let di = depth.saturating_sub(BRICK_CELLS.trailing_zeros()).min(8);
    let roots = volume.root_grid().unwrap_or([1; 3]);
    if roots.iter().any(|&r| r > 1 << 12) {
        return Err(ExportError::TooLarge(roots));
    }
    let cells = roots.map(|r| r << di);
    let (min, max) = volume.bounds();
    let size = max - min;
    // Which brick each indirection cell uses: (level, node coordinates at
    // depth di − level), numbered in first-use order (deterministic).
    let mut index: std::collections::BTreeMap<(u32, [u32; 3]), u32> = Default::default();
    let mut bricks: Vec<(u32, [u32; 3])> = Vec::new();
    let total: u64 = cells.iter().map(|&c| c as u64).product();
    if total > 1 << 24 {
        return Err(ExportError::TooLarge(cells));
    }
    let mut cell_brick = Vec::with_capacity(total as usize);
    for k in 0..cells[2] {
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                let q = [i, j, k];
                let c = min
                    + Vec3::from_array(std::array::from_fn(|a| {
                        (q[a] as f32 + 0.5) / cells[a] as f32
                    })) * size;
                let level = di - volume.leaf_depth_at(c).min(di);
                let node = q.map(|x| x >> level);
                let b = *index.entry((level, node)).or_insert_with(|| {
                    bricks.push((level, node));
                    (bricks.len() - 1) as u32
                });
                cell_brick.push((b, level));
            }
        }
    }
    let nb = bricks.len();
    let ax = ((nb as f64).cbrt().ceil() as usize).max(1);
    let ay = ((nb as f64 / ax as f64).sqrt().ceil() as usize).max(1);
    let az = nb.div_ceil(ax * ay).max(1);
    if ax > 255 || ay > 255 || az > 255 {
        return Err(ExportError::TooLarge([ax as u32, ay as u32, az as u32]));
    }
    let t = BRICK_CELLS as usize + 1;
    let res = [(ax * t) as u32, (ay * t) as u32, (az * t) as u32];
    if res.iter().map(|&x| x as u64).product::<u64>() > 1 << 26 {
        return Err(ExportError::TooLarge(res));
    }
    Ok(BrickPlan {
        cells,
        bricks,
        cell_brick,
        atlas: [ax, ay, az],
        res,
    })
}

/// Samples and encodes the atlas of `plan` (see [`export_bricks`]).
fn bricks_from_plan(
    volume: &Volume,
    plan: &BrickPlan,
    encoding: Ktx2Encoding,
) -> Result<Ktx2Export, ExportError> {
    let BrickPlan {
        cells,
        ref bricks,
        ref cell_brick,
        atlas: [ax, ay, az],
        res,
    } = *plan;
    let nb = bricks.len();
    let (min, max) = volume.bounds();
    let size = max - min;
    let t = BRICK_CELLS as usize + 1;
    let (rx, ry) = (res[0] as usize, res[1] as usize);
    let mut pts = vec![min; rx * ry * res[2] as usize];
    for (b, &(level, node)) in bricks.iter().enumerate() {
        let (bx, by, bz) = (b % ax, (b / ax) % ay, b / (ax * ay));
        let n = Vec3::from_array(cells.map(|c| c as f32));
        let extent = size * ((1u32 << level) as f32 / n);
        let origin = min + Vec3::from_array(node.map(|x| x as f32)) * extent;
        for w in 0..t {
            for v in 0..t {
                for u in 0..t {
                    let f = Vec3::new(u as f32, v as f32, w as f32) / BRICK_CELLS as f32;
                    let (x, y, z) = (bx * t + u, by * t + v, bz * t + w);
                    pts[x + rx * (y + ry * z)] = (origin + f * extent).min(max);
                }
            }
        }
    }
    let n = volume.coeffs_per_sample();
    let mut sh = vec![Vec3::ZERO; pts.len() * n];
    volume.sample_sh_batch(&pts, Interp::Trilinear, &mut sh)?;
    let (mut textures, bounds) = encode_sh_textures(&sh, n, res, encoding)?;
    let mut ind = Vec::with_capacity(cell_brick.len() * 4);
    for &(b, level) in cell_brick {
        let b = b as usize;
        ind.extend_from_slice(&[
            (b % ax) as u8,
            ((b / ax) % ay) as u8,
            (b / (ax * ay)) as u8,
            level as u8,
        ]);
    }
    textures.insert(
        0,
        (
            "indirection_rgba8ui.ktx2".to_string(),
            Ktx2 {
                format: TexelFormat::Rgba8Uint,
                size: cells,
                kvd: vec![("KTXwriter".to_string(), "probekit".to_string())],
                data: ind,
            },
        ),
    );
    let atlas_bytes: usize = textures.iter().skip(1).map(|(_, t)| t.data.len()).sum();
    let sidecar = serde_json::json!({
        "format": "probekit-volume-bricks",
        "box": {"min": min.to_array(), "max": max.to_array()},
        "indirection": {
            "file": "indirection_rgba8ui.ktx2",
            "resolution": cells,
            "texel": "r,g,b = brick coordinates in the atlas (in bricks), a = level: the brick covers 2^level indirection cells per axis",
        },
        "brick_cells": BRICK_CELLS,
        "brick_texels": BRICK_CELLS + 1,
        "bricks": nb,
        "atlas_bricks": [ax, ay, az],
        "atlas_resolution": res,
        "atlas_bytes": atlas_bytes,
        "lookup": "c = floor(uvw*N) (uvw = (p-min)/(max-min), N = indirection resolution); (b, level) = indirection[c]; s = 2^level; o = floor(c/s)*s; f = (uvw*N - o)/s in [0,1]^3; atlas texel coordinate = b*(brick_cells+1) + 0.5 + f*brick_cells (texels); divide by atlas_resolution for normalized coordinates",
    });
    Ok(Ktx2Export {
        sidecar: with_coefficient_fields(sidecar, volume.order(), encoding, &bounds, &textures),
        textures,
    })
}

/// The smaller of the two KTX2 layouts: a uniform volume at its own
/// resolution; an octree as a brick atlas ([`export_bricks`]) when its atlas
/// holds fewer texels than the finest-level lattice, else resampled densely
/// ([`export_ktx2`]). Bricks duplicate their faces (5³ texels per 4³ cells),
/// so an octree that is nearly full at its finest level is smaller dense.
pub fn export_auto(volume: &Volume, encoding: Ktx2Encoding) -> Result<Ktx2Export, ExportError> {
    if volume.grid_resolution().is_some() {
        return export_ktx2(volume, encoding, None);
    }
    let plan = plan_bricks(volume)?;
    let atlas: u64 = plan.res.iter().map(|&r| r as u64).product();
    let roots = volume.root_grid().unwrap_or([1; 3]);
    let dense: u64 = roots
        .iter()
        .map(|&r| ((r as u64) << volume.max_depth().min(10)) + 1)
        .product();
    if atlas < dense {
        bricks_from_plan(volume, &plan, encoding)
    } else {
        export_ktx2(volume, encoding, None)
    }
}

/// Writes an [`export_ktx2`] result into directory `dir` (created).
pub fn write_ktx2_export(export: &Ktx2Export, dir: &Path) -> Result<(), ExportError> {
    std::fs::create_dir_all(dir).map_err(|source| ExportError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    // Each file goes to a temporary name and is renamed into place, so an
    // interrupted export never leaves a half-written texture.
    let put = |p: PathBuf, bytes: &[u8]| {
        crate::format::write_atomic(&p, bytes).map_err(|e| match e {
            crate::format::WriteError::Io { path, source } => ExportError::Io { path, source },
            other => ExportError::Io {
                path: p.clone(),
                source: std::io::Error::other(other.to_string()),
            },
        })
    };
    for (name, t) in &export.textures {
        put(dir.join(name), &t.to_bytes())?;
    }
    let json = serde_json::to_string_pretty(&export.sidecar).expect("JSON value");
    put(dir.join("volume.json"), json.as_bytes())
}

/// Bevy's ambient-cube voxel texture of `volume` at `resolution` voxels per
/// axis (module docs give the layout and scale), and the `LightProbe`
/// transform as JSON (`translation` = box centre, `scale` = box size,
/// `rotation` identity quaternion `[x, y, z, w]`).
pub fn export_bevy(
    volume: &Volume,
    resolution: [u32; 3],
) -> Result<(Ktx2, serde_json::Value), ExportError> {
    if resolution.contains(&0) || resolution.iter().map(|&r| r as u64).product::<u64>() > 1 << 24 {
        return Err(ExportError::TooLarge(resolution));
    }
    let (min, max) = volume.bounds();
    let pts = texel_positions(min, max, resolution, true);
    let n = volume.coeffs_per_sample();
    let mut sh = vec![Vec3::ZERO; pts.len() * n];
    volume.sample_sh_batch(&pts, Interp::Trilinear, &mut sh)?;
    let [rx, ry, rz] = resolution.map(|r| r as usize);
    let mut data = vec![0u8; rx * 2 * ry * 3 * rz * 4];
    for z in 0..rz {
        for y in 0..ry {
            for x in 0..rx {
                let t = x + rx * (y + ry * z);
                let cube = fit_from_sh(&sh[t * n..(t + 1) * n]);
                // AmbientCube faces: +X, −X, +Y, −Y, +Z, −Z.
                for (f, face) in cube.faces.iter().enumerate() {
                    let (axis, neg) = (f / 2, f % 2 == 1);
                    let (tx, ty, tz) = (x, y + if neg { ry } else { 0 }, z + axis * rz);
                    let o = 4 * (tx + rx * (ty + 2 * ry * tz));
                    let e = *face / std::f32::consts::PI;
                    data[o..o + 4]
                        .copy_from_slice(&codec::encode_rgb9e5(e.max(Vec3::ZERO)).to_le_bytes());
                }
            }
        }
    }
    let tex = Ktx2 {
        format: TexelFormat::Rgb9e5,
        size: [resolution[0], 2 * resolution[1], 3 * resolution[2]],
        kvd: vec![("KTXwriter".to_string(), "probekit".to_string())],
        data,
    };
    let json = serde_json::json!({
        "bevy_version": "0.20.0-dev (bevyengine/bevy 4805ca7)",
        "resolution": resolution,
        "light_probe_transform": {
            "translation": ((min + max) * 0.5).to_array(),
            "rotation": [0.0, 0.0, 0.0, 1.0],
            "scale": (max - min).to_array(),
        },
        "intensity": 1.0,
        "texel": "E/pi per ambient-cube face (radiance units), RGB9E5",
    });
    Ok((tex, json))
}

/// Reads Bevy's texel for face `face` (0..6 = +X, −X, +Y, −Y, +Z, −Z) of
/// voxel `(x, y, z)` from an [`export_bevy`] texture: the inverse of its
/// layout, for tests and tools.
pub fn bevy_texel(tex: &Ktx2, voxel: [u32; 3], face: usize) -> Option<Vec3> {
    let [w, h2, d3] = tex.size;
    let (rx, ry, rz) = (w as usize, h2 as usize / 2, d3 as usize / 3);
    let [x, y, z] = voxel.map(|v| v as usize);
    if face >= 6 || x >= rx || y >= ry || z >= rz {
        return None;
    }
    let (axis, neg) = (face / 2, face % 2 == 1);
    let (tx, ty, tz) = (x, y + if neg { ry } else { 0 }, z + axis * rz);
    let o = 4 * (tx + rx * (ty + 2 * ry * tz));
    let b = tex.data.get(o..o + 4)?;
    Some(codec::decode_rgb9e5(u32::from_le_bytes(b.try_into().ok()?)))
}
