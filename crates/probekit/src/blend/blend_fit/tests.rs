use super::*;
use crate::capture::{Baker, CaptureSettings};
use crate::delaunay::tetrahedralize;
use glam::Vec3;
use probekit_runtime::cloud::{ProbeCloud, WalkState};
use probekit_sh::ShRgb;

/// Seeded uniform points in `[lo, hi]³` (the crate's sampler).
struct Lcg(crate::sampling::SampleRng);
impl Lcg {
    fn new(seed: u64) -> Self {
        Self(crate::sampling::SampleRng::new(seed, 0, 0))
    }
    fn v(&mut self, lo: f32, hi: f32) -> Vec3 {
        let r = &mut self.0;
        Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * (hi - lo) + Vec3::splat(lo)
    }
}

/// The default settings with regularization `rho`.
fn settings(rho: f32) -> BlendFitSettings {
    BlendFitSettings {
        regularization: rho,
        ..BlendFitSettings::new(1)
    }
}

/// L2 SH of a uniform grey sky of radiance `dc / Y00`.
fn grey(dc: f32) -> ShRgb {
    let mut c = vec![Vec3::ZERO; 9];
    c[0] = Vec3::splat(dc);
    ShRgb::from_coeffs(c).unwrap()
}

/// A 4 × 4 × 4 lattice (1 m) whose probe `bright` has 50× the others'
/// light.
fn outlier_cloud(bright: usize) -> ProbeCloud {
    let mut pos = Vec::new();
    for z in 0..4 {
        for y in 0..4 {
            for x in 0..4 {
                pos.push(Vec3::new(x as f32, y as f32, z as f32));
            }
        }
    }
    let mesh = tetrahedralize(&pos).unwrap().to_tet_mesh(&pos).unwrap();
    let coeffs = (0..pos.len())
        .flat_map(|i| grey(if i == bright { 50.0 } else { 1.0 }).coeffs().to_vec())
        .collect();
    ProbeCloud::new(mesh, 3, coeffs).unwrap()
}

/// Independent relative error of the cloud at `p` against a constant
/// field `truth`: the RMS over 200 Fibonacci-sphere normals of the
/// irradiance difference, over the RMS of the true irradiance.
fn sphere_rel_error(cloud: &ProbeCloud, p: Vec3, truth: &ShRgb) -> f32 {
    let (se, st) = sphere_errors(cloud, p, truth);
    (se / st).sqrt() as f32
}

/// A probe that sees light its neighbourhood does not (50× brighter
/// than a field that is constant everywhere) is weighted down to the
/// floor, the others stay near 1, and the independently measured
/// error at fresh points falls more than tenfold.
#[test]
fn an_outlier_probe_is_weighted_down_and_the_error_falls() {
    let bright = 21; // (1, 1, 1): interior
    let cloud = outlier_cloud(bright);
    let mut g = Lcg::new(1);
    let truth = grey(1.0);
    let training = TrainingSet {
        positions: (0..800).map(|_| g.v(0.05, 2.95)).collect(),
        sh: vec![truth.clone(); 800],
        ..TrainingSet::default()
    };
    let w = fit_probe_weights(&cloud, &training, &settings(1e-5)).unwrap();
    assert_eq!(w.len(), 64);
    assert!(w[bright] < (LOG_WEIGHT_MIN + 1.0).exp(), "{}", w[bright]);
    let mut others: Vec<f32> = (0..64).filter(|&i| i != bright).map(|i| w[i]).collect();
    others.sort_by(f32::total_cmp);
    assert!((0.8..1.25).contains(&others[31]), "median {}", others[31]);
    let mut fitted = cloud.clone();
    fitted.set_probe_weights(Some(w)).unwrap();
    let test: Vec<Vec3> = (0..300).map(|_| g.v(0.05, 2.95)).collect();
    let mean = |c: &ProbeCloud| {
        test.iter()
            .map(|&p| sphere_rel_error(c, p, &truth))
            .sum::<f32>()
            / test.len() as f32
    };
    let (before, after) = (mean(&cloud), mean(&fitted));
    assert!(after < 0.1 * before, "{before} → {after}");
}

