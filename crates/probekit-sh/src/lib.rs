//! # probekit-sh — spherical harmonics and friends for diffuse lighting
//!
//! The math crate of probekit: real spherical harmonics (SH) of up to eight
//! bands, projection, clamped-cosine convolution, evaluation of irradiance,
//! and (in sibling modules) windowing, rotation, analytic lights, ZH3,
//! Geomerics L1, the ambient cube, the HL2 basis and quantized codecs. Its
//! dependencies (`glam`, `half`, `once_cell`; `libm` without std) are all
//! `no_std`, so an engine's runtime can use it, with or without std.
//!
//! ## Features
//! * `std` (default): std's float math and `std::error::Error`.
//! * Without `std` the crate is `#![no_std]` + `alloc`; enable `libm` for the
//!   float functions `core` lacks ([`math`]). Every function works the same;
//!   float results can differ from std's in the last bit.
//!
//! ## Conventions (the single source; `docs/conventions.md` has worked examples)
//!
//! - **Space**: right-handed, +Y up, metres (as glTF).
//! - **Colour**: linear RGB (Rec. 709 primaries); luminance is
//!   `0.2126 R + 0.7152 G + 0.0722 B` ([`LUMINANCE`]).
//! - **SH basis**: real SH indexed `l*(l+1)+m`, with the Condon–Shortley phase
//!   of Sloan's *Stupid SH Tricks*: `Y1,-1 = -0.4886·y`, `Y1,0 = 0.4886·z`,
//!   `Y1,1 = -0.4886·x` ([`basis`]). The basis's polar axis is +Z.
//! - **Order** means a number of bands: order 2 is L1 (4 coefficients), order
//!   3 is L2 (9), at most [`MAX_ORDER`] = 8.
//! - **Radiance, not irradiance**: every stored or exported SH holds radiance
//!   `L(ω)`. Irradiance `E(n) = ∫ L(ω) max(0, n·ω) dω` is **not divided by
//!   π**; it comes from the clamped-cosine convolution, bands scaled by
//!   `π, 2π/3, π/4` ([`convolve`]). Diffuse reflected radiance is `ρ·E/π`.
//! - **Directions** point *away* from the probe towards where light comes from.
//! - **Equirectangular maps** (three.js convention, handled in the baking
//!   library): row 0 at the top; for a pixel centre `(u, v)` in `[0,1]²`,
//!   `φ = 2π(u − ½)`, latitude `= π(½ − v)`,
//!   `d = (cos lat·cos φ, sin lat, cos lat·sin φ)`.

#![warn(missing_docs)]
// Without the default `std` feature the crate is `no_std` + `alloc`.
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

#[cfg(not(any(feature = "std", feature = "libm")))]
compile_error!("probekit-sh needs the `std` feature or, without std, the `libm` feature");

pub mod ambient_cube;
pub mod basis;
pub mod codec;
pub mod coeffs;
pub mod convolve;
pub mod geomerics;
pub mod hl2;
pub mod lights;
pub mod math;
mod numeric;
pub mod project;
pub mod rotate;
pub mod window;
pub mod zh3;
pub mod zonal;

pub use basis::{eval_basis, eval_l1, eval_l2, index, num_coeffs, MAX_COEFFS, MAX_ORDER};
pub use coeffs::{ShRgb, LUMINANCE};
pub use convolve::{clamped_cosine_band, irradiance, irradiance_l1, irradiance_l2};
pub use project::{fibonacci_point, fibonacci_sphere, project_fn};
pub use rotate::{rotate_l1, rotate_l2, ShRotation};
pub use window::{
    choose_window_for, min_over_sphere, solve_min_ringing_strength, Window, WindowKind,
    MIN_RINGING_STRENGTH,
};
