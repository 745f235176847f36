//! Helpers shared by the probe commands: CSV rows, `x,y,z` arguments,
//! loading scenes and probe files with one-line errors.

use anyhow::{anyhow, bail, Context, Result};
use glam::Vec3;
use probekit::format::ProbeFile;
use probekit::scene::Scene;
use std::path::Path;

/// Reads a CSV of `cols` finite numbers per row (header line optional,
/// blank lines and `#` comments skipped). Errors name the file and line.
pub fn read_csv(path: &Path, cols: usize) -> Result<Vec<Vec<f32>>> {
    let name = path.display();
    let text = std::fs::read_to_string(path).with_context(|| format!("{name}"))?;
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let parsed: Result<Vec<f32>, _> = fields.iter().map(|f| f.parse::<f32>()).collect();
        let row = match parsed {
            Ok(r) => r,
            Err(_) if rows.is_empty() && i == 0 => continue, // header
            Err(_) => bail!("{name}: line {}: expected {cols} numbers", i + 1),
        };
        if row.len() != cols {
            bail!(
                "{name}: line {}: expected {cols} numbers, found {}",
                i + 1,
                row.len()
            );
        }
        if row.iter().any(|v| !v.is_finite()) {
            bail!("{name}: line {}: NaN or infinite value", i + 1);
        }
        rows.push(row);
    }
    if rows.is_empty() {
        bail!("{name}: no rows");
    }
    Ok(rows)
}

/// Parses `x,y,z` (finite).
pub fn parse_vec3(s: &str, what: &str) -> Result<Vec3> {
    let v: Result<Vec<f32>, _> = s.split(',').map(|f| f.trim().parse::<f32>()).collect();
    match v {
        Ok(v) if v.len() == 3 && v.iter().all(|x| x.is_finite()) => Ok(Vec3::new(v[0], v[1], v[2])),
        _ => bail!("{what} {s}: expected three finite numbers x,y,z"),
    }
}

/// The default output file of a command run on `scene`: its name without
/// folder and extension (`builtin:NAME` → `NAME`), with `ext`, in the
/// current folder.
pub fn output_named_after(scene: &str, ext: &str) -> std::path::PathBuf {
    let stem = match scene.strip_prefix("builtin:") {
        Some(name) => name.to_string(),
        None => Path::new(scene)
            .file_stem()
            .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned()),
    };
    std::path::PathBuf::from(format!("{stem}.{ext}"))
}

/// Loads a scene (path or `builtin:demo`), printing its warnings to stderr.
pub fn load_scene(name: &str) -> Result<Scene> {
    let scene = Scene::load(name).with_context(|| name.to_string())?;
    for w in &scene.warnings {
        eprintln!("warning: {name}: {w}");
    }
    Ok(scene)
}

/// The scene to use with a probe file: `given` (`--scene`), else the scene
/// the file recorded when it was baked. Refuses one whose lighting hash
/// differs from the file's ([`probekit::format::check_scene`]) unless
/// `allow_other`, then only warns. Returns the scene and the name it was
/// loaded by.
pub fn scene_for_file(
    file: &ProbeFile,
    file_path: &Path,
    given: Option<&str>,
    allow_other: bool,
) -> Result<(Scene, String)> {
    let file_name = file_path.display().to_string();
    let name = match given {
        Some(g) => g.to_string(),
        None => probekit::format::recorded_scene(&file.metadata).ok_or_else(|| {
            anyhow!("{file_name}: the file records no scene it was baked from; give --scene")
        })?,
    };
    let scene = Scene::load(&name).with_context(|| match given {
        Some(_) => name.clone(),
        None => format!("{name} (the scene {file_name} was baked from; give --scene if it moved)"),
    })?;
    for w in &scene.warnings {
        eprintln!("warning: {name}: {w}");
    }
    if let Err(e) = probekit::format::check_scene(&file.metadata, &file_name, &scene, &name) {
        if !allow_other {
            return Err(e.into());
        }
        eprintln!("warning: {e}");
    }
    Ok((scene, name))
}

