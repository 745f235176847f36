//! Coefficient codecs: how a probe's SH is stored in the `COEF` section.
//!
//! | id | codec  | order | bytes per probe | layout |
//! |----|--------|-------|-----------------|--------|
//! | 0  | `f32`  | 1..=8 | `12·order²`     | coefficient-major, RGB interleaved, IEEE binary32 LE |
//! | 1  | `f16`  | 1..=8 | `6·order²`      | same, IEEE binary16 LE |
//! | 2  | `l1`   | 2     | 13              | `probekit_sh::codec::encode_l1` (ratio-quantized L1, Roughton et al. 2024) |
//! | 3  | `zh3`  | 3     | 16              | `probekit_sh::codec::encode_zh3` (stored ZH3, decoded to L2) |
//! | 4  | `l2`   | 3     | 28              | `probekit_sh::codec::encode_l2` (ratio-quantized L2) |
//!
//! The quantized encodings are the ratio scheme of Roughton, Sloan et al.,
//! "ZH3: Quadratic Zonal Harmonics" (I3D 2024): DC per channel, every
//! other coefficient stored as a normalised ratio to DC.

use super::error::FormatError;
use crate::prelude::*;
use glam::Vec3;
use probekit_sh::MAX_ORDER;

/// How SH coefficients are stored per probe. Ids are part of the file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Codec {
    /// IEEE binary32, `3·order²` floats per probe. Lossless.
    F32,
    /// IEEE binary16, `3·order²` halves per probe (relative error ≤ 2⁻¹¹,
    /// range ±65504).
    F16,
    /// Ratio-quantized L1 (order 2) in 13 bytes (Roughton et al. 2024).
    L1Q13,
    /// Stored ZH3 in 16 bytes, decoded to L2 (order 3) (Roughton et al. 2024).
    Zh3Q16,
    /// Ratio-quantized L2 (order 3) in 28 bytes (Roughton et al. 2024).
    L2Q28,
}

impl Codec {
    /// Every codec, in id order.
    pub const ALL: [Codec; 5] = [
        Codec::F32,
        Codec::F16,
        Codec::L1Q13,
        Codec::Zh3Q16,
        Codec::L2Q28,
    ];

    /// The id stored in the file.
    pub const fn id(self) -> u32 {
        match self {
            Codec::F32 => 0,
            Codec::F16 => 1,
            Codec::L1Q13 => 2,
            Codec::Zh3Q16 => 3,
            Codec::L2Q28 => 4,
        }
    }

    /// The codec with file id `id`.
    pub fn from_id(id: u32) -> Result<Self, FormatError> {
        Self::ALL
            .into_iter()
            .find(|c| c.id() == id)
            .ok_or(FormatError::UnknownCodec(id))
    }

    /// Short name, as accepted by `probekit convert --codec`:
    /// `f32`, `f16`, `l1`, `zh3`, `l2`.
    pub const fn name(self) -> &'static str {
        match self {
            Codec::F32 => "f32",
            Codec::F16 => "f16",
            Codec::L1Q13 => "l1",
            Codec::Zh3Q16 => "zh3",
            Codec::L2Q28 => "l2",
        }
    }

    /// The codec named `name` (see [`Codec::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }

    /// The only SH order a quantized codec stores (decoded order for ZH3);
    /// `None` for the float codecs, which store any order in `1..=8`.
    pub const fn fixed_order(self) -> Option<u32> {
        match self {
            Codec::F32 | Codec::F16 => None,
            Codec::L1Q13 => Some(2),
            Codec::Zh3Q16 | Codec::L2Q28 => Some(3),
        }
    }

    /// Bytes per probe for SH of `order` bands, or `None` if the codec
    /// cannot store that order.
    pub const fn stride(self, order: u32) -> Option<usize> {
        if order == 0 || order as usize > MAX_ORDER {
            return None;
        }
        let n = (order * order) as usize;
        match (self, self.fixed_order()) {
            (Codec::F32, _) => Some(12 * n),
            (Codec::F16, _) => Some(6 * n),
            (Codec::L1Q13, Some(o)) if o == order => Some(13),
            (Codec::Zh3Q16, Some(o)) if o == order => Some(16),
            (Codec::L2Q28, Some(o)) if o == order => Some(28),
            _ => None,
        }
    }
}

