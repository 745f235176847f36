//! SH projection of environment maps with exact texel solid angles, and the
//! brute-force reference irradiance.
//!
//! Both treat a map as piecewise constant over its texels and integrate each
//! texel as its centre direction times its exact solid angle (midpoint rule in
//! direction, exact in area). Work is split over rows with rayon; each row's
//! partial sum is computed in f64 and the partial sums are then added in row
//! order on one thread, so results are bit-identical whatever the thread count.

use super::{CubeFace, Cubemap, EnvMap};
use glam::{DVec3, Vec3};
use probekit_sh::basis::{eval_basis_f64, num_coeffs, MAX_COEFFS, MAX_ORDER};
use probekit_sh::ShRgb;
use rayon::prelude::*;

/// One texel as a quadrature point: the unit direction through its centre and
/// its radiance times its exact solid angle (`L·ΔΩ`, radiance × steradians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeightedTexel {
    /// Unit direction of the texel centre.
    pub dir: Vec3,
    /// Radiance × solid angle.
    pub flux: Vec3,
}

/// An environment that can be projected to SH and integrated texel by texel:
/// implemented by [`EnvMap`] and [`Cubemap`].
pub trait Environment: Sync {
    /// Every texel as a [`WeightedTexel`], in a fixed order.
    fn weighted_texels(&self) -> Vec<WeightedTexel>;
    /// Radiance SH of `order` bands with exact texel solid angles.
    fn project(&self, order: usize) -> ShRgb;
}

impl Environment for EnvMap {
    fn weighted_texels(&self) -> Vec<WeightedTexel> {
        let mut out = Vec::with_capacity(self.width() * self.height());
        for y in 0..self.height() {
            let w = self.row_solid_angle(y) as f32;
            for x in 0..self.width() {
                out.push(WeightedTexel {
                    dir: self.texel_direction(x, y),
                    flux: self.texel(x, y) * w,
                });
            }
        }
        out
    }
    fn project(&self, order: usize) -> ShRgb {
        project_equirect(self, order)
    }
}

impl Environment for Cubemap {
    fn weighted_texels(&self) -> Vec<WeightedTexel> {
        let n = self.size();
        let mut out = Vec::with_capacity(6 * n * n);
        for face in CubeFace::ALL {
            for y in 0..n {
                for x in 0..n {
                    out.push(WeightedTexel {
                        dir: self.texel_direction(face, x, y),
                        flux: self.face(face)[y * n + x] * self.texel_solid_angle(x, y) as f32,
                    });
                }
            }
        }
        out
    }
    fn project(&self, order: usize) -> ShRgb {
        project_cubemap(self, order)
    }
}

fn clamp_order(order: usize) -> usize {
    order.clamp(1, MAX_ORDER)
}

fn to_sh(order: usize, acc: &[DVec3]) -> ShRgb {
    let mut sh = ShRgb::zeros(order);
    for (c, a) in sh.coeffs_mut().iter_mut().zip(acc) {
        *c = a.as_vec3();
    }
    sh
}

/// Radiance SH (`order` bands, clamped to `1..=8`) of an equirect map:
/// `c_lm = Σ_texels L(texel) · Y_lm(centre) · ΔΩ(texel)` with the exact solid
/// angle of [`EnvMap::row_solid_angle`]. Parallel over rows, deterministic.
pub fn project_equirect(map: &EnvMap, order: usize) -> ShRgb {
    let order = clamp_order(order);
    let nc = num_coeffs(order);
    let (w, h) = (map.width(), map.height());
    // cos φ, sin φ per column (three.js: φ = 2π(u − ½)).
    let cols: Vec<(f64, f64)> = (0..w)
        .map(|x| {
            let phi = 2.0 * std::f64::consts::PI * ((x as f64 + 0.5) / w as f64 - 0.5);
            (phi.cos(), phi.sin())
        })
        .collect();
    let rows: Vec<[DVec3; MAX_COEFFS]> = (0..h)
        .into_par_iter()
        .map(|y| {
            let lat = std::f64::consts::PI * (0.5 - (y as f64 + 0.5) / h as f64);
            let (sl, cl) = lat.sin_cos();
            let mut acc = [DVec3::ZERO; MAX_COEFFS];
            let mut b = [0.0f64; MAX_COEFFS];
            let row = &map.texels()[y * w..(y + 1) * w];
            for (t, (cp, sp)) in row.iter().zip(&cols) {
                let d = DVec3::new(cl * cp, sl, cl * sp);
                eval_basis_f64(order, d, &mut b);
                let l = t.as_dvec3();
                for i in 0..nc {
                    acc[i] += l * b[i];
                }
            }
            let dw = map.row_solid_angle(y);
            for a in &mut acc[..nc] {
                *a *= dw;
            }
            acc
        })
        .collect();
    let mut total = [DVec3::ZERO; MAX_COEFFS];
    for r in &rows {
        for i in 0..nc {
            total[i] += r[i];
        }
    }
    to_sh(order, &total[..nc])
}

