// probekit_lights.wgsl — the exact, unshadowed irradiance of one light
// (probekit_runtime's `rig::Light::irradiance` with the sphere table,
// crates/probekit-runtime/src/rig/lights.rs): sphere, point, spot, disk and
// directional lights, from the 16-word light record that
// `probekit_shaders::layout::pack_rig_light` writes. Shared by a rig's near
// lights (probekit_rig.wgsl, records in `pk_rig`) and a cloud's run-time
// lights (probekit_cloud.wgsl, records in `pk_cloud`): one record layout,
// one decoder (`pk_light_unpack`), one evaluation (`pk_light_irradiance`).
// Concatenate after probekit.wgsl.
//
// One u32 storage buffer: `pk_sphere_table`, the runtime's `SphereTable`
// (word 0 its side, then side² f32 entries, row j = sin α, column i =
// cos θ; `probekit_shaders::layout::pack_sphere_table`), shared by every
// rig and cloud.

@group(0) @binding(6) var<storage, read> pk_sphere_table: array<u32>;

// Light kinds (the C API's PK_LIGHT_*; probekit_runtime's `Light`).
const PK_LIGHT_SPHERE: u32 = 0u;
const PK_LIGHT_POINT: u32 = 1u;
const PK_LIGHT_SPOT: u32 = 2u;
const PK_LIGHT_DISK: u32 = 3u;
const PK_LIGHT_DIRECTIONAL: u32 = 4u;
/// Words per light record, in pk_rig and pk_cloud alike: kind, position
/// (3 f32), direction (3 f32), radius, intensity (3 f32), spot scale, spot
/// offset, share (a rig's per-vertex share; 1 for a cloud's run-time
/// light), two reserved words (probekit_shaders::layout::pack_rig_light).
const PK_RIG_LIGHT_WORDS: u32 = 16u;

/// One light (probekit_runtime's `rig::Light`), in the frame of the
/// positions it is evaluated at (a rig's object frame; world space for a
/// cloud's run-time lights): `kind` a PK_LIGHT_*, `position` (m; unused for a
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

/// The light of a record given as its four groups of four words (words
/// 0–3, 4–7, 8–11, 12–15 of the record; f32 fields as their bits): what
/// `pk_rig_light_at` and `pk_cloud_light` read from their buffers.
fn pk_light_unpack(a: vec4<u32>, b: vec4<u32>, c: vec4<u32>, d: vec4<u32>) -> PkRigLight {
    let fa = bitcast<vec4<f32>>(a);
    let fb = bitcast<vec4<f32>>(b);
    let fc = bitcast<vec4<f32>>(c);
    let fd = bitcast<vec4<f32>>(d);
    return PkRigLight(a.x, fa.yzw, fb.xyz, fb.w, fc.xyz, fc.w, fd.x);
}

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
/// table, the runtime's per-vertex path; the one light evaluation of the
/// library, for a rig's near lights and a cloud's run-time lights alike): a sphere through
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
