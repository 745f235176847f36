//! `probekit bake [SCENE] [--placement M] [--budget N] [--positions FILE.csv | --grid N | --cell SIZE]
//! [-o OUT.probes] [--samples N] [--bounces B] [--order N] [--seed S]
//! [--codec C] [--indirect-only] [--groups] [--shard I/N] [--json]` and
//! `probekit merge PART... -o OUT.probes`.
//!
//! A sharded bake writes a *part*: a cloud file without tetrahedra holding
//! the shard's captured positions, f32 SH and validity, whose `META` JSON is
//! `{"part":{"shard","shards","first_index","count","total"},"bake":<the
//! BakeMetadata of the whole bake>}`. `merge` checks the parts and builds the
//! same file as the unsharded bake, byte for byte. With `--groups` the part
//! also carries the light groups (`LGRP`, f32), which `merge` encodes in the
//! bake's codec like the main coefficients.
//!
//! `--groups` stores one radiance SH per light group next to the total, so an
//! engine can rescale groups at run time (`ProbeFile::relit`, `query
//! --group-scale`). With `--indirect-only` the groups are indirect-only too:
//! the stored total is the indirect light, and it equals the sum of the
//! stored groups (every emitter is in exactly one group, including
//! `"default"`, `"emissive"` and `"environment"`), so scaling a group rescales
//! its indirect light while the engine scales its direct light itself.

use super::util::{check_outputs, first_given, load_probes, load_scene, read_csv};
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use glam::Vec3;
use probekit::blend::blend_fit::BlendFitSettings;
use probekit::blend::cell_visibility::CellLattice;
use probekit::blend::visibility::VisibilitySettings;
use probekit::blend::visibility_bake::VisibilityBake;
use probekit::capture::{shard_range, BakeOutput, CaptureSettings};
use probekit::format::cloud::{cloud_file, decode_light_groups, file_validity, light_groups};
use probekit::format::settings::settings_json;
use probekit::format::{write_probe_file, BakeMetadata, Codec, Placement, ProbeFile, Validity};
use probekit::placement::LightShells;
use probekit::scene::Scene;
use probekit_sh::ShRgb;
use std::path::PathBuf;

/// Default receiver directions per probe on the command line (a scene's
/// `[bake] samples` or `--samples` override it).
pub const DEFAULT_SAMPLES: u32 = 1024;
/// Default approximate probe count of the grid placement.
pub const DEFAULT_GRID: usize = 256;
/// Default `--budget` of the adaptive and seed-003 placements.
pub const DEFAULT_BUDGET: usize = 256;
/// Default `--tolerance` of the adaptive placement.
pub const DEFAULT_TOLERANCE: f32 = 0.02;

/// The capture settings the flags ask for: the scene's, with `samples`
/// (else the scene's `[bake] samples`, else [`DEFAULT_SAMPLES`]), `bounces`
/// and `seed` applied where given.
pub fn capture_settings(
    scene: &Scene,
    samples: Option<u32>,
    bounces: Option<u32>,
    seed: Option<u64>,
) -> CaptureSettings {
    let mut s = CaptureSettings::from_scene(scene);
    s.samples = samples.or(scene.bake.samples).unwrap_or(DEFAULT_SAMPLES);
    if let Some(b) = bounces {
        s.bounces = b;
    }
    if let Some(seed) = seed {
        s.seed = seed;
    }
    s
}

