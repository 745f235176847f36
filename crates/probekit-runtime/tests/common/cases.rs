//! The broken-file corpus: each case named for what is wrong with it and
//! the error it must give (`tests/corpus.rs` writes and checks them).

use super::*;

/// Broken files, each named for what is wrong, with the error it must give.
/// `valid_full` is the one good file (it must load and equal [`full_file`]).
pub fn corpus_cases() -> Vec<(&'static str, Vec<u8>, Expect)> {
    let f = full_file();
    let good = f.to_bytes().unwrap();
    let entry_field = |k: usize, field: usize| HEADER_LEN + k * ENTRY_LEN + field;
    let mut v: Vec<(&'static str, Vec<u8>, Expect)> = vec![];
    v.push(("valid_full", good.clone(), |_| false));
    v.push(("empty_file", vec![], |e| {
        matches!(e, FormatError::Truncated { .. })
    }));
    v.push((
        "bad_magic",
        {
            let mut b = good.clone();
            b[0] = b'Q';
            b
        },
        |e| matches!(e, FormatError::BadMagic),
    ));
    v.push((
        "text_file",
        b"# not a probe file, just some text\n".to_vec(),
        |e| matches!(e, FormatError::BadMagic),
    ));
    v.push((
        "newer_major_version",
        patch_header(&good, |b| {
            b[header::MAJOR..header::MAJOR + 2].copy_from_slice(&3u16.to_le_bytes())
        }),
        |e| matches!(e, FormatError::UnsupportedVersion { major: 3, .. }),
    ));
    v.push((
        "older_major_version",
        patch_header(&good, |b| {
            b[header::MAJOR..header::MAJOR + 2].copy_from_slice(&1u16.to_le_bytes());
            b[header::MINOR..header::MINOR + 2].copy_from_slice(&11u16.to_le_bytes());
        }),
        |e| {
            matches!(
                e,
                FormatError::OlderVersion {
                    major: 1,
                    minor: 11,
                    ..
                }
            )
        },
    ));
    v.push(("truncated_header", good[..40].to_vec(), |e| {
        matches!(
            e,
            FormatError::Truncated {
                needed: 48,
                len: 40
            }
        )
    }));
    v.push(("truncated_table", good[..HEADER_LEN + 40].to_vec(), |e| {
        matches!(e, FormatError::Truncated { .. })
    }));
    v.push(
        ("truncated_section", good[..good.len() - 16].to_vec(), |e| {
            matches!(e, FormatError::Truncated { .. })
        }),
    );
    v.push((
        "trailing_bytes",
        {
            let mut b = good.clone();
            b.extend_from_slice(&[0; 16]);
            b
        },
        |e| matches!(e, FormatError::LengthMismatch { .. }),
    ));
    v.push((
        "header_checksum",
        {
            let mut b = good.clone();
            b[header::FLAGS] ^= 1;
            b
        },
        |e| matches!(e, FormatError::ChecksumMismatch { what, .. } if what == "header"),
    ));
    v.push((
        "section_checksum",
        {
            let mut b = good.clone();
            let (off, _) = find_section(&b, SectionId::POSITIONS);
            b[off + 20] ^= 0x40;
            b
        },
        |e| matches!(e, FormatError::ChecksumMismatch { what, .. } if what == "positions"),
    ));
    v.push((
        "section_out_of_bounds",
        patch_header(&good, |b| {
            let at = entry_field(1, entry::OFFSET);
            let off = b.len() as u64;
            b[at..at + 8].copy_from_slice(&off.to_le_bytes());
        }),
        |e| matches!(e, FormatError::SectionOutOfBounds { .. }),
    ));
    v.push((
        "section_length_overflow",
        patch_header(&good, |b| {
            let at = entry_field(1, entry::LENGTH);
            b[at..at + 8].copy_from_slice(&(!15u64).to_le_bytes());
        }),
        |e| matches!(e, FormatError::SectionOutOfBounds { .. }),
    ));
    v.push((
        "section_inside_table",
        patch_header(&good, |b| {
            let at = entry_field(0, entry::OFFSET);
            b[at..at + 8].copy_from_slice(&16u64.to_le_bytes());
        }),
        |e| matches!(e, FormatError::SectionOutOfBounds { .. }),
    ));
    v.push((
        "section_misaligned",
        patch_header(&good, |b| {
            let at = entry_field(1, entry::OFFSET);
            let off = u64::from_le_bytes(b[at..at + 8].try_into().unwrap()) + 4;
            b[at..at + 8].copy_from_slice(&off.to_le_bytes());
        }),
        |e| matches!(e, FormatError::SectionMisaligned { .. }),
    ));
    v.push((
        "sections_overlap",
        patch_header(&good, |b| {
            let off = entry_field(0, entry::OFFSET);
            let o0 = b[off..off + 8].to_vec();
            let at = entry_field(1, entry::OFFSET);
            b[at..at + 8].copy_from_slice(&o0);
        }),
        |e| matches!(e, FormatError::SectionOverlap { .. }),
    ));
    v.push((
        "duplicate_section",
        patch_header(&good, |b| {
            put_u32(b, entry_field(2, entry::ID), SectionId::POSITIONS.0)
        }),
        |e| matches!(e, FormatError::DuplicateSection(id) if *id == SectionId::POSITIONS),
    ));
    v.push((
        "unknown_section_same_minor",
        patch_header(&good, |b| {
            put_u32(
                b,
                entry_field(2, entry::ID),
                SectionId::from_fourcc(*b"XXXX").0,
            )
        }),
        |e| matches!(e, FormatError::UnknownSection(_)),
    ));
    v.push((
        "missing_positions",
        with_sections(&f, |s| s.retain(|(id, _)| *id != SectionId::POSITIONS)),
        |e| matches!(e, FormatError::MissingSection(id) if *id == SectionId::POSITIONS),
    ));
    let grid_volume = grid_volume_file();
    v.push((
        "volume_without_grid_or_octree",
        with_sections(&grid_volume, |s| s.retain(|(id, _)| *id != SectionId::GRID)),
        |e| matches!(e, FormatError::MissingSection(id) if *id == SectionId::GRID),
    ));
    v.push((
        "volume_with_tetrahedra",
        // The cloud relabelled a volume: its TETS has no place there.
        patch_header(&good, |b| put_u32(b, header::KIND, 1)),
        |e| {
            matches!(e, FormatError::MisplacedSection { id, kind: "volume" }
                if *id == SectionId::TETRAHEDRA)
        },
    ));
    v.push((
        "rigs_file_with_positions",
        // The cloud relabelled rigs: rigs files hold no probes.
        patch_header(&good, |b| put_u32(b, header::KIND, 2)),
        |e| {
            matches!(e, FormatError::MisplacedSection { id, kind: "rig" }
                if *id == SectionId::POSITIONS)
        },
    ));
    v.push((
        "cloud_with_grid",
        // The uniform volume relabelled a cloud.
        patch_header(&grid_volume.to_bytes().unwrap(), |b| {
            put_u32(b, header::KIND, 0)
        }),
        |e| {
            matches!(e, FormatError::MisplacedSection { id, kind: "cloud" }
                if *id == SectionId::GRID)
        },
    ));
    v.push((
        "unknown_kind",
        patch_header(&good, |b| put_u32(b, header::KIND, 7)),
        |e| matches!(e, FormatError::UnknownKind(7)),
    ));
    v.push((
        "positions_count_too_large",
        patch(&good, SectionId::POSITIONS, |s| put_u32(s, 0, 6)),
        |e| matches!(e, FormatError::SectionSize { id, .. } if *id == SectionId::POSITIONS),
    ));
    v.push((
        "positions_count_absurd",
        patch(&good, SectionId::POSITIONS, |s| put_u32(s, 0, u32::MAX)),
        |e| matches!(e, FormatError::SectionSize { id, .. } if *id == SectionId::POSITIONS),
    ));
    v.push(("section_shorter_than_its_header", with_sections(&f, |s| {
        s.iter_mut().find(|(id, _)| *id == SectionId::METADATA).unwrap().1 = vec![];
    }), |e| matches!(e, FormatError::SectionSize { id, expected: 16, .. } if *id == SectionId::METADATA)));
    v.push((
        "rig_counts_overflow",
        patch(&good, SectionId::RIGS, |s| {
            // First rig: a 65535 × 65535 × 1 lattice with u32::MAX samples.
            let r = 16;
            put_u32(s, r, 2);
            for a in 0..3 {
                put_u32(s, r + 4 + 4 * a, 2);
            }
            put_u32(s, r + 16, 65535);
            put_u32(s, r + 20, 65535);
            put_u32(s, r + 24, 1);
            put_u32(s, r + 32, u32::MAX);
            put_u32(s, r + 36, 65535 * 65535);
        }),
        |e| matches!(e, FormatError::CountOverflow(id) if *id == SectionId::RIGS),
    ));
    v.push((
        "rig_unknown_model",
        patch(&good, SectionId::RIGS, |s| put_u32(s, 16, 9)),
        |e| matches!(e, FormatError::InvalidValue { id, .. } if *id == SectionId::RIGS),
    ));
    v.push(("coefficients_fewer_than_positions", with_sections(&f, |s| {
        let c = s.iter_mut().find(|(id, _)| *id == SectionId::COEFFICIENTS).unwrap();
        let mut sec = SectionBuilder::new([0, 3, 4, 108]);
        sec.bytes(&c.1[16..16 + 4 * 108]);
        c.1 = sec.finish();
    }), |e| matches!(e, FormatError::CountMismatch { id, expected: 5, actual: 4 } if *id == SectionId::COEFFICIENTS)));
    v.push((
        "unknown_codec",
        patch(&good, SectionId::COEFFICIENTS, |s| put_u32(s, 0, 9)),
        |e| matches!(e, FormatError::UnknownCodec(9)),
    ));
    v.push((
        "codec_order_mismatch",
        patch(&good, SectionId::COEFFICIENTS, |s| put_u32(s, 0, 2)),
        |e| {
            matches!(
                e,
                FormatError::CodecOrderMismatch {
                    codec: "l1",
                    order: 3,
                    ..
                }
            )
        },
    ));
    v.push((
        "nan_position",
        patch(&good, SectionId::POSITIONS, |s| {
            s[16 + 12 * 3 + 4..16 + 12 * 3 + 8].copy_from_slice(&f32::NAN.to_le_bytes())
        }),
        |e| matches!(e, FormatError::NonFinite { id, element: 3 } if *id == SectionId::POSITIONS),
    ));
    v.push(("infinite_coefficient", patch(&good, SectionId::COEFFICIENTS, |s| {
        s[16 + 108 * 2 + 8..16 + 108 * 2 + 12].copy_from_slice(&f32::INFINITY.to_le_bytes())
    }), |e| matches!(e, FormatError::NonFinite { id, element: 2 } if *id == SectionId::COEFFICIENTS)));
    v.push((
        "nan_barycentric_matrix",
        patch(&good, SectionId::TETRAHEDRA, |s| {
            s[16 + 32 + 32 + 48 + 4..16 + 32 + 32 + 48 + 8].copy_from_slice(&f32::NAN.to_le_bytes())
        }),
        |e| matches!(e, FormatError::NonFinite { id, element: 1 } if *id == SectionId::TETRAHEDRA),
    ));
    v.push((
        "tet_vertex_out_of_range",
        patch(&good, SectionId::TETRAHEDRA, |s| put_u32(s, 16 + 16 + 8, 5)),
        |e| {
            matches!(
                e,
                FormatError::IndexOutOfRange {
                    value: 5,
                    limit: 5,
                    element: 1,
                    ..
                }
            )
        },
    ));
    v.push((
        "tet_neighbour_out_of_range",
        patch(&good, SectionId::TETRAHEDRA, |s| put_u32(s, 16 + 32 + 4, 2)),
        |e| {
            matches!(
                e,
                FormatError::IndexOutOfRange {
                    value: 2,
                    limit: 2,
                    element: 0,
                    ..
                }
            )
        },
    ));
    v.push((
        "tet_repeated_vertex",
        patch(&good, SectionId::TETRAHEDRA, |s| put_u32(s, 16 + 4, 0)),
        |e| matches!(e, FormatError::InvalidTopology { element: 0, .. }),
    ));
    v.push((
        "tet_neighbours_not_symmetric",
        patch(&good, SectionId::TETRAHEDRA, |s| {
            put_u32(s, 16 + 32 + 16, u32::MAX)
        }),
        |e| matches!(e, FormatError::InvalidTopology { element: 0, .. }),
    ));
    v.push((
        "hull_face_adjacent_out_of_range",
        patch(&good, SectionId::OUTER, |s| put_u32(s, 16 + 48, 4)),
        |e| {
            matches!(
                e,
                FormatError::IndexOutOfRange {
                    value: 4,
                    limit: 4,
                    ..
                }
            )
        },
    ));
    v.push(("grid_resolution_mismatch", {
        patch(&grid_volume.to_bytes().unwrap(), SectionId::GRID, |s| put_u32(s, 4, 2))
    }, |e| matches!(e, FormatError::CountMismatch { id, expected: 5, actual: 10 } if *id == SectionId::GRID)));
    let compact = compact_volume_file().to_bytes().unwrap();
    v.push((
        "octc_node_count_not_one_plus_eight_per_parent",
        patch(&compact, SectionId::OCTREE, |s| put_u32(s, 0, 10)),
        |e| matches!(e, FormatError::InvalidValue { id, .. } if *id == SectionId::OCTREE),
    ));
    v.push((
        "octree_inverted_box",
        // Root box min x 0 → 5, past its max.
        patch(&compact, SectionId::OCTREE, |s| {
            s[16..20].copy_from_slice(&5.0f32.to_le_bytes())
        }),
        |e| matches!(e, FormatError::InvalidValue { id, .. } if *id == SectionId::OCTREE),
    ));
    v.push((
        "octc_leaf_corner_without_probe",
        // Root box max x 1 → 2: the octants' corners leave the probe lattice.
        patch(&compact, SectionId::OCTREE, |s| {
            s[28..32].copy_from_slice(&2.0f32.to_le_bytes())
        }),
        |e| matches!(e, FormatError::InvalidTopology { id, .. } if *id == SectionId::OCTREE),
    ));
    v.push((
        "metadata_not_utf8",
        patch(&good, SectionId::METADATA, |s| s[16] = 0xFF),
        |e| matches!(e, FormatError::InvalidUtf8(id) if *id == SectionId::METADATA),
    ));
    v.push((
        "validity_count_mismatch",
        with_sections(&f, |s| {
            let c = s
                .iter_mut()
                .find(|(id, _)| *id == SectionId::VALIDITY)
                .unwrap();
            let mut sec = SectionBuilder::new([3, 0, 0, 0]);
            sec.bytes(&c.1[16..16 + 24]);
            c.1 = sec.finish();
        }),
        |e| matches!(e, FormatError::CountMismatch { id, .. } if *id == SectionId::VALIDITY),
    ));
    light_group_cases(&mut v);
    super::lights::runtime_light_cases(&mut v);
    v
}

/// Broken `LGRP` sections, around [`groups_file`].
fn light_group_cases(v: &mut Vec<(&'static str, Vec<u8>, Expect)>) {
    const LGRP: SectionId = SectionId::LIGHT_GROUPS;
    let g = groups_file();
    let good = g.to_bytes().unwrap();
    v.push(("valid_groups", good.clone(), |_| false));
    let lamp = p(&g).groups[0].coefficients.data.clone();
    let replace = |sec: Vec<u8>| {
        with_sections(&g, move |s| {
            s.iter_mut().find(|(id, _)| *id == LGRP).unwrap().1 = sec;
        })
    };
    // Record 1 ("sün") starts after the section header, record 0's header,
    // its padded name and its padded data.
    let rec1 = 16 + 16 + 16 + 544;
    v.push((
        "groups_nan_coefficient",
        patch(&good, LGRP, |s| {
            // f16 NaN in probe 3 of group 1.
            let at = rec1 + 16 + 16 + 3 * 54 + 10;
            s[at..at + 2].copy_from_slice(&0x7E00u16.to_le_bytes());
        }),
        |e| matches!(e, FormatError::NonFinite { id, element: 1 } if *id == SectionId::LIGHT_GROUPS),
    ));
    v.push((
        "groups_fewer_probes_than_positions",
        replace(lgrp_section(4, &[(0, 3, 108, b"lamp", &lamp[..4 * 108])])),
        |e| {
            matches!(e, FormatError::CountMismatch { id, expected: 5, actual: 4 }
                if *id == SectionId::LIGHT_GROUPS)
        },
    ));
    v.push((
        "groups_count_absurd",
        patch(&good, LGRP, |s| put_u32(s, 0, u32::MAX)),
        |e| matches!(e, FormatError::SectionSize { id, .. } if *id == SectionId::LIGHT_GROUPS),
    ));
    v.push((
        "groups_probe_count_absurd",
        patch(&good, LGRP, |s| put_u32(s, 4, u32::MAX)),
        |e| matches!(e, FormatError::SectionSize { id, .. } if *id == SectionId::LIGHT_GROUPS),
    ));
    v.push((
        "groups_name_length_absurd",
        patch(&good, LGRP, |s| put_u32(s, 16 + 12, u32::MAX)),
        |e| matches!(e, FormatError::SectionSize { id, .. } if *id == SectionId::LIGHT_GROUPS),
    ));
    v.push((
        "groups_name_not_utf8",
        patch(&good, LGRP, |s| s[32] = 0xFF),
        |e| matches!(e, FormatError::InvalidUtf8(id) if *id == SectionId::LIGHT_GROUPS),
    ));
    v.push((
        "groups_duplicate_name",
        replace(lgrp_section(
            5,
            &[(0, 3, 108, b"lamp", &lamp), (0, 3, 108, b"lamp", &lamp)],
        )),
        |e| {
            matches!(e, FormatError::InvalidValue { id, element: 1, .. }
                if *id == SectionId::LIGHT_GROUPS)
        },
    ));
    v.push((
        "groups_empty_name",
        replace(lgrp_section(5, &[(0, 3, 108, b"", &lamp)])),
        |e| {
            matches!(e, FormatError::InvalidValue { id, element: 0, .. }
                if *id == SectionId::LIGHT_GROUPS)
        },
    ));
    v.push((
        "groups_unknown_codec",
        patch(&good, LGRP, |s| put_u32(s, 16, 9)),
        |e| matches!(e, FormatError::UnknownCodec(9)),
    ));
    v.push((
        "groups_stride_mismatch",
        patch(&good, LGRP, |s| put_u32(s, 16 + 8, 54)),
        |e| {
            matches!(
                e,
                FormatError::CodecOrderMismatch {
                    codec: "f32",
                    order: 3,
                    stride: 54
                }
            )
        },
    ));
    v.push((
        "groups_order_differs_from_coefficients",
        replace(lgrp_section(5, &[(0, 2, 48, b"lamp", &lamp[..5 * 48])])),
        |e| {
            matches!(e, FormatError::InvalidValue { id, element: 0, .. }
                if *id == SectionId::LIGHT_GROUPS)
        },
    ));
    v.push((
        "groups_trailing_bytes",
        with_sections(&g, |s| {
            s.iter_mut()
                .find(|(id, _)| *id == LGRP)
                .unwrap()
                .1
                .extend([0; 16]);
        }),
        |e| matches!(e, FormatError::SectionSize { id, .. } if *id == SectionId::LIGHT_GROUPS),
    ));
    v.push((
        "groups_file_with_unknown_section",
        // A file of this reader's own minor: an unknown id is refused, not
        // skipped.
        with_sections(&g, |s| {
            s.push((SectionId::from_fourcc(*b"XXXX"), vec![0; 16]));
        }),
        |e| matches!(e, FormatError::UnknownSection(_)),
    ));
}
