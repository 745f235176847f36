//! Irradiance and radiance SH at points, for clouds and volumes alike.

use crate::args::{finite, floats_in, floats_out, times3, vec3_in};
use crate::cloud::walk_state;
use crate::error::{run, Error};
use crate::probes::handle;
use crate::{PkProbes, PkStatus, PkWalkState};
use glam::Vec3;
use probekit_runtime::{ObjectState, QueryError};

/// `e` with the index of the point of a batch it is about, for the message.
fn at(e: QueryError, i: usize) -> Error {
    let Error(status, msg) = Error::from(e);
    Error(status, format!("point {i}: {msg}"))
}

/// Irradiance at `position[3]` (metres) for `normal[3]` (any non-zero
/// length) into `out_rgb[3]` (not divided by π;
/// `probekit_runtime::Probes::irradiance`): the whole light of the scene,
/// a file's run-time lights' direct light included (each light's exact
/// irradiance times its blended occlusion; [`crate::pk_sh_irradiance`]
/// leaves it out). `state` may be null (a cold walk each call) and is
/// ignored for volumes. No allocation.
#[no_mangle]
pub unsafe extern "C" fn pk_irradiance(
    probes: *const PkProbes,
    state: *mut PkWalkState,
    position: *const f32,
    normal: *const f32,
    out_rgb: *mut f32,
) -> PkStatus {
    // SAFETY: the caller's contract is this function's.
    unsafe { irradiance_one(probes, state, position, normal, out_rgb, true) }
}

/// The SH part of [`pk_irradiance`] (`probekit_runtime::Probes::sh_irradiance`):
/// irradiance (not divided by π, linear RGB, W/m² for a scene in W) at
/// `position[3]` for `normal[3]` into `out_rgb[3]` without the direct light
/// of the file's run-time lights, for an engine that draws those lights
/// itself ([`crate::pk_runtime_light`], [`crate::pk_light_occlusion`]);
/// their bounce light stays in. Equal to [`pk_irradiance`] for a file
/// without run-time lights. Arguments as in [`pk_irradiance`]. No allocation.
#[no_mangle]
pub unsafe extern "C" fn pk_sh_irradiance(
    probes: *const PkProbes,
    state: *mut PkWalkState,
    position: *const f32,
    normal: *const f32,
    out_rgb: *mut f32,
) -> PkStatus {
    // SAFETY: the caller's contract is this function's.
    unsafe { irradiance_one(probes, state, position, normal, out_rgb, false) }
}

/// [`pk_irradiance`] (`lights`) or [`pk_sh_irradiance`] (not `lights`).
unsafe fn irradiance_one(
    probes: *const PkProbes,
    state: *mut PkWalkState,
    position: *const f32,
    normal: *const f32,
    out_rgb: *mut f32,
    lights: bool,
) -> PkStatus {
    run(|| {
        let h = handle(probes)?;
        let p = vec3_in(position, "position")?;
        let n = vec3_in(normal, "normal")?;
        let out = floats_out(out_rgb, 3, "out_rgb")?;
        let mut cold = ObjectState::new();
        let ws = walk_state(state).unwrap_or(&mut cold);
        let e = if lights {
            h.probes.irradiance(ws, p, n)?
        } else {
            h.probes.sh_irradiance(ws, p, n)?
        };
        out.copy_from_slice(&e);
        Ok(())
    })
}

/// [`pk_irradiance`] for `count` points: `positions`, `normals` and
/// `out_rgb` each hold `3·count` floats (xyz / rgb interleaved). Points are
/// visited in order with one walk state, so coherent batches walk little.
/// On an error nothing after the offending point is written.
#[no_mangle]
pub unsafe extern "C" fn pk_irradiance_many(
    probes: *const PkProbes,
    state: *mut PkWalkState,
    count: usize,
    positions: *const f32,
    normals: *const f32,
    out_rgb: *mut f32,
) -> PkStatus {
    run(|| {
        let h = handle(probes)?;
        let ps = floats_in(positions, count, "positions")?;
        let ns = floats_in(normals, count, "normals")?;
        let out = floats_out(out_rgb, times3(count)?, "out_rgb")?;
        let mut cold = ObjectState::new();
        let ws = walk_state(state).unwrap_or(&mut cold);
        for (i, ((p, n), o)) in ps
            .chunks_exact(3)
            .zip(ns.chunks_exact(3))
            .zip(out.chunks_exact_mut(3))
            .enumerate()
        {
            let p = finite(Vec3::from_slice(p), "position", i)?;
            let n = finite(Vec3::from_slice(n), "normal", i)?;
            let e = h.probes.irradiance(ws, p, n).map_err(|e| at(e, i))?;
            o.copy_from_slice(&e);
        }
        Ok(())
    })
}

/// Interpolated radiance SH at `position[3]` into `out` (`out_len` floats,
/// at least `3·pk_sh_count`): coefficient `k = l(l+1)+m`, channel `c` at
/// `out[3k + c]`; bands 0–2 at most (`probekit_runtime::Probes::sh_at`),
/// with an L1 file's hallucinated zonal lobe in band 2 where it is
/// evaluated that way. Buffer too short: [`PkStatus::BufferTooSmall`], nothing
/// written. `state` as in [`pk_irradiance`]. No allocation.
#[no_mangle]
pub unsafe extern "C" fn pk_sh(
    probes: *const PkProbes,
    state: *mut PkWalkState,
    position: *const f32,
    out: *mut f32,
    out_len: usize,
) -> PkStatus {
    run(|| {
        let h = handle(probes)?;
        let p = vec3_in(position, "position")?;
        let need = 3 * h.sh_count();
        if out_len < need {
            return Err(Error::new(
                PkStatus::BufferTooSmall,
                format!("out holds {out_len} floats, {need} needed"),
            ));
        }
        let out = floats_out(out, need, "out")?;
        let mut cold = ObjectState::new();
        let sh = h.probes.sh_at(walk_state(state).unwrap_or(&mut cold), p)?;
        for (o, c) in out.chunks_exact_mut(3).zip(&sh) {
            o.copy_from_slice(c);
        }
        Ok(())
    })
}

/// [`pk_sh`] for `count` points (`positions`: `3·count` floats); `out`
/// (`out_len` floats, at least `count·3·pk_sh_count`) holds point after point,
/// each laid out as in [`pk_sh`].
#[no_mangle]
pub unsafe extern "C" fn pk_sh_many(
    probes: *const PkProbes,
    state: *mut PkWalkState,
    count: usize,
    positions: *const f32,
    out: *mut f32,
    out_len: usize,
) -> PkStatus {
    run(|| {
        let h = handle(probes)?;
        let ps = floats_in(positions, count, "positions")?;
        let per = 3 * h.sh_count();
        let need = count
            .checked_mul(per)
            .ok_or_else(|| Error::new(PkStatus::InvalidArgument, "count too large"))?;
        if out_len < need {
            return Err(Error::new(
                PkStatus::BufferTooSmall,
                format!("out holds {out_len} floats, {need} needed"),
            ));
        }
        let out = floats_out(out, need, "out")?;
        let mut cold = ObjectState::new();
        let ws = walk_state(state).unwrap_or(&mut cold);
        for (i, (p, o)) in ps
            .chunks_exact(3)
            .zip(out.chunks_exact_mut(per))
            .enumerate()
        {
            let p = finite(Vec3::from_slice(p), "position", i)?;
            let sh = h.probes.sh_at(ws, p).map_err(|e| at(e, i))?;
            for (o, c) in o.chunks_exact_mut(3).zip(&sh) {
                o.copy_from_slice(c);
            }
        }
        Ok(())
    })
}
