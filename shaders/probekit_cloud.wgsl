// probekit_cloud.wgsl — probe-cloud blending as the runtime does it
// (crates/probekit-runtime/src/cloud): barycentric weights of the cell that
// holds a point, times each probe's Chebyshev visibility (VISM), the cell
// visibility bits or occluder plane (CVSP, CPLN), the fitted probe weight
// and brightness factor (PWGT), renormalized with the hidden-cell fallback;
// then the plain or directional blend of the probes' radiance SH; plus the
// file's run-time lights (LITE, OCCL): each light's exact irradiance
// (`pk_light_irradiance` of probekit_lights.wgsl) times the probes' visible
// fractions of it blended with the same weights, as probekit_runtime's
// `Probes::irradiance` adds them.
// Concatenate after probekit.wgsl, probekit_buffers.wgsl and
// probekit_lights.wgsl (whose `pk_sphere_table` the light term reads: bind
// it to use `pk_cloud_irradiance`; `pk_cloud_sh_irradiance`, the SH part
// alone, does not read it).
//
// Everything comes from one u32 storage buffer, `pk_cloud`, that
// `probekit_shaders::layout::pack_cloud` fills from a loaded cloud: a
// 32-word header (PK_CLOUD_H_*) then the sections at the word offsets the
// header gives. Floats are stored as their bits. docs/shaders.md lists the
// layout.
//
// A cell is a tetrahedron index, or PK_CLOUD_HULL | f for hull face f (a
// point outside the probes' convex hull, lit from its closest hull point):
// what the runtime's `TetMesh::locate` returns, or what `pk_cloud_locate`
// finds on the GPU.

@group(0) @binding(3) var<storage, read> pk_cloud: array<u32>;

// Header words of pk_cloud (probekit_shaders::layout::CLOUD_HEADER).
const PK_CLOUD_H_PROBES: u32 = 0u;
const PK_CLOUD_H_TETS: u32 = 1u;
const PK_CLOUD_H_HULL_FACES: u32 = 2u;
const PK_CLOUD_H_COEFFS: u32 = 3u;
const PK_CLOUD_H_FLAGS: u32 = 4u;
const PK_CLOUD_H_BRIGHTNESS: u32 = 5u;
const PK_CLOUD_H_DIRECTIONAL: u32 = 6u;
const PK_CLOUD_H_VIS_RESOLUTION: u32 = 7u;
const PK_CLOUD_H_VIS_BIAS: u32 = 8u;
const PK_CLOUD_H_VIS_SHARPNESS: u32 = 9u;
const PK_CLOUD_H_VIS_MIN_VARIANCE: u32 = 10u;
const PK_CLOUD_H_VIS_MAX_DISTANCE: u32 = 11u;
const PK_CLOUD_H_CELL_SUBDIVISION: u32 = 12u;
const PK_CLOUD_H_POSITIONS: u32 = 13u;
const PK_CLOUD_H_COEFFICIENTS: u32 = 14u;
const PK_CLOUD_H_LUMINANCE: u32 = 15u;
const PK_CLOUD_H_DIR_LUMINANCE: u32 = 16u;
const PK_CLOUD_H_PROBE_WEIGHTS: u32 = 17u;
const PK_CLOUD_H_TET_RECORDS: u32 = 18u;
const PK_CLOUD_H_HULL_RECORDS: u32 = 19u;
const PK_CLOUD_H_MOMENTS: u32 = 20u;
const PK_CLOUD_H_CELLS: u32 = 21u;
const PK_CLOUD_H_CELL_BITS: u32 = 22u;
const PK_CLOUD_H_PLANES: u32 = 23u;
const PK_CLOUD_H_DIR_TABLES: u32 = 24u;
const PK_CLOUD_H_START_GRID: u32 = 25u;
// Run-time lights: their count (0 without), the offset of their records
// (PK_RIG_LIGHT_WORDS words each, world space) and of the probes' occlusion
// rows (⌈count/4⌉ words per probe, four 8-bit fractions per word).
const PK_CLOUD_H_LIGHTS: u32 = 26u;
const PK_CLOUD_H_LIGHT_RECORDS: u32 = 27u;
const PK_CLOUD_H_LIGHT_OCCLUSION: u32 = 28u;

// Flags (header word PK_CLOUD_H_FLAGS): which weighting is on.
const PK_CLOUD_FLAG_VISIBILITY: u32 = 1u;
const PK_CLOUD_FLAG_CELLS: u32 = 2u;
const PK_CLOUD_FLAG_PROBE_WEIGHTS: u32 = 4u;

