//! The octree section `OCTC`: round trip of a regular octree, a section
//! assembled byte by byte from `docs/file-format.md` decoded and compared
//! with boxes and corners computed independently (by halving), the writer
//! refusing irregular trees, and typed errors for hostile sections.

mod common;

use common::*;
use glam::Vec3;
use probekit_runtime::format::layout::{self, NONE};
use probekit_runtime::format::*;

/// Box [0, 2]³ split once, child 0 split again (max depth 2): 17 nodes,
/// 15 leaves. Positions are the 27 + 19 distinct lattice corners at spacing
/// 0.5 (exact in f32, so halving gives the same bits as the lattice
/// formula), listed in a scrambled order with one unused probe.
fn regular_volume() -> ProbeFile {
    let mut nodes = vec![OctreeNode {
        min: Vec3::ZERO,
        max: Vec3::splat(2.0),
        first_child: 1,
        depth: 0,
        sample_offset: 0,
        sample_count: 0,
    }];
    let octant = |min: Vec3, max: Vec3, k: u32| {
        let h = (max - min) * 0.5;
        let lo = min + h * Vec3::new((k & 1) as f32, ((k >> 1) & 1) as f32, ((k >> 2) & 1) as f32);
        (lo, lo + h)
    };
    for k in 0..8 {
        let (lo, hi) = octant(Vec3::ZERO, Vec3::splat(2.0), k);
        nodes.push(OctreeNode {
            min: lo,
            max: hi,
            first_child: if k == 0 { 9 } else { NONE },
            depth: 1,
            sample_offset: 0,
            sample_count: 0,
        });
    }
    for k in 0..8 {
        let (lo, hi) = octant(Vec3::ZERO, Vec3::ONE, k);
        nodes.push(OctreeNode {
            min: lo,
            max: hi,
            first_child: NONE,
            depth: 2,
            sample_offset: 0,
            sample_count: 0,
        });
    }
    // Corner lists in node order; positions deduplicated, then reversed.
    let mut positions: Vec<Vec3> = Vec::new();
    let mut lists = Vec::new();
    for n in &mut nodes {
        if n.first_child != NONE {
            continue;
        }
        n.sample_offset = lists.len() as u32;
        n.sample_count = 8;
        for k in 0..8u32 {
            let p = Vec3::new(
                if k & 1 == 1 { n.max.x } else { n.min.x },
                if k & 2 == 2 { n.max.y } else { n.min.y },
                if k & 4 == 4 { n.max.z } else { n.min.z },
            );
            let i = positions.iter().position(|q| *q == p).unwrap_or_else(|| {
                positions.push(p);
                positions.len() - 1
            });
            lists.push(i);
        }
    }
    let count = positions.len();
    positions.reverse();
    positions.push(Vec3::splat(7.0)); // not a corner
    let samples = lists.iter().map(|&i| (count - 1 - i) as u32).collect();
    let coeffs: Vec<Vec3> = (0..positions.len())
        .map(|i| Vec3::splat(i as f32))
        .collect();
    ProbeFile::Volume(VolumeFile::new(
        ProbeSet::new(positions, Coefficients::from_f32(1, &coeffs).unwrap()),
        VolumeStructure::Adaptive(Octree {
            nodes,
            samples,
            roots: [1, 1, 1],
        }),
    ))
}

fn section_ids(bytes: &[u8]) -> Vec<SectionId> {
    read_sections(bytes)
        .unwrap()
        .1
        .iter()
        .map(|s| s.id)
        .collect()
}

#[test]
fn regular_octree_round_trips_compactly() {
    let f = regular_volume();
    assert_eq!(p(&f).positions.len(), 47);
    let bytes = f.to_bytes().unwrap();
    let ids = section_ids(&bytes);
    assert!(ids.contains(&SectionId::OCTREE));
    assert_eq!(minor_of(&bytes), layout::VERSION_MINOR);
    assert_eq!(ProbeFile::from_bytes(&bytes).unwrap(), f);
    // 16 header + 32 box + 16 bits (17 nodes → 3 bytes, padded).
    let (_, len) = find_section(&bytes, SectionId::OCTREE);
    assert_eq!(len, 64);
    assert_eq!(f.bytes_by_section().unwrap()["octree"], 64);
    // An explicit node list of the same tree: 17 × 40 + 120 × 4 bytes.
    let explicit = 16 + 17 * 40 + 120 * 4;
    assert!(len * 10 < explicit);
}

