//! Tests of the path-traced volume source ([`super::BakerSource`]).

use super::*;
use crate::capture::{CaptureSettings, ValiditySettings};
use crate::format::layout::{VALIDITY_INVALID, VALIDITY_VIRTUAL_OFFSET};
use crate::format::Parts;
use crate::scene::{Light, LightKind, Material, Scene, Triangle};
use crate::sh::lights::sphere_light_sh_and_gradient;
use glam::{Vec2, Vec3};
use proptest::prelude::*;
use std::sync::Mutex;

fn tri(a: Vec3, b: Vec3, c: Vec3) -> Triangle {
    let n = (b - a).cross(c - a).normalize();
    Triangle {
        positions: [a, b, c],
        normals: [n; 3],
        uvs: [Vec2::ZERO; 3],
        material: 0,
    }
}

/// A closed axis-aligned box, faces pointing outward.
fn box_tris(min: Vec3, max: Vec3) -> Vec<Triangle> {
    let c = (min + max) * 0.5;
    let h = (max - min) * 0.5;
    let mut out = Vec::new();
    for a in 0..3 {
        let (ua, va) = ((a + 1) % 3, (a + 2) % 3);
        for s in [-1.0f32, 1.0] {
            let fc = c + Vec3::AXES[a] * h[a] * s;
            let (u, v) = (Vec3::AXES[ua] * h[ua], Vec3::AXES[va] * h[va]);
            let mut q = [fc - u - v, fc + u - v, fc + u + v, fc - u + v];
            if s < 0.0 {
                q.reverse();
            }
            out.push(tri(q[0], q[1], q[2]));
            out.push(tri(q[0], q[2], q[3]));
        }
    }
    out
}

/// A scene of `objects` (grey, albedo 0.5) under a uniform sky; a 1 mm
/// speck 1 km away stands in when there is no geometry.
fn scene(objects: Vec<Triangle>, sky: Vec3, lights: Vec<Light>) -> Scene {
    let far = Vec3::splat(1000.0);
    let mut objs = vec![(
        "speck".to_string(),
        vec![tri(far, far + Vec3::X * 1e-3, far + Vec3::Y * 1e-3)],
    )];
    if !objects.is_empty() {
        objs.push(("box".to_string(), objects));
    }
    let mat = Material {
        name: "grey".into(),
        base_color: Vec3::splat(0.5),
        ..Material::default()
    };
    let mut s = Scene::from_triangles("test", objs, vec![mat], lights).expect("scene");
    s.environment.color = sky;
    s
}

fn settings(samples: u32, virtual_offset: bool) -> CaptureSettings {
    CaptureSettings {
        samples,
        bounces: 1,
        order: 3,
        seed: 7,
        validity: ValiditySettings {
            virtual_offset,
            pre_pass_rays: 64,
            ..ValiditySettings::default()
        },
        ..CaptureSettings::default()
    }
}

fn common(min: Vec3, max: Vec3, src: &BakerSource, g: GradientMode) -> CommonSettings {
    CommonSettings {
        min,
        max,
        gradients: g,
        validity_threshold: src.validity_threshold(),
    }
}

fn sample_sh(file: &crate::format::ProbeFile, i: usize) -> Vec<Vec3> {
    let n = (file.probe_set().coefficients.order * file.probe_set().coefficients.order) as usize;
    file.probe_set().coefficients.to_f32().unwrap()[i * n..(i + 1) * n].to_vec()
}

/// Under a uniform sky `L` and nothing else, every sample's irradiance is
/// `π·L` for every normal (∫ L max(0, n·ω) dω = πL), evaluated from the
/// stored SH by the SH core's convolution at 50 normals.
#[test]
fn uniform_sky_gives_pi_l_irradiance_at_every_sample() {
    let sky = Vec3::new(0.5, 0.8, 1.2);
    let sc = scene(Vec::new(), sky, Vec::new());
    let src = BakerSource::new(&sc, settings(256, true)).unwrap();
    let c = common(Vec3::splat(-1.0), Vec3::ONE, &src, GradientMode::None);
    let (file, stats) = build_uniform(&src, &c, [3, 2, 2]).unwrap();
    assert_eq!(stats.captures, 12);
    assert_eq!(src.captures(), 12);
    assert_eq!(stats.dilated, 0);
    for i in 0..file.probe_set().positions.len() {
        let sh = probekit_sh::ShRgb::from_coeffs(sample_sh(&file, i)).unwrap();
        for n in probekit_sh::fibonacci_sphere(50) {
            let e = sh.irradiance(n);
            let want = sky * std::f32::consts::PI;
            assert!(
                ((e - want) / want).abs().max_element() < 0.03,
                "sample {i} normal {n}: {e} vs {want}"
            );
        }
    }
}

