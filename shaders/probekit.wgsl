// probekit.wgsl — probekit's shader library: evaluation of diffuse lighting
// stored as spherical harmonics (SH) and related bases, and decoding of the
// quantized probe codecs.
//
// Pure functions only (no bindings): concatenate this file in front of your
// shader. `probekit_buffers.wgsl` adds storage-buffer access (codecs from a
// u32 buffer, uniform volumes: trilinear, Taylor, tricubic),
// `probekit_cloud.wgsl` probe-cloud blending and `probekit_bricks.wgsl`
// octree volumes from their brick atlas. docs/shaders.md explains the
// buffer layouts; every function here reproduces the Rust function named in
// its comment (crates/probekit-sh, crates/probekit-runtime), and the tests
// of crates/probekit-shaders compare them on random inputs and baked files.
//
// Conventions (crates/probekit-sh/src/lib.rs): right-handed, +Y up; linear
// RGB; real SH indexed l*(l+1)+m with Sloan's Condon–Shortley phase
// (Y1,-1 = -0.4886·y, Y1,0 = 0.4886·z, Y1,1 = -0.4886·x). Inputs are RADIANCE
// SH; irradiance outputs are E(n) = ∫ L(ω) max(0, n·ω) dω, NOT divided by π
// (clamped-cosine bands π, 2π/3, π/4: Ramamoorthi & Hanrahan 2001). Diffuse
// reflected radiance is albedo · E / π. Normals must be unit length.

// --- constants (probekit_sh::basis) -----------------------------------------

const PK_PI: f32 = 3.14159265358979;
const PK_Y00: f32 = 0.2820948;
const PK_Y1: f32 = 0.4886025;
const PK_Y2_A: f32 = 1.0925485;
const PK_Y2_B: f32 = 0.31539157;
const PK_Y2_C: f32 = 0.5462742;
// Clamped-cosine band factors Â_l (probekit_sh::convolve::clamped_cosine_band).
const PK_A0: f32 = 3.14159265358979;
const PK_A1: f32 = 2.09439510239320;
const PK_A2: f32 = 0.78539816339745;
// Rec. 709 luminance weights (probekit_sh::LUMINANCE).
const PK_LUMINANCE: vec3<f32> = vec3<f32>(0.2126, 0.7152, 0.0722);
// Ratio ranges of the quantized codecs (probekit_sh::codec::ratio_range):
// band 1 is [-√3, √3], band 2 (m ≠ 0) [-√15/2, √15/2], band 2 m = 0 and the ZH3
// zonal coefficient [-√5/2, √5] (mid √5/4, half-width 3√5/4).
const PK_RATIO_L1: f32 = 1.7320508;
const PK_RATIO_L2: f32 = 1.9364917;
const PK_RATIO_ZONAL_MID: f32 = 0.5590170;
const PK_RATIO_ZONAL_HALF: f32 = 1.6770510;

// --- types (field names as in the Rust structs) -----------------------------

/// L1 radiance SH, RGB: `c[l*(l+1)+m]` (Rust `[Vec3; 4]`).
struct PkShL1 {
    c: array<vec3<f32>, 4>,
}

/// L2 radiance SH, RGB: `c[l*(l+1)+m]` (Rust `[Vec3; 9]`).
struct PkShL2 {
    c: array<vec3<f32>, 9>,
}

/// Stored ZH3 (Rust `probekit_sh::zh3::Zh3`): L1 radiance, one zonal band-2
/// coefficient per channel and each channel's unit zonal axis.
struct PkZh3 {
    l1: array<vec3<f32>, 4>,
    zonal: vec3<f32>,
    axes: array<vec3<f32>, 3>,
}

/// Valve ambient cube (Rust `probekit_sh::ambient_cube::AmbientCube`): six
/// IRRADIANCE values, faces +X, -X, +Y, -Y, +Z, -Z.
struct PkAmbientCube {
    faces: array<vec3<f32>, 6>,
}

/// A uniform probe volume (Rust `probekit_runtime::format::VolumeGrid`):
/// box corners in metres and probes per axis; probes sit at the corners of
/// `resolution - 1` cells per axis, probe (i, j, k) at index
/// `i + rx·(j + ry·k)`; `gradient_coeffs`: how many coefficients per probe
/// have stored gradients (the `GRAD` section's order², 0 without
/// gradients, at most 9 read). As a uniform: min at byte 0, max at 16,
/// resolution at 32, gradient_coeffs at 44, 48 bytes.
struct PkVolumeGrid {
    min: vec3<f32>,
    max: vec3<f32>,
    resolution: vec3<u32>,
    gradient_coeffs: u32,
}

