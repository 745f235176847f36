//! # probekit-runtime — load and query baked probes
//!
//! What an engine links: load a `.probes` file and answer "irradiance at this
//! point, for this normal" without allocating per query. Conventions are those
//! of [`probekit_sh`].
//!
//! ## Querying any file the same way
//! [`Probes`] holds a probe cloud, an irradiance volume or a file of rigs
//! only. Choose what is chosen once per file in [`LoadOptions`] (a volume's
//! interpolation, how L1 coefficients are evaluated, blend overrides for
//! diagnostics), give every moving object an [`ObjectState`], and ask for
//! irradiance (not divided by π) or radiance SH (bands 0–2) at world
//! positions; bad input is a [`QueryError`], never a panic.
//!
//! ```no_run
//! use glam::Vec3;
//! use probekit_runtime::{LoadOptions, ObjectState, Probes};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let probes = Probes::load("level.probes", LoadOptions::default())?;
//! let mut state = ObjectState::new(); // one per moving object
//! let e = probes.irradiance(&mut state, Vec3::new(1.0, 1.5, -2.0), Vec3::Y)?;
//! let sh = probes.sh_at(&mut state, Vec3::new(1.0, 1.5, -2.0))?; // 9 RGB coefficients
//! # let _ = (e, sh);
//! # Ok(())
//! # }
//! ```
//!
//! Batches ([`Probes::irradiance_many`], [`Probes::sh_at_many`]) share one
//! state, so an object's vertices walk little. A file baked with light
//! groups is relit in place with [`Probes::relight`]. Rigs: [`Probes::rig`],
//! [`Probes::update_rig`], [`Probes::rig_irradiance`]. The modules below
//! ([`cloud`], [`volume`], [`format`](mod@format), [`rig`]) are the parts `Probes` is
//! built from, for tools and diagnostics.
//!
//! ## Features
//! * `std` (default): [`ProbeFile::load`] from a path, `FormatError::Io`,
//!   std's float math and hash maps.
//! * Without `std` the crate is `#![no_std]` + `alloc`; enable `libm` for the
//!   float functions `core` lacks (`cargo build -p probekit-runtime
//!   --no-default-features --features libm`). Loading from bytes and every
//!   query work the same. Without `std` no crate in the dependency graph
//!   uses std (`probekit-sh`, `glam`, `half` and `thiserror` are built
//!   without theirs), so the crate links on targets that have no std.

#![warn(missing_docs)]
// Without the default `std` feature the crate is `no_std` + `alloc` (path
// loading and `FormatError::Io` disappear; float math comes from `libm`).
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

#[cfg(not(any(feature = "std", feature = "libm")))]
compile_error!("probekit-runtime needs the `std` feature or, without std, the `libm` feature");

pub use probekit_sh as sh;

