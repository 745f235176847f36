//! Cell visibility: `CVSP` (sparse: clear cells have no record) round trips
//! with the bytes of the documented layout; hostile sections (bad
//! subdivision, wrong counts, set padding bits, a stored clear record,
//! truncation, byte mutations) are refused with typed errors, never a panic.

mod common;

use common::*;
use probekit_runtime::cloud::cell_visibility::record_bytes;
use probekit_runtime::cloud::CellVisibility;
use probekit_runtime::format::layout::SECTION_HEADER_LEN;
use probekit_runtime::format::*;

#[test]
fn cell_visibility_round_trips_with_the_documented_size() {
    let f = cvis_file();
    let tets = c(&f).tetrahedra.as_ref().unwrap().vertices.len();
    let c = c(&f).blend.cell_visibility.as_ref().unwrap();
    let cells = tets + HULL;
    // Every third cell is clear and has no record.
    let clear = (0..cells).filter(|i| i % 3 == 0).count();
    assert_eq!(c.record_count(), cells - clear);
    assert_eq!(c.to_dense(), dense_records(tets));
    let bytes = f.to_bytes().unwrap();
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
    let (off, _) = find_section(&bytes, SectionId::CELL_VISIBILITY);
    let w = |i: usize| u32::from_le_bytes(bytes[off + 4 * i..off + 4 * i + 4].try_into().unwrap());
    assert_eq!([w(0), w(1), w(2), w(3)], [tets as u32, HULL as u32, K, 0]);
    // The mask: bit i set for the cells with a record (i % 3 != 0).
    let mask = &bytes[off + 16..off + 16 + cells.div_ceil(8)];
    for i in 0..cells {
        assert_eq!(mask[i >> 3] >> (i & 7) & 1 == 1, i % 3 != 0, "cell {i}");
    }
    // Without the section the file is the one without cell visibility.
    let mut old = f.clone();
    cm(&mut old).blend.cell_visibility = None;
    assert_eq!(old.to_bytes().unwrap(), full_file().to_bytes().unwrap());
}

#[test]
fn the_writer_refuses_inconsistent_cell_visibility() {
    // A padding bit set in a stored record: a k = 2 hull record uses 18 of
    // its 24 bits; hull face h (cell tets + h) is not clear.
    let mut f = cvis_file();
    let tets = c(&f).tetrahedra.as_ref().unwrap().vertices.len();
    let h = (0..HULL).find(|h| (tets + h) % 3 != 0).unwrap();
    let mut data = dense_records(tets);
    data[tets * 5 + 3 * h + 2] |= 0x80;
    cm(&mut f).blend.cell_visibility = Some(CellVisibility::new(K, tets, HULL, data).unwrap());
    assert!(matches!(
        f.to_bytes(),
        Err(FormatError::InvalidValue { id, element, .. })
            if id == SectionId::CELL_VISIBILITY && element == (tets + h) as u64
    ));
    // One record short of the tetrahedra.
    let mut f = cvis_file();
    let data = vec![0u8; (tets - 1) * record_bytes(4, K) + HULL * record_bytes(3, K)];
    cm(&mut f).blend.cell_visibility = Some(CellVisibility::new(K, tets - 1, HULL, data).unwrap());
    assert!(matches!(
        f.to_bytes(),
        Err(FormatError::CountMismatch { .. })
    ));
    // Without tetrahedra.
    let mut f = cvis_file();
    cm(&mut f).tetrahedra = None;
    assert!(f.to_bytes().is_err());
    // A stored record that is clear, or a mask padding bit: not canonical.
    let c = c(&cvis_file()).blend.cell_visibility.clone().unwrap();
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
    let id = SectionId::CELL_VISIBILITY;
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
    let c = c(&f).blend.cell_visibility.as_ref().unwrap();
    let last = mask_at + cells.div_ceil(8).div_ceil(16) * 16 + c.records().len() - 1;
    assert!(last < off + len);
    assert!(matches!(
        patched(&|b| b[last] |= 0x40),
        Err(FormatError::InvalidValue { .. })
    ));
    // Truncations and byte mutations: errors, never a panic.
    hostile_section_variants(&good, id, 2000, 0x9e37_79b9_7f4a_7c15u64);
}
