//! `pk_cloud`: a probe cloud for `shaders/probekit_cloud.wgsl`.

use super::lights::{light_occlusion_words, put_runtime_lights};
use super::{check_size, LayoutError};
use glam::Vec3;
use probekit_runtime::cloud::cell_visibility::record_bytes;
use probekit_runtime::cloud::directional::{DirectionTable, DIRECTIONAL_COEFFS, DIRECTIONS};
use probekit_runtime::cloud::{Location, TetMesh, WalkState};
use probekit_runtime::format::RuntimeLights;
use probekit_runtime::sh::LUMINANCE;
use probekit_runtime::{ProbeCloud, ProbeFile};
use std::collections::HashMap;
use std::ops::Range;

/// Words of the header at the start of `pk_cloud`.
pub const CLOUD_HEADER_WORDS: usize = 32;

/// The header words of `pk_cloud`, by their WGSL constant names
/// (`shaders/probekit_cloud.wgsl`; a test checks that the two agree).
/// Counts: probes, tetrahedra, hull faces, coefficients per probe
/// (`min(order², 9)`). Settings: flags ([`CLOUD_FLAG_VISIBILITY`], …),
/// brightness exponent α and directional exponent γ (f32 bits), the
/// distance moments' resolution, bias (m), sharpness, minimum variance
/// (m²) and maximum distance (m), the cell lattice's subdivision. Then the
/// word offset of each section. Then the run-time lights: their count (0
/// without), the word offsets of their records and of the probes'
/// occlusion rows ([`pack_cloud_with_lights`]). Words 29–31 are zero.
pub const CLOUD_HEADER: [(&str, usize); 29] = [
    ("PK_CLOUD_H_PROBES", 0),
    ("PK_CLOUD_H_TETS", 1),
    ("PK_CLOUD_H_HULL_FACES", 2),
    ("PK_CLOUD_H_COEFFS", 3),
    ("PK_CLOUD_H_FLAGS", 4),
    ("PK_CLOUD_H_BRIGHTNESS", 5),
    ("PK_CLOUD_H_DIRECTIONAL", 6),
    ("PK_CLOUD_H_VIS_RESOLUTION", 7),
    ("PK_CLOUD_H_VIS_BIAS", 8),
    ("PK_CLOUD_H_VIS_SHARPNESS", 9),
    ("PK_CLOUD_H_VIS_MIN_VARIANCE", 10),
    ("PK_CLOUD_H_VIS_MAX_DISTANCE", 11),
    ("PK_CLOUD_H_CELL_SUBDIVISION", 12),
    ("PK_CLOUD_H_POSITIONS", 13),
    ("PK_CLOUD_H_COEFFICIENTS", 14),
    ("PK_CLOUD_H_LUMINANCE", 15),
    ("PK_CLOUD_H_DIR_LUMINANCE", 16),
    ("PK_CLOUD_H_PROBE_WEIGHTS", 17),
    ("PK_CLOUD_H_TET_RECORDS", 18),
    ("PK_CLOUD_H_HULL_RECORDS", 19),
    ("PK_CLOUD_H_MOMENTS", 20),
    ("PK_CLOUD_H_CELLS", 21),
    ("PK_CLOUD_H_CELL_BITS", 22),
    ("PK_CLOUD_H_PLANES", 23),
    ("PK_CLOUD_H_DIR_TABLES", 24),
    ("PK_CLOUD_H_START_GRID", 25),
    ("PK_CLOUD_H_LIGHTS", 26),
    ("PK_CLOUD_H_LIGHT_RECORDS", 27),
    ("PK_CLOUD_H_LIGHT_OCCLUSION", 28),
];

const H_PROBES: usize = 0;
const H_TETS: usize = 1;
const H_HULL_FACES: usize = 2;
const H_COEFFS: usize = 3;
const H_FLAGS: usize = 4;
const H_BRIGHTNESS: usize = 5;
const H_DIRECTIONAL: usize = 6;
const H_VIS_RESOLUTION: usize = 7;
const H_VIS_BIAS: usize = 8;
const H_VIS_SHARPNESS: usize = 9;
const H_VIS_MIN_VARIANCE: usize = 10;
const H_VIS_MAX_DISTANCE: usize = 11;
const H_CELL_SUBDIVISION: usize = 12;
const H_POSITIONS: usize = 13;
const H_COEFFICIENTS: usize = 14;
const H_LUMINANCE: usize = 15;
const H_DIR_LUMINANCE: usize = 16;
const H_PROBE_WEIGHTS: usize = 17;
const H_TET_RECORDS: usize = 18;
const H_HULL_RECORDS: usize = 19;
const H_MOMENTS: usize = 20;
const H_CELLS: usize = 21;
const H_CELL_BITS: usize = 22;
const H_PLANES: usize = 23;
const H_DIR_TABLES: usize = 24;
const H_START_GRID: usize = 25;
const H_LIGHTS: usize = 26;
const H_LIGHT_RECORDS: usize = 27;
const H_LIGHT_OCCLUSION: usize = 28;