/// Cell code of hull face f: PK_CLOUD_HULL | f (probekit_runtime's
/// `Location::Outside`).
const PK_CLOUD_HULL: u32 = 0x80000000u;
/// An entry of the cell table without a record (a clear cell).
const PK_CLOUD_NONE: u32 = 0xffffffffu;
/// Words per tetrahedron record: probes (4), barycentric rows (9 f32),
/// origin (3 f32), neighbours (4; PK_CLOUD_HULL | f on the hull).
const PK_CLOUD_TET_WORDS: u32 = 20u;
/// Words per hull-face record: probes a, b, c (3), adjacent faces (3), the
/// rows giving the barycentric coordinates of b and c of the projection of
/// p − a onto the face's plane (6 f32), and the rows giving the parameter
/// along edges ab, ac, bc of the closest point of each edge's line to
/// p − (its first vertex) (9 f32); rows computed in f64 by the packer.
const PK_CLOUD_HULL_WORDS: u32 = 21u;
/// Relative decrease of the squared distance the hull descent needs to
/// move to another face: beyond the f32 rounding of the distances, so that
/// faces sharing the closest point (an edge or vertex of the hull) are a
/// tie the descent does not move across, like the runtime's f64 test.
const PK_CLOUD_CLOSER: f32 = 1e-6;
/// The runtime's constants (probekit_runtime::cloud): INSIDE_TOLERANCE,
/// HIDDEN_MASS_FLOOR and directional::DIRECTIONAL_RATIO.
const PK_INSIDE_TOLERANCE: f32 = 1e-5;
const PK_HIDDEN_MASS_FLOOR: f32 = 0.1;
const PK_DIRECTIONAL_RATIO: f32 = 3.0;
/// Steps of `pk_cloud_locate`'s walk and of its hull descent.
const PK_CLOUD_WALK_STEPS: u32 = 1024u;
const PK_CLOUD_HULL_STEPS: u32 = 256u;
const PK_CLOUD_MAX_FAN: u32 = 1024u;

/// The blend at a point: four probe indices and their weights (unused
/// slots: probe 0, weight 0), what probekit_runtime's
/// `ProbeCloud::weights_at` returns.
struct PkCloudWeights {
    probes: vec4<u32>,
    weights: vec4<f32>,
}

fn pk_cloud_u(i: u32) -> u32 {
    return pk_cloud[i];
}

fn pk_cloud_f(i: u32) -> f32 {
    return bitcast<f32>(pk_cloud[i]);
}

fn pk_cloud_v3(i: u32) -> vec3<f32> {
    return vec3<f32>(pk_cloud_f(i), pk_cloud_f(i + 1u), pk_cloud_f(i + 2u));
}

/// Section offset (words) from header word `h`.
fn pk_cloud_off(h: u32) -> u32 {
    return pk_cloud[h];
}

/// Position of probe `i` (metres).
fn pk_cloud_position(i: u32) -> vec3<f32> {
    return pk_cloud_v3(pk_cloud_off(PK_CLOUD_H_POSITIONS) + 3u * i);
}

/// Radiance SH of probe `i` as L2 (coefficients past the stored
/// `order²`, at most 9, are zero).
fn pk_cloud_probe_sh(i: u32) -> PkShL2 {
    let n = pk_cloud_u(PK_CLOUD_H_COEFFS);
    let base = pk_cloud_off(PK_CLOUD_H_COEFFICIENTS) + 3u * n * i;
    var out: PkShL2;
    for (var c = 0u; c < n; c = c + 1u) {
        out.c[c] = pk_cloud_v3(base + 3u * c);
    }
    return out;
}

/// The four probes of tetrahedron `t`.
fn pk_cloud_tet_probes(t: u32) -> vec4<u32> {
    let b = pk_cloud_off(PK_CLOUD_H_TET_RECORDS) + PK_CLOUD_TET_WORDS * t;
    return vec4<u32>(pk_cloud_u(b), pk_cloud_u(b + 1u), pk_cloud_u(b + 2u), pk_cloud_u(b + 3u));
}

/// Barycentric coordinates of `p` in tetrahedron `t`
/// (probekit_runtime::cloud::BaryMatrix::coords).
fn pk_cloud_bary(t: u32, p: vec3<f32>) -> vec4<f32> {
    let b = pk_cloud_off(PK_CLOUD_H_TET_RECORDS) + PK_CLOUD_TET_WORDS * t;
    let d = p - pk_cloud_v3(b + 13u);
    let l0 = dot(pk_cloud_v3(b + 4u), d);
    let l1 = dot(pk_cloud_v3(b + 7u), d);
    let l2 = dot(pk_cloud_v3(b + 10u), d);
    return vec4<f32>(l0, l1, l2, 1.0 - l0 - l1 - l2);
}

/// The three probes of hull face `f`, wound counter-clockwise seen from
/// outside (probekit_runtime::cloud::TetMesh::hull_face_probes).
fn pk_cloud_hull_probes(f: u32) -> vec3<u32> {
    let b = pk_cloud_off(PK_CLOUD_H_HULL_RECORDS) + PK_CLOUD_HULL_WORDS * f;
    return vec3<u32>(pk_cloud_u(b), pk_cloud_u(b + 1u), pk_cloud_u(b + 2u));
}

