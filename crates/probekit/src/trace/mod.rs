//! # CPU ray tracing over a [`Scene`]
//!
//! A [`Tracer`] holds a compressed 8-wide BVH (CWBVH, Ylitie et al. 2017) built by the `obvhs`
//! crate (PLOC build + reinsertion, no spatial splits so every triangle sits in exactly one leaf),
//! and intersects triangles with the **watertight** test of Woop, Benthin and Wald,
//! "Watertight Ray/Triangle Intersection", JCGT 2(1), 2013: a ray through a shared edge or
//! vertex of a closed mesh always hits at least one of the triangles there (edge functions
//! that are exactly zero are recomputed in f64, as in the paper).
//!
//! Queries:
//! * [`Tracer::closest_hit`]: nearest surface with non-zero opacity; fully transparent hits
//!   (alpha-masked-out texels, opacity 0) are skipped, partly transparent ones (glTF `BLEND`,
//!   OBJ `d < 1`) are reported with their [`Hit::opacity`]. A path tracer then either continues
//!   through with probability `1 − opacity` (stochastic; unbiased) or splits the weight
//!   (deterministic): reflect with weight `opacity`, continue with weight `1 − opacity` from
//!   [`Hit::continue_ray`]. Either way partly transparent surfaces pass light straight through.
//! * [`Tracer::transmittance`]: product of `(1 − opacity)` over every surface crossing on a
//!   segment, as a grey RGB value (glass is not tinted). 0 when anything opaque is in the way.
//! * [`Tracer::occluded`]: true exactly when [`Tracer::transmittance`] is zero, i.e. an opaque
//!   surface blocks the segment (partly transparent surfaces do not occlude).
//!
//! No back faces are culled. `t` values are in units of the ray direction's length (metres when
//! it is a unit vector). Surfaces closer than 0.1 mm to a ray's origin may be missed (obvhs's
//! node test starts at t = 1e-4 m); offset origins are far smaller than that, and no probe or
//! shading point should sit that close to a surface it wants to see. Self-intersection: offset new ray origins with [`offset_ray_origin`]
//! (Wächter & Binder, "A Fast and Robust Method for Avoiding Self-Intersection",
//! Ray Tracing Gems, ch. 6, 2019).
//!
//! Threading: a `Tracer` is `Sync`; queries take `&self` and allocate nothing, so call them from
//! any number of rayon threads.
//!
//! Counting: every query above (but the benchmark-only raw obvhs one) counts one ray
//! ([`Tracer::rays`]), for the phase report of a bake.

mod counter;
pub mod free_space;

use counter::RayCounter;

use crate::scene::Scene;
use glam::{Vec2, Vec3};
use glam_obvhs::{UVec2, Vec3A as OVec3A};
use obvhs::{cwbvh::CwBvh, ray::Ray as ORay, ray::RayHit as ORayHit, traverse, BvhBuildParams};

/// A ray `origin + t · direction`. The direction need not be unit length; `t` is measured in
/// multiples of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point (metres). Offset it off surfaces with [`offset_ray_origin`].
    pub origin: Vec3,
    /// Direction (non-zero, finite).
    pub direction: Vec3,
}

impl Ray {
    /// A ray from `origin` along `direction`.
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        Ray { origin, direction }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.direction
    }
}

