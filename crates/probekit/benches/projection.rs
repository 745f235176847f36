//! Projection of a 2048×1024 equirect map to L2 SH (exact texel solid
//! angles), on rayon pools of 1 and 2 threads; plus the brute-force reference
//! irradiance of the basis comparison (4096 normals over a 256×128 map).
//!
//! Run: `cargo bench -p probekit --bench projection`.

use criterion::{criterion_group, criterion_main, Criterion};
use probekit::env::{project_equirect, reference_irradiance, EnvMap};
use probekit::sh::compare::spherical_fibonacci;
use std::hint::black_box;

fn projection(c: &mut Criterion) {
    let map = EnvMap::builtin_sky(2048, 1024);
    let mut g = c.benchmark_group("project_equirect_2048x1024_l2");
    g.sample_size(10);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        g.bench_function(format!("{threads}_threads"), |b| {
            b.iter(|| pool.install(|| project_equirect(black_box(&map), 3)))
        });
    }
    g.finish();

    let small = EnvMap::builtin_sky(256, 128);
    let normals = spherical_fibonacci(4096);
    let mut g = c.benchmark_group("reference_irradiance_4096_normals_256x128");
    g.sample_size(10);
    g.bench_function("default_pool", |b| {
        b.iter(|| reference_irradiance(black_box(&small), black_box(&normals)))
    });
    g.finish();
}

criterion_group!(benches, projection);
criterion_main!(benches);