/// Radiance SH (`order` bands, clamped to `1..=8`) of a cubemap, summing
/// every texel with its exact solid angle ([`Cubemap::texel_solid_angle`])
/// directly on the cube (no resampling). Parallel over face rows, deterministic.
pub fn project_cubemap(cube: &Cubemap, order: usize) -> ShRgb {
    let order = clamp_order(order);
    let nc = num_coeffs(order);
    let n = cube.size();
    let rows: Vec<[DVec3; MAX_COEFFS]> = (0..6 * n)
        .into_par_iter()
        .map(|fy| {
            let face = CubeFace::ALL[fy / n];
            let y = fy % n;
            let mut acc = [DVec3::ZERO; MAX_COEFFS];
            let mut b = [0.0f64; MAX_COEFFS];
            for x in 0..n {
                let a = 2.0 * (x as f64 + 0.5) / n as f64 - 1.0;
                let bb = 2.0 * (y as f64 + 0.5) / n as f64 - 1.0;
                let d = face.direction(a as f32, bb as f32).as_dvec3();
                // recompute in f64 for accuracy (direction() is exact for these small integers/n)
                let d = d.normalize();
                eval_basis_f64(order, d, &mut b);
                let l = cube.face(face)[y * n + x].as_dvec3() * cube.texel_solid_angle(x, y);
                for i in 0..nc {
                    acc[i] += l * b[i];
                }
            }
            acc
        })
        .collect();
    let mut total = [DVec3::ZERO; MAX_COEFFS];
    for r in &rows {
        for i in 0..nc {
            total[i] += r[i];
        }
    }
    to_sh(order, &total[..nc])
}

/// Brute-force irradiance `E(n) = Σ_texels L·ΔΩ·max(0, n·ω)` (not divided by
/// π) of an equirect map for each unit normal, over every texel with exact
/// solid angles: the ground truth that SH reconstructions are compared with.
/// Parallel over normals; each normal's sum runs in texel order in f64, so
/// the result does not depend on the thread count. Cost: `normals × texels`
/// multiply-adds (4096 × 512·256 ≈ 5·10⁸).
pub fn reference_irradiance(map: &EnvMap, normals: &[Vec3]) -> Vec<Vec3> {
    reference_irradiance_texels(&map.weighted_texels(), normals)
}

/// [`reference_irradiance`] over any list of quadrature texels (e.g. a
/// [`Cubemap`]'s, via [`Environment::weighted_texels`]).
pub fn reference_irradiance_texels(texels: &[WeightedTexel], normals: &[Vec3]) -> Vec<Vec3> {
    // Structure of arrays for a tight inner loop.
    let dx: Vec<f32> = texels.iter().map(|t| t.dir.x).collect();
    let dy: Vec<f32> = texels.iter().map(|t| t.dir.y).collect();
    let dz: Vec<f32> = texels.iter().map(|t| t.dir.z).collect();
    let fr: Vec<f32> = texels.iter().map(|t| t.flux.x).collect();
    let fg: Vec<f32> = texels.iter().map(|t| t.flux.y).collect();
    let fb: Vec<f32> = texels.iter().map(|t| t.flux.z).collect();
    const CHUNK: usize = 512;
    normals
        .par_iter()
        .map(|n| {
            let mut total = DVec3::ZERO;
            let mut start = 0;
            while start < dx.len() {
                let end = (start + CHUNK).min(dx.len());
                // f32 within a short chunk (auto-vectorised), f64 across chunks.
                let (mut r, mut g, mut b) = (0.0f32, 0.0f32, 0.0f32);
                for i in start..end {
                    let c = (n.x * dx[i] + n.y * dy[i] + n.z * dz[i]).max(0.0);
                    r += c * fr[i];
                    g += c * fg[i];
                    b += c * fb[i];
                }
                total += DVec3::new(r as f64, g as f64, b as f64);
                start = end;
            }
            total.as_vec3()
        })
        .collect()
}
