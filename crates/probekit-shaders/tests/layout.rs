//! The packers of `probekit_shaders::layout` on the CPU (no adapter
//! needed): every section of the cloud buffer holds the runtime's data at
//! the offsets its header gives, the hull-face rows reproduce the
//! projection onto a face's plane (checked against a plane computed
//! independently), the volume, brick and rig buffers hold their inputs
//! where `docs/shaders.md` says, and bad input is a typed error.

// Index loops over coefficients read like the layout tables.
#![allow(clippy::needless_range_loop)]

use glam::Vec3;
use probekit_runtime::cloud::directional::{directions, DirectionTable};
use probekit_runtime::cloud::{
    face_neighbors, lattice_tets, CellPlanes, CellVisibility, TetMesh, VisibilityMaps,
};
use probekit_runtime::format::{
    AxisModel, Coefficients, Gradients, LightOcclusion, Octree, OctreeNode, ProbeSet, Rig,
    RigModel, RuntimeLight, RuntimeLights, Transition, VolumeFile, VolumeGrid, VolumeStructure,
};
use probekit_runtime::rig::{Light, SphereTable, SplitRig};
use probekit_runtime::sh::basis::eval_l2;
use probekit_runtime::sh::LUMINANCE;
use probekit_runtime::{ProbeCloud, ProbeFile};
use probekit_shaders::layout::{
    light_occlusion_words, pack_bricks, pack_cloud, pack_cloud_with_lights, pack_rig_light,
    pack_sphere_table, pack_split_rig, pack_volume_grid, BrickAtlas, BrickEncoding, LayoutError,
    CLOUD_HEADER, CLOUD_HULL, CLOUD_HULL_WORDS, CLOUD_NONE, CLOUD_TET_WORDS, RIG_HEADER,
    RIG_HEADER_WORDS, RIG_LIGHT_WORDS,
};
use std::sync::Arc;

/// xorshift32 in [0, 1).
struct Rng(u32);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        (self.0 >> 8) as f32 / (1 << 24) as f32
    }
}

/// Header word `name` of `CLOUD_HEADER`.
fn h(words: &[u32], name: &str) -> usize {
    let i = CLOUD_HEADER
        .iter()
        .find(|(n, _)| *n == name)
        .unwrap_or_else(|| panic!("{name}"))
        .1;
    words[i] as usize
}

fn f(words: &[u32], i: usize) -> f32 {
    f32::from_bits(words[i])
}

fn v3(words: &[u32], i: usize) -> Vec3 {
    Vec3::new(f(words, i), f(words, i + 1), f(words, i + 2))
}

