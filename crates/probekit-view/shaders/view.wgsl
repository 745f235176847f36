// view.wgsl — the entry points of `probekit view`'s page, appended to
// shaders/probekit.wgsl (whose functions they call) and translated by naga to
// GLSL ES 3.00 for WebGL2 (tests/glsl.rs writes assets/shaders.gen.js).
//
// GLSL ES 3.00 has no storage buffers and no ldexp, so nothing here reads a
// buffer: per-probe SH come in as instance attributes, the test object's SH as
// a uniform; functions of the library these entry points do not call (the
// codecs, which use ldexp) are dropped before translation.
//
// Uniform structs hold only vec4 and mat4x4 members, so WGSL's uniform layout
// and GLSL's std140 agree and the page fills them as plain float arrays.
//
// Colours: inputs are linear; outputs are sRGB-encoded display values. Scene
// units as in probekit: irradiance E (not divided by π), a Lambertian surface
// of albedo a shows radiance a·E/π.

/// What every program shares (binding 0): the camera and the display.
struct PvFrame {
    /// World to clip space (the page builds it in OpenGL's clip convention).
    view_proj: mat4x4<f32>,
    /// x: exposure multiplier 2^EV; y: scene shading (0 flat, 1 probes);
    /// z: extra alpha factor of scene surfaces; w: unused.
    display: vec4<f32>,
    /// xyz: unit direction towards the light of flat shading.
    flat_light: vec4<f32>,
    /// x: section height (metres): scene surfaces above it are cut away, so
    /// that rooms can be seen from above.
    section: vec4<f32>,
}

/// The test object (binding 1): its transform, albedo and the radiance SH
/// the runtime returned for its position (L2, coefficient i in sh[i].xyz).
struct PvObject {
    model: mat4x4<f32>,
    /// rgb: albedo; a: unused.
    albedo: vec4<f32>,
    sh: array<vec4<f32>, 9>,
}

@group(0) @binding(0) var<uniform> pv_frame: PvFrame;
@group(0) @binding(1) var<uniform> pv_object: PvObject;

/// Linear → sRGB transfer (IEC 61966-2-1), per channel, after clamping to [0, 1].
fn pv_srgb(linear: vec3<f32>) -> vec3<f32> {
    let c = clamp(linear, vec3<f32>(0.0), vec3<f32>(1.0));
    let lo = c * 12.92;
    let hi = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - vec3<f32>(0.055);
    return select(hi, lo, c <= vec3<f32>(0.0031308));
}

/// Display value of linear radiance under the frame's exposure.
fn pv_display(radiance: vec3<f32>) -> vec3<f32> {
    return pv_srgb(radiance * pv_frame.display.x);
}

// --- scene geometry ------------------------------------------------------------

struct PvSceneIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    /// Base colour (linear) and alpha (glass < 1).
    @location(2) color: vec4<f32>,
    /// The probes' irradiance at the vertex for its normal (from the server's
    /// runtime query), linear RGB, not divided by π.
    @location(3) irradiance: vec3<f32>,
}

struct PvSceneOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) color: vec4<f32>,
    @location(2) irradiance: vec3<f32>,
    @location(3) world: vec3<f32>,
}

@vertex
fn pv_scene_vs(v: PvSceneIn) -> PvSceneOut {
    var o: PvSceneOut;
    o.clip = pv_frame.view_proj * vec4<f32>(v.position, 1.0);
    o.normal = v.normal;
    o.color = v.color;
    o.irradiance = v.irradiance;
    o.world = v.position;
    return o;
}

@fragment
fn pv_scene_fs(f: PvSceneOut) -> @location(0) vec4<f32> {
    if f.world.y > pv_frame.section.x {
        discard;
    }
    let n = normalize(f.normal);
    var rgb: vec3<f32>;
    if pv_frame.display.y > 0.5 {
        rgb = pv_display(f.color.rgb * f.irradiance / PK_PI);
    } else {
        // Flat: a fixed light and an ambient term, no exposure.
        let k = 0.35 + 0.65 * abs(dot(n, pv_frame.flat_light.xyz));
        rgb = pv_srgb(f.color.rgb * k);
    }
    return vec4<f32>(rgb, f.color.a * pv_frame.display.z);
}

// --- probes: instanced spheres, each lit per pixel by its own SH ---------------