/// A very large `ρ` keeps every weight at exactly 1; the fit is
/// deterministic; bad input is a typed error.
#[test]
fn regularization_determinism_and_bad_input() {
    let cloud = outlier_cloud(5);
    let mut g = Lcg::new(2);
    let training = TrainingSet {
        positions: (0..200).map(|_| g.v(0.05, 2.95)).collect(),
        sh: vec![grey(1.0); 200],
        ..TrainingSet::default()
    };
    assert_eq!(
        fit_probe_weights(&cloud, &training, &settings(1e9)).unwrap(),
        vec![1.0; 64]
    );
    let a = fit_probe_weights(&cloud, &training, &settings(1e-4)).unwrap();
    assert_eq!(
        a,
        fit_probe_weights(&cloud, &training, &settings(1e-4)).unwrap()
    );
    // Weights the cloud already has are ignored, and so is a
    // directional exponent in `fit_blend` (not fitted for).
    let mut weighted = cloud.clone();
    weighted.set_probe_weights(Some(vec![7.0; 64])).unwrap();
    assert_eq!(
        fit_probe_weights(&weighted, &training, &settings(1e-4)).unwrap(),
        a
    );
    weighted.set_directional_brightness(2.0).unwrap();
    let d = BlendFitSettings {
        directional: 0.75,
        ..settings(1e-4)
    };
    let f = fit_blend(&weighted, &training, &d, &[0.0]).unwrap();
    assert_eq!((f.weights, f.directional), (a.clone(), 0.75));
    for bad in [-0.5, f32::NAN, 4.5] {
        let s = BlendFitSettings {
            directional: bad,
            ..settings(1e-4)
        };
        assert!(matches!(
            fit_probe_weights(&cloud, &training, &s),
            Err(BlendFitError::Settings(_))
        ));
    }
    // The settings' JSON round trip, the exponents included.
    let j = BlendFitSettings {
        brightness: Some(0.5),
        directional: 0.75,
        ..settings(1e-4)
    };
    assert_eq!(BlendFitSettings::from_json(&j.to_json(), &settings(1.0)), j);
    let mut short = training.clone();
    short.sh.pop();
    assert!(matches!(
        fit_probe_weights(&cloud, &short, &settings(1e-4)),
        Err(BlendFitError::Mismatch(_))
    ));
    let mut l1 = training.clone();
    l1.sh[3] = ShRgb::zeros(2);
    assert!(matches!(
        fit_probe_weights(&cloud, &l1, &settings(1e-4)),
        Err(BlendFitError::Mismatch(_))
    ));
    for bad in [-1.0, f32::NAN, f32::INFINITY] {
        assert!(matches!(
            fit_probe_weights(&cloud, &training, &settings(bad)),
            Err(BlendFitError::Settings(_))
        ));
        let beta = BlendFitSettings {
            absolute_weight: bad,
            ..settings(1e-4)
        };
        assert!(matches!(
            fit_probe_weights(&cloud, &training, &beta),
            Err(BlendFitError::Settings(_))
        ));
    }
    let empty = TrainingSet {
        positions: vec![],
        sh: vec![],
        ..TrainingSet::default()
    };
    assert_eq!(
        fit_probe_weights(&cloud, &empty, &settings(1e-4)).unwrap(),
        vec![1.0; 64]
    );
}

/// L2 SH of a sky whose radiance is `dc / Y00` (uniform) plus a linear
/// lobe `z` along +z: irradiance changes with the normal, so a blend is
/// judged on every band.
fn lobed(dc: f32, z: f32) -> ShRgb {
    let mut c = vec![Vec3::ZERO; 9];
    c[0] = Vec3::splat(dc);
    c[2] = Vec3::splat(z);
    ShRgb::from_coeffs(c).unwrap()
}