#[test]
fn fuzz_seed_volume_is_written_compactly() {
    let f = compact_volume_file();
    let bytes = f.to_bytes().unwrap();
    assert!(section_ids(&bytes).contains(&SectionId::OCTREE));
    assert_eq!(ProbeFile::from_bytes(&bytes).unwrap(), f);
}

#[test]
fn irregular_octree_is_refused_by_the_writer() {
    // A leaf listing a 9th sample, or a corner moved off the lattice: the
    // compact encoding cannot hold either, and it is the only one.
    let mut f = regular_volume();
    let o = octree_mut(&mut f).unwrap();
    o.samples.push(0);
    o.nodes[2].sample_count = 9;
    assert!(f.validate().is_ok());
    let e = f.to_bytes().unwrap_err();
    assert!(matches!(e, FormatError::Unrepresentable(_)), "{e:?}");

    let mut g = regular_volume();
    let moved = octree(&g).unwrap().samples[0] as usize;
    pm(&mut g).positions[moved].x += 1e-3;
    let e = g.to_bytes().unwrap_err();
    assert!(matches!(e, FormatError::Unrepresentable(_)), "{e:?}");
}

/// An `OCTC` section written from the documented layout, without the
/// writer: header (N, D, 0, 0), f32[6] box padded to 32, child bits.
fn octc_bytes(nodes: u32, depth: u32, min: Vec3, max: Vec3, bits: &[u8]) -> Vec<u8> {
    octc_forest_bytes([nodes, depth, 0, 0], min, max, bits)
}

/// [`octc_bytes`] with all four header words (`w2`, `w3`: the root grid).
fn octc_forest_bytes(words: [u32; 4], min: Vec3, max: Vec3, bits: &[u8]) -> Vec<u8> {
    let mut s = Vec::new();
    for w in words {
        s.extend_from_slice(&w.to_le_bytes());
    }
    for v in min.to_array().into_iter().chain(max.to_array()) {
        s.extend_from_slice(&v.to_le_bytes());
    }
    s.resize(48, 0);
    s.extend_from_slice(bits);
    s.resize(48 + bits.len().div_ceil(16) * 16, 0);
    s
}

/// A volume file of the given positions whose octree section is `octc`.
fn file_with(positions: Vec<Vec3>, extra: Vec<(SectionId, Vec<u8>)>) -> Vec<u8> {
    let coeffs: Vec<Vec3> = vec![Vec3::ONE; positions.len()];
    let resolution = [positions.len() as u32, 1, 1];
    let f = ProbeFile::Volume(VolumeFile::new(
        ProbeSet::new(positions, Coefficients::from_f32(1, &coeffs).unwrap()),
        VolumeStructure::Uniform(VolumeGrid {
            min: Vec3::ZERO,
            max: Vec3::ONE,
            resolution,
        }),
    ));
    let bytes = f.to_bytes().unwrap();
    let (_, sections) = read_sections(&bytes).unwrap();
    let mut owned: Vec<(SectionId, Vec<u8>)> = sections
        .iter()
        .filter(|s| s.id != SectionId::GRID)
        .map(|s| (s.id, s.bytes.to_vec()))
        .collect();
    let meta = owned.pop().unwrap();
    owned.extend(extra);
    owned.push(meta);
    assemble_file(ProbeFileKind::Volume.id(), layout::VERSION_MINOR, 0, &owned)
}

/// The 27 points of a 3×3×3 lattice over [-1, 3] × [0, 1] × [2, 6], z-major.
fn lattice27() -> Vec<Vec3> {
    let (min, max) = (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 1.0, 6.0));
    let mut p = Vec::new();
    for k in 0..3 {
        for j in 0..3 {
            for i in 0..3 {
                p.push(min + (max - min) * Vec3::new(i as f32, j as f32, k as f32) * 0.5);
            }
        }
    }
    p
}

