//! End-to-end tests of `probekit volume` and `probekit export`.

use std::process::{Command, Output};

fn probekit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_probekit"))
        .args(args)
        .output()
        .expect("run probekit")
}

/// Uniform bake: the JSON counts match the resolution, the file's bytes are
/// the sum of its sections, gradients add 3× the coefficient bytes; export to
/// KTX2 (f16 and quantized) and Bevy writes the expected files.
#[test]
fn volume_bake_and_export() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("u.probes");
    let o = probekit(&[
        "volume",
        "builtin:lights-demo",
        "-o",
        out.to_str().unwrap(),
        "--layout",
        "uniform",
        "--resolution",
        "5,4,3",
        "--gradients",
        "analytic",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["probes"], 60);
    assert_eq!(v["leaves"], 4 * 3 * 2);
    // `basis` is spelled as for clouds (`sh<order>/<codec name>`).
    assert_eq!(v["basis"], "sh3/f32");
    let by = v["bytes_by_section"].as_object().unwrap();
    let sum: u64 = by.values().map(|x| x.as_u64().unwrap()).sum();
    assert_eq!(sum, v["bytes"].as_u64().unwrap());
    assert_eq!(sum, std::fs::metadata(&out).unwrap().len());
    let (c, g) = (
        by["coefficients"].as_u64().unwrap(),
        by["gradients"].as_u64().unwrap(),
    );
    assert!(g >= 3 * (60 * 9 * 12) && c >= 60 * 9 * 12 && g < 3 * c + 64);

    let k = dir.path().join("k");
    let o = probekit(&[
        "export",
        out.to_str().unwrap(),
        "--format",
        "ktx2",
        "-o",
        k.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(k.join("volume.json").exists() && k.join("sh_f16_6.ktx2").exists());
    let b = dir.path().join("b.ktx2");
    let o = probekit(&[
        "export",
        out.to_str().unwrap(),
        "--format",
        "bevy",
        "-o",
        b.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(&b).unwrap();
    assert_eq!(&bytes[..4], &[0xAB, 0x4B, 0x54, 0x58]);
    // Rx × 2Ry × 3Rz texels.
    let w = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
    assert_eq!((w(20), w(24), w(28)), (5, 8, 9));
    assert!(dir.path().join("b.json").exists());
}

/// `probekit volume builtin:lights-demo -o x.probes` followed by `rest`.
fn lights_demo(rest: &[&'static str]) -> Vec<&'static str> {
    let mut v = vec!["volume", "builtin:lights-demo", "-o", "x.probes"];
    v.extend_from_slice(rest);
    v
}

/// Adaptive bake and bad input: one line naming the problem, exit code 1.
#[test]
fn volume_adaptive_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.probes");
    let o = probekit(&[
        "volume",
        "builtin:lights-demo",
        "-o",
        out.to_str().unwrap(),
        "--layout",
        "octree",
        "--set",
        "volume.min_depth=1",
        "--max-depth",
        "3",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["probes"].as_u64().unwrap() > 27 && v["probes"].as_u64().unwrap() <= 9 * 9 * 9);
    // The lights demo's box is a cube: one root; an explicit root grid is
    // kept and reported.
    assert_eq!(v["roots"], serde_json::json!([1, 1, 1]));
    let f = dir.path().join("f.probes");
    let o = probekit(&[
        "volume",
        "builtin:lights-demo",
        "-o",
        f.to_str().unwrap(),
        "--layout",
        "octree",
        "--set",
        "volume.roots=[2,1,3]",
        "--max-depth",
        "1",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["roots"], serde_json::json!([2, 1, 3]));
    assert_eq!(v["probes"], 5 * 3 * 7);
    // An octree exports as a brick atlas on request: indirection texture,
    // atlas textures and a sidecar that says so.
    let k = dir.path().join("bricks");
    let o = probekit(&[
        "export",
        out.to_str().unwrap(),
        "--format",
        "ktx2",
        "--layout",
        "bricks",
        "-o",
        k.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let side: serde_json::Value =
        serde_json::from_slice(&std::fs::read(k.join("volume.json")).unwrap()).unwrap();
    assert_eq!(side["format"], "probekit-volume-bricks");
    assert!(side["bricks"].as_u64().unwrap() >= 1);
    assert!(k.join("indirection_rgba8ui.ktx2").exists() && k.join("sh_f16_0.ktx2").exists());
    let u = dir.path().join("u.probes");
    let o = probekit(&[
        "volume",
        "builtin:lights-demo",
        "-o",
        u.to_str().unwrap(),
        "--layout",
        "uniform",
        "--resolution",
        "2,2,2",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (us, ks) = (
        u.to_str().unwrap().to_string(),
        k.join("u").to_str().unwrap().to_string(),
    );
    for args in [
        vec![
            "export", &us, "--format", "ktx2", "--layout", "bricks", "-o", &ks,
        ],
        vec![
            "export", &us, "--format", "ktx2", "--layout", "sparse", "-o", &ks,
        ],
        vec![
            "volume", "nope", "-o", "x.probes", "--layout", "uniform", "--cell", "1",
        ],
        lights_demo(&["--layout", "uniform"]),
        lights_demo(&["--layout", "uniform", "--resolution", "1,2"]),
        vec![
            "export",
            "missing.probes",
            "--format",
            "bevy",
            "-o",
            "x.ktx2",
        ],
        lights_demo(&["--layout", "octree", "--set", "volume.roots=[0,1,1]"]),
        lights_demo(&["--layout", "octree", "--set", "volume.roots=[2,1]"]),
        lights_demo(&[
            "--layout",
            "uniform",
            "--cell",
            "1",
            "--set",
            "volume.gradients.step=0.1",
        ]),
        lights_demo(&[
            "--layout",
            "uniform",
            "--cell",
            "1",
            "--gradients",
            "central",
            "--set",
            "volume.gradients.step=-0.1",
        ]),
        lights_demo(&[
            "--layout",
            "uniform",
            "--cell",
            "1",
            "--gradients",
            "analytic",
            "--set",
            "volume.gradients.order=0",
        ]),
        lights_demo(&[
            "--layout",
            "uniform",
            "--cell",
            "1",
            "--set",
            "volume.gradients.order=2",
        ]),
    ] {
        let o = probekit(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.starts_with("error: "), "{err}");
    }
}

/// A path-traced volume of the demo scene: `volume builtin:demo --uniform
/// --resolution 3,3,3 --samples 16` writes 27 samples (walls on the box faces
/// dilated, never black), `--plot` writes a PNG, and `eval` on the file
/// returns finite JSON; `--gradients analytic` is refused with one line.
#[test]
fn volume_of_a_path_traced_scene_evaluates() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d.probes");
    let png = dir.path().join("d.png");
    let o = probekit(&[
        "volume",
        "builtin:demo",
        "-o",
        out.to_str().unwrap(),
        "--layout",
        "uniform",
        "--resolution",
        "3,3,3",
        "--samples",
        "16",
        "--plot",
        png.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["probes"], 27);
    assert_eq!(v["captures"], 27);
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    let o = probekit(&[
        "eval",
        out.to_str().unwrap(),
        "--scene",
        "builtin:demo",
        "--points",
        "10",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let e: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for k in ["rel_rmse", "p95_rel_error"] {
        let x = e[k].as_f64().unwrap();
        assert!(x.is_finite() && x >= 0.0, "{k} = {x}");
    }
    let o = probekit(&[
        "volume",
        "builtin:demo",
        "-o",
        out.to_str().unwrap(),
        "--layout",
        "uniform",
        "--resolution",
        "2,2,2",
        "--samples",
        "4",
        "--gradients",
        "analytic",
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("builtin:demo") && err.contains("closed-form"),
        "{err}"
    );
}

/// Export options of one format are refused with another (exit code 1,
/// the flag named), and nothing is written.
#[test]
fn export_options_of_another_format_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let v = dir.path().join("v.probes");
    let v = v.to_str().unwrap();
    let grid = ["--layout", "uniform", "--resolution", "3,3,3"];
    let o = probekit(&[&["volume", "builtin:lights-demo", "-o", v][..], &grid].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.path().join("x.ktx2");
    let x = out.to_str().unwrap();
    for (args, flag) in [
        (
            &["--format", "bevy", "--encoding", "quantized"][..],
            "--encoding",
        ),
        (&["--format", "bevy", "--layout", "dense"], "--layout"),
        (
            &["--format", "ktx2", "--resolution", "4,4,4"],
            "--resolution",
        ),
    ] {
        let mut all = vec!["export", v, "-o", x];
        all.extend_from_slice(args);
        let r = probekit(&all);
        assert_eq!(r.status.code(), Some(1), "{args:?} was accepted");
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(err.contains(&format!("{flag} applies to")), "{err}");
        assert!(!out.exists());
    }
}

/// The adaptive octree's keys with `--layout uniform`, and the uniform
/// grid's with `--layout octree`, are refused (exit code 1, one line naming
/// the key and the layout) rather than ignored, and nothing is written.
#[test]
fn volume_options_of_the_other_layout_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("v.probes");
    let o = out.to_str().unwrap();
    for (args, key) in [
        (
            &[
                "--layout",
                "uniform",
                "--resolution",
                "3,3,3",
                "--max-depth",
                "2",
            ][..],
            "volume.max_depth",
        ),
        (
            &["--cell", "1", "--set", "volume.tolerance=0.5"],
            "volume.tolerance",
        ),
        (
            &["--cell", "1", "--set", "volume.geometry=false"],
            "volume.geometry",
        ),
        (
            &["--layout", "octree", "--resolution", "3,3,3"],
            "volume.resolution",
        ),
        (&["--layout", "octree", "--cell", "0.5"], "volume.cell"),
    ] {
        let mut all = vec!["volume", "builtin:lights-demo", "-o", o];
        all.extend_from_slice(args);
        let r = probekit(&all);
        assert_eq!(r.status.code(), Some(1), "{args:?} was accepted");
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(
            err.contains(key) && err.contains("does not read it"),
            "{err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!out.exists());
    }
}
