// probekit_buffers.wgsl — storage-buffer access for probekit.wgsl (concatenate
// after it). Change the @group/@binding numbers to fit your pipeline layout;
// docs/shaders.md describes the layouts.
//
// pk_probe_words: the bytes of quantized probes (the `.probes` coefficient
//   section, codec L1 13 B / ZH3 16 B / L2 28 B, probes packed back to back
//   and so not 4-byte aligned) viewed as little-endian u32 words. Pad the
//   buffer with 8 zero words at the end: a probe is read through an 8-word
//   window starting at the word that holds its first byte.
// pk_sh_coeffs: f32 L2 radiance SH, 27 floats per probe, coefficient-major
//   (probe p, coefficient i, channel ch at p·27 + i·3 + ch) — the `f32` codec
//   layout of probekit_sh::codec::encode_f32; L1 probes with a zero band 2.
// pk_sh_gradients: a uniform volume's SH gradients, 81 floats per probe:
//   probe p, axis a (x, y, z), coefficient i, channel ch at
//   p·81 + a·27 + i·3 + ch, per metre; zero past the stored gradient order.
//   `probekit_shaders::layout::pack_volume_grid` fills both.

@group(0) @binding(0) var<storage, read> pk_probe_words: array<u32>;
@group(0) @binding(1) var<storage, read> pk_sh_coeffs: array<f32>;
@group(0) @binding(2) var<storage, read> pk_sh_gradients: array<f32>;

/// The 8-word window of pk_probe_words that starts at the word holding byte
/// `byte_offset`.
fn pk_load_window(byte_offset: u32) -> array<u32, 8> {
    let w0 = byte_offset >> 2u;
    var w: array<u32, 8>;
    for (var k = 0u; k < 8u; k = k + 1u) {
        w[k] = pk_probe_words[w0 + k];
    }
    return w;
}

/// The L1 probe (13-byte codec) at byte `byte_offset` of pk_probe_words.
fn pk_load_l1_q_at(byte_offset: u32) -> PkShL1 {
    var w = pk_load_window(byte_offset);
    return pk_decode_l1_window(&w, byte_offset & 3u);
}

/// The ZH3 probe (16-byte codec) at byte `byte_offset` of pk_probe_words.
fn pk_load_zh3_q_at(byte_offset: u32) -> PkZh3 {
    var w = pk_load_window(byte_offset);
    return pk_decode_zh3_window(&w, byte_offset & 3u);
}

/// The L2 probe (28-byte codec) at byte `byte_offset` of pk_probe_words.
fn pk_load_l2_q_at(byte_offset: u32) -> PkShL2 {
    var w = pk_load_window(byte_offset);
    return pk_decode_l2_window(&w, byte_offset & 3u);
}

/// The ambient cube (24-byte codec) at byte `byte_offset` of pk_probe_words.
fn pk_load_ambient_cube_at(byte_offset: u32) -> PkAmbientCube {
    var w = pk_load_window(byte_offset);
    return pk_decode_ambient_cube_window(&w, byte_offset & 3u);
}

/// Probe `p` of a packed L1 (13 B) coefficient array starting at byte 0.
fn pk_load_l1_q(p: u32) -> PkShL1 {
    return pk_load_l1_q_at(13u * p);
}

/// Probe `p` of a packed ZH3 (16 B) coefficient array starting at byte 0.
fn pk_load_zh3_q(p: u32) -> PkZh3 {
    return pk_load_zh3_q_at(16u * p);
}

/// Probe `p` of a packed L2 (28 B) coefficient array starting at byte 0.
fn pk_load_l2_q(p: u32) -> PkShL2 {
    return pk_load_l2_q_at(28u * p);
}