/// A ray/triangle intersection with everything a shader needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit (distance in metres for a unit direction).
    pub t: f32,
    /// Index into [`Scene::triangles`].
    pub triangle: u32,
    /// Barycentric weights `(b1, b2)` of vertices 1 and 2; vertex 0 has `1 − b1 − b2`.
    pub barycentrics: Vec2,
    /// True when the ray arrives on the side the geometric normal points to
    /// (`dot(direction, geometric_normal) < 0`), i.e. it hits the counter-clockwise (front) side.
    /// Where [`Hit::winding_consistent`] is false this says nothing about inside/outside.
    pub front_face: bool,
    /// Unit geometric normal `normalize((p1 − p0) × (p2 − p0))`, as wound (not flipped towards the ray).
    pub geometric_normal: Vec3,
    /// Unit interpolated shading normal, as given by the source (not flipped towards the ray).
    pub shading_normal: Vec3,
    /// Index into [`Scene::materials`].
    pub material: u32,
    /// Interpolated texture coordinate (glTF convention).
    pub uv: Vec2,
    /// The hit point, computed from the barycentrics on the triangle (more accurate than
    /// `origin + t · direction`).
    pub point: Vec3,
    /// Opacity at the hit, in (0, 1]; below 1 for partly transparent surfaces.
    pub opacity: f32,
    /// [`Scene::winding_consistent`] for this triangle.
    pub winding_consistent: bool,
}

impl Hit {
    /// The unit geometric normal flipped to face against the ray (towards where it came from).
    pub fn facing_normal(&self) -> Vec3 {
        if self.front_face {
            self.geometric_normal
        } else {
            -self.geometric_normal
        }
    }

    /// A ray that continues along `direction` from just beyond this hit (origin offset to the
    /// far side of the surface), for passing through partly transparent surfaces.
    pub fn continue_ray(&self, direction: Vec3) -> Ray {
        let n = if direction.dot(self.geometric_normal) > 0.0 {
            self.geometric_normal
        } else {
            -self.geometric_normal
        };
        Ray::new(offset_ray_origin(self.point, n), direction)
    }

    /// A ray leaving the surface along `direction` (on whichever side `direction` points to),
    /// origin offset against self-intersection.
    pub fn spawn_ray(&self, direction: Vec3) -> Ray {
        self.continue_ray(direction)
    }
}

/// Offsets a point on a surface along the geometric normal `n` (any length, pointing to the side
/// the new ray leaves to) so a ray from it does not re-hit the surface it starts on. The offset
/// scales with the magnitude of the coordinates, so it works at any distance from the origin.
///
/// Wächter & Binder, "A Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing
/// Gems ch. 6 (2019): near the origin a fixed float offset (`1/32 · 2⁻¹⁶ · n`); elsewhere an
/// integer offset of `256 · n` ulps in the float representation of each coordinate.
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let n = n.normalize_or_zero();
    let mut out = [0.0f32; 3];
    for i in 0..3 {
        let of_i = (INT_SCALE * n[i]) as i32;
        let pi = p[i];
        let bits = pi.to_bits() as i32;
        let moved = f32::from_bits((bits + if pi < 0.0 { -of_i } else { of_i }) as u32);
        out[i] = if pi.abs() < ORIGIN {
            pi + FLOAT_SCALE * n[i]
        } else {
            moved
        };
    }
    Vec3::from(out)
}

/// Per-ray constants of the watertight test (Woop et al. 2013, §3).
#[derive(Clone, Copy)]
struct WatertightRay {
    org: Vec3,
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
}

impl WatertightRay {
    fn new(org: Vec3, dir: Vec3) -> Self {
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        WatertightRay {
            org,
            kx,
            ky,
            kz,
            sx: dir[kx] / dir[kz],
            sy: dir[ky] / dir[kz],
            sz: 1.0 / dir[kz],
        }
    }

    /// Returns `(t, b1, b2)` of the hit in `(t_min, t_max)`, or `None`.
    #[inline(always)]
    fn intersect(&self, p: &[Vec3; 3], t_min: f32, t_max: f32) -> Option<(f32, f32, f32)> {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let a = p[0] - self.org;
        let b = p[1] - self.org;
        let c = p[2] - self.org;
        let ax = a[kx] - self.sx * a[kz];
        let ay = a[ky] - self.sy * a[kz];
        let bx = b[kx] - self.sx * b[kz];
        let by = b[ky] - self.sy * b[kz];
        let cx = c[kx] - self.sx * c[kz];
        let cy = c[ky] - self.sy * c[kz];
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (
                ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
            );
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let az = self.sz * a[kz];
        let bz = self.sz * b[kz];
        let cz = self.sz * c[kz];
        let tt = u * az + v * bz + w * cz;
        let inv = 1.0 / det;
        let t = tt * inv;
        if !(t > t_min && t < t_max) {
            return None;
        }
        // u weights vertex 0, v vertex 1, w vertex 2.
        Some((t, v * inv, w * inv))
    }
}

