//! The corpus of broken files in `tests/corpus/`: each file is named for
//! what is wrong with it and must give its error variant (and never panic).
//! `valid_full.probes` is a good format 2.0 file that must keep loading
//! (and that the writer must keep writing byte for byte);
//! `valid_groups.probes` is the same with light groups (`LGRP`).
//!
//! Regenerate after a deliberate format change with
//! `PROBEKIT_REGEN_CORPUS=1 cargo test -p probekit-runtime --test corpus`.

mod common;

use common::*;
use probekit_runtime::format::*;
use std::path::PathBuf;

fn corpus_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/corpus")
}

#[test]
fn every_corpus_file_gives_its_error() {
    let dir = corpus_dir();
    if std::env::var_os("PROBEKIT_REGEN_CORPUS").is_some() {
        std::fs::create_dir_all(&dir).unwrap();
        for (name, bytes, _) in corpus_cases() {
            std::fs::write(dir.join(format!("{name}.probes")), bytes).unwrap();
        }
    }
    let cases = corpus_cases();
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_str().unwrap().to_string();
        let (_, generated, expect) = cases
            .iter()
            .find(|c| c.0 == name)
            .unwrap_or_else(|| panic!("corpus file {name} has no expected error"));
        let bytes = std::fs::read(&path).unwrap();
        let result = ProbeFile::from_bytes(&bytes);
        if name.starts_with("valid_") {
            let want = match name.as_str() {
                "valid_full" => full_file(),
                "valid_groups" => groups_file(),
                _ => with_runtime_lights(full_file()),
            };
            assert_eq!(
                result.unwrap(),
                want,
                "the reference file {name} no longer loads"
            );
            assert_eq!(
                &bytes, generated,
                "the writer's output changed: format drift"
            );
        } else {
            let err = result.expect_err(&name);
            assert!(expect(&err), "{name}: unexpected error {err:?}");
            // Messages are one line and name the problem.
            assert!(!err.to_string().contains('\n'));
        }
        seen += 1;
    }
    assert_eq!(seen, cases.len(), "every case has a committed file");
}

#[test]
fn generated_cases_match_expectations() {
    // The same checks on the in-memory cases, so a new case fails here
    // before its file is committed.
    for (name, bytes, expect) in corpus_cases() {
        match ProbeFile::from_bytes(&bytes) {
            Ok(f) => assert!(name.starts_with("valid_"), "{name} loaded: {:?}", f.kind()),
            Err(e) => assert!(expect(&e), "{name}: unexpected error {e:?}"),
        }
    }
}

#[test]
fn load_reports_missing_file_and_writer_refuses_invalid_contents() {
    let err = ProbeFile::load("/nonexistent/dir/x.probes").unwrap_err();
    assert!(matches!(err, FormatError::Io { .. }));
    assert!(err.to_string().contains("/nonexistent/dir/x.probes"));

    let mut f = full_file();
    cm(&mut f).tetrahedra.as_mut().unwrap().vertices[0][0] = 99;
    assert!(matches!(
        f.to_bytes(),
        Err(FormatError::IndexOutOfRange { value: 99, .. })
    ));

    let mut f = full_file();
    pm(&mut f).positions[0].x = f32::NAN;
    assert!(matches!(f.to_bytes(), Err(FormatError::NonFinite { .. })));

    let mut f = full_file();
    f.rigs_mut()[0].transitions.swap(0, 1);
    assert!(matches!(
        f.to_bytes(),
        Err(FormatError::InvalidValue { .. })
    ));

    assert!(matches!(
        Coefficients::from_f32(3, &[glam::Vec3::ZERO; 10]),
        Err(FormatError::Unrepresentable(_))
    ));
}
