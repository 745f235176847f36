//! A synthetic "default bake" of a 100 k-probe cloud: a 47³ lattice of
//! probes at 1 m (103 823 probes, 584 016 Kuhn tetrahedra) in a building of
//! 8 m rooms, each lit to its own level (log-uniform over three decades),
//! with every section `probekit bake` stores by default: L2 `f32`
//! coefficients, 8×8 distance moments (the distance to the probe's room
//! walls), cell visibility at k = 4 (a corner sees a lattice point when both
//! are in the same room; cells inside one room are clear), an occluder plane
//! in every cell one wall cuts, fitted probe weights, brightness exponent 1
//! and directional exponent 0.5.

use glam::Vec3;
use probekit_runtime::cloud::cell_visibility::{
    lattice_numerators, lattice_position, record_from, DEFAULT_CELL_SUBDIVISION,
};
use probekit_runtime::cloud::visibility::{oct_decode, oct_texel_center};
use probekit_runtime::cloud::{
    face_neighbors, lattice_tets, CellPlanes, CellVisibility, TetMesh, HULL,
};
use probekit_runtime::format::{layout::NONE, DistanceMoments, ProbeFile, TetSection};

/// Probes per axis.
pub const K: u32 = 47;
/// Room size in metres; walls at `ROOM·i + WALL_OFFSET` on every axis.
const ROOM: f32 = 8.0;
const WALL_OFFSET: f32 = 4.5;
/// Distance-moment resolution and range.
const MOMENTS: u32 = 8;
const MAX_DISTANCE: f32 = 16.0;

/// A tiny deterministic generator (SplitMix64).
pub struct Rng(pub u64);

