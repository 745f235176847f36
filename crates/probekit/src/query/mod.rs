//! Querying a baked file from the baker. Every query goes through the
//! runtime's [`Probes`](probekit_runtime::Probes), the type an engine
//! loads, so `probekit query`, `eval`, `render`, rigs, sweeps and the
//! viewer measure what an engine shows. This module adds what the commands
//! choose about a load ([`QueryOptions`]: a volume's interpolation, a
//! cloud's blend overrides, light-group scales, parsed and checked against
//! the file's kind), the irradiance `probekit query` prints
//! ([`QueryReport`]), the barycentric SH blend placement scores with, and
//! what a cloud's blend does at given points (outside the hull, weight on
//! probes hidden by geometry).

mod options;
mod report;

pub use options::{
    check_exponent, parse_blend, parse_group_scales, parse_interp, QueryOptionError, QueryOptions,
};
pub use report::{irradiance_at, Irradiance, QueryReport};

use crate::trace::free_space::{segment_clear, EvalPoint};
use crate::trace::Tracer;
use probekit_runtime::cloud::WalkState;
use probekit_runtime::ProbeCloud;
use probekit_sh::ShRgb;

/// Order-`order` radiance SH blended from the probes `idx` of `sh` with the
/// barycentric weights `w`, in vertex order; vertices of weight 0 (and
/// indices past `sh`) are skipped.
pub(crate) fn blend_sh(sh: &[ShRgb], idx: [u32; 4], w: [f32; 4], order: usize) -> ShRgb {
    let mut acc = ShRgb::zeros(order);
    for k in 0..4 {
        if w[k] != 0.0 {
            if let Some(s) = sh.get(idx[k] as usize) {
                acc.add_scaled(s, w[k]);
            }
        }
    }
    acc
}

/// Whether each point lies outside the convex hull of `cloud`'s probes, in
/// order: it is lit from the outer cell of the closest hull face
/// ([`probekit_runtime::cloud::Location::Outside`]). Probes keep a
/// clearance from surfaces, so the band between a room's walls, floor or
/// ceiling and its outermost probes is such a region; a hull face there
/// can reach past an inner wall (a closet's floor corner lit from a face
/// between probes in the rooms around it: BENCHMARKS.md, "Leaks in sight
/// given a share").
pub fn outside_hull(cloud: &ProbeCloud, points: &[EvalPoint]) -> Vec<bool> {
    let mut st = WalkState::new();
    points
        .iter()
        .map(|p| {
            matches!(
                cloud.mesh().locate(p.position, &mut st),
                probekit_runtime::cloud::Location::Outside { .. }
            )
        })
        .collect()
}

/// Whether each point's blend in `cloud` gives weight to a probe that
/// geometry hides from it (the segment from the point to the probe is
/// blocked, [`crate::trace::free_space::segment_clear`]; the weights of
/// [`ProbeCloud::weights_at`], whose positive ones the directional blend
/// keeps), in order: a leak at such a point is light from behind a wall; one
/// elsewhere is an error of interpolating light in sight (a gradient next to
/// a lamp, say).
pub fn blends_hidden_probes(
    cloud: &ProbeCloud,
    tracer: &Tracer,
    points: &[EvalPoint],
) -> Vec<bool> {
    let pos = cloud.mesh().positions();
    let mut st = WalkState::new();
    points
        .iter()
        .map(|p| {
            let (idx, w) = cloud.weights_at(p.position, &mut st);
            (0..4).any(|k| w[k] > 0.0 && !segment_clear(tracer, p.position, pos[idx[k] as usize]))
        })
        .collect()
}
