//! The placement target, measured: for each level N of `--budgets`, a
//! uniform grid of about `GF·N` cell centres over the bake box (`G` probes:
//! `probekit bake`'s grid, whose cells inside geometry the virtual offset
//! moves out) against `adaptive` with budget `⌊G / GF⌋`,
//! which places at most that many (the budget is a hard cap), so adaptive
//! never has more than `1/GF` of the grid's probes; on the same evaluation
//! points and the same cached ground truth.
//!
//! ```text
//! cargo run --release -p probekit --example placement_target -- [SCENE] \
//!     [--budgets 125,500,2000] [--grid-factor 4] [--points 400] [--samples 512] [--top] [--floor]
//!     [--light-shells off|on|auto] [--no-grid] [--no-adaptive] [--visibility [--cell-visibility auto|K] [--no-cell-planes] [--no-weights] [--fit-points N] [--fit-samples N]
//!     [--fit-regularization R] [--fit-absolute-weight B] [--brightness auto|A] [--directional G] [--normal-brightness A]]
//!     [--seeds 1,2,3] [--seed S] [--leaks-in REGION] [--dump DIR]
//!     [--near-lights N [--near-radius R] [--near-seed S]]
//! ```
//!
//! Every cloud is baked by the pipeline `probekit bake` runs
//! ([`probekit::pipeline::Bake`]: place, capture, assemble, blend data),
//! with the recipe of the scene's `[bake]` table and the flags below (the
//! placement `grid` or `adaptive`, `capture.samples = --samples`,
//! `capture.seed = --seed`, the `[blend]` of `--visibility`), and queried
//! through [`probekit_runtime::Probes`] as an engine would.
//!
//! `--near-lights N`: also N points in a ball of R metres (default 1) around
//! each positional light, and a `stratified=` figure: the same population
//! relative RMSE the uniform points estimate, with far less variance where
//! a few points next to small lamps decide it (`common::NearLights`). The
//! other figures stay those of the uniform points.
//!
//! `--dump DIR`: per cloud, `DIR/{grid|adaptive}_{probes}_s{seed}.csv` with
//! each evaluation point's position, squared error `|Ê − E|²` and squared
//! truth `|E|²` (the sums of `rel_rmse`), its weight and stratum, and the
//! blended and true irradiance averaged over the colour channels (`pe`,
//! `te`: which way the blend errs), in the evaluation's order, for a
//! paired bootstrap of two methods (`scripts/bootstrap_ratio.py`) and the
//! split by distance to the lamps (`scripts/error_by_distance.py`).
//!
//! `--seed`: the capture seed (`capture.seed`), which also seeds adaptive
//! placement (another seed, another placement of the same budget: its
//! spread shows how much of a difference between two placements is chance).
//!
//! `--seeds`: the evaluation points of several seeds pooled (default 1).
//!
//! `--light-shells`: adaptive's `placement.light_shells` (default `auto`,
//! as `probekit bake`);
//! `--no-grid`: evaluate the adaptive clouds only; `--no-adaptive`: the
//! grids only.
//!
//! `--floor`: first, the figures of a probe captured at every evaluation
//! point (at `--samples` and at 16× as many): SH truncation and capture noise
//! alone, the floor no placement at that sample count can go below.
//!
//! `--visibility`: every cloud (grid and adaptive alike) bakes the blend
//! data `probekit bake` stores by default — distance moments (`VISM`),
//! cell visibility (`CVSP`) and probe weights fitted with the default
//! settings (`PWGT`; `--no-weights`: none; `--fit-*` as `probekit bake`'s
//! `blend.fit.*`; `--cell-visibility` as `blend.cell_visibility`, default
//! `auto`; occluder planes `CPLN` unless `--no-cell-planes`) — and blends
//! as `probekit eval` does on such a file.
//! `--brightness A` (with `--visibility`; default 0 here): the brightness
//! exponent `blend.brightness_exponent` the weights are fitted for
//! (`probekit eval --brightness-weight A`); `auto`: the exponent the fit
//! chooses (`probekit bake`'s default), printed. With `--no-weights` the
//! blend still uses `A` (a load option, `BlendOverrides::brightness_exponent`).
//! `--directional G` (with `--visibility`; default 0 here, 0.5 in
//! `probekit bake`): and with directional brightness `G` on top of the
//! fitted weights (`blend.directional_exponent`).
//! `--normal-brightness A` (with `--visibility`; an experiment, not a
//! run-time feature): after the blend, each probe's weight is divided by
//! its own irradiance *for the point's normal* to the power `A` (luminance,
//! floored at 10⁻³ of the cell's brightest) and the probes' irradiances are
//! blended with the renormalized weights — a per-normal harmonic-style
//! blend, no longer one SH per point.
//!
//! `--leaks-in REGION` (with `--visibility`): the orphan pockets
//! (`placement::orphan_points`) of each cloud, then every leak in the named
//! region (any name not in the scene: all leaks) with its cell's four
//! probes: blend weight, fitted weight, irradiance for the point's normal,
//! and whether a segment test reaches them from the point.
//!
//! SCENE defaults to `builtin:demo`. Ground truth is cached in the system
//! temporary directory, keyed by scene hash and the points. Prints one line
//! per cloud with `rel_rmse`, `p95_rel_error`, leaks, `through=K` (with
//! `--visibility`: leaks through geometry, `probekit eval`'s
//! `leaks_through_geometry`), `outside=K` (with `--visibility`: leaks
//! beyond the probes' hull, `leaks_outside_hull`), `unlit=K` (leaks at points of zero truth,
//! sealed voids: `leaks_unlit`) and per-region `rel_rmse/leaks+through` (the
//! `probekit eval` figures).

