//! Irradiance volumes: the interpolation mode a handle was loaded with.

use crate::PkProbes;
use probekit_runtime::Interp;

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

/// A volume's interpolation mode (`PK_INTERP_*`), chosen at load
/// ([`crate::PkLoadOptions`]), or -1 for null or a handle that is not a
/// volume.
#[no_mangle]
pub unsafe extern "C" fn pk_volume_interp(probes: *const PkProbes) -> i32 {
    // SAFETY: see `crate::probes::handle`.
    let interp = unsafe { probes.as_ref() }.and_then(|h| h.probes.interpolation());
    interp
        .and_then(|i| INTERPS.iter().position(|&m| m == i))
        .map_or(-1, |m| m as i32)
}

/// 1 if the handle is a volume storing SH gradients (Taylor and tricubic
/// modes available), else 0.
#[no_mangle]
pub unsafe extern "C" fn pk_volume_has_gradients(probes: *const PkProbes) -> i32 {
    // SAFETY: see `crate::probes::handle`.
    match unsafe { probes.as_ref() }.and_then(|h| h.probes.volume()) {
        Some(v) => v.has_gradients() as i32,
        None => 0,
    }
}
