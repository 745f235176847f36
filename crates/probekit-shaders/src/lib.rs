//! # probekit-shaders — the WGSL shader library and its generated versions
//!
//! `shaders/probekit.wgsl` (pure functions), `shaders/probekit_buffers.wgsl`
//! (storage-buffer access: codecs, uniform volumes),
//! `shaders/probekit_lights.wgsl` (the exact irradiance of one light, shared
//! by rigs and clouds), `shaders/probekit_cloud.wgsl` (probe-cloud blending
//! and run-time lights), `shaders/probekit_bricks.wgsl` (octree volumes
//! from their brick atlas), `shaders/probekit_rig.wgsl` (irradiance rigs
//! with the analytic/rig split, per vertex) and
//! `shaders/probekit_check.wgsl` (a compute
//! kernel that calls every function) are the sources. This crate parses and
//! validates them with `naga` and translates them to HLSL, GLSL and MSL
//! ([`generate`]); the `gen-shaders` binary writes the results to
//! `shaders/generated/`, and a test checks that the committed files are up to
//! date. [`layout`] packs loaded files into the buffers the shaders read.
//! The library reproduces the Rust evaluations of `probekit-sh` and
//! `probekit-runtime`; the tests run it through `wgpu` and compare (see
//! `docs/shaders.md`).
//!
//! Conventions are those of `probekit-sh`: radiance SH in, irradiance not
//! divided by π out.

#![warn(missing_docs)]

pub mod layout;

use naga::back::{glsl, hlsl, msl};
use naga::valid::{Capabilities, ValidationFlags, Validator};
use std::fmt;

/// `shaders/probekit.wgsl`: structs and pure functions (no bindings).
pub const PROBEKIT_WGSL: &str = include_str!("../../../shaders/probekit.wgsl");
/// `shaders/probekit_buffers.wgsl`: storage-buffer bindings and the
/// functions that read them (codecs, a plain four-probe blend, uniform
/// volume sampling: trilinear, Taylor, tricubic).
pub const PROBEKIT_BUFFERS_WGSL: &str = include_str!("../../../shaders/probekit_buffers.wgsl");
/// `shaders/probekit_lights.wgsl`: the light record's decoder and the exact
/// irradiance of every light kind (`probekit_runtime::rig::Light::irradiance`
/// with the sphere table), from [`layout::pack_rig_light`] records and the
/// table of [`layout::pack_sphere_table`]; what rigs and clouds share.
pub const PROBEKIT_LIGHTS_WGSL: &str = include_str!("../../../shaders/probekit_lights.wgsl");
/// `shaders/probekit_cloud.wgsl`: probe-cloud blending as
/// `probekit_runtime::ProbeCloud` does it and the run-time lights' term of
/// `probekit_runtime::Probes::irradiance`, from the buffer of
/// [`layout::pack_cloud_with_lights`].
pub const PROBEKIT_CLOUD_WGSL: &str = include_str!("../../../shaders/probekit_cloud.wgsl");
/// `shaders/probekit_bricks.wgsl`: octree volumes sampled from the brick
/// atlas of `probekit export --format ktx2 --layout bricks`, from the
/// buffer of [`layout::pack_bricks`].
pub const PROBEKIT_BRICKS_WGSL: &str = include_str!("../../../shaders/probekit_bricks.wgsl");
/// `shaders/probekit_rig.wgsl`: the per-vertex half of an irradiance rig
/// with the analytic/rig split (`probekit_runtime::rig::SplitRig::irradiance`),
/// from the buffer of [`layout::pack_split_rig`]; its lights go through
/// [`PROBEKIT_LIGHTS_WGSL`].
pub const PROBEKIT_RIG_WGSL: &str = include_str!("../../../shaders/probekit_rig.wgsl");
/// `shaders/probekit_check.wgsl`: the reference compute kernel `pk_check`.
pub const PROBEKIT_CHECK_WGSL: &str = include_str!("../../../shaders/probekit_check.wgsl");

/// Name of the compute entry point of [`PROBEKIT_CHECK_WGSL`].
pub const CHECK_ENTRY_POINT: &str = "pk_check";
/// Floats read per test case by `pk_check` (`PK_CHECK_IN`).
pub const CHECK_IN_FLOATS: usize = 68;
/// Floats written per test case by `pk_check` (`PK_CHECK_OUT`).
pub const CHECK_OUT_FLOATS: usize = 168;

/// The command that regenerates `shaders/generated/` (printed by the
/// up-to-date test when it fails).
pub const REGENERATE_COMMAND: &str = "cargo run -p probekit-shaders --bin gen-shaders";

/// Error from parsing, validating or translating the shaders.
#[derive(Debug)]
pub enum ShaderError {
    /// WGSL parse error, rendered with source context.
    Parse(String),
    /// naga validation error, rendered with source context.
    Validate(String),
    /// A back end failed to translate the module.
    Translate {
        /// Which back end: "hlsl", "glsl" or "msl".
        backend: &'static str,
        /// The back end's message.
        message: String,
    },
}

