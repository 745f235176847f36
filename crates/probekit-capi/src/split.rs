//! Irradiance rigs with the near/transition/rig split: one object's
//! [`SplitRig`], updated each frame from the object's transform and the
//! scene's lights, queried per vertex.

use crate::args::{finite, floats_in, floats_out, times3, vec3_in};
use crate::error::{run, run_value, Error};
use crate::probes::handle;
use crate::{PkProbes, PkStatus};
use glam::{Affine3A, Vec3};
use probekit_runtime::rig::{Light, SplitRig};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// `PkLight::kind`: a sphere (`position`, `radius`, `intensity`).
pub const PK_LIGHT_SPHERE: u32 = 0;
/// `PkLight::kind`: a point light (`position`, `intensity`).
pub const PK_LIGHT_POINT: u32 = 1;
/// `PkLight::kind`: a glTF spot light (`position`, `direction`,
/// `inner_deg`, `outer_deg`, `intensity`).
pub const PK_LIGHT_SPOT: u32 = 2;
/// `PkLight::kind`: a one-sided disk (`position`, `direction`, `radius`,
/// `intensity`).
pub const PK_LIGHT_DISK: u32 = 3;
/// `PkLight::kind`: a directional light (`direction`, `intensity` is the
/// irradiance on a surface facing it, W/m²).
pub const PK_LIGHT_DIRECTIONAL: u32 = 4;

/// One light of the scene (`PkLight` in the header;
/// `probekit_runtime::rig::Light`): world coordinates, metres; `direction`
/// the unit way light travels; `intensity` W/sr per RGB channel (for a
/// directional light, its irradiance W/m²); fields a kind does not use are
/// ignored.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PkLight {
    /// `PK_LIGHT_*`.
    pub kind: u32,
    /// Centre or position (m).
    pub position: [f32; 3],
    /// Unit direction light travels (spot axis, disk normal, sun).
    pub direction: [f32; 3],
    /// Sphere or disk radius (m), > 0.
    pub radius: f32,
    /// Spot inner cone half-angle (degrees).
    pub inner_deg: f32,
    /// Spot outer cone half-angle (degrees).
    pub outer_deg: f32,
    /// Intensity × colour (W/sr), or a directional light's irradiance.
    pub intensity: [f32; 3],
}

impl PkLight {
    /// The C form of `l`, fields its kind does not use zero (what
    /// [`crate::pk_runtime_light`] writes).
    pub(crate) fn from_light(l: &Light) -> Self {
        let mut c = PkLight {
            kind: 0,
            position: [0.0; 3],
            direction: [0.0; 3],
            radius: 0.0,
            inner_deg: 0.0,
            outer_deg: 0.0,
            intensity: [0.0; 3],
        };
        match *l {
            Light::Sphere {
                position,
                radius,
                intensity,
            } => {
                c.kind = PK_LIGHT_SPHERE;
                (c.position, c.radius, c.intensity) = (position.into(), radius, intensity.into());
            }
            Light::Point {
                position,
                intensity,
            } => {
                c.kind = PK_LIGHT_POINT;
                (c.position, c.intensity) = (position.into(), intensity.into());
            }
            Light::Spot {
                position,
                direction,
                inner_deg,
                outer_deg,
                intensity,
            } => {
                c.kind = PK_LIGHT_SPOT;
                (c.position, c.direction) = (position.into(), direction.into());
                (c.inner_deg, c.outer_deg, c.intensity) = (inner_deg, outer_deg, intensity.into());
            }
            Light::Disk {
                position,
                direction,
                radius,
                intensity,
            } => {
                c.kind = PK_LIGHT_DISK;
                (c.position, c.direction) = (position.into(), direction.into());
                (c.radius, c.intensity) = (radius, intensity.into());
            }
            Light::Directional {
                direction,
                irradiance,
            } => {
                c.kind = PK_LIGHT_DIRECTIONAL;
                (c.direction, c.intensity) = (direction.into(), irradiance.into());
            }
        }
        c
    }

    fn to_light(self, i: usize) -> Result<Light, Error> {
        let bad = |what: &str| Error::new(PkStatus::InvalidArgument, format!("light {i}: {what}"));
        let floats = [self.radius, self.inner_deg, self.outer_deg];
        let all = self
            .position
            .iter()
            .chain(&self.direction)
            .chain(&self.intensity)
            .chain(&floats);
        if !all.clone().all(|x| x.is_finite()) {
            return Err(bad("a value is NaN or infinite"));
        }
        let position = Vec3::from(self.position);
        let direction = Vec3::from(self.direction);
        let intensity = Vec3::from(self.intensity);
        let unit = || {
            direction
                .try_normalize()
                .ok_or_else(|| bad("the direction has zero length"))
        };
        let radius = || {
            (self.radius > 0.0)
                .then_some(self.radius)
                .ok_or_else(|| bad("the radius is not positive"))
        };
        Ok(match self.kind {
            PK_LIGHT_SPHERE => Light::Sphere {
                position,
                radius: radius()?,
                intensity,
            },
            PK_LIGHT_POINT => Light::Point {
                position,
                intensity,
            },
            PK_LIGHT_SPOT => Light::Spot {
                position,
                direction: unit()?,
                inner_deg: self.inner_deg,
                outer_deg: self.outer_deg,
                intensity,
            },
            PK_LIGHT_DISK => Light::Disk {
                position,
                direction: unit()?,
                radius: radius()?,
                intensity,
            },
            PK_LIGHT_DIRECTIONAL => Light::Directional {
                direction: unit()?,
                irradiance: intensity,
            },
            k => return Err(bad(&format!("unknown kind {k}"))),
        })
    }
}

