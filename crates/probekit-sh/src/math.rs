//! Float functions that `core` lacks (roots, rounding, trigonometry, powers)
//! for `f32` and `f64`, so that the crate, and `probekit-runtime` with it,
//! builds without std.
//!
//! With the `std` feature each method is std's own; without it, it is the
//! `libm` crate's (a port of musl's libm), which can differ from std's in the
//! last bit. [`FloatMath::powi`] without std is binary exponentiation, the
//! algorithm of compiler-rt's `__powisf2`/`__powidf2` that std's `powi` calls.
//!
//! Inside the crate, a module that calls these methods imports the trait only
//! without std (`#[cfg(not(feature = "std"))] use crate::math::FloatMath;`):
//! with std the inherent methods of the same names are found first, so the
//! code and its results are exactly std's.

/// The float functions of std that `core` lacks, as methods of `f32` and
/// `f64`: std's methods with the `std` feature, `libm`'s without.
pub trait FloatMath: Copy {
    /// Square root (`NaN` for negative input).
    fn sqrt(self) -> Self;
    /// Cube root.
    fn cbrt(self) -> Self;
    /// Largest integer not above `self`.
    fn floor(self) -> Self;
    /// Nearest integer, halves away from zero.
    fn round(self) -> Self;
    /// Sine of an angle in radians.
    fn sin(self) -> Self;
    /// Cosine of an angle in radians.
    fn cos(self) -> Self;
    /// `(sin, cos)` of an angle in radians.
    fn sin_cos(self) -> (Self, Self);
    /// Arc cosine in radians, in `[0, π]` (`NaN` outside `[-1, 1]`).
    fn acos(self) -> Self;
    /// Four-quadrant arc tangent of `self / x` (`self` the y coordinate), in
    /// radians, in `[-π, π]`.
    fn atan2(self, x: Self) -> Self;
    /// `self` raised to the float power `n`.
    fn powf(self, n: Self) -> Self;
    /// `self` raised to the integer power `n`.
    fn powi(self, n: i32) -> Self;
}

/// The trait for one float type: each method is std's inherent method of the
/// same name, or the function of that name in module `$nostd`.
macro_rules! impl_float_math {
    ($t:ty, $nostd:ident) => {
        impl FloatMath for $t {
            impl_float_math!(@one $t, $nostd, sqrt());
            impl_float_math!(@one $t, $nostd, cbrt());
            impl_float_math!(@one $t, $nostd, floor());
            impl_float_math!(@one $t, $nostd, round());
            impl_float_math!(@one $t, $nostd, sin());
            impl_float_math!(@one $t, $nostd, cos());
            impl_float_math!(@one $t, $nostd, acos());
            impl_float_math!(@one $t, $nostd, atan2(x: $t));
            impl_float_math!(@one $t, $nostd, powf(n: $t));
            impl_float_math!(@one $t, $nostd, powi(n: i32));

            #[inline]
            fn sin_cos(self) -> ($t, $t) {
                (FloatMath::sin(self), FloatMath::cos(self))
            }
        }
    };
    (@one $t:ty, $nostd:ident, $name:ident($($arg:ident: $argty:ty),*)) => {
        #[inline]
        fn $name(self $(, $arg: $argty)*) -> $t {
            #[cfg(feature = "std")]
            return <$t>::$name(self $(, $arg)*);
            #[cfg(not(feature = "std"))]
            return $nostd::$name(self $(, $arg)*);
        }
    };
}

impl_float_math!(f32, nostd_f32);
impl_float_math!(f64, nostd_f64);

/// `x` to the power `n` by binary exponentiation, as compiler-rt's
/// `__powisf2`/`__powidf2` (what std's `powi` calls for a power that is not a
/// compile-time constant).
#[cfg(any(not(feature = "std"), test))]
macro_rules! powi_by_squaring {
    ($x:expr, $n:expr) => {{
        let (mut a, n): (_, i32) = ($x, $n);
        let mut b = n.unsigned_abs();
        let mut r = 1.0;
        loop {
            if b & 1 != 0 {
                r *= a;
            }
            b >>= 1;
            if b == 0 {
                break;
            }
            a *= a;
        }
        if n < 0 {
            1.0 / r
        } else {
            r
        }
    }};
}