// --- outer cells (probekit_runtime::cloud::hull) ------------------------------

/// Closest point of a triangle to a point: its barycentric `weights`, the
/// `point`, and the `feature` holding it (0: the face; 1, 2, 3: the edge
/// opposite local vertex 0, 1, 2; 4, 5, 6: local vertex 0, 1, 2).
struct PkTriangleClosest {
    weights: vec3<f32>,
    point: vec3<f32>,
    feature: u32,
}

/// Closest point of hull face `f` to `p` (the runtime's
/// `TetMesh::closest_in_face`): the projection onto the face's plane where
/// its barycentric coordinates are all ≥ 0, else the closest of the three
/// edges' closest points (the same point as the Voronoi-region test),
/// computed from the face record's f64-derived rows, so that a thin hull
/// face loses no more precision than a tetrahedron's barycentric matrix
/// (the runtime classifies p by Ericson's Voronoi-region test in f64:
/// Real-Time Collision Detection, §5.1.5; both give the closest point).
fn pk_cloud_closest_in_face(p: vec3<f32>, f: u32) -> PkTriangleClosest {
    let r = pk_cloud_off(PK_CLOUD_H_HULL_RECORDS) + PK_CLOUD_HULL_WORDS * f;
    let v = vec3<u32>(pk_cloud_u(r), pk_cloud_u(r + 1u), pk_cloud_u(r + 2u));
    let a = pk_cloud_position(v.x);
    let b = pk_cloud_position(v.y);
    let c = pk_cloud_position(v.z);
    let lb = dot(pk_cloud_v3(r + 6u), p - a);
    let lc = dot(pk_cloud_v3(r + 9u), p - a);
    let la = 1.0 - lb - lc;
    if la >= 0.0 && lb >= 0.0 && lc >= 0.0 {
        return PkTriangleClosest(vec3<f32>(la, lb, lc), a * la + b * lb + c * lc, 0u);
    }
    var best: PkTriangleClosest;
    var best_d = 3.4e38;
    // Edges ab, ac, bc: opposite local vertex 2, 1, 0.
    for (var e = 0u; e < 3u; e = e + 1u) {
        var u = a;
        var q = b;
        var iu = 0u;
        var iq = 1u;
        if e == 1u {
            q = c;
            iq = 2u;
        } else if e == 2u {
            u = b;
            q = c;
            iu = 1u;
            iq = 2u;
        }
        let t = clamp(dot(pk_cloud_v3(r + 12u + 3u * e), p - u), 0.0, 1.0);
        let x = u + (q - u) * t;
        let d = pk_dist2(p, x);
        if d < best_d {
            best_d = d;
            var w = vec3<f32>(0.0);
            w[iu] = 1.0 - t;
            w[iq] = t;
            var feature = 3u - e;
            if t <= 0.0 {
                feature = 4u + iu;
            } else if t >= 1.0 {
                feature = 4u + iq;
            }
            best = PkTriangleClosest(w, x, feature);
        }
    }
    return best;
}

fn pk_dist2(a: vec3<f32>, b: vec3<f32>) -> f32 {
    let d = a - b;
    return dot(d, d);
}

/// Hull face `f`'s neighbour across the edge opposite its local vertex `k`.
fn pk_cloud_hull_adjacent(f: u32, k: u32) -> u32 {
    return pk_cloud_u(pk_cloud_off(PK_CLOUD_H_HULL_RECORDS) + PK_CLOUD_HULL_WORDS * f + 3u + k);
}

/// The hull face closest to `p` (outside the hull), by descent over hull
/// faces from face `start` (probekit_runtime's `TetMesh::closest_on_hull`:
/// across the edge, or around the vertex, that holds the closest point while
/// that gets strictly closer). At most PK_CLOUD_HULL_STEPS steps and
/// PK_CLOUD_MAX_FAN faces around a vertex.
fn pk_cloud_closest_hull_face(p: vec3<f32>, start: u32) -> u32 {
    var h = start;
    var cur = pk_cloud_closest_in_face(p, h);
    for (var step = 0u; step < PK_CLOUD_HULL_STEPS; step = step + 1u) {
        let d = pk_dist2(p, cur.point);
        var next = PK_CLOUD_NONE;
        var best_d = d;
        if cur.feature >= 1u && cur.feature <= 3u {
            let g = pk_cloud_hull_adjacent(h, cur.feature - 1u);
            let cand = pk_cloud_closest_in_face(p, g);
            if pk_dist2(p, cand.point) < d * (1.0 - PK_CLOUD_CLOSER) {
                next = g;
            }
        } else if cur.feature >= 4u {
            let k = cur.feature - 4u;
            let v = pk_cloud_hull_probes(h)[k];
            var g = h;
            var kg = k;
            for (var i = 0u; i < PK_CLOUD_MAX_FAN; i = i + 1u) {
                g = pk_cloud_hull_adjacent(g, (kg + 1u) % 3u);
                let q = pk_cloud_hull_probes(g);
                if g == h || (q.x != v && q.y != v && q.z != v) {
                    break;
                }
                kg = select(select(2u, 1u, q.y == v), 0u, q.x == v);
                let cand = pk_cloud_closest_in_face(p, g);
                let d2 = pk_dist2(p, cand.point);
                if d2 < d * (1.0 - PK_CLOUD_CLOSER) && d2 < best_d {
                    best_d = d2;
                    next = g;
                }
            }
        }
        if next == PK_CLOUD_NONE {
            break;
        }
        h = next;
        cur = pk_cloud_closest_in_face(p, h);
    }
    return h;
}

