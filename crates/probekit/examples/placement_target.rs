//! The placement target, measured: for each level N of `--budgets`, a
//! uniform grid of about `GF·N` cell centres over the bake box (those inside
//! geometry dropped: `G` probes) against `adaptive` with budget `⌊G / GF⌋`,
//! which places at most that many (the budget is a hard cap), so adaptive
//! never has more than `1/GF` of the grid's probes; on the same evaluation
//! points and the same cached ground truth.
//!
//! ```text
//! cargo run --release -p probekit --example placement_target -- [SCENE] \
//!     [--budgets 125,500,2000] [--grid-factor 4] [--points 400] [--samples 512] [--top] [--floor]
//!     [--light-shells off|on|auto] [--no-grid] [--no-adaptive] [--visibility [--cell-visibility auto|K] [--no-cell-planes] [--no-weights] [--fit-points N] [--fit-samples N]
//!     [--fit-regularization R] [--fit-absolute-weight B] [--brightness auto|A] [--directional G] [--normal-brightness A]]
//!     [--seeds 1,2,3] [--seed S] [--leaks-in REGION] [--analytic-lights] [--dump DIR]
//!     [--near-lights N [--near-radius R] [--near-seed S]]
//! ```
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
//! `--seed`: the capture seed, which also seeds adaptive placement (another
//! seed, another placement of the same budget: its spread shows how much of a
//! difference between two placements is chance).
//!
//! `--seeds`: the evaluation points of several seeds pooled (default 1).
//!
//! `--light-shells`: adaptive's [`LightShells`] mode (default `auto`, as
//! `probekit bake`);
//! `--no-grid`: evaluate the adaptive clouds only; `--no-adaptive`: the
//! grids only.
//!
//! `--floor`: first, the figures of a probe captured at every evaluation
//! point (at `--samples` and at 16× as many): SH truncation and capture noise
//! alone, the floor no placement at that sample count can go below.
//!
//! `--visibility`: every cloud (grid and adaptive alike) blends with what
//! `probekit bake` stores by default — distance moments (`VISM`), cell
//! visibility (`CVSP`) and probe weights fitted with the default settings
//! (`PWGT`; `--no-weights`: none; `--fit-*` as `probekit bake`'s;
//! `--cell-visibility` as `probekit bake`'s, default `auto`; occluder
//! planes `CPLN` unless `--no-cell-planes`) — as
//! `probekit eval` does on such a file.
//! `--brightness A` (with `--visibility`): and with brightness weighting
//! `A` (`probekit eval --brightness-weight A`), the weights fitted for it;
//! `auto`: the exponent the fit chooses (`probekit bake`'s default), printed.
//! `--directional G` (with `--visibility`; default 0 here, 0.5 in
//! `probekit bake`): and with directional brightness `G` on top of the
//! fitted weights (`probekit bake --directional-brightness G`).
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
//! `--analytic-lights` (with `--visibility`; an experiment,
//! not a run-time feature yet): the positional (sphere and point) lights in
//! the bake box are left to an analytic term. Every capture — probes, the
//! placement's pool and held-out points — leaves out their direct light
//! ([`CaptureSettings::exclude_direct`], each such light in a group of its
//! own), each probe records the fraction of each light it sees (its captured
//! direct DC over the light's unshadowed SH DC), and a point's irradiance is
//! the blend of the probes' SH plus, per light, its exact unshadowed
//! irradiance (`lights::Light::irradiance`) times the probes'
//! fractions blended with the same weights (fitted probe weights, when on, are
//! fitted to the light the probes hold). The ground truth is unchanged.
//! `--analytic-sun`: the same, and directional lights too.
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
use probekit::blend::blend_fit::{
    capture_training_set, fit_blend, BlendFitSettings, BRIGHTNESS_CHOICES,
};
use probekit::blend::cell_planes::{bake_cell_planes, CELL_PLANE_SEED};
use probekit::blend::cell_visibility::{bake_cell_visibility, CellLattice};
use probekit::blend::visibility::{bake_distance_moments, VisibilitySettings};
use probekit::capture::{Baker, CaptureSettings};
use probekit::delaunay::tetrahedralize;
use probekit::eval::{
    interpolate_cloud, leaks_at, metrics, region_leaks_at, region_metrics, unlit_points,
    worst_points,
};
use probekit::placement::{grid_points, place, LightShells, PlacementMethod, PROBE_CLEARANCE};
use probekit::query::{blends_hidden_probes, outside_hull};
use probekit::scene::{LightKind, Scene};
use probekit::trace::free_space::inside_geometry;
use probekit_runtime::cloud::{ProbeCloud, VisibilityMaps, WalkState};
use probekit_sh::ShRgb;
use std::error::Error;