// --- SH basis and irradiance -------------------------------------------------

/// The L1 basis at unit `d` (probekit_sh::basis::eval_l1).
fn pk_eval_l1(d: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(PK_Y00, -PK_Y1 * d.y, PK_Y1 * d.z, -PK_Y1 * d.x);
}

/// The L2 basis at unit `d` (probekit_sh::basis::eval_l2).
fn pk_eval_l2(d: vec3<f32>) -> array<f32, 9> {
    let x = d.x;
    let y = d.y;
    let z = d.z;
    return array<f32, 9>(
        PK_Y00,
        -PK_Y1 * y,
        PK_Y1 * z,
        -PK_Y1 * x,
        PK_Y2_A * x * y,
        -PK_Y2_A * y * z,
        PK_Y2_B * (3.0 * z * z - 1.0),
        -PK_Y2_A * x * z,
        PK_Y2_C * (x * x - y * y),
    );
}

/// Radiance of L2 SH in direction `d` (probekit_sh::convolve::eval_sh).
fn pk_radiance_l2(sh: PkShL2, d: vec3<f32>) -> vec3<f32> {
    var b = pk_eval_l2(d);
    var e = vec3<f32>(0.0);
    for (var i = 0u; i < 9u; i = i + 1u) {
        e = e + sh.c[i] * b[i];
    }
    return e;
}

/// Irradiance (not divided by π) at unit normal `n` from L1 radiance SH
/// (probekit_sh::convolve::irradiance_l1; Ramamoorthi & Hanrahan 2001).
fn pk_irradiance_l1(sh: PkShL1, n: vec3<f32>) -> vec3<f32> {
    return sh.c[0] * (PK_A0 * PK_Y00)
        + (sh.c[1] * -n.y + sh.c[2] * n.z + sh.c[3] * -n.x) * (PK_A1 * PK_Y1);
}

/// Irradiance (not divided by π) at unit normal `n` from L2 radiance SH
/// (probekit_sh::convolve::irradiance_l2; Ramamoorthi & Hanrahan 2001).
fn pk_irradiance_l2(sh: PkShL2, n: vec3<f32>) -> vec3<f32> {
    let b = pk_eval_l2(n);
    return sh.c[0] * (PK_A0 * b[0])
        + (sh.c[1] * b[1] + sh.c[2] * b[2] + sh.c[3] * b[3]) * PK_A1
        + (sh.c[4] * b[4] + sh.c[5] * b[5] + sh.c[6] * b[6] + sh.c[7] * b[7] + sh.c[8] * b[8]) * PK_A2;
}

/// The L1 part of L2 SH.
fn pk_l2_to_l1(sh: PkShL2) -> PkShL1 {
    return PkShL1(array<vec3<f32>, 4>(sh.c[0], sh.c[1], sh.c[2], sh.c[3]));
}

// --- Geomerics L1 -------------------------------------------------------------

fn pk_geomerics_channel(c0: f32, v: vec3<f32>, n: vec3<f32>) -> f32 {
    // `!(c0 > 0)` also rejects NaN where the platform keeps NaNs.
    if !(c0 > 0.0) {
        return 0.0;
    }
    let r0 = PK_PI * PK_Y00 * c0;
    let len = length(v);
    if !(len > 0.0) {
        return r0;
    }
    let ratio = clamp(len / (1.7320508 * c0), 0.0, 1.0);
    let dir = v / len;
    let q = clamp(0.5 * (1.0 + dot(dir, n)), 0.0, 1.0);
    let p = 1.0 + 2.0 * ratio;
    let a = (1.0 - ratio) / (1.0 + ratio);
    // pow(0, p) is left undefined by some platforms; q^p is 0 there (p ≥ 1).
    var qp = 0.0;
    if q > 0.0 {
        qp = pow(q, p);
    }
    return r0 * (a + (1.0 - a) * (p + 1.0) * qp);
}

