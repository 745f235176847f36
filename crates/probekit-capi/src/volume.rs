//! Irradiance volumes: the interpolation mode of a handle.

use crate::error::{run, Error};
use crate::probes::{handle, Body};
use crate::{PkProbes, PkStatus};
use probekit_runtime::Interp;
use std::sync::atomic::Ordering;

/// Volume interpolation modes (`PK_INTERP_*` in the header); see
/// `probekit_runtime::volume` for the formulas (Tatarchuk, *Irradiance
/// Volumes for Games*).
pub(crate) const INTERPS: [Interp; 5] = [
    Interp::Trilinear,
    Interp::Taylor,
    Interp::Tricubic,
    Interp::InverseDistance,
    Interp::LeafTrilinear,
];

/// Sets a volume's interpolation mode (`PK_INTERP_*`: 0 trilinear, 1 Taylor,
/// 2 tricubic, 3 inverse distance, 4 leaf trilinear). Taylor and tricubic
/// need stored gradients ([`PkStatus::NoGradients`] otherwise, mode
/// unchanged). Atomic: safe while other threads query (they see the old or
/// the new mode).
#[no_mangle]
pub unsafe extern "C" fn pk_volume_set_interp(probes: *const PkProbes, mode: u32) -> PkStatus {
    run(|| {
        let h = handle(probes)?;
        let Body::Volume(v) = &h.body else {
            return Err(Error::new(PkStatus::WrongKind, "not a volume"));
        };
        let interp = INTERPS.get(mode as usize).ok_or_else(|| {
            Error::new(
                PkStatus::InvalidArgument,
                format!("unknown interpolation mode {mode}"),
            )
        })?;
        if interp.needs_gradients() && !v.has_gradients() {
            return Err(Error::new(
                PkStatus::NoGradients,
                format!("interpolation {interp:?} needs gradients; the volume has none"),
            ));
        }
        h.interp.store(mode, Ordering::Relaxed);
        Ok(())
    })
}

/// A volume's current interpolation mode (`PK_INTERP_*`), or -1 for null or
/// a handle that is not a volume.
#[no_mangle]
pub unsafe extern "C" fn pk_volume_interp(probes: *const PkProbes) -> i32 {
    // SAFETY: see `handle`.
    match unsafe { probes.as_ref() } {
        Some(h) if matches!(h.body, Body::Volume(_)) => h.interp.load(Ordering::Relaxed) as i32,
        _ => -1,
    }
}

/// 1 if the handle is a volume storing SH gradients (Taylor and tricubic
/// modes available), else 0.
#[no_mangle]
pub unsafe extern "C" fn pk_volume_has_gradients(probes: *const PkProbes) -> i32 {
    // SAFETY: see `handle`.
    match unsafe { probes.as_ref() }.map(|h| &h.body) {
        Some(Body::Volume(v)) => v.has_gradients() as i32,
        _ => 0,
    }
}
