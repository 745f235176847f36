//! A file of format 1.x (written by an older probekit) given to the C API:
//! loading from bytes or from a path returns a null handle and
//! `PK_ERR_FORMAT`, never a panic, and `pk_last_error` says the file
//! must be baked again.

use probekit_capi::*;
use probekit_runtime::format::layout::ENTRY_LEN;
use probekit_runtime::format::layout::{header, HEADER_LEN};
use probekit_runtime::format::Crc32;
use std::ffi::{CStr, CString};

mod common;
use common::*;

/// A good file relabelled 1.11, checksums recomputed so only the version
/// is wrong.
fn format_1_bytes() -> Vec<u8> {
    let mut b = cloud_file().to_bytes().unwrap();
    b[header::MAJOR..header::MAJOR + 2].copy_from_slice(&1u16.to_le_bytes());
    b[header::MINOR..header::MINOR + 2].copy_from_slice(&11u16.to_le_bytes());
    let count = u32::from_le_bytes(b[header::SECTION_COUNT..][..4].try_into().unwrap()) as usize;
    let table_end = HEADER_LEN + ENTRY_LEN * count;
    let mut c = Crc32::new();
    c.update(&b[..header::CRC]);
    c.update(&b[HEADER_LEN..table_end]);
    let c = c.finish();
    b[header::CRC..header::CRC + 4].copy_from_slice(&c.to_le_bytes());
    b
}

fn last_error() -> String {
    unsafe { CStr::from_ptr(pk_last_error()) }
        .to_str()
        .unwrap()
        .to_string()
}

fn assert_older_version_error(h: *mut PkProbes, st: PkStatus) {
    assert!(h.is_null());
    assert_eq!(st, PkStatus::Format);
    let msg = last_error();
    assert!(msg.contains("older probekit"), "{msg}");
    assert!(msg.contains("baked again"), "{msg}");
    assert!(msg.contains("1.11"), "{msg}");
}

#[test]
fn a_format_1_file_is_a_format_error_from_bytes() {
    let bytes = format_1_bytes();
    for options in [std::ptr::null(), &pk_load_options_default() as *const _] {
        let mut st = PkStatus::Ok;
        let h = unsafe { pk_probes_load_bytes(bytes.as_ptr(), bytes.len(), options, &mut st) };
        assert_older_version_error(h, st);
    }
    let mut st = PkStatus::Ok;
    let h = unsafe { pk_load_bytes(bytes.as_ptr(), bytes.len(), &mut st) };
    assert_older_version_error(h, st);
}

#[test]
fn a_format_1_file_is_a_format_error_from_a_path() {
    let path = std::env::temp_dir().join(format!(
        "probekit-capi-older-format-{}.probes",
        std::process::id()
    ));
    std::fs::write(&path, format_1_bytes()).unwrap();
    let c = CString::new(path.to_str().unwrap()).unwrap();
    let mut st = PkStatus::Ok;
    let h = unsafe { pk_probes_load_file(c.as_ptr(), std::ptr::null(), &mut st) };
    assert_older_version_error(h, st);
    let mut st = PkStatus::Ok;
    let h = unsafe { pk_load_file(c.as_ptr(), &mut st) };
    assert_older_version_error(h, st);
    std::fs::remove_file(&path).unwrap();
}