impl Rng {
    pub fn next_f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// The room holding `p`, per axis.
fn room(p: Vec3) -> [i32; 3] {
    [0, 1, 2].map(|a| ((p[a] - WALL_OFFSET) / ROOM).floor() as i32)
}

/// Distance from `p` along unit `d` to the walls of its room.
fn wall_distance(p: Vec3, d: Vec3) -> f32 {
    let r = room(p);
    let mut t = f32::INFINITY;
    for a in 0..3 {
        let lo = r[a] as f32 * ROOM + WALL_OFFSET;
        let wall = if d[a] > 0.0 { lo + ROOM } else { lo };
        if d[a] != 0.0 {
            t = t.min((wall - p[a]) / d[a]);
        }
    }
    t.clamp(0.0, MAX_DISTANCE)
}

/// The lattice's mesh (positions, Kuhn tetrahedra, neighbours).
pub fn mesh() -> TetMesh {
    let mut pos = Vec::new();
    for z in 0..K {
        for y in 0..K {
            for x in 0..K {
                pos.push(Vec3::new(x as f32, y as f32, z as f32));
            }
        }
    }
    let tets = lattice_tets([K; 3]);
    let n = face_neighbors(&tets).unwrap();
    TetMesh::new(pos, tets, n).unwrap()
}

/// L2 radiance SH of a probe at `p`: its room's level, band 1 pointing at
/// the room's light (the room's ceiling centre), a little band 2.
fn probe_sh(p: Vec3, level: f32, rng: &mut Rng) -> [Vec3; 9] {
    let r = room(p);
    let centre = Vec3::new(
        (r[0] as f32 + 0.5) * ROOM + WALL_OFFSET,
        (r[1] as f32 + 0.9) * ROOM + WALL_OFFSET,
        (r[2] as f32 + 0.5) * ROOM + WALL_OFFSET,
    );
    let to_light = (centre - p).normalize_or(Vec3::Y);
    let tint = Vec3::new(1.0, 0.85 + 0.1 * rng.next_f32(), 0.7 + 0.2 * rng.next_f32());
    let dc = tint * level;
    let b1 = 0.5 * level;
    let mut c = [Vec3::ZERO; 9];
    c[0] = dc;
    // Band 1 of a lobe towards `to_light`: (−y, z, −x) order l(l+1)+m.
    c[1] = tint * (-b1 * to_light.y);
    c[2] = tint * (b1 * to_light.z);
    c[3] = tint * (-b1 * to_light.x);
    for k in c.iter_mut().skip(4) {
        *k = tint * (0.1 * level * (rng.next_f32() - 0.5));
    }
    c
}

/// The file of the module docs, ready for `Probes::from_bytes`.
pub fn default_bake(plain: bool) -> ProbeFile {
    let mesh = mesh();
    let positions = mesh.positions().to_vec();
    let tets = mesh.tets().to_vec();
    let neighbours: Vec<[u32; 4]> = mesh
        .neighbors()
        .map(|n| n.map(|t| if t == HULL { NONE } else { t }))
        .collect();
    let barycentric = (0..tets.len() as u32)
        .map(|t| {
            let b = mesh.bary(t);
            b.rows.map(|r| [r.x, r.y, r.z, -r.dot(b.origin)])
        })
        .collect();
    let mut rng = Rng(2026);
    let mut levels = std::collections::HashMap::new();
    let coeffs: Vec<Vec3> = positions
        .iter()
        .flat_map(|&p| {
            let level = *levels
                .entry(room(p))
                .or_insert_with(|| 10f32.powf(3.0 * rng.next_f32() - 1.5));
            probe_sh(p, level, &mut rng)
        })
        .collect();
    let mut file = ProbeFile::cloud(positions.clone(), 3, &coeffs).unwrap();
    let f = file.as_cloud_mut().unwrap();
    f.tetrahedra = Some(TetSection {
        vertices: tets.clone(),
        neighbours,
        barycentric,
    });
    if plain {
        return file;
    }
    // Distance moments: each texel's distance to the probe's room walls.
    let res = MOMENTS;
    let dirs: Vec<Vec3> = (0..res * res)
        .map(|i| oct_decode(oct_texel_center(res, i % res, i / res)))
        .collect();
    let half = |x: f32| half::f16::from_f32(x).to_bits();
    let mut data = Vec::with_capacity(positions.len() * dirs.len() * 2);
    for &p in &positions {
        for &d in &dirs {
            let mu = wall_distance(p, d) / MAX_DISTANCE;
            data.push(half(mu));
            data.push(half((mu * mu * 1.02).min(1.0)));
        }
    }
    f.blend.distance_moments = Some(DistanceMoments {
        resolution: res,
        max_distance: MAX_DISTANCE,
        data,
    });
    // Cell visibility: a corner sees a lattice point of its cell when both
    // lie in the same room; an occluder plane where one wall cuts the cell.
    let k = DEFAULT_CELL_SUBDIVISION;
    let (lat4, lat3) = (lattice_numerators(4, k), lattice_numerators(3, k));
    let mut bits = Vec::new();
    let mut planes = (Vec::new(), Vec::new());
    let cell = |probes: &[u32], lattice: &[[u32; 4]], bits: &mut Vec<u8>| {
        let corners: Vec<Vec3> = probes.iter().map(|&i| positions[i as usize]).collect();
        let points: Vec<Vec3> = lattice
            .iter()
            .map(|n| lattice_position(probes, &positions, n, k))
            .collect();
        bits.extend(record_from(probes.len(), k, |v, l| {
            room(corners[v]) == room(points[l])
        }));
        corners
    };
    for (t, v) in tets.iter().enumerate() {
        let corners = cell(v, &lat4, &mut bits);
        let rooms: Vec<[i32; 3]> = corners.iter().map(|&c| room(c)).collect();
        let cut: Vec<usize> = (0..3)
            .filter(|&a| rooms.iter().any(|r| r[a] != rooms[0][a]))
            .collect();
        if let [a] = cut[..] {
            let lo = rooms.iter().map(|r| r[a]).min().unwrap();
            let wall = (lo + 1) as f32 * ROOM + WALL_OFFSET;
            let mut n = [0.0f32; 3];
            n[a] = 1.0;
            planes.0.push(t as u32);
            planes.1.push([n[0], n[1], n[2], wall]);
        }
    }
    for h in 0..mesh.hull_face_count() as u32 {
        cell(&mesh.hull_face_probes(h).unwrap(), &lat3, &mut bits);
    }
    let cells = CellVisibility::new(k, tets.len(), mesh.hull_face_count(), bits).unwrap();
    let b = &mut f.blend;
    b.cell_visibility = Some(cells);
    b.cell_planes = Some(CellPlanes::new(tets.len(), planes.0, planes.1).unwrap());
    // Fitted probe weights, and the exponents they were fitted with.
    b.probe_weights = Some(
        (0..positions.len())
            .map(|_| 0.5 + 1.5 * rng.next_f32())
            .collect(),
    );
    b.brightness_exponent = 1.0;
    b.directional_exponent = 0.5;
    file
}
