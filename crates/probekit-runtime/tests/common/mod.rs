//! Shared test helpers: a file with every section, a small PRNG, and a
//! checksum re-sealer so mutations reach the section parsers.
#![allow(dead_code)]

mod cases;
pub mod clouds;
mod lights;
mod parts;

#[allow(unused_imports)] // Only tests/corpus.rs uses them.
pub use cases::corpus_cases;
#[allow(unused_imports)]
pub use lights::{runtime_light_list, with_runtime_lights, OCCLUSION};
pub use parts::*;

use glam::Vec3;
use probekit_runtime::cloud::cell_visibility;
use probekit_runtime::format::layout::{self, entry, header, ENTRY_LEN, HEADER_LEN, NONE};
use probekit_runtime::format::*;

/// SplitMix64: tiny deterministic generator for tests.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    }
    pub fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.f32(), self.f32(), self.f32())
    }
}

/// A cloud of 5 probes holding every section of a cloud but the blend
/// data, with consistent indices: validity, two tetrahedra sharing a face,
/// a 4-face hull table, two rigs and JSON metadata (volumes:
/// [`grid_volume_file`], [`compact_volume_file`]).
pub fn full_file() -> ProbeFile {
    full_parts().0
}

/// [`full_file`] and the SH gradients of [`grid_volume_file`], drawn from
/// one generator in the order the fixture of format 1 drew them, so every
/// section the two share with it has the same bytes.
fn full_parts() -> (ProbeFile, Gradients) {
    let mut rng = Rng(7);
    let positions = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 1.0, 1.0),
    ];
    let order = 3;
    let coeffs: Vec<Vec3> = (0..positions.len() * 9).map(|_| rng.vec3()).collect();
    let mut f = ProbeFile::cloud(positions, order, &coeffs).unwrap();
    pm(&mut f).validity = Some(
        (0..5)
            .map(|i| Validity {
                value: i as f32 / 4.0,
                flags: if i == 2 {
                    layout::VALIDITY_INVALID | layout::VALIDITY_VIRTUAL_OFFSET
                } else {
                    0
                },
            })
            .collect(),
    );
    cm(&mut f).tetrahedra = Some(TetSection {
        vertices: vec![[0, 1, 2, 3], [4, 1, 2, 3]],
        neighbours: vec![[1, NONE, NONE, NONE], [0, NONE, NONE, NONE]],
        barycentric: (0..2)
            .map(|_| [0; 3].map(|_| [0; 4].map(|_| rng.f32())))
            .collect(),
    });
    cm(&mut f).outer = Some(OuterCells {
        vertices: vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [4, 2, 1]],
        adjacent: vec![[1, 2, 3], [2, 0, 3], [0, 1, 3], [0, 1, 2]],
        planes: (0..4).map(|_| [0; 4].map(|_| rng.f32())).collect(),
        tetrahedra: vec![0, 0, 0, 1],
    });
    let gradients = Gradients {
        order: 2,
        data: (0..5 * 3 * 4).map(|_| rng.vec3()).collect(),
    };
    *f.rigs_mut() = vec![
        Rig {
            name: "car".into(),
            model: RigModel::Tensor([
                AxisModel::Lattice(3),
                AxisModel::Gradient,
                AxisModel::Constant,
            ]),
            order: 3,
            bbox_min: Vec3::new(-2.0, 0.0, -1.0),
            bbox_max: Vec3::new(2.0, 1.5, 1.0),
            bounding_radius: 0.0,
            samples: (0..7).map(|_| rng.vec3()).collect(),
            fitting: (0..6 * 7).map(|_| rng.f32()).collect(),
            transitions: vec![
                Transition {
                    distance: 0.5,
                    error: 12.0,
                },
                Transition {
                    distance: 2.0,
                    error: 3.0,
                },
                Transition {
                    distance: 8.0,
                    error: 0.5,
                },
            ],
        },
        Rig {
            name: "dinosaur ü".into(),
            model: RigModel::Gradient,
            order: 2,
            bbox_min: Vec3::ZERO,
            bbox_max: Vec3::ONE,
            bounding_radius: 0.0,
            samples: (0..3).map(|_| rng.vec3()).collect(),
            fitting: (0..4 * 3).map(|_| rng.f32()).collect(),
            transitions: vec![],
        },
    ];
    *f.metadata_mut() =
        r#"{"placement":{"method":"adaptive"},"scene_hash":"abc","tool_version":"0.1.0"}"#.into();
    (f, gradients)
}