/// Flag: Chebyshev visibility from the distance moments is on.
pub const CLOUD_FLAG_VISIBILITY: u32 = 1;
/// Flag: cell visibility (lattice bits and occluder planes) is on.
pub const CLOUD_FLAG_CELLS: u32 = 2;
/// Flag: the fitted probe weights are on.
pub const CLOUD_FLAG_PROBE_WEIGHTS: u32 = 4;

/// Cell code bit of a hull face (`PK_CLOUD_HULL`): a point outside the
/// convex hull, lit from hull face `code & !CLOUD_HULL`; also marks hull
/// faces among a tetrahedron's neighbours and occluder planes in the cell
/// table.
pub const CLOUD_HULL: u32 = 1 << 31;
/// A cell-table entry of a clear cell (`PK_CLOUD_NONE`).
pub const CLOUD_NONE: u32 = u32::MAX;
/// Words per tetrahedron (`PK_CLOUD_TET_WORDS`): its four probes, the
/// barycentric rows (9 f32) and origin (3 f32) of
/// [`probekit_runtime::cloud::BaryMatrix`], and its four neighbours
/// (opposite each vertex; `CLOUD_HULL | f` across hull face `f`).
pub const CLOUD_TET_WORDS: usize = 20;
/// Words per hull face (`PK_CLOUD_HULL_WORDS`): its three probes `a, b, c`
/// (outward winding, [`TetMesh::hull_face_probes`]), the hull faces across
/// the edges opposite them, the rows `r_b, r_c` (3 f32 each) with
/// `λ_b = r_b·(p − a)`, `λ_c = r_c·(p − a)` the barycentric coordinates of
/// the projection of `p` onto the face's plane, and the rows `e_ab, e_ac,
/// e_bc` (3 f32 each), `e_uv = (v − u)/|v − u|²`, giving the parameter
/// `e_uv·(p − u)` along each edge of the closest point of its line; rows
/// computed in f64.
pub const CLOUD_HULL_WORDS: usize = 21;

/// A packed `pk_cloud` buffer.
#[derive(Clone, Debug, PartialEq)]
pub struct PackedCloud {
    /// The buffer's words (upload [`super::words_to_bytes`] of them).
    pub words: Vec<u32>,
    /// Word range of the coefficients (`min(order², 9)` RGB coefficients
    /// per probe, probe after probe, f32 bits): an engine that relights the
    /// cloud rewrites only these words. The brightness luminances stay those
    /// packed, as the runtime keeps the ones it was built with.
    pub coefficients: Range<usize>,
    /// Word range of the run-time light records ([`super::RIG_LIGHT_WORDS`]
    /// words per light, [`super::pack_rig_light`] with share 1; empty
    /// without run-time lights): an engine that dims a light with its group,
    /// or moves it, rewrites that light's record here.
    pub lights: Range<usize>,
}

/// The cell code of a located point (`Location` of
/// [`TetMesh::locate`]): the tetrahedron index, or [`CLOUD_HULL`] `|` the
/// hull face outside the hull — the `cell` argument of `pk_cloud_weights`,
/// `pk_cloud_sh` and `pk_cloud_irradiance`.
pub fn cell_code(location: &Location) -> u32 {
    match *location {
        Location::Inside { tet, .. } => tet,
        Location::Outside { hull_face, .. } => CLOUD_HULL | hull_face,
    }
}

/// [`pack_cloud_with_lights`] of the cloud a file holds
/// (`ProbeCloud::from_file`: its blend data switched on as stored) and of
/// its run-time lights, if it has any.
pub fn pack_cloud_file(file: &ProbeFile) -> Result<PackedCloud, LayoutError> {
    let lights = file.probes().and_then(|p| p.runtime_lights.as_ref());
    pack_cloud_with_lights(&ProbeCloud::from_file(file)?, lights)
}

/// Appends `x` as f32 bits.
fn put_f(out: &mut Vec<u32>, x: f32) {
    out.push(x.to_bits());
}

fn put_v3(out: &mut Vec<u32>, v: Vec3) {
    out.extend(v.to_array().map(f32::to_bits));
}

