//! One module per subcommand; each exposes `Args` (clap derive) and `run`.

pub mod bake;
pub mod convert;
pub mod eval;
pub mod export;
pub mod load_args;
pub mod probes;
pub mod recipe_args;
pub mod render;
pub mod rig;
pub mod sh;
pub mod util;
pub mod view;
pub mod volume;