/// A cloud on an irregularly spaced 3 × 3 × 2 lattice with random SH,
/// distance moments, cell visibility, one occluder plane and probe weights.
fn test_cloud() -> ProbeCloud {
    let xs = [0.0, 1.0, 2.5];
    let ys = [0.0, 1.3, 2.0];
    let zs = [0.0, 0.8];
    let mut positions = Vec::new();
    for z in zs {
        for y in ys {
            for x in xs {
                positions.push(Vec3::new(x, y, z));
            }
        }
    }
    let tets = lattice_tets([3, 3, 2]);
    let neighbours = face_neighbors(&tets).unwrap();
    let mesh = TetMesh::new(positions.clone(), tets, neighbours).unwrap();
    let mut rng = Rng(7);
    let coeffs: Vec<Vec3> = (0..positions.len() * 9)
        .map(|i| {
            let v = Vec3::new(rng.next(), rng.next(), rng.next());
            if i % 9 == 0 {
                v + 0.5
            } else {
                v - 0.5
            }
        })
        .collect();
    let mut cloud = ProbeCloud::new(mesh, 3, coeffs).unwrap();
    let res = 3;
    let moments = (0..positions.len() * res * res)
        .map(|_| {
            let mu = 0.5 + 2.0 * rng.next();
            [mu, mu * mu + rng.next()]
        })
        .collect();
    cloud
        .set_visibility_maps(Some(VisibilityMaps::new(res as u32, 5.0, moments).unwrap()))
        .unwrap();
    let (t, hf) = (cloud.mesh().tets().len(), cloud.mesh().hull_face_count());
    let k = 2;
    let len = probekit_runtime::cloud::cell_visibility::records_len(k, t, hf).unwrap();
    // Every third record byte random, the rest all ones: some cells clear.
    let mut bits = vec![0xffu8; len];
    for (i, b) in bits.iter_mut().enumerate() {
        if i % 3 == 0 && i < len / 2 {
            *b = (rng.next() * 255.0) as u8;
        }
    }
    // Clear padding bits so the records are canonical.
    let dense = CellVisibility::new(k, t, hf, bits).unwrap();
    let canonical = CellVisibility::new(k, t, hf, dense.to_dense()).unwrap();
    cloud.set_cell_visibility_bits(Some(canonical)).unwrap();
    cloud
        .set_cell_planes(Some(
            CellPlanes::new(t, vec![3], vec![[1.0, 0.0, 0.0, 0.7]]).unwrap(),
        ))
        .unwrap();
    cloud
        .set_probe_weights(Some(
            (0..positions.len()).map(|i| 0.5 + i as f32 * 0.1).collect(),
        ))
        .unwrap();
    cloud.set_brightness_weighting(0.5).unwrap();
    cloud.set_directional_brightness(0.5).unwrap();
    cloud
}

