//! End-to-end tests of `probekit rig --probes`: a baked volume written by
//! the test as the rig's lighting source.

use glam::Vec3;
use probekit_runtime::format::{
    Coefficients, ProbeFile, ProbeSet, VolumeFile, VolumeGrid, VolumeStructure,
};
use std::process::Command;

fn probekit() -> Command {
    Command::new(env!("CARGO_BIN_EXE_probekit"))
}

/// A 2 × 2 × 2 L2 volume around the car at the origin whose SH is affine
/// in position (trilinear interpolation reproduces it exactly).
fn affine_volume() -> Vec<u8> {
    let (lo, hi) = (Vec3::new(-3.0, -1.0, -2.0), Vec3::new(3.0, 2.5, 2.0));
    let mut pos = Vec::new();
    let mut coeffs = Vec::new();
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..2 {
                let p = Vec3::new([lo.x, hi.x][i], [lo.y, hi.y][j], [lo.z, hi.z][k]);
                pos.push(p);
                for c in 0..9 {
                    let base = if c == 0 { 3.0 } else { 0.2 / c as f32 };
                    coeffs.push(
                        Vec3::splat(base)
                            + Vec3::new(0.1, -0.05, 0.08) * p.x
                            + Vec3::new(0.03, 0.06, -0.02) * p.y
                            + Vec3::new(-0.04, 0.02, 0.05) * p.z * (c as f32 + 1.0) / 9.0,
                    );
                }
            }
        }
    }
    let f = ProbeFile::Volume(VolumeFile::new(
        ProbeSet::new(pos, Coefficients::from_f32(3, &coeffs).unwrap()),
        VolumeStructure::Uniform(VolumeGrid {
            min: lo,
            max: hi,
            resolution: [2, 2, 2],
        }),
    ));
    f.to_bytes().unwrap()
}

fn rel_rmse(args: &[&str]) -> f64 {
    let out = probekit().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    v["rel_rmse"].as_f64().unwrap()
}

/// With only the baked file (no --scene), the gradient rig reproduces an
/// affine field (error at f32 round-off), the constant rig does not.
#[test]
fn rig_from_affine_volume() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("vol.probes");
    std::fs::write(&p, affine_volume()).unwrap();
    let ps = p.to_str().unwrap();
    let base = [
        "rig",
        "builtin:car",
        "--probes",
        ps,
        "--samples",
        "64",
        "--split",
        "off",
        "--json",
        "--rig",
    ];
    let g = rel_rmse(&[&base[..], &["gradient"]].concat());
    let c = rel_rmse(&[&base[..], &["constant"]].concat());
    assert!(g < 1e-4, "gradient {g}");
    assert!(c > 100.0 * g.max(1e-7), "constant {c}");
}

/// A missing probe file: one line naming it, exit code 1.
#[test]
fn rig_missing_probes_is_one_line_exit_1() {
    let out = probekit()
        .args([
            "rig",
            "builtin:car",
            "--probes",
            "/nonexistent/b.probes",
            "--rig",
            "constant",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("/nonexistent/b.probes"), "{err}");
}
