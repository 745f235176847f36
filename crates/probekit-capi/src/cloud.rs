//! Probe-cloud specifics: the per-object walk state, and the blend
//! weights a cloud uses at a point.

use crate::args::{floats_out, vec3_in};
use crate::error::{run, Error};
use crate::probes::handle;
use crate::{PkProbes, PkStatus};
use probekit_runtime::{ObjectState, ProbeFileKind};
use std::panic::catch_unwind;

/// A per-object query state (opaque `PkWalkState` in C): the runtime's
/// [`ObjectState`], the walk cache of a probe cloud (unused by volumes).
/// Created by [`pk_walk_state_new`].
pub struct PkWalkState(ObjectState);

pub(crate) fn walk_state<'a>(ws: *mut PkWalkState) -> Option<&'a mut ObjectState> {
    // SAFETY: non-null walk states come from pk_walk_state_new.
    unsafe { ws.as_mut() }.map(|w| &mut w.0)
}

/// A new, cold walk state for one object querying a probe cloud; free with
/// [`pk_walk_state_free`]. Null only if allocation fails.
#[no_mangle]
pub extern "C" fn pk_walk_state_new() -> *mut PkWalkState {
    catch_unwind(|| Box::into_raw(Box::new(PkWalkState(ObjectState::new()))))
        .unwrap_or(std::ptr::null_mut())
}

/// Frees a walk state (null is a no-op).
#[no_mangle]
pub unsafe extern "C" fn pk_walk_state_free(state: *mut PkWalkState) {
    if !state.is_null() {
        // SAFETY: created by pk_walk_state_new; freed once.
        drop(unsafe { Box::from_raw(state) });
    }
}

/// Makes a walk state cold again (e.g. after the object teleported or is
/// moved to another cloud). Null is a no-op.
#[no_mangle]
pub unsafe extern "C" fn pk_walk_state_reset(state: *mut PkWalkState) {
    if let Some(w) = walk_state(state) {
        *w = ObjectState::new();
    }
}

/// The blend a probe cloud uses at `position[3]`: its 4 probe indices into
/// `out_indices[4]` and their weights into `out_weights[4]` (summing to 1;
/// unused slots weight 0, index any) — barycentric in the enclosing
/// tetrahedron or outer cell, times each probe's Chebyshev visibility when
/// the file stores distance moments (`VISM`), its cell visibility (`CVSP`,
/// refined by the occluder planes of `CPLN`) and its fitted weight
/// (`PWGT`), renormalized; where the cell visibility hides every probe of
/// positive weight, the cell's darkest probe alone, and where it leaves
/// less than a tenth of the weight in sight, a blend towards that probe
/// (`probekit_runtime::Probes::query`). These are the weights the
/// shaders' `pk_blend_l1` / `pk_blend_l2` take, so a GPU blend of the four
/// probes equals [`pk_sh`] — except for a file whose `PWGT` stores a
/// directional brightness exponent: [`pk_sh`] then blends per
/// direction, which four weights cannot express, so use [`pk_sh`] per
/// object. Not a cloud: [`PkStatus::WrongKind`]. `state`
/// as in [`pk_irradiance`]. No allocation.
///
/// [`pk_sh`]: crate::pk_sh
/// [`pk_irradiance`]: crate::pk_irradiance
#[no_mangle]
pub unsafe extern "C" fn pk_cloud_weights(
    probes: *const PkProbes,
    state: *mut PkWalkState,
    position: *const f32,
    out_indices: *mut u32,
    out_weights: *mut f32,
) -> PkStatus {
    run(|| {
        let h = handle(probes)?;
        if h.probes.cloud().is_none() || h.probes.kind() != ProbeFileKind::Cloud {
            return Err(Error::new(PkStatus::WrongKind, "not a probe cloud"));
        }
        let p = vec3_in(position, "position")?;
        if out_indices.is_null() {
            return Err(Error::null("out_indices"));
        }
        let weights = floats_out(out_weights, 4, "out_weights")?;
        let mut cold = ObjectState::new();
        let q = h.probes.query(walk_state(state).unwrap_or(&mut cold), p)?;
        // SAFETY: non-null; the header requires 4 writable u32.
        unsafe { std::slice::from_raw_parts_mut(out_indices, 4) }.copy_from_slice(&q.probes[..4]);
        weights.copy_from_slice(&q.weights[..4]);
        Ok(())
    })
}