/// Locates `p` on the GPU: the start tetrahedron of the packed start grid
/// (one per grid cell over the probes' bounding box), then the walk
/// through the face opposite the most negative barycentric coordinate
/// (probekit_runtime's `TetMesh::locate`, Cupisz 2012); leaving through a
/// hull face, the hull descent of `pk_cloud_closest_hull_face`. Returns a
/// cell code. The runtime's cycle guards (stochastic walk) are replaced by
/// a step limit: after PK_CLOUD_WALK_STEPS steps the tetrahedron with the
/// largest smallest coordinate seen is returned.
fn pk_cloud_locate(p: vec3<f32>) -> u32 {
    let g = pk_cloud_off(PK_CLOUD_H_START_GRID);
    let origin = pk_cloud_v3(g);
    let per_metre = pk_cloud_v3(g + 3u);
    let dims = vec3<u32>(pk_cloud_u(g + 6u), pk_cloud_u(g + 7u), pk_cloud_u(g + 8u));
    let c = floor((p - origin) * per_metre);
    let ix = min(u32(max(c.x, 0.0)), dims.x - 1u);
    let iy = min(u32(max(c.y, 0.0)), dims.y - 1u);
    let iz = min(u32(max(c.z, 0.0)), dims.z - 1u);
    var t = pk_cloud_u(g + 9u + (iz * dims.y + iy) * dims.x + ix);
    var best = t;
    var best_min = -3.4e38;
    let records = pk_cloud_off(PK_CLOUD_H_TET_RECORDS);
    for (var step = 0u; step < PK_CLOUD_WALK_STEPS; step = step + 1u) {
        let l = pk_cloud_bary(t, p);
        var i = 0u;
        for (var k = 1u; k < 4u; k = k + 1u) {
            if l[k] < l[i] {
                i = k;
            }
        }
        if l[i] >= -PK_INSIDE_TOLERANCE {
            return t;
        }
        if l[i] > best_min {
            best_min = l[i];
            best = t;
        }
        let n = pk_cloud_u(records + PK_CLOUD_TET_WORDS * t + 16u + i);
        if (n & PK_CLOUD_HULL) != 0u {
            return PK_CLOUD_HULL | pk_cloud_closest_hull_face(p, n & ~PK_CLOUD_HULL);
        }
        t = n;
    }
    return best;
}

// --- cell visibility (probekit_runtime::cloud::cell_visibility) ------------

/// Bit `bit` of the record that starts at byte `byte_offset` of the cell
/// bits section (least significant bit of each byte first).
fn pk_cloud_record_bit(byte_offset: u32, bit: u32) -> bool {
    let within = (byte_offset & 3u) * 8u + bit;
    let word = pk_cloud_off(PK_CLOUD_H_CELL_BITS) + (byte_offset >> 2u) + (within >> 5u);
    return ((pk_cloud[word] >> (within & 31u)) & 1u) != 0u;
}

