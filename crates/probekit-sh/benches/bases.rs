//! Criterion benchmarks of the alternative bases and codecs (ZH3, Geomerics L1, ambient cube, HL2):
//! per-normal irradiance evaluation (scalar and a batch of 1024 normals),
//! the ZH3 axis solve and fits per probe, ambient-cube fit, and the codecs.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use glam::Vec3;
use probekit_sh::ambient_cube::AmbientCube;
use probekit_sh::codec;
use probekit_sh::geomerics::irradiance_geomerics_l1;
use probekit_sh::zh3::{
    fit_zh3_per_channel, fit_zh3_shared, solve_zh3_axis, zh3_hallucinated_irradiance, AxisWeights,
};
use probekit_sh::{irradiance_l1, irradiance_l2};

fn probe() -> [Vec3; 9] {
    [
        Vec3::new(2.1, 2.0, 1.8),
        Vec3::new(-0.6, -0.5, -0.3),
        Vec3::new(0.4, 0.5, 0.6),
        Vec3::new(0.2, -0.1, 0.05),
        Vec3::new(0.1, 0.2, -0.1),
        Vec3::new(-0.3, 0.1, 0.2),
        Vec3::new(0.5, 0.4, 0.3),
        Vec3::new(0.05, -0.2, 0.1),
        Vec3::new(-0.1, 0.3, 0.2),
    ]
}

fn normals(n: usize) -> Vec<Vec3> {
    let ga = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f32 + 1.0) / n as f32;
            let r = (1.0 - z * z).sqrt();
            Vec3::new(r * (ga * i as f32).cos(), r * (ga * i as f32).sin(), z)
        })
        .collect()
}

fn eval(c: &mut Criterion) {
    let l2 = probe();
    let l1: [Vec3; 4] = l2[..4].try_into().unwrap();
    let zh = fit_zh3_shared(&l2);
    let cube = AmbientCube::fit_from_sh(&l2);
    let ns = normals(1024);
    let n = Vec3::new(0.3, 0.8, -0.52).normalize();
    c.bench_function("eval_scalar/l1", |b| {
        b.iter(|| irradiance_l1(black_box(&l1), black_box(n)))
    });
    c.bench_function("eval_scalar/l2", |b| {
        b.iter(|| irradiance_l2(black_box(&l2), black_box(n)))
    });
    c.bench_function("eval_scalar/geomerics_l1", |b| {
        b.iter(|| irradiance_geomerics_l1(black_box(&l1), black_box(n)))
    });
    c.bench_function("eval_scalar/zh3_hallucinated", |b| {
        b.iter(|| zh3_hallucinated_irradiance(black_box(&l1), black_box(n)))
    });
    c.bench_function("eval_scalar/zh3_stored", |b| {
        b.iter(|| black_box(&zh).irradiance(black_box(n)))
    });
    c.bench_function("eval_scalar/ambient_cube", |b| {
        b.iter(|| black_box(&cube).irradiance(black_box(n)))
    });
    let mut g = c.benchmark_group("eval_batch_1024");
    g.bench_function("l1", |b| {
        b.iter(|| ns.iter().map(|n| irradiance_l1(&l1, *n)).sum::<Vec3>())
    });
    g.bench_function("l2", |b| {
        b.iter(|| ns.iter().map(|n| irradiance_l2(&l2, *n)).sum::<Vec3>())
    });
    g.bench_function("geomerics_l1", |b| {
        b.iter(|| {
            ns.iter()
                .map(|n| irradiance_geomerics_l1(&l1, *n))
                .sum::<Vec3>()
        })
    });
    g.bench_function("zh3_hallucinated", |b| {
        b.iter(|| {
            ns.iter()
                .map(|n| zh3_hallucinated_irradiance(&l1, *n))
                .sum::<Vec3>()
        })
    });
    g.finish();
}

fn fits(c: &mut Criterion) {
    let l2 = probe();
    c.bench_function("fit/zh3_shared", |b| {
        b.iter(|| fit_zh3_shared(black_box(&l2)))
    });
    c.bench_function("fit/zh3_per_channel", |b| {
        b.iter(|| fit_zh3_per_channel(black_box(&l2)))
    });
    c.bench_function("fit/zh3_axis_solve_luminance", |b| {
        b.iter(|| solve_zh3_axis(black_box(&l2), AxisWeights::Luminance))
    });
    c.bench_function("fit/ambient_cube_from_l2", |b| {
        b.iter(|| AmbientCube::fit_from_sh(black_box(&l2)))
    });
    let zh = fit_zh3_shared(&l2);
    let l1: [Vec3; 4] = l2[..4].try_into().unwrap();
    c.bench_function("codec/l1_round_trip", |b| {
        b.iter(|| codec::decode_l1(&codec::encode_l1(black_box(&l1))))
    });
    c.bench_function("codec/zh3_round_trip", |b| {
        b.iter(|| codec::decode_zh3(&codec::encode_zh3(black_box(&zh))))
    });
    c.bench_function("codec/l2_round_trip", |b| {
        b.iter(|| codec::decode_l2(&codec::encode_l2(black_box(&l2))))
    });
}

criterion_group!(benches, eval, fits);
criterion_main!(benches);
