//! One module per subcommand; each exposes `Args` (clap derive) and `run`.

pub mod eval;
pub mod export;
pub mod rig;
pub mod sh;
pub mod volume;