/// Checks, before a command's long work, that each of its output files
/// can be written ([`probekit::format::check_writable`]): a mistyped folder
/// then costs nothing rather than the bake. `None`s are skipped.
pub fn check_outputs(paths: &[Option<&Path>]) -> Result<()> {
    for p in paths.iter().flatten() {
        probekit::format::check_writable(p).with_context(|| p.display().to_string())?;
    }
    Ok(())
}

/// The first flag of `flags` (`(given, flag)`, in order) that was given on
/// the command line, if any: the one to name when a set of flags does not
/// apply.
pub fn first_given<'a>(flags: impl IntoIterator<Item = (bool, &'a str)>) -> Option<&'a str> {
    flags
        .into_iter()
        .find_map(|(given, flag)| given.then_some(flag))
}

/// The error for a flag of the cloud's blend given with a volume file.
pub fn cloud_flag_on_volume(flag: &str) -> anyhow::Error {
    anyhow!("{flag} applies to probe clouds; this file is an irradiance volume")
}

/// The error for a volume's `--interp` given with a probe cloud.
pub fn interp_on_cloud(interp: &str) -> anyhow::Error {
    anyhow!(
        "--interp {interp} applies to irradiance volumes; this file is a probe cloud (it \
         interpolates by its tetrahedra)"
    )
}

/// Loads a `.probes` file.
pub fn load_probes(path: &Path) -> Result<ProbeFile> {
    ProbeFile::load(path).with_context(|| path.display().to_string())
}

/// `[r, g, b]` for JSON.
pub fn rgb(v: Vec3) -> [f32; 3] {
    v.to_array()
}

/// `--interp` of volume files: `trilinear` (the default, `None`), `taylor`
/// or `tricubic`. A probe cloud (a file with tetrahedra) interpolates by its
/// tetrahedra, so `--interp` given with one is an error rather than ignored.
pub fn parse_interp(file: &ProbeFile, s: Option<&str>) -> Result<probekit_runtime::Interp> {
    use probekit_runtime::Interp;
    if let (Some(s), Some(_)) = (s, &file.tetrahedra) {
        return Err(interp_on_cloud(s));
    }
    Ok(match s.unwrap_or("trilinear") {
        "trilinear" => Interp::Trilinear,
        "taylor" => Interp::Taylor,
        "tricubic" => Interp::Tricubic,
        o => bail!("--interp {o}: expected trilinear, taylor or tricubic"),
    })
}

/// Query-time visibility settings of a probe cloud, shared by `query` and
/// `eval` (`#[command(flatten)]`).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct VisibilityArgs {
    /// Clouds: blend without any of the file's visibility weighting
    /// (distance moments and cell visibility).
    #[arg(long)]
    pub no_visibility: bool,
    /// Clouds: blend without the file's cell visibility (`CVSP`) weighting.
    #[arg(long)]
    pub no_cell_visibility: bool,
    /// Clouds: blend without the file's fitted probe weights (`PWGT`; they
    /// apply with or without `--no-visibility` otherwise).
    #[arg(long)]
    pub no_probe_weights: bool,
    /// Clouds: distance bias of the visibility test in metres (default
    /// 0.05): a point this much beyond the surface a probe sees still counts
    /// as seen.
    #[arg(long)]
    pub visibility_bias: Option<f32>,
    /// Clouds: exponent of the Chebyshev visibility (default 3, as DDGI;
    /// at most 16): higher drops partly hidden probes faster.
    #[arg(long)]
    pub visibility_sharpness: Option<u32>,
    /// Clouds: brightness exponent α, 0 to 4 (default: the one the file's
    /// probe weights were fitted with, 0 without them or with
    /// `--no-probe-weights`): each probe's weight is divided by its mean
    /// irradiance to the power α, so one bright probe does not light a dark
    /// cell (1: harmonic mean; fewer leaks, a low bias next to lights; see
    /// `ProbeCloud::set_brightness_weighting`).
    #[arg(long)]
    pub brightness_weight: Option<f32>,
    /// Clouds: directional brightness exponent γ, 0 to 4 (default: the one
    /// stored with the file's probe weights, 0 without them or with
    /// `--no-probe-weights`): per normal direction, the weight of a probe
    /// more than 3× brighter than its cell for that direction is divided by
    /// the excess to the power γ, so a probe bright only towards a doorway
    /// does not light the dark side of its cell (see
    /// `ProbeCloud::set_directional_brightness`).
    #[arg(long)]
    pub directional_brightness: Option<f32>,
}

