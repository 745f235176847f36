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

/// True for a progress line (what long commands print on stderr off a
/// terminal before any result or error): `PHASE: started (N)`, `PHASE: 40 %
/// (…)`, `PHASE: done …`.
pub fn is_progress_line(line: &str) -> bool {
    line.contains(": started (") || line.contains(" % (") || line.contains(": done ")
}

/// Asserts that `probekit ARGS` exits with code 1 and one stderr line
/// (progress lines aside) containing `needle`.
pub fn fails_one_line(dir: &Path, args: &[&str], needle: &str) {
    let o = run(dir, args);
    assert_eq!(o.status.code(), Some(1), "{args:?}");
    let err = String::from_utf8(o.stderr).unwrap();
    let lines: Vec<&str> = err.lines().filter(|l| !is_progress_line(l)).collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(lines[0].contains(needle), "{err} lacks {needle}");
}
