//! `pk_rig` and `pk_sphere_table`: an irradiance rig with the analytic/rig
//! split for `pk_rig_irradiance` of `shaders/probekit_rig.wgsl`.
//!
//! The runtime's [`SplitRig::update`] does the per-frame work on the CPU
//! (which lights are near, their shares, the rig's refit); [`pack_split_rig`]
//! writes its result — the rig's model and box, its current parameters and
//! the near lights in object coordinates with their shares — into the
//! words the vertex shader reads. The sphere-light table is the same for
//! every rig and every frame: [`super::pack_sphere_table`] once. Light
//! records and the table are shared with the cloud's run-time lights
//! (`super::lights`).

use super::lights::{
    pack_rig_light, LIGHT_DIRECTIONAL, LIGHT_DISK, LIGHT_POINT, LIGHT_SPHERE, LIGHT_SPOT,
    RIG_LIGHT_WORDS,
};
use super::{check_size, LayoutError};
use probekit_runtime::format::{AxisModel, RigModel};
use probekit_runtime::rig::SplitRig;

/// Words of the header at the start of each packed rig.
pub const RIG_HEADER_WORDS: usize = 20;

/// The header words of a packed rig, by their WGSL constant names
/// (`shaders/probekit_rig.wgsl`; a test checks that the two agree): the
/// model ([`RIG_CODES`]: constant, gradient, tensor), three axis models
/// (tensor rigs) and three function counts per axis (at least 1: the stride
/// of the parameter index), coefficients per parameter (`order²`: 1, 4 or
/// 9), the parameter count, the near-light count, the word offsets of the
/// parameters and of the light records from the rig's first word, and the
/// box corners (3 f32 each, m). Words 18 and 19 are zero.
pub const RIG_HEADER: [(&str, usize); 10] = [
    ("PK_RIG_H_MODEL", 0),
    ("PK_RIG_H_AXIS_X", 1),
    ("PK_RIG_H_COUNT_X", 4),
    ("PK_RIG_H_COEFFS", 7),
    ("PK_RIG_H_PARAMS", 8),
    ("PK_RIG_H_LIGHTS", 9),
    ("PK_RIG_H_PARAMETERS", 10),
    ("PK_RIG_H_LIGHT_RECORDS", 11),
    ("PK_RIG_H_BOX_MIN", 12),
    ("PK_RIG_H_BOX_MAX", 15),
];

const H_MODEL: usize = 0;
const H_AXIS_X: usize = 1;
const H_COUNT_X: usize = 4;
const H_COEFFS: usize = 7;
const H_PARAMS: usize = 8;
const H_LIGHTS: usize = 9;
const H_PARAMETERS: usize = 10;
const H_LIGHT_RECORDS: usize = 11;
const H_BOX_MIN: usize = 12;
const H_BOX_MAX: usize = 15;

/// The codes the rig buffer uses, by their WGSL constant names: rig models
/// (header word `PK_RIG_H_MODEL`), axis models (`PK_RIG_H_AXIS_X + a`) and
/// light kinds (word 0 of a light record; the C API's `PK_LIGHT_*`, also
/// [`super::LIGHT_CODES`], declared in `shaders/probekit_lights.wgsl`).
pub const RIG_CODES: [(&str, u32); 11] = [
    ("PK_RIG_MODEL_CONSTANT", MODEL_CONSTANT),
    ("PK_RIG_MODEL_GRADIENT", MODEL_GRADIENT),
    ("PK_RIG_MODEL_TENSOR", MODEL_TENSOR),
    ("PK_RIG_AXIS_CONSTANT", AXIS_CONSTANT),
    ("PK_RIG_AXIS_GRADIENT", AXIS_GRADIENT),
    ("PK_RIG_AXIS_LATTICE", AXIS_LATTICE),
    ("PK_LIGHT_SPHERE", LIGHT_SPHERE),
    ("PK_LIGHT_POINT", LIGHT_POINT),
    ("PK_LIGHT_SPOT", LIGHT_SPOT),
    ("PK_LIGHT_DISK", LIGHT_DISK),
    ("PK_LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
];

const MODEL_CONSTANT: u32 = 0;
const MODEL_GRADIENT: u32 = 1;
const MODEL_TENSOR: u32 = 2;
const AXIS_CONSTANT: u32 = 0;
const AXIS_GRADIENT: u32 = 1;
const AXIS_LATTICE: u32 = 2;
/// The most SH bands a packed rig may have: the shader evaluates L2
/// (`pk_irradiance_l2`), so an order-4+ rig, whose band-4 term the runtime
/// keeps, is refused rather than silently truncated.
pub const RIG_MAX_ORDER: usize = 3;

/// The axis code and function count (at least 1) of one tensor axis.
fn axis_code(a: AxisModel) -> (u32, u32) {
    let code = match a {
        AxisModel::Constant => AXIS_CONSTANT,
        AxisModel::Gradient => AXIS_GRADIENT,
        AxisModel::Lattice(_) => AXIS_LATTICE,
    };
    (code, a.count().max(1))
}

/// Packs `rig` as it stands after [`SplitRig::update`] into the words of
/// one rig of `pk_rig` (`docs/shaders.md`, "Irradiance rigs"): the header
/// ([`RIG_HEADER`]), the current parameters (`parameter_count × order²`
/// RGB coefficients, parameter-major, f32 bits), then one record per near
/// light ([`pack_rig_light`] of [`SplitRig::near_lights`]). Offsets are
/// relative to the rig's first word, so packed rigs can be concatenated
/// and addressed by where each starts. Pack and upload again after every
/// update. A rig of more than [`RIG_MAX_ORDER`] bands is an error.
pub fn pack_split_rig(rig: &SplitRig) -> Result<Vec<u32>, LayoutError> {
    let state = rig.state();
    let order = state.order();
    if order > RIG_MAX_ORDER {
        return Err(LayoutError::RigOrder { order });
    }
    let coeffs = order * order;
    let params = state.parameter_count();
    let near = rig.near_lights();
    let words = RIG_HEADER_WORDS + 3 * coeffs * params + RIG_LIGHT_WORDS * near.len();
    check_size("rig", words)?;
    let mut w = vec![0u32; RIG_HEADER_WORDS];
    w.reserve(words - RIG_HEADER_WORDS);
    let (model, axes) = match state.model() {
        RigModel::Constant => (MODEL_CONSTANT, [AxisModel::Constant; 3]),
        RigModel::Gradient => (MODEL_GRADIENT, [AxisModel::Constant; 3]),
        RigModel::Tensor(axes) => (MODEL_TENSOR, axes),
    };
    w[H_MODEL] = model;
    for (a, axis) in axes.into_iter().enumerate() {
        (w[H_AXIS_X + a], w[H_COUNT_X + a]) = axis_code(axis);
    }
    w[H_COEFFS] = coeffs as u32;
    w[H_PARAMS] = params as u32;
    w[H_LIGHTS] = near.len() as u32;
    let (lo, hi) = state.bounds();
    for k in 0..3 {
        w[H_BOX_MIN + k] = lo[k].to_bits();
        w[H_BOX_MAX + k] = hi[k].to_bits();
    }
    w[H_PARAMETERS] = w.len() as u32;
    w.extend(
        state
            .parameters()
            .iter()
            .flat_map(|c| c.to_array().map(f32::to_bits)),
    );
    w[H_LIGHT_RECORDS] = w.len() as u32;
    for (light, share) in near {
        w.extend(pack_rig_light(light, *share));
    }
    debug_assert_eq!(w.len(), words);
    Ok(w)
}