/// One object's rig with the split (opaque `PkSplitRig` in C): the
/// runtime's [`SplitRig`] and a buffer for the frame's lights.
pub struct PkSplitRig {
    rig: SplitRig,
    lights: Vec<Light>,
}

/// Per-object split rig for rig `index` of the file
/// (`probekit_runtime::Probes::split_rig`); free with [`pk_split_rig_free`].
/// Null on error, with `status` (may be null) and `pk_last_error`.
#[no_mangle]
pub unsafe extern "C" fn pk_split_rig_new(
    probes: *const PkProbes,
    index: usize,
    status: *mut PkStatus,
) -> *mut PkSplitRig {
    run_value(status, std::ptr::null_mut(), || {
        let h = handle(probes)?;
        let rig = h.probes.split_rig(index)?;
        Ok(Box::into_raw(Box::new(PkSplitRig {
            rig,
            lights: Vec::new(),
        })))
    })
}

/// Frees a split rig (null is a no-op).
#[no_mangle]
pub unsafe extern "C" fn pk_split_rig_free(rig: *mut PkSplitRig) {
    if !rig.is_null() {
        // SAFETY: created by pk_split_rig_new; freed once.
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(rig) })));
    }
}

/// Per-frame update (`SplitRig::update`): the object placed by the rigid
/// transform `world_from_object` (12 floats, column-major: the three axis
/// columns, then the translation) among `count` `lights` (world
/// coordinates), `target` grey levels of error allowed, `white` the
/// reflected radiance shown as white. Allocates only when more lights than
/// ever before are near the object.
#[no_mangle]
pub unsafe extern "C" fn pk_split_rig_update(
    rig: *mut PkSplitRig,
    world_from_object: *const f32,
    lights: *const PkLight,
    count: usize,
    target: f32,
    white: f32,
) -> PkStatus {
    run(|| {
        // SAFETY: non-null split rigs come from pk_split_rig_new.
        let r = unsafe { rig.as_mut() }.ok_or_else(|| Error::null("rig"))?;
        if world_from_object.is_null() {
            return Err(Error::null("world_from_object"));
        }
        // SAFETY: non-null; the header requires 12 readable floats.
        let m = unsafe { std::slice::from_raw_parts(world_from_object, 12) };
        let mut cols = [0.0f32; 12];
        cols.copy_from_slice(m);
        let transform = Affine3A::from_cols_array(&cols);
        let src: &[PkLight] = if count == 0 {
            &[]
        } else if lights.is_null() {
            return Err(Error::null("lights"));
        } else if count > isize::MAX as usize / std::mem::size_of::<PkLight>() {
            return Err(Error::new(PkStatus::InvalidArgument, "count too large"));
        } else {
            // SAFETY: non-null; the caller provides `count` lights.
            unsafe { std::slice::from_raw_parts(lights, count) }
        };
        r.lights.clear();
        for (i, l) in src.iter().enumerate() {
            r.lights.push(l.to_light(i)?);
        }
        r.rig
            .update(transform, &r.lights, target, white)
            .map_err(|e| Error::new(PkStatus::InvalidArgument, e.to_string()))
    })
}

/// Irradiance (not divided by π) of the split rig at `count` vertices:
/// `positions`, `normals` (object coordinates, unit normals) and `out_rgb`
/// hold `3·count` floats each. No allocation.
#[no_mangle]
pub unsafe extern "C" fn pk_split_rig_irradiance_many(
    rig: *const PkSplitRig,
    count: usize,
    positions: *const f32,
    normals: *const f32,
    out_rgb: *mut f32,
) -> PkStatus {
    run(|| {
        // SAFETY: non-null split rigs come from pk_split_rig_new.
        let r = unsafe { rig.as_ref() }.ok_or_else(|| Error::null("rig"))?;
        let ps = floats_in(positions, count, "positions")?;
        let ns = floats_in(normals, count, "normals")?;
        let out = floats_out(out_rgb, times3(count)?, "out_rgb")?;
        for (i, ((p, n), o)) in ps
            .chunks_exact(3)
            .zip(ns.chunks_exact(3))
            .zip(out.chunks_exact_mut(3))
            .enumerate()
        {
            let p = finite(Vec3::from_slice(p), "position", i)?;
            let n = finite(Vec3::from_slice(n), "normal", i)?;
            o.copy_from_slice(&r.rig.irradiance(p, n).to_array());
        }
        Ok(())
    })
}

/// [`pk_split_rig_irradiance_many`] for one vertex.
#[no_mangle]
pub unsafe extern "C" fn pk_split_rig_irradiance(
    rig: *const PkSplitRig,
    position: *const f32,
    normal: *const f32,
    out_rgb: *mut f32,
) -> PkStatus {
    run(|| {
        // SAFETY: non-null split rigs come from pk_split_rig_new.
        let r = unsafe { rig.as_ref() }.ok_or_else(|| Error::null("rig"))?;
        let p = vec3_in(position, "position")?;
        let n = vec3_in(normal, "normal")?;
        let out = floats_out(out_rgb, 3, "out_rgb")?;
        out.copy_from_slice(&r.rig.irradiance(p, n).to_array());
        Ok(())
    })
}
