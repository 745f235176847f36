// probekit_bricks.wgsl — sampling an adaptive (octree) volume from the
// brick atlas that `probekit export --format ktx2 --layout bricks` writes
// (crates/probekit/src/volume/export/bricks.rs): an indirection texture of
// N = roots·2^Di texels per axis over the box, whose RGBA8UI texel holds a
// brick's position in the atlas (in bricks) and its level, and an atlas of
// bricks of 5³ texels, each the octree's trilinear query sampled at the
// corners and quarter points of one octree node. Concatenate after
// probekit.wgsl and probekit_buffers.wgsl.
//
// Everything comes from one u32 storage buffer, `pk_bricks`, that
// `probekit_shaders::layout::pack_bricks` fills from the exported textures
// (the level-0 bytes of each KTX2 file, unchanged): a 24-word header
// (PK_BRICKS_H_*), the indirection texels (one word each, r | g<<8 | b<<16
// | level<<24), then the atlas textures in sidecar order. docs/shaders.md
// lists the layout.

@group(0) @binding(4) var<storage, read> pk_bricks: array<u32>;

// Header words of pk_bricks (probekit_shaders::layout::BRICKS_HEADER).
const PK_BRICKS_H_ENCODING: u32 = 0u;
const PK_BRICKS_H_COEFFS: u32 = 1u;
const PK_BRICKS_H_MIN: u32 = 2u;
const PK_BRICKS_H_MAX: u32 = 5u;
const PK_BRICKS_H_CELLS: u32 = 8u;
const PK_BRICKS_H_ATLAS: u32 = 11u;
const PK_BRICKS_H_INDIRECTION: u32 = 14u;
const PK_BRICKS_H_TEXELS: u32 = 15u;
const PK_BRICKS_H_RATIO_BOUNDS: u32 = 16u;

/// Atlas encodings (header word PK_BRICKS_H_ENCODING): the export's
/// `--encoding f16` (RGBA16F textures of 4 floats c0.r, c0.g, c0.b, c1.r, …)
/// and `--encoding quantized` (an RGB9E5 DC texture, then RGBA8_SNORM
/// textures of c_i / c_0 / bound_i).
const PK_BRICKS_F16: u32 = 0u;
const PK_BRICKS_QUANTIZED: u32 = 1u;
/// Texels per brick edge (bricks::BRICK_CELLS + 1).
const PK_BRICK_TEXELS: u32 = 5u;

fn pk_bricks_f(i: u32) -> f32 {
    return bitcast<f32>(pk_bricks[i]);
}

fn pk_bricks_v3(i: u32) -> vec3<f32> {
    return vec3<f32>(pk_bricks_f(i), pk_bricks_f(i + 1u), pk_bricks_f(i + 2u));
}

fn pk_bricks_u3(i: u32) -> vec3<u32> {
    return vec3<u32>(pk_bricks[i], pk_bricks[i + 1u], pk_bricks[i + 2u]);
}

/// Radiance SH of atlas texel `t` (index x + ax·(y + ay·z)), decoded as the
/// export encoded it (lattice::encode_sh_textures): L2, zero past the
/// stored order² (at most 9 coefficients read).
fn pk_bricks_texel(t: u32) -> PkShL2 {
    let n = min(pk_bricks[PK_BRICKS_H_COEFFS], 9u);
    let a = pk_bricks_u3(PK_BRICKS_H_ATLAS);
    let texels = a.x * a.y * a.z;
    let base = pk_bricks[PK_BRICKS_H_TEXELS];
    var out: PkShL2;
    if pk_bricks[PK_BRICKS_H_ENCODING] == PK_BRICKS_F16 {
        for (var f = 0u; f < 3u * n; f = f + 1u) {
            let g = f / 4u;
            let comp = f % 4u;
            let word = pk_bricks[base + 2u * (g * texels + t) + comp / 2u];
            out.c[f / 3u][f % 3u] = pk_decode_f16(word >> (16u * (comp & 1u)));
        }
    } else {
        let dc = pk_decode_rgb9e5(pk_bricks[base + t]);
        out.c[0] = dc;
        for (var f = 0u; f + 3u < 3u * n; f = f + 1u) {
            let g = f / 4u;
            let comp = f % 4u;
            let b = (pk_bricks[base + texels * (1u + g) + t] >> (8u * comp)) & 0xffu;
            let i = 1u + f / 3u;
            let ch = f % 3u;
            out.c[i][ch] = pk_unsnorm8(b) * pk_bricks_f(PK_BRICKS_H_RATIO_BOUNDS + i - 1u) * dc[ch];
        }
    }
    return out;
}

