//! The WGSL sources validate with naga, and `shaders/generated/` holds exactly
//! what the generator produces from them.

use probekit_shaders::{
    full_wgsl, generate, validate_wgsl, PROBEKIT_BUFFERS_WGSL, PROBEKIT_WGSL, REGENERATE_COMMAND,
};
use std::path::PathBuf;

#[test]
fn wgsl_validates_with_naga() {
    // The pure library on its own (no bindings, no entry point) …
    let (module, _) =
        validate_wgsl("probekit.wgsl", PROBEKIT_WGSL).unwrap_or_else(|e| panic!("{e}"));
    for f in [
        "pk_irradiance_l1",
        "pk_irradiance_l2",
        "pk_irradiance_geomerics_l1",
        "pk_irradiance_zh3",
        "pk_irradiance_zh3_hallucinated",
        "pk_irradiance_ambient_cube",
        "pk_blend_l2",
        "pk_volume_cell",
        "pk_decode_rgb9e5",
        "pk_decode_l1_window",
        "pk_decode_zh3_window",
        "pk_decode_l2_window",
    ] {
        assert!(
            module
                .functions
                .iter()
                .any(|(_, g)| g.name.as_deref() == Some(f)),
            "probekit.wgsl lacks {f}"
        );
    }
    assert!(module.entry_points.is_empty());
    // … with the buffer access, and the full module with the check kernel.
    let lib_buffers = format!("{PROBEKIT_WGSL}\n{PROBEKIT_BUFFERS_WGSL}");
    validate_wgsl("probekit_buffers.wgsl", &lib_buffers).unwrap_or_else(|e| panic!("{e}"));
    let (full, _) =
        validate_wgsl("probekit_check.wgsl", &full_wgsl()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(full.entry_points.len(), 1);
}

#[test]
fn generated_files_are_up_to_date() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shaders/generated");
    let files = generate().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(files.len(), 3);
    for f in &files {
        // Every back end emitted the library functions, not only the kernel.
        for name in [
            "pk_irradiance_geomerics_l1",
            "pk_volume_sh_l2",
            "pk_decode_zh3_window",
        ] {
            assert!(f.contents.contains(name), "{} lacks {name}", f.name);
        }
        let path = dir.join(f.name);
        // A checkout with CRLF line endings is still up to date.
        let committed = std::fs::read_to_string(&path)
            .unwrap_or_default()
            .replace("\r\n", "\n");
        assert!(
            committed == f.contents,
            "{} is out of date with shaders/*.wgsl; regenerate it with `{REGENERATE_COMMAND}` \
             and commit shaders/generated/",
            path.display()
        );
    }
    assert_eq!(
        generate().unwrap(),
        files,
        "generation is not deterministic"
    );
}

#[test]
fn docs_example_validates() {
    let docs = include_str!("../../../docs/shaders.md");
    let start = docs
        .find("```wgsl\n")
        .expect("docs/shaders.md has a ```wgsl example")
        + 8;
    let len = docs[start..].find("```").expect("unterminated example");
    let example = &docs[start..start + len];
    let source = format!("{PROBEKIT_WGSL}\n{PROBEKIT_BUFFERS_WGSL}\n{example}");
    let (module, _) =
        validate_wgsl("docs/shaders.md example", &source).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(module.entry_points.len(), 1);
}
