//! docs/distributed-baking.md runs as written: its shell blocks, with the
//! Slurm array played by a loop over `SLURM_ARRAY_TASK_ID` (3 shards, 64
//! samples), on a small scene and positions file shipped with this test,
//! give a merged file equal byte for byte to a single-machine bake.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The ```bash blocks of a Markdown page, in order.
fn bash_blocks(page: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in page.lines() {
        match (&mut current, line.trim_start()) {
            (None, l) if l.starts_with("```bash") => current = Some(String::new()),
            (Some(_), l) if l.starts_with("```") => blocks.extend(current.take()),
            (Some(b), _) => {
                b.push_str(line);
                b.push('\n');
            }
            (None, _) => {}
        }
    }
    blocks
}

/// Runs `script` with bash in `dir`, `probekit` on the PATH and `env` set.
fn bash(dir: &Path, script: &str, env: &[(&str, String)]) {
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_probekit"));
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let out = Command::new("bash")
        .arg("-euc")
        .arg(script)
        .current_dir(dir)
        .env("PATH", path)
        .envs(env.iter().map(|(k, v)| (*k, v.as_str())))
        .output()
        .expect("run bash");
    assert!(
        out.status.success(),
        "{script}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn the_pages_slurm_steps_merge_to_the_single_machine_bake() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let page = std::fs::read_to_string(root.join("../../docs/distributed-baking.md")).unwrap();
    let blocks = bash_blocks(&page);
    assert_eq!(blocks.len(), 2, "the page's array step and merge step");
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for f in ["scene.toml", "room.obj", "probes.csv"] {
        std::fs::copy(root.join("tests/data/distributed").join(f), d.join(f)).unwrap();
    }
    let (shards, samples) = (3, 64);
    let vars = |task: Option<usize>| {
        let mut v = vec![
            ("SHARDS", shards.to_string()),
            ("SAMPLES", samples.to_string()),
        ];
        if let Some(t) = task {
            v.push(("SLURM_ARRAY_TASK_ID", t.to_string()));
        }
        v
    };
    for task in 0..shards {
        bash(d, &blocks[0], &vars(Some(task)));
    }
    bash(d, &blocks[1], &vars(None));
    bash(
        d,
        &format!(
            "probekit bake scene.toml --positions probes.csv --samples {samples} -o single.probes"
        ),
        &[],
    );
    let merged = std::fs::read(d.join("scene.probes")).unwrap();
    let single = std::fs::read(d.join("single.probes")).unwrap();
    assert!(merged.len() > 1000);
    assert!(
        merged == single,
        "the merged file differs from the single bake"
    );
}
