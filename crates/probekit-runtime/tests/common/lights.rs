//! A file with run-time lights (`LITE`, `OCCL`) and its broken variants
//! for the corpus.

use super::*;
use probekit_runtime::rig::Light;

/// Four run-time lights of every positional kind and a sun.
pub fn runtime_light_list() -> Vec<RuntimeLight> {
    vec![
        RuntimeLight {
            light: Light::Point {
                position: Vec3::new(0.5, 2.0, 0.0),
                intensity: Vec3::new(4.0, 3.0, 2.0),
            },
            group: "lamp".into(),
        },
        RuntimeLight {
            light: Light::Sphere {
                position: Vec3::new(-0.5, 1.0, 1.0),
                radius: 0.1,
                intensity: Vec3::splat(2.0),
            },
            group: "default".into(),
        },
        RuntimeLight {
            light: Light::Spot {
                position: Vec3::new(0.0, 3.0, 0.0),
                direction: Vec3::NEG_Y,
                inner_deg: 10.0,
                outer_deg: 30.0,
                intensity: Vec3::ONE,
            },
            group: "default".into(),
        },
        RuntimeLight {
            light: Light::Directional {
                direction: Vec3::new(0.0, -0.6, -0.8),
                irradiance: Vec3::splat(3.0),
            },
            group: "sün".into(),
        },
    ]
}

/// Quantised fractions of 5 probes × 4 lights, some zero (not stored).
pub const OCCLUSION: [u8; 20] = [
    255, 0, 12, 200, //
    128, 7, 0, 0, //
    0, 0, 0, 0, //
    64, 255, 1, 99, //
    255, 255, 255, 255,
];

/// `f` (5 probes) with [`runtime_light_list`] and [`OCCLUSION`].
pub fn with_runtime_lights(mut f: ProbeFile) -> ProbeFile {
    pm(&mut f).runtime_lights = Some(RuntimeLights {
        lights: runtime_light_list(),
        occlusion: LightOcclusion::from_dense(4, &OCCLUSION).unwrap(),
    });
    f
}

/// Broken `LITE` and `OCCL` sections, around [`with_runtime_lights`] of
/// [`full_file`].
pub(super) fn runtime_light_cases(v: &mut Vec<(&'static str, Vec<u8>, Expect)>) {
    const LITE: SectionId = SectionId::RUNTIME_LIGHTS;
    const OCCL: SectionId = SectionId::LIGHT_OCCLUSION;
    let f = with_runtime_lights(full_file());
    let good = f.to_bytes().unwrap();
    v.push(("valid_runtime_lights", good.clone(), |_| false));
    v.push((
        "runtime_lights_without_occlusion",
        with_sections(&f, |s| s.retain(|(id, _)| *id != OCCL)),
        |e| matches!(e, FormatError::MissingSection(id) if *id == OCCL),
    ));
    v.push((
        "occlusion_without_runtime_lights",
        with_sections(&f, |s| s.retain(|(id, _)| *id != LITE)),
        |e| matches!(e, FormatError::MissingSection(id) if *id == LITE),
    ));
    v.push((
        "runtime_light_unknown_kind",
        patch(&good, LITE, |s| put_u32(s, 16, 9)),
        |e| matches!(e, FormatError::InvalidValue { id, .. } if *id == LITE),
    ));
    v.push((
        "runtime_light_nan_position",
        patch(&good, LITE, |s| put_u32(s, 16 + 8, f32::NAN.to_bits())),
        |e| matches!(e, FormatError::InvalidValue { id, .. } if *id == LITE),
    ));
    v.push((
        "runtime_light_count_absurd",
        patch(&good, LITE, |s| put_u32(s, 0, u32::MAX)),
        |e| matches!(e, FormatError::SectionSize { id, .. } if *id == LITE),
    ));
    v.push((
        "occlusion_light_count_differs",
        patch(&good, OCCL, |s| put_u32(s, 4, 3)),
        |e| matches!(e, FormatError::CountMismatch { id, .. } if *id == OCCL),
    ));
    v.push((
        "occlusion_entry_count_absurd",
        patch(&good, OCCL, |s| put_u32(s, 8, u32::MAX)),
        |e| matches!(e, FormatError::SectionSize { id, .. } if *id == OCCL),
    ));
    v.push((
        // The first entry (probe 0, light 0) names light 200.
        "occlusion_light_out_of_range",
        patch(&good, OCCL, |s| s[32] = 200),
        |e| matches!(e, FormatError::InvalidValue { id, .. } if *id == OCCL),
    ));
    v.push((
        // Probe 0's entries: lights 0, 2, 3; make them 0, 3, 3.
        "occlusion_entries_out_of_order",
        patch(&good, OCCL, |s| s[34] = 3),
        |e| matches!(e, FormatError::InvalidValue { id, .. } if *id == OCCL),
    ));
    v.push((
        "occlusion_counts_exceed_entries",
        patch(&good, OCCL, |s| s[16] = 9),
        |e| matches!(e, FormatError::CountMismatch { id, .. } if *id == OCCL),
    ));
}
