//! End-to-end tests of the spawn-and-merge and gradient-ascent placements
//! (`bake --placement spawn-and-merge|gradient-ascent`) and of `eval --compare grid` / `--plot`.

use std::path::Path;
use std::process::{Command, Output};

fn probekit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_probekit"))
        .args(args)
        .output()
        .expect("run probekit")
}

/// A floor slab and a wall (OBJ, outward CCW) under a low sun and a grey sky.
fn write_scene(dir: &Path) -> String {
    let cube = |lo: [f32; 3], hi: [f32; 3], base: usize| {
        let mut s = String::new();
        for (x, y, z) in [
            (lo[0], lo[1], lo[2]),
            (hi[0], lo[1], lo[2]),
            (hi[0], hi[1], lo[2]),
            (lo[0], hi[1], lo[2]),
            (lo[0], lo[1], hi[2]),
            (hi[0], lo[1], hi[2]),
            (hi[0], hi[1], hi[2]),
            (lo[0], hi[1], hi[2]),
        ] {
            s += &format!("v {x} {y} {z}\n");
        }
        for q in [
            [1, 2, 6, 5],
            [4, 8, 7, 3],
            [1, 4, 3, 2],
            [5, 6, 7, 8],
            [1, 5, 8, 4],
            [2, 3, 7, 6],
        ] {
            let q = q.map(|i| i + base);
            s += &format!(
                "f {} {} {}\nf {} {} {}\n",
                q[0], q[1], q[2], q[0], q[2], q[3]
            );
        }
        s
    };
    let mut obj = String::from("o floor\n");
    obj += &cube([-1.0, -0.2, -1.0], [5.0, 0.0, 4.0], 0);
    obj += "o wall\n";
    obj += &cube([2.0, 0.0, -1.0], [2.2, 1.5, 2.0], 8);
    std::fs::write(dir.join("corner.obj"), obj).unwrap();
    let toml = r#"
[[mesh]]
path = "corner.obj"

[[light]]
kind = "directional"
direction = [1, -1, 0.3]
intensity = 3

[environment]
color = [0.2, 0.2, 0.2]

[bake]
box = [[0, 0.05, 0], [4, 2, 3]]
samples = 16
bounces = 1
"#;
    let p = dir.join("corner.toml");
    std::fs::write(&p, toml).unwrap();
    p.to_str().unwrap().to_string()
}

fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn seed_placements_bake_and_record_their_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    // `--directions` is spawn-merge's (gradient-ascent refuses it).
    for (method, key, extra) in [
        (
            "spawn-and-merge",
            "contrast",
            &["--set", "placement.directions=6"][..],
        ),
        ("gradient-ascent", "step", &[]),
    ] {
        let out = dir.path().join(format!("{method}.probes"));
        let mut args = vec!["bake", &scene, "--placement", method, "--budget", "24"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["-o", out.to_str().unwrap(), "--json"]);
        let v = json(&probekit(&args));
        let n = v["probes"].as_u64().unwrap();
        assert!(n >= 4, "{method}: {v}");
        let i = json(&probekit(&["inspect", out.to_str().unwrap(), "--json"]));
        let pl = &i["recipe"]["placement"];
        assert_eq!(pl["method"], method, "{i}");
        assert!(pl[key].is_number(), "{i}");
        assert_eq!(i["placed"]["count"].as_u64(), Some(n), "{i}");
    }
    let sm = dir.path().join("spawn-and-merge.probes");
    let i = json(&probekit(&["inspect", sm.to_str().unwrap(), "--json"]));
    assert_eq!(i["recipe"]["placement"]["directions"], 6);
    // Bad input: one line naming the problem, exit code 1.
    for args in [
        vec!["bake", scene.as_str(), "--placement", "nope"],
        vec![
            "bake",
            scene.as_str(),
            "--placement",
            "spawn-and-merge",
            "--set",
            "placement.directions=7",
        ],
        vec![
            "bake",
            scene.as_str(),
            "--placement",
            "spawn-and-merge",
            "--set",
            "placement.contrast=2",
        ],
    ] {
        let o = probekit(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert!(!String::from_utf8_lossy(&o.stderr).trim().is_empty());
    }
}