/// Where a point falls in the brick atlas: `coord`, the atlas texel
/// coordinate in texel-centre units (texel k's centre at k; add 0.5 and
/// divide by the atlas resolution for a normalized hardware-sampling
/// coordinate), and `brick`, the first texel of its brick.
struct PkBrickLookup {
    coord: vec3<f32>,
    brick: vec3<u32>,
}

/// The lookup of bricks.rs: uvw = (p − min)/(max − min) (p clamped to the
/// box), g = uvw·N, c = ⌊g⌋, (b, level) = indirection[c], s = 2^level,
/// o = ⌊c/s⌋·s, f = (g − o)/s ∈ [0, 1]³, coordinate b·5 + 4f.
fn pk_bricks_lookup(pos: vec3<f32>) -> PkBrickLookup {
    let lo = pk_bricks_v3(PK_BRICKS_H_MIN);
    let hi = pk_bricks_v3(PK_BRICKS_H_MAX);
    let cells = pk_bricks_u3(PK_BRICKS_H_CELLS);
    let p = clamp(pos, lo, hi);
    let g = (p - lo) / (hi - lo) * vec3<f32>(cells);
    let c = min(vec3<u32>(max(floor(g), vec3<f32>(0.0))), cells - vec3<u32>(1u));
    let texel = pk_bricks[pk_bricks[PK_BRICKS_H_INDIRECTION] + c.x + cells.x * (c.y + cells.y * c.z)];
    let b = vec3<u32>(texel & 0xffu, (texel >> 8u) & 0xffu, (texel >> 16u) & 0xffu);
    let s = 1u << (texel >> 24u);
    let o = (c / s) * s;
    let f = clamp((g - vec3<f32>(o)) / f32(s), vec3<f32>(0.0), vec3<f32>(1.0));
    let brick = b * PK_BRICK_TEXELS;
    return PkBrickLookup(vec3<f32>(brick) + f32(PK_BRICK_TEXELS - 1u) * f, brick);
}

/// Radiance SH at world position `pos` of an octree volume from its brick
/// atlas: the indirection lookup of `pk_bricks_lookup`, then trilinear
/// interpolation of the decoded texels inside the brick (what a hardware
/// trilinear fetch of an f16 atlas gives, at full f32 weight precision; a
/// quantized atlas is decoded before interpolating). Matches
/// probekit_runtime::volume::Volume::sample_sh (Interp::Trilinear) at the
/// brick texels up to the encoding's rounding, and in between up to the
/// interpolation between them (docs/shaders.md gives the measured
/// differences).
fn pk_bricks_sh_l2(pos: vec3<f32>) -> PkShL2 {
    let l = pk_bricks_lookup(pos);
    let a = pk_bricks_u3(PK_BRICKS_H_ATLAS);
    let i0 = min(vec3<u32>(floor(l.coord)), l.brick + vec3<u32>(PK_BRICK_TEXELS - 2u));
    let fr = l.coord - vec3<f32>(i0);
    var out: PkShL2;
    for (var corner = 0u; corner < 8u; corner = corner + 1u) {
        let o = vec3<u32>(corner & 1u, (corner >> 1u) & 1u, (corner >> 2u) & 1u);
        let wv = select(vec3<f32>(1.0) - fr, fr, o == vec3<u32>(1u));
        let w = wv.x * wv.y * wv.z;
        let q = i0 + o;
        let sh = pk_bricks_texel(q.x + a.x * (q.y + a.y * q.z));
        for (var c = 0u; c < 9u; c = c + 1u) {
            out.c[c] = out.c[c] + sh.c[c] * w;
        }
    }
    return out;
}

/// Irradiance (not divided by π) at `pos` for unit normal `n` of an octree
/// volume's brick atlas.
fn pk_bricks_irradiance(pos: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return pk_irradiance_l2(pk_bricks_sh_l2(pos), n);
}

/// The same by hallucinated ZH3 from the interpolated bands ≤ 1 (an L1
/// volume's option).
fn pk_bricks_irradiance_zh3(pos: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return pk_irradiance_zh3_hallucinated(pk_l2_to_l1(pk_bricks_sh_l2(pos)), n);
}
