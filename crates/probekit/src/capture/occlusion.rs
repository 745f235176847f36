//! # Light occlusion
//!
//! How much of one light a point sees: the *visible fraction* of the light
//! in [0, 1], estimated with stratified shadow rays. A light whose direct
//! term is evaluated at run time (exact unoccluded irradiance, see
//! [`crate::lights::from_scene_light`]) is shadowed by this fraction, stored
//! per probe and blended like the probes' SH.
//!
//! Per kind of light, with `x` the point (metres):
//! - **Point, spot**: one shadow ray to the light's position; the fraction is
//!   its transmittance (0 or 1 through opaque geometry, `1 − α` products
//!   through partly transparent surfaces).
//! - **Sphere**: directions uniform in solid angle in the cone the sphere
//!   subtends from `x`, one shadow ray to the sphere's surface along each:
//!   the visible fraction of the light's solid angle. `x` inside the sphere
//!   sees all of it (1).
//! - **Disk**: points uniform over the disk's area (concentric mapping),
//!   one shadow ray to each: the visible fraction of the light's area. A
//!   point on or behind the disk's plane (the side its `direction` does not
//!   point to) receives none of its light: 0.
//! - **Directional**: with `angular_diameter = 0` one ray towards
//!   `−direction`, unbounded; otherwise directions uniform in solid angle
//!   in the cone of half-angle `angular_diameter/2` about `−direction` (the
//!   sun's disc).
//!
//! The 2-D samples of the sphere, disk and sun cone are the points of a
//! scrambled Sobol' (0,2)-sequence ([`crate::sampling::sobol02_point`]),
//! one scramble per `key`, so `samples` rays are stratified over the light.
//!
//! Shadow rays are the capture's own (the integrator's shadow test, with
//! the same light sampling as its next-event estimation): origin at `x`
//! as given (no offset: offset a point on a surface first, e.g. with
//! [`crate::trace::offset_ray_origin`]), segment shortened at the light's
//! end by [`crate::trace::SHADOW_EPSILON`], unbounded towards a directional
//! light, and the scene's *other* sphere and disk lights (radius and power
//! above zero) block like the capture's, so a probe in free space sees the
//! same visibility the capture gave its direct light. The light itself is
//! recognised among the scene's lights by equality. Each ray counts by the
//! luminance of its RGB transmittance (grey in practice: glass is not
//! tinted).
//!
//! With a receiver normal `n` the fraction is weighted by what each sample
//! contributes to the irradiance at a surface there: sphere and sun-cone
//! directions `ω` by `max(0, n·ω)`; disk points by `max(0, n·ω) cos θ_l /
//! d²` (`θ_l` the angle at the disk, `d` the distance); a point, spot or
//! sharp directional light by `max(0, n·ω)` of its one ray. The estimate is
//! `Σ wᵢ Vᵢ / Σ wᵢ` (0 when every weight is 0), so that the exact
//! unoccluded irradiance × this fraction is the shadowed direct irradiance.

use super::emitters::ShapeLight;
use crate::sampling::{sample_uniform_cone, sobol02_point, sobol02_scramble, Frame};
use crate::scene::{Light, LightKind};
use crate::trace::{Ray, Tracer, SHADOW_EPSILON};
use glam::Vec3;
use probekit_sh::LUMINANCE;
use rayon::prelude::*;

#[cfg(test)]
#[path = "occlusion_tests.rs"]
mod tests;

/// The fraction (in [0, 1]) of `light` visible from the point `x` (metres),
/// estimated with stratified shadow rays through `tracer`'s scene (see the
/// [module docs](self) for the method per kind of light).
///
/// - `normal`: `None` for a point in free space (a probe): the visible
///   fraction of the light's solid angle (sphere, sun cone) or area (disk).
///   `Some(n)` (unit) for a receiver surface: the fraction weighted by each
///   sample's contribution to the irradiance on it, so that exact
///   unoccluded irradiance × fraction = shadowed direct irradiance; 0 when
///   no part of the light is above the surface's horizon.
/// - `samples`: shadow rays for sphere and disk lights and for directional
///   lights with an angular diameter (0 counts as 1); point, spot and sharp
///   directional lights take one ray whatever it is.
/// - `key`: the random key of the rays' scrambled (0,2)-sequence; equal
///   keys give equal results ([`visible_fractions`] uses
///   [`crate::sampling::hash3`]`(seed, point index, light index)`).
///
/// `x` is used as given: offset a point on a surface off it first. A sphere
/// or disk light with radius ≤ 0 (no area) is treated as a point at its
/// position; a disk stays one-sided.
pub fn visible_fraction(
    tracer: &Tracer,
    x: Vec3,
    light: &Light,
    normal: Option<Vec3>,
    samples: u32,
    key: u64,
) -> f32 {
    let blockers = Blockers::of_scene(tracer);
    fraction(tracer, &blockers, x, light, normal, samples, key)
}

