//! The run-time light split of a bake: which lights' direct light leaves
//! the probes' SH for an exact run-time term, and each probe's occlusion
//! of them (`docs/scene-format.md`, "Light modes").
//!
//! 1. **Candidates.** Every light whose `mode` is `runtime` or `auto` (or,
//!    with a recorded choice, every light recorded `runtime`) with non-zero
//!    power gets a light group of its own, so each capture can leave its
//!    direct light out and report it apart; placement and the probes'
//!    capture see the light less the candidates' direct light.
//! 2. **Occlusion.** Each probe's visible fraction of each candidate
//!    ([`crate::capture::occlusion`]: stratified shadow rays over a sphere's
//!    solid angle or a disk's area, one ray to a point, spot or sun).
//! 3. **Choice.** An `auto` light becomes run-time where the bake's own
//!    held-out estimate says that lowers the error: on held-out points of
//!    free space (with random normals), dense around the positional
//!    candidates and weighted by the volume each stands for
//!    (`decision_points`), the light's shadowed direct
//!    irradiance (exact irradiance × its receiver-weighted visible fraction)
//!    against (a) its exact irradiance × the probes' blended visible
//!    fractions and (b) the probes' blended SH of its direct light; it runs
//!    at run time when (a)'s squared error is below [`DECISION_MARGIN`]
//!    times (b)'s.
//! 4. **K per probe.** Where more than K run-time lights reach one probe
//!    (a stored occlusion: visible and at least [`MATTERS`] of the probe's
//!    light), whole lights are demoted to baked, the lowest contribution at
//!    that probe first, until no probe has more than K.
//! 5. **Compose.** Lights that ended baked get their direct light back in
//!    the SH (the capture reported it apart: nothing is captured again);
//!    each run-time light's bounce light stays in the SH, in its light
//!    group.

use crate::capture::occlusion::{visible_fraction, visible_fractions};
use crate::capture::{BakeOutput, Baker, DEFAULT_GROUP};
use crate::lights::from_scene_light;
use crate::placement::held_out_points;
use crate::recipe::{Lights, Recipe, ResolvedMode};
use crate::sampling::{sample_uniform_sphere, SampleRng};
use crate::scene::{Aabb, LightMode, Scene};
use crate::trace::free_space::{is_evaluation_point, EvalPoint};
use crate::trace::Tracer;
use glam::Vec3;
use probekit_runtime::cloud::WalkState;
use probekit_runtime::format::{quantize_occlusion, LightOcclusion, RuntimeLight, RuntimeLights};
use probekit_runtime::ProbeCloud;
use probekit_sh::{ShRgb, LUMINANCE};
use rayon::prelude::*;
use serde::Serialize;

/// A light at a probe is stored (it "reaches" the probe) when its
/// unshadowed contribution times the visible fraction is at least this
/// fraction of the probe's light.
pub const MATTERS: f32 = 1e-3;

/// An `auto` light runs at run time when its held-out error there is below
/// this fraction of its error baked. A run-time light's blended occlusion
/// can light a point in shadow at the light's full exact irradiance, a
/// risk the squared error alone weighs little: on the demo the sun's gain
/// was 2 % and it made 21 more points leak, the lamp's 99 %.
pub const DECISION_MARGIN: f64 = 0.9;

/// Seed offset of the held-out points of the choice (not the evaluation's).
const DECISION_SEED: u64 = 0x6c69_6768_7473;

/// The candidates of a bake's split and the light groups that isolate them.
#[derive(Clone, Debug, Default)]
pub struct LightSplit {
    /// Scene light indices of the candidates, increasing.
    pub candidates: Vec<usize>,
    /// Per candidate: whether the bake decides (`auto`, no recorded choice).
    pub auto: Vec<bool>,
    /// Per candidate: baked by a recorded choice (`demoted`).
    pub demoted: Vec<bool>,
    /// The capture's group of each scene light: a candidate's own, the
    /// light's `group` (or `"default"`) otherwise.
    pub capture_groups: Vec<String>,
    /// Each scene light's own group (`group` or `"default"`).
    pub user_groups: Vec<String>,
}

