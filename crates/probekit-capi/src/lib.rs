//! # probekit-capi — the C ABI of probekit-runtime
//!
//! What a C or C++ engine links (`libprobekit_capi.a`, `.so`, `.dylib` or
//! `.dll`) together with the header `include/probekit.h`, which documents
//! every function, its units and conventions. This crate is a thin shell: it
//! converts pointers into slices, checks them, and calls
//! [`probekit_runtime`]. Build and link instructions: `docs/c-api.md`.
//!
//! ## Rules every function follows
//! * Every pointer is null-checked; a null or otherwise bad argument returns
//!   a [`PkStatus`] error (or null / 0 for constructors and getters) and sets
//!   the thread's last error message ([`pk_last_error`]).
//! * No panic crosses the boundary: the code has no panicking path on bad
//!   input, and every body runs under [`std::panic::catch_unwind`] as a last
//!   guard ([`PkStatus::Panic`]).
//! * Queries ([`pk_irradiance`], [`pk_sh`], their batched forms, the rig
//!   queries) never allocate; only loading, state creation and error
//!   reporting do.
//! * A [`PkProbes`] is immutable after loading except for its volume
//!   interpolation mode (an atomic), so it can be queried from many threads
//!   at once; a [`PkWalkState`] or a [`PkRig`] belongs to one object and
//!   must not be used by two threads at the same time.
//!
//! Conventions are those of `probekit_sh`: right-handed, +Y up, metres,
//! linear RGB, real SH indexed `l(l+1)+m` (Sloan's Condon–Shortley phase),
//! stored SH is radiance SH, irradiance `E(n) = ∫ L(ω) max(0, n·ω) dω` is
//! not divided by π.

#![warn(missing_docs)]
// The exported functions take raw pointers from C; each one null-checks and
// documents its contract in include/probekit.h rather than in `# Safety`.
#![allow(clippy::missing_safety_doc)]

use glam::Vec3;
use probekit_runtime::cloud::WalkState;
use probekit_runtime::format::{FormatError, Rig};
use probekit_runtime::rig::RigState;
use probekit_runtime::sh::MAX_COEFFS;
use probekit_runtime::{Interp, ProbeCloud, ProbeFile, ProbeFileKind, Volume};
use std::cell::RefCell;
use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicU32, Ordering};

/// Version of this C ABI; `PK_ABI_VERSION` in the header. Bumped when a
/// signature or a struct/enum value changes.
pub const PK_ABI_VERSION: u32 = 1;

/// Result of every fallible call (`PkStatus` in the header). On anything but
/// [`PkStatus::Ok`], [`pk_last_error`] describes the problem.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PkStatus {
    /// Success.
    Ok = 0,
    /// A required pointer argument was null.
    NullArgument = 1,
    /// The file could not be read (missing, permissions, not UTF-8 path on
    /// a platform that needs one).
    Io = 2,
    /// The bytes are not a valid `.probes` file (magic, version, checksum,
    /// sizes, indices, NaN, ...), or its content cannot be queried.
    Format = 3,
    /// An argument is out of its domain (NaN position, unknown enum value,
    /// size overflow).
    InvalidArgument = 4,
    /// The handle is of a kind that cannot answer this call (e.g. a
    /// volume call on a cloud).
    WrongKind = 5,
    /// An output buffer is too short; nothing was written.
    BufferTooSmall = 6,
    /// The interpolation mode needs gradients the volume does not store.
    NoGradients = 7,
    /// An index (rig number) is out of range.
    OutOfRange = 8,
    /// An internal error (a bug): a panic was caught at the boundary.
    Panic = 9,
}

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

/// Volume interpolation modes (`PK_INTERP_*` in the header); see
/// `probekit_runtime::volume` for the formulas (seed 001, Tatarchuk).
const INTERPS: [Interp; 5] = [
    Interp::Trilinear,
    Interp::Taylor,
    Interp::Tricubic,
    Interp::InverseDistance,
    Interp::LeafTrilinear,
];

/// What a handle can be queried as.
enum Body {
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
    body: Body,
    /// Index into [`INTERPS`]; atomic so that queries may run concurrently.
    interp: AtomicU32,
    rigs: Vec<Rig>,
}

