//! End-to-end tests of `probekit rig`: the real binary in a temporary folder.

use std::process::Command;

fn probekit() -> Command {
    Command::new(env!("CARGO_BIN_EXE_probekit"))
}

/// `--json` prints exactly the documented object, with plausible values.
#[test]
fn rig_json_has_the_issue_shape() {
    let out = probekit()
        .args([
            "rig",
            "builtin:character",
            "--scene",
            "builtin:rig-demo",
            "--rig",
            "mixed:l2,g,c",
            "--at=1,0,-1",
            "--samples",
            "48",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let obj = v.as_object().unwrap();
    let mut keys: Vec<&str> = obj.keys().map(|k| k.as_str()).collect();
    keys.sort();
    assert_eq!(
        keys,
        [
            "lights",
            "max_error_grey_levels",
            "ns_per_frame",
            "parameters",
            "rel_rmse",
            "rig",
            "samples"
        ]
    );
    assert_eq!(v["rig"], "mixed:l2,g,c");
    assert_eq!(v["parameters"], 4);
    assert_eq!(v["samples"], 48);
    let l = &v["lights"];
    let total = l["analytic"].as_u64().unwrap()
        + l["transition"].as_u64().unwrap()
        + l["rig"].as_u64().unwrap();
    assert_eq!(total, 8);
    let e = v["rel_rmse"].as_f64().unwrap();
    assert!((0.0..0.5).contains(&e), "{e}");
}

/// `--render` writes the comparison and the zone pictures; `--split off`
/// puts every light in the rig.
#[test]
fn rig_render_writes_two_pngs() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("fig.png");
    let out = probekit()
        .args([
            "rig",
            "builtin:character",
            "--scene",
            "builtin:rig-demo",
            "--rig",
            "gradient",
            "--samples",
            "32",
            "--split",
            "off",
            "--json",
            "--render",
        ])
        .arg(&png)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["lights"]["rig"], 8);
    // --out writes a rig-only .probes file that starts with the magic.
    let probes = dir.path().join("car.probes");
    let out = probekit()
        .args([
            "rig",
            "builtin:character",
            "--scene",
            "builtin:rig-demo",
            "--rig",
            "gradient",
            "--samples",
            "16",
            "--out",
        ])
        .arg(&probes)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(&std::fs::read(&probes).unwrap()[..8], b"PROBEKIT");
    for p in [png.clone(), dir.path().join("fig_zones.png")] {
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(&bytes[1..4], b"PNG", "{}", p.display());
    }
}

/// Bad input: one line on stderr naming the problem, exit code 1.
#[test]
fn rig_bad_input_is_one_line_exit_1() {
    for (args, needle) in [
        (
            vec![
                "rig",
                "builtin:car",
                "--scene",
                "builtin:rig-demo",
                "--rig",
                "lattice:2x2",
            ],
            "lattice",
        ),
        (
            vec![
                "rig",
                "builtin:boat",
                "--scene",
                "builtin:rig-demo",
                "--rig",
                "constant",
            ],
            "builtin:boat",
        ),
        (
            vec![
                "rig",
                "builtin:car",
                "--scene",
                "/nonexistent/s.toml",
                "--rig",
                "constant",
            ],
            "/nonexistent/s.toml",
        ),
        (
            vec![
                "rig",
                "builtin:car",
                "--scene",
                "builtin:rig-demo",
                "--rig",
                "constant",
                "--at",
                "1,2",
            ],
            "--at",
        ),
    ] {
        let out = probekit().args(&args).output().unwrap();
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains(needle), "{err}");
    }
}

/// `--interp` is the volume's: refused without `--probes` (exit code 2,
/// from the argument parser) and with a probe cloud (exit code 1, the
/// file named), rather than ignored.
#[test]
fn rig_interp_needs_a_volume() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = dir.path().join("c.probes");
    let c = cloud.to_str().unwrap();
    let bake = probekit()
        .args([
            "bake",
            "--placement",
            "grid",
            "--budget",
            "12",
            "--samples",
            "16",
            "--set",
            "capture.bounces=1",
        ])
        .args([
            "--set",
            "blend.distance_moments=0",
            "--set",
            "blend.cell_visibility=0",
        ])
        .args(["--set", "blend.probe_weights=false", "-o", c])
        .output()
        .unwrap();
    assert!(
        bake.status.success(),
        "{}",
        String::from_utf8_lossy(&bake.stderr)
    );
    let rig = ["rig", "builtin:car", "--rig", "constant", "--samples", "16"];
    let no_probes = probekit()
        .args(rig)
        .args(["--scene", "builtin:rig-demo", "--interp", "taylor"])
        .output()
        .unwrap();
    assert_eq!(no_probes.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&no_probes.stderr).contains("--probes"));
    let on_cloud = probekit()
        .args(rig)
        .args(["--probes", c, "--interp", "trilinear"])
        .output()
        .unwrap();
    assert_eq!(on_cloud.status.code(), Some(1));
    let err = String::from_utf8_lossy(&on_cloud.stderr);
    assert!(
        err.contains("c.probes") && err.contains("probe cloud"),
        "{err}"
    );
    let plain = probekit()
        .args(rig)
        .args(["--probes", c, "--json"])
        .output()
        .unwrap();
    assert!(
        plain.status.success(),
        "{}",
        String::from_utf8_lossy(&plain.stderr)
    );
}
