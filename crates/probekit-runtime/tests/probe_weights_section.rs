//! Fitted probe weights: `PWGT` (with its brightness and directional exponents) round trips with the
//! bytes of the documented layout, reaches [`ProbeCloud`], and hostile
//! sections (out-of-range or non-finite weights, wrong counts, a non-cloud
//! file, truncation, byte mutations) are refused with typed errors, never a
//! panic.

mod common;

use common::*;
use probekit_runtime::cloud::ProbeCloud;
use probekit_runtime::format::*;

#[test]
fn probe_weights_round_trip_with_the_documented_bytes() {
    let f = weights_file();
    let w = c(&f).blend.probe_weights.clone().unwrap();
    let bytes = f.to_bytes().unwrap();
    assert_eq!(ProbeFile::from_bytes(&bytes).unwrap(), f);
    let (off, len) = find_section(&bytes, SectionId::PROBE_WEIGHTS);
    // Header [count, 0, 0, 0], then one little-endian f32 per probe, padded to 16.
    assert_eq!(len, 16 + (4 * w.len()).div_ceil(16) * 16);
    let word =
        |i: usize| u32::from_le_bytes(bytes[off + 4 * i..off + 4 * i + 4].try_into().unwrap());
    assert_eq!(
        [word(0), word(1), word(2), word(3)],
        [w.len() as u32, 0, 0, 0]
    );
    for (i, x) in w.iter().enumerate() {
        assert_eq!(f32::from_bits(word(4 + i)), *x);
    }
    assert_eq!(
        file_bytes_by_section(&bytes).unwrap()["probe_weights"],
        len as u64
    );
    // Without the section the file is the one without weights.
    let mut old = f.clone();
    cm(&mut old).blend.probe_weights = None;
    assert_eq!(old.to_bytes().unwrap(), cvis_file().to_bytes().unwrap());
}

#[test]
fn a_loaded_cloud_blends_with_the_files_weights() {
    // `full_file`'s tetrahedra with weights (`cvis_file`'s bits are a
    // format fixture, not the mesh's hull).
    let mut f = full_file();
    cm(&mut f).blend.probe_weights = c(&weights_file()).blend.probe_weights.clone();
    let cloud =
        ProbeCloud::from_file(&ProbeFile::from_bytes(&f.to_bytes().unwrap()).unwrap()).unwrap();
    assert_eq!(cloud.probe_weights(), c(&f).blend.probe_weights.as_deref());
    assert!(cloud.probe_weighting_enabled());
}

#[test]
fn bad_probe_weights_are_typed_errors() {
    let good = weights_file().to_bytes().unwrap();
    let (off, _) = find_section(&good, SectionId::PROBE_WEIGHTS);
    for (k, bad) in [
        (0usize, f32::NAN),
        (1, 0.0),
        (2, -1.0),
        (3, 2e6),
        (4, f32::INFINITY),
        (0, 1e-7),
    ] {
        let r = load_patched(&good, |b| put_u32(b, off + 16 + 4 * k, bad.to_bits()));
        assert!(
            matches!(
                r,
                Err(FormatError::InvalidValue { id: SectionId::PROBE_WEIGHTS, element, .. }) if element == k as u64
            ),
            "{bad} at {k}: {r:?}"
        );
    }
    // The writer refuses them too.
    let mut f = weights_file();
    cm(&mut f).blend.probe_weights.as_mut().unwrap()[2] = f32::NAN;
    assert!(f.to_bytes().is_err());
    // One weight fewer than probes.
    let mut f = weights_file();
    cm(&mut f).blend.probe_weights.as_mut().unwrap().pop();
    assert!(f.validate().is_err());
    let r = load_patched(&good, |b| put_u32(b, off, 4));
    assert!(r.is_err(), "{r:?}");
}

#[test]
fn hostile_probe_weight_sections_never_panic() {
    let good = weights_file().to_bytes().unwrap();
    hostile_section_variants(&good, SectionId::PROBE_WEIGHTS, 400, 0x9e37);
}

