//! The page's shaders are naga's GLSL ES 3.00 translation of the project's
//! WGSL (`shaders/probekit.wgsl` followed by the page's entry points in
//! `crates/probekit-view/shaders/view.wgsl`). This test translates them
//! again and checks that the committed `assets/shaders.gen.js`, which the
//! page compiles, is exactly that output; with `PROBEKIT_VIEW_REGENERATE=1`
//! it writes the file instead. The browser test (`tests/browser.rs`) checks
//! that WebGL2 compiles and links every program of it.

use naga::back::glsl;
use naga::valid::{Capabilities, ValidationFlags, Validator};
use std::fmt::Write as _;
use std::path::PathBuf;

/// The shader library, as the engines' shaders use it.
const LIBRARY: &str = include_str!("../../../shaders/probekit.wgsl");
/// The page's entry points.
const PAGE: &str = include_str!("../shaders/view.wgsl");
/// The programs of the page: (name, vertex entry point, fragment entry point).
const PROGRAMS: [(&str, &str, &str); 4] = [
    ("scene", "pv_scene_vs", "pv_scene_fs"),
    ("probe", "pv_probe_vs", "pv_probe_fs"),
    ("object", "pv_object_vs", "pv_object_fs"),
    ("color", "pv_color_vs", "pv_color_fs"),
];
const REGENERATE: &str = "PROBEKIT_VIEW_REGENERATE=1 cargo test -p probekit-view --test glsl";

fn generated_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/shaders.gen.js")
}

/// Parses, validates, drops what the entry points do not reach (the
/// library's codecs use `ldexp`, which GLSL ES 3.00 lacks) and validates
/// again.
fn module() -> (naga::Module, naga::valid::ModuleInfo) {
    let source = format!("{LIBRARY}\n{PAGE}");
    let mut module = naga::front::wgsl::parse_str(&source)
        .unwrap_or_else(|e| panic!("WGSL: {}", e.emit_to_string(&source)));
    let mut validator = Validator::new(ValidationFlags::all(), Capabilities::empty());
    validator
        .validate(&module)
        .unwrap_or_else(|e| panic!("naga validation: {}", e.emit_to_string(&source)));
    naga::compact::compact(&mut module, naga::compact::KeepUnused::No);
    let info = validator
        .validate(&module)
        .unwrap_or_else(|e| panic!("naga validation after compaction: {e:?}"));
    (module, info)
}

/// One stage in GLSL ES 3.00 and its uniform blocks (name → binding).
/// Vertex inputs carry `layout(location = N)` with their WGSL locations.
fn translate(
    module: &naga::Module,
    info: &naga::valid::ModuleInfo,
    stage: naga::ShaderStage,
    entry: &str,
) -> (String, Vec<(String, u32)>) {
    let options = glsl::Options {
        version: glsl::Version::Embedded {
            version: 300,
            is_webgl: true,
        },
        // The page builds its matrices in OpenGL's clip convention.
        writer_flags: glsl::WriterFlags::empty(),
        ..Default::default()
    };
    let pipeline = glsl::PipelineOptions {
        shader_stage: stage,
        entry_point: entry.to_string(),
        multiview: None,
    };
    let mut text = String::new();
    let reflection = {
        let mut w = glsl::Writer::new(
            &mut text,
            module,
            info,
            &options,
            &pipeline,
            naga::proc::BoundsCheckPolicies::default(),
        )
        .unwrap_or_else(|e| panic!("{entry}: GLSL ES 3.00: {e}"));
        w.write()
            .unwrap_or_else(|e| panic!("{entry}: GLSL ES 3.00: {e}"))
    };
    let mut blocks: Vec<(String, u32)> = reflection
        .uniforms
        .iter()
        .map(|(&h, name)| {
            let binding = module.global_variables[h]
                .binding
                .as_ref()
                .map_or(u32::MAX, |b| b.binding);
            (name.clone(), binding)
        })
        .collect();
    blocks.sort();
    (text, blocks)
}

/// `assets/shaders.gen.js`: an ES module exporting `SHADERS`, one entry per
/// program with its entry points, two sources and uniform blocks.
fn generate() -> String {
    let (module, info) = module();
    let mut out = String::new();
    out.push_str(
        "// GLSL ES 3.00 of the page's programs: naga's translation of shaders/probekit.wgsl\n\
         // followed by crates/probekit-view/shaders/view.wgsl. Generated; do not edit.\n",
    );
    let _ = writeln!(out, "// Regenerate: {REGENERATE}");
    out.push_str("export const SHADERS = {\n");
    for (name, vs, fs) in PROGRAMS {
        let (vtext, vblocks) = translate(&module, &info, naga::ShaderStage::Vertex, vs);
        let (ftext, fblocks) = translate(&module, &info, naga::ShaderStage::Fragment, fs);
        let mut blocks = vblocks;
        blocks.extend(fblocks);
        let json = |pairs: &[(String, u32)]| {
            let items: Vec<String> = pairs
                .iter()
                .map(|(n, b)| format!("{}: {b}", serde_json::to_string(n).unwrap()))
                .collect();
            format!("{{ {} }}", items.join(", "))
        };
        let _ = writeln!(out, "  {name}: {{");
        let _ = writeln!(
            out,
            "    vertexEntry: {},",
            serde_json::to_string(vs).unwrap()
        );
        let _ = writeln!(
            out,
            "    fragmentEntry: {},",
            serde_json::to_string(fs).unwrap()
        );
        let _ = writeln!(
            out,
            "    vertex: {},",
            serde_json::to_string(&vtext).unwrap()
        );
        let _ = writeln!(
            out,
            "    fragment: {},",
            serde_json::to_string(&ftext).unwrap()
        );
        let _ = writeln!(out, "    uniformBlocks: {},", json(&blocks));
        out.push_str("  },\n");
    }
    out.push_str("};\n");
    out
}

#[test]
fn page_shaders_are_nagas_glsl_es_300_of_the_wgsl() {
    let text = generate();
    // What ES 3.00 and WebGL2 need, and what they lack.
    assert!(text.contains("#version 300 es"), "not GLSL ES 3.00");
    for missing in ["ldexp", "buffer ", "layout(binding"] {
        assert!(
            !text.contains(missing),
            "the page's GLSL uses {missing:?}, which GLSL ES 3.00 / WebGL2 lack"
        );
    }
    // The library's SH evaluation is what lights probes and object.
    assert!(text.contains("pk_irradiance_l2"));
    let path = generated_path();
    if std::env::var_os("PROBEKIT_VIEW_REGENERATE").is_some() {
        std::fs::write(&path, &text).unwrap();
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == text,
        "{} is not naga's output of the current WGSL; run `{REGENERATE}`",
        path.display()
    );
}
