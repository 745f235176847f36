//! A pinhole camera and the automatic view of a bake box.

use super::RenderError;
use crate::scene::Aabb;
use crate::trace::{Ray, Tracer};
use glam::Vec3;

/// Default vertical field of view, degrees.
pub const DEFAULT_FOV_DEGREES: f32 = 65.0;

/// No automatic camera stands nearer than this to a surface, metres.
pub const EYE_CLEARANCE: f32 = 0.1;

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

    /// The automatic view of `bake_box` for test objects that `fits` counts
    /// (the spheres [`super::place_spheres`] finds room for in a view, or
    /// whether a mesh is in sight): always from inside the box, from free
    /// space, looking at where the objects can go.
    ///
    /// Candidate eyes sit on a 3 × 2 × 3 lattice in the box (at 10 %, 50 %
    /// and 90 % of its width and depth, 55 % and 80 % of its height); an eye
    /// within [`EYE_CLEARANCE`] of a surface, or inside geometry, is
    /// skipped. Each looks at the box's centre lowered to 35 % of its
    /// height, and along ±x and ±z, tilted 20° down. A view is ranked by
    /// how many objects fit, then by how enclosed it is (the share of 16 × 9
    /// probe rays that hit a surface within the box's diagonal: a view of a
    /// room beats a view out of a window), then by how deep it sees. `None`
    /// when no view has room for any object. Deterministic.
    pub fn auto(
        tracer: &Tracer,
        bake_box: &Aabb,
        aspect: f32,
        fits: &dyn Fn(&Camera) -> usize,
    ) -> Option<Camera> {
        let (lo, size) = (bake_box.min, bake_box.size());
        let diag = size.length().max(1e-3);
        let target = lo + size * Vec3::new(0.5, 0.35, 0.5);
        let tilt = 20f32.to_radians().tan();
        let mut best: Option<((usize, f32, f32), Camera)> = None;
        for fy in [0.8, 0.55] {
            for fz in [0.1, 0.5, 0.9] {
                for fx in [0.1, 0.5, 0.9] {
                    let eye = lo + size * Vec3::new(fx, fy, fz);
                    if !crate::trace::free_space::is_free(tracer, eye, EYE_CLEARANCE) {
                        continue;
                    }
                    let mut targets = vec![target];
                    for d in [Vec3::X, Vec3::NEG_X, Vec3::Z, Vec3::NEG_Z] {
                        targets.push(eye + d - Vec3::Y * tilt);
                    }
                    for t in targets {
                        let Ok(cam) = Camera::new(eye, t, DEFAULT_FOV_DEGREES) else {
                            continue;
                        };
                        let n = fits(&cam);
                        if n == 0 {
                            continue;
                        }
                        let (enclosed, depth) = cam.openness(tracer, aspect, diag);
                        let score = (n, enclosed, depth);
                        let better = match &best {
                            None => true,
                            Some((b, _)) => score.partial_cmp(b).is_some_and(|o| o.is_gt()),
                        };
                        if better {
                            best = Some((score, cam));
                        }
                    }
                }
            }
        }
        best.map(|(_, c)| c)
    }

    /// True when `p` is in front of the camera, inside the frame of an
    /// image of `aspect`, and no surface lies between the eye and it.
    pub fn sees(&self, tracer: &Tracer, p: Vec3, aspect: f32) -> bool {
        let v = self.to_view(p);
        if v.z <= 0.0 {
            return false;
        }
        let th = self.half_height();
        if (v.x / v.z).abs() > th * aspect || (v.y / v.z).abs() > th {
            return false;
        }
        let d = p - self.eye;
        !tracer.occluded_ray(&Ray::new(self.eye, d), 0.99)
    }

    /// The share of 16 × 9 probe rays of this view that hit a surface
    /// within `diag`, and their mean depth (misses count `diag`).
    fn openness(&self, tracer: &Tracer, aspect: f32, diag: f32) -> (f32, f32) {
        let (w, h) = ((90.0 * aspect).round().max(1.0) as u32, 90u32);
        let (mut hits, mut sum) = (0usize, 0.0f32);
        for j in 0..9 {
            for i in 0..16 {
                let x = (i as f32 + 0.5) / 16.0 * w as f32;
                let y = (j as f32 + 0.5) / 9.0 * h as f32;
                match tracer.closest_hit(&self.ray(x, y, w, h), diag) {
                    Some(hit) => {
                        hits += 1;
                        sum += hit.t.min(diag);
                    }
                    None => sum += diag,
                }
            }
        }
        (hits as f32 / 144.0, sum / 144.0)
    }
}