/// The `f32` functions without std (compiled in tests too, to check them
/// against std's).
#[cfg(any(not(feature = "std"), test))]
mod nostd_f32 {
    pub(super) fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }
    pub(super) fn cbrt(x: f32) -> f32 {
        libm::cbrtf(x)
    }
    pub(super) fn floor(x: f32) -> f32 {
        libm::floorf(x)
    }
    pub(super) fn round(x: f32) -> f32 {
        libm::roundf(x)
    }
    pub(super) fn sin(x: f32) -> f32 {
        libm::sinf(x)
    }
    pub(super) fn cos(x: f32) -> f32 {
        libm::cosf(x)
    }
    pub(super) fn acos(x: f32) -> f32 {
        libm::acosf(x)
    }
    pub(super) fn atan2(y: f32, x: f32) -> f32 {
        libm::atan2f(y, x)
    }
    pub(super) fn powf(x: f32, n: f32) -> f32 {
        libm::powf(x, n)
    }
    pub(super) fn powi(x: f32, n: i32) -> f32 {
        powi_by_squaring!(x, n)
    }
}

/// The `f64` functions without std (compiled in tests too, to check them
/// against std's).
#[cfg(any(not(feature = "std"), test))]
mod nostd_f64 {
    pub(super) fn sqrt(x: f64) -> f64 {
        libm::sqrt(x)
    }
    pub(super) fn cbrt(x: f64) -> f64 {
        libm::cbrt(x)
    }
    pub(super) fn floor(x: f64) -> f64 {
        libm::floor(x)
    }
    pub(super) fn round(x: f64) -> f64 {
        libm::round(x)
    }
    pub(super) fn sin(x: f64) -> f64 {
        libm::sin(x)
    }
    pub(super) fn cos(x: f64) -> f64 {
        libm::cos(x)
    }
    pub(super) fn acos(x: f64) -> f64 {
        libm::acos(x)
    }
    pub(super) fn atan2(y: f64, x: f64) -> f64 {
        libm::atan2(y, x)
    }
    pub(super) fn powf(x: f64, n: f64) -> f64 {
        libm::pow(x, n)
    }
    pub(super) fn powi(x: f64, n: i32) -> f64 {
        powi_by_squaring!(x, n)
    }
}

#[cfg(test)]
mod tests {
    //! The functions used without std against std's own, in every test run.

    use super::{nostd_f32, nostd_f64};

    /// Arguments across signs and magnitudes, with halves for the rounding.
    fn args() -> impl Iterator<Item = f64> {
        let special = [
            0.0, -0.0, 0.5, -0.5, 1.5, 2.5, -2.5, 1e-300, 1e300, 1.0, -1.0,
        ];
        (-200..=200).map(|i| i as f64 * 0.173 + 0.01).chain(special)
    }

    /// `got` is within `ulps` units in the last place of `want` (relative to
    /// `max(|want|, 1)`, so results near zero get an absolute bound), or both
    /// are NaN.
    fn close_f64(got: f64, want: f64, ulps: f64) -> bool {
        (got.is_nan() && want.is_nan())
            || got == want
            || (got - want).abs() <= ulps * f64::EPSILON * want.abs().max(1.0)
    }

    fn close_f32(got: f32, want: f32, ulps: f32) -> bool {
        (got.is_nan() && want.is_nan())
            || got == want
            || (got - want).abs() <= ulps * f32::EPSILON * want.abs().max(1.0)
    }

