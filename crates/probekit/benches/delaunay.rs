//! Tetrahedralization speed: 100 k uniform random points and a 47³ regular
//! grid (103 823 points, every cube co-spherical). The Qhull peer runs on the
//! same points from `scripts/bench_qhull.py`; see `docs/bench/delaunay.md`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use probekit::cloud::{bench_points, tetrahedralize};

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
}

criterion_group!(benches, bench);
criterion_main!(benches);
