//! Load and save speed of `.probes` files: a 100 000-probe L2 cloud with
//! validity and 400 000 tetrahedra (f32 coefficients), about 45 MB.
//! `cargo bench -p probekit-runtime --bench format`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use probekit_runtime::format::*;

fn big_cloud() -> ProbeFile {
    let n = 100_000u32;
    let positions: Vec<Vec3> = (0..n)
        .map(|i| {
            Vec3::new(
                (i % 100) as f32,
                (i / 100 % 100) as f32,
                (i / 10_000) as f32,
            )
        })
        .collect();
    let coeffs: Vec<Vec3> = (0..n * 9)
        .map(|i| Vec3::splat((i % 97) as f32 * 0.01))
        .collect();
    let mut file = ProbeFile::cloud(positions, 3, &coeffs).unwrap();
    let f = file.as_cloud_mut().unwrap();
    f.probes.validity = Some(
        (0..n)
            .map(|i| Validity {
                value: (i % 3) as f32 * 0.5,
                flags: 0,
            })
            .collect(),
    );
    let t = 4 * n;
    f.tetrahedra = Some(TetSection {
        vertices: (0..t)
            .map(|k| [k % n, (k + 1) % n, (k + 2) % n, (k + 3) % n])
            .collect(),
        // Chain neighbours: k <-> k+1 across face 0/1 (reciprocal).
        neighbours: (0..t)
            .map(|k| {
                let prev = if k == 0 { u32::MAX } else { k - 1 };
                let next = if k + 1 == t { u32::MAX } else { k + 1 };
                [next, prev, u32::MAX, u32::MAX]
            })
            .collect(),
        barycentric: (0..t).map(|k| [[k as f32 * 1e-3; 4]; 3]).collect(),
    });
    f.metadata = r#"{"tool_version":"bench"}"#.into();
    file
}

fn bench(c: &mut Criterion) {
    let f = big_cloud();
    let bytes = f.to_bytes().unwrap();
    let mut g = c.benchmark_group("probes_file_100k_l2");
    g.sample_size(10);
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("from_bytes", |b| {
        b.iter(|| ProbeFile::from_bytes(std::hint::black_box(&bytes)).unwrap())
    });
    g.bench_function("to_bytes", |b| {
        b.iter(|| std::hint::black_box(&f).to_bytes().unwrap())
    });
    g.bench_function("crc32", |b| b.iter(|| crc32(std::hint::black_box(&bytes))));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
