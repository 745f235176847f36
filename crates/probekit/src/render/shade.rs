//! Shading one pixel: the probes' or the reference's irradiance on the
//! scene and the test object, the sky, and the probe and edge overlay.

use super::{RenderError, Sphere, TestObject};
use crate::env::EnvMap;
use crate::scene::Scene;
use crate::trace::{Ray, Tracer};
use glam::{Quat, Vec3};
use probekit_runtime::{ObjectState, ProbeFile, Probes};

/// The probes' irradiance `E(n)` at `p` for unit normal `n`, as an engine
/// reads it from the loaded file (0 where the query is refused: a normal
/// that is not finite, say).
pub(super) fn probe_irradiance(probes: &Probes, p: Vec3, n: Vec3, state: &mut ObjectState) -> Vec3 {
    probes
        .irradiance(state, p, n)
        .map_or(Vec3::ZERO, Vec3::from_array)
}

/// What a ray escaping the scene sees.
pub(super) enum Sky {
    Uniform(Vec3),
    Map {
        map: EnvMap,
        scale: f32,
        map_from_world: Quat,
    },
}

impl Sky {
    pub(super) fn new(scene: &Scene) -> Result<Self, RenderError> {
        let e = &scene.environment;
        Ok(match &e.map {
            None => Sky::Uniform(e.color * e.intensity),
            Some(path) => Sky::Map {
                map: EnvMap::load(path)?,
                scale: e.intensity,
                map_from_world: Quat::from_rotation_y(e.rotation_y_degrees.to_radians()).inverse(),
            },
        })
    }

    pub(super) fn radiance(&self, d: Vec3) -> Vec3 {
        match self {
            Sky::Uniform(c) => *c,
            Sky::Map {
                map,
                scale,
                map_from_world,
            } => {
                let (x, y) = map.texel_of(*map_from_world * d);
                map.texel(x, y) * *scale
            }
        }
    }
}

/// One drawn probe: position, radius, radiance SH.
pub(super) struct Glyph {
    pub(super) center: Vec3,
    pub(super) sh: Vec<Vec3>,
}

/// Probe spheres and edges for `show_probes`.
pub(super) struct Overlay {
    pub(super) glyphs: Vec<Glyph>,
    pub(super) radius: f32,
    pub(super) edges: Vec<(Vec3, Vec3)>,
}

impl Overlay {
    pub(super) fn new(file: &ProbeFile, probes: &Probes, bake_box: &crate::scene::Aabb) -> Self {
        let n = file.positions().len().max(1);
        let vol = bake_box.size();
        let spacing = (vol.x.max(1e-3) * vol.y.max(1e-3) * vol.z.max(1e-3) / n as f32).cbrt();
        let radius = (0.12 * spacing).min(0.08);
        let glyphs = match probes.cloud() {
            Some(c) => c
                .mesh()
                .positions()
                .iter()
                .enumerate()
                .map(|(i, p)| Glyph {
                    center: *p,
                    sh: c.probe_sh(i).to_vec(),
                })
                .collect(),
            None => {
                // A volume's samples (a rigs file has none).
                let (k, coeffs) = file.probes().map_or((1, Vec::new()), |p| {
                    let c = &p.coefficients;
                    (c.coeffs_per_probe(), c.to_f32().unwrap_or_default())
                });
                file.positions()
                    .iter()
                    .enumerate()
                    .filter_map(|(i, p)| {
                        coeffs.get(i * k..(i + 1) * k).map(|c| Glyph {
                            center: *p,
                            sh: c.to_vec(),
                        })
                    })
                    .collect()
            }
        };
        let mut edges = Vec::new();
        if let Some(c) = probes.cloud() {
            let mut set = std::collections::BTreeSet::new();
            for t in c.mesh().tets() {
                for a in 0..4 {
                    for b in a + 1..4 {
                        let (i, j) = (t[a].min(t[b]), t[a].max(t[b]));
                        set.insert((i, j));
                    }
                }
            }
            let pos = c.mesh().positions();
            edges = set
                .into_iter()
                .map(|(i, j)| (pos[i as usize], pos[j as usize]))
                .collect();
        }
        Overlay {
            glyphs,
            radius,
            edges,
        }
    }
}

