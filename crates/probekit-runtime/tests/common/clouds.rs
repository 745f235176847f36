//! Random probe clouds with every blend section (distance moments, cell
//! visibility bits, occluder planes, fitted probe weights, brightness and
//! directional exponents), for tests that compare query paths.
#![allow(dead_code)]

use super::Rng;
use glam::Vec3;
use probekit_runtime::cloud::cell_visibility::record_from;
use probekit_runtime::cloud::{
    face_neighbors, lattice_tets, CellPlanes, CellVisibility, ProbeCloud, TetMesh, VisibilityMaps,
};

/// What to attach to a random cloud.
#[derive(Clone, Copy, Debug)]
pub struct Blend {
    pub moments: bool,
    pub cells: bool,
    pub planes: bool,
    pub weights: bool,
    pub alpha: f32,
    pub gamma: f32,
}

impl Blend {
    /// Everything on, at the given exponents.
    pub fn all(alpha: f32, gamma: f32) -> Self {
        Blend {
            moments: true,
            cells: true,
            planes: true,
            weights: true,
            alpha,
            gamma,
        }
    }

    /// Nothing: the plain barycentric blend.
    pub fn none() -> Self {
        Blend {
            moments: false,
            cells: false,
            planes: false,
            weights: false,
            alpha: 0.0,
            gamma: 0.0,
        }
    }

    /// A random choice of sections and exponents.
    pub fn random(rng: &mut Rng) -> Self {
        let alphas = [0.0, 0.5, 1.0, 1.7];
        let gammas = [0.0, 0.25, 0.5, 0.7, 1.0, 1.3];
        let weights = rng.below(4) != 0;
        Blend {
            moments: rng.below(3) != 0,
            cells: rng.below(3) != 0,
            planes: rng.below(2) != 0,
            weights,
            alpha: if weights { alphas[rng.below(4)] } else { 0.0 },
            gamma: if weights { gammas[rng.below(6)] } else { 0.0 },
        }
    }
}

/// The positions of a `dims` lattice of unit spacing, interior points moved
/// by up to ±0.15 (the hull stays the lattice's box, so it is convex), and
/// its Kuhn tetrahedralization.
pub fn jittered_lattice(dims: [u32; 3], rng: &mut Rng) -> TetMesh {
    let mut pos = Vec::new();
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let c = [x, y, z];
                let interior = (0..3).all(|a| c[a] > 0 && c[a] + 1 < dims[a]);
                let j = if interior {
                    rng.vec3() * 0.15
                } else {
                    Vec3::ZERO
                };
                pos.push(Vec3::new(x as f32, y as f32, z as f32) + j);
            }
        }
    }
    let tets = lattice_tets(dims);
    let n = face_neighbors(&tets).unwrap();
    TetMesh::new(pos, tets, n).unwrap()
}

/// Radiance SH of `order` bands for a probe of mean brightness `level`:
/// DC grey-ish around `level`, band 1 up to ±0.8 of it, higher bands up to
/// ±0.3 of it.
pub fn random_sh(order: u32, level: f32, rng: &mut Rng) -> Vec<Vec3> {
    let n = (order * order) as usize;
    (0..n)
        .map(|c| {
            let scale = match c {
                0 => 1.0,
                1..=3 => 0.8,
                _ => 0.3,
            };
            if c == 0 {
                Vec3::splat(level) * (Vec3::ONE + rng.vec3() * 0.2)
            } else {
                rng.vec3() * (scale * level)
            }
        })
        .collect()
}

/// A random cloud on a jittered `dims` lattice with SH of `order` bands
/// (probe brightness log-uniform over four decades, so the brightness and
/// directional factors matter) and the sections `blend` asks for.
pub fn random_cloud(dims: [u32; 3], order: u32, blend: Blend, rng: &mut Rng) -> ProbeCloud {
    let mesh = jittered_lattice(dims, rng);
    let probes = mesh.positions().len();
    let coeffs: Vec<Vec3> = (0..probes)
        .flat_map(|_| {
            let level = 10f32.powf(2.0 * rng.f32());
            random_sh(order, level, rng)
        })
        .collect();
    let (tets, faces) = (mesh.tets().len(), mesh.hull_face_count());
    let positions = mesh.positions().to_vec();
    let tet_vertices = mesh.tets().to_vec();
    let mut cloud = ProbeCloud::new(mesh, order, coeffs).unwrap();
    if blend.moments {
        let res = 2 + rng.below(7) as u32;
        let moments = (0..probes * (res * res) as usize)
            .map(|_| {
                let mu = 0.3 + 2.5 * (rng.f32() * 0.5 + 0.5);
                [mu, mu * mu * (1.0 + 0.2 * (rng.f32() * 0.5 + 0.5))]
            })
            .collect();
        let maps = VisibilityMaps::new(res, 10.0, moments).unwrap();
        cloud.set_visibility_maps(Some(maps)).unwrap();
    }
    if blend.cells {
        let k = 1 + rng.below(4) as u32;
        let mut bits = Vec::new();
        for vertices in (0..tets).map(|_| 4).chain((0..faces).map(|_| 3)) {
            let kind = rng.below(4);
            bits.extend(record_from(vertices, k, |_, _| match kind {
                0 => false,
                1 => rng.below(2) == 0,
                _ => true,
            }));
        }
        let cells = CellVisibility::new(k, tets, faces, bits).unwrap();
        if blend.planes {
            let ids: Vec<u32> = (0..tets as u32)
                .filter(|&t| cells.tet_has_record(t) && rng.below(2) == 0)
                .collect();
            let planes = ids
                .iter()
                .map(|&t| {
                    let c = tet_vertices[t as usize]
                        .iter()
                        .map(|&i| positions[i as usize])
                        .sum::<Vec3>()
                        / 4.0;
                    let n = (rng.vec3() + Vec3::new(0.0, 0.0, 1e-3)).normalize();
                    let off = c + rng.vec3() * 0.1;
                    [n.x, n.y, n.z, n.dot(off)]
                })
                .collect();
            cloud
                .set_cell_planes(Some(CellPlanes::new(tets, ids, planes).unwrap()))
                .unwrap();
        }
        cloud.set_cell_visibility_bits(Some(cells)).unwrap();
    }
    if blend.weights {
        let w = (0..probes).map(|_| 10f32.powf(0.5 * rng.f32())).collect();
        cloud.set_probe_weights(Some(w)).unwrap();
        cloud.set_brightness_weighting(blend.alpha).unwrap();
        cloud.set_directional_brightness(blend.gamma).unwrap();
    }
    cloud
}
