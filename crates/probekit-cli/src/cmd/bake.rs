//! `probekit bake [SCENE] [--positions FILE.csv | --grid N | --cell SIZE]
//! [-o OUT.probes] [--samples N] [--bounces B] [--order N] [--seed S]
//! [--codec C] [--indirect-only] [--shard I/N] [--json]` and
//! `probekit merge PART... -o OUT.probes`.
//!
//! A sharded bake writes a *part*: a cloud file without tetrahedra holding
//! the shard's captured positions, f32 SH and validity, whose `META` JSON is
//! `{"part":{"shard","shards","first_index","count","total"},"bake":<the
//! BakeMetadata of the whole bake>}`. `merge` checks the parts and builds the
//! same file as the unsharded bake, byte for byte.

use super::util::{load_probes, load_scene, read_csv};
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use probekit::bake::{bake_shard, shard_range, BakeOutput, CaptureSettings};
use probekit::cloud::file::{cloud_file, file_validity, settings_json};
use probekit::format::{write_probe_file, BakeMetadata, Codec, Placement, ProbeFile, Validity};
use probekit::scene::Scene;
use probekit_sh::ShRgb;
use std::path::PathBuf;

/// Default receiver directions per probe on the command line (a scene's
/// `[bake] samples` or `--samples` override it).
pub const DEFAULT_SAMPLES: u32 = 1024;
/// Default approximate probe count of the grid placement.
pub const DEFAULT_GRID: usize = 256;