struct PvProbeIn {
    /// Unit-sphere vertex (also its normal).
    @location(0) unit: vec3<f32>,
    /// Instance: centre (xyz) and radius (w), metres.
    @location(1) centre: vec4<f32>,
    /// Instance: x 0 valid, 1 invalid, 2 moved by the virtual offset;
    /// y: weight of the probe in the current query (0 when not used).
    @location(2) state: vec4<f32>,
    @location(3) c0: vec3<f32>,
    @location(4) c1: vec3<f32>,
    @location(5) c2: vec3<f32>,
    @location(6) c3: vec3<f32>,
    @location(7) c4: vec3<f32>,
    @location(8) c5: vec3<f32>,
    @location(9) c6: vec3<f32>,
    @location(10) c7: vec3<f32>,
    @location(11) c8: vec3<f32>,
}

struct PvProbeOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) @interpolate(flat) state: vec4<f32>,
    @location(2) @interpolate(flat) c0: vec3<f32>,
    @location(3) @interpolate(flat) c1: vec3<f32>,
    @location(4) @interpolate(flat) c2: vec3<f32>,
    @location(5) @interpolate(flat) c3: vec3<f32>,
    @location(6) @interpolate(flat) c4: vec3<f32>,
    @location(7) @interpolate(flat) c5: vec3<f32>,
    @location(8) @interpolate(flat) c6: vec3<f32>,
    @location(9) @interpolate(flat) c7: vec3<f32>,
    @location(10) @interpolate(flat) c8: vec3<f32>,
}

@vertex
fn pv_probe_vs(v: PvProbeIn) -> PvProbeOut {
    var o: PvProbeOut;
    o.clip = pv_frame.view_proj * vec4<f32>(v.centre.xyz + v.unit * v.centre.w, 1.0);
    o.normal = v.unit;
    o.state = v.state;
    o.c0 = v.c0;
    o.c1 = v.c1;
    o.c2 = v.c2;
    o.c3 = v.c3;
    o.c4 = v.c4;
    o.c5 = v.c5;
    o.c6 = v.c6;
    o.c7 = v.c7;
    o.c8 = v.c8;
    return o;
}

@fragment
fn pv_probe_fs(f: PvProbeOut) -> @location(0) vec4<f32> {
    let n = normalize(f.normal);
    let sh = PkShL2(array<vec3<f32>, 9>(f.c0, f.c1, f.c2, f.c3, f.c4, f.c5, f.c6, f.c7, f.c8));
    // A white Lambertian ball: radiance E(n)/π.
    var rgb = pv_display(max(pk_irradiance_l2(sh, n), vec3<f32>(0.0)) / PK_PI);
    // Marks: a band around the ball's equator (y = 0 in its frame) in red for
    // an invalid probe, orange for one the virtual offset moved; a yellow
    // band around its pole for a probe the current query blends.
    if f.state.x > 0.5 && abs(n.y) < 0.3 {
        rgb = select(vec3<f32>(1.0, 0.55, 0.0), vec3<f32>(1.0, 0.1, 0.1), f.state.x < 1.5);
    }
    if f.state.y > 0.0 && n.y > 0.75 {
        rgb = vec3<f32>(1.0, 0.95, 0.2);
    }
    return vec4<f32>(rgb, 1.0);
}

// --- the test object, lit per pixel by the SH of the runtime's query ---------

struct PvObjectIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

struct PvObjectOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
}

@vertex
fn pv_object_vs(v: PvObjectIn) -> PvObjectOut {
    var o: PvObjectOut;
    o.clip = pv_frame.view_proj * (pv_object.model * vec4<f32>(v.position, 1.0));
    // The model matrix is a rotation about +Y times a uniform scale and a
    // translation: its upper 3×3 carries normals up to length.
    o.normal = (pv_object.model * vec4<f32>(v.normal, 0.0)).xyz;
    return o;
}

@fragment
fn pv_object_fs(f: PvObjectOut) -> @location(0) vec4<f32> {
    let n = normalize(f.normal);
    var sh: PkShL2;
    for (var i = 0u; i < 9u; i = i + 1u) {
        sh.c[i] = pv_object.sh[i].xyz;
    }
    let e = max(pk_irradiance_l2(sh, n), vec3<f32>(0.0));
    return vec4<f32>(pv_display(pv_object.albedo.rgb * e / PK_PI), 1.0);
}

// --- lines and markers: a display colour per vertex --------------------------

struct PvColorIn {
    @location(0) position: vec3<f32>,
    /// sRGB display colour and alpha.
    @location(1) color: vec4<f32>,
}

struct PvColorOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
}

@vertex
fn pv_color_vs(v: PvColorIn) -> PvColorOut {
    var o: PvColorOut;
    o.clip = pv_frame.view_proj * vec4<f32>(v.position, 1.0);
    o.color = v.color;
    return o;
}

@fragment
fn pv_color_fs(f: PvColorOut) -> @location(0) vec4<f32> {
    return f.color;
}