/// What the split did, as `bake --json` reports it.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LightSplitReport {
    /// Scene light indices (0-based) evaluated at run time.
    pub runtime: Vec<usize>,
    /// `auto` lights the held-out estimate kept baked.
    pub kept_baked: Vec<usize>,
    /// Lights demoted to baked because more than K run-time lights reached
    /// a probe.
    pub demoted: Vec<usize>,
    /// Per `auto` light `[index, error run-time, error baked]`: the summed
    /// squared luminance error of its direct light on the held-out points.
    pub held_out: Vec<(usize, f64, f64)>,
    /// Stored occlusion entries (probe, light pairs).
    pub occlusion_entries: usize,
    /// K: the most run-time lights that may reach one probe.
    pub max_per_probe: u32,
}

impl LightSplit {
    /// The candidates of `scene` under `lights` (none when the split is off
    /// or the probes store indirect light only).
    pub fn new(scene: &Scene, lights: &Lights, indirect_only: bool) -> Self {
        let user_groups: Vec<String> = scene
            .lights
            .iter()
            .map(|l| l.group.clone().unwrap_or_else(|| DEFAULT_GROUP.into()))
            .collect();
        let mut split = LightSplit {
            capture_groups: user_groups.clone(),
            user_groups,
            ..Default::default()
        };
        if !lights.split || indirect_only {
            return split;
        }
        for (i, l) in scene.lights.iter().enumerate() {
            let lit = (l.color * l.intensity).max_element() > 0.0 && from_scene_light(l).is_some();
            let (candidate, auto, demoted) = match lights.resolved.get(i) {
                Some(ResolvedMode::Runtime) => (true, false, false),
                Some(ResolvedMode::Demoted) => (true, false, true),
                Some(ResolvedMode::Baked) => (false, false, false),
                None => match l.mode {
                    LightMode::Baked => (false, false, false),
                    LightMode::Runtime => (true, false, false),
                    LightMode::Auto => (true, true, false),
                },
            };
            if candidate && lit {
                split.candidates.push(i);
                split.auto.push(auto);
                split.demoted.push(demoted);
                split.capture_groups[i] = format!("{}\u{1f}runtime {i}", split.user_groups[i]);
            }
        }
        split
    }

    /// The capture groups whose direct light the SH leaves out.
    pub fn excluded_groups(&self, runtime: &[usize]) -> Vec<String> {
        runtime
            .iter()
            .map(|&i| self.capture_groups[i].clone())
            .collect()
    }
}

/// The split's result for a captured bake: the composed output, the
/// file's run-time lights and the per-light choice.
pub struct Split {
    /// The capture with baked candidates' direct light back in the SH and
    /// light groups under the scene's names.
    pub output: BakeOutput,
    /// The file's `LITE`/`OCCL` (`None` when no light ended run-time).
    pub lights: Option<RuntimeLights>,
    /// The choice for every scene light, in order.
    pub resolved: Vec<ResolvedMode>,
    /// What happened.
    pub report: LightSplitReport,
}

