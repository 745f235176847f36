//! Loading a `.probes` file into a handle, and what the handle answers
//! about itself.

use crate::error::{run_value, Error};
use crate::volume::INTERPS;
use crate::PkStatus;
use glam::Vec3;
use probekit_runtime::cloud::WalkState;
use probekit_runtime::format::Rig;
use probekit_runtime::sh::MAX_COEFFS;
use probekit_runtime::{Interp, ProbeCloud, ProbeFile, ProbeFileKind, Volume};
use std::ffi::{c_char, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicU32, Ordering};

/// What a loaded file holds (`PkKind` in the header); the values are the
/// file header's kind ids.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PkKind {
    /// A probe cloud (tetrahedral interpolation).
    Cloud = 0,
    /// An irradiance volume (uniform grid or adaptive octree).
    Volume = 1,
    /// Irradiance rigs only (no queryable probes).
    Rig = 2,
    /// Returned for a null handle.
    Invalid = -1,
}

/// What a handle can be queried as.
pub(crate) enum Body {
    Cloud(ProbeCloud),
    Volume(Volume),
    /// A rig-only file: no probe queries.
    None,
}

/// A loaded `.probes` file (opaque `PkProbes` in C): created by
/// [`pk_load_file`] / [`pk_load_bytes`], freed by [`pk_free`].
pub struct PkProbes {
    kind: PkKind,
    order: u32,
    probe_count: usize,
    pub(crate) body: Body,
    /// Index into [`INTERPS`]; atomic so that queries may run concurrently.
    pub(crate) interp: AtomicU32,
    pub(crate) rigs: Vec<Rig>,
}

pub(crate) fn handle<'a>(p: *const PkProbes) -> Result<&'a PkProbes, Error> {
    // SAFETY: non-null handles come from pk_load_* and are live until pk_free.
    unsafe { p.as_ref() }.ok_or_else(|| Error::null("probes handle"))
}

impl PkProbes {
    fn from_file(file: ProbeFile) -> Result<Self, Error> {
        let order = file.coefficients.order;
        if order == 0 || (order * order) as usize > MAX_COEFFS {
            return Err(Error::new(PkStatus::Format, "SH order outside 1..=8"));
        }
        let (kind, body) = match file.kind {
            ProbeFileKind::Cloud => {
                let c = ProbeCloud::from_file(&file)
                    .map_err(|e| Error::new(PkStatus::Format, e.to_string()))?;
                (PkKind::Cloud, Body::Cloud(c))
            }
            ProbeFileKind::Volume => {
                let v = Volume::from_file(&file)
                    .map_err(|e| Error::new(PkStatus::Format, e.to_string()))?;
                (PkKind::Volume, Body::Volume(v))
            }
            ProbeFileKind::Rig => (PkKind::Rig, Body::None),
            _ => return Err(Error::new(PkStatus::Format, "unknown file kind")),
        };
        Ok(PkProbes {
            kind,
            order,
            probe_count: file.positions.len(),
            body,
            interp: AtomicU32::new(0),
            rigs: file.rigs,
        })
    }

    fn interp(&self) -> Interp {
        INTERPS
            .get(self.interp.load(Ordering::Relaxed) as usize)
            .copied()
            .unwrap_or(Interp::Trilinear)
    }

    pub(crate) fn coeff_count(&self) -> usize {
        (self.order * self.order) as usize
    }

    /// Interpolated radiance SH at `p` into `out[..order²]` (`out` holds
    /// [`MAX_COEFFS`]). No allocation.
    pub(crate) fn sh_into(
        &self,
        p: Vec3,
        ws: Option<&mut WalkState>,
        out: &mut [Vec3; MAX_COEFFS],
    ) -> Result<(), Error> {
        let n = self.coeff_count();
        match &self.body {
            Body::Cloud(c) => {
                let mut cold = WalkState::new();
                c.sh_at(p, ws.unwrap_or(&mut cold), &mut out[..n]);
                Ok(())
            }
            Body::Volume(v) => v
                .sample_sh(p, self.interp(), &mut out[..n])
                .map_err(|e| Error::new(PkStatus::NoGradients, e.to_string())),
            Body::None => Err(Error::new(
                PkStatus::WrongKind,
                "a rig file has no probes to query",
            )),
        }
    }