use glam::Vec3;
use probekit::capture::Baker;
use probekit::eval::{
    is_leak, leaks_at, metrics, region_leaks_at, region_metrics, unlit_points, worst_points,
};
use probekit::format::ProbeFile;
use probekit::pipeline::{Bake, Placed};
use probekit::placement::{orphan_points, PROBE_CLEARANCE};
use probekit::progress::Clock;
use probekit::query::{blends_hidden_probes, outside_hull};
use probekit::recipe::{
    Blend, CellVisibility, Exponent, LightShellsName, Placement, Recipe, RecipeLayers,
};
use probekit::scene::Scene;
use probekit::trace::free_space::{segment_clear, EvalPoint};
use probekit_runtime::{LoadOptions, ObjectState, Probes};
use std::error::Error;
use toml::Value;

mod common;
use common::{arg, eval_seeds, EvalSet, NearLights};

/// No progress output.
fn quiet(_: &str, _: usize, _: usize) {}

/// The command line (see the module docs).
struct Options {
    scene: String,
    points: usize,
    samples: u32,
    grid_factor: usize,
    budgets: Vec<usize>,
    seeds: String,
    seed: Option<u64>,
    top: bool,
    leaks_in: Option<String>,
    skip_grid: bool,
    skip_adaptive: bool,
    dump: Option<String>,
    floor: bool,
    light_shells: LightShellsName,
    visibility: bool,
    normal_brightness: Option<f32>,
    /// `None`: `auto`.
    brightness: Option<f32>,
    weights: bool,
    near_lights: usize,
    near_radius: f32,
    near_seed: u64,
    args: Vec<String>,
}

impl Options {
    fn parse() -> Result<Self, Box<dyn Error>> {
        let args: Vec<String> = std::env::args().skip(1).collect();
        let has = |flag: &str| args.iter().any(|a| a == flag);
        let scene = args
            .first()
            .filter(|a| !a.starts_with("--"))
            .cloned()
            .unwrap_or_else(|| "builtin:demo".into());
        let budgets = arg(&args, "--budgets", "125,500,2000".to_string())
            .split(',')
            .map(|s| s.trim().parse())
            .collect::<Result<_, _>>()?;
        let brightness = match arg(&args, "--brightness", "0".to_string()).as_str() {
            "auto" => None,
            a => Some(a.parse()?),
        };
        Ok(Options {
            points: arg(&args, "--points", 400),
            samples: arg(&args, "--samples", 512),
            grid_factor: arg(&args, "--grid-factor", 4),
            budgets,
            seeds: arg(&args, "--seeds", "1".to_string()),
            seed: args
                .iter()
                .position(|a| a == "--seed")
                .and_then(|i| args.get(i + 1))
                .and_then(|v| v.parse().ok()),
            top: has("--top"),
            leaks_in: has("--leaks-in").then(|| arg(&args, "--leaks-in", String::new())),
            skip_grid: has("--no-grid"),
            skip_adaptive: has("--no-adaptive"),
            dump: has("--dump").then(|| arg(&args, "--dump", String::new())),
            floor: has("--floor"),
            light_shells: match arg(&args, "--light-shells", "auto".to_string()).as_str() {
                "on" => LightShellsName::On,
                "off" => LightShellsName::Off,
                _ => LightShellsName::Auto,
            },
            visibility: has("--visibility"),
            normal_brightness: has("--normal-brightness")
                .then(|| arg(&args, "--normal-brightness", 0.0)),
            brightness,
            weights: !has("--no-weights"),
            near_lights: arg(&args, "--near-lights", 0),
            near_radius: arg(&args, "--near-radius", 1.0),
            near_seed: arg(&args, "--near-seed", 1),
            scene,
            args,
        })
    }

