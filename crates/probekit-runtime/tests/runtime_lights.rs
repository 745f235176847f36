//! Run-time lights (`LITE`) and the probes' occlusion of them (`OCCL`):
//! round trip, refusal of broken tables, and the combined answer of a
//! query checked against a hand computation (trilinear weights of a grid
//! volume and the closed form `I·max(0, n·ω)/d²` of a point light).

mod common;

use common::*;
use glam::Vec3;
use probekit_runtime::format::*;
use probekit_runtime::rig::Light;
use probekit_runtime::{LoadOptions, ObjectState, Probes};

fn lights() -> Vec<RuntimeLight> {
    runtime_light_list()
}

const OCC: [u8; 20] = OCCLUSION;

fn with_lights(f: ProbeFile) -> ProbeFile {
    with_runtime_lights(f)
}

#[test]
fn runtime_lights_round_trip_sparse() {
    for f in [with_lights(full_file()), with_lights(grid_volume_file())] {
        let bytes = f.to_bytes().unwrap();
        let back = ProbeFile::from_bytes(&bytes).unwrap();
        assert_eq!(back, f);
        let by = file_bytes_by_section(&bytes).unwrap();
        assert!(by["runtime_lights"] > 0 && by["light_occlusion"] > 0);
        let o = &p(&back).runtime_lights.as_ref().unwrap().occlusion;
        // Only the non-zero values are stored.
        assert_eq!(o.entries().len(), OCC.iter().filter(|&&v| v > 0).count());
        assert_eq!(o.counts(), &[3, 2, 0, 4, 4]);
        for i in 0..5 {
            for l in 0..4 {
                assert_eq!(o.value(i, l), OCC[i * 4 + l] as f32 / 255.0);
            }
        }
    }
    assert_eq!(quantize_occlusion(0.5), 128);
    assert_eq!(quantize_occlusion(f32::NAN), 0);
    assert_eq!(quantize_occlusion(2.0), 255);
}

#[test]
fn broken_runtime_light_tables_are_refused() {
    let good = with_lights(full_file());
    // An entry naming a light the file does not hold.
    let mut f = good.clone();
    let l = pm(&mut f).runtime_lights.as_mut().unwrap();
    l.lights.truncate(2);
    assert!(matches!(
        f.to_bytes(),
        Err(FormatError::InvalidValue { .. })
    ));
    // Occlusion rows for another probe count.
    let mut f = good.clone();
    pm(&mut f).runtime_lights.as_mut().unwrap().occlusion =
        LightOcclusion::from_dense(4, &OCC[..16]).unwrap();
    assert!(matches!(
        f.to_bytes(),
        Err(FormatError::CountMismatch { .. })
    ));
    // A spot cone out of order, a zero radius.
    let mut f = good.clone();
    pm(&mut f).runtime_lights.as_mut().unwrap().lights[2].light = Light::Spot {
        position: Vec3::ZERO,
        direction: Vec3::Y,
        inner_deg: 40.0,
        outer_deg: 30.0,
        intensity: Vec3::ONE,
    };
    assert!(f.to_bytes().is_err());
    let mut f = good.clone();
    pm(&mut f).runtime_lights.as_mut().unwrap().lights[1].light = Light::Sphere {
        position: Vec3::ZERO,
        radius: 0.0,
        intensity: Vec3::ONE,
    };
    assert!(f.to_bytes().is_err());

    // LITE without OCCL, an unknown light kind: refused on reading.
    let bytes = good.to_bytes().unwrap();
    let (_, sections) = read_sections(&bytes).unwrap();
    let owned: Vec<(SectionId, Vec<u8>)> = sections
        .iter()
        .filter(|s| s.id != SectionId::LIGHT_OCCLUSION)
        .map(|s| (s.id, s.bytes.to_vec()))
        .collect();
    let no_occl = assemble_file(0, minor_of(&bytes), 0, &owned);
    assert!(matches!(
        ProbeFile::from_bytes(&no_occl),
        Err(FormatError::MissingSection(SectionId::LIGHT_OCCLUSION))
    ));
    let (at, _) = find_section(&bytes, SectionId::RUNTIME_LIGHTS);
    let bad = load_patched(&bytes, |b| put_u32(b, at + 16, 9));
    assert!(matches!(bad, Err(FormatError::InvalidValue { .. })));
}

