//! Probe capture rate: probes per second at 4096 samples and 3 bounces, on the
//! built-in demo scene and on every `*.toml` scene under `shared/data/scenes`
//! (found by walking up from this crate; skipped with a message when absent).
//! Prints each scene's rays per probe, so probes per second read as rays per
//! second, and measures the peer in the same run: obvhs's raw closest-hit
//! rate on the same scene's BVH, for rays leaving the same points in uniform
//! directions (`raw_obvhs_rays`, two threads like the capture).
//! Run: `cargo bench -p probekit --bench capture`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use probekit::capture::{Baker, CaptureSettings};
use probekit::sampling::{sample_uniform_sphere, SampleRng};
use probekit::scene::Scene;
use probekit::trace::Ray;
use rayon::prelude::*;
use std::path::PathBuf;

/// Rays per iteration of the raw obvhs peer.
const RAW_RAYS: usize = 20_000;

fn scenes_dir() -> Option<PathBuf> {
    let here = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    here.ancestors()
        .map(|a| a.join("shared/data/scenes"))
        .find(|p| p.is_dir())
}

fn bench_scene(c: &mut Criterion, name: &str, scene: &Scene) {
    let baker = match Baker::new(scene) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("skipping {name}: {e}");
            return;
        }
    };
    let settings = CaptureSettings {
        samples: 4096,
        bounces: 3,
        ..CaptureSettings::default()
    };
    let bb = scene.bake_box();
    // a few points inside the bake box, cycled through
    let points: Vec<Vec3> = [0.3f32, 0.5, 0.7]
        .iter()
        .map(|t| bb.min + (bb.max - bb.min) * Vec3::new(*t, 0.45, 1.0 - *t))
        .collect();
    // Rays per probe (closest-hit, any-hit and transmittance queries), so the
    // rate reads as rays per second beside the tracer's own in `trace`.
    let before = baker.tracer().rays();
    for (k, p) in points.iter().enumerate() {
        baker.capture(*p, k as u64, &settings).expect("capture");
    }
    let per_probe = (baker.tracer().rays() - before) / points.len() as u64;
    eprintln!("{name}: {per_probe} rays per probe");
    let mut group = c.benchmark_group("capture_4096spp_3bounces");
    group.sample_size(10);
    group.throughput(Throughput::Elements(1));
    let mut i = 0usize;
    group.bench_function(name, |b| {
        b.iter(|| {
            i += 1;
            baker
                .capture(points[i % points.len()], i as u64, &settings)
                .expect("capture")
        })
    });
    // The peer: obvhs's own traversal and triangle test on the same BVH,
    // closest hit only, rays from the same points in uniform directions.
    let tracer = baker.tracer();
    let raw_tris = tracer.obvhs_triangles_in_leaf_order();
    let mut rng = SampleRng::from_state(7);
    let rays: Vec<Ray> = (0..RAW_RAYS)
        .map(|k| {
            Ray::new(
                points[k % points.len()],
                sample_uniform_sphere(rng.next_2d()),
            )
        })
        .collect();
    group.throughput(Throughput::Elements(RAW_RAYS as u64));
    group.bench_function(format!("{name}/raw_obvhs_rays"), |b| {
        b.iter(|| {
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
    });
    group.finish();
}

fn capture(c: &mut Criterion) {
    bench_scene(c, "builtin_demo", &Scene::builtin_demo());
    match scenes_dir() {
        None => eprintln!("shared/data/scenes not found: only the demo scene is measured"),
        Some(dir) => {
            let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
                .into_iter()
                .flatten()
                .flatten()
                .filter(|e| e.path().is_dir())
                .flat_map(|e| std::fs::read_dir(e.path()).into_iter().flatten().flatten())
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|x| x == "toml"))
                .collect();
            files.sort();
            for f in files {
                let name = f.file_stem().unwrap().to_string_lossy().to_string();
                match Scene::load(&f) {
                    Ok(s) => bench_scene(c, &name, &s),
                    Err(e) => eprintln!("skipping {}: {e}", f.display()),
                }
            }
        }
    }
}

criterion_group!(benches, capture);
criterion_main!(benches);