#[test]
fn cloud_buffer_holds_the_runtime_data() {
    let cloud = test_cloud();
    let packed = pack_cloud(&cloud).unwrap();
    let w = &packed.words;
    let mesh = cloud.mesh();
    let probes = cloud.probe_count();
    let tets = mesh.tets().len();
    let hull = mesh.hull_face_count();
    assert_eq!(h(w, "PK_CLOUD_H_PROBES"), probes);
    assert_eq!(h(w, "PK_CLOUD_H_TETS"), tets);
    assert_eq!(h(w, "PK_CLOUD_H_HULL_FACES"), hull);
    assert_eq!(h(w, "PK_CLOUD_H_COEFFS"), 9);
    assert_eq!(h(w, "PK_CLOUD_H_FLAGS"), 7);
    assert_eq!(f(w, 5), 0.5);
    assert_eq!(f(w, 6), 0.5);

    // Per probe: positions, coefficients (the range the struct names),
    // luminance, directional luminance, weights.
    let pos = h(w, "PK_CLOUD_H_POSITIONS");
    let coe = h(w, "PK_CLOUD_H_COEFFICIENTS");
    assert_eq!(packed.coefficients, coe..coe + probes * 27);
    let table = DirectionTable::new();
    for i in 0..probes {
        assert_eq!(v3(w, pos + 3 * i), mesh.positions()[i]);
        for c in 0..9 {
            assert_eq!(v3(w, coe + 27 * i + 3 * c), cloud.probe_sh(i)[c]);
        }
        let lum = LUMINANCE.dot(cloud.probe_sh(i)[0]);
        assert_eq!(f(w, h(w, "PK_CLOUD_H_LUMINANCE") + i), lum);
        let dl = table.luminance(cloud.probe_sh(i));
        for (d, l) in dl.iter().enumerate() {
            assert_eq!(f(w, h(w, "PK_CLOUD_H_DIR_LUMINANCE") + 12 * i + d), *l);
        }
        assert_eq!(
            f(w, h(w, "PK_CLOUD_H_PROBE_WEIGHTS") + i),
            cloud.probe_weights().unwrap()[i]
        );
    }

    // Tetrahedra: probes, barycentric matrix, neighbours (hull faces coded).
    let tr = h(w, "PK_CLOUD_H_TET_RECORDS");
    let hr = h(w, "PK_CLOUD_H_HULL_RECORDS");
    let mut hull_seen = vec![false; hull];
    for t in 0..tets {
        let r = tr + CLOUD_TET_WORDS * t;
        assert_eq!(&w[r..r + 4], &mesh.tets()[t]);
        let b = mesh.bary(t as u32);
        for k in 0..3 {
            assert_eq!(v3(w, r + 4 + 3 * k), b.rows[k]);
        }
        assert_eq!(v3(w, r + 13), b.origin);
        for face in 0..4 {
            let n = w[r + 16 + face];
            match mesh.neighbor(t as u32, face) {
                Some(u) => assert_eq!(n, u),
                None => {
                    assert_ne!(n & CLOUD_HULL, 0);
                    let hf = (n & !CLOUD_HULL) as usize;
                    hull_seen[hf] = true;
                    let mut a = mesh.hull_face_probes(hf as u32).unwrap().to_vec();
                    let mut e: Vec<u32> = (0..4)
                        .filter(|&k| k != face)
                        .map(|k| mesh.tets()[t][k])
                        .collect();
                    a.sort_unstable();
                    e.sort_unstable();
                    assert_eq!(a, e, "tet {t} face {face}");
                }
            }
        }
    }
    assert!(hull_seen.iter().all(|&s| s));

    // Hull faces: probes, adjacency, and rows that reproduce the projection
    // onto the face's plane and the parameter along each edge.
    let mut rng = Rng(99);
    for hf in 0..hull {
        let r = hr + CLOUD_HULL_WORDS * hf;
        let q = mesh.hull_face_probes(hf as u32).unwrap();
        assert_eq!(&w[r..r + 3], &q);
        let [a, b, c] = q.map(|i| mesh.positions()[i as usize]);
        for k in 0..3 {
            let g = w[r + 3 + k] as usize;
            let (u, v) = (q[(k + 1) % 3], q[(k + 2) % 3]);
            let gq = mesh.hull_face_probes(g as u32).unwrap();
            let at = |x: u32| gq.iter().position(|&y| y == x).unwrap();
            assert_eq!((at(v) + 1) % 3, at(u), "face {g} holds edge {v}→{u}");
        }
        let n = (b - a).cross(c - a).normalize();
        for _ in 0..8 {
            let p = Vec3::new(rng.next(), rng.next(), rng.next()) * 4.0 - 1.0;
            let proj = p - n * n.dot(p - a);
            let lb = v3(w, r + 6).dot(p - a);
            let lc = v3(w, r + 9).dot(p - a);
            let back = a * (1.0 - lb - lc) + b * lb + c * lc;
            assert!((back - proj).length() < 1e-5, "{back} {proj}");
        }
        for (k, (u, v)) in [(a, b), (a, c), (b, c)].into_iter().enumerate() {
            let e = v3(w, r + 12 + 3 * k);
            assert!((e.dot(v - u) - 1.0).abs() < 1e-6);
            assert!(e.dot((v - u).normalize().any_orthonormal_vector()).abs() < 1e-6);
        }
    }

    // Distance moments as the maps hold them, with the test's settings.
    let maps = cloud.visibility_maps().unwrap();
    let res = h(w, "PK_CLOUD_H_VIS_RESOLUTION");
    assert_eq!(res, 3);
    assert_eq!(f(w, 8), maps.bias());
    assert_eq!(w[9], maps.sharpness());
    assert_eq!(f(w, 10), maps.min_variance());
    let mo = h(w, "PK_CLOUD_H_MOMENTS");
    for i in 0..probes {
        for (t, m) in maps.probe_map(i).iter().enumerate() {
            let k = mo + 2 * (i * res * res + t);
            assert_eq!([f(w, k), f(w, k + 1)], *m);
        }
    }

    // Cells: a record's byte offset into the bits (the dense record there),
    // the occluder plane, or none for a clear cell.
    let cells = cloud.cell_visibility_bits().unwrap();
    let k = cells.subdivision();
    assert_eq!(h(w, "PK_CLOUD_H_CELL_SUBDIVISION"), k as usize);
    let dense = cells.to_dense();
    let bits: Vec<u8> = w[h(w, "PK_CLOUD_H_CELL_BITS")..]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let rb = |v| probekit_runtime::cloud::cell_visibility::record_bytes(v, k);
    let (mut records, mut clear) = (0, 0);
    for cell in 0..tets + hull {
        let e = w[h(w, "PK_CLOUD_H_CELLS") + cell];
        let (start, len) = if cell < tets {
            (cell * rb(4), rb(4))
        } else {
            (tets * rb(4) + (cell - tets) * rb(3), rb(3))
        };
        if cell == 3 {
            assert_eq!(e, CLOUD_HULL);
            let p = h(w, "PK_CLOUD_H_PLANES");
            assert_eq!(
                [f(w, p), f(w, p + 1), f(w, p + 2), f(w, p + 3)],
                [1.0, 0.0, 0.0, 0.7]
            );
        } else if e == CLOUD_NONE {
            clear += 1;
            assert!(dense[start..start + len]
                .iter()
                .enumerate()
                .all(|(i, &b)| { b == 0xff || i == len - 1 }));
        } else {
            records += 1;
            let e = e as usize;
            assert_eq!(&bits[e..e + len], &dense[start..start + len], "cell {cell}");
        }
    }
    assert!(records > 0 && clear > 0, "{records} records, {clear} clear");

    // The directional tables: A_l·Y_c(d) and (4π/12)·Y_c(d)/A_l, computed
    // here from the basis and the directions.
    let dt = h(w, "PK_CLOUD_H_DIR_TABLES");
    let band = |c: usize| match c {
        0 => std::f32::consts::PI,
        1..=3 => 2.0 * std::f32::consts::PI / 3.0,
        _ => std::f32::consts::PI / 4.0,
    };
    for (d, dir) in directions().into_iter().enumerate() {
        let y = eval_l2(dir);
        for c in 0..9 {
            let irr = f(w, dt + 9 * d + c);
            let proj = f(w, dt + 108 + 9 * d + c);
            assert!((irr - band(c) * y[c]).abs() < 1e-6);
            assert!((proj - 4.0 * std::f32::consts::PI / 12.0 * y[c] / band(c)).abs() < 1e-6);
        }
    }

    // The start grid: dimensions, then a tetrahedron per cell.
    let g = h(w, "PK_CLOUD_H_START_GRID");
    let dims = [w[g + 6], w[g + 7], w[g + 8]];
    let n = dims.iter().product::<u32>() as usize;
    assert!(n >= 1);
    assert_eq!(w.len(), g + 9 + n);
    assert!(w[g + 9..].iter().all(|&t| (t as usize) < tets));

    // No run-time lights: a zero count and empty sections.
    assert_eq!(h(w, "PK_CLOUD_H_LIGHTS"), 0);
    assert_eq!(h(w, "PK_CLOUD_H_LIGHT_RECORDS"), g);
    assert_eq!(h(w, "PK_CLOUD_H_LIGHT_OCCLUSION"), g);
    assert!(packed.lights.is_empty());
    assert_eq!(&w[29..32], &[0, 0, 0]);
}