/// [`full_file`] relit-ready: two light groups, `"lamp"` (f32) and `"sün"`
/// (f16, a non-ASCII name), whose sum is the file's coefficients.
pub fn groups_file() -> ProbeFile {
    let mut f = full_file();
    let mut rng = Rng(11);
    let a: Vec<Vec3> = (0..5 * 9).map(|_| rng.vec3()).collect();
    let b: Vec<Vec3> = (0..5 * 9).map(|_| rng.vec3()).collect();
    // Round b through f16 first so the stored total is exactly a + b.
    let b16: Vec<u16> = b
        .iter()
        .flat_map(|v| v.to_array())
        .map(|x| half::f16::from_f32(x).to_bits())
        .collect();
    let b: Vec<Vec3> = b16
        .chunks(3)
        .map(|c| Vec3::from_array([0, 1, 2].map(|k| f16_to_f32(c[k]))))
        .collect();
    let total: Vec<Vec3> = a.iter().zip(&b).map(|(x, y)| *x + *y).collect();
    pm(&mut f).coefficients = Coefficients::from_f32(3, &total).unwrap();
    pm(&mut f).groups = vec![
        LightGroup {
            name: "lamp".into(),
            coefficients: Coefficients::from_f32(3, &a).unwrap(),
        },
        LightGroup {
            name: "sün".into(),
            coefficients: Coefficients {
                codec: Codec::F16,
                order: 3,
                data: b16.iter().flat_map(|h| h.to_le_bytes()).collect(),
            },
        },
    ];
    f
}

/// One raw `LGRP` record: `(codec, order, stride, name, data)`.
pub type GroupRecord<'a> = (u32, u32, u32, &'a [u8], &'a [u8]);