/// A sample inside a closed box: without virtual offset it is flagged
/// invalid and dilated from its neighbours (not black); with it, it is
/// captured outside, flagged `VIRTUAL_OFFSET`, valid, and still stored at
/// its grid corner.
#[test]
fn sample_inside_a_closed_box_is_flagged_and_dilated_or_offset() {
    let sky = Vec3::splat(1.0);
    let sc = scene(
        box_tris(Vec3::splat(-0.3), Vec3::splat(0.3)),
        sky,
        Vec::new(),
    );
    let centre = 13; // (1,1,1) of a 3×3×3 grid over [-1,1]³
    let off = BakerSource::new(&sc, settings(64, false)).unwrap();
    let c = common(Vec3::splat(-1.0), Vec3::ONE, &off, GradientMode::None);
    let (file, stats) = build_uniform(&off, &c, [3, 3, 3]).unwrap();
    assert_eq!(file.probe_set().positions[centre], Vec3::ZERO);
    let v = file.probe_set().validity.as_ref().unwrap();
    assert_eq!(stats.dilated, 1);
    assert!(v[centre].flags & VALIDITY_INVALID != 0);
    assert!(v
        .iter()
        .enumerate()
        .all(|(i, x)| i == centre || x.flags == 0));
    // Dilated: the mean of the 26 valid neighbours (all equal validity 1).
    let mut mean = [Vec3::ZERO; 9];
    for j in (0..27).filter(|&j| j != centre) {
        for (m, s) in mean.iter_mut().zip(sample_sh(&file, j)) {
            *m += s / 26.0;
        }
    }
    let got = sample_sh(&file, centre);
    assert!(got[0].min_element() > 0.1, "black: {:?}", got[0]);
    for (g, m) in got.iter().zip(&mean) {
        assert!((*g - *m).abs().max_element() < 1e-4, "{g} vs {m}");
    }

    let on = BakerSource::new(&sc, settings(64, true)).unwrap();
    let (file, stats) = build_uniform(&on, &c, [3, 3, 3]).unwrap();
    let v = file.probe_set().validity.as_ref().unwrap();
    assert_eq!(stats.dilated, 0);
    assert_eq!(file.probe_set().positions[centre], Vec3::ZERO);
    assert_eq!(v[centre].flags, VALIDITY_VIRTUAL_OFFSET);
    assert!(v[centre].value >= on.validity_threshold());
    // Captured just outside a face: it sees about half the sky (+ the
    // lit box face), far from black.
    assert!(sample_sh(&file, centre)[0].min_element() > 0.5);
}