/// Run-time lights: the records `pack_rig_light` writes (share 1), then
/// per probe its 8-bit occlusion values four to a word, the file's values
/// exactly; the rest of the buffer as without lights.
#[test]
fn cloud_runtime_lights_layout() {
    let cloud = test_cloud();
    let probes = cloud.probe_count();
    let lights: Vec<RuntimeLight> = [
        Light::Sphere {
            position: Vec3::new(1.0, 1.0, 0.4),
            radius: 0.1,
            intensity: Vec3::new(3.0, 2.0, 1.0),
        },
        Light::Point {
            position: Vec3::new(2.0, 0.5, 0.2),
            intensity: Vec3::splat(4.0),
        },
        Light::Spot {
            position: Vec3::new(0.2, 2.0, 0.0),
            direction: -Vec3::Y,
            inner_deg: 20.0,
            outer_deg: 35.0,
            intensity: Vec3::splat(6.0),
        },
        Light::Disk {
            position: Vec3::new(0.0, 0.0, -1.8),
            direction: Vec3::Z,
            radius: 0.5,
            intensity: Vec3::splat(2.0),
        },
        Light::Directional {
            direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
            irradiance: Vec3::ONE,
        },
    ]
    .into_iter()
    .map(|light| RuntimeLight {
        light,
        group: "g".into(),
    })
    .collect();
    let count = lights.len();
    // Every value 0..=255 somewhere, zeros (not stored) among them.
    let values: Vec<u8> = (0..probes * count).map(|i| (i * 37 % 256) as u8).collect();
    let occlusion = LightOcclusion::from_dense(count, &values).unwrap();
    let runtime = RuntimeLights { lights, occlusion };
    let plain = pack_cloud(&cloud).unwrap();
    let packed = pack_cloud_with_lights(&cloud, Some(&runtime)).unwrap();
    let w = &packed.words;
    assert_eq!(h(w, "PK_CLOUD_H_LIGHTS"), count);
    let records = h(w, "PK_CLOUD_H_LIGHT_RECORDS");
    assert_eq!(records, h(&plain.words, "PK_CLOUD_H_START_GRID"));
    assert_eq!(packed.lights, records..records + RIG_LIGHT_WORDS * count);
    for (l, r) in runtime.lights.iter().enumerate() {
        let at = records + RIG_LIGHT_WORDS * l;
        assert_eq!(&w[at..at + RIG_LIGHT_WORDS], &pack_rig_light(&r.light, 1.0));
    }
    let occ = h(w, "PK_CLOUD_H_LIGHT_OCCLUSION");
    assert_eq!(occ, packed.lights.end);
    let stride = light_occlusion_words(count);
    assert_eq!(stride, 2);
    let dense = runtime.occlusion.to_dense(count);
    for i in 0..probes {
        for l in 0..count {
            let byte = (w[occ + stride * i + l / 4] >> (8 * (l % 4))) & 0xff;
            assert_eq!(byte, u32::from(values[i * count + l]));
            assert_eq!(byte as f32 / 255.0, dense[i * count + l]);
        }
        // Unused bytes of the row's last word are zero.
        assert_eq!(w[occ + stride * i + 1] >> 8, 0);
    }
    assert_eq!(h(w, "PK_CLOUD_H_START_GRID"), occ + stride * probes);
    // Everything before the lights as without them (but the header's light
    // words and the start grid's offset).
    let g = h(&plain.words, "PK_CLOUD_H_START_GRID");
    for k in 0..g {
        if !(25..29).contains(&k) {
            assert_eq!(w[k], plain.words[k], "word {k}");
        }
    }
    assert_eq!(&w[w.len() - (plain.words.len() - g)..], &plain.words[g..]);
    // Occlusion of another number of probes.
    let short = RuntimeLights {
        occlusion: LightOcclusion::from_dense(count, &values[..count * (probes - 1)]).unwrap(),
        ..runtime
    };
    assert!(matches!(
        pack_cloud_with_lights(&cloud, Some(&short)),
        Err(LayoutError::LightOcclusion { probes: p, rows }) if p == probes && rows == probes - 1
    ));
}

