//! The octahedral map (encoding, texel centres, the wrapped bilinear
//! filter) and the Chebyshev test, as free functions (the parent module's
//! docs give the formulas and the map's orientation).

#![cfg_attr(not(feature = "write"), allow(dead_code))]

use super::{VISIBILITY_CRUSH, VISIBILITY_FLOOR};
use crate::math;
use glam::{Vec2, Vec3};

/// `±1` by the sign bit, `+1` for `+0.0` (the octahedral fold needs a sign
/// that is never zero).
#[inline]
fn sign_not_zero(x: f32) -> f32 {
    if x.is_sign_negative() {
        -1.0
    } else {
        1.0
    }
}

/// Octahedral encoding of a direction (any non-zero length) into `[−1, 1]²`,
/// +Y at the centre (orientation in the [module docs](super); Cigolle et al.
/// 2014). The zero vector maps to the centre (+Y).
#[inline]
pub fn oct_encode(d: Vec3) -> Vec2 {
    let l1 = d.x.abs() + d.y.abs() + d.z.abs();
    let n = if l1 > 0.0 { d / l1 } else { Vec3::Y };
    if n.y >= 0.0 {
        Vec2::new(n.x, n.z)
    } else {
        Vec2::new(
            (1.0 - n.z.abs()) * sign_not_zero(n.x),
            (1.0 - n.x.abs()) * sign_not_zero(n.z),
        )
    }
}

/// Inverse of [`oct_encode`]: the unit direction of map point `e ∈ [−1, 1]²`.
#[inline]
pub fn oct_decode(e: Vec2) -> Vec3 {
    let y = 1.0 - e.x.abs() - e.y.abs();
    let (x, z) = if y < 0.0 {
        (
            (1.0 - e.y.abs()) * sign_not_zero(e.x),
            (1.0 - e.x.abs()) * sign_not_zero(e.y),
        )
    } else {
        (e.x, e.y)
    };
    Vec3::new(x, y, z).normalize()
}

/// Map coordinates `(u, v)` of the centre of texel `(col, row)` of an
/// `resolution × resolution` octahedral map.
#[inline]
pub fn oct_texel_center(resolution: u32, col: u32, row: u32) -> Vec2 {
    let s = resolution as f32;
    Vec2::new(
        -1.0 + (2.0 * col as f32 + 1.0) / s,
        -1.0 + (2.0 * row as f32 + 1.0) / s,
    )
}

/// Index of texel `(i, j)` (column, row; each in `−1..=S`) after the
/// octahedral border wrap of the [module docs](super).
#[inline]
fn wrapped_index(s: i32, mut i: i32, mut j: i32) -> usize {
    if i < 0 {
        i = 0;
        j = s - 1 - j;
    } else if i >= s {
        i = s - 1;
        j = s - 1 - j;
    }
    if j < 0 {
        j = 0;
        i = s - 1 - i;
    } else if j >= s {
        j = s - 1;
        i = s - 1 - i;
    }
    (j * s + i) as usize
}

/// Bilinearly filtered value of one probe's octahedral `map` (`S²` texels of
/// `[μ, μ2]`, row-major, `S = resolution`) in direction `dir`, wrapping
/// across the map's edges so the result is continuous over the sphere.
/// `map.len()` must be `resolution²` (shorter maps read as zero).
pub fn sample_oct_bilinear(map: &[[f32; 2]], resolution: u32, dir: Vec3) -> [f32; 2] {
    let s = resolution.max(1) as i32;
    let e = oct_encode(dir);
    let half = 0.5 * s as f32;
    let x = ((e.x + 1.0) * half - 0.5).clamp(-0.5, s as f32 - 0.5);
    let y = ((e.y + 1.0) * half - 0.5).clamp(-0.5, s as f32 - 0.5);
    let (x0, y0) = (math::floor(x), math::floor(y));
    let (fx, fy) = (x - x0, y - y0);
    let (i0, j0) = (x0 as i32, y0 as i32);
    let at = |i: i32, j: i32| {
        map.get(wrapped_index(s, i, j))
            .copied()
            .unwrap_or([0.0, 0.0])
    };
    let su = s as usize;
    let (a, b, c, d) = if i0 >= 0 && j0 >= 0 && i0 + 1 < s && j0 + 1 < s && map.len() >= su * su {
        // Away from the map's edges: no wrap.
        let k = j0 as usize * su + i0 as usize;
        (map[k], map[k + 1], map[k + su], map[k + su + 1])
    } else {
        (
            at(i0, j0),
            at(i0 + 1, j0),
            at(i0, j0 + 1),
            at(i0 + 1, j0 + 1),
        )
    };
    let mut out = [0.0; 2];
    for k in 0..2 {
        let top = a[k] + (b[k] - a[k]) * fx;
        let bottom = c[k] + (d[k] - c[k]) * fx;
        out[k] = top + (bottom - top) * fy;
    }
    out
}

/// The one-sided Chebyshev (Cantelli) bound on the fraction of a texel's
/// rays that travel at least `d` (Donnelly & Lauritzen 2006): 1 when
/// `d ≤ μ`, else `σ²/(σ² + (d − μ)²)` with `σ² = max(μ2 − μ², min_variance)`.
#[inline]
pub fn chebyshev_bound(d: f32, mu: f32, mu2: f32, min_variance: f32) -> f32 {
    if d.is_nan() || d <= mu {
        return 1.0;
    }
    let var = (mu2 - mu * mu).max(min_variance);
    let t = d - mu;
    var / (var + t * t)
}

/// The visibility of a point at distance `d` (bias already subtracted)
/// given the moments `μ`, `μ2` (DDGI §5): [`chebyshev_bound`] raised to
/// `sharpness`, crushed below [`VISIBILITY_CRUSH`] (`v ← v³/c²`), at least
/// [`VISIBILITY_FLOOR`]. Continuous and non-increasing in `d`.
#[inline]
pub fn chebyshev_visibility(d: f32, mu: f32, mu2: f32, min_variance: f32, sharpness: u32) -> f32 {
    let c = chebyshev_bound(d, mu, mu2, min_variance);
    let mut v = 1.0;
    for _ in 0..sharpness {
        v *= c;
    }
    if v < VISIBILITY_CRUSH {
        v *= v * v / (VISIBILITY_CRUSH * VISIBILITY_CRUSH);
    }
    v.max(VISIBILITY_FLOOR)
}