/// Central-difference gradients of the baker source near a sphere light
/// (no geometry, direct light only) against (a) the closed-form sphere-light
/// SH gradient of the SH core and (b) a finite difference of two direct
/// `Baker` captures at a 4× larger step with the sample's random numbers.
#[test]
fn central_gradients_match_the_closed_form_and_a_wider_difference() {
    let l = Light {
        kind: LightKind::Sphere,
        position: Vec3::new(0.2, 1.5, -0.3),
        direction: Vec3::NEG_Y,
        color: Vec3::ONE,
        intensity: 20.0,
        radius: 0.3,
        inner_angle: 0.0,
        outer_angle: 0.0,
        group: None,
        mode: crate::scene::LightMode::Auto,
        angular_diameter: 0.0,
    };
    let sc = scene(Vec::new(), Vec3::ZERO, vec![l.clone()]);
    let mut s = settings(1024, false);
    s.bounces = 0;
    let src = BakerSource::new(&sc, s.clone()).unwrap();
    let h = 0.02;
    let c = common(
        Vec3::new(-0.5, -0.5, -0.5),
        Vec3::new(0.5, 0.0, 0.5),
        &src,
        GradientMode::Central { step: h },
    );
    let (file, stats) = build_uniform(&src, &c, [2, 2, 2]).unwrap();
    assert_eq!(stats.captures, 8 * 7);
    let g = &file.volume().gradients.as_ref().unwrap().data;
    let n = 9;
    let mut value = vec![Vec3::ZERO; n];
    let mut grad = vec![[Vec3::ZERO; 3]; n];
    let baker = crate::capture::Baker::new(&sc).unwrap();
    for (i, p) in file.probe_set().positions.iter().enumerate() {
        sphere_light_sh_and_gradient(
            3,
            *p,
            l.position,
            l.radius,
            l.color * l.intensity,
            &mut value,
            &mut grad,
        );
        // The stored value itself matches the closed form.
        let got = sample_sh(&file, i);
        let vnorm: f32 = value.iter().map(|v| v.length_squared()).sum::<f32>().sqrt();
        let verr: f32 = got
            .iter()
            .zip(&value)
            .map(|(a, b)| (*a - *b).length_squared())
            .sum::<f32>()
            .sqrt();
        assert!(verr < 0.03 * vnorm, "sample {i} value: {verr} vs {vnorm}");
        let norm: f32 = grad
            .iter()
            .flat_map(|c| c.iter())
            .map(|v| v.length_squared())
            .sum::<f32>()
            .sqrt();
        let mut err = 0.0f32;
        for a in 0..3 {
            for k in 0..n {
                err += (g[(i * 3 + a) * n + k] - grad[k][a]).length_squared();
            }
        }
        assert!(
            err.sqrt() < 0.08 * norm,
            "sample {i}: {} vs {norm}",
            err.sqrt()
        );
        // (b): x axis, step 4h, the same key as the sample.
        let key = position_key(*p);
        let e = Vec3::X * 4.0 * h;
        let plus = baker.capture(*p + e, key, &s).unwrap();
        let minus = baker.capture(*p - e, key, &s).unwrap();
        for k in 0..n {
            let wide = (plus.sh.coeffs()[k] - minus.sh.coeffs()[k]) / (8.0 * h);
            assert!(
                (wide - g[(i * 3) * n + k]).length() < 0.05 * norm,
                "sample {i} coeff {k}: {wide} vs {}",
                g[(i * 3) * n + k]
            );
        }
    }
}

/// Records every captured point, to check corners are captured once.
struct Recording<'a> {
    inner: &'a BakerSource<'a>,
    seen: Mutex<Vec<Vec3>>,
}

impl VolumeSource for Recording<'_> {
    fn order(&self) -> usize {
        self.inner.order()
    }
    fn capture(&self, points: &[Vec3]) -> Vec<Captured> {
        self.seen.lock().unwrap().extend_from_slice(points);
        self.inner.capture(points)
    }
    fn contains_geometry(&self, min: Vec3, max: Vec3) -> bool {
        self.inner.contains_geometry(min, max)
    }
    fn depth_harmonic_mean(&self, p: Vec3) -> f32 {
        self.inner.depth_harmonic_mean(p)
    }
}

/// An adaptive build around a box refines at the box (geometry heuristic),
/// captures every lattice point once (no position twice, count = stats),
/// and gives the same bytes as a second build on one thread.
#[test]
fn adaptive_baker_build_captures_shared_corners_once_and_is_deterministic() {
    let sc = scene(
        box_tris(Vec3::new(0.1, -0.9, 0.1), Vec3::new(0.7, -0.3, 0.7)),
        Vec3::splat(1.0),
        Vec::new(),
    );
    let src = BakerSource::new(&sc, settings(16, true)).unwrap();
    let rec = Recording {
        inner: &src,
        seen: Mutex::new(Vec::new()),
    };
    let s = super::tests::geometry_only(
        common(Vec3::splat(-1.0), Vec3::ONE, &src, GradientMode::None),
        3,
    );
    let (file, stats) = build_adaptive(&rec, &s).unwrap();
    let seen = rec.seen.into_inner().unwrap();
    let mut keys: Vec<[u32; 3]> = seen
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    assert_eq!(keys.len(), seen.len(), "a point was captured twice");
    assert_eq!(seen.len(), stats.captures);
    assert_eq!(src.captures(), stats.captures);
    // Refined only where the box is: depth-3 leaves exist, and all of them
    // touch the box's octant (x > 0, y < 0, z > 0).
    let oct = file.octree().unwrap();
    let deep: Vec<_> = oct
        .nodes
        .iter()
        .filter(|n| n.sample_count > 0 && n.depth == 3)
        .collect();
    assert!(!deep.is_empty());
    assert!(deep
        .iter()
        .all(|n| n.max.x >= 0.0 && n.min.y <= 0.0 && n.max.z >= 0.0));
    assert!(oct.nodes.iter().any(|n| n.sample_count > 0 && n.depth == 1));
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let src1 = BakerSource::new(&sc, settings(16, true)).unwrap();
    let (again, _) = one.install(|| build_adaptive(&src1, &s)).unwrap();
    assert_eq!(again, file);
}

