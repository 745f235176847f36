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
//   layout of probekit_sh::codec::encode_f32.

@group(0) @binding(0) var<storage, read> pk_probe_words: array<u32>;
@group(0) @binding(1) var<storage, read> pk_sh_coeffs: array<f32>;

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

/// Probe-cloud blending: Σ weights[k]·probe(indices[k]) over the four probes
/// of a tetrahedron (barycentric weights, summing to 1) from pk_sh_coeffs.
fn pk_cloud_sh_l2(indices: vec4<u32>, weights: vec4<f32>) -> PkShL2 {
    return pk_blend_l2(
        pk_load_sh_l2(indices.x),
        pk_load_sh_l2(indices.y),
        pk_load_sh_l2(indices.z),
        pk_load_sh_l2(indices.w),
        weights,
    );
}

/// Trilinear volume sampling: L2 radiance SH at world position `pos` from the
/// probes of `grid` stored in pk_sh_coeffs (probe (i, j, k) at index
/// i + rx·(j + ry·k)); positions outside the box clamp to it.
fn pk_volume_sh_l2(grid: PkVolumeGrid, pos: vec3<f32>) -> PkShL2 {
    let cell = pk_volume_cell(grid, pos);
    let f = cell.frac;
    var out: PkShL2;
    for (var corner = 0u; corner < 8u; corner = corner + 1u) {
        let o = vec3<u32>(corner & 1u, (corner >> 1u) & 1u, (corner >> 2u) & 1u);
        let wv = select(vec3<f32>(1.0) - f, f, o == vec3<u32>(1u));
        let w = wv.x * wv.y * wv.z;
        let sh = pk_load_sh_l2(pk_volume_index(grid, cell.corner + o));
        for (var i = 0u; i < 9u; i = i + 1u) {
            out.c[i] = out.c[i] + sh.c[i] * w;
        }
    }
    return out;
}
