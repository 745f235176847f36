//! Blend data of a probe cloud, baked beside its Delaunay tetrahedralization:
//! per-probe distance moments ([`visibility`]), per-cell visibility bits and
//! planes ([`cell_visibility`], [`cell_planes`]), fitted per-probe blend weights and the
//! brightness exponent ([`blend_fit`]), and all of them baked into a file as
//! a cloud asks ([`visibility_bake`]). The runtime blends with them
//! (`probekit_runtime::cloud`).

pub mod blend_fit;
pub mod cell_planes;
pub mod cell_visibility;
pub mod visibility;
pub mod visibility_bake;