/// Geomerics' non-negative irradiance (not divided by π) at unit normal `n`
/// from L1 radiance SH (probekit_sh::geomerics::irradiance_geomerics_l1;
/// Hazel/Geomerics via Pettineo, SG Series Part 1, and Roughton et al. 2024).
fn pk_irradiance_geomerics_l1(sh: PkShL1, n: vec3<f32>) -> vec3<f32> {
    var out = vec3<f32>(0.0);
    for (var ch = 0u; ch < 3u; ch = ch + 1u) {
        let v = vec3<f32>(-sh.c[3][ch], -sh.c[1][ch], sh.c[2][ch]);
        out[ch] = pk_geomerics_channel(sh.c[0][ch], v, n);
    }
    return out;
}

// --- ZH3 (Roughton, Sloan, Silvennoinen, Iwanicki, Drobot, I3D 2024) --------

/// The normalised band-1 vector of the luminance of `l1`, or (0, 0, 0) when
/// it has none (probekit_sh::zh3::luminance_axis, `None` ↦ zero vector).
fn pk_luminance_axis(l1: array<vec3<f32>, 4>) -> vec3<f32> {
    let v = vec3<f32>(-dot(l1[3], PK_LUMINANCE), -dot(l1[1], PK_LUMINANCE), dot(l1[2], PK_LUMINANCE));
    let len = length(v);
    if len > 1e-30 {
        return v / len;
    }
    return vec3<f32>(0.0);
}

/// The shared ZH3 axis: the luminance axis, or +Y when there is none
/// (probekit_sh::zh3::shared_axis).
fn pk_shared_axis(l1: array<vec3<f32>, 4>) -> vec3<f32> {
    let a = pk_luminance_axis(l1);
    if dot(a, a) > 0.0 {
        return a;
    }
    return vec3<f32>(0.0, 1.0, 0.0);
}

/// Irradiance (not divided by π) at unit normal `n` of stored ZH3
/// (probekit_sh::zh3::Zh3::irradiance): L1 irradiance plus
/// (π/4)·zonal·Y2,0(axis·n) per channel.
fn pk_irradiance_zh3(zh: PkZh3, n: vec3<f32>) -> vec3<f32> {
    let t = vec3<f32>(dot(zh.axes[0], n), dot(zh.axes[1], n), dot(zh.axes[2], n));
    return pk_irradiance_l1(PkShL1(zh.l1), n)
        + zh.zonal * (3.0 * t * t - vec3<f32>(1.0)) * (0.25 * PK_PI * PK_Y2_B);
}

/// Hallucinated ZH3 as a PkZh3 (probekit_sh::zh3::zh3_hallucinate): shared
/// luminance axis and per channel zonal = c0·(0.08·r + 0.6·r²),
/// r = |v·axis|/c0; channels with c0 ≤ 0 or L1 without a luminance axis get 0.
fn pk_zh3_hallucinate(l1: array<vec3<f32>, 4>) -> PkZh3 {
    let a = pk_luminance_axis(l1);
    var zonal = vec3<f32>(0.0);
    var axis = vec3<f32>(0.0, 1.0, 0.0);
    if dot(a, a) > 0.0 {
        axis = a;
        for (var ch = 0u; ch < 3u; ch = ch + 1u) {
            let c0 = l1[0][ch];
            if c0 > 0.0 {
                let v = vec3<f32>(-l1[3][ch], -l1[1][ch], l1[2][ch]);
                let r = abs(dot(v, a)) / c0;
                zonal[ch] = c0 * (0.08 * r + 0.6 * r * r);
            }
        }
    }
    return PkZh3(l1, zonal, array<vec3<f32>, 3>(axis, axis, axis));
}

/// Irradiance (not divided by π) at unit normal `n` from L1 radiance SH by
/// hallucinated ZH3 (probekit_sh::zh3::zh3_hallucinated_irradiance; Roughton et al. 2024,
/// `SHHallucinateZH3Irradiance`, kernel π/4 for our unnormalised cosine).
fn pk_irradiance_zh3_hallucinated(sh: PkShL1, n: vec3<f32>) -> vec3<f32> {
    return pk_irradiance_zh3(pk_zh3_hallucinate(sh.c), n);
}

// --- ambient cube (McTaggart, GDC 2004; Mitchell et al. 2006) ----------------