/// A per-object probe-cloud walk cache (opaque `PkWalkState` in C): the
/// runtime's [`WalkState`]. Created by [`pk_walk_state_new`].
pub struct PkWalkState(WalkState);

/// One object's irradiance rig (opaque `PkRig` in C): the runtime's
/// [`RigState`] plus the rig's sample points and a scratch buffer for
/// [`pk_rig_update_from_probes`]. Created by [`pk_rig_new`].
pub struct PkRig {
    state: RigState,
    samples: Vec<Vec3>,
    scratch: Vec<Vec3>,
}

/// An error on its way to the caller: status and message.
struct Error(PkStatus, String);

impl Error {
    fn new(status: PkStatus, msg: impl Into<String>) -> Self {
        Error(status, msg.into())
    }
    fn null(what: &str) -> Self {
        Error(PkStatus::NullArgument, format!("{what} is null"))
    }
}

impl From<FormatError> for Error {
    fn from(e: FormatError) -> Self {
        let status = match e {
            FormatError::Io { .. } => PkStatus::Io,
            _ => PkStatus::Format,
        };
        Error(status, e.to_string())
    }
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_error(status: PkStatus, msg: &str) {
    let text = format!("{status:?}: {msg}").replace('\0', " ");
    let c = CString::new(text).unwrap_or_default();
    // A thread being torn down has no last error to keep; ignore.
    let _ = LAST_ERROR.try_with(|e| {
        if let Ok(mut e) = e.try_borrow_mut() {
            *e = c;
        }
    });
}

/// Runs a status-returning body under `catch_unwind`, recording any error.
fn run(f: impl FnOnce() -> Result<(), Error>) -> PkStatus {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => PkStatus::Ok,
        Ok(Err(Error(status, msg))) => {
            set_error(status, &msg);
            status
        }
        Err(_) => {
            set_error(PkStatus::Panic, "internal panic caught at the C boundary");
            PkStatus::Panic
        }
    }
}

/// Runs a value-returning body (constructor or getter): `fallback` on error,
/// with the status written to `status` when it is not null.
fn run_value<T>(status: *mut PkStatus, fallback: T, f: impl FnOnce() -> Result<T, Error>) -> T {
    let mut value = None;
    let s = run(|| {
        value = Some(f()?);
        Ok(())
    });
    if !status.is_null() {
        // SAFETY: the caller passes either null or a valid PkStatus pointer.
        unsafe { status.write(s) };
    }
    value.unwrap_or(fallback)
}

fn handle<'a>(p: *const PkProbes) -> Result<&'a PkProbes, Error> {
    // SAFETY: non-null handles come from pk_load_* and are live until pk_free.
    unsafe { p.as_ref() }.ok_or_else(|| Error::null("probes handle"))
}

/// Reads 3 floats (a point or a normal); refuses null and non-finite values.
fn vec3_in(p: *const f32, what: &str) -> Result<Vec3, Error> {
    if p.is_null() {
        return Err(Error::null(what));
    }
    // SAFETY: non-null; the header requires 3 readable floats.
    let v = Vec3::from_slice(unsafe { std::slice::from_raw_parts(p, 3) });
    if !v.is_finite() {
        return Err(Error::new(
            PkStatus::InvalidArgument,
            format!("{what} is NaN or infinite"),
        ));
    }
    Ok(v)
}

/// `3·n` floats from `p` (null allowed only when `n == 0`).
fn floats_in<'a>(p: *const f32, n: usize, what: &str) -> Result<&'a [f32], Error> {
    let len = n
        .checked_mul(3)
        .filter(|&l| l <= isize::MAX as usize / 4)
        .ok_or_else(|| Error::new(PkStatus::InvalidArgument, "count too large"))?;
    if len == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(Error::null(what));
    }
    // SAFETY: non-null; the header requires `len` readable floats.
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

/// `3·count`, refused when it overflows.
fn times3(count: usize) -> Result<usize, Error> {
    count
        .checked_mul(3)
        .ok_or_else(|| Error::new(PkStatus::InvalidArgument, "count too large"))
}

