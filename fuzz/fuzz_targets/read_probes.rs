//! libFuzzer target for the `.probes` reader.
//!
//! Each input is parsed twice: as given, and with its checksums recomputed
//! ("re-sealed"), so mutations reach the section parsers and validation
//! behind the CRCs instead of stopping at the first checksum. Whatever the
//! reader accepts must write and read back identically.
//!
//! `cargo +nightly fuzz run read_probes` (see docs/file-format.md).
#![no_main]

use libfuzzer_sys::fuzz_target;
use probekit_runtime::format::layout::{entry, header, ENTRY_LEN, HEADER_LEN};
use probekit_runtime::format::{crc32, file_bytes_by_section, Crc32, ProbeFile};

fn u64_at(b: &[u8], o: usize) -> u64 {
    u64::from_le_bytes(b[o..o + 8].try_into().unwrap())
}

/// Recomputes section CRCs (for in-bounds entries) and the header CRC.
fn reseal(b: &mut [u8]) {
    if b.len() < HEADER_LEN {
        return;
    }
    let count = u32::from_le_bytes(b[header::SECTION_COUNT..][..4].try_into().unwrap()) as usize;
    let Some(end) = count.checked_mul(ENTRY_LEN).and_then(|t| t.checked_add(HEADER_LEN)) else {
        return;
    };
    if end > b.len() {
        return;
    }
    for k in 0..count {
        let e = HEADER_LEN + k * ENTRY_LEN;
        let (off, len) = (u64_at(b, e + entry::OFFSET), u64_at(b, e + entry::LENGTH));
        if let Some(stop) = off.checked_add(len).filter(|&s| s <= b.len() as u64) {
            let c = crc32(&b[off as usize..stop as usize]);
            b[e + entry::CRC..e + entry::CRC + 4].copy_from_slice(&c.to_le_bytes());
        }
    }
    let mut c = Crc32::new();
    c.update(&b[..header::CRC]);
    c.update(&b[HEADER_LEN..end]);
    let c = c.finish();
    b[header::CRC..header::CRC + 4].copy_from_slice(&c.to_le_bytes());
}

fn check(bytes: &[u8]) {
    let _ = file_bytes_by_section(bytes);
    if let Ok(f) = ProbeFile::from_bytes(bytes) {
        let again = f.to_bytes().expect("an accepted file re-encodes");
        assert_eq!(ProbeFile::from_bytes(&again).expect("and re-reads"), f);
    }
}

fuzz_target!(|data: &[u8]| {
    check(data);
    let mut sealed = data.to_vec();
    reseal(&mut sealed);
    check(&sealed);
});
