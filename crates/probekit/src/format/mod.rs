//! Writing `.probes` files: codec encoding, bake metadata, and atomic
//! file replacement. Two submodules sit above the capture and the Delaunay
//! code, which they take their inputs from: [`cloud`] assembles a baked
//! probe cloud, [`settings`] records the capture settings in the metadata
//! and reads them back.
//!
//! The format itself (layout, reader, serializer, validation) lives in the
//! runtime crate, [`probekit_runtime::format`], re-exported here, so the
//! reader an engine links and the writer the baker uses cannot drift apart.
//! The layout is specified byte by byte in `docs/file-format.md`.
//!
//! ```no_run
//! use probekit::format::{
//!     encode_coefficients, write_probe_file, CloudFile, Codec, ProbeFile, ProbeSet,
//! };
//! use glam::Vec3;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let positions = vec![Vec3::ZERO, Vec3::X];
//! let sh = vec![Vec3::splat(0.3); 2 * 9]; // L2 radiance SH, 9 per probe
//! let coefficients = encode_coefficients(Codec::F16, 3, &sh)?;
//! let file = ProbeFile::Cloud(CloudFile::new(ProbeSet::new(positions, coefficients)));
//! write_probe_file("bake.probes", &file)?;
//! # Ok(()) }
//! ```

mod atomic;
pub mod cloud;
mod metadata;
mod parts;
pub mod settings;

pub use atomic::{check_writable, write_atomic, write_probe_file, WriteError};
pub use metadata::{
    check_scene, check_scene_hash, recorded_scene, scene_hash, BakeMetadata, Placement,
    SceneMismatch,
};
pub(crate) use parts::Parts;
pub use probekit_runtime::format::*;

use glam::Vec3;
use std::collections::BTreeMap;

/// Serializes `file` (validating it first). Deterministic: equal contents
/// give equal bytes, whatever the machine or thread count.
pub fn to_bytes(file: &ProbeFile) -> Result<Vec<u8>, FormatError> {
    file.to_bytes()
}

/// Bytes each section of `file` takes when written (`"header"` for header
/// plus table); the values sum to the file size. Used by `inspect --json`.
pub fn bytes_by_section(file: &ProbeFile) -> Result<BTreeMap<String, u64>, FormatError> {
    file.bytes_by_section()
}

/// Encodes radiance SH into `codec`.
///
/// `coeffs` holds `order²` coefficients per probe (index `l*(l+1)+m`),
/// probe after probe. Float codecs keep `order`; the quantized codecs keep
/// the first 4 (L1) or 9 (ZH3, L2) coefficients and need `order` at least 2
/// or 3. `f16` rounds to nearest even (the `half` crate) and refuses values
/// beyond ±65504; every input must be finite.
pub fn encode_coefficients(
    codec: Codec,
    order: u32,
    coeffs: &[Vec3],
) -> Result<Coefficients, FormatError> {
    if order == 0 || order as usize > probekit_sh::MAX_ORDER {
        return Err(FormatError::Unrepresentable("SH order outside 1..=8"));
    }
    let n = (order * order) as usize;
    if coeffs.len() % n != 0 {
        return Err(FormatError::Unrepresentable(
            "coefficient count is not a multiple of order²",
        ));
    }
    if let Some(i) = coeffs.iter().position(|c| !c.is_finite()) {
        return Err(FormatError::NonFinite {
            id: SectionId::COEFFICIENTS,
            element: (i / n) as u64,
        });
    }
    let out_order = codec.fixed_order().unwrap_or(order);
    if out_order > order {
        return Err(FormatError::CodecOrderMismatch {
            codec: codec.name(),
            order,
            stride: 0,
        });
    }
    let stride = codec
        .stride(out_order)
        .ok_or(FormatError::CodecOrderMismatch {
            codec: codec.name(),
            order,
            stride: 0,
        })?;
    let probes = coeffs.len() / n;
    let mut data = Vec::with_capacity(probes * stride);
    match codec {
        Codec::F32 => return Coefficients::from_f32(order, coeffs),
        Codec::F16 => {
            for (p, probe) in coeffs.chunks_exact(n).enumerate() {
                for v in probe.iter().flat_map(|c| c.to_array()) {
                    let h = half::f16::from_f32(v);
                    if !h.is_finite() {
                        return Err(FormatError::NonFinite {
                            id: SectionId::COEFFICIENTS,
                            element: p as u64,
                        });
                    }
                    data.extend_from_slice(&h.to_bits().to_le_bytes());
                }
            }
        }
        _ => quantized::encode(codec, coeffs.chunks_exact(n), &mut data)?,
    }
    Ok(Coefficients {
        codec,
        order: out_order,
        data,
    })
}

