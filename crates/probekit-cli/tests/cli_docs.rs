//! docs/cli.md is the command-line reference generated from the argument
//! definitions: it must match what `probekit markdown-help` prints.

use std::process::Command;

#[test]
fn cli_reference_is_current() {
    let o = Command::new(env!("CARGO_BIN_EXE_probekit"))
        .arg("markdown-help")
        .output()
        .expect("run probekit");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let generated = String::from_utf8(o.stdout).unwrap();
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/cli.md");
    let page = std::fs::read_to_string(path).unwrap_or_default();
    assert!(
        page == generated,
        "docs/cli.md is out of date: run `cargo run -p probekit-cli -- markdown-help > docs/cli.md`"
    );
    // Each command's options fit on a help screen.
    for section in generated.split("\n## ").skip(1) {
        let name = section.lines().next().unwrap_or_default();
        let options = section.lines().filter(|l| l.starts_with("- `-")).count();
        assert!(options <= 15, "{name}: {options} options");
    }
}
