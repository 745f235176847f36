//! Analytic-light SH cost: sphere light (value; value + full gradient) at
//! L2 (order 3), with the point and disk lights for scale.
//! Run: `cargo bench -p probekit-sh --bench lights`.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use glam::Vec3;
use probekit_sh::lights::{
    disk_light_sh, point_sh, sphere_light_sh, sphere_light_sh_and_gradient,
    sphere_light_sh_gradient,
};

fn bench(c: &mut Criterion) {
    let p = Vec3::new(0.2, 1.1, -0.4);
    let center = Vec3::new(1.5, 2.0, 0.7);
    let i = Vec3::new(10.0, 8.0, 6.0);
    let mut v = [Vec3::ZERO; 9];
    let mut g = [[Vec3::ZERO; 3]; 9];
    c.bench_function("sphere_light_sh order 3", |b| {
        b.iter(|| {
            sphere_light_sh(
                3,
                black_box(p),
                black_box(center),
                0.3,
                black_box(i),
                &mut v,
            );
            black_box(&v);
        })
    });
    c.bench_function("sphere_light_sh_gradient order 3", |b| {
        b.iter(|| {
            sphere_light_sh_gradient(
                3,
                black_box(p),
                black_box(center),
                0.3,
                black_box(i),
                &mut g,
            );
            black_box(&g);
        })
    });
    c.bench_function("sphere_light_sh_and_gradient order 3", |b| {
        b.iter(|| {
            sphere_light_sh_and_gradient(
                3,
                black_box(p),
                black_box(center),
                0.3,
                black_box(i),
                &mut v,
                &mut g,
            );
            black_box((&v, &g));
        })
    });
    c.bench_function("point_sh order 3", |b| {
        b.iter(|| {
            point_sh(3, black_box(p), black_box(center), black_box(i), &mut v);
            black_box(&v);
        })
    });
    c.bench_function("disk_light_sh order 3", |b| {
        b.iter(|| {
            disk_light_sh(
                3,
                black_box(p),
                black_box(center),
                Vec3::new(-0.6, -0.5, -0.6).normalize(),
                0.3,
                black_box(i),
                &mut v,
            );
            black_box(&v);
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(30)
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