/// Cell visibility of each corner of cell `cell` (tetrahedra first, then
/// hull faces; `vertices` corners) at barycentric `bary`: the occluder
/// plane's side test where the cell has one, else its lattice bits
/// interpolated on the Kuhn sub-simplex, 1 for a clear cell
/// (ProbeCloud::weights_at with CellVisibility::tet / hull_face and
/// CellPlanes::visibility). Unused fourth slot of a hull face: 1.
fn pk_cloud_cell_visibility(cell: u32, vertices: u32, bary: vec4<f32>, p: vec3<f32>, probes: vec4<u32>) -> vec4<f32> {
    let entry = pk_cloud_u(pk_cloud_off(PK_CLOUD_H_CELLS) + cell);
    if entry == PK_CLOUD_NONE {
        return vec4<f32>(1.0);
    }
    var out = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    if (entry & PK_CLOUD_HULL) != 0u {
        // An occluder plane n·x = d: 1 where the corner is on p's side.
        let b = pk_cloud_off(PK_CLOUD_H_PLANES) + 4u * (entry & ~PK_CLOUD_HULL);
        let n = pk_cloud_v3(b);
        let d = pk_cloud_f(b + 3u);
        let s = dot(n, p) - d >= 0.0;
        for (var v = 0u; v < 4u; v = v + 1u) {
            let sv = dot(n, pk_cloud_position(probes[v])) - d >= 0.0;
            out[v] = select(0.0, 1.0, sv == s);
        }
        return out;
    }
    let k = pk_cloud_u(PK_CLOUD_H_CELL_SUBDIVISION);
    let kuhn = pk_kuhn_weights(bary, vertices, k);
    let len = pk_lattice_len(vertices, k);
    for (var v = 0u; v < vertices; v = v + 1u) {
        var o = 0.0;
        for (var j = 0u; j < vertices; j = j + 1u) {
            if kuhn.w[j] > 0.0 && pk_cloud_record_bit(entry, v * len + kuhn.idx[j]) {
                o = o + kuhn.w[j];
            }
        }
        out[v] = o;
    }
    return out;
}

// --- Chebyshev visibility (probekit_runtime::cloud::visibility) -------------

/// Texel `t` of probe `probe`'s distance moments: [μ, μ2] in metres and m²
/// (VisibilityMaps::probe_map; the packer stores the decoded f32 pair).
fn pk_cloud_moment(probe: u32, t: u32) -> vec2<f32> {
    let res = pk_cloud_u(PK_CLOUD_H_VIS_RESOLUTION);
    let k = pk_cloud_off(PK_CLOUD_H_MOMENTS) + 2u * (probe * res * res + t);
    return vec2<f32>(pk_cloud_f(k), pk_cloud_f(k + 1u));
}

/// Bilinearly filtered moments of probe `probe` in direction `dir`, wrapping
/// across the map's edges (visibility::sample_oct_bilinear).
fn pk_cloud_sample_moments(probe: u32, dir: vec3<f32>) -> vec2<f32> {
    let s = i32(max(pk_cloud_u(PK_CLOUD_H_VIS_RESOLUTION), 1u));
    let e = pk_oct_encode(dir);
    let half_s = 0.5 * f32(s);
    let x = clamp((e.x + 1.0) * half_s - 0.5, -0.5, f32(s) - 0.5);
    let y = clamp((e.y + 1.0) * half_s - 0.5, -0.5, f32(s) - 0.5);
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let i0 = i32(x0);
    let j0 = i32(y0);
    let a = pk_cloud_moment(probe, pk_oct_wrapped_index(s, i0, j0));
    let b = pk_cloud_moment(probe, pk_oct_wrapped_index(s, i0 + 1, j0));
    let c = pk_cloud_moment(probe, pk_oct_wrapped_index(s, i0, j0 + 1));
    let d = pk_cloud_moment(probe, pk_oct_wrapped_index(s, i0 + 1, j0 + 1));
    let top = a + (b - a) * fx;
    let bottom = c + (d - c) * fx;
    return top + (bottom - top) * fy;
}

/// Chebyshev visibility of `p` from probe `i` (VisibilityMaps::visibility).
fn pk_cloud_probe_visibility(i: u32, p: vec3<f32>) -> f32 {
    let v = p - pk_cloud_position(i);
    let len = length(v);
    let d = len - pk_cloud_f(PK_CLOUD_H_VIS_BIAS);
    if !(d > 0.0) || !(len > 0.0) {
        return 1.0;
    }
    let m = pk_cloud_sample_moments(i, v / len);
    return pk_chebyshev_visibility(d, m.x, m.y, pk_cloud_f(PK_CLOUD_H_VIS_MIN_VARIANCE), pk_cloud_u(PK_CLOUD_H_VIS_SHARPNESS));
}

// --- the blend weights (ProbeCloud::weights_at, probes/blend.rs) ------------

/// `Ē_i` of probe `i`: the luminance of its DC coefficient as packed.
fn pk_cloud_luminance(i: u32) -> f32 {
    return pk_cloud_f(pk_cloud_off(PK_CLOUD_H_LUMINANCE) + i);
}