/// The lattice of [`outlier_cloud`] holding `field(position)` at each
/// probe, 50× that at probe `outlier`.
fn field_cloud(field: &dyn Fn(Vec3) -> ShRgb, outlier: Option<usize>) -> ProbeCloud {
    let c = outlier_cloud(0);
    let coeffs = c
        .mesh()
        .positions()
        .iter()
        .enumerate()
        .flat_map(|(i, &p)| {
            let k = if Some(i) == outlier { 50.0 } else { 1.0 };
            field(p).coeffs().iter().map(|&x| x * k).collect::<Vec<_>>()
        })
        .collect();
    ProbeCloud::new(c.mesh().clone(), 3, coeffs).unwrap()
}

/// Mean squared irradiance error and mean squared true irradiance over
/// 200 Fibonacci-sphere normals at `p` (RGB lengths).
fn sphere_errors(cloud: &ProbeCloud, p: Vec3, truth: &ShRgb) -> (f64, f64) {
    let mut ws = WalkState::new();
    let (mut se, mut st) = (0.0f64, 0.0f64);
    let n = 200;
    for i in 0..n {
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
        let r = (1.0 - z * z).sqrt();
        let phi = i as f32 * 2.399_963;
        let d = Vec3::new(r * phi.cos(), z, r * phi.sin());
        let t = truth.irradiance(d);
        se += (cloud.irradiance(p, d, &mut ws) - t).length_squared() as f64;
        st += t.length_squared() as f64;
    }
    (se / n as f64, st / n as f64)
}

/// The exponent is chosen by the data, and checked against an
/// independent measure of both criteria (relative-plus-absolute and
/// absolute squared errors integrated over 200 normals at fresh points,
/// not the fit's Gram matrices), for every exponent refitted:
/// * a field linear in space (what barycentric blending reproduces
///   exactly) keeps the plain blend;
/// * one outlier probe 50× brighter than the constant field around it
///   (a doorway probe seeing light the cell does not), weights held at 1
///   by a huge `ρ`, gets an exponent > 0: lower error on both criteria;
/// * a bright ramp meeting a dark region between two probe layers, weights
///   held at 1: an exponent > 0 lowers the relative error of the dark
///   points, but raises the absolute one far beyond the tolerance, so
///   the plain blend is kept.
///
/// In each case the choice is the one the rule makes on the measured
/// errors.
#[test]
fn fit_blend_chooses_the_exponent_the_data_asks_for() {
    let linear = |p: Vec3| lobed(1.0 + 2.0 * p.x, 0.5 + 0.25 * p.y);
    let constant = |_: Vec3| lobed(1.0, 0.4);
    let ramp_then_dark = |p: Vec3| {
        if p.x < 1.5 {
            lobed(10.0 + 40.0 * p.x, 4.0 + 16.0 * p.x)
        } else {
            lobed(1.0, 0.4)
        }
    };
    let mut g = Lcg::new(5);
    type Field<'a> = &'a dyn Fn(Vec3) -> ShRgb;
    let cases: [(&str, Field, Option<usize>, f32, bool); 3] = [
        ("linear", &linear, None, 1e-5, true),
        ("outlier", &constant, Some(21), 1e9, false),
        ("ramp then dark", &ramp_then_dark, None, 1e9, true),
    ];
    for (name, field, outlier, rho, plain_wins) in cases {
        let cloud = field_cloud(field, outlier);
        let pts: Vec<Vec3> = (0..600).map(|_| g.v(0.05, 2.95)).collect();
        let training = TrainingSet {
            sh: pts.iter().map(|&p| field(p)).collect(),
            positions: pts,
            ..TrainingSet::default()
        };
        let fit = settings(rho);
        let chosen = fit_blend(&cloud, &training, &fit, &BRIGHTNESS_CHOICES).unwrap();
        assert_eq!(chosen.weights.len(), 64);
        assert_eq!(chosen.brightness == 0.0, plain_wins, "{name}: {chosen:?}");
        let test: Vec<Vec3> = (0..300).map(|_| g.v(0.05, 2.95)).collect();
        let beta = fit.absolute_weight as f64;
        let measured = |alpha: f32| {
            let f = fit_blend(&cloud, &training, &fit, &[alpha]).unwrap();
            assert_eq!(f.brightness, alpha);
            let mut c = cloud.clone();
            c.set_brightness_weighting(alpha).unwrap();
            c.set_probe_weights(Some(f.weights)).unwrap();
            let e: Vec<(f64, f64)> = test
                .iter()
                .map(|&p| sphere_errors(&c, p, &field(p)))
                .collect();
            let k = e.len() as f64;
            let mean = e.iter().map(|x| x.1.sqrt()).sum::<f64>() / k;
            let mean_square = e.iter().map(|x| x.1).sum::<f64>() / k;
            let objective = e
                .iter()
                .map(|&(se, st)| se / (st.sqrt() + 0.01 * mean).powi(2) + beta * se / mean_square)
                .sum::<f64>()
                / k;
            let absolute = e.iter().map(|x| x.0).sum::<f64>() / k / mean_square;
            (objective, absolute)
        };
        let m = BRIGHTNESS_CHOICES.map(measured);
        let lowest = m.iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
        let rule = (0..m.len())
            .filter(|&i| m[i].1 <= lowest * (1.0 + BRIGHTNESS_ABSOLUTE_TOLERANCE))
            .min_by(|&a, &b| m[a].0.total_cmp(&m[b].0))
            .unwrap();
        assert_eq!(
            BRIGHTNESS_CHOICES[rule], chosen.brightness,
            "{name}: measured (objective, absolute) {m:?}"
        );
        if name == "ramp then dark" {
            // The objective alone would have taken an exponent > 0.
            assert!(m[2].0 < m[0].0 && m[2].1 > 1.1 * m[0].1, "{m:?}");
        }
    }
    // Bad input: no exponent, or one out of range.
    let cloud = outlier_cloud(3);
    let t = TrainingSet {
        positions: vec![Vec3::ONE],
        sh: vec![grey(1.0)],
        ..TrainingSet::default()
    };
    for bad in [&[][..], &[5.0], &[f32::NAN]] {
        assert!(matches!(
            fit_blend(&cloud, &t, &settings(1e-5), bad),
            Err(BlendFitError::Settings(_))
        ));
    }
}

