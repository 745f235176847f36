//! Run-time lights (format 2.1): the small lights whose direct light a bake
//! leaves out of the probes' SH for the engine to evaluate exactly, their
//! parameters and the probes' blended occlusion of them.
//!
//! [`crate::pk_irradiance`] already answers with their light added; an
//! engine that draws them itself takes [`crate::pk_sh_irradiance`] and adds,
//! per light, its own exact irradiance times [`pk_light_occlusion`].

use crate::args::{floats_out, name_out, vec3_in};
use crate::cloud::walk_state;
use crate::error::{run, Error};
use crate::probes::handle;
use crate::{PkLight, PkProbes, PkStatus, PkWalkState};
use probekit_runtime::format::RuntimeLight;
use probekit_runtime::ObjectState;
use std::ffi::c_char;

/// Run-time light `index` of `h`, or [`PkStatus::OutOfRange`].
fn light(h: &PkProbes, index: usize) -> Result<&RuntimeLight, Error> {
    let lights = h.probes.runtime_lights();
    lights.get(index).ok_or_else(|| {
        Error::new(
            PkStatus::OutOfRange,
            format!("run-time light {index} of {}", lights.len()),
        )
    })
}

/// Number of run-time lights the file leaves to the engine (at most 255;
/// 0 for a file without them, a rigs-only file, or null). Their order is
/// that of [`pk_runtime_light`] and [`pk_light_occlusion`].
#[no_mangle]
pub unsafe extern "C" fn pk_runtime_light_count(probes: *const PkProbes) -> usize {
    // SAFETY: see `handle`.
    unsafe { probes.as_ref() }.map_or(0, |p| p.probes.runtime_lights().len())
}

/// Run-time light `index` into `*out`: world coordinates (metres),
/// `direction` the unit way light travels, `intensity` W/sr per linear RGB
/// channel (a directional light's irradiance facing it, W/m²); fields its
/// kind does not use are 0. The same [`PkLight`] a split rig takes.
/// [`PkStatus::OutOfRange`] for `index >= pk_runtime_light_count`.
#[no_mangle]
pub unsafe extern "C" fn pk_runtime_light(
    probes: *const PkProbes,
    index: usize,
    out: *mut PkLight,
) -> PkStatus {
    run(|| {
        let h = handle(probes)?;
        let l = light(h, index)?;
        if out.is_null() {
            return Err(Error::null("out"));
        }
        // SAFETY: non-null; the header requires one writable PkLight.
        unsafe { out.write(PkLight::from_light(&l.light)) };
        Ok(())
    })
}

/// Light group of run-time light `index` (UTF-8; the group its bounce light
/// was baked into: scale that group's SH when dimming the light) into `buf`
/// (`buf_len` bytes, NUL-terminated); `*name_len` (may be null) receives its
/// length in bytes without the NUL. Too short: nothing written,
/// [`PkStatus::BufferTooSmall`] (ask with `buf` null and `buf_len` 0), as
/// [`crate::pk_rig_name`].
#[no_mangle]
pub unsafe extern "C" fn pk_runtime_light_group(
    probes: *const PkProbes,
    index: usize,
    buf: *mut c_char,
    buf_len: usize,
    name_len: *mut usize,
) -> PkStatus {
    run(|| {
        let h = handle(probes)?;
        let name = light(h, index)?.group.as_bytes();
        name_out(name, "light group", buf, buf_len, name_len)
    })
}

/// Each run-time light's visible fraction at `position[3]` (metres), in
/// `[0, 1]`, into `out[0..count]` (`count = pk_runtime_light_count`; `out`
/// holds `out_len >= count` floats, the rest untouched; null allowed when
/// `count` is 0): the probes' stored fractions blended with the SH's
/// weights (`probekit_runtime::Probes::light_occlusion`). Light `l`'s exact
/// unoccluded irradiance times `out[l]`, summed over the lights, is what
/// [`crate::pk_irradiance`] adds to [`crate::pk_sh_irradiance`].
/// `out_len < count`: [`PkStatus::BufferTooSmall`], nothing written.
/// `state` as in [`crate::pk_irradiance`]. No allocation.
#[no_mangle]
pub unsafe extern "C" fn pk_light_occlusion(
    probes: *const PkProbes,
    state: *mut PkWalkState,
    position: *const f32,
    out: *mut f32,
    out_len: usize,
) -> PkStatus {
    run(|| {
        let h = handle(probes)?;
        let p = vec3_in(position, "position")?;
        let need = h.probes.runtime_lights().len();
        if out_len < need {
            return Err(Error::new(
                PkStatus::BufferTooSmall,
                format!("out holds {out_len} floats, {need} needed (one per run-time light)"),
            ));
        }
        let out = floats_out(out, need, "out")?;
        let mut cold = ObjectState::new();
        let ws = walk_state(state).unwrap_or(&mut cold);
        h.probes.light_occlusion(ws, p, out)?;
        Ok(())
    })
}
