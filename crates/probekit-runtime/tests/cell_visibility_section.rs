//! Cell visibility: `CVSP` (format 1.5, sparse, what the writer writes)
//! round trips at minor 5 with the bytes of the documented layout; `CVIS`
//! (1.4, dense) files still load, to the same bits; hostile sections (bad
//! subdivision, wrong counts, set padding bits, a stored clear record,
//! truncation, byte mutations) are refused with typed errors, never a panic.

mod common;

use common::*;
use probekit_runtime::cloud::cell_visibility::record_bytes;
use probekit_runtime::cloud::CellVisibility;
use probekit_runtime::format::layout::{ENTRY_LEN, HEADER_LEN, SECTION_HEADER_LEN};
use probekit_runtime::format::*;

/// The file's sections, with `id`'s replaced by `with` (kept in place).
fn replace_section(bytes: &[u8], id: SectionId, with: (SectionId, Vec<u8>)) -> Vec<u8> {
    let count = u32::from_le_bytes(bytes[20..24].try_into().unwrap()) as usize;
    let sections: Vec<(SectionId, Vec<u8>)> = (0..count)
        .map(|k| {
            let (sid, off, len) = entry_of(bytes, k);
            if sid == id {
                with.clone()
            } else {
                (sid, bytes[off..off + len].to_vec())
            }
        })
        .collect();
    assert!(HEADER_LEN + count * ENTRY_LEN <= bytes.len());
    assemble_file(0, minor_of(bytes), 0, &sections)
}

/// A dense `CVIS` (1.4) section holding `records`.
fn cvis_section(tets: usize, records: &[u8]) -> (SectionId, Vec<u8>) {
    let mut s = SectionBuilder::new([tets as u32, HULL as u32, K, 0]);
    s.bytes(records);
    (SectionId::CELL_VISIBILITY, s.finish())
}

#[test]
fn cell_visibility_round_trips_sparse_at_minor_5_with_the_documented_size() {
    let f = cvis_file();
    let c = f.cell_visibility.as_ref().unwrap();
    let tets = f.tetrahedra.as_ref().unwrap().vertices.len();
    let cells = tets + HULL;
    // Every third cell is clear and has no record.
    let clear = (0..cells).filter(|i| i % 3 == 0).count();
    assert_eq!(c.record_count(), cells - clear);
    assert_eq!(c.to_dense(), dense_records(tets));
    let bytes = f.to_bytes().unwrap();
    assert_eq!(minor_of(&bytes), 5);
    let back = ProbeFile::from_bytes(&bytes).unwrap();
    assert_eq!(back, f);
    // k = 2: L3 = 10 points, 40 bits = 5 bytes; L2 = 6 points, 18 bits = 3 bytes.
    assert_eq!((record_bytes(4, 2), record_bytes(3, 2)), (5, 3));
    let stored_tets = (0..tets).filter(|i| i % 3 != 0).count();
    let stored_hull = (tets..cells).filter(|i| i % 3 != 0).count();
    let want = 16
        + cells.div_ceil(8).div_ceil(16) * 16
        + (stored_tets * 5 + stored_hull * 3).div_ceil(16) * 16;
    let by = file_bytes_by_section(&bytes).unwrap();
    assert_eq!(by["cell_visibility"], want as u64);
    let (off, _) = find_section(&bytes, SectionId::CELL_VISIBILITY_SPARSE);
    let w = |i: usize| u32::from_le_bytes(bytes[off + 4 * i..off + 4 * i + 4].try_into().unwrap());
    assert_eq!([w(0), w(1), w(2), w(3)], [tets as u32, HULL as u32, K, 0]);
    // The mask: bit i set for the cells with a record (i % 3 != 0).
    let mask = &bytes[off + 16..off + 16 + cells.div_ceil(8)];
    for i in 0..cells {
        assert_eq!(mask[i >> 3] >> (i & 7) & 1 == 1, i % 3 != 0, "cell {i}");
    }
    // Without the section the file is what it was before 1.4.
    let mut old = f.clone();
    old.cell_visibility = None;
    assert_eq!(old.to_bytes().unwrap(), full_file().to_bytes().unwrap());
    assert!(minor_of(&old.to_bytes().unwrap()) < 4);
}

