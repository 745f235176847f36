//! Status codes, the error type every body returns, the guard that keeps
//! panics from crossing the boundary, and the thread's last error message.

use probekit_runtime::format::FormatError;
use std::cell::RefCell;
use std::ffi::{c_char, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

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

/// An error on its way to the caller: status and message.
pub(crate) struct Error(pub(crate) PkStatus, pub(crate) String);

impl Error {
    pub(crate) fn new(status: PkStatus, msg: impl Into<String>) -> Self {
        Error(status, msg.into())
    }
    pub(crate) fn null(what: &str) -> Self {
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
pub(crate) fn run(f: impl FnOnce() -> Result<(), Error>) -> PkStatus {
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
pub(crate) fn run_value<T>(
    status: *mut PkStatus,
    fallback: T,
    f: impl FnOnce() -> Result<T, Error>,
) -> T {
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