/// An `LGRP` section from raw records for `probes` probes, laid out as the
/// format says (for broken-file cases).
pub fn lgrp_section(probes: u32, records: &[GroupRecord<'_>]) -> Vec<u8> {
    let mut s = SectionBuilder::new([records.len() as u32, probes, 0, 0]);
    for &(codec, order, stride, name, data) in records {
        s.u32s([codec, order, stride, name.len() as u32]);
        s.bytes(name).pad();
        s.bytes(data).pad();
    }
    s.finish()
}

/// Recomputes every section CRC (for entries whose range lies in the file)
/// and the header CRC, so a mutated file gets past the checksums and
/// exercises the parsers behind them.
pub fn reseal(bytes: &mut [u8]) {
    if bytes.len() < HEADER_LEN {
        return;
    }
    let count =
        u32::from_le_bytes(bytes[header::SECTION_COUNT..][..4].try_into().unwrap()) as usize;
    let Some(table_end) = count
        .checked_mul(ENTRY_LEN)
        .and_then(|t| t.checked_add(HEADER_LEN))
    else {
        return;
    };
    if table_end > bytes.len() {
        return;
    }
    for k in 0..count {
        let e = HEADER_LEN + k * ENTRY_LEN;
        let off = u64::from_le_bytes(bytes[e + entry::OFFSET..][..8].try_into().unwrap());
        let len = u64::from_le_bytes(bytes[e + entry::LENGTH..][..8].try_into().unwrap());
        if let Some(end) = off.checked_add(len) {
            if end <= bytes.len() as u64 {
                let c = crc32(&bytes[off as usize..end as usize]);
                bytes[e + entry::CRC..e + entry::CRC + 4].copy_from_slice(&c.to_le_bytes());
            }
        }
    }
    let mut c = Crc32::new();
    c.update(&bytes[..header::CRC]);
    c.update(&bytes[HEADER_LEN..table_end]);
    let c = c.finish();
    bytes[header::CRC..header::CRC + 4].copy_from_slice(&c.to_le_bytes());
}

/// Table entry `k`: (id, offset, length).
pub fn entry_of(bytes: &[u8], k: usize) -> (SectionId, usize, usize) {
    let e = HEADER_LEN + k * ENTRY_LEN;
    let id = u32::from_le_bytes(bytes[e..][..4].try_into().unwrap());
    let off = u64::from_le_bytes(bytes[e + entry::OFFSET..][..8].try_into().unwrap());
    let len = u64::from_le_bytes(bytes[e + entry::LENGTH..][..8].try_into().unwrap());
    (SectionId(id), off as usize, len as usize)
}

/// Offset and length of section `id` in a file.
pub fn find_section(bytes: &[u8], id: SectionId) -> (usize, usize) {
    let count =
        u32::from_le_bytes(bytes[header::SECTION_COUNT..][..4].try_into().unwrap()) as usize;
    (0..count)
        .map(|k| entry_of(bytes, k))
        .find(|e| e.0 == id)
        .map(|e| (e.1, e.2))
        .expect("section present")
}

/// The format minor version a file's header records.
pub fn minor_of(bytes: &[u8]) -> u16 {
    u16::from_le_bytes([bytes[header::MINOR], bytes[header::MINOR + 1]])
}

/// `good` with `edit` applied anywhere in it, checksums resealed (so the
/// section parsers see the edit), loaded.
pub fn load_patched(good: &[u8], edit: impl FnOnce(&mut [u8])) -> Result<ProbeFile, FormatError> {
    ProbeFile::from_bytes(&patch_header(good, edit))
}

pub fn put_u32(bytes: &mut [u8], at: usize, v: u32) {
    bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

/// Hostile variants of a good file: every 7th truncation must fail to load,
/// and `rounds` deterministic single-byte mutations inside section `id`
/// (resealed, so the parser sees them) must never panic; whatever still
/// loads writes back to bytes that load to the same file.
pub fn hostile_section_variants(good: &[u8], id: SectionId, rounds: usize, seed: u64) {
    for cut in (0..good.len()).step_by(7) {
        assert!(ProbeFile::from_bytes(&good[..cut]).is_err());
    }
    let (off, len) = find_section(good, id);
    let mut s = seed | 1;
    for _ in 0..rounds {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        let mut b = good.to_vec();
        let at = off + (s % len as u64) as usize;
        b[at] = (s >> 32) as u8;
        reseal(&mut b);
        if let Ok(f) = ProbeFile::from_bytes(&b) {
            assert_eq!(ProbeFile::from_bytes(&f.to_bytes().unwrap()).unwrap(), f);
        }
    }
}

/// Checks an error's variant.
pub type Expect = fn(&FormatError) -> bool;

fn with_sections(f: &ProbeFile, edit: impl FnOnce(&mut Vec<(SectionId, Vec<u8>)>)) -> Vec<u8> {
    let bytes = f.to_bytes().unwrap();
    let (_, sections) = read_sections(&bytes).unwrap();
    let mut owned: Vec<(SectionId, Vec<u8>)> =
        sections.iter().map(|s| (s.id, s.bytes.to_vec())).collect();
    edit(&mut owned);
    assemble_file(f.kind().id(), layout::VERSION_MINOR, 0, &owned)
}

/// Patches `edit` into section `id`'s bytes (offsets relative to the
/// section), then re-seals the checksums.
fn patch(base: &[u8], id: SectionId, edit: impl FnOnce(&mut [u8])) -> Vec<u8> {
    let mut b = base.to_vec();
    let (off, len) = find_section(&b, id);
    edit(&mut b[off..off + len]);
    reseal(&mut b);
    b
}

/// `base` with `edit` applied to its bytes (the header or anywhere), then
/// the checksums resealed.
fn patch_header(base: &[u8], edit: impl FnOnce(&mut [u8])) -> Vec<u8> {
    let mut b = base.to_vec();
    edit(&mut b);
    reseal(&mut b);
    b
}

/// An adaptive volume whose octree the writer stores as `OCTC`: a root
/// over [0, 1]³ split into 8 leaves, corners on the 3×3×3 lattice.
pub fn compact_volume_file() -> ProbeFile {
    let mut positions = Vec::new();
    for k in 0..3 {
        for j in 0..3 {
            for i in 0..3 {
                positions.push(Vec3::new(i as f32, j as f32, k as f32) * 0.5);
            }
        }
    }
    let mut nodes = vec![OctreeNode {
        min: Vec3::ZERO,
        max: Vec3::ONE,
        first_child: 1,
        depth: 0,
        sample_offset: 0,
        sample_count: 0,
    }];
    let mut samples = Vec::new();
    for k in 0..8u32 {
        let o = [k & 1, (k >> 1) & 1, (k >> 2) & 1];
        let lo = Vec3::new(o[0] as f32, o[1] as f32, o[2] as f32) * 0.5;
        nodes.push(OctreeNode {
            min: lo,
            max: lo + 0.5,
            first_child: NONE,
            depth: 1,
            sample_offset: samples.len() as u32,
            sample_count: 8,
        });
        for c in 0..8u32 {
            let q = [0, 1, 2].map(|a| o[a] + ((c >> a) & 1));
            samples.push(q[0] + 3 * (q[1] + 3 * q[2]));
        }
    }
    let coeffs: Vec<Vec3> = (0..27 * 4).map(|i| Vec3::splat(i as f32 * 0.01)).collect();
    let probes = ProbeSet::new(positions, Coefficients::from_f32(2, &coeffs).unwrap());
    let mut f = VolumeFile::new(
        probes,
        VolumeStructure::Adaptive(Octree {
            nodes,
            samples,
            roots: [1, 1, 1],
        }),
    );
    f.metadata = "{}".into();
    ProbeFile::Volume(f)
}

/// [`full_file`]'s probes, validity and rigs as a uniform volume of 5 × 1
/// × 1 samples with L1 SH gradients.
pub fn grid_volume_file() -> ProbeFile {
    let (cloud, gradients) = full_parts();
    let c = c(&cloud);
    let mut v = VolumeFile::new(
        c.probes.clone(),
        VolumeStructure::Uniform(VolumeGrid {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(2.0),
            resolution: [5, 1, 1],
        }),
    );
    v.gradients = Some(gradients);
    v.rigs = c.rigs.clone();
    v.metadata = c.metadata.clone();
    ProbeFile::Volume(v)
}

/// Cell-visibility subdivision of [`cvis_file`].
pub const K: u32 = 2;
/// Hull faces [`cvis_file`] claims (the file alone does not check them).
pub const HULL: usize = 5;

/// Dense records at `k = 2`: bits set in a fixed pattern, padding bits
/// clear, and every third cell clear (all used bits set).
pub fn dense_records(tets: usize) -> Vec<u8> {
    let mut data = Vec::new();
    let mut cell = 0;
    for (n, count) in [(4usize, tets), (3, HULL)] {
        for r in 0..count {
            data.extend(cell_visibility::record_from(n, K, |v, l| {
                let bit = cell_visibility::record_bit_index(n, K, v, l);
                cell % 3 == 0 || (bit * 7 + r * 3) % 5 < 3
            }));
            cell += 1;
        }
    }
    data
}

/// `full_file()` with cell visibility from [`dense_records`] (written as
/// the sparse `CVSP` section).
pub fn cvis_file() -> ProbeFile {
    let mut f = full_file();
    let tets = c(&f).tetrahedra.as_ref().unwrap().vertices.len();
    cm(&mut f).blend.cell_visibility = Some(
        probekit_runtime::cloud::CellVisibility::new(K, tets, HULL, dense_records(tets)).unwrap(),
    );
    f
}

/// [`cvis_file`] with fitted probe weights (`PWGT`).
pub fn weights_file() -> ProbeFile {
    let mut f = cvis_file();
    let n = p(&f).positions.len();
    cm(&mut f).blend.probe_weights = Some((0..n).map(|i| 0.25 + 0.5 * i as f32).collect());
    f
}

/// Planes of [`planes_file`]'s two tetrahedra: `[n_x, n_y, n_z, d]`, unit
/// normals.
pub const PLANES: [[f32; 4]; 2] = [[0.6, 0.8, 0.0, 0.25], [0.0, 0.0, -1.0, -0.5]];

/// [`cvis_file`] with an occluder plane for each of its two tetrahedra
/// (`CPLN`).
pub fn planes_file() -> ProbeFile {
    let mut f = cvis_file();
    let tets = c(&f).tetrahedra.as_ref().unwrap().vertices.len();
    cm(&mut f).blend.cell_planes =
        Some(probekit_runtime::cloud::CellPlanes::new(tets, vec![0, 1], PLANES.to_vec()).unwrap());
    f
}
