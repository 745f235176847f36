//! No query allocates: a counting global allocator around batches of
//! queries on a cloud (every blend factor on), a volume (each
//! interpolation) and a rig.

mod common;

use common::clouds::{jittered_lattice, random_sh};
use common::{cm, Rng};
use glam::Vec3;
use probekit_runtime::cloud::cell_visibility::record_from;
use probekit_runtime::cloud::{CellPlanes, CellVisibility, HULL};
use probekit_runtime::format::layout::NONE;
use probekit_runtime::format::{
    Coefficients, DistanceMoments, Gradients, ProbeFile, ProbeSet, TetSection, VolumeFile,
    VolumeGrid, VolumeStructure,
};
use probekit_runtime::{Interp, L1Mode, LoadOptions, ObjectState, Probes};

#[path = "support/counting.rs"]
mod counting;
use counting::allocations;

/// A cloud file on a jittered 4×4×4 lattice with every blend section
/// (distance moments, cell visibility, occluder planes, probe weights,
/// brightness and directional exponents) and two rigs, SH of `order` bands.
fn cloud_bytes(order: u32) -> Vec<u8> {
    let mut rng = Rng(21);
    let mesh = jittered_lattice([4, 4, 4], &mut rng);
    let probes = mesh.positions().len();
    let coeffs: Vec<Vec3> = (0..probes)
        .flat_map(|i| random_sh(order, 0.1 + i as f32 * 0.05, &mut rng))
        .collect();
    let mut f = ProbeFile::cloud(mesh.positions().to_vec(), order, &coeffs).unwrap();
    let (tets, faces) = (mesh.tets().len(), mesh.hull_face_count());
    cm(&mut f).tetrahedra = Some(TetSection {
        vertices: mesh.tets().to_vec(),
        neighbours: mesh
            .neighbors()
            .map(|n| n.map(|t| if t == HULL { NONE } else { t }))
            .collect(),
        barycentric: (0..tets as u32)
            .map(|t| {
                let b = mesh.bary(t);
                b.rows.map(|r| [r.x, r.y, r.z, -r.dot(b.origin)])
            })
            .collect(),
    });
    let k = 2;
    let mut bits = Vec::new();
    for (c, vertices) in (0..tets)
        .map(|_| 4)
        .chain((0..faces).map(|_| 3))
        .enumerate()
    {
        bits.extend(record_from(vertices, k, |v, l| (c + v + l) % 5 != 0));
    }
    cm(&mut f).blend.cell_visibility = Some(CellVisibility::new(k, tets, faces, bits).unwrap());
    let ids: Vec<u32> = (0..tets as u32).step_by(3).collect();
    let planes = ids.iter().map(|_| [0.0, 0.0, 1.0, 1.5]).collect();
    cm(&mut f).blend.cell_planes = Some(CellPlanes::new(tets, ids, planes).unwrap());
    cm(&mut f).blend.probe_weights = Some((0..probes).map(|i| 0.5 + 0.01 * i as f32).collect());
    cm(&mut f).blend.brightness_exponent = 1.0;
    cm(&mut f).blend.directional_exponent = 0.5;
    let res = 2;
    let half = |x: f32| half::f16::from_f32(x).to_bits();
    cm(&mut f).blend.distance_moments = Some(DistanceMoments {
        resolution: res,
        max_distance: 4.0,
        data: (0..probes * (res * res) as usize)
            .flat_map(|i| {
                let mu = 0.2 + 0.1 * (i % 5) as f32;
                [half(mu), half(mu * mu * 1.1)]
            })
            .collect(),
    });
    *f.rigs_mut() = common::full_file().rigs().to_vec();
    f.to_bytes().unwrap()
}

