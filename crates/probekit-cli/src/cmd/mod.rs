//! One module per subcommand; each exposes `Args` (clap derive) and `run`.

pub mod sh;