/// On the demo scene: training points are captured in free space and
/// fitted, deterministically, to weights in range, not all 1; bad
/// settings are refused before any work.
#[test]
fn fits_a_small_cloud_of_the_demo_scene() {
    let scene = crate::scene::Scene::load(std::path::Path::new("builtin:demo")).unwrap();
    let baker = Baker::new(&scene).unwrap();
    let b = scene.bake_box();
    let mut pos = Vec::new();
    for i in 0..4 {
        for j in 0..3 {
            for k in 0..3 {
                let t = Vec3::new(i as f32 + 0.5, j as f32 + 0.5, k as f32 + 0.5)
                    / Vec3::new(4.0, 3.0, 3.0);
                let p = b.min + t * (b.max - b.min);
                if !crate::trace::free_space::inside_geometry(baker.tracer(), p) {
                    pos.push(p);
                }
            }
        }
    }
    let mut cs = CaptureSettings::from_scene(&scene);
    cs.samples = 16;
    let sh: Vec<ShRgb> = baker
        .capture_many(&pos, 0, &cs, &|_, _| {})
        .unwrap()
        .into_iter()
        .map(|r| r.sh)
        .collect();
    let file = crate::format::cloud::test_cloud_file(&pos, &sh);
    let fit = BlendFitSettings {
        points_per_probe: 4,
        samples: 16,
        ..BlendFitSettings::new(9)
    };
    let run = || fit_file_probe_weights(&baker, &file, &b, &cs, &fit, &|_, _| {});
    let fitted = run().unwrap();
    assert!(BRIGHTNESS_CHOICES.contains(&fitted.brightness));
    assert_eq!(fitted.directional, DEFAULT_DIRECTIONAL);
    let w = fitted.weights.clone();
    assert_eq!(w.len(), pos.len());
    assert!(w
        .iter()
        .all(|x| probekit_runtime::cloud::PROBE_WEIGHT_RANGE.contains(x)));
    assert!(w.iter().any(|&x| x != 1.0));
    assert_eq!(fitted, run().unwrap());
    // A fixed exponent is kept.
    let fixed = BlendFitSettings {
        brightness: Some(0.25),
        ..fit
    };
    let f = fit_file_probe_weights(&baker, &file, &b, &cs, &fixed, &|_, _| {}).unwrap();
    assert_eq!(f.brightness, 0.25);
    let cloud = ProbeCloud::from_file(&file).unwrap();
    let t = capture_training_set(&baker, &b, cloud.mesh(), 50, &cs, &fit, &|_, _| {}).unwrap();
    assert_eq!(t.positions.len(), 50);
    assert!(t.positions.iter().all(|p| b.contains(*p)));
    for bad in [
        BlendFitSettings {
            points_per_probe: 0,
            ..fit
        },
        BlendFitSettings { samples: 0, ..fit },
        BlendFitSettings {
            regularization: -1.0,
            ..fit
        },
        BlendFitSettings {
            brightness: Some(4.5),
            ..fit
        },
    ] {
        assert!(matches!(
            fit_file_probe_weights(&baker, &file, &b, &cs, &bad, &|_, _| {}),
            Err(BlendFitError::Settings(_))
        ));
    }
}