/// [`visible_fraction`] of every light from every point, free space
/// (`normal = None`), row-major: entry `i · lights.len() + l` is point `i`
/// and light `l`. The rays of entry `(i, l)` are keyed by
/// [`crate::sampling::hash3`]`(seed, i, l)`; entries are computed in
/// parallel (rayon) and independently, so the result is bit-identical for
/// any thread count. `samples` as in [`visible_fraction`].
pub fn visible_fractions(
    tracer: &Tracer,
    points: &[Vec3],
    lights: &[Light],
    samples: u32,
    seed: u64,
) -> Vec<f32> {
    let nl = lights.len();
    if nl == 0 {
        return Vec::new();
    }
    let blockers = Blockers::of_scene(tracer);
    (0..points.len() * nl)
        .into_par_iter()
        .map(|e| {
            let (i, l) = (e / nl, e % nl);
            let key = crate::sampling::hash3(seed, i as u64, l as u64);
            fraction(tracer, &blockers, points[i], &lights[l], None, samples, key)
        })
        .collect()
}

/// The scene's sphere and disk lights as shadow-ray blockers, as the
/// capture prepares them (`Emitters::new`: finite, power and radius above
/// zero), each with its scene light for recognising the light itself.
struct Blockers<'s> {
    shapes: Vec<(&'s Light, ShapeLight)>,
}

impl<'s> Blockers<'s> {
    fn of_scene(tracer: &Tracer<'s>) -> Self {
        let shapes = tracer
            .scene()
            .lights
            .iter()
            .filter(|l| {
                l.position.is_finite()
                    && l.direction.is_finite()
                    && l.color.is_finite()
                    && l.intensity.is_finite()
                    && (l.color * l.intensity).max_element() > 0.0
                    && l.radius > 0.0
            })
            .filter_map(|l| shape_of(l).map(|s| (l, s)))
            .collect();
        Blockers { shapes }
    }
}

/// The capture's shape of a sphere or disk light of radius > 0 (`None`
/// otherwise). Radiance and group do not matter here.
fn shape_of(l: &Light) -> Option<ShapeLight> {
    let disk = match l.kind {
        LightKind::Sphere => false,
        LightKind::Disk => true,
        _ => return None,
    };
    (l.radius > 0.0).then(|| ShapeLight {
        center: l.position,
        radius: l.radius,
        radiance: Vec3::ONE,
        disk_normal: disk.then(|| l.direction.normalize_or(Vec3::NEG_Y)),
        group: 0,
    })
}

/// The capture's shadow test (`Baker::shadow`): luminance of the
/// transmittance from `from` along unit `wi` over `dist` (∞ allowed),
/// 0 when another sphere or disk light is in the way.
fn shadow(
    tracer: &Tracer,
    blockers: &Blockers,
    light: &Light,
    from: Vec3,
    wi: Vec3,
    dist: f32,
) -> f32 {
    for (l, s) in &blockers.shapes {
        if *l == light {
            continue;
        }
        if let Some(t) = s.intersect(from, wi, 0.0) {
            if t < dist * (1.0 - SHADOW_EPSILON) {
                return 0.0;
            }
        }
    }
    let ray = Ray::new(from, wi);
    let t = if dist.is_finite() {
        tracer.transmittance_ray(&ray, dist * (1.0 - SHADOW_EPSILON))
    } else {
        tracer.transmittance_ray(&ray, f32::INFINITY)
    };
    t.dot(LUMINANCE).clamp(0.0, 1.0)
}

