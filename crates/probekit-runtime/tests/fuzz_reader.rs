//! A bounded, deterministic mutation fuzzer for the reader, run in every
//! test pass (the `fuzz/` crate holds the libFuzzer target for longer runs,
//! see `docs/file-format.md`). Mutations of valid files — bit flips, byte
//! overwrites, truncations, extensions, length/count/offset field edits,
//! splices and random bytes — half of them with checksums re-sealed so the
//! section parsers and validation behind the CRCs are exercised. Asserts
//! that `from_bytes` returns (Ok or a typed error) without panicking, and
//! that whatever it accepts survives a write/read round trip.

mod common;

use common::*;
use probekit_runtime::format::layout::{ENTRY_LEN, HEADER_LEN};
use probekit_runtime::format::*;

const ITERATIONS: usize = 20_000;

fn seeds() -> Vec<Vec<u8>> {
    let mut small = ProbeFile::cloud(
        vec![glam::Vec3::ZERO, glam::Vec3::ONE],
        2,
        &[glam::Vec3::splat(0.5); 8],
    )
    .unwrap();
    *small.metadata_mut() = "{}".into();
    let rig = ProbeFile::Rigs(RigFile {
        rigs: full_file().rigs().to_vec(),
        metadata: "{}".into(),
    });
    vec![
        full_file().to_bytes().unwrap(),
        small.to_bytes().unwrap(),
        rig.to_bytes().unwrap(),
        groups_file().to_bytes().unwrap(),
        compact_volume_file().to_bytes().unwrap(),
        grid_volume_file().to_bytes().unwrap(),
        cvis_file().to_bytes().unwrap(),
        weights_file().to_bytes().unwrap(),
        planes_file().to_bytes().unwrap(),
    ]
}

/// Positions of `u32`/`u64` fields worth editing: header counts and lengths,
/// table offsets/lengths, and the first words of each section (its counts).
fn interesting_fields(b: &[u8]) -> Vec<usize> {
    let mut v = vec![12, 16, 20, 24];
    let count = if b.len() >= HEADER_LEN {
        (u32::from_le_bytes(b[20..24].try_into().unwrap()) as usize).min(16)
    } else {
        0
    };
    for k in 0..count {
        let e = HEADER_LEN + k * ENTRY_LEN;
        if e + ENTRY_LEN <= b.len() {
            v.extend([e, e + 8, e + 16]);
            let (_, off, len) = entry_of(b, k);
            if off < b.len() && len >= 16 {
                v.extend([off, off + 4, off + 8, off + 12]);
                if len >= 32 {
                    v.extend([off + 16, off + 20, off + 24, off + 28]);
                }
            }
        }
    }
    v.retain(|&o| o + 4 <= b.len());
    v
}

fn mutate(rng: &mut Rng, seed: &[u8]) -> Vec<u8> {
    let mut b = seed.to_vec();
    let rounds = 1 + rng.below(4);
    for _ in 0..rounds {
        match rng.below(9) {
            0 if !b.is_empty() => {
                let i = rng.below(b.len());
                b[i] ^= 1 << rng.below(8);
            }
            1 if !b.is_empty() => {
                let i = rng.below(b.len());
                b[i] = rng.next_u64() as u8;
            }
            2 => {
                let n = rng.below(b.len() + 1);
                b.truncate(n);
            }
            3 => {
                let extra = rng.below(64);
                for _ in 0..extra {
                    b.push(rng.next_u64() as u8);
                }
            }
            4 | 5 => {
                let fields = interesting_fields(&b);
                if !fields.is_empty() {
                    let at = fields[rng.below(fields.len())];
                    let old = u32::from_le_bytes(b[at..at + 4].try_into().unwrap());
                    let new = match rng.below(6) {
                        0 => 0,
                        1 => u32::MAX,
                        2 => old.wrapping_add(1),
                        3 => old.wrapping_sub(1),
                        4 => old.wrapping_add(16),
                        _ => rng.next_u64() as u32,
                    };
                    put_u32(&mut b, at, new);
                }
            }
            6 if b.len() > 8 => {
                // Copy a run of bytes elsewhere in the file.
                let len = 1 + rng.below(32.min(b.len() / 2));
                let from = rng.below(b.len() - len);
                let to = rng.below(b.len() - len);
                let chunk = b[from..from + len].to_vec();
                b[to..to + len].copy_from_slice(&chunk);
            }
            7 => {
                let n = rng.below(256);
                b = (0..n).map(|_| rng.next_u64() as u8).collect();
                if rng.below(2) == 0 && b.len() >= 8 {
                    b[..8].copy_from_slice(b"PROBEKIT");
                }
            }
            _ => {
                // Keep the header valid but fix the length field to match.
                if b.len() >= HEADER_LEN {
                    let len = b.len() as u64;
                    b[24..32].copy_from_slice(&len.to_le_bytes());
                }
            }
        }
    }
    if rng.below(2) == 0 {
        reseal(&mut b);
    }
    b
}

#[test]
fn mutated_files_never_panic() {
    let seeds = seeds();
    let mut rng = Rng(0x5EED);
    let mut accepted = 0usize;
    let mut past_checksums = 0usize;
    for _ in 0..ITERATIONS {
        let seed = &seeds[rng.below(seeds.len())];
        let input = mutate(&mut rng, seed);
        match ProbeFile::from_bytes(&input) {
            Ok(f) => {
                accepted += 1;
                // Whatever the reader accepts, the writer can write and the
                // reader reads back identically.
                let again = f.to_bytes().expect("accepted file re-encodes");
                assert_eq!(ProbeFile::from_bytes(&again).expect("re-read"), f);
            }
            Err(e) => {
                if !matches!(
                    e,
                    FormatError::ChecksumMismatch { .. }
                        | FormatError::Truncated { .. }
                        | FormatError::BadMagic
                        | FormatError::LengthMismatch { .. }
                ) {
                    past_checksums += 1;
                }
                let _ = e.to_string();
            }
        }
        // The low-level table reader must not panic either.
        let _ = file_bytes_by_section(&input);
    }
    // The mutations must reach the parsers, not only the checksums.
    assert!(past_checksums > ITERATIONS / 10, "{past_checksums}");
    assert!(accepted > 0);
}
