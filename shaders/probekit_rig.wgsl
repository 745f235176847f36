// probekit_rig.wgsl — the per-vertex half of an irradiance rig with the
// analytic/rig split (Yuan, Nowrouzezahrai & Sloan, "Irradiance Rigs", JGT
// 2011, §3), as probekit_runtime's `SplitRig::irradiance` evaluates it
// (crates/probekit-runtime/src/rig.rs, rig/split.rs, rig/lights.rs): the
// rig's radiance SH at the vertex from its parameters, convolved with the
// clamped cosine, plus each near light's exact irradiance
// (`pk_light_irradiance` of probekit_lights.wgsl) times its per-vertex
// share. The CPU half (`SplitRig::update`: which lights are near, the
// shares, the refit of the parameters) runs once per frame in the runtime
// or the C API; `probekit_shaders::layout::pack_split_rig` writes its
// result into `pk_rig`. Concatenate after probekit.wgsl and
// probekit_lights.wgsl.
//
// Two u32 storage buffers (floats stored as their bits; docs/shaders.md
// gives the layouts):
// * `pk_rig`: one or more packed rigs, each a 20-word header (PK_RIG_H_*:
//   model, box, counts, section offsets relative to the rig's first word),
//   its parameters (PK_RIG_H_COEFFS RGB coefficients per parameter) and
//   its near lights (PK_RIG_LIGHT_WORDS words each). Functions take `rig`,
//   the word offset of the rig's header in `pk_rig` (0 for a buffer that
//   holds one rig).
// * `pk_sphere_table` (declared in probekit_lights.wgsl): the runtime's
//   `SphereTable`, shared by every rig
//   (`probekit_shaders::layout::pack_sphere_table`).
//
// Positions and normals are in the object's own coordinates (those of the
// mesh the rig was fitted to; the near lights are packed in them).

@group(0) @binding(5) var<storage, read> pk_rig: array<u32>;

// Header words of a packed rig (probekit_shaders::layout::RIG_HEADER).
const PK_RIG_H_MODEL: u32 = 0u;
const PK_RIG_H_AXIS_X: u32 = 1u;
const PK_RIG_H_COUNT_X: u32 = 4u;
const PK_RIG_H_COEFFS: u32 = 7u;
const PK_RIG_H_PARAMS: u32 = 8u;
const PK_RIG_H_LIGHTS: u32 = 9u;
const PK_RIG_H_PARAMETERS: u32 = 10u;
const PK_RIG_H_LIGHT_RECORDS: u32 = 11u;
const PK_RIG_H_BOX_MIN: u32 = 12u;
const PK_RIG_H_BOX_MAX: u32 = 15u;

// Rig models (header word PK_RIG_H_MODEL; probekit_runtime's `RigModel`).
const PK_RIG_MODEL_CONSTANT: u32 = 0u;
const PK_RIG_MODEL_GRADIENT: u32 = 1u;
const PK_RIG_MODEL_TENSOR: u32 = 2u;
// Axis models of a tensor rig (words PK_RIG_H_AXIS_X + a; `AxisModel`);
// words PK_RIG_H_COUNT_X + a hold each axis's function count (at least 1).
const PK_RIG_AXIS_CONSTANT: u32 = 0u;
const PK_RIG_AXIS_GRADIENT: u32 = 1u;
const PK_RIG_AXIS_LATTICE: u32 = 2u;

/// Most model functions with a weight at one point (probekit_runtime's
/// `rig::MAX_WEIGHTS`).
const PK_RIG_MAX_WEIGHTS: u32 = 8u;

/// The non-zero model functions of a rig at a point: `index[k]` the
/// parameter, `weight[k]` its weight, `count` how many
/// (probekit_runtime's `rig::rig_weights`).
struct PkRigWeights {
    index: array<u32, 8>,
    weight: array<f32, 8>,
    count: u32,
}

fn pk_rig_f(i: u32) -> f32 {
    return bitcast<f32>(pk_rig[i]);
}

fn pk_rig_v3(i: u32) -> vec3<f32> {
    return vec3<f32>(pk_rig_f(i), pk_rig_f(i + 1u), pk_rig_f(i + 2u));
}

fn pk_rig_u4(i: u32) -> vec4<u32> {
    return vec4<u32>(pk_rig[i], pk_rig[i + 1u], pk_rig[i + 2u], pk_rig[i + 3u]);
}

/// The light record whose first word is `word` of `pk_rig`.
fn pk_rig_light_at(word: u32) -> PkRigLight {
    return pk_light_unpack(pk_rig_u4(word), pk_rig_u4(word + 4u), pk_rig_u4(word + 8u), pk_rig_u4(word + 12u));
}

/// Word of near light `k` of the rig at `rig`.
fn pk_rig_light_word(rig: u32, k: u32) -> u32 {
    return rig + pk_rig[rig + PK_RIG_H_LIGHT_RECORDS] + PK_RIG_LIGHT_WORDS * k;
}

/// Near light `k` of the rig at `rig` (object frame).
fn pk_rig_light(rig: u32, k: u32) -> PkRigLight {
    return pk_rig_light_at(pk_rig_light_word(rig, k));
}

/// Per-vertex share `1 − w` of near light `k` (`rig::rig_weight`).
fn pk_rig_light_share(rig: u32, k: u32) -> f32 {
    return pk_rig_f(pk_rig_light_word(rig, k) + 13u);
}