/// Arguments of `probekit bake`.
#[derive(Debug, Args)]
pub struct BakeArgs {
    /// Scene file (`.toml`, `.gltf`, `.glb`, `.obj`) or `builtin:demo`.
    #[arg(default_value = "builtin:demo")]
    pub scene: String,
    /// `grid` (default), `manual` (= `--positions`) or `adaptive` (`--budget`, `--tolerance`).
    #[arg(long)]
    pub placement: Option<String>,
    /// Adaptive placement: probe budget.
    #[arg(long, default_value_t = 256)]
    pub budget: usize,
    /// Adaptive placement: stop when the mean relative disagreement is below this.
    #[arg(long, default_value_t = 0.02)]
    pub tolerance: f32,
    /// CSV of probe positions `x,y,z` (header optional).
    #[arg(long)]
    pub positions: Option<PathBuf>,
    /// Grid placement: approximate probe count over the bake box.
    #[arg(long)]
    pub grid: Option<usize>,
    /// Grid placement: cell size in metres (instead of `--grid`).
    #[arg(long)]
    pub cell: Option<f32>,
    /// Output probe file (a part file with `--shard`).
    #[arg(short, long, default_value = "demo.probes")]
    pub output: PathBuf,
    /// Receiver directions per probe.
    #[arg(long)]
    pub samples: Option<u32>,
    /// Scattering events per path.
    #[arg(long)]
    pub bounces: Option<u32>,
    /// SH bands (2 = L1, 3 = L2).
    #[arg(long)]
    pub order: Option<usize>,
    /// Random seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Coefficient codec: f32, f16, l1, zh3 or l2.
    #[arg(long, default_value = "f32")]
    pub codec: String,
    /// Store only indirect light (direct light is added at run time).
    #[arg(long)]
    pub indirect_only: bool,
    /// Bake only shard I of N (`I/N`, I from 0) into a part file for `merge`.
    #[arg(long)]
    pub shard: Option<String>,
    /// Also write a picture of the result (`probekit render` with the
    /// automatic camera); the default demo bake writes `demo.png` beside
    /// `demo.probes`.
    #[arg(long)]
    pub render: Option<PathBuf>,
    /// Print a JSON summary.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `probekit merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Part files written by `bake --shard I/N`.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// Output probe file.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Grid over `scene.bake_box()`: cell centres of a grid with about `n`
/// cells (or cells of edge `cell`), at least 2 per axis.
fn grid_points(
    scene: &Scene,
    n: Option<usize>,
    cell: Option<f32>,
) -> Result<(Vec<Vec3>, [usize; 3])> {
    let b = scene.bake_box();
    let size = b.size();
    if !(size.is_finite() && size.min_element() > 0.0) {
        bail!("{}: the bake box is empty or flat", scene.source.display());
    }
    let cell = match (n, cell) {
        (_, Some(c)) if c.is_finite() && c > 0.0 => c,
        (_, Some(c)) => bail!("--cell {c}: expected a positive size"),
        (Some(0), None) => bail!("--grid 0: expected a positive probe count"),
        (n, None) => (size.x * size.y * size.z / n.unwrap_or(DEFAULT_GRID) as f32).cbrt(),
    };
    let res = size
        .to_array()
        .map(|s| ((s / cell).round() as usize).max(2));
    if res.iter().product::<usize>() > 5_000_000 {
        bail!("grid of {res:?} probes is too large");
    }
    let mut pts = Vec::new();
    for k in 0..res[2] {
        for j in 0..res[1] {
            for i in 0..res[0] {
                let t = Vec3::new(
                    (i as f32 + 0.5) / res[0] as f32,
                    (j as f32 + 0.5) / res[1] as f32,
                    (k as f32 + 0.5) / res[2] as f32,
                );
                pts.push(b.min + t * size);
            }
        }
    }
    Ok((pts, res))
}

/// Parses `I/N`.
fn parse_shard(s: &str) -> Result<(usize, usize)> {
    let bad = || anyhow!("--shard {s}: expected I/N with 0 ≤ I < N");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (i, n): (usize, usize) = (
        i.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if n == 0 || i >= n {
        return Err(bad());
    }
    Ok((i, n))
}

/// The SH that a bake stores (all light, or indirect only).
fn stored_sh(out: &BakeOutput, indirect_only: bool) -> Vec<ShRgb> {
    match (&out.indirect, indirect_only) {
        (Some(ind), true) => ind.clone(),
        _ => out.sh.clone(),
    }
}

/// Runs `probekit bake`.
pub fn run(a: &BakeArgs) -> Result<()> {
    let scene = load_scene(&a.scene)?;
    let codec = Codec::from_name(&a.codec)
        .ok_or_else(|| anyhow!("--codec {}: expected f32, f16, l1, zh3 or l2", a.codec))?;
    let method = match (a.placement.as_deref(), &a.positions) {
        (Some("manual") | None, Some(_)) => "manual",
        (Some("manual"), None) => bail!("--placement manual needs --positions FILE.csv"),
        (Some("grid") | None, None) => "grid",
        (Some("grid"), Some(_)) => bail!("--placement grid and --positions exclude each other"),
        (Some("adaptive"), None) => "adaptive",
        (Some("adaptive"), Some(_)) => {
            bail!("--placement adaptive and --positions exclude each other")
        }
        (Some(o), _) => bail!("--placement {o}: expected grid, manual or adaptive"),
    };
    let (points, parameters) = if method == "adaptive" {
        let baker = probekit::bake::Baker::new(&scene).with_context(|| a.scene.clone())?;
        let settings = CaptureSettings::from_scene(&scene);
        let pb = ProgressBar::new(a.budget as u64);
        let placed = probekit::placement::place(
            &baker,
            scene.bake_box(),
            &probekit::placement::PlacementMethod::Adaptive {
                budget: a.budget,
                tolerance: a.tolerance,
            },
            &settings,
            &|_, done, total| {
                pb.set_length(total as u64);
                pb.set_position(done as u64)
            },
        )
        .with_context(|| format!("{}: adaptive placement", a.scene))?;
        pb.finish_and_clear();
        let n = placed.positions.len();
        (
            placed.positions,
            serde_json::json!({ "budget": a.budget, "tolerance": a.tolerance, "count": n }),
        )
    } else if let Some(p) = &a.positions {
        let rows = read_csv(p, 3)?;
        let pts: Vec<Vec3> = rows.iter().map(|r| Vec3::new(r[0], r[1], r[2])).collect();
        let n = pts.len();
        (pts, serde_json::json!({ "count": n }))
    } else {
        let (pts, res) = grid_points(&scene, a.grid, a.cell)?;
        let param = match a.cell {
            Some(c) => serde_json::json!({ "cell": c, "resolution": res }),
            None => {
                serde_json::json!({ "grid": a.grid.unwrap_or(DEFAULT_GRID), "resolution": res })
            }
        };
        (pts, param)
    };
    let mut settings = CaptureSettings::from_scene(&scene);
    settings.samples = a.samples.or(scene.bake.samples).unwrap_or(DEFAULT_SAMPLES);
    if let Some(b) = a.bounces {
        settings.bounces = b;
    }
    if let Some(o) = a.order {
        settings.order = o;
    }
    if let Some(s) = a.seed {
        settings.seed = s;
    }
    settings.split_direct = a.indirect_only;
    let mut sj = settings_json(&settings, codec);
    sj["indirect_only"] = serde_json::json!(a.indirect_only);
    let meta = BakeMetadata::new(
        format!("{:016x}", scene.content_hash()),
        Placement {
            method: method.into(),
            parameters,
        },
        sj,
    );
    let (shard, shards) = match &a.shard {
        Some(s) => parse_shard(s)?,
        None => (0, 1),
    };
    let range = shard_range(points.len(), shard, shards)?;
    let pb = ProgressBar::new(range.len() as u64);
    pb.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} probes  {elapsed} elapsed, ETA {eta}")
            .expect("static template"),
    );
    let out = bake_shard(&scene, &points, shard, shards, &settings, &|done, _| {
        pb.set_position(done as u64)
    })
    .with_context(|| a.scene.clone())?;
    pb.finish_and_clear();
    let sh = stored_sh(&out, a.indirect_only);
    let validity: Vec<Validity> = out.validity.iter().map(file_validity).collect();
    let invalid = out.validity.iter().filter(|v| !v.valid).count();
    let outname = a.output.display().to_string();
    let file = if a.shard.is_some() {
        part_file(&out, &sh, validity, &meta, shard, shards, points.len())
            .with_context(|| outname.clone())?
    } else {
        cloud_file(&out.captured_positions, &sh, &validity, codec, &meta)
            .with_context(|| outname.clone())?
    };
    write_probe_file(&a.output, &file).with_context(|| outname.clone())?;
    let default_demo = a.scene == probekit::scene::BUILTIN_DEMO
        && a.output == std::path::Path::new("demo.probes")
        && a.shard.is_none();
    let picture = a
        .render
        .clone()
        .or_else(|| default_demo.then(|| a.output.with_extension("png")));
    if let Some(png) = &picture {
        let rs = super::render::bake_settings(&file, &scene);
        super::render::render_to_png(&scene, &file, &rs, png, &outname)?;
    }
    let bytes: u64 = file.bytes_by_section()?.values().sum();
    if a.json {
        println!(
            "{}",
            serde_json::json!({
                "output": outname,
                "probes": file.positions.len(),
                "tetrahedra": file.tetrahedra.as_ref().map_or(0, |t| t.vertices.len()),
                "invalid": invalid,
                "bytes": bytes,
                "shard": a.shard.as_ref().map(|_| serde_json::json!([shard, shards])),
            })
        );
    } else {
        println!(
            "{outname}: {} probes ({invalid} invalid), {bytes} bytes{}",
            file.positions.len(),
            if a.shard.is_some() {
                format!(", shard {shard}/{shards}")
            } else {
                String::new()
            }
        );
    }
    Ok(())
}

