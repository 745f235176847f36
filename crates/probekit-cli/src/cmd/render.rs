//! `probekit render [SCENE] --probes PROBES -o OUT.png [--camera ...]
//! [--width W --height H] [--object spheres|MESH] [--show-probes]
//! [--samples N] [--json]`: the scene lit by the probes beside the same
//! path-traced, and the error (library: [`probekit::render`]).

use super::util::{load_probes, scene_for_file};
use anyhow::{bail, Context, Result};
use clap::Args;
use glam::Vec3;
use probekit::capture::CaptureSettings;
use probekit::format::ProbeFile;
use probekit::query::{check_exponent, QueryOptionError};
use probekit::render::{render, Camera, ObjectKind, RenderSettings, Rendered};
use probekit::scene::Scene;
use probekit_runtime::{BlendOverrides, ProbeFileKind};
use std::path::{Path, PathBuf};

/// Arguments of `probekit render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Scene file or `builtin:NAME` (default: the scene the probes were
    /// baked from, as the file records it).
    pub scene: Option<String>,
    /// The baked cloud or volume.
    #[arg(long)]
    pub probes: PathBuf,
    /// Output PNG.
    #[arg(short, long)]
    pub output: PathBuf,
    /// `EYE_X,EYE_Y,EYE_Z,TARGET_X,TARGET_Y,TARGET_Z[,FOV_DEG]` (default: automatic).
    #[arg(long, allow_hyphen_values = true)]
    pub camera: Option<String>,
    /// Width of each of the three panels, pixels.
    #[arg(long, default_value_t = 480)]
    pub width: u32,
    /// Height of each panel, pixels.
    #[arg(long, default_value_t = 320)]
    pub height: u32,
    /// Test object: `spheres` (3×2 grid) or a mesh file (OBJ, glTF, GLB).
    #[arg(long, default_value = "spheres")]
    pub object: String,
    /// Draw the probes as small spheres and a cloud's tetrahedra as lines.
    #[arg(long)]
    pub show_probes: bool,
    /// Most path samples per ground-truth point.
    #[arg(long, default_value_t = 1024)]
    pub samples: u32,
    /// Clouds: brightness exponent of the test object's blend, 0 to 4
    /// (default: the one stored with the file's probe weights, 0 without;
    /// as `query --blend brightness=A`).
    #[arg(long)]
    pub brightness_weight: Option<f32>,
    /// Clouds: directional brightness exponent of the test object's blend,
    /// 0 to 4 (default: the one stored with the file's probe weights, 0
    /// without; as `query --blend directional=G`).
    #[arg(long)]
    pub directional_brightness: Option<f32>,
    /// Use a scene whose lighting differs from the scene the probes were
    /// baked from (refused otherwise: the picture would compare the probes
    /// with another scene's light).
    #[arg(long)]
    pub allow_other_scene: bool,
    /// Print a JSON summary.
    #[arg(long)]
    pub json: bool,
}

/// Parses `--camera`.
fn parse_camera(s: &str) -> Result<Camera> {
    let v = match super::util::finite_list(s) {
        Some(v) if v.len() == 6 || v.len() == 7 => v,
        _ => bail!("--camera {s}: expected EYE_X,EYE_Y,EYE_Z,TARGET_X,TARGET_Y,TARGET_Z[,FOV_DEG]"),
    };
    let fov = v
        .get(6)
        .copied()
        .unwrap_or(probekit::render::camera::DEFAULT_FOV_DEGREES);
    Camera::new(
        Vec3::new(v[0], v[1], v[2]),
        Vec3::new(v[3], v[4], v[5]),
        fov,
    )
    .with_context(|| format!("--camera {s}"))
}

/// Bounces of the bake that wrote `file` (its metadata), else the scene's default.
fn bake_bounces(file: &ProbeFile, scene: &Scene) -> u32 {
    probekit::pipeline::recorded_capture(file)
        .map(|c| c.bounces)
        .unwrap_or_else(|| CaptureSettings::from_scene(scene).bounces)
}

/// Renders with a progress bar and writes the PNG; shared with `bake --render`.
pub fn render_to_png(
    scene: &Scene,
    file: &ProbeFile,
    settings: &RenderSettings,
    output: &Path,
    what: &str,
) -> Result<Rendered> {
    let progress = crate::progress::Progress::new();
    let r = render(scene, file, settings, &progress.phase("render"))
        .with_context(|| what.to_string())?;
    progress.finish();
    for w in &r.warnings {
        eprintln!("warning: {what}: {w}");
    }
    r.save_png(output)
        .with_context(|| output.display().to_string())?;
    Ok(r)
}

/// The settings `bake` uses for its picture of the probes it just wrote.
pub fn bake_settings(file: &ProbeFile, scene: &Scene) -> RenderSettings {
    RenderSettings {
        width: 480,
        height: 360,
        samples: 1024,
        bounces: bake_bounces(file, scene),
        ..RenderSettings::default()
    }
}

/// Runs `probekit render`.
pub fn run(a: &RenderArgs) -> Result<()> {
    super::util::check_outputs(&[Some(&a.output)])?;
    let mut blend = BlendOverrides::default();
    let exponent = |flag, x: Option<f32>| x.map(|x| check_exponent(flag, x)).transpose();
    blend.brightness_exponent = exponent("--brightness-weight", a.brightness_weight)?;
    blend.directional_exponent = exponent("--directional-brightness", a.directional_brightness)?;
    let file = load_probes(&a.probes)?;
    if file.kind() == ProbeFileKind::Volume {
        let flag = (a.brightness_weight.map(|_| "--brightness-weight"))
            .or(a.directional_brightness.map(|_| "--directional-brightness"));
        if let Some(flag) = flag {
            return Err(QueryOptionError::CloudOnly(flag.into()))
                .with_context(|| a.probes.display().to_string());
        }
    }
    let (scene, scene_name) =
        scene_for_file(&file, &a.probes, a.scene.as_deref(), a.allow_other_scene)?;
    let object = match a.object.as_str() {
        "spheres" => ObjectKind::default(),
        path => ObjectKind::Mesh(PathBuf::from(path)),
    };
    let settings = RenderSettings {
        width: a.width,
        height: a.height,
        camera: a.camera.as_deref().map(parse_camera).transpose()?,
        object,
        show_probes: a.show_probes,
        samples: a.samples,
        bounces: bake_bounces(&file, &scene),
        blend,
        ..RenderSettings::default()
    };
    let what = format!("{scene_name} with {}", a.probes.display());
    let r = render_to_png(&scene, &file, &settings, &a.output, &what)?;
    let out = a.output.display().to_string();
    if a.json {
        println!(
            "{}",
            serde_json::json!({
                "output": out,
                "width": r.image.width(),
                "height": r.image.height(),
                "object_pixels": r.object_pixels,
                "rel_rmse": r.rel_rmse,
                "max_rel_error": r.max_rel_error,
                "probes": r.probes,
            })
        );
    } else {
        println!(
            "{out}: {}x{} px, {} object pixels, rel. RMSE {:.1} %, max {:.0} %",
            r.image.width(),
            r.image.height(),
            r.object_pixels,
            100.0 * r.rel_rmse,
            100.0 * r.max_rel_error
        );
        for s in &r.spheres {
            println!(
                "  test sphere at {:.3},{:.3},{:.3} radius {:.3}",
                s.center.x, s.center.y, s.center.z, s.radius
            );
        }
    }
    Ok(())
}
