//! Irradiance and radiance SH at points, for clouds and volumes alike.

use crate::args::{finite, floats_in, floats_out, times3, vec3_in};
use crate::cloud::walk_state;
use crate::error::{run, Error};
use crate::probes::handle;
use crate::{PkProbes, PkStatus, PkWalkState};
use glam::Vec3;
use probekit_runtime::cloud::WalkState;
use probekit_runtime::sh::MAX_COEFFS;

/// Irradiance at `position[3]` (metres) for unit `normal[3]` into
/// `out_rgb[3]` (not divided by π). `state` may be null (a cold walk each
/// call) and is ignored for volumes. No allocation.
#[no_mangle]
pub unsafe extern "C" fn pk_irradiance(
    probes: *const PkProbes,
    state: *mut PkWalkState,
    position: *const f32,
    normal: *const f32,
    out_rgb: *mut f32,
) -> PkStatus {
    run(|| {
        let h = handle(probes)?;
        let p = vec3_in(position, "position")?;
        let n = vec3_in(normal, "normal")?;
        let out = floats_out(out_rgb, 3, "out_rgb")?;
        let e = h.irradiance(p, n, walk_state(state))?;
        out.copy_from_slice(&e.to_array());
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
        let mut cold = WalkState::new();
        let ws = walk_state(state).unwrap_or(&mut cold);
        for (i, ((p, n), o)) in ps
            .chunks_exact(3)
            .zip(ns.chunks_exact(3))
            .zip(out.chunks_exact_mut(3))
            .enumerate()
        {
            let p = finite(Vec3::from_slice(p), "position", i)?;
            let n = finite(Vec3::from_slice(n), "normal", i)?;
            let e = h.irradiance(p, n, Some(&mut *ws))?;
            o.copy_from_slice(&e.to_array());
        }
        Ok(())
    })
}

/// Interpolated radiance SH at `position[3]` into `out` (`out_len` floats,
/// at least `3·order²`): coefficient `k = l(l+1)+m`, channel `c` at
/// `out[3k + c]`. Buffer too short: [`PkStatus::BufferTooSmall`], nothing
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
        let need = 3 * h.coeff_count();
        if out_len < need {
            return Err(Error::new(
                PkStatus::BufferTooSmall,
                format!("out holds {out_len} floats, {need} needed"),
            ));
        }
        let out = floats_out(out, need, "out")?;
        let mut buf = [Vec3::ZERO; MAX_COEFFS];
        h.sh_into(p, walk_state(state), &mut buf)?;
        for (o, c) in out.chunks_exact_mut(3).zip(&buf) {
            o.copy_from_slice(&c.to_array());
        }
        Ok(())
    })
}

/// [`pk_sh`] for `count` points (`positions`: `3·count` floats); `out`
/// (`out_len` floats, at least `count·3·order²`) holds point after point,
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
        let per = 3 * h.coeff_count();
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
        let mut cold = WalkState::new();
        let ws = walk_state(state).unwrap_or(&mut cold);
        let mut buf = [Vec3::ZERO; MAX_COEFFS];
        for (i, (p, o)) in ps
            .chunks_exact(3)
            .zip(out.chunks_exact_mut(per))
            .enumerate()
        {
            let p = finite(Vec3::from_slice(p), "position", i)?;
            h.sh_into(p, Some(&mut *ws), &mut buf)?;
            for (o, c) in o.chunks_exact_mut(3).zip(&buf) {
                o.copy_from_slice(&c.to_array());
            }
        }
        Ok(())
    })
}
