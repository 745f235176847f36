//! Per-frame cost of an irradiance rig against brute-force analytic lighting
//! (Yuan et al. 2011 §4: a character with 4 sphere lights, 8 small bright sphere
//! lights and 192 disk lights; the paper saw 449 vs 62 fps on a GPU).
//!
//! `cargo bench -p probekit --bench rig`

use criterion::{criterion_group, criterion_main, Criterion};
use glam::Vec3;
use probekit::lights::SphereTable;
use probekit::rig::fit::FittedRig;
use probekit::rig::lights::paper_cost_lights;
use probekit::rig::mesh;
use probekit::rig::split::{self, Frame};
use probekit::rig::RigSpec;

fn bench(c: &mut Criterion) {
    let ch = mesh::character();
    let lights = paper_cost_lights();
    let table = SphereTable::default();
    let mut out = vec![Vec3::ZERO; ch.positions.len()];
    let all_analytic = vec![0.0f32; lights.len()];
    let all_rig = vec![1.0f32; lights.len()];
    let mut g = c.benchmark_group("rig_frame_character_204_lights");
    g.sample_size(10);
    for spec in ["gradient", "lattice:2x2x3"] {
        for samples in [64usize, 512] {
            let spec: RigSpec = spec.parse().unwrap();
            let fitted = FittedRig::fit(&ch, spec, 3, samples, 1, "character").unwrap();
            let mut frame = Frame::new(&fitted);
            g.bench_function(format!("{spec}_{samples}samples_all_in_rig"), |b| {
                b.iter(|| {
                    split::update_from_lights(&mut frame, &fitted, Vec3::ZERO, &lights, &all_rig);
                    split::split_irradiance(
                        &frame,
                        &ch,
                        Vec3::ZERO,
                        &lights,
                        &all_rig,
                        &table,
                        &mut out,
                    );
                })
            });
        }
    }
    let fitted = FittedRig::fit(&ch, RigSpec::Constant, 3, 1, 1, "character").unwrap();
    let frame = Frame::new(&fitted);
    g.bench_function("brute_force_analytic_per_vertex", |b| {
        b.iter(|| {
            split::split_irradiance(
                &frame,
                &ch,
                Vec3::ZERO,
                &lights,
                &all_analytic,
                &table,
                &mut out,
            )
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
