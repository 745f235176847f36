//! Query speed on ~100 k probes.
//!
//! `cloud_100k`: irradiance queries (L2, one thread) on a synthetic default
//! bake of a 47³ probe lattice in a building of 8 m rooms (`query/scene.rs`:
//! every section `probekit bake` stores by default): the walk alone
//! (`TetMesh::weights_at`), the plain barycentric blend (a file with
//! positions, coefficients and tetrahedra only) and the default blend, each
//! for coherent queries (one object moving in 5 cm steps through the rooms,
//! one `ObjectState`) and cold ones (random points, a fresh state each).
//!
//! `query_kuhn47`: point location alone on the Freudenthal (Kuhn)
//! triangulation of a 47³ probe grid (103 823 probes, 584 K tetrahedra,
//! maximally co-spherical): cold random queries, coherent queries, and
//! queries outside the hull (closest-hull-point outer cells).
//!
//! `cloud_visibility`: the cost of each blend section on a 20³ Kuhn grid
//! (distance moments, cell visibility, both, and both with fitted probe
//! weights; cell visibility with occluder planes; everything with the
//! brightness exponent, then with directional brightness on top).
//! Random Delaunay clouds are benchmarked in `probekit/benches/delaunay.rs`.

#[path = "query/scene.rs"]
mod scene;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use probekit_runtime::cloud::{
    cell_visibility, face_neighbors, lattice_tets, CellPlanes, CellVisibility, ProbeCloud, TetMesh,
    VisibilityMaps, WalkState,
};
use probekit_runtime::{LoadOptions, ObjectState, Probes};
use std::hint::black_box;

fn kuhn_grid(k: u32) -> TetMesh {
    let mut pos = Vec::new();
    for z in 0..k {
        for y in 0..k {
            for x in 0..k {
                pos.push(Vec3::new(x as f32, y as f32, z as f32));
            }
        }
    }
    let tets = lattice_tets([k; 3]);
    let n = face_neighbors(&tets).unwrap();
    TetMesh::new(pos, tets, n).unwrap()
}

fn points(n: usize, seed: u64, lo: f32, hi: f32) -> Vec<Vec3> {
    let mut s = seed;
    let mut f = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((s >> 40) as f32 / (1u64 << 24) as f32)
    };
    (0..n).map(|_| Vec3::new(f(), f(), f())).collect()
}

fn bench(c: &mut Criterion) {
    let m = kuhn_grid(47);
    const N: usize = 10_000;
    let cold = points(N, 1, 0.0, 46.0);
    let mut p = Vec3::splat(23.0);
    let dirs = points(N, 2, -1.0, 1.0);
    // A moving object: 5 cm steps (1/20 of the probe spacing), bouncing in the box.
    let coherent: Vec<Vec3> = dirs
        .iter()
        .map(|d| {
            p = (p + Vec3::new(0.05, 0.02, 0.01) + *d * 0.01).rem_euclid(Vec3::splat(46.0));
            p
        })
        .collect();
    let outside = points(N, 3, -20.0, 66.0);
    let mut g = c.benchmark_group("query_kuhn47");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("cold_random", |b| {
        b.iter(|| {
            for &q in &cold {
                black_box(m.weights_at(q, &mut WalkState::new()));
            }
        })
    });
    g.bench_function("coherent_moving", |b| {
        let mut s = WalkState::new();
        b.iter(|| {
            for &q in &coherent {
                black_box(m.weights_at(q, &mut s));
            }
        })
    });
    g.bench_function("cold_random_box_with_outside", |b| {
        b.iter(|| {
            for &q in &outside {
                black_box(m.weights_at(q, &mut WalkState::new()));
            }
        })
    });
    g.finish();
}

