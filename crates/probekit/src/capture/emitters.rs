//! Light sources as the path tracer sees them: delta lights (point, spot,
//! directional), area lights that rays can hit (sphere, disk, emissive
//! triangles) and the environment, each with sampling routines and the
//! densities multiple importance sampling needs.
//!
//! Units (the scene format's, `docs/scene-format.md`): 1 cd = 1 W/sr of radiant intensity, lux =
//! W/m²; sphere and disk lights have uniform radiance `I/(π r²)`.

use super::BakeError;
use crate::env::{EnvMap, EnvSampler};
use crate::sampling::{
    cone_one_minus_cos, sample_uniform_cone, sample_uniform_disk_concentric,
    sample_uniform_triangle, uniform_cone_pdf, Frame,
};
use crate::scene::{LightKind, Scene};
use glam::{Quat, Vec2, Vec3};
use probekit_sh::LUMINANCE;
use std::f32::consts::PI;

/// Group name of analytic lights without a `group`.
pub const DEFAULT_GROUP: &str = "default";
/// Group name of emissive triangles.
pub const EMISSIVE_GROUP: &str = "emissive";
/// Group name of the environment (sky).
pub const ENVIRONMENT_GROUP: &str = "environment";

/// A light that no ray can hit: its contribution is added analytically.
#[derive(Clone, Debug)]
pub(crate) enum DeltaLight {
    /// Point or spot light at `position`, intensity `intensity` (RGB candela).
    Point {
        position: Vec3,
        intensity: Vec3,
        /// Spot axis (the way light travels) and `(cos inner, cos outer)`, `None` for points.
        spot: Option<(Vec3, f32, f32)>,
        group: u16,
    },
    /// Light from infinitely far away; `to_light` is the unit direction towards it.
    Directional {
        to_light: Vec3,
        irradiance: Vec3,
        group: u16,
    },
}

impl DeltaLight {
    /// Incident direction, irradiance arriving at `p` on a surface facing the
    /// light, and the distance to the light (∞ for directional).
    pub(crate) fn incident(&self, p: Vec3) -> Option<(Vec3, Vec3, f32)> {
        match *self {
            DeltaLight::Point {
                position,
                intensity,
                spot,
                ..
            } => {
                let d = position - p;
                let d2 = d.length_squared();
                if d2 <= 0.0 {
                    return None;
                }
                let dist = d2.sqrt();
                let wi = d / dist;
                let falloff = match spot {
                    None => 1.0,
                    Some((axis, ci, co)) => spot_falloff(axis.dot(-wi), ci, co),
                };
                if falloff <= 0.0 {
                    return None;
                }
                Some((wi, intensity * (falloff / d2), dist))
            }
            DeltaLight::Directional {
                to_light,
                irradiance,
                ..
            } => Some((to_light, irradiance, f32::INFINITY)),
        }
    }

    pub(crate) fn group(&self) -> u16 {
        match *self {
            DeltaLight::Point { group, .. } | DeltaLight::Directional { group, .. } => group,
        }
    }
}

/// The KHR_lights_punctual spot ramp: 1 inside the inner cone, 0 outside the
/// outer, `((cos θ − cos outer)/(cos inner − cos outer))²` between.
pub(crate) fn spot_falloff(cos_theta: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if cos_theta >= cos_inner {
        1.0
    } else if cos_theta <= cos_outer || cos_inner <= cos_outer {
        0.0
    } else {
        let x = (cos_theta - cos_outer) / (cos_inner - cos_outer);
        x * x
    }
}

/// A sphere or one-sided disk light of uniform radiance.
#[derive(Clone, Debug)]
pub(crate) struct ShapeLight {
    pub center: Vec3,
    pub radius: f32,
    pub radiance: Vec3,
    /// `Some(normal)` for a disk emitting towards `normal`; `None` for a sphere.
    pub disk_normal: Option<Vec3>,
    pub group: u16,
}

/// A light sample: direction, distance to the sampled point, radiance and
/// solid-angle density.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightSample {
    pub wi: Vec3,
    pub dist: f32,
    pub radiance: Vec3,
    pub pdf: f32,
}

impl ShapeLight {
    /// Nearest ray parameter `t > t_min` where the unit-direction ray hits the shape.
    pub(crate) fn intersect(&self, o: Vec3, d: Vec3, t_min: f32) -> Option<f32> {
        match self.disk_normal {
            None => {
                let oc = o - self.center;
                let b = oc.dot(d);
                let c = oc.length_squared() - self.radius * self.radius;
                let disc = b * b - c;
                if disc < 0.0 {
                    return None;
                }
                let s = disc.sqrt();
                // numerically stable pair of roots
                let t0 = -b - s;
                let t1 = -b + s;
                if t0 > t_min {
                    Some(t0)
                } else if t1 > t_min {
                    Some(t1)
                } else {
                    None
                }
            }
            Some(n) => {
                let denom = n.dot(d);
                if denom.abs() < 1e-12 {
                    return None;
                }
                let t = (self.center - o).dot(n) / denom;
                if t <= t_min {
                    return None;
                }
                let p = o + d * t;
                ((p - self.center).length_squared() <= self.radius * self.radius).then_some(t)
            }
        }
    }

