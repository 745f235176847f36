//! Round trips through the `.probes` bytes: every section, every float
//! codec, determinism, alignment, and random contents (proptest).

mod common;

use common::*;
use glam::Vec3;
use probekit_runtime::format::layout::{HEADER_LEN, MAGIC};
use probekit_runtime::format::*;
use proptest::prelude::*;

#[test]
fn every_section_round_trips_exactly() {
    let f = full_file();
    let bytes = f.to_bytes().unwrap();
    let back = ProbeFile::from_bytes(&bytes).unwrap();
    assert_eq!(back, f);
    // Field by field, so a failure names the section.
    assert_eq!(p(&back).positions, p(&f).positions);
    assert_eq!(p(&back).coefficients, p(&f).coefficients);
    assert_eq!(p(&back).validity, p(&f).validity);
    assert_eq!(c(&back).tetrahedra, c(&f).tetrahedra);
    assert_eq!(c(&back).outer, c(&f).outer);
    assert_eq!(back.rigs(), f.rigs());
    assert_eq!(back.metadata(), f.metadata());
    // A uniform volume: grid and gradients.
    let g = grid_volume_file();
    let back = ProbeFile::from_bytes(&g.to_bytes().unwrap()).unwrap();
    assert_eq!(back, g);
    assert_eq!(grid(&back), grid(&g));
    assert_eq!(v(&back).gradients, v(&g).gradients);
    assert_eq!(back.rigs(), g.rigs());
}

#[test]
fn writing_is_deterministic_and_sections_are_aligned() {
    let a = full_file().to_bytes().unwrap();
    let b = full_file().clone().to_bytes().unwrap();
    assert_eq!(a, b);
    // Re-encoding what was read gives the same bytes (shards compare with cmp).
    let c = ProbeFile::from_bytes(&a).unwrap().to_bytes().unwrap();
    assert_eq!(a, c);
    assert_eq!(&a[..8], &MAGIC);
    let (_, sections) = read_sections(&a).unwrap();
    assert_eq!(sections.len(), 7);
    let mut end = HEADER_LEN + 32 * sections.len();
    for s in &sections {
        assert_eq!(s.offset % 16, 0, "{} misaligned", s.id);
        assert_eq!(s.offset as usize, end, "sections are back to back");
        end += s.bytes.len();
    }
    assert_eq!(end, a.len());
    let sizes = file_bytes_by_section(&a).unwrap();
    assert_eq!(sizes.values().sum::<u64>(), a.len() as u64);
    assert_eq!(sizes, full_file().bytes_by_section().unwrap());
    assert_eq!(sizes["positions"], 16 + 64, "5 × 12 bytes padded to 64");
}

#[test]
fn positions_are_readable_in_place_when_mapped_aligned() {
    // What an engine that maps the file does: cast the payload of an aligned
    // buffer without copying.
    let f = full_file();
    let bytes = f.to_bytes().unwrap();
    let mut aligned: Vec<u128> = vec![0; bytes.len().div_ceil(16)];
    let buf: &mut [u8] = bytemuck::cast_slice_mut(&mut aligned);
    buf[..bytes.len()].copy_from_slice(&bytes);
    let buf = &buf[..bytes.len()];
    let (_, sections) = read_sections(buf).unwrap();
    let pos = sections
        .iter()
        .find(|s| s.id == SectionId::POSITIONS)
        .unwrap();
    let floats: &[[f32; 3]] = bytemuck::cast_slice(&pos.bytes[16..16 + 5 * 12]);
    for (p, q) in floats.iter().zip(&p(&f).positions) {
        assert_eq!(Vec3::from_array(*p), *q);
    }
    // The reader takes unaligned buffers too (copies instead of casting).
    let mut shifted = vec![0u8; bytes.len() + 1];
    shifted[1..].copy_from_slice(&bytes);
    assert_eq!(ProbeFile::from_bytes(&shifted[1..]).unwrap(), f);
}

fn f16_coefficients(order: u32, coeffs: &[Vec3]) -> Coefficients {
    let mut data = Vec::new();
    for c in coeffs {
        for v in c.to_array() {
            data.extend_from_slice(&half::f16::from_f32(v).to_bits().to_le_bytes());
        }
    }
    Coefficients {
        codec: Codec::F16,
        order,
        data,
    }
}

