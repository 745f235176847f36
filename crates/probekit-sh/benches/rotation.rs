//! Rotation benchmarks: the L2 fast path against the general
//! (Ivanic–Ruedenberg) rotation, construction and application.
//!
//! `cargo bench -p probekit-sh --bench rotation`

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use glam::{EulerRot, Mat3, Quat, Vec3};
use probekit_sh::{rotate_l1, rotate_l2, ShRotation};

fn coeffs9() -> [Vec3; 9] {
    std::array::from_fn(|i| Vec3::new((i as f32).sin(), (i as f32 * 0.5).cos(), 0.1 * i as f32))
}

fn bench(c: &mut Criterion) {
    let m = Mat3::from_quat(Quat::from_euler(EulerRot::ZYX, 0.3, -1.1, 2.0));
    let c9 = coeffs9();
    let c4: [Vec3; 4] = c9[..4].try_into().unwrap();

    c.bench_function("rotate_l1 fast path (RGB)", |b| {
        b.iter(|| rotate_l1(black_box(m), black_box(&c4)))
    });
    c.bench_function("rotate_l2 fast path (RGB)", |b| {
        b.iter(|| rotate_l2(black_box(m), black_box(&c9)))
    });
    c.bench_function("ShRotation::new order 3", |b| {
        b.iter(|| ShRotation::new(3, black_box(m)))
    });
    c.bench_function("ShRotation::new + apply order 3 (RGB)", |b| {
        let mut out = [Vec3::ZERO; 9];
        b.iter(|| {
            let r = ShRotation::new(3, black_box(m));
            r.apply(black_box(&c9), &mut out);
            out
        })
    });
    let r3 = ShRotation::new(3, m);
    c.bench_function("ShRotation::apply order 3 (RGB, prebuilt)", |b| {
        let mut out = [Vec3::ZERO; 9];
        b.iter(|| {
            r3.apply(black_box(&c9), &mut out);
            out
        })
    });
    let r8 = ShRotation::new(8, m);
    let c64: Vec<Vec3> = (0..64).map(|i| Vec3::splat(i as f32 * 0.01)).collect();
    c.bench_function("ShRotation::new order 8", |b| {
        b.iter(|| ShRotation::new(8, black_box(m)))
    });
    c.bench_function("ShRotation::apply order 8 (RGB, prebuilt)", |b| {
        let mut out = vec![Vec3::ZERO; 64];
        b.iter(|| {
            r8.apply(black_box(&c64), &mut out);
            out[63]
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