/// The harmonic mean of scene depth at the centre of a closed cube of
/// half-size a is `a / mean(max|dᵢ|)` over directions; the mean is computed
/// here by a midpoint rule over (cos θ, φ) (independent of the source's
/// Fibonacci rays).
#[test]
fn depth_harmonic_mean_in_a_cube_matches_quadrature() {
    let a = 0.8;
    let sc = scene(
        box_tris(Vec3::splat(-a), Vec3::splat(a)),
        Vec3::ONE,
        Vec::new(),
    );
    let src = BakerSource::new(&sc, settings(4, false))
        .unwrap()
        .with_depth_rays(4096);
    let (nz, nphi) = (400, 800);
    let mut sum = 0.0f64;
    for i in 0..nz {
        let z = -1.0 + (i as f64 + 0.5) * 2.0 / nz as f64;
        let r = (1.0 - z * z).sqrt();
        for j in 0..nphi {
            let phi = (j as f64 + 0.5) * std::f64::consts::TAU / nphi as f64;
            let d = [r * phi.cos(), r * phi.sin(), z];
            sum += d.iter().map(|x| x.abs()).fold(0.0, f64::max);
        }
    }
    let want = a as f64 / (sum / (nz * nphi) as f64);
    let got = src.depth_harmonic_mean(Vec3::ZERO) as f64;
    assert!((got - want).abs() < 0.005 * want, "{got} vs {want}");
    // Outside everything (the speck aside): nothing is hit.
    let empty = scene(Vec::new(), Vec3::ONE, Vec::new());
    let src = BakerSource::new(&empty, settings(4, false)).unwrap();
    assert!(src.depth_harmonic_mean(Vec3::ZERO) > 1e3);
}

/// The geometry heuristic on a box scene: cells through a face contain
/// geometry, cells strictly inside or outside do not.
#[test]
fn contains_geometry_finds_the_box_faces_only() {
    let sc = scene(
        box_tris(Vec3::splat(-0.5), Vec3::splat(0.5)),
        Vec3::ONE,
        Vec::new(),
    );
    let src = BakerSource::new(&sc, settings(4, false)).unwrap();
    assert!(src.contains_geometry(Vec3::new(0.4, -0.1, -0.1), Vec3::new(0.6, 0.1, 0.1)));
    assert!(!src.contains_geometry(Vec3::splat(-0.2), Vec3::splat(0.2)));
    assert!(!src.contains_geometry(Vec3::splat(0.6), Vec3::splat(0.9)));
    assert!(src.contains_geometry(Vec3::splat(-2.0), Vec3::splat(2.0)));
}

fn dense_overlap(t: [Vec3; 3], min: Vec3, max: Vec3, margin: f32) -> bool {
    let n = 60;
    for i in 0..=n {
        for j in 0..=(n - i) {
            let (b1, b2) = (i as f32 / n as f32, j as f32 / n as f32);
            let p = t[0] * (1.0 - b1 - b2) + t[1] * b1 + t[2] * b2;
            if (p.cmpge(min - margin) & p.cmple(max + margin)).all() {
                return true;
            }
        }
    }
    false
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    /// Separating-axis overlap against dense barycentric sampling of the
    /// triangle: a sample inside the box ⇒ overlap; overlap ⇒ a sample
    /// within one sampling spacing of the box.
    #[test]
    fn triangle_box_overlap_agrees_with_dense_sampling(
        v in proptest::array::uniform9(-1.0f32..1.0),
        c in proptest::array::uniform3(-0.5f32..0.5),
        h in proptest::array::uniform3(0.05f32..0.6),
    ) {
        let t = [
            Vec3::new(v[0], v[1], v[2]),
            Vec3::new(v[3], v[4], v[5]),
            Vec3::new(v[6], v[7], v[8]),
        ];
        let (c, h) = (Vec3::from(c), Vec3::from(h));
        let (min, max) = (c - h, c + h);
        let got = triangle_box_overlap(t, min, max);
        if dense_overlap(t, min, max, 0.0) {
            prop_assert!(got);
        }
        if got {
            let spacing = (t[1] - t[0]).length().max((t[2] - t[0]).length()) / 60.0;
            prop_assert!(dense_overlap(t, min, max, spacing + 1e-4));
        }
    }
}

