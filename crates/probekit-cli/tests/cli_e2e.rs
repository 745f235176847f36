//! End-to-end: the real `probekit` binary on `builtin:demo` with tiny sample
//! counts, checking each JSON shape, sharded bake + merge = unsharded bake
//! byte for byte, and one-line errors with exit code 1 on bad input.

mod common;
use common::{fails_one_line, json, run};
use serde_json::Value;

fn triple(v: &Value) -> bool {
    v.as_array()
        .is_some_and(|a| a.len() == 3 && a.iter().all(|x| x.as_f64().is_some_and(f64::is_finite)))
}

#[test]
fn sharded_bake_merges_to_the_unsharded_file() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    let common = [
        "bake",
        "--placement",
        "grid",
        "--budget",
        "30",
        "--samples",
        "64",
        "--set",
        "capture.bounces=1",
    ];
    let full = json(d, &[&common[..], &["-o", "full.probes", "--json"]].concat());
    assert_eq!(full["probes"], 30);
    assert!(full["bytes"].as_u64().unwrap() > 0);
    for i in 0..3 {
        let s = format!("{i}/3");
        let o = format!("p{i}.probes");
        json(
            d,
            &[&common[..], &["--shard", &s, "-o", &o, "--json"]].concat(),
        );
    }
    // Parts in any order.
    let m = run(
        d,
        &[
            "merge",
            "p2.probes",
            "p0.probes",
            "p1.probes",
            "-o",
            "m.probes",
            "--scene",
            "builtin:demo",
        ],
    );
    assert!(m.status.success(), "{}", String::from_utf8_lossy(&m.stderr));
    let a = std::fs::read(d.join("full.probes")).unwrap();
    let b = std::fs::read(d.join("m.probes")).unwrap();
    assert!(a == b, "merged file differs from the unsharded bake");
    // Cell visibility spans every probe: merge bakes it, from the same
    // scene — the one the parts recorded when none is given.
    std::fs::write(d.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let merge = [
        "merge",
        "p0.probes",
        "p1.probes",
        "p2.probes",
        "-o",
        "x.probes",
    ];
    let m = run(d, &merge);
    assert!(m.status.success(), "{}", String::from_utf8_lossy(&m.stderr));
    assert!(std::fs::read(d.join("x.probes")).unwrap() == a);
    std::fs::remove_file(d.join("x.probes")).unwrap();
    fails_one_line(
        d,
        &[&merge[..], &["--scene", "tri.obj"]].concat(),
        "p0.probes was baked from builtin:demo (lighting hash",
    );
    // A gap, an overlap and a different setting are refused.
    fails_one_line(
        d,
        &["merge", "p0.probes", "p2.probes", "-o", "x.probes"],
        "gap",
    );
    fails_one_line(
        d,
        &[
            "merge",
            "p0.probes",
            "p0.probes",
            "p1.probes",
            "p2.probes",
            "-o",
            "x.probes",
        ],
        "overlaps",
    );
    json(
        d,
        &[
            "bake",
            "--placement",
            "grid",
            "--budget",
            "30",
            "--samples",
            "32",
            "--set",
            "capture.bounces=1",
            "--shard",
            "1/3",
            "-o",
            "q1.probes",
            "--json",
        ],
    );
    fails_one_line(
        d,
        &[
            "merge",
            "p0.probes",
            "q1.probes",
            "p2.probes",
            "-o",
            "x.probes",
        ],
        "different",
    );
}