/// Probe `p` of pk_sh_coeffs (f32 L2, 27 floats per probe).
fn pk_load_sh_l2(p: u32) -> PkShL2 {
    var out: PkShL2;
    let base = 27u * p;
    for (var i = 0u; i < 9u; i = i + 1u) {
        let k = base + 3u * i;
        out.c[i] = vec3<f32>(pk_sh_coeffs[k], pk_sh_coeffs[k + 1u], pk_sh_coeffs[k + 2u]);
    }
    return out;
}

/// A plain four-probe blend: Σ weights[k]·probe(indices[k]) from
/// pk_sh_coeffs, with weights from the engine (e.g. the runtime's
/// `ProbeCloud::weights_at`). probekit_cloud.wgsl computes the runtime's
/// weights and blend on the GPU (`pk_cloud_sh`).
fn pk_cloud_sh_l2(indices: vec4<u32>, weights: vec4<f32>) -> PkShL2 {
    return pk_blend_l2(
        pk_load_sh_l2(indices.x),
        pk_load_sh_l2(indices.y),
        pk_load_sh_l2(indices.z),
        pk_load_sh_l2(indices.w),
        weights,
    );
}

/// Interpolation schemes of `pk_volume_sample`
/// (probekit_runtime::volume::Interp): trilinear, first-order Taylor from
/// each probe then trilinear weights, tricubic Hermite from values and
/// gradients (Tatarchuk 2005).
const PK_INTERP_TRILINEAR: u32 = 0u;
const PK_INTERP_TAYLOR: u32 = 1u;
const PK_INTERP_TRICUBIC: u32 = 2u;

/// Gradient of probe `p` along `axis` (0 x, 1 y, 2 z) from
/// pk_sh_gradients: ∂ coefficient / ∂ axis per metre, L2 (zero past the
/// stored gradient order).
fn pk_load_sh_gradient(p: u32, axis: u32) -> PkShL2 {
    var out: PkShL2;
    let base = 81u * p + 27u * axis;
    for (var i = 0u; i < 9u; i = i + 1u) {
        let k = base + 3u * i;
        out.c[i] = vec3<f32>(pk_sh_gradients[k], pk_sh_gradients[k + 1u], pk_sh_gradients[k + 2u]);
    }
    return out;
}