/// `depth_rows` on an adaptive LightsDemo volume: leaf counts per depth add
/// up to the leaves, samples to the samples, volume fractions to 1.
#[test]
fn depth_rows_partition_leaves_samples_and_volume() {
    let src = LightsDemo::demo(2);
    let (min, max) = LightsDemo::demo_box();
    let common = CommonSettings {
        min,
        max,
        gradients: GradientMode::None,
        validity_threshold: 0.5,
    };
    let s = AdaptiveSettings {
        prediction_tolerance: Some(0.25),
        ..super::tests::geometry_only(common, 3)
    };
    let (file, stats) = build_adaptive(&src, &s).unwrap();
    let rows = depth_rows(&file);
    assert_eq!(rows.iter().map(|r| r.leaves).sum::<usize>(), stats.leaves);
    assert_eq!(rows.iter().map(|r| r.samples).sum::<usize>(), stats.samples);
    let vol: f64 = rows.iter().map(|r| r.volume_fraction).sum();
    assert!((vol - 1.0).abs() < 1e-9);
    assert_eq!(rows[0].leaves, 0);
    assert!(rows[3].leaves > 0);
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("d.png");
    plot_depths(&file, &p, "t").unwrap();
    assert!(std::fs::metadata(&p).unwrap().len() > 1000);
}

/// Draws docs/img/volume_error_memory.png from the CSV named by
/// `PROBEKIT_VOLBAKE_CSV` (`method,bytes,rel_rmse` rows, one line per
/// method in file order), for BENCHMARKS.md, "Irradiance volumes against
/// uniform grids". Not a test: run with `--ignored` after the measurement script.
#[test]
#[ignore]
fn draw_error_memory_plot_from_bench_csv() {
    let Ok(csv) = std::env::var("PROBEKIT_VOLBAKE_CSV") else {
        return;
    };
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let (x, y) = (f[1].parse::<f64>().unwrap(), f[2].parse::<f64>().unwrap());
        match series.iter_mut().find(|s| s.0 == f[0]) {
            Some(s) => s.1.push((x, y)),
            None => series.push((f[0].to_string(), vec![(x, y)])),
        }
    }
    for s in &mut series {
        s.1.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    let out = std::env::var("PROBEKIT_VOLBAKE_PNG")
        .unwrap_or_else(|_| "../../docs/img/volume_error_memory.png".into());
    let title = std::env::var("PROBEKIT_VOLBAKE_TITLE")
        .unwrap_or_else(|_| "builtin:demo: eval rel. RMSE vs file bytes".into());
    crate::plot::line_chart_log(
        out,
        &title,
        &series,
        "bytes (inspect --json)",
        &std::env::var("PROBEKIT_VOLBAKE_YLABEL").unwrap_or_else(|_| "rel_rmse".into()),
        true,
        true,
    )
    .unwrap();
}

/// The capture's standard error is the batch-means formula over its
/// 256-sample chunks, recomputed here from captures of 256, 512, 768 and
/// 1024 samples (the same random numbers per sample index, so chunk `k`'s
/// mean is `k·c_k − (k−1)·c_{k−1}`); below two chunks there is none.
#[test]
fn capture_std_error_is_batch_means_over_the_chunks() {
    let sc = scene(
        box_tris(Vec3::new(0.3, -1.0, -1.0), Vec3::new(1.0, 1.0, 1.0)),
        Vec3::ONE,
        Vec::new(),
    );
    let baker = crate::capture::Baker::new(&sc).unwrap();
    let p = Vec3::new(-0.2, 0.1, 0.0);
    let cap = |n: u32| baker.capture_with_error(p, 5, &settings(n, false)).unwrap();
    assert!(cap(256).1.is_none());
    let c: Vec<Vec<Vec3>> = (1..=4)
        .map(|k| cap(256 * k).0.sh.coeffs().to_vec())
        .collect();
    let (_, se) = cap(1024);
    let se = se.unwrap();
    assert_eq!(se.len(), 9);
    for i in 0..9 {
        let m: Vec<Vec3> = (0..4)
            .map(|k| {
                let prev = if k == 0 {
                    Vec3::ZERO
                } else {
                    c[k - 1][i] * k as f32
                };
                c[k][i] * (k + 1) as f32 - prev
            })
            .collect();
        let mean = m.iter().copied().sum::<Vec3>() / 4.0;
        let var = m.iter().map(|x| (*x - mean) * (*x - mean)).sum::<Vec3>() / 3.0;
        let want = (var / 4.0).powf(0.5);
        let tol = 1e-3 * c[3][0].length() + 1e-3 * want.length();
        assert!(
            (se[i] - want).abs().max_element() <= tol,
            "{i}: {} vs {want}",
            se[i]
        );
    }
    // A Monte Carlo capture of a lit scene is noisy, not exact.
    assert!(se[0].max_element() > 0.0);
}

