//! Run-time lights (`LITE`) and the probes' occlusion of them (`OCCL`).
//!
//! A bake may leave the *direct* light of some lights out of the probes'
//! SH: small, bright, local lights whose `1/d²` fall-off and dependence on
//! the normal no probe spacing resolves. An engine evaluates them exactly
//! at run time instead. Each probe stores, per such light that reaches it,
//! the fraction of the light it sees (its occlusion, 8 bits); a query
//! blends those fractions with the same weights as the SH:
//!
//! `E(x, n) = E_SH(x, n) + Σ_l E_l(x, n) · Σ_i w_i(x) · v_{i,l}`
//!
//! with `E_l` the light's exact unoccluded irradiance
//! ([`crate::rig::Light::irradiance`]), `w_i` the blend weights of the
//! probes around `x` and `v_{i,l}` probe `i`'s visible fraction of light
//! `l`. The product is an approximation: the visible fraction is measured
//! at the probe over the light's solid angle (or area), not cosine-weighted
//! at the receiver. The light's bounce light stays in the SH, in the light's
//! group, so scaling that group scales the bounce with the light.

use super::error::FormatError;
use super::layout::{SectionId, MAX_RUNTIME_LIGHTS};
use crate::prelude::*;
use crate::rig::Light;

/// One light evaluated at run time.
#[derive(Clone, Debug, PartialEq)]
pub struct RuntimeLight {
    /// The light, in world space (metres; intensity × colour in W/sr, or a
    /// directional light's irradiance in W/m²).
    pub light: Light,
    /// The light group its bounce light was baked into (the scene's
    /// `group`, or `"default"`): scale that group when dimming the light.
    pub group: String,
}

/// The lights a file leaves to run time and each probe's occlusion of them.
#[derive(Clone, Debug, PartialEq)]
pub struct RuntimeLights {
    /// The lights (at most [`MAX_RUNTIME_LIGHTS`]).
    pub lights: Vec<RuntimeLight>,
    /// Per probe, the visible fraction of each light that reaches it.
    pub occlusion: LightOcclusion,
}

/// Each probe's occlusion of the run-time lights, sparse: for each probe the
/// lights that reach it, in increasing light order, with their visible
/// fraction quantised to `1..=255` (`value / 255`). A light not listed at a
/// probe does not reach it (fully occluded, or too dim there to matter).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LightOcclusion {
    /// Entries per probe.
    counts: Vec<u8>,
    /// `[light, value]` pairs, probe by probe.
    entries: Vec<[u8; 2]>,
    /// Start of each probe's entries (`counts`' prefix sums), one more than
    /// the probes.
    offsets: Vec<u32>,
}

/// Quantises a visible fraction in `[0, 1]` to 8 bits (round to nearest; a
/// NaN is 0).
pub fn quantize_occlusion(v: f32) -> u8 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    (v * 255.0 + 0.5) as u8
}

impl LightOcclusion {
    /// From one row of `lights` quantised values per probe (row-major,
    /// `values.len() = probes × lights`); zeros are dropped. Errors if the
    /// length is not a multiple of `lights`, or more than
    /// [`MAX_RUNTIME_LIGHTS`] lights.
    pub fn from_dense(lights: usize, values: &[u8]) -> Result<Self, FormatError> {
        if lights > MAX_RUNTIME_LIGHTS {
            return Err(FormatError::Unrepresentable(
                "more than 255 run-time lights",
            ));
        }
        if lights == 0 {
            return Ok(Self::default());
        }
        if values.len() % lights != 0 {
            return Err(FormatError::Unrepresentable(
                "occlusion values are not a whole number of rows",
            ));
        }
        let mut counts = Vec::with_capacity(values.len() / lights);
        let mut entries = Vec::new();
        for row in values.chunks_exact(lights) {
            let before = entries.len();
            for (l, &v) in row.iter().enumerate() {
                if v > 0 {
                    entries.push([l as u8, v]);
                }
            }
            counts.push((entries.len() - before) as u8);
        }
        Ok(Self::from_parts(counts, entries))
    }

