//! Light groups (`LGRP`): round trip, version handling, and
//! relighting checked against a direct per-probe sum `Σ_g s_g·G_g`
//! computed in f64 from the decoded groups.

mod common;

use common::*;
use glam::{DVec3, Vec3};
use probekit_runtime::format::layout;
use probekit_runtime::format::*;

#[test]
fn groups_round_trip_and_leave_no_trace_when_absent() {
    let g = groups_file();
    let bytes = g.to_bytes().unwrap();
    let back = ProbeFile::from_bytes(&bytes).unwrap();
    assert_eq!(back, g);
    assert_eq!(back.group_names().collect::<Vec<_>>(), ["lamp", "sün"]);
    assert_eq!(back.group("sün").unwrap().coefficients.codec, Codec::F16);
    let by = file_bytes_by_section(&bytes).unwrap();
    assert!(by["light_groups"] > 0);
    assert_eq!(by.values().sum::<u64>(), bytes.len() as u64);
    assert_eq!(g.bytes_by_section().unwrap(), by);

    // Without groups the writer writes the file without them, byte for
    // byte (also pinned by the corpus).
    let f = full_file();
    let old = f.to_bytes().unwrap();
    let mut f2 = g.clone();
    pm(&mut f2).groups.clear();
    pm(&mut f2).coefficients = p(&f).coefficients.clone();
    assert_eq!(f2.to_bytes().unwrap(), old);
}

#[test]
fn a_reader_skips_sections_of_a_newer_minor_but_keeps_groups() {
    // A 2.1 file with an unknown section next to LGRP loads, groups
    // intact: how this reader treats a file of a newer minor.
    let g = groups_file();
    let bytes = g.to_bytes().unwrap();
    let (_, sections) = read_sections(&bytes).unwrap();
    let mut owned: Vec<(SectionId, Vec<u8>)> =
        sections.iter().map(|s| (s.id, s.bytes.to_vec())).collect();
    owned.insert(2, (SectionId::from_fourcc(*b"ZZZZ"), vec![7; 32]));
    let newer = assemble_file(0, layout::VERSION_MINOR + 1, 0, &owned);
    assert_eq!(ProbeFile::from_bytes(&newer).unwrap(), g);
    // The same bytes at this reader's minor: the unknown section is refused.
    let same = assemble_file(0, layout::VERSION_MINOR, 0, &owned);
    assert!(matches!(
        ProbeFile::from_bytes(&same),
        Err(FormatError::UnknownSection(_))
    ));
}

/// `Σ_g s_g·G_g` per coefficient, in f64, from the decoded groups.
fn direct_sum(f: &ProbeFile, scales: &[Vec3]) -> Vec<DVec3> {
    let n = p(f).coefficients.len() * 9;
    let mut out = vec![DVec3::ZERO; n];
    for (g, s) in p(f).groups.iter().zip(scales) {
        for (o, c) in out.iter_mut().zip(g.coefficients.to_f32().unwrap()) {
            *o += c.as_dvec3() * s.as_dvec3();
        }
    }
    out
}

#[test]
fn relighting_equals_the_scaled_sum_of_groups() {
    let g = groups_file();
    // groups_file's total is lamp + sün exactly (f32 sum of the decoded values).
    let unit = direct_sum(&g, &[Vec3::ONE; 2]);
    for (t, u) in p(&g).coefficients.to_f32().unwrap().iter().zip(&unit) {
        assert!((t.as_dvec3() - *u).abs().max_element() < 1e-6);
    }
    // Scale 1 everywhere gives the stored total bit for bit.
    let same = g.relit(&[]).unwrap();
    assert_eq!(same.to_f32().unwrap(), p(&g).coefficients.to_f32().unwrap());

    let cases = [
        [Vec3::new(0.0, 0.0, 0.0), Vec3::ONE],
        [Vec3::ONE, Vec3::ZERO],
        [Vec3::new(2.0, 0.5, -1.0), Vec3::new(0.25, 3.0, 1.0)],
    ];
    for s in cases {
        let got = g.relit(&[("lamp", s[0]), ("sün", s[1])]).unwrap();
        assert_eq!(got.codec, Codec::F32);
        assert_eq!(got.order, 3);
        let want = direct_sum(&g, &s);
        for (a, b) in got.to_f32().unwrap().iter().zip(&want) {
            let tol = 1e-5 * (1.0 + b.abs().max_element());
            assert!((a.as_dvec3() - *b).abs().max_element() < tol, "{a} vs {b}");
        }
    }
}

#[test]
fn relighter_works_in_place_per_probe_and_checks_its_inputs() {
    let g = groups_file();
    let r = Relighter::new(&g).unwrap();
    assert_eq!(r.probe_count(), 5);
    assert_eq!(r.group_names(), ["lamp", "sün"]);
    let s = r.scales_for(&[("sün", Vec3::new(0.0, 2.0, 1.0))]).unwrap();
    assert_eq!(s, [Vec3::ONE, Vec3::new(0.0, 2.0, 1.0)]);
    let mut all = vec![Vec3::ZERO; 5 * 9];
    r.relight_into(&s, &mut all).unwrap();
    let want = direct_sum(&g, &s);
    let mut one = [Vec3::ZERO; 9];
    for i in 0..5 {
        r.relight_probe(i, &s, &mut one).unwrap();
        assert_eq!(one, all[i * 9..i * 9 + 9]);
        for (a, b) in one.iter().zip(&want[i * 9..]) {
            assert!((a.as_dvec3() - *b).abs().max_element() < 1e-5);
        }
    }
    // Bad input: typed errors, no panic.
    assert!(matches!(
        r.scales_for(&[("moon", Vec3::ONE)]),
        Err(FormatError::UnknownGroup(n)) if n == "moon"
    ));
    assert!(matches!(
        g.relit(&[("lamp", Vec3::splat(f32::NAN))]),
        Err(FormatError::NonFinite { .. })
    ));
    assert!(r.relight_into(&s[..1], &mut all).is_err());
    assert!(r.relight_into(&s, &mut all[..9]).is_err());
    assert!(r.relight_probe(5, &s, &mut one).is_err());
    assert!(r.relight_probe(0, &s, &mut one[..4]).is_err());
    // A file without groups relights to itself.
    let f = full_file();
    assert_eq!(f.relit(&[]).unwrap(), p(&f).coefficients);
}

#[test]
fn writer_refuses_inconsistent_groups() {
    let mut g = groups_file();
    pm(&mut g).groups[1].name = "lamp".into();
    assert!(matches!(
        g.to_bytes(),
        Err(FormatError::InvalidValue { element: 1, .. })
    ));
    let mut g = groups_file();
    pm(&mut g).groups[0].coefficients = Coefficients::from_f32(3, &[Vec3::ONE; 4 * 9]).unwrap();
    assert!(matches!(
        g.to_bytes(),
        Err(FormatError::CountMismatch {
            expected: 5,
            actual: 4,
            ..
        })
    ));
    let mut g = groups_file();
    pm(&mut g).groups[0].coefficients =
        Coefficients::from_f32(3, &[Vec3::splat(f32::INFINITY); 45]).unwrap();
    assert!(matches!(
        g.to_bytes(),
        Err(FormatError::NonFinite { element: 0, .. })
    ));
}