/// Radiance SH at world position `pos` in the uniform volume `grid` with
/// probes in pk_sh_coeffs (and, for Taylor and tricubic, gradients in
/// pk_sh_gradients), interpolated by `interp` (PK_INTERP_*); positions
/// outside the box clamp to it. Reproduces the grid branch of
/// probekit_runtime::volume::Volume::sample_sh: per corner of the cell,
/// offset d = p − c_s and t_a = |d_a|/h_a; trilinear weight Π(1 − t_a);
/// Taylor value v_s + ∇v_s·d; tricubic weight Π H₀(t_a), H₀(t) = 1 − 3t² +
/// 2t³, plus tangent terms d_a(1 − t_a)²Π_{b≠a}H₀(t_b)·∂_a v_s, and the
/// trilinear weight for coefficients without gradients; each set of
/// coefficients divided by its weight sum.
fn pk_volume_sample(grid: PkVolumeGrid, pos: vec3<f32>, interp: u32) -> PkShL2 {
    let cell = pk_volume_cell(grid, pos);
    let res = grid.resolution;
    let h = cell.size;
    let gn = min(grid.gradient_coeffs, 9u);
    var out: PkShL2;
    var wsum = vec2<f32>(0.0);
    for (var corner = 0u; corner < 8u; corner = corner + 1u) {
        var idx = vec3<u32>(0u);
        var d = vec3<f32>(0.0);
        var skip = false;
        for (var a = 0u; a < 3u; a = a + 1u) {
            let b = (corner >> a) & 1u;
            if res[a] < 2u {
                skip = skip || b == 1u;
                continue;
            }
            idx[a] = cell.corner[a] + b;
            if b == 0u {
                d[a] = cell.frac[a] * h[a];
            } else {
                d[a] = (cell.frac[a] - 1.0) * h[a];
            }
        }
        var t = vec3<f32>(0.0);
        for (var a = 0u; a < 3u; a = a + 1u) {
            if h[a] > 0.0 {
                t[a] = abs(d[a]) / h[a];
                skip = skip || t[a] >= 1.0;
            }
        }
        if skip {
            continue;
        }
        let s = idx.x + res.x * (idx.y + res.y * idx.z);
        let v = pk_load_sh_l2(s);
        let wl = (1.0 - t.x) * (1.0 - t.y) * (1.0 - t.z);
        if interp == PK_INTERP_TRICUBIC {
            let h0 = vec3<f32>(1.0) - t * t * (vec3<f32>(3.0) - 2.0 * t);
            let w = h0.x * h0.y * h0.z;
            wsum.x = wsum.x + w;
            let u = vec3<f32>(1.0) - t;
            let tan = vec3<f32>(
                d.x * (u.x * u.x) * h0.y * h0.z,
                d.y * (u.y * u.y) * h0.x * h0.z,
                d.z * (u.z * u.z) * h0.x * h0.y,
            );
            let gx = pk_load_sh_gradient(s, 0u);
            let gy = pk_load_sh_gradient(s, 1u);
            let gz = pk_load_sh_gradient(s, 2u);
            for (var c = 0u; c < gn; c = c + 1u) {
                out.c[c] = out.c[c] + (v.c[c] * w + gx.c[c] * tan.x + gy.c[c] * tan.y + gz.c[c] * tan.z);
            }
            if gn < 9u {
                wsum.y = wsum.y + wl;
                for (var c = gn; c < 9u; c = c + 1u) {
                    out.c[c] = out.c[c] + v.c[c] * wl;
                }
            }
        } else if interp == PK_INTERP_TAYLOR {
            wsum.x = wsum.x + wl;
            let gx = pk_load_sh_gradient(s, 0u);
            let gy = pk_load_sh_gradient(s, 1u);
            let gz = pk_load_sh_gradient(s, 2u);
            for (var c = 0u; c < 9u; c = c + 1u) {
                out.c[c] = out.c[c] + (v.c[c] + gx.c[c] * d.x + gy.c[c] * d.y + gz.c[c] * d.z) * wl;
            }
        } else {
            wsum.x = wsum.x + wl;
            for (var c = 0u; c < 9u; c = c + 1u) {
                out.c[c] = out.c[c] + v.c[c] * wl;
            }
        }
    }
    var flat_from = 9u;
    if interp == PK_INTERP_TRICUBIC {
        flat_from = gn;
    }
    for (var c = 0u; c < 9u; c = c + 1u) {
        var w = wsum.x;
        if c >= flat_from {
            w = wsum.y;
        }
        if w > 0.0 && w <= 3.4028235e38 {
            out.c[c] = out.c[c] * (1.0 / w);
        }
    }
    return out;
}

/// Trilinear volume sampling: L2 radiance SH at world position `pos` from the
/// probes of `grid` stored in pk_sh_coeffs (probe (i, j, k) at index
/// i + rx·(j + ry·k)); positions outside the box clamp to it
/// (`pk_volume_sample` with PK_INTERP_TRILINEAR).
fn pk_volume_sh_l2(grid: PkVolumeGrid, pos: vec3<f32>) -> PkShL2 {
    return pk_volume_sample(grid, pos, PK_INTERP_TRILINEAR);
}

/// Irradiance (not divided by π) at `pos` for unit normal `n` of an L1
/// volume by hallucinated ZH3: interpolate as usual, then
/// probekit_sh::zh3::zh3_hallucinated_irradiance of the bands ≤ 1.
fn pk_volume_irradiance_zh3(grid: PkVolumeGrid, pos: vec3<f32>, interp: u32, n: vec3<f32>) -> vec3<f32> {
    return pk_irradiance_zh3_hallucinated(pk_l2_to_l1(pk_volume_sample(grid, pos, interp)), n);
}
