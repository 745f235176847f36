//! Subcommands, one module each.

use clap::Subcommand;

pub mod rig;

/// The subcommands.
#[derive(Subcommand)]
pub enum Command {
    /// Fit an irradiance rig to a mesh among lights and compare it with the exact lighting.
    Rig(rig::RigArgs),
}

/// Runs a subcommand.
pub fn run(c: Command) -> anyhow::Result<()> {
    match c {
        Command::Rig(a) => rig::run(a),
    }
}