#[test]
fn json_shapes_and_bad_input() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    json(
        d,
        &[
            "bake",
            "--placement",
            "grid",
            "--budget",
            "40",
            "--samples",
            "64",
            "--set",
            "capture.bounces=1",
            "-o",
            "c.probes",
            "--json",
        ],
    );
    let i = json(d, &["inspect", "c.probes", "--json"]);
    assert!(i["probes"].as_u64().unwrap() >= 24);
    assert!(i["tetrahedra"].as_u64().unwrap() > 0);
    // A grid's outer probes are exactly co-planar: no sliver on the hull.
    assert_eq!(i["hull_slivers"], 0);
    assert!(i["basis"].is_string());
    let by = i["bytes_by_section"].as_object().unwrap();
    let sum: u64 = by.values().map(|v| v.as_u64().unwrap()).sum();
    assert_eq!(i["bytes"].as_u64().unwrap(), sum);
    assert_eq!(
        i["bytes"].as_u64().unwrap(),
        std::fs::metadata(d.join("c.probes")).unwrap().len()
    );
    assert_eq!(i["recipe"]["placement"]["method"], "grid");

    let q = json(
        d,
        &[
            "query", "c.probes", "--at", "2,1,2", "--normal", "0,1,0", "--json",
        ],
    );
    assert!(triple(&q["irradiance"]));
    std::fs::write(
        d.join("pts.csv"),
        "x,y,z,nx,ny,nz\n2,1,2,0,1,0\n1,1.5,1,1,0,0\n",
    )
    .unwrap();
    let q = json(d, &["query", "c.probes", "--points", "pts.csv", "--json"]);
    let rows = q["irradiance"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(triple));

    let c = json(
        d,
        &[
            "capture",
            "builtin:demo",
            "--at",
            "2,1,2",
            "--order",
            "2",
            "--samples",
            "64",
            "--json",
        ],
    );
    let co = c["coefficients"].as_array().unwrap();
    assert_eq!(co.len(), 4);
    assert!(co.iter().all(triple));
    assert!(c["validity"]["backface_fraction"].is_number());
    assert!(c["validity"]["valid"].is_boolean());

    let r = json(
        d,
        &[
            "reference",
            "builtin:demo",
            "--points",
            "pts.csv",
            "--samples",
            "256",
            "--json",
        ],
    );
    let rows = r["irradiance"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(triple));

    let cv = json(
        d,
        &[
            "convert",
            "c.probes",
            "--codec",
            "l1",
            "-o",
            "l1.probes",
            "--json",
        ],
    );
    assert!(cv["bytes_after"].as_u64().unwrap() < cv["bytes_before"].as_u64().unwrap());
    let rel = cv["rel_rmse"].as_f64().unwrap();
    assert!(rel > 0.0 && rel < 1.0, "{rel}");
    let cv = json(
        d,
        &[
            "convert",
            "c.probes",
            "--codec",
            "f32",
            "-o",
            "same.probes",
            "--json",
        ],
    );
    assert_eq!(cv["rel_rmse"].as_f64().unwrap(), 0.0);

    let e = run(
        d,
        &["export", "c.probes", "--format", "json", "-o", "c.json"],
    );
    assert!(e.status.success());
    let ej: Value = serde_json::from_slice(&std::fs::read(d.join("c.json")).unwrap()).unwrap();
    assert_eq!(
        ej["probes"].as_array().unwrap().len() as u64,
        i["probes"].as_u64().unwrap()
    );
    assert_eq!(ej["probes"][0]["sh"].as_array().unwrap().len(), 9);
    assert_eq!(
        ej["tetrahedra"].as_array().unwrap().len() as u64,
        i["tetrahedra"].as_u64().unwrap()
    );
    // The outer cells' hull faces are the tetrahedra's faces that no other
    // tetrahedron shares, counted here from the exported tetrahedra alone.
    let index = |v: &Value| v.as_u64().unwrap() as u32;
    let mut faces = std::collections::HashMap::<[u32; 3], usize>::new();
    for t in ej["tetrahedra"].as_array().unwrap() {
        let t: Vec<u32> = t.as_array().unwrap().iter().map(index).collect();
        for skip in 0..4 {
            let mut f: Vec<u32> = (0..4).filter(|&k| k != skip).map(|k| t[k]).collect();
            f.sort_unstable();
            *faces.entry([f[0], f[1], f[2]]).or_default() += 1;
        }
    }
    let mut once: Vec<[u32; 3]> = faces
        .into_iter()
        .filter(|e| e.1 == 1)
        .map(|e| e.0)
        .collect();
    let mut hull: Vec<[u32; 3]> = ej["outer_cells"]["hull_faces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let mut f: Vec<u32> = f.as_array().unwrap().iter().map(index).collect();
            f.sort_unstable();
            [f[0], f[1], f[2]]
        })
        .collect();
    once.sort_unstable();
    hull.sort_unstable();
    assert!(!hull.is_empty());
    assert_eq!(hull, once);
    assert!(ej["outer_cells"]["rule"].as_str().unwrap().contains("hull"));
    // Volume-only options are refused for a cloud rather than ignored.
    fails_one_line(
        d,
        &[
            "export", "c.probes", "--format", "json", "-o", "x.json", "--layout", "dense",
        ],
        "--layout applies",
    );
    assert!(!d.join("x.json").exists());
    let e = run(d, &["export", "c.probes", "--format", "csv", "-o", "c.csv"]);
    assert!(e.status.success());
    let csv = std::fs::read_to_string(d.join("c.csv")).unwrap();
    assert!(csv.starts_with("x,y,z,c0_r,c0_g,c0_b,"));
    assert_eq!(
        csv.lines().count() as u64,
        i["probes"].as_u64().unwrap() + 1
    );

    fails_one_line(d, &["inspect", "missing.probes"], "missing.probes");
    std::fs::write(d.join("bad.probes"), b"PROBEKIT garbage").unwrap();
    fails_one_line(d, &["query", "bad.probes", "--at", "0,0,0"], "bad.probes");
    std::fs::write(d.join("nan.csv"), "1,2,3\n1,nan,3\n").unwrap();
    fails_one_line(
        d,
        &["bake", "--positions", "nan.csv", "--samples", "8"],
        "nan.csv: line 2",
    );
    fails_one_line(d, &["query", "c.probes", "--points", "nan.csv"], "nan.csv");
    fails_one_line(d, &["bake", "--shard", "3/3", "--samples", "8"], "--shard");
}