/// The fit predicts what a query returns when the file has run-time
/// lights: SH part plus each light times the blended occlusion. A lattice
/// whose SH is the same constant field everywhere, but whose interior probe
/// alone sees a directional light the training points do not receive (a
/// doorway probe seeing a sun patch): fitted on the SH part, nothing is
/// wrong and the weights stay 1; fitted on the combined answer, that probe
/// is weighted down (the others stay near 1), and the combined error measured
/// independently (the light's exact irradiance, `Light::irradiance`, over
/// 200 normals at fresh points, not the fit's SH Gram matrices) falls more
/// than tenfold. An occlusion table of another probe count is an error.
#[test]
fn run_time_lights_are_part_of_what_the_weights_are_fitted_on() {
    use probekit_runtime::format::{LightOcclusion, RuntimeLight, RuntimeLights};
    use probekit_runtime::rig::Light;
    let bright = 21; // (1, 1, 1): interior
    let flat: Vec<Vec3> = (0..64).flat_map(|_| grey(1.0).coeffs().to_vec()).collect();
    let cloud = ProbeCloud::new(outlier_cloud(bright).mesh().clone(), 3, flat).unwrap();
    let sun = Light::Directional {
        direction: Vec3::new(0.3, -1.0, 0.2).normalize(),
        irradiance: Vec3::new(5.0, 4.0, 3.0),
    };
    let mut occ = vec![0u8; 64];
    occ[bright] = 255;
    let lights = RuntimeLights {
        lights: vec![RuntimeLight {
            light: sun,
            group: "sun".into(),
        }],
        occlusion: LightOcclusion::from_dense(1, &occ).unwrap(),
    };
    let mut g = Lcg::new(3);
    let truth = grey(1.0);
    let mut training = TrainingSet {
        positions: (0..800).map(|_| g.v(0.05, 2.95)).collect(),
        sh: vec![truth.clone(); 800],
        ..TrainingSet::default()
    };
    let sh_only = fit_probe_weights(&cloud, &training, &settings(1e-5)).unwrap();
    assert!(sh_only.iter().all(|&w| w == 1.0));
    training.lights = Some(lights.clone());
    let w = fit_probe_weights(&cloud, &training, &settings(1e-5)).unwrap();
    assert!(w[bright] < 0.05, "{}", w[bright]);
    let mut others: Vec<f32> = (0..64).filter(|&i| i != bright).map(|i| w[i]).collect();
    others.sort_by(f32::total_cmp);
    assert!((0.8..1.25).contains(&others[31]), "median {}", others[31]);
    // The combined answer's relative error, the light exact.
    let combined_error = |c: &ProbeCloud, pts: &[Vec3]| -> f64 {
        let mut ws = WalkState::new();
        let (mut se, mut st) = (0.0f64, 0.0f64);
        for &p in pts {
            let (probes, wt) = c.weights_at(p, &mut ws);
            let v: f32 = (0..4)
                .map(|k| wt[k] * lights.occlusion.value(probes[k] as usize, 0))
                .sum();
            for i in 0..200 {
                let z = 1.0 - 2.0 * (i as f32 + 0.5) / 200.0;
                let r = (1.0 - z * z).sqrt();
                let phi = i as f32 * 2.399_963;
                let n = Vec3::new(r * phi.cos(), z, r * phi.sin());
                let got = c.irradiance(p, n, &mut ws) + sun.irradiance(p, n, None) * v;
                let t = truth.irradiance(n);
                se += (got - t).length_squared() as f64;
                st += t.length_squared() as f64;
            }
        }
        (se / st).sqrt()
    };
    let test: Vec<Vec3> = (0..300).map(|_| g.v(0.05, 2.95)).collect();
    let mut fitted = cloud.clone();
    fitted.set_probe_weights(Some(w)).unwrap();
    let (before, after) = (
        combined_error(&cloud, &test),
        combined_error(&fitted, &test),
    );
    assert!(after < 0.1 * before, "{before} → {after}");
    // An occlusion table for another cloud.
    training.lights = Some(RuntimeLights {
        occlusion: LightOcclusion::from_dense(1, &[255; 8]).unwrap(),
        ..lights
    });
    assert!(matches!(
        fit_probe_weights(&cloud, &training, &settings(1e-5)),
        Err(BlendFitError::Mismatch(_))
    ));
}