#[test]
fn f32_is_exact_and_f16_within_half_precision_for_every_order() {
    let mut rng = Rng(3);
    for order in 1..=8u32 {
        let n = 7usize;
        let positions: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
        let coeffs: Vec<Vec3> = (0..n * (order * order) as usize)
            .map(|_| rng.vec3() * 100.0)
            .collect();
        let f = ProbeFile::cloud(positions.clone(), order, &coeffs).unwrap();
        let back = ProbeFile::from_bytes(&f.to_bytes().unwrap()).unwrap();
        assert_eq!(
            p(&back).coefficients.to_f32().unwrap(),
            coeffs,
            "f32 order {order}"
        );

        let mut g = f.clone();
        pm(&mut g).coefficients = f16_coefficients(order, &coeffs);
        let bytes = g.to_bytes().unwrap();
        let back = ProbeFile::from_bytes(&bytes).unwrap();
        assert_eq!(p(&back).coefficients.codec, Codec::F16);
        assert_eq!(p(&back).coefficients.stride(), 6 * (order * order) as usize);
        let decoded = p(&back).coefficients.to_f32().unwrap();
        for (d, c) in decoded.iter().zip(&coeffs) {
            for k in 0..3 {
                // Round to nearest: relative error ≤ 2⁻¹¹ for normal halves.
                let tol = c[k].abs() * (1.0 / 2048.0) + 1e-7;
                assert!(
                    (d[k] - c[k]).abs() <= tol,
                    "f16 order {order}: {} vs {}",
                    d[k],
                    c[k]
                );
            }
        }
        // Single-probe decoding without allocation agrees with the bulk form.
        let mut one = [Vec3::ZERO; 64];
        p(&back).coefficients.decode_probe(n - 1, &mut one).unwrap();
        let m = (order * order) as usize;
        assert_eq!(&one[..m], &decoded[(n - 1) * m..n * m]);
    }
}

#[test]
fn volume_and_rig_kinds_round_trip() {
    let mut rng = Rng(11);
    // Uniform volume: 3×2×2 grid.
    let positions: Vec<Vec3> = (0..12).map(|_| rng.vec3()).collect();
    let coeffs: Vec<Vec3> = (0..12 * 4).map(|_| rng.vec3()).collect();
    let v = ProbeFile::Volume(VolumeFile::new(
        ProbeSet::new(positions, Coefficients::from_f32(2, &coeffs).unwrap()),
        VolumeStructure::Uniform(VolumeGrid {
            min: Vec3::ZERO,
            max: Vec3::new(2.0, 1.0, 1.0),
            resolution: [3, 2, 2],
        }),
    ));
    assert_eq!(ProbeFile::from_bytes(&v.to_bytes().unwrap()).unwrap(), v);

    // Rig-only file: no probes, and only RIGS and META.
    let r = ProbeFile::Rigs(RigFile {
        rigs: full_file().rigs().to_vec(),
        metadata: full_file().metadata().into(),
    });
    let bytes = r.to_bytes().unwrap();
    let ids: Vec<SectionId> = read_sections(&bytes)
        .unwrap()
        .1
        .iter()
        .map(|s| s.id)
        .collect();
    assert_eq!(ids, [SectionId::RIGS, SectionId::METADATA]);
    let back = ProbeFile::from_bytes(&r.to_bytes().unwrap()).unwrap();
    assert_eq!(back, r);
    assert_eq!(back.rigs()[0].model.parameter_count(), Some(6));
}

#[test]
fn newer_minor_version_skips_unknown_sections() {
    let f = full_file();
    let bytes = f.to_bytes().unwrap();
    let (_, sections) = read_sections(&bytes).unwrap();
    let mut owned: Vec<(SectionId, Vec<u8>)> =
        sections.iter().map(|s| (s.id, s.bytes.to_vec())).collect();
    owned.insert(2, (SectionId::from_fourcc(*b"FUTR"), vec![0xAB; 32]));
    let newer = assemble_file(
        f.kind().id(),
        layout::VERSION_MINOR + 1,
        0x8000_0000,
        &owned,
    );
    assert_eq!(ProbeFile::from_bytes(&newer).unwrap(), f);
    let sizes = file_bytes_by_section(&newer).unwrap();
    assert_eq!(sizes["'FUTR'"], 32);
    // The same unknown section in a file of our own minor is refused.
    let same = assemble_file(f.kind().id(), layout::VERSION_MINOR, 0, &owned);
    assert!(matches!(
        ProbeFile::from_bytes(&same),
        Err(FormatError::UnknownSection(id)) if id == SectionId::from_fourcc(*b"FUTR")
    ));
}

