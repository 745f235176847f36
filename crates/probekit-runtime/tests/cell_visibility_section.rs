//! Cell visibility (`CVIS`, format 1.4): round trip at minor 4, the bytes of
//! the documented layout, and hostile sections (bad subdivision, wrong
//! counts, set padding bits, truncation, byte mutations) refused with typed
//! errors, never a panic.

mod common;

use common::*;
use probekit_runtime::cloud::cell_visibility::{lattice_len, record_bytes};
use probekit_runtime::cloud::CellVisibility;
use probekit_runtime::format::layout::SECTION_HEADER_LEN;
use probekit_runtime::format::*;

const K: u32 = 2;
const HULL: usize = 5;

/// `full_file()` with cell visibility at `k = 2`: record bits set in a
/// fixed pattern, padding bits clear.
fn cvis_file() -> ProbeFile {
    let mut f = full_file();
    let tets = f.tetrahedra.as_ref().unwrap().vertices.len();
    let mut data = Vec::new();
    for (n, count) in [(4usize, tets), (3, HULL)] {
        let used = n * lattice_len(n, K);
        for r in 0..count {
            let mut rec = vec![0u8; record_bytes(n, K)];
            for bit in 0..used {
                if (bit * 7 + r * 3) % 5 < 3 {
                    rec[bit >> 3] |= 1 << (bit & 7);
                }
            }
            data.extend(rec);
        }
    }
    f.cell_visibility = Some(CellVisibility::new(K, tets, HULL, data).unwrap());
    f
}

#[test]
fn cell_visibility_round_trips_at_minor_4_with_the_documented_size() {
    let f = cvis_file();
    let bytes = f.to_bytes().unwrap();
    assert_eq!(minor_of(&bytes), 4);
    let back = ProbeFile::from_bytes(&bytes).unwrap();
    assert_eq!(back, f);
    let tets = f.tetrahedra.as_ref().unwrap().vertices.len();
    // k = 2: L3 = 10 points, 40 bits = 5 bytes; L2 = 6 points, 18 bits = 3 bytes.
    assert_eq!((record_bytes(4, 2), record_bytes(3, 2)), (5, 3));
    let want = 16 + (tets * 5 + HULL * 3).div_ceil(16) * 16;
    let by = file_bytes_by_section(&bytes).unwrap();
    assert_eq!(by["cell_visibility"], want as u64);
    let (off, _) = find_section(&bytes, SectionId::CELL_VISIBILITY);
    let w = |i: usize| u32::from_le_bytes(bytes[off + 4 * i..off + 4 * i + 4].try_into().unwrap());
    assert_eq!([w(0), w(1), w(2), w(3)], [tets as u32, HULL as u32, K, 0]);
    // Without the section the file is what it was before 1.4.
    let mut old = f.clone();
    old.cell_visibility = None;
    assert_eq!(old.to_bytes().unwrap(), full_file().to_bytes().unwrap());
    assert!(minor_of(&old.to_bytes().unwrap()) < 4);
}

#[test]
fn the_writer_refuses_inconsistent_cell_visibility() {
    // A padding bit set: a k = 2 hull record uses 18 of its 24 bits.
    let mut f = cvis_file();
    let tets = f.tetrahedra.as_ref().unwrap().vertices.len();
    let c = f.cell_visibility.take().unwrap();
    let mut data = c.data().to_vec();
    let first_hull = tets * record_bytes(4, K);
    data[first_hull + 2] |= 0x80; // bit 23 of the first hull record: padding.
    f.cell_visibility = Some(CellVisibility::new(K, tets, HULL, data).unwrap());
    assert!(matches!(
        f.to_bytes(),
        Err(FormatError::InvalidValue { id, element, .. })
            if id == SectionId::CELL_VISIBILITY && element == tets as u64
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
    // The constructor refuses a bad k or a wrong length.
    assert!(CellVisibility::new(0, 1, 0, vec![]).is_none());
    assert!(CellVisibility::new(9, 1, 0, vec![0; 1000]).is_none());
    assert!(CellVisibility::new(2, 1, 0, vec![0; 4]).is_none());
}

#[test]
fn truncated_or_corrupt_sections_are_typed_errors() {
    let good = cvis_file().to_bytes().unwrap();
    let (off, _) = find_section(&good, SectionId::CELL_VISIBILITY);
    let patched = |edit: &dyn Fn(&mut [u8])| load_patched(&good, edit);
    let tets = u32::from_le_bytes(good[off..off + 4].try_into().unwrap());
    // More records than the section holds, or counts that overflow.
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
    // A set padding bit in the last hull record (bits 18..24 of 24).
    let last = off + SECTION_HEADER_LEN + tets as usize * 5 + HULL * 3 - 1;
    assert!(matches!(
        patched(&|b| b[last] |= 0x40),
        Err(FormatError::InvalidValue { .. })
    ));
    // Truncations and byte mutations: errors, never a panic.
    hostile_section_variants(
        &good,
        SectionId::CELL_VISIBILITY,
        2000,
        0x9e37_79b9_7f4a_7c15u64,
    );
}
