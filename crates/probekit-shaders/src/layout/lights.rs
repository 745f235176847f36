//! Light records and the sphere-light table, shared by irradiance rigs
//! (`pk_rig`, [`super::pack_split_rig`]) and a cloud's run-time lights
//! (`pk_cloud`, [`super::pack_cloud_with_lights`]):
//! `shaders/probekit_lights.wgsl` reads both kinds of record with one
//! decoder (`pk_light_unpack`) and evaluates them with one function
//! (`pk_light_irradiance`), which reads `pk_sphere_table`.

use super::LayoutError;
use glam::Vec3;
use probekit_runtime::format::RuntimeLights;
use probekit_runtime::rig::{Light, SphereTable};
use probekit_runtime::sh::lights::spot_scale_offset;
use std::ops::Range;

/// The light kinds (word 0 of a light record), by their WGSL constant
/// names (`shaders/probekit_lights.wgsl`; the C API's `PK_LIGHT_*`).
pub const LIGHT_CODES: [(&str, u32); 5] = [
    ("PK_LIGHT_SPHERE", LIGHT_SPHERE),
    ("PK_LIGHT_POINT", LIGHT_POINT),
    ("PK_LIGHT_SPOT", LIGHT_SPOT),
    ("PK_LIGHT_DISK", LIGHT_DISK),
    ("PK_LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
];

pub(super) const LIGHT_SPHERE: u32 = 0;
pub(super) const LIGHT_POINT: u32 = 1;
pub(super) const LIGHT_SPOT: u32 = 2;
pub(super) const LIGHT_DISK: u32 = 3;
pub(super) const LIGHT_DIRECTIONAL: u32 = 4;

/// Words per light record (`PK_RIG_LIGHT_WORDS`), in a rig and in a
/// cloud alike: the kind ([`LIGHT_CODES`]), position (3 f32, m), unit
/// direction (3 f32, the way light travels), radius (m), intensity (3 f32,
/// W/sr; a directional light's irradiance, W/m²), the spot attenuation's
/// scale and offset, the share (a rig's per-vertex share; 1 for a cloud's
/// run-time light), two zero words. Unused fields are zero.
pub const RIG_LIGHT_WORDS: usize = 16;

/// The light record of `light` with share `share` (`PkRigLight` and the
/// share, [`RIG_LIGHT_WORDS`]; a rig's near light carries its per-vertex
/// share, a cloud's run-time light 1). A spot's
/// attenuation scale `1/max(cos inner − cos outer, 0.001)` and offset
/// `−cos outer · scale` are computed here exactly as
/// `probekit_sh::lights::spot_attenuation` computes them, so the shader
/// only multiplies, adds and clamps.
pub fn pack_rig_light(light: &Light, share: f32) -> [u32; RIG_LIGHT_WORDS] {
    let mut r = [0u32; RIG_LIGHT_WORDS];
    let mut put = |at: usize, v: Vec3| {
        for (k, x) in v.to_array().into_iter().enumerate() {
            r[at + k] = x.to_bits();
        }
    };
    let (kind, radius, spot) = match *light {
        Light::Sphere {
            position,
            radius,
            intensity,
        } => {
            put(1, position);
            put(8, intensity);
            (LIGHT_SPHERE, radius, [0.0; 2])
        }
        Light::Point {
            position,
            intensity,
        } => {
            put(1, position);
            put(8, intensity);
            (LIGHT_POINT, 0.0, [0.0; 2])
        }
        Light::Spot {
            position,
            direction,
            inner_deg,
            outer_deg,
            intensity,
        } => {
            put(1, position);
            put(4, direction);
            put(8, intensity);
            let cone = spot_scale_offset(inner_deg.to_radians(), outer_deg.to_radians());
            (LIGHT_SPOT, 0.0, cone)
        }
        Light::Disk {
            position,
            direction,
            radius,
            intensity,
        } => {
            put(1, position);
            put(4, direction);
            put(8, intensity);
            (LIGHT_DISK, radius, [0.0; 2])
        }
        Light::Directional {
            direction,
            irradiance,
        } => {
            put(4, direction);
            put(8, irradiance);
            (LIGHT_DIRECTIONAL, 0.0, [0.0; 2])
        }
    };
    r[0] = kind;
    r[7] = radius.to_bits();
    r[11] = spot[0].to_bits();
    r[12] = spot[1].to_bits();
    r[13] = share.to_bits();
    r
}

/// `pk_sphere_table`: the table's side, then its `side²` entries as f32
/// bits, row after row ([`SphereTable::values`]). Upload once; every rig
/// made by the same [`probekit_runtime::Probes`] shares it, and so do a
/// cloud's run-time lights (`SphereTable::default()`, the table the
/// runtime's rigs use).
pub fn pack_sphere_table(table: &SphereTable) -> Vec<u32> {
    let mut w = Vec::with_capacity(1 + table.values().len());
    w.push(table.size() as u32);
    w.extend(table.values().iter().map(|x| x.to_bits()));
    w
}

/// Words of a probe's occlusion row for `lights` run-time lights: four
/// 8-bit values per word (`⌈lights / 4⌉`).
pub fn light_occlusion_words(lights: usize) -> usize {
    lights.div_ceil(4)
}

/// Where [`put_runtime_lights`] put the sections.
pub(super) struct LightSections {
    /// Word range of the light records.
    pub records: Range<usize>,
    /// Word offset of the occlusion rows.
    pub occlusion: usize,
}

/// Appends a file's run-time lights to `w`: one record per light
/// ([`pack_rig_light`] with share 1), then per probe `i` its occlusion row
/// of [`light_occlusion_words`] words, probe after probe, light `l`'s
/// stored 8-bit visible fraction `v` (`v/255`; 0 where the probe does not
/// list the light) in bits `8·(l mod 4) .. 8·(l mod 4) + 8` of word
/// `l / 4`. The occlusion must be of `probes` probes.
pub(super) fn put_runtime_lights(
    lights: &RuntimeLights,
    probes: usize,
    w: &mut Vec<u32>,
) -> Result<LightSections, LayoutError> {
    let occlusion = &lights.occlusion;
    if occlusion.probe_count() != probes {
        return Err(LayoutError::LightOcclusion {
            probes,
            rows: occlusion.probe_count(),
        });
    }
    let start = w.len();
    for l in &lights.lights {
        w.extend(pack_rig_light(&l.light, 1.0));
    }
    let records = start..w.len();
    let stride = light_occlusion_words(lights.lights.len());
    let at = w.len();
    w.resize(at + stride * probes, 0);
    for i in 0..probes {
        for &[l, v] in occlusion.probe(i) {
            let l = usize::from(l);
            if l < lights.lights.len() {
                w[at + stride * i + l / 4] |= u32::from(v) << (8 * (l % 4));
            }
        }
    }
    Ok(LightSections {
        records,
        occlusion: at,
    })
}
