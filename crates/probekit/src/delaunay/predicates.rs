//! Exact geometric predicates — the only place in [`crate::delaunay`] that looks at
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
//!
//! # Filters (what makes the predicates fast)
//! Each orient3d/insphere first evaluates the determinant in plain `f64` and
//! accepts its sign when `|det|` exceeds a *semi-static* error bound computed
//! from the largest absolute coordinate difference per axis (`Mx`, `My`, `Mz`)
//! — Shewchuk's stage-A bound (`o3derrboundA`, `isperrboundA`, 1997 §4.3) with
//! the permanent replaced by its upper bound in terms of `Mx`, `My`, `Mz`, the
//! idea of CGAL's static filters (Devillers & Pion, "Efficient exact geometric
//! predicates for Delaunay triangulations", ALENEX 2003). Only the rare calls
//! inside the bound go on to an exact evaluation. A [`Kernel`] built for the
//! whole point set adds a second exact stage: when every coordinate is an
//! integer multiple of one power of two `u` and the extent is small in units of
//! `u` (every `f32` grid, and `f32` points in `[0, 1)` on a 2⁻²⁴ raster), the
//! determinants are evaluated exactly in `f64` (tiny extents) or in `i128`
//! integer arithmetic; everything else falls back to the `robust` crate.

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

/// Unit roundoff of `f64`, Shewchuk's ε = 2⁻⁵³.
const EPS: f64 = f64::EPSILON * 0.5;

/// Semi-static orient3d filter factor. Shewchuk (1997, §4.3, `o3derrboundA =
/// (7 + 56ε)ε`) bounds the error of the plain `f64` determinant by
/// `o3derrboundA · permanent`, where the permanent (the determinant expansion
/// with every product replaced by its absolute value) is at most
/// `6·Mx·My·Mz` for per-axis maxima `M` of the absolute coordinate
/// differences. Rounding 7 + 56ε up to 8 leaves more than 12 % for the few
/// roundings in evaluating the bound itself (each a factor `1 + ε`).
const O3D_SEMI_STATIC: f64 = 6.0 * 8.0 * EPS;

/// Semi-static insphere filter factor: Shewchuk's `isperrboundA = (16 + 224ε)ε`
/// times the permanent's bound `24·Mx·My·Mz·(Mx² + My² + Mz²)` (four lifted
/// terms, each a lift `≤ Mx² + My² + Mz²` times a 3×3 permanent `≤ 6·Mx·My·Mz`);
/// 16 + 224ε is rounded up to 17 for the bound's own roundings.
const ISP_SEMI_STATIC: f64 = 24.0 * 17.0 * EPS;

/// The filters are only trusted when every per-axis maximum lies in
/// `[FILTER_MIN, FILTER_MAX]`: then no product in the determinant overflows,
/// and an underflowed product (absolute error ≤ 2⁻¹⁰⁷⁵, scaled by at most
/// three further factors ≤ 2¹⁰⁰) is far below the bound's slack. Inputs that
/// start as `f32` never underflow at all (every non-zero difference is at least
/// 2⁻¹⁴⁹, every product of five at least 2⁻⁷⁴⁵); the check catches extreme `f64`.
const FILTER_MIN: f64 = 7.888_609_052_210_118e-31; // 2⁻¹⁰⁰
const FILTER_MAX: f64 = 1.267_650_600_228_229_4e30; // 2¹⁰⁰

/// Largest coordinate extent, in lattice units, for which the `i128`
/// evaluation of insphere cannot overflow: with differences `|d| ≤ D` every
/// intermediate is at most `72·D⁵ < 2¹²⁷` (see [`Kernel`]).
const I128_MAX_EXTENT: u64 = 1 << 24;