#[test]
fn documented_bytes_decode_to_root_and_eight_octants() {
    let (min, max) = (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 1.0, 6.0));
    let positions = lattice27();
    let bytes = file_with(
        positions.clone(),
        vec![(
            SectionId::OCTREE,
            octc_bytes(9, 1, min, max, &[0b0000_0001, 0]),
        )],
    );
    assert_eq!(&SectionId::OCTREE.fourcc(), b"OCTC");
    let f = ProbeFile::from_bytes(&bytes).unwrap();
    let o = octree(&f).unwrap();
    assert_eq!(o.nodes.len(), 9);
    assert_eq!(o.nodes[0].first_child, 1);
    assert_eq!((o.nodes[0].min, o.nodes[0].max), (min, max));
    let mid = (min + max) * 0.5;
    for k in 0..8usize {
        let n = &o.nodes[1 + k];
        assert_eq!((n.first_child, n.depth, n.sample_count), (NONE, 1, 8));
        let pick = |bit: usize, a: f32, b: f32| if k & bit != 0 { b } else { a };
        let lo = Vec3::new(
            pick(1, min.x, mid.x),
            pick(2, min.y, mid.y),
            pick(4, min.z, mid.z),
        );
        let hi = Vec3::new(
            pick(1, mid.x, max.x),
            pick(2, mid.y, max.y),
            pick(4, mid.z, max.z),
        );
        assert_eq!((n.min, n.max), (lo, hi));
        // Corner c of octant k is lattice point (k bits + c bits) per axis.
        for c in 0..8usize {
            let s = o.samples[n.sample_offset as usize + c] as usize;
            let ijk = [1, 2, 4].map(|b| (k & b != 0) as usize + (c & b != 0) as usize);
            assert_eq!(s, ijk[0] + 3 * (ijk[1] + 3 * ijk[2]));
        }
    }
}

#[test]
fn hostile_compact_sections_give_typed_errors() {
    let (min, max) = (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 1.0, 6.0));
    let ok = |bits: &[u8], n: u32, d: u32| {
        file_with(
            lattice27(),
            vec![(SectionId::OCTREE, octc_bytes(n, d, min, max, bits))],
        )
    };
    let err = |b: Vec<u8>| ProbeFile::from_bytes(&b).unwrap_err();
    let compact = SectionId::OCTREE;
    // 10 nodes with one parent.
    let e = err(ok(&[1, 0], 10, 1));
    assert!(
        matches!(e, FormatError::InvalidValue { id, .. } if id == compact),
        "{e:?}"
    );
    // A child bit on a node at the maximum depth.
    let e = err(ok(&[0b11, 0, 0], 17, 1));
    assert!(
        matches!(e, FormatError::InvalidTopology { id, .. } if id == compact),
        "{e:?}"
    );
    // Root a leaf, node 1 a parent: node 1 is unreachable.
    let e = err(ok(&[0b10, 0], 9, 1));
    assert!(
        matches!(e, FormatError::InvalidTopology { id, element: 1, .. } if id == compact),
        "{e:?}"
    );
    // A lattice corner without a probe.
    let mut missing = lattice27();
    missing.remove(13);
    let e = err(file_with(
        missing,
        vec![(compact, octc_bytes(9, 1, min, max, &[1, 0]))],
    ));
    assert!(
        matches!(e, FormatError::InvalidTopology { id, .. } if id == compact),
        "{e:?}"
    );
    // Absurd depth; inverted box; a bit past the last node.
    let e = err(ok(&[1, 0], 9, 40));
    assert!(matches!(e, FormatError::InvalidValue { .. }), "{e:?}");
    let e = err(file_with(
        lattice27(),
        vec![(compact, octc_bytes(9, 1, max, min, &[1, 0]))],
    ));
    assert!(matches!(e, FormatError::InvalidValue { .. }), "{e:?}");
    let e = err(ok(&[1, 0b10], 9, 1));
    assert!(
        matches!(e, FormatError::InvalidValue { element: 9, .. }),
        "{e:?}"
    );
    // A node count whose bit array the section does not hold.
    let e = err(ok(&[1, 0], u32::MAX, 1));
    assert!(matches!(e, FormatError::SectionSize { .. }), "{e:?}");
}

