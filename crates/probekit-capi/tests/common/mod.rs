//! Test files shared by the C program test and the Rust-side ABI tests: a
//! probe cloud (27 probes, Kuhn tetrahedra, one rig) and a uniform volume
//! (same probes, exact gradients) holding a radiance field linear in position.
#![allow(dead_code)]

use glam::Vec3;
use probekit_runtime::cloud::{face_neighbors, lattice_tets, TetMesh};
use probekit_runtime::format::{
    AxisModel, Coefficients, Gradients, ProbeFile, ProbeSet, Rig, RigModel, TetSection, VolumeFile,
    VolumeGrid, VolumeStructure,
};

pub const ORDER: u32 = 3;
pub const N: usize = (ORDER * ORDER) as usize;

/// Radiance SH coefficient `k` of a field linear in position.
pub fn field(p: Vec3, k: usize) -> Vec3 {
    let k = k as f32;
    Vec3::new(
        0.6 + 0.05 * k + 0.2 * p.x - 0.1 * p.y,
        0.9 - 0.04 * k + 0.15 * p.z,
        0.3 + 0.02 * k + 0.1 * (p.x + p.y + p.z),
    )
}

/// Gradient of [`field`] coefficient `k` along `axis`.
pub fn field_gradient(axis: usize, _k: usize) -> Vec3 {
    [
        Vec3::new(0.2, 0.0, 0.1),
        Vec3::new(-0.1, 0.0, 0.1),
        Vec3::new(0.0, 0.15, 0.1),
    ][axis]
}

/// 3×3×3 probes on a 2 m cube; `i + 3(j + 3k)`.
pub fn grid_positions() -> Vec<Vec3> {
    let mut p = Vec::new();
    for k in 0..3 {
        for j in 0..3 {
            for i in 0..3 {
                p.push(Vec3::new(i as f32, j as f32, k as f32));
            }
        }
    }
    p
}

pub fn coeffs(positions: &[Vec3]) -> Vec<Vec3> {
    positions
        .iter()
        .flat_map(|&p| (0..N).map(move |k| field(p, k)))
        .collect()
}

/// The cloud file: the 27 grid probes, each cube split into the 6 Kuhn
/// tetrahedra around its main diagonal (consistent across cubes), with
/// neighbours and barycentric matrices, plus one rig.
pub fn cloud_file() -> ProbeFile {
    let pos = grid_positions();
    let tets = lattice_tets([3; 3]);
    let neighbours = face_neighbors(&tets).unwrap();
    let mesh = TetMesh::new(pos.clone(), tets.clone(), neighbours.clone()).unwrap();
    let barycentric = (0..tets.len() as u32)
        .map(|t| {
            let b = mesh.bary(t);
            b.rows.map(|r| [r.x, r.y, r.z, -r.dot(b.origin)])
        })
        .collect();
    let mut file = ProbeFile::cloud(pos.clone(), ORDER, &coeffs(&pos)).unwrap();
    let f = file.as_cloud_mut().unwrap();
    f.tetrahedra = Some(TetSection {
        vertices: tets,
        neighbours,
        barycentric,
    });
    let samples: Vec<Vec3> = (0..6)
        .map(|s| Vec3::new(0.1 * s as f32, 0.5 - 0.08 * s as f32, 0.3 + 0.05 * s as f32))
        .collect();
    f.rigs = vec![Rig {
        name: "crate ü".into(),
        model: RigModel::Tensor([
            AxisModel::Lattice(2),
            AxisModel::Gradient,
            AxisModel::Constant,
        ]),
        order: ORDER,
        bbox_min: Vec3::ZERO,
        bbox_max: Vec3::new(0.5, 0.5, 0.6),
        bounding_radius: 0.0,
        fitting: (0..4 * samples.len())
            .map(|i| ((i * 7 % 11) as f32 - 3.0) / 10.0)
            .collect(),
        samples,
        transitions: Vec::new(),
    }];
    file.validate().unwrap();
    file
}

