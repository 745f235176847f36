//! One rig experiment end to end (what `probekit rig` runs): fit a rig to a
//! mesh placed at a point among lights, build its transition table, split
//! the lights, evaluate per vertex, compare with the exact evaluation and
//! time a frame.

use super::fit::FittedRig;
use super::lights::{lights_from_scene, paper_cost_lights, rig_demo_lights, SceneLights};
use super::mesh::{self, Mesh};
use super::render::{comparison_figure, zones_figure, Column, RenderError};
use super::source::ProbeSource;
use super::split::{self, Frame, Zone};
use super::{RigSetupError, RigSpec};
use crate::lights::{Light, SphereTable};
use crate::scene::Scene;
use glam::Vec3;
use probekit_runtime::ObjectState;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Seed of the sample distribution unless told otherwise.
pub const DEFAULT_SEED: u64 = 0x5EED_0000;
/// Table distances used by [`run`].
pub const TABLE_DISTANCES: usize = 24;

/// Loads a mesh: `builtin:car`, `builtin:character`, or an OBJ/glTF/TOML
/// file through the scene loader ([`mesh::load`]).
pub fn load_mesh(name: &str) -> Result<Mesh, RigSetupError> {
    mesh::load(name)
}

/// Loads the lights of a scene: the rig's own light sets
/// `builtin:rig-demo` and `builtin:paper-cost` (the Irradiance Rigs paper's demo: 4 + 8
/// sphere lights and 192 disks), or anything [`Scene::load`] reads
/// (`builtin:demo`, `.toml`, `.gltf`, `.glb`, `.obj`), converted by
/// [`lights_from_scene`] (its warnings say what was left out). Load errors
/// are the scene loader's, which name the file.
pub fn load_lights(scene: &str) -> Result<SceneLights, RigSetupError> {
    let own = |lights| SceneLights {
        lights,
        ..SceneLights::default()
    };
    match scene {
        "builtin:rig-demo" => Ok(own(rig_demo_lights())),
        "builtin:paper-cost" => Ok(own(paper_cost_lights())),
        s if s.starts_with("builtin:") && s != crate::scene::BUILTIN_DEMO => {
            Err(RigSetupError::UnknownBuiltin(s.to_string()))
        }
        path => {
            let s = Scene::load(path).map_err(|e| RigSetupError::Scene(e.to_string()))?;
            Ok(lights_from_scene(&s))
        }
    }
}

/// Settings of one experiment.
#[derive(Clone, Debug)]
pub struct RunConfig {
    /// The rig type.
    pub spec: RigSpec,
    /// Where the mesh's origin is placed (world).
    pub at: Vec3,
    /// Analytic/rig split on (else every light goes through the rig).
    pub split: bool,
    /// Sample points on the mesh.
    pub samples: usize,
    /// SH order (bands), 3 = L2.
    pub order: usize,
    /// White level (reflected radiance); `None`: the largest exact one over the mesh.
    pub white: Option<f32>,
    /// Target error for the split, grey levels.
    pub target_grey: f32,
    /// Sampling seed.
    pub seed: u64,
}

impl Default for RunConfig {
    fn default() -> Self {
        Self {
            spec: RigSpec::Gradient,
            at: Vec3::ZERO,
            split: true,
            samples: 512,
            order: 3,
            white: None,
            target_grey: 1.0,
            seed: DEFAULT_SEED,
        }
    }
}

/// Results of [`run`].
#[derive(Clone, Debug)]
pub struct RunReport {
    /// The fitted rig, with its transition table.
    pub fitted: FittedRig,
    /// Zone of each light, in scene order.
    pub zones: Vec<Zone>,
    /// Transition distance of each light (bounding radii), when split.
    pub thresholds: Vec<f32>,
    /// Per-vertex irradiance of the rig (with the split when on).
    pub approx: Vec<Vec3>,
    /// Exact per-vertex irradiance of every light.
    pub exact: Vec<Vec3>,
    /// Errors of `approx` against `exact`.
    pub stats: split::ErrorStats,
    /// Errors of `approx` against the per-vertex SH of the rig's lights
    /// (plus the analytic ones exactly): the rig's spatial error alone,
    /// without the SH truncation every rig shares.
    pub stats_vs_sh: split::ErrorStats,
    /// Median wall time of one frame: SH at the samples for the rig's
    /// lights, the rig update and the per-vertex evaluation (with analytic
    /// lights), single thread, ns.
    pub ns_per_frame: f64,
    /// Median wall time of evaluating every light analytically per vertex
    /// (the brute-force alternative), ns.
    pub ns_brute_force: f64,
}

impl RunReport {
    /// Lights per zone: `(analytic, transition, rig)`.
    pub fn zone_counts(&self) -> (usize, usize, usize) {
        let mut c = (0, 0, 0);
        for z in &self.zones {
            match z {
                Zone::Analytic => c.0 += 1,
                Zone::Transition(_) => c.1 += 1,
                Zone::Rig => c.2 += 1,
            }
        }
        c
    }
}

