//! Quantized storage of probes: the ratio-based encoding of Roughton et al.,
//! *ZH3: Quadratic Zonal Harmonics* (Roughton et al., I3D 2024), RGB9E5 shared
//! exponents (`GL_EXT_texture_shared_exponent`), and plain f16 / f32 layouts.
//!
//! ## Why ratios are bounded
//!
//! For a non-negative radiance `f`, `c_lm / c_00 = E_p[Y_lm] / Y_00` where
//! `p = f / ∫f` is a probability density on the sphere. So
//! `min Y_lm / Y_00 ≤ c_lm / c_00 ≤ max Y_lm / Y_00`, and a delta at the
//! arg-max attains the bound (tight per coefficient). In our basis:
//!
//! | coefficients | ratio range `[lo, hi]` |
//! |---|---|
//! | `c1,−1`, `c1,0`, `c1,1` | `[−√3, √3]` |
//! | `c2,−2`, `c2,−1`, `c2,1`, `c2,2` | `[−√15/2, √15/2]` (`max xy = ½` on the sphere) |
//! | `c2,0` and the ZH3 zonal coefficient | `[−√5/2, √5]` (`3z² − 1 ∈ [−1, 2]`) |
//!
//! The L1 vector obeys the joint bound `|c1| ≤ √3·c00` (same argument with
//! `Y1·(v·ω)` maximised at `ω = v/|v|`); per coefficient it gives nothing
//! beyond `√3`, so L1 uses `√3`. The band-2 zonal range is asymmetric, and we
//! use it: it is mapped affinely onto `[−1, 1]` (25 % finer steps than the
//! symmetric `±√5`). (Wiederien & Sloan 2022 derive still tighter, joint
//! bounds; not implemented here.)
//!
//! Each non-DC coefficient is stored as `snorm8(t)`, `q = round(127·clamp(t, −1, 1))`,
//! `t = (c_lm/c00 − mid)/half` with `mid = (lo+hi)/2`, `half = (hi−lo)/2`
//! (for symmetric ranges simply `t = c_lm / (c00·B_lm)`, `B_lm = hi`). The
//! ratio is taken against the **decoded** DC of the same channel, so DC
//! quantisation does not compound; a channel whose decoded DC is 0 stores 0.
//!
//! ## Byte layouts (little-endian)
//!
//! | format | bytes | layout |
//! |---|---|---|
//! | L1 | 13 | `[0..4]` DC RGB9E5 · `[4..13]` snorm8 for coefficient `i = 1..3`, channel `ch = R,G,B` at byte `4 + 3(i−1) + ch` |
//! | ZH3 | 16 | `[0..13]` as L1 · `[13..16]` zonal coefficient R,G,B (affine `[−√5/2, √5]` range); the axis is not stored: it is the luminance axis of the **decoded** L1 |
//! | L2 | 28 | `[0..4]` DC RGB9E5 · `[4..28]` snorm8 for coefficient `i = 1..8`, channel `ch` at byte `4 + 3(i−1) + ch` (pad to 32 for cache-line alignment if wanted) |
//! | ambient cube | 24 | six RGB9E5 words, faces +X, −X, +Y, −Y, +Z, −Z |
//! | f16 | 6 per coefficient | R, G, B as IEEE binary16 |
//! | f32 | 12 per coefficient | R, G, B as IEEE binary32 |
//!
//! RGB9E5 word: bits 0–8 red mantissa, 9–17 green, 18–26 blue, 27–31 shared
//! exponent (bias 15), value `m · 2^(e − 24)`.

// Index loops over colour channels and SH coefficients read like the formulas.
#![allow(clippy::needless_range_loop)]

use crate::ambient_cube::AmbientCube;
#[cfg(not(feature = "std"))]
use crate::math::FloatMath;
use crate::zh3::{shared_axis, zonal_projection, Zh3};
use alloc::vec::Vec;
use glam::Vec3;

