//! Image decoding for environment maps: `.hdr` and `.png` through `image`,
//! `.exr` through `exr`. Texels come back linear RGB, row 0 at the top.

use super::EnvError;
use glam::Vec3;
use std::path::Path;

/// Decodes `path` by extension into `(width, height, texels)`; validation of
/// texel values is left to the caller.
pub(crate) fn load_image(path: &Path) -> Result<(usize, usize, Vec<Vec3>), EnvError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    // Open first so a missing file reports as an I/O error, whatever its extension.
    std::fs::metadata(path).map_err(|source| EnvError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    match ext.as_deref() {
        Some("exr") => load_exr(path),
        Some("hdr") | Some("png") => load_with_image(path),
        _ => Err(EnvError::UnsupportedFormat {
            path: path.to_path_buf(),
        }),
    }
}

/// `.hdr` (linear f32) and `.png` (8/16-bit sRGB-encoded, decoded to linear
/// with the sRGB transfer function, IEC 61966-2-1).
fn load_with_image(path: &Path) -> Result<(usize, usize, Vec<Vec3>), EnvError> {
    let decode_err = |e: image::ImageError| EnvError::Decode {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let reader = image::ImageReader::open(path).map_err(|source| EnvError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let img = reader.decode().map_err(decode_err)?;
    let is_float = matches!(
        img,
        image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_)
    );
    let rgb = img.into_rgb32f();
    let (w, h) = (rgb.width() as usize, rgb.height() as usize);
    let texels = rgb
        .pixels()
        .map(|p| {
            let v = Vec3::from_array(p.0);
            if is_float {
                v
            } else {
                Vec3::new(
                    srgb_to_linear(v.x),
                    srgb_to_linear(v.y),
                    srgb_to_linear(v.z),
                )
            }
        })
        .collect();
    Ok((w, h, texels))
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The compressions this version of the `exr` crate decodes.
fn exr_can_decode(c: exr::compression::Compression) -> bool {
    use exr::compression::Compression::*;
    matches!(
        c,
        Uncompressed | RLE | ZIP1 | ZIP16 | PIZ | PXR24 | B44 | B44A | DWAA(_) | DWAB(_)
    )
}

/// Upper-case name of an EXR compression, as users know it (`DWAA`, `ZIP`...).
fn exr_compression_name(c: exr::compression::Compression) -> String {
    use exr::compression::Compression::*;
    match c {
        DWAA(_) => "DWAA".into(),
        DWAB(_) => "DWAB".into(),
        ZIP1 => "ZIPS".into(),
        ZIP16 => "ZIP".into(),
        other => format!("{other:?}").to_ascii_uppercase(),
    }
}

/// First RGB(A) layer of an EXR as f32. The header is read first so that a
/// compression the crate cannot decode is reported by name before any pixel
/// decoding; a decoding failure of a lossy or exotic compression is also
/// reported with the compression's name and the advice to re-save as ZIP/PIZ.
fn load_exr(path: &Path) -> Result<(usize, usize, Vec<Vec3>), EnvError> {
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| EnvError::Decode {
        path: path.to_path_buf(),
        message: format!("bad EXR header: {e}"),
    })?;
    let Some(header) = meta.headers.first() else {
        return Err(EnvError::Decode {
            path: path.to_path_buf(),
            message: "EXR has no layers".into(),
        });
    };
    let compression = header.compression;
    if !exr_can_decode(compression) {
        return Err(EnvError::ExrCompression {
            path: path.to_path_buf(),
            compression: exr_compression_name(compression),
            message: "the exr crate does not implement it".into(),
        });
    }
    let size = header.layer_size;
    if size.0 == 0 || size.1 == 0 {
        return Err(EnvError::ZeroSize {
            path: path.to_path_buf(),
            width: size.0,
            height: size.1,
        });
    }
    let owned = path.to_path_buf();
    let result = std::panic::catch_unwind(move || {
        exr::prelude::read_first_rgba_layer_from_file(
            &owned,
            |res, _| (res.0, vec![Vec3::ZERO; res.0 * res.1]),
            |(w, px): &mut (usize, Vec<Vec3>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.1 * *w + pos.0] = Vec3::new(r, g, b);
            },
        )
    });
    let image = match result {
        Ok(Ok(img)) => img,
        Ok(Err(e)) => {
            use exr::compression::Compression::*;
            let plain = matches!(compression, Uncompressed | RLE | ZIP1 | ZIP16 | PIZ);
            return Err(if plain {
                EnvError::Decode {
                    path: path.to_path_buf(),
                    message: e.to_string(),
                }
            } else {
                EnvError::ExrCompression {
                    path: path.to_path_buf(),
                    compression: exr_compression_name(compression),
                    message: e.to_string(),
                }
            });
        }
        Err(_) => {
            return Err(EnvError::ExrCompression {
                path: path.to_path_buf(),
                compression: exr_compression_name(compression),
                message: "the decoder failed".into(),
            })
        }
    };
    let layer = image.layer_data;
    let (w, texels) = layer.channel_data.pixels;
    let h = texels.len() / w.max(1);
    Ok((w, h, texels))
}

/// Writes texels as a 32-bit float RGB OpenEXR with ZIP compression, scan lines.
pub(crate) fn save_exr(path: &Path, width: usize, texels: &[Vec3]) -> Result<(), EnvError> {
    use exr::prelude::*;
    let height = texels.len() / width.max(1);
    let encoding = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let layer = Layer::new(
        (width, height),
        LayerAttributes::named("rgb"),
        encoding,
        SpecificChannels::rgb(|p: Vec2<usize>| {
            let t = texels[p.y() * width + p.x()];
            (t.x, t.y, t.z)
        }),
    );
    Image::from_layer(layer)
        .write()
        .to_file(path)
        .map_err(|e| EnvError::Decode {
            path: path.to_path_buf(),
            message: format!("cannot write EXR: {e}"),
        })
}

/// Writes texels as Radiance RGBE `.hdr` (the `image` crate's encoder).
pub(crate) fn save_hdr(path: &Path, width: usize, texels: &[Vec3]) -> Result<(), EnvError> {
    let height = texels.len() / width.max(1);
    let file = std::fs::File::create(path).map_err(|source| EnvError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let px: Vec<image::Rgb<f32>> = texels.iter().map(|t| image::Rgb(t.to_array())).collect();
    image::codecs::hdr::HdrEncoder::new(std::io::BufWriter::new(file))
        .encode(&px, width, height)
        .map_err(|e| EnvError::Decode {
            path: path.to_path_buf(),
            message: format!("cannot write HDR: {e}"),
        })
}
