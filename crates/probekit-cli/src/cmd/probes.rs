//! `probekit capture`, `reference`, `query` and `inspect`: one probe, ground
//! truth, and questions to a baked file.

use super::util::{load_probes, load_scene, parse_interp, parse_vec3, read_csv, rgb};
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use glam::Vec3;
use probekit::capture::{Baker, CaptureSettings, ReferenceSettings};
use probekit::query::Predictor;
use probekit_runtime::cloud::WalkState;
use std::path::PathBuf;

/// Arguments of `probekit capture`.
#[derive(Debug, Args)]
pub struct CaptureArgs {
    /// Scene file or `builtin:demo`.
    pub scene: String,
    /// The point `x,y,z` (metres).
    #[arg(long, allow_hyphen_values = true)]
    pub at: String,
    /// SH bands.
    #[arg(long)]
    pub order: Option<usize>,
    /// Receiver directions.
    #[arg(long)]
    pub samples: Option<u32>,
    /// Print JSON (the only output form).
    #[arg(long)]
    pub json: bool,
}

/// Runs `probekit capture`: `{"coefficients":[[r,g,b],...],"validity":{...}}`.
pub fn capture(a: &CaptureArgs) -> Result<()> {
    let scene = load_scene(&a.scene)?;
    let p = parse_vec3(&a.at, "--at")?;
    let mut s = CaptureSettings::from_scene(&scene);
    if let Some(o) = a.order {
        s.order = o;
    }
    if let Some(n) = a.samples {
        s.samples = n;
    }
    let baker = Baker::new(&scene).with_context(|| a.scene.clone())?;
    let r = baker.capture(p, 0, &s).with_context(|| a.scene.clone())?;
    let v = &r.validity;
    let coeffs: Vec<[f32; 3]> = r.sh.coeffs().iter().map(|&c| rgb(c)).collect();
    println!(
        "{}",
        serde_json::json!({
            "position": rgb(r.position),
            "coefficients": coeffs,
            "validity": {
                "backface_fraction": v.backface_fraction,
                "harmonic_mean_distance": v.harmonic_mean_distance,
                "nearest_distance": v.nearest_distance,
                "valid": v.valid,
                "offset": rgb(v.offset),
                "offset_applied": v.offset_applied,
            }
        })
    );
    Ok(())
}

/// Arguments of `probekit reference`.
#[derive(Debug, Args)]
pub struct ReferenceArgs {
    /// Scene file or `builtin:demo`.
    pub scene: String,
    /// CSV rows `x,y,z,nx,ny,nz`.
    #[arg(long)]
    pub points: PathBuf,
    /// Most samples per point (default: until 1 % precision, ≤ 262144).
    #[arg(long)]
    pub samples: Option<u32>,
    /// Print JSON (the only output form).
    #[arg(long)]
    pub json: bool,
}

/// Runs `probekit reference`: `{"irradiance":[[r,g,b],...]}` in row order.
pub fn reference(a: &ReferenceArgs) -> Result<()> {
    let scene = load_scene(&a.scene)?;
    let rows = read_csv(&a.points, 6)?;
    let mut s = ReferenceSettings::default();
    if let Some(n) = a.samples {
        if n == 0 {
            bail!("--samples 0: expected at least 1");
        }
        s.max_samples = n;
        s.min_samples = s.min_samples.min(n);
    }
    // Every row is checked before the first point is traced.
    if let Some(i) = rows
        .iter()
        .position(|r| Vec3::new(r[3], r[4], r[5]).length_squared() < 1e-12)
    {
        bail!("{}: row {}: zero normal", a.points.display(), i + 1);
    }
    let baker = Baker::new(&scene).with_context(|| a.scene.clone())?;
    let progress = crate::progress::Progress::new();
    let mut out = Vec::with_capacity(rows.len());
    for (i, r) in rows.iter().enumerate() {
        let p = Vec3::new(r[0], r[1], r[2]);
        let n = Vec3::new(r[3], r[4], r[5]).normalize();
        let e = baker
            .reference_irradiance(p, n, i as u64, &s)
            .with_context(|| format!("{}: row {}", a.points.display(), i + 1))?;
        out.push(rgb(e.irradiance));
        progress.update("ground truth", i + 1, rows.len());
    }
    progress.finish();
    println!("{}", serde_json::json!({ "irradiance": out }));
    Ok(())
}

/// Arguments of `probekit query`.
#[derive(Debug, Args)]
pub struct QueryArgs {
    /// A cloud or volume `.probes` file.
    pub probes: PathBuf,
    /// One point `x,y,z`.
    #[arg(long, allow_hyphen_values = true)]
    pub at: Option<String>,
    /// Its normal `x,y,z` (default `0,1,0`).
    #[arg(long, allow_hyphen_values = true)]
    pub normal: Option<String>,
    /// CSV rows `x,y,z,nx,ny,nz` instead of `--at`.
    #[arg(long)]
    pub points: Option<PathBuf>,
    /// Volumes: trilinear (default), taylor or tricubic (an error with a
    /// probe cloud, which interpolates by its tetrahedra).
    #[arg(long)]
    pub interp: Option<String>,
    /// Relight before querying: `NAME=s[,NAME=s...]` scales light group
    /// NAME (stored by `bake --groups`) by `s`, or by RGB `r:g:b`.
    #[arg(long)]
    pub group_scale: Vec<String>,
    /// Clouds: blend overrides for diagnosis.
    #[command(flatten)]
    pub blend: super::blend_args::BlendArgs,
    /// Print JSON (the only output form).
    #[arg(long)]
    pub json: bool,
}