#[test]
fn a_dense_cvis_file_of_format_1_4_loads_to_the_same_bits() {
    let f = cvis_file();
    let tets = f.tetrahedra.as_ref().unwrap().vertices.len();
    let sparse = f.to_bytes().unwrap();
    let mut dense = replace_section(
        &sparse,
        SectionId::CELL_VISIBILITY_SPARSE,
        cvis_section(tets, &dense_records(tets)),
    );
    dense[10..12].copy_from_slice(&4u16.to_le_bytes());
    reseal(&mut dense);
    let back = ProbeFile::from_bytes(&dense).unwrap();
    assert_eq!(back.cell_visibility, f.cell_visibility);
    // Written again, it is the sparse file.
    assert_eq!(back.to_bytes().unwrap(), sparse);
    // A set padding bit in a dense record (here a clear one, which the
    // sparse form would drop) is still refused.
    let mut recs = dense_records(tets);
    recs[tets * 5 + 2] |= 0x80; // bit 23 of hull record 0 (18 used): padding.
    let mut bad = replace_section(
        &sparse,
        SectionId::CELL_VISIBILITY_SPARSE,
        cvis_section(tets, &recs),
    );
    reseal(&mut bad);
    assert!(matches!(
        ProbeFile::from_bytes(&bad),
        Err(FormatError::InvalidValue { id, element, .. })
            if id == SectionId::CELL_VISIBILITY && element == tets as u64
    ));
    // Both sections in one file: refused.
    let count = u32::from_le_bytes(sparse[20..24].try_into().unwrap()) as usize;
    let mut sections: Vec<(SectionId, Vec<u8>)> = (0..count)
        .map(|k| {
            let (sid, off, len) = entry_of(&sparse, k);
            (sid, sparse[off..off + len].to_vec())
        })
        .collect();
    sections.insert(0, cvis_section(tets, &dense_records(tets)));
    let mut both = assemble_file(0, 5, 0, &sections);
    reseal(&mut both);
    assert!(matches!(
        ProbeFile::from_bytes(&both),
        Err(FormatError::InvalidValue { .. })
    ));
}

#[test]
fn the_writer_refuses_inconsistent_cell_visibility() {
    // A padding bit set in a stored record: a k = 2 hull record uses 18 of
    // its 24 bits; hull face h (cell tets + h) is not clear.
    let mut f = cvis_file();
    let tets = f.tetrahedra.as_ref().unwrap().vertices.len();
    let h = (0..HULL).find(|h| (tets + h) % 3 != 0).unwrap();
    let mut data = dense_records(tets);
    data[tets * 5 + 3 * h + 2] |= 0x80;
    f.cell_visibility = Some(CellVisibility::new(K, tets, HULL, data).unwrap());
    assert!(matches!(
        f.to_bytes(),
        Err(FormatError::InvalidValue { id, element, .. })
            if id == SectionId::CELL_VISIBILITY_SPARSE && element == (tets + h) as u64
    ));
    // One record short of the tetrahedra.
    let mut f = cvis_file();
    let data = vec![0u8; (tets - 1) * record_bytes(4, K) + HULL * record_bytes(3, K)];
    f.cell_visibility = Some(CellVisibility::new(K, tets - 1, HULL, data).unwrap());
    assert!(matches!(
        f.to_bytes(),
        Err(FormatError::CountMismatch { .. })
    ));
    // Without tetrahedra.
    let mut f = cvis_file();
    f.tetrahedra = None;
    assert!(f.to_bytes().is_err());
    // A stored record that is clear, or a mask padding bit: not canonical.
    let c = cvis_file().cell_visibility.unwrap();
    let mut mask = c.mask().to_vec();
    mask[0] |= 1; // cell 0 is clear: now it claims a record...
    let mut recs = vec![0xffu8; 5]; // ...which is all ones (a clear record).
    recs[4] = 0xff;
    recs.extend_from_slice(c.records());
    let odd = CellVisibility::from_sparse(K, tets, HULL, mask, recs).unwrap();
    assert_eq!(odd.first_noncanonical(), Some(0));
    let mut mask = c.mask().to_vec();
    *mask.last_mut().unwrap() |= 0x80;
    let cells = tets + HULL;
    assert!(cells % 8 != 0, "the mask must have padding bits");
    let odd = CellVisibility::from_sparse(K, tets, HULL, mask, c.records().to_vec()).unwrap();
    assert_eq!(odd.first_noncanonical(), Some(cells));
    // The constructors refuse a bad k or a wrong length.
    assert!(CellVisibility::new(0, 1, 0, vec![]).is_none());
    assert!(CellVisibility::new(9, 1, 0, vec![0; 1000]).is_none());
    assert!(CellVisibility::new(2, 1, 0, vec![0; 4]).is_none());
    let wrong_mask = vec![0; (tets + HULL).div_ceil(8) + 1];
    assert!(CellVisibility::from_sparse(K, tets, HULL, wrong_mask, vec![]).is_none());
    assert!(CellVisibility::from_sparse(
        K,
        tets,
        HULL,
        c.mask().to_vec(),
        c.records()[1..].to_vec()
    )
    .is_none());
}