/// Arguments of `probekit bake`.
#[derive(Debug, Args)]
pub struct BakeArgs {
    /// Scene file (`.toml`, `.gltf`, `.glb`, `.obj`) or `builtin:demo`.
    #[arg(default_value = "builtin:demo")]
    pub scene: String,
    /// `adaptive` (default: `--budget`, `--tolerance`), `grid` (default when
    /// `--grid` or `--cell` is given), `manual` (= `--positions`),
    /// `spawn-merge` or `gradient-ascent` (seed 003; `--budget` and the flags below).
    #[arg(long)]
    pub placement: Option<String>,
    /// Probe budget (default 256). Adaptive placement: a hard cap (the
    /// final leak and orphan-pocket probes included); spawn-merge: its cap
    /// before the final leak pass (which may add a tenth more, at least 4);
    /// gradient-ascent: its initial grid unless `--initial`; grid
    /// placement: the grid's approximate probe count, like `--grid`.
    #[arg(long)]
    pub budget: Option<usize>,
    /// Adaptive placement: stop when the relative RMSE estimated on the
    /// placement's own captured pool is below this (default 0.02).
    #[arg(long)]
    pub tolerance: Option<f32>,
    /// Adaptive placement: candidate shells around point, spot, sphere and
    /// disk lights (lower error near small bright lights, fewer probes
    /// elsewhere): `auto` (default: place both ways, keep the lower error at
    /// held-out points), `on` (also the bare flag) or `off`.
    #[arg(long, value_name = "WHEN", num_args = 0..=1, default_missing_value = "on")]
    pub light_shells: Option<String>,
    /// CSV of probe positions `x,y,z` (header optional).
    #[arg(long)]
    pub positions: Option<PathBuf>,
    /// Grid placement: approximate probe count over the bake box.
    #[arg(long)]
    pub grid: Option<usize>,
    /// Grid placement: cell size in metres (instead of `--grid`).
    #[arg(long)]
    pub cell: Option<f32>,
    /// Output probe file (a part file with `--shard`); default: named after
    /// the scene in the current folder (`builtin:demo` → `demo.probes`,
    /// `rooms/cornell_box.toml` → `cornell_box.probes`).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
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
    /// Also store one SH per light group (`group` key on lights) for
    /// run-time relighting; indirect-only with `--indirect-only`.
    #[arg(long)]
    pub groups: bool,
    /// Bake only shard I of N (`I/N`, I from 0) into a part file for `merge`.
    #[arg(long)]
    pub shard: Option<String>,
    /// Also write a picture of the result (`probekit render` with the
    /// automatic camera); the default demo bake writes `demo.png` beside
    /// `demo.probes`. Not with `--shard` (a part has no tetrahedra to
    /// light the picture with; render the merged file).
    #[arg(long, conflicts_with = "shard")]
    pub render: Option<PathBuf>,
    /// Texels per side of each probe's octahedral distance-moment map
    /// (`VISM`, visibility-aware blending at run time; 1..=64).
    #[arg(long, default_value_t = probekit::blend::visibility::DEFAULT_RESOLUTION)]
    pub visibility_res: u32,
    /// Lattice subdivision of the per-cell visibility bits (`CVSP`, 1..=8;
    /// 0: none; `auto`, the default: 4 to 8 from the cell size, the
    /// volume-weighted median of the tetrahedra's mean edge lengths over
    /// 0.25 m): each probe of a cell tests its view of (k+1)(k+2)(k+3)/6
    /// points of the cell.
    #[arg(long, default_value = "auto")]
    pub cell_visibility: String,
    /// Do not fit occluder planes (`CPLN`) to the cells one flat wall cuts
    /// (they make such cells' visibility exact up to the wall, where the
    /// lattice interpolates between its points).
    #[arg(long)]
    pub no_cell_planes: bool,
    /// Do not bake distance moments or cell visibility (the cloud blends
    /// without visibility; probe weights are still fitted unless
    /// `--no-probe-weights`). The visibility flags are refused with it.
    #[arg(long, conflicts_with_all = ["visibility_res", "cell_visibility", "no_cell_planes"])]
    pub no_visibility: bool,
    /// Do not fit per-probe blend weights (`PWGT`). The fit's flags and
    /// the two brightness exponents stored with the weights are refused
    /// with it.
    #[arg(long, conflicts_with_all = [
        "fit_points",
        "fit_samples",
        "fit_regularization",
        "fit_absolute_weight",
        "brightness_weight",
        "directional_brightness",
    ])]
    pub no_probe_weights: bool,
    /// Training points per probe of the probe weight fit.
    #[arg(long, default_value_t = probekit::blend::blend_fit::DEFAULT_POINTS_PER_PROBE)]
    pub fit_points: u32,
    /// Path-traced samples per training point of the probe weight fit.
    #[arg(long, default_value_t = probekit::blend::blend_fit::DEFAULT_FIT_SAMPLES)]
    pub fit_samples: u32,
    /// Regularization `ρ` of the probe weight fit (≥ 0; larger keeps the
    /// weights nearer 1).
    #[arg(long, default_value_t = probekit::blend::blend_fit::DEFAULT_REGULARIZATION)]
    pub fit_regularization: f32,
    /// Weight `β` of the absolute error beside the relative one in the
    /// probe weight fit (≥ 0; 0 fits relative error alone).
    #[arg(long, default_value_t = probekit::blend::blend_fit::DEFAULT_ABSOLUTE_WEIGHT)]
    pub fit_absolute_weight: f32,
    /// Brightness exponent α the cloud blends with and the probe weights
    /// are fitted for (0 to 4; 0: the plain blend, 1: harmonic mean of the
    /// probes' brightness), stored with the weights; `auto` (default): fit
    /// the weights for α = 0, 0.5 and 1 and keep the one that predicts
    /// held-out training points best without raising their absolute error
    /// by more than 1 % (`probekit::blend::blend_fit::fit_blend`).
    #[arg(long, default_value = "auto", value_name = "auto|A")]
    pub brightness_weight: String,
    /// Directional brightness exponent γ the cloud blends with on top of
    /// the fitted probe weights (0 to 4; 0: off), stored with them: per
    /// normal direction, a probe more than 3× brighter than its cell towards
    /// one side (a doorway seeing a lit corridor) counts less for the
    /// normals facing it. Not
    /// fitted for: a fixed bias against leaks
    /// (`probekit::blend::blend_fit::DEFAULT_DIRECTIONAL`).
    #[arg(long, default_value_t = probekit::blend::blend_fit::DEFAULT_DIRECTIONAL, value_name = "G")]
    pub directional_brightness: f32,
    /// Print a JSON summary.
    #[arg(long)]
    pub json: bool,
    /// Parameters of `--placement spawn-merge` and `gradient-ascent`.
    #[command(flatten)]
    pub seed003: Seed003Args,
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
    /// The scene the parts were baked from (file or `builtin:NAME`; default:
    /// the scene the parts recorded): needed when they were baked with cell
    /// visibility or probe weights, which depend on all probes and are
    /// baked here.
    #[arg(long)]
    pub scene: Option<String>,
}