/// Decodes an IEEE binary16 value exactly (every half is representable as a
/// binary32). Written here so the runtime needs no `half` dependency; checked
/// against the `half` crate on all 65 536 inputs in the tests.
pub fn f16_to_f32(h: u16) -> f32 {
    let sign = ((h as u32) >> 15) << 31;
    let exp = ((h >> 10) & 0x1F) as u32;
    let man = (h & 0x3FF) as u32;
    let magnitude = match exp {
        // Zero and subnormals: man · 2⁻²⁴, exact in binary32.
        0 => (man as f32 * (1.0 / 16_777_216.0)).to_bits(),
        // Infinity and NaN: keep the payload.
        31 => 0x7F80_0000 | (man << 13),
        // Normal: rebias the exponent from 15 to 127.
        _ => ((exp + 112) << 23) | (man << 13),
    };
    f32::from_bits(sign | magnitude)
}

/// `true` if the binary16 bit pattern is NaN or ±∞.
pub const fn f16_is_non_finite(h: u16) -> bool {
    h & 0x7C00 == 0x7C00
}

/// The SH coefficients of every probe, kept in their stored codec.
///
/// `data` holds the `COEF` payload exactly as in the file: `count · stride`
/// bytes, little-endian. Decode a probe with [`Coefficients::decode_probe`]
/// (no allocation) or all of them with [`Coefficients::to_f32`].
#[derive(Clone, Debug, PartialEq)]
pub struct Coefficients {
    /// The codec.
    pub codec: Codec,
    /// SH order (number of bands) after decoding: 4 coefficients for 2, 9 for 3.
    pub order: u32,
    /// Encoded payload, [`Coefficients::stride`] bytes per probe.
    pub data: Vec<u8>,
}

impl Coefficients {
    /// No probes: an empty `f32` set of `order` bands (rig-only files).
    pub fn empty(order: u32) -> Self {
        Self {
            codec: Codec::F32,
            order,
            data: Vec::new(),
        }
    }

    /// Stores radiance SH losslessly as `f32`. `coeffs` holds `order²`
    /// coefficients per probe, probe after probe (index `l*(l+1)+m`).
    pub fn from_f32(order: u32, coeffs: &[Vec3]) -> Result<Self, FormatError> {
        let stride = Codec::F32
            .stride(order)
            .ok_or(FormatError::CodecOrderMismatch {
                codec: "f32",
                order,
                stride: 0,
            })?;
        let n = (order * order) as usize;
        if coeffs.len() % n != 0 {
            return Err(FormatError::Unrepresentable(
                "coefficient count is not a multiple of order²",
            ));
        }
        let mut data = Vec::with_capacity(coeffs.len() / n * stride);
        for c in coeffs {
            for v in c.to_array() {
                data.extend_from_slice(&v.to_le_bytes());
            }
        }
        Ok(Self {
            codec: Codec::F32,
            order,
            data,
        })
    }

    /// Bytes per probe; 0 if codec and order do not fit together.
    pub fn stride(&self) -> usize {
        self.codec.stride(self.order).unwrap_or(0)
    }

    /// Coefficients per probe after decoding (`order²`).
    pub fn coeffs_per_probe(&self) -> usize {
        (self.order as usize).saturating_mul(self.order as usize)
    }

    /// Number of probes.
    pub fn len(&self) -> usize {
        match self.stride() {
            0 => 0,
            s => self.data.len() / s,
        }
    }

