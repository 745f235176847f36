//! # probekit-runtime — load and query baked probes
//!
//! What an engine links: load a `.probes` file and answer "irradiance at this
//! point, for this normal" without allocating per query. Conventions are those
//! of [`probekit_sh`].

#![warn(missing_docs)]

pub use probekit_sh as sh;

pub mod cloud;
pub mod format;
pub mod rig;
pub mod volume;

pub use cloud::{ProbeCloud, ProbeCloudError};
pub use format::{FormatError, ProbeFile, ProbeFileKind};
pub use volume::{Interp, Volume, VolumeError};
