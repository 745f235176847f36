//! The WGSL sources validate with naga, and `shaders/generated/` holds exactly
//! what the generator produces from them.

use probekit_shaders::layout::{
    BRICKS_HEADER, CLOUD_FLAG_CELLS, CLOUD_FLAG_PROBE_WEIGHTS, CLOUD_FLAG_VISIBILITY, CLOUD_HEADER,
    CLOUD_HEADER_WORDS, CLOUD_HULL, CLOUD_HULL_WORDS, CLOUD_NONE, CLOUD_TET_WORDS, LIGHT_CODES,
    RIG_CODES, RIG_HEADER, RIG_HEADER_WORDS, RIG_LIGHT_WORDS,
};
use probekit_shaders::{
    full_wgsl, generate, library_wgsl, validate_wgsl, PROBEKIT_BRICKS_WGSL, PROBEKIT_BUFFERS_WGSL,
    PROBEKIT_CLOUD_WGSL, PROBEKIT_LIGHTS_WGSL, PROBEKIT_RIG_WGSL, PROBEKIT_WGSL,
    REGENERATE_COMMAND,
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
    // … with the buffer access, with the cloud and the bricks, and the full
    // module with the check kernels.
    let lib_buffers = format!("{PROBEKIT_WGSL}\n{PROBEKIT_BUFFERS_WGSL}");
    validate_wgsl("probekit_buffers.wgsl", &lib_buffers).unwrap_or_else(|e| panic!("{e}"));
    let (library, _) =
        validate_wgsl("probekit library", &library_wgsl()).unwrap_or_else(|e| panic!("{e}"));
    for f in [
        "pk_volume_sample",
        "pk_volume_irradiance_zh3",
        "pk_cloud_weights",
        "pk_cloud_sh",
        "pk_cloud_irradiance",
        "pk_cloud_irradiance_zh3",
        "pk_cloud_sh_irradiance",
        "pk_cloud_sh_irradiance_zh3",
        "pk_cloud_light",
        "pk_cloud_light_occlusion",
        "pk_cloud_lights_irradiance",
        "pk_cloud_locate",
        "pk_bricks_sh_l2",
        "pk_bricks_irradiance",
        "pk_bricks_irradiance_zh3",
        "pk_sphere_table_lookup",
        "pk_light_unpack",
        "pk_light_irradiance",
        "pk_rig_weights",
        "pk_rig_sh",
        "pk_rig_model_irradiance",
        "pk_rig_irradiance",
    ] {
        assert!(
            library
                .functions
                .iter()
                .any(|(_, g)| g.name.as_deref() == Some(f)),
            "the library lacks {f}"
        );
    }
    assert!(library.entry_points.is_empty());
    // The light file needs only the pure library, the rig file those two.
    let lib_lights = format!("{PROBEKIT_WGSL}\n{PROBEKIT_LIGHTS_WGSL}");
    validate_wgsl("probekit_lights.wgsl", &lib_lights).unwrap_or_else(|e| panic!("{e}"));
    let lib_rig = format!("{lib_lights}\n{PROBEKIT_RIG_WGSL}");
    validate_wgsl("probekit_rig.wgsl", &lib_rig).unwrap_or_else(|e| panic!("{e}"));
    // The cloud file needs the pure library, the buffers and the lights.
    let lib_cloud = format!("{lib_buffers}\n{PROBEKIT_LIGHTS_WGSL}\n{PROBEKIT_CLOUD_WGSL}");
    validate_wgsl("probekit_cloud.wgsl", &lib_cloud).unwrap_or_else(|e| panic!("{e}"));
    let (full, _) =
        validate_wgsl("probekit_check.wgsl", &full_wgsl()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(full.entry_points.len(), 6);
}

/// The `u32` value of `const NAME: u32 = Vu;` in `source`.
fn wgsl_const(source: &str, name: &str) -> u32 {
    let prefix = format!("const {name}: u32 = ");
    let start = source
        .find(&prefix)
        .unwrap_or_else(|| panic!("no const {name}"))
        + prefix.len();
    let end = start + source[start..].find("u;").expect("a u32 literal");
    let text = &source[start..end];
    match text.strip_prefix("0x") {
        Some(hex) => u32::from_str_radix(hex, 16).unwrap(),
        None => text.parse().unwrap(),
    }
}

/// The buffer layouts the packers write are the ones the WGSL reads.
#[test]
fn layout_constants_agree_with_the_wgsl() {
    for (name, word) in CLOUD_HEADER {
        assert_eq!(wgsl_const(PROBEKIT_CLOUD_WGSL, name), word as u32, "{name}");
    }
    assert!(CLOUD_HEADER.iter().all(|&(_, w)| w < CLOUD_HEADER_WORDS));
    for (name, word) in BRICKS_HEADER {
        assert_eq!(
            wgsl_const(PROBEKIT_BRICKS_WGSL, name),
            word as u32,
            "{name}"
        );
    }
    for (name, value) in [
        ("PK_CLOUD_FLAG_VISIBILITY", CLOUD_FLAG_VISIBILITY),
        ("PK_CLOUD_FLAG_CELLS", CLOUD_FLAG_CELLS),
        ("PK_CLOUD_FLAG_PROBE_WEIGHTS", CLOUD_FLAG_PROBE_WEIGHTS),
        ("PK_CLOUD_HULL", CLOUD_HULL),
        ("PK_CLOUD_NONE", CLOUD_NONE),
        ("PK_CLOUD_TET_WORDS", CLOUD_TET_WORDS as u32),
        ("PK_CLOUD_HULL_WORDS", CLOUD_HULL_WORDS as u32),
    ] {
        assert_eq!(wgsl_const(PROBEKIT_CLOUD_WGSL, name), value, "{name}");
    }
    for (name, word) in RIG_HEADER {
        assert_eq!(wgsl_const(PROBEKIT_RIG_WGSL, name), word as u32, "{name}");
    }
    // The last header entry is a vec3 (the box's max corner).
    assert!(RIG_HEADER.iter().all(|&(_, w)| w + 3 <= RIG_HEADER_WORDS));
    // Rig codes in the rig file, light kinds in the light file.
    let lights_rig = format!("{PROBEKIT_LIGHTS_WGSL}\n{PROBEKIT_RIG_WGSL}");
    for (name, value) in RIG_CODES {
        assert_eq!(wgsl_const(&lights_rig, name), value, "{name}");
    }
    for (name, value) in LIGHT_CODES {
        assert_eq!(wgsl_const(PROBEKIT_LIGHTS_WGSL, name), value, "{name}");
        assert!(RIG_CODES.contains(&(name, value)), "{name}");
    }
    assert_eq!(
        wgsl_const(PROBEKIT_LIGHTS_WGSL, "PK_RIG_LIGHT_WORDS"),
        RIG_LIGHT_WORDS as u32
    );
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
            "pk_volume_sample",
            "pk_cloud_weights",
            "pk_cloud_locate",
            "pk_bricks_sh_l2",
            "pk_rig_irradiance",
            "pk_light_irradiance",
            "pk_cloud_lights_irradiance",
            "pk_sphere_table_lookup",
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
fn docs_examples_validate() {
    let docs = include_str!("../../../docs/shaders.md");
    let mut rest = docs;
    let mut examples = 0;
    while let Some(start) = rest.find("```wgsl\n") {
        let body = &rest[start + 8..];
        let len = body.find("```").expect("unterminated example");
        let example = &body[..len];
        let source = format!("{}\n{example}", library_wgsl());
        let (module, _) =
            validate_wgsl("docs/shaders.md example", &source).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(module.entry_points.len(), 1, "{example}");
        examples += 1;
        rest = &body[len + 3..];
    }
    assert!(
        examples >= 2,
        "docs/shaders.md has a volume and a rig example"
    );
}
