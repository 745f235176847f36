//! The typed report of an evaluation (`probekit eval --json` serialises it).

use super::{
    leaks_at, mean_luminance, metrics, region_leaks_at, region_metrics, unlit_points, worst_points,
    Metrics,
};
use crate::query::{blends_hidden_probes, outside_hull};
use crate::scene::Scene;
use crate::trace::free_space::EvalPoint;
use crate::trace::Tracer;
use glam::Vec3;
use probekit_runtime::cloud::WalkState;
use probekit_runtime::Probes;
use serde::Serialize;
use std::collections::BTreeMap;

/// Error of one prediction against ground truth, overall, per region and at
/// its worst points. Irradiance is linear RGB, not divided by π.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EvalReport {
    /// Points, relative RMSE, p95 relative error and leaks ([`metrics`]).
    #[serde(flatten)]
    pub metrics: Metrics,
    /// Probes (volume samples) of the evaluated file.
    pub probes: usize,
    /// Points no light reaches ([`unlit_points`]).
    pub unlit_points: usize,
    /// Leaks among them.
    pub leaks_unlit: usize,
    /// Clouds: leaks whose blend reaches a probe that geometry hides from
    /// the point ([`blends_hidden_probes`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leaks_through_geometry: Option<usize>,
    /// Clouds: points beyond the probes' hull ([`outside_hull`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub points_outside_hull: Option<usize>,
    /// Clouds: leaks among them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leaks_outside_hull: Option<usize>,
    /// The figures per region of the scene, by name.
    pub regions: BTreeMap<String, RegionReport>,
    /// The points that carry the most squared error, worst first (empty
    /// unless asked for).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub worst: Vec<WorstReport>,
}

/// The figures of one region.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RegionReport {
    /// The region's metrics.
    #[serde(flatten)]
    pub metrics: Metrics,
    /// Clouds: leaks through geometry in the region.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leaks_through_geometry: Option<usize>,
    /// Clouds: leaks beyond the hull in the region.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leaks_outside_hull: Option<usize>,
}

/// One of the worst points.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WorstReport {
    /// Position, metres.
    pub position: [f32; 3],
    /// Normal.
    pub normal: [f32; 3],
    /// Path-traced irradiance.
    pub truth: [f32; 3],
    /// Predicted irradiance.
    pub irradiance: [f32; 3],
    /// Its share of the squared error over all points.
    pub share: f32,
    /// The regions holding it.
    pub regions: Vec<String>,
    /// Clouds: the probes of its blend (weights before any directional
    /// brightness) and each probe's own irradiance for its normal.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blend: Option<Vec<BlendProbe>>,
}

/// A probe of a worst point's blend.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BlendProbe {
    /// Probe index.
    pub probe: usize,
    /// Its position, metres.
    pub position: [f32; 3],
    /// Its blend weight.
    pub weight: f32,
    /// Its own irradiance for the point's normal.
    pub irradiance: [f32; 3],
}

/// The report of `pred`, the irradiance of `probes` at `pts`
/// ([`predict`](super::predict)), against `truth` over `scene`'s regions,
/// with segment tests by `tracer` for the leaks through geometry (clouds),
/// and the `worst` worst points (0: none).
pub fn evaluate(
    scene: &Scene,
    pts: &[EvalPoint],
    pred: &[Vec3],
    truth: &[Vec3],
    tracer: &Tracer,
    worst: usize,
    probes: &Probes,
) -> EvalReport {
    let mean = mean_luminance(truth);
    let (unlit, leaks_unlit) = unlit_points(pred, truth, mean);
    let cloud = probes.cloud();
    let hidden = cloud.map(|c| blends_hidden_probes(c, tracer, pts));
    let outside = cloud.map(|c| outside_hull(c, pts));
    let per_region =
        |flags: &[bool]| region_leaks_at(&scene.regions, pts, pred, truth, mean, flags);
    let through = hidden.as_deref().map(per_region);
    let beyond = outside.as_deref().map(per_region);
    let regions = region_metrics(&scene.regions, pts, pred, truth, mean)
        .into_iter()
        .enumerate()
        .map(|(i, (r, m))| {
            let report = RegionReport {
                metrics: m,
                leaks_through_geometry: through.as_ref().map(|t| t[i]),
                leaks_outside_hull: beyond.as_ref().map(|b| b[i]),
            };
            (r.name.clone(), report)
        })
        .collect();
    let worst = worst_points(pred, truth, worst)
        .into_iter()
        .map(|w| {
            let p = &pts[w.index];
            let blend = match cloud {
                Some(c) => {
                    let (idx, wt) = c.weights_at(p.position, &mut WalkState::new());
                    Some(
                        (0..4)
                            .filter(|&k| wt[k] > 0.0)
                            .map(|k| {
                                let i = idx[k] as usize;
                                BlendProbe {
                                    probe: i,
                                    position: c.mesh().positions()[i].to_array(),
                                    weight: wt[k],
                                    irradiance: probekit_sh::irradiance(c.probe_sh(i), p.normal)
                                        .to_array(),
                                }
                            })
                            .collect(),
                    )
                }
                None => None,
            };
            WorstReport {
                position: p.position.to_array(),
                normal: p.normal.to_array(),
                truth: truth[w.index].to_array(),
                irradiance: pred[w.index].to_array(),
                share: w.share,
                regions: (scene.region_names_at(p.position).into_iter())
                    .map(str::to_string)
                    .collect(),
                blend,
            }
        })
        .collect();
    EvalReport {
        metrics: metrics(pred, truth, mean),
        probes: probes.probe_count(),
        unlit_points: unlit,
        leaks_unlit,
        leaks_through_geometry: hidden.as_deref().map(|h| leaks_at(pred, truth, mean, h)),
        points_outside_hull: outside.as_ref().map(|o| o.iter().filter(|&&f| f).count()),
        leaks_outside_hull: outside.as_deref().map(|o| leaks_at(pred, truth, mean, o)),
        regions,
        worst,
    }
}
