//! Loading a `.probes` file into a handle, and what the handle answers
//! about itself.

use crate::error::{run_value, Error};
use crate::volume::INTERPS;
use crate::PkStatus;
use probekit_runtime::format::{FormatError, Rig};
use probekit_runtime::{
    L1Mode, LoadError, LoadOptions, ProbeFile, ProbeFileKind, Probes, QueryError, VolumeError,
};
use std::ffi::{c_char, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};

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

/// `PkLoadOptions::l1_mode`: evaluate L1 files as the bake recorded.
pub const PK_L1_MODE_AS_BAKED: i32 = -1;
/// `PkLoadOptions::l1_mode`: L1 coefficients as plain linear SH.
pub const PK_L1_MODE_LINEAR: i32 = 0;
/// `PkLoadOptions::l1_mode`: L1 coefficients with hallucinated ZH3
/// (Roughton et al., I3D 2024).
pub const PK_L1_MODE_ZH3_HALLUCINATED: i32 = 1;

/// Choices made once, when a file is loaded (`PkLoadOptions` in the
/// header; `probekit_runtime::LoadOptions`). A null pointer means
/// [`pk_load_options_default`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PkLoadOptions {
    /// A volume's interpolation (`PK_INTERP_*`: 0 trilinear, 1 Taylor,
    /// 2 tricubic, 3 inverse distance, 4 leaf trilinear); ignored by
    /// clouds. Taylor and tricubic need stored gradients: loading a volume
    /// without them fails with [`PkStatus::NoGradients`].
    pub interpolation: u32,
    /// How L1 coefficients become irradiance: `PK_L1_MODE_AS_BAKED` (-1),
    /// `PK_L1_MODE_LINEAR` (0) or `PK_L1_MODE_ZH3_HALLUCINATED` (1);
    /// ignored for other orders.
    pub l1_mode: i32,
}

/// The default options: trilinear volumes, L1 files evaluated as baked.
#[no_mangle]
pub extern "C" fn pk_load_options_default() -> PkLoadOptions {
    PkLoadOptions {
        interpolation: 0,
        l1_mode: PK_L1_MODE_AS_BAKED,
    }
}

impl PkLoadOptions {
    fn to_runtime(self) -> Result<LoadOptions, Error> {
        let mut o = LoadOptions::default();
        o.interpolation = *INTERPS.get(self.interpolation as usize).ok_or_else(|| {
            Error::new(
                PkStatus::InvalidArgument,
                format!("unknown interpolation mode {}", self.interpolation),
            )
        })?;
        o.l1_mode = match self.l1_mode {
            PK_L1_MODE_AS_BAKED => None,
            PK_L1_MODE_LINEAR => Some(L1Mode::Linear),
            PK_L1_MODE_ZH3_HALLUCINATED => Some(L1Mode::Zh3Hallucinated),
            m => {
                return Err(Error::new(
                    PkStatus::InvalidArgument,
                    format!("unknown L1 mode {m}"),
                ))
            }
        };
        Ok(o)
    }
}

/// A loaded `.probes` file (opaque `PkProbes` in C): a
/// [`probekit_runtime::Probes`] and the rigs' sample points. Created by
/// [`pk_probes_load_file`] / [`pk_probes_load_bytes`] (or their
/// default-option forms), freed by [`pk_free`].
pub struct PkProbes {
    kind: PkKind,
    pub(crate) probes: Probes,
    pub(crate) rigs: Vec<Rig>,
}

pub(crate) fn handle<'a>(p: *const PkProbes) -> Result<&'a PkProbes, Error> {
    // SAFETY: non-null handles come from pk_*load_* and are live until pk_free.
    unsafe { p.as_ref() }.ok_or_else(|| Error::null("probes handle"))
}

impl From<LoadError> for Error {
    fn from(e: LoadError) -> Self {
        let status = match &e {
            LoadError::Format(FormatError::Io { .. }) => PkStatus::Io,
            LoadError::Volume(VolumeError::NoGradients(_)) => PkStatus::NoGradients,
            LoadError::VisibilityBias(_) | LoadError::VisibilitySharpness(_) => {
                PkStatus::InvalidArgument
            }
            _ => PkStatus::Format,
        };
        Error(status, e.to_string())
    }
}

impl From<QueryError> for Error {
    fn from(e: QueryError) -> Self {
        let status = match e {
            QueryError::NoProbes => PkStatus::WrongKind,
            QueryError::NoSuchRig { .. } => PkStatus::OutOfRange,
            _ => PkStatus::InvalidArgument,
        };
        Error(status, e.to_string())
    }
}