/// The emitter rule's test: an emissive triangle (not its box) and a sphere light's
/// ball (its radius around its position) overlap a cell; nothing else does.
#[test]
fn contains_emitter_finds_emissive_triangles_and_positional_lights() {
    let emissive = |t: Triangle| Triangle { material: 1, ..t };
    let quad = [
        emissive(tri(
            Vec3::new(0.0, 0.9, 0.0),
            Vec3::new(0.2, 0.9, 0.0),
            Vec3::new(0.2, 0.9, 0.2),
        )),
        emissive(tri(
            Vec3::new(0.0, 0.9, 0.0),
            Vec3::new(0.2, 0.9, 0.2),
            Vec3::new(0.0, 0.9, 0.2),
        )),
        // A diagonal triangle at z = 0.5, x + y ≤ −1 (its box reaches x + y = −0.2).
        emissive(tri(
            Vec3::new(-0.9, -0.9, 0.5),
            Vec3::new(-0.1, -0.9, 0.5),
            Vec3::new(-0.9, -0.1, 0.5),
        )),
    ];
    let lamp = Material {
        name: "lamp".into(),
        emissive: Vec3::splat(5.0),
        ..Material::default()
    };
    let grey = Material {
        name: "grey".into(),
        base_color: Vec3::splat(0.5),
        ..Material::default()
    };
    let mut objs: Vec<(String, Vec<Triangle>)> = vec![(
        "walls".into(),
        box_tris(Vec3::splat(-1.0), Vec3::splat(1.0)),
    )];
    objs.push(("lamp".into(), quad.to_vec()));
    let light = |kind, position: Vec3, radius| Light {
        kind,
        position,
        direction: Vec3::NEG_Y,
        color: Vec3::ONE,
        intensity: 1.0,
        radius,
        inner_angle: 0.0,
        outer_angle: 0.0,
        group: None,
        mode: crate::scene::LightMode::Auto,
        angular_diameter: 0.0,
    };
    let sphere = light(LightKind::Sphere, Vec3::splat(-0.5), 0.1);
    // A directional light has no position (its field is ignored).
    let sun = light(LightKind::Directional, Vec3::new(0.95, 0.05, 0.05), 0.0);
    let sc =
        Scene::from_triangles("emit", objs, vec![grey, lamp], vec![sphere, sun]).expect("scene");
    assert_eq!(sc.emissive_triangles.len(), 3, "the quad and the diagonal");
    let src = BakerSource::new(&sc, settings(4, false)).unwrap();
    let cell = |lo: [f32; 3], size: f32| (Vec3::from(lo), Vec3::from(lo) + size);
    // The quad (y = 0.9, x and z in [0, 0.2]).
    let (a, b) = cell([0.1, 0.85, 0.1], 0.1);
    assert!(src.contains_emitter(a, b));
    let (a, b) = cell([0.25, 0.85, 0.1], 0.1);
    assert!(!src.contains_emitter(a, b));
    let (a, b) = cell([0.1, 0.7, 0.1], 0.1);
    assert!(!src.contains_emitter(a, b));
    // The sphere light's ball: a cell 0.05 from its centre, and one 0.3 away.
    let (a, b) = cell([-0.45, -0.5, -0.5], 0.1);
    assert!(src.contains_emitter(a, b));
    let (a, b) = cell([-0.2, -0.5, -0.5], 0.1);
    assert!(!src.contains_emitter(a, b));
    // The diagonal triangle: by its surface, not its box.
    let (a, b) = cell([-0.8, -0.8, 0.45], 0.1);
    assert!(src.contains_emitter(a, b));
    let (a, b) = cell([-0.25, -0.25, 0.45], 0.1);
    assert!(!src.contains_emitter(a, b));
    // The walls are not emitters, and the sun has no position.
    let (a, b) = cell([0.95, 0.0, 0.0], 0.1);
    assert!(!src.contains_emitter(a, b));
}