/// Weighted mean `Σ wᵢ Vᵢ / Σ wᵢ` of per-sample `(w, V)` pairs (summed in
/// f64, in sample order); 0 when the weights sum to 0.
#[derive(Default)]
struct Mean {
    wv: f64,
    w: f64,
}

impl Mean {
    fn add(&mut self, w: f32, v: impl FnOnce() -> f32) {
        if w > 0.0 {
            self.wv += w as f64 * v() as f64;
            self.w += w as f64;
        }
    }

    fn get(&self) -> f32 {
        if self.w > 0.0 {
            (self.wv / self.w).clamp(0.0, 1.0) as f32
        } else {
            0.0
        }
    }
}

/// Receiver weight of a direction: 1 in free space, `max(0, n·ω)` on a surface.
fn cos_weight(normal: Option<Vec3>, wi: Vec3) -> f32 {
    normal.map_or(1.0, |n| n.dot(wi).max(0.0))
}

fn fraction(
    tracer: &Tracer,
    blockers: &Blockers,
    x: Vec3,
    light: &Light,
    normal: Option<Vec3>,
    samples: u32,
    key: u64,
) -> f32 {
    let n = samples.max(1);
    let scramble = sobol02_scramble(key, 0);
    let mut mean = Mean::default();
    // One shadow ray to a position (point, spot, area light without area).
    let towards_point = |mean: &mut Mean, p: Vec3| {
        let d = p - x;
        let d2 = d.length_squared();
        if d2 <= 0.0 {
            // At the light: nothing in between.
            mean.add(1.0, || 1.0);
            return;
        }
        let dist = d2.sqrt();
        let wi = d / dist;
        mean.add(cos_weight(normal, wi), || {
            shadow(tracer, blockers, light, x, wi, dist)
        });
    };
    match light.kind {
        LightKind::Point | LightKind::Spot => towards_point(&mut mean, light.position),
        LightKind::Directional => {
            let to_light = -light.direction.normalize_or(Vec3::NEG_Y);
            let half = 0.5 * light.angular_diameter;
            if half > 0.0 {
                // 1 − cos(half) without cancellation; the cone at most a hemisphere.
                let s = (0.5 * half.min(std::f32::consts::FRAC_PI_2)).sin();
                let omc = 2.0 * s * s;
                let frame = Frame::from_z(to_light);
                for i in 0..n {
                    let u = sobol02_point(i, scramble);
                    let wi = frame.to_world(sample_uniform_cone(u, omc)).normalize();
                    mean.add(cos_weight(normal, wi), || {
                        shadow(tracer, blockers, light, x, wi, f32::INFINITY)
                    });
                }
            } else {
                mean.add(cos_weight(normal, to_light), || {
                    shadow(tracer, blockers, light, x, to_light, f32::INFINITY)
                });
            }
        }
        LightKind::Sphere | LightKind::Disk => {
            let Some(shape) = shape_of(light) else {
                if light.kind == LightKind::Disk {
                    let axis = light.direction.normalize_or(Vec3::NEG_Y);
                    if (x - light.position).dot(axis) <= 0.0 {
                        return 0.0;
                    }
                }
                towards_point(&mut mean, light.position);
                return mean.get();
            };
            match shape.disk_normal {
                None => {
                    let r2 = shape.radius * shape.radius;
                    if (x - shape.center).length_squared() <= r2 {
                        return 1.0;
                    }
                }
                Some(axis) => {
                    if (x - shape.center).dot(axis) <= 0.0 {
                        return 0.0;
                    }
                }
            }
            for i in 0..n {
                // The capture's light sample: uniform in the subtended cone
                // (sphere) or over the area (disk).
                let Some(ls) = shape.sample(x, sobol02_point(i, scramble)) else {
                    continue;
                };
                let w = match shape.disk_normal {
                    None => cos_weight(normal, ls.wi),
                    Some(axis) if normal.is_some() => {
                        let cos_l = -axis.dot(ls.wi);
                        cos_weight(normal, ls.wi) * cos_l.max(0.0) / (ls.dist * ls.dist)
                    }
                    Some(_) => 1.0,
                };
                mean.add(w, || shadow(tracer, blockers, light, x, ls.wi, ls.dist));
            }
        }
    }
    mean.get()
}