/// Checks a `--brightness-weight` value: the range
/// `ProbeCloud::set_brightness_weighting` accepts (NaN refused), so a bad
/// value fails before any work, for volumes too.
pub fn check_brightness_weight(a: f32) -> Result<()> {
    check_exponent("--brightness-weight", a)
}

/// Checks a `--directional-brightness` value, as
/// [`check_brightness_weight`].
pub fn check_directional_brightness(g: f32) -> Result<()> {
    check_exponent("--directional-brightness", g)
}

/// Checks that `flag`'s value `x` lies in
/// `0..=`[`probekit_runtime::cloud::MAX_BRIGHTNESS_EXPONENT`].
fn check_exponent(flag: &str, x: f32) -> Result<()> {
    let max = probekit_runtime::cloud::MAX_BRIGHTNESS_EXPONENT;
    if !(0.0..=max).contains(&x) {
        bail!("{flag} {x}: expected 0 to {max}");
    }
    Ok(())
}

impl VisibilityArgs {
    /// Checks the values (a finite bias, a sharpness of at most 16,
    /// brightness exponents in 0..=4).
    fn check(&self) -> Result<()> {
        if let Some(b) = self.visibility_bias.filter(|b| !b.is_finite()) {
            bail!("--visibility-bias {b}: expected a finite distance in metres");
        }
        if let Some(k) = self.visibility_sharpness.filter(|&k| k > 16) {
            bail!("--visibility-sharpness {k}: expected 0 to 16");
        }
        if let Some(a) = self.brightness_weight {
            check_brightness_weight(a)?;
        }
        if let Some(g) = self.directional_brightness {
            check_directional_brightness(g)?;
        }
        Ok(())
    }

    /// The first of these flags given on the command line, if any.
    fn first_given(&self) -> Option<&'static str> {
        first_given([
            (self.no_visibility, "--no-visibility"),
            (self.no_cell_visibility, "--no-cell-visibility"),
            (self.no_probe_weights, "--no-probe-weights"),
            (self.visibility_bias.is_some(), "--visibility-bias"),
            (
                self.visibility_sharpness.is_some(),
                "--visibility-sharpness",
            ),
            (self.brightness_weight.is_some(), "--brightness-weight"),
            (
                self.directional_brightness.is_some(),
                "--directional-brightness",
            ),
        ])
    }

    /// Applies the settings to a cloud predictor, after [`Self::check`].
    /// They are the cloud's blend: given with a volume they are an error
    /// rather than ignored.
    pub fn apply(&self, p: &mut probekit::query::Predictor) -> Result<()> {
        self.check()?;
        if let (Some(flag), probekit::query::Predictor::Volume(..)) = (self.first_given(), &*p) {
            return Err(cloud_flag_on_volume(flag));
        }
        self.set(p);
        Ok(())
    }

    /// [`Self::apply`] without the check, for settings already checked.
    pub fn set(&self, p: &mut probekit::query::Predictor) {
        if let probekit::query::Predictor::Cloud(c) = p {
            c.set_visibility(!self.no_visibility);
            c.set_cell_visibility(!self.no_visibility && !self.no_cell_visibility);
            c.set_probe_weighting(!self.no_probe_weights);
            if let Some(b) = self.visibility_bias {
                c.set_visibility_bias(b);
            }
            if let Some(k) = self.visibility_sharpness {
                if let Some(m) = c.visibility_maps_mut() {
                    m.set_sharpness(k);
                }
            }
            // The file's exponent belongs to its fitted weights.
            let a = self
                .brightness_weight
                .or(self.no_probe_weights.then_some(0.0));
            if let Some(a) = a {
                let in_range = c.set_brightness_weighting(a).is_ok();
                debug_assert!(in_range, "checked by VisibilityArgs::check");
            }
            let g = self
                .directional_brightness
                .or(self.no_probe_weights.then_some(0.0));
            if let Some(g) = g {
                let in_range = c.set_directional_brightness(g).is_ok();
                debug_assert!(in_range, "checked by VisibilityArgs::check");
            }
        }
    }
}
