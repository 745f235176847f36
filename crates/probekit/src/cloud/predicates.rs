//! Exact geometric predicates — the only place in [`crate::cloud`] that looks at
//! the sign of a floating-point determinant.
//!
//! All predicates evaluate Shewchuk's adaptive-precision determinants
//! ("Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric
//! Predicates", 1997) through the `robust` crate, on `f64` copies of the input
//! (every `f32` is exactly representable as `f64`, so the answers are exact for
//! the input points). Callers get enums, never a raw determinant.
//!
//! # Orientation convention
//! A tetrahedron `(a, b, c, d)` is [`Orientation::Positive`] when
//! `det[b − a, c − a, d − a] > 0`, i.e. `d` lies on the side of triangle `abc`
//! from which `abc` appears clockwise (right-handed: the signed volume is positive).
//! Note this is the opposite sign of `robust::orient3d`, which is positive when
//! `d` lies *below* `abc` seen counter-clockwise.
//!
//! # Symbolic perturbation
//! Co-spherical configurations (every cube of a regular grid) are resolved by
//! the lifting perturbation of Devillers & Teillaud, "Perturbations for
//! Delaunay and weighted Delaunay 3D triangulations" (CGAL, 2011): point `i` is
//! lifted to `|p_i|² + δ_i` with `δ_i > 0` infinitesimal and
//! `δ_i ≫ δ_j` whenever `rank(i) > rank(j)`. Expanding the 5×5 lifted
//! determinant along the perturbation column, the sign of a degenerate
//! in-sphere test is the sign of the first non-zero cofactor, taken in order of
//! decreasing rank; each cofactor is an orientation of four of the points.
//! Raising the query point's lift moves it outwards, so when the query point
//! has the highest rank it is [`InSphere::Outside`]; raising a tetrahedron
//! vertex `v` puts the query inside exactly when it lies on `v`'s side of the
//! face opposite `v`. The perturbed answer is never "on the sphere".

use robust::{Coord, Coord3D};

/// A point in `f64` (exact copy of the `f32` input).
pub type P3 = [f64; 3];

/// Sign of the signed volume of a tetrahedron `(a, b, c, d)`; see the module docs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Orientation {
    /// `det[b − a, c − a, d − a] > 0`.
    Positive,
    /// `det[b − a, c − a, d − a] < 0`.
    Negative,
    /// The four points are co-planar.
    Zero,
}

/// Where a query point lies relative to a (symbolically perturbed) circumsphere.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InSphere {
    /// Strictly inside (or inside after perturbation).
    Inside,
    /// Strictly outside (or outside after perturbation).
    Outside,
}

#[inline(always)]
fn c3(p: &P3) -> Coord3D<f64> {
    Coord3D {
        x: p[0],
        y: p[1],
        z: p[2],
    }
}

/// Exact orientation of the tetrahedron `(a, b, c, d)`.
#[inline]
pub fn orient3d(a: &P3, b: &P3, c: &P3, d: &P3) -> Orientation {
    let det = robust::orient3d(c3(a), c3(b), c3(c), c3(d));
    if det < 0.0 {
        Orientation::Positive
    } else if det > 0.0 {
        Orientation::Negative
    } else {
        Orientation::Zero
    }
}

/// Exact test whether `a`, `b`, `c` are co-linear (all three coordinate-plane
/// projections of the triangle are degenerate).
pub fn collinear(a: &P3, b: &P3, c: &P3) -> bool {
    (0..3).all(|axis| orient2d_projected(a, b, c, axis) == 0.0)
}

