//! `bake` stores distance moments (`VISM`) by default, `inspect` reports
//! them, `query`/`eval` use them unless `--no-visibility`, and bad settings
//! are one-line errors.

mod common;
use common::{fails_one_line, json, run};
use std::path::Path;

/// Query points near the demo's dividing wall (both sides), in room A and
/// in room B, as `pts.csv` in `d`.
fn write_points(d: &Path) {
    std::fs::write(
        d.join("pts.csv"),
        "x,y,z,nx,ny,nz\n3.9,1.2,2.0,1,0,0\n4.25,1.2,2.0,-1,0,0\n1.0,1.5,1.0,0,1,0\n6.5,0.5,3.5,0,0,-1\n",
    )
    .unwrap();
}

/// `query FILE --points pts.csv --json EXTRA...`'s irradiance array.
fn query(d: &Path, file: &str, extra: &[&str]) -> serde_json::Value {
    json(
        d,
        &[&["query", file, "--points", "pts.csv", "--json"][..], extra].concat(),
    )["irradiance"]
        .clone()
}

#[test]
fn bake_inspect_query_with_and_without_visibility() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    // Visibility alone here (probe weights: the next test).
    let common = [
        "bake",
        "--placement",
        "grid",
        "--budget",
        "40",
        "--samples",
        "32",
        "--set",
        "capture.bounces=1",
        "--set",
        "blend.probe_weights=false",
    ];
    json(
        d,
        &[
            &common[..],
            &[
                "-o",
                "v.probes",
                "--set",
                "blend.distance_moments=4",
                "--json",
            ],
        ]
        .concat(),
    );
    json(
        d,
        &[
            &common[..],
            &[
                "-o",
                "n.probes",
                "--set",
                "blend.distance_moments=0",
                "--set",
                "blend.cell_visibility=0",
                "--json",
            ],
        ]
        .concat(),
    );
    let v = json(d, &["inspect", "v.probes", "--json"]);
    let n = json(d, &["inspect", "n.probes", "--json"]);
    assert_eq!(v["visibility"]["resolution"], 4);
    assert!(v["visibility"]["max_distance"].as_f64().unwrap() > 1.0);
    // 16-byte header + probes · 4² texels · 2 values · 2 bytes, padded to 16.
    let probes = v["probes"].as_u64().unwrap();
    assert_eq!(
        v["bytes_by_section"]["visibility"].as_u64().unwrap(),
        16 + (probes * 64).div_ceil(16) * 16
    );
    // The lattice comes from the cell size by default (`auto`): the
    // library's choice for the file's mesh, recorded as "auto".
    let file = probekit_runtime::ProbeFile::load(d.join("v.probes")).unwrap();
    let mesh = probekit_runtime::cloud::ProbeCloud::mesh_from_file(&file).unwrap();
    assert_eq!(
        v["cell_visibility"]["subdivision"],
        probekit::blend::cell_visibility::auto_subdivision(&mesh)
    );
    // Sparse: some cells stored, none more than exist.
    let cells = v["cell_visibility"]["cells"].as_u64().unwrap();
    let stored = v["cell_visibility"]["stored_cells"].as_u64().unwrap();
    assert!(cells > 0 && stored <= cells, "{}", v["cell_visibility"]);
    assert!(n["cell_visibility"].is_null());
    assert!(n["visibility"].is_null());
    assert!(n["bytes_by_section"].get("visibility").is_none());
    // The same probes and SH: only the moments differ.
    assert_eq!(v["probes"], n["probes"]);
    // The file records the recipe it was baked with.
    assert_eq!(v["recipe"]["blend"]["distance_moments"], 4, "{v}");
    assert_eq!(v["recipe"]["blend"]["cell_visibility"], "auto", "{v}");
    // A given subdivision is kept.
    json(
        d,
        &[
            &common[..],
            &[
                "-o",
                "k3.probes",
                "--set",
                "blend.cell_visibility=3",
                "--json",
            ],
        ]
        .concat(),
    );
    let k3 = json(d, &["inspect", "k3.probes", "--json"]);
    assert_eq!(k3["cell_visibility"]["subdivision"], 3);
    // Occluder planes by default (the demo's walls cut cells), recorded;
    // `--no-cell-planes` leaves them out and changes nothing else.
    let planes = probekit::blend::cell_planes::bake_cell_planes(
        &probekit::trace::Tracer::new(&probekit::scene::Scene::builtin_demo()),
        &mesh,
        file.as_cloud()
            .unwrap()
            .blend
            .cell_visibility
            .as_ref()
            .unwrap(),
        probekit::blend::cell_planes::CELL_PLANE_SEED,
        &|_, _| {},
    )
    .unwrap();
    assert!(!planes.is_empty());
    assert_eq!(
        file.as_cloud().unwrap().blend.cell_planes.as_ref(),
        Some(&planes)
    );
    assert_eq!(v["cell_visibility"]["planes"], planes.len());
    assert!(planes.len() as u64 <= stored);
    assert_eq!(v["recipe"]["blend"]["occluder_planes"], true, "{v}");
    json(
        d,
        &[
            &common[..],
            &[
                "-o",
                "np.probes",
                "--set",
                "blend.distance_moments=4",
                "--set",
                "blend.occluder_planes=false",
                "--json",
            ],
        ]
        .concat(),
    );
    let np = probekit_runtime::ProbeFile::load(d.join("np.probes")).unwrap();
    assert!(np.as_cloud().unwrap().blend.cell_planes.is_none());
    assert_eq!(
        np.as_cloud().unwrap().blend.cell_visibility,
        file.as_cloud().unwrap().blend.cell_visibility
    );
    assert_eq!(
        np.probes().unwrap().coefficients,
        file.probes().unwrap().coefficients
    );
    for bad in ["9", "fine"] {
        fails_one_line(
            d,
            &[
                &common[..],
                &[
                    "-o",
                    "x.probes",
                    "--set",
                    &format!("blend.cell_visibility={}", bad),
                ],
            ]
            .concat(),
            "blend.cell_visibility",
        );
    }

    // Near the demo's dividing wall a query differs with visibility on and
    // off; --no-visibility on the file with moments equals the file without.
    write_points(d);
    let q = |f: &str, extra: &[&str]| query(d, f, extra);
    assert_eq!(
        q("v.probes", &["--blend", "visibility=off"]),
        q("n.probes", &[])
    );
    assert_eq!(q("n.probes", &[]), q("n.probes", &["--blend", "bias=0.2"]));
    assert_ne!(q("v.probes", &[]), q("n.probes", &[]));
    // Each weighting alone differs from both together.
    assert_ne!(
        q("v.probes", &["--blend", "cell-visibility=off"]),
        q("v.probes", &[])
    );
    assert_ne!(
        q("v.probes", &["--blend", "cell-visibility=off"]),
        q("n.probes", &[])
    );
    assert_ne!(q("v.probes", &["--blend", "bias=0.01"]), q("n.probes", &[]));

    fails_one_line(
        d,
        &[
            &common[..],
            &["-o", "x.probes", "--set", "blend.distance_moments=65"],
        ]
        .concat(),
        "blend.distance_moments",
    );
    fails_one_line(
        d,
        &[
            "query", "v.probes", "--points", "pts.csv", "--blend", "bias=nan", "--json",
        ],
        "--blend bias",
    );
    fails_one_line(
        d,
        &[
            "query",
            "v.probes",
            "--points",
            "pts.csv",
            "--blend",
            "sharpness=17",
            "--json",
        ],
        "--blend sharpness",
    );
    // Brightness weighting changes the blend; 0 is the default; out of
    // range is refused.
    assert_ne!(
        q("v.probes", &["--blend", "brightness=1"]),
        q("v.probes", &[])
    );
    assert_eq!(
        q("v.probes", &["--blend", "brightness=0"]),
        q("v.probes", &[])
    );
    for bad in ["4.5", "nan", "-0.5"] {
        fails_one_line(
            d,
            &[
                "query",
                "v.probes",
                "--points",
                "pts.csv",
                &format!("--blend=brightness={bad}"),
                "--json",
            ],
            "--blend brightness",
        );
    }
    // The flags are checked for volumes too (they ignore them), so a bad
    // value is never silently dropped.
    json(
        d,
        &[
            "volume",
            "builtin:lights-demo",
            "-o",
            "vol.probes",
            "--layout",
            "uniform",
            "--resolution",
            "3,3,3",
            "--json",
        ],
    );
    fails_one_line(
        d,
        &[
            "query",
            "vol.probes",
            "--at",
            "0,0,0",
            "--blend",
            "bias=inf",
            "--json",
        ],
        "--blend bias",
    );
    // Sharpness 0 switches the moments' test off: with cell visibility off
    // too, the plain barycentric blend.
    assert_eq!(
        q(
            "v.probes",
            &["--blend", "sharpness=0", "--blend", "cell-visibility=off"]
        ),
        q("n.probes", &[])
    );
    assert!(run(d, &["query", "v.probes", "--at", "1,1,1", "--json"])
        .status
        .success());
}