/// Cost of visibility-weighted blending: `ProbeCloud::irradiance` (L2 SH)
/// on a 20³ Kuhn grid (8 000 probes, 8×8 distance-moment maps of random
/// plausible moments), coherent queries (one object moving in small steps),
/// weighting on and off.
fn visibility(c: &mut Criterion) {
    let k = 20;
    let mesh = kuhn_grid(k);
    let probes = mesh.positions().len();
    let coeffs = (0..probes * 9)
        .map(|i| Vec3::splat((i % 7) as f32 * 0.1))
        .collect();
    let mut cloud = ProbeCloud::new(mesh, 3, coeffs).unwrap();
    let mut s = 1u64;
    let moments: Vec<[f32; 2]> = (0..probes * 64)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let mu = 0.3 + 2.0 * ((s >> 40) as f32 / (1u64 << 24) as f32);
            [mu, mu * mu * 1.05]
        })
        .collect();
    cloud
        .set_visibility_maps(Some(VisibilityMaps::new(8, 40.0, moments).unwrap()))
        .unwrap();
    // Cell visibility at the default k: three cells in four clear (a baked
    // demo cloud has 73 % clear tetrahedra; they have no record), the others
    // pseudo-random bits (padding bits clear).
    let (tets, faces) = (cloud.mesh().tets().len(), cloud.mesh().hull_face_count());
    let k = cell_visibility::DEFAULT_CELL_SUBDIVISION;
    let mut bits: Vec<u8> = Vec::new();
    for vertices in (0..tets).map(|_| 4).chain((0..faces).map(|_| 3)) {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let clear = (s >> 60) % 4 != 0;
        bits.extend(cell_visibility::record_from(vertices, k, |_, _| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            clear || (s >> 62) != 0
        }));
    }
    cloud
        .set_cell_visibility_bits(Some(CellVisibility::new(k, tets, faces, bits).unwrap()))
        .unwrap();
    // Fitted probe weights, switched on for the last case only.
    cloud
        .set_probe_weights(Some(
            (0..probes).map(|i| 0.25 + (i % 9) as f32 * 0.3).collect(),
        ))
        .unwrap();
    let path: Vec<Vec3> = (0..10_000)
        .map(|i| {
            let t = i as f32 * 1e-3;
            Vec3::new(
                2.0 + 15.0 * t,
                9.0 + 5.0 * (3.0 * t).sin(),
                9.0 + 5.0 * (2.0 * t).cos(),
            )
        })
        .collect();
    // Irradiance along the whole path, from a cold walk state.
    let walk = |cloud: &ProbeCloud| {
        let mut st = WalkState::new();
        let mut acc = Vec3::ZERO;
        for &p in &path {
            acc += cloud.irradiance(p, Vec3::Y, &mut st);
        }
        black_box(acc)
    };
    let mut g = c.benchmark_group("cloud_visibility");
    g.throughput(Throughput::Elements(path.len() as u64));
    for (moments, cells, weights) in [
        (false, false, false),
        (true, false, false),
        (false, true, false),
        (true, true, false),
        (true, true, true),
    ] {
        cloud.set_visibility(moments);
        cloud.set_cell_visibility(cells);
        cloud.set_probe_weighting(weights);
        let name = match (moments, cells, weights) {
            (false, false, _) => "irradiance_visibility_off",
            (true, false, _) => "irradiance_moments",
            (false, true, _) => "irradiance_cells",
            (true, true, false) => "irradiance_moments_and_cells",
            (true, true, true) => "irradiance_moments_cells_and_weights",
        };
        g.bench_function(name, |b| b.iter(|| walk(&cloud)));
    }
    // Occluder planes in every other cell with a record (a baked demo cloud
    // has one in ~40 % of them): the side test replaces the bits there.
    let planes = {
        let bits = cloud.cell_visibility_bits().unwrap();
        let (pos, tets) = (cloud.mesh().positions(), cloud.mesh().tets());
        let ids: Vec<u32> = (0..tets.len() as u32)
            .filter(|&t| bits.tet_has_record(t))
            .step_by(2)
            .collect();
        let n = Vec3::new(1.0, 0.3, 0.2).normalize();
        let planes = ids
            .iter()
            .map(|&t| {
                let c = tets[t as usize]
                    .iter()
                    .map(|&i| pos[i as usize])
                    .sum::<Vec3>()
                    / 4.0;
                [n.x, n.y, n.z, n.dot(c)]
            })
            .collect();
        CellPlanes::new(tets.len(), ids, planes).unwrap()
    };
    cloud.set_visibility(false);
    cloud.set_cell_visibility(true);
    cloud.set_probe_weighting(false);
    cloud.set_cell_planes(Some(planes)).unwrap();
    g.bench_function("irradiance_cells_and_planes", |b| b.iter(|| walk(&cloud)));
    // What `probekit bake` stores by default: everything on, brightness
    // exponent 1, then with directional brightness 0.25 on top.
    cloud.set_visibility(true);
    cloud.set_probe_weighting(true);
    cloud.set_brightness_weighting(1.0).unwrap();
    g.bench_function("irradiance_all_brightness", |b| b.iter(|| walk(&cloud)));
    cloud.set_directional_brightness(0.25).unwrap();
    g.bench_function("irradiance_all_brightness_directional", |b| {
        b.iter(|| walk(&cloud))
    });
    g.finish();
}

