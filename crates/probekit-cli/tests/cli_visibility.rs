//! `bake` stores distance moments (`VISM`) by default, `inspect` reports
//! them, `query`/`eval` use them unless `--no-visibility`, and bad settings
//! are one-line errors.

mod common;
use common::{fails_one_line, json, run};

#[test]
fn bake_inspect_query_with_and_without_visibility() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    let common = ["bake", "--grid", "40", "--samples", "32", "--bounces", "1"];
    json(
        d,
        &[
            &common[..],
            &["-o", "v.probes", "--visibility-res", "4", "--json"],
        ]
        .concat(),
    );
    json(
        d,
        &[
            &common[..],
            &["-o", "n.probes", "--no-visibility", "--json"],
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
    assert_eq!(
        v["cell_visibility"]["subdivision"],
        probekit_runtime::cloud::cell_visibility::DEFAULT_CELL_SUBDIVISION
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
    let meta = std::fs::read(d.join("v.probes")).unwrap();
    assert!(String::from_utf8_lossy(&meta).contains("\"rays_per_texel\":16"));

    // Near the demo's dividing wall a query differs with visibility on and
    // off; --no-visibility on the file with moments equals the file without.
    std::fs::write(
        d.join("pts.csv"),
        "x,y,z,nx,ny,nz\n3.9,1.2,2.0,1,0,0\n4.25,1.2,2.0,-1,0,0\n1.0,1.5,1.0,0,1,0\n",
    )
    .unwrap();
    let q = |f: &str, extra: &[&str]| {
        json(
            d,
            &[&["query", f, "--points", "pts.csv", "--json"][..], extra].concat(),
        )["irradiance"]
            .clone()
    };
    assert_eq!(q("v.probes", &["--no-visibility"]), q("n.probes", &[]));
    assert_eq!(
        q("n.probes", &[]),
        q("n.probes", &["--visibility-bias", "0.2"])
    );
    assert_ne!(q("v.probes", &[]), q("n.probes", &[]));
    // Each weighting alone differs from both together.
    assert_ne!(q("v.probes", &["--no-cell-visibility"]), q("v.probes", &[]));
    assert_ne!(q("v.probes", &["--no-cell-visibility"]), q("n.probes", &[]));
    assert_ne!(
        q("v.probes", &["--visibility-bias", "0.01"]),
        q("n.probes", &[])
    );

    fails_one_line(
        d,
        &[&common[..], &["-o", "x.probes", "--visibility-res", "0"]].concat(),
        "visibility",
    );
    fails_one_line(
        d,
        &[
            "query",
            "v.probes",
            "--points",
            "pts.csv",
            "--visibility-bias",
            "nan",
            "--json",
        ],
        "visibility-bias",
    );
    fails_one_line(
        d,
        &[
            "query",
            "v.probes",
            "--points",
            "pts.csv",
            "--visibility-sharpness",
            "17",
            "--json",
        ],
        "visibility-sharpness",
    );
    // Brightness weighting changes the blend; 0 is the default; out of
    // range is refused.
    assert_ne!(
        q("v.probes", &["--brightness-weight", "1"]),
        q("v.probes", &[])
    );
    assert_eq!(
        q("v.probes", &["--brightness-weight", "0"]),
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
                &format!("--brightness-weight={bad}"),
                "--json",
            ],
            "brightness-weight",
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
            "--uniform",
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
            "--visibility-bias",
            "inf",
            "--json",
        ],
        "visibility-bias",
    );
    // Sharpness 0 switches the moments' test off: with cell visibility off
    // too, the plain barycentric blend.
    assert_eq!(
        q(
            "v.probes",
            &["--visibility-sharpness", "0", "--no-cell-visibility"]
        ),
        q("n.probes", &[])
    );
    assert!(run(d, &["query", "v.probes", "--at", "1,1,1", "--json"])
        .status
        .success());
}