// --- the rig model -----------------------------------------------------------

/// Normalised box coordinate of `x` on `[lo, hi]`, ½ for an empty axis.
fn pk_rig_unit(x: f32, lo: f32, hi: f32) -> f32 {
    let e = hi - lo;
    if e > 0.0 {
        return (x - lo) / e;
    }
    return 0.5;
}

/// The rig model's non-zero functions at object-space point `p`
/// (`rig::rig_weights`, in the same order).
fn pk_rig_weights(rig: u32, p: vec3<f32>) -> PkRigWeights {
    let lo = pk_rig_v3(rig + PK_RIG_H_BOX_MIN);
    let hi = pk_rig_v3(rig + PK_RIG_H_BOX_MAX);
    let u = vec3<f32>(pk_rig_unit(p.x, lo.x, hi.x), pk_rig_unit(p.y, lo.y, hi.y), pk_rig_unit(p.z, lo.z, hi.z));
    var out: PkRigWeights;
    let model = pk_rig[rig + PK_RIG_H_MODEL];
    if model == PK_RIG_MODEL_GRADIENT {
        out.index[0] = 0u;
        out.weight[0] = 1.0;
        for (var a = 0u; a < 3u; a = a + 1u) {
            out.index[a + 1u] = a + 1u;
            out.weight[a + 1u] = 2.0 * u[a] - 1.0;
        }
        out.count = 4u;
        return out;
    }
    if model != PK_RIG_MODEL_TENSOR {
        out.index[0] = 0u;
        out.weight[0] = 1.0;
        out.count = 1u;
        return out;
    }
    // Per axis (rig::axis_weights): up to two (function, value) pairs.
    var wi: array<vec2<u32>, 3>;
    var wv: array<vec2<f32>, 3>;
    var wn: array<u32, 3>;
    for (var a = 0u; a < 3u; a = a + 1u) {
        let kind = pk_rig[rig + PK_RIG_H_AXIS_X + a];
        let count = pk_rig[rig + PK_RIG_H_COUNT_X + a];
        if kind == PK_RIG_AXIS_GRADIENT {
            wi[a] = vec2<u32>(0u, 1u);
            wv[a] = vec2<f32>(1.0, 2.0 * u[a] - 1.0);
            wn[a] = 2u;
        } else if kind == PK_RIG_AXIS_LATTICE && count > 1u {
            var uc = clamp(u[a], 0.0, 1.0);
            if u[a] != u[a] {
                uc = 0.0;
            }
            let s = uc * f32(count - 1u);
            let i = min(u32(floor(s)), count - 2u);
            let f = s - f32(i);
            wi[a] = vec2<u32>(i, i + 1u);
            wv[a] = vec2<f32>(1.0 - f, f);
            wn[a] = 2u;
        } else {
            wi[a] = vec2<u32>(0u, 0u);
            wv[a] = vec2<f32>(1.0, 0.0);
            wn[a] = 1u;
        }
    }
    let nx = pk_rig[rig + PK_RIG_H_COUNT_X];
    let ny = pk_rig[rig + PK_RIG_H_COUNT_X + 1u];
    var m = 0u;
    for (var z = 0u; z < wn[2]; z = z + 1u) {
        for (var y = 0u; y < wn[1]; y = y + 1u) {
            for (var x = 0u; x < wn[0]; x = x + 1u) {
                out.index[m] = wi[0][x] + nx * (wi[1][y] + ny * wi[2][z]);
                out.weight[m] = wv[0][x] * wv[1][y] * wv[2][z];
                m = m + 1u;
            }
        }
    }
    out.count = m;
    return out;
}

/// Radiance SH of the rig at object-space point `p` as L2 (coefficients
/// past the rig's order² are zero): `Σ weight · parameter`
/// (`RigState::sh_at`).
fn pk_rig_sh(rig: u32, p: vec3<f32>) -> PkShL2 {
    let w = pk_rig_weights(rig, p);
    let coeffs = pk_rig[rig + PK_RIG_H_COEFFS];
    let params = rig + pk_rig[rig + PK_RIG_H_PARAMETERS];
    var out: PkShL2;
    for (var k = 0u; k < w.count; k = k + 1u) {
        let base = params + 3u * coeffs * w.index[k];
        for (var c = 0u; c < coeffs; c = c + 1u) {
            out.c[c] = out.c[c] + pk_rig_v3(base + 3u * c) * w.weight[k];
        }
    }
    return out;
}

/// Irradiance (not divided by π) of the rig alone at object-space point
/// `p`, unit normal `n` (`RigState::irradiance`).
fn pk_rig_model_irradiance(rig: u32, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return pk_irradiance_l2(pk_rig_sh(rig, p), n);
}

/// Irradiance (not divided by π) at object-space vertex `p` with unit
/// object-space normal `n`: the rig plus each near light's exact
/// irradiance times its per-vertex share (`SplitRig::irradiance`).
fn pk_rig_irradiance(rig: u32, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    var e = pk_rig_model_irradiance(rig, p, n);
    let lights = pk_rig[rig + PK_RIG_H_LIGHTS];
    for (var k = 0u; k < lights; k = k + 1u) {
        e = e + pk_light_irradiance(pk_rig_light(rig, k), p, n) * pk_rig_light_share(rig, k);
    }
    return e;
}