    /// `true` if no probe is stored.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The encoded bytes of probe `i`.
    pub fn probe_bytes(&self, i: usize) -> Option<&[u8]> {
        let s = self.stride();
        let start = i.checked_mul(s)?;
        self.data.get(start..start.checked_add(s)?)
    }

    /// Decodes probe `i` into `out[..order²]` (radiance SH, index
    /// `l*(l+1)+m`). Allocates nothing.
    pub fn decode_probe(&self, i: usize, out: &mut [Vec3]) -> Result<(), FormatError> {
        let n = self.coeffs_per_probe();
        let bytes = (i < self.len())
            .then(|| self.probe_bytes(i))
            .flatten()
            .ok_or(FormatError::IndexOutOfRange {
                id: super::SectionId::COEFFICIENTS,
                element: i as u64,
                value: i as u64,
                limit: self.len() as u64,
            })?;
        let out = out.get_mut(..n).ok_or(FormatError::Unrepresentable(
            "output slice shorter than order²",
        ))?;
        decode_into(self.codec, bytes, out)
    }

    /// Decodes every probe: `order²` coefficients per probe, probe after probe.
    pub fn to_f32(&self) -> Result<Vec<Vec3>, FormatError> {
        let n = self.coeffs_per_probe();
        let mut out = vec![Vec3::ZERO; self.len() * n];
        if n == 0 {
            return Ok(out);
        }
        for (i, chunk) in out.chunks_exact_mut(n).enumerate() {
            self.decode_probe(i, chunk)?;
        }
        Ok(out)
    }
}

/// Decodes one probe's bytes (exactly one stride) into `out` (`order²` long).
fn decode_into(codec: Codec, bytes: &[u8], out: &mut [Vec3]) -> Result<(), FormatError> {
    match codec {
        Codec::F32 => {
            for (o, c) in out.iter_mut().zip(bytes.chunks_exact(12)) {
                *o = Vec3::new(f32_at(c, 0), f32_at(c, 4), f32_at(c, 8));
            }
            Ok(())
        }
        Codec::F16 => {
            for (o, c) in out.iter_mut().zip(bytes.chunks_exact(6)) {
                let h = |k: usize| f16_to_f32(u16::from_le_bytes([c[k], c[k + 1]]));
                *o = Vec3::new(h(0), h(2), h(4));
            }
            Ok(())
        }
        Codec::L1Q13 | Codec::Zh3Q16 | Codec::L2Q28 => quantized::decode(codec, bytes, out),
    }
}

fn f32_at(c: &[u8], k: usize) -> f32 {
    f32::from_le_bytes([c[k], c[k + 1], c[k + 2], c[k + 3]])
}

/// Checks that every stored value decodes to a finite number. For the float
/// codecs this reads the bit patterns directly; the quantized codecs are
/// decoded (when compiled in).
pub(crate) fn check_finite(coeffs: &Coefficients) -> Result<(), FormatError> {
    let non_finite = |p: usize| FormatError::NonFinite {
        id: super::SectionId::COEFFICIENTS,
        element: p as u64,
    };
    let stride = coeffs.stride();
    if stride == 0 {
        return Ok(());
    }
    match coeffs.codec {
        Codec::F32 => {
            for (i, c) in coeffs.data.chunks_exact(4).enumerate() {
                if !f32_at(c, 0).is_finite() {
                    return Err(non_finite(i * 4 / stride));
                }
            }
        }
        Codec::F16 => {
            for (i, c) in coeffs.data.chunks_exact(2).enumerate() {
                if f16_is_non_finite(u16::from_le_bytes([c[0], c[1]])) {
                    return Err(non_finite(i * 2 / stride));
                }
            }
        }
        _ => quantized::check_finite(coeffs)?,
    }
    Ok(())
}

mod quantized {
    //! The quantized codecs, through `probekit_sh::codec` (Roughton et al. 2024).
    use super::{Codec, Coefficients, FormatError};
    use glam::Vec3;
    use probekit_sh::codec::{decode_l1, decode_l2, decode_zh3};

