//! # probekit-capi — the C ABI of probekit-runtime
//!
//! What a C or C++ engine links (`libprobekit_capi.a`, `.so`, `.dylib` or
//! `.dll`) together with the header `include/probekit.h`, which documents
//! every function, its units and conventions. This crate is a thin shell: it
//! converts pointers into slices, checks them, and calls
//! [`probekit_runtime`]. Build and link instructions: `docs/c-api.md`.
//!
//! ## Rules every function follows
//! * Every pointer is null-checked; a null or otherwise bad argument returns
//!   a [`PkStatus`] error (or null / 0 for constructors and getters) and sets
//!   the thread's last error message ([`pk_last_error`]).
//! * No panic crosses the boundary: the code has no panicking path on bad
//!   input, and every body runs under [`std::panic::catch_unwind`] as a last
//!   guard ([`PkStatus::Panic`]).
//! * Queries ([`pk_irradiance`], [`pk_sh`], their batched forms,
//!   [`pk_sh_irradiance`], [`pk_light_occlusion`], the rig queries) never
//!   allocate; only loading, state creation and error reporting do.
//! * A [`PkProbes`] is immutable after loading (a volume's interpolation
//!   and the L1 evaluation are chosen at load, [`PkLoadOptions`]), so it
//!   can be queried from many threads at once; a [`PkWalkState`] or a
//!   [`PkRig`] belongs to one object and must not be used by two threads at
//!   the same time.
//! * Every query goes through [`probekit_runtime::Probes`]: the C API and
//!   the Rust runtime give the same numbers.
//! * A file with run-time lights (format 2.1): [`pk_irradiance`] includes
//!   their direct light; an engine drawing them itself reads them with
//!   [`pk_runtime_light_count`], [`pk_runtime_light`] and
//!   [`pk_runtime_light_group`], and adds their light, times
//!   [`pk_light_occlusion`], to [`pk_sh_irradiance`].
//!
//! Conventions are those of `probekit_sh`: right-handed, +Y up, metres,
//! linear RGB, real SH indexed `l(l+1)+m` (Sloan's Condon–Shortley phase),
//! stored SH is radiance SH, irradiance `E(n) = ∫ L(ω) max(0, n·ω) dω` is
//! not divided by π.

#![warn(missing_docs)]
// The exported functions take raw pointers from C; each one null-checks and
// documents its contract in include/probekit.h rather than in `# Safety`.
#![allow(clippy::missing_safety_doc)]

mod args;
mod cloud;
mod error;
mod probes;
mod query;
mod rig;
mod runtime_lights;
mod split;
mod volume;

pub use cloud::{
    pk_cloud_weights, pk_walk_state_free, pk_walk_state_new, pk_walk_state_reset, PkWalkState,
};
pub use error::{pk_last_error, pk_last_error_copy, PkStatus};
pub use probes::{
    pk_free, pk_kind, pk_l1_mode, pk_load_bytes, pk_load_file, pk_load_options_default,
    pk_probe_count, pk_probes_load_bytes, pk_probes_load_file, pk_sh_count, pk_sh_order, PkKind,
    PkLoadOptions, PkProbes, PK_L1_MODE_AS_BAKED, PK_L1_MODE_LINEAR, PK_L1_MODE_ZH3_HALLUCINATED,
};
pub use query::{pk_irradiance, pk_irradiance_many, pk_sh, pk_sh_irradiance, pk_sh_many};
pub use rig::{
    pk_rig_count, pk_rig_free, pk_rig_irradiance, pk_rig_irradiance_many, pk_rig_name, pk_rig_new,
    pk_rig_order, pk_rig_sample_count, pk_rig_sample_points, pk_rig_update,
    pk_rig_update_from_probes, PkRig,
};
pub use runtime_lights::{
    pk_light_occlusion, pk_runtime_light, pk_runtime_light_count, pk_runtime_light_group,
};
pub use split::{
    pk_split_rig_free, pk_split_rig_irradiance, pk_split_rig_irradiance_many, pk_split_rig_new,
    pk_split_rig_update, PkLight, PkSplitRig, PK_LIGHT_DIRECTIONAL, PK_LIGHT_DISK, PK_LIGHT_POINT,
    PK_LIGHT_SPHERE, PK_LIGHT_SPOT,
};
pub use volume::{pk_volume_has_gradients, pk_volume_interp};

/// Version of this C ABI; `PK_ABI_VERSION` in the header. Bumped when a
/// signature or a struct/enum value changes.
pub const PK_ABI_VERSION: u32 = 2;

/// [`PK_ABI_VERSION`]: compare with the header's `PK_ABI_VERSION` at start-up.
#[no_mangle]
pub extern "C" fn pk_abi_version() -> u32 {
    PK_ABI_VERSION
}