/// A forest written from the documented layout: root grid
/// 3 × 1 × 1 over [0, 3] × [0, 1] × [0, 1] in `w2 = (rx − 1) | (ry − 1) << 16`,
/// `w3 = rz − 1`, max depth 1, root 1 split. Boxes and corners are checked
/// against unit cubes and halves computed here.
#[test]
fn documented_bytes_decode_to_a_forest() {
    let (min, max) = (Vec3::ZERO, Vec3::new(3.0, 1.0, 1.0));
    // Every point of the depth-1 lattice (spacing 0.5), 7 × 3 × 3.
    let mut positions = Vec::new();
    for k in 0..3 {
        for j in 0..3 {
            for i in 0..7 {
                positions.push(Vec3::new(i as f32, j as f32, k as f32) * 0.5);
            }
        }
    }
    let forest = |w2: u32, w3: u32, nodes: u32| {
        file_with(
            positions.clone(),
            vec![(
                SectionId::OCTREE,
                octc_forest_bytes([nodes, 1, w2, w3], min, max, &[0b0000_0010, 0]),
            )],
        )
    };
    let f = ProbeFile::from_bytes(&forest(2, 0, 11)).unwrap();
    let o = octree(&f).unwrap();
    assert_eq!(o.roots, [3, 1, 1]);
    assert_eq!(o.nodes.len(), 11);
    for i in 0..3usize {
        let n = &o.nodes[i];
        assert_eq!(n.depth, 0);
        let lo = Vec3::new(i as f32, 0.0, 0.0);
        assert_eq!((n.min, n.max), (lo, lo + Vec3::ONE));
        assert_eq!(n.first_child, if i == 1 { 3 } else { NONE });
    }
    for k in 0..8usize {
        let n = &o.nodes[3 + k];
        let lo = Vec3::new(
            1.0 + 0.5 * (k & 1) as f32,
            0.5 * ((k >> 1) & 1) as f32,
            0.5 * ((k >> 2) & 1) as f32,
        );
        assert_eq!((n.min, n.max, n.depth), (lo, lo + Vec3::splat(0.5), 1));
        let list = &o.samples[n.sample_offset as usize..][..8];
        for (c, &s) in list.iter().enumerate() {
            let want = Vec3::new(
                if c & 1 == 1 { n.max.x } else { n.min.x },
                if c & 2 == 2 { n.max.y } else { n.min.y },
                if c & 4 == 4 { n.max.z } else { n.min.z },
            );
            assert_eq!(p(&f).positions[s as usize], want);
        }
    }
    // Writing it again keeps the root grid.
    let bytes = f.to_bytes().unwrap();
    assert_eq!(minor_of(&bytes), layout::VERSION_MINOR);
    assert_eq!(ProbeFile::from_bytes(&bytes).unwrap(), f);
    // A root grid that does not match the node count, or out of range.
    for (w2, w3, nodes) in [
        (3, 0, 11),
        (2, 1, 11),
        (2, 0, 12),
        (2, 65536, 11),
        (u32::MAX, 0, 11),
    ] {
        assert!(
            ProbeFile::from_bytes(&forest(w2, w3, nodes)).is_err(),
            "w2 {w2} w3 {w3} nodes {nodes}"
        );
    }
}

/// A forest of leaf roots keeps its root grid, and an octree whose root
/// grid does not match its nodes is refused.
#[test]
fn leaf_forest_round_trips_and_roots_must_match() {
    let f = ProbeFile::from_bytes(&{
        let (min, max) = (Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0));
        let mut positions = Vec::new();
        for k in 0..2 {
            for j in 0..2 {
                for i in 0..3 {
                    positions.push(Vec3::new(i as f32, j as f32, k as f32));
                }
            }
        }
        file_with(
            positions,
            vec![(
                SectionId::OCTREE,
                octc_forest_bytes([2, 0, 1, 0], min, max, &[0]),
            )],
        )
    })
    .unwrap();
    let bytes = f.to_bytes().unwrap();
    let back = ProbeFile::from_bytes(&bytes).unwrap();
    assert_eq!(octree(&back).unwrap().roots, [2, 1, 1]);
    assert_eq!(back, f);
    let mut h = f.clone();
    octree_mut(&mut h).unwrap().roots = [3, 1, 1];
    assert!(h.validate().is_err(), "3 roots, 2 nodes");
    let mut h = f;
    octree_mut(&mut h).unwrap().roots = [1, 1, 1];
    assert!(h.validate().is_err(), "node 1 unreachable");
}