/// Probes of a 5 × 1 × 1 grid on x ∈ [−1, 2] (spacing 0.75): a point's
/// answer is the SH part plus each light's exact irradiance times the
/// linear blend of its two neighbouring samples' fractions.
#[test]
fn a_query_adds_each_light_times_its_blended_occlusion() {
    let f = with_lights(grid_volume_file());
    let probes = Probes::from_file(&f, LoadOptions::default()).unwrap();
    assert_eq!(probes.runtime_lights().len(), 4);
    let mut st = ObjectState::new();
    let x = Vec3::new(0.2, 0.5, 0.5);
    let n = Vec3::new(0.3, 1.0, -0.2).normalize();
    // x = 0.2: samples 1 and 2, weights 0.4 and 0.6.
    let (t, i0) = ((0.2f64 + 1.0) / 0.75 - 1.0, 1usize);
    let frac = |l: usize| {
        (1.0 - t) * OCC[i0 * 4 + l] as f64 / 255.0 + t * OCC[(i0 + 1) * 4 + l] as f64 / 255.0
    };
    let mut occ = [0.0f32; 4];
    probes.light_occlusion(&mut st, x, &mut occ).unwrap();
    for (l, o) in occ.iter().enumerate() {
        assert!(
            (*o as f64 - frac(l)).abs() < 1e-6,
            "light {l}: {o} vs {}",
            frac(l)
        );
    }
    // The point light in closed form; the others through the light model.
    let w = Vec3::new(0.5, 2.0, 0.0) - x;
    let d2 = w.length_squared() as f64;
    let point = Vec3::new(4.0, 3.0, 2.0).as_dvec3() * (n.dot(w.normalize()).max(0.0) as f64 / d2);
    let mut expected = point * frac(0);
    for (l, r) in lights().iter().enumerate().skip(1) {
        expected += r.light.irradiance(x, n, None).as_dvec3() * frac(l);
    }
    let all = Vec3::from(probes.irradiance(&mut st, x, n).unwrap()).as_dvec3();
    let sh = Vec3::from(probes.sh_irradiance(&mut st, x, n).unwrap()).as_dvec3();
    let got = all - sh;
    assert!(
        (got - expected).length() < 1e-4 * expected.length().max(1.0),
        "{got} vs {expected}"
    );
    // The SH part is what the same file without run-time lights answers.
    let plain = Probes::from_file(&grid_volume_file(), LoadOptions::default()).unwrap();
    let e0 = Vec3::from(plain.irradiance(&mut st, x, n).unwrap()).as_dvec3();
    assert!((e0 - sh).length() < 1e-6 * e0.length().max(1.0));
    // Too short an output slice.
    assert!(probes.light_occlusion(&mut st, x, &mut occ[..2]).is_err());
}

/// Relighting scales a run-time light with its group, as it scales the
/// bounce light the group holds: the light term (answer less SH part)
/// equals `Σ_l s_{group(l)} · E_l(x, n) · occlusion_l`, computed here from
/// the light model and the blended occlusion; lights of groups the file
/// does not hold keep scale 1; `runtime_lights` still reports them as
/// baked.
#[test]
fn relighting_scales_each_run_time_light_with_its_group() {
    let f = with_lights(groups_file());
    let relighter = Relighter::new(&f).unwrap();
    let mut probes = Probes::from_file(&f, LoadOptions::default()).unwrap();
    let scale_of = |g: &str| match g {
        "lamp" => Vec3::new(2.0, 0.5, 0.0),
        "sün" => Vec3::splat(3.0),
        _ => Vec3::ONE,
    };
    let scales = relighter
        .scales_for(&[("lamp", scale_of("lamp")), ("sün", scale_of("sün"))])
        .unwrap();
    probes.relight(&relighter, &scales).unwrap();
    assert_eq!(probes.runtime_lights(), &lights()[..]);
    let mut st = ObjectState::new();
    for x in [Vec3::new(0.2, 0.2, 0.2), Vec3::new(0.5, 0.4, 0.6)] {
        let n = Vec3::new(0.1, 1.0, 0.3).normalize();
        let mut occ = [0.0f32; 4];
        probes.light_occlusion(&mut st, x, &mut occ).unwrap();
        let expected: Vec3 = lights()
            .iter()
            .zip(occ)
            .map(|(r, o)| scale_of(&r.group) * r.light.irradiance(x, n, None) * o)
            .sum();
        let all = Vec3::from(probes.irradiance(&mut st, x, n).unwrap());
        let sh = Vec3::from(probes.sh_irradiance(&mut st, x, n).unwrap());
        let got = all - sh;
        assert!(expected.length() > 0.0, "a light reaches {x}");
        assert!(
            (got - expected).length() < 1e-4 * expected.length(),
            "{x}: {got} vs {expected}"
        );
    }
}