    /// The recipe every cloud shares: the defaults, the scene's `[bake]`
    /// table, `--samples` and `--seed`, and the `[blend]` of
    /// `--visibility` (none without it). Each level sets its placement.
    fn recipe(&self, scene: &Scene) -> Result<Recipe, Box<dyn Error>> {
        let mut layers = RecipeLayers::new();
        layers.push_scene(&self.scene, scene);
        let int = |v: u64| Value::Integer(v as i64);
        layers.push_value("--samples", "capture.samples", int(self.samples.into()));
        if let Some(seed) = self.seed {
            layers.push_value("--seed", "capture.seed", int(seed));
        }
        let mut recipe = layers.resolve()?;
        recipe.blend = if self.visibility {
            let a = &self.args;
            let b = recipe.blend;
            let cells = match arg(a, "--cell-visibility", "auto".to_string()).as_str() {
                "auto" => CellVisibility::Auto,
                k => CellVisibility::Subdivision(
                    k.parse()
                        .map_err(|_| "--cell-visibility: expected auto or 1 to 8")?,
                ),
            };
            Blend {
                cell_visibility: cells,
                occluder_planes: !self.args.iter().any(|x| x == "--no-cell-planes"),
                probe_weights: self.weights,
                brightness_exponent: self.brightness.map_or(Exponent::Auto, Exponent::Value),
                directional_exponent: arg(a, "--directional", 0.0),
                fit: probekit::recipe::Fit {
                    points_per_probe: arg(a, "--fit-points", b.fit.points_per_probe),
                    samples: arg(a, "--fit-samples", b.fit.samples),
                    regularization: arg(a, "--fit-regularization", b.fit.regularization),
                    absolute_weight: arg(a, "--fit-absolute-weight", b.fit.absolute_weight),
                },
                ..b
            }
        } else {
            Blend::none()
        };
        Ok(recipe)
    }

    /// How the clouds are loaded: as baked, but with `--no-weights` the
    /// brightness exponent of `--brightness` (which a file stores with its
    /// probe weights only).
    fn load_options(&self) -> LoadOptions {
        let mut o = LoadOptions::default();
        if self.visibility && !self.weights {
            o.blend.brightness_exponent = Some(self.brightness.unwrap_or(0.0));
        }
        o
    }
}

/// The evaluation points (uniform, then `--near-lights`' balls) with
/// their truth, weight and stratum, and what each cloud's report needs.
struct Evaluation<'a> {
    options: &'a Options,
    scene: &'a Scene,
    baker: &'a Baker<'a>,
    /// The capture seed (`--dump`'s file names).
    seed: u64,
    /// The uniform points, their truth and its mean luminance.
    uniform: EvalSet,
    strata: Option<NearLights>,
    /// Per point of `points`: truth, the free volume it stands for (1 per
    /// uniform point without `--near-lights`) and its stratum (0: uniform;
    /// j + 1: light j's ball).
    points: Vec<EvalPoint>,
    truth: Vec<Vec3>,
    weight: Vec<f32>,
    stratum: Vec<u32>,
}

fn main() -> Result<(), Box<dyn Error>> {
    let o = Options::parse()?;
    let scene = Scene::load(std::path::Path::new(&o.scene))?;
    let recipe = o.recipe(&scene)?;
    // The evaluation's ray tracer, and the placement the levels change.
    let base = Bake::new(&scene, &o.scene, &recipe)?;
    let ev = Evaluation::new(&o, &scene, base.baker(), recipe.capture.seed)?;
    if o.floor {
        ev.floor(&recipe)?;
    }
    let with = |placement| Recipe {
        placement,
        ..recipe.clone()
    };
    let gf = o.grid_factor;
    for &b in &o.budgets {
        let grid = Bake::new(
            &scene,
            &o.scene,
            &with(Placement::Grid {
                budget: Some(b * gf),
                cell: None,
            }),
        )?;
        let placed = grid.place(&quiet)?;
        if !o.skip_grid {
            ev.report("grid", &finish(&grid, &placed)?)?;
        }
        if o.skip_adaptive {
            continue;
        }
        // At most a 1/GF share of the grid's probes.
        let budget = (placed.positions.len() / gf).max(8);
        let adaptive = Bake::new(
            &scene,
            &o.scene,
            &with(Placement::Adaptive {
                budget,
                tolerance: 0.0,
                light_shells: o.light_shells,
            }),
        )?;
        let t = std::time::Instant::now();
        let a = adaptive.place(&quiet)?;
        println!(
            "level {b}: grid {} probes, adaptive budget {budget} (1/{gf} of the grid), {} placed",
            placed.positions.len(),
            a.positions.len()
        );
        eprintln!(
            "adaptive budget {budget}: placed in {:.1} s, {:?}",
            t.elapsed().as_secs_f32(),
            a.report
        );
        ev.report("adaptive", &finish(&adaptive, &a)?)?;
    }
    Ok(())
}

