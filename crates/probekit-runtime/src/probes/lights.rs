//! The run-time light term of a query: each run-time light's exact
//! unoccluded irradiance times the probes' visible fractions of it, blended
//! with the SH's weights (`crate::format::RuntimeLights`, module docs).

use crate::format::{ProbeSet, RuntimeLight};
use crate::prelude::*;
use glam::Vec3;

/// A file's run-time lights, ready for queries.
#[derive(Clone, Debug)]
pub(super) struct LightTerm {
    lights: Vec<RuntimeLight>,
    /// Visible fractions, `probes × lights`, row-major.
    occlusion: Vec<f32>,
    /// Each light's RGB scale from its group's relighting (1 as baked).
    scales: Vec<Vec3>,
}

impl LightTerm {
    /// The run-time lights of `probes` (`None` where it has none).
    pub(super) fn new(probes: &ProbeSet) -> Option<Self> {
        let r = probes.runtime_lights.as_ref()?;
        Some(Self {
            occlusion: r.occlusion.to_dense(r.lights.len()),
            lights: r.lights.clone(),
            scales: vec![Vec3::ONE; r.lights.len()],
        })
    }

    /// Scales each light by `scale_of` its group (relighting: the light
    /// scales with the bounce light its group holds).
    pub(super) fn set_group_scales(&mut self, scale_of: impl Fn(&str) -> Vec3) {
        for (s, l) in self.scales.iter_mut().zip(&self.lights) {
            *s = scale_of(&l.group);
        }
    }

    pub(super) fn lights(&self) -> &[RuntimeLight] {
        &self.lights
    }

    /// Light `l`'s visible fraction blended with `weights` of `probes`.
    #[inline]
    fn blended(&self, l: usize, probes: &[u32], weights: &[f32]) -> f32 {
        let n = self.lights.len();
        let mut v = 0.0;
        for (&i, &w) in probes.iter().zip(weights) {
            if w != 0.0 {
                v += w * self
                    .occlusion
                    .get(i as usize * n + l)
                    .copied()
                    .unwrap_or(0.0);
            }
        }
        v
    }

    /// Every light's blended visible fraction into `out` (one per light).
    pub(super) fn occlusion_into(&self, probes: &[u32], weights: &[f32], out: &mut [f32]) {
        for (l, o) in out.iter_mut().enumerate().take(self.lights.len()) {
            *o = self.blended(l, probes, weights);
        }
    }

    /// `Σ_l E_l(p, n) · v_l`: the lights' exact irradiance at `p` for unit
    /// normal `n` times their blended visible fractions. A light no probe of
    /// the blend sees costs no evaluation.
    pub(super) fn irradiance(&self, probes: &[u32], weights: &[f32], p: Vec3, n: Vec3) -> Vec3 {
        let mut e = Vec3::ZERO;
        for (l, r) in self.lights.iter().enumerate() {
            let v = self.blended(l, probes, weights);
            if v > 0.0 {
                e += v * self.scales[l] * r.light.irradiance(p, n, None);
            }
        }
        e
    }
}