impl PkProbes {
    fn new(file: ProbeFile, options: *const PkLoadOptions) -> Result<Self, Error> {
        // SAFETY: null or a valid PkLoadOptions per the header.
        let options = unsafe { options.as_ref() }
            .copied()
            .unwrap_or_else(|| pk_load_options_default())
            .to_runtime()?;
        let kind = match file.kind() {
            ProbeFileKind::Cloud => PkKind::Cloud,
            ProbeFileKind::Volume => PkKind::Volume,
            ProbeFileKind::Rig => PkKind::Rig,
            _ => return Err(Error::new(PkStatus::Format, "unknown file kind")),
        };
        let probes = Probes::from_file(&file, options)?;
        Ok(PkProbes {
            kind,
            probes,
            rigs: file.rigs().to_vec(),
        })
    }

    /// Coefficients [`crate::pk_sh`] writes per point.
    pub(crate) fn sh_count(&self) -> usize {
        match (self.probes.order(), self.probes.l1_mode()) {
            (_, L1Mode::Zh3Hallucinated) => 9,
            (order, _) => (order * order).min(9) as usize,
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
    // SAFETY: the caller's contract is pk_probes_load_file's.
    unsafe { pk_probes_load_file(path, std::ptr::null(), status) }
}

/// Loads the `.probes` file at `path` as [`pk_load_file`] does, with
/// `options` (null: [`pk_load_options_default`]): a volume's
/// interpolation and the L1 evaluation are chosen here, once.
#[no_mangle]
pub unsafe extern "C" fn pk_probes_load_file(
    path: *const c_char,
    options: *const PkLoadOptions,
    status: *mut PkStatus,
) -> *mut PkProbes {
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
        let h = PkProbes::new(file, options)
            .map_err(|Error(s, m)| Error(s, format!("{}: {m}", p.display())))?;
        Ok(Box::into_raw(Box::new(h)))
    })
}

/// Loads a `.probes` file from `len` bytes at `data` (copied; the caller
/// keeps ownership) with the default options. Returns a handle or null,
/// like [`pk_load_file`].
#[no_mangle]
pub unsafe extern "C" fn pk_load_bytes(
    data: *const u8,
    len: usize,
    status: *mut PkStatus,
) -> *mut PkProbes {
    // SAFETY: the caller's contract is pk_probes_load_bytes's.
    unsafe { pk_probes_load_bytes(data, len, std::ptr::null(), status) }
}

/// [`pk_load_bytes`] with `options` (null: [`pk_load_options_default`]).
#[no_mangle]
pub unsafe extern "C" fn pk_probes_load_bytes(
    data: *const u8,
    len: usize,
    options: *const PkLoadOptions,
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
        Ok(Box::into_raw(Box::new(PkProbes::new(file, options)?)))
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
    unsafe { probes.as_ref() }.map_or(0, |p| p.probes.probe_count())
}

/// SH order (number of bands: 2 = L1, 3 = L2) of the stored radiance;
/// coefficients per probe are its square. 0 for null.
#[no_mangle]
pub unsafe extern "C" fn pk_sh_order(probes: *const PkProbes) -> u32 {
    // SAFETY: see `handle`.
    unsafe { probes.as_ref() }.map_or(0, |p| p.probes.order())
}

/// Coefficients per point that [`crate::pk_sh`] writes (times 3 floats):
/// 9 (bands 0–2) for L2 and higher orders and for an L1 file evaluated
/// with hallucinated ZH3, 4 for a linear L1 file, 1 for L0; 0 for null.
#[no_mangle]
pub unsafe extern "C" fn pk_sh_count(probes: *const PkProbes) -> u32 {
    // SAFETY: see `handle`.
    unsafe { probes.as_ref() }.map_or(0, |p| p.sh_count() as u32)
}

/// How the handle's L1 coefficients become irradiance, as chosen at load:
/// `PK_L1_MODE_LINEAR` (also for every other order) or
/// `PK_L1_MODE_ZH3_HALLUCINATED`; -1 for null.
#[no_mangle]
pub unsafe extern "C" fn pk_l1_mode(probes: *const PkProbes) -> i32 {
    // SAFETY: see `handle`.
    match unsafe { probes.as_ref() }.map(|p| p.probes.l1_mode()) {
        Some(L1Mode::Zh3Hallucinated) => PK_L1_MODE_ZH3_HALLUCINATED,
        Some(_) => PK_L1_MODE_LINEAR,
        None => -1,
    }
}