/// Steps 2–5 of the module docs for `out`, a capture whose settings left
/// every candidate's direct light out and reported light groups with the
/// direct/indirect split; `recipe` says how (`[lights]`), with which seed,
/// and whether the file keeps light groups and the direct/indirect split.
pub fn resolve(
    baker: &Baker<'_>,
    split: &LightSplit,
    recipe: &Recipe,
    bake_box: &Aabb,
    mut out: BakeOutput,
) -> Result<Split, crate::pipeline::PipelineError> {
    let settings = &recipe.lights;
    let seed = recipe.capture.seed;
    let (keep_groups, keep_split) = (recipe.capture.groups, recipe.capture.indirect_only);
    let scene = baker.scene();
    let tracer = baker.tracer();
    let cands: Vec<crate::scene::Light> = split
        .candidates
        .iter()
        .map(|&i| scene.lights[i].clone())
        .collect();
    let probes = out.captured_positions.len();
    let order = out.settings.order;
    let nc = cands.len();
    // Each candidate's direct SH per probe: its group less the group's
    // indirect light.
    let direct: Vec<Vec<ShRgb>> = split
        .candidates
        .iter()
        .map(|&i| {
            let name = &split.capture_groups[i];
            let all = out.groups.iter().find(|g| &g.0 == name);
            let ind = out.groups_indirect.iter().find(|g| &g.0 == name);
            match (all, ind) {
                (Some((_, a)), Some((_, b))) => a
                    .iter()
                    .zip(b)
                    .map(|(a, b)| {
                        let mut d = a.clone();
                        d.add_scaled(b, -1.0);
                        d
                    })
                    .collect(),
                _ => vec![ShRgb::zeros(order); probes],
            }
        })
        .collect();
    let frac = visible_fractions(
        tracer,
        &out.captured_positions,
        &cands,
        settings.occlusion_samples,
        seed,
    );
    // Contribution of candidate l at probe i (luminance of the unshadowed
    // DC times the visible fraction) and the probe's light.
    let lum = |v: Vec3| LUMINANCE.dot(v);
    let rt: Vec<_> = cands.iter().map(from_scene_light).collect();
    let mut contribution = vec![0.0f32; probes * nc];
    for i in 0..probes {
        let x = out.captured_positions[i];
        let mut total = lum(out.sh[i].coeffs()[0]);
        for d in &direct {
            total += lum(d[i].coeffs()[0]);
        }
        for (l, light) in rt.iter().enumerate() {
            let Some(light) = light else { continue };
            let mut dc = [Vec3::ZERO];
            light.add_sh(1, x, 1.0, &mut dc);
            let q = quantize_occlusion(frac[i * nc + l]);
            let c = lum(dc[0]) * f32::from(q) / 255.0;
            if q > 0 && c >= MATTERS * total.max(0.0) && c > 0.0 {
                contribution[i * nc + l] = c;
            }
        }
    }

    // Step 3: the held-out choice of `auto` lights.
    let mut runtime: Vec<bool> = split.demoted.iter().map(|d| !d).collect();
    let mut report = LightSplitReport {
        max_per_probe: settings.max_per_probe,
        ..Default::default()
    };
    if split.auto.iter().any(|&a| a) {
        let cloud = provisional_cloud(&out)?;
        let points = decision_points(tracer, &cands, bake_box, settings.decision_points, seed);
        for l in (0..nc).filter(|&l| split.auto[l]) {
            let Some(light) = rt[l] else { continue };
            let (e_rt, e_bk) = points
                .par_iter()
                .enumerate()
                .map(|(j, &(p, volume))| {
                    let mut ws = WalkState::new();
                    let (idx, w) = cloud.weights_at(p.position, &mut ws);
                    let exact = lum(light.irradiance(p.position, p.normal, None));
                    let key = crate::sampling::hash3(seed, j as u64, l as u64);
                    let truth = if exact > 0.0 {
                        exact
                            * visible_fraction(
                                tracer,
                                p.position,
                                &cands[l],
                                Some(p.normal),
                                settings.occlusion_samples,
                                key,
                            )
                    } else {
                        0.0
                    };
                    let mut v = 0.0;
                    let mut sh = ShRgb::zeros(order);
                    for k in 0..4 {
                        let i = idx[k] as usize;
                        if w[k] != 0.0 {
                            v += w[k] * f32::from(quantize_occlusion(frac[i * nc + l])) / 255.0;
                            sh.add_scaled(&direct[l][i], w[k]);
                        }
                    }
                    let baked = lum(sh.irradiance(p.normal));
                    let a = (exact * v - truth) as f64;
                    let b = (baked - truth) as f64;
                    let volume = f64::from(volume);
                    (volume * a * a, volume * b * b)
                })
                .reduce(|| (0.0, 0.0), |x, y| (x.0 + y.0, x.1 + y.1));
            runtime[l] = e_rt < DECISION_MARGIN * e_bk;
            report.held_out.push((split.candidates[l], e_rt, e_bk));
            if !runtime[l] {
                report.kept_baked.push(split.candidates[l]);
            }
        }
    }

    // Step 4: at most K run-time lights reach a probe.
    let k = settings.max_per_probe as usize;
    'demote: loop {
        for i in 0..probes {
            let reach: Vec<usize> = (0..nc)
                .filter(|&l| runtime[l] && contribution[i * nc + l] > 0.0)
                .collect();
            if reach.len() > k {
                let weakest = reach
                    .iter()
                    .copied()
                    .min_by(|&a, &b| contribution[i * nc + a].total_cmp(&contribution[i * nc + b]))
                    .unwrap_or(reach[0]);
                runtime[weakest] = false;
                report.demoted.push(split.candidates[weakest]);
                continue 'demote;
            }
        }
        break;
    }

    // Step 5: compose.
    for (l, d) in direct.iter().enumerate() {
        if !runtime[l] {
            for (s, d) in out.sh.iter_mut().zip(d) {
                s.add_scaled(d, 1.0);
            }
        }
    }
    let kept: Vec<usize> = (0..nc).filter(|&l| runtime[l]).collect();
    let mut resolved = vec![ResolvedMode::Baked; scene.lights.len()];
    for &i in &split.candidates {
        resolved[i] = ResolvedMode::Demoted;
    }
    let mut lights = Vec::new();
    let mut dense = Vec::with_capacity(probes * kept.len());
    for &l in &kept {
        let i = split.candidates[l];
        resolved[i] = ResolvedMode::Runtime;
        report.runtime.push(i);
        if let Some(light) = rt[l] {
            lights.push(RuntimeLight {
                light,
                group: split.user_groups[i].clone(),
            });
        }
    }
    for i in 0..probes {
        for &l in &kept {
            let c = contribution[i * nc + l];
            dense.push(if c > 0.0 {
                quantize_occlusion(frac[i * nc + l])
            } else {
                0
            });
        }
    }
    report.occlusion_entries = dense.iter().filter(|&&v| v > 0).count();
    let runtime_lights = if lights.is_empty() {
        None
    } else {
        Some(RuntimeLights {
            occlusion: LightOcclusion::from_dense(lights.len(), &dense)?,
            lights,
        })
    };
    regroup(&mut out, split, &direct, &runtime, keep_groups);
    if !keep_split {
        out.direct = None;
        out.indirect = None;
    }
    Ok(Split {
        output: out,
        lights: runtime_lights,
        resolved,
        report,
    })
}