/// Issue 5's bad probe sets through `--positions` (all in free space of
/// `builtin:demo`, away from its sphere light, so no probe is moved):
/// fewer than 4 distinct positions and co-planar ones fail, before any
/// capture, with one line naming the CSV and the cause, and write nothing; a repeated position
/// bakes, with a warning that names the merged probe, and `inspect` counts
/// it.
#[test]
fn manual_probe_sets_degenerate_and_duplicate() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    let bake = |csv: &'static str, out: &'static str| {
        [
            "bake",
            "--positions",
            csv,
            "--samples",
            "8",
            "--set",
            "capture.bounces=1",
            "-o",
            out,
        ]
    };
    let rows = |r: &[[f32; 3]]| {
        r.iter()
            .map(|p| format!("{},{},{}\n", p[0], p[1], p[2]))
            .collect::<String>()
    };
    let a = [2.0, 0.5, 2.0];
    let b = [3.0, 0.5, 2.0];
    let c = [2.0, 0.5, 3.0];
    let e = [3.0, 0.5, 3.0];
    let up = [3.0, 1.5, 3.0];
    std::fs::write(d.join("three.csv"), rows(&[a, b, c, a])).unwrap();
    std::fs::write(d.join("flat.csv"), rows(&[a, b, c, e, [2.5, 0.5, 2.5]])).unwrap();
    std::fs::write(d.join("dup.csv"), rows(&[a, b, c, up, b])).unwrap();
    fails_one_line(
        d,
        &bake("three.csv", "three.probes"),
        "three.csv: the probe positions cannot be tetrahedralized: need at least 4 distinct probe positions, got 3",
    );
    fails_one_line(
        d,
        &bake("flat.csv", "flat.probes"),
        "flat.csv: the probe positions cannot be tetrahedralized: all probe positions are co-planar",
    );
    assert!(!d.join("three.probes").exists() && !d.join("flat.probes").exists());

    let o = run(d, &bake("dup.csv", "dup.probes"));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8(o.stderr).unwrap();
    assert!(
        err.contains("warning: dup.probes: 1 probe(s) share a position with another")
            && err.contains("probe 4 at 3, 0.5, 2"),
        "{err}"
    );
    let i = json(d, &["inspect", "dup.probes", "--json"]);
    assert_eq!(i["probes"], 5);
    assert_eq!(i["unused_probes"], 1);
    // Four distinct, non-co-planar positions: one tetrahedron.
    assert_eq!(i["tetrahedra"], 1);
}