/// One pixel's result.
#[derive(Clone, Copy)]
pub(super) struct Px {
    pub(super) probes: Vec3,
    pub(super) reference: Vec3,
    /// `(E_probes, E_truth)` where the object is the nearest thing seen.
    pub(super) object: Option<(Vec3, Vec3)>,
    /// Distance to what the pixel shows (for depth-tested lines).
    pub(super) depth: f32,
}

/// Shades one primary ray for both panels.
#[allow(clippy::too_many_arguments)]
pub(super) fn shade_pixel(
    ray: &Ray,
    tracer: &Tracer,
    scene: &Scene,
    (probes, wall_probes): (&Probes, &Probes),
    sky: &Sky,
    object: &TestObject,
    overlay: Option<(&Overlay, &[u32])>,
    albedo: f32,
    ws: &mut ObjectState,
) -> Px {
    let inv_pi = std::f32::consts::FRAC_1_PI;
    // The nearest foreground thing: test object or a probe sphere.
    let obj = object.hit(ray, f32::INFINITY);
    let mut fg_t = obj.map_or(f32::INFINITY, |o| o.t);
    let mut object = obj.map(|o| (probe_irradiance(probes, o.point, o.normal, ws), o.truth));
    let mut fg: Option<(Vec3, Vec3)> =
        object.map(|(e, t)| (albedo * inv_pi * e, albedo * inv_pi * t));
    if let Some((ov, cands)) = overlay {
        for &i in cands {
            let g = &ov.glyphs[i as usize];
            let s = Sphere {
                center: g.center,
                radius: ov.radius,
            };
            if let Some(t) = s.intersect(ray) {
                if t < fg_t {
                    fg_t = t;
                    let n = (ray.at(t) - g.center).normalize();
                    let c = probekit_sh::irradiance(&g.sh, n) * inv_pi;
                    fg = Some((c, c));
                    object = None;
                }
            }
        }
    }
    // Scene layers in front of the foreground, front to back.
    let (mut col, mut trans) = (Vec3::ZERO, 1.0f32);
    let mut depth = fg_t;
    let mut r = *ray;
    let mut travelled = 0.0f32;
    let mut escaped = false;
    for _ in 0..16 {
        let Some(hit) = tracer.closest_hit(&r, fg_t - travelled) else {
            escaped = true;
            break;
        };
        let nf = hit.facing_normal();
        let ns = if hit.shading_normal.dot(nf) < 0.0 {
            -hit.shading_normal
        } else {
            hit.shading_normal
        };
        let e = probe_irradiance(wall_probes, hit.point + 0.01 * nf, ns, ws);
        let c =
            scene.emission(hit.material, hit.uv) + scene.albedo(hit.material, hit.uv) * inv_pi * e;
        col += trans * hit.opacity * c;
        trans *= 1.0 - hit.opacity;
        let dist = (hit.point - ray.origin).length();
        if hit.opacity >= 0.5 && dist < depth {
            depth = dist;
        }
        if trans < 1e-3 {
            break;
        }
        travelled = dist;
        r = hit.continue_ray(r.direction);
    }
    let (probes, reference) = match (escaped, fg) {
        (true, Some((a, b))) => (col + trans * a, col + trans * b),
        (true, None) => {
            let bg = trans * sky.radiance(ray.direction);
            (col + bg, col + bg)
        }
        (false, _) => (col, col),
    };
    // The object counts for the metrics only where it is seen (not hidden
    // behind an almost opaque layer).
    let object = if escaped && trans >= 0.5 {
        object
    } else {
        None
    };
    Px {
        probes,
        reference,
        object,
        depth,
    }
}
