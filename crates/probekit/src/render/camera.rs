//! A pinhole camera and the automatic view of a bake box.

use super::RenderError;
use crate::scene::Aabb;
use crate::trace::{Ray, Tracer};
use glam::Vec3;

/// Default vertical field of view, degrees.
pub const DEFAULT_FOV_DEGREES: f32 = 65.0;

/// A pinhole camera: right-handed, +Y up; it looks from `eye` at `target`.
/// Pixel `(x, y)` (continuous, `(0, 0)` the top-left corner of the image)
/// maps to the ray through the image plane at unit distance, `fov_y_degrees`
/// spanning the image height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position, metres.
    pub eye: Vec3,
    /// Point looked at, metres.
    pub target: Vec3,
    /// Vertical field of view, degrees, in (1, 179).
    pub fov_y_degrees: f32,
}

impl Camera {
    /// A camera, checked: finite, `eye ≠ target`, field of view in (1°, 179°).
    pub fn new(eye: Vec3, target: Vec3, fov_y_degrees: f32) -> Result<Self, RenderError> {
        if !(eye.is_finite() && target.is_finite()) {
            return Err(RenderError::BadCamera(
                "eye and target must be finite".into(),
            ));
        }
        if (target - eye).length() < 1e-6 {
            return Err(RenderError::BadCamera("eye and target coincide".into()));
        }
        if !(fov_y_degrees > 1.0 && fov_y_degrees < 179.0) {
            return Err(RenderError::BadCamera(format!(
                "field of view {fov_y_degrees}°: expected between 1 and 179 degrees"
            )));
        }
        Ok(Self {
            eye,
            target,
            fov_y_degrees,
        })
    }

    /// `(right, up, forward)` unit vectors. `up` is world +Y made orthogonal
    /// to `forward` (world +Z when looking straight up or down).
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let f = (self.target - self.eye).normalize();
        let world_up = if f.y.abs() > 0.999 { Vec3::Z } else { Vec3::Y };
        let r = f.cross(world_up).normalize();
        let u = r.cross(f);
        (r, u, f)
    }

    /// Half-height of the image plane at unit distance: `tan(fov/2)`.
    fn half_height(&self) -> f32 {
        (0.5 * self.fov_y_degrees.to_radians()).tan()
    }

    /// The primary ray (unit direction) through continuous pixel position
    /// `(x, y)` of a `w × h` image (`x + 0.5, y + 0.5` is a pixel centre).
    pub fn ray(&self, x: f32, y: f32, w: u32, h: u32) -> Ray {
        let (r, u, f) = self.basis();
        let th = self.half_height();
        let aspect = w as f32 / h as f32;
        let sx = (2.0 * x / w as f32 - 1.0) * th * aspect;
        let sy = (1.0 - 2.0 * y / h as f32) * th;
        Ray::new(self.eye, (f + sx * r + sy * u).normalize())
    }

    /// Camera-space coordinates of `p`: `(x right, y up, z forward)`.
    pub fn to_view(&self, p: Vec3) -> Vec3 {
        let (r, u, f) = self.basis();
        let d = p - self.eye;
        Vec3::new(d.dot(r), d.dot(u), d.dot(f))
    }

    /// Continuous pixel position of a camera-space point with `z > 0`
    /// (the inverse of [`Camera::ray`]).
    pub fn view_to_pixel(&self, v: Vec3, w: u32, h: u32) -> (f32, f32) {
        let th = self.half_height();
        let aspect = w as f32 / h as f32;
        let sx = v.x / v.z / (th * aspect);
        let sy = v.y / v.z / th;
        ((sx + 1.0) * 0.5 * w as f32, (1.0 - sy) * 0.5 * h as f32)
    }

    /// The automatic view of `bake_box`. A closed scene (all of 14 rays from
    /// the box centre hit something) is seen from inside: from each of the
    /// four upper corners of the box (inset 6 % of its size, at 85 % of its
    /// height) looking at the centre lowered to 35 % of the height, the
    /// candidate whose 16 × 9 probe rays see deepest on average (a view
    /// through a doorway beats a view of the nearest wall) wins; candidates
    /// inside geometry are skipped. An open scene is seen from outside the
    /// box, above a corner. Deterministic.
    pub fn auto(tracer: &Tracer, bake_box: &Aabb, aspect: f32) -> Camera {
        let (lo, size) = (bake_box.min, bake_box.size());
        let centre = bake_box.center();
        let diag = size.length().max(1e-3);
        let mut misses = 0;
        for x in -1i32..=1 {
            for y in -1i32..=1 {
                for z in -1i32..=1 {
                    let d = Vec3::new(x as f32, y as f32, z as f32);
                    let axis = x.abs() + y.abs() + z.abs();
                    if axis == 1 || axis == 3 {
                        let ray = Ray::new(centre, d.normalize());
                        if tracer.closest_hit(&ray, f32::INFINITY).is_none() {
                            misses += 1;
                        }
                    }
                }
            }
        }
        let target = lo + size * Vec3::new(0.5, 0.35, 0.5);
        if misses > 0 {
            let eye = centre + (size * Vec3::new(0.5, 0.5, 0.5)) * Vec3::new(1.6, 1.3, 1.6);
            return Camera {
                eye,
                target: centre,
                fov_y_degrees: DEFAULT_FOV_DEGREES,
            };
        }
        let mut best: Option<(f32, Camera)> = None;
        for (fx, fz) in [(0.94, 0.94), (0.06, 0.94), (0.94, 0.06), (0.06, 0.06)] {
            let eye = lo + size * Vec3::new(fx, 0.85, fz);
            if crate::placement::inside_geometry(tracer, eye) {
                continue;
            }
            let cam = Camera {
                eye,
                target,
                fov_y_degrees: DEFAULT_FOV_DEGREES,
            };
            let (w, h) = ((90.0 * aspect).round().max(1.0) as u32, 90u32);
            let mut sum = 0.0;
            for j in 0..9 {
                for i in 0..16 {
                    let x = (i as f32 + 0.5) / 16.0 * w as f32;
                    let y = (j as f32 + 0.5) / 9.0 * h as f32;
                    let ray = cam.ray(x, y, w, h);
                    sum += tracer
                        .closest_hit(&ray, diag)
                        .map_or(diag, |hit| hit.t.min(diag));
                }
            }
            let better = match &best {
                None => true,
                Some((s, _)) => sum > *s,
            };
            if better {
                best = Some((sum, cam));
            }
        }
        best.map(|(_, c)| c).unwrap_or(Camera {
            eye: lo + size * Vec3::new(0.94, 0.85, 0.94),
            target,
            fov_y_degrees: DEFAULT_FOV_DEGREES,
        })
    }
}