/// Per-primitive data in BVH leaf order.
#[derive(Clone, Copy)]
struct Prim {
    p: [Vec3; 3],
    /// Scene triangle index.
    tri: u32,
    /// True when the material may be less than fully opaque somewhere.
    maybe_transparent: bool,
}

/// A BVH over all triangles of a scene, with closest-hit, any-hit and transmittance queries.
pub struct Tracer<'s> {
    scene: &'s Scene,
    bvh: CwBvh,
    prims: Vec<Prim>,
    rays: RayCounter,
}

/// Relative padding of triangle boxes in the BVH (≈ 8 ulps of the largest coordinate).
const BOX_PAD_RELATIVE: f32 = 1.0 / (1 << 20) as f32;
/// Absolute padding of triangle boxes in the BVH (metres), for triangles at the origin.
const BOX_PAD_ABSOLUTE: f32 = 1e-9;

/// A primitive box for the obvhs builder.
struct PaddedBox(obvhs::aabb::Aabb);

impl obvhs::Boundable for PaddedBox {
    fn aabb(&self) -> obvhs::aabb::Aabb {
        self.0
    }
}

/// Relative shortening of shadow segments at their target end (pbrt's `ShadowEpsilon`), so a
/// target on a surface does not occlude itself.
pub const SHADOW_EPSILON: f32 = 1e-4;

/// Checks a ray and normalises it: returns (unit direction, |direction|, t_max in metres).
/// obvhs's node test assumes nothing about the length, but its fixed near limit of 1e-4 (in t)
/// is then 0.1 mm whatever the caller's direction length.
#[inline]
fn normalized(ray: &Ray, t_max: f32) -> Option<(Vec3, f32, f32)> {
    let len = ray.direction.length();
    if !(ray.origin.is_finite() && len.is_finite() && len > 0.0) || t_max.is_nan() || t_max <= 0.0 {
        return None;
    }
    // `+ 0.0` turns −0.0 into +0.0: obvhs takes the sign of a zero component from the
    // comparison `d < 0` but the sign of its inverse from the zero's sign bit, and a mismatch
    // makes the slab test miss every box.
    Some((ray.direction / len + Vec3::ZERO, len, t_max * len))
}

fn oray(origin: Vec3, direction: Vec3, t_max: f32) -> ORay {
    ORay::new(
        OVec3A::new(origin.x, origin.y, origin.z),
        OVec3A::new(direction.x, direction.y, direction.z),
        0.0,
        t_max,
    )
}

