//! Cost of the C boundary: the same coherent irradiance queries (one object
//! walking through a 20³-probe Kuhn-grid cloud, L2) through
//! `Probes::irradiance` directly, through `pk_irradiance` per point, and
//! through `pk_irradiance_many`; and a uniform volume (trilinear) the same
//! three ways.
//! The difference is argument checking and the `catch_unwind` frame.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use probekit_capi::*;
use probekit_runtime::cloud::{face_neighbors, lattice_tets, TetMesh};
use probekit_runtime::format::{
    Coefficients, ProbeFile, ProbeSet, TetSection, VolumeFile, VolumeGrid, VolumeStructure,
};
use probekit_runtime::{LoadOptions, ObjectState, Probes};
use std::hint::black_box;
use std::ptr::null_mut;

const K: u32 = 20;

fn grid() -> (Vec<Vec3>, Vec<Vec3>) {
    let mut pos = Vec::new();
    for z in 0..K {
        for y in 0..K {
            for x in 0..K {
                pos.push(Vec3::new(x as f32, y as f32, z as f32));
            }
        }
    }
    let coeffs = pos
        .iter()
        .flat_map(|p| (0..9).map(move |k| Vec3::new(1.0 + 0.1 * p.x, 0.5 + 0.01 * k as f32, 0.7)))
        .collect();
    (pos, coeffs)
}

fn cloud_bytes() -> Vec<u8> {
    let (pos, coeffs) = grid();
    let tets = lattice_tets([K; 3]);
    let neighbours = face_neighbors(&tets).unwrap();
    let mesh = TetMesh::new(pos.clone(), tets.clone(), neighbours.clone()).unwrap();
    let barycentric = (0..tets.len() as u32)
        .map(|t| {
            let b = mesh.bary(t);
            b.rows.map(|r| [r.x, r.y, r.z, -r.dot(b.origin)])
        })
        .collect();
    let mut f = ProbeFile::cloud(pos, 3, &coeffs).unwrap();
    f.as_cloud_mut().unwrap().tetrahedra = Some(TetSection {
        vertices: tets,
        neighbours,
        barycentric,
    });
    f.to_bytes().unwrap()
}

fn volume_bytes() -> Vec<u8> {
    let (pos, coeffs) = grid();
    let f = ProbeFile::Volume(VolumeFile::new(
        ProbeSet::new(pos, Coefficients::from_f32(3, &coeffs).unwrap()),
        VolumeStructure::Uniform(VolumeGrid {
            min: Vec3::ZERO,
            max: Vec3::splat((K - 1) as f32),
            resolution: [K; 3],
        }),
    ));
    f.to_bytes().unwrap()
}

/// A path through the cloud in 2 cm steps.
fn path(n: usize) -> (Vec<f32>, Vec<f32>) {
    let mut p = Vec::new();
    let mut nrm = Vec::new();
    for i in 0..n {
        let t = i as f32 * 0.02;
        let q = Vec3::new(
            1.0 + t % 17.0,
            3.0 + (t * 0.7).sin() * 2.0,
            5.0 + (t * 0.3).cos() * 3.0,
        );
        let d = Vec3::new((t * 1.3).cos(), 0.5, (t * 1.3).sin()).normalize();
        p.extend(q.to_array());
        nrm.extend(d.to_array());
    }
    (p, nrm)
}

fn bench(c: &mut Criterion) {
    let n = 1024;
    let (ps, ns) = path(n);
    let mut out = vec![0.0f32; 3 * n];
    for (name, bytes) in [("cloud", cloud_bytes()), ("volume", volume_bytes())] {
        let h = unsafe { pk_load_bytes(bytes.as_ptr(), bytes.len(), null_mut()) };
        assert!(!h.is_null());
        let mut g = c.benchmark_group(format!("{name}_irradiance_1024_coherent"));
        g.throughput(Throughput::Elements(n as u64));
        // The peer: the engine's Rust type, loaded from the same bytes.
        let probes = Probes::from_bytes(&bytes, LoadOptions::default()).unwrap();
        g.bench_function("rust", |b| {
            let mut state = ObjectState::new();
            b.iter(|| {
                for (p, q) in ps.chunks_exact(3).zip(ns.chunks_exact(3)) {
                    black_box(
                        probes
                            .irradiance(&mut state, Vec3::from_slice(p), Vec3::from_slice(q))
                            .unwrap(),
                    );
                }
            })
        });
        let ws = pk_walk_state_new();
        g.bench_function("pk_irradiance", |b| {
            b.iter(|| {
                for ((p, q), o) in ps
                    .chunks_exact(3)
                    .zip(ns.chunks_exact(3))
                    .zip(out.chunks_exact_mut(3))
                {
                    let s = unsafe { pk_irradiance(h, ws, p.as_ptr(), q.as_ptr(), o.as_mut_ptr()) };
                    debug_assert_eq!(s, PkStatus::Ok);
                }
                black_box(&out);
            })
        });
        g.bench_function("pk_irradiance_many", |b| {
            b.iter(|| {
                let s = unsafe {
                    pk_irradiance_many(h, ws, n, ps.as_ptr(), ns.as_ptr(), out.as_mut_ptr())
                };
                debug_assert_eq!(s, PkStatus::Ok);
                black_box(&out);
            })
        });
        g.finish();
        unsafe {
            pk_walk_state_free(ws);
            pk_free(h);
        }
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