/// Parses `--group-scale` values: `NAME=s` or `NAME=r:g:b`, comma-separated.
fn parse_group_scales(args: &[String]) -> Result<Vec<(String, Vec3)>> {
    let mut out = Vec::new();
    for item in args.iter().flat_map(|a| a.split(',')) {
        let bad = || anyhow!("--group-scale {item}: expected NAME=s or NAME=r:g:b");
        let (name, value) = item.split_once('=').ok_or_else(bad)?;
        let parts: Vec<f32> = value
            .split(':')
            .map(|v| v.trim().parse::<f32>().map_err(|_| bad()))
            .collect::<Result<_>>()?;
        let rgb = match parts[..] {
            [s] => Vec3::splat(s),
            [r, g, b] => Vec3::new(r, g, b),
            _ => return Err(bad()),
        };
        if name.trim().is_empty() || !rgb.is_finite() {
            return Err(bad());
        }
        out.push((name.trim().to_string(), rgb));
    }
    Ok(out)
}

/// Runs `probekit query`: `{"irradiance":[r,g,b]}` for `--at`, or
/// `{"irradiance":[[r,g,b],...]}` for `--points`. With `--group-scale` the
/// file's coefficients are relit (`ProbeFile::relit`): a cloud in place, as
/// an engine does, so it keeps the blend of its baked light.
pub fn query(a: &QueryArgs) -> Result<()> {
    let name = a.probes.display().to_string();
    let mut file = load_probes(&a.probes)?;
    let scales = parse_group_scales(&a.group_scale)?;
    let interp = parse_interp(&file, a.interp.as_deref()).with_context(|| name.clone())?;
    let mut relit = None;
    if !scales.is_empty() {
        if file.groups.is_empty() {
            bail!(
                "{name}: --group-scale needs a file baked with --groups (it has no light groups)"
            );
        }
        let named: Vec<(&str, Vec3)> = scales.iter().map(|(n, s)| (n.as_str(), *s)).collect();
        relit = Some(file.relit(&named).with_context(|| {
            let names: Vec<&str> = file.group_names().collect();
            format!("{name}: --group-scale (groups: {})", names.join(", "))
        })?);
    }
    // A volume loads the relit coefficients; a cloud (what `Predictor`
    // builds from a file with tetrahedra) is relit in place after loading.
    if file.tetrahedra.is_none() {
        if let Some(r) = relit.take() {
            file.coefficients = r;
        }
    }
    let mut probes = Predictor::from_file(&file, interp).with_context(|| name.clone())?;
    if let (Some(r), Predictor::Cloud(c)) = (relit, &mut probes) {
        let coeffs = r.to_f32().with_context(|| name.clone())?;
        let dst = c.coefficients_mut();
        if dst.len() != coeffs.len() {
            bail!("{name}: relit coefficients do not match the cloud's");
        }
        dst.copy_from_slice(&coeffs);
    }
    a.blend.apply(&mut probes).with_context(|| name.clone())?;
    let mut st = WalkState::new();
    match (&a.at, &a.points) {
        (Some(at), None) => {
            let p = parse_vec3(at, "--at")?;
            let n = parse_vec3(a.normal.as_deref().unwrap_or("0,1,0"), "--normal")?;
            if n.length_squared() < 1e-12 {
                bail!("--normal: zero vector");
            }
            let e = probes
                .irradiance(p, n.normalize(), &mut st)
                .with_context(|| name.clone())?;
            println!("{}", serde_json::json!({ "irradiance": rgb(e) }));
        }
        (None, Some(csv)) => {
            let rows = read_csv(csv, 6)?;
            let mut out = Vec::with_capacity(rows.len());
            for (i, r) in rows.iter().enumerate() {
                let n = Vec3::new(r[3], r[4], r[5]);
                if n.length_squared() < 1e-12 {
                    bail!("{}: row {}: zero normal", csv.display(), i + 1);
                }
                let e = probes
                    .irradiance(Vec3::new(r[0], r[1], r[2]), n.normalize(), &mut st)
                    .with_context(|| name.clone())?;
                out.push(rgb(e));
            }
            println!("{}", serde_json::json!({ "irradiance": out }));
        }
        _ => return Err(anyhow!("query needs exactly one of --at or --points")),
    }
    Ok(())
}

/// Arguments of `probekit inspect`.
#[derive(Debug, Args)]
pub struct InspectArgs {
    /// A `.probes` file.
    pub probes: PathBuf,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `probekit inspect`: a short summary for people, or with `--json`
/// the [`probekit::inspect::FileSummary`] as one JSON object.
pub fn inspect(a: &InspectArgs) -> Result<()> {
    let name = a.probes.display().to_string();
    let file = load_probes(&a.probes)?;
    let summary = probekit::inspect::summarize(&file).with_context(|| name.clone())?;
    if a.json {
        println!("{}", serde_json::to_string(&summary)?);
    } else {
        print!("{name}: {summary}");
    }
    Ok(())
}
