//! Occluder planes of cells: `CPLN` round trips with
//! the bytes of the documented layout, reaches [`ProbeCloud`], and hostile
//! sections (truncated, counts past the body, unsorted, repeated or
//! out-of-range indices, non-finite values, normals that are not unit, a
//! tetrahedron count other than `TETS`'s, no cell visibility, a file that is
//! not a cloud, byte mutations) are refused with typed errors, never a
//! panic.

mod common;

use common::*;
use probekit_runtime::cloud::cell_visibility::records_len;
use probekit_runtime::cloud::{CellPlanes, CellVisibility, ProbeCloud};
use probekit_runtime::format::layout::{self, SECTION_HEADER_LEN};
use probekit_runtime::format::*;

const ID: SectionId = SectionId::CELL_PLANES;

/// The sections of a file, in table order, as owned bytes.
fn sections_of(bytes: &[u8]) -> Vec<(SectionId, Vec<u8>)> {
    let (_, sections) = read_sections(bytes).unwrap();
    sections.iter().map(|s| (s.id, s.bytes.to_vec())).collect()
}

/// A file of `kind` from `sections`, at this version's minor.
fn assemble(kind: u32, sections: &[(SectionId, Vec<u8>)]) -> Vec<u8> {
    assemble_file(kind, layout::VERSION_MINOR, 0, sections)
}

/// [`planes_file`]'s bytes with its `CPLN` section replaced by `body`.
fn with_cpln(body: Vec<u8>) -> Vec<u8> {
    let mut sections = sections_of(&planes_file().to_bytes().unwrap());
    for (id, b) in &mut sections {
        if *id == ID {
            *b = body.clone();
        }
    }
    assemble(0, &sections)
}

/// A `CPLN` section as the documented layout spells it.
fn cpln(tet_count: u32, tets: &[u32], planes: &[[f32; 4]]) -> Vec<u8> {
    let mut s = SectionBuilder::new([tet_count, tets.len() as u32, 0, 0]);
    s.u32s(tets.iter().copied()).pad();
    s.f32s(planes.iter().flatten().copied());
    s.finish()
}

#[test]
fn cell_planes_round_trip_with_the_documented_bytes() {
    let f = planes_file();
    let p = c(&f).blend.cell_planes.clone().unwrap();
    let tets = c(&f).tetrahedra.as_ref().unwrap().vertices.len();
    assert_eq!((p.tet_count(), p.len()), (tets, 2));
    let bytes = f.to_bytes().unwrap();
    let back = ProbeFile::from_bytes(&bytes).unwrap();
    assert_eq!(back, f);
    assert_eq!(
        c(&back).blend.cell_planes.as_ref().unwrap().planes(),
        &PLANES[..]
    );
    assert_eq!(back.to_bytes().unwrap(), bytes);
    // Header [tet_count, count, 0, 0]; count u32 indices padded to 16; count
    // × 4 f32, little-endian.
    let (off, len) = find_section(&bytes, ID);
    assert_eq!(len, 16 + 16 + 2 * 16);
    let word =
        |i: usize| u32::from_le_bytes(bytes[off + 4 * i..off + 4 * i + 4].try_into().unwrap());
    assert_eq!([word(0), word(1), word(2), word(3)], [tets as u32, 2, 0, 0]);
    assert_eq!([word(4), word(5), word(6), word(7)], [0, 1, 0, 0]);
    for (k, plane) in PLANES.iter().enumerate() {
        for (c, x) in plane.iter().enumerate() {
            assert_eq!(f32::from_bits(word(8 + 4 * k + c)), *x);
        }
    }
    assert_eq!(
        &bytes[off..off + len],
        &cpln(tets as u32, &[0, 1], &PLANES)[..]
    );
    assert_eq!(
        file_bytes_by_section(&bytes).unwrap()["cell_planes"],
        len as u64
    );
    assert_eq!(f.bytes_by_section().unwrap()["cell_planes"], len as u64);
    // After the cell visibility (and probe weights), before the metadata.
    let order: Vec<SectionId> = sections_of(&bytes).iter().map(|s| s.0).collect();
    let at = |id| order.iter().position(|&x| x == id).unwrap();
    assert!(at(SectionId::CELL_VISIBILITY) < at(ID));
    assert!(at(ID) < at(SectionId::METADATA));
    let mut both = f.clone();
    cm(&mut both).blend.probe_weights = c(&weights_file()).blend.probe_weights.clone();
    let b = both.to_bytes().unwrap();
    let order: Vec<SectionId> = sections_of(&b).iter().map(|s| s.0).collect();
    let at = |id| order.iter().position(|&x| x == id).unwrap();
    assert!(at(SectionId::PROBE_WEIGHTS) < at(ID));
    assert_eq!(ProbeFile::from_bytes(&b).unwrap(), both);
}

