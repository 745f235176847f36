//! The factors that scale a probe's blend weight beyond its barycentric
//! weight and visibility: the brightness weighting (each probe's mean
//! irradiance), the directional brightness (per direction, applied by
//! [`ProbeCloud::sh_at`]'s directional blend) and the fitted probe weights.

use super::{ProbeCloud, ProbeCloudError, MAX_BRIGHTNESS_EXPONENT, PROBE_WEIGHT_RANGE};
use crate::prelude::*;
use glam::{Vec3, Vec4};

impl ProbeCloud {
    baker_only! {
        /// Sets the brightness exponent `α` (0, the default, switches it off;
        /// what it does: [`ProbeCloud::brightness_weighting`]). Errors on a
        /// value outside `0..=`[`MAX_BRIGHTNESS_EXPONENT`] or not a number.
        fn set_brightness_weighting(&mut self, alpha: f32) -> Result<(), ProbeCloudError> {
            if !(0.0..=MAX_BRIGHTNESS_EXPONENT).contains(&alpha) {
                return Err(ProbeCloudError::BrightnessExponent(alpha));
            }
            self.brightness = alpha;
            // What does not depend on the query point, once: each probe's
            // `Ē_i^−α` (+∞ where `Ē_i ≤ 0`, which the floor replaces), and the
            // floor's `(10⁻³)^−α`.
            self.brightness_pow = if alpha > 0.0 {
                self.luminance
                    .iter()
                    .map(|&e| {
                        if e > 0.0 {
                            crate::math::powf(e, -alpha)
                        } else {
                            f32::INFINITY
                        }
                    })
                    .collect()
            } else {
                Vec::new()
            };
            self.brightness_floor = crate::math::powf(1e3, alpha);
            Ok(())
        }
    }

    /// The brightness exponent `α` (0: off): each probe's blend weight is
    /// divided by `Ē_i^α`, `Ē_i` the luminance of its mean irradiance (its DC
    /// coefficient) as the cloud was built — a cloud relit in place
    /// ([`crate::Probes::relight`]) keeps the blend of its baked light, so
    /// relighting stays linear — floored at 10⁻³ of the brightest probe of
    /// the cell, then the weights are renormalized. A file's probe weights
    /// carry the exponent they were fitted for ([`ProbeCloud::from_file`]);
    /// a load can override it ([`crate::BlendOverrides::brightness_exponent`]).
    /// The blend stays a convex combination of the probes' SH, continuous in
    /// `p`, and exact for a constant field; at `α = 1` the blended mean
    /// irradiance is the weighted *harmonic* mean of the probes'
    /// `(Σ b_i/Ē_i)⁻¹`, at most `Ē_j / b_j` for every probe `j`: one bright
    /// probe (one that sees light the point does not, e.g. on a doorway's
    /// lit side next to a dark closet) no longer dominates a dark cell. The
    /// price is a low bias in strong gradients next to lights. Measured on
    /// builtin:demo (BENCHMARKS.md, "Brightness-weighted blending"): `α = 1`
    /// removes the closet and wall leaks of adaptive clouds from ~500 probes
    /// on, for 13 % (525 probes) to 50 % (2100) more rel_rmse; `α = 0.5` is
    /// between. Our own measure, not from a paper.
    pub fn brightness_weighting(&self) -> f32 {
        self.brightness
    }

    baker_only! {
        /// Sets the directional brightness exponent `γ` (0, the default,
        /// switches it off; what it does:
        /// [`ProbeCloud::directional_brightness`]). Errors on a value outside
        /// `0..=`[`MAX_BRIGHTNESS_EXPONENT`] or not a number.
        fn set_directional_brightness(&mut self, gamma: f32) -> Result<(), ProbeCloudError> {
            if !(0.0..=MAX_BRIGHTNESS_EXPONENT).contains(&gamma) {
                return Err(ProbeCloudError::BrightnessExponent(gamma));
            }
            self.directional = gamma;
            Ok(())
        }
    }

    /// The directional brightness exponent `γ` (0: off):
    /// [`ProbeCloud::sh_at`] blends the cell per direction, the weight of
    /// each probe more than `DIRECTIONAL_RATIO` times brighter *for that
    /// direction* than the cell (its weighted harmonic mean) divided by the
    /// excess to the power `γ` (luminances as the cloud was built, so
    /// relighting stays linear), and projects the twelve directions' blends
    /// back to SH (the `directional` module, feature `write`). Where the
    /// mean brightness ([`ProbeCloud::brightness_weighting`]) damps a probe
    /// that is bright on average, this damps a probe bright only towards one
    /// side — a doorway probe seeing a lit corridor, next to a dark closet —
    /// for the normals facing that side. Still one radiance SH per point, a
    /// convex blend per direction, exact for a constant field, and the plain
    /// blend at `γ = 0`. A file's probe weights carry the exponent they were
    /// fitted for and the directional one ([`ProbeCloud::from_file`]); a
    /// load can override it ([`crate::BlendOverrides::directional_exponent`]).
    pub fn directional_brightness(&self) -> f32 {
        self.directional
    }