fn volume_bytes() -> Vec<u8> {
    let mut rng = Rng(23);
    let n = 27 * 9;
    let coefficients =
        Coefficients::from_f32(3, &(0..n).map(|_| rng.vec3()).collect::<Vec<_>>()).unwrap();
    let positions = (0..27)
        .map(|i| Vec3::new((i % 3) as f32, (i / 3 % 3) as f32, (i / 9) as f32))
        .collect();
    let mut f = VolumeFile::new(
        ProbeSet::new(positions, coefficients),
        VolumeStructure::Uniform(VolumeGrid {
            min: Vec3::ZERO,
            max: Vec3::splat(2.0),
            resolution: [3, 3, 3],
        }),
    );
    f.gradients = Some(Gradients {
        order: 3,
        data: (0..3 * n).map(|_| rng.vec3()).collect(),
    });
    ProbeFile::Volume(f).to_bytes().unwrap()
}

fn batch(count: usize) -> (Vec<Vec3>, Vec<Vec3>) {
    let mut rng = Rng(29);
    (0..count)
        .map(|_| {
            (
                rng.vec3() * 2.5 + Vec3::splat(1.5),
                rng.vec3().normalize_or(Vec3::Y),
            )
        })
        .unzip()
}

#[test]
fn queries_do_not_allocate() {
    // The counter itself works.
    assert!(allocations(|| drop(std::hint::black_box(vec![1u8; 64]))) >= 1);
    let (ps, ns) = batch(500);
    let mut e = vec![[0.0f32; 3]; ps.len()];
    let mut sh = vec![[[0.0f32; 3]; 9]; ps.len()];
    let mut files = Vec::new();
    for order in [2, 3] {
        files.push((cloud_bytes(order), LoadOptions::default()));
    }
    let mut zh3 = LoadOptions::default();
    zh3.l1_mode = Some(L1Mode::Zh3Hallucinated);
    files.push((cloud_bytes(2), zh3));
    for interp in [Interp::Trilinear, Interp::Taylor, Interp::Tricubic] {
        let mut o = LoadOptions::default();
        o.interpolation = interp;
        files.push((volume_bytes(), o));
    }
    for (bytes, options) in &files {
        let mut probes = Probes::from_bytes(bytes, *options).unwrap();
        let mut state = ObjectState::new();
        let n = allocations(|| {
            probes
                .irradiance_many(&mut state, &ps, &ns, &mut e)
                .unwrap();
            probes.sh_at_many(&mut state, &ps, &mut sh).unwrap();
            for (&p, &n) in ps.iter().zip(&ns) {
                probes.irradiance(&mut state, p, n).unwrap();
                probes.sh_at(&mut state, p).unwrap();
                probes.query(&mut state, p).unwrap();
            }
        });
        assert_eq!(n, 0, "{options:?}");
        for r in 0..probes.rig_count() {
            let rig = probes.rig(r).unwrap();
            let samples = vec![Vec3::splat(0.3); rig.sample_count() * rig.order() * rig.order()];
            probes.update_rig(r, &samples).unwrap();
            let n = allocations(|| {
                probes.update_rig(r, &samples).unwrap();
                for (&p, &n) in ps.iter().zip(&ns) {
                    probes.rig_irradiance(r, p, n).unwrap();
                }
            });
            assert_eq!(n, 0, "rig {r}");
            // The split rig: after a first update has sized its buffers.
            let mut split = probes.split_rig(r).unwrap();
            let lights = [
                probekit_runtime::rig::Light::Point {
                    position: Vec3::new(0.5, 0.5, 2.0),
                    intensity: Vec3::ONE,
                },
                probekit_runtime::rig::Light::Directional {
                    direction: -Vec3::Y,
                    irradiance: Vec3::ONE,
                },
            ];
            let at = glam::Affine3A::from_translation(Vec3::new(0.1, 0.0, 0.0));
            split.update(at, &lights, 1e-6, 1.0).unwrap();
            let n = allocations(|| {
                split.update(at, &lights, 1e-6, 1.0).unwrap();
                for (&p, &n) in ps.iter().zip(&ns) {
                    std::hint::black_box(split.irradiance(p, n));
                }
            });
            assert_eq!(n, 0, "split rig {r}");
        }
    }
}