    /// From the stored arrays (checked by [`LightOcclusion::validate`]).
    pub(crate) fn from_parts(counts: Vec<u8>, entries: Vec<[u8; 2]>) -> Self {
        let mut offsets = Vec::with_capacity(counts.len() + 1);
        let mut at = 0u32;
        offsets.push(0);
        for &c in &counts {
            at = at.saturating_add(u32::from(c));
            offsets.push(at);
        }
        Self {
            counts,
            entries,
            offsets,
        }
    }

    /// Number of probes.
    pub fn probe_count(&self) -> usize {
        self.counts.len()
    }

    /// Entries per probe.
    pub fn counts(&self) -> &[u8] {
        &self.counts
    }

    /// Every `[light, value]` pair, probe by probe.
    pub fn entries(&self) -> &[[u8; 2]] {
        &self.entries
    }

    /// Probe `i`'s `[light, value]` pairs (empty past the end).
    pub fn probe(&self, i: usize) -> &[[u8; 2]] {
        match (self.offsets.get(i), self.offsets.get(i + 1)) {
            (Some(&a), Some(&b)) => self.entries.get(a as usize..b as usize).unwrap_or(&[]),
            _ => &[],
        }
    }

    /// Probe `i`'s visible fraction of light `l` (0 where not stored).
    pub fn value(&self, i: usize, l: usize) -> f32 {
        self.probe(i)
            .iter()
            .find(|e| e[0] as usize == l)
            .map_or(0.0, |e| f32::from(e[1]) / 255.0)
    }

    /// Dense visible fractions, `probes × lights`, row-major.
    pub fn to_dense(&self, lights: usize) -> Vec<f32> {
        let mut out = vec![0.0f32; self.counts.len() * lights];
        for i in 0..self.counts.len() {
            for e in self.probe(i) {
                if let Some(o) = out.get_mut(i * lights + e[0] as usize) {
                    *o = f32::from(e[1]) / 255.0;
                }
            }
        }
        out
    }

    /// Checks the table against `probes` probes and `lights` lights: one
    /// count per probe, counts summing to the entries, light indices below
    /// `lights` and increasing within a probe, values non-zero.
    pub(crate) fn validate(&self, probes: usize, lights: usize) -> Result<(), FormatError> {
        let id = SectionId::LIGHT_OCCLUSION;
        if self.counts.len() != probes {
            return Err(FormatError::CountMismatch {
                id,
                expected: probes as u64,
                actual: self.counts.len() as u64,
            });
        }
        let total: u64 = self.counts.iter().map(|&c| u64::from(c)).sum();
        if total != self.entries.len() as u64 {
            return Err(FormatError::CountMismatch {
                id,
                expected: total,
                actual: self.entries.len() as u64,
            });
        }
        for i in 0..probes {
            let row = self.probe(i);
            for (k, e) in row.iter().enumerate() {
                let bad = |reason| FormatError::InvalidValue {
                    id,
                    element: i as u64,
                    reason,
                };
                if e[0] as usize >= lights {
                    return Err(bad("occlusion of a light the file does not hold"));
                }
                if e[1] == 0 {
                    return Err(bad("occlusion entry of value 0 (not stored)"));
                }
                if k > 0 && row[k - 1][0] >= e[0] {
                    return Err(bad(
                        "occlusion entries of a probe not in increasing light order",
                    ));
                }
            }
        }
        Ok(())
    }
}

impl RuntimeLights {
    /// Checks the lights (finite, radii > 0, unit directions, spot cones
    /// in order, at most [`MAX_RUNTIME_LIGHTS`]) and the occlusion table
    /// against `probes` probes.
    pub(crate) fn validate(&self, probes: usize) -> Result<(), FormatError> {
        let id = SectionId::RUNTIME_LIGHTS;
        if self.lights.is_empty() || self.lights.len() > MAX_RUNTIME_LIGHTS {
            return Err(FormatError::InvalidValue {
                id,
                element: 0,
                reason: "a file holds 1 to 255 run-time lights",
            });
        }
        for (k, l) in self.lights.iter().enumerate() {
            if let Err(reason) = check_light(&l.light) {
                return Err(FormatError::InvalidValue {
                    id,
                    element: k as u64,
                    reason,
                });
            }
            if l.group.is_empty() || u32::try_from(l.group.len()).is_err() {
                return Err(FormatError::InvalidValue {
                    id,
                    element: k as u64,
                    reason: "a run-time light's group name is empty or too long",
                });
            }
        }
        self.occlusion.validate(probes, self.lights.len())
    }
}