/// Grid over `scene.bake_box()` sized by the library's one rule
/// ([`probekit::placement::grid_resolution`]): about `n` cells (or cells of
/// edge `cell`), at least 2 per axis.
fn grid_points(
    scene: &Scene,
    n: Option<usize>,
    cell: Option<f32>,
) -> Result<(Vec<Vec3>, [usize; 3])> {
    let b = scene.bake_box();
    let n = n.or(cell.is_none().then_some(DEFAULT_GRID));
    let ctx = || scene.source.display().to_string();
    let res = probekit::placement::grid_resolution(&b, cell, n).with_context(ctx)?;
    let pts = probekit::placement::grid_points(&b, cell, n).with_context(ctx)?;
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

/// The light groups that a bake stores (all light, or indirect only), in
/// the order of the names (sorted).
fn stored_groups(out: &BakeOutput, indirect_only: bool) -> Vec<(String, Vec<ShRgb>)> {
    if indirect_only {
        out.groups_indirect.clone()
    } else {
        out.groups.clone()
    }
}

/// The placement method `a` asks for: `--placement` if given, else
/// `manual` with `--positions`, `grid` with `--grid` or `--cell`, else
/// `adaptive`. Flags that the method would ignore are errors, so that a
/// user never gets a bake other than the one asked for (`--grid` beside
/// `--cell`, `--budget` beside either, or any of them with `--positions`;
/// `--grid` or `--cell` with a method other than `grid`; adaptive's and
/// seed 003's flags with another method).
fn placement_method(a: &BakeArgs) -> Result<&'static str> {
    let sized_grid = a.grid.is_some() || a.cell.is_some();
    let method = match (a.placement.as_deref(), &a.positions) {
        (Some("manual") | None, Some(_)) => "manual",
        (Some("manual"), None) => bail!("--placement manual needs --positions FILE.csv"),
        (None, None) if !sized_grid => "adaptive",
        (Some("grid") | None, None) => "grid",
        (Some(m @ ("grid" | "adaptive" | "spawn-merge" | "gradient-ascent")), Some(_)) => {
            bail!("--placement {m} and --positions exclude each other")
        }
        (Some("adaptive"), None) => "adaptive",
        (Some("spawn-merge"), None) => "spawn-merge",
        (Some("gradient-ascent"), None) => "gradient-ascent",
        (Some(o), _) => bail!(
            "--placement {o}: expected grid, manual, adaptive, spawn-merge or gradient-ascent"
        ),
    };
    match method {
        "grid" => {
            if a.grid.is_some() && a.cell.is_some() {
                bail!("--grid and --cell exclude each other (a probe count or a cell size)");
            }
            if a.budget.is_some() && sized_grid {
                bail!(
                    "--budget and --{} exclude each other: a grid placement takes one size",
                    if a.grid.is_some() { "grid" } else { "cell" }
                );
            }
        }
        "manual" => {
            if a.budget.is_some() || sized_grid {
                bail!(
                    "--positions places the probes given: --budget, --grid and --cell do not apply"
                );
            }
        }
        m => {
            if sized_grid {
                bail!(
                    "--{} sizes a grid placement, not --placement {m} (which takes --budget)",
                    if a.grid.is_some() { "grid" } else { "cell" }
                );
            }
        }
    }
    if method != "adaptive" {
        let adaptive_only = first_given([
            (a.tolerance.is_some(), "--tolerance"),
            (a.light_shells.is_some(), "--light-shells"),
        ]);
        if let Some(flag) = adaptive_only {
            bail!("{flag} applies to --placement adaptive, not {method}");
        }
    }
    if let Some((flag, methods)) = a.seed003.first_inapplicable(method) {
        bail!("{flag} applies to --placement {methods}, not {method}");
    }
    Ok(method)
}