#[test]
fn the_documented_example_section() {
    // docs/file-format.md, `CPLN`: 2 tetrahedra, tetrahedron 1 cut by z = 0.5.
    let hex = "02000000 01000000 00000000 00000000 01000000 00000000 00000000 00000000 \
               00000000 00000000 0000803f 0000003f";
    let want: Vec<u8> = hex
        .split_whitespace()
        .flat_map(|w| {
            (0..w.len())
                .step_by(2)
                .map(move |i| u8::from_str_radix(&w[i..i + 2], 16).unwrap())
        })
        .collect();
    assert_eq!(cpln(2, &[1], &[[0.0, 0.0, 1.0, 0.5]]), want);
    let f = ProbeFile::from_bytes(&with_cpln(want)).unwrap();
    let p = c(&f).blend.cell_planes.as_ref().unwrap();
    assert_eq!((p.tet_count(), p.tets()), (2, &[1][..]));
    assert_eq!(p.plane(1), Some([0.0, 0.0, 1.0, 0.5]));
}

#[test]
fn files_without_cell_planes_are_the_files_without_them() {
    let mut old = planes_file();
    cm(&mut old).blend.cell_planes = None;
    assert_eq!(old.to_bytes().unwrap(), cvis_file().to_bytes().unwrap());
}

#[test]
fn an_empty_plane_set_round_trips() {
    let mut f = cvis_file();
    let tets = c(&f).tetrahedra.as_ref().unwrap().vertices.len();
    cm(&mut f).blend.cell_planes = Some(CellPlanes::new(tets, vec![], vec![]).unwrap());
    let bytes = f.to_bytes().unwrap();
    assert_eq!(find_section(&bytes, ID).1, SECTION_HEADER_LEN);
    assert_eq!(ProbeFile::from_bytes(&bytes).unwrap(), f);
}

#[test]
fn a_loaded_cloud_answers_with_the_files_planes() {
    // `full_file`'s mesh with cell visibility sized to its hull (`cvis_file`'s
    // bits are a format fixture, not the mesh's hull).
    let mut f = full_file();
    let mesh = ProbeCloud::mesh_from_file(&f).unwrap();
    let (tets, hull) = (mesh.tets().len(), mesh.hull_face_count());
    let data = vec![0u8; records_len(K, tets, hull).unwrap()];
    cm(&mut f).blend.cell_visibility = Some(CellVisibility::new(K, tets, hull, data).unwrap());
    cm(&mut f).blend.cell_planes = Some(CellPlanes::new(tets, vec![1], vec![PLANES[1]]).unwrap());
    let back = ProbeFile::from_bytes(&f.to_bytes().unwrap()).unwrap();
    let cloud = ProbeCloud::from_file(&back).unwrap();
    let planes = cloud.cell_planes().expect("planes loaded");
    assert_eq!(Some(planes), c(&f).blend.cell_planes.as_ref());
    assert_eq!(planes.tets(), &[1]);
    assert_eq!(planes.planes(), &[PLANES[1]]);
    assert_eq!(planes.plane(1), Some(PLANES[1]));
    assert_eq!(planes.plane(0), None);
}