/// Methods that change a loaded cloud's blend or data (its setters), which
/// the crate itself and the baker call and an engine does not: `pub` with
/// the `write` feature, crate-private without it. An engine chooses a
/// blend once, at load ([`LoadOptions::blend`]), and relights through
/// [`Probes::relight`], so a shared handle never changes under a query.
macro_rules! baker_only {
    ($($(#[$attr:meta])* fn $name:ident $args:tt $(-> $ret:ty)? $body:block)*) => {$(
        $(#[$attr])*
        #[cfg(feature = "write")]
        pub fn $name $args $(-> $ret)? $body

        $(#[$attr])*
        #[cfg(not(feature = "write"))]
        #[allow(dead_code)]
        pub(crate) fn $name $args $(-> $ret)? $body
    )*};
}

pub mod cloud;
pub mod format;
pub mod rig;
pub mod volume;

/// What `std`'s prelude would give, from `alloc` (works with and without std).
mod prelude {
    pub(crate) use alloc::boxed::Box;
    pub(crate) use alloc::string::{String, ToString};
    pub(crate) use alloc::vec;
    pub(crate) use alloc::vec::Vec;
}

/// Float functions that `core` lacks: probekit-sh's [`FloatMath`], which is
/// std's methods with `std` and `libm`'s without.
///
/// [`FloatMath`]: probekit_sh::math::FloatMath
mod math {
    use probekit_sh::math::FloatMath;

    /// `x.floor()`.
    #[inline]
    pub(crate) fn floor(x: f32) -> f32 {
        FloatMath::floor(x)
    }

    /// `x.sqrt()`.
    #[inline]
    pub(crate) fn sqrt(x: f32) -> f32 {
        FloatMath::sqrt(x)
    }

    /// `x.cbrt()`.
    #[inline]
    pub(crate) fn cbrt(x: f32) -> f32 {
        FloatMath::cbrt(x)
    }

    /// `x.powf(y)`.
    #[inline]
    pub(crate) fn powf(x: f32, y: f32) -> f32 {
        FloatMath::powf(x, y)
    }

    /// `x.powi(n)`.
    #[inline]
    pub(crate) fn powi(x: f32, n: i32) -> f32 {
        FloatMath::powi(x, n)
    }

    /// `log2(x)` for finite `x > 0`: the exponent of `x` plus `ln(m)/ln 2`
    /// of its mantissa `m ∈ [√½, √2)`, by the series
    /// `ln m = 2·atanh(s) = 2(s + s³/3 + … + s⁹/9)`, `s = (m − 1)/(m + 1)`,
    /// `|s| ≤ 0.172` (truncation below 10⁻⁹; the error is `f32` rounding).
    #[inline]
    pub(crate) fn log2(x: f32) -> f32 {
        let (x, bias) = if x < f32::MIN_POSITIVE {
            (x * (1u64 << 24) as f32, 24)
        } else {
            (x, 0)
        };
        let bits = x.to_bits();
        let mut e = ((bits >> 23) & 0xff) as i32 - 127 - bias;
        let mut m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
        if m > core::f32::consts::SQRT_2 {
            m *= 0.5;
            e += 1;
        }
        let s = (m - 1.0) / (m + 1.0);
        let s2 = s * s;
        let series =
            s * (2.0 + s2 * (2.0 / 3.0 + s2 * (0.4 + s2 * (2.0 / 7.0 + s2 * (2.0 / 9.0)))));
        e as f32 + series * core::f32::consts::LOG2_E
    }

    /// `2^t`: `2^n` (exponent bits) times `e^{f·ln 2}` for `f = t − n ∈
    /// [−½, ½]` by its Taylor series to degree 6 (truncation below
    /// 2·10⁻⁷); 0 below −126, +∞ above 128.
    #[inline]
    pub(crate) fn exp2(t: f32) -> f32 {
        if t.is_nan() {
            return t;
        }
        if t < -126.0 {
            return 0.0;
        }
        if t >= 128.0 {
            return f32::INFINITY;
        }
        let n = floor(t + 0.5);
        let y = (t - n) * core::f32::consts::LN_2;
        let p = 1.0
            + y * (1.0
                + y * (0.5 + y * (1.0 / 6.0 + y * (1.0 / 24.0 + y * (1.0 / 120.0 + y / 720.0)))));
        // n ∈ [−126, 128]: 2^n as the product of two normal powers of two.
        let n = n as i32;
        let (a, b) = (n / 2, n - n / 2);
        let pow2 = |k: i32| f32::from_bits(((k + 127) as u32) << 23);
        p * pow2(a) * pow2(b)
    }

    /// `x^y` for finite `x > 0` as `2^{y·log2 x}` ([`log2`], [`exp2`]):
    /// within a few 10⁻⁷ relative of `powf` while `|y·log2 x| < 20`, which
    /// is the range the blend uses it in, and without the cost of `powf`.
    #[inline]
    pub(crate) fn pow(x: f32, y: f32) -> f32 {
        exp2(y * log2(x))
    }

    #[cfg(test)]
    mod tests {
        /// The approximations against std's functions over many decades.
        #[test]
        fn log2_exp2_and_pow_match_std() {
            let mut x = 1e-40f32;
            while x < 1e38 {
                let want = (x as f64).log2();
                assert!(
                    (super::log2(x) as f64 - want).abs() <= 2e-7 * want.abs().max(1.0),
                    "log2 {x}"
                );
                x *= 1.37;
            }
            let mut t = -125.9f32;
            while t < 127.9 {
                let want = 2f64.powf(t as f64);
                let got = super::exp2(t) as f64;
                assert!((got - want).abs() <= 4e-7 * want, "exp2 {t}: {got} {want}");
                t += 0.0731;
            }
            for &y in &[-4.0f32, -1.7, -0.7, -0.3, 0.3, 1.3, 2.5] {
                let mut x = 1e-3f32;
                while x < 1e3 {
                    let want = (x as f64).powf(y as f64);
                    let got = super::pow(x, y) as f64;
                    assert!((got - want).abs() <= 3e-6 * want, "{x}^{y}: {got} {want}");
                    x *= 1.11;
                }
            }
        }
    }
}

/// Irradiance from radiance SH with the fixed-order fast paths.
mod eval {
    use glam::Vec3;
    use probekit_sh::convolve;

    /// Irradiance `E(n)` (not divided by π) of radiance SH `c` of any order
    /// for unit normal `n`: [`convolve::irradiance_l1`] /
    /// [`convolve::irradiance_l2`] for 4 and 9 coefficients, `π·Y00·c₀` for
    /// 1, [`convolve::irradiance`] otherwise.
    #[inline]
    pub(crate) fn irradiance(c: &[Vec3], n: Vec3) -> Vec3 {
        match c.len() {
            1 => c[0] * (core::f32::consts::PI * probekit_sh::basis::Y00),
            4 => convolve::irradiance_l1(c.try_into().expect("4 coefficients"), n),
            9 => convolve::irradiance_l2(c.try_into().expect("9 coefficients"), n),
            _ => convolve::irradiance(c, n),
        }
    }
}

/// Hash maps with std; ordered maps (same lookups, no hasher) without.
mod collections {
    #[cfg(feature = "std")]
    pub(crate) type Map<K, V> = std::collections::HashMap<K, V>;
    #[cfg(not(feature = "std"))]
    pub(crate) type Map<K, V> = alloc::collections::BTreeMap<K, V>;
    #[cfg(feature = "std")]
    pub(crate) type Set<T> = std::collections::HashSet<T>;
    #[cfg(not(feature = "std"))]
    pub(crate) type Set<T> = alloc::collections::BTreeSet<T>;

    /// An empty map with room for `n` entries where the map type supports it.
    pub(crate) fn map_with_capacity<K, V>(n: usize) -> Map<K, V> {
        #[cfg(feature = "std")]
        return Map::with_capacity(n);
        #[cfg(not(feature = "std"))]
        {
            let _ = n;
            Map::new()
        }
    }
}

mod probes;

pub use cloud::{ProbeCloud, ProbeCloudError};
pub use format::{FormatError, L1Mode, ProbeFile, ProbeFileKind};
pub use probes::{
    BlendOverrides, Cell, LoadError, LoadOptions, ObjectState, Probes, Query, QueryError, Sh,
};
pub use volume::{Interp, Volume, VolumeError};