/// Median time of `f` in ns over enough repetitions (≥ 3, ~0.2 s).
pub fn time_ns(mut f: impl FnMut()) -> f64 {
    let mut t = Vec::new();
    let start = Instant::now();
    while t.len() < 3 || (start.elapsed().as_secs_f64() < 0.2 && t.len() < 200) {
        let s = Instant::now();
        f();
        t.push(s.elapsed().as_nanos() as f64);
    }
    t.sort_by(|a, b| a.total_cmp(b));
    t[t.len() / 2]
}

/// Runs the experiment for `mesh` (own coordinates; placed at `cfg.at`)
/// among `lights` and, when given, the baked lighting of `probes` (which
/// goes through the rig; its exact reference is the file's irradiance at
/// each vertex, see [`super::source`]). `time` off skips the timing (tests).
pub fn run(
    mesh: &Mesh,
    name: &str,
    lights: &[Light],
    probes: Option<&ProbeSource>,
    cfg: &RunConfig,
    time: bool,
) -> Result<RunReport, RigSetupError> {
    let mut fitted = FittedRig::fit(mesh, cfg.spec, cfg.order, cfg.samples, cfg.seed, name)?;
    let mut walk = ObjectState::new();
    let mut exact = split::exact_irradiance(mesh, cfg.at, lights);
    if let Some(src) = probes {
        split::add_probe_irradiance(mesh, cfg.at, src, cfg.order, &mut walk, &mut exact);
    }
    let l_white = cfg
        .white
        .unwrap_or_else(|| split::white_level(&exact))
        .max(f32::MIN_POSITIVE);
    let (c_local, r) = mesh.bounding_sphere();
    let center = c_local + cfg.at;
    let (zones, thresholds) = if cfg.split {
        fitted.rig.transitions = split::transition_table(
            &fitted,
            mesh,
            &split::table_distances(TABLE_DISTANCES),
            &split::table_directions(),
        );
        let th: Vec<f32> = lights
            .iter()
            .map(|l| {
                split::transition_distance(
                    &fitted.rig.transitions,
                    l,
                    center,
                    r,
                    l_white,
                    cfg.target_grey,
                )
            })
            .collect();
        let z = lights
            .iter()
            .zip(&th)
            .map(|(l, &t)| {
                let x = l
                    .position()
                    .map_or(f32::INFINITY, |p| p.distance(center) / r);
                split::zone(x, t)
            })
            .collect();
        (z, th)
    } else {
        (vec![Zone::Rig; lights.len()], Vec::new())
    };
    let weights: Vec<f32> = zones.iter().map(|z| z.rig_weight()).collect();
    let table = SphereTable::default();
    let mut frame = Frame::new(&fitted);
    let mut approx = vec![Vec3::ZERO; mesh.positions.len()];
    split::update_from_sources(
        &mut frame, &fitted, cfg.at, lights, &weights, probes, &mut walk,
    );
    split::split_irradiance(&frame, mesh, cfg.at, lights, &weights, &table, &mut approx);
    let stats = split::error_stats(&approx, &exact, Some(l_white));
    let mut sh_ref = split::sh_reference_irradiance(mesh, cfg.at, lights, &weights, cfg.order);
    if let Some(src) = probes {
        split::add_probe_irradiance(mesh, cfg.at, src, cfg.order, &mut walk, &mut sh_ref);
    }
    let stats_vs_sh = split::error_stats(&approx, &sh_ref, Some(l_white));
    let (mut ns_per_frame, mut ns_brute_force) = (0.0, 0.0);
    if time {
        ns_per_frame = time_ns(|| {
            split::update_from_sources(
                &mut frame, &fitted, cfg.at, lights, &weights, probes, &mut walk,
            );
            split::split_irradiance(&frame, mesh, cfg.at, lights, &weights, &table, &mut approx);
        });
        let zeros = vec![0.0f32; lights.len()];
        let empty = Frame::new(&fitted);
        let mut brute = vec![Vec3::ZERO; mesh.positions.len()];
        // Brute force: every light analytically and the file queried at
        // every vertex.
        ns_brute_force = time_ns(|| {
            split::split_irradiance(&empty, mesh, cfg.at, lights, &zeros, &table, &mut brute);
            if let Some(src) = probes {
                split::add_probe_irradiance(mesh, cfg.at, src, cfg.order, &mut walk, &mut brute);
            }
        });
    }
    Ok(RunReport {
        fitted,
        zones,
        thresholds,
        approx,
        exact,
        stats,
        stats_vs_sh,
        ns_per_frame,
        ns_brute_force,
    })
}