/// Packs `cloud` — its probes, mesh, blend data and switches as they are —
/// into the `pk_cloud` buffer (`docs/shaders.md`, "The cloud buffer").
/// The runtime's load-time data is computed the runtime's way: each probe's
/// DC luminance `Ē_i` and its twelve directional luminances from the
/// cloud's current coefficients, and the directional blend's tables
/// (read back from [`DirectionTable`] exactly). Coefficients past band 2
/// are dropped (the shaders blend L2; irradiance loses the band-4 term,
/// `A_4 = π/24`, of an order ≥ 5 cloud). No run-time lights
/// (`PK_CLOUD_H_LIGHTS` = 0): [`pack_cloud_with_lights`] with `None`.
pub fn pack_cloud(cloud: &ProbeCloud) -> Result<PackedCloud, LayoutError> {
    pack_cloud_with_lights(cloud, None)
}

/// [`pack_cloud`] with a file's run-time lights
/// ([`ProbeSet::runtime_lights`](probekit_runtime::format::ProbeSet)), whose
/// direct light the probes' SH leaves out, for `pk_cloud_irradiance` to add
/// as `probekit_runtime::Probes::irradiance` does:
/// `Σ_l pk_light_irradiance(light_l, p, n) · Σ_k w_k·v_{k,l}` over the
/// blend's probes `k` and weights `w_k` (`pk_cloud_weights`).
///
/// Layout: header word `PK_CLOUD_H_LIGHTS` holds the light count `L` (0
/// with `None`). At word `PK_CLOUD_H_LIGHT_RECORDS`, one light record per
/// light ([`super::RIG_LIGHT_WORDS`] words, [`super::pack_rig_light`] with
/// share 1: the rig's record, world coordinates). At word
/// `PK_CLOUD_H_LIGHT_OCCLUSION`, one row of `⌈L/4⌉` words
/// ([`super::light_occlusion_words`]) per probe, probe after probe: probe
/// `i`'s stored 8-bit visible fraction `v` of light `l` (the file's
/// `OCCL` value, 0 where the probe does not list the light) is byte
/// `l mod 4` (least significant first) of word `⌈L/4⌉·i + l/4`, and
/// the fraction is `v/255`. Both sections come before the start grid.
/// Occlusion of another number of probes than the cloud's is a
/// [`LayoutError::LightOcclusion`].
pub fn pack_cloud_with_lights(
    cloud: &ProbeCloud,
    lights: Option<&RuntimeLights>,
) -> Result<PackedCloud, LayoutError> {
    let mesh = cloud.mesh();
    let probes = cloud.probe_count();
    let tets = mesh.tets().len();
    let hull = mesh.hull_face_count();
    let n = cloud.coeffs_per_probe().min(DIRECTIONAL_COEFFS);
    let mut h = vec![0u32; CLOUD_HEADER_WORDS];
    h[H_PROBES] = probes as u32;
    h[H_TETS] = tets as u32;
    h[H_HULL_FACES] = hull as u32;
    h[H_COEFFS] = n as u32;
    let mut flags = 0;
    if cloud.visibility_enabled() {
        flags |= CLOUD_FLAG_VISIBILITY;
    }
    if cloud.cell_visibility_enabled() {
        flags |= CLOUD_FLAG_CELLS;
    }
    if cloud.probe_weighting_enabled() {
        flags |= CLOUD_FLAG_PROBE_WEIGHTS;
    }
    h[H_FLAGS] = flags;
    h[H_BRIGHTNESS] = cloud.brightness_weighting().to_bits();
    h[H_DIRECTIONAL] = cloud.directional_brightness().to_bits();
    let mut w = h;

    // Per probe: positions, coefficients, Ē_i, directional luminances, s_i.
    w[H_POSITIONS] = w.len() as u32;
    for p in mesh.positions() {
        put_v3(&mut w, *p);
    }
    w[H_COEFFICIENTS] = w.len() as u32;
    let coeff_start = w.len();
    for i in 0..probes {
        for c in &cloud.probe_sh(i)[..n] {
            put_v3(&mut w, *c);
        }
    }
    let coefficients = coeff_start..w.len();
    let table = DirectionTable::new();
    w[H_LUMINANCE] = w.len() as u32;
    for i in 0..probes {
        put_f(&mut w, LUMINANCE.dot(cloud.probe_sh(i)[0]));
    }
    w[H_DIR_LUMINANCE] = w.len() as u32;
    for i in 0..probes {
        for l in table.luminance(cloud.probe_sh(i)) {
            put_f(&mut w, l);
        }
    }
    w[H_PROBE_WEIGHTS] = w.len() as u32;
    if let Some(s) = cloud.probe_weights() {
        for &x in s {
            put_f(&mut w, x);
        }
    }

    // Tetrahedra and hull faces.
    let hull_faces = hull_faces(mesh)?;
    w[H_TET_RECORDS] = w.len() as u32;
    let mut next_hull = 0u32;
    for t in 0..tets {
        w.extend(mesh.tets()[t]);
        let b = mesh.bary(t as u32);
        for r in b.rows {
            put_v3(&mut w, r);
        }
        put_v3(&mut w, b.origin);
        for face in 0..4 {
            match mesh.neighbor(t as u32, face) {
                Some(u) => w.push(u),
                None => {
                    w.push(CLOUD_HULL | next_hull);
                    next_hull += 1;
                }
            }
        }
    }
    w[H_HULL_RECORDS] = w.len() as u32;
    for f in &hull_faces {
        w.extend(f.probes);
        w.extend(f.adjacent);
        let [a, b, c] = f.probes.map(|i| mesh.positions()[i as usize].as_dvec3());
        let (ab, ac, bc) = (b - a, c - a, c - b);
        let (g00, g01, g11) = (ab.dot(ab), ab.dot(ac), ac.dot(ac));
        let det = g00 * g11 - g01 * g01;
        for r in [
            (ab * g11 - ac * g01) / det,
            (ac * g00 - ab * g01) / det,
            ab / g00,
            ac / g11,
            bc / bc.dot(bc),
        ] {
            put_v3(&mut w, r.as_vec3());
        }
    }

    // Distance moments, decoded (VisibilityMaps::probe_map).
    w[H_MOMENTS] = w.len() as u32;
    if let Some(m) = cloud.visibility_maps() {
        w[H_VIS_RESOLUTION] = m.resolution();
        w[H_VIS_BIAS] = m.bias().to_bits();
        w[H_VIS_SHARPNESS] = m.sharpness();
        w[H_VIS_MIN_VARIANCE] = m.min_variance().to_bits();
        w[H_VIS_MAX_DISTANCE] = m.max_distance().to_bits();
        for i in 0..probes {
            for &[mu, mu2] in m.probe_map(i) {
                put_f(&mut w, mu);
                put_f(&mut w, mu2);
            }
        }
    }

    // The cell table (a record's byte offset, CLOUD_HULL | plane, or
    // CLOUD_NONE), then the records as stored.
    let mut cells = vec![CLOUD_NONE; tets + hull];
    let mut bits: &[u8] = &[];
    if let Some(c) = cloud.cell_visibility_bits() {
        let k = c.subdivision();
        w[H_CELL_SUBDIVISION] = k;
        let mut offset = 0usize;
        for (i, cell) in cells.iter_mut().enumerate() {
            if c.mask()[i >> 3] >> (i & 7) & 1 != 0 {
                *cell = offset as u32;
                offset += record_bytes(if i < tets { 4 } else { 3 }, k);
            }
        }
        bits = c.records();
    }
    let mut planes: &[[f32; 4]] = &[];
    if let Some(p) = cloud.cell_planes() {
        for (j, &t) in p.tets().iter().enumerate() {
            cells[t as usize] = CLOUD_HULL | j as u32;
        }
        planes = p.planes();
    }
    w[H_CELLS] = w.len() as u32;
    w.extend(&cells);
    w[H_CELL_BITS] = w.len() as u32;
    w.extend(bits.chunks(4).map(|b| {
        let mut q = [0u8; 4];
        q[..b.len()].copy_from_slice(b);
        u32::from_le_bytes(q)
    }));
    w[H_PLANES] = w.len() as u32;
    for p in planes {
        w.extend(p.map(f32::to_bits));
    }

    // The directional tables, read back exactly: the irradiance of a unit
    // coefficient, and the projection of a unit irradiance sample.
    w[H_DIR_TABLES] = w.len() as u32;
    let mut irradiance = [[0.0f32; DIRECTIONAL_COEFFS]; DIRECTIONS];
    for c in 0..DIRECTIONAL_COEFFS {
        let mut unit = [Vec3::ZERO; DIRECTIONAL_COEFFS];
        unit[c] = Vec3::ONE;
        for (d, e) in table.irradiance(&unit).iter().enumerate() {
            irradiance[d][c] = e.x;
        }
    }
    for row in irradiance {
        w.extend(row.map(f32::to_bits));
    }
    for d in 0..DIRECTIONS {
        let mut unit = [Vec3::ZERO; DIRECTIONS];
        unit[d] = Vec3::ONE;
        let mut out = [Vec3::ZERO; DIRECTIONAL_COEFFS];
        table.project(&unit, &mut out);
        w.extend(out.map(|v| v.x.to_bits()));
    }

    // The run-time lights: records, then each probe's occlusion row.
    let mut light_records = w.len()..w.len();
    w[H_LIGHT_RECORDS] = w.len() as u32;
    w[H_LIGHT_OCCLUSION] = w.len() as u32;
    if let Some(l) = lights {
        let count = l.lights.len();
        check_size("cloud", w.len() + light_occlusion_words(count) * probes)?;
        let s = put_runtime_lights(l, probes, &mut w)?;
        w[H_LIGHTS] = count as u32;
        w[H_LIGHT_RECORDS] = s.records.start as u32;
        w[H_LIGHT_OCCLUSION] = s.occlusion as u32;
        light_records = s.records;
    }

    w[H_START_GRID] = w.len() as u32;
    start_grid(mesh, &mut w);
    check_size("cloud", w.len())?;
    Ok(PackedCloud {
        words: w,
        coefficients,
        lights: light_records,
    })
}

