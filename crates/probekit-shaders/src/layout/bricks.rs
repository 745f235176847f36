//! `pk_bricks`: a brick-atlas export for `shaders/probekit_bricks.wgsl`.

use super::{check_size, LayoutError};

/// Words of the header at the start of `pk_bricks`.
pub const BRICKS_HEADER_WORDS: usize = 24;

/// The header words of `pk_bricks`, by their WGSL constant names
/// (`shaders/probekit_bricks.wgsl`; a test checks that the two agree):
/// encoding (0 f16, 1 quantized), coefficients per texel (order²), box min
/// and max (3 f32 each), indirection texels per axis, atlas texels per
/// axis (3 u32 each), the word offsets of the indirection texels and of the
/// atlas, and the quantized encoding's ratio bounds of coefficients 1–8
/// (8 f32).
pub const BRICKS_HEADER: [(&str, usize); 9] = [
    ("PK_BRICKS_H_ENCODING", 0),
    ("PK_BRICKS_H_COEFFS", 1),
    ("PK_BRICKS_H_MIN", 2),
    ("PK_BRICKS_H_MAX", 5),
    ("PK_BRICKS_H_CELLS", 8),
    ("PK_BRICKS_H_ATLAS", 11),
    ("PK_BRICKS_H_INDIRECTION", 14),
    ("PK_BRICKS_H_TEXELS", 15),
    ("PK_BRICKS_H_RATIO_BOUNDS", 16),
];

/// Texels per brick edge (`probekit::volume::export::BRICK_CELLS + 1`).
const BRICK_TEXELS: u32 = 5;

/// How the atlas textures store coefficients (the export's `--encoding`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BrickEncoding {
    /// `sh_f16_{g}.ktx2`: RGBA16F textures holding the floats `c0.r, c0.g,
    /// c0.b, c1.r, …` four by four.
    F16,
    /// `sh_dc_rgb9e5.ktx2` (the DC in RGB9E5), then `sh_ratio_snorm8_{g}.ktx2`
    /// (RGBA8_SNORM textures of `c_i / c_0 / bound_i`, channel by channel).
    Quantized,
}

/// A brick atlas as `probekit export --format ktx2 --layout bricks` writes
/// it: the numbers of its `volume.json` and the level-0 data of its KTX2
/// files.
#[derive(Clone, Copy, Debug)]
pub struct BrickAtlas<'a> {
    /// The textures' encoding (`"encoding"`).
    pub encoding: BrickEncoding,
    /// SH coefficients per texel, `sh_order²` (`"sh_order"` squared).
    pub coeffs: u32,
    /// Box minimum corner, metres (`"box"."min"`).
    pub min: [f32; 3],
    /// Box maximum corner (`"box"."max"`).
    pub max: [f32; 3],
    /// Indirection texels per axis (`"indirection"."resolution"`).
    pub cells: [u32; 3],
    /// Atlas texels per axis (`"atlas_resolution"`).
    pub atlas: [u32; 3],
    /// `"ratio_bounds"` (bound of coefficient `i ≥ 1` at `i − 1`; quantized
    /// only, may be empty for f16).
    pub ratio_bounds: &'a [f32],
    /// `indirection_rgba8ui.ktx2`'s texels: 4 bytes each, x fastest.
    pub indirection: &'a [u8],
    /// The atlas textures' texels in sidecar order (x fastest): 8 bytes
    /// per texel for f16, 4 for quantized.
    pub textures: &'a [&'a [u8]],
}

/// Packs a brick atlas into the `pk_bricks` buffer: the header, the
/// indirection texels as words, then the atlas textures' bytes unchanged.
/// Checks every size and that every indirection texel names a brick inside
/// the atlas.
pub fn pack_bricks(atlas: &BrickAtlas<'_>) -> Result<Vec<u32>, LayoutError> {
    let bad = |m: String| Err(LayoutError::Bricks(m));
    let n = atlas.coeffs as usize;
    let cells: usize = atlas.cells.iter().map(|&c| c as usize).product();
    let texels: usize = atlas.atlas.iter().map(|&c| c as usize).product();
    if n == 0 || cells == 0 || texels == 0 {
        return bad("an empty size".into());
    }
    let (textures, bytes) = match atlas.encoding {
        BrickEncoding::F16 => ((3 * n).div_ceil(4), 8),
        BrickEncoding::Quantized => (1 + (3 * (n - 1)).div_ceil(4), 4),
    };
    if atlas.textures.len() != textures {
        return bad(format!(
            "{} textures for {n} coefficients, expected {textures}",
            atlas.textures.len()
        ));
    }
    if let Some((g, t)) = atlas
        .textures
        .iter()
        .enumerate()
        .find(|(_, t)| t.len() != texels * bytes)
    {
        return bad(format!(
            "texture {g} holds {} bytes, expected {}",
            t.len(),
            texels * bytes
        ));
    }
    if atlas.indirection.len() != 4 * cells {
        return bad(format!(
            "indirection holds {} bytes, expected {}",
            atlas.indirection.len(),
            4 * cells
        ));
    }
    if atlas.encoding == BrickEncoding::Quantized && atlas.ratio_bounds.len() < (n - 1).min(8) {
        return bad("too few ratio bounds".into());
    }
    let bricks = atlas.atlas.map(|a| a / BRICK_TEXELS);
    for t in atlas.indirection.chunks_exact(4) {
        if (0..3).any(|a| t[a] as u32 >= bricks[a]) || t[3] >= 32 {
            return bad(format!("indirection texel {t:?} outside the atlas"));
        }
    }
    let total = BRICKS_HEADER_WORDS + cells + textures * texels * bytes / 4;
    check_size("bricks", total)?;
    let mut w = vec![0u32; BRICKS_HEADER_WORDS];
    w[0] = match atlas.encoding {
        BrickEncoding::F16 => 0,
        BrickEncoding::Quantized => 1,
    };
    w[1] = atlas.coeffs;
    for a in 0..3 {
        w[2 + a] = atlas.min[a].to_bits();
        w[5 + a] = atlas.max[a].to_bits();
        w[8 + a] = atlas.cells[a];
        w[11 + a] = atlas.atlas[a];
    }
    for (k, b) in atlas.ratio_bounds.iter().take(8).enumerate() {
        w[16 + k] = b.to_bits();
    }
    w[14] = w.len() as u32;
    w.extend(
        atlas
            .indirection
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
    );
    w[15] = w.len() as u32;
    for t in atlas.textures {
        w.extend(
            t.chunks_exact(4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        );
    }
    Ok(w)
}
