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

use super::{Light, RigError, RigState, SphereTable};
use crate::format::{Rig, Transition};
use crate::prelude::*;
use alloc::sync::Arc;
use core::f32::consts::PI;
use glam::{Affine3A, Vec3};

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

/// One object's rig with the split: near lights evaluated exactly per
/// vertex (spheres and disks through the [`SphereTable`]), lights in the
/// transition band cross-faded, the rest through the rig (*Irradiance
/// Rigs* §3). Made from a file's rig ([`SplitRig::new`],
/// [`crate::Probes::split_rig`]); [`SplitRig::update`] once per frame with
/// the scene's lights, then [`SplitRig::irradiance`] per vertex.
///
/// The bounding sphere the transition distances are measured from is
/// centred on the rig box's centre with the rig's
/// [`bounding_radius`](crate::format::Rig::bounding_radius) (the sphere the
/// baker measured its transition table from), or half the box's diagonal
/// where the file does not record it, in the object's own coordinates.
#[derive(Clone, Debug)]
pub struct SplitRig {
    state: RigState,
    samples: Vec<Vec3>,
    sample_sh: Vec<Vec3>,
    transitions: Vec<Transition>,
    center: Vec3,
    radius: f32,
    table: Arc<SphereTable>,
    /// This frame's lights in object coordinates with their per-vertex
    /// share `1 − w` (only those with `w < 1`).
    near: Vec<(Light, f32)>,
}

impl SplitRig {
    /// The per-object state of `rig` (parameters zero until the first
    /// update), sharing the sphere-light `table`.
    pub fn new(rig: &Rig, table: Arc<SphereTable>) -> Result<Self, RigError> {
        let state = RigState::new(rig)?;
        let n2 = state.order() * state.order();
        let len = n2
            .checked_mul(rig.samples.len())
            .ok_or(RigError::ParameterCount)?;
        Ok(Self {
            samples: rig.samples.clone(),
            sample_sh: vec![Vec3::ZERO; len],
            transitions: rig.transitions.clone(),
            center: 0.5 * (rig.bbox_min + rig.bbox_max),
            radius: if rig.bounding_radius > 0.0 {
                rig.bounding_radius
            } else {
                (0.5 * (rig.bbox_max - rig.bbox_min).length()).max(f32::MIN_POSITIVE)
            },
            table,
            near: Vec::new(),
            state,
        })
    }

    /// The same rig measuring transition distances from the sphere
    /// (`center`, `radius`, object coordinates, m) instead of the one the
    /// file records: for a rig fitted elsewhere whose transition table was
    /// measured from another sphere. A radius that is not positive and
    /// finite, or a centre that is not finite, is an error.
    pub fn with_bounding_sphere(mut self, center: Vec3, radius: f32) -> Result<Self, RigError> {
        if !(center.is_finite() && radius.is_finite() && radius > 0.0) {
            return Err(RigError::BoundingBox);
        }
        (self.center, self.radius) = (center, radius);
        Ok(self)
    }

    /// The rig alone, with its current parameters.
    pub fn state(&self) -> &RigState {
        &self.state
    }

    /// This frame's per-vertex lights, in the order they were given to
    /// [`SplitRig::update`]: each light taken into the object's frame
    /// (positions and directions in object coordinates, m) with its
    /// per-vertex share `1 − w` in `(0, 1]` ([`rig_weight`]); lights wholly
    /// in the rig are left out. Empty before the first update.
    /// [`SplitRig::irradiance`] is the rig plus `Σ share ·`
    /// [`Light::irradiance`] of these, looked up in
    /// [`SplitRig::sphere_table`].
    pub fn near_lights(&self) -> &[(Light, f32)] {
        &self.near
    }

    /// The table sphere and disk lights are looked up in per vertex.
    pub fn sphere_table(&self) -> &SphereTable {
        &self.table
    }

    /// Per-frame update for the object placed by the rigid transform
    /// `world_from_object` among `lights` (world coordinates): each light
    /// is taken into the object's frame, its transition distance found
    /// ([`transition_distance`], `target` grey levels, `white` the reflected
    /// radiance shown as white, W/(m²·sr)) and its rig share
    /// ([`rig_weight`]); the rig is refitted to the weighted lights' SH at
    /// its sample points, and the near lights are kept for
    /// [`SplitRig::irradiance`]. Allocates only when more near lights than
    /// ever before must be kept. A transform that is not finite or not
    /// invertible is an error, and the state is left unchanged.
    pub fn update(
        &mut self,
        world_from_object: Affine3A,
        lights: &[Light],
        target: f32,
        white: f32,
    ) -> Result<(), RigError> {
        let det = world_from_object.matrix3.determinant();
        if !world_from_object.is_finite() || !det.is_normal() {
            return Err(RigError::Transform);
        }
        let object_from_world = world_from_object.inverse();
        let order = self.state.order();
        let n2 = order * order;
        self.sample_sh.fill(Vec3::ZERO);
        self.near.clear();
        for light in lights {
            let l = transformed(light, &object_from_world);
            let x_star = transition_distance(
                &self.transitions,
                &l,
                self.center,
                self.radius,
                white,
                target,
            );
            let x = l
                .position()
                .map_or(f32::INFINITY, |p| p.distance(self.center) / self.radius);
            let w = rig_weight(x, x_star);
            if w > 0.0 {
                for (s, out) in self.samples.iter().zip(self.sample_sh.chunks_exact_mut(n2)) {
                    l.add_sh(order, *s, w, out);
                }
            }
            if w < 1.0 {
                self.near.push((l, 1.0 - w));
            }
        }
        self.state.update(&self.sample_sh)
    }

    /// Irradiance (not divided by π) at `position` (the object's own
    /// coordinates, m) for unit `normal` (object frame): the rig plus each
    /// near light's exact irradiance times its per-vertex share. No
    /// allocation.
    pub fn irradiance(&self, position: Vec3, normal: Vec3) -> Vec3 {
        let mut e = self.state.irradiance(position, normal);
        for (l, share) in &self.near {
            e += l.irradiance(position, normal, Some(&self.table)) * *share;
        }
        e
    }
}

/// `light` in the frame `to` maps into (positions as points, directions as
/// vectors, renormalized; sizes and intensities unchanged: a rigid
/// transform).
fn transformed(light: &Light, to: &Affine3A) -> Light {
    let point = |p: Vec3| to.transform_point3(p);
    let dir = |d: Vec3| to.transform_vector3(d).normalize_or(d);
    match *light {
        Light::Sphere {
            position,
            radius,
            intensity,
        } => Light::Sphere {
            position: point(position),
            radius,
            intensity,
        },
        Light::Point {
            position,
            intensity,
        } => Light::Point {
            position: point(position),
            intensity,
        },
        Light::Spot {
            position,
            direction,
            inner_deg,
            outer_deg,
            intensity,
        } => Light::Spot {
            position: point(position),
            direction: dir(direction),
            inner_deg,
            outer_deg,
            intensity,
        },
        Light::Disk {
            position,
            direction,
            radius,
            intensity,
        } => Light::Disk {
            position: point(position),
            direction: dir(direction),
            radius,
            intensity,
        },
        Light::Directional {
            direction,
            irradiance,
        } => Light::Directional {
            direction: dir(direction),
            irradiance,
        },
    }
}
