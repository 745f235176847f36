//! Test tier on the real CC0 environment maps in `<workspace>/../shared/data/env`
//! (or `$PROBEKIT_DATA_DIR/env`). Prints the basis comparison table for every
//! map; skips with a message when the folder is absent.

use probekit::env::{project_equirect, reference_irradiance, EnvMap, Environment};
use probekit::sh::compare::{compare_bases, relative_rmse, spherical_fibonacci, MIN_NORMALS};
use std::io::Write;
use std::path::PathBuf;

/// Reports a skipped tier straight to stderr (the harness captures `print!`).
fn skip(why: &str) {
    let _ = writeln!(std::io::stderr(), "SKIPPED: {why}");
}

fn env_dir() -> Option<PathBuf> {
    let dir = match std::env::var_os("PROBEKIT_DATA_DIR") {
        Some(d) => PathBuf::from(d).join("env"),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/env"),
    };
    if dir.is_dir() {
        Some(dir)
    } else {
        skip(&format!(
            "real environment maps not found at {} (set PROBEKIT_DATA_DIR)",
            dir.display()
        ));
        None
    }
}

fn maps(dir: &PathBuf) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("hdr" | "exr")))
        .collect();
    v.sort();
    v
}

/// Every real map loads, and the comparison table is printed. Checks what
/// must hold whatever the map: errors are finite and below 100 %, and L2
/// (which adds the band-2 term, orthogonal to the rest) is never worse than L1.
#[test]
fn comparison_table_for_every_real_map() {
    let Some(dir) = env_dir() else { return };
    let files = maps(&dir);
    assert!(!files.is_empty(), "no maps in {}", dir.display());
    for path in files {
        let map = EnvMap::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let c = compare_bases(&map, MIN_NORMALS);
        println!(
            "== {}\n{}",
            path.file_name().unwrap().to_string_lossy(),
            c.table()
        );
        let (l1, l2) = (c.bases.l1.unwrap(), c.bases.l2.unwrap());
        assert!(l1.is_finite() && l1 < 1.0 && l2 >= 0.0, "{l1} {l2}");
        assert!(l2 <= l1 + 1e-6, "{}: l2 {l2} > l1 {l1}", path.display());
    }
}

/// `city.exr` (f32) and `city.hdr` (RGBE of the same pixels) give the same SH
/// to RGBE precision (each coefficient within 1 % of the DC magnitude).
#[test]
fn city_exr_and_hdr_agree() {
    let Some(dir) = env_dir() else { return };
    let (e, h) = (dir.join("city.exr"), dir.join("city.hdr"));
    if !e.is_file() || !h.is_file() {
        skip(&format!(
            "city.exr / city.hdr not found in {}",
            dir.display()
        ));
        return;
    }
    let se = project_equirect(&EnvMap::load(&e).unwrap(), 3);
    let sh = project_equirect(&EnvMap::load(&h).unwrap(), 3);
    let dc = se.coeffs()[0];
    for (i, (a, b)) in se.coeffs().iter().zip(sh.coeffs()).enumerate() {
        let rel = ((*a - *b) / dc).abs().max_element();
        println!("c{i}: exr {a} hdr {b} (Δ/DC {:.3} %)", rel * 100.0);
        assert!(rel < 0.01, "coefficient {i}: {a} vs {b}");
    }
}

/// The comparison's reference integrates a 2×2-averaged map; on a real map
/// that changes the irradiance by < 0.1 % RMS against the full resolution.
#[test]
fn downsampled_reference_is_accurate_on_real_map() {
    let Some(dir) = env_dir() else { return };
    let path = dir.join("sunset.hdr");
    if !path.is_file() {
        skip(&format!("{} not found", path.display()));
        return;
    }
    let map = EnvMap::load(&path).unwrap();
    let normals = spherical_fibonacci(512);
    let full = reference_irradiance(&map, &normals);
    let reduced = probekit::env::reference_irradiance_texels(&map.reference_texels(), &normals);
    let err = relative_rmse(&reduced, &full).unwrap();
    println!(
        "sunset: downsampled reference differs by {:.4} % RMS",
        err * 100.0
    );
    assert!(err < 1e-3, "{err}");
}