    /// Radiance leaving the shape towards a ray travelling along `d` that hit it.
    pub(crate) fn radiance_towards(&self, d: Vec3) -> Vec3 {
        match self.disk_normal {
            None => self.radiance,
            Some(n) if n.dot(d) < 0.0 => self.radiance,
            Some(_) => Vec3::ZERO,
        }
    }

    /// Samples a direction from `p` towards the light: sphere lights uniformly
    /// within the subtended cone (pbrt-v4 `SphereLight`/`Sphere::Sample`
    /// by solid angle), disks uniformly by area converted to solid angle.
    pub(crate) fn sample(&self, p: Vec3, u: Vec2) -> Option<LightSample> {
        match self.disk_normal {
            None => {
                let oc = self.center - p;
                let d2 = oc.length_squared();
                let r2 = self.radius * self.radius;
                if d2 <= r2 {
                    return None; // inside the light: not sampled (nor hit from inside)
                }
                let d = d2.sqrt();
                let omc = cone_one_minus_cos(r2 / d2);
                let frame = Frame::from_z(oc / d);
                let wi = frame.to_world(sample_uniform_cone(u, omc)).normalize();
                let t = self
                    .intersect(p, wi, 0.0)
                    .unwrap_or_else(|| (d2 - r2).max(0.0).sqrt());
                Some(LightSample {
                    wi,
                    dist: t,
                    radiance: self.radiance,
                    pdf: uniform_cone_pdf(omc),
                })
            }
            Some(n) => {
                let frame = Frame::from_z(n);
                let q2 = sample_uniform_disk_concentric(u) * self.radius;
                let q = self.center + frame.x * q2.x + frame.y * q2.y;
                let v = q - p;
                let dist2 = v.length_squared();
                if dist2 <= 0.0 {
                    return None;
                }
                let dist = dist2.sqrt();
                let wi = v / dist;
                let cos_l = -n.dot(wi);
                if cos_l <= 0.0 {
                    return None;
                }
                Some(LightSample {
                    wi,
                    dist,
                    radiance: self.radiance,
                    pdf: dist2 / (cos_l * PI * self.radius * self.radius),
                })
            }
        }
    }

    /// Solid-angle density with which [`ShapeLight::sample`] from `p` yields
    /// unit direction `wi`, which hit the light at distance `t`.
    pub(crate) fn pdf(&self, p: Vec3, wi: Vec3, t: f32) -> f32 {
        match self.disk_normal {
            None => {
                let d2 = (self.center - p).length_squared();
                let r2 = self.radius * self.radius;
                if d2 <= r2 {
                    return 0.0;
                }
                uniform_cone_pdf(cone_one_minus_cos(r2 / d2))
            }
            Some(n) => {
                let cos_l = -n.dot(wi);
                if cos_l <= 0.0 {
                    return 0.0;
                }
                t * t / (cos_l * PI * self.radius * self.radius)
            }
        }
    }
}

/// The environment: black, a uniform colour, or an importance-sampled map.
pub(crate) enum Environment {
    Black,
    Uniform(Vec3),
    Map {
        sampler: Box<EnvSampler>,
        /// Multiplier on the map.
        scale: f32,
        /// Rotation taking a world direction to map space.
        map_from_world: Quat,
        world_from_map: Quat,
    },
}

impl Environment {
    /// Radiance arriving from world direction `d` (unit). For a map it is the
    /// nearest texel, matching the piecewise-constant density of
    /// [`EnvSampler`], so both MIS strategies estimate the same function.
    pub(crate) fn radiance(&self, d: Vec3) -> Vec3 {
        match self {
            Environment::Black => Vec3::ZERO,
            Environment::Uniform(c) => *c,
            Environment::Map {
                sampler,
                scale,
                map_from_world,
                ..
            } => {
                let m = sampler.map();
                let (x, y) = m.texel_of(*map_from_world * d);
                m.texel(x, y) * *scale
            }
        }
    }

    /// True when light sampling is worthwhile (a map; a uniform sky is
    /// sampled perfectly well by the BSDF/probe directions alone).
    pub(crate) fn is_sampled(&self) -> bool {
        matches!(self, Environment::Map { .. })
    }

    pub(crate) fn is_black(&self) -> bool {
        match self {
            Environment::Black => true,
            Environment::Uniform(c) => c.max_element() <= 0.0,
            Environment::Map { scale, .. } => *scale <= 0.0,
        }
    }

