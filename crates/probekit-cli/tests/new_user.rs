//! What a new user hit, and what they get now: flat and huge requests
//! refused before any work, scenes of lights alone, the lighting hash that
//! keeps a file from being judged against another scene, progress in a
//! pipe, requests never silently changed, and small things (output named
//! after the scene, a `.glb` that is not one).

mod common;

use common::{fails_one_line, json, run};
use std::path::Path;
use std::process::Command;

/// A scene of one 4 × 4 m floor quad and a point light, no `[bake] box`.
fn flat_scene(d: &Path) {
    std::fs::write(
        d.join("floor.obj"),
        "v 0 0 0\nv 0 0 4\nv 4 0 4\nv 4 0 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    std::fs::write(
        d.join("flat.toml"),
        "[[mesh]]\npath = \"floor.obj\"\n[[light]]\nkind = \"point\"\nposition = [2, 1, 2]\nintensity = 10\n",
    )
    .unwrap();
}

/// A scene of a sphere lamp and a sky, no meshes, with a bake box (and
/// one without the box).
fn lights_scene(d: &Path) {
    let body = "[environment]\ncolor = [0.2, 0.3, 0.5]\n[[light]]\nkind = \"sphere\"\n\
                position = [0, 1, 0]\nradius = 0.1\nintensity = 10\n";
    std::fs::write(
        d.join("lights.toml"),
        format!("{body}[bake]\nbox = [[-1, 0, -1], [1, 2, 1]]\n"),
    )
    .unwrap();
    std::fs::write(d.join("nobox.toml"), body).unwrap();
}

/// Runs `probekit ARGS` in `dir` under a 2 GB address-space limit, so a
/// request that allocated without bound fails here rather than eat the
/// machine's memory.
fn run_limited(dir: &Path, args: &[&str]) -> std::process::Output {
    let cmd = "ulimit -v 2000000; exec \"$0\" \"$@\"";
    Command::new("bash")
        .arg("-c")
        .arg(cmd)
        .arg(env!("CARGO_BIN_EXE_probekit"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run probekit")
}

#[test]
fn a_flat_bake_box_is_refused_by_every_placement_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    flat_scene(d);
    for extra in [
        &[][..],
        &["--placement", "grid"],
        &["--placement", "spawn-and-merge"],
        &["--placement", "gradient-ascent"],
    ] {
        let args = [&["bake", "flat.toml", "-o", "f.probes"][..], extra].concat();
        let t = std::time::Instant::now();
        let o = run_limited(d, &args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("the bake box [0, 0, 0] – [4, 0, 4] is empty or flat"),
            "{args:?}: {err}"
        );
        // Refused before any capture: well under the time of one.
        assert!(t.elapsed().as_secs() < 20, "{args:?}");
        assert!(!d.join("f.probes").exists());
    }
    let o = run_limited(
        d,
        &[
            "volume",
            "flat.toml",
            "--layout",
            "octree",
            "-o",
            "v.probes",
        ],
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("is empty or flat"));
}

#[test]
fn budgets_above_the_cap_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    lights_scene(d);
    for (args, needle) in [
        (
            &["bake", "lights.toml", "--budget", "99999999999"][..],
            "adaptive budget 99999999999 is above the limit of 5000000 probes",
        ),
        (
            &[
                "bake",
                "lights.toml",
                "--placement",
                "grid",
                "--budget",
                "99999999999",
            ][..],
            "above the limit of 5000000 probes",
        ),
        (
            &[
                "bake",
                "lights.toml",
                "--placement",
                "grid",
                "--set",
                "placement.cell=0.0001",
            ][..],
            "above the limit of 5000000 probes",
        ),
    ] {
        let o = run_limited(d, args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

#[test]
fn a_scene_of_lights_alone_bakes_captures_and_evaluates_with_a_box() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    lights_scene(d);
    let b = json(
        d,
        &[
            "bake",
            "lights.toml",
            "--budget",
            "32",
            "--samples",
            "32",
            "--json",
        ],
    );
    assert!(b["probes"].as_u64().unwrap() >= 8, "{b}");
    assert_eq!(b["output"], "lights.probes");
    let c = json(d, &["capture", "lights.toml", "--at", "0,0.5,0", "--json"]);
    assert!(c["coefficients"][0][0].as_f64().unwrap() > 0.0);
    std::fs::write(d.join("pts.csv"), "0,0.5,0,0,1,0\n").unwrap();
    let r = json(
        d,
        &["reference", "lights.toml", "--points", "pts.csv", "--json"],
    );
    // A lamp of intensity 10 half a metre above an up-facing normal, plus
    // the sky's hemisphere: well above the sky alone (π·0.3 ≈ 0.9).
    assert!(r["irradiance"][0][1].as_f64().unwrap() > 10.0, "{r}");
    // eval defaults to the scene the file recorded.
    let e = json(d, &["eval", "lights.probes", "--points", "50", "--json"]);
    assert_eq!(e["points"], 50);
    let v = json(
        d,
        &[
            "volume",
            "lights.toml",
            "--layout",
            "uniform",
            "--resolution",
            "3,3,3",
            "--samples",
            "16",
            "-o",
            "v.probes",
            "--json",
        ],
    );
    assert_eq!(v["probes"], 27);
    // Without a box: what is missing, by name.
    for args in [
        &["bake", "nobox.toml", "--samples", "8"][..],
        &[
            "volume",
            "nobox.toml",
            "--layout",
            "octree",
            "-o",
            "v2.probes",
        ],
    ] {
        fails_one_line(d, args, "no bake box: the scene has no geometry");
    }
}

#[test]
fn eval_render_and_rig_refuse_another_scenes_lighting() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    lights_scene(d);
    json(
        d,
        &[
            "bake",
            "lights.toml",
            "--placement",
            "grid",
            "--budget",
            "27",
            "--samples",
            "16",
            "--set",
            "blend.probe_weights=false",
            "-o",
            "l.probes",
            "--json",
        ],
    );
    for args in [
        &[
            "eval",
            "l.probes",
            "--scene",
            "builtin:demo",
            "--points",
            "10",
        ][..],
        &[
            "render",
            "builtin:demo",
            "--probes",
            "l.probes",
            "-o",
            "r.png",
        ],
        &[
            "rig",
            "builtin:car",
            "--scene",
            "builtin:demo",
            "--probes",
            "l.probes",
            "--rig",
            "constant",
            "--samples",
            "16",
        ],
    ] {
        fails_one_line(
            d,
            args,
            "l.probes was baked from lights.toml (lighting hash",
        );
        let o = run(d, args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("not from builtin:demo (lighting hash"),
            "{err}"
        );
        assert!(!d.join("r.png").exists());
    }
    // Allowed on request, with a warning.
    let e = json(
        d,
        &[
            "eval",
            "l.probes",
            "--scene",
            "builtin:demo",
            "--points",
            "10",
            "--allow-other-scene",
            "--json",
        ],
    );
    assert_eq!(e["points"], 10);
    // The same scene through another path is the same lighting.
    let abs = d.join("lights.toml").canonicalize().unwrap();
    let e = json(
        d,
        &[
            "eval",
            "l.probes",
            "--scene",
            abs.to_str().unwrap(),
            "--points",
            "10",
            "--json",
        ],
    );
    assert_eq!(e["points"], 10);
    // Volumes record the hash too.
    json(
        d,
        &[
            "volume",
            "lights.toml",
            "--layout",
            "uniform",
            "--resolution",
            "3,3,3",
            "--samples",
            "8",
            "-o",
            "v.probes",
            "--json",
        ],
    );
    let i = json(d, &["inspect", "v.probes", "--json"]);
    assert_eq!(i["scene"], "lights.toml");
    assert_eq!(i["scene_hash"].as_str().unwrap().len(), 16);
    fails_one_line(
        d,
        &[
            "eval",
            "v.probes",
            "--scene",
            "builtin:demo",
            "--points",
            "10",
        ],
        "v.probes was baked from lights.toml",
    );
}

#[test]
fn progress_off_a_terminal_is_a_line_per_phase() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    lights_scene(d);
    let o = run(
        d,
        &[
            "bake",
            "lights.toml",
            "--placement",
            "grid",
            "--budget",
            "27",
            "--samples",
            "16",
            "-o",
            "p.probes",
        ],
    );
    assert!(o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    for phase in [
        "capture",
        "distance moments",
        "cell visibility",
        "weight fit",
    ] {
        assert!(err.contains(&format!("{phase}: started (")), "{err}");
        assert!(err.contains(&format!("{phase}: done (")), "{err}");
    }
    // A count never passes its total.
    for line in err.lines().filter(|l| l.contains('/')) {
        if let Some((a, b)) = line
            .split_once('(')
            .and_then(|(_, r)| r.split_once(')'))
            .and_then(|(r, _)| r.split_once('/'))
        {
            let (a, b): (usize, usize) = (a.parse().unwrap(), b.parse().unwrap());
            assert!(a <= b, "{line}");
        }
    }
}

#[test]
fn requests_are_not_silently_changed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    lights_scene(d);
    fails_one_line(
        d,
        &[
            "bake",
            "lights.toml",
            "--placement",
            "grid",
            "--budget",
            "1",
        ],
        "`placement.budget`: 1: expected at least 8",
    );
    fails_one_line(
        d,
        &[
            "volume",
            "lights.toml",
            "-o",
            "v.probes",
            "--layout",
            "octree",
            "--cell",
            "0.5",
        ],
        "`volume.cell`",
    );
}