/// The brightness exponent the weights were fitted with rides in `PWGT`'s
/// header word `w1`: written as `f32` bits, read back and applied by
/// [`ProbeCloud::from_file`]; zero leaves the word zero.
#[test]
fn the_brightness_exponent_rides_in_pwgt_w1() {
    let mut f = weights_file();
    cm(&mut f).blend.brightness_exponent = 0.5;
    let bytes = f.to_bytes().unwrap();
    let (off, _) = find_section(&bytes, SectionId::PROBE_WEIGHTS);
    let w1 = u32::from_le_bytes(bytes[off + 4..off + 8].try_into().unwrap());
    assert_eq!(f32::from_bits(w1), 0.5);
    assert_eq!(ProbeFile::from_bytes(&bytes).unwrap(), f);
    // -0.0 is 0.0: the bytes without an exponent.
    let mut zero = weights_file();
    cm(&mut zero).blend.brightness_exponent = -0.0;
    assert_eq!(zero.to_bytes().unwrap(), weights_file().to_bytes().unwrap());
    // The loaded cloud blends with it.
    let mut g = full_file();
    cm(&mut g).blend.probe_weights = c(&weights_file()).blend.probe_weights.clone();
    cm(&mut g).blend.brightness_exponent = 1.0;
    let cloud =
        ProbeCloud::from_file(&ProbeFile::from_bytes(&g.to_bytes().unwrap()).unwrap()).unwrap();
    assert_eq!(cloud.brightness_weighting(), 1.0);
    cm(&mut g).blend.brightness_exponent = 0.0;
    let plain = ProbeCloud::from_file(&g).unwrap();
    assert_eq!(plain.brightness_weighting(), 0.0);
}

/// An exponent (brightness in `w1`, directional in `w2`) out of range or
/// not a number, in a file or handed to the writer, is a typed error; so is
/// one without probe weights to carry it.
#[test]
fn bad_brightness_exponents_are_typed_errors() {
    let good = weights_file().to_bytes().unwrap();
    let (off, _) = find_section(&good, SectionId::PROBE_WEIGHTS);
    type Field = fn(&mut ProbeFile) -> &mut f32;
    let fields: [(usize, Field); 2] = [
        (1, |f| &mut cm(f).blend.brightness_exponent),
        (2, |f| &mut cm(f).blend.directional_exponent),
    ];
    for (word, field) in fields {
        for bad in [f32::NAN, -0.5, 4.5, f32::INFINITY, f32::NEG_INFINITY] {
            let r = load_patched(&good, |b| put_u32(b, off + 4 * word, bad.to_bits()));
            assert!(
                matches!(
                    r,
                    Err(FormatError::InvalidValue {
                        id: SectionId::PROBE_WEIGHTS,
                        element: 0,
                        ..
                    })
                ),
                "w{word} {bad}: {r:?}"
            );
            let mut f = weights_file();
            *field(&mut f) = bad;
            assert!(f.to_bytes().is_err(), "w{word} {bad}");
        }
        let mut f = cvis_file();
        *field(&mut f) = 1.0;
        assert!(matches!(f.to_bytes(), Err(FormatError::Unrepresentable(_))));
    }
}

/// The directional brightness exponent rides in `PWGT`'s header word `w2`:
/// written as `f32` bits (with or without the brightness exponent beside
/// it in `w1`), read back and applied by [`ProbeCloud::from_file`]; zero
/// leaves the word zero, and a file with the word zeroed blends without it.
#[test]
fn the_directional_exponent_rides_in_pwgt_w2() {
    let mut f = weights_file();
    cm(&mut f).blend.brightness_exponent = 0.5;
    cm(&mut f).blend.directional_exponent = 0.25;
    let bytes = f.to_bytes().unwrap();
    let (off, _) = find_section(&bytes, SectionId::PROBE_WEIGHTS);
    let word =
        |i: usize| u32::from_le_bytes(bytes[off + 4 * i..off + 4 * i + 4].try_into().unwrap());
    assert_eq!(f32::from_bits(word(1)), 0.5);
    assert_eq!(f32::from_bits(word(2)), 0.25);
    assert_eq!(word(3), 0);
    assert_eq!(ProbeFile::from_bytes(&bytes).unwrap(), f);
    let mut only = weights_file();
    cm(&mut only).blend.directional_exponent = 1.0;
    // -0.0 is 0.0: the bytes without it.
    let mut zero = f.clone();
    cm(&mut zero).blend.directional_exponent = -0.0;
    let mut eight = f.clone();
    cm(&mut eight).blend.directional_exponent = 0.0;
    assert_eq!(zero.to_bytes().unwrap(), eight.to_bytes().unwrap());
    // The loaded cloud blends with it; with the word zeroed, without.
    let mut g = full_file();
    cm(&mut g).blend.probe_weights = c(&weights_file()).blend.probe_weights.clone();
    cm(&mut g).blend.directional_exponent = 0.25;
    let gb = g.to_bytes().unwrap();
    let cloud = ProbeCloud::from_file(&ProbeFile::from_bytes(&gb).unwrap()).unwrap();
    assert_eq!(cloud.directional_brightness(), 0.25);
    let (goff, _) = find_section(&gb, SectionId::PROBE_WEIGHTS);
    let old = load_patched(&gb, |b| put_u32(b, goff + 8, 0)).unwrap();
    assert_eq!(
        ProbeCloud::from_file(&old)
            .unwrap()
            .directional_brightness(),
        0.0
    );
}
