// probekit_rig.wgsl — the per-vertex half of an irradiance rig with the
// analytic/rig split (Yuan, Nowrouzezahrai & Sloan, "Irradiance Rigs", JGT
// 2011, §3), as probekit_runtime's `SplitRig::irradiance` evaluates it
// (crates/probekit-runtime/src/rig.rs, rig/split.rs, rig/lights.rs): the
// rig's radiance SH at the vertex from its parameters, convolved with the
// clamped cosine, plus each near light's exact irradiance times its
// per-vertex share. The CPU half (`SplitRig::update`: which lights are
// near, the shares, the refit of the parameters) runs once per frame in the
// runtime or the C API; `probekit_shaders::layout::pack_split_rig` writes
// its result into `pk_rig`. Concatenate after probekit.wgsl.
//
// Two u32 storage buffers (floats stored as their bits; docs/shaders.md
// gives the layouts):
// * `pk_rig`: one or more packed rigs, each a 20-word header (PK_RIG_H_*:
//   model, box, counts, section offsets relative to the rig's first word),
//   its parameters (PK_RIG_H_COEFFS RGB coefficients per parameter) and
//   its near lights (PK_RIG_LIGHT_WORDS words each). Functions take `rig`,
//   the word offset of the rig's header in `pk_rig` (0 for a buffer that
//   holds one rig).
// * `pk_sphere_table`: the runtime's `SphereTable` (word 0 its side, then
//   side² f32 entries, row j = sin α, column i = cos θ), shared by every
//   rig (`probekit_shaders::layout::pack_sphere_table`).
//
// Positions and normals are in the object's own coordinates (those of the
// mesh the rig was fitted to; the near lights are packed in them).

@group(0) @binding(5) var<storage, read> pk_rig: array<u32>;
@group(0) @binding(6) var<storage, read> pk_sphere_table: array<u32>;

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

// Light kinds (the C API's PK_LIGHT_*; probekit_runtime's `Light`).
const PK_LIGHT_SPHERE: u32 = 0u;
const PK_LIGHT_POINT: u32 = 1u;
const PK_LIGHT_SPOT: u32 = 2u;
const PK_LIGHT_DISK: u32 = 3u;
const PK_LIGHT_DIRECTIONAL: u32 = 4u;
/// Words per light record: kind, position (3 f32), direction (3 f32),
/// radius, intensity (3 f32), spot scale, spot offset, per-vertex share,
/// two reserved words.
const PK_RIG_LIGHT_WORDS: u32 = 16u;
/// Most model functions with a weight at one point (probekit_runtime's
/// `rig::MAX_WEIGHTS`).
const PK_RIG_MAX_WEIGHTS: u32 = 8u;

/// One light of a rig scene in the object's frame (probekit_runtime's
/// `rig::Light`): `kind` a PK_LIGHT_*, `position` (m; unused for a
/// directional light), unit `direction` the way light travels (spot axis,
/// disk normal, directional), `radius` (m; sphere and disk), `intensity`
/// W/sr per channel (a directional light's irradiance facing it, W/m²), and
/// for a spot the attenuation's `spot_scale = 1/max(cos inner − cos outer,
/// 0.001)` and `spot_offset = −cos outer · spot_scale`, computed on the CPU
/// as `probekit_sh::lights::spot_attenuation` computes them.
struct PkRigLight {
    kind: u32,
    position: vec3<f32>,
    direction: vec3<f32>,
    radius: f32,
    intensity: vec3<f32>,
    spot_scale: f32,
    spot_offset: f32,
}

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

// --- the sphere-light table and the lights ---------------------------------