impl fmt::Display for ShaderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ShaderError::Parse(m) => write!(f, "WGSL parse error: {m}"),
            ShaderError::Validate(m) => write!(f, "naga validation error: {m}"),
            ShaderError::Translate { backend, message } => {
                write!(f, "{backend} translation failed: {message}")
            }
        }
    }
}

impl std::error::Error for ShaderError {}

/// The library without the check kernel: pure functions, buffer access,
/// light evaluation, cloud and brick sampling, rigs, in that order (what an
/// engine concatenates in front of its own shader).
pub fn library_wgsl() -> String {
    [
        PROBEKIT_WGSL,
        PROBEKIT_BUFFERS_WGSL,
        PROBEKIT_LIGHTS_WGSL,
        PROBEKIT_CLOUD_WGSL,
        PROBEKIT_BRICKS_WGSL,
        PROBEKIT_RIG_WGSL,
    ]
    .join("\n")
}

/// The full WGSL module: [`library_wgsl`] and the check kernel (what `wgpu`
/// compiles in the tests and what the generator translates).
pub fn full_wgsl() -> String {
    [library_wgsl().as_str(), PROBEKIT_CHECK_WGSL].join("\n")
}

/// Parses and validates WGSL source with naga (all validation flags, default
/// capabilities); `name` labels errors.
pub fn validate_wgsl(
    name: &str,
    source: &str,
) -> Result<(naga::Module, naga::valid::ModuleInfo), ShaderError> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| ShaderError::Parse(e.emit_to_string_with_path(source, name)))?;
    let info = Validator::new(ValidationFlags::all(), Capabilities::empty())
        .validate(&module)
        .map_err(|e| ShaderError::Validate(e.emit_to_string_with_path(source, name)))?;
    Ok((module, info))
}

/// One generated file: its name under `shaders/generated/` and its text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GeneratedFile {
    /// File name, e.g. `probekit.hlsl`.
    pub name: &'static str,
    /// File contents.
    pub contents: String,
}

fn header(lang: &str, comment: &str) -> String {
    format!(
        "{comment} GENERATED by naga {} from shaders/probekit.wgsl + probekit_buffers.wgsl +\n\
         {comment} probekit_lights.wgsl + probekit_cloud.wgsl + probekit_bricks.wgsl +\n\
         {comment} probekit_rig.wgsl + probekit_check.wgsl ({lang}).\n\
         {comment} Do not edit: change the WGSL and run\n\
         {comment} `{REGENERATE_COMMAND}`. See docs/shaders.md.\n",
        naga_version(),
        comment = comment,
        lang = lang,
    )
}

/// The naga version the generated files are stamped with (the one this crate
/// is built against, as pinned in Cargo.lock).
fn naga_version() -> &'static str {
    "30"
}

/// Translates [`full_wgsl`] to HLSL (shader model 5.1), GLSL (desktop 450,
/// compute entry point `pk_check`) and MSL (2.1): the files of
/// `shaders/generated/`, in a fixed order. Deterministic.
pub fn generate() -> Result<Vec<GeneratedFile>, ShaderError> {
    let source = full_wgsl();
    let (module, info) = validate_wgsl("probekit.wgsl", &source)?;

    let mut hlsl_out = String::new();
    {
        let options = hlsl::Options {
            shader_model: hlsl::ShaderModel::V5_1,
            ..Default::default()
        };
        let pipeline = hlsl::PipelineOptions::default();
        let mut w = hlsl::Writer::new(&mut hlsl_out, &options, &pipeline);
        w.write(&module, &info, None)
            .map_err(|e| ShaderError::Translate {
                backend: "hlsl",
                message: e.to_string(),
            })?;
    }

    let mut glsl_out = String::new();
    {
        let options = glsl::Options {
            version: glsl::Version::Desktop(450),
            writer_flags: glsl::WriterFlags::empty(),
            ..Default::default()
        };
        let pipeline = glsl::PipelineOptions {
            shader_stage: naga::ShaderStage::Compute,
            entry_point: CHECK_ENTRY_POINT.to_string(),
            multiview: None,
        };
        let mut w = glsl::Writer::new(
            &mut glsl_out,
            &module,
            &info,
            &options,
            &pipeline,
            naga::proc::BoundsCheckPolicies::default(),
        )
        .map_err(|e| ShaderError::Translate {
            backend: "glsl",
            message: e.to_string(),
        })?;
        w.write().map_err(|e| ShaderError::Translate {
            backend: "glsl",
            message: e.to_string(),
        })?;
    }

    let msl_options = msl::Options {
        lang_version: (2, 1),
        ..Default::default()
    };
    let (msl_out, _) = msl::write_string(
        &module,
        &info,
        &msl_options,
        &msl::PipelineOptions::default(),
    )
    .map_err(|e| ShaderError::Translate {
        backend: "msl",
        message: e.to_string(),
    })?;

    Ok(vec![
        GeneratedFile {
            name: "probekit.hlsl",
            contents: header("HLSL, shader model 5.1", "//") + &hlsl_out,
        },
        GeneratedFile {
            name: "probekit.comp.glsl",
            contents: header("GLSL 450 compute", "//") + &glsl_out,
        },
        GeneratedFile {
            name: "probekit.metal",
            contents: header("MSL 2.1", "//") + &msl_out,
        },
    ])
}