/// Bytes of a quantized L1 probe: 4 (DC RGB9E5) + 9 (snorm8) (Roughton et al., ZH3).
pub const L1_BYTES: usize = 13;
/// Bytes of a quantized shared-axis ZH3 probe: L1 + 3 zonal bytes (Roughton et al., ZH3).
pub const ZH3_BYTES: usize = 16;
/// Bytes of a quantized L2 probe: 4 (DC RGB9E5) + 24 (snorm8) (Roughton et al., ZH3).
pub const L2_BYTES: usize = 28;
/// Bytes of an ambient cube: six RGB9E5 words.
pub const AMBIENT_CUBE_BYTES: usize = 24;

/// The largest RGB9E5 value, `(2⁹ − 1)/2⁹ · 2^(31 − 15) = 65408`.
pub const RGB9E5_MAX: f32 = 65408.0;

/// Error of the variable-length decoders.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CodecError {
    /// The byte count is not a whole number of coefficients.
    Length {
        /// The byte count given.
        len: usize,
        /// Bytes per coefficient of the layout.
        stride: usize,
    },
}

impl core::fmt::Display for CodecError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            CodecError::Length { len, stride } => write!(
                f,
                "{len} bytes is not a whole number of {stride}-byte coefficients"
            ),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for CodecError {}

// `core::error::Error` is the same trait (Rust 1.81+, as thiserror needs
// without std).
#[cfg(not(feature = "std"))]
impl core::error::Error for CodecError {}

/// Floor of log2 of a positive finite f32 (exact, from the bits).
fn floor_log2(x: f32) -> i32 {
    let bits = x.to_bits();
    let e = ((bits >> 23) & 0xff) as i32;
    if e == 0 {
        // subnormal
        let m = bits & 0x7f_ffff;
        -127 - m.leading_zeros() as i32 + 9
    } else {
        e - 127
    }
}

/// Encodes non-negative linear RGB as RGB9E5 (algorithm of the
/// `GL_EXT_texture_shared_exponent` specification: 9-bit mantissas, 5-bit
/// shared exponent, bias 15, round to nearest). Negative and NaN components
/// become 0, values above [`RGB9E5_MAX`] clamp to it.
pub fn encode_rgb9e5(v: Vec3) -> u32 {
    const N: i32 = 9;
    const B: i32 = 15;
    let clamp = |x: f32| {
        if x > 0.0 {
            x.min(RGB9E5_MAX)
        } else {
            0.0
        }
    };
    let (r, g, b) = (clamp(v.x), clamp(v.y), clamp(v.z));
    let max_c = r.max(g).max(b);
    let exp_p = if max_c > 0.0 {
        (-B - 1).max(floor_log2(max_c)) + 1 + B
    } else {
        0
    };
    let scale = |e: i32| (2.0f64).powi(e - B - N);
    let max_s = (max_c as f64 / scale(exp_p) + 0.5).floor() as i32;
    let e = if max_s == 1 << N { exp_p + 1 } else { exp_p };
    let s = scale(e);
    let q = |x: f32| ((x as f64 / s + 0.5).floor() as u32).min(511);
    q(r) | (q(g) << 9) | (q(b) << 18) | ((e as u32) << 27)
}

/// Decodes an RGB9E5 word: `mantissa · 2^(exponent − 15 − 9)` per channel.
pub fn decode_rgb9e5(x: u32) -> Vec3 {
    let e = (x >> 27) as i32;
    let s = (2.0f64).powi(e - 24);
    let m = |k: u32| (((x >> k) & 0x1ff) as f64 * s) as f32;
    Vec3::new(m(0), m(9), m(18))
}

/// Ratio range `[lo, hi]` of `c_i / c_00` for non-negative functions, for
/// coefficient index `i` in `1..9` (module docs); the band-2 zonal range also
/// bounds the ZH3 zonal coefficient.
pub fn ratio_range(i: usize) -> (f32, f32) {
    let s3 = 3f32.sqrt();
    let s15h = 15f32.sqrt() / 2.0;
    let s5 = 5f32.sqrt();
    match i {
        1..=3 => (-s3, s3),
        6 => (-s5 / 2.0, s5),
        _ => (-s15h, s15h),
    }
}

/// The ratio range of the ZH3 zonal coefficient (`Y2,0` about any axis).
fn zonal_range() -> (f32, f32) {
    ratio_range(6)
}