/// `len` writable floats at `p` (null allowed only when `len == 0`).
fn floats_out<'a>(p: *mut f32, len: usize, what: &str) -> Result<&'a mut [f32], Error> {
    if len > isize::MAX as usize / 4 {
        return Err(Error::new(PkStatus::InvalidArgument, "count too large"));
    }
    if len == 0 {
        return Ok(&mut []);
    }
    if p.is_null() {
        return Err(Error::null(what));
    }
    // SAFETY: non-null; the header requires `len` writable floats.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

fn finite(v: Vec3, what: &str, i: usize) -> Result<Vec3, Error> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::new(
            PkStatus::InvalidArgument,
            format!("{what} {i} is NaN or infinite"),
        ))
    }
}

fn walk_state<'a>(ws: *mut PkWalkState) -> Option<&'a mut WalkState> {
    // SAFETY: non-null walk states come from pk_walk_state_new.
    unsafe { ws.as_mut() }.map(|w| &mut w.0)
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

    fn coeff_count(&self) -> usize {
        (self.order * self.order) as usize
    }

    /// Interpolated radiance SH at `p` into `out[..order²]` (`out` holds
    /// [`MAX_COEFFS`]). No allocation.
    fn sh_into(
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

    fn irradiance(&self, p: Vec3, n: Vec3, ws: Option<&mut WalkState>) -> Result<Vec3, Error> {
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

// ---------------------------------------------------------------- errors --

/// The calling thread's last error message (UTF-8, NUL-terminated, never
/// null; `""` before any error). Valid until the next failing call on the
/// same thread. Successful calls leave it unchanged.
#[no_mangle]
pub extern "C" fn pk_last_error() -> *const c_char {
    catch_unwind(|| {
        LAST_ERROR
            .try_with(|e| e.try_borrow().map(|s| s.as_ptr()).ok())
            .ok()
            .flatten()
    })
    .ok()
    .flatten()
    .unwrap_or(c"".as_ptr())
}

/// Copies the last error message into `buf` (`len` bytes, NUL-terminated,
/// truncated if needed; `buf` may be null when `len` is 0). Returns the
/// message length in bytes without the NUL, so `len` must exceed it for an
/// untruncated copy.
#[no_mangle]
pub unsafe extern "C" fn pk_last_error_copy(buf: *mut c_char, len: usize) -> usize {
    catch_unwind(|| {
        LAST_ERROR
            .try_with(|e| {
                let Ok(s) = e.try_borrow() else { return 0 };
                let bytes = s.as_bytes();
                if !buf.is_null() && len > 0 {
                    let k = bytes.len().min(len - 1);
                    // SAFETY: the caller provides `len` writable bytes at `buf`.
                    unsafe {
                        std::ptr::copy_nonoverlapping(bytes.as_ptr().cast::<c_char>(), buf, k);
                        buf.add(k).write(0);
                    }
                }
                bytes.len()
            })
            .unwrap_or(0)
    })
    .unwrap_or(0)
}

/// [`PK_ABI_VERSION`]: compare with the header's `PK_ABI_VERSION` at start-up.
#[no_mangle]
pub extern "C" fn pk_abi_version() -> u32 {
    PK_ABI_VERSION
}

// --------------------------------------------------------------- loading --

/// Loads the `.probes` file at `path` (NUL-terminated; UTF-8 on Windows,
/// bytes elsewhere). Returns a handle to free with [`pk_free`], or null with
/// the reason in `status` (may be null) and [`pk_last_error`].
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

// ----------------------------------------------------------- walk state --

/// A new, cold walk state for one object querying a probe cloud; free with
/// [`pk_walk_state_free`]. Null only if allocation fails.
#[no_mangle]
pub extern "C" fn pk_walk_state_new() -> *mut PkWalkState {
    catch_unwind(|| Box::into_raw(Box::new(PkWalkState(WalkState::new()))))
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
        *w = WalkState::new();
    }
}

// --------------------------------------------------------------- queries --

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

// ----------------------------------------------------------------- cloud --

/// The blend a probe cloud uses at `position[3]`: its 4 probe indices into
/// `out_indices[4]` and their weights into `out_weights[4]` (summing to 1;
/// unused slots weight 0, index any) — barycentric in the enclosing
/// tetrahedron or outer cell, times each probe's Chebyshev visibility when
/// the file stores distance moments (`VISM`), its cell visibility (`CVSP`,
/// refined by the occluder planes of `CPLN`) and its fitted weight
/// (`PWGT`), renormalized; where the cell visibility hides every probe of
/// positive weight, the cell's darkest probe alone, and where it leaves
/// less than a tenth of the weight in sight, a blend towards that probe
/// (`ProbeCloud::weights_at`). These are the weights the
/// shaders' `pk_blend_l1` / `pk_blend_l2` take, so a GPU blend of the four
/// probes equals [`pk_sh`] — except for a file whose `PWGT` stores a
/// directional brightness exponent (format 1.9): [`pk_sh`] then blends per
/// direction (`ProbeCloud::set_directional_brightness`), which four weights
/// cannot express, so use [`pk_sh`] per object. Not a cloud: [`PkStatus::WrongKind`]. `state`
/// as in [`pk_irradiance`]. No allocation.
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
        let Body::Cloud(c) = &h.body else {
            return Err(Error::new(PkStatus::WrongKind, "not a probe cloud"));
        };
        let p = vec3_in(position, "position")?;
        if out_indices.is_null() {
            return Err(Error::null("out_indices"));
        }
        let weights = floats_out(out_weights, 4, "out_weights")?;
        let mut cold = WalkState::new();
        let (idx, w) = c.weights_at(p, walk_state(state).unwrap_or(&mut cold));
        // SAFETY: non-null; the header requires 4 writable u32.
        unsafe { std::slice::from_raw_parts_mut(out_indices, 4) }.copy_from_slice(&idx);
        weights.copy_from_slice(&w);
        Ok(())
    })
}

