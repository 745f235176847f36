//! End-to-end `probekit render` and `bake --render` on `builtin:demo` with
//! tiny sizes: the JSON shape, the PNG on disk, one-line errors with exit
//! code 1 for missing/corrupt probe files and a zero-size image.

mod common;
use common::{fails_one_line, json};

#[test]
fn render_json_png_and_errors() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    let baked = json(
        d,
        &[
            "bake",
            "--placement",
            "grid",
            "--budget",
            "12",
            "--samples",
            "32",
            "--set",
            "capture.bounces=1",
            "-o",
            "t.probes",
            "--json",
        ],
    );
    let render = |extra: &[&str]| {
        let base = [
            "render",
            "--probes",
            "t.probes",
            "-o",
            "r.png",
            "--width",
            "48",
            "--height",
            "32",
            "--samples",
            "32",
            "--json",
        ];
        json(d, &[&base[..], extra].concat())
    };
    let j = render(&[]);
    assert_eq!(j["output"], "r.png");
    assert_eq!(j["probes"], baked["probes"]);
    let (w, h) = (j["width"].as_u64().unwrap(), j["height"].as_u64().unwrap());
    assert!(w > 3 * 48 && h > 32);
    assert!(j["object_pixels"].as_u64().is_some());
    assert!(j["rel_rmse"].as_f64().is_some_and(f64::is_finite));
    assert!(j["max_rel_error"].as_f64().is_some_and(f64::is_finite));
    // PNG signature, then the IHDR chunk: big-endian width and height.
    let png = std::fs::read(d.join("r.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let be = |i: usize| u32::from_be_bytes(png[i..i + 4].try_into().unwrap()) as u64;
    assert_eq!((be(16), be(20)), (w, h));

    // Brightness weighting reaches the test object's blend; out of range
    // is refused before any work.
    let rmse = |alpha: &str| {
        render(&["--brightness-weight", alpha])["rel_rmse"]
            .as_f64()
            .unwrap()
    };
    let plain = j["rel_rmse"].as_f64().unwrap();
    // The file's own exponent gives the file's render; another does not.
    let info = json(d, &["inspect", "t.probes", "--json"]);
    let alpha = info["probe_weights"]["brightness_exponent"]
        .as_f64()
        .unwrap_or(0.0);
    assert_eq!(rmse(&alpha.to_string()), plain);
    assert_ne!(rmse("0"), rmse("1"));
    fails_one_line(
        d,
        &[
            "render",
            "--probes",
            "t.probes",
            "-o",
            "x.png",
            "--brightness-weight=9",
        ],
        "brightness-weight",
    );

    // A mesh test object: a 0.5 m cube (OBJ) in room B, the camera aimed at it.
    let mut obj = String::new();
    for k in 0..8 {
        let f = |b: usize| if k & b == 0 { -0.25 } else { 0.25 };
        obj += &format!("v {} {} {}\n", 5.8 + f(4), 1.2 + f(2), 2.6 + f(1));
    }
    for q in [
        [1, 2, 4, 3],
        [5, 7, 8, 6],
        [1, 5, 6, 2],
        [3, 4, 8, 7],
        [1, 3, 7, 5],
        [2, 6, 8, 4],
    ] {
        obj += &format!(
            "f {} {} {}\nf {} {} {}\n",
            q[0], q[1], q[2], q[0], q[2], q[3]
        );
    }
    std::fs::write(d.join("cube.obj"), obj).unwrap();
    let m = json(
        d,
        &[
            "render",
            "--probes",
            "t.probes",
            "-o",
            "m.png",
            "--object",
            "cube.obj",
            "--camera",
            "7.7,2.3,3.7,5.8,1.2,2.6",
            "--width",
            "48",
            "--height",
            "32",
            "--samples",
            "16",
            "--json",
        ],
    );
    assert!(m["object_pixels"].as_u64().unwrap() > 20, "{m}");
    assert!(m["rel_rmse"].as_f64().is_some_and(f64::is_finite));
    fails_one_line(
        d,
        &[
            "render", "--probes", "t.probes", "-o", "x.png", "--object", "nope.obj",
        ],
        "nope.obj",
    );

    // A volume file (of another scene: only the code path is checked) with
    // its samples drawn.
    json(
        d,
        &[
            "volume",
            "builtin:lights-demo",
            "-o",
            "v.probes",
            "--layout",
            "uniform",
            "--resolution",
            "4,3,3",
            "--json",
        ],
    );
    let v = json(
        d,
        &[
            "render",
            "builtin:demo",
            "--probes",
            "v.probes",
            "-o",
            "v.png",
            "--width",
            "32",
            "--height",
            "24",
            "--samples",
            "16",
            "--show-probes",
            "--json",
        ],
    );
    assert_eq!(v["probes"], 36);
    assert!(d.join("v.png").is_file());

    std::fs::write(d.join("bad.probes"), b"PKPRnot really a probe file").unwrap();
    fails_one_line(
        d,
        &["render", "--probes", "bad.probes", "-o", "x.png"],
        "bad.probes",
    );
    fails_one_line(
        d,
        &["render", "--probes", "missing.probes", "-o", "x.png"],
        "missing.probes",
    );
    fails_one_line(
        d,
        &[
            "render", "--probes", "t.probes", "-o", "x.png", "--width", "0",
        ],
        "image size",
    );
    fails_one_line(
        d,
        &[
            "render", "--probes", "t.probes", "-o", "x.png", "--camera", "1,2,3",
        ],
        "--camera",
    );
    assert!(!d.join("x.png").exists());
}

/// The shared scenes (`../shared/data`; skipped with a message when absent),
/// or `None`.
fn shared_scene(name: &str) -> Option<std::path::PathBuf> {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    if !data.is_dir() {
        eprintln!("SKIPPED: {} not found", data.display());
        return None;
    }
    Some(data.join("scenes").join(name).join(format!("{name}.toml")))
}

/// On each shared scene the automatic camera stands inside the bake box,
/// in free space, and the default picture shows the test objects.
#[test]
fn the_automatic_camera_shows_the_objects_on_every_shared_scene() {
    for name in ["cornell_box", "fzk_haus", "duplex_apartment"] {
        let Some(scene) = shared_scene(name) else {
            return;
        };
        let t = tempfile::tempdir().unwrap();
        let d = t.path();
        let scene = scene.to_str().unwrap();
        json(
            d,
            &[
                "bake",
                scene,
                "--placement",
                "grid",
                "--budget",
                "27",
                "--samples",
                "16",
                "--set",
                "blend.probe_weights=false",
                "--set",
                "blend.distance_moments=0",
                "--set",
                "blend.cell_visibility=0",
                "-o",
                "s.probes",
                "--json",
            ],
        );
        let j = json(
            d,
            &[
                "render",
                "--probes",
                "s.probes",
                "-o",
                "s.png",
                "--width",
                "96",
                "--height",
                "64",
                "--samples",
                "16",
                "--json",
            ],
        );
        assert!(j["object_pixels"].as_u64().unwrap() > 0, "{name}: {j}");
    }
}

/// A camera with no free space in view for the test objects (looking
/// into the floor from just above it) is an error, not a picture of the
/// scene alone.
#[test]
fn no_place_for_the_objects_is_an_error() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    json(
        d,
        &[
            "bake",
            "--placement",
            "grid",
            "--budget",
            "12",
            "--samples",
            "16",
            "-o",
            "t.probes",
            "--json",
        ],
    );
    fails_one_line(
        d,
        &[
            "render",
            "--probes",
            "t.probes",
            "-o",
            "r.png",
            "--width",
            "32",
            "--height",
            "24",
            "--camera",
            "1,0.05,1,1,-1,1.001",
        ],
        "no place for the test objects",
    );
    assert!(!d.join("r.png").exists());
}
