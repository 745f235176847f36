//! README's tour runs as written: every `probekit …` line of its "A short
//! tour" block, verbatim, through `sh` from a copy of the repository root
//! (the example CSVs it uses, `../shared` beside it), with the built binary
//! first on `PATH`. It uses `../shared/data`, so it skips, saying so, when
//! that folder is absent.

use std::path::Path;
use std::process::Command;

/// The tour's command lines: the first ```sh block after "## A short tour".
fn tour_commands(readme: &str) -> Vec<String> {
    let tour = readme
        .split("## A short tour")
        .nth(1)
        .expect("README has a tour");
    let block = tour
        .split("```sh")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("the tour has a sh block");
    block
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with("probekit "))
        .map(str::to_string)
        .collect()
}

#[test]
fn readme_tour_runs_as_written() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let shared = root.join("../shared/data");
    if !shared.is_dir() {
        eprintln!("skipped: {} is absent", shared.display());
        return;
    }
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let commands = tour_commands(&readme);
    assert!(commands.len() >= 10, "{commands:?}");
    // A scratch "repository root" with the tour's inputs and `../shared`.
    let tmp = tempfile::tempdir().unwrap();
    let repo = tmp.path().join("repo");
    std::fs::create_dir(&repo).unwrap();
    std::os::unix::fs::symlink(
        root.join("examples").canonicalize().unwrap(),
        repo.join("examples"),
    )
    .unwrap();
    std::os::unix::fs::symlink(
        root.join("../shared").canonicalize().unwrap(),
        tmp.path().join("shared"),
    )
    .unwrap();
    let bin = Path::new(env!("CARGO_BIN_EXE_probekit")).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    for line in &commands {
        let o = Command::new("sh")
            .arg("-c")
            .arg(line)
            .current_dir(&repo)
            .env("PATH", &path)
            .output()
            .expect("run sh");
        assert!(
            o.status.success(),
            "{line}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    for made in [
        "demo.probes",
        "demo.png",
        "grid.toml",
        "tuned.probes",
        "volume.ktx2",
    ] {
        assert!(repo.join(made).is_file(), "{made} not written");
    }
}