    fn arr<const N: usize>(bytes: &[u8]) -> Result<&[u8; N], FormatError> {
        bytes
            .try_into()
            .map_err(|_| FormatError::Unrepresentable("probe bytes shorter than the codec stride"))
    }

    pub(super) fn decode(codec: Codec, bytes: &[u8], out: &mut [Vec3]) -> Result<(), FormatError> {
        match codec {
            Codec::L1Q13 => out.copy_from_slice(&decode_l1(arr::<13>(bytes)?)),
            Codec::Zh3Q16 => out.copy_from_slice(&decode_zh3(arr::<16>(bytes)?).to_l2()),
            Codec::L2Q28 => out.copy_from_slice(&decode_l2(arr::<28>(bytes)?)),
            Codec::F32 | Codec::F16 => {
                return Err(FormatError::Unrepresentable("not a quantized codec"))
            }
        }
        Ok(())
    }

    pub(super) fn check_finite(coeffs: &Coefficients) -> Result<(), FormatError> {
        let mut buf = [Vec3::ZERO; 9];
        let n = coeffs.coeffs_per_probe().min(9);
        for i in 0..coeffs.len() {
            coeffs.decode_probe(i, &mut buf[..n])?;
            if !buf[..n].iter().all(|v| v.is_finite()) {
                return Err(FormatError::NonFinite {
                    id: crate::format::SectionId::COEFFICIENTS,
                    element: i as u64,
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f16_decoding_matches_half_crate_on_every_bit_pattern() {
        for h in 0..=u16::MAX {
            let ours = f16_to_f32(h);
            let theirs = half::f16::from_bits(h).to_f32();
            if theirs.is_nan() {
                assert!(ours.is_nan(), "{h:#06x}");
                assert!(f16_is_non_finite(h));
            } else {
                assert_eq!(ours.to_bits(), theirs.to_bits(), "{h:#06x}");
                assert_eq!(f16_is_non_finite(h), theirs.is_infinite());
            }
        }
    }

    #[test]
    fn decode_probe_checks_index_and_output_length() {
        let c = Coefficients::from_f32(2, &[Vec3::ONE; 8]).unwrap();
        let mut out = [Vec3::ZERO; 4];
        c.decode_probe(1, &mut out).unwrap();
        assert_eq!(out, [Vec3::ONE; 4]);
        assert!(matches!(
            c.decode_probe(2, &mut out),
            Err(FormatError::IndexOutOfRange { .. })
        ));
        assert!(c.decode_probe(0, &mut out[..3]).is_err());
        // A codec/order pair that does not exist holds no probes.
        let bad = Coefficients {
            codec: Codec::L1Q13,
            order: 3,
            data: vec![0; 26],
        };
        assert_eq!(bad.len(), 0);
        assert!(bad.decode_probe(0, &mut [Vec3::ZERO; 9]).is_err());
    }

    #[test]
    fn strides_and_ids() {
        assert_eq!(Codec::F32.stride(3), Some(108));
        assert_eq!(Codec::F16.stride(2), Some(24));
        assert_eq!(Codec::L1Q13.stride(2), Some(13));
        assert_eq!(Codec::L1Q13.stride(3), None);
        assert_eq!(Codec::Zh3Q16.stride(3), Some(16));
        assert_eq!(Codec::L2Q28.stride(3), Some(28));
        assert_eq!(Codec::F32.stride(0), None);
        assert_eq!(Codec::F32.stride(9), None);
        for c in Codec::ALL {
            assert_eq!(Codec::from_id(c.id()).unwrap(), c);
            assert_eq!(Codec::from_name(c.name()), Some(c));
        }
        assert!(matches!(
            Codec::from_id(5),
            Err(FormatError::UnknownCodec(5))
        ));
    }
}