mod common;
use common::{arg, eval_seeds, EvalSet, NearLights};

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene_name = args
        .first()
        .filter(|a| !a.starts_with("--"))
        .cloned()
        .unwrap_or_else(|| "builtin:demo".into());
    let scene = Scene::load(std::path::Path::new(&scene_name))?;
    let npts: usize = arg(&args, "--points", 400);
    let samples: u32 = arg(&args, "--samples", 512);
    let gf: usize = arg(&args, "--grid-factor", 4);
    let budgets: Vec<usize> = arg(&args, "--budgets", "125,500,2000".to_string())
        .split(',')
        .map(|s| s.trim().parse())
        .collect::<Result<_, _>>()?;
    let top = args.iter().any(|a| a == "--top");
    let leaks_in: Option<String> = args
        .iter()
        .any(|a| a == "--leaks-in")
        .then(|| arg(&args, "--leaks-in", String::new()));
    let skip_grid = args.iter().any(|a| a == "--no-grid");
    let skip_adaptive = args.iter().any(|a| a == "--no-adaptive");
    let dump = args
        .iter()
        .any(|a| a == "--dump")
        .then(|| arg(&args, "--dump", String::new()));
    let floor = args.iter().any(|a| a == "--floor");
    let shells = match arg(&args, "--light-shells", "auto".to_string()).as_str() {
        "on" => LightShells::On,
        "off" => LightShells::Off,
        _ => LightShells::Auto,
    };
    let visibility = args.iter().any(|a| a == "--visibility");
    // `auto`: the exponent the weight fit chooses (`probekit bake`'s default).
    let normal_brightness: Option<f32> = args
        .iter()
        .any(|a| a == "--normal-brightness")
        .then(|| arg(&args, "--normal-brightness", 0.0));
    let brightness_arg: String = arg(&args, "--brightness", "0".to_string());
    let brightness: Option<f32> = match brightness_arg.as_str() {
        "auto" => None,
        a => Some(a.parse()?),
    };
    let weights = !args.iter().any(|a| a == "--no-weights");
    let no_planes = args.iter().any(|a| a == "--no-cell-planes");
    let lattice = CellLattice::from_name(&arg(&args, "--cell-visibility", "auto".to_string()))
        .ok_or("--cell-visibility: expected auto or 1 to 8")?;
    let baker = Baker::new(&scene)?;
    let bbox = scene.bake_box();
    // `--analytic-lights`: the positional lights in the bake box, each in a
    // light group of its own, for captures that split off their direct light.
    let analytic_sun = args.iter().any(|a| a == "--analytic-sun");
    let analytic = analytic_sun || args.iter().any(|a| a == "--analytic-lights");
    if analytic && !visibility {
        return Err("--analytic-lights needs --visibility".into());
    }
    // Only then: a second copy of the scene and its BVH.
    let mut near: Vec<(String, probekit::lights::Light)> = Vec::new();
    let grouped = analytic.then(|| {
        let mut grouped = scene.clone();
        for (i, l) in grouped.lights.iter_mut().enumerate() {
            let positional =
                matches!(l.kind, LightKind::Sphere | LightKind::Point) && bbox.contains(l.position);
            if positional || (analytic_sun && l.kind == LightKind::Directional) {
                if let Some(rl) = probekit::lights::from_scene_light(l) {
                    l.group = Some(format!("near{i:02}"));
                    near.push((format!("near{i:02}"), rl));
                }
            }
        }
        grouped
    });
    let grouped_baker = grouped.as_ref().map(Baker::new).transpose()?;
    // The baker whose captures leave the near lights' direct light out
    // (with `s`, below): placement and the weight fit use it too.
    let split_baker = grouped_baker.as_ref().unwrap_or(&baker);
    let EvalSet {
        points: pts,
        truth,
        mean,
    } = eval_seeds(
        &baker,
        &scene,
        npts,
        &arg(&args, "--seeds", "1".to_string()),
    )?;
    // `--near-lights N`: N more points in a ball around each positional
    // light, for the stratified estimate (`common::NearLights`).
    let near_n: usize = arg(&args, "--near-lights", 0);
    let strata = (near_n > 0)
        .then(|| {
            NearLights::sample(
                &baker,
                &scene,
                pts.len(),
                near_n,
                arg(&args, "--near-radius", 1.0),
                arg(&args, "--near-seed", 1),
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
    let all_pts: Vec<probekit::trace::free_space::EvalPoint> = pts
        .iter()
        .chain(strata.iter().flat_map(|nl| nl.set.points.iter()))
        .copied()
        .collect();
    // Per point of `all_pts`: truth, the free volume it stands for (1 per
    // uniform point without `--near-lights`) and its stratum (0: uniform;
    // j + 1: light j's ball).
    let all_truth: Vec<Vec3> = truth
        .iter()
        .chain(strata.iter().flat_map(|nl| nl.set.truth.iter()))
        .copied()
        .collect();
    let (all_weight, all_stratum): (Vec<f32>, Vec<u32>) = pts
        .iter()
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
    let mut s = CaptureSettings::from_scene(&scene);
    s.samples = samples;
    // The capture seed, which also seeds placement (pool jitter, spawns).
    s.seed = arg(&args, "--seed", s.seed);
    if analytic {
        // Probes, the placement's pool and its held-out points hold the
        // light less the near lights' direct part.
        s.exclude_direct = near.iter().map(|(n, _)| n.clone()).collect();
    }
    let diag: std::cell::RefCell<Option<ProbeCloud>> = std::cell::RefCell::new(None);
    let eval = |name: &str, pos: &[Vec3]| -> Result<(), Box<dyn Error>> {
        *diag.borrow_mut() = None;
        // With `--analytic-lights`: each probe's SH less the direct light of
        // the near lights, and per near light the fraction of it the probe
        // sees (its captured direct DC over the unshadowed one).
        let mut light_vis: Vec<Vec<f32>> = Vec::new();
        let sh: Vec<ShRgb> = if let Some(gb) = &grouped_baker {
            let mut s2 = s.clone();
            s2.groups = true;
            s2.split_direct = true;
            let res = gb.capture_many(pos, 0, &s2, &|_, _| {})?;
            let mut out = Vec::with_capacity(res.len());
            for r in res {
                let order = r.sh.order();
                let mut vis = Vec::with_capacity(near.len());
                for (name, light) in &near {
                    let g = r.groups.iter().find(|(n, _)| n == name);
                    let gi = r.groups_indirect.iter().find(|(n, _)| n == name);
                    let (Some((_, g)), Some((_, gi))) = (g, gi) else {
                        vis.push(0.0);
                        continue;
                    };
                    let direct0 = g.coeffs()[0] - gi.coeffs()[0];
                    let mut a = vec![Vec3::ZERO; order * order];
                    light.add_sh(order, r.position, 1.0, &mut a);
                    let lum = |v: Vec3| probekit_sh::LUMINANCE.dot(v);
                    vis.push(if lum(a[0]) > 0.0 {
                        (lum(direct0) / lum(a[0])).clamp(0.0, 1.0)
                    } else {
                        0.0
                    });
                }
                light_vis.push(vis);
                out.push(r.sh);
            }
            out
        } else {
            baker
                .capture_many(pos, 0, &s, &|_, _| {})?
                .into_iter()
                .map(|r| r.sh)
                .collect()
        };
        let mesh = tetrahedralize(pos)?.to_tet_mesh(pos)?;
        if leaks_in.is_some() {
            let o = probekit::placement::orphan_points(baker.tracer(), pos, PROBE_CLEARANCE)?;
            println!("{name}: {} orphan points", o.len());
            for p in o.iter().take(20) {
                println!("   orphan {p:.3?}");
            }
        }
        let pred = if visibility {
            let order = sh.first().map_or(1, |s| s.order());
            let coeffs: Vec<Vec3> = sh.iter().flat_map(|s| s.coeffs().to_vec()).collect();
            let tracer = baker.tracer();
            let moments = bake_distance_moments(
                tracer,
                pos,
                &VisibilitySettings::new(bbox.size().length(), s.seed),
                &|_, _| {},
            )?;
            let cells = bake_cell_visibility(tracer, &mesh, lattice.resolve(&mesh), &|_, _| {})?;
            let planes = (!no_planes)
                .then(|| bake_cell_planes(tracer, &mesh, &cells, CELL_PLANE_SEED, &|_, _| {}))
                .transpose()?;
            let mut cloud = ProbeCloud::new(mesh, order as u32, coeffs)?;
            cloud.set_visibility_maps(VisibilityMaps::from_moments(&moments))?;
            cloud.set_cell_visibility_bits(Some(cells))?;
            cloud.set_cell_planes(planes)?;
            cloud.set_brightness_weighting(brightness.unwrap_or(0.0))?;
            if weights {
                let d = BlendFitSettings::new(s.seed);
                let fit = BlendFitSettings {
                    points_per_probe: arg(&args, "--fit-points", d.points_per_probe),
                    samples: arg(&args, "--fit-samples", d.samples),
                    regularization: arg(&args, "--fit-regularization", d.regularization),
                    absolute_weight: arg(&args, "--fit-absolute-weight", d.absolute_weight),
                    directional: arg(&args, "--directional", 0.0),
                    ..d
                };
                let n = fit.points_per_probe as usize * pos.len();
                // Under the analytic split the weights are fitted to the
                // light the probes hold.
                let t = capture_training_set(
                    split_baker,
                    &bbox,
                    cloud.mesh(),
                    n,
                    &s,
                    &fit,
                    &|_, _| {},
                )?;
                let exps = brightness.map_or(BRIGHTNESS_CHOICES.to_vec(), |a| vec![a]);
                let f = fit_blend(&cloud, &t, &fit, &exps)?;
                if brightness.is_none() {
                    println!(
                        "{name}: brightness exponent {} (objective {:.4})",
                        f.brightness, f.objective
                    );
                }
                cloud.set_brightness_weighting(f.brightness)?;
                cloud.set_directional_brightness(f.directional)?;
                cloud.set_probe_weights(Some(f.weights))?;
            }
            let mut ws = WalkState::new();
            // The blend, for the leak split and the diagnosis of the worst points.
            *diag.borrow_mut() = Some(cloud.clone());
            all_pts
                .iter()
                .map(|p| {
                    let mut e = match normal_brightness {
                        Some(a) => per_normal_blend(&cloud, p.position, p.normal, a, &mut ws),
                        None => cloud.irradiance(p.position, p.normal, &mut ws),
                    };
                    if analytic {
                        // The near lights' exact unshadowed irradiance, times
                        // their visibility blended like the SH.
                        let (idx, w) = cloud.weights_at(p.position, &mut ws);
                        for (l, (_, light)) in near.iter().enumerate() {
                            let v: f32 = (0..4).map(|k| w[k] * light_vis[idx[k] as usize][l]).sum();
                            if v > 0.0 {
                                e += v * light.irradiance(p.position, p.normal, None);
                            }
                        }
                    }
                    e
                })
                .collect()
        } else {
            interpolate_cloud(&mesh, &sh, &all_pts)
        };
        // With `--near-lights`, the stratified estimate over all points;
        // the other figures are the uniform points'.
        let strat = strata.as_ref().map(|_| {
            let (mut se, mut st) = (0.0f64, 0.0f64);
            for ((e, t), w) in pred.iter().zip(&all_truth).zip(&all_weight) {
                se += *w as f64 * (*e - *t).length_squared() as f64;
                st += *w as f64 * t.length_squared() as f64;
            }
            (se / st.max(1e-30)).sqrt()
        });
        if let Some(dir) = &dump {
            // Per point: position, squared error and squared truth (the
            // terms of `rel_rmse`), its weight and stratum, for a paired
            // bootstrap across methods; and the blended and true mean
            // irradiance, for the sign of the error.
            let mut csv = String::from("x,y,z,se,st,w,s,pe,te\n");
            for (i, p) in all_pts.iter().enumerate() {
                let (q, e, t) = (p.position, pred[i], all_truth[i]);
                csv += &format!(
                    "{},{},{},{},{},{},{},{},{}\n",
                    q.x,
                    q.y,
                    q.z,
                    (e - t).length_squared(),
                    t.length_squared(),
                    all_weight[i],
                    all_stratum[i],
                    e.element_sum() / 3.0,
                    t.element_sum() / 3.0
                );
            }
            std::fs::create_dir_all(dir)?;
            let file = format!("{dir}/{name}_{}_s{}.csv", pos.len(), s.seed);
            std::fs::write(&file, csv)?;
        }
        let pred = &pred[..pts.len()];
        let m = metrics(pred, &truth, mean);
        // Leaks whose blend reaches a probe behind geometry (`probekit eval`'s
        // `leaks_through_geometry`), overall and per region after a `+`, and
        // at points beyond the probes' hull, lit from its outer cells
        // (`leaks_outside_hull`).
        let (hidden, outside) = match diag.borrow().as_ref() {
            Some(c) => (
                blends_hidden_probes(c, baker.tracer(), &pts),
                outside_hull(c, &pts),
            ),
            None => (vec![false; pts.len()], vec![false; pts.len()]),
        };
        let through = region_leaks_at(&scene.regions, &pts, pred, &truth, mean, &hidden);
        let mut reg = String::new();
        for ((r, mm), t) in region_metrics(&scene.regions, &pts, pred, &truth, mean)
            .into_iter()
            .zip(through)
        {
            reg += &format!(" {}:{:.2}/{}+{t}", r.name, mm.rel_rmse, mm.leaks);
        }
        if top {
            for w in worst_points(pred, &truth, 8) {
                let i = w.index;
                println!(
                    "   p={:.2?} truth={:.3?} pred={:.3?} share={:.3}",
                    pts[i].position, truth[i], pred[i], w.share
                );
                if let Some(c) = diag.borrow().as_ref() {
                    let mut ws = WalkState::new();
                    let (idx4, w4) = c.weights_at(pts[i].position, &mut ws);
                    for k in 0..4 {
                        let j = idx4[k] as usize;
                        let e = probekit_sh::irradiance(c.probe_sh(j), pts[i].normal);
                        println!(
                            "      probe {j} at {:.2?}: weight {:.3}, fitted s {:.3}, E(n) {:.1}",
                            pos[j],
                            w4[k],
                            c.probe_weights().map_or(1.0, |s| s[j]),
                            e.x
                        );
                    }
                }
            }
        }
        if let (Some(rn), Some(c)) = (leaks_in.as_ref(), diag.borrow().as_ref()) {
            let region = scene.regions.iter().find(|r| &r.name == rn);
            for (i, p) in pts.iter().enumerate() {
                let inside = region.map_or(true, |r| r.aabb().contains(p.position));
                if !inside || !probekit::eval::is_leak(pred[i], truth[i], mean) {
                    continue;
                }
                println!(
                    "  LEAK p={:.3?} n={:.2?} truth={:.4?} pred={:.4?}",
                    p.position, p.normal, truth[i], pred[i]
                );
                let mut ws = WalkState::new();
                let (idx4, w4) = c.weights_at(p.position, &mut ws);
                for k in 0..4 {
                    let j = idx4[k] as usize;
                    let e = probekit_sh::irradiance(c.probe_sh(j), p.normal);
                    println!(
                        "      probe {j} at {:.3?}: weight {:.3}, fitted s {:.3}, E(n) {:.3}, clear {}",
                        pos[j],
                        w4[k],
                        c.probe_weights().map_or(1.0, |s| s[j]),
                        probekit_sh::LUMINANCE.dot(e),
                        probekit::trace::free_space::segment_clear(baker.tracer(), p.position, pos[j])
                    );
                }
            }
        }
        let strat = strat.map_or(String::new(), |x| format!(" stratified={x:.3}"));
        let (_, unlit) = unlit_points(pred, &truth, mean);
        println!(
            "{name:>9} probes={:5} rel_rmse={:.3}{strat} p95={:.2} leaks={:3} through={} outside={} unlit={unlit} |{reg}",
            pos.len(),
            m.rel_rmse,
            m.p95_rel_error,
            m.leaks,
            leaks_at(pred, &truth, mean, &hidden),
            leaks_at(pred, &truth, mean, &outside)
        );
        Ok(())
    };
    if floor {
        // A probe at every evaluation point, captured like the clouds' probes
        // (and at 16× the samples): no interpolation error at all, only SH
        // truncation and capture noise, so no placement can go below it.
        let at: Vec<Vec3> = pts.iter().map(|p| p.position).collect();
        for k in [1, 16] {
            let mut sk = s.clone();
            sk.samples = samples * k;
            let pred: Vec<Vec3> = baker
                .capture_many(&at, 0, &sk, &|_, _| {})?
                .iter()
                .zip(&pts)
                .map(|(r, p)| r.sh.irradiance(p.normal))
                .collect();
            let m = metrics(&pred, &truth, mean);
            println!(
                "    floor samples={:5} rel_rmse={:.3} p95={:.2} leaks={:3}",
                sk.samples, m.rel_rmse, m.p95_rel_error, m.leaks
            );
        }
    }
    for &b in &budgets {
        let g: Vec<Vec3> = grid_points(&bbox, None, Some(b * gf))?
            .into_iter()
            .filter(|p| !inside_geometry(baker.tracer(), *p))
            .collect();
        if !skip_grid {
            eval("grid", &g)?;
        }
        if skip_adaptive {
            continue;
        }
        let t = std::time::Instant::now();
        // At most a 1/GF share of the grid's probes, whatever the grid
        // dropped inside geometry.
        let budget = (g.len() / gf).max(8);
        let m = PlacementMethod::Adaptive {
            budget,
            tolerance: 0.0,
            light_shells: shells,
        };
        // With `--analytic-lights` placement sees the light less the near
        // lights' direct part.
        let a = place(split_baker, bbox, &m, &s, &|_, _, _| {})?;
        println!(
            "level {b}: grid {} probes, adaptive budget {budget} (1/{gf} of the grid), {} placed",
            g.len(),
            a.positions.len()
        );
        eprintln!(
            "adaptive budget {budget}: placed in {:.1} s, {:?}",
            t.elapsed().as_secs_f32(),
            a.stats
        );
        eval("adaptive", &a.positions)?;
    }
    Ok(())
}

/// `--normal-brightness`: the cloud's blend weights at `p`, each divided by
/// the luminance of its probe's irradiance for `normal` to the power `a`
/// (floored at 10⁻³ of the cell's brightest), renormalized, blending the
/// probes' irradiances for `normal`.
fn per_normal_blend(cloud: &ProbeCloud, p: Vec3, normal: Vec3, a: f32, ws: &mut WalkState) -> Vec3 {
    let (idx, w) = cloud.weights_at(p, ws);
    let e: [Vec3; 4] = std::array::from_fn(|k| {
        if w[k] > 0.0 {
            probekit_sh::convolve::irradiance(cloud.probe_sh(idx[k] as usize), normal)
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
    if sum > 0.0 {
        out / sum
    } else {
        cloud.irradiance(p, normal, ws)
    }
}