#[test]
fn volume_grid_layout() {
    let res = [3u32, 2, 2];
    let count = 12;
    let coeffs: Vec<Vec3> = (0..count * 9).map(|i| Vec3::splat(i as f32)).collect();
    let probes = ProbeSet::new(
        vec![Vec3::ZERO; count],
        Coefficients::from_f32(3, &coeffs).unwrap(),
    );
    let mut file = VolumeFile::new(
        probes,
        VolumeStructure::Uniform(VolumeGrid {
            min: Vec3::new(-1.0, 0.0, 1.0),
            max: Vec3::new(1.0, 2.0, 3.0),
            resolution: res,
        }),
    );
    file.gradients = Some(Gradients {
        order: 2,
        data: (0..count * 3 * 4)
            .map(|i| Vec3::splat(-(i as f32)))
            .collect(),
    });
    let file = ProbeFile::Volume(file);
    let v = pack_volume_grid(&file).unwrap();
    let word = |i: usize| u32::from_le_bytes(v.grid[i..i + 4].try_into().unwrap());
    assert_eq!(f32::from_bits(word(0)), -1.0);
    assert_eq!(f32::from_bits(word(16 + 8)), 3.0);
    assert_eq!([word(32), word(36), word(40)], res);
    assert_eq!(word(44), 4, "gradient coefficients");
    for p in 0..count {
        for c in 0..9 {
            assert_eq!(v.coefficients[27 * p + 3 * c], (9 * p + c) as f32);
        }
        for a in 0..3 {
            for c in 0..9 {
                let want = if c < 4 {
                    -(((p * 3 + a) * 4 + c) as f32)
                } else {
                    0.0
                };
                assert_eq!(v.gradients[81 * p + 27 * a + 3 * c + 2], want);
            }
        }
    }
    // A cloud, and a volume without a grid, are refused.
    let cloud = ProbeFile::cloud(vec![Vec3::ZERO], 1, &[Vec3::ONE]).unwrap();
    assert!(matches!(
        pack_volume_grid(&cloud),
        Err(LayoutError::Volume(_))
    ));
    // An adaptive volume has no grid to pack.
    let mut no_grid = file.clone();
    no_grid.as_volume_mut().unwrap().structure = VolumeStructure::Adaptive(Octree {
        nodes: vec![OctreeNode {
            min: Vec3::new(-1.0, 0.0, 1.0),
            max: Vec3::new(1.0, 2.0, 3.0),
            first_child: probekit_runtime::format::layout::NONE,
            depth: 0,
            sample_offset: 0,
            sample_count: 8,
        }],
        samples: (0..8).collect(),
        roots: [1, 1, 1],
    });
    assert!(pack_volume_grid(&no_grid).is_err());
}

