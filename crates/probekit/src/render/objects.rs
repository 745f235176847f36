//! The test object: where it is, how a ray hits it, and its ground truth.
//!
//! The object is **not** part of the scene: it receives light and does not
//! shadow or reflect onto the scene, exactly as probes see it. Ground truth
//! is therefore the path-traced irradiance of the scene without the object,
//! at the object's surface points ([`Baker::reference_irradiance`]).
//!
//! * Spheres: truth at `K` spherical-Fibonacci normals per sphere
//!   (`probekit_sh::project::fibonacci_point`), at the surface points
//!   `c + r·n_k`. Per pixel we evaluate the least-squares fit of real SH of
//!   order `p = min(5, ⌊√(K/2)⌋)` (bands `0..p`, at most L4) to those `K`
//!   values: smooth, and exact for irradiance up to band 4 (the clamped-cosine
//!   kernel's next non-zero band, l = 6, holds `(π/64)/π ≈ 1.6 %` of the DC
//!   weight — Ramamoorthi & Hanrahan 2001, eq. 9 —, so a fit to band 4 misses
//!   at most that much of a sharp light's irradiance).
//! * A mesh: truth at every distinct vertex (position and normal) at the
//!   vertex moved 1 mm along its normal; per pixel the barycentric blend of
//!   the hit triangle's three vertex values.

use super::RenderError;
use crate::capture::{Baker, ReferenceSettings};
use crate::scene::{Aabb, Scene};
use crate::trace::free_space::inside_geometry;
use crate::trace::{Ray, Tracer};
use glam::Vec3;
use probekit_sh::project::fibonacci_point;
use probekit_sh::{eval_basis, num_coeffs};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A sphere of the default test object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre, metres.
    pub center: Vec3,
    /// Radius, metres.
    pub radius: f32,
}

impl Sphere {
    /// Nearest `t > 0` where the unit-direction `ray` enters the sphere.
    pub fn intersect(&self, ray: &Ray) -> Option<f32> {
        let oc = ray.origin - self.center;
        let b = oc.dot(ray.direction);
        let c = oc.length_squared() - self.radius * self.radius;
        let disc = b * b - c;
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        let t0 = -b - s;
        if t0 > 0.0 {
            return Some(t0);
        }
        let t1 = -b + s;
        (t1 > 0.0).then_some(t1)
    }
}

/// Clearance (metres) between a test sphere and any surface or other sphere.
pub const SPHERE_CLEARANCE: f32 = 0.05;

/// 26 directions (cube corners, edges and faces), unit length.
fn around() -> Vec<Vec3> {
    let mut d = Vec::new();
    for x in -1i32..=1 {
        for y in -1i32..=1 {
            for z in -1i32..=1 {
                if (x, y, z) != (0, 0, 0) {
                    d.push(Vec3::new(x as f32, y as f32, z as f32).normalize());
                }
            }
        }
    }
    d
}

/// True when a sphere at `c` of radius `r` sits in free space: not inside
/// geometry, and no surface within `r + SPHERE_CLEARANCE` along 26 rays.
pub fn sphere_is_free(tracer: &Tracer, c: Vec3, r: f32) -> bool {
    !around().iter().any(|d| {
        tracer
            .closest_hit(&Ray::new(c, *d), r + SPHERE_CLEARANCE)
            .is_some()
    }) && !inside_geometry(tracer, c)
}

/// Places up to `cols × rows` spheres of radius `radius` where the camera
/// sees them: for each cell of a `cols × rows` grid over the lower 60 % of the
/// image, along the ray through the cell centre, at the first of a few
/// fractions of the distance to the first surface (or the bake box's far
/// side) where the sphere is free ([`sphere_is_free`]), inside `bake_box`,
/// at least `3·radius` from the eye and clear of the spheres already placed.
/// Cells with no such place get no sphere (e.g. a camera facing a wall).
pub fn place_spheres(
    tracer: &Tracer,
    camera: &super::Camera,
    aspect: f32,
    bake_box: &Aabb,
    radius: f32,
    cols: usize,
    rows: usize,
) -> Vec<Sphere> {
    let (w, h) = ((1000.0 * aspect).round().max(1.0) as u32, 1000u32);
    let mut out: Vec<Sphere> = Vec::new();
    let inner = Aabb::new(
        bake_box.min + Vec3::splat(radius),
        bake_box.max - Vec3::splat(radius),
    );
    for j in 0..rows {
        for i in 0..cols {
            let x = (i as f32 + 0.5) / cols as f32 * w as f32;
            let y = (0.4 + 0.6 * (j as f32 + 0.5) / rows as f32) * h as f32;
            let ray = camera.ray(x, y, w, h);
            let far = tracer
                .closest_hit(&ray, f32::INFINITY)
                .map_or(f32::INFINITY, |hit| hit.t);
            let far = far.min(box_exit(bake_box, &ray));
            if !far.is_finite() {
                continue;
            }
            for f in [0.5, 0.35, 0.65, 0.25, 0.8, 0.15] {
                let d = f * far;
                let c = ray.at(d);
                if d < 3.0 * radius || !inner.contains(c) {
                    continue;
                }
                if out
                    .iter()
                    .any(|s| (s.center - c).length() < 2.0 * radius + SPHERE_CLEARANCE)
                {
                    continue;
                }
                if sphere_is_free(tracer, c, radius) {
                    out.push(Sphere { center: c, radius });
                    break;
                }
            }
        }
    }
    out
}