/// The pipeline's stages after placement: the cloud file `probekit bake`
/// writes for `placed` (its phase times are not used here).
fn finish(bake: &Bake, placed: &Placed) -> Result<ProbeFile, Box<dyn Error>> {
    Ok(bake.finish(placed, &quiet, Clock::new(0))?.file)
}

impl<'a> Evaluation<'a> {
    fn new(
        o: &'a Options,
        scene: &'a Scene,
        baker: &'a Baker<'a>,
        seed: u64,
    ) -> Result<Self, Box<dyn Error>> {
        let uniform = eval_seeds(baker, scene, o.points, &o.seeds)?;
        // `--near-lights N`: N more points in a ball around each positional
        // light, for the stratified estimate (`common::NearLights`).
        let strata = (o.near_lights > 0)
            .then(|| {
                NearLights::sample(
                    baker,
                    scene,
                    uniform.points.len(),
                    o.near_lights,
                    o.near_radius,
                    o.near_seed,
                )
            })
            .transpose()?;
        if let Some(nl) = &strata {
            println!(
                "near lights: {} points in {} balls of {} m, uniform weight {:.4} m3",
                nl.set.points.len(),
                nl.centres.len(),
                nl.radius,
                nl.uniform_weight
            );
        }
        let balls = || strata.iter().flat_map(|nl| nl.set.points.iter());
        let points = uniform.points.iter().chain(balls()).copied().collect();
        let truth = (uniform.truth.iter())
            .chain(strata.iter().flat_map(|nl| nl.set.truth.iter()))
            .copied()
            .collect();
        let (weight, stratum) = (uniform.points.iter())
            .map(|p| {
                let w = strata
                    .as_ref()
                    .map_or(1.0, |nl| nl.uniform_weight_at(p.position));
                (w, 0)
            })
            .chain(
                strata
                    .iter()
                    .flat_map(|nl| nl.weights.iter().copied().zip(nl.stratum.iter().copied())),
            )
            .unzip();
        Ok(Evaluation {
            options: o,
            scene,
            baker,
            seed,
            uniform,
            strata,
            points,
            truth,
            weight,
            stratum,
        })
    }

    /// A probe at every evaluation point, captured like the clouds' probes
    /// (and at 16× the samples): no interpolation error at all, only SH
    /// truncation and capture noise, so no placement can go below it.
    fn floor(&self, recipe: &Recipe) -> Result<(), Box<dyn Error>> {
        let EvalSet {
            points,
            truth,
            mean,
        } = &self.uniform;
        let at: Vec<Vec3> = points.iter().map(|p| p.position).collect();
        for k in [1, 16] {
            let mut s = recipe.capture_settings();
            s.samples *= k;
            let pred: Vec<Vec3> = (self.baker)
                .capture_many(&at, 0, &s, &|_, _| {})?
                .iter()
                .zip(points)
                .map(|(r, p)| r.sh.irradiance(p.normal))
                .collect();
            let m = metrics(&pred, truth, *mean);
            println!(
                "    floor samples={:5} rel_rmse={:.3} p95={:.2} leaks={:3}",
                s.samples, m.rel_rmse, m.p95_rel_error, m.leaks
            );
        }
        Ok(())
    }