mod quantized {
    //! The quantized encoders of `probekit_sh::codec` (Iwanicki & Sloan 2017, "Ambient Dice").
    use super::{Codec, FormatError};
    use glam::Vec3;
    use probekit_sh::codec::{encode_l1, encode_l2, encode_zh3};
    use probekit_sh::zh3::fit_zh3_shared;

    pub(super) fn encode<'a>(
        codec: Codec,
        probes: impl Iterator<Item = &'a [Vec3]>,
        out: &mut Vec<u8>,
    ) -> Result<(), FormatError> {
        for probe in probes {
            let short = || FormatError::Unrepresentable("probe has too few coefficients for codec");
            match codec {
                Codec::L1Q13 => {
                    let l1: [Vec3; 4] = probe
                        .get(..4)
                        .ok_or_else(short)?
                        .try_into()
                        .map_err(|_| short())?;
                    out.extend_from_slice(&encode_l1(&l1));
                }
                Codec::Zh3Q16 => {
                    let l2: [Vec3; 9] = probe
                        .get(..9)
                        .ok_or_else(short)?
                        .try_into()
                        .map_err(|_| short())?;
                    out.extend_from_slice(&encode_zh3(&fit_zh3_shared(&l2)));
                }
                Codec::L2Q28 => {
                    let l2: [Vec3; 9] = probe
                        .get(..9)
                        .ok_or_else(short)?
                        .try_into()
                        .map_err(|_| short())?;
                    out.extend_from_slice(&encode_l2(&l2));
                }
                _ => return Err(FormatError::Unrepresentable("not a quantized codec")),
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg_coeffs(n: usize, seed: u32) -> Vec<Vec3> {
        let mut s = seed;
        let mut f = move || {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (s >> 8) as f32 / (1u32 << 24) as f32 * 20.0 - 10.0
        };
        (0..n).map(|_| Vec3::new(f(), f(), f())).collect()
    }

    #[test]
    fn f16_encoding_is_within_half_an_ulp_and_round_trips_through_a_file() {
        let order = 3;
        let coeffs = lcg_coeffs(6 * 9, 1);
        let enc = encode_coefficients(Codec::F16, order, &coeffs).unwrap();
        assert_eq!(enc.data.len(), 6 * 54);
        let mut file = ProbeFile::cloud(vec![Vec3::ZERO; 6], order, &coeffs).unwrap();
        file.probe_set_mut().coefficients = enc;
        let back = ProbeFile::from_bytes(&to_bytes(&file).unwrap()).unwrap();
        let dec = back.probe_set().coefficients.to_f32().unwrap();
        for (d, c) in dec.iter().zip(&coeffs) {
            for k in 0..3 {
                // |x| in [2^e, 2^(e+1)) has f16 spacing 2^(e-10); nearest
                // rounding errs by at most half of it.
                let e = c[k].abs().log2().floor();
                let half_ulp = 2f32.powf(e - 11.0).max(2f32.powi(-25));
                assert!((d[k] - c[k]).abs() <= half_ulp, "{} vs {}", d[k], c[k]);
            }
        }
    }

    #[test]
    fn encoding_refuses_what_the_codec_cannot_hold() {
        let big = vec![Vec3::new(1.0e5, 0.0, 0.0); 4];
        assert!(matches!(
            encode_coefficients(Codec::F16, 2, &big),
            Err(FormatError::NonFinite { .. })
        ));
        let nan = vec![Vec3::new(f32::NAN, 0.0, 0.0); 4];
        assert!(matches!(
            encode_coefficients(Codec::F32, 2, &nan),
            Err(FormatError::NonFinite { .. })
        ));
        assert!(matches!(
            encode_coefficients(Codec::L2Q28, 2, &[Vec3::ONE; 4]),
            Err(FormatError::CodecOrderMismatch { .. })
        ));
        assert!(matches!(
            encode_coefficients(Codec::F32, 3, &[Vec3::ONE; 4]),
            Err(FormatError::Unrepresentable(_))
        ));
        // f32 keeps everything bit for bit.
        let c = lcg_coeffs(2 * 16, 9);
        let e = encode_coefficients(Codec::F32, 4, &c).unwrap();
        assert_eq!(e.to_f32().unwrap(), c);
    }

    /// The file adds nothing to the codecs: what comes out of a file is
    /// exactly `decode(encode(x))` of the SH core, and sizes match the
    /// strides of Iwanicki & Sloan 2017 (13, 16, 28 bytes).
    #[test]
    fn quantized_codecs_round_trip_through_a_file_bit_for_bit() {
        use probekit_sh::codec::{
            decode_l1, decode_l2, decode_zh3, encode_l1, encode_l2, encode_zh3,
        };
        use probekit_sh::zh3::fit_zh3_shared;
        let probes = 5;
        let coeffs: Vec<Vec3> = lcg_coeffs(probes * 9, 3)
            .into_iter()
            .enumerate()
            // Positive DC, smaller higher bands: a plausible radiance SH.
            .map(|(i, c)| if i % 9 == 0 { c.abs() + 5.0 } else { c * 0.1 })
            .collect();
        for codec in [Codec::L1Q13, Codec::Zh3Q16, Codec::L2Q28] {
            let enc = encode_coefficients(codec, 3, &coeffs).unwrap();
            let mut file = ProbeFile::cloud(vec![Vec3::ZERO; probes], 3, &coeffs).unwrap();
            file.probe_set_mut().coefficients = enc;
            let bytes = to_bytes(&file).unwrap();
            let back = ProbeFile::from_bytes(&bytes).unwrap();
            let stride = [13, 16, 28][codec.id() as usize - 2];
            assert_eq!(back.probe_set().coefficients.data.len(), probes * stride);
            let dec = back.probe_set().coefficients.to_f32().unwrap();
            for (p, probe) in coeffs.chunks_exact(9).enumerate() {
                let l1: [Vec3; 4] = probe[..4].try_into().unwrap();
                let l2: [Vec3; 9] = probe.try_into().unwrap();
                let expect: Vec<Vec3> = match codec {
                    Codec::L1Q13 => decode_l1(&encode_l1(&l1)).to_vec(),
                    Codec::Zh3Q16 => decode_zh3(&encode_zh3(&fit_zh3_shared(&l2)))
                        .to_l2()
                        .to_vec(),
                    _ => decode_l2(&encode_l2(&l2)).to_vec(),
                };
                let n = expect.len();
                assert_eq!(&dec[p * n..(p + 1) * n], &expect[..], "{}", codec.name());
            }
        }
    }

    #[test]
    fn written_files_are_byte_identical_for_identical_bakes() {
        let dir = tempfile::tempdir().unwrap();
        let coeffs = lcg_coeffs(3 * 4, 5);
        let mut f = ProbeFile::cloud(vec![Vec3::ZERO, Vec3::X, Vec3::Y], 2, &coeffs).unwrap();
        *f.metadata_mut() = BakeMetadata::new(
            scene_hash(b"demo"),
            Placement {
                method: "grid".into(),
                parameters: serde_json::json!({"cell": 0.5}),
            },
            serde_json::json!({"seed": 1}),
        )
        .to_json();
        let (a, b) = (dir.path().join("a.probes"), dir.path().join("b.probes"));
        write_probe_file(&a, &f).unwrap();
        write_probe_file(&b, &f.clone()).unwrap();
        let (ba, bb) = (std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        assert_eq!(ba, bb);
        assert_eq!(ProbeFile::load(&a).unwrap(), f);
        let sizes = bytes_by_section(&f).unwrap();
        assert_eq!(sizes.values().sum::<u64>(), ba.len() as u64);
        assert_eq!(sizes, file_bytes_by_section(&ba).unwrap());
    }
}
