//! Cost of visibility-weighted blending: `ProbeCloud::irradiance` (L2 SH) on
//! a 20³ Kuhn-triangulated probe grid (8 000 probes, 8×8 distance-moment maps
//! of random plausible moments), coherent queries (one object moving in
//! small steps), with the weighting on and off.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use probekit_runtime::cloud::{face_neighbors, ProbeCloud, TetMesh, VisibilityMaps, WalkState};
use std::hint::black_box;

fn kuhn_grid(k: u32) -> TetMesh {
    let id = |x: u32, y: u32, z: u32| (z * k + y) * k + x;
    let mut pos = Vec::new();
    for z in 0..k {
        for y in 0..k {
            for x in 0..k {
                pos.push(Vec3::new(x as f32, y as f32, z as f32));
            }
        }
    }
    let mut tets = Vec::new();
    for z in 0..k - 1 {
        for y in 0..k - 1 {
            for x in 0..k - 1 {
                for s in [
                    [0, 1, 2],
                    [0, 2, 1],
                    [1, 0, 2],
                    [1, 2, 0],
                    [2, 0, 1],
                    [2, 1, 0],
                ] {
                    let mut c = [x, y, z];
                    let mut t = [id(x, y, z); 4];
                    for (j, &axis) in s.iter().enumerate() {
                        c[axis] += 1;
                        t[j + 1] = id(c[0], c[1], c[2]);
                    }
                    tets.push(t);
                }
            }
        }
    }
    let n = face_neighbors(&tets).unwrap();
    TetMesh::new(pos, tets, n).unwrap()
}

fn bench(c: &mut Criterion) {
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
    let mut g = c.benchmark_group("cloud_visibility");
    g.throughput(Throughput::Elements(path.len() as u64));
    for on in [false, true] {
        cloud.set_visibility(on);
        let name = if on {
            "irradiance_visibility_on"
        } else {
            "irradiance_visibility_off"
        };
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut st = WalkState::new();
                let mut acc = Vec3::ZERO;
                for &p in &path {
                    acc += cloud.irradiance(p, Vec3::Y, &mut st);
                }
                black_box(acc)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
