//! The `probekit` command-line tool: a thin layer over the `probekit` library.
//! One file per subcommand in `cmd/`; each parses its arguments (clap
//! derive), calls the library and prints. Errors are one line naming the
//! file and the problem, exit code 1.

use clap::Parser;

mod cmd;

/// Bake and inspect diffuse lighting (light probes, SH).
#[derive(Parser)]
#[command(name = "probekit", version, about)]
struct Cli {
    #[command(subcommand)]
    command: cmd::Command,
}

fn main() {
    let cli = Cli::parse();
    if let Err(e) = cmd::run(cli.command) {
        eprintln!("probekit: {e:#}");
        std::process::exit(1);
    }
}
