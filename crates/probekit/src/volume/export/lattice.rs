//! The dense lattice export ([`export_ktx2`]) and the coefficient encodings
//! every KTX2 export of radiance SH shares.
//!
//! Texel `(i, j, k)` is the volume's radiance SH at `min + (i, j, k) /
//! (R − 1) · (max − min)` (cell corners, as the volume's samples). A uniform
//! volume is written at its own resolution. An octree is resampled onto the
//! uniform lattice of its finest level (`roots·2^depth + 1` texels per axis,
//! `roots` the octree's root grid, [`Volume::root_grid`]) with
//! the runtime's continuous trilinear query — simple, but memory grows like
//! the finest level (`--layout dense`); [`super::export_bricks`] keeps the
//! octree's adaptivity instead, and [`super::export_auto`] (the CLI's default)
//! picks the smaller.
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

use super::{ExportError, Ktx2, TexelFormat};
use crate::sh::codec;
use crate::volume::{Interp, Volume};
use glam::Vec3;

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

/// Texels per axis of a dense lattice: an octree's `roots·2^depth + 1` for
/// `finest = Some(depth)` (depth at most 10), else a uniform volume's own
/// resolution; refused above 2^26 texels.
pub(super) fn lattice_resolution(v: &Volume, finest: Option<u32>) -> Result<[u32; 3], ExportError> {
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

/// The lattice's points, x fastest: texel `(i, j, k)` at `min + (i, j, k) /
/// (R − 1) · (max − min)` (the box's centre on an axis with one texel).
pub(super) fn texel_positions(min: Vec3, max: Vec3, r: [u32; 3]) -> Vec<Vec3> {
    let mut out = Vec::new();
    for k in 0..r[2] {
        for j in 0..r[1] {
            for i in 0..r[0] {
                let q = [i, j, k];
                let f = Vec3::from_array(std::array::from_fn(|a| {
                    if r[a] > 1 {
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
pub(super) fn encode_sh_textures(
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
pub(super) fn with_coefficient_fields(
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
    let pts = texel_positions(min, max, res);
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