#[test]
fn inspect_summarises_for_people_and_names_rig_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    lights_scene(d);
    json(
        d,
        &[
            "bake",
            "lights.toml",
            "--placement",
            "grid",
            "--budget",
            "27",
            "--samples",
            "16",
            "-o",
            "l.probes",
            "--json",
        ],
    );
    let o = run(d, &["inspect", "l.probes"]);
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(
        text.starts_with("l.probes: probe cloud: 27 probes"),
        "{text}"
    );
    assert!(text.contains("baked from lights.toml"), "{text}");
    assert!(!text.contains('{'), "not JSON: {text}");
    let o = run(
        d,
        &[
            "rig",
            "builtin:car",
            "--scene",
            "builtin:rig-demo",
            "--rig",
            "constant",
            "--samples",
            "16",
            "--out",
            "rig.probes",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let i = json(d, &["inspect", "rig.probes", "--json"]);
    assert_eq!(i["kind"], "rigs");
    assert_eq!(i["rigs"], 1);
    let text = String::from_utf8(run(d, &["inspect", "rig.probes"]).stdout).unwrap();
    assert!(text.contains("irradiance rigs: 1 rig"), "{text}");
}

#[test]
fn the_output_is_named_after_the_scene_and_a_bad_glb_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    lights_scene(d);
    let b = json(
        d,
        &[
            "bake",
            "lights.toml",
            "--placement",
            "grid",
            "--budget",
            "8",
            "--samples",
            "8",
            "--json",
        ],
    );
    assert_eq!(b["output"], "lights.probes");
    assert!(d.join("lights.probes").is_file());
    assert!(!d.join("demo.probes").exists());
    std::fs::write(d.join("model.glb"), "this is text, not a glTF container").unwrap();
    fails_one_line(
        d,
        &["bake", "model.glb", "--samples", "8"],
        "model.glb: broken glTF: not a binary glTF (bad magic",
    );
}
