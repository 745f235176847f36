//! Outer cells: the closest point of the convex hull to a point outside it,
//! by descent over hull triangles (see the parent module's docs, "Outside
//! the convex hull").

use super::TetMesh;
use glam::{DVec3, Vec3};

/// Largest fan (hull faces around one hull vertex) visited by the hull descent.
const MAX_FAN: u32 = 1024;

impl TetMesh {
    /// Closest point of the hull to `p` (outside), by descent over hull faces
    /// from face `h`. Returns the face, barycentric weights in it, and the point.
    pub(super) fn closest_on_hull(&self, p: Vec3, mut h: u32) -> (u32, [f32; 3], Vec3) {
        let pd = p.as_dvec3();
        let mut cur = self.closest_in_face(p, h);
        // Distances in f64: neighbouring hull faces are often co-planar, where
        // moving the closest point by δ changes the distance only by O(δ²).
        let dist = |c: &([f32; 3], DVec3, Feature)| (pd - c.1).length_squared();
        for _ in 0..self.hull.len() + 8 {
            let d = dist(&cur);
            // Strictly closer (beyond f64 rounding), so the descent terminates.
            let closer = |d2: f64| d2 < d * (1.0 - 1e-12);
            let next = match cur.2 {
                Feature::Face => None,
                Feature::Edge(k) => {
                    let g = self.hull[h as usize].adjacent[k];
                    let cand = self.closest_in_face(p, g);
                    closer(dist(&cand)).then_some((g, cand))
                }
                Feature::Vertex(k) => {
                    // Rotate around the vertex: the edge opposite local vertex
                    // k + 1 contains it, and consistent winding keeps turning
                    // the same way.
                    let v = self.hull[h as usize].probes[k];
                    let mut best = None;
                    let mut best_d = d;
                    let (mut g, mut kg) = (h, k);
                    for _ in 0..MAX_FAN {
                        g = self.hull[g as usize].adjacent[(kg + 1) % 3];
                        let Some(k2) = self.hull[g as usize].probes.iter().position(|&x| x == v)
                        else {
                            break;
                        };
                        if g == h {
                            break;
                        }
                        kg = k2;
                        let cand = self.closest_in_face(p, g);
                        let d2 = dist(&cand);
                        if closer(d2) && d2 < best_d {
                            best_d = d2;
                            best = Some((g, cand));
                        }
                    }
                    best
                }
            };
            match next {
                Some((g, cand)) => {
                    h = g;
                    cur = cand;
                }
                None => break,
            }
        }
        (h, cur.0, cur.1.as_vec3())
    }

    /// Closest point of hull face `h` to `p`: weights, point and feature.
    pub(super) fn closest_in_face(&self, p: Vec3, h: u32) -> ([f32; 3], DVec3, Feature) {
        let f = self.hull[h as usize]
            .probes
            .map(|v| self.positions[v as usize]);
        closest_point_on_triangle(p, f[0], f[1], f[2])
    }
}

/// Which feature of a triangle holds the closest point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Feature {
    Face,
    /// The edge opposite local vertex `k`.
    Edge(usize),
    /// Local vertex `k`.
    Vertex(usize),
}

/// Closest point of triangle `abc` to `p` with its barycentric weights, by
/// classifying `p` into the triangle's Voronoi regions (vertex, edge, face)
/// — the standard construction, e.g. Ericson, "Real-Time Collision
/// Detection" §5.1.5. Computed in `f64` for robustness on thin triangles.
fn closest_point_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> ([f32; 3], DVec3, Feature) {
    let (p, a, b, c) = (p.as_dvec3(), a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
    let out = |w: [f64; 3], f: Feature| {
        let q: DVec3 = a * w[0] + b * w[1] + c * w[2];
        (w.map(|x| x as f32), q, f)
    };
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return out([1.0, 0.0, 0.0], Feature::Vertex(0));
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return out([0.0, 1.0, 0.0], Feature::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return out([1.0 - v, v, 0.0], Feature::Edge(2));
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return out([0.0, 0.0, 1.0], Feature::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return out([1.0 - w, 0.0, w], Feature::Edge(1));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return out([0.0, 1.0 - w, w], Feature::Edge(0));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    out([1.0 - v - w, v, w], Feature::Face)
}