/// Irradiance at unit normal `n` of an ambient cube: Σ_i n_i²·face(i, sign n_i)
/// (probekit_sh::ambient_cube::AmbientCube::irradiance; n_i = 0 picks the
/// positive face with weight 0).
fn pk_irradiance_ambient_cube(cube: PkAmbientCube, n: vec3<f32>) -> vec3<f32> {
    let n2 = n * n;
    let fx = select(cube.faces[0], cube.faces[1], n.x < 0.0);
    let fy = select(cube.faces[2], cube.faces[3], n.y < 0.0);
    let fz = select(cube.faces[4], cube.faces[5], n.z < 0.0);
    return fx * n2.x + fy * n2.y + fz * n2.z;
}

// --- blending -----------------------------------------------------------------

/// Σ w_k·sh_k over four L1 probes (blending in a tetrahedron: weights sum
/// to 1; take them from the runtime's `ProbeCloud::weights_at` or the C
/// ABI's `pk_cloud_weights`, which include per-probe visibility when the
/// file stores distance moments).
fn pk_blend_l1(a: PkShL1, b: PkShL1, c: PkShL1, d: PkShL1, w: vec4<f32>) -> PkShL1 {
    var out: PkShL1;
    for (var i = 0u; i < 4u; i = i + 1u) {
        out.c[i] = a.c[i] * w.x + b.c[i] * w.y + c.c[i] * w.z + d.c[i] * w.w;
    }
    return out;
}

/// Σ w_k·sh_k over four L2 probes (blending in a tetrahedron: weights sum
/// to 1; take them from the runtime's `ProbeCloud::weights_at` or the C
/// ABI's `pk_cloud_weights`, which include per-probe visibility when the
/// file stores distance moments).
fn pk_blend_l2(a: PkShL2, b: PkShL2, c: PkShL2, d: PkShL2, w: vec4<f32>) -> PkShL2 {
    var out: PkShL2;
    for (var i = 0u; i < 9u; i = i + 1u) {
        out.c[i] = a.c[i] * w.x + b.c[i] * w.y + c.c[i] * w.z + d.c[i] * w.w;
    }
    return out;
}

/// The trilinear cell of a position in a uniform volume: lower corner
/// (probe coordinates), fractions in it, and the cell size per axis
/// (metres; 0 on an axis with one probe).
struct PkVolumeCell {
    corner: vec3<u32>,
    frac: vec3<f32>,
    size: vec3<f32>,
}

/// The trilinear cell of `pos` in `grid`, positions clamped to the box; an
/// axis with one probe has corner 0, fraction 0 and size 0 (the grid branch
/// of probekit_runtime::volume::Volume::sample_sh, same arithmetic).
fn pk_volume_cell(grid: PkVolumeGrid, pos: vec3<f32>) -> PkVolumeCell {
    let p = clamp(pos, grid.min, grid.max);
    var cell: PkVolumeCell;
    for (var a = 0u; a < 3u; a = a + 1u) {
        let r = grid.resolution[a];
        if r < 2u {
            continue;
        }
        let h = (grid.max[a] - grid.min[a]) / f32(r - 1u);
        var x = 0.0;
        if h > 0.0 {
            x = (p[a] - grid.min[a]) / h;
        }
        let i = min(u32(max(floor(x), 0.0)), r - 2u);
        cell.corner[a] = i;
        cell.frac[a] = clamp(x - f32(i), 0.0, 1.0);
        cell.size[a] = h;
    }
    return cell;
}

/// Index of probe (i, j, k) of `grid`: i + rx·(j + ry·k), coordinates clamped
/// to the grid.
fn pk_volume_index(grid: PkVolumeGrid, ijk: vec3<u32>) -> u32 {
    let res = max(grid.resolution, vec3<u32>(1u));
    let c = min(ijk, res - vec3<u32>(1u));
    return c.x + res.x * (c.y + res.y * c.z);
}

// --- quantized codecs (probekit_sh::codec) -----------------------------------

/// RGB9E5 word → linear RGB: mantissas in bits 0–8, 9–17, 18–26, shared
/// exponent in 27–31 (bias 15), value m·2^(e−24)
/// (probekit_sh::codec::decode_rgb9e5; GL_EXT_texture_shared_exponent).
fn pk_decode_rgb9e5(x: u32) -> vec3<f32> {
    let e = i32(x >> 27u) - 24;
    let m = vec3<f32>(f32(x & 0x1ffu), f32((x >> 9u) & 0x1ffu), f32((x >> 18u) & 0x1ffu));
    // ldexp is exact (exp2 of an integer need not be on every platform).
    return ldexp(m, vec3<i32>(e));
}