/// One hull face as packed.
struct HullFace {
    probes: [u32; 3],
    adjacent: [u32; 3],
}

/// The mesh's hull faces in its order, with their adjacency (the face
/// across the edge opposite each vertex, as `TetMesh::new` matches directed
/// edges). The runtime numbers hull faces in the order of the tetrahedron
/// faces without a neighbour; checked against the faces' probes.
fn hull_faces(mesh: &TetMesh) -> Result<Vec<HullFace>, LayoutError> {
    let count = mesh.hull_face_count();
    let mut faces = Vec::with_capacity(count);
    for t in 0..mesh.tets().len() {
        for i in 0..4 {
            if mesh.neighbor(t as u32, i).is_some() {
                continue;
            }
            let h = faces.len();
            let probes = mesh
                .hull_face_probes(h as u32)
                .ok_or(LayoutError::HullOrder { face: h })?;
            let mut a = probes;
            let mut b: Vec<u32> = (0..4)
                .filter(|&k| k != i)
                .map(|k| mesh.tets()[t][k])
                .collect();
            a.sort_unstable();
            b.sort_unstable();
            if a[..] != b[..] {
                return Err(LayoutError::HullOrder { face: h });
            }
            faces.push(HullFace {
                probes,
                adjacent: [CLOUD_NONE; 3],
            });
        }
    }
    if faces.len() != count {
        return Err(LayoutError::HullOrder { face: faces.len() });
    }
    let mut edges = HashMap::with_capacity(3 * count);
    for (h, f) in faces.iter().enumerate() {
        for k in 0..3 {
            edges.insert((f.probes[(k + 1) % 3], f.probes[(k + 2) % 3]), h as u32);
        }
    }
    for (h, f) in faces.iter_mut().enumerate() {
        for k in 0..3 {
            let (a, b) = (f.probes[(k + 1) % 3], f.probes[(k + 2) % 3]);
            f.adjacent[k] = *edges
                .get(&(b, a))
                .ok_or(LayoutError::HullOrder { face: h })?;
        }
    }
    Ok(faces)
}

