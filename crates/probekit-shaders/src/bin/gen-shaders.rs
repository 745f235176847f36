//! `gen-shaders`: writes the naga translations of `shaders/*.wgsl` to
//! `shaders/generated/` (run `cargo run -p probekit-shaders --bin gen-shaders`
//! after changing the WGSL; the `generated_files_are_up_to_date` test checks
//! the committed files).

use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shaders/generated");
    let files = match probekit_shaders::generate() {
        Ok(f) => f,
        Err(e) => {
            eprintln!("gen-shaders: {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Err(e) = std::fs::create_dir_all(&dir) {
        eprintln!("gen-shaders: {}: {e}", dir.display());
        return ExitCode::FAILURE;
    }
    for f in files {
        let path = dir.join(f.name);
        if let Err(e) = std::fs::write(&path, &f.contents) {
            eprintln!("gen-shaders: {}: {e}", path.display());
            return ExitCode::FAILURE;
        }
        println!("wrote {} ({} bytes)", path.display(), f.contents.len());
    }
    ExitCode::SUCCESS
}