/// `orient2d` of the projection that drops coordinate `axis`.
#[inline]
fn orient2d_projected(a: &P3, b: &P3, c: &P3, axis: usize) -> f64 {
    let (i, j) = match axis {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    let p = |q: &P3| Coord { x: q[i], y: q[j] };
    robust::orient2d(p(a), p(b), p(c))
}

/// Exact in-plane orientation of `p` relative to the directed line `b → c`,
/// compared with that of `a`, for four co-planar points with `a`, `b`, `c` not
/// co-linear: `Positive` if `p` is on `a`'s side, `Negative` on the other side,
/// `Zero` on the line.
pub fn coplanar_same_side(a: &P3, b: &P3, c: &P3, p: &P3) -> Orientation {
    // An axis projection with a non-degenerate image of abc is an affine
    // bijection of the plane, so it preserves sides of lines.
    for axis in 0..3 {
        let ref_sign = orient2d_projected(a, b, c, axis);
        if ref_sign != 0.0 {
            let s = orient2d_projected(p, b, c, axis);
            return if s == 0.0 {
                Orientation::Zero
            } else if (s > 0.0) == (ref_sign > 0.0) {
                Orientation::Positive
            } else {
                Orientation::Negative
            };
        }
    }
    Orientation::Zero
}

/// Exact in-sphere test of `e` against the circumsphere of the positively
/// oriented tetrahedron `t = [a, b, c, d]`, without perturbation:
/// `Some(Inside)`, `Some(Outside)` or `None` when the five points are co-spherical.
#[inline]
pub fn insphere_exact(t: [&P3; 4], e: &P3) -> Option<InSphere> {
    // robust::insphere wants robust-positive (= our negative) orientation: swap a, b.
    let det = robust::insphere(c3(t[1]), c3(t[0]), c3(t[2]), c3(t[3]), c3(e));
    if det > 0.0 {
        Some(InSphere::Inside)
    } else if det < 0.0 {
        Some(InSphere::Outside)
    } else {
        None
    }
}

/// Perturbed in-sphere test of point `e` (rank `re`) against the positively
/// oriented tetrahedron `t` with vertex ranks `rt` (all ranks distinct).
/// See the module docs for the rule.
pub fn insphere_perturbed(t: [&P3; 4], rt: [u32; 4], e: &P3, re: u32) -> InSphere {
    if let Some(s) = insphere_exact(t, e) {
        return s;
    }
    perturbed_tie(t, rt, e, re)
}

/// Resolves an exact co-spherical (or, for infinite cells, co-circular) tie by
/// the lifting perturbation. Vertices of `t` may include points for which the
/// orientation with `e` substituted is always `Zero`; those are skipped.
fn perturbed_tie(t: [&P3; 4], rt: [u32; 4], e: &P3, re: u32) -> InSphere {
    // Visit the vertices of t with rank above re in decreasing rank.
    let mut order = [0usize, 1, 2, 3];
    order.sort_unstable_by(|&i, &j| rt[j].cmp(&rt[i]));
    for &i in &order {
        if rt[i] < re {
            break;
        }
        let mut q = t;
        q[i] = e;
        match orient3d(q[0], q[1], q[2], q[3]) {
            Orientation::Positive => return InSphere::Inside,
            Orientation::Negative => return InSphere::Outside,
            Orientation::Zero => {}
        }
    }
    InSphere::Outside
}

/// Conflict test of point `e` (rank `re`) with the infinite cell whose finite
/// face is `f = [a, b, c]`, oriented so that `(a, b, c, ∞)` is positive (the
/// point at infinity lies on the positive side of `abc`). `inner` is any point
/// strictly on the negative side of `abc` (the fourth vertex of the finite cell
/// across the face). Returns `Inside` when `e` is in the cell's "circumsphere"
/// (the open half-space beyond `abc`, plus the perturbed circumdisk of `abc`).
pub fn in_infinite_cell(f: [&P3; 3], rf: [u32; 3], inner: &P3, e: &P3, re: u32) -> InSphere {
    match orient3d(f[0], f[1], f[2], e) {
        Orientation::Positive => InSphere::Inside,
        Orientation::Negative => InSphere::Outside,
        Orientation::Zero => {
            // e is in the plane of abc; a sphere through a, b, c and a point off
            // the plane cuts the plane in abc's circumcircle, so the exact test
            // is an in-sphere test against (b, a, c, inner), which is positive.
            let t = [f[1], f[0], f[2], inner];
            if let Some(s) = insphere_exact(t, e) {
                return s;
            }
            // Co-circular: perturb within the plane (the 3D rule restricted to
            // the plane; substituting e for the point at infinity is always
            // co-planar and therefore skipped).
            let mut order = [0usize, 1, 2];
            order.sort_unstable_by(|&i, &j| rf[j].cmp(&rf[i]));
            for &i in &order {
                if rf[i] < re {
                    break;
                }
                let (o1, o2) = ((i + 1) % 3, (i + 2) % 3);
                match coplanar_same_side(f[i], f[o1], f[o2], e) {
                    Orientation::Positive => return InSphere::Inside,
                    Orientation::Negative => return InSphere::Outside,
                    Orientation::Zero => {}
                }
            }
            InSphere::Outside
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: P3 = [0.0, 0.0, 0.0];
    const B: P3 = [1.0, 0.0, 0.0];
    const C: P3 = [0.0, 1.0, 0.0];
    const D: P3 = [0.0, 0.0, 1.0];

    #[test]
    fn orientation_sign_matches_signed_volume() {
        // det[b-a, c-a, d-a] of the unit corner tetrahedron is +1.
        assert_eq!(orient3d(&A, &B, &C, &D), Orientation::Positive);
        assert_eq!(orient3d(&B, &A, &C, &D), Orientation::Negative);
        assert_eq!(orient3d(&A, &B, &C, &[1.0, 1.0, 0.0]), Orientation::Zero);
    }

    #[test]
    fn insphere_matches_distance_to_circumcentre() {
        // Circumcentre of the corner tetrahedron is (1/2, 1/2, 1/2), radius² 3/4.
        let t = [&A, &B, &C, &D];
        assert_eq!(insphere_exact(t, &[0.5, 0.5, 0.6]), Some(InSphere::Inside));
        assert_eq!(
            insphere_exact(t, &[1.0, 1.0, 1.01]),
            Some(InSphere::Outside)
        );
        assert_eq!(insphere_exact(t, &[1.0, 1.0, 1.0]), None); // cube corner
        assert_eq!(insphere_exact(t, &[1.0, 1.0, 0.99]), Some(InSphere::Inside));
    }

    #[test]
    fn perturbed_tie_is_antisymmetric_for_cube() {
        // Cube corners: the two tetrahedra sharing a face, each tested against
        // the other's apex, must not both be "Inside" (else Bowyer–Watson breaks).
        let e = [1.0, 1.0, 1.0];
        let t = [&A, &B, &C, &D];
        let r1 = insphere_perturbed(t, [0, 1, 2, 3], &e, 4);
        assert_eq!(r1, InSphere::Outside); // query has the top rank
        let r2 = insphere_perturbed(t, [0, 1, 2, 4], &e, 3);
        // Raising d: is e on d's side of abc? yes → Inside.
        assert_eq!(r2, InSphere::Inside);
    }
}