/// IEEE binary16 in the low 16 bits of `h` → f32, exactly (what
/// `unpack2x16float` gives, without the float16 capability it needs in
/// naga; probekit_runtime::format::f16_to_f32).
fn pk_decode_f16(h: u32) -> f32 {
    let sign = (h & 0x8000u) << 16u;
    let e = (h >> 10u) & 0x1fu;
    let m = h & 0x3ffu;
    if e == 0u {
        // Zero and subnormals: m·2^−24, exact in f32.
        let v = ldexp(f32(m), -24);
        return select(v, -v, sign != 0u);
    }
    if e == 31u {
        return bitcast<f32>(sign | 0x7f800000u | (m << 13u));
    }
    return bitcast<f32>(sign | ((e + 112u) << 23u) | (m << 13u));
}

/// Byte `i` of a little-endian word window.
fn pk_window_byte(w: ptr<function, array<u32, 8>>, i: u32) -> u32 {
    return ((*w)[i >> 2u] >> ((i & 3u) * 8u)) & 0xffu;
}

/// Little-endian u32 at byte `i` (any alignment) of a word window.
fn pk_window_u32(w: ptr<function, array<u32, 8>>, i: u32) -> u32 {
    return pk_window_byte(w, i) | (pk_window_byte(w, i + 1u) << 8u)
        | (pk_window_byte(w, i + 2u) << 16u) | (pk_window_byte(w, i + 3u) << 24u);
}

/// snorm8 byte → [-1, 1]: max(i8 / 127, -1) (probekit_sh::codec, `unsnorm8`).
fn pk_unsnorm8(b: u32) -> f32 {
    let s = (i32(b << 24u)) >> 24u;
    return max(f32(s) / 127.0, -1.0);
}

/// A ratio-coded coefficient: c0·(mid + half_width·unsnorm8(b)), 0 when c0 ≤ 0
/// (probekit_sh::codec, `decode_ratio`).
fn pk_decode_ratio(b: u32, c0: f32, mid: f32, half_width: f32) -> f32 {
    if !(c0 > 0.0) {
        return 0.0;
    }
    return c0 * (mid + half_width * pk_unsnorm8(b));
}

/// Decodes an L1 probe (13 bytes: DC RGB9E5, then snorm8 ratio of
/// coefficient i = 1..3, channel ch at byte 4 + 3(i−1) + ch) that starts at
/// byte `start` (0..3) of the word window `w`
/// (probekit_sh::codec::decode_l1; Roughton et al. 2024).
fn pk_decode_l1_window(w: ptr<function, array<u32, 8>>, start: u32) -> PkShL1 {
    var out: PkShL1;
    let c0 = pk_decode_rgb9e5(pk_window_u32(w, start));
    out.c[0] = c0;
    for (var i = 1u; i < 4u; i = i + 1u) {
        for (var ch = 0u; ch < 3u; ch = ch + 1u) {
            let b = pk_window_byte(w, start + 4u + 3u * (i - 1u) + ch);
            out.c[i][ch] = pk_decode_ratio(b, c0[ch], 0.0, PK_RATIO_L1);
        }
    }
    return out;
}

/// Decodes an L2 probe (28 bytes: DC RGB9E5, then snorm8 ratio of
/// coefficient i = 1..8, channel ch at byte 4 + 3(i−1) + ch) that starts at
/// byte `start` (0..3) of the word window `w` (probekit_sh::codec::decode_l2).
fn pk_decode_l2_window(w: ptr<function, array<u32, 8>>, start: u32) -> PkShL2 {
    var out: PkShL2;
    let c0 = pk_decode_rgb9e5(pk_window_u32(w, start));
    out.c[0] = c0;
    for (var i = 1u; i < 9u; i = i + 1u) {
        var mid = 0.0;
        var half_width = PK_RATIO_L2;
        if i < 4u {
            half_width = PK_RATIO_L1;
        } else if i == 6u {
            mid = PK_RATIO_ZONAL_MID;
            half_width = PK_RATIO_ZONAL_HALF;
        }
        for (var ch = 0u; ch < 3u; ch = ch + 1u) {
            let b = pk_window_byte(w, start + 4u + 3u * (i - 1u) + ch);
            out.c[i][ch] = pk_decode_ratio(b, c0[ch], mid, half_width);
        }
    }
    return out;
}