/// `bake --seed` seeds adaptive placement too (its pool jitter, spawns and
/// captures): another seed, other positions; the same seed, the same bytes.
#[test]
fn bake_seed_seeds_adaptive_placement() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let bake = |seed: &str, name: &str| {
        let out = dir.path().join(name);
        json(&probekit(&[
            "bake",
            &scene,
            "--budget",
            "16",
            "--seed",
            seed,
            "--set",
            "blend.distance_moments=0",
            "--set",
            "blend.cell_visibility=0",
            "-o",
            out.to_str().unwrap(),
            "--json",
        ]));
        out
    };
    let positions = |p: &Path| {
        let j = dir.path().join("export.json");
        let o = probekit(&[
            "export",
            p.to_str().unwrap(),
            "--format",
            "json",
            "-o",
            j.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&j).unwrap()).unwrap();
        v["probes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p["position"].to_string())
            .collect::<Vec<_>>()
    };
    let (a, a2, b) = (
        bake("1", "a.probes"),
        bake("1", "a2.probes"),
        bake("2", "b.probes"),
    );
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&a2).unwrap());
    assert_ne!(positions(&a), positions(&b));
}

#[test]
fn eval_compare_and_sweep_plot() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let probes = dir.path().join("g.probes");
    json(&probekit(&[
        "bake",
        &scene,
        "--placement",
        "grid",
        "--budget",
        "20",
        "-o",
        probes.to_str().unwrap(),
        "--json",
    ]));
    let p = probes.to_str().unwrap();
    let eval_compare = |f: &str, extra: &[&str]| {
        let mut args = vec![
            "eval",
            f,
            "--scene",
            &scene,
            "--points",
            "25",
            "--compare",
            "grid",
            "--json",
        ];
        args.extend_from_slice(extra);
        json(&probekit(&args))
    };
    let v = eval_compare(p, &[]);
    let g = &v["compare"]["grid"];
    assert!(v["rel_rmse"].as_f64().unwrap() >= 0.0, "{v}");
    assert!(g["rel_rmse"].as_f64().unwrap() >= 0.0, "{v}");
    assert!(
        g["p95_rel_error"].is_number() && g["leaks"].is_number(),
        "{v}"
    );
    assert_eq!(g["points"], v["points"]);
    // Leaks through geometry are some of the leaks, overall and per region;
    // so are the leaks at unlit points, some of those points.
    for f in [&v, g] {
        let (t, l) = (f["leaks_through_geometry"].as_u64(), f["leaks"].as_u64());
        assert!(t.unwrap() <= l.unwrap(), "{v}");
        let (u, ul) = (f["unlit_points"].as_u64(), f["leaks_unlit"].as_u64());
        assert!(ul.unwrap() <= u.unwrap().min(l.unwrap()), "{v}");
        // Points beyond the probes' hull, and their leaks, are some of each.
        let (o, ol) = (
            f["points_outside_hull"].as_u64(),
            f["leaks_outside_hull"].as_u64(),
        );
        assert!(o.unwrap() <= f["points"].as_u64().unwrap(), "{v}");
        assert!(ol.unwrap() <= o.unwrap().min(l.unwrap()), "{v}");
        for (_, r) in f["regions"].as_object().unwrap() {
            assert!(
                r["leaks_through_geometry"].as_u64() <= r["leaks"].as_u64(),
                "{r}"
            );
            assert!(
                r["leaks_outside_hull"].as_u64() <= r["leaks"].as_u64(),
                "{r}"
            );
        }
    }
    // A 20-probe grid's probes stand at cell centres, half a cell (about
    // 0.8 m) in from the box's faces: most of the box is beyond their hull.
    assert!(v["points_outside_hull"].as_u64().unwrap() > 0, "{v}");
    // `--worst K`: the points with the most squared error, worst first;
    // asked for more than there are, every point with an error, and their
    // shares add up to the whole (the file's and the grid's).
    assert!(v.get("worst").is_none(), "{v}");
    let w = eval_compare(p, &["--worst", "1000"]);
    assert_eq!(w["rel_rmse"], v["rel_rmse"]);
    for f in [&w, &w["compare"]["grid"]] {
        let list = f["worst"].as_array().unwrap();
        assert!(list.len() >= 2 && list.len() <= 25, "{f}");
        let e = |x: &serde_json::Value, k: &str| -> Vec<f64> {
            x[k].as_array()
                .unwrap()
                .iter()
                .map(|c| c.as_f64().unwrap())
                .collect()
        };
        // The squared error from the listed truth and prediction.
        let se = |x: &serde_json::Value| -> f64 {
            let (t, i) = (e(x, "truth"), e(x, "irradiance"));
            t.iter().zip(&i).map(|(a, b)| (a - b) * (a - b)).sum()
        };
        assert!(list.windows(2).all(|p| se(&p[0]) >= se(&p[1])), "{f}");
        let shares: Vec<f64> = list.iter().map(|x| x["share"].as_f64().unwrap()).collect();
        assert!(shares.windows(2).all(|s| s[0] >= s[1]), "{shares:?}");
        let total: f64 = shares.iter().sum();
        assert!((total - 1.0).abs() < 1e-4, "{total}");
        // Each share is its squared error over the sum of them.
        let sum: f64 = list.iter().map(se).sum();
        assert!((shares[0] - se(&list[0]) / sum).abs() < 1e-3, "{f}");
        assert_eq!(e(&list[0], "position").len(), 3);
        assert!(list[0]["regions"].is_array());
        // A cloud's points list the probes of their blend: weights that sum
        // to one, probes of the file.
        for x in list {
            let blend = x["blend"].as_array().unwrap();
            assert!(!blend.is_empty() && blend.len() <= 4, "{x}");
            let sum: f64 = blend.iter().map(|b| b["weight"].as_f64().unwrap()).sum();
            assert!((sum - 1.0).abs() < 1e-3, "{x}");
            for b in blend {
                assert!(b["probe"].as_u64().unwrap() < f["probes"].as_u64().unwrap());
                assert_eq!(e(b, "irradiance").len(), 3);
            }
        }
    }
    // A grid of the file's probe count, less cells inside the wall.
    let (gn, n) = (g["probes"].as_u64().unwrap(), v["probes"].as_u64().unwrap());
    assert!(gn >= 4 && gn <= n, "{v}");
    // The grid is baked with the file's visibility data and probe weights
    // and blended with the same flags: `--no-visibility --no-probe-weights`
    // on a file with both gives the grid figures of a file baked without.
    let plain = dir.path().join("plain.probes");
    json(&probekit(&[
        "bake",
        &scene,
        "--placement",
        "grid",
        "--budget",
        "20",
        "--set",
        "blend.distance_moments=0",
        "--set",
        "blend.cell_visibility=0",
        "--set",
        "blend.probe_weights=false",
        "-o",
        plain.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(
        eval_compare(
            p,
            &["--blend", "visibility=off", "--blend", "probe-weights=off"]
        )["compare"]["grid"],
        eval_compare(plain.to_str().unwrap(), &[])["compare"]["grid"]
    );
    let o = probekit(&[
        "eval",
        p,
        "--scene",
        &scene,
        "--points",
        "5",
        "--compare",
        "octree",
    ]);
    assert_eq!(o.status.code(), Some(1));

    let png = dir.path().join("sweep.png");
    let v = json(&probekit(&[
        "eval",
        p,
        "--scene",
        &scene,
        "--points",
        "20",
        "--plot",
        png.to_str().unwrap(),
        "--budgets",
        "12,24",
        "--methods",
        "grid,spawn-merge,gradient-ascent",
        "--json",
    ]));
    let rows = v["sweep"].as_array().unwrap();
    assert!(!rows.is_empty() && rows.len() <= 6, "{v}");
    for r in rows {
        assert!(r["probes"].as_u64().unwrap() >= 4, "{r}");
        assert!(r["rel_rmse"].as_f64().unwrap().is_finite(), "{r}");
        assert!(r["p95_rel_error"].is_number() && r["leaks"].is_number());
        assert!(
            ["grid", "spawn-and-merge", "gradient-ascent"].contains(&r["method"].as_str().unwrap())
        );
    }
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
}

/// `bake --light-shells auto` records its choice and both held-out errors
/// in the placement metadata; a bad mode is a one-line error, no file.
#[test]
fn bake_light_shells_auto_records_its_choice() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("auto.probes");
    let o = out.to_str().unwrap();
    let base = [
        "bake",
        "builtin:demo",
        "--budget",
        "24",
        "--samples",
        "32",
        "--set",
        "blend.distance_moments=0",
        "--set",
        "blend.cell_visibility=0",
        "--set",
        "blend.probe_weights=false",
        "-o",
        o,
    ];
    let bad = probekit(&[&base[..], &["--set", "placement.light_shells=maybe"]].concat());
    assert_eq!(bad.status.code(), Some(1));
    let msg = String::from_utf8_lossy(&bad.stderr);
    assert!(msg.contains("unknown variant `maybe`"), "{msg}");
    assert!(!out.exists());
    json(&probekit(
        &[
            &base[..],
            &["--set", "placement.light_shells=auto", "--json"],
        ]
        .concat(),
    ));
    let i = json(&probekit(&["inspect", o, "--json"]));
    assert_eq!(i["recipe"]["placement"]["light_shells"], "auto", "{i}");
    let p = &i["placed"];
    let e: Vec<f64> = p["held_out_error"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(e.len(), 2, "{i}");
    assert!(e.iter().all(|x| x.is_finite() && *x > 0.0), "{i}");
    assert_eq!(p["light_shells"].as_bool(), Some(e[1] < e[0]), "{i}");
    json(&probekit(
        &[&base[..], &["--set", "placement.light_shells=on", "--json"]].concat(),
    ));
    let i = json(&probekit(&["inspect", o, "--json"]));
    assert_eq!(i["recipe"]["placement"]["light_shells"], "on");
    assert!(i["placed"]["held_out_error"].is_null());
}

/// `--placement grid --budget N` is the grid `--set placement.budget=N`
/// gives, and keys the chosen method does not read are refused before any
/// capture, naming the key, the method and the keys it reads.
#[test]
fn bake_flags_fit_the_placement_or_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let bake = |extra: &[&str], name: &str| {
        let out = dir.path().join(name);
        let mut args = vec![
            "bake",
            &scene,
            "--samples",
            "16",
            "--set",
            "capture.bounces=1",
        ];
        args.extend_from_slice(&[
            "--set",
            "blend.distance_moments=0",
            "--set",
            "blend.cell_visibility=0",
            "--set",
            "blend.probe_weights=false",
        ]);
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--json", "-o"]);
        args.push(out.to_str().unwrap());
        let o = probekit(&args);
        (o, out)
    };
    let (by_budget, a) = bake(&["--placement", "grid", "--budget", "20"], "a.probes");
    let (by_key, b) = bake(
        &[
            "--set",
            "placement.method=grid",
            "--set",
            "placement.budget=20",
        ],
        "b.probes",
    );
    let (ja, jb) = (json(&by_budget), json(&by_key));
    assert_eq!(ja["probes"], jb["probes"]);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    // The default grid has about 256 probes: far more than 20.
    assert!(ja["probes"].as_u64().unwrap() < 60, "{ja}");

    let positions = dir.path().join("p.csv");
    std::fs::write(&positions, "0,1,0\n1,1,0\n0,2,0\n0,1,1\n").unwrap();
    let p = positions.to_str().unwrap();
    for (args, needle) in [
        (
            vec!["--placement", "grid", "--budget", "20", "--set", "placement.cell=0.5"],
            "not both",
        ),
        (
            vec!["--placement", "spawn-and-merge", "--set", "placement.cell=0.5"],
            "`placement.cell`: spawn-and-merge placement does not read it (grid placement reads it)",
        ),
        (
            vec!["--positions", p, "--budget", "20"],
            "manual placement does not read it",
        ),
        (
            vec!["--placement", "grid", "--positions", p],
            "cannot be used with",
        ),
        (
            vec!["--placement", "grid", "--set", "placement.tolerance=0.1"],
            "grid placement does not read it (adaptive placement reads it)",
        ),
        (
            vec!["--positions", p, "--set", "placement.light_shells=off"],
            "manual placement does not read it",
        ),
        (
            vec!["--placement", "spawn-and-merge", "--set", "placement.step=0.3"],
            "spawn-and-merge placement does not read it (gradient-ascent placement reads it)",
        ),
        (
            vec!["--placement", "gradient-ascent", "--set", "placement.contrast=0.3"],
            "gradient-ascent placement does not read it",
        ),
        (
            vec!["--set", "placement.max_iterations=2"],
            "adaptive placement does not read it",
        ),
        (
            vec!["--placement", "grid", "--budget", "20", "--shard", "0/2", "--render", "x.png"],
            "cannot be used with",
        ),
        (vec!["--set", "blend.fit.points=8"], "`blend.fit.points`"),
        (vec!["--set", "capture.samples=0"], "capture.samples"),
        (vec!["--placement", "grid", "--budget", "2"], "placement.budget"),
    ] {
        let (o, out) = bake(&args, "refused.probes");
        assert!(!o.status.success(), "{args:?} was accepted");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
}

/// Manual positions that span a volume as given but not once the virtual
/// offset has moved a probe out of a wall are refused before the capture,
/// with a message that says so, and nothing is written.
#[test]
fn manual_positions_flattened_by_the_virtual_offset_are_refused_before_capture() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    // Inside the wall (x 2–2.2): `capture` reports where the offset moves
    // it, with the same index (row 0), seed and pre-pass as the bake.
    let in_wall = "2.1,0.7,0.5";
    let c = json(&probekit(&["capture", &scene, "--at", in_wall, "--json"]));
    let moved = c["position"].as_array().unwrap();
    let x = moved[0].to_string();
    assert!(x.parse::<f32>().unwrap() < 2.0, "not moved out: {c}");
    // Three free points in the moved probe's plane x = const, beside the
    // wall: the four span a volume as given, a plane once it has moved.
    let csv = format!("{in_wall}\n{x},0.5,0.2\n{x},1.2,0.9\n{x},1.0,1.5\n");
    let positions = dir.path().join("p.csv");
    std::fs::write(&positions, csv).unwrap();
    let out = dir.path().join("m.probes");
    let o = probekit(&[
        "bake",
        &scene,
        "--positions",
        positions.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "accepted");
    assert!(err.contains("once the virtual offset"), "{err}");
    assert!(err.contains("co-planar"), "{err}");
    assert!(!out.exists());
}
