//! Which lights a rig evaluates and which are evaluated per vertex: the
//! error-driven split of *Irradiance Rigs* (Yuan, Nowrouzezahrai & Sloan,
//! JGT 2011, §3), from the transition table a bake stores with the rig.
//!
//! The table gives, at light distances `x` (in bounding-sphere radii from
//! the sphere's centre), the rig's error `e(x)` in 8-bit grey levels for a
//! light normalised so that its reflected radiance at the bounding-sphere
//! point nearest to it is white. Errors are linear in intensity, so a real
//! light at `x` has error `g(x) = e(x)·(E_near(x)/π)/L_white` grey levels,
//! `E_near(x)` its own exact irradiance at that nearest point (normal
//! facing the light) when moved along its direction to `x`. `g` falls with
//! distance: the light's transition distance `x*` is where `g` reaches the
//! target ([`transition_distance`]). Closer lights are evaluated exactly
//! per vertex, lights between `x*` and [`TRANSITION_BAND`]`·x*` are
//! cross-faded, farther ones go through the rig ([`rig_weight`]).

use super::Light;
use crate::format::Transition;
use core::f32::consts::PI;
use glam::Vec3;

/// The cross-fade band: a light between `x*` and `TRANSITION_BAND · x*`
/// (bounding radii) is split between the per-vertex path and the rig.
pub const TRANSITION_BAND: f32 = 1.25;

/// Exact irradiance (largest channel) of `light` moved to `x·radius` along
/// unit `dir` from `center`, at `center + radius·dir` with normal `dir`.
fn nearest_point_irradiance(light: &Light, center: Vec3, radius: f32, dir: Vec3, x: f32) -> f32 {
    let moved = light.moved_to(center + dir * (x * radius));
    moved
        .irradiance(center + dir * radius, dir, None)
        .max_element()
}

/// Transition distance `x*` (bounding radii from `center`) of `light` for
/// an error of `target` grey levels with white at reflected radiance
/// `white` (module docs), from the rig's transition `table` (distances
/// increasing): binary search for the bracket where `g` falls to `target`,
/// then linear interpolation in it. The table's first distance if `g` is
/// already below the target there, its last if `g` is still above it (the
/// light is per-vertex within the table's range); 0 (always the rig) for a
/// directional light or an empty table. `center` and `radius` (m) are the
/// object's bounding sphere in the frame of `light`.
pub fn transition_distance(
    table: &[Transition],
    light: &Light,
    center: Vec3,
    radius: f32,
    white: f32,
    target: f32,
) -> f32 {
    let (Some(position), Some(first), Some(last)) = (light.position(), table.first(), table.last())
    else {
        return 0.0;
    };
    let dir = (position - center).try_normalize().unwrap_or(Vec3::Y);
    let g = |t: &Transition| {
        t.error * nearest_point_irradiance(light, center, radius, dir, t.distance) / PI / white
    };
    if g(first) <= target {
        return first.distance;
    }
    let g_last = g(last);
    // NaN (a zero white or radius) also ends here: no bracket to search.
    if g_last > target || g_last.is_nan() || target.is_nan() {
        return last.distance;
    }
    // Invariant: g(lo) > target ≥ g(hi).
    let (mut lo, mut hi) = (0usize, table.len() - 1);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if g(&table[mid]) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let (glo, ghi) = (g(&table[lo]), g(&table[hi]));
    let (xlo, xhi) = (table[lo].distance, table[hi].distance);
    xlo + (glo - target) / (glo - ghi) * (xhi - xlo)
}

/// The rig's share of a light at distance `x` (bounding radii;
/// `f32::INFINITY` for a directional light) with transition distance
/// `x_star`: 0 below `x*` (per vertex), rising linearly to 1 at
/// [`TRANSITION_BAND`]`·x*`, 1 beyond (the rig alone). The per-vertex path
/// takes `1 −` this share.
pub fn rig_weight(x: f32, x_star: f32) -> f32 {
    if x < x_star {
        0.0
    } else if x < TRANSITION_BAND * x_star {
        (x - x_star) / ((TRANSITION_BAND - 1.0) * x_star)
    } else {
        1.0
    }
}