    /// Evaluates a baked cloud and prints its line (and what `--top`,
    /// `--leaks-in` and `--dump` ask for).
    fn report(&self, name: &str, file: &ProbeFile) -> Result<(), Box<dyn Error>> {
        let o = self.options;
        let pos = file.positions();
        if o.leaks_in.is_some() {
            let orphans = orphan_points(self.baker.tracer(), pos, PROBE_CLEARANCE)?;
            println!("{name}: {} orphan points", orphans.len());
            for p in orphans.iter().take(20) {
                println!("   orphan {p:.3?}");
            }
        }
        if o.visibility && o.weights && o.brightness.is_none() {
            let alpha = file.as_cloud().map_or(0.0, |c| c.blend.brightness_exponent);
            println!("{name}: brightness exponent {alpha}");
        }
        let probes = Probes::from_file(file, o.load_options())?;
        let pred = self.predict(&probes)?;
        if let Some(dir) = &o.dump {
            self.dump(dir, name, file, &pred)?;
        }
        let EvalSet {
            points: pts,
            truth,
            mean,
        } = &self.uniform;
        let mean = *mean;
        // With `--near-lights`, the stratified estimate over all points;
        // the other figures are the uniform points'.
        let strat = self.strata.as_ref().map_or(String::new(), |_| {
            let (mut se, mut st) = (0.0f64, 0.0f64);
            for ((e, t), w) in pred.iter().zip(&self.truth).zip(&self.weight) {
                se += *w as f64 * (*e - *t).length_squared() as f64;
                st += *w as f64 * t.length_squared() as f64;
            }
            format!(" stratified={:.3}", (se / st.max(1e-30)).sqrt())
        });
        let pred = &pred[..pts.len()];
        let m = metrics(pred, truth, mean);
        // Leaks whose blend reaches a probe behind geometry (`probekit eval`'s
        // `leaks_through_geometry`), overall and per region after a `+`, and
        // at points beyond the probes' hull, lit from its outer cells
        // (`leaks_outside_hull`); with `--visibility` only.
        let diag = probes.cloud().filter(|_| o.visibility);
        let (hidden, outside) = match diag {
            Some(c) => (
                blends_hidden_probes(c, self.baker.tracer(), pts),
                outside_hull(c, pts),
            ),
            None => (vec![false; pts.len()], vec![false; pts.len()]),
        };
        let regions = &self.scene.regions;
        let through = region_leaks_at(regions, pts, pred, truth, mean, &hidden);
        let mut reg = String::new();
        for ((r, mm), t) in region_metrics(regions, pts, pred, truth, mean)
            .into_iter()
            .zip(through)
        {
            reg += &format!(" {}:{:.2}/{}+{t}", r.name, mm.rel_rmse, mm.leaks);
        }
        if o.top {
            for w in worst_points(pred, truth, 8) {
                let (i, p) = (w.index, &pts[w.index]);
                println!(
                    "   p={:.2?} truth={:.3?} pred={:.3?} share={:.3}",
                    p.position, truth[i], pred[i], w.share
                );
                if diag.is_some() {
                    for b in blend_probes(&probes, p)? {
                        println!(
                            "      probe {} at {:.2?}: weight {:.3}, fitted s {:.3}, E(n) {:.1}",
                            b.index, pos[b.index], b.weight, b.fitted, b.irradiance.x
                        );
                    }
                }
            }
        }
        if let (Some(rn), Some(_)) = (o.leaks_in.as_ref(), diag) {
            let region = regions.iter().find(|r| &r.name == rn);
            for (i, p) in pts.iter().enumerate() {
                let inside = region.map_or(true, |r| r.aabb().contains(p.position));
                if !inside || !is_leak(pred[i], truth[i], mean) {
                    continue;
                }
                println!(
                    "  LEAK p={:.3?} n={:.2?} truth={:.4?} pred={:.4?}",
                    p.position, p.normal, truth[i], pred[i]
                );
                for b in blend_probes(&probes, p)? {
                    println!(
                        "      probe {} at {:.3?}: weight {:.3}, fitted s {:.3}, E(n) {:.3}, clear {}",
                        b.index,
                        pos[b.index],
                        b.weight,
                        b.fitted,
                        probekit_sh::LUMINANCE.dot(b.irradiance),
                        segment_clear(self.baker.tracer(), p.position, pos[b.index])
                    );
                }
            }
        }
        let (_, unlit) = unlit_points(pred, truth, mean);
        println!(
            "{name:>9} probes={:5} rel_rmse={:.3}{strat} p95={:.2} leaks={:3} through={} outside={} unlit={unlit} |{reg}",
            pos.len(),
            m.rel_rmse,
            m.p95_rel_error,
            m.leaks,
            leaks_at(pred, truth, mean, &hidden),
            leaks_at(pred, truth, mean, &outside)
        );
        Ok(())
    }