#[test]
fn bricks_layout_and_errors() {
    // One brick of 5³ texels, L1 in f16: 3 textures of 8 bytes per texel.
    let texels = 125;
    let tex: Vec<Vec<u8>> = (0..3)
        .map(|g| (0..texels * 8).map(|i| (i + g) as u8).collect())
        .collect();
    let refs: Vec<&[u8]> = tex.iter().map(|t| &t[..]).collect();
    let ind = [0u8, 0, 0, 0];
    let atlas = BrickAtlas {
        encoding: BrickEncoding::F16,
        coeffs: 4,
        min: [0.0, 1.0, 2.0],
        max: [1.0, 2.0, 3.0],
        cells: [1, 1, 1],
        atlas: [5, 5, 5],
        ratio_bounds: &[],
        indirection: &ind,
        textures: &refs,
    };
    let w = pack_bricks(&atlas).unwrap();
    assert_eq!(w[0], 0);
    assert_eq!(w[1], 4);
    assert_eq!(f32::from_bits(w[3]), 1.0);
    assert_eq!(&w[8..14], &[1, 1, 1, 5, 5, 5]);
    assert_eq!(w[w[14] as usize], 0);
    let t0 = w[15] as usize;
    assert_eq!(w[t0], u32::from_le_bytes([0, 1, 2, 3]));
    assert_eq!(w[t0 + 2 * texels], u32::from_le_bytes([1, 2, 3, 4]));
    assert_eq!(w.len(), t0 + 3 * 2 * texels);
    // Wrong texture count, wrong size, a brick outside the atlas.
    let bad = |a: BrickAtlas| matches!(pack_bricks(&a), Err(LayoutError::Bricks(_)));
    assert!(bad(BrickAtlas {
        textures: &refs[..2],
        ..atlas
    }));
    let short = [&tex[0][..8], &tex[1][..], &tex[2][..]];
    assert!(bad(BrickAtlas {
        textures: &short,
        ..atlas
    }));
    assert!(bad(BrickAtlas {
        indirection: &[1, 0, 0, 0],
        ..atlas
    }));
    assert!(bad(BrickAtlas {
        encoding: BrickEncoding::Quantized,
        ..atlas
    }));
}

