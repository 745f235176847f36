//! ns per volume sample: trilinear, Taylor and tricubic, single and batched,
//! on a uniform 17³ L2 grid with gradients and on a two-level octree.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use glam::Vec3;
use probekit_runtime::format::{
    layout::NONE, Coefficients, Gradients, Octree, OctreeNode, ProbeFile, ProbeSet, VolumeFile,
    VolumeGrid, VolumeStructure,
};
use probekit_runtime::volume::{Interp, Volume};

fn field(p: Vec3, c: usize) -> Vec3 {
    Vec3::new(
        (p.x * 1.3 + c as f32).sin(),
        (p.y * 0.7).cos() + 1.0,
        p.z * 0.1 * c as f32,
    )
}

fn file(positions: Vec<Vec3>, structure: VolumeStructure) -> ProbeFile {
    let n = 9;
    let coeffs: Vec<Vec3> = positions
        .iter()
        .flat_map(|p| (0..n).map(move |c| field(*p, c)))
        .collect();
    let grads: Vec<Vec3> = positions
        .iter()
        .flat_map(|p| (0..3 * n).map(move |c| field(*p * 0.5, c) * 0.1))
        .collect();
    let probes = ProbeSet::new(positions, Coefficients::from_f32(3, &coeffs).unwrap());
    ProbeFile::Volume(VolumeFile {
        gradients: Some(Gradients {
            order: 3,
            data: grads,
        }),
        ..VolumeFile::new(probes, structure)
    })
}

fn uniform() -> Volume {
    let r = 17usize;
    let mut pos = Vec::new();
    for k in 0..r {
        for j in 0..r {
            for i in 0..r {
                pos.push(Vec3::new(i as f32, j as f32, k as f32) / (r - 1) as f32 * 4.0 - 2.0);
            }
        }
    }
    let g = VolumeGrid {
        min: Vec3::splat(-2.0),
        max: Vec3::splat(2.0),
        resolution: [17; 3],
    };
    Volume::from_file(&file(pos, VolumeStructure::Uniform(g))).unwrap()
}

/// Root split once; child 0 split again (27 + extra lattice points).
fn octree() -> Volume {
    let mut pos = Vec::new();
    let mut index = std::collections::HashMap::new();
    let mut id = |q: [u32; 3], pos: &mut Vec<Vec3>| -> u32 {
        *index.entry(q).or_insert_with(|| {
            pos.push(Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) - 2.0);
            (pos.len() - 1) as u32
        })
    };
    let mut nodes = vec![];
    let mut samples = vec![];
    let mut push = |lo: [u32; 3],
                    s: u32,
                    depth: u32,
                    first_child: u32,
                    nodes: &mut Vec<OctreeNode>,
                    pos: &mut Vec<Vec3>| {
        let off = samples.len() as u32;
        if first_child == NONE {
            for c in 0..8u32 {
                let q = [
                    lo[0] + s * (c & 1),
                    lo[1] + s * ((c >> 1) & 1),
                    lo[2] + s * ((c >> 2) & 1),
                ];
                samples.push(id(q, pos));
            }
        }
        nodes.push(OctreeNode {
            min: Vec3::new(lo[0] as f32, lo[1] as f32, lo[2] as f32) - 2.0,
            max: Vec3::new((lo[0] + s) as f32, (lo[1] + s) as f32, (lo[2] + s) as f32) - 2.0,
            first_child,
            depth,
            sample_offset: off,
            sample_count: if first_child == NONE { 8 } else { 0 },
        });
    };
    push([0; 3], 4, 0, 1, &mut nodes, &mut pos);
    for c in 0..8u32 {
        let lo = [2 * (c & 1), 2 * ((c >> 1) & 1), 2 * ((c >> 2) & 1)];
        push(
            lo,
            2,
            1,
            if c == 0 { 9 } else { NONE },
            &mut nodes,
            &mut pos,
        );
    }
    for c in 0..8u32 {
        push(
            [c & 1, (c >> 1) & 1, (c >> 2) & 1],
            1,
            2,
            NONE,
            &mut nodes,
            &mut pos,
        );
    }
    let o = Octree {
        nodes,
        samples,
        roots: [1, 1, 1],
    };
    Volume::from_file(&file(pos, VolumeStructure::Adaptive(o))).unwrap()
}

fn points(n: usize) -> Vec<Vec3> {
    let mut s = 1u64;
    (0..n)
        .map(|_| {
            let mut f = || {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 40) as f32 / (1u64 << 24) as f32 * 4.0 - 2.0
            };
            Vec3::new(f(), f(), f())
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let pts = points(1024);
    for (name, v) in [("uniform17", uniform()), ("octree", octree())] {
        for interp in [Interp::Trilinear, Interp::Taylor, Interp::Tricubic] {
            let mut out = vec![Vec3::ZERO; 9];
            let mut i = 0;
            c.bench_function(&format!("{name}/{interp:?}/single"), |b| {
                b.iter(|| {
                    i = (i + 1) & 1023;
                    v.sample_sh(black_box(pts[i]), interp, &mut out).unwrap();
                    black_box(&out);
                })
            });
            let mut outb = vec![Vec3::ZERO; 9 * pts.len()];
            c.bench_function(&format!("{name}/{interp:?}/batch1024"), |b| {
                b.iter(|| {
                    v.sample_sh_batch(black_box(&pts), interp, &mut outb)
                        .unwrap();
                    black_box(&outb);
                })
            });
        }
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).warm_up_time(std::time::Duration::from_millis(300)).measurement_time(std::time::Duration::from_millis(800));
    targets = bench
}
criterion_main!(benches);