/// About `n` held-out points of the choice in free space of `bake_box`
/// ([`is_evaluation_point`], as `probekit eval`'s), each with a random
/// normal and the volume it stands for (m³): stratified as placement's
/// held-out points ([`held_out_points`]): half of them drawn around the
/// positional candidates, a third of the whole kept in their 1 m balls. A
/// lamp's error sits within a metre of it, where uniform points are few:
/// on the duplex's ~2000 bake 2 000 uniform
/// points kept a 10 cm lamp baked (squared error 703 at run time against
/// 624 baked), and `probekit eval` then put 73 % of the bake's squared
/// error on two points beside it (`rel_rmse` 0.256 against 0.115 with the
/// lamp at run time).
fn decision_points(
    tracer: &Tracer,
    candidates: &[crate::scene::Light],
    bake_box: &Aabb,
    n: u32,
    seed: u64,
) -> Vec<(EvalPoint, f32)> {
    let points = held_out_points(candidates, bake_box, n as usize, seed ^ DECISION_SEED);
    points
        .into_par_iter()
        .enumerate()
        .filter(|(_, (p, _))| is_evaluation_point(tracer, *p))
        .map(|(j, (position, volume))| {
            let mut rng = SampleRng::new(seed ^ DECISION_SEED, 0x4e4f_524d, j as u64);
            let normal = sample_uniform_sphere(rng.next_2d());
            (EvalPoint { position, normal }, volume)
        })
        .collect()
}

