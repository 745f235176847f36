//! A `#![no_std]` `#![no_main]` program over probekit-runtime built without
//! its `std` feature: it loads a `.probes` file from bytes, queries
//! irradiance at a point and exits 0 when the answer matches the closed form
//! of `field.rs` (1 when it does not, 2 when the file does not load).
//!
//! It defines its own `#[panic_handler]`, so if std enters the dependency
//! graph the build fails: "found duplicate lang item `panic_impl`". It links
//! against the C library only (entry point `main`, `write`, `abort`; and the
//! `mem*` functions `core` calls), not against Rust's std.

#![no_std]
#![no_main]

mod bump;
mod field;

use core::ffi::{c_char, c_int};
use glam::Vec3;
use probekit_runtime::{LoadOptions, ObjectState, Probes};

#[global_allocator]
static ALLOCATOR: bump::Bump = bump::Bump::new();

/// The file `build.rs` wrote with the std build of the same crate.
static FILE: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/grid.probes"));

#[link(name = "c")]
extern "C" {
    fn write(fd: c_int, buf: *const u8, count: usize) -> isize;
    fn abort() -> !;
}

/// Writes `msg` to standard error.
fn say(msg: &str) {
    // SAFETY: `msg` is valid for `msg.len()` bytes; a short write loses text only.
    unsafe { write(2, msg.as_ptr(), msg.len()) };
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    say("probekit no_std check: panic\n");
    // SAFETY: abort takes no arguments and never returns.
    unsafe { abort() }
}

// Rust's precompiled `alloc` has unwinding landing pads, which name these two
// symbols (std, or the unwinder library, would define them). With
// `panic = "abort"` nothing unwinds, so neither is ever called.

/// Never called (nothing unwinds); only satisfies the linker.
#[no_mangle]
pub extern "C" fn rust_eh_personality() {}

/// Never called (nothing unwinds); only satisfies the linker.
#[no_mangle]
pub extern "C" fn _Unwind_Resume() -> ! {
    // SAFETY: abort takes no arguments and never returns.
    unsafe { abort() }
}

/// The C entry point (the C runtime's start files call it).
#[no_mangle]
pub extern "C" fn main(_argc: c_int, _argv: *const *const c_char) -> c_int {
    // Through the engine's entry point: trilinear volumes by default.
    let Ok(probes) = Probes::from_bytes(FILE, LoadOptions::default()) else {
        say("probekit no_std check: the file does not load\n");
        return 2;
    };
    // Inside the box, off the probes, with a normal off every axis.
    let p = Vec3::new(0.25, 1.0, 3.5);
    let n = Vec3::new(1.0, 2.0, 2.0) / 3.0;
    let mut state = ObjectState::new();
    let Ok(got) = probes.irradiance(&mut state, p, n) else {
        say("probekit no_std check: the query failed\n");
        return 1;
    };
    let want = field::irradiance(p.to_array(), n.to_array());
    let close = (0..3).all(|c| got[c].is_finite() && (got[c] - want[c]).abs() <= 1e-5 * want[c]);
    if !close {
        say("probekit no_std check: irradiance differs from the closed form\n");
        return 1;
    }
    say("probekit no_std check: ok\n");
    0
}
