//! Training points: drawn in free space (half uniform in the bake box, half
//! uniform in the cloud's cells) and captured as radiance SH.

use super::{BlendFitError, BlendFitSettings};
use crate::capture::{Baker, CaptureResult, CaptureSettings};
use crate::sampling::SampleRng;
use crate::scene::Aabb;
use crate::trace::free_space::{is_free, sample_points, SURFACE_CLEARANCE};
use glam::Vec3;
use probekit_runtime::cloud::TetMesh;
use probekit_runtime::format::RuntimeLights;
use probekit_sh::ShRgb;

/// Seed stream of the training points (`"wfit"`), apart from `probekit
/// eval`'s points of the same seed.
const TRAINING_STREAM: u64 = 0x7766_6974;

/// Stream of the per-cell training points' random numbers.
const CELL_STREAM: u64 = 0x6365_6c6c; // "cell"

/// Capture index of the first training point: far above any probe's, so
/// training points never share a probe's random numbers.
const TRAINING_INDEX: usize = 1 << 32;

/// Captured training points: positions (metres) and their radiance SH
/// (empty by default), and the run-time lights of the file being fitted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TrainingSet {
    /// Where each point was captured.
    pub positions: Vec<Vec3>,
    /// Radiance SH at each point (all light, or indirect only, as the cloud
    /// stores). With [`TrainingSet::lights`], all light including theirs:
    /// the combined answer's truth.
    pub sh: Vec<ShRgb>,
    /// The run-time lights of the file being fitted and its probes'
    /// occlusion of them, if it has any: the fit then predicts each point
    /// with the combined answer the runtime gives, the blend of each
    /// probe's SH plus each light's radiance SH at the point
    /// ([`probekit_runtime::rig::Light::add_sh`]) times the probe's visible
    /// fraction of it, so the weights are fitted on what a query returns,
    /// not on the SH part alone.
    pub lights: Option<RuntimeLights>,
    /// Per point, the direct light the capture left out of `sh`
    /// ([`CaptureSettings::exclude_direct`]: the run-time lights'), or
    /// empty when it left none out. The truth the fit predicts is `sh`
    /// plus this; each point's weight in the objective comes from `sh`
    /// alone.
    pub excluded: Vec<ShRgb>,
}

/// Draws `count` training points in free space of `bake_box` (seeded by
/// `fit.seed`) and captures them with `capture` at `fit.samples` samples:
/// all light, or indirect light only when `capture.split_direct` (the
/// convention of the cloud bakes: what `bake --indirect-only` stores). Half are uniform in the box, as `probekit eval`'s points; the
/// other half are uniform in tetrahedra of `mesh` chosen uniformly (not by
/// volume), so every cell has evidence and small cells — where adaptive
/// placement packed probes, next to lights — are sampled densely: a fit that
/// only saw uniform points could shift weight onto a probe beside a light
/// where no point would show the overshoot. `progress(done, total)` counts
/// points. Deterministic (any thread count).
pub fn capture_training_set(
    baker: &Baker,
    bake_box: &Aabb,
    mesh: &TetMesh,
    count: usize,
    capture: &CaptureSettings,
    fit: &BlendFitSettings,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<TrainingSet, BlendFitError> {
    let uniform = count.div_ceil(2);
    capture_training_points(
        baker,
        bake_box,
        mesh,
        [uniform, count - uniform],
        capture,
        fit,
        progress,
    )
}

/// [`capture_training_set`] with its two halves sized apart: `counts[0]`
/// points uniform in the box, `counts[1]` uniform in tetrahedra chosen
/// uniformly (a bake whose placement captured points of free space uses
/// those for the first kind and captures only the second).
pub fn capture_training_points(
    baker: &Baker,
    bake_box: &Aabb,
    mesh: &TetMesh,
    counts: [usize; 2],
    capture: &CaptureSettings,
    fit: &BlendFitSettings,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<TrainingSet, BlendFitError> {
    fit.validate()?;
    let seed = fit.seed ^ TRAINING_STREAM;
    let [uniform, want] = counts;
    let mut pts: Vec<Vec3> = sample_points(baker.tracer(), bake_box, uniform, seed)
        .into_iter()
        .map(|p| p.position)
        .collect();
    let tets = mesh.tets();
    let pos = mesh.positions();
    let mut tries = 0u64;
    let mut cell_points = 0;
    while !tets.is_empty() && cell_points < want && tries < 200 * want as u64 + 1000 {
        let mut rng = SampleRng::new(seed, CELL_STREAM, tries);
        tries += 1;
        let t = &tets[((rng.next_f32() * tets.len() as f32) as usize).min(tets.len() - 1)];
        // Uniform in the simplex: the gaps of three sorted uniforms.
        let mut u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
        u.sort_by(f32::total_cmp);
        let b = [u[0], u[1] - u[0], u[2] - u[1], 1.0 - u[2]];
        let p = (0..4).fold(Vec3::ZERO, |acc, k| acc + b[k] * pos[t[k] as usize]);
        // Not in a sphere light either: captured without the virtual
        // offset, a point there would keep the lamp's radiance.
        if bake_box.contains(p)
            && baker
                .scene()
                .sphere_light_at(p, SURFACE_CLEARANCE)
                .is_none()
            && is_free(baker.tracer(), p, SURFACE_CLEARANCE)
        {
            pts.push(p);
            cell_points += 1;
        }
    }
    if pts.is_empty() {
        if counts == [0, 0] {
            return Ok(TrainingSet::default());
        }
        return Err(BlendFitError::NoTrainingPoints);
    }
    let mut s = capture.clone();
    s.samples = fit.samples;
    // The light left out is reported per group: its direct part.
    let excluding = !capture.exclude_direct.is_empty();
    s.groups = excluding;
    s.split_direct |= excluding;
    // The points keep a clearance from every surface (`is_free`): the
    // virtual offset's pre-pass would trace its rays to leave them where
    // they are.
    s.validity.virtual_offset = false;
    let rs = baker.capture_many(&pts, TRAINING_INDEX, &s, progress)?;
    let excluded = if excluding {
        rs.iter()
            .map(|r| excluded_direct(r, &capture.exclude_direct))
            .collect()
    } else {
        Vec::new()
    };
    let (positions, sh) = rs
        .into_iter()
        .map(|r| {
            let sh = match (capture.split_direct, r.indirect) {
                (true, Some(ind)) => ind,
                _ => r.sh,
            };
            (r.position, sh)
        })
        .unzip();
    Ok(TrainingSet {
        positions,
        sh,
        lights: None,
        excluded,
    })
}

/// The direct light of the groups `names` in `r` (its per-group SH less
/// their scattered part).
fn excluded_direct(r: &CaptureResult, names: &[String]) -> ShRgb {
    let order = r.sh.order();
    let mut c = vec![Vec3::ZERO; order * order];
    for ((name, all), (_, scattered)) in r.groups.iter().zip(&r.groups_indirect) {
        if names.contains(name) {
            for ((o, a), s) in c.iter_mut().zip(all.coeffs()).zip(scattered.coeffs()) {
                *o += *a - *s;
            }
        }
    }
    ShRgb::from_coeffs(c).unwrap_or_else(|| ShRgb::zeros(order))
}
