// probekit_check.wgsl — the reference compute kernel: calls every function
// of probekit.wgsl, probekit_buffers.wgsl, probekit_lights.wgsl,
// probekit_cloud.wgsl, probekit_bricks.wgsl and probekit_rig.wgsl once per
// test case. The tests of
// crates/probekit-shaders run it on wgpu and compare with the Rust functions;
// the generator compiles it so that naga's HLSL/GLSL/MSL back ends emit the
// whole library (they only write what an entry point can reach).
//
// check_params.mode selects what a case checks; every mode reads
// PK_CHECK_IN floats at check_in[i·PK_CHECK_IN] and writes PK_CHECK_OUT
// floats at check_out[i·PK_CHECK_OUT].
//
// Mode 0 (PK_CHECK_LIBRARY): the pure functions and codecs.
// Case `i` reads:
//   [0..3) unit normal n, [3..30) L2 radiance SH (coefficient-major RGB),
//   [30..33) ZH3 zonal, [33..36) ZH3 unit axis (shared), [36..54) ambient cube
//   faces RGB, [54..58) cloud probe indices (as floats), [58..62) cloud weights,
//   [62..65) volume sample position,
// and writes PK_CHECK_OUT floats at check_out[i·PK_CHECK_OUT]:
//   [0..3) L1 irradiance, [3..6) L2, [6..9) Geomerics L1, [9..12) hallucinated
//   ZH3, [12..15) stored ZH3, [15..18) ambient cube, [18..30) decoded L1 probe i,
//   [30..42) decoded ZH3 probe i: L1, [42..45) its zonal, [45..48) its axis,
//   [48..75) decoded L2 probe i, [75..102) cloud blend, [102..129) volume
//   sample, [129..132) hallucinated ZH3 zonal, [132..135) its axis,
//   [135..138) radiance of the L2 SH in direction n, [138..150) L1 blend of
//   (L1 part of the input, decoded L1 probe i, the same two again) with the
//   cloud weights, [150..168) decoded ambient cube i (faces RGB).
//
// Modes 1–3 read [0..3) a position p, [3..6) a unit normal n, and mode 1
// also [6] a cell index and [7] 1 for a hull face, 0 for a tetrahedron.
// Mode 1 (PK_CHECK_CLOUD), from pk_cloud: [0..4) the blend's probes,
//   [4..8) its weights, [8..35) pk_cloud_sh, [35..38) pk_cloud_irradiance,
//   [38..41) pk_cloud_irradiance_zh3, [41..43) pk_cloud_locate(p) as
//   (index, hull flag), [43..70) pk_cloud_sh in the located cell,
//   [70..73) pk_cloud_sh_irradiance, [73..76) pk_cloud_sh_irradiance_zh3,
//   [76..79) pk_cloud_lights_irradiance of the blend, [79..87)
//   pk_cloud_light_occlusion of run-time lights 0..7 (0 past the count),
//   [87] pk_cloud_light_count.
// Mode 2 (PK_CHECK_VOLUME), from pk_sh_coeffs/pk_sh_gradients and
//   check_params.grid: [27k..27k+27) pk_volume_sample with interpolation k
//   (trilinear, Taylor, tricubic), [81+3k..84+3k) its irradiance,
//   [90+3k..93+3k) pk_volume_irradiance_zh3.
// Mode 3 (PK_CHECK_BRICKS), from pk_bricks: [0..27) pk_bricks_sh_l2,
//   [27..30) pk_bricks_irradiance, [30..33) pk_bricks_irradiance_zh3,
//   [33..36) the atlas coordinate of pk_bricks_lookup.
// Mode 4 (PK_CHECK_RIG), from pk_rig and pk_sphere_table, also reads [6]
//   the rig's first word in pk_rig: [0..3) pk_rig_irradiance,
//   [3..6) pk_rig_model_irradiance, [6..33) pk_rig_sh.
// Mode 5 (PK_CHECK_LIGHT) also reads [6] the first word of a light record
//   in pk_rig and [7], [8] a (cos θ, sin α) pair: [0..3)
//   pk_light_irradiance of the record, [3] pk_sphere_table_lookup of the
//   pair.

const PK_CHECK_IN: u32 = 68u;
const PK_CHECK_OUT: u32 = 168u;
const PK_CHECK_LIBRARY: u32 = 0u;
const PK_CHECK_CLOUD: u32 = 1u;
const PK_CHECK_VOLUME: u32 = 2u;
const PK_CHECK_BRICKS: u32 = 3u;
const PK_CHECK_RIG: u32 = 4u;
const PK_CHECK_LIGHT: u32 = 5u;

