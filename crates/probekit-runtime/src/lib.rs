//! # probekit-runtime — load and query baked probes
//!
//! What an engine links: load a `.probes` file and answer "irradiance at this
//! point, for this normal" without allocating per query. Conventions are those
//! of [`probekit_sh`].
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

pub use cloud::{ProbeCloud, ProbeCloudError};
pub use format::{FormatError, ProbeFile, ProbeFileKind};
pub use volume::{Interp, Volume, VolumeError};