    /// The blended irradiance at every evaluation point (uniform, then the
    /// balls'), as loaded, or with `--normal-brightness`'s per-normal blend.
    fn predict(&self, probes: &Probes) -> Result<Vec<Vec3>, Box<dyn Error>> {
        let mut state = ObjectState::new();
        let nb = self
            .options
            .normal_brightness
            .filter(|_| self.options.visibility);
        self.points
            .iter()
            .map(|p| {
                Ok(match nb {
                    Some(a) => per_normal_blend(probes, p, a, &mut state)?,
                    None => Vec3::from(probes.irradiance(&mut state, p.position, p.normal)?),
                })
            })
            .collect()
    }

    /// `--dump`: per point, position, squared error and squared truth (the
    /// terms of `rel_rmse`), its weight and stratum, for a paired bootstrap
    /// across methods; and the blended and true mean irradiance, for the
    /// sign of the error.
    fn dump(
        &self,
        dir: &str,
        name: &str,
        file: &ProbeFile,
        pred: &[Vec3],
    ) -> Result<(), Box<dyn Error>> {
        let mut csv = String::from("x,y,z,se,st,w,s,pe,te\n");
        for (i, p) in self.points.iter().enumerate() {
            let (q, e, t) = (p.position, pred[i], self.truth[i]);
            csv += &format!(
                "{},{},{},{},{},{},{},{},{}\n",
                q.x,
                q.y,
                q.z,
                (e - t).length_squared(),
                t.length_squared(),
                self.weight[i],
                self.stratum[i],
                e.element_sum() / 3.0,
                t.element_sum() / 3.0
            );
        }
        std::fs::create_dir_all(dir)?;
        let path = format!("{dir}/{name}_{}_s{}.csv", file.probe_count(), self.seed);
        std::fs::write(&path, csv)?;
        Ok(())
    }
}

/// A probe of a point's blend.
struct BlendProbe {
    index: usize,
    /// Its blend weight at the point.
    weight: f32,
    /// Its fitted probe weight (1 without).
    fitted: f32,
    /// Its own irradiance for the point's normal.
    irradiance: Vec3,
}

/// The four probes of the blend at `p` (a hull face's three and a fourth
/// of weight 0 outside the hull), in the cell's order.
fn blend_probes(probes: &Probes, p: &EvalPoint) -> Result<Vec<BlendProbe>, Box<dyn Error>> {
    let q = probes.query(&mut ObjectState::new(), p.position)?;
    let cloud = probes.cloud().ok_or("not a cloud")?;
    Ok((0..4)
        .map(|k| {
            let j = q.probes[k] as usize;
            BlendProbe {
                index: j,
                weight: q.weights[k],
                fitted: cloud.probe_weights().map_or(1.0, |s| s[j]),
                irradiance: probekit_sh::irradiance(cloud.probe_sh(j), p.normal),
            }
        })
        .collect())
}

/// `--normal-brightness`: the blend weights at `p`, each divided by the
/// luminance of its probe's irradiance for the point's normal to the power
/// `a` (floored at 10⁻³ of the cell's brightest), renormalized, blending
/// the probes' irradiances for the normal.
fn per_normal_blend(
    probes: &Probes,
    p: &EvalPoint,
    a: f32,
    state: &mut ObjectState,
) -> Result<Vec3, Box<dyn Error>> {
    let q = probes.query(state, p.position)?;
    let cloud = probes.cloud().ok_or("not a cloud")?;
    let w = &q.weights[..4];
    let e: [Vec3; 4] = std::array::from_fn(|k| {
        if w[k] > 0.0 {
            probekit_sh::convolve::irradiance(cloud.probe_sh(q.probes[k] as usize), p.normal)
        } else {
            Vec3::ZERO
        }
    });
    let lum = |v: Vec3| probekit_sh::LUMINANCE.dot(v).max(0.0);
    let top = (0..4)
        .filter(|&k| w[k] > 0.0)
        .map(|k| lum(e[k]))
        .fold(0.0f32, f32::max);
    let (mut sum, mut out) = (0.0f32, Vec3::ZERO);
    for k in (0..4).filter(|&k| w[k] > 0.0) {
        let f = w[k] * lum(e[k]).max(1e-3 * top).max(1e-30).powf(-a);
        sum += f;
        out += f * e[k];
    }
    Ok(if sum > 0.0 {
        out / sum
    } else {
        Vec3::from(probes.irradiance(state, p.position, p.normal)?)
    })
}