/// The start grid of `pk_cloud_locate` (the runtime's jump-and-walk grid:
/// about one cell per 4 probes over the tetrahedra's bounding box, at most
/// 64 per axis): origin (3 f32), cells per metre (3 f32), cells per axis
/// (3 u32), then per cell (x fastest) the tetrahedron the runtime's walk
/// reaches from the cell's centre.
fn start_grid(mesh: &TetMesh, w: &mut Vec<u32>) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for t in mesh.tets() {
        for &v in t {
            lo = lo.min(mesh.positions()[v as usize]);
            hi = hi.max(mesh.positions()[v as usize]);
        }
    }
    let ext = (hi - lo).max(Vec3::splat(1e-6));
    let target = (mesh.positions().len() as f32 / 4.0).clamp(1.0, 64.0 * 64.0 * 64.0);
    let cell = (ext.x * ext.y * ext.z / target).cbrt();
    let dims = (ext / cell).ceil().clamp(Vec3::ONE, Vec3::splat(64.0));
    let dims = [dims.x as u32, dims.y as u32, dims.z as u32];
    let per_metre = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) / ext;
    put_v3(w, lo);
    put_v3(w, per_metre);
    w.extend(dims);
    let mut state = WalkState::new();
    for iz in 0..dims[2] {
        for iy in 0..dims[1] {
            for ix in 0..dims[0] {
                let c = lo + (Vec3::new(ix as f32, iy as f32, iz as f32) + 0.5) / per_metre;
                mesh.locate(c, &mut state);
                w.push(state.last_tet().unwrap_or(0));
            }
        }
    }
}