fn snorm8(t: f32) -> u8 {
    let t = if t.is_nan() { 0.0 } else { t.clamp(-1.0, 1.0) };
    ((t * 127.0).round() as i8) as u8
}

fn unsnorm8(b: u8) -> f32 {
    ((b as i8) as f32 / 127.0).max(-1.0)
}

fn encode_ratio(c: f32, c0: f32, range: (f32, f32)) -> u8 {
    if c0.is_nan() || c0 <= 0.0 {
        return snorm8(0.0);
    }
    let mid = 0.5 * (range.0 + range.1);
    let half = 0.5 * (range.1 - range.0);
    snorm8((c / c0 - mid) / half)
}

fn decode_ratio(b: u8, c0: f32, range: (f32, f32)) -> f32 {
    if c0.is_nan() || c0 <= 0.0 {
        return 0.0;
    }
    let mid = 0.5 * (range.0 + range.1);
    let half = 0.5 * (range.1 - range.0);
    c0 * (mid + half * unsnorm8(b))
}

/// Encodes DC + coefficients `1..N` into `out` (`out.len() = 4 + 3(N−1)`).
fn encode_ratios(c: &[Vec3], out: &mut [u8]) -> Vec3 {
    let dc = encode_rgb9e5(c[0]);
    out[..4].copy_from_slice(&dc.to_le_bytes());
    let c0 = decode_rgb9e5(dc);
    for i in 1..c.len() {
        for ch in 0..3 {
            out[4 + 3 * (i - 1) + ch] = encode_ratio(c[i][ch], c0[ch], ratio_range(i));
        }
    }
    c0
}