struct PkCheckParams {
    grid: PkVolumeGrid,
    count: u32,
    l1_offset: u32,
    zh3_offset: u32,
    l2_offset: u32,
    cube_offset: u32,
    mode: u32,
}

@group(0) @binding(8) var<storage, read> check_in: array<f32>;
@group(0) @binding(9) var<storage, read_write> check_out: array<f32>;
@group(0) @binding(10) var<uniform> check_params: PkCheckParams;

fn check_in_vec3(k: u32) -> vec3<f32> {
    return vec3<f32>(check_in[k], check_in[k + 1u], check_in[k + 2u]);
}

fn check_put(k: u32, v: vec3<f32>) {
    check_out[k] = v.x;
    check_out[k + 1u] = v.y;
    check_out[k + 2u] = v.z;
}

fn check_put_l1(k: u32, sh: array<vec3<f32>, 4>) {
    for (var i = 0u; i < 4u; i = i + 1u) {
        check_put(k + 3u * i, sh[i]);
    }
}

fn check_put_l2(k: u32, sh: PkShL2) {
    for (var i = 0u; i < 9u; i = i + 1u) {
        check_put(k + 3u * i, sh.c[i]);
    }
}

fn check_cloud(a: u32, o: u32) {
    let p = check_in_vec3(a);
    let n = check_in_vec3(a + 3u);
    var cell = u32(check_in[a + 6u]);
    if check_in[a + 7u] != 0.0 {
        cell = cell | PK_CLOUD_HULL;
    }
    let w = pk_cloud_weights(cell, p);
    for (var k = 0u; k < 4u; k = k + 1u) {
        check_out[o + k] = f32(w.probes[k]);
        check_out[o + 4u + k] = w.weights[k];
    }
    let sh = pk_cloud_blend(w);
    check_put_l2(o + 8u, sh);
    check_put(o + 35u, pk_cloud_irradiance(cell, p, n));
    check_put(o + 38u, pk_cloud_irradiance_zh3(cell, p, n));
    let located = pk_cloud_locate(p);
    check_out[o + 41u] = f32(located & ~PK_CLOUD_HULL);
    check_out[o + 42u] = f32(located >> 31u);
    check_put_l2(o + 43u, pk_cloud_sh(located, p));
    check_put(o + 70u, pk_cloud_sh_irradiance(cell, p, n));
    check_put(o + 73u, pk_cloud_sh_irradiance_zh3(cell, p, n));
    check_put(o + 76u, pk_cloud_lights_irradiance(w, p, n));
    let lights = pk_cloud_light_count();
    for (var l = 0u; l < 8u; l = l + 1u) {
        var v = 0.0;
        if l < lights {
            v = pk_cloud_light_occlusion(w, l);
        }
        check_out[o + 79u + l] = v;
    }
    check_out[o + 87u] = f32(lights);
}

fn check_volume(a: u32, o: u32) {
    let p = check_in_vec3(a);
    let n = check_in_vec3(a + 3u);
    for (var k = 0u; k < 3u; k = k + 1u) {
        let sh = pk_volume_sample(check_params.grid, p, k);
        check_put_l2(o + 27u * k, sh);
        check_put(o + 81u + 3u * k, pk_irradiance_l2(sh, n));
        check_put(o + 90u + 3u * k, pk_volume_irradiance_zh3(check_params.grid, p, k, n));
    }
}

fn check_bricks(a: u32, o: u32) {
    let p = check_in_vec3(a);
    let n = check_in_vec3(a + 3u);
    check_put_l2(o, pk_bricks_sh_l2(p));
    check_put(o + 27u, pk_bricks_irradiance(p, n));
    check_put(o + 30u, pk_bricks_irradiance_zh3(p, n));
    check_put(o + 33u, pk_bricks_lookup(p).coord);
}

fn check_rig(a: u32, o: u32) {
    let p = check_in_vec3(a);
    let n = check_in_vec3(a + 3u);
    let rig = u32(check_in[a + 6u]);
    check_put(o, pk_rig_irradiance(rig, p, n));
    check_put(o + 3u, pk_rig_model_irradiance(rig, p, n));
    check_put_l2(o + 6u, pk_rig_sh(rig, p));
}

fn check_light(a: u32, o: u32) {
    let p = check_in_vec3(a);
    let n = check_in_vec3(a + 3u);
    let light = pk_rig_light_at(u32(check_in[a + 6u]));
    check_put(o, pk_light_irradiance(light, p, n));
    check_out[o + 3u] = pk_sphere_table_lookup(check_in[a + 7u], check_in[a + 8u]);
}

