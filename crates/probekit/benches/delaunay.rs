//! Tetrahedralization speed: 100 k uniform random points and a 47³ regular
//! grid (103 823 points, every cube co-spherical). The Qhull peer runs on the
//! same points from `scripts/bench_qhull.py`; see BENCHMARKS.md, "Delaunay tetrahedralization".

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use probekit::delaunay::{bench_points, tetrahedralize};
use probekit_runtime::cloud::WalkState;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("tetrahedralize");
    g.sample_size(10);
    for (name, pts) in [
        ("random_100k", bench_points::uniform(100_000, 1)),
        ("grid_47", bench_points::grid(47)),
    ] {
        let pts: Vec<Vec3> = pts;
        g.throughput(Throughput::Elements(pts.len() as u64));
        g.bench_with_input(BenchmarkId::from_parameter(name), &pts, |b, pts| {
            b.iter(|| tetrahedralize(pts).expect("valid input"))
        });
    }
    g.finish();

    // Queries on a real random Delaunay cloud of 100 k probes.
    let pts = bench_points::uniform(100_000, 1);
    let mesh = tetrahedralize(&pts).unwrap().to_tet_mesh(&pts).unwrap();
    const N: usize = 10_000;
    let cold = bench_points::uniform(N, 2);
    let mut p = Vec3::splat(0.5);
    let coherent: Vec<Vec3> = bench_points::uniform(N, 3)
        .iter()
        .map(|d| {
            // ~1/20 of the mean probe spacing (0.0215) per step.
            p = (p + (Vec3::new(0.6, 0.3, 0.1) + (*d - 0.5)) * 1e-3).rem_euclid(Vec3::ONE);
            p
        })
        .collect();
    let mut g = c.benchmark_group("query_delaunay_100k");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("cold_random", |b| {
        b.iter(|| {
            for &q in &cold {
                black_box(mesh.weights_at(q, &mut WalkState::new()));
            }
        })
    });
    g.bench_function("coherent_moving", |b| {
        let mut s = WalkState::new();
        b.iter(|| {
            for &q in &coherent {
                black_box(mesh.weights_at(q, &mut s));
            }
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
