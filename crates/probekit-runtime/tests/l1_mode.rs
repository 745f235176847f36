//! The intended L1 evaluation in the header's flags: written
//! only when not linear, read back, refused where it makes no sense, and
//! read as linear from unknown values of newer minors.

mod common;

use common::{load_patched, p, pm, put_u32};
use glam::Vec3;
use probekit_runtime::format::layout::{self, header};
use probekit_runtime::format::{Codec, Coefficients, FormatError, L1Mode, ProbeFile};

/// A two-probe L1 cloud (positions only, no tetrahedra needed here).
fn l1_file(codec: Codec) -> ProbeFile {
    let sh = [
        Vec3::new(1.0, 0.9, 0.8),
        Vec3::new(0.1, 0.0, -0.1),
        Vec3::new(0.2, 0.3, 0.1),
        Vec3::new(-0.1, 0.1, 0.05),
    ];
    let mut f = ProbeFile::cloud(vec![Vec3::ZERO, Vec3::X], 2, &[sh, sh].concat()).unwrap();
    if codec == Codec::L1Q13 {
        // The 13-byte codec's bytes, encoded by the SH crate.
        let enc = probekit_runtime::sh::codec::encode_l1(&sh);
        pm(&mut f).coefficients = Coefficients {
            codec,
            order: 2,
            data: [enc, enc].concat(),
        };
    }
    f
}

fn flags_of(bytes: &[u8]) -> u32 {
    u32::from_le_bytes(bytes[header::FLAGS..header::FLAGS + 4].try_into().unwrap())
}

#[test]
fn linear_files_keep_flags_zero() {
    let bytes = l1_file(Codec::F32).to_bytes().unwrap();
    assert_eq!(flags_of(&bytes), 0);
    assert_eq!(
        ProbeFile::from_bytes(&bytes).unwrap().l1_mode(),
        L1Mode::Linear
    );
}

#[test]
fn hallucinated_zh3_round_trips_in_the_flags() {
    for codec in [Codec::F32, Codec::F16, Codec::L1Q13] {
        let mut f = l1_file(codec);
        pm(&mut f).l1_mode = L1Mode::Zh3Hallucinated;
        let bytes = f.to_bytes().unwrap();
        assert_eq!(flags_of(&bytes) & layout::FLAGS_L1_MODE, 1, "{codec:?}");
        let back = ProbeFile::from_bytes(&bytes).unwrap();
        assert_eq!(back, f);
        assert_eq!(back.to_bytes().unwrap(), bytes);
    }
}

#[test]
fn a_mode_other_than_linear_needs_l1_coefficients() {
    for order in [1u32, 3] {
        let n = (order * order) as usize;
        let mut f = ProbeFile::cloud(vec![Vec3::ZERO], order, &vec![Vec3::ONE; n]).unwrap();
        pm(&mut f).l1_mode = L1Mode::Zh3Hallucinated;
        assert!(matches!(
            f.to_bytes(),
            Err(FormatError::InvalidValue { .. })
        ));
        // The same file with the flag patched in is refused by the reader.
        pm(&mut f).l1_mode = L1Mode::Linear;
        let good = f.to_bytes().unwrap();
        let r = load_patched(&good, |b| put_u32(b, header::FLAGS, 1));
        assert!(matches!(r, Err(FormatError::InvalidValue { .. })), "{r:?}");
    }
}

#[test]
fn reserved_values_are_refused_and_other_bits_ignored() {
    let good = l1_file(Codec::L1Q13).to_bytes().unwrap();
    for reserved in [2u32, 3] {
        let r = load_patched(&good, |b| put_u32(b, header::FLAGS, reserved));
        assert!(matches!(r, Err(FormatError::InvalidValue { .. })), "{r:?}");
    }
    // Undefined bits above the mode are ignored.
    let f = load_patched(&good, |b| put_u32(b, header::FLAGS, 0xF000_0001)).unwrap();
    assert_eq!(p(&f).l1_mode, L1Mode::Zh3Hallucinated);
    // A newer minor may define more modes: read as linear.
    let f = load_patched(&good, |b| {
        put_u32(b, header::FLAGS, 2);
        b[header::MINOR..header::MINOR + 2]
            .copy_from_slice(&(layout::VERSION_MINOR + 1).to_le_bytes());
    })
    .unwrap();
    assert_eq!(p(&f).l1_mode, L1Mode::Linear);
}