    /// Importance-samples a direction (only for maps).
    pub(crate) fn sample(&self, u: Vec2) -> Option<LightSample> {
        match self {
            Environment::Map {
                sampler,
                scale,
                world_from_map,
                ..
            } => {
                let (d, l, pdf) = sampler.sample(u);
                (pdf > 0.0).then(|| LightSample {
                    wi: (*world_from_map * d).normalize(),
                    dist: f32::INFINITY,
                    radiance: l * *scale,
                    pdf,
                })
            }
            _ => None,
        }
    }

    /// Density of [`Environment::sample`] for world direction `d`.
    pub(crate) fn pdf(&self, d: Vec3) -> f32 {
        match self {
            Environment::Map {
                sampler,
                map_from_world,
                ..
            } => sampler.pdf(*map_from_world * d),
            _ => 0.0,
        }
    }
}

/// Every light of a scene, prepared for sampling, and the light-group names.
pub(crate) struct Emitters {
    pub delta: Vec<DeltaLight>,
    pub shapes: Vec<ShapeLight>,
    /// Emissive triangles: scene triangle index and cumulative selection probability.
    pub tri_index: Vec<u32>,
    pub tri_cdf: Vec<f32>,
    /// Per scene triangle: probability of choosing it (0 if not emissive); empty if none.
    pub tri_prob: Vec<f32>,
    pub emissive_group: u16,
    pub env: Environment,
    pub env_group: u16,
    /// Sorted, unique group names; indices are the `group` fields above.
    pub groups: Vec<String>,
}

impl Emitters {
    /// Prepares the scene's lights and loads its environment map.
    pub(crate) fn new(scene: &Scene) -> Result<Self, BakeError> {
        let names: Vec<String> = scene
            .lights
            .iter()
            .map(|l| l.group.clone().unwrap_or_else(|| DEFAULT_GROUP.to_string()))
            .collect();
        Self::with_light_groups(scene, &names)
    }

    /// [`Emitters::new`] with light `i` in group `light_groups[i]` instead
    /// of its own `group` (one name per light).
    pub(crate) fn with_light_groups(
        scene: &Scene,
        light_groups: &[String],
    ) -> Result<Self, BakeError> {
        let mut names: Vec<String> = light_groups.to_vec();
        names.push(EMISSIVE_GROUP.into());
        names.push(ENVIRONMENT_GROUP.into());
        names.sort();
        names.dedup();
        let gi = |n: &str| names.iter().position(|x| x == n).expect("group listed") as u16;
        let mut delta = Vec::new();
        let mut shapes = Vec::new();
        for (i, l) in scene.lights.iter().enumerate() {
            let bad = |what: &str| BakeError::BadLight {
                index: i,
                message: what.to_string(),
            };
            if !(l.position.is_finite()
                && l.direction.is_finite()
                && l.color.is_finite()
                && l.intensity.is_finite())
            {
                return Err(bad("non-finite position, direction, colour or intensity"));
            }
            let group = gi(light_groups.get(i).map_or(DEFAULT_GROUP, String::as_str));
            let power = l.color * l.intensity;
            if power.max_element() <= 0.0 {
                continue;
            }
            match l.kind {
                LightKind::Point => delta.push(DeltaLight::Point {
                    position: l.position,
                    intensity: power,
                    spot: None,
                    group,
                }),
                LightKind::Spot => delta.push(DeltaLight::Point {
                    position: l.position,
                    intensity: power,
                    spot: Some((
                        l.direction.normalize_or(Vec3::NEG_Y),
                        l.inner_angle.cos(),
                        l.outer_angle.cos(),
                    )),
                    group,
                }),
                LightKind::Directional => delta.push(DeltaLight::Directional {
                    to_light: -l.direction.normalize_or(Vec3::NEG_Y),
                    irradiance: power,
                    group,
                }),
                LightKind::Sphere | LightKind::Disk => {
                    if l.radius.is_nan() || l.radius <= 0.0 {
                        return Err(bad("sphere and disk lights need a radius > 0"));
                    }
                    shapes.push(ShapeLight {
                        center: l.position,
                        radius: l.radius,
                        radiance: power / (PI * l.radius * l.radius),
                        disk_normal: (l.kind == LightKind::Disk)
                            .then(|| l.direction.normalize_or(Vec3::NEG_Y)),
                        group,
                    });
                }
            }
        }
        // Emissive triangles, chosen in proportion to luminance × area (power).
        let mut tri_index = Vec::new();
        let mut weights = Vec::new();
        for e in &scene.emissive_triangles {
            let w = e
                .radiance
                .dot(LUMINANCE)
                .max(e.radiance.max_element() * 1e-3)
                * e.area;
            if w > 0.0 && w.is_finite() {
                tri_index.push(e.triangle);
                weights.push(w as f64);
            }
        }
        let total: f64 = weights.iter().sum();
        let mut tri_cdf = Vec::with_capacity(weights.len());
        let mut tri_prob = Vec::new();
        if total > 0.0 {
            tri_prob = vec![0.0f32; scene.triangles.len()];
            let mut acc = 0.0f64;
            for (k, w) in weights.iter().enumerate() {
                acc += w;
                tri_cdf.push((acc / total) as f32);
                tri_prob[tri_index[k] as usize] += (w / total) as f32;
            }
            if let Some(last) = tri_cdf.last_mut() {
                *last = 1.0;
            }
        }
        let env = Self::environment(scene)?;
        Ok(Self {
            delta,
            shapes,
            tri_index,
            tri_cdf,
            tri_prob,
            emissive_group: gi(EMISSIVE_GROUP),
            env,
            env_group: gi(ENVIRONMENT_GROUP),
            groups: names,
        })
    }

