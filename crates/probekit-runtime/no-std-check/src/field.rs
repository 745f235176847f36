//! The probe field the check queries, shared by `build.rs` (which writes it
//! as a `.probes` file) and `main.rs` (which knows the answer in closed form).
//!
//! A 2×2×2 grid of order-2 (L1) probes over `MIN..MAX`. At position `p` the
//! radiance towards direction `ω` is `a(p) + b·ω_y` per RGB channel, with
//! `a` linear in `p`, so the grid's trilinear interpolation reproduces it
//! exactly, and the irradiance
//! `E(n) = ∫ L(ω) max(0, n·ω) dω = π·a(p) + (2π/3)·b·n_y`
//! (the clamped-cosine integrals of a constant and of a linear function).

// build.rs uses the field, main.rs the irradiance.
#![allow(dead_code)]

/// Minimum corner of the grid's box (metres).
pub const MIN: [f32; 3] = [-1.0, 0.0, 2.0];
/// Maximum corner of the grid's box (metres).
pub const MAX: [f32; 3] = [1.0, 3.0, 4.0];
/// Probes per axis.
pub const RESOLUTION: [u32; 3] = [2, 2, 2];
/// `b`: radiance per unit `ω_y` (towards +Y brighter), RGB.
pub const UP_GAIN: [f32; 3] = [0.1, 0.05, 0.2];

/// `a(p)`: the uniform part of the radiance at `p`, RGB (linear in `p`).
pub fn uniform(p: [f32; 3]) -> [f32; 3] {
    [
        0.5 + 0.25 * p[0],
        0.2 + 0.1 * p[1],
        1.0 - 0.125 * p[2] + 0.05 * p[0],
    ]
}

/// `E(n) = π·a(p) + (2π/3)·b·n_y` at `p` for unit normal `n`, RGB.
pub fn irradiance(p: [f32; 3], n: [f32; 3]) -> [f32; 3] {
    use core::f32::consts::PI;
    let a = uniform(p);
    [0, 1, 2].map(|c| PI * a[c] + 2.0 * PI / 3.0 * UP_GAIN[c] * n[1])
}
