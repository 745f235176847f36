//! Ray-tracing throughput: closest-hit queries with incoherent random rays on a procedurally
//! generated scene of 1,000,008 triangles (83,334 random boxes in a 100 m cube), on 1 and 2
//! threads, beside obvhs's own raw rate (same BVH, obvhs's Möller–Trumbore triangle test, no
//! hit record) in the same run.
//!
//! Run: `cargo bench -p probekit --bench trace`. Results: BENCHMARKS.md, "Ray tracing".

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use probekit::sampling::{sample_uniform_sphere, SampleRng};
use probekit::scene::{demo::box_triangles, Material, Scene};
use probekit::trace::{Ray, Tracer};
use rayon::prelude::*;

const BOXES: usize = 83_334;
const RAYS: usize = 20_000;

/// Test draws from the bake's generator ([`SampleRng`], SplitMix64).
trait Draws {
    /// Uniform in `[0, 1)`.
    fn f32(&mut self) -> f32;
    /// A uniform unit direction.
    fn dir(&mut self) -> Vec3;
}

impl Draws for SampleRng {
    fn f32(&mut self) -> f32 {
        self.next_f32()
    }
    fn dir(&mut self) -> Vec3 {
        sample_uniform_sphere(self.next_2d())
    }
}

fn scene() -> Scene {
    let mut rng = SampleRng::from_state(42);
    let mut tris = Vec::with_capacity(BOXES * 12);
    for _ in 0..BOXES {
        let c = 100.0 * Vec3::new(rng.f32(), rng.f32(), rng.f32());
        let h = 0.05 + 0.45 * Vec3::new(rng.f32(), rng.f32(), rng.f32());
        tris.extend(box_triangles(c - h, c + h, 0));
    }
    Scene::from_triangles(
        "bench",
        vec![("boxes".into(), tris)],
        vec![Material::default()],
        vec![],
    )
    .expect("valid bench scene")
}

fn rays() -> Vec<Ray> {
    let mut rng = SampleRng::from_state(7);
    (0..RAYS)
        .map(|_| {
            Ray::new(
                100.0 * Vec3::new(rng.f32(), rng.f32(), rng.f32()),
                rng.dir(),
            )
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let t0 = std::time::Instant::now();
    let scene = scene();
    let t1 = std::time::Instant::now();
    let tracer = Tracer::new(&scene);
    let t2 = std::time::Instant::now();
    eprintln!(
        "scene: {} triangles (generated in {:.2?}), BVH built in {:.2?}, {} nodes",
        scene.triangles.len(),
        t1 - t0,
        t2 - t1,
        tracer.node_count()
    );
    let rays = rays();
    let raw_tris = tracer.obvhs_triangles_in_leaf_order();
    let hits = rays
        .iter()
        .filter(|r| tracer.closest_hit(r, f32::INFINITY).is_some())
        .count();
    eprintln!("{hits} of {} rays hit", rays.len());

    let mut g = c.benchmark_group("trace_1M_incoherent");
    g.throughput(Throughput::Elements(RAYS as u64));
    g.sample_size(10);
    g.warm_up_time(std::time::Duration::from_millis(500));
    g.measurement_time(std::time::Duration::from_secs(3));
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        g.bench_function(format!("probekit_closest_hit/{threads}t"), |b| {
            b.iter(|| {
                pool.install(|| {
                    rays.par_chunks(256)
                        .map(|ch| {
                            ch.iter()
                                .filter(|r| tracer.closest_hit(r, f32::INFINITY).is_some())
                                .count()
                        })
                        .sum::<usize>()
                })
            })
        });
        g.bench_function(format!("obvhs_raw_closest/{threads}t"), |b| {
            b.iter(|| {
                pool.install(|| {
                    rays.par_chunks(256)
                        .map(|ch| {
                            ch.iter()
                                .filter(|r| {
                                    tracer
                                        .raw_obvhs_closest(r, f32::INFINITY, &raw_tris)
                                        .is_some()
                                })
                                .count()
                        })
                        .sum::<usize>()
                })
            })
        });
        g.bench_function(format!("probekit_occluded/{threads}t"), |b| {
            b.iter(|| {
                pool.install(|| {
                    rays.par_chunks(256)
                        .map(|ch| ch.iter().filter(|r| tracer.occluded_ray(r, 50.0)).count())
                        .sum::<usize>()
                })
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