/// Predicates specialised to one point set (see the module docs, "Filters").
///
/// All answers are exact and identical to those of the free functions; the
/// kernel only chooses a cheaper exact stage. When every coordinate is an
/// integer multiple of a power of two `u` and the largest per-axis extent is
/// `D·u`, the coordinate differences are exact `f64` values and the
/// determinants are polynomials in integers `|d| ≤ D` with intermediates at
/// most `6·D³` (orient3d: 2×2 minors `≤ 2D²`, three terms `≤ 2D³`) and
/// `72·D⁵` (insphere: 3×3 minors `≤ 6D³`, lifts `≤ 3D²`, four terms `≤ 18D⁵`).
/// Below 2⁵³ the plain `f64` evaluation is then exact; below 2¹²⁷ it is done in
/// `i128` after scaling by `1/u`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kernel {
    /// `1/u` when the points lie on a lattice of spacing `u = 2^k` with extent
    /// at most [`I128_MAX_EXTENT`] units (integer exact stage); `0` otherwise.
    inv_unit: f64,
    /// Static orient3d filter: `|det| >` this decides the sign (`∞`: none).
    static_orient: f64,
    /// Static insphere filter, likewise.
    static_insphere: f64,
    /// The `f64` orient3d determinant is exact (`6·D³ < 2⁵³`); then
    /// `static_orient` is `0`.
    exact_f64_orient: bool,
    /// The `f64` insphere determinant is exact (`72·D⁵ < 2⁵³`); then
    /// `static_insphere` is `0`.
    exact_f64_insphere: bool,
}

/// Our orientation from the sign of Shewchuk's orient3d determinant (opposite).
#[inline(always)]
fn shewchuk_orientation(det: f64) -> Orientation {
    if det < 0.0 {
        Orientation::Positive
    } else if det > 0.0 {
        Orientation::Negative
    } else {
        Orientation::Zero
    }
}

/// In-sphere answer from the sign of Shewchuk's insphere determinant.
#[inline(always)]
fn insphere_sign(det: f64) -> Option<InSphere> {
    if det > 0.0 {
        Some(InSphere::Inside)
    } else if det < 0.0 {
        Some(InSphere::Outside)
    } else {
        None
    }
}

/// Exponent `k` of the lowest set bit of a non-zero finite `x` (so `x` is an
/// odd integer times `2^k`).
fn low_bit_exponent(x: f64) -> i32 {
    let bits = x.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let frac = bits & ((1u64 << 52) - 1);
    let (mantissa, exp) = if biased == 0 {
        (frac, -1074)
    } else {
        (frac | (1u64 << 52), biased - 1075)
    };
    exp + mantissa.trailing_zeros() as i32
}

impl Kernel {
    /// Semi-static filters plus the `robust` crate: valid for any finite points.
    pub const GENERAL: Kernel = Kernel {
        inv_unit: 0.0,
        static_orient: f64::INFINITY,
        static_insphere: f64::INFINITY,
        exact_f64_orient: false,
        exact_f64_insphere: false,
    };

