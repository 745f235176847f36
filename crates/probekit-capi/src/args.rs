//! Pointer arguments from C turned into values and slices: null checks,
//! finiteness, and lengths that cannot overflow.

use crate::error::Error;
use crate::PkStatus;
use glam::Vec3;

/// Writes `name` (UTF-8, `what` in errors) as a NUL-terminated string into
/// `buf` (`buf_len` bytes) and its length without the NUL into `name_len`
/// (may be null, written even when the buffer is too small, so a caller
/// can ask with a null buffer of length 0 first). Too small a buffer is
/// [`PkStatus::BufferTooSmall`], nothing written to it.
pub(crate) fn name_out(
    name: &[u8],
    what: &str,
    buf: *mut std::ffi::c_char,
    buf_len: usize,
    name_len: *mut usize,
) -> Result<(), Error> {
    if !name_len.is_null() {
        // SAFETY: non-null, points to a usize per the header.
        unsafe { name_len.write(name.len()) };
    }
    if buf_len <= name.len() {
        return Err(Error::new(
            PkStatus::BufferTooSmall,
            format!("{what} needs {} bytes", name.len() + 1),
        ));
    }
    if buf.is_null() {
        return Err(Error::null("buf"));
    }
    // SAFETY: `buf` holds `buf_len > name.len()` writable bytes.
    unsafe {
        std::ptr::copy_nonoverlapping(name.as_ptr().cast::<std::ffi::c_char>(), buf, name.len());
        buf.add(name.len()).write(0);
    }
    Ok(())
}

/// Reads 3 floats (a point or a normal); refuses null and non-finite values.
pub(crate) fn vec3_in(p: *const f32, what: &str) -> Result<Vec3, Error> {
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
pub(crate) fn floats_in<'a>(p: *const f32, n: usize, what: &str) -> Result<&'a [f32], Error> {
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
pub(crate) fn times3(count: usize) -> Result<usize, Error> {
    count
        .checked_mul(3)
        .ok_or_else(|| Error::new(PkStatus::InvalidArgument, "count too large"))
}

/// `len` writable floats at `p` (null allowed only when `len == 0`).
pub(crate) fn floats_out<'a>(p: *mut f32, len: usize, what: &str) -> Result<&'a mut [f32], Error> {
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

pub(crate) fn finite(v: Vec3, what: &str, i: usize) -> Result<Vec3, Error> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::new(
            PkStatus::InvalidArgument,
            format!("{what} {i} is NaN or infinite"),
        ))
    }
}