    pub(crate) fn irradiance(
        &self,
        p: Vec3,
        n: Vec3,
        ws: Option<&mut WalkState>,
    ) -> Result<Vec3, Error> {
        match &self.body {
            Body::Cloud(c) => {
                let mut cold = WalkState::new();
                Ok(c.irradiance(p, n, ws.unwrap_or(&mut cold)))
            }
            Body::Volume(v) => v
                .irradiance(p, n, self.interp())
                .map_err(|e| Error::new(PkStatus::NoGradients, e.to_string())),
            Body::None => Err(Error::new(
                PkStatus::WrongKind,
                "a rig file has no probes to query",
            )),
        }
    }
}

/// Loads the `.probes` file at `path` (NUL-terminated; UTF-8 on Windows,
/// bytes elsewhere). Returns a handle to free with [`pk_free`], or null with
/// the reason in `status` (may be null) and [`pk_last_error`].
///
/// [`pk_last_error`]: crate::pk_last_error
#[no_mangle]
pub unsafe extern "C" fn pk_load_file(path: *const c_char, status: *mut PkStatus) -> *mut PkProbes {
    run_value(status, std::ptr::null_mut(), || {
        if path.is_null() {
            return Err(Error::null("path"));
        }
        // SAFETY: non-null, NUL-terminated per the header.
        let c = unsafe { CStr::from_ptr(path) };
        #[cfg(unix)]
        let p = {
            use std::os::unix::ffi::OsStrExt;
            std::path::Path::new(std::ffi::OsStr::from_bytes(c.to_bytes()))
        };
        #[cfg(not(unix))]
        let p = std::path::Path::new(
            c.to_str()
                .map_err(|_| Error::new(PkStatus::Io, "path is not UTF-8"))?,
        );
        let file = ProbeFile::load(p)?;
        let h = PkProbes::from_file(file)
            .map_err(|Error(s, m)| Error(s, format!("{}: {m}", p.display())))?;
        Ok(Box::into_raw(Box::new(h)))
    })
}

/// Loads a `.probes` file from `len` bytes at `data` (copied; the caller
/// keeps ownership). Returns a handle or null, like [`pk_load_file`].
#[no_mangle]
pub unsafe extern "C" fn pk_load_bytes(
    data: *const u8,
    len: usize,
    status: *mut PkStatus,
) -> *mut PkProbes {
    run_value(status, std::ptr::null_mut(), || {
        let bytes: &[u8] = if len == 0 {
            &[]
        } else if data.is_null() {
            return Err(Error::null("data"));
        } else if len > isize::MAX as usize {
            return Err(Error::new(PkStatus::InvalidArgument, "length too large"));
        } else {
            // SAFETY: non-null; the caller provides `len` readable bytes.
            unsafe { std::slice::from_raw_parts(data, len) }
        };
        let file = ProbeFile::from_bytes(bytes)?;
        Ok(Box::into_raw(Box::new(PkProbes::from_file(file)?)))
    })
}

/// Frees a handle from [`pk_load_file`] / [`pk_load_bytes`] (null is a no-op).
/// Rig states created from it stay valid (they own their data).
#[no_mangle]
pub unsafe extern "C" fn pk_free(probes: *mut PkProbes) {
    if !probes.is_null() {
        // SAFETY: created by Box::into_raw in pk_load_*; freed once.
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(probes) })));
    }
}

/// The handle's kind; [`PkKind::Invalid`] for null.
#[no_mangle]
pub unsafe extern "C" fn pk_kind(probes: *const PkProbes) -> PkKind {
    // SAFETY: see `handle`.
    unsafe { probes.as_ref() }.map_or(PkKind::Invalid, |p| p.kind)
}

/// Number of probes (volume samples) in the file; 0 for null.
#[no_mangle]
pub unsafe extern "C" fn pk_probe_count(probes: *const PkProbes) -> usize {
    // SAFETY: see `handle`.
    unsafe { probes.as_ref() }.map_or(0, |p| p.probe_count)
}

/// SH order (number of bands: 2 = L1, 3 = L2) of the stored radiance;
/// coefficients per probe are its square. 0 for null.
#[no_mangle]
pub unsafe extern "C" fn pk_sh_order(probes: *const PkProbes) -> u32 {
    // SAFETY: see `handle`.
    unsafe { probes.as_ref() }.map_or(0, |p| p.order)
}