    #[test]
    fn one_argument_functions_match_std() {
        type F64 = fn(f64) -> f64;
        type F32 = fn(f32) -> f32;
        let cases: [(&str, F64, F64, F32, F32); 7] = [
            (
                "sqrt",
                nostd_f64::sqrt,
                f64::sqrt,
                nostd_f32::sqrt,
                f32::sqrt,
            ),
            (
                "cbrt",
                nostd_f64::cbrt,
                f64::cbrt,
                nostd_f32::cbrt,
                f32::cbrt,
            ),
            (
                "floor",
                nostd_f64::floor,
                f64::floor,
                nostd_f32::floor,
                f32::floor,
            ),
            (
                "round",
                nostd_f64::round,
                f64::round,
                nostd_f32::round,
                f32::round,
            ),
            ("sin", nostd_f64::sin, f64::sin, nostd_f32::sin, f32::sin),
            ("cos", nostd_f64::cos, f64::cos, nostd_f32::cos, f32::cos),
            (
                "acos",
                nostd_f64::acos,
                f64::acos,
                nostd_f32::acos,
                f32::acos,
            ),
        ];
        for (name, ours64, std64, ours32, std32) in cases {
            // Rounding is exact; the rest within a couple of ulps.
            let ulps = if name == "floor" || name == "round" {
                0.0
            } else {
                2.0
            };
            for x in args() {
                let (got, want) = (ours64(x), std64(x));
                assert!(close_f64(got, want, ulps), "{name}({x}): {got} vs {want}");
                let x = x as f32;
                let (got, want) = (ours32(x), std32(x));
                assert!(
                    close_f32(got, want, ulps as f32),
                    "{name}({x}): {got} vs {want}"
                );
            }
        }
        // The domains: NaN outside, as std.
        assert!(nostd_f64::sqrt(-1.0).is_nan() && nostd_f64::acos(1.5).is_nan());
        assert!(nostd_f32::sqrt(-1.0).is_nan() && nostd_f32::acos(1.5).is_nan());
    }

    #[test]
    fn atan2_takes_y_then_x_as_std() {
        for y in args().step_by(7) {
            for x in args().step_by(11) {
                let (got, want) = (nostd_f64::atan2(y, x), y.atan2(x));
                assert!(
                    close_f64(got, want, 2.0),
                    "atan2({y}, {x}): {got} vs {want}"
                );
                let (y, x) = (y as f32, x as f32);
                let (got, want) = (nostd_f32::atan2(y, x), y.atan2(x));
                assert!(
                    close_f32(got, want, 2.0),
                    "atan2({y}, {x}): {got} vs {want}"
                );
            }
        }
        // The quadrant: y = 1, x = −1 is 3π/4.
        let q = nostd_f64::atan2(1.0, -1.0);
        assert!((q - 0.75 * core::f64::consts::PI).abs() < 1e-15);
    }

    #[test]
    fn powers_match_std() {
        for i in 1..60 {
            let x = i as f64 * 0.17;
            for k in -12..=12 {
                let n = k as f64 * 0.25;
                let (got, want) = (nostd_f64::powf(x, n), x.powf(n));
                assert!(close_f64(got, want, 4.0), "{x}^{n}: {got} vs {want}");
                let (got, want) = (
                    nostd_f32::powf(x as f32, n as f32),
                    (x as f32).powf(n as f32),
                );
                assert!(close_f32(got, want, 4.0), "{x}^{n}: {got} vs {want}");
            }
        }
        // Integer powers of either sign; binary exponentiation rounds once per
        // product, so a few ulps, growing with the power.
        for x in [-3.7, -1.0, -0.31, 0.0, 0.5, 1.0, 1.9, 10.0] {
            for n in -9..=9 {
                let (got, want) = (nostd_f64::powi(x, n), x.powi(n));
                assert!(close_f64(got, want, 8.0), "{x}^{n}: {got} vs {want}");
                let (got, want) = (nostd_f32::powi(x as f32, n), (x as f32).powi(n));
                assert!(close_f32(got, want, 8.0), "{x}^{n}: {got} vs {want}");
            }
        }
        assert_eq!(nostd_f64::powi(2.0, -3), 0.125);
        assert_eq!(nostd_f64::powi(-2.0, 3), -8.0);
        assert_eq!(nostd_f32::powi(7.0, 0), 1.0);
    }
}
