//! Importance sampling of an equirect environment for path tracing.
//!
//! The map is treated as piecewise constant over texels. A texel is chosen
//! with probability proportional to `luminance × ΔΩ` (exact solid angle) by a
//! marginal distribution over rows and a conditional one over columns
//! (Pharr, Jakob & Humphreys, *PBRT* 3rd ed., §13.6.7 and §14.2.4, with
//! solid-angle weights in place of the `sin θ` Jacobian). Inside the texel the
//! direction is uniform in solid angle (uniform in `φ` and in `sin lat`), so
//! the density is exactly `P(texel) / ΔΩ(texel)` with no Jacobian singularity
//! at the poles. A map that is black everywhere falls back to uniform
//! sphere sampling (weights `ΔΩ`).

use super::EnvMap;
use glam::{Vec2, Vec3};
use probekit_sh::LUMINANCE;
use std::f64::consts::PI;

/// A piecewise-constant 2D distribution over the texels of an [`EnvMap`]
/// (weights `luminance × solid angle`); see the [module docs](self).
#[derive(Clone, Debug)]
pub struct EnvSampler {
    map: EnvMap,
    /// `height + 1` cumulative row probabilities, `[0] = 0`, last = 1.
    marginal: Vec<f64>,
    /// Per row, `width + 1` cumulative column probabilities within the row.
    conditional: Vec<f64>,
    /// Per texel probability `P(texel)`.
    prob: Vec<f64>,
    /// `sin` of each row boundary's latitude (`height + 1`, top first).
    sin_lat: Vec<f64>,
}

impl EnvSampler {
    /// Builds the distribution (O(texels)). The map is cloned.
    pub fn new(map: &EnvMap) -> Self {
        let (w, h) = (map.width(), map.height());
        let sin_lat: Vec<f64> = (0..=h)
            .map(|y| (PI * (0.5 - y as f64 / h as f64)).sin())
            .collect();
        let lum_total: f64 = map.texels().iter().map(|t| t.dot(LUMINANCE) as f64).sum();
        let use_lum = lum_total > 0.0;
        let mut weights = vec![0.0f64; w * h];
        for y in 0..h {
            let dw = map.row_solid_angle(y);
            for x in 0..w {
                let l = if use_lum {
                    map.texel(x, y).dot(LUMINANCE) as f64
                } else {
                    1.0
                };
                weights[y * w + x] = l * dw;
            }
        }
        let total: f64 = weights.iter().sum();
        let mut marginal = Vec::with_capacity(h + 1);
        marginal.push(0.0);
        let mut conditional = Vec::with_capacity(h * (w + 1));
        let mut acc = 0.0;
        for y in 0..h {
            let row = &weights[y * w..(y + 1) * w];
            let row_sum: f64 = row.iter().sum();
            let mut c = 0.0;
            conditional.push(0.0);
            for v in row {
                c += v;
                conditional.push(if row_sum > 0.0 { c / row_sum } else { 0.0 });
            }
            acc += row_sum;
            marginal.push(acc / total);
        }
        *marginal.last_mut().expect("h >= 1") = 1.0;
        let prob = weights.iter().map(|v| v / total).collect();
        Self {
            map: map.clone(),
            marginal,
            conditional,
            prob,
            sin_lat,
        }
    }

    /// Draws a direction from uniform numbers `u` in `[0,1)²`: returns the unit
    /// direction, the radiance of its texel (nearest texel, consistent with
    /// the piecewise-constant density), and the density with respect to
    /// solid angle (sr⁻¹). Estimator of `∫ L f dω`: `L·f / pdf`.
    pub fn sample(&self, u: Vec2) -> (Vec3, Vec3, f32) {
        let (w, h) = (self.map.width(), self.map.height());
        let uy = (u.y as f64).clamp(0.0, 1.0);
        let y = (self.marginal.partition_point(|&c| c <= uy).max(1) - 1).min(h - 1);
        let (c0, c1) = (self.marginal[y], self.marginal[y + 1]);
        let vy = if c1 > c0 {
            ((uy - c0) / (c1 - c0)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let cond = &self.conditional[y * (w + 1)..(y + 1) * (w + 1)];
        let ux = (u.x as f64).clamp(0.0, 1.0);
        let x = (cond.partition_point(|&c| c <= ux).max(1) - 1).min(w - 1);
        let (d0, d1) = (cond[x], cond[x + 1]);
        let vx = if d1 > d0 {
            ((ux - d0) / (d1 - d0)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        // uniform in φ across the column and in sin(lat) across the row
        let phi = 2.0 * PI * ((x as f64 + vx) / w as f64 - 0.5);
        let s = self.sin_lat[y] + (self.sin_lat[y + 1] - self.sin_lat[y]) * vy;
        let c = (1.0 - s * s).max(0.0).sqrt();
        let dir = glam::DVec3::new(c * phi.cos(), s, c * phi.sin()).as_vec3();
        let pdf = self.prob[y * w + x] / self.map.row_solid_angle(y);
        (dir, self.map.texel(x, y), pdf as f32)
    }

    /// Density (sr⁻¹) with which [`EnvSampler::sample`] produces unit direction `dir`.
    pub fn pdf(&self, dir: Vec3) -> f32 {
        let (x, y) = self.map.texel_of(dir);
        (self.prob[y * self.map.width() + x] / self.map.row_solid_angle(y)) as f32
    }

    /// The map being sampled.
    pub fn map(&self) -> &EnvMap {
        &self.map
    }
}