/// `s_i·Ē_i^−α` for the slots with a non-zero barycentric weight, 1
/// elsewhere (ProbeCloud::probe_factors, brightness_factors).
fn pk_cloud_probe_factors(probes: vec4<u32>, bary: vec4<f32>) -> vec4<f32> {
    var f = vec4<f32>(1.0);
    let alpha = pk_cloud_f(PK_CLOUD_H_BRIGHTNESS);
    if alpha > 0.0 {
        var e = vec4<f32>(0.0);
        var top = 0.0;
        for (var k = 0u; k < 4u; k = k + 1u) {
            if bary[k] != 0.0 {
                e[k] = pk_cloud_luminance(probes[k]);
            }
            // f32::max: a NaN operand yields the other one.
            if e[k] > top {
                top = e[k];
            }
        }
        if top > 0.0 && top <= 3.4028235e38 {
            for (var k = 0u; k < 4u; k = k + 1u) {
                if bary[k] != 0.0 {
                    f[k] = pow(max(e[k], 1e-3 * top), -alpha);
                }
            }
        }
    }
    if (pk_cloud_u(PK_CLOUD_H_FLAGS) & PK_CLOUD_FLAG_PROBE_WEIGHTS) != 0u {
        let base = pk_cloud_off(PK_CLOUD_H_PROBE_WEIGHTS);
        for (var k = 0u; k < 4u; k = k + 1u) {
            if bary[k] != 0.0 {
                f[k] = f[k] * pk_cloud_f(base + probes[k]);
            }
        }
    }
    return f;
}

/// Blend weights at `p` in cell `cell` (a tetrahedron, or PK_CLOUD_HULL | f
/// for hull face f): barycentric weights `b_i` (of the closest hull point
/// outside the hull) times cell visibility `c_i`, Chebyshev visibility
/// `v_i` and `f_i = s_i·Ē_i^−α`, renormalized; where cell visibility leaves
/// less than PK_HIDDEN_MASS_FLOOR of the weight in sight, blended towards
/// the cell's darkest probe, which takes all of it where none is in sight;
/// falling back to b·v·f, b·f, b where the sum vanishes
/// (probekit_runtime's ProbeCloud::weights_at, step for step).
fn pk_cloud_weights(cell: u32, p: vec3<f32>) -> PkCloudWeights {
    var probes: vec4<u32>;
    var bary: vec4<f32>;
    var used = 4u;
    var cell_index = cell;
    if (cell & PK_CLOUD_HULL) != 0u {
        let f = cell & ~PK_CLOUD_HULL;
        let q = pk_cloud_hull_probes(f);
        let closest = pk_cloud_closest_in_face(p, f);
        probes = vec4<u32>(q, 0u);
        bary = vec4<f32>(closest.weights, 0.0);
        used = 3u;
        cell_index = pk_cloud_u(PK_CLOUD_H_TETS) + f;
    } else {
        probes = pk_cloud_tet_probes(cell);
        bary = pk_cloud_bary(cell, p);
    }
    let flags = pk_cloud_u(PK_CLOUD_H_FLAGS);
    let alpha = pk_cloud_f(PK_CLOUD_H_BRIGHTNESS);
    if flags == 0u && alpha <= 0.0 {
        return PkCloudWeights(probes, bary);
    }
    let has_cells = (flags & PK_CLOUD_FLAG_CELLS) != 0u;
    var c = vec4<f32>(1.0);
    if has_cells {
        c = pk_cloud_cell_visibility(cell_index, used, bary, p, probes);
    }
    var v = vec4<f32>(1.0);
    if (flags & PK_CLOUD_FLAG_VISIBILITY) != 0u {
        for (var k = 0u; k < 4u; k = k + 1u) {
            if bary[k] != 0.0 {
                v[k] = pk_cloud_probe_visibility(probes[k], p);
            }
        }
    }
    let f = pk_cloud_probe_factors(probes, bary);
    let bcv = bary * c * v * f;
    var mass = 0.0;
    for (var k = 0u; k < used; k = k + 1u) {
        mass = mass + bary[k] * c[k];
    }
    // The cell's darkest probe (lowest Ē, the first on a tie).
    var dk = 0u;
    for (var k = 1u; k < used; k = k + 1u) {
        if pk_cloud_luminance(probes[k]) < pk_cloud_luminance(probes[dk]) {
            dk = k;
        }
    }
    var darkest = vec4<f32>(0.0);
    darkest[dk] = 1.0;
    let r = pk_normalized(bcv);
    if has_cells && mass > 0.0 && mass < PK_HIDDEN_MASS_FLOOR && r.ok {
        let t = mass / PK_HIDDEN_MASS_FLOOR;
        return PkCloudWeights(probes, t * r.w + (1.0 - t) * darkest);
    }
    if r.ok {
        return PkCloudWeights(probes, r.w);
    }
    if has_cells && mass == 0.0 {
        return PkCloudWeights(probes, darkest);
    }
    let rv = pk_normalized(bary * v * f);
    if rv.ok {
        return PkCloudWeights(probes, rv.w);
    }
    let rf = pk_normalized(bary * f);
    if rf.ok {
        return PkCloudWeights(probes, rf.w);
    }
    return PkCloudWeights(probes, bary);
}

// --- the blend (ProbeCloud::sh_at, directional_blend; cloud::directional) --