/// Decodes a shared-axis ZH3 probe (16 bytes: the L1 layout, then the zonal
/// coefficient R, G, B in the [-√5/2, √5] ratio range) that starts at byte
/// `start` (0..3) of the word window `w`; the axis is the shared axis of the
/// decoded L1 (probekit_sh::codec::decode_zh3).
fn pk_decode_zh3_window(w: ptr<function, array<u32, 8>>, start: u32) -> PkZh3 {
    let l1 = pk_decode_l1_window(w, start);
    let axis = pk_shared_axis(l1.c);
    var zonal = vec3<f32>(0.0);
    for (var ch = 0u; ch < 3u; ch = ch + 1u) {
        let b = pk_window_byte(w, start + 13u + ch);
        zonal[ch] = pk_decode_ratio(b, l1.c[0][ch], PK_RATIO_ZONAL_MID, PK_RATIO_ZONAL_HALF);
    }
    return PkZh3(l1.c, zonal, array<vec3<f32>, 3>(axis, axis, axis));
}

/// Decodes an ambient cube (24 bytes: six RGB9E5 words, faces +X, −X, +Y,
/// −Y, +Z, −Z) that starts at byte `start` (0..3) of the word window `w`
/// (probekit_sh::codec::decode_ambient_cube).
fn pk_decode_ambient_cube_window(w: ptr<function, array<u32, 8>>, start: u32) -> PkAmbientCube {
    var cube: PkAmbientCube;
    for (var k = 0u; k < 6u; k = k + 1u) {
        cube.faces[k] = pk_decode_rgb9e5(pk_window_u32(w, start + 4u * k));
    }
    return cube;
}

// --- cloud blending helpers (probekit_runtime::cloud) ------------------------
// Pure parts of the blend of probekit_cloud.wgsl: the Freudenthal–Kuhn
// interpolation of cell visibility bits, the octahedral map and Chebyshev
// test of the distance moments, and renormalization.

/// DDGI's crush threshold and visibility floor
/// (probekit_runtime::cloud::visibility::VISIBILITY_CRUSH, VISIBILITY_FLOOR).
const PK_VISIBILITY_CRUSH: f32 = 0.2;
const PK_VISIBILITY_FLOOR: f32 = 1e-4;

/// Lattice index of the point with cumulative numerators `c` in a cell with
/// `vertices` corners (cell_visibility::lattice, `lattice_index`).
fn pk_lattice_index(vertices: u32, c: vec3<u32>) -> u32 {
    let tri = c.y * (c.y + 1u) / 2u;
    if vertices == 3u {
        return tri + c.x;
    }
    return c.z * (c.z + 1u) * (c.z + 2u) / 6u + tri + c.x;
}

/// Lattice points of a cell with `vertices` corners at subdivision `k`
/// (cell_visibility::lattice_len).
fn pk_lattice_len(vertices: u32, k: u32) -> u32 {
    if vertices == 3u {
        return (k + 1u) * (k + 2u) / 2u;
    }
    return (k + 1u) * (k + 2u) * (k + 3u) / 6u;
}

/// The Freudenthal–Kuhn sub-simplex holding a point: its lattice indices
/// and the point's weights in it (unused fourth slot of a hull face: 0).
struct PkKuhn {
    idx: vec4<u32>,
    w: vec4<f32>,
}

/// `before(a, b)`: axis a sorts before axis b (decreasing fraction, ties
/// the higher axis first).
fn pk_kuhn_before(f: vec3<f32>, a: u32, b: u32) -> bool {
    return f[a] > f[b] || (f[a] == f[b] && a > b);
}

