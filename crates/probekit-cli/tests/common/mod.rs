//! Helpers shared by the CLI end-to-end tests: run the real `probekit`
//! binary, parse its `--json` line, expect a one-line error with exit code 1.
#![allow(dead_code)] // each test binary uses a subset

use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

/// Runs `probekit ARGS` in `dir`.
pub fn run(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_probekit"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run probekit")
}

/// Runs `probekit ARGS` in `dir`, asserts success and parses the last
/// stdout line as JSON.
pub fn json(dir: &Path, args: &[&str]) -> Value {
    let o = run(dir, args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = String::from_utf8(o.stdout).unwrap();
    serde_json::from_str(text.lines().last().unwrap()).unwrap()
}

/// Asserts that `probekit ARGS` exits with code 1 and one stderr line
/// containing `needle`.
pub fn fails_one_line(dir: &Path, args: &[&str], needle: &str) {
    let o = run(dir, args);
    assert_eq!(o.status.code(), Some(1), "{args:?}");
    let err = String::from_utf8(o.stderr).unwrap();
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains(needle), "{err} lacks {needle}");
}