/// Directional blend factors of direction `d` for the cell's probes with
/// blend weights `w` (probekit_runtime::cloud::directional::factors).
fn pk_cloud_directional_factors(probes: vec4<u32>, w: vec4<f32>, d: u32, gamma: f32) -> vec4<f32> {
    let base = pk_cloud_off(PK_CLOUD_H_DIR_LUMINANCE);
    var lum: vec4<f32>;
    var total = 0.0;
    var top = 0.0;
    for (var k = 0u; k < 4u; k = k + 1u) {
        lum[k] = pk_cloud_f(base + 12u * probes[k] + d);
        if w[k] > 0.0 {
            total = total + w[k];
            if lum[k] > top {
                top = lum[k];
            }
        }
    }
    if !(top > 0.0 && pk_finite(top)) || gamma <= 0.0 || !(total > 0.0 && pk_finite(total)) {
        return vec4<f32>(1.0);
    }
    let l = max(lum, vec4<f32>(1e-3 * top));
    var inverse = 0.0;
    for (var k = 0u; k < 4u; k = k + 1u) {
        if w[k] > 0.0 {
            inverse = inverse + w[k] / l[k];
        }
    }
    let threshold = PK_DIRECTIONAL_RATIO * total / inverse;
    var f = vec4<f32>(1.0);
    for (var k = 0u; k < 4u; k = k + 1u) {
        if w[k] > 0.0 && l[k] > threshold {
            let x = l[k] / threshold;
            // directional::inverse_power: exact roots for common exponents.
            if gamma == 0.25 {
                f[k] = 1.0 / sqrt(sqrt(x));
            } else if gamma == 0.5 {
                f[k] = 1.0 / sqrt(x);
            } else if gamma == 1.0 {
                f[k] = 1.0 / x;
            } else {
                f[k] = pow(x, -gamma);
            }
        }
    }
    return f;
}

/// The directional blend of the cell (ProbeCloud::directional_blend): per
/// direction d of the twelve icosahedron vertices, the probes' irradiance
/// E_k(d) blended with weights w_k·f_k(d), projected back to radiance SH
/// bands ≤ 2 (directional::DirectionTable, tables packed in the buffer).
fn pk_cloud_directional_blend(probes: vec4<u32>, w: vec4<f32>, gamma: f32) -> PkShL2 {
    let n = pk_cloud_u(PK_CLOUD_H_COEFFS);
    let tables = pk_cloud_off(PK_CLOUD_H_DIR_TABLES);
    var sh: array<PkShL2, 4>;
    for (var k = 0u; k < 4u; k = k + 1u) {
        if w[k] > 0.0 {
            sh[k] = pk_cloud_probe_sh(probes[k]);
        }
    }
    var out: PkShL2;
    for (var d = 0u; d < 12u; d = d + 1u) {
        let f = pk_cloud_directional_factors(probes, w, d, gamma);
        var sum = 0.0;
        var acc = vec3<f32>(0.0);
        var plain = vec3<f32>(0.0);
        for (var k = 0u; k < 4u; k = k + 1u) {
            var e = vec3<f32>(0.0);
            if w[k] > 0.0 {
                for (var c = 0u; c < n; c = c + 1u) {
                    e = e + sh[k].c[c] * pk_cloud_f(tables + 9u * d + c);
                }
                let u = w[k] * f[k];
                sum = sum + u;
                acc = acc + e * u;
            }
            plain = plain + e * w[k];
        }
        var blended = plain;
        if sum > 0.0 && pk_finite(sum) {
            blended = acc / sum;
        }
        for (var c = 0u; c < n; c = c + 1u) {
            out.c[c] = out.c[c] + blended * pk_cloud_f(tables + 108u + 9u * d + c);
        }
    }
    return out;
}

/// The radiance SH of the cell's probes blended with weights `wt`: the
/// directional blend when the packed exponent γ > 0, else Σ w_k·sh_k over
/// the slots with w_k ≠ 0 (ProbeCloud::sh_at).
fn pk_cloud_blend(wt: PkCloudWeights) -> PkShL2 {
    let gamma = pk_cloud_f(PK_CLOUD_H_DIRECTIONAL);
    if gamma > 0.0 {
        return pk_cloud_directional_blend(wt.probes, wt.weights, gamma);
    }
    let n = pk_cloud_u(PK_CLOUD_H_COEFFS);
    var out: PkShL2;
    for (var k = 0u; k < 4u; k = k + 1u) {
        let w = wt.weights[k];
        if w != 0.0 {
            let sh = pk_cloud_probe_sh(wt.probes[k]);
            for (var c = 0u; c < n; c = c + 1u) {
                out.c[c] = out.c[c] + sh.c[c] * w;
            }
        }
    }
    return out;
}

/// Radiance SH at `p` in cell `cell` (ProbeCloud::sh_at): L2, or L1 with a
/// zero band 2 for an L1 cloud.
fn pk_cloud_sh(cell: u32, p: vec3<f32>) -> PkShL2 {
    return pk_cloud_blend(pk_cloud_weights(cell, p));
}