/// Why the comparison pictures could not be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PictureError {
    /// One of the compared rigs could not be fitted.
    #[error(transparent)]
    Rig(#[from] RigSetupError),
    /// A picture could not be written.
    #[error(transparent)]
    Write(#[from] RenderError),
}

/// The rig types every comparison picture shows ([`comparison_pictures`]).
pub const COMPARED_RIGS: [&str; 6] = [
    "constant",
    "gradient",
    "lattice:2x2x3",
    "lattice:3x2x2",
    "mixed:l3,g,c",
    "lattice:8x4x2",
];

/// `probekit rig --render OUT`: writes to `out` the comparison picture
/// ([`comparison_figure`]) of the rigs of [`COMPARED_RIGS`] and `cfg`'s own
/// (each fitted with every light through the rig, as `run` does with the
/// split off) beside the exact lighting of `report` (the experiment of
/// `cfg`), with their error heat maps, and beside it `STEM_zones.png`
/// (STEM: `out`'s name without its extension), the mesh lit with the split
/// and the lights' zones ([`zones_figure`]). Returns the zones picture's
/// path.
pub fn comparison_pictures(
    out: &Path,
    mesh: &Mesh,
    lights: &[Light],
    probes: Option<&ProbeSource>,
    cfg: &RunConfig,
    report: &RunReport,
) -> Result<PathBuf, PictureError> {
    let mut specs: Vec<RigSpec> = COMPARED_RIGS
        .iter()
        .map(|s| s.parse().expect("built-in spec"))
        .collect();
    if !specs.contains(&cfg.spec) {
        specs.push(cfg.spec);
    }
    let l_white = report.stats.l_white;
    let mut runs = Vec::new();
    for s in &specs {
        // Rigs are compared with each other with every light in the rig.
        let c = RunConfig {
            spec: *s,
            split: false,
            ..cfg.clone()
        };
        runs.push((s, run(mesh, "mesh", lights, probes, &c, false)?));
    }
    let grey = |r: &RunReport| -> Vec<f32> {
        r.approx
            .iter()
            .zip(&r.exact)
            .map(|(x, e)| 255.0 * (*x - *e).abs().max_element() / std::f32::consts::PI / l_white)
            .collect()
    };
    let mut cols: Vec<Column> = runs
        .iter()
        .map(|(s, r)| Column {
            name: s.to_string(),
            irradiance: &r.approx,
            error_grey: Some(grey(r)),
        })
        .collect();
    cols.push(Column {
        name: "exact".into(),
        irradiance: &report.exact,
        error_grey: None,
    });
    comparison_figure(out, mesh, &cols, l_white, 64.0)?;
    let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("rig");
    let zones_path = out.with_file_name(format!("{stem}_zones.png"));
    let world = mesh.translated(cfg.at);
    // Directional lights have no position to draw.
    let lw: Vec<(Vec3, f32)> = lights
        .iter()
        .zip(&report.zones)
        .filter_map(|(l, z)| Some((l.position()?, z.rig_weight())))
        .collect();
    zones_figure(&zones_path, &world, &report.approx, l_white, &lw)?;
    Ok(zones_path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// End to end on the car: the split never makes things worse than the
    /// rig alone, puts the nearest demo light (beside the front wheel)
    /// in the analytic zone when the car is at the origin, and the
    /// brute-force route through `run` agrees with the exact evaluation.
    #[test]
    fn split_improves_on_rig_alone() {
        let car = mesh::car();
        let lights = rig_demo_lights();
        let mut cfg = RunConfig {
            spec: "mixed:l3,g,c".parse().unwrap(),
            samples: 128,
            ..RunConfig::default()
        };
        cfg.split = false;
        let off = run(&car, "car", &lights, None, &cfg, false).unwrap();
        cfg.split = true;
        let on = run(&car, "car", &lights, None, &cfg, false).unwrap();
        assert!(
            on.stats.max_grey <= off.stats.max_grey + 1e-3,
            "{:?} vs {:?}",
            on.stats,
            off.stats
        );
        assert!(on.stats.rel_rmse < off.stats.rel_rmse);
        assert_eq!(on.zones[3], Zone::Analytic, "{:?}", on.zones);
        assert_eq!(off.zone_counts(), (0, 0, lights.len()));
    }

    #[test]
    fn bad_names_are_typed_errors() {
        assert!(matches!(
            load_mesh("builtin:boat"),
            Err(RigSetupError::UnknownBuiltin(_))
        ));
        assert!(matches!(
            load_lights("builtin:nope"),
            Err(RigSetupError::UnknownBuiltin(_))
        ));
        let e = load_lights("/nonexistent/x.toml").unwrap_err();
        assert!(e.to_string().contains("/nonexistent/x.toml"), "{e}");
        let e = load_mesh("/nonexistent/m.obj").unwrap_err();
        assert!(e.to_string().contains("/nonexistent/m.obj"), "{e}");
    }
}