/// `count` random points in the scene's box.
fn random_points(count: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = scene::Rng(seed);
    let hi = (scene::K - 1) as f32;
    (0..count)
        .map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * hi)
        .collect()
}

/// One object moving in ~5 cm steps through the rooms (bouncing in the
/// box), with a normal that turns slowly.
fn coherent_path(count: usize) -> (Vec<Vec3>, Vec<Vec3>) {
    let mut rng = scene::Rng(7);
    let hi = (scene::K - 1) as f32;
    let mut p = Vec3::splat(hi / 2.0);
    let mut v = Vec3::new(0.04, 0.02, 0.03);
    let mut points = Vec::with_capacity(count);
    let mut normals = Vec::with_capacity(count);
    for i in 0..count {
        let jitter = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
        p += v + jitter * 0.01;
        for a in 0..3 {
            if p[a] < 0.0 || p[a] > hi {
                v[a] = -v[a];
                p[a] = p[a].clamp(0.0, hi);
            }
        }
        points.push(p);
        let t = i as f32 * 1e-3;
        normals.push(Vec3::new(t.cos(), 0.5, t.sin()).normalize());
    }
    (points, normals)
}

/// Irradiance on a 100 k-probe cloud: walk alone, plain blend, default blend.
fn cloud_100k(c: &mut Criterion) {
    const N: usize = 10_000;
    // Through bytes, as an engine loads them.
    let load = |plain| {
        let bytes = scene::default_bake(plain).to_bytes().unwrap();
        Probes::from_bytes(&bytes, LoadOptions::default()).unwrap()
    };
    let (plain, full) = (load(true), load(false));
    let (path, normals) = coherent_path(N);
    let cold = random_points(N, 11);
    let mut g = c.benchmark_group("cloud_100k");
    g.throughput(Throughput::Elements(N as u64));
    let mesh = plain.cloud().unwrap().mesh();
    g.bench_function("walk_coherent", |b| {
        let mut s = WalkState::new();
        b.iter(|| {
            for &q in &path {
                black_box(mesh.weights_at(q, &mut s));
            }
        })
    });
    g.bench_function("walk_cold", |b| {
        b.iter(|| {
            for &q in &cold {
                black_box(mesh.weights_at(q, &mut WalkState::new()));
            }
        })
    });
    for (name, probes) in [("plain", &plain), ("default", &full)] {
        g.bench_function(format!("{name}_coherent"), |b| {
            let mut s = ObjectState::new();
            b.iter(|| {
                let mut acc = 0.0;
                for (&q, &n) in path.iter().zip(&normals) {
                    acc += probes.irradiance(&mut s, q, n).unwrap()[0];
                }
                black_box(acc)
            })
        });
        g.bench_function(format!("{name}_cold"), |b| {
            b.iter(|| {
                let mut acc = 0.0;
                for (&q, &n) in cold.iter().zip(&normals) {
                    acc += probes.irradiance(&mut ObjectState::new(), q, n).unwrap()[0];
                }
                black_box(acc)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, cloud_100k, bench, visibility);
criterion_main!(benches);