/// Why `light` cannot be evaluated, if it cannot.
fn check_light(light: &Light) -> Result<(), &'static str> {
    let unit = |d: glam::Vec3| d.is_finite() && (d.length() - 1.0).abs() < 1e-3;
    let intensity = |i: glam::Vec3| i.is_finite() && i.min_element() >= 0.0;
    let ok = match *light {
        Light::Sphere {
            position,
            radius,
            intensity: i,
        } => position.is_finite() && radius.is_finite() && radius > 0.0 && intensity(i),
        Light::Point {
            position,
            intensity: i,
        } => position.is_finite() && intensity(i),
        Light::Spot {
            position,
            direction,
            inner_deg,
            outer_deg,
            intensity: i,
        } => {
            position.is_finite()
                && unit(direction)
                && (0.0..=180.0).contains(&inner_deg)
                && inner_deg <= outer_deg
                && outer_deg > 0.0
                && outer_deg <= 180.0
                && intensity(i)
        }
        Light::Disk {
            position,
            direction,
            radius,
            intensity: i,
        } => {
            position.is_finite()
                && unit(direction)
                && radius.is_finite()
                && radius > 0.0
                && intensity(i)
        }
        Light::Directional {
            direction,
            irradiance,
        } => unit(direction) && intensity(irradiance),
    };
    if ok {
        Ok(())
    } else {
        Err("a run-time light with a non-finite value, a radius ≤ 0, a direction not of unit length or a spot cone out of order")
    }
}

/// A light's kind id in `LITE` and its 16 words after the kind (see
/// `docs/file-format.md`): kind, name length, position, direction, radius,
/// inner and outer cone (degrees), intensity, two zero words.
pub(crate) fn light_words(light: &Light) -> (u32, [f32; 13]) {
    let z = glam::Vec3::ZERO;
    let (kind, p, d, r, inner, outer, i) = match *light {
        Light::Sphere {
            position,
            radius,
            intensity,
        } => (0, position, z, radius, 0.0, 0.0, intensity),
        Light::Point {
            position,
            intensity,
        } => (1, position, z, 0.0, 0.0, 0.0, intensity),
        Light::Spot {
            position,
            direction,
            inner_deg,
            outer_deg,
            intensity,
        } => (2, position, direction, 0.0, inner_deg, outer_deg, intensity),
        Light::Disk {
            position,
            direction,
            radius,
            intensity,
        } => (3, position, direction, radius, 0.0, 0.0, intensity),
        Light::Directional {
            direction,
            irradiance,
        } => (4, z, direction, 0.0, 0.0, 0.0, irradiance),
    };
    (
        kind,
        [
            p.x, p.y, p.z, d.x, d.y, d.z, r, inner, outer, i.x, i.y, i.z, 0.0,
        ],
    )
}

/// The light of kind id `kind` from its words ([`light_words`]); `None`
/// for an unknown kind.
pub(crate) fn light_from_words(kind: u32, w: &[f32; 13]) -> Option<Light> {
    let p = glam::Vec3::new(w[0], w[1], w[2]);
    let d = glam::Vec3::new(w[3], w[4], w[5]);
    let i = glam::Vec3::new(w[9], w[10], w[11]);
    Some(match kind {
        0 => Light::Sphere {
            position: p,
            radius: w[6],
            intensity: i,
        },
        1 => Light::Point {
            position: p,
            intensity: i,
        },
        2 => Light::Spot {
            position: p,
            direction: d,
            inner_deg: w[7],
            outer_deg: w[8],
            intensity: i,
        },
        3 => Light::Disk {
            position: p,
            direction: d,
            radius: w[6],
            intensity: i,
        },
        4 => Light::Directional {
            direction: d,
            irradiance: i,
        },
        _ => return None,
    })
}