/// Flags a file kind or a command's mode would ignore are refused with a
/// one-line error: the volume's `--interp` on a cloud, the cloud's blend
/// flags on a volume (`query`, `render`), the sweep's `--budgets`/`--methods` without `--plot`,
/// `--samples` without a bake to set, and no evaluation points.
#[test]
fn ignored_flags_are_refused() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    let bake = [
        "bake",
        "--placement",
        "grid",
        "--budget",
        "12",
        "--samples",
        "16",
        "--set",
        "capture.bounces=1",
    ];
    json(d, &[&bake[..], &["-o", "c.probes", "--json"]].concat());
    let volume = [
        "volume",
        "builtin:demo",
        "-o",
        "v.probes",
        "--layout",
        "uniform",
    ];
    json(
        d,
        &[&volume[..], &["--resolution", "3,3,3", "--json"]].concat(),
    );
    let at = ["--at", "1,1.5,2", "--json"];
    json(d, &[&["query", "c.probes"][..], &at].concat());
    json(
        d,
        &[&["query", "v.probes", "--interp", "trilinear"][..], &at].concat(),
    );
    fails_one_line(
        d,
        &[&["query", "c.probes", "--interp", "trilinear"][..], &at].concat(),
        "probe cloud",
    );
    for flag in [
        &["--blend", "visibility=off"][..],
        &["--blend", "cell-visibility=off"],
        &["--blend", "probe-weights=off"],
        &["--blend", "bias=0.1"],
        &["--blend", "sharpness=4"],
        &["--blend", "brightness=1"],
        &["--blend", "directional=1"],
    ] {
        let args = [&["query", "v.probes"][..], flag, &at].concat();
        fails_one_line(d, &args, &format!("{} applies to probe clouds", flag[0]));
    }
    for flag in ["--brightness-weight", "--directional-brightness"] {
        let args = ["render", "--probes", "v.probes", "-o", "r.png", flag, "1"];
        fails_one_line(d, &args, &format!("{flag} applies to probe clouds"));
    }
    assert!(!d.join("r.png").exists());
    let eval = ["eval", "c.probes", "--scene", "builtin:demo", "--json"];
    for (extra, needle) in [
        (&["--budgets", "10,20"][..], "--budgets"),
        (&["--methods", "grid"], "--methods"),
        (&["--samples", "8"], "--samples"),
        (&["--points", "0"], "--points 0"),
        (&["--interp", "taylor"], "probe cloud"),
    ] {
        fails_one_line(d, &[&eval[..], extra].concat(), needle);
    }
    let v = json(
        d,
        &[
            &eval[..],
            &["--points", "20", "--compare", "grid", "--samples", "8"],
        ]
        .concat(),
    );
    assert_eq!(v["compare"]["grid"]["points"], 20);
}

/// Output paths are checked before the work: a missing folder or a folder
/// given as the file is reported first (before a later error the inputs
/// would give, here co-planar positions or a bad SH order), and nothing is
/// left behind.
#[test]
fn outputs_are_checked_before_the_work() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(d.join("flat.csv"), "0,1,0\n1,1,0\n0,1,1\n1,1,1\n").unwrap();
    let flat = ["bake", "--positions", "flat.csv", "-o"];
    let volume = [
        "volume",
        "builtin:demo",
        "--layout",
        "uniform",
        "--resolution",
        "3,3,3",
    ];
    let bad_order = ["--order", "99", "-o", "v.probes", "--plot", "missing/p.png"];
    for (args, needle) in [
        (
            [&flat[..], &["missing/x.probes"]].concat(),
            "missing/x.probes",
        ),
        ([&flat[..], &["."]].concat(), "is a directory"),
        ([&volume[..], &bad_order].concat(), "missing/p.png"),
        // With a writable output the same inputs fail on their own problem.
        ([&flat[..], &["x.probes"]].concat(), "co-planar"),
    ] {
        fails_one_line(d, &args, needle);
    }
    let left: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "flat.csv")
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn l1_files_record_how_an_engine_evaluates_them() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    let bake = |extra: &[&str], out: &str| {
        let mut args = vec![
            "bake",
            "--placement",
            "grid",
            "--budget",
            "24",
            "--samples",
            "32",
            "--set",
            "capture.bounces=1",
            "--set",
            "blend.distance_moments=0",
            "--set",
            "blend.cell_visibility=0",
            "--set",
            "blend.probe_weights=false",
            "-o",
            out,
            "--json",
        ];
        args.extend_from_slice(extra);
        json(d, &args)
    };
    bake(
        &["--codec", "l1", "--set", "l1_evaluation=zh3-hallucinated"],
        "zh3.probes",
    );
    let i = json(d, &["inspect", "zh3.probes", "--json"]);
    assert_eq!(i["basis"], "sh2/l1");
    assert_eq!(i["l1_evaluation"], "zh3-hallucinated");
    assert_eq!(i["recipe"]["l1_evaluation"], "zh3-hallucinated");
    bake(&["--codec", "l1"], "l1.probes");
    let i = json(d, &["inspect", "l1.probes", "--json"]);
    assert_eq!(i["l1_evaluation"], "linear");
    // Asking for it on an L2 bake is an error that names the key.
    fails_one_line(
        d,
        &[
            "bake",
            "--placement",
            "grid",
            "--budget",
            "24",
            "--set",
            "l1_evaluation=zh3-hallucinated",
            "-o",
            "bad.probes",
        ],
        "l1_evaluation",
    );
    assert!(!d.join("bad.probes").exists());
}

/// A reader that stops early (`probekit … | head`) ends the output quietly:
/// no panic message about the failed write.
#[cfg(unix)]
#[test]
fn a_closed_pipe_ends_the_output_quietly() {
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_probekit"))
        .arg("markdown-help")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
}