#[test]
fn bad_entries_are_typed_errors_naming_the_first_bad_one() {
    let good = planes_file().to_bytes().unwrap();
    let (off, _) = find_section(&good, ID);
    let tet_at = |k: usize| off + 16 + 4 * k;
    let plane_at = |k: usize, c: usize| off + 32 + 16 * k + 4 * c;
    // Unsorted, repeated.
    for pair in [[1, 0], [0, 0], [1, 1]] {
        let r = load_patched(&good, |b| {
            put_u32(b, tet_at(0), pair[0]);
            put_u32(b, tet_at(1), pair[1]);
        });
        assert!(
            matches!(
                r,
                Err(FormatError::InvalidValue { id: ID, element: 1, reason })
                    if reason.contains("increasing")
            ),
            "{pair:?}: {r:?}"
        );
    }
    // Past the tetrahedra.
    for (k, v) in [(1usize, 2u32), (1, u32::MAX)] {
        let r = load_patched(&good, |b| put_u32(b, tet_at(k), v));
        assert!(
            matches!(
                r,
                Err(FormatError::IndexOutOfRange { id: ID, element: 1, value, limit: 2 })
                    if value == v as u64
            ),
            "{v}: {r:?}"
        );
    }
    // Not finite: NaN d, infinite normal component.
    for (k, c, x) in [
        (0usize, 3usize, f32::NAN),
        (1, 3, f32::NAN),
        (1, 0, f32::INFINITY),
    ] {
        let r = load_patched(&good, |b| put_u32(b, plane_at(k, c), x.to_bits()));
        assert!(
            matches!(r, Err(FormatError::NonFinite { id: ID, element }) if element == k as u64),
            "{k} {c}: {r:?}"
        );
    }
    // A normal of length 2, one of length 0, one just outside the tolerance.
    for (k, n) in [
        (1usize, [0.0f32, 0.0, -2.0]),
        (0, [0.0, 0.0, 0.0]),
        (0, [1.002, 0.0, 0.0]),
    ] {
        let r = load_patched(&good, |b| {
            for (c, x) in n.iter().enumerate() {
                put_u32(b, plane_at(k, c), x.to_bits());
            }
        });
        assert!(
            matches!(
                r,
                Err(FormatError::InvalidValue { id: ID, element, reason })
                    if element == k as u64 && reason.contains("unit")
            ),
            "{n:?}: {r:?}"
        );
    }
    // Within the tolerance it loads.
    let r = load_patched(&good, |b| {
        put_u32(b, plane_at(1, 2), (-1.0005f32).to_bits())
    });
    assert!(r.is_ok(), "{r:?}");
    // The first bad entry is named: entry 0 non-finite, entry 1 out of range.
    let r = load_patched(&good, |b| {
        put_u32(b, plane_at(0, 1), f32::NAN.to_bits());
        put_u32(b, tet_at(1), 7);
    });
    assert!(
        matches!(r, Err(FormatError::NonFinite { id: ID, element: 0 })),
        "{r:?}"
    );
    // The same refusals from sections built whole.
    let r = ProbeFile::from_bytes(&with_cpln(cpln(2, &[1, 0], &PLANES)));
    assert!(
        matches!(
            r,
            Err(FormatError::InvalidValue {
                id: ID,
                element: 1,
                ..
            })
        ),
        "{r:?}"
    );
    let mut long = PLANES;
    long[1] = [0.0, 2.0, 0.0, 1.0];
    let r = ProbeFile::from_bytes(&with_cpln(cpln(2, &[0, 1], &long)));
    assert!(
        matches!(
            r,
            Err(FormatError::InvalidValue {
                id: ID,
                element: 1,
                ..
            })
        ),
        "{r:?}"
    );
    // And the constructor refuses what the reader refuses.
    assert!(CellPlanes::new(2, vec![1, 0], PLANES.to_vec()).is_none());
    assert!(CellPlanes::new(2, vec![0, 0], PLANES.to_vec()).is_none());
    assert!(CellPlanes::new(2, vec![0, 2], PLANES.to_vec()).is_none());
    assert!(CellPlanes::new(2, vec![0, 1], long.to_vec()).is_none());
}

#[test]
fn counts_and_lengths_that_disagree_are_typed_errors() {
    let good = planes_file().to_bytes().unwrap();
    let (off, len) = find_section(&good, ID);
    let body = good[off..off + len].to_vec();
    // Truncated body: the last plane (16 bytes) or the whole plane array
    // cut off; the header alone.
    for cut in [16usize, 32, 48] {
        let r = ProbeFile::from_bytes(&with_cpln(body[..len - cut].to_vec()));
        assert!(
            matches!(r, Err(FormatError::SectionSize { id: ID, actual, .. }) if actual == (len - cut) as u64),
            "cut {cut}: {r:?}"
        );
    }
    // A count larger (or smaller) than the body holds; counts that overflow.
    for count in [3u32, 1, 0, 1 << 28, u32::MAX] {
        let r = load_patched(&good, |b| put_u32(b, off + 4, count));
        assert!(
            matches!(
                r,
                Err(FormatError::SectionSize { id: ID, .. } | FormatError::CountOverflow(ID))
            ),
            "{count}: {r:?}"
        );
    }
    // A tetrahedron count other than TETS's, huge ones included (checked
    // before the planes' lookup table is allocated).
    for tet_count in [3u32, 1, 0, u32::MAX] {
        let r = load_patched(&good, |b| put_u32(b, off, tet_count));
        assert!(
            matches!(
                r,
                Err(FormatError::CountMismatch { id: ID, expected: 2, actual })
                    if actual == tet_count as u64
            ),
            "{tet_count}: {r:?}"
        );
    }
    // Two CPLN sections.
    let mut sections = sections_of(&good);
    sections.insert(0, (ID, body.clone()));
    let r = ProbeFile::from_bytes(&assemble(0, &sections));
    assert!(matches!(r, Err(FormatError::DuplicateSection(ID))), "{r:?}");
}

