//! # probekit — the baking library
//!
//! Scenes, ray tracing, probe capture, probe clouds, irradiance volumes and
//! rigs. Conventions (axes, SH basis, radiance vs irradiance, units) are
//! defined once in [`probekit_sh`]'s crate documentation and `docs/conventions.md`.

#![warn(missing_docs)]

pub mod blend;
pub mod capture;
pub mod delaunay;
pub mod env;
pub mod eval;
pub mod format;
pub mod inspect;
pub mod lights;
pub mod pipeline;
pub mod placement;
pub mod plot;
pub mod progress;
pub mod query;
pub mod recipe;
pub mod render;
pub mod rig;
pub mod sampling;
pub mod scene;
pub mod sh;
pub mod trace;
pub mod volume;
