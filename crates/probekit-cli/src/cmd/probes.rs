//! `probekit capture`, `reference`, `query` and `inspect`: one probe, ground
//! truth, and questions to a baked file.

use super::util::{load_probes, load_scene, parse_vec3, read_csv, rgb};
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use glam::Vec3;
use probekit::capture::{Baker, CaptureSettings, ReferenceSettings};
use probekit::query::QueryReport;
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
    /// Relight before querying: `NAME=s[,NAME=s...]` scales light group
    /// NAME (stored by `bake --groups`) by `s`, or by RGB `r:g:b`.
    #[arg(long)]
    pub group_scale: Vec<String>,
    /// Volumes: interpolation; clouds: blend overrides for diagnosis.
    #[command(flatten)]
    pub load: super::load_args::LoadArgs,
    /// Print JSON (the only output form).
    #[arg(long)]
    pub json: bool,
}

/// Runs `probekit query`: [`QueryReport`] as JSON, `{"irradiance":[r,g,b]}`
/// for `--at`, `{"irradiance":[[r,g,b],...]}` for `--points`. With
/// `--group-scale` the loaded probes are relit in place, as an engine
/// relights them (`Probes::relight`: a cloud keeps the blend of its baked
/// light).
pub fn query(a: &QueryArgs) -> Result<()> {
    let name = a.probes.display().to_string();
    let file = load_probes(&a.probes)?;
    let options = a.load.options(&a.group_scale)?;
    let probes = options.load(&file).with_context(|| name.clone())?;
    // A normal of zero length is refused with `zero`'s message.
    let unit = |n: Vec3, zero: &dyn Fn() -> String| {
        if n.length_squared() < 1e-12 {
            bail!("{}", zero());
        }
        Ok(n.normalize())
    };
    let report = match (&a.at, &a.points) {
        (Some(at), None) => {
            let p = parse_vec3(at, "--at")?;
            let n = parse_vec3(a.normal.as_deref().unwrap_or("0,1,0"), "--normal")?;
            QueryReport::one(&probes, p, unit(n, &|| "--normal: zero vector".into())?)
        }
        (None, Some(csv)) => {
            let rows = read_csv(csv, 6)?;
            let mut points = Vec::with_capacity(rows.len());
            for (i, r) in rows.iter().enumerate() {
                let row = || format!("{}: row {}: zero normal", csv.display(), i + 1);
                let n = unit(Vec3::new(r[3], r[4], r[5]), &row)?;
                points.push((Vec3::new(r[0], r[1], r[2]), n));
            }
            QueryReport::batch(&probes, &points)
        }
        _ => return Err(anyhow!("query needs exactly one of --at or --points")),
    };
    let report = report.with_context(|| name.clone())?;
    println!("{}", serde_json::to_value(&report)?);
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
