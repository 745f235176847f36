//! Scene geometry: boxes, world-space triangles, source objects, and the
//! checks loading runs on them (degenerate triangles, winding).

use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// An axis-aligned box, `min` ≤ `max` componentwise, in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (min = +∞, max = −∞); growing it by any point gives that point.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// A box from two corners (ordered componentwise, so any two opposite corners work).
    pub fn new(a: Vec3, b: Vec3) -> Self {
        Aabb {
            min: a.min(b),
            max: a.max(b),
        }
    }

    /// Grows the box to contain `p`.
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// True when the box contains no point (some `min > max`).
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// True when `p` lies inside or on the boundary.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// True when the closed boxes share a point (touching counts).
    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.cmple(other.max).all() && self.max.cmpge(other.min).all()
    }

    /// `max − min`.
    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }

    /// The centre point.
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Checks that the box can hold a bake: finite, and longer than 0 along
    /// every axis. [`Aabb::EMPTY`] (what [`Scene::bake_box`](super::Scene::bake_box) gives for a
    /// scene without geometry and without a `[bake] box`) is refused as
    /// [`BakeBoxError::NoGeometry`]. Every placement, volume and evaluation
    /// checks its box with this before any work, so a flat scene (one floor
    /// quad) is refused the same way everywhere.
    pub fn check_bake_box(&self) -> Result<(), BakeBoxError> {
        if *self == Aabb::EMPTY {
            return Err(BakeBoxError::NoGeometry);
        }
        let size = self.size();
        if !(self.min.is_finite() && self.max.is_finite() && size.min_element() > 0.0) {
            return Err(BakeBoxError::Flat {
                min: self.min,
                max: self.max,
            });
        }
        Ok(())
    }
}

/// Why a box cannot hold a bake ([`Aabb::check_bake_box`]).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BakeBoxError {
    /// The scene has no geometry to bound a bake and names no `[bake] box`.
    #[error(
        "no bake box: the scene has no geometry to take one from; give one as `[bake] box` in \
         the scene file"
    )]
    NoGeometry,
    /// The box is not finite or has no extent along some axis (a scene of one
    /// floor quad, without a `[bake] box`).
    #[error(
        "the bake box {min} – {max} is empty or flat (every side must be longer than 0); \
         give a `[bake] box` in the scene file"
    )]
    Flat {
        /// Smallest corner, metres.
        min: Vec3,
        /// Largest corner, metres.
        max: Vec3,
    },
}

/// One triangle in world space, with everything needed to shade a hit on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// Vertex positions in metres. The geometric normal is `(p1 − p0) × (p2 − p0)`
    /// (counter-clockwise seen from the front).
    pub positions: [Vec3; 3],
    /// Unit per-vertex shading normals; the unit geometric normal repeated when the source has
    /// none (or gives a zero / non-finite one).
    pub normals: [Vec3; 3],
    /// Per-vertex texture coordinates in the glTF convention (`(0,0)` = top-left of the image);
    /// zero when the source has none.
    pub uvs: [Vec2; 3],
    /// Index into [`Scene::materials`](super::Scene::materials).
    pub material: u32,
}

impl Triangle {
    /// The unnormalised geometric normal `(p1 − p0) × (p2 − p0)`; its length is twice the area.
    pub fn geometric_normal_unnormalized(&self) -> Vec3 {
        let [a, b, c] = self.positions;
        (b - a).cross(c - a)
    }

    /// The unit geometric normal (zero for a degenerate triangle).
    pub fn geometric_normal(&self) -> Vec3 {
        self.geometric_normal_unnormalized().normalize_or_zero()
    }

    /// Area in m².
    pub fn area(&self) -> f32 {
        0.5 * self.geometric_normal_unnormalized().length()
    }

    /// The point with barycentric weights `(1 − b1 − b2, b1, b2)` for vertices 0, 1, 2.
    pub fn point(&self, b1: f32, b2: f32) -> Vec3 {
        let [a, b, c] = self.positions;
        (1.0 - b1 - b2) * a + b1 * b + b2 * c
    }

    /// Interpolated texture coordinate at barycentrics `(b1, b2)` (weights as in [`Triangle::point`]).
    pub fn uv(&self, b1: f32, b2: f32) -> Vec2 {
        let [a, b, c] = self.uvs;
        (1.0 - b1 - b2) * a + b1 * b + b2 * c
    }
}

/// A contiguous range of [`Scene::triangles`](super::Scene::triangles) that came from one source object (an OBJ `o`/`g`
/// group, a glTF mesh primitive, a demo-scene box). Winding is checked per object.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshObject {
    /// `file: object name`.
    pub name: String,
    /// First triangle index.
    pub first: u32,
    /// Number of triangles.
    pub count: u32,
}

/// Zero area in floating point: twice the area is below f32 rounding of the longest edge squared.
pub(super) fn is_degenerate(t: &Triangle) -> bool {
    let [a, b, c] = t.positions;
    let cross = (b - a).cross(c - a).length();
    let longest = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    cross.is_nan() || cross <= f32::EPSILON * longest || longest == 0.0
}

/// A vertex identified by the exact bits of its position.
type VertexKey = [u32; 3];
/// Per undirected edge (lo, hi): uses lo→hi, uses hi→lo, and the triangles using it.
type EdgeUses = HashMap<(VertexKey, VertexKey), (u32, u32, Vec<u32>)>;

/// Winding check within one object. Vertices are identified by their exact position bits.
/// A manifold edge (used by exactly two triangles) is inconsistent when both run it in the same
/// direction; edges used by three or more triangles (touching solids, T-junction-free fins)
/// cannot be judged and are skipped. Returns (per-triangle ok flag, number of inconsistent edges).
pub(super) fn check_winding(tris: &[Triangle]) -> (Vec<bool>, usize) {
    let key = |p: Vec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    let mut edges: EdgeUses = HashMap::new();
    for (i, t) in tris.iter().enumerate() {
        for e in 0..3 {
            let a = key(t.positions[e]);
            let b = key(t.positions[(e + 1) % 3]);
            if a == b {
                continue;
            }
            let (lo, hi, forward) = if a < b { (a, b, true) } else { (b, a, false) };
            let entry = edges.entry((lo, hi)).or_insert((0, 0, Vec::new()));
            if forward {
                entry.0 += 1;
            } else {
                entry.1 += 1;
            }
            entry.2.push(i as u32);
        }
    }
    let mut ok = vec![true; tris.len()];
    let mut bad = 0;
    for (_, (f, r, ts)) in edges {
        if f + r == 2 && (f == 2 || r == 2) {
            bad += 1;
            for t in ts {
                ok[t as usize] = false;
            }
        }
    }
    (ok, bad)
}
