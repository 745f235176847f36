//! Irradiance rigs: per-object state, its update from sampled SH, and
//! its irradiance at the object's vertices.

use crate::args::{finite, floats_in, floats_out, name_out, times3, vec3_in};
use crate::cloud::walk_state;
use crate::error::{run, run_value, Error};
use crate::probes::handle;
use crate::{PkProbes, PkStatus, PkWalkState};
use glam::Vec3;
use probekit_runtime::rig::RigState;
use probekit_runtime::ObjectState;
use std::ffi::c_char;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// One object's irradiance rig (opaque `PkRig` in C): the runtime's
/// [`RigState`] plus the rig's sample points and a scratch buffer for
/// [`pk_rig_update_from_probes`]. Created by [`pk_rig_new`].
pub struct PkRig {
    state: RigState,
    samples: Vec<Vec3>,
    scratch: Vec<Vec3>,
}

/// Number of irradiance rigs the file holds (any kind may hold rigs); 0 for null.
#[no_mangle]
pub unsafe extern "C" fn pk_rig_count(probes: *const PkProbes) -> usize {
    // SAFETY: see `handle`.
    unsafe { probes.as_ref() }.map_or(0, |p| p.rigs.len())
}

/// Name (UTF-8 mesh name) of rig `index` into `buf` (`buf_len` bytes,
/// NUL-terminated). `*name_len` (may be null) receives the name's length in
/// bytes without the NUL. If `buf_len` is too short, nothing is written and
/// [`PkStatus::BufferTooSmall`] is returned (call with `buf = NULL,
/// buf_len = 0` to ask for the length).
#[no_mangle]
pub unsafe extern "C" fn pk_rig_name(
    probes: *const PkProbes,
    index: usize,
    buf: *mut c_char,
    buf_len: usize,
    name_len: *mut usize,
) -> PkStatus {
    run(|| {
        let h = handle(probes)?;
        let rig = h.rigs.get(index).ok_or_else(|| {
            Error::new(
                PkStatus::OutOfRange,
                format!("rig {index} of {}", h.rigs.len()),
            )
        })?;
        name_out(rig.name.as_bytes(), "rig name", buf, buf_len, name_len)
    })
}

/// Per-object state for rig `index` of the file: parameters start at zero
/// (irradiance 0) until the first update. Independent of the handle
/// afterwards (it may be freed first). Free with [`pk_rig_free`]. Null on
/// error, with `status` (may be null) and [`pk_last_error`].
///
/// [`pk_last_error`]: crate::pk_last_error
#[no_mangle]
pub unsafe extern "C" fn pk_rig_new(
    probes: *const PkProbes,
    index: usize,
    status: *mut PkStatus,
) -> *mut PkRig {
    run_value(status, std::ptr::null_mut(), || {
        let h = handle(probes)?;
        let state = h.probes.rig(index)?.clone();
        let rig = h.rigs.get(index).ok_or_else(|| {
            Error::new(
                PkStatus::OutOfRange,
                format!("rig {index} of {}", h.rigs.len()),
            )
        })?;
        let len = (state.order() * state.order())
            .checked_mul(rig.samples.len())
            .ok_or_else(|| Error::new(PkStatus::Format, "rig too large"))?;
        let scratch = vec![Vec3::ZERO; len];
        Ok(Box::into_raw(Box::new(PkRig {
            state,
            samples: rig.samples.clone(),
            scratch,
        })))
    })
}

/// Frees a rig state (null is a no-op).
#[no_mangle]
pub unsafe extern "C" fn pk_rig_free(rig: *mut PkRig) {
    if !rig.is_null() {
        // SAFETY: created by pk_rig_new; freed once.
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(rig) })));
    }
}

fn rig_ref<'a>(rig: *const PkRig) -> Result<&'a PkRig, Error> {
    // SAFETY: non-null rigs come from pk_rig_new and live until pk_rig_free.
    unsafe { rig.as_ref() }.ok_or_else(|| Error::null("rig"))
}

/// SH order (bands) of the rig's parameters and of the SH its update expects; 0 for null.
#[no_mangle]
pub unsafe extern "C" fn pk_rig_order(rig: *const PkRig) -> u32 {
    rig_ref(rig).map_or(0, |r| r.state.order() as u32)
}

/// Number of sample points the rig's update expects; 0 for null.
#[no_mangle]
pub unsafe extern "C" fn pk_rig_sample_count(rig: *const PkRig) -> usize {
    rig_ref(rig).map_or(0, |r| r.samples.len())
}