    /// The kernel for predicates on (any subset of) `pts`, all finite.
    ///
    /// Detects the common power-of-two lattice and its extent (see the type
    /// docs). When every coordinate is a multiple of 2⁻¹⁴⁹ of magnitude at most
    /// 2¹²⁸ (every `f32` is; then no product of up to five differences under-
    /// or overflows), it also sets *static* filter bounds:
    /// the semi-static bounds of the module docs with the per-call maxima
    /// `Mx, My, Mz` replaced by the extents of `pts` (Devillers & Pion 2003),
    /// which bound every difference; rounding is monotone, so the computed
    /// extents bound the computed differences.
    pub fn for_points(pts: &[P3]) -> Kernel {
        let mut k = i32::MAX;
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in pts {
            for a in 0..3 {
                if p[a] != 0.0 {
                    k = k.min(low_bit_exponent(p[a]));
                }
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let mut kernel = Kernel::GENERAL;
        if pts.is_empty() {
            return kernel;
        }
        // Multiples of 2⁻¹⁴⁹ up to 2¹²⁸ in magnitude (every f32 qualifies):
        // non-zero differences are at least 2⁻¹⁴⁹, so products of up to five
        // stay normal, and at most 2¹²⁹, so they stay finite.
        const MAX_MAGNITUDE: f64 = 3.402_823_669_209_385e38; // 2¹²⁸
        let no_underflow =
            k >= -149 && (0..3).all(|a| lo[a].abs().max(hi[a].abs()) <= MAX_MAGNITUDE);
        if no_underflow {
            let [ex, ey, ez] = [0, 1, 2].map(|a| hi[a] - lo[a]);
            kernel.static_orient = O3D_SEMI_STATIC * (ex * ey * ez);
            kernel.static_insphere =
                ISP_SEMI_STATIC * (ex * ey * ez) * (ex * ex + ey * ey + ez * ez);
        }
        // u⁵ must stay a normal f64 for the exact f64 evaluation; u·2²⁴ must too.
        if !(-200..=900).contains(&k) {
            return kernel;
        }
        let inv_unit = 2f64.powi(-k);
        let mut extent = 0u64;
        for a in 0..3 {
            let d = (hi[a] - lo[a]) * inv_unit;
            if d.is_nan() || d > I128_MAX_EXTENT as f64 {
                return kernel;
            }
            // hi - lo is a multiple of u below 2²⁴·u: exact, and d an integer.
            extent = extent.max(d as u64);
        }
        kernel.inv_unit = inv_unit;
        let d = extent as u128;
        if 6 * d * d * d < 1u128 << 53 {
            kernel.exact_f64_orient = true;
            kernel.static_orient = 0.0;
        }
        if 72 * d * d * d * d * d < 1u128 << 53 {
            kernel.exact_f64_insphere = true;
            kernel.static_insphere = 0.0;
        }
        kernel
    }

    /// Exact orientation of `(a, b, c, d)`; see [`Orientation`].
    #[inline(always)]
    pub fn orient3d(&self, a: &P3, b: &P3, c: &P3, d: &P3) -> Orientation {
        // Shewchuk's orient3d: det[a − d; b − d; c − d], the opposite sign of ours.
        let (adx, ady, adz) = (a[0] - d[0], a[1] - d[1], a[2] - d[2]);
        let (bdx, bdy, bdz) = (b[0] - d[0], b[1] - d[1], b[2] - d[2]);
        let (cdx, cdy, cdz) = (c[0] - d[0], c[1] - d[1], c[2] - d[2]);
        let det = adz * (bdx * cdy - cdx * bdy)
            + bdz * (cdx * ady - adx * cdy)
            + cdz * (adx * bdy - bdx * ady);
        if det.abs() > self.static_orient {
            return shewchuk_orientation(det);
        }
        if self.exact_f64_orient {
            return Orientation::Zero; // det == 0 exactly
        }
        let mx = adx.abs().max(bdx.abs()).max(cdx.abs());
        let my = ady.abs().max(bdy.abs()).max(cdy.abs());
        let mz = adz.abs().max(bdz.abs()).max(cdz.abs());
        if mx.min(my).min(mz) >= FILTER_MIN
            && mx.max(my).max(mz) <= FILTER_MAX
            && det.abs() > O3D_SEMI_STATIC * (mx * my * mz)
        {
            return shewchuk_orientation(det);
        }
        self.orient3d_exact(a, b, c, d)
    }

    /// The exact stage of [`Kernel::orient3d`].
    #[cold]
    #[inline(never)]
    fn orient3d_exact(&self, a: &P3, b: &P3, c: &P3, d: &P3) -> Orientation {
        let sign = if self.inv_unit != 0.0 {
            let s = self.inv_unit;
            let q = |p: &P3| [0, 1, 2].map(|k| i128::from(((p[k] - d[k]) * s) as i64));
            let (pa, pb, pc) = (q(a), q(b), q(c));
            let det = pa[2] * (pb[0] * pc[1] - pc[0] * pb[1])
                + pb[2] * (pc[0] * pa[1] - pa[0] * pc[1])
                + pc[2] * (pa[0] * pb[1] - pb[0] * pa[1]);
            det.signum() as f64
        } else {
            robust::orient3d(c3(a), c3(b), c3(c), c3(d))
        };
        shewchuk_orientation(sign)
    }

    /// Exact in-sphere test of `e` against the circumsphere of the positively
    /// oriented tetrahedron `t`, without perturbation (`None` when co-spherical).
    #[inline(always)]
    pub fn insphere(&self, t: [&P3; 4], e: &P3) -> Option<InSphere> {
        // Shewchuk's insphere(pa, pb, pc, pd, pe) wants his positive
        // orientation (= our negative): pa, pb = t[1], t[0].
        let [pb, pa, pc, pd] = t;
        let (aex, aey, aez) = (pa[0] - e[0], pa[1] - e[1], pa[2] - e[2]);
        let (bex, bey, bez) = (pb[0] - e[0], pb[1] - e[1], pb[2] - e[2]);
        let (cex, cey, cez) = (pc[0] - e[0], pc[1] - e[1], pc[2] - e[2]);
        let (dex, dey, dez) = (pd[0] - e[0], pd[1] - e[1], pd[2] - e[2]);
        let ab = aex * bey - bex * aey;
        let bc = bex * cey - cex * bey;
        let cd = cex * dey - dex * cey;
        let da = dex * aey - aex * dey;
        let ac = aex * cey - cex * aey;
        let bd = bex * dey - dex * bey;
        let abc = aez * bc - bez * ac + cez * ab;
        let bcd = bez * cd - cez * bd + dez * bc;
        let cda = cez * da + dez * ac + aez * cd;
        let dab = dez * ab + aez * bd + bez * da;
        let alift = aex * aex + aey * aey + aez * aez;
        let blift = bex * bex + bey * bey + bez * bez;
        let clift = cex * cex + cey * cey + cez * cez;
        let dlift = dex * dex + dey * dey + dez * dez;
        let det = (dlift * abc - clift * dab) + (blift * cda - alift * bcd);
        if det.abs() > self.static_insphere {
            return insphere_sign(det);
        }
        if self.exact_f64_insphere {
            return None; // det == 0 exactly
        }
        let mx = aex.abs().max(bex.abs()).max(cex.abs().max(dex.abs()));
        let my = aey.abs().max(bey.abs()).max(cey.abs().max(dey.abs()));
        let mz = aez.abs().max(bez.abs()).max(cez.abs().max(dez.abs()));
        if mx.min(my).min(mz) >= FILTER_MIN
            && mx.max(my).max(mz) <= FILTER_MAX
            && det.abs() > ISP_SEMI_STATIC * (mx * my * mz) * (mx * mx + my * my + mz * mz)
        {
            return insphere_sign(det);
        }
        self.insphere_exact(t, e)
    }

    /// The exact stage of [`Kernel::insphere`].
    #[cold]
    #[inline(never)]
    fn insphere_exact(&self, t: [&P3; 4], e: &P3) -> Option<InSphere> {
        let sign = if self.inv_unit != 0.0 {
            let s = self.inv_unit;
            // |differences| ≤ 2²⁴: products of two fit i64 easily.
            let q = |p: &P3| [0, 1, 2].map(|k| ((p[k] - e[k]) * s) as i64);
            let [pb, pa, pc, pd] = t.map(q);
            let m2 = |p: [i64; 3], r: [i64; 3]| i128::from(p[0] * r[1] - r[0] * p[1]);
            let (ab, bc, cd) = (m2(pa, pb), m2(pb, pc), m2(pc, pd));
            let (da, ac, bd) = (m2(pd, pa), m2(pa, pc), m2(pb, pd));
            let z = |p: [i64; 3]| i128::from(p[2]);
            let abc = z(pa) * bc - z(pb) * ac + z(pc) * ab;
            let bcd = z(pb) * cd - z(pc) * bd + z(pd) * bc;
            let cda = z(pc) * da + z(pd) * ac + z(pa) * cd;
            let dab = z(pd) * ab + z(pa) * bd + z(pb) * da;
            let lift = |p: [i64; 3]| i128::from(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            let det = (lift(pd) * abc - lift(pc) * dab) + (lift(pb) * cda - lift(pa) * bcd);
            det.signum() as f64
        } else {
            robust::insphere(c3(t[1]), c3(t[0]), c3(t[2]), c3(t[3]), c3(e))
        };
        insphere_sign(sign)
    }

    /// Perturbed in-sphere test of point `e` (rank `re`) against the positively
    /// oriented tetrahedron `t` with vertex ranks `rt` (all ranks distinct).
    /// See the module docs for the rule.
    #[inline(always)]
    pub fn insphere_perturbed(&self, t: [&P3; 4], rt: [u32; 4], e: &P3, re: u32) -> InSphere {
        if let Some(s) = self.insphere(t, e) {
            return s;
        }
        self.perturbed_tie(t, rt, e, re)
    }

    /// Resolves an exact co-spherical tie (where [`Kernel::insphere`] is
    /// `None`) by the lifting perturbation; arguments as for
    /// [`Kernel::insphere_perturbed`]. Vertices of `t` for which the
    /// orientation with `e` substituted is `Zero` are skipped.
    #[inline(never)]
    pub fn perturbed_tie(&self, t: [&P3; 4], rt: [u32; 4], e: &P3, re: u32) -> InSphere {
        // Visit the vertices of t with rank above re in decreasing rank:
        // `rank · 4 + index` sorted by a branch-free network of five
        // compare-exchanges (on a grid about a third of all conflict tests are
        // ties; this measured 8 % faster there than `sort_unstable_by`).
        let mut key = [0, 1, 2, 3].map(|i| u64::from(rt[i]) << 2 | i as u64);
        for (a, b) in [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)] {
            let (x, y) = (key[a], key[b]);
            key[a] = x.max(y);
            key[b] = x.min(y);
        }
        for k in key {
            let i = (k & 3) as usize;
            if rt[i] < re {
                break;
            }
            let mut q = t;
            q[i] = e;
            match self.orient3d(q[0], q[1], q[2], q[3]) {
                Orientation::Positive => return InSphere::Inside,
                Orientation::Negative => return InSphere::Outside,
                Orientation::Zero => {}
            }
        }
        InSphere::Outside
    }

    /// Conflict test of point `e` with the infinite cell whose finite face is
    /// `f = [a, b, c]`, oriented so that `(a, b, c, ∞)` is positive. Only in
    /// the co-planar case is `coplanar()` called, for `(inner, rf, re)`: any
    /// point strictly on the negative side of `abc`, the ranks of `f` and
    /// that of `e`. Returns `Inside` when `e` is in the open half-space beyond
    /// `abc` or in the perturbed circumdisk of `abc`.
    #[inline(always)]
    pub fn in_infinite_cell<'p>(
        &self,
        f: [&P3; 3],
        e: &P3,
        coplanar: impl FnOnce() -> (&'p P3, [u32; 3], u32),
    ) -> InSphere {
        match self.orient3d(f[0], f[1], f[2], e) {
            Orientation::Positive => InSphere::Inside,
            Orientation::Negative => InSphere::Outside,
            Orientation::Zero => {
                let (inner, rf, re) = coplanar();
                self.in_infinite_cell_coplanar(f, rf, inner, e, re)
            }
        }
    }

    /// [`Kernel::in_infinite_cell`] for `e` in the plane of `f`.
    #[cold]
    #[inline(never)]
    fn in_infinite_cell_coplanar(
        &self,
        f: [&P3; 3],
        rf: [u32; 3],
        inner: &P3,
        e: &P3,
        re: u32,
    ) -> InSphere {
        // A sphere through a, b, c and a point off the plane cuts the plane in
        // abc's circumcircle, so the exact test is an in-sphere test against
        // (b, a, c, inner), which is positive.
        let t = [f[1], f[0], f[2], inner];
        if let Some(s) = self.insphere(t, e) {
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

/// Exact orientation of the tetrahedron `(a, b, c, d)` (filtered; see the module docs).
#[inline]
pub fn orient3d(a: &P3, b: &P3, c: &P3, d: &P3) -> Orientation {
    Kernel::GENERAL.orient3d(a, b, c, d)
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
    Kernel::GENERAL.insphere(t, e)
}

/// Perturbed in-sphere test of point `e` (rank `re`) against the positively
/// oriented tetrahedron `t` with vertex ranks `rt` (all ranks distinct).
/// See the module docs for the rule.
pub fn insphere_perturbed(t: [&P3; 4], rt: [u32; 4], e: &P3, re: u32) -> InSphere {
    Kernel::GENERAL.insphere_perturbed(t, rt, e, re)
}

/// Conflict test of point `e` (rank `re`) with the infinite cell whose finite
/// face is `f = [a, b, c]`, oriented so that `(a, b, c, ∞)` is positive (the
/// point at infinity lies on the positive side of `abc`). `inner` is any point
/// strictly on the negative side of `abc` (the fourth vertex of the finite cell
/// across the face). Returns `Inside` when `e` is in the cell's "circumsphere"
/// (the open half-space beyond `abc`, plus the perturbed circumdisk of `abc`).
pub fn in_infinite_cell(f: [&P3; 3], rf: [u32; 3], inner: &P3, e: &P3, re: u32) -> InSphere {
    Kernel::GENERAL.in_infinite_cell(f, e, || (inner, rf, re))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use proptest::test_runner::TestCaseError;

    const A: P3 = [0.0, 0.0, 0.0];
    const B: P3 = [1.0, 0.0, 0.0];
    const C: P3 = [0.0, 1.0, 0.0];
    const D: P3 = [0.0, 0.0, 1.0];

    // ---- Filtered and lattice predicates against the `robust` crate ----

    /// Shewchuk's exact orient3d through `robust`, in our sign convention.
    fn robust_orient(a: &P3, b: &P3, c: &P3, d: &P3) -> Orientation {
        shewchuk_orientation(robust::orient3d(c3(a), c3(b), c3(c), c3(d)))
    }

    /// Shewchuk's exact insphere determinant through `robust` (argument order
    /// as in [`Kernel::insphere`]; the sign relation holds for any orientation).
    fn robust_insphere(t: [&P3; 4], e: &P3) -> Option<InSphere> {
        insphere_sign(robust::insphere(
            c3(t[1]),
            c3(t[0]),
            c3(t[2]),
            c3(t[3]),
            c3(e),
        ))
    }

    /// Every orient3d of 4 and insphere of 5 points of `pts` (taken as
    /// consecutive windows and all vertex substitutions used by the builder)
    /// agrees with `robust` under the general kernel, the kernel built for
    /// `pts` and that kernel's exact stage alone; returns how many exact zeros
    /// were seen (so callers can check the inputs really are degenerate).
    fn agree_with_robust(pts: &[P3]) -> Result<usize, TestCaseError> {
        let kernels = [Kernel::GENERAL, Kernel::for_points(pts)];
        let mut zeros = 0;
        let n = pts.len();
        for s in 0..n {
            let q: [&P3; 5] = std::array::from_fn(|i| &pts[(s + i) % n]);
            let o = robust_orient(q[0], q[1], q[2], q[3]);
            let i = robust_insphere([q[0], q[1], q[2], q[3]], q[4]);
            zeros += usize::from(o == Orientation::Zero) + usize::from(i.is_none());
            for k in &kernels {
                prop_assert_eq!(k.orient3d(q[0], q[1], q[2], q[3]), o, "{:?} {:?}", k, q);
                prop_assert_eq!(k.orient3d_exact(q[0], q[1], q[2], q[3]), o);
                prop_assert_eq!(
                    k.insphere([q[0], q[1], q[2], q[3]], q[4]),
                    i,
                    "{:?} {:?}",
                    k,
                    q
                );
                prop_assert_eq!(k.insphere_exact([q[0], q[1], q[2], q[3]], q[4]), i);
                // The walk's and the perturbation's substituted orientations.
                for j in 0..4 {
                    let mut r = [q[0], q[1], q[2], q[3]];
                    r[j] = q[4];
                    prop_assert_eq!(
                        k.orient3d(r[0], r[1], r[2], r[3]),
                        robust_orient(r[0], r[1], r[2], r[3])
                    );
                }
            }
        }
        Ok(zeros)
    }

    /// `x` moved by `k` units in the last place (as `f32`).
    fn nudge(x: f32, k: i8) -> f32 {
        let mut x = x;
        for _ in 0..k.unsigned_abs() {
            x = if k > 0 { x.next_up() } else { x.next_down() };
        }
        x
    }

    fn to_p3(v: &[[f32; 3]]) -> Vec<P3> {
        v.iter().map(|p| p.map(f64::from)).collect()
    }

    #[test]
    fn lattice_detection() {
        let grid: Vec<P3> = (0..27)
            .map(|i| [(i % 3) as f64, (i / 3 % 3) as f64, (i / 9) as f64])
            .collect();
        let k = Kernel::for_points(&grid);
        assert!(k.exact_f64_orient && k.exact_f64_insphere && k.inv_unit == 1.0);
        // f32 points in [0, 1) on the 2⁻²⁴ raster: i128 stage, no exact f64.
        let raster = [
            [0.0, 0.5, 1.0 - 2f64.powi(-24)],
            [2f64.powi(-24), 0.25, 0.75],
        ];
        let k = Kernel::for_points(&raster);
        assert!(!k.exact_f64_insphere && k.inv_unit == 2f64.powi(24));
        assert!(k.static_insphere.is_finite() && k.static_insphere > 0.0);
        // Extent 2²⁵ units: no lattice stage, static filters still on.
        let wide = [[0.0, 0.0, 0.0], [1.0, 2f64.powi(-25), 0.0]];
        let k = Kernel::for_points(&wide);
        assert_eq!(k.inv_unit, 0.0);
        assert!(k.static_orient.is_finite());
        // Not a multiple of 2⁻¹⁴⁹: no static filter.
        let tiny = [[1e-300, 0.0, 0.0], [1.0, 1.0, 1.0]];
        assert_eq!(Kernel::for_points(&tiny).static_orient, f64::INFINITY);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// Grid points (every cube co-spherical, many co-planar quadruples),
        /// scaled by a power of two, shifted, and some coordinates moved by
        /// one or two ulps: the hardest inputs for a filter.
        #[test]
        fn filters_agree_on_nudged_grids(
            cells in proptest::collection::vec((0i8..3, 0i8..3, 0i8..3, -2i8..=2, 0u8..4), 5..12),
            scale_exp in -30i32..12,
            offset in -100.0f32..100.0,
        ) {
            let h = 2f32.powi(scale_exp);
            let pts: Vec<[f32; 3]> = cells
                .iter()
                .map(|&(x, y, z, k, axis)| {
                    let mut p = [x, y, z].map(|c| offset + c as f32 * h);
                    if axis < 3 {
                        p[axis as usize] = nudge(p[axis as usize], k);
                    }
                    p
                })
                .collect();
            agree_with_robust(&to_p3(&pts))?;
        }

        /// Points rounded onto a sphere (near co-spherical, tiny non-zero
        /// insphere determinants), some moved by an ulp.
        #[test]
        fn filters_agree_near_spheres(
            dirs in proptest::collection::vec((-3i8..=3, -3i8..=3, -3i8..=3, -1i8..=1), 5..10),
            radius in 1e-3f32..1e3,
            centre in (-10.0f32..10.0, -10.0f32..10.0, -10.0f32..10.0),
        ) {
            let pts: Vec<[f32; 3]> = dirs
                .iter()
                .filter(|d| (d.0, d.1, d.2) != (0, 0, 0))
                .map(|&(x, y, z, k)| {
                    let v = glam::Vec3::new(x as f32, y as f32, z as f32).normalize() * radius;
                    [nudge(centre.0 + v.x, k), centre.1 + v.y, centre.2 + v.z]
                })
                .collect();
            if pts.len() >= 5 {
                agree_with_robust(&to_p3(&pts))?;
            }
        }

        /// Integer lattices large enough for the i128 stage (extent up to
        /// 2²⁴ units), with exactly co-spherical and co-planar subsets.
        #[test]
        fn integer_stage_agrees_on_wide_lattices(
            base in proptest::collection::vec((0i32..3, 0i32..3, 0i32..3), 5..10),
            spread in 0u32..=24,
            jitter in proptest::collection::vec((-1i32..=1, -1i32..=1), 10),
        ) {
            let step = (1i64 << spread).min((1 << 23) - 1) as f64; // 2·step + 1 < 2²⁴
            let pts: Vec<P3> = base
                .iter()
                .zip(jitter.iter().cycle())
                .map(|(&(x, y, z), &(jx, jy))| {
                    [x as f64 * step + jx as f64, y as f64 * step + jy as f64, z as f64 * step]
                })
                .collect();
            let k = Kernel::for_points(&pts);
            prop_assert!(k.inv_unit != 0.0);
            agree_with_robust(&pts)?;
        }
    }

    #[test]
    fn degenerate_sets_do_reach_the_exact_stages() {
        // The agreement tests above are only meaningful if exact zeros occur.
        let cube: Vec<P3> = (0..8)
            .map(|i| [(i & 1) as f64, (i >> 1 & 1) as f64, (i >> 2) as f64])
            .collect();
        let zeros = agree_with_robust(&cube).unwrap();
        assert!(zeros >= 8, "{zeros}");
    }

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