/// The Freudenthal–Kuhn sub-simplex of the `k`-subdivided cell with
/// `vertices` (3 or 4) corners holding the point with barycentric
/// coordinates `bary` (probekit_runtime::cloud::cell_visibility::kuhn_weights).
fn pk_kuhn_weights(bary: vec4<f32>, vertices: u32, k: u32) -> PkKuhn {
    let dim = vertices - 1u;
    let kf = f32(max(k, 1u));
    let top = max(k, 1u) - 1u;
    var y = vec3<f32>(0.0);
    var acc = 0.0;
    var prev = 0.0;
    for (var j = 0u; j < dim; j = j + 1u) {
        acc = acc + max(bary[j], 0.0);
        let v = clamp(acc * kf, prev, kf);
        y[j] = v;
        prev = v;
    }
    var base = vec3<u32>(0u);
    var f = vec3<f32>(0.0);
    for (var j = 0u; j < dim; j = j + 1u) {
        let b = min(u32(max(floor(y[j]), 0.0)), top);
        base[j] = b;
        f[j] = clamp(y[j] - f32(b), 0.0, 1.0);
    }
    var axes = vec3<u32>(0u, 1u, 2u);
    for (var i = 0u; i < dim; i = i + 1u) {
        for (var j = 0u; j + 1u < dim - i; j = j + 1u) {
            if pk_kuhn_before(f, axes[j + 1u], axes[j]) {
                let t = axes[j];
                axes[j] = axes[j + 1u];
                axes[j + 1u] = t;
            }
        }
    }
    var out: PkKuhn;
    var c = base;
    out.idx[0] = pk_lattice_index(vertices, c);
    out.w[0] = 1.0 - f[axes[0]];
    for (var m = 0u; m < dim; m = m + 1u) {
        c[axes[m]] = c[axes[m]] + 1u;
        out.idx[m + 1u] = pk_lattice_index(vertices, c);
        if m + 1u < dim {
            out.w[m + 1u] = f[axes[m]] - f[axes[m + 1u]];
        } else {
            out.w[m + 1u] = f[axes[m]];
        }
    }
    return out;
}

/// ±1 by the sign bit (+1 for +0.0) (visibility, `sign_not_zero`).
fn pk_sign_not_zero(x: f32) -> f32 {
    return select(1.0, -1.0, (bitcast<u32>(x) & 0x80000000u) != 0u);
}

/// Octahedral encoding with +Y at the centre (visibility::oct_encode;
/// Cigolle et al. 2014).
fn pk_oct_encode(d: vec3<f32>) -> vec2<f32> {
    let l1 = abs(d.x) + abs(d.y) + abs(d.z);
    var n = vec3<f32>(0.0, 1.0, 0.0);
    if l1 > 0.0 {
        n = d / l1;
    }
    if n.y >= 0.0 {
        return vec2<f32>(n.x, n.z);
    }
    return vec2<f32>((1.0 - abs(n.z)) * pk_sign_not_zero(n.x), (1.0 - abs(n.x)) * pk_sign_not_zero(n.z));
}

/// Texel (i, j) ∈ [−1, S]² after the octahedral border wrap
/// (visibility, `wrapped_index`).
fn pk_oct_wrapped_index(s: i32, i_in: i32, j_in: i32) -> u32 {
    var i = i_in;
    var j = j_in;
    if i < 0 {
        i = 0;
        j = s - 1 - j;
    } else if i >= s {
        i = s - 1;
        j = s - 1 - j;
    }
    if j < 0 {
        j = 0;
        i = s - 1 - i;
    } else if j >= s {
        j = s - 1;
        i = s - 1 - i;
    }
    return u32(j * s + i);
}

/// DDGI's visibility of a point at distance `d` from moments μ, μ2: the
/// one-sided Chebyshev bound to the power `sharpness`, crushed below 0.2,
/// floored at 1e-4 (visibility::chebyshev_visibility, chebyshev_bound;
/// Majercik et al. 2019, Donnelly & Lauritzen 2006).
fn pk_chebyshev_visibility(d: f32, mu: f32, mu2: f32, min_variance: f32, sharpness: u32) -> f32 {
    var c = 1.0;
    // `!(d <= mu)` is also true for a NaN distance, which the bound treats
    // as visible; d is never NaN here.
    if d > mu {
        let variance = max(mu2 - mu * mu, min_variance);
        let t = d - mu;
        c = variance / (variance + t * t);
    }
    var v = 1.0;
    for (var k = 0u; k < sharpness; k = k + 1u) {
        v = v * c;
    }
    if v < PK_VISIBILITY_CRUSH {
        v = v * (v * v / (PK_VISIBILITY_CRUSH * PK_VISIBILITY_CRUSH));
    }
    return max(v, PK_VISIBILITY_FLOOR);
}

fn pk_finite(x: f32) -> bool {
    return abs(x) <= 3.4028235e38;
}

/// `w / Σw` (`ok`), or `w` unchanged where the sum is not positive and
/// finite (`!ok`).
struct PkNormalized {
    w: vec4<f32>,
    ok: bool,
}

fn pk_normalized(w: vec4<f32>) -> PkNormalized {
    let sum = w.x + w.y + w.z + w.w;
    if pk_finite(sum) && sum > 0.0 {
        return PkNormalized(w / sum, true);
    }
    return PkNormalized(w, false);
}
