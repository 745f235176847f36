//! The `probekit` command-line tool: a thin layer over the `probekit` library.
//!
//! `main` only parses arguments and dispatches to one module per subcommand
//! under [`cmd`]; every failure is reported as one line
//! `error: <file>: <problem>` on stderr with exit code 1.

#![warn(missing_docs)]

mod cmd;
mod markdown;
mod progress;

use clap::{CommandFactory, Parser, Subcommand};
use std::process::ExitCode;

/// probekit: bake and inspect diffuse lighting (light probes, spherical harmonics).
#[derive(Debug, Parser)]
#[command(name = "probekit", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The subcommands; each lives in `src/cmd/<name>.rs`.
#[derive(Debug, Subcommand)]
enum Command {
    /// Bake a probe cloud: adaptive placement (default), a grid, given positions, spawn-and-merge
    /// or gradient ascent; `--shard I/N` for one part.
    Bake(cmd::bake::BakeArgs),
    /// Join shard parts into the file a single-machine bake writes.
    Merge(cmd::bake::MergeArgs),
    /// Capture one probe's radiance SH and validity (JSON).
    Capture(cmd::probes::CaptureArgs),
    /// Ground-truth irradiance at points with normals (JSON).
    Reference(cmd::probes::ReferenceArgs),
    /// Irradiance from a baked cloud or volume at points with normals (JSON).
    Query(cmd::probes::QueryArgs),
    /// Summarise a probe file: probes, tetrahedra, basis, bytes per section.
    Inspect(cmd::probes::InspectArgs),
    /// Re-encode a probe file's coefficients; reports size and irradiance error.
    Convert(cmd::convert::ConvertArgs),
    /// Radiance SH of an environment map, or a comparison of diffuse bases.
    Sh(cmd::sh::ShArgs),
    /// Bake an irradiance volume (uniform grid or adaptive octree).
    Volume(cmd::volume::VolumeArgs),
    /// Export a volume (KTX2, Bevy) or a probe cloud (JSON, CSV).
    Export(cmd::export::ExportArgs),
    /// Fit an irradiance rig to a mesh among lights and compare it with the exact lighting.
    Rig(cmd::rig::RigArgs),
    /// Error of a probe cloud against path-traced ground truth.
    Eval(cmd::eval::EvalArgs),
    /// Picture: the scene lit by the probes beside path-traced truth, and the error.
    Render(cmd::render::RenderArgs),
    /// Look at a bake in the browser: probes, tetrahedra, a test object lit by
    /// the runtime's query, and path-traced truth at any point (docs/view.md).
    View(cmd::view::ViewArgs),
    /// Print docs/cli.md, the command-line reference, from these definitions.
    #[command(hide = true)]
    MarkdownHelp,
}

/// Parses the command line. Help and the version print as clap writes
/// them; a usage error is one line on stderr, exit code 1, like every other
/// error.
fn parse() -> Result<Cli, ExitCode> {
    Cli::try_parse().map_err(|e| {
        use clap::error::ErrorKind;
        if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion)
            || e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
        {
            let _ = e.print();
            return if e.use_stderr() {
                ExitCode::FAILURE
            } else {
                ExitCode::SUCCESS
            };
        }
        let text = e.render().to_string();
        let line: Vec<&str> = text
            .lines()
            .map(str::trim)
            .filter(|l| {
                !l.is_empty() && !l.starts_with("Usage:") && !l.starts_with("For more information")
            })
            .collect();
        eprintln!("{}", line.join(" "));
        ExitCode::FAILURE
    })
}

fn main() -> ExitCode {
    // Output piped into a reader that stops early (`probekit inspect F |
    // head`) ends the process quietly, as it does for other Unix tools,
    // instead of panicking on the failed write.
    #[cfg(unix)]
    // SAFETY: restoring the default action of a signal at start-up, before
    // any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = match parse() {
        Ok(cli) => cli,
        Err(code) => return code,
    };
    let result = match cli.command {
        Command::Bake(args) => cmd::bake::run(&args),
        Command::Merge(args) => cmd::bake::merge(&args),
        Command::Capture(args) => cmd::probes::capture(&args),
        Command::Reference(args) => cmd::probes::reference(&args),
        Command::Query(args) => cmd::probes::query(&args),
        Command::Inspect(args) => cmd::probes::inspect(&args),
        Command::Convert(args) => cmd::convert::run(&args),
        Command::Sh(args) => cmd::sh::run(&args),
        Command::Volume(args) => cmd::volume::run(&args),
        Command::Export(args) => cmd::export::run(&args),
        Command::Rig(args) => cmd::rig::run(args),
        Command::Eval(args) => cmd::eval::run(&args),
        Command::Render(args) => cmd::render::run(&args),
        Command::View(args) => cmd::view::run(&args),
        Command::MarkdownHelp => {
            let mut cli = Cli::command();
            cli.build();
            print!("{}", markdown::cli_markdown(&cli));
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // One line: the context chain joined by ": ", skipping causes
            // whose text the message already contains (library errors embed them).
            let mut msg = String::new();
            for cause in e.chain() {
                let c = cause.to_string();
                if !msg.is_empty() && c.starts_with(&format!("{msg}: ")) {
                    // The cause names the file already: keep its text alone.
                    msg = c;
                } else if !msg.contains(&c) {
                    if !msg.is_empty() {
                        msg += ": ";
                    }
                    msg += &c;
                }
            }
            let msg = msg.replace('\n', " ");
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}
