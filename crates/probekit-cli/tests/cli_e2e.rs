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
    let common = ["bake", "--grid", "30", "--samples", "64", "--bounces", "1"];
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
    // Cell visibility spans every probe: merge bakes it, from the same scene.
    std::fs::write(d.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let merge = [
        "merge",
        "p0.probes",
        "p1.probes",
        "p2.probes",
        "-o",
        "x.probes",
    ];
    fails_one_line(d, &merge, "--scene");
    fails_one_line(
        d,
        &[&merge[..], &["--scene", "tri.obj"]].concat(),
        "not the scene",
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
            "--grid",
            "30",
            "--samples",
            "32",
            "--bounces",
            "1",
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
            "--grid",
            "40",
            "--samples",
            "64",
            "--bounces",
            "1",
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
    assert_eq!(i["placement"]["method"], "grid");

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