/// Distance along `ray` (unit direction) at which it leaves `b` (infinite if
/// it never is inside).
fn box_exit(b: &Aabb, ray: &Ray) -> f32 {
    let mut t_far = f32::INFINITY;
    for k in 0..3 {
        let d = ray.direction[k];
        if d.abs() < 1e-12 {
            continue;
        }
        let t1 = (b.min[k] - ray.origin[k]) / d;
        let t2 = (b.max[k] - ray.origin[k]) / d;
        t_far = t_far.min(t1.max(t2));
    }
    t_far.max(0.0)
}

/// What the ray hit on the test object.
#[derive(Clone, Copy, Debug)]
pub struct ObjectHit {
    /// Distance along the (unit) ray, metres.
    pub t: f32,
    /// Surface point.
    pub point: Vec3,
    /// Unit normal (outward).
    pub normal: Vec3,
    /// Ground-truth irradiance there (see the module docs).
    pub truth: Vec3,
}

/// A test object with its ground truth computed.
pub enum TestObject<'m> {
    /// Spheres, each with the SH fit (order `order`) of its truth.
    Spheres {
        /// The spheres.
        spheres: Vec<Sphere>,
        /// Per sphere, `order²` RGB coefficients of the fitted irradiance.
        fits: Vec<Vec<Vec3>>,
        /// SH order of the fits.
        order: usize,
    },
    /// A mesh with per-vertex truth.
    Mesh {
        /// Ray tracer over the mesh (its own scene).
        tracer: Tracer<'m>,
        /// Per triangle, the indices of its three vertices in `truth`.
        corners: Vec<[u32; 3]>,
        /// Truth per distinct vertex.
        truth: Vec<Vec3>,
    },
}

/// SH order used to fit `k` truth values per sphere.
pub fn fit_order(k: usize) -> usize {
    let mut p = 1;
    while p < 5 && (p + 1) * (p + 1) * 2 <= k {
        p += 1;
    }
    p
}

/// Least-squares fit of `order²` real SH coefficients (RGB) to `values` at
/// unit `dirs` (SVD pseudo-inverse, nalgebra).
pub fn fit_sh(dirs: &[Vec3], values: &[Vec3], order: usize) -> Vec<Vec3> {
    let n = num_coeffs(order);
    let mut a = nalgebra::DMatrix::<f64>::zeros(dirs.len(), n);
    let mut y = vec![0.0f32; n];
    for (i, d) in dirs.iter().enumerate() {
        eval_basis(order, *d, &mut y);
        for j in 0..n {
            a[(i, j)] = y[j] as f64;
        }
    }
    let mut b = nalgebra::DMatrix::<f64>::zeros(dirs.len(), 3);
    for (i, v) in values.iter().enumerate() {
        for c in 0..3 {
            b[(i, c)] = v[c] as f64;
        }
    }
    let svd = a.svd(true, true);
    let x = svd
        .solve(&b, 1e-9)
        .unwrap_or_else(|_| nalgebra::DMatrix::zeros(n, 3));
    (0..n)
        .map(|j| Vec3::new(x[(j, 0)] as f32, x[(j, 1)] as f32, x[(j, 2)] as f32))
        .collect()
}

/// Evaluates a fit from [`fit_sh`] in direction `d`.
pub fn eval_fit(coeffs: &[Vec3], order: usize, d: Vec3) -> Vec3 {
    let mut y = [0.0f32; 64];
    eval_basis(order, d, &mut y[..num_coeffs(order)]);
    coeffs.iter().zip(&y).map(|(c, w)| *c * *w).sum()
}