#[test]
fn cell_planes_need_a_cloud_with_cell_visibility() {
    let good = planes_file().to_bytes().unwrap();
    // Without cell visibility: the reader and the writer refuse.
    let sections: Vec<_> = sections_of(&good)
        .into_iter()
        .filter(|(id, _)| *id != SectionId::CELL_VISIBILITY)
        .collect();
    let r = ProbeFile::from_bytes(&assemble(0, &sections));
    assert!(
        matches!(
            r,
            Err(FormatError::MissingSection(SectionId::CELL_VISIBILITY))
        ),
        "{r:?}"
    );
    let mut f = planes_file();
    cm(&mut f).blend.cell_visibility = None;
    assert!(matches!(
        f.to_bytes(),
        Err(FormatError::MissingSection(SectionId::CELL_VISIBILITY))
    ));
    // Without tetrahedra (and so without a count to check against).
    let sections: Vec<_> = sections_of(&good)
        .into_iter()
        .filter(|(id, _)| *id != SectionId::TETRAHEDRA)
        .collect();
    let r = ProbeFile::from_bytes(&assemble(0, &sections));
    assert!(
        matches!(r, Err(FormatError::MissingSection(SectionId::TETRAHEDRA))),
        "{r:?}"
    );
    // In a volume or rig file: sections of a cloud do not belong there.
    for kind in [ProbeFileKind::Volume, ProbeFileKind::Rig] {
        let r = ProbeFile::from_bytes(&assemble(kind.id(), &sections_of(&good)));
        assert!(
            matches!(r, Err(FormatError::MisplacedSection { .. })),
            "{kind:?}: {r:?}"
        );
    }
    // A volume file with a CPLN section added.
    let mut sections = sections_of(&compact_volume_file().to_bytes().unwrap());
    sections.insert(sections.len() - 1, (ID, cpln(0, &[], &[])));
    let r = ProbeFile::from_bytes(&assemble(ProbeFileKind::Volume.id(), &sections));
    assert!(
        matches!(
            r,
            Err(FormatError::MisplacedSection {
                id: ID,
                kind: "volume"
            })
        ),
        "{r:?}"
    );
    // Planes for another mesh: the writer refuses them.
    let mut f = planes_file();
    cm(&mut f).blend.cell_planes = Some(CellPlanes::new(3, vec![0, 2], PLANES.to_vec()).unwrap());
    assert!(matches!(
        f.to_bytes(),
        Err(FormatError::CountMismatch {
            id: ID,
            expected: 2,
            actual: 3
        })
    ));
}

#[test]
fn a_reader_skips_unknown_sections_of_newer_minors_only() {
    // An unknown id next to CPLN is refused at this reader's minor and
    // skipped at the next one.
    let good = planes_file().to_bytes().unwrap();
    let mut sections = sections_of(&good);
    sections.insert(
        0,
        (
            SectionId::from_fourcc(*b"ZZZZ"),
            SectionBuilder::new([0; 4]).finish(),
        ),
    );
    let same = assemble_file(0, layout::VERSION_MINOR, 0, &sections);
    assert!(matches!(
        ProbeFile::from_bytes(&same),
        Err(FormatError::UnknownSection(_))
    ));
    let newer = assemble_file(0, layout::VERSION_MINOR + 1, 0, &sections);
    assert_eq!(ProbeFile::from_bytes(&newer).unwrap(), planes_file());
}

#[test]
fn hostile_cell_plane_sections_never_panic() {
    let good = planes_file().to_bytes().unwrap();
    hostile_section_variants(&good, ID, 2000, 0x517c_c1b7_2722_0a95_u64);
}
