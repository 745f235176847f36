//! `docs/file-format.md` ("Codecs") specifies every coefficient codec byte by
//! byte so that an engine can write its own loader. This test is such a
//! loader, written from that section alone (in f64), and checks it against
//! the runtime's decoder (`Coefficients::decode_probe`) on random probes of
//! every codec: if the code and the document disagree, it fails.

use glam::Vec3;
use probekit_runtime::format::{Codec, Coefficients};
use std::f64::consts::PI;

/// SplitMix64.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn bytes(&mut self, n: usize) -> Vec<u8> {
        (0..n).map(|_| self.next() as u8).collect()
    }
}

type Rgb = [f64; 3];

/// Step 1: RGB9E5.
fn rgb9e5(b: &[u8]) -> Rgb {
    let w = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    let e = (w >> 27) as i32;
    let s = 2f64.powi(e - 24);
    [
        (w & 0x1FF) as f64 * s,
        ((w >> 9) & 0x1FF) as f64 * s,
        ((w >> 18) & 0x1FF) as f64 * s,
    ]
}

/// Step 2: the ratio range of coefficient `i` (index 9 stands for ZH3's z).
fn range(i: usize) -> (f64, f64) {
    match i {
        1..=3 => (-3f64.sqrt(), 3f64.sqrt()),
        6 | 9 => (-(5f64.sqrt()) / 2.0, 5f64.sqrt()),
        _ => (-(15f64.sqrt()) / 2.0, 15f64.sqrt() / 2.0),
    }
}

fn ratio(byte: u8, c0: f64, i: usize) -> f64 {
    if c0 <= 0.0 {
        return 0.0;
    }
    let t = ((byte as i8) as f64 / 127.0).max(-1.0);
    let (lo, hi) = range(i);
    c0 * ((lo + hi) / 2.0 + (hi - lo) / 2.0 * t)
}

/// DC at 0..4, coefficient i (1..n) channel ch at 4 + 3(i−1) + ch.
fn ratio_probe(b: &[u8], n: usize) -> Vec<Rgb> {
    let dc = rgb9e5(b);
    let mut out = vec![dc];
    for i in 1..n {
        out.push([0, 1, 2].map(|ch| ratio(b[4 + 3 * (i - 1) + ch], dc[ch], i)));
    }
    out
}

/// Step 3: ZH3 → L2.
fn zh3_probe(b: &[u8]) -> Vec<Rgb> {
    let mut out = ratio_probe(&b[..13], 4);
    let w = [0.2126, 0.7152, 0.0722];
    let dot = |c: Rgb| c[0] * w[0] + c[1] * w[1] + c[2] * w[2];
    let v = [-dot(out[3]), -dot(out[1]), dot(out[2])];
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let a = if len > 1e-30 && len.is_finite() {
        v.map(|x| x / len)
    } else {
        [0.0, 1.0, 0.0]
    };
    let (x, y, z) = (a[0], a[1], a[2]);
    let k2 = (15.0 / (4.0 * PI)).sqrt();
    let y2 = [
        k2 * x * y,
        -k2 * y * z,
        (5.0 / (16.0 * PI)).sqrt() * (3.0 * z * z - 1.0),
        -k2 * x * z,
        (15.0 / (16.0 * PI)).sqrt() * (x * x - y * y),
    ];
    let zonal = [0, 1, 2].map(|ch| ratio(b[13 + ch], out[0][ch], 9));
    for ym in y2 {
        out.push(zonal.map(|zc| (4.0 * PI / 5.0).sqrt() * zc * ym));
    }
    out
}

fn half_to_f64(h: u16) -> f64 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let e = ((h >> 10) & 0x1F) as i32;
    let m = (h & 0x3FF) as f64;
    sign * match e {
        0 => m * 2f64.powi(-24),
        31 if m == 0.0 => f64::INFINITY,
        31 => f64::NAN,
        _ => (1.0 + m / 1024.0) * 2f64.powi(e - 15),
    }
}

/// The document's decoder for one probe of `codec` with `order` bands.
fn doc_decode(codec: Codec, order: usize, b: &[u8]) -> Vec<Rgb> {
    let n = order * order;
    match codec {
        Codec::F32 => (0..n)
            .map(|i| {
                [0, 1, 2].map(|ch| {
                    let o = 12 * i + 4 * ch;
                    f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]) as f64
                })
            })
            .collect(),
        Codec::F16 => (0..n)
            .map(|i| {
                [0, 1, 2].map(|ch| {
                    let o = 6 * i + 2 * ch;
                    half_to_f64(u16::from_le_bytes([b[o], b[o + 1]]))
                })
            })
            .collect(),
        Codec::L1Q13 => ratio_probe(b, 4),
        Codec::L2Q28 => ratio_probe(b, 9),
        Codec::Zh3Q16 => zh3_probe(b),
        _ => unreachable!("a codec the document does not describe"),
    }
}

fn same(ours: f64, theirs: f32, scale: f64) -> bool {
    if ours.is_nan() {
        return theirs.is_nan();
    }
    if ours.is_infinite() {
        return theirs as f64 == ours;
    }
    (ours - theirs as f64).abs() <= 2e-6 * ours.abs() + 1e-6 * scale
}

#[test]
fn document_decoder_matches_the_runtime_on_random_probes() {
    let mut rng = Rng(0x5eed);
    let mut checked = 0;
    for codec in Codec::ALL {
        for order in 1..=8u32 {
            let Some(stride) = codec.stride(order) else {
                continue;
            };
            let probes = 200;
            let mut data = rng.bytes(stride * probes);
            if codec == Codec::F32 {
                // Mostly ordinary floats: random bits are often huge or tiny.
                for c in data.chunks_exact_mut(4) {
                    let v = (rng.next() as i32) as f32 / 1e6;
                    c.copy_from_slice(&v.to_le_bytes());
                }
            }
            let coeffs = Coefficients {
                codec,
                order,
                data: data.clone(),
            };
            assert_eq!(coeffs.len(), probes, "{codec:?} order {order}");
            let n = (order * order) as usize;
            let mut out = vec![Vec3::ZERO; n];
            for p in 0..probes {
                let bytes = &data[p * stride..(p + 1) * stride];
                coeffs.decode_probe(p, &mut out).unwrap();
                let doc = doc_decode(codec, order as usize, bytes);
                let scale = doc
                    .iter()
                    .flatten()
                    .filter(|x| x.is_finite())
                    .fold(0.0f64, |m, x| m.max(x.abs()));
                for (i, (d, o)) in doc.iter().zip(&out).enumerate() {
                    for ch in 0..3 {
                        assert!(
                            same(d[ch], o[ch], scale),
                            "{codec:?} order {order} probe {p} coefficient {i} channel {ch}: \
                             document {} vs runtime {}",
                            d[ch],
                            o[ch]
                        );
                    }
                }
                checked += 1;
            }
        }
    }
    // f32 and f16 at 8 orders each, plus l1, zh3, l2.
    assert_eq!(checked, 200 * (8 + 8 + 3));
}