// --- run-time lights (probekit_runtime's probes/lights.rs) -------------------

/// Number of run-time lights packed (0 for a cloud without).
fn pk_cloud_light_count() -> u32 {
    return pk_cloud_u(PK_CLOUD_H_LIGHTS);
}

fn pk_cloud_u4(i: u32) -> vec4<u32> {
    return vec4<u32>(pk_cloud[i], pk_cloud[i + 1u], pk_cloud[i + 2u], pk_cloud[i + 3u]);
}

/// Run-time light `l` (world space; its record as a rig's near light).
fn pk_cloud_light(l: u32) -> PkRigLight {
    let r = pk_cloud_off(PK_CLOUD_H_LIGHT_RECORDS) + PK_RIG_LIGHT_WORDS * l;
    return pk_light_unpack(pk_cloud_u4(r), pk_cloud_u4(r + 4u), pk_cloud_u4(r + 8u), pk_cloud_u4(r + 12u));
}

/// Probe `i`'s visible fraction of run-time light `l`: its stored 8-bit
/// value / 255, 0 where the file lists none (LightOcclusion::value).
fn pk_cloud_probe_light_occlusion(i: u32, l: u32) -> f32 {
    let stride = (pk_cloud_light_count() + 3u) / 4u;
    let word = pk_cloud[pk_cloud_off(PK_CLOUD_H_LIGHT_OCCLUSION) + stride * i + l / 4u];
    return f32((word >> (8u * (l & 3u))) & 0xffu) / 255.0;
}

/// Run-time light `l`'s visible fraction blended with the weights `wt`:
/// Σ w_k·v_k over the slots with w_k ≠ 0 (Probes::light_occlusion).
fn pk_cloud_light_occlusion(wt: PkCloudWeights, l: u32) -> f32 {
    var v = 0.0;
    for (var k = 0u; k < 4u; k = k + 1u) {
        let w = wt.weights[k];
        if w != 0.0 {
            v = v + w * pk_cloud_probe_light_occlusion(wt.probes[k], l);
        }
    }
    return v;
}

/// The run-time lights' term at `p` for unit normal `n` with blend weights
/// `wt` (those of `pk_cloud_weights`, before any directional correction):
/// Σ_l pk_light_irradiance(light l, p, n) × its blended visible fraction,
/// skipping lights no probe of the blend sees; zero without lights (the
/// runtime's LightTerm::irradiance).
fn pk_cloud_lights_irradiance(wt: PkCloudWeights, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    var e = vec3<f32>(0.0);
    let count = pk_cloud_light_count();
    for (var l = 0u; l < count; l = l + 1u) {
        let v = pk_cloud_light_occlusion(wt, l);
        if v > 0.0 {
            e = e + v * pk_light_irradiance(pk_cloud_light(l), p, n);
        }
    }
    return e;
}

// --- irradiance ---------------------------------------------------------------

/// The SH part of the irradiance (not divided by π) at `p` in cell `cell`
/// for unit normal `n`, without the run-time lights' direct light
/// (ProbeCloud::irradiance, Probes::sh_irradiance).
fn pk_cloud_sh_irradiance(cell: u32, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return pk_irradiance_l2(pk_cloud_sh(cell, p), n);
}

/// Irradiance (not divided by π) at `p` in cell `cell` for unit normal `n`:
/// the SH part plus the run-time lights' term, one blend for both
/// (Probes::irradiance; pk_cloud_sh_irradiance for a cloud without lights).
fn pk_cloud_irradiance(cell: u32, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let wt = pk_cloud_weights(cell, p);
    return pk_irradiance_l2(pk_cloud_blend(wt), n) + pk_cloud_lights_irradiance(wt, p, n);
}

/// The SH part of the irradiance (not divided by π) at `p` in cell `cell`
/// for unit normal `n` by hallucinated ZH3 from the blended L1 (blend as
/// usual, then probekit_sh::zh3::zh3_hallucinated_irradiance of the
/// blend's bands ≤ 1): the evaluation an L1 cloud (13-byte codec) may
/// choose.
fn pk_cloud_sh_irradiance_zh3(cell: u32, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return pk_irradiance_zh3_hallucinated(pk_l2_to_l1(pk_cloud_sh(cell, p)), n);
}

/// pk_cloud_sh_irradiance_zh3 plus the run-time lights' term (an L1 file
/// in `L1Mode::Zh3Hallucinated`: Probes::irradiance).
fn pk_cloud_irradiance_zh3(cell: u32, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let wt = pk_cloud_weights(cell, p);
    let sh = pk_irradiance_zh3_hallucinated(pk_l2_to_l1(pk_cloud_blend(wt)), n);
    return sh + pk_cloud_lights_irradiance(wt, p, n);
}