/// Mode 0 for case `i`.
fn check_library(i: u32) {
    let a = i * PK_CHECK_IN;
    let o = i * PK_CHECK_OUT;
    let n = check_in_vec3(a);
    var sh: PkShL2;
    for (var k = 0u; k < 9u; k = k + 1u) {
        sh.c[k] = check_in_vec3(a + 3u + 3u * k);
    }
    let l1 = pk_l2_to_l1(sh);
    let axis = check_in_vec3(a + 33u);
    let zh = PkZh3(l1.c, check_in_vec3(a + 30u), array<vec3<f32>, 3>(axis, axis, axis));
    var cube: PkAmbientCube;
    for (var k = 0u; k < 6u; k = k + 1u) {
        cube.faces[k] = check_in_vec3(a + 36u + 3u * k);
    }
    let idx = vec4<u32>(vec4<f32>(check_in[a + 54u], check_in[a + 55u], check_in[a + 56u], check_in[a + 57u]));
    let wts = vec4<f32>(check_in[a + 58u], check_in[a + 59u], check_in[a + 60u], check_in[a + 61u]);
    let pos = check_in_vec3(a + 62u);

    check_put(o, pk_irradiance_l1(l1, n));
    check_put(o + 3u, pk_irradiance_l2(sh, n));
    check_put(o + 6u, pk_irradiance_geomerics_l1(l1, n));
    check_put(o + 9u, pk_irradiance_zh3_hallucinated(l1, n));
    check_put(o + 12u, pk_irradiance_zh3(zh, n));
    check_put(o + 15u, pk_irradiance_ambient_cube(cube, n));
    let l1q = pk_load_l1_q_at(check_params.l1_offset + 13u * i);
    check_put_l1(o + 18u, l1q.c);
    let zq = pk_load_zh3_q_at(check_params.zh3_offset + 16u * i);
    check_put_l1(o + 30u, zq.l1);
    check_put(o + 42u, zq.zonal);
    check_put(o + 45u, zq.axes[0]);
    check_put_l2(o + 48u, pk_load_l2_q_at(check_params.l2_offset + 28u * i));
    check_put_l2(o + 75u, pk_cloud_sh_l2(idx, wts));
    check_put_l2(o + 102u, pk_volume_sh_l2(check_params.grid, pos));
    let hz = pk_zh3_hallucinate(l1.c);
    check_put(o + 129u, hz.zonal);
    check_put(o + 132u, hz.axes[0]);
    check_put(o + 135u, pk_radiance_l2(sh, n));
    check_put_l1(o + 138u, pk_blend_l1(l1, l1q, l1, l1q, wts).c);
    let cq = pk_load_ambient_cube_at(check_params.cube_offset + 24u * i);
    for (var k = 0u; k < 6u; k = k + 1u) {
        check_put(o + 150u + 3u * k, cq.faces[k]);
    }
}

/// Every mode, by check_params.mode: the kernel the generated HLSL, GLSL
/// and MSL are written for (it reaches every function).
@compute @workgroup_size(64)
fn pk_check(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= check_params.count {
        return;
    }
    let a = i * PK_CHECK_IN;
    let o = i * PK_CHECK_OUT;
    if check_params.mode == PK_CHECK_CLOUD {
        check_cloud(a, o);
    } else if check_params.mode == PK_CHECK_VOLUME {
        check_volume(a, o);
    } else if check_params.mode == PK_CHECK_BRICKS {
        check_bricks(a, o);
    } else if check_params.mode == PK_CHECK_RIG {
        check_rig(a, o);
    } else if check_params.mode == PK_CHECK_LIGHT {
        check_light(a, o);
    } else {
        check_library(i);
    }
}

// One kernel per mode, so that a test compiles only what it checks.

@compute @workgroup_size(64)
fn pk_check_library(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x < check_params.count {
        check_library(gid.x);
    }
}

@compute @workgroup_size(64)
fn pk_check_cloud(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x < check_params.count {
        check_cloud(gid.x * PK_CHECK_IN, gid.x * PK_CHECK_OUT);
    }
}

@compute @workgroup_size(64)
fn pk_check_volume(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x < check_params.count {
        check_volume(gid.x * PK_CHECK_IN, gid.x * PK_CHECK_OUT);
    }
}

@compute @workgroup_size(64)
fn pk_check_bricks(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x < check_params.count {
        check_bricks(gid.x * PK_CHECK_IN, gid.x * PK_CHECK_OUT);
    }
}

/// Modes 4 and 5 (rigs and lights), by check_params.mode.
@compute @workgroup_size(64)
fn pk_check_rig(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x < check_params.count {
        if check_params.mode == PK_CHECK_LIGHT {
            check_light(gid.x * PK_CHECK_IN, gid.x * PK_CHECK_OUT);
        } else {
            check_rig(gid.x * PK_CHECK_IN, gid.x * PK_CHECK_OUT);
        }
    }
}
