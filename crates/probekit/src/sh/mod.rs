//! SH in the baking library: everything of [`probekit_sh`] (re-exported here,
//! so `probekit::sh::ShRgb` keeps working) plus baking-side tools that need
//! environment maps or threads, such as the basis comparison of [`compare`].

pub use probekit_sh::*;

pub mod compare;