// ---------------------------------------------------------------- volume --

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

// ------------------------------------------------------------------- rigs --

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
        let name = rig.name.as_bytes();
        if !name_len.is_null() {
            // SAFETY: non-null, points to a usize per the header.
            unsafe { name_len.write(name.len()) };
        }
        if buf_len <= name.len() {
            return Err(Error::new(
                PkStatus::BufferTooSmall,
                format!("rig name needs {} bytes", name.len() + 1),
            ));
        }
        if buf.is_null() {
            return Err(Error::null("buf"));
        }
        // SAFETY: `buf` holds `buf_len > name.len()` writable bytes.
        unsafe {
            std::ptr::copy_nonoverlapping(name.as_ptr().cast::<c_char>(), buf, name.len());
            buf.add(name.len()).write(0);
        }
        Ok(())
    })
}

/// Per-object state for rig `index` of the file: parameters start at zero
/// (irradiance 0) until the first update. Independent of the handle
/// afterwards (it may be freed first). Free with [`pk_rig_free`]. Null on
/// error, with `status` (may be null) and [`pk_last_error`].
#[no_mangle]
pub unsafe extern "C" fn pk_rig_new(
    probes: *const PkProbes,
    index: usize,
    status: *mut PkStatus,
) -> *mut PkRig {
    run_value(status, std::ptr::null_mut(), || {
        let h = handle(probes)?;
        let rig = h.rigs.get(index).ok_or_else(|| {
            Error::new(
                PkStatus::OutOfRange,
                format!("rig {index} of {}", h.rigs.len()),
            )
        })?;
        let state = RigState::new(rig).map_err(|e| Error::new(PkStatus::Format, e.to_string()))?;
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
/// The lighting's SH is truncated or zero-padded to the rig's order.
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
        let m = n2.min(h.coeff_count());
        let mut cold = WalkState::new();
        let ws = walk_state(state).unwrap_or(&mut cold);
        let mut buf = [Vec3::ZERO; MAX_COEFFS];
        for (s, dst) in r.samples.iter().zip(r.scratch.chunks_exact_mut(n2.max(1))) {
            h.sh_into(*s + t, Some(&mut *ws), &mut buf)?;
            dst.fill(Vec3::ZERO);
            dst[..m].copy_from_slice(&buf[..m]);
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