/// A shard's part file (see the module docs).
fn part_file(
    out: &BakeOutput,
    sh: &[ShRgb],
    validity: Vec<Validity>,
    meta: &BakeMetadata,
    shard: usize,
    shards: usize,
    total: usize,
) -> Result<ProbeFile> {
    let order = sh.first().map_or(out.settings.order, |s| s.order()) as u32;
    let flat: Vec<Vec3> = sh.iter().flat_map(|s| s.coeffs().iter().copied()).collect();
    let mut f = ProbeFile::cloud(out.captured_positions.clone(), order, &flat)?;
    f.validity = Some(validity);
    f.metadata = serde_json::json!({
        "part": {
            "shard": shard,
            "shards": shards,
            "first_index": out.first_index,
            "count": out.positions.len(),
            "total": total,
        },
        "bake": serde_json::to_value(meta)?,
    })
    .to_string();
    Ok(f)
}

/// Runs `probekit merge`.
pub fn merge(a: &MergeArgs) -> Result<()> {
    struct Part {
        name: String,
        first: usize,
        count: usize,
        total: usize,
        meta: BakeMetadata,
        file: ProbeFile,
    }
    let mut parts = Vec::new();
    for p in &a.parts {
        let name = p.display().to_string();
        let file = load_probes(p)?;
        let v: serde_json::Value = serde_json::from_str(&file.metadata)
            .map_err(|_| anyhow!("{name}: not a shard part (no part metadata)"))?;
        let field = |k: &str| v["part"][k].as_u64().map(|x| x as usize);
        let (Some(first), Some(count), Some(total)) =
            (field("first_index"), field("count"), field("total"))
        else {
            bail!("{name}: not a shard part (no part metadata)");
        };
        let meta: BakeMetadata = serde_json::from_value(v["bake"].clone())
            .map_err(|_| anyhow!("{name}: not a shard part (no bake metadata)"))?;
        if count != file.positions.len() {
            bail!(
                "{name}: part says {count} probes but holds {}",
                file.positions.len()
            );
        }
        parts.push(Part {
            name,
            first,
            count,
            total,
            meta,
            file,
        });
    }
    parts.sort_by_key(|p| p.first);
    let head = &parts[0];
    for p in &parts[1..] {
        if p.meta.scene_hash != head.meta.scene_hash {
            bail!("{} and {}: different scene hashes", head.name, p.name);
        }
        if p.meta != head.meta || p.total != head.total {
            bail!("{} and {}: different bake settings", head.name, p.name);
        }
    }
    let mut end = 0;
    for p in &parts {
        if p.first < end {
            bail!(
                "{}: overlaps the previous part (starts at probe {}, expected {end})",
                p.name,
                p.first
            );
        }
        if p.first > end {
            bail!(
                "{}: gap before this part (probes {end}..{} missing)",
                p.name,
                p.first
            );
        }
        end = p.first + p.count;
    }
    if end != head.total {
        bail!(
            "{}: gap after this part (probes {end}..{} missing)",
            parts[parts.len() - 1].name,
            head.total
        );
    }
    let codec = head.meta.settings["codec"]
        .as_str()
        .and_then(Codec::from_name)
        .ok_or_else(|| anyhow!("{}: bake metadata names no codec", head.name))?;
    let mut positions = Vec::new();
    let mut sh = Vec::new();
    let mut validity = Vec::new();
    for p in &parts {
        let c = p
            .file
            .coefficients
            .to_f32()
            .with_context(|| p.name.clone())?;
        let n = p.file.coefficients.coeffs_per_probe();
        positions.extend_from_slice(&p.file.positions);
        sh.extend(
            c.chunks(n)
                .map(|ch| ShRgb::from_coeffs(ch.to_vec()).expect("order² coefficients")),
        );
        validity.extend(p.file.validity.clone().unwrap_or_default());
    }
    let out = a.output.display().to_string();
    let file =
        cloud_file(&positions, &sh, &validity, codec, &head.meta).with_context(|| out.clone())?;
    write_probe_file(&a.output, &file).with_context(|| out.clone())?;
    println!(
        "{out}: {} probes from {} parts",
        positions.len(),
        parts.len()
    );
    Ok(())
}