impl<'m> TestObject<'m> {
    /// Spheres with truth at `k` Fibonacci normals each; `progress` is
    /// called with the number of truth points finished.
    pub fn spheres(
        baker: &Baker,
        spheres: Vec<Sphere>,
        k: usize,
        settings: &ReferenceSettings,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<Self, RenderError> {
        let dirs: Vec<Vec3> = (0..k).map(|i| fibonacci_point(i, k)).collect();
        let done = AtomicUsize::new(0);
        let truth: Vec<Vec3> = (0..spheres.len() * k)
            .into_par_iter()
            .map(|idx| {
                let (s, i) = (&spheres[idx / k], idx % k);
                let p = s.center + s.radius * dirs[i];
                let e = baker.reference_irradiance(p, dirs[i], idx as u64, settings)?;
                progress(done.fetch_add(1, Ordering::Relaxed) + 1);
                Ok(e.irradiance)
            })
            .collect::<Result<_, crate::capture::BakeError>>()?;
        let order = fit_order(k);
        let fits = truth
            .chunks(k.max(1))
            .map(|t| fit_sh(&dirs, t, order))
            .collect();
        Ok(TestObject::Spheres {
            spheres,
            fits,
            order,
        })
    }

    /// A mesh (its own scene, e.g. loaded with [`Scene::load`]) with truth
    /// at every distinct vertex.
    pub fn mesh(
        baker: &Baker,
        mesh: &'m Scene,
        settings: &ReferenceSettings,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<Self, RenderError> {
        let key = |p: Vec3, n: Vec3| {
            [
                p.x.to_bits(),
                p.y.to_bits(),
                p.z.to_bits(),
                n.x.to_bits(),
                n.y.to_bits(),
                n.z.to_bits(),
            ]
        };
        let mut index: HashMap<[u32; 6], u32> = HashMap::new();
        let mut verts: Vec<(Vec3, Vec3)> = Vec::new();
        let corners: Vec<[u32; 3]> = mesh
            .triangles
            .iter()
            .map(|t| {
                [0, 1, 2].map(|c| {
                    let (p, n) = (t.positions[c], t.normals[c]);
                    *index.entry(key(p, n)).or_insert_with(|| {
                        verts.push((p, n));
                        verts.len() as u32 - 1
                    })
                })
            })
            .collect();
        let done = AtomicUsize::new(0);
        let truth: Vec<Vec3> = verts
            .par_iter()
            .enumerate()
            .map(|(i, (p, n))| {
                let n = n.normalize_or(Vec3::Y);
                let e = baker.reference_irradiance(*p + 1e-3 * n, n, i as u64, settings)?;
                progress(done.fetch_add(1, Ordering::Relaxed) + 1);
                Ok(e.irradiance)
            })
            .collect::<Result<_, crate::capture::BakeError>>()?;
        Ok(TestObject::Mesh {
            tracer: Tracer::new(mesh),
            corners,
            truth,
        })
    }

    /// The nearest hit of `ray` (unit direction) on the object before `t_max`.
    pub fn hit(&self, ray: &Ray, t_max: f32) -> Option<ObjectHit> {
        match self {
            TestObject::Spheres {
                spheres,
                fits,
                order,
            } => {
                let mut best: Option<(f32, usize)> = None;
                for (i, s) in spheres.iter().enumerate() {
                    if let Some(t) = s.intersect(ray) {
                        if t < t_max && best.is_none_or_lt(t) {
                            best = Some((t, i));
                        }
                    }
                }
                let (t, i) = best?;
                let point = ray.at(t);
                let normal = (point - spheres[i].center).normalize();
                Some(ObjectHit {
                    t,
                    point,
                    normal,
                    truth: eval_fit(&fits[i], *order, normal),
                })
            }
            TestObject::Mesh {
                tracer,
                corners,
                truth,
            } => {
                let h = tracer.closest_hit(ray, t_max)?;
                let c = corners[h.triangle as usize];
                let (b1, b2) = (h.barycentrics.x, h.barycentrics.y);
                let e = truth[c[0] as usize] * (1.0 - b1 - b2)
                    + truth[c[1] as usize] * b1
                    + truth[c[2] as usize] * b2;
                Some(ObjectHit {
                    t: h.t,
                    point: h.point,
                    normal: h.shading_normal,
                    truth: e,
                })
            }
        }
    }
}

/// `best` is empty or holds a larger distance than `t`.
trait NearestSoFar {
    fn is_none_or_lt(&self, t: f32) -> bool;
}

impl NearestSoFar for Option<(f32, usize)> {
    fn is_none_or_lt(&self, t: f32) -> bool {
        match self {
            None => true,
            Some((b, _)) => t < *b,
        }
    }
}