/// The rig's sample points in mesh coordinates (metres) into `out`
/// (`out_len` floats, at least `3·sample_count`, xyz interleaved).
#[no_mangle]
pub unsafe extern "C" fn pk_rig_sample_points(
    rig: *const PkRig,
    out: *mut f32,
    out_len: usize,
) -> PkStatus {
    run(|| {
        let r = rig_ref(rig)?;
        let need = times3(r.samples.len())?;
        if out_len < need {
            return Err(Error::new(
                PkStatus::BufferTooSmall,
                format!("out holds {out_len} floats, {need} needed"),
            ));
        }
        let out = floats_out(out, need, "out")?;
        for (o, s) in out.chunks_exact_mut(3).zip(&r.samples) {
            o.copy_from_slice(&s.to_array());
        }
        Ok(())
    })
}

/// Per-frame update from radiance SH sampled at the rig's sample points
/// (`parameters = L × samples`, Yuan et al. 2011 §2.2): `sample_sh` holds
/// `len = sample_count·order²·3` floats, sample-major, each sample laid out
/// as [`pk_sh`] writes it. The SH must be in the mesh's frame (rotate world
/// SH into it for a rotated object). No allocation.
///
/// [`pk_sh`]: crate::pk_sh
#[no_mangle]
pub unsafe extern "C" fn pk_rig_update(
    rig: *mut PkRig,
    sample_sh: *const f32,
    len: usize,
) -> PkStatus {
    run(|| {
        // SAFETY: non-null rigs come from pk_rig_new.
        let r = unsafe { rig.as_mut() }.ok_or_else(|| Error::null("rig"))?;
        let need = times3(r.scratch.len())?;
        if len != need {
            return Err(Error::new(
                PkStatus::InvalidArgument,
                format!("sample_sh holds {len} floats, {need} expected"),
            ));
        }
        let src = floats_in(sample_sh, r.scratch.len(), "sample_sh")?;
        for (i, (d, s)) in r.scratch.iter_mut().zip(src.chunks_exact(3)).enumerate() {
            *d = finite(Vec3::from_slice(s), "sample coefficient", i)?;
        }
        r.state
            .update(&r.scratch)
            .map_err(|e| Error::new(PkStatus::InvalidArgument, e.to_string()))
    })
}

/// Convenience update for an object that is only translated: samples
/// `lighting` (a cloud or volume handle) at `sample point + translation[3]`
/// (world = mesh + translation, metres) and updates as [`pk_rig_update`].
/// The lighting's SH (as [`crate::pk_sh`] gives it) is truncated or zero-padded
/// to the rig's order.
/// `state` (may be null) is the object's walk state for a cloud. No
/// allocation. A rotated object must rotate the SH itself and call
/// [`pk_rig_update`].
#[no_mangle]
pub unsafe extern "C" fn pk_rig_update_from_probes(
    rig: *mut PkRig,
    lighting: *const PkProbes,
    state: *mut PkWalkState,
    translation: *const f32,
) -> PkStatus {
    run(|| {
        // SAFETY: non-null rigs come from pk_rig_new.
        let r = unsafe { rig.as_mut() }.ok_or_else(|| Error::null("rig"))?;
        let h = handle(lighting)?;
        let t = vec3_in(translation, "translation")?;
        let n2 = r.state.order() * r.state.order();
        let m = n2.min(h.sh_count());
        let mut cold = ObjectState::new();
        let ws = walk_state(state).unwrap_or(&mut cold);
        for (s, dst) in r.samples.iter().zip(r.scratch.chunks_exact_mut(n2.max(1))) {
            let sh = h.probes.sh_at(ws, *s + t)?;
            dst.fill(Vec3::ZERO);
            for (d, c) in dst[..m].iter_mut().zip(&sh) {
                *d = Vec3::from(*c);
            }
        }
        r.state
            .update(&r.scratch)
            .map_err(|e| Error::new(PkStatus::InvalidArgument, e.to_string()))
    })
}

/// The rig's irradiance (not divided by π) at mesh-space `position[3]` for
/// unit mesh-space `normal[3]` into `out_rgb[3]`. No allocation.
#[no_mangle]
pub unsafe extern "C" fn pk_rig_irradiance(
    rig: *const PkRig,
    position: *const f32,
    normal: *const f32,
    out_rgb: *mut f32,
) -> PkStatus {
    run(|| {
        let r = rig_ref(rig)?;
        let p = vec3_in(position, "position")?;
        let n = vec3_in(normal, "normal")?;
        let out = floats_out(out_rgb, 3, "out_rgb")?;
        out.copy_from_slice(&r.state.irradiance(p, n).to_array());
        Ok(())
    })
}

/// [`pk_rig_irradiance`] per vertex: `positions`, `normals` and `out_rgb`
/// each hold `3·count` floats.
#[no_mangle]
pub unsafe extern "C" fn pk_rig_irradiance_many(
    rig: *const PkRig,
    count: usize,
    positions: *const f32,
    normals: *const f32,
    out_rgb: *mut f32,
) -> PkStatus {
    run(|| {
        let r = rig_ref(rig)?;
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
            o.copy_from_slice(&r.state.irradiance(p, n).to_array());
        }
        Ok(())
    })
}