impl<'s> Tracer<'s> {
    /// Builds the BVH (obvhs CWBVH, `medium_build` preset without spatial splits).
    pub fn new(scene: &'s Scene) -> Self {
        // Each triangle's box, padded by a few ulps of its coordinates: flat boxes (axis-aligned
        // triangles) and float rounding in the slab test could otherwise cull a node the ray
        // actually touches, and the watertight triangle test would never get to see it.
        let boxes: Vec<PaddedBox> = scene
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.positions;
                let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
                let pad =
                    BOX_PAD_RELATIVE * lo.abs().max(hi.abs()).max_element() + BOX_PAD_ABSOLUTE;
                PaddedBox(obvhs::aabb::Aabb::new(
                    OVec3A::new(lo.x - pad, lo.y - pad, lo.z - pad),
                    OVec3A::new(hi.x + pad, hi.y + pad, hi.z + pad),
                ))
            })
            .collect();
        let mut params = BvhBuildParams::medium_build();
        // Spatial pre-splits would reference a triangle from several leaves, and any-hit
        // transmittance would then count it more than once (build_cwbvh never splits).
        params.pre_split = false;
        let bvh =
            obvhs::cwbvh::builder::build_cwbvh(&boxes, params, &mut std::time::Duration::default());
        let prims = bvh
            .primitive_indices
            .iter()
            .map(|&i| {
                let t = &scene.triangles[i as usize];
                Prim {
                    p: t.positions,
                    tri: i,
                    maybe_transparent: !scene.materials[t.material as usize].is_opaque(),
                }
            })
            .collect();
        Tracer {
            scene,
            bvh,
            prims,
            rays: RayCounter::new(),
        }
    }

    /// Rays intersected with the scene so far (closest-hit, any-hit and
    /// transmittance queries with a valid ray, one each), by every thread.
    /// The work of a bake is deterministic, so is this count.
    pub fn rays(&self) -> u64 {
        self.rays.total()
    }

    /// The scene this tracer was built over.
    pub fn scene(&self) -> &'s Scene {
        self.scene
    }

    /// Opacity of primitive `prim` at barycentrics (b1, b2).
    #[inline]
    fn opacity_at(&self, prim: &Prim, b1: f32, b2: f32) -> f32 {
        if !prim.maybe_transparent {
            return 1.0;
        }
        let t = &self.scene.triangles[prim.tri as usize];
        self.scene.opacity(t.material, t.uv(b1, b2))
    }

    /// The nearest hit with `0 < t < t_max` on a surface with non-zero opacity (see the module
    /// docs for partly transparent surfaces), or `None`.
    pub fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let (dir, len, t_max) = normalized(ray, t_max)?;
        self.rays.add_one();
        let wr = WatertightRay::new(ray.origin, dir);
        let mut hit = ORayHit::none();
        let mut best = (0.0f32, 0.0f32);
        let found = self
            .bvh
            .ray_traverse(oray(ray.origin, dir, t_max), &mut hit, |r, id| {
                let prim = &self.prims[id];
                match wr.intersect(&prim.p, 0.0, r.tmax) {
                    Some((t, b1, b2)) => {
                        if prim.maybe_transparent && self.opacity_at(prim, b1, b2) <= 0.0 {
                            return f32::INFINITY;
                        }
                        best = (b1, b2);
                        t
                    }
                    None => f32::INFINITY,
                }
            });
        if !found {
            return None;
        }
        let prim = &self.prims[hit.primitive_id as usize];
        // `best` holds the barycentrics of the last accepted (hence nearest) candidate.
        Some(self.make_hit(ray, prim, hit.t / len, best.0, best.1))
    }

    fn make_hit(&self, ray: &Ray, prim: &Prim, t: f32, b1: f32, b2: f32) -> Hit {
        let tri = &self.scene.triangles[prim.tri as usize];
        let ng = tri.geometric_normal();
        let b0 = 1.0 - b1 - b2;
        let ns = (b0 * tri.normals[0] + b1 * tri.normals[1] + b2 * tri.normals[2]).normalize_or(ng);
        let uv = tri.uv(b1, b2);
        Hit {
            t,
            triangle: prim.tri,
            barycentrics: Vec2::new(b1, b2),
            front_face: ray.direction.dot(ng) < 0.0,
            geometric_normal: ng,
            shading_normal: ns,
            material: tri.material,
            uv,
            point: tri.point(b1, b2),
            opacity: self.opacity_at(prim, b1, b2),
            winding_consistent: self.scene.winding_consistent(prim.tri),
        }
    }

    /// True when an opaque surface lies on the ray with `0 < t < t_max`.
    /// Partly transparent surfaces do not occlude (use [`Tracer::transmittance_ray`]).
    pub fn occluded_ray(&self, ray: &Ray, t_max: f32) -> bool {
        let Some((dir, _, t_max)) = normalized(ray, t_max) else {
            return false;
        };
        self.rays.add_one();
        let wr = WatertightRay::new(ray.origin, dir);
        !self
            .bvh
            .ray_traverse_miss(oray(ray.origin, dir, t_max), |r, id| {
                let prim = &self.prims[id];
                match wr.intersect(&prim.p, 0.0, r.tmax) {
                    Some((t, b1, b2)) => {
                        if prim.maybe_transparent && self.opacity_at(prim, b1, b2) < 1.0 {
                            f32::INFINITY
                        } else {
                            t
                        }
                    }
                    None => f32::INFINITY,
                }
            })
    }

    /// True when an opaque surface blocks the segment from `origin` to `target` (both should
    /// already be offset off their surfaces with [`offset_ray_origin`]). The segment is
    /// shortened by [`SHADOW_EPSILON`] (relative) at the target end.
    /// Equivalent to `transmittance(origin, target) == Vec3::ZERO`.
    pub fn occluded(&self, origin: Vec3, target: Vec3) -> bool {
        self.occluded_ray(&Ray::new(origin, target - origin), 1.0 - SHADOW_EPSILON)
    }

    /// Fraction of light passing along the ray for `0 < t < t_max`: the product of
    /// `(1 − opacity)` over every surface crossing, as grey RGB (0 if anything opaque is hit).
    /// A crossing exactly through a shared edge can count both triangles there.
    pub fn transmittance_ray(&self, ray: &Ray, t_max: f32) -> Vec3 {
        let Some((dir, _, t_max)) = normalized(ray, t_max) else {
            return Vec3::ONE;
        };
        self.rays.add_one();
        let wr = WatertightRay::new(ray.origin, dir);
        let r = oray(ray.origin, dir, t_max);
        let mut tr = 1.0f32;
        let mut state = self.bvh.new_traversal(r.direction);
        let mut node;
        let bvh = &self.bvh;
        traverse!(bvh, node, state, node.intersect_ray(&r, state.oct_inv4), {
            let prim = &self.prims[state.primitive_id as usize];
            if let Some((_, b1, b2)) = wr.intersect(&prim.p, 0.0, t_max) {
                let o = self.opacity_at(prim, b1, b2);
                tr *= 1.0 - o;
                if tr <= 0.0 {
                    break;
                }
            }
        });
        Vec3::splat(tr.max(0.0))
    }

    /// Transmittance of the segment from `origin` to `target` (see [`Tracer::transmittance_ray`]),
    /// shortened by [`SHADOW_EPSILON`] at the target end like [`Tracer::occluded`].
    pub fn transmittance(&self, origin: Vec3, target: Vec3) -> Vec3 {
        self.transmittance_ray(&Ray::new(origin, target - origin), 1.0 - SHADOW_EPSILON)
    }

    /// Number of BVH nodes (for reports).
    pub fn node_count(&self) -> usize {
        self.bvh.nodes.len()
    }

    /// The raw obvhs closest-hit rate baseline: traverses with obvhs's own (non-watertight)
    /// Möller–Trumbore triangle test and returns only `(t, triangle)`. For benchmarks only.
    #[doc(hidden)]
    pub fn raw_obvhs_closest(
        &self,
        ray: &Ray,
        t_max: f32,
        tris: &[obvhs::triangle::Triangle],
    ) -> Option<(f32, u32)> {
        let mut hit = ORayHit::none();
        let found =
            self.bvh
                .ray_traverse(oray(ray.origin, ray.direction, t_max), &mut hit, |r, id| {
                    tris[id].intersect(r)
                });
        found.then(|| (hit.t, self.prims[hit.primitive_id as usize].tri))
    }

    /// Triangles in BVH leaf order, as obvhs triangles (for [`Tracer::raw_obvhs_closest`]).
    #[doc(hidden)]
    pub fn obvhs_triangles_in_leaf_order(&self) -> Vec<obvhs::triangle::Triangle> {
        self.prims
            .iter()
            .map(|p| {
                let c = |v: Vec3| OVec3A::new(v.x, v.y, v.z);
                obvhs::triangle::Triangle {
                    v0: c(p.p[0]),
                    v1: c(p.p[1]),
                    v2: c(p.p[2]),
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests;