/// The capture's groups under the scene's names: candidates' groups
/// summed into their lights' own groups, less the direct light of the
/// lights that run at run time (so the groups still sum to the SH).
fn regroup(
    out: &mut BakeOutput,
    split: &LightSplit,
    direct: &[Vec<ShRgb>],
    runtime: &[bool],
    keep: bool,
) {
    if !keep {
        out.groups.clear();
        out.groups_indirect.clear();
        return;
    }
    let user_of = |name: &str| -> String {
        split
            .capture_groups
            .iter()
            .position(|g| g == name)
            .map_or_else(|| name.to_string(), |i| split.user_groups[i].clone())
    };
    let merge = |groups: &mut Vec<(String, Vec<ShRgb>)>| {
        let mut merged: Vec<(String, Vec<ShRgb>)> = Vec::new();
        for (name, sh) in groups.drain(..) {
            let user = user_of(&name);
            match merged.iter_mut().find(|g| g.0 == user) {
                Some((_, acc)) => {
                    for (a, s) in acc.iter_mut().zip(&sh) {
                        a.add_scaled(s, 1.0);
                    }
                }
                None => merged.push((user, sh)),
            }
        }
        merged.sort_by(|a, b| a.0.cmp(&b.0));
        *groups = merged;
    };
    for (l, &i) in split.candidates.iter().enumerate() {
        if !runtime[l] {
            continue;
        }
        let name = &split.capture_groups[i];
        if let Some((_, g)) = out.groups.iter_mut().find(|g| &g.0 == name) {
            for (s, d) in g.iter_mut().zip(&direct[l]) {
                s.add_scaled(d, -1.0);
            }
        }
    }
    merge(&mut out.groups);
    merge(&mut out.groups_indirect);
}

/// A plain-blend cloud of the captured probes, for the held-out choice
/// (a cloud blends without the probes' validity, so none is read).
fn provisional_cloud(out: &BakeOutput) -> Result<ProbeCloud, crate::pipeline::PipelineError> {
    let valid = probekit_runtime::format::Validity {
        value: 1.0,
        flags: 0,
    };
    let validity = vec![valid; out.captured_positions.len()];
    let file = crate::format::cloud::cloud_file(
        &out.captured_positions,
        &out.sh,
        &validity,
        probekit_runtime::format::Codec::F32,
        "",
    )?;
    ProbeCloud::from_file(&file)
        .map_err(|e| crate::pipeline::PipelineError::Parts(format!("run-time light split: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::capture::tests::{box_tris, light, material, scene_of};
    use crate::scene::LightKind;
    use crate::trace::free_space::SURFACE_CLEARANCE;

    /// The choice's points stand for the volume they sample: inside a
    /// closed room their weights add up to its free volume (the room less
    /// the evaluation's clearance from its walls, a closed form), and those
    /// within 1 m of the lamp, a third of them (2 % of the room's volume),
    /// to the ball's volume.
    #[test]
    fn decision_points_are_dense_at_lamps_and_weigh_their_volume() {
        let half = 3.0;
        let room = box_tris(Vec3::splat(-half), Vec3::splat(half), true, 0);
        let lamp_at = Vec3::new(0.5, 1.0, -0.5);
        let lamp = light(LightKind::Point, lamp_at, Vec3::NEG_Y, 5.0, 0.0);
        let scene = scene_of(vec![room], vec![material(0.5, 0.0)], vec![lamp], Vec3::ZERO);
        let tracer = Tracer::new(&scene);
        let bbox = Aabb::new(Vec3::splat(-half), Vec3::splat(half));
        let points = decision_points(&tracer, &scene.lights, &bbox, 4000, 1);
        let total: f32 = points.iter().map(|p| p.1).sum();
        let free = (2.0 * (half - SURFACE_CLEARANCE)).powi(3);
        assert!(
            (total / free - 1.0).abs() < 0.01,
            "{total} m³ against {free}"
        );
        let near: Vec<f32> = (points.iter())
            .filter(|p| p.0.position.distance(lamp_at) < 1.0)
            .map(|p| p.1)
            .collect();
        let share = near.len() as f32 / points.len() as f32;
        assert!(
            (0.3..0.4).contains(&share),
            "{share} of the points near the lamp"
        );
        let ball = 4.0 / 3.0 * std::f32::consts::PI;
        let sum: f32 = near.iter().sum();
        assert!((sum / ball - 1.0).abs() < 0.02, "{sum} m³ in the 1 m ball");
        for (p, _) in &points {
            assert!((p.normal.length() - 1.0).abs() < 1e-5);
        }
    }
}