/// The volume file: the same 27 probes as a uniform grid, with the field's
/// exact gradients.
pub fn volume_file() -> ProbeFile {
    let pos = grid_positions();
    let probes = ProbeSet::new(
        pos.clone(),
        Coefficients::from_f32(ORDER, &coeffs(&pos)).unwrap(),
    );
    let mut f = VolumeFile::new(
        probes,
        VolumeStructure::Uniform(VolumeGrid {
            min: Vec3::ZERO,
            max: Vec3::splat(2.0),
            resolution: [3, 3, 3],
        }),
    );
    f.gradients = Some(Gradients {
        order: ORDER,
        data: (0..pos.len())
            .flat_map(|_| (0..3).flat_map(|a| (0..N).map(move |k| field_gradient(a, k))))
            .collect(),
    });
    let f = ProbeFile::Volume(f);
    f.validate().unwrap();
    f
}

/// Query points (inside, on faces, outside the hull) and unit normals.
pub fn points() -> Vec<(Vec3, Vec3)> {
    let mut s = 0x2545_F491_u32;
    let mut r = || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        s as f32 / u32::MAX as f32
    };
    let mut v: Vec<(Vec3, Vec3)> = (0..12)
        .map(|_| {
            let p = Vec3::new(r(), r(), r()) * 2.0;
            let n = (Vec3::new(r(), r(), r()) - 0.5).normalize_or(Vec3::Y);
            (p, n)
        })
        .collect();
    v.push((Vec3::new(1.0, 1.0, 0.5), Vec3::Y)); // on shared faces
    v.push((Vec3::new(3.0, 0.5, -1.0), Vec3::X)); // outside the hull / box
    v
}

/// Run-time lights (format 2.1), one of each kind, groups with a non-ASCII
/// name among them.
pub fn runtime_lights() -> Vec<probekit_runtime::format::RuntimeLight> {
    use probekit_runtime::format::RuntimeLight;
    use probekit_runtime::rig::Light;
    let l = |light, group: &str| RuntimeLight {
        light,
        group: group.into(),
    };
    vec![
        l(
            Light::Point {
                position: Vec3::new(0.5, 2.5, 1.0),
                intensity: Vec3::new(4.0, 3.0, 2.0),
            },
            "lamp",
        ),
        l(
            Light::Sphere {
                position: Vec3::new(1.5, 1.0, 2.4),
                radius: 0.1,
                intensity: Vec3::splat(2.0),
            },
            "default",
        ),
        l(
            Light::Spot {
                position: Vec3::new(1.0, 3.0, 1.0),
                direction: Vec3::NEG_Y,
                inner_deg: 10.0,
                outer_deg: 30.0,
                intensity: Vec3::new(1.0, 0.5, 0.25),
            },
            "default",
        ),
        l(
            Light::Disk {
                position: Vec3::new(-0.5, 1.0, 1.0),
                direction: Vec3::X,
                radius: 0.2,
                intensity: Vec3::new(0.5, 1.5, 1.0),
            },
            "panel",
        ),
        l(
            Light::Directional {
                direction: Vec3::new(0.0, -0.6, -0.8),
                irradiance: Vec3::splat(3.0),
            },
            "sün",
        ),
    ]
}

/// `f` (27 probes) with [`runtime_lights`] and a fixed pattern of
/// quantised occlusion per probe and light, a quarter of it zero (not
/// stored).
pub fn with_runtime_lights(mut f: ProbeFile) -> ProbeFile {
    use probekit_runtime::format::{LightOcclusion, RuntimeLights};
    let lights = runtime_lights();
    let probes = f.probes().expect("probes").positions.len();
    let values: Vec<u8> = (0..probes * lights.len())
        .map(|i| match i % 4 {
            0 => 0,
            1 => 255,
            _ => ((i * 37 + 11) % 254 + 1) as u8,
        })
        .collect();
    f.probes_mut().expect("probes").runtime_lights = Some(RuntimeLights {
        occlusion: LightOcclusion::from_dense(lights.len(), &values).unwrap(),
        lights,
    });
    f.validate().unwrap();
    f
}