/// Header word `name` of `RIG_HEADER`.
fn rh(name: &str) -> usize {
    RIG_HEADER.iter().find(|e| e.0 == name).unwrap().1
}

/// A mixed tensor rig (`[Lattice(3), Gradient, Constant]`, 6 parameters)
/// over a box, with an arbitrary fitting matrix and a falling transition
/// table, so that an update keeps near lights and refits the parameters.
fn test_rig(order: u32) -> Rig {
    let samples: Vec<Vec3> = (0..7)
        .map(|i| {
            Vec3::new(
                i as f32 * 0.3 - 1.0,
                (i % 3) as f32 * 0.4,
                0.1 * i as f32 - 0.3,
            )
        })
        .collect();
    Rig {
        name: "layout".into(),
        model: RigModel::Tensor([
            AxisModel::Lattice(3),
            AxisModel::Gradient,
            AxisModel::Constant,
        ]),
        order,
        bbox_min: Vec3::new(-1.0, 0.0, -0.5),
        bbox_max: Vec3::new(1.0, 0.8, 0.5),
        bounding_radius: 1.3,
        fitting: (0..6 * samples.len())
            .map(|i| ((i * 37 % 11) as f32 - 5.0) / 7.0)
            .collect(),
        samples,
        transitions: (0..10)
            .map(|i| {
                let x = 1.1 * 1.5f32.powi(i);
                Transition {
                    distance: x,
                    error: 200.0 / (x * x),
                }
            })
            .collect(),
    }
}