    fn environment(scene: &Scene) -> Result<Environment, BakeError> {
        let e = &scene.environment;
        if !(e.intensity.is_finite() && e.color.is_finite() && e.rotation_y_degrees.is_finite()) {
            return Err(BakeError::BadEnvironment(
                "non-finite colour, intensity or rotation".into(),
            ));
        }
        match &e.map {
            None => {
                let c = e.color * e.intensity;
                Ok(if c.max_element() > 0.0 {
                    Environment::Uniform(c)
                } else {
                    Environment::Black
                })
            }
            Some(path) => {
                let map = EnvMap::load(path)?;
                Ok(Self::map_environment(
                    &map,
                    e.intensity,
                    e.rotation_y_degrees,
                ))
            }
        }
    }

    /// A map environment rotated counter-clockwise seen from above (+Y) by
    /// `rotation_y_degrees`: world radiance `L(d) = map(R⁻¹ d)`.
    pub(crate) fn map_environment(
        map: &EnvMap,
        scale: f32,
        rotation_y_degrees: f32,
    ) -> Environment {
        let world_from_map = Quat::from_rotation_y(rotation_y_degrees.to_radians());
        Environment::Map {
            sampler: Box::new(EnvSampler::new(map)),
            scale,
            map_from_world: world_from_map.inverse(),
            world_from_map,
        }
    }

    /// True when some emissive triangle can be sampled.
    pub(crate) fn has_emissive_triangles(&self) -> bool {
        !self.tri_cdf.is_empty()
    }

    /// Picks an emissive triangle for `u ∈ [0,1)`: `(scene triangle, probability)`.
    pub(crate) fn pick_triangle(&self, u: f32) -> (u32, f32) {
        let k = self
            .tri_cdf
            .partition_point(|&c| c <= u)
            .min(self.tri_cdf.len() - 1);
        let t = self.tri_index[k];
        (t, self.tri_prob[t as usize])
    }

    /// Samples a point on the emissive triangles as seen from `p`: returns
    /// the sample and the chosen point (for the shadow ray).
    pub(crate) fn sample_triangle(
        &self,
        scene: &Scene,
        p: Vec3,
        u_pick: f32,
        u: Vec2,
    ) -> Option<(LightSample, Vec3)> {
        let (t, prob) = self.pick_triangle(u_pick);
        let tri = &scene.triangles[t as usize];
        let b = sample_uniform_triangle(u);
        let q = tri.point(b.y, b.z);
        let v = q - p;
        let dist2 = v.length_squared();
        if dist2 <= 0.0 {
            return None;
        }
        let dist = dist2.sqrt();
        let wi = v / dist;
        let n = tri.geometric_normal();
        let cos_l = n.dot(wi).abs();
        let area = tri.area();
        if cos_l <= 1e-7 || area <= 0.0 {
            return None;
        }
        let radiance = scene.emission(tri.material, tri.uv(b.y, b.z));
        Some((
            LightSample {
                wi,
                dist,
                radiance,
                pdf: prob / area * dist2 / cos_l,
            },
            q,
        ))
    }

    /// Solid-angle density of [`Emitters::sample_triangle`] for a ray that hit
    /// emissive triangle `tri` at distance `t` along unit `wi`.
    pub(crate) fn triangle_pdf(&self, scene: &Scene, tri: u32, wi: Vec3, t: f32) -> f32 {
        let Some(&prob) = self.tri_prob.get(tri as usize) else {
            return 0.0;
        };
        if prob <= 0.0 {
            return 0.0;
        }
        let tr = &scene.triangles[tri as usize];
        let cos_l = tr.geometric_normal().dot(wi).abs();
        let area = tr.area();
        if cos_l <= 1e-7 || area <= 0.0 {
            return 0.0;
        }
        prob / area * t * t / cos_l
    }
}
