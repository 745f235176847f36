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