    baker_only! {
        /// Attaches (or with `None` removes) fitted per-probe blend weights
        /// `s_i`, one per probe, each in [`PROBE_WEIGHT_RANGE`] (what they do:
        /// [`ProbeCloud::probe_weights`]).
        fn set_probe_weights(&mut self, weights: Option<Vec<f32>>) -> Result<(), ProbeCloudError> {
            if let Some(w) = &weights {
                let bad = (w.len() != self.probe_count())
                    .then_some((0, f32::NAN))
                    .or_else(|| {
                        w.iter()
                            .position(|x| !PROBE_WEIGHT_RANGE.contains(x))
                            .map(|i| (i, w[i]))
                    });
                if let Some((index, value)) = bad {
                    return Err(ProbeCloudError::ProbeWeights {
                        count: w.len(),
                        probes: self.probe_count(),
                        index,
                        value,
                    });
                }
            }
            self.probe_weights = weights;
            Ok(())
        }
    }

    /// The fitted per-probe blend weights `s_i`, if the cloud has them
    /// (whether or not they are switched on): probe `i`'s blend weight is
    /// multiplied by `s_i` before the renormalization of
    /// [`ProbeCloud::weights_at`]. The blend stays a convex combination of
    /// the probes' SH, exact for a constant field, and continuous: on a face
    /// the fourth probe's barycentric weight is 0, so both cells blend the
    /// face's three probes alike. `probekit bake` fits them to path-traced
    /// points (`probekit::blend::blend_fit`, the file's `PWGT` section), so
    /// that a probe whose light should not reach its neighbours' space — one
    /// standing in a doorway, seeing a lit corridor, beside a dark closet —
    /// counts less. All weights 1 is the plain blend.
    pub fn probe_weights(&self) -> Option<&[f32]> {
        self.probe_weights.as_deref()
    }

    baker_only! {
        /// Switches the fitted probe weights on (the default) or off; without
        /// weights it has no effect.
        fn set_probe_weighting(&mut self, on: bool) {
            self.probe_weights_on = on;
        }
    }

    /// True when queries apply fitted probe weights (present and on).
    pub fn probe_weighting_enabled(&self) -> bool {
        self.probe_weights_on && self.probe_weights.is_some()
    }

    /// `s_i·Ē_i^−α` for the cell's probes with a non-zero weight in `bary`:
    /// the fitted probe weight (1 when absent or off) times the brightness
    /// factor (1 when off or when no probe is bright); 1 in unused slots.
    ///
    /// The brightness factor of [`ProbeCloud::set_brightness_weighting`],
    /// `max(Ē_k, 10⁻³·top)^−α` with `top` the brightest used probe's `Ē`,
    /// is `min(Ē_k^−α, 10^{3α}·top^−α)`, and `top^−α` is the smallest
    /// `Ē_k^−α` of the cell: both come from the per-probe powers computed
    /// when the exponent is set, so a query takes no power.
    pub(super) fn probe_factors(&self, probes: &[u32; 4], bary: &[f32; 4]) -> [f32; 4] {
        let mut f = [1.0f32; 4];
        if self.brightness > 0.0 {
            let pow = &self.brightness_pow;
            let b: [f32; 4] = core::array::from_fn(|k| {
                if bary[k] != 0.0 {
                    pow[probes[k] as usize]
                } else {
                    f32::INFINITY
                }
            });
            let top = b[0].min(b[1]).min(b[2].min(b[3]));
            // `top` is the brightest's `Ē^−α`: +∞ when no used probe is
            // bright, 0 when one is too bright for `f32`; both mean no
            // brightness weighting.
            if top > 0.0 && top < f32::INFINITY {
                let floor = self.brightness_floor * top;
                for k in 0..4 {
                    if bary[k] != 0.0 {
                        f[k] = b[k].min(floor);
                    }
                }
            }
        }
        if let Some(s) = self
            .probe_weights
            .as_ref()
            .filter(|_| self.probe_weights_on)
        {
            for k in 0..4 {
                if bary[k] != 0.0 {
                    f[k] *= s[probes[k] as usize];
                }
            }
        }
        f
    }

    /// Adds to `out` (bands ≤ 2) the directional blend's departure from the
    /// plain blend of the cell `probes` with blend weights `weights` (see
    /// [`directional`]); `out` holds the plain blend.
    pub(super) fn directional_correction(
        &self,
        probes: &[u32; 4],
        weights: &[f32; 4],
        out: &mut [Vec3],
    ) {
        const NONE: [Vec4; 3] = [Vec4::INFINITY; 3];
        let data = &self.directional_data;
        let used = weights.map(|w| w > 0.0);
        let recip = core::array::from_fn(|k| {
            if used[k] {
                &data.reciprocal_luminance[probes[k] as usize]
            } else {
                &NONE
            }
        });
        let sh = core::array::from_fn(|k| {
            if used[k] {
                self.probe_sh(probes[k] as usize)
            } else {
                &[]
            }
        });
        data.table
            .correct(recip, sh, weights, self.directional, out);
    }
}