#[test]
fn split_rig_layout_and_errors() {
    let table = Arc::new(SphereTable::new(16));
    let mut rig = SplitRig::new(&test_rig(3), table.clone()).unwrap();
    let lights = [
        Light::Sphere {
            position: Vec3::new(1.5, 0.4, 0.3),
            radius: 0.1,
            intensity: Vec3::new(3.0, 2.0, 1.0),
        },
        Light::Point {
            position: Vec3::new(-9.0, 1.0, 0.5),
            intensity: Vec3::splat(4.0),
        },
        Light::Spot {
            position: Vec3::new(0.2, 2.0, 0.0),
            direction: -Vec3::Y,
            inner_deg: 20.0,
            outer_deg: 35.0,
            intensity: Vec3::splat(6.0),
        },
        Light::Disk {
            position: Vec3::new(0.0, 0.0, -1.8),
            direction: Vec3::Z,
            radius: 0.5,
            intensity: Vec3::splat(2.0),
        },
        Light::Directional {
            direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
            irradiance: Vec3::ONE,
        },
    ];
    let m = glam::Affine3A::from_rotation_translation(
        glam::Quat::from_rotation_y(0.4),
        Vec3::new(0.3, 0.0, -0.2),
    );
    rig.update(m, &lights, 1.0, 0.5).unwrap();
    let near = rig.near_lights();
    assert!(near.len() >= 2 && near.len() < lights.len(), "{near:?}");
    let w = pack_split_rig(&rig).unwrap();
    assert_eq!(w[rh("PK_RIG_H_MODEL")], 2, "tensor");
    let (axes, counts) = (rh("PK_RIG_H_AXIS_X"), rh("PK_RIG_H_COUNT_X"));
    assert_eq!(
        &w[axes..axes + 3],
        &[2, 1, 0],
        "lattice, gradient, constant"
    );
    assert_eq!(&w[counts..counts + 3], &[3, 2, 1]);
    assert_eq!(w[rh("PK_RIG_H_COEFFS")], 9);
    assert_eq!(w[rh("PK_RIG_H_PARAMS")], 6);
    assert_eq!(w[rh("PK_RIG_H_LIGHTS")] as usize, near.len());
    let (lo, hi) = rig.state().bounds();
    assert_eq!(v3(&w, rh("PK_RIG_H_BOX_MIN")), lo);
    assert_eq!(v3(&w, rh("PK_RIG_H_BOX_MAX")), hi);
    assert_eq!(&w[18..RIG_HEADER_WORDS], &[0, 0]);
    let params = w[rh("PK_RIG_H_PARAMETERS")] as usize;
    assert_eq!(params, RIG_HEADER_WORDS);
    let state_params = rig.state().parameters();
    assert_eq!(state_params.len(), 6 * 9);
    assert!(state_params.iter().any(|c| *c != Vec3::ZERO));
    for (i, c) in state_params.iter().enumerate() {
        assert_eq!(v3(&w, params + 3 * i), *c, "parameter coefficient {i}");
    }
    let records = w[rh("PK_RIG_H_LIGHT_RECORDS")] as usize;
    assert_eq!(records, params + 3 * state_params.len());
    assert_eq!(w.len(), records + RIG_LIGHT_WORDS * near.len());
    for (k, (light, share)) in near.iter().enumerate() {
        let r = &w[records + RIG_LIGHT_WORDS * k..][..RIG_LIGHT_WORDS];
        assert_eq!(f(r, 13), *share);
        assert_eq!(&r[14..], &[0, 0]);
        match *light {
            Light::Sphere {
                position,
                radius,
                intensity,
            } => {
                assert_eq!(r[0], 0);
                assert_eq!((v3(r, 1), f(r, 7), v3(r, 8)), (position, radius, intensity));
            }
            Light::Point {
                position,
                intensity,
            } => {
                assert_eq!(r[0], 1);
                assert_eq!((v3(r, 1), v3(r, 8)), (position, intensity));
            }
            Light::Spot {
                position,
                direction,
                intensity,
                ..
            } => {
                assert_eq!(r[0], 2);
                assert_eq!(
                    (v3(r, 1), v3(r, 4), v3(r, 8)),
                    (position, direction, intensity)
                );
                // The attenuation from the packed scale and offset is the
                // runtime's, at the axis, the cone's edges and outside.
                for deg in [0.0f32, 20.0, 27.5, 35.0, 50.0] {
                    let c = deg.to_radians().cos();
                    let t = (c * f(r, 11) + f(r, 12)).clamp(0.0, 1.0);
                    let want = probekit_runtime::sh::lights::spot_attenuation(
                        c,
                        20f32.to_radians(),
                        35f32.to_radians(),
                    );
                    assert_eq!(t * t, want, "{deg}°");
                }
            }
            Light::Disk {
                position,
                direction,
                radius,
                intensity,
            } => {
                assert_eq!(r[0], 3);
                assert_eq!(
                    (v3(r, 1), v3(r, 4), f(r, 7), v3(r, 8)),
                    (position, direction, radius, intensity)
                );
            }
            Light::Directional { .. } => panic!("a directional light is never near"),
        }
    }
    // The table: its side, then its entries.
    let t = pack_sphere_table(&table);
    assert_eq!(t[0], 16);
    assert_eq!(t.len(), 1 + 16 * 16);
    assert!(t[1..]
        .iter()
        .zip(table.values())
        .all(|(a, b)| f32::from_bits(*a) == *b));
    // An order-4 rig keeps a band-4 term the shader does not evaluate.
    let r4 = SplitRig::new(&test_rig(4), table).unwrap();
    assert!(matches!(
        pack_split_rig(&r4),
        Err(LayoutError::RigOrder { order: 4 })
    ));
}