fn decode_ratios(b: &[u8], out: &mut [Vec3]) {
    let c0 = decode_rgb9e5(u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    out[0] = c0;
    for i in 1..out.len() {
        for ch in 0..3 {
            out[i][ch] = decode_ratio(b[4 + 3 * (i - 1) + ch], c0[ch], ratio_range(i));
        }
    }
}

/// Encodes L1 radiance SH in 13 bytes (layout table in the module docs).
pub fn encode_l1(c: &[Vec3; 4]) -> [u8; L1_BYTES] {
    let mut out = [0u8; L1_BYTES];
    encode_ratios(c, &mut out);
    out
}

/// Decodes 13 bytes from [`encode_l1`].
pub fn decode_l1(b: &[u8; L1_BYTES]) -> [Vec3; 4] {
    let mut out = [Vec3::ZERO; 4];
    decode_ratios(b, &mut out);
    out
}

/// Encodes L2 radiance SH in 28 bytes (layout table in the module docs).
pub fn encode_l2(c: &[Vec3; 9]) -> [u8; L2_BYTES] {
    let mut out = [0u8; L2_BYTES];
    encode_ratios(c, &mut out);
    out
}

/// Decodes 28 bytes from [`encode_l2`].
pub fn decode_l2(b: &[u8; L2_BYTES]) -> [Vec3; 9] {
    let mut out = [Vec3::ZERO; 9];
    decode_ratios(b, &mut out);
    out
}

/// Encodes ZH3 in 16 bytes as **shared-axis** ZH3 (Roughton et al., I3D 2024): the L1 part as
/// [`encode_l1`], then per channel the zonal coefficient about the luminance
/// axis of the *decoded* L1 ([`shared_axis`]), the axis the decoder will
/// derive. The zonal coefficient is re-projected from `c.to_l2()` onto that
/// axis, so a ZH3 fitted with another axis (per-channel, solved) is stored as
/// its best shared-luminance-axis approximation.
pub fn encode_zh3(c: &Zh3) -> [u8; ZH3_BYTES] {
    let mut out = [0u8; ZH3_BYTES];
    let l1 = encode_l1(&c.l1);
    out[..L1_BYTES].copy_from_slice(&l1);
    let dl1 = decode_l1(&l1);
    let axis = shared_axis(&dl1);
    let l2 = c.to_l2();
    for ch in 0..3 {
        let band2 = [l2[4][ch], l2[5][ch], l2[6][ch], l2[7][ch], l2[8][ch]];
        let z = zonal_projection(&band2, axis);
        out[L1_BYTES + ch] = encode_ratio(z, dl1[0][ch], zonal_range());
    }
    out
}

/// Decodes 16 bytes from [`encode_zh3`]: shared axis from the decoded L1.
pub fn decode_zh3(b: &[u8; ZH3_BYTES]) -> Zh3 {
    let mut l1b = [0u8; L1_BYTES];
    l1b.copy_from_slice(&b[..L1_BYTES]);
    let l1 = decode_l1(&l1b);
    let axis = shared_axis(&l1);
    let mut zonal = Vec3::ZERO;
    for ch in 0..3 {
        zonal[ch] = decode_ratio(b[L1_BYTES + ch], l1[0][ch], zonal_range());
    }
    Zh3 {
        l1,
        zonal,
        axes: [axis; 3],
    }
}

/// Encodes an ambient cube as six RGB9E5 words (24 bytes, faces in order).
pub fn encode_ambient_cube(c: &AmbientCube) -> [u8; AMBIENT_CUBE_BYTES] {
    let mut out = [0u8; AMBIENT_CUBE_BYTES];
    for (k, f) in c.faces.iter().enumerate() {
        out[4 * k..4 * k + 4].copy_from_slice(&encode_rgb9e5(*f).to_le_bytes());
    }
    out
}

/// Decodes 24 bytes from [`encode_ambient_cube`].
pub fn decode_ambient_cube(b: &[u8; AMBIENT_CUBE_BYTES]) -> AmbientCube {
    let mut faces = [Vec3::ZERO; 6];
    for (k, f) in faces.iter_mut().enumerate() {
        *f = decode_rgb9e5(u32::from_le_bytes([
            b[4 * k],
            b[4 * k + 1],
            b[4 * k + 2],
            b[4 * k + 3],
        ]));
    }
    AmbientCube { faces }
}

/// f16 layout: each coefficient as R, G, B IEEE binary16, little-endian
/// (6 bytes per coefficient; round to nearest, overflow to ±inf as `half` does).
pub fn encode_f16(c: &[Vec3]) -> Vec<u8> {
    let mut out = Vec::with_capacity(c.len() * 6);
    for v in c {
        for x in v.to_array() {
            out.extend_from_slice(&half::f16::from_f32(x).to_le_bytes());
        }
    }
    out
}

/// Decodes [`encode_f16`] bytes; errors if the length is not a multiple of 6.
pub fn decode_f16(b: &[u8]) -> Result<Vec<Vec3>, CodecError> {
    if b.len() % 6 != 0 {
        return Err(CodecError::Length {
            len: b.len(),
            stride: 6,
        });
    }
    Ok(b.chunks_exact(6)
        .map(|c| {
            let h = |i: usize| half::f16::from_le_bytes([c[i], c[i + 1]]).to_f32();
            Vec3::new(h(0), h(2), h(4))
        })
        .collect())
}

/// f32 layout: each coefficient as R, G, B IEEE binary32, little-endian
/// (12 bytes per coefficient, lossless).
pub fn encode_f32(c: &[Vec3]) -> Vec<u8> {
    let mut out = Vec::with_capacity(c.len() * 12);
    for v in c {
        for x in v.to_array() {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
    out
}

/// Decodes [`encode_f32`] bytes; errors if the length is not a multiple of 12.
pub fn decode_f32(b: &[u8]) -> Result<Vec<Vec3>, CodecError> {
    if b.len() % 12 != 0 {
        return Err(CodecError::Length {
            len: b.len(),
            stride: 12,
        });
    }
    Ok(b.chunks_exact(12)
        .map(|c| {
            let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
            Vec3::new(f(0), f(4), f(8))
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::{eval_l2, Y00};
    use crate::convolve::{irradiance_l1, irradiance_l2};
    use crate::numeric::fibonacci_sphere;
    use crate::zh3::fit_zh3_shared;
    use proptest::prelude::*;

    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 40) as f32) / (1u64 << 24) as f32
        }
        fn dir(&mut self) -> Vec3 {
            let z = 2.0 * self.next() - 1.0;
            let phi = 2.0 * std::f32::consts::PI * self.next();
            let r = (1.0 - z * z).max(0.0).sqrt();
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        }
    }

    /// A random non-negative radiance projected to L2: a sum of positive
    /// deltas (weights spread over four decades, per channel), sometimes plus
    /// a positive constant, sometimes plus narrow positive lobes (each lobe a
    /// cluster of deltas).
    fn random_non_negative(rng: &mut Lcg) -> [Vec3; 9] {
        let mut c = [Vec3::ZERO; 9];
        let k = 1 + (rng.next() * 6.0) as usize;
        for _ in 0..k {
            let d = rng.dir();
            let w = Vec3::new(
                10f32.powf(4.0 * rng.next() - 2.0),
                10f32.powf(4.0 * rng.next() - 2.0),
                10f32.powf(4.0 * rng.next() - 2.0),
            );
            let spread = if rng.next() < 0.5 { 0.0 } else { 0.3 };
            for _ in 0..if spread > 0.0 { 8 } else { 1 } {
                let dd = (d + rng.dir() * spread * rng.next()).normalize();
                let y = eval_l2(dd);
                for i in 0..9 {
                    c[i] += w * y[i];
                }
            }
        }
        if rng.next() < 0.3 {
            c[0] += Vec3::splat(rng.next() * 2.0) / Y00;
        }
        c
    }

    #[test]
    fn ratio_bounds_hold_for_random_non_negative_functions() {
        let mut rng = Lcg(42);
        for _ in 0..3000 {
            let c = random_non_negative(&mut rng);
            for i in 1..9 {
                let (lo, hi) = ratio_range(i);
                for ch in 0..3 {
                    let r = c[i][ch] / c[0][ch];
                    let tol = 1e-4 * hi;
                    assert!(
                        r >= lo - tol && r <= hi + tol,
                        "coefficient {i} ratio {r} outside [{lo}, {hi}]"
                    );
                }
            }
            // ZH3 zonal coefficient about the luminance axis, and the L1 joint bound.
            let zh = fit_zh3_shared(&c);
            let (lo, hi) = zonal_range();
            for ch in 0..3 {
                let r = zh.zonal[ch] / c[0][ch];
                assert!(r >= lo - 1e-4 && r <= hi + 1e-4, "zonal ratio {r}");
                let v = Vec3::new(-c[3][ch], -c[1][ch], c[2][ch]);
                assert!(v.length() <= 3f32.sqrt() * c[0][ch] * (1.0 + 1e-4));
            }
        }
    }

    /// The bounds are tight: single deltas reach both ends used by the codec.
    #[test]
    fn ratio_bounds_are_attained_by_deltas() {
        let cases = [
            (Vec3::Z, 2, 3f32.sqrt()),
            (-Vec3::Y, 1, 3f32.sqrt()),
            (Vec3::Z, 6, 5f32.sqrt()),
            (Vec3::X, 6, -(5f32.sqrt()) / 2.0),
            (Vec3::new(1.0, 1.0, 0.0).normalize(), 4, 15f32.sqrt() / 2.0),
            (Vec3::X, 8, 15f32.sqrt() / 2.0),
            (Vec3::Y, 1, -(3f32.sqrt())),
            (Vec3::Y, 8, -(15f32.sqrt()) / 2.0),
        ];
        for (d, i, expect) in cases {
            let y = eval_l2(d);
            assert!((y[i] / y[0] - expect).abs() < 1e-5, "{i}: {}", y[i] / y[0]);
            let (lo, hi) = ratio_range(i);
            let end = if expect > 0.0 { hi } else { lo };
            assert!((end - expect).abs() < 1e-5, "range of {i} is not tight");
        }
    }

    #[test]
    fn rgb9e5_known_words() {
        assert_eq!(
            encode_rgb9e5(Vec3::ONE),
            256 | (256 << 9) | (256 << 18) | (16 << 27)
        );
        assert_eq!(decode_rgb9e5(encode_rgb9e5(Vec3::ONE)), Vec3::ONE);
        let m = encode_rgb9e5(Vec3::splat(1e9));
        assert_eq!(m, 511 | (511 << 9) | (511 << 18) | (31 << 27));
        assert_eq!(decode_rgb9e5(m), Vec3::splat(RGB9E5_MAX));
        assert_eq!(
            encode_rgb9e5(Vec3::new(-1.0, f32::NAN, 0.0)) & 0x7ff_ffff,
            0
        );
        assert_eq!(decode_rgb9e5(encode_rgb9e5(Vec3::ZERO)), Vec3::ZERO);
        // 0.5, 0.25: mantissa 256 at exponent 15; 128 at 15.
        let w = encode_rgb9e5(Vec3::new(0.5, 0.25, 0.0));
        assert_eq!(w, 256 | (128 << 9) | (15 << 27));
        // Rounding up past 511 bumps the exponent (spec's max_s == 2^N case).
        let w = encode_rgb9e5(Vec3::new(1.999, 0.0, 0.0));
        assert_eq!(w >> 27, 17);
        assert_eq!(decode_rgb9e5(w).x, 2.0);
    }

    proptest! {
        #[test]
        fn rgb9e5_round_trip_error_bounded(
            r in 0.0f32..1000.0, g in 0.0f32..1000.0, b in 0.0f32..1000.0, s in -20i32..15,
        ) {
            // Values above the format's maximum clamp to it.
            let v = (Vec3::new(r, g, b) * 2f32.powi(s)).min(Vec3::splat(RGB9E5_MAX));
            let d = decode_rgb9e5(encode_rgb9e5(v));
            let m = v.max_element();
            for ch in 0..3 {
                // half a step; a step is at most max/2^8
                prop_assert!((d[ch] - v[ch]).abs() <= m / 512.0 * 1.0001 + 1e-30,
                    "{} vs {}", d[ch], v[ch]);
            }
        }

        /// Round trip of arbitrary in-bound L2: each coefficient within half a
        /// quantisation step of its range, relative to the decoded DC.
        #[test]
        fn l2_round_trip_within_half_step(
            dc in prop::array::uniform3(0.01f32..100.0),
            t in prop::collection::vec(-1.0f32..1.0, 24),
        ) {
            let mut c = [Vec3::ZERO; 9];
            c[0] = Vec3::from(dc);
            for i in 1..9 {
                let (lo, hi) = ratio_range(i);
                for ch in 0..3 {
                    let u = 0.5 * (t[3 * (i - 1) + ch] + 1.0);
                    c[i][ch] = c[0][ch] * (lo + u * (hi - lo));
                }
            }
            let d = decode_l2(&encode_l2(&c));
            for ch in 0..3 {
                prop_assert!((d[0][ch] - c[0][ch]).abs() <= c[0].max_element() / 512.0 * 1.0001);
            }
            for i in 1..9 {
                let (lo, hi) = ratio_range(i);
                for ch in 0..3 {
                    let step = (hi - lo) / 254.0 * d[0][ch];
                    // The ratio is taken against the decoded DC, clamped to the range.
                    let exact = (c[i][ch] / d[0][ch]).clamp(lo, hi) * d[0][ch];
                    prop_assert!((d[i][ch] - exact).abs() <= 0.5 * step * 1.001 + 1e-6,
                        "coefficient {} ch {}: {} vs {}", i, ch, d[i][ch], exact);
                }
            }
            let l1: [Vec3; 4] = c[..4].try_into().unwrap();
            let d1 = decode_l1(&encode_l1(&l1));
            for i in 0..4 { prop_assert!((d1[i] - d[i]).length() < 1e-6); }
        }
    }

    #[test]
    fn f16_f32_layouts_round_trip_and_reject_bad_lengths() {
        let c = vec![Vec3::new(1.0, -2.5, 0.125), Vec3::new(1e-3, 300.0, -7.0)];
        let b = encode_f16(&c);
        assert_eq!(b.len(), 12);
        let d = decode_f16(&b).unwrap();
        for (x, y) in c.iter().zip(&d) {
            assert!((*x - *y).abs().max_element() <= x.abs().max_element() * 1e-3);
        }
        assert_eq!(decode_f32(&encode_f32(&c)).unwrap(), c);
        assert!(matches!(
            decode_f16(&b[..5]),
            Err(CodecError::Length { len: 5, .. })
        ));
        assert!(decode_f32(&[0u8; 13]).is_err());
        let cube = AmbientCube {
            faces: [
                Vec3::ONE,
                Vec3::X,
                Vec3::Y,
                Vec3::Z,
                Vec3::splat(0.5),
                Vec3::ZERO,
            ],
        };
        assert_eq!(decode_ambient_cube(&encode_ambient_cube(&cube)), cube);
    }

    /// A ZH3 with another axis (solved) is stored as the projection of its
    /// L2 expansion onto the luminance axis of the decoded L1 — exactly what
    /// the decoder assumes — up to half a quantisation step.
    #[test]
    fn zh3_with_other_axis_is_stored_as_shared_projection() {
        let mut rng = Lcg(99);
        for _ in 0..50 {
            let c = random_non_negative(&mut rng);
            let solved = crate::zh3::solve_zh3_axis(&c, crate::zh3::AxisWeights::Equal);
            let d = decode_zh3(&encode_zh3(&solved));
            let axis = shared_axis(&d.l1);
            assert!((d.axes[0] - axis).length() < 1e-6);
            let l2 = solved.to_l2();
            let (lo, hi) = zonal_range();
            for ch in 0..3 {
                let band2 = [l2[4][ch], l2[5][ch], l2[6][ch], l2[7][ch], l2[8][ch]];
                let c0 = d.l1[0][ch];
                let z = (zonal_projection(&band2, axis) / c0).clamp(lo, hi) * c0;
                let half_step = 0.5 * (hi - lo) / 254.0 * c0;
                assert!(
                    (d.zonal[ch] - z).abs() <= half_step * 1.001 + 1e-6,
                    "{} vs {}",
                    d.zonal[ch],
                    z
                );
            }
        }
    }

    fn rel_rmse(a: impl Fn(Vec3) -> Vec3, b: impl Fn(Vec3) -> Vec3, dirs: &[Vec3]) -> f64 {
        let (mut num, mut den) = (0.0f64, 0.0f64);
        for d in dirs {
            let (x, y) = (a(*d).as_dvec3(), b(*d).as_dvec3());
            num += (x - y).length_squared();
            den += y.length_squared();
        }
        (num / den).sqrt()
    }

    /// Round-trip irradiance relative RMSE (over 1024 normals and the three
    /// channels) on random non-negative functions; the numbers are reported in
    /// BENCHMARKS.md, "SH bases on real environment maps" (run with `--nocapture`).
    #[test]
    fn round_trip_irradiance_error_on_non_negative_functions() {
        let dirs: Vec<Vec3> = fibonacci_sphere(1024).iter().map(|d| d.as_vec3()).collect();
        let mut rng = Lcg(7);
        let n = 300;
        let mut stats = [(0.0f64, 0.0f64); 3]; // (sum, max) for L1, ZH3, L2
        for _ in 0..n {
            let c = random_non_negative(&mut rng);
            let l1: [Vec3; 4] = c[..4].try_into().unwrap();
            let dl1 = decode_l1(&encode_l1(&l1));
            let e1 = rel_rmse(|n| irradiance_l1(&dl1, n), |n| irradiance_l1(&l1, n), &dirs);
            let zh = fit_zh3_shared(&c);
            let dzh = decode_zh3(&encode_zh3(&zh));
            let ez = rel_rmse(|n| dzh.irradiance(n), |n| zh.irradiance(n), &dirs);
            let dl2 = decode_l2(&encode_l2(&c));
            let e2 = rel_rmse(|n| irradiance_l2(&dl2, n), |n| irradiance_l2(&c, n), &dirs);
            for (s, e) in stats.iter_mut().zip([e1, ez, e2]) {
                s.0 += e;
                s.1 = s.1.max(e);
            }
        }
        for (name, s) in ["L1 13 B", "ZH3 16 B", "L2 28 B"].iter().zip(stats) {
            println!(
                "{name}: round-trip irradiance relative RMSE mean {:.4}% max {:.4}% over {n} functions",
                100.0 * s.0 / n as f64,
                100.0 * s.1
            );
            assert!(s.1 < 0.03, "{name}: max relative error {}", s.1);
            assert!(s.0 / (n as f64) < 0.01, "{name}: mean relative error");
        }
    }
}