/// Training points captured without a group's direct light report it
/// apart: `sh + excluded` is the capture of all light at the same points
/// (same random numbers, so to rounding), and `excluded` is empty when
/// nothing is left out.
#[test]
fn training_points_report_the_direct_light_they_leave_out() {
    let scene = crate::capture::tests::two_group_room(Vec3::ONE);
    let baker = Baker::new(&scene).unwrap();
    let corners: Vec<Vec3> = (0..8)
        .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, (i >> 2) as f32) * 1.5 - 0.75)
        .collect();
    let mesh = tetrahedralize(&corners)
        .unwrap()
        .to_tet_mesh(&corners)
        .unwrap();
    let fit = BlendFitSettings {
        samples: 256,
        ..BlendFitSettings::new(4)
    };
    let all = CaptureSettings {
        samples: 256,
        ..CaptureSettings::from_scene(&scene)
    };
    let without_a = CaptureSettings {
        exclude_direct: vec!["a".into()],
        ..all.clone()
    };
    let bounds = scene.bake_box();
    let capture = |c: &CaptureSettings| {
        capture_training_points(&baker, &bounds, &mesh, [40, 10], c, &fit, &|_, _| {}).unwrap()
    };
    let (full, part) = (capture(&all), capture(&without_a));
    assert!(full.excluded.is_empty());
    assert_eq!(part.excluded.len(), part.positions.len());
    assert_eq!(full.positions, part.positions);
    let mut left_out = 0.0f32;
    for j in 0..full.positions.len() {
        for k in 0..9 {
            let want = full.sh[j].coeffs()[k];
            let got = part.sh[j].coeffs()[k] + part.excluded[j].coeffs()[k];
            assert!(
                (got - want).abs().max_element() <= 1e-4 * (1.0 + want.abs().max_element()),
                "point {j} coefficient {k}: {got} vs {want}"
            );
        }
        left_out += part.excluded[j].coeffs()[0].x;
    }
    assert!(left_out > 0.0, "the sphere light reaches some point");
}