/// Unit-radiance irradiance of a sphere light at `(cos θ, sin α)` from
/// `pk_sphere_table`, bilinear, arguments clamped to the table's range and
/// NaN read as its start (`SphereTable::lookup`, step for step).
fn pk_sphere_table_lookup(cos_theta: f32, sin_alpha: f32) -> f32 {
    let size = pk_sphere_table[0];
    let m = f32(size - 1u);
    var x = clamp((cos_theta + 1.0) * 0.5, 0.0, 1.0) * m;
    var y = clamp(sin_alpha, 0.0, 1.0) * m;
    if x != x {
        x = 0.0;
    }
    if y != y {
        y = 0.0;
    }
    let i = min(u32(x), size - 2u);
    let j = min(u32(y), size - 2u);
    let fx = x - f32(i);
    let fy = y - f32(j);
    let row0 = 1u + j * size + i;
    let row1 = row0 + size;
    let a00 = bitcast<f32>(pk_sphere_table[row0]);
    let a10 = bitcast<f32>(pk_sphere_table[row0 + 1u]);
    let a01 = bitcast<f32>(pk_sphere_table[row1]);
    let a11 = bitcast<f32>(pk_sphere_table[row1 + 1u]);
    let a = a00 + (a10 - a00) * fx;
    let b = a01 + (a11 - a01) * fx;
    return a + (b - a) * fy;
}

/// The glTF spot attenuation `t²`, `t = clamp(cos · scale + offset, 0, 1)`
/// (probekit_sh::lights::spot_attenuation with its scale and offset
/// precomputed, see PkRigLight).
fn pk_spot_attenuation(cos_to_receiver: f32, scale: f32, offset: f32) -> f32 {
    let t = clamp(cos_to_receiver * scale + offset, 0.0, 1.0);
    return t * t;
}

/// Exact irradiance (not divided by π) of `light` at surface point `p` with
/// unit normal `n`, unshadowed (`rig::Light::irradiance` with the sphere
/// table, the runtime's per-vertex path): a sphere through
/// pk_sphere_table_lookup (its horizon-clipped form factor, Snyder 1996) times
/// its radiance `I/(π r²)`, `I` inside it; a disk as the sphere of equal
/// projected area and radiance in the same table, zero behind it; point and
/// spot `I·max(0, n·ω)/d²` (spot times its attenuation); directional
/// `E·max(0, n·(−dir))`.
fn pk_light_irradiance(light: PkRigLight, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    switch light.kind {
        case PK_LIGHT_SPHERE: {
            let w = light.position - p;
            let d = length(w);
            let l = light.intensity / (PK_PI * light.radius * light.radius);
            if d <= light.radius {
                return l * PK_PI;
            }
            return l * pk_sphere_table_lookup(dot(n, w) / d, light.radius / d);
        }
        case PK_LIGHT_POINT: {
            let w = light.position - p;
            let d2 = dot(w, w);
            if d2 <= 0.0 {
                return vec3<f32>(0.0);
            }
            return light.intensity * (max(dot(n, w), 0.0) / (d2 * sqrt(d2)));
        }
        case PK_LIGHT_SPOT: {
            let w = light.position - p;
            let d2 = dot(w, w);
            if d2 <= 0.0 {
                return vec3<f32>(0.0);
            }
            let d = sqrt(d2);
            let att = pk_spot_attenuation(dot(light.direction, -w / d), light.spot_scale, light.spot_offset);
            return light.intensity * (att * max(dot(n, w), 0.0) / (d2 * d));
        }
        case PK_LIGHT_DISK: {
            let w = p - light.position;
            let d = length(w);
            let facing = dot(w, light.direction);
            if facing <= 0.0 || d <= 0.0 {
                return vec3<f32>(0.0);
            }
            let l = light.intensity / (PK_PI * light.radius * light.radius);
            let req = light.radius * sqrt(facing / d);
            return l * pk_sphere_table_lookup(-dot(n, w) / d, min(req / d, 1.0));
        }
        case PK_LIGHT_DIRECTIONAL: {
            return light.intensity * max(dot(n, -light.direction), 0.0);
        }
        default: {
            return vec3<f32>(0.0);
        }
    }
}

/// The light record whose first word is `word` of `pk_rig`.
fn pk_rig_light_at(word: u32) -> PkRigLight {
    return PkRigLight(
        pk_rig[word],
        pk_rig_v3(word + 1u),
        pk_rig_v3(word + 4u),
        pk_rig_f(word + 7u),
        pk_rig_v3(word + 8u),
        pk_rig_f(word + 11u),
        pk_rig_f(word + 12u),
    );
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
