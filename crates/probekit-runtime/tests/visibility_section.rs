//! Distance moments (`VISM`): round trip, the
//! decoded values against the `half` crate, and hostile sections (truncated,
//! corrupt counts, non-finite and out-of-range values) refused with typed
//! errors, never a panic.

mod common;

use common::*;
use probekit_runtime::format::layout::{self, SECTION_HEADER_LEN};
use probekit_runtime::format::*;

/// `full_file()` with a 3×3 map per probe of values `k/(n+1)` (in [0, 1)).
fn vis_file() -> ProbeFile {
    let mut f = full_file();
    let n = p(&f).positions.len() * 9 * 2;
    cm(&mut f).blend.distance_moments = Some(DistanceMoments {
        resolution: 3,
        max_distance: 7.5,
        data: (0..n)
            .map(|k| half::f16::from_f32(k as f32 / (n + 1) as f32).to_bits())
            .collect(),
    });
    f
}

#[test]
fn moments_round_trip_and_decode_like_half() {
    let f = vis_file();
    let bytes = f.to_bytes().unwrap();
    let back = ProbeFile::from_bytes(&bytes).unwrap();
    assert_eq!(back, f);
    let by = file_bytes_by_section(&bytes).unwrap();
    // 16-byte header + pad16(probes · 9 texels · 2 values · 2 bytes).
    let want = 16 + (p(&f).positions.len() * 36).div_ceil(16) * 16;
    assert_eq!(by["visibility"], want as u64);
    assert_eq!(by.values().sum::<u64>(), bytes.len() as u64);
    let v = c(&back).blend.distance_moments.as_ref().unwrap();
    assert_eq!(v.probe_count(), p(&f).positions.len());
    for (k, m) in v.decode().iter().enumerate() {
        let h = |i: usize| half::f16::from_bits(v.data[2 * k + i]).to_f32();
        assert_eq!(m[0], h(0) * 7.5);
        assert_eq!(m[1], h(1) * 7.5 * 7.5);
    }
    // Without the section the file is the one without moments.
    let mut old = f.clone();
    cm(&mut old).blend.distance_moments = None;
    assert_eq!(old.to_bytes().unwrap(), full_file().to_bytes().unwrap());
}

#[test]
fn the_writer_refuses_bad_moments() {
    type Edit = fn(&mut DistanceMoments);
    let cases: [(&str, Edit); 6] = [
        ("resolution 0", |v| v.resolution = 0),
        ("resolution 65", |v| v.resolution = 65),
        ("max NaN", |v| v.max_distance = f32::NAN),
        ("max negative", |v| v.max_distance = -1.0),
        ("one value short", |v| {
            v.data.pop();
        }),
        ("negative value", |v| {
            v.data[5] = half::f16::from_f32(-0.5).to_bits()
        }),
    ];
    for (what, edit) in cases {
        let mut f = vis_file();
        edit(cm(&mut f).blend.distance_moments.as_mut().unwrap());
        assert!(f.to_bytes().is_err(), "{what}");
    }
    let mut f = vis_file();
    cm(&mut f).blend.distance_moments.as_mut().unwrap().data[3] = 0x7C00; // +inf
    assert!(matches!(
        f.to_bytes(),
        Err(FormatError::NonFinite { id, .. }) if id == SectionId::VISIBILITY
    ));
    let mut f = vis_file();
    cm(&mut f).blend.distance_moments.as_mut().unwrap().data[3] =
        half::f16::from_f32(1.5).to_bits();
    assert!(matches!(
        f.to_bytes(),
        Err(FormatError::InvalidValue { id, .. }) if id == SectionId::VISIBILITY
    ));
}

#[test]
fn truncated_or_corrupt_sections_are_typed_errors() {
    let good = vis_file().to_bytes().unwrap();
    let (off, len) = find_section(&good, SectionId::VISIBILITY);
    let patched = |edit: &dyn Fn(&mut [u8])| load_patched(&good, edit);
    // Probe count one more than the data holds: the section is too short.
    let probes = u32::from_le_bytes(good[off..off + 4].try_into().unwrap());
    assert!(matches!(
        patched(&|b| put_u32(b, off, probes + 1)),
        Err(FormatError::SectionSize { .. })
    ));
    // Count that overflows the size arithmetic.
    assert!(matches!(
        patched(&|b| put_u32(b, off, u32::MAX)),
        Err(FormatError::SectionSize { .. } | FormatError::CountOverflow(_))
    ));
    // Count smaller than the probes, section length adjusted: a count mismatch.
    assert!(matches!(
        patched(&|b| put_u32(b, off, 0)),
        Err(FormatError::SectionSize { .. } | FormatError::CountMismatch { .. })
    ));
    // Resolution 0 and 1000.
    for r in [0, 1000] {
        assert!(matches!(
            patched(&|b| put_u32(b, off + 4, r)),
            Err(FormatError::InvalidValue { .. })
        ));
    }
    // Max distance NaN, 0.
    assert!(matches!(
        patched(&|b| put_u32(b, off + 8, f32::NAN.to_bits())),
        Err(FormatError::NonFinite { .. })
    ));
    assert!(matches!(
        patched(&|b| put_u32(b, off + 8, 0)),
        Err(FormatError::InvalidValue { .. })
    ));
    // A NaN moment in the last probe's map.
    let last = off + SECTION_HEADER_LEN + (probes as usize * 36) - 2;
    assert!(matches!(
        patched(&|b| b[last..last + 2].copy_from_slice(&0x7E00u16.to_le_bytes())),
        Err(FormatError::NonFinite { element, .. }) if element == probes as u64 - 1
    ));
    // A flipped byte without resealing: the checksum catches it.
    let mut b = good.clone();
    b[off + len - 20] ^= 0x55;
    assert!(matches!(
        ProbeFile::from_bytes(&b),
        Err(FormatError::ChecksumMismatch { .. })
    ));
    // Truncations and byte mutations: errors, never a panic.
    hostile_section_variants(&good, SectionId::VISIBILITY, 2000, 0x2545_f491_4f6c_dd1du64);
}

#[test]
fn a_reader_skips_unknown_sections_of_a_newer_minor() {
    // What this reader does with a 2.1 file, simulated here: a section id
    // this reader does not know, in a file of a newer minor, is skipped.
    let f = vis_file();
    let bytes = f.to_bytes().unwrap();
    let (_, sections) = read_sections(&bytes).unwrap();
    let owned: Vec<(SectionId, Vec<u8>)> = sections
        .iter()
        .map(|s| {
            let id = if s.id == SectionId::VISIBILITY {
                SectionId::from_fourcc(*b"VISX")
            } else {
                s.id
            };
            (id, s.bytes.to_vec())
        })
        .collect();
    let newer = assemble_file(0, layout::VERSION_MINOR + 1, 0, &owned);
    let back = ProbeFile::from_bytes(&newer).unwrap();
    assert!(c(&back).blend.distance_moments.is_none());
    assert_eq!(p(&back).positions, p(&f).positions);
}