/// `bake` fits probe weights (`PWGT`) and their brightness exponent by
/// default, `inspect` reports them, `query` uses them unless
/// `--no-probe-weights`, the metadata records the fit's settings, a fixed
/// `--brightness-weight` is stored as given, so is the directional
/// brightness (0.5 by default, `query` blends with it), and bad fit settings are
/// one-line errors.
#[test]
fn bake_fits_probe_weights_and_query_uses_them() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    let common = [
        "bake",
        "--placement",
        "grid",
        "--budget",
        "40",
        "--samples",
        "32",
        "--set",
        "capture.bounces=1",
    ];
    let fit = [
        "--set",
        "blend.fit.points_per_probe=4",
        "--set",
        "blend.fit.samples=16",
    ];
    json(
        d,
        &[&common[..], &fit[..], &["-o", "w.probes", "--json"]].concat(),
    );
    json(
        d,
        &[
            &common[..],
            &[
                "-o",
                "p.probes",
                "--set",
                "blend.probe_weights=false",
                "--json",
            ],
        ]
        .concat(),
    );
    let w = json(d, &["inspect", "w.probes", "--json"]);
    let p = json(d, &["inspect", "p.probes", "--json"]);
    let probes = w["probes"].as_u64().unwrap();
    assert_eq!(w["probes"], p["probes"]);
    // 16-byte header + one f32 per probe, padded to 16.
    assert_eq!(
        w["bytes_by_section"]["probe_weights"].as_u64().unwrap(),
        16 + (4 * probes).div_ceil(16) * 16
    );
    let pw = &w["probe_weights"];
    let (lo, mid, hi) = (
        pw["min"].as_f64().unwrap(),
        pw["median"].as_f64().unwrap(),
        pw["max"].as_f64().unwrap(),
    );
    assert!(0.0 < lo && lo <= mid && mid <= hi && hi <= 1e6, "{pw}");
    assert!(lo < hi, "some weight moved: {pw}");
    assert!(p["probe_weights"].is_null());
    assert!(p["bytes_by_section"].get("probe_weights").is_none());
    let blend = &w["recipe"]["blend"];
    assert_eq!(blend["probe_weights"], true, "{w}");
    assert_eq!(blend["brightness_exponent"], "auto", "{w}");
    assert_eq!(blend["directional_exponent"], 0.5, "{w}");
    assert_eq!(blend["fit"]["points_per_probe"], 4, "{w}");
    let alpha = pw["brightness_exponent"].as_f64().unwrap();
    assert!([0.0, 0.5, 1.0].contains(&alpha), "{pw}");
    // A fixed exponent is stored as given, and query blends with it.
    json(
        d,
        &[
            &common[..],
            &fit[..],
            &[
                "-o",
                "h.probes",
                "--set",
                "blend.brightness_exponent=0.75",
                "--json",
            ],
        ]
        .concat(),
    );
    let h = json(d, &["inspect", "h.probes", "--json"]);
    assert_eq!(h["probe_weights"]["brightness_exponent"], 0.75);
    // Directional brightness: 0.5 by default, stored as given.
    assert_eq!(pw["directional_exponent"], 0.5);
    assert_eq!(h["probe_weights"]["directional_exponent"], 0.5);
    json(
        d,
        &[
            &common[..],
            &fit[..],
            &[
                "-o",
                "g.probes",
                "--set",
                "blend.directional_exponent=0",
                "--json",
            ],
        ]
        .concat(),
    );
    let g = json(d, &["inspect", "g.probes", "--json"]);
    assert_eq!(g["probe_weights"]["directional_exponent"], 0.0);

    write_points(d);
    let q = |f: &str, extra: &[&str]| query(d, f, extra);
    assert_eq!(
        q("w.probes", &["--blend", "probe-weights=off"]),
        q("p.probes", &[])
    );
    assert_ne!(q("w.probes", &[]), q("p.probes", &[]));
    assert_eq!(
        q("h.probes", &[]),
        q("h.probes", &["--blend", "brightness=0.75"])
    );
    assert_ne!(
        q("h.probes", &[]),
        q("h.probes", &["--blend", "brightness=0"])
    );
    // The file's directional exponent is the default; the weights are the
    // same with or without it (not fitted for).
    assert_eq!(
        q("w.probes", &[]),
        q("w.probes", &["--blend", "directional=0.5"])
    );
    assert_ne!(
        q("w.probes", &[]),
        q("w.probes", &["--blend", "directional=0"])
    );
    assert_eq!(
        q("g.probes", &[]),
        q("w.probes", &["--blend", "directional=0"])
    );
    fails_one_line(
        d,
        &[
            "query",
            "w.probes",
            "--points",
            "pts.csv",
            "--blend",
            "directional=9",
        ],
        "--blend directional",
    );

    for (flag, bad) in [
        ("--set", "blend.fit.points_per_probe=0"),
        ("--set", "blend.fit.samples=0"),
        ("--set", "blend.fit.regularization=-1"),
        ("--set", "blend.fit.regularization=nan"),
        ("--set", "blend.fit.absolute_weight=-2"),
        ("--set", "blend.brightness_exponent=5"),
        ("--set", "blend.brightness_exponent=often"),
        ("--set", "blend.directional_exponent=-1"),
        ("--set", "blend.directional_exponent=nan"),
    ] {
        let key = bad.split('=').next().unwrap();
        fails_one_line(
            d,
            &[&common[..], &["-o", "x.probes", flag, bad]].concat(),
            key,
        );
    }
    assert!(!d.join("x.probes").exists());
}
