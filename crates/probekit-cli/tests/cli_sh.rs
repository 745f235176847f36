//! End-to-end tests of `probekit sh`: the real binary in a temporary folder.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn probekit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_probekit"))
        .args(args)
        .output()
        .expect("run probekit")
}

fn stdout(o: &Output) -> String {
    String::from_utf8(o.stdout.clone()).unwrap()
}

/// `--json` on the built-in sky: the documented shape, N² finite coefficients,
/// and the DC term is the mean radiance × √(4π) (positive for a lit sky).
#[test]
fn sh_json_on_builtin_sky() {
    let o = probekit(&["sh", "builtin:sky", "--order", "4", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_str(stdout(&o).trim()).unwrap();
    assert_eq!(v["order"], 4);
    let c = v["coefficients"].as_array().unwrap();
    assert_eq!(c.len(), 16);
    for rgb in c {
        let rgb = rgb.as_array().unwrap();
        assert_eq!(rgb.len(), 3);
        assert!(rgb.iter().all(|x| x.as_f64().unwrap().is_finite()));
    }
    assert!(c[0][0].as_f64().unwrap() > 0.0);
    // the default is 3 bands, and the table form has one row per coefficient
    let o = probekit(&["sh", "builtin:sky"]);
    assert!(o.status.success());
    assert_eq!(stdout(&o).lines().count(), 1 + 9);
}

/// `--compare --json` has every documented key; measured errors are in
/// (0, 1); `--plot` writes a PNG; the table form lists every basis.
#[test]
fn sh_compare_on_builtin_sky() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("bars.png");
    let o = probekit(&[
        "sh",
        "builtin:sky",
        "--compare",
        "--json",
        "--plot",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_str(stdout(&o).trim()).unwrap();
    for key in [
        "l1",
        "l1_geomerics",
        "zh3_hallucinated",
        "zh3_shared",
        "zh3_per_channel",
        "zh3_solved",
        "l2",
        "l2_windowed",
        "ambient_cube",
    ] {
        assert!(v["bases"].get(key).is_some(), "bases.{key}");
        assert!(v["bytes"].get(key).is_some(), "bytes.{key}");
    }
    let (l1, l2) = (
        v["bases"]["l1"].as_f64().unwrap(),
        v["bases"]["l2"].as_f64().unwrap(),
    );
    assert!(0.0 < l2 && l2 < l1 && l1 < 1.0, "l1 {l1} l2 {l2}");
    assert_eq!(v["bytes"]["l1"], 13);
    assert!(v.get("window").is_some());
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let o = probekit(&["sh", "builtin:sky", "--compare"]);
    let table = stdout(&o);
    assert!(
        table.contains("zh3_hallucinated") && table.contains("ambient_cube"),
        "{table}"
    );
}

fn assert_one_line_error(o: &Output, file: &Path, what: &str) {
    assert_eq!(o.status.code(), Some(1), "exit code");
    let err = String::from_utf8(o.stderr.clone()).unwrap();
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(
        err.contains(&file.display().to_string()),
        "names the file: {err}"
    );
    assert!(err.contains(what), "says {what}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(o.stdout.is_empty());
}

#[test]
fn sh_bad_inputs_fail_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let text = dir.path().join("notes.hdr");
    std::fs::write(&text, "not an image\n").unwrap();
    assert_one_line_error(
        &probekit(&["sh", text.to_str().unwrap()]),
        &text,
        "not a readable image",
    );
    let missing: PathBuf = dir.path().join("missing.exr");
    assert_one_line_error(
        &probekit(&["sh", missing.to_str().unwrap()]),
        &missing,
        "cannot read",
    );
    // an empty folder is not a cubemap
    assert_one_line_error(
        &probekit(&["sh", dir.path().to_str().unwrap(), "--json"]),
        dir.path(),
        "face +X missing",
    );
}

/// A cubemap folder (six `.exr` faces) of a constant radiance: the DC
/// coefficient is `L·√(4π)` and the rest vanish (exact cube solid angles).
#[test]
fn sh_on_cubemap_folder() {
    use probekit::env::EnvMap;
    let dir = tempfile::tempdir().unwrap();
    for stem in ["px", "nx", "py", "ny", "pz", "nz"] {
        let face = EnvMap::from_texels(
            Path::new(stem),
            8,
            8,
            vec![glam::Vec3::new(1.0, 0.5, 0.25); 64],
        )
        .unwrap();
        face.save_exr(dir.path().join(format!("{stem}.exr")))
            .unwrap();
    }
    let o = probekit(&["sh", dir.path().to_str().unwrap(), "--order", "2", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_str(stdout(&o).trim()).unwrap();
    let c = v["coefficients"].as_array().unwrap();
    let s = (4.0 * std::f64::consts::PI).sqrt();
    for (ch, l) in [1.0, 0.5, 0.25].iter().enumerate() {
        assert!((c[0][ch].as_f64().unwrap() - l * s).abs() < 1e-4);
        for ck in &c[1..4] {
            assert!(ck[ch].as_f64().unwrap().abs() < 1e-5);
        }
    }
}
