//! `VISM`: per-probe distance moments on an octahedral map, for
//! visibility-aware blending of a probe cloud (DDGI: Majercik et al. 2019,
//! "Dynamic Diffuse Global Illumination with Ray-Traced Irradiance Fields",
//! JCGT 8(2)). The run-time weighting is in [`crate::cloud::visibility`].

use super::codec::{f16_is_non_finite, f16_to_f32};
use super::error::FormatError;
use super::layout::SectionId;
use crate::prelude::*;

/// Largest octahedral map resolution a file may hold (texels per side).
pub const MAX_VISIBILITY_RESOLUTION: u32 = 64;

/// Per-probe distance moments as stored in a `VISM` section.
///
/// For every probe, an octahedral map of `resolution × resolution` texels
/// (texel `(col, row)` at index `row·resolution + col`, row 0 at map
/// coordinate `v = −1`, column 0 at `u = −1`; orientation in
/// [`crate::cloud::visibility::oct_encode`]), each texel two IEEE binary16
/// values: the mean distance `μ` and the mean squared distance `μ2` from the
/// probe to the first surface along the texel's rays, **divided by
/// `max_distance` and `max_distance²`** respectively (so both lie in
/// `[0, 1]`: rays that hit nothing, or hit farther than `max_distance`,
/// count as `max_distance`). Probe after probe in `POSN` order, texel after
/// texel, `μ` before `μ2`.
#[derive(Clone, Debug, PartialEq)]
pub struct DistanceMoments {
    /// Texels per side of each probe's octahedral map (`1..=64`).
    pub resolution: u32,
    /// Distance clamp in metres (finite, > 0); the unit of the stored values.
    pub max_distance: f32,
    /// `probes × resolution² × 2` binary16 bit patterns (see the type docs).
    pub data: Vec<u16>,
}

impl DistanceMoments {
    /// Binary16 values per probe: `2·resolution²`.
    pub fn values_per_probe(&self) -> usize {
        2 * (self.resolution as usize) * (self.resolution as usize)
    }

    /// Number of probes the data covers.
    pub fn probe_count(&self) -> usize {
        self.data
            .len()
            .checked_div(self.values_per_probe())
            .unwrap_or(0)
    }

    /// Every texel decoded to `[μ, μ2]` in metres and square metres, probe
    /// after probe (the layout of [`DistanceMoments::data`]).
    pub fn decode(&self) -> Vec<[f32; 2]> {
        let m = self.max_distance;
        self.data
            .chunks_exact(2)
            .map(|c| [f16_to_f32(c[0]) * m, f16_to_f32(c[1]) * m * m])
            .collect()
    }

    /// Checks the section against the probe count: resolution in range,
    /// `max_distance` finite and positive, one map per probe, every value
    /// finite and in `[0, 1]`.
    pub(super) fn validate(&self, probes: usize) -> Result<(), FormatError> {
        let id = SectionId::VISIBILITY;
        let bad = |element: usize, reason| FormatError::InvalidValue {
            id,
            element: element as u64,
            reason,
        };
        if self.resolution == 0 || self.resolution > MAX_VISIBILITY_RESOLUTION {
            return Err(bad(0, "visibility map resolution outside 1..=64"));
        }
        if !self.max_distance.is_finite() {
            return Err(FormatError::NonFinite { id, element: 0 });
        }
        if self.max_distance <= 0.0 {
            return Err(bad(0, "visibility max distance is not positive"));
        }
        let per = self.values_per_probe();
        if self.data.len() % per != 0 || self.data.len() / per != probes {
            return Err(FormatError::CountMismatch {
                id,
                expected: probes as u64,
                actual: (self.data.len() / per) as u64,
            });
        }
        for (k, &h) in self.data.iter().enumerate() {
            let probe = k / per;
            if f16_is_non_finite(h) {
                return Err(FormatError::NonFinite {
                    id,
                    element: probe as u64,
                });
            }
            let x = f16_to_f32(h);
            // -0.0 is allowed (it is zero).
            if !(0.0..=1.0).contains(&x) {
                return Err(bad(probe, "distance moment outside [0, 1]"));
            }
        }
        Ok(())
    }
}
