//! `bake --groups` end to end on `builtin:demo` (groups `lamp` and `sun`):
//! a 3-way sharded bake with groups merges byte for byte into the unsharded
//! file; `inspect --json` lists the groups and their section; `query
//! --group-scale` relights linearly (all groups × 2 doubles the irradiance,
//! all × 0 leaves nothing, since the groups sum to the stored total — also
//! with `--indirect-only`); bad scales fail with one line.

mod common;
use common::{fails_one_line, json, run};
use serde_json::Value;

fn rgb(v: &Value) -> [f64; 3] {
    let a = v.as_array().unwrap();
    [0, 1, 2].map(|k| a[k].as_f64().unwrap())
}

const COMMON: [&str; 9] = [
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

#[test]
fn sharded_bake_with_groups_merges_to_the_unsharded_file() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    let extra = ["--set", "capture.groups=true", "--codec", "f16"];
    let full = json(
        d,
        &[&COMMON[..], &extra, &["-o", "full.probes", "--json"]].concat(),
    );
    let names: Vec<&str> = full["groups"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(
        names.contains(&"lamp") && names.contains(&"sun"),
        "{names:?}"
    );
    for i in 0..3 {
        let s = format!("{i}/3");
        let o = format!("p{i}.probes");
        json(
            d,
            &[&COMMON[..], &extra, &["--shard", &s, "-o", &o, "--json"]].concat(),
        );
    }
    let m = run(
        d,
        &[
            "merge",
            "p1.probes",
            "p2.probes",
            "p0.probes",
            "-o",
            "m.probes",
            "--scene",
            "builtin:demo",
        ],
    );
    assert!(m.status.success(), "{}", String::from_utf8_lossy(&m.stderr));
    let a = std::fs::read(d.join("full.probes")).unwrap();
    let b = std::fs::read(d.join("m.probes")).unwrap();
    assert!(
        a == b,
        "merged file with groups differs from the unsharded bake"
    );

    let i = json(d, &["inspect", "m.probes", "--json"]);
    assert_eq!(i["groups"], full["groups"]);
    assert!(i["bytes_by_section"]["light_groups"].as_u64().unwrap() > 0);
    let sum: u64 = i["bytes_by_section"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .sum();
    assert_eq!(sum, i["bytes"].as_u64().unwrap());

    // A part baked without groups does not merge with parts that have them.
    json(
        d,
        &[
            &COMMON[..],
            &[
                "--codec",
                "f16",
                "--shard",
                "1/3",
                "-o",
                "q1.probes",
                "--json",
            ],
        ]
        .concat(),
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
fn query_group_scale_relights_linearly() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    for (out, flags) in [
        ("g.probes", &["--set", "capture.groups=true"][..]),
        (
            "gi.probes",
            &[
                "--set",
                "capture.groups=true",
                "--set",
                "capture.indirect_only=true",
            ][..],
        ),
    ] {
        let b = json(d, &[&COMMON[..], flags, &["-o", out, "--json"]].concat());
        let names: Vec<String> = b["groups"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap().to_string())
            .collect();
        let all = |s: &str| {
            names
                .iter()
                .map(|n| format!("{n}={s}"))
                .collect::<Vec<_>>()
                .join(",")
        };
        // 2,1,2 is in the lamp's room, 6,1,2 in the sunlit one.
        for at in ["2,1,2", "6,1,2"] {
            let q = |scale: Option<String>| {
                let mut args = vec!["query", out, "--at", at, "--normal", "0,1,0", "--json"];
                let s;
                if let Some(x) = scale {
                    s = x;
                    args.extend(["--group-scale", s.as_str()]);
                }
                rgb(&json(d, &args)["irradiance"])
            };
            let e = q(None);
            assert!(e.iter().any(|&x| x > 1e-4), "{out}: lit at {at}: {e:?}");
            let twice = q(Some(all("2")));
            let none = q(Some(all("0")));
            let rgb_scale = q(Some(all("2:2:2")));
            // Each group alone (the others × 0), summed over groups.
            let mut alone_sum = [0.0; 3];
            for g in &names {
                let others: Vec<String> = names
                    .iter()
                    .filter(|n| *n != g)
                    .map(|n| format!("{n}=0"))
                    .collect();
                let one = if others.is_empty() {
                    e
                } else {
                    q(Some(others.join(",")))
                };
                for k in 0..3 {
                    alone_sum[k] += one[k];
                }
            }
            for k in 0..3 {
                let tol = 1e-4 * e[k].abs() + 1e-6;
                assert!((twice[k] - 2.0 * e[k]).abs() <= tol, "{out} {at}");
                assert_eq!(twice[k], rgb_scale[k]);
                // Σ groups = total: nothing is left when every group is off,
                // and the groups alone add up to the unscaled irradiance.
                assert!(none[k].abs() <= tol, "{out} {at}: {none:?}");
                assert!(
                    (alone_sum[k] - e[k]).abs() <= tol,
                    "{out} {at}: {alone_sum:?} vs {e:?}"
                );
            }
        }
    }
    fails_one_line(
        d,
        &[
            "query",
            "g.probes",
            "--at",
            "2,1,2",
            "--group-scale",
            "moon=0",
        ],
        "moon",
    );
    fails_one_line(
        d,
        &[
            "query",
            "g.probes",
            "--at",
            "2,1,2",
            "--group-scale",
            "lamp",
        ],
        "--group-scale",
    );
    json(
        d,
        &[&COMMON[..], &["-o", "plain.probes", "--json"]].concat(),
    );
    fails_one_line(
        d,
        &[
            "query",
            "plain.probes",
            "--at",
            "2,1,2",
            "--group-scale",
            "lamp=0",
        ],
        "no light groups",
    );
}