/// Runs `probekit bake`.
pub fn run(a: &BakeArgs) -> Result<()> {
    let output = a
        .output
        .clone()
        .unwrap_or_else(|| super::util::output_named_after(&a.scene, "probes"));
    check_outputs(&[Some(&output), a.render.as_deref()])?;
    let progress = crate::progress::Progress::new();
    let scene = load_scene(&a.scene)?;
    let codec = Codec::from_name(&a.codec)
        .ok_or_else(|| anyhow!("--codec {}: expected f32, f16, l1, zh3 or l2", a.codec))?;
    let method = placement_method(a)?;
    let budget = a.budget.unwrap_or(DEFAULT_BUDGET);
    // The capture settings the user asked for (seed, bounces, order,
    // samples); placement captures with them too (at most
    // `PLACEMENT_SAMPLES` each), so `--seed` gives another placement.
    let mut placement_settings = capture_settings(&scene, a.samples, a.bounces, a.seed);
    if let Some(o) = a.order {
        placement_settings.order = o;
    }
    // One baker (and BVH) for placement, the probes and the blend data.
    let baker = probekit::capture::Baker::new(&scene).with_context(|| a.scene.clone())?;
    let (points, parameters) = if method == "spawn-merge" || method == "gradient-ascent" {
        a.seed003.place(
            &baker,
            &a.scene,
            method,
            budget,
            &placement_settings,
            &progress,
        )?
    } else if method == "adaptive" {
        let shells = a.light_shells.as_deref().unwrap_or("auto");
        let light_shells = LightShells::from_name(shells)
            .ok_or_else(|| anyhow!("--light-shells {shells}: expected off, on or auto"))?;
        let tolerance = a.tolerance.unwrap_or(DEFAULT_TOLERANCE);
        let placed = probekit::placement::place(
            &baker,
            scene.bake_box(),
            &probekit::placement::PlacementMethod::Adaptive {
                budget,
                tolerance,
                light_shells,
            },
            &placement_settings,
            &|phase, done, total| progress.update(&format!("placing: {phase}"), done, total),
        )
        .with_context(|| format!("{}: adaptive placement", a.scene))?;
        let n = placed.positions.len();
        (
            placed.positions,
            serde_json::json!({ "budget": budget, "tolerance": tolerance, "light_shells": placed.stats.light_shells, "light_shells_mode": light_shells.name(), "held_out_error": placed.stats.held_out_error, "count": n }),
        )
    } else if let Some(p) = &a.positions {
        let rows = read_csv(p, 3)?;
        let pts: Vec<Vec3> = rows.iter().map(|r| Vec3::new(r[0], r[1], r[2])).collect();
        // Refuse a set that spans no volume before capturing it, not after:
        // as given, then where the capture will put them (the virtual
        // offset moves probes out of geometry and sphere lights, and the
        // file is tetrahedralized at those positions).
        probekit::delaunay::tetrahedralize(&pts).with_context(|| {
            format!(
                "{}: the probe positions cannot be tetrahedralized",
                p.display()
            )
        })?;
        let captured = baker
            .capture_positions(&pts, 0, &placement_settings)
            .with_context(|| format!("{}: {}", a.scene, p.display()))?;
        probekit::delaunay::tetrahedralize(&captured).with_context(|| {
            format!(
                "{}: the probe positions cannot be tetrahedralized once the virtual offset has \
                 moved the probes in geometry or in sphere lights out of them",
                p.display()
            )
        })?;
        let n = pts.len();
        (pts, serde_json::json!({ "count": n }))
    } else {
        let count = a.grid.or(a.budget);
        let (pts, res) = grid_points(&scene, count, a.cell)?;
        let param = match a.cell {
            Some(c) => serde_json::json!({ "cell": c, "resolution": res }),
            None => {
                serde_json::json!({ "grid": count.unwrap_or(DEFAULT_GRID), "resolution": res })
            }
        };
        (pts, param)
    };
    let mut settings = placement_settings;
    settings.split_direct = a.indirect_only;
    settings.groups = a.groups;
    let mut sj = settings_json(&settings, codec);
    sj["indirect_only"] = serde_json::json!(a.indirect_only);
    // Distance moments for visibility-aware blending (a shard bakes its own
    // probes' maps; `merge` concatenates them).
    let bb = scene.bake_box();
    let vis = (!a.no_visibility).then(|| VisibilitySettings {
        resolution: a.visibility_res,
        ..VisibilitySettings::new(bb.size().length().max(1e-3), settings.seed)
    });
    sj["visibility"] = vis.map_or(serde_json::Value::Null, |v| v.to_json());
    let lattice =
        match a.cell_visibility.as_str() {
            "0" => None,
            k => Some(CellLattice::from_name(k).ok_or_else(|| {
                anyhow!("--cell-visibility {k}: expected auto, 0 (none) or 1 to 8")
            })?),
        };
    let cells = lattice.filter(|_| !a.no_visibility);
    sj["cell_visibility"] = cells.map_or(serde_json::Value::Null, CellLattice::to_json);
    let planes = cells.is_some() && !a.no_cell_planes;
    sj["cell_planes"] = serde_json::json!(planes);
    let weights = (!a.no_probe_weights).then_some(BlendFitSettings {
        points_per_probe: a.fit_points,
        samples: a.fit_samples,
        regularization: a.fit_regularization,
        absolute_weight: a.fit_absolute_weight,
        seed: settings.seed,
        brightness: match a.brightness_weight.as_str() {
            "auto" => None,
            s => {
                let v: f32 = s.parse().map_err(|_| {
                    anyhow!("--brightness-weight {s}: expected auto or a number 0 to 4")
                })?;
                super::util::check_brightness_weight(v)?;
                Some(v)
            }
        },
        directional: {
            super::util::check_directional_brightness(a.directional_brightness)?;
            a.directional_brightness
        },
    });
    if let Some(w) = &weights {
        if w.points_per_probe == 0 || w.samples == 0 {
            bail!("--fit-points and --fit-samples: expected at least 1");
        }
        if !(w.regularization >= 0.0 && w.regularization.is_finite()) {
            bail!(
                "--fit-regularization {}: expected a finite number ≥ 0",
                w.regularization
            );
        }
        if !(w.absolute_weight >= 0.0 && w.absolute_weight.is_finite()) {
            bail!(
                "--fit-absolute-weight {}: expected a finite number ≥ 0",
                w.absolute_weight
            );
        }
    }
    sj["probe_weights"] = weights.map_or(serde_json::Value::Null, |w| w.to_json());
    let meta = BakeMetadata::new(
        String::new(),
        Placement {
            method: method.into(),
            parameters,
        },
        sj,
    )
    .with_scene(&a.scene, &scene);
    let (shard, shards) = match &a.shard {
        Some(s) => parse_shard(s)?,
        None => (0, 1),
    };
    let range = shard_range(points.len(), shard, shards)?;
    let out = baker
        .bake_shard(&points, shard, shards, &settings, &|done, _| {
            progress.update("capture", done, range.len())
        })
        .with_context(|| a.scene.clone())?;
    let sh = stored_sh(&out, a.indirect_only);
    let groups = stored_groups(&out, a.indirect_only);
    let validity: Vec<Validity> = out.validity.iter().map(file_validity).collect();
    let invalid = out.validity.iter().filter(|v| !v.valid).count();
    let outname = output.display().to_string();
    let mut file = if a.shard.is_some() {
        let mut f = part_file(&out, &sh, validity, &meta, shard, shards, points.len())
            .with_context(|| outname.clone())?;
        f.groups = light_groups(&groups, out.settings.order, Codec::F32)
            .with_context(|| outname.clone())?;
        f
    } else {
        let mut f = cloud_file(&out.captured_positions, &sh, &validity, codec, &meta)
            .with_context(|| outname.clone())?;
        f.groups =
            light_groups(&groups, out.settings.order, codec).with_context(|| outname.clone())?;
        f
    };
    // Cell visibility and probe weights need every probe's tetrahedra: not
    // in shard parts (`merge --scene` bakes them).
    let whole = a.shard.is_none();
    let kinds = VisibilityBake {
        moments: vis,
        cell_subdivision: cells.filter(|_| whole),
        cell_planes: planes && whole,
        probe_weights: weights.filter(|_| whole),
    };
    if kinds != VisibilityBake::none() {
        probekit::eval::sweep::bake_blend_data(
            &baker,
            &kinds,
            &settings,
            &mut file,
            &progress.callback(),
        )
        .with_context(|| format!("{}: visibility data and probe weights", outname))?;
    }
    progress.finish();
    file.validate().with_context(|| outname.clone())?;
    write_probe_file(&output, &file).with_context(|| outname.clone())?;
    warn_unused_probes(&outname, &file);
    // README's first command, `probekit bake`, also draws its picture.
    let default_demo =
        a.scene == probekit::scene::BUILTIN_DEMO && a.output.is_none() && a.shard.is_none();
    let picture = a
        .render
        .clone()
        .or_else(|| default_demo.then(|| output.with_extension("png")));
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
                "groups": file.group_names().collect::<Vec<_>>(),
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

/// Tells on stderr which probes share a position with an earlier one: the
/// tetrahedralization merged them ([`probekit::delaunay::unused_probes`]), so
/// they are stored but no query reaches them.
fn warn_unused_probes(outname: &str, file: &ProbeFile) {
    let Some(t) = &file.tetrahedra else {
        return;
    };
    let unused = probekit::delaunay::unused_probes(file.positions.len(), &t.vertices);
    if let Some(&first) = unused.first() {
        let p = file.positions[first as usize];
        eprintln!(
            "warning: {outname}: {} probe(s) share a position with another and take no part in \
             the tetrahedra (first: probe {first} at {}, {}, {})",
            unused.len(),
            p.x,
            p.y,
            p.z
        );
    }
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
    check_outputs(&[Some(&a.output)])?;
    let progress = crate::progress::Progress::new();
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
            bail!(
                "{} and {}: baked from scenes of different lighting (hashes {} and {})",
                head.name,
                p.name,
                head.meta.scene_hash,
                p.meta.scene_hash
            );
        }
        // Nodes may name the same scene by different paths: the lighting
        // hash says it is the same; the rest must match.
        let same_settings = BakeMetadata {
            scene: head.meta.scene.clone(),
            ..p.meta.clone()
        } == head.meta;
        if !same_settings || p.total != head.total {
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
    // Distance moments: every part has them (same settings, as the equal
    // metadata says) or none does.
    let mut moments = head.file.visibility.clone().map(|mut v| {
        v.data.clear();
        v
    });
    let mut groups: Vec<(String, Vec<ShRgb>)> = Vec::new();
    for (k, p) in parts.iter().enumerate() {
        let g = decode_light_groups(&p.file).with_context(|| p.name.clone())?;
        if k == 0 {
            groups = g;
        } else if g.iter().map(|x| &x.0).ne(groups.iter().map(|x| &x.0)) {
            bail!("{} and {}: different light groups", head.name, p.name);
        } else {
            for ((_, dst), (_, src)) in groups.iter_mut().zip(g) {
                dst.extend(src);
            }
        }
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
        match (&mut moments, &p.file.visibility) {
            (None, None) => {}
            (Some(m), Some(v))
                if m.resolution == v.resolution && m.max_distance == v.max_distance =>
            {
                m.data.extend_from_slice(&v.data)
            }
            _ => bail!("{} and {}: different visibility maps", head.name, p.name),
        }
    }
    let out = a.output.display().to_string();
    let mut file =
        cloud_file(&positions, &sh, &validity, codec, &head.meta).with_context(|| out.clone())?;
    let order = head.file.coefficients.order as usize;
    file.groups = light_groups(&groups, order, codec).with_context(|| out.clone())?;
    file.visibility = moments;
    let cells = CellLattice::from_json(&head.meta.settings["cell_visibility"]);
    let weights = &head.meta.settings["probe_weights"];
    if cells.is_some() || weights.is_object() {
        // The scene given, else the one the parts recorded.
        let scene_name = match (&a.scene, head.meta.scene.is_empty()) {
            (Some(s), _) => s.clone(),
            (None, false) => head.meta.scene.clone(),
            (None, true) => bail!(
                "{}: baked with cell visibility or probe weights, which merge bakes over all \
                 probes, and the part records no scene: pass --scene",
                head.name
            ),
        };
        let scene = super::util::load_scene(&scene_name)?;
        probekit::format::check_scene_hash(
            &serde_json::to_string(&head.meta).unwrap_or_default(),
            &head.name,
            &scene.lighting_hash_hex(),
            &scene_name,
        )?;
        let scene_name = &scene_name;
        let baker = probekit::capture::Baker::new(&scene).with_context(|| scene_name.clone())?;
        if let Some(lattice) = cells {
            let cells = probekit::blend::cell_visibility::bake_file_cell_visibility(
                baker.tracer(),
                &file,
                lattice,
                &progress.phase("cell visibility"),
            )
            .with_context(|| out.clone())?;
            file.cell_visibility = Some(cells);
            if head.meta.settings["cell_planes"] == serde_json::json!(true) {
                file.cell_planes = probekit::blend::cell_planes::bake_file_cell_planes(
                    baker.tracer(),
                    &file,
                    &progress.phase("occluder planes"),
                )
                .with_context(|| out.clone())?;
            }
        }
        if weights.is_object() {
            // The parts' capture settings, as the bake recorded them.
            let (capture, _) = probekit::format::settings::settings_from_json(
                &head.meta.settings,
                &probekit::capture::CaptureSettings::from_scene(&scene),
            );
            let fit = BlendFitSettings::from_json(weights, &BlendFitSettings::new(capture.seed));
            let fitted = probekit::blend::blend_fit::fit_file_probe_weights(
                &baker,
                &file,
                &scene.bake_box(),
                &capture,
                &fit,
                &progress.phase("probe weights"),
            )
            .with_context(|| out.clone())?;
            file.probe_weights = Some(fitted.weights);
            file.brightness_exponent = fitted.brightness;
            file.directional_exponent = fitted.directional;
        }
    }
    file.validate().with_context(|| out.clone())?;
    write_probe_file(&a.output, &file).with_context(|| out.clone())?;
    println!(
        "{out}: {} probes from {} parts",
        positions.len(),
        parts.len()
    );
    Ok(())
}

/// Flags of seed 003's placements (`--placement spawn-merge|gradient-ascent`);
/// `--budget` sets their size (see [`Seed003Args::method`]).
#[derive(Debug, Args)]
pub struct Seed003Args {
    /// Spawn-merge / gradient-ascent: probes of the initial uniform grid
    /// (default: budget/2 for spawn-merge, budget for gradient-ascent).
    #[arg(long)]
    pub initial: Option<usize>,
    /// Spawn-merge: contrast threshold in (0, 1) (default 0.2).
    #[arg(long)]
    pub contrast: Option<f32>,
    /// Spawn-merge: SH sampling directions for the contrast, 6 or 26
    /// (default 26).
    #[arg(long)]
    pub directions: Option<u32>,
    /// Spawn-merge: merge similar pairs shorter than this (metres; default 1.05 cells).
    #[arg(long)]
    pub merge_distance: Option<f32>,
    /// Spawn-merge: spawn between contrasting pairs no longer than this (metres; default 2 cells).
    #[arg(long)]
    pub spawn_distance: Option<f32>,
    /// Spawn-merge: spawned probes at least this far from both ends (metres; default cell/4).
    #[arg(long)]
    pub min_distance: Option<f32>,
    /// Spawn-merge / gradient-ascent: most iterations (default 8).
    #[arg(long)]
    pub max_iterations: Option<u32>,
    /// Gradient-ascent: gradient field from indirect light only.
    #[arg(long)]
    pub gradient_indirect: bool,
    /// Gradient-ascent: initial step as a fraction of the grid cell
    /// (default 0.5).
    #[arg(long)]
    pub step: Option<f32>,
    /// Gradient-ascent: stop a probe once its step is below this fraction
    /// of the cell (default 0.05).
    #[arg(long)]
    pub min_step: Option<f32>,
    /// Gradient-ascent: k-means clusters replacing dark probes (default n/8).
    #[arg(long)]
    pub dark_clusters: Option<usize>,
}

impl Seed003Args {
    /// The first flag given that placement `method` does not read, with
    /// the placements that read it: each applies to spawn-merge,
    /// gradient-ascent or both, and to no other method.
    fn first_inapplicable(&self, method: &str) -> Option<(&'static str, &'static str)> {
        const SM: &str = "spawn-merge";
        const GA: &str = "gradient-ascent";
        const BOTH: &str = "spawn-merge and gradient-ascent";
        [
            (self.initial.is_some(), "--initial", BOTH),
            (self.contrast.is_some(), "--contrast", SM),
            (self.directions.is_some(), "--directions", SM),
            (self.merge_distance.is_some(), "--merge-distance", SM),
            (self.spawn_distance.is_some(), "--spawn-distance", SM),
            (self.min_distance.is_some(), "--min-distance", SM),
            (self.max_iterations.is_some(), "--max-iterations", BOTH),
            (self.gradient_indirect, "--gradient-indirect", GA),
            (self.step.is_some(), "--step", GA),
            (self.min_step.is_some(), "--min-step", GA),
            (self.dark_clusters.is_some(), "--dark-clusters", GA),
        ]
        .into_iter()
        .find_map(|(given, flag, methods)| {
            let applies = methods == method || (methods == BOTH && (method == SM || method == GA));
            (given && !applies).then_some((flag, methods))
        })
    }

    /// The placement method `name` (`spawn-merge` or `gradient-ascent`)
    /// with these flags; spawn-merge's probe limit is `budget`.
    pub fn method(
        &self,
        name: &str,
        budget: usize,
    ) -> Result<probekit::placement::PlacementMethod> {
        use probekit::placement::gradient_ascent::GradientAscentParams;
        use probekit::placement::spawn_merge::{Directions, SpawnMergeParams};
        use probekit::placement::PlacementMethod;
        Ok(match name {
            "spawn-merge" => PlacementMethod::SpawnMerge(SpawnMergeParams {
                initial: self.initial.unwrap_or(budget / 2),
                contrast: self.contrast.unwrap_or(0.2),
                merge_distance: self.merge_distance,
                spawn_distance: self.spawn_distance,
                min_distance: self.min_distance,
                directions: Directions::from_count(self.directions.unwrap_or(26))?,
                max_probes: budget,
                max_iterations: self.max_iterations.unwrap_or(8),
            }),
            _ => PlacementMethod::GradientAscent(GradientAscentParams {
                initial: self.initial.unwrap_or(budget),
                indirect_only: self.gradient_indirect,
                step: self.step.unwrap_or(0.5),
                min_step: self.min_step.unwrap_or(0.05),
                max_iterations: self.max_iterations.unwrap_or(8),
                dark_clusters: self.dark_clusters,
                ..Default::default()
            }),
        })
    }

    /// Places probes with `name` in the scene's bake box, capturing with
    /// `settings` (at most `PLACEMENT_SAMPLES` each); returns the positions
    /// and the placement parameters for the file's metadata (the method's
    /// parameters plus the probe `count`).
    pub fn place(
        &self,
        baker: &probekit::capture::Baker,
        scene_name: &str,
        name: &str,
        budget: usize,
        settings: &CaptureSettings,
        progress: &crate::progress::Progress,
    ) -> Result<(Vec<Vec3>, serde_json::Value)> {
        use probekit::placement::PlacementMethod;
        let method = self.method(name, budget)?;
        let scene = baker.scene();
        let placed = probekit::placement::place(
            baker,
            scene.bake_box(),
            &method,
            settings,
            &|phase, done, total| progress.update(&format!("placing: {phase}"), done, total),
        )
        .with_context(|| format!("{scene_name}: {name} placement"))?;
        let mut params = match &method {
            PlacementMethod::SpawnMerge(p) => p.to_json(&scene.bake_box()),
            PlacementMethod::GradientAscent(p) => p.to_json(),
            _ => serde_json::json!({}),
        };
        params["count"] = placed.positions.len().into();
        Ok((placed.positions, params))
    }
}