#[test]
fn truncated_or_corrupt_sections_are_typed_errors() {
    let f = cvis_file();
    let good = f.to_bytes().unwrap();
    let id = SectionId::CELL_VISIBILITY_SPARSE;
    let (off, len) = find_section(&good, id);
    let patched = |edit: &dyn Fn(&mut [u8])| load_patched(&good, edit);
    let tets = u32::from_le_bytes(good[off..off + 4].try_into().unwrap());
    // More cells than the section holds, or counts that overflow.
    assert!(matches!(
        patched(&|b| put_u32(b, off, tets + 100)),
        Err(FormatError::SectionSize { .. })
    ));
    for w in [0usize, 1] {
        assert!(matches!(
            patched(&|b| put_u32(b, off + 4 * w, u32::MAX)),
            Err(FormatError::SectionSize { .. } | FormatError::CountOverflow(_))
        ));
    }
    // k = 0 and k = 9.
    for k in [0, 9] {
        assert!(matches!(
            patched(&|b| put_u32(b, off + 8, k)),
            Err(FormatError::InvalidValue { .. })
        ));
    }
    let cells = tets as usize + HULL;
    let mask_at = off + SECTION_HEADER_LEN;
    // A mask padding bit; a clear cell's bit set (one record more than the
    // section holds).
    assert!(cells % 8 != 0);
    assert!(matches!(
        patched(&|b| b[mask_at + cells / 8] |= 0x80),
        Err(FormatError::InvalidValue { .. })
    ));
    assert!(matches!(
        patched(&|b| b[mask_at] |= 1),
        Err(FormatError::SectionSize { .. })
    ));
    // A set padding bit in the last stored record (a hull face: bits 18..24
    // of 24).
    let c = f.cell_visibility.as_ref().unwrap();
    let last = mask_at + cells.div_ceil(8).div_ceil(16) * 16 + c.records().len() - 1;
    assert!(last < off + len);
    assert!(matches!(
        patched(&|b| b[last] |= 0x40),
        Err(FormatError::InvalidValue { .. })
    ));
    // Truncations and byte mutations, of the sparse and of a dense section:
    // errors, never a panic.
    hostile_section_variants(&good, id, 2000, 0x9e37_79b9_7f4a_7c15u64);
    let mut dense = replace_section(
        &good,
        id,
        cvis_section(tets as usize, &dense_records(tets as usize)),
    );
    reseal(&mut dense);
    hostile_section_variants(
        &dense,
        SectionId::CELL_VISIBILITY,
        1000,
        0x2545_f491_4f6c_dd1du64,
    );
}