/// Every 1.x file (and every layout of one: the sections inside are never
/// looked at) is refused with [`FormatError::OlderVersion`], whose message
/// tells the user to bake again; a newer major is `UnsupportedVersion`.
#[test]
fn files_of_format_1_are_refused_as_written_by_an_older_probekit() {
    let bytes = full_file().to_bytes().unwrap();
    assert_eq!(
        u16::from_le_bytes([bytes[8], bytes[9]]),
        layout::VERSION_MAJOR
    );
    assert_eq!(layout::VERSION_MAJOR, 2);
    assert_eq!(minor_of(&bytes), layout::VERSION_MINOR);
    for minor in [0u16, 1, 7, 11, 200] {
        let e = load_patched(&bytes, |b| {
            b[layout::header::MAJOR..][..2].copy_from_slice(&1u16.to_le_bytes());
            b[layout::header::MINOR..][..2].copy_from_slice(&minor.to_le_bytes());
        })
        .unwrap_err();
        assert!(
            matches!(e, FormatError::OlderVersion { major: 1, minor: m, supported: 2 } if m == minor),
            "{e:?}"
        );
        let msg = e.to_string();
        assert!(msg.contains("older probekit"), "{msg}");
        assert!(msg.contains("baked again"), "{msg}");
        assert!(msg.contains(&format!("1.{minor}")), "{msg}");
    }
    // Too short to hold sections, a 1.x header alone is still "older".
    let mut head = bytes[..HEADER_LEN].to_vec();
    head[8..10].copy_from_slice(&1u16.to_le_bytes());
    assert!(matches!(
        ProbeFile::from_bytes(&head),
        Err(FormatError::OlderVersion { .. })
    ));
    let e = load_patched(&bytes, |b| b[8..10].copy_from_slice(&3u16.to_le_bytes())).unwrap_err();
    assert!(
        matches!(e, FormatError::UnsupportedVersion { major: 3, .. }),
        "{e:?}"
    );
}

use probekit_runtime::format::layout;

fn finite() -> impl Strategy<Value = f32> {
    -1.0e6f32..1.0e6
}

fn vec3() -> impl Strategy<Value = Vec3> {
    (finite(), finite(), finite()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

prop_compose! {
    fn random_file()(n in 0usize..24, order in 1u32..5)
        (positions in prop::collection::vec(vec3(), n),
         coeffs in prop::collection::vec(vec3(), n * (order * order) as usize),
         validity in prop::option::of(prop::collection::vec((finite(), any::<u32>()), n)),
         grad_order in 1u32..4,
         with_grad in any::<bool>(),
         grads in prop::collection::vec(vec3(), n * 3 * 9),
         meta in "\\PC{0,40}",
         rig_samples in prop::collection::vec(vec3(), 0..6),
         lattice in 1u32..4,
         order in Just(order),
         n in Just(n))
        -> ProbeFile
    {
        let mut f = ProbeFile::cloud(positions, order, &coeffs).unwrap();
        pm(&mut f).validity = validity.map(|v| v.into_iter().map(|(value, flags)| Validity { value, flags }).collect());
        if with_grad && n > 0 {
            // A uniform volume of n × 1 × 1 samples with gradients.
            let per = 3 * (grad_order * grad_order) as usize;
            let mut v = VolumeFile::new(
                p(&f).clone(),
                VolumeStructure::Uniform(VolumeGrid {
                    min: Vec3::ZERO,
                    max: Vec3::ONE,
                    resolution: [n as u32, 1, 1],
                }),
            );
            v.gradients = Some(Gradients { order: grad_order, data: grads[..n * per].to_vec() });
            f = ProbeFile::Volume(v);
        } else if n >= 5 {
            cm(&mut f).tetrahedra = Some(TetSection {
                vertices: vec![[0, 1, 2, 3], [4, 1, 2, 3]],
                neighbours: vec![[1, u32::MAX, u32::MAX, u32::MAX], [0, u32::MAX, u32::MAX, u32::MAX]],
                barycentric: vec![[[0.5; 4]; 3], [[-0.25; 4]; 3]],
            });
        }
        let params = lattice * 2;
        *f.rigs_mut() = vec![Rig {
            name: meta.clone(),
            model: RigModel::Tensor([AxisModel::Lattice(lattice), AxisModel::Constant, AxisModel::Gradient]),
            order: 2,
            bbox_min: Vec3::ZERO,
            bbox_max: Vec3::ONE,
            bounding_radius: 0.0,
            fitting: (0..params as usize * rig_samples.len()).map(|i| i as f32 * 0.25).collect(),
            samples: rig_samples,
            transitions: vec![Transition { distance: 1.0, error: 2.0 }],
        }];
        *f.metadata_mut() = meta;
        f
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn random_contents_round_trip(f in random_file()) {
        let bytes = f.to_bytes().unwrap();
        prop_assert_eq!(bytes.len() % 16, 0);
        let back = ProbeFile::from_bytes(&bytes).unwrap();
        prop_assert_eq!(&back, &f);
        prop_assert_eq!(back.to_bytes().unwrap(), bytes);
    }
}
