//! Query cost of a cloud with run-time lights: the whole answer (SH plus
//! each light's exact irradiance times its blended occlusion) against the
//! same file's SH part alone, on the default demo bake (a sphere lamp and
//! the sun, both run-time where the bake chooses so).
//!
//! `cargo bench -p probekit --bench runtime_lights`

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use glam::Vec3;
use probekit::pipeline::Bake;
use probekit::recipe::Recipe;
use probekit::sampling::SampleRng;
use probekit::scene::Scene;
use probekit_runtime::{LoadOptions, ObjectState, Probes};

fn bench(c: &mut Criterion) {
    let scene = Scene::builtin_demo();
    let baked = Bake::new(&scene, "builtin:demo", &Recipe::default())
        .unwrap()
        .run(&|_, _, _| {})
        .unwrap();
    let probes = Probes::from_file(&baked.file, LoadOptions::default()).unwrap();
    println!(
        "default demo bake: {} probes, {} run-time lights, {} bytes",
        probes.probe_count(),
        probes.runtime_lights().len(),
        baked.report.bytes
    );
    // 10 000 points of the bake box, a random walk (coherent, as an
    // object's queries are), random unit normals.
    let b = scene.bake_box();
    let mut rng = SampleRng::new(7, 1, 2);
    let mut p = b.min + b.size() * 0.5;
    let pts: Vec<(Vec3, Vec3)> = (0..10_000)
        .map(|_| {
            let step = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
            p = (p + step * 0.1).clamp(b.min, b.max);
            let n = (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5)
                .normalize_or(Vec3::Y);
            (p, n)
        })
        .collect();
    let mut g = c.benchmark_group("runtime_lights_10k_queries");
    g.bench_function("irradiance_with_lights", |bch| {
        bch.iter(|| {
            let mut st = ObjectState::new();
            let mut acc = Vec3::ZERO;
            for &(p, n) in &pts {
                acc += Vec3::from(probes.irradiance(&mut st, p, n).unwrap());
            }
            black_box(acc)
        })
    });
    g.bench_function("sh_part_only", |bch| {
        bch.iter(|| {
            let mut st = ObjectState::new();
            let mut acc = Vec3::ZERO;
            for &(p, n) in &pts {
                acc += Vec3::from(probes.sh_irradiance(&mut st, p, n).unwrap());
            }
            black_box(acc)
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
