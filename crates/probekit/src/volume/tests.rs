use super::*;
use crate::format::Parts;
use crate::sh::ShRgb;
use glam::Vec3;
use std::sync::Mutex;

/// A source from closures: value and (optionally) gradient of every
/// coefficient, independent of the volume code.
struct FieldSource<F: Fn(Vec3) -> Vec<Vec3> + Sync, G: Fn(Vec3) -> Vec<Vec3> + Sync> {
    order: usize,
    f: F,
    g: G,
    log: Mutex<Vec<Vec3>>,
}

impl<F: Fn(Vec3) -> Vec<Vec3> + Sync, G: Fn(Vec3) -> Vec<Vec3> + Sync> VolumeSource
    for FieldSource<F, G>
{
    fn order(&self) -> usize {
        self.order
    }
    fn capture(&self, points: &[Vec3]) -> Vec<Captured> {
        self.log.lock().unwrap().extend_from_slice(points);
        points.iter().map(|p| exact((self.f)(*p))).collect()
    }
    fn analytic_gradients(&self, points: &[Vec3]) -> Option<Vec<Vec3>> {
        Some(points.iter().flat_map(|p| (self.g)(*p)).collect())
    }
}

/// A fully valid capture of exact (noise-free) radiance SH `coeffs`.
fn exact(coeffs: Vec<Vec3>) -> Captured {
    Captured {
        sh: ShRgb::from_coeffs(coeffs).unwrap(),
        validity: 1.0,
        virtual_offset: false,
        std_error: None,
    }
}

fn common(min: Vec3, max: Vec3, gradients: GradientMode) -> CommonSettings {
    CommonSettings {
        min,
        max,
        gradients,
        validity_threshold: 0.5,
    }
}

/// Octree settings with only the geometry heuristic on, depths 1 to
/// `max_depth`: no depth, gradient, prediction or prune test, no noise
/// discount, no balance.
pub(super) fn geometry_only(common: CommonSettings, max_depth: u32) -> AdaptiveSettings {
    AdaptiveSettings {
        common,
        min_depth: 1,
        max_depth,
        geometry: true,
        depth_factor: None,
        gradient_threshold: None,
        prediction_tolerance: None,
        prune_tolerance: None,
        relative_floor: 0.0,
        geometry_depth: u32::MAX,
        emitter_depth: 0,
        noise_k: 0.0,
        balance: false,
        roots: Some([1, 1, 1]),
    }
}

/// Deterministic pseudo-random numbers in [0, 1) (xorshift).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn point(&mut self, min: Vec3, max: Vec3) -> Vec3 {
        min + Vec3::new(self.next(), self.next(), self.next()) * (max - min)
    }
}

fn sh_at(v: &Volume, p: Vec3, i: Interp) -> Vec<Vec3> {
    let mut out = vec![Vec3::ZERO; v.coeffs_per_sample()];
    v.sample_sh(p, i, &mut out).unwrap();
    out
}

fn dist(a: &[Vec3], b: &[Vec3]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).length_squared())
        .sum::<f32>()
        .sqrt()
}

#[test]
fn uniform_trilinear_reproduces_a_linear_field() {
    let f = |p: Vec3| {
        (0..4)
            .map(|k| {
                Vec3::splat(1.0 + k as f32)
                    + p * (0.3 * k as f32 - 0.5)
                    + Vec3::new(p.y, p.z, p.x) * 0.2
            })
            .collect::<Vec<_>>()
    };
    let src = FieldSource {
        order: 2,
        f,
        g: |_| vec![Vec3::ZERO; 12],
        log: Mutex::new(vec![]),
    };
    let (min, max) = (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(2.0, 1.5, 3.0));
    let (file, stats) =
        build_uniform(&src, &common(min, max, GradientMode::None), [4, 3, 5]).unwrap();
    assert_eq!(stats.samples, 60);
    let v = Volume::from_file(&file).unwrap();
    let mut rng = Rng(7);
    for _ in 0..200 {
        let p = rng.point(min, max);
        let got = sh_at(&v, p, Interp::Trilinear);
        assert!(dist(&got, &f(p)) < 1e-4, "{p}: {got:?} vs {:?}", f(p));
    }
}

#[test]
fn tricubic_is_exact_for_separable_cubics_and_trilinear_is_not() {
    // c(p) = x³ − 2y² + z³/3 + x (per coefficient, scaled), gradient exact.
    let f = |p: Vec3| {
        let s = p.x.powi(3) - 2.0 * p.y * p.y + p.z.powi(3) / 3.0 + p.x;
        vec![Vec3::new(s, 2.0 * s, -s)]
    };
    let g = |p: Vec3| {
        let d = Vec3::new(3.0 * p.x * p.x + 1.0, -4.0 * p.y, p.z * p.z);
        vec![
            Vec3::new(d.x, 2.0 * d.x, -d.x),
            Vec3::new(d.y, 2.0 * d.y, -d.y),
            Vec3::new(d.z, 2.0 * d.z, -d.z),
        ]
    };
    let src = FieldSource {
        order: 1,
        f,
        g,
        log: Mutex::new(vec![]),
    };
    let (min, max) = (Vec3::splat(-1.0), Vec3::splat(1.0));
    let (file, _) =
        build_uniform(&src, &common(min, max, GradientMode::Analytic), [4, 4, 4]).unwrap();
    let v = Volume::from_file(&file).unwrap();
    let mut rng = Rng(11);
    let (mut e_cubic, mut e_lin) = (0.0f32, 0.0f32);
    for _ in 0..200 {
        let p = rng.point(min, max);
        let want = f(p);
        e_cubic = e_cubic.max(dist(&sh_at(&v, p, Interp::Tricubic), &want));
        e_lin = e_lin.max(dist(&sh_at(&v, p, Interp::Trilinear), &want));
    }
    assert!(e_cubic < 1e-4, "tricubic error {e_cubic}");
    assert!(e_lin > 1e-2, "trilinear error {e_lin} suspiciously small");
}

fn lights_no_slab(order: usize) -> LightsDemo {
    let mut d = LightsDemo::demo(order);
    d.slabs.clear();
    d
}

#[test]
fn central_differences_match_the_closed_form_sphere_light_gradient() {
    let src = lights_no_slab(3);
    let (min, max) = (Vec3::new(-0.5, -0.5, -0.5), Vec3::new(0.5, 0.5, 0.5));
    let (a, _) = build_uniform(&src, &common(min, max, GradientMode::Analytic), [3, 3, 3]).unwrap();
    let (c, stats) = build_uniform(
        &src,
        &common(min, max, GradientMode::Central { step: 1e-3 }),
        [3, 3, 3],
    )
    .unwrap();
    assert_eq!(stats.captures, 27 * 7, "6 extra captures per sample");
    let (ga, gc) = (
        &a.volume().gradients.as_ref().unwrap().data,
        &c.volume().gradients.as_ref().unwrap().data,
    );
    let scale = ga
        .iter()
        .map(|v| v.abs().max_element())
        .fold(0.0f32, f32::max);
    assert!(scale > 0.1);
    for (x, y) in ga.iter().zip(gc) {
        assert!((*x - *y).abs().max_element() < 2e-2 * scale, "{x} vs {y}");
    }
}

/// `truncate_gradients` keeps each (sample, axis) group's first `order²`
/// gradients, and the runtime interpolates the dropped bands trilinearly:
/// Taylor and tricubic of the truncated file equal those of the full file
/// in bands 0–1 and trilinear in band 2 (Taylor with a zero gradient is
/// trilinear; tricubic switches to the trilinear weight), at random points
/// of a grid and of an octree. Order 0 is refused; a larger order or a
/// file without gradients is left alone.
#[test]
fn truncated_gradients_keep_the_low_bands_and_flatten_the_rest() {
    let src = lights_no_slab(3);
    let (min, max) = (Vec3::new(-0.5, -0.5, -0.5), Vec3::new(0.5, 0.5, 0.5));
    let c = common(min, max, GradientMode::Analytic);
    let (grid, _) = build_uniform(&src, &c, [3, 3, 3]).unwrap();
    let (tree, _) = build_adaptive(
        &src,
        &AdaptiveSettings {
            geometry: false,
            prediction_tolerance: Some(0.05),
            ..geometry_only(c, 3)
        },
    )
    .unwrap();
    let depths: Vec<u32> = tree
        .octree()
        .as_ref()
        .unwrap()
        .nodes
        .iter()
        .map(|n| n.depth)
        .collect();
    assert!(depths.contains(&1) && depths.contains(&3), "a graded tree");
    for full in [grid, tree] {
        let count = full.probe_set().positions.len();
        let mut cut = full.clone();
        truncate_gradients(&mut cut, 2).unwrap();
        let (gf, gc) = (
            full.volume().gradients.as_ref().unwrap(),
            cut.volume().gradients.as_ref().unwrap(),
        );
        assert_eq!((gf.order, gc.order), (3, 2));
        assert_eq!(gc.data.len(), count * 3 * 4);
        for (a, b) in gf.data.chunks_exact(9).zip(gc.data.chunks_exact(4)) {
            assert_eq!(&a[..4], b);
        }
        let (vf, vc) = (
            Volume::from_file(&full).unwrap(),
            Volume::from_file(&cut).unwrap(),
        );
        let mut rng = Rng(5);
        // How much the gradients change each band group (the test is void
        // if the gradient terms vanish anyway).
        let mut moved = [0.0f32; 2];
        for _ in 0..100 {
            let p = rng.point(min, max);
            for interp in [Interp::Taylor, Interp::Tricubic] {
                let (mut tf, mut tc, mut tl) = ([Vec3::ZERO; 9], [Vec3::ZERO; 9], [Vec3::ZERO; 9]);
                vf.sample_sh(p, interp, &mut tf).unwrap();
                vc.sample_sh(p, interp, &mut tc).unwrap();
                vf.sample_sh(p, Interp::Trilinear, &mut tl).unwrap();
                for k in 0..9 {
                    let want = if k < 4 { tf[k] } else { tl[k] };
                    assert!(
                        (tc[k] - want).abs().max_element() < 1e-4,
                        "{interp:?} {p} coeff {k}: {} vs {want}",
                        tc[k]
                    );
                    let m = &mut moved[(k >= 4) as usize];
                    *m = m.max((tf[k] - tl[k]).abs().max_element());
                }
            }
        }
        assert!(moved[0] > 1e-2 && moved[1] > 1e-3, "{moved:?}");
        assert!(matches!(
            truncate_gradients(&mut cut.clone(), 0),
            Err(VolumeBuildError::BadGradientOrder(0))
        ));
        let mut same = full.clone();
        truncate_gradients(&mut same, 5).unwrap();
        assert_eq!(same, full);
    }
    let (mut plain, _) =
        build_uniform(&src, &common(min, max, GradientMode::None), [3, 3, 3]).unwrap();
    let before = plain.clone();
    truncate_gradients(&mut plain, 1).unwrap();
    assert_eq!(plain, before);
}

#[test]
fn taylor_and_trilinear_errors_on_a_quadratic_are_opposite_and_exact() {
    // c0 = x²: along x, trilinear overshoots by t(1−t)h² (½f''·t(1−t)h²),
    // first-order Taylor from both ends then blending undershoots by the same.
    let src = FieldSource {
        order: 1,
        f: |p: Vec3| vec![Vec3::splat(p.x * p.x)],
        g: |p: Vec3| vec![Vec3::splat(2.0 * p.x), Vec3::ZERO, Vec3::ZERO],
        log: Mutex::new(vec![]),
    };
    let (min, max) = (Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0));
    let (file, _) =
        build_uniform(&src, &common(min, max, GradientMode::Analytic), [3, 2, 2]).unwrap();
    let v = Volume::from_file(&file).unwrap();
    let mut rng = Rng(5);
    for _ in 0..100 {
        let p = rng.point(min, max);
        let t = p.x.fract();
        let want = t * (1.0 - t);
        let lin = sh_at(&v, p, Interp::Trilinear)[0].x - p.x * p.x;
        let tay = sh_at(&v, p, Interp::Taylor)[0].x - p.x * p.x;
        assert!((lin - want).abs() < 1e-4, "trilinear {lin} vs {want}");
        assert!((tay + want).abs() < 1e-4, "taylor {tay} vs {}", -want);
    }
}

#[test]
fn tricubic_beats_trilinear_on_sphere_lights() {
    let src = lights_no_slab(3);
    let (min, max) = (Vec3::new(-0.6, -0.4, -0.6), Vec3::new(0.6, 0.8, 0.6));
    let (file, _) =
        build_uniform(&src, &common(min, max, GradientMode::Analytic), [4, 4, 4]).unwrap();
    let v = Volume::from_file(&file).unwrap();
    let mut rng = Rng(3);
    let mut err = [0.0f64; 2];
    for _ in 0..300 {
        let p = rng.point(min, max);
        let want = src.capture(&[p]).remove(0).sh.into_coeffs();
        for (e, i) in err.iter_mut().zip([Interp::Trilinear, Interp::Tricubic]) {
            *e += dist(&sh_at(&v, p, i), &want) as f64;
        }
    }
    assert!(
        err[1] < err[0] * 0.5,
        "tricubic {} trilinear {}",
        err[1],
        err[0]
    );
}

fn adaptive(
    src: &dyn VolumeSource,
    gradients: GradientMode,
) -> (crate::format::ProbeFile, BuildStats) {
    let (min, max) = LightsDemo::demo_box();
    build_adaptive(
        src,
        &AdaptiveSettings {
            depth_factor: Some(1.0),
            prediction_tolerance: Some(0.25),
            prune_tolerance: Some(0.1),
            ..geometry_only(common(min, max, gradients), 4)
        },
    )
    .unwrap()
}

#[test]
fn adaptive_refines_at_the_wall_and_captures_shared_corners_once() {
    let demo = LightsDemo::demo(3);
    let src = FieldSource {
        order: 3,
        f: |p| demo.capture(&[p]).remove(0).sh.into_coeffs(),
        g: |_| vec![],
        log: Mutex::new(vec![]),
    };
    let (file, stats) = adaptive(&src, GradientMode::None);
    let log = src.log.lock().unwrap();
    let mut keys: Vec<[u32; 3]> = log.iter().map(|p| p.to_array().map(f32::to_bits)).collect();
    keys.sort_unstable();
    let before = keys.len();
    keys.dedup();
    assert_eq!(before, keys.len(), "a lattice point was captured twice");
    assert_eq!(stats.captures, before);
    let oct = file.octree().unwrap();
    let leaves: Vec<_> = oct
        .nodes
        .iter()
        .filter(|n| n.first_child == u32::MAX)
        .collect();
    assert_eq!(stats.leaves, leaves.len());
    // Leaves touching the slab x ∈ [0.9, 1.1] are at max depth.
    for l in &leaves {
        if l.min.x < 1.1 && l.max.x > 0.9 {
            assert_eq!(l.depth, 4, "leaf {l:?} touches the wall");
        }
    }
    let depths: std::collections::BTreeSet<u32> = leaves.iter().map(|l| l.depth).collect();
    assert!(depths.len() >= 2, "not adaptive: {depths:?}");
    // Fewer samples than the uniform lattice at max depth.
    assert!(
        stats.samples < 17 * 17 * 17 * 3 / 4,
        "{} samples",
        stats.samples
    );
    // Samples unique in the file.
    let mut pos: Vec<_> = file
        .probe_set()
        .positions
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect();
    pos.sort_unstable();
    let n = pos.len();
    pos.dedup();
    assert_eq!(n, pos.len());
}

/// Largest step-to-step SH change along a segment sampled every `step`.
fn max_jump(v: &Volume, a: Vec3, b: Vec3, step: f32, interp: Interp) -> f32 {
    let len = (b - a).length();
    let n = (len / step).ceil() as usize;
    let mut prev = sh_at(v, a, interp);
    let mut worst = 0.0f32;
    for k in 1..=n {
        let p = a + (b - a) * (k as f32 / n as f32);
        let cur = sh_at(v, p, interp);
        worst = worst.max(dist(&cur, &prev));
        prev = cur;
    }
    worst
}

/// Largest steps along `a → b` at a coarse (finest cell / 4) and a fine
/// (finest cell / 64) sampling step.
fn jumps(v: &Volume, a: Vec3, b: Vec3, finest: f32, interp: Interp) -> (f32, f32) {
    (
        max_jump(v, a, b, finest / 4.0, interp),
        max_jump(v, a, b, finest / 64.0, interp),
    )
}

/// Continuous, piecewise smooth along `a → b` for the three seam-free
/// schemes: the largest step shrinks with the step (ratio ≈ 1/16); a jump
/// would keep it ≈ 1.
fn assert_continuous_on_line(v: &Volume, a: Vec3, b: Vec3, finest: f32) {
    for interp in [Interp::Trilinear, Interp::Taylor, Interp::Tricubic] {
        let (jc, jf) = jumps(v, a, b, finest, interp);
        assert!(
            jf <= 0.35 * jc + 1e-6,
            "{interp:?} {a}→{b}: {jf} at fine step vs {jc}"
        );
    }
}

#[test]
fn lighting_is_continuous_along_random_lines_across_levels() {
    let demo = LightsDemo::demo(2);
    let (file, _) = adaptive(&demo, GradientMode::Analytic);
    let v = Volume::from_file(&file).unwrap();
    let (min, max) = LightsDemo::demo_box();
    let finest = (max.x - min.x) / 16.0;
    let mut rng = Rng(99);
    let mut naive_jumps = 0;
    for _ in 0..24 {
        let (a, b) = (rng.point(min, max), rng.point(min, max));
        assert_continuous_on_line(&v, a, b, finest);
        let (jc, jf) = jumps(&v, a, b, finest, Interp::LeafTrilinear);
        if jf > 0.35 * jc {
            naive_jumps += 1;
        }
    }
    // The test has power: the naive per-leaf lookup pops on some lines.
    assert!(naive_jumps > 0, "naive leaf trilinear never jumped");
}

#[test]
fn invalid_samples_are_dilated_from_valid_neighbours() {
    let demo = LightsDemo::demo(2);
    let (min, max) = LightsDemo::demo_box();
    // x = −2 + 0.2 i: i = 15 is x = 1.0, inside the slab (0.9, 1.1).
    let (file, stats) =
        build_uniform(&demo, &common(min, max, GradientMode::None), [21, 5, 5]).unwrap();
    assert_eq!(stats.dilated, 25);
    let coeffs = file.probe_set().coefficients.to_f32().unwrap();
    let flags = file.probe_set().validity.as_ref().unwrap();
    for (s, p) in file.probe_set().positions.iter().enumerate() {
        if (p.x - 1.0).abs() > 1e-4 {
            continue;
        }
        assert_ne!(flags[s].flags & crate::format::layout::VALIDITY_INVALID, 0);
        // Independent: every grid neighbour with x ≠ 1 is valid with weight 1.
        let step = Vec3::new(0.2, 1.0, 1.0);
        let mut want = [Vec3::ZERO; 4];
        let mut count = 0.0;
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in [-1, 1] {
                    let q = *p + Vec3::new(dx as f32, dy as f32, dz as f32) * step;
                    if q.cmplt(min - 1e-4).any() || q.cmpgt(max + 1e-4).any() {
                        continue;
                    }
                    let c = demo.capture(&[q]).remove(0);
                    for (w, x) in want.iter_mut().zip(c.sh.coeffs()) {
                        *w += *x;
                    }
                    count += 1.0;
                }
            }
        }
        let got = &coeffs[s * 4..s * 4 + 4];
        assert!(got[0].max_element() > 0.0, "left black");
        for (g, w) in got.iter().zip(want) {
            assert!((*g - w / count).abs().max_element() < 1e-4 * (1.0 + w.abs().max_element()));
        }
    }
}

#[test]
fn file_round_trip_memory_and_errors() {
    let demo = lights_no_slab(3);
    let (min, max) = (Vec3::splat(-0.5), Vec3::splat(0.5));
    // Tatarchuk 2005's uniform scene: 17³ = 4913 samples, L2 + gradients ≈ 2 MB.
    let (file, _) = build_uniform(
        &demo,
        &common(min, max, GradientMode::Analytic),
        [17, 17, 17],
    )
    .unwrap();
    let bytes = file.to_bytes().unwrap();
    let by = file.bytes_by_section().unwrap();
    assert_eq!(by.values().sum::<u64>(), bytes.len() as u64);
    let payload = 4913.0 * (9.0 + 27.0) * 12.0;
    assert!((bytes.len() as f64) > payload && (bytes.len() as f64) < payload * 1.1 + 4913.0 * 24.0);
    let back = crate::format::ProbeFile::from_bytes(&bytes).unwrap();
    let (a, b) = (
        Volume::from_file(&file).unwrap(),
        Volume::from_file(&back).unwrap(),
    );
    let p = Vec3::new(0.1, -0.2, 0.33);
    assert_eq!(
        sh_at(&a, p, Interp::Tricubic),
        sh_at(&b, p, Interp::Tricubic)
    );
    // Errors, not panics.
    let (nograd, _) =
        build_uniform(&demo, &common(min, max, GradientMode::None), [2, 2, 2]).unwrap();
    let v = Volume::from_file(&nograd).unwrap();
    let mut out = [Vec3::ZERO; 9];
    assert!(matches!(
        v.sample_sh(p, Interp::Taylor, &mut out),
        Err(VolumeError::NoGradients(_))
    ));
    assert!(matches!(
        v.sample_sh(p, Interp::Trilinear, &mut out[..3]),
        Err(VolumeError::OutputTooShort { .. })
    ));
    assert!(build_uniform(&demo, &common(max, min, GradientMode::None), [2, 2, 2]).is_err());
    assert!(build_uniform(&demo, &common(min, max, GradientMode::None), [1, 2, 2]).is_err());
    struct NoGrad;
    impl VolumeSource for NoGrad {
        fn order(&self) -> usize {
            1
        }
        fn capture(&self, p: &[Vec3]) -> Vec<Captured> {
            p.iter()
                .map(|_| Captured {
                    sh: ShRgb::zeros(1),
                    validity: 0.0,
                    virtual_offset: false,
                    std_error: None,
                })
                .collect()
        }
    }
    assert!(matches!(
        build_uniform(&NoGrad, &common(min, max, GradientMode::None), [2, 2, 2]),
        Err(VolumeBuildError::NoValidSamples)
    ));
}

#[test]
fn ktx2_export_parses_back_and_matches_the_query() {
    use super::export::*;
    let demo = lights_no_slab(3);
    let (min, max) = (Vec3::splat(-0.5), Vec3::splat(0.5));
    let (file, _) = build_uniform(&demo, &common(min, max, GradientMode::None), [3, 4, 5]).unwrap();
    let v = Volume::from_file(&file).unwrap();
    let ex = export_ktx2(&v, Ktx2Encoding::F16, None).unwrap();
    assert_eq!(ex.textures.len(), 7); // 27 floats in groups of 4
    let coeffs = file.probe_set().coefficients.to_f32().unwrap();
    for (g, (_, t)) in ex.textures.iter().enumerate() {
        let back = Ktx2::from_bytes(&t.to_bytes()).unwrap();
        assert_eq!(&back, t);
        assert_eq!(back.size, [3, 4, 5]);
        assert_eq!(
            back.kvd,
            vec![("KTXwriter".to_string(), "probekit".to_string())]
        );
        for s in 0..60 {
            for c in 0..4 {
                let f = 4 * g + c;
                let o = 8 * s + 2 * c;
                let h = half::f16::from_bits(u16::from_le_bytes([back.data[o], back.data[o + 1]]))
                    .to_f32();
                let want = if f < 27 {
                    coeffs[s * 9 + f / 3][f % 3]
                } else {
                    0.0
                };
                assert!(
                    (h - want).abs() <= 1e-3 * (1.0 + want.abs()),
                    "{h} vs {want}"
                );
            }
        }
    }
    // Quantized: DC (RGB9E5) and ratios (SNORM8) reconstruct within codec precision.
    let q = export_ktx2(&v, Ktx2Encoding::Quantized, None).unwrap();
    let bounds: Vec<f32> = q.sidecar["ratio_bounds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap() as f32)
        .collect();
    let dc = Ktx2::from_bytes(&q.textures[0].1.to_bytes()).unwrap();
    assert_eq!(dc.format, TexelFormat::Rgb9e5);
    for s in 0..60 {
        let d = crate::sh::codec::decode_rgb9e5(u32::from_le_bytes(
            dc.data[4 * s..4 * s + 4].try_into().unwrap(),
        ));
        let want = coeffs[s * 9];
        assert!((d - want).abs().max_element() <= 0.01 * want.max_element());
        for i in 1..9 {
            for ch in 0..3 {
                let f = 3 * (i - 1) + ch;
                let t = &q.textures[1 + f / 4].1;
                let sn = t.data[4 * s + f % 4] as i8 as f32 / 127.0;
                let got = sn * bounds[i - 1] * d[ch];
                let w = coeffs[s * 9 + i][ch];
                assert!(
                    (got - w).abs() <= 0.02 * want.max_element(),
                    "coef {i} ch {ch}: {got} vs {w}"
                );
            }
        }
    }
    // Garbage is an error, not a panic.
    assert!(Ktx2::from_bytes(&[0u8; 200]).is_err());
    let mut bytes = ex.textures[0].1.to_bytes();
    bytes.truncate(bytes.len() - 1);
    assert!(Ktx2::from_bytes(&bytes).is_err());
}

/// Bevy's voxel centre `i` (`(i + ½)/R` of the unit cube, mapped through
/// the sidecar's `light_probe_transform`: scale, then rotate, then translate).
fn bevy_voxel_centre(json: &serde_json::Value, res: [u32; 3], voxel: [u32; 3]) -> Vec3 {
    let t = &json["light_probe_transform"];
    let v3 = |k: &str| Vec3::from_array(std::array::from_fn(|a| t[k][a].as_f64().unwrap() as f32));
    let q = t["rotation"].as_array().unwrap();
    let q = glam::Quat::from_xyzw(
        q[0].as_f64().unwrap() as f32,
        q[1].as_f64().unwrap() as f32,
        q[2].as_f64().unwrap() as f32,
        q[3].as_f64().unwrap() as f32,
    );
    let unit = Vec3::from_array(std::array::from_fn(|a| {
        (voxel[a] as f32 + 0.5) / res[a] as f32 - 0.5
    }));
    v3("translation") + q * (v3("scale") * unit)
}

/// A uniform volume at its own resolution: voxel `i` is probe `i` — Bevy's
/// voxel centre, through the sidecar's transform, lands on the probe's
/// position, and its faces are E/π of the non-negative least-squares
/// ambient cube of the probe's stored SH (read from the file, not through
/// the query).
#[test]
fn bevy_export_of_a_uniform_volume_puts_each_probes_ambient_cube_on_a_voxel_centre() {
    use super::export::*;
    let demo = LightsDemo::demo(3);
    let (min, max) = LightsDemo::demo_box();
    let res = [4, 3, 5];
    let (file, _) = build_uniform(&demo, &common(min, max, GradientMode::None), res).unwrap();
    let v = Volume::from_file(&file).unwrap();
    let ex = export_bevy(&v, None).unwrap();
    assert_eq!(ex.resolution, res);
    assert_eq!(ex.lattice, BevyLattice::Probes);
    let tex = Ktx2::from_bytes(&ex.texture.to_bytes()).unwrap();
    assert_eq!(tex.size, [4, 6, 15]);
    let coeffs = file.probe_set().coefficients.to_f32().unwrap();
    let n = v.coeffs_per_sample();
    let size = (max - min).max_element();
    for z in 0..res[2] {
        for y in 0..res[1] {
            for x in 0..res[0] {
                let s = (x + res[0] * (y + res[1] * z)) as usize;
                let centre = bevy_voxel_centre(&ex.sidecar, res, [x, y, z]);
                assert!(
                    (centre - file.probe_set().positions[s]).abs().max_element() < 1e-5 * size,
                    "voxel {x} {y} {z}: centre {centre} vs probe {}",
                    file.probe_set().positions[s]
                );
                let cube =
                    crate::sh::ambient_cube::fit_from_sh_nonnegative(&coeffs[s * n..(s + 1) * n]);
                for face in 0..6 {
                    let got = bevy_texel(&tex, [x, y, z], face).unwrap();
                    let want = cube.faces[face] / std::f32::consts::PI;
                    assert!(
                        (got - want).abs().max_element() <= 0.005 * want.max_element() + 1e-7,
                        "{x} {y} {z} face {face}: {got} vs {want}"
                    );
                }
            }
        }
    }
    // A single voxel on an axis cannot reach both faces of the box.
    assert!(matches!(
        export_bevy(&v, Some([1, 3, 3])),
        Err(ExportError::BevyResolution(_))
    ));
}

/// An octree exports on its finest lattice (`2^depth + 1` voxels per axis
/// for one root): Bevy's voxel centres on the lattice points, each holding
/// the ambient cube of the runtime's query there; an explicit resolution
/// off any octree level is reported as resampled.
#[test]
fn bevy_export_of_an_octree_uses_its_finest_lattice() {
    use super::export::*;
    let demo = LightsDemo::demo(3);
    let (file, _) = adaptive(&demo, GradientMode::None);
    let v = Volume::from_file(&file).unwrap();
    let d = v.max_depth();
    let ex = export_bevy(&v, None).unwrap();
    let r = (1u32 << d) + 1;
    assert_eq!(ex.resolution, [r; 3]);
    assert_eq!(
        ex.lattice,
        BevyLattice::OctreeLevel {
            depth: d,
            finest: true
        }
    );
    let (min, max) = v.bounds();
    for (x, y, z) in [
        (0, 0, 0),
        (r - 1, 1, 2),
        (3, r - 1, r / 2),
        (r / 2, 5, r - 1),
    ] {
        let p = min + Vec3::new(x as f32, y as f32, z as f32) / (r - 1) as f32 * (max - min);
        let centre = bevy_voxel_centre(&ex.sidecar, [r; 3], [x, y, z]);
        assert!((centre - p).abs().max_element() < 1e-5, "{centre} vs {p}");
        let cube =
            crate::sh::ambient_cube::fit_from_sh_nonnegative(&sh_at(&v, p, Interp::Trilinear));
        for face in 0..6 {
            let got = bevy_texel(&ex.texture, [x, y, z], face).unwrap();
            let want = cube.faces[face] / std::f32::consts::PI;
            assert!(
                (got - want).abs().max_element() <= 0.005 * want.max_element() + 1e-7,
                "{x} {y} {z} face {face}: {got} vs {want}"
            );
        }
    }
    let other = export_bevy(&v, Some([4, 3, 2])).unwrap();
    assert_eq!(other.lattice, BevyLattice::Resampled);
    assert_eq!(other.texture.size, [4, 6, 6]);
}

/// The recommended intensity undoes Bevy's exposure: Bevy's
/// `Exposure::exposure()` is `2^−EV100 / 1.2` (bevy_camera `camera.rs`),
/// computed here in f64, and the sidecar's number for the default EV100 9.7
/// times it is 1 (1.2 · 2^9.7 = 998.1).
#[test]
fn bevy_intensity_for_the_default_exposure_undoes_bevys_exposure() {
    use super::export::*;
    let exposure = |ev100: f64| (-ev100).exp2() / 1.2;
    for ev in [-0.263, 0.0, 7.0, 9.7, 15.0] {
        let i = bevy_intensity_for_exposure(ev as f32) as f64;
        assert!((i * exposure(ev) - 1.0).abs() < 1e-6, "EV100 {ev}: {i}");
        assert!((bevy_exposure(ev as f32) as f64 / exposure(ev) - 1.0).abs() < 1e-6);
    }
    let demo = LightsDemo::demo(3);
    let (min, max) = LightsDemo::demo_box();
    let (file, _) = build_uniform(&demo, &common(min, max, GradientMode::None), [2, 2, 2]).unwrap();
    let ex = export_bevy(&Volume::from_file(&file).unwrap(), None).unwrap();
    let at_default = ex.sidecar["intensity_for_bevy_default_exposure"]
        .as_f64()
        .unwrap();
    assert!((at_default - 998.1).abs() < 0.01, "{at_default}");
    assert!((at_default * exposure(9.7) - 1.0).abs() < 1e-4);
    assert_eq!(ex.sidecar["intensity_in_scene_units"], 1.0);
    assert_eq!(
        ex.sidecar["bevy_default_exposure_ev100"].as_f64().unwrap() as f32,
        9.7
    );
    assert!(ex.sidecar.get("intensity").is_none());
}

/// Constant radiance with a geometric slab at x ∈ [0.3, 0.35]: the octree
/// refines around it, the field stays constant.
struct ConstantWithWall;
impl VolumeSource for ConstantWithWall {
    fn order(&self) -> usize {
        2
    }
    fn capture(&self, p: &[Vec3]) -> Vec<Captured> {
        p.iter()
            .map(|_| {
                exact(vec![
                    Vec3::new(1.0, 2.0, 3.0),
                    Vec3::splat(0.5),
                    Vec3::splat(-0.25),
                    Vec3::ZERO,
                ])
            })
            .collect()
    }
    fn contains_geometry(&self, min: Vec3, max: Vec3) -> bool {
        min.x < 0.35 && max.x > 0.3
    }
    fn analytic_gradients(&self, p: &[Vec3]) -> Option<Vec<Vec3>> {
        Some(vec![Vec3::ZERO; p.len() * 12])
    }
}

mod props {
    use super::*;
    use proptest::prelude::*;

    fn octree_volume() -> &'static Volume {
        static V: std::sync::OnceLock<Volume> = std::sync::OnceLock::new();
        V.get_or_init(|| {
            let (file, _) = build_adaptive(
                &ConstantWithWall,
                &geometry_only(common(Vec3::ZERO, Vec3::ONE, GradientMode::Analytic), 5),
            )
            .unwrap();
            assert!(file
                .octree()
                .as_ref()
                .unwrap()
                .nodes
                .iter()
                .any(|n| n.depth == 5));
            Volume::from_file(&file).unwrap()
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Every scheme is a normalised combination: a constant field comes
        /// back exactly anywhere in a multi-level octree (and outside it, clamped).
        #[test]
        fn constant_field_is_reproduced_on_an_octree(
            x in -0.2f32..1.2, y in -0.2f32..1.2, z in -0.2f32..1.2,
        ) {
            let v = octree_volume();
            let want = ConstantWithWall.capture(&[Vec3::ZERO]).remove(0).sh.into_coeffs();
            for i in [Interp::Trilinear, Interp::Taylor, Interp::Tricubic, Interp::InverseDistance, Interp::LeafTrilinear] {
                let got = sh_at(v, Vec3::new(x, y, z), i);
                prop_assert!(dist(&got, &want) < 1e-5, "{:?}: {:?}", i, got);
            }
        }

        /// Trilinear reproduces any affine field on any uniform grid.
        #[test]
        fn affine_fields_on_random_grids(
            a in prop::array::uniform3(-2.0f32..2.0), b in prop::array::uniform3(-2.0f32..2.0),
            lo in prop::array::uniform3(-5.0f32..5.0), ext in prop::array::uniform3(0.5f32..4.0),
            rx in 2u32..6, ry in 2u32..6, rz in 2u32..6, t in prop::array::uniform3(0.0f32..1.0),
        ) {
            let (a, b) = (Vec3::from(a), Vec3::from(b));
            let f = move |p: Vec3| vec![Vec3::splat(a.dot(p)) + b];
            let src = FieldSource { order: 1, f, g: |_| vec![], log: Mutex::new(vec![]) };
            let (min, max) = (Vec3::from(lo), Vec3::from(lo) + Vec3::from(ext));
            let (file, _) = build_uniform(&src, &common(min, max, GradientMode::None), [rx, ry, rz]).unwrap();
            let v = Volume::from_file(&file).unwrap();
            let p = min + Vec3::from(t) * (max - min);
            let got = sh_at(&v, p, Interp::Trilinear);
            let want = f(p);
            prop_assert!(dist(&got, &want) < 1e-4 * (1.0 + want[0].abs().max_element()));
        }
    }
}

/// The brick atlas, looked up as its sidecar describes (indirection texel →
/// brick and level → hardware-style trilinear inside the brick, written here
/// from the description), reproduces the octree's own trilinear query, in
/// fewer texels than the finest-level lattice; a uniform volume is refused.
#[test]
fn brick_atlas_reproduces_the_octree_query() {
    use super::export::*;
    // A smooth, non-linear field; the octree refines only at a wall
    // (x ∈ 0.30..0.35), so most of the box stays coarse.
    struct WavyWithWall;
    impl VolumeSource for WavyWithWall {
        fn order(&self) -> usize {
            3
        }
        fn capture(&self, p: &[Vec3]) -> Vec<Captured> {
            p.iter()
                .map(|p| {
                    exact(
                        (0..9)
                            .map(|k| {
                                let k = k as f32;
                                Vec3::new(
                                    2.0 + (3.0 * p.x + k).sin() * (2.0 * p.y).cos(),
                                    1.0 + p.z * p.z - 0.1 * k,
                                    (p.x * p.y + 0.3 * k).cos(),
                                )
                            })
                            .collect(),
                    )
                })
                .collect()
        }
        fn contains_geometry(&self, min: Vec3, max: Vec3) -> bool {
            min.x < 0.35 && max.x > 0.3
        }
    }
    let (file, _) = build_adaptive(
        &WavyWithWall,
        &geometry_only(common(Vec3::ZERO, Vec3::ONE, GradientMode::None), 5),
    )
    .unwrap();
    let v = Volume::from_file(&file).unwrap();
    let ex = export_bricks(&v, Ktx2Encoding::F16).unwrap();
    let ind = Ktx2::from_bytes(&ex.textures[0].1.to_bytes()).unwrap();
    assert_eq!(ind.format, TexelFormat::Rgba8Uint);
    let atlas: Vec<Ktx2> = ex.textures[1..]
        .iter()
        .map(|(_, t)| Ktx2::from_bytes(&t.to_bytes()).unwrap())
        .collect();
    assert_eq!(atlas.len(), 7);
    let n = v.coeffs_per_sample();
    let res = atlas[0].size.map(|r| r as usize);
    let bricks = ex.sidecar["bricks"].as_u64().unwrap() as usize;
    let finest = ((1usize << v.max_depth()) + 1).pow(3);
    let t = BRICK_CELLS as usize + 1;
    assert!(
        bricks * t.pow(3) < finest,
        "{bricks} bricks of {t}³ vs {finest} finest-level texels"
    );
    assert_eq!(
        ex.sidecar["atlas_resolution"][0].as_u64(),
        Some(res[0] as u64)
    );
    let fetch = |x: usize, y: usize, z: usize, f: usize| -> f32 {
        let tex = &atlas[f / 4];
        let o = 8 * (x + res[0] * (y + res[1] * z)) + 2 * (f % 4);
        half::f16::from_bits(u16::from_le_bytes([tex.data[o], tex.data[o + 1]])).to_f32()
    };
    let (min, max) = v.bounds();
    let cells = ind.size[0] as f32;
    let lookup = |p: Vec3| -> Vec<f32> {
        let g = (p - min) / (max - min) * cells;
        let c = g.floor().clamp(Vec3::ZERO, Vec3::splat(cells - 1.0));
        let o = 4
            * (c.x as usize
                + ind.size[0] as usize * (c.y as usize + ind.size[1] as usize * c.z as usize));
        let b = [ind.data[o], ind.data[o + 1], ind.data[o + 2]].map(|x| x as usize);
        let s = (1u32 << ind.data[o + 3]) as f32;
        let f = ((g - (c / s).floor() * s) / s).clamp(Vec3::ZERO, Vec3::ONE);
        let tc = f * BRICK_CELLS as f32;
        let i0 = tc.floor().min(Vec3::splat(BRICK_CELLS as f32 - 1.0));
        let fr = tc - i0;
        let mut out = vec![0.0f32; 3 * n];
        for corner in 0..8usize {
            let bit = |a: usize| (corner >> a) & 1;
            let w: f32 = (0..3)
                .map(|a| if bit(a) == 1 { fr[a] } else { 1.0 - fr[a] })
                .product();
            let (x, y, z) = (
                b[0] * t + i0.x as usize + bit(0),
                b[1] * t + i0.y as usize + bit(1),
                b[2] * t + i0.z as usize + bit(2),
            );
            for (k, o) in out.iter_mut().enumerate() {
                *o += w * fetch(x, y, z, k);
            }
        }
        out
    };
    let mut rng = Rng(11);
    let (mut diff, mut mag, mut worst, mut dc_max) = (0.0f64, 0.0f64, 0.0f32, 0.0f32);
    for _ in 0..400 {
        let p = rng.point(min, max);
        let want = sh_at(&v, p, Interp::Trilinear);
        let got = lookup(p);
        dc_max = dc_max.max(want[0].max_element());
        for (k, w) in want.iter().enumerate() {
            for ch in 0..3 {
                let d = (got[3 * k + ch] - w[ch]).abs();
                diff += d as f64;
                mag += w[ch].abs() as f64;
                worst = worst.max(d);
            }
        }
    }
    // f16 rounding, and coarse leaves next to finer ones (whose query blends
    // the finer face samples) sampled at 5 texels per axis.
    assert!(diff < 0.005 * mag, "mean difference {}", diff / mag);
    assert!(worst < 0.05 * dc_max, "worst {worst} vs DC {dc_max}");
    let (u, _) = build_uniform(
        &WavyWithWall,
        &common(min, max, GradientMode::None),
        [3, 3, 3],
    )
    .unwrap();
    let u = Volume::from_file(&u).unwrap();
    assert!(matches!(
        export_bricks(&u, Ktx2Encoding::F16),
        Err(ExportError::NotAnOctree)
    ));
    // `export_auto`: the sparse octree as bricks, the grid densely.
    let auto = |v: &Volume| export_auto(v, Ktx2Encoding::F16).unwrap().sidecar["format"].clone();
    assert_eq!(auto(&v), "probekit-volume-bricks");
    assert_eq!(auto(&u), "probekit-volume-ktx2");
}

/// DC-only field `base(p)` plus a position-hashed noise of half-width
/// `amp` (uniform, standard deviation `amp/√3`), reported as the capture's
/// standard error, like a Monte Carlo capture.
struct NoisySource<F: Fn(Vec3) -> f32 + Sync> {
    base: F,
    amp: f32,
}

impl<F: Fn(Vec3) -> f32 + Sync> VolumeSource for NoisySource<F> {
    fn order(&self) -> usize {
        1
    }
    fn capture(&self, points: &[Vec3]) -> Vec<Captured> {
        points
            .iter()
            .map(|p| {
                let mut r = Rng(position_key(*p) | 1);
                let v = (self.base)(*p) + self.amp * (2.0 * r.next() - 1.0);
                Captured {
                    sh: ShRgb::from_coeffs(vec![Vec3::splat(v)]).unwrap(),
                    validity: 1.0,
                    virtual_offset: false,
                    std_error: Some(vec![Vec3::splat(self.amp / 3f32.sqrt())]),
                }
            })
            .collect()
    }
}

fn noisy_settings(noise_k: f32) -> AdaptiveSettings {
    AdaptiveSettings {
        geometry: false,
        geometry_depth: 0,
        prediction_tolerance: Some(0.1),
        noise_k,
        ..geometry_only(common(Vec3::ZERO, Vec3::ONE, GradientMode::None), 4)
    }
}

/// Depth of the leaf containing `p` (boxes from the file's octree).
fn leaf_depth(file: &crate::format::ProbeFile, p: Vec3) -> u32 {
    let o = file.octree().unwrap();
    let mut i = 0;
    loop {
        let n = o.nodes[i];
        if n.first_child == crate::format::layout::NONE {
            return n.depth;
        }
        let mid = (n.min + n.max) * 0.5;
        let k = (p.x >= mid.x) as usize
            | ((p.y >= mid.y) as usize) << 1
            | ((p.z >= mid.z) as usize) << 2;
        i = n.first_child as usize + k;
    }
}

/// Noise-aware refinement: on a linear ramp (which trilinear prediction
/// reproduces exactly) plus capture noise 3× the tolerance, raw misses
/// refine the octree almost everywhere, misses discounted by 3 standard
/// errors leave it at `min_depth`; a real step of 5 (50× the tolerance)
/// is still refined to the finest level where it lies, and not far from it.
#[test]
fn noise_aware_refinement_ignores_noise_but_not_a_step() {
    let ramp = NoisySource {
        base: |p: Vec3| 1.0 + 0.1 * p.x,
        amp: 0.3,
    };
    let (raw, raw_stats) = build_adaptive(&ramp, &noisy_settings(0.0)).unwrap();
    let (aware, aware_stats) = build_adaptive(&ramp, &noisy_settings(3.0)).unwrap();
    assert_eq!(aware_stats.leaves, 8, "noise alone must not refine");
    assert!(
        raw_stats.leaves > 400,
        "raw misses chase noise: {raw_stats:?}"
    );
    assert!(leaf_depth(&raw, Vec3::splat(0.4)) >= 3);

    let step = NoisySource {
        base: |p: Vec3| if p.x < 0.3 { 1.0 } else { 6.0 },
        amp: 0.3,
    };
    let (file, stats) = build_adaptive(&step, &noisy_settings(3.0)).unwrap();
    assert!(
        stats.leaves > 8 && stats.leaves < raw_stats.leaves,
        "{stats:?}"
    );
    for y in [0.1, 0.45, 0.8] {
        assert_eq!(leaf_depth(&file, Vec3::new(0.3, y, 0.6)), 4);
        assert!(leaf_depth(&file, Vec3::new(0.9, y, 0.6)) <= 2);
    }
    let _ = aware;
}

/// `geometry_depth`: geometry alone refines the slab's cells to the
/// finest level under Tatarchuk's rule, only down to `geometry_depth` when
/// the field (constant, so the prediction test never fires) gives no reason.
#[test]
fn geometry_depth_caps_refinement_by_geometry_alone() {
    let build = |g: u32| {
        let (file, _) = build_adaptive(
            &ConstantWithWall,
            &AdaptiveSettings {
                geometry_depth: g,
                prediction_tolerance: Some(0.1),
                noise_k: 2.0,
                ..geometry_only(common(Vec3::ZERO, Vec3::ONE, GradientMode::None), 4)
            },
        )
        .unwrap();
        file
    };
    let deepest = |f: &crate::format::ProbeFile| {
        f.octree()
            .as_ref()
            .unwrap()
            .nodes
            .iter()
            .map(|n| n.depth)
            .max()
            .unwrap()
    };
    let seed_rule = build(4);
    assert_eq!(deepest(&seed_rule), 4);
    assert_eq!(leaf_depth(&seed_rule, Vec3::new(0.32, 0.5, 0.5)), 4);
    for g in [1, 2, 3] {
        let f = build(g);
        assert_eq!(deepest(&f), g.max(1));
        assert_eq!(leaf_depth(&f, Vec3::new(0.32, 0.5, 0.5)), g.max(1));
        assert!(f.probe_set().positions.len() < seed_rule.probe_set().positions.len());
    }
    // Far from the slab nothing refines beyond min_depth in either case.
    assert_eq!(leaf_depth(&seed_rule, Vec3::new(0.9, 0.9, 0.9)), 1);
}

/// Largest depth difference between two leaves whose closed boxes touch
/// (brute force over all pairs).
fn worst_neighbour_jump(file: &crate::format::ProbeFile) -> u32 {
    let o = file.octree().unwrap();
    let leaves: Vec<_> = o
        .nodes
        .iter()
        .filter(|n| n.first_child == crate::format::layout::NONE)
        .collect();
    let mut worst = 0;
    for a in &leaves {
        for b in &leaves {
            let touch = (0..3).all(|k| a.min[k] <= b.max[k] + 1e-6 && b.min[k] <= a.max[k] + 1e-6);
            if touch {
                worst = worst.max(a.depth.abs_diff(b.depth));
            }
        }
    }
    worst
}

/// 2:1 balance: on a step that refines to depth 4 next to depth-1
/// leaves, the balanced octree has no touching leaves two levels apart,
/// keeps every split of the unbalanced one (more leaves) and still
/// reproduces the step's side values at the samples.
#[test]
fn balance_limits_neighbouring_leaves_to_one_level() {
    let step = NoisySource {
        base: |p: Vec3| if p.x < 0.3 { 1.0 } else { 6.0 },
        amp: 0.0,
    };
    let mut s = noisy_settings(2.0);
    let (plain, plain_stats) = build_adaptive(&step, &s).unwrap();
    assert!(worst_neighbour_jump(&plain) >= 2);
    s.balance = true;
    let (bal, bal_stats) = build_adaptive(&step, &s).unwrap();
    assert_eq!(worst_neighbour_jump(&bal), 1);
    assert!(bal_stats.leaves > plain_stats.leaves);
    for p in [Vec3::new(0.3, 0.5, 0.5), Vec3::new(0.9, 0.1, 0.2)] {
        assert!(leaf_depth(&bal, p) >= leaf_depth(&plain, p));
    }
    let c = bal.probe_set().coefficients.to_f32().unwrap();
    for (i, p) in bal.probe_set().positions.iter().enumerate() {
        let want = if p.x < 0.3 { 1.0 } else { 6.0 };
        assert_eq!(c[i], Vec3::splat(want));
    }
}

/// Forests of near-cubic root octrees.
mod forest {
    use super::*;

    #[test]
    fn near_cubic_roots_of_boxes() {
        let r = |x: f32, y: f32, z: f32| near_cubic_roots(Vec3::ZERO, Vec3::new(x, y, z)).unwrap();
        assert_eq!(r(8.0, 3.0, 4.0), [5, 2, 3]);
        assert_eq!(r(2.0, 2.0, 2.0), [1, 1, 1]);
        assert_eq!(r(1.0, 1.0, 10.0), [1, 1, 10]);
        assert_eq!(r(1.0, 1.0, 2.5), [1, 1, 3]);
        // Whatever the box, the root cells' aspect is what the rule says.
        let mut rng = Rng(5);
        for _ in 0..200 {
            let ext = Vec3::new(
                0.5 + 10.0 * rng.next(),
                0.5 + 10.0 * rng.next(),
                0.5 + 10.0 * rng.next(),
            );
            let roots = near_cubic_roots(Vec3::ZERO, ext).unwrap();
            let cell = ext / Vec3::from_array(roots.map(|v| v as f32));
            let aspect = cell.max_element() / cell.min_element();
            // m = 4 alone bounds the aspect by (1 + 1/8) / (1 − 1/8) · …;
            // 1.6 is a generous envelope of the four tries.
            assert!(aspect < 1.6, "{ext} → {roots:?}: aspect {aspect}");
        }
        assert!(near_cubic_roots(Vec3::ONE, Vec3::ONE).is_err());
    }

    /// A wavy field, independent of the volume code.
    fn wavy(p: Vec3) -> Vec<Vec3> {
        (0..4)
            .map(|k| {
                let k = k as f32;
                Vec3::new(
                    2.0 + (1.3 * p.x + k).sin() * (0.7 * p.y).cos(),
                    1.0 + 0.1 * p.z * p.z - 0.1 * k,
                    (0.5 * p.x * p.y + 0.3 * k).cos(),
                )
            })
            .collect()
    }

    /// A forest that never splits below depth 1 is a uniform grid of
    /// `roots·2 + 1` samples per axis: the octree query (kernels found
    /// through the root grid) must equal the grid query (a separate code
    /// path) everywhere.
    #[test]
    fn unsplit_forest_equals_the_uniform_grid() {
        let src = FieldSource {
            order: 2,
            f: wavy,
            g: |_| vec![],
            log: Mutex::new(vec![]),
        };
        let (min, max) = (Vec3::new(-1.0, 0.0, 0.5), Vec3::new(3.0, 1.5, 5.0));
        let mut s = geometry_only(common(min, max, GradientMode::None), 1);
        s.geometry = false;
        s.roots = Some([2, 1, 3]);
        let (file, _) = build_adaptive(&src, &s).unwrap();
        let o = file.octree().unwrap();
        assert_eq!(o.roots, [2, 1, 3]);
        assert_eq!(o.nodes.len(), 6 + 6 * 8);
        let tree = Volume::from_file(&file).unwrap();
        assert_eq!(tree.root_grid(), Some([2, 1, 3]));
        assert_eq!(tree.bounds(), (min, max));
        let (grid_file, _) =
            build_uniform(&src, &common(min, max, GradientMode::None), [5, 3, 7]).unwrap();
        let grid = Volume::from_file(&grid_file).unwrap();
        let mut rng = Rng(17);
        for _ in 0..500 {
            let p = rng.point(min - 0.2, max + 0.2);
            let (a, b) = (
                sh_at(&tree, p, Interp::Trilinear),
                sh_at(&grid, p, Interp::Trilinear),
            );
            assert!(dist(&a, &b) < 1e-4, "{p}: {a:?} vs {b:?}");
            assert_eq!(tree.leaf_depth_at(p), 1);
        }
    }

    fn wall_forest() -> (crate::format::ProbeFile, Vec3, Vec3) {
        // 2 × 1 × 1 box: roots 2 × 1 × 1 unit cubes; the wall refines x ≈ 0.3.
        let (min, max) = (Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0));
        let s = geometry_only(common(min, max, GradientMode::Analytic), 4);
        let s = AdaptiveSettings { roots: None, ..s };
        let (file, _) = build_adaptive(&ConstantWithWall, &s).unwrap();
        (file, min, max)
    }

    /// Leaves of an auto-rooted forest are cubes; the file round-trips
    /// through `OCTC` as format 2.0; a constant field comes back everywhere.
    #[test]
    fn forest_leaves_are_cubes_and_round_trip() {
        let (file, min, max) = wall_forest();
        let o = file.octree().unwrap();
        assert_eq!(o.roots, [2, 1, 1]);
        for n in &o.nodes {
            let e = n.max - n.min;
            assert!(e.max_element() / e.min_element() < 1.0 + 1e-5, "{n:?}");
        }
        assert!(o.nodes.iter().any(|n| n.depth == 4));
        let bytes = file.to_bytes().unwrap();
        let major = crate::format::layout::header::MAJOR;
        let version = |at: usize| u16::from_le_bytes([bytes[at], bytes[at + 1]]);
        assert_eq!((version(major), version(major + 2)), (2, 1));
        let back = crate::format::ProbeFile::from_bytes(&bytes).unwrap();
        assert_eq!(back, file);
        let v = Volume::from_file(&back).unwrap();
        let want = ConstantWithWall
            .capture(&[Vec3::ZERO])
            .remove(0)
            .sh
            .into_coeffs();
        let mut rng = Rng(23);
        for _ in 0..300 {
            let p = rng.point(min, max);
            for i in [Interp::Trilinear, Interp::Taylor, Interp::Tricubic] {
                assert!(dist(&sh_at(&v, p, i), &want) < 1e-5, "{i:?} at {p}");
            }
        }
    }

    /// Lighting stays continuous along random lines that cross root cells
    /// and levels (the same criterion as the single-root test).
    #[test]
    fn forest_lighting_is_continuous_along_random_lines() {
        let demo = LightsDemo::demo(2);
        let (min, max) = (Vec3::new(-2.0, -1.0, -2.0), Vec3::new(2.0, 1.0, 2.0));
        let mut s = geometry_only(common(min, max, GradientMode::Analytic), 3);
        s.roots = None;
        s.prediction_tolerance = Some(0.25);
        let (file, _) = build_adaptive(&demo, &s).unwrap();
        assert_eq!(file.octree().unwrap().roots, [2, 1, 2]);
        let v = Volume::from_file(&file).unwrap();
        let mut rng = Rng(7);
        for _ in 0..16 {
            let (a, b) = (rng.point(min, max), rng.point(min, max));
            assert_continuous_on_line(&v, a, b, 1.0 / 8.0);
        }
    }

    /// The dense KTX2 lattice of a forest has `roots·2^depth + 1` texels per
    /// axis, and the brick atlas plan covers `roots·2^Di` indirection cells.
    #[test]
    fn forest_exports_follow_the_root_grid() {
        use super::super::export::*;
        let (file, _, _) = wall_forest();
        let v = Volume::from_file(&file).unwrap();
        let dense = export_ktx2(&v, Ktx2Encoding::F16, None).unwrap();
        let (_, tex) = &dense.textures[0];
        assert_eq!(tex.size, [2 * 16 + 1, 17, 17]);
        let bricks = export_bricks(&v, Ktx2Encoding::F16).unwrap();
        assert_eq!(
            bricks.sidecar["indirection"]["resolution"],
            serde_json::json!([2 * 4, 4, 4])
        );
    }
}

/// Constant radiance with a small emitter at `EMITTER` (a 2 cm cube): no
/// prediction test can see it, only the emitter rule.
struct ConstantWithEmitter;
const EMITTER: Vec3 = Vec3::new(0.61, 0.37, 0.83);
impl VolumeSource for ConstantWithEmitter {
    fn order(&self) -> usize {
        1
    }
    fn capture(&self, p: &[Vec3]) -> Vec<Captured> {
        p.iter().map(|_| exact(vec![Vec3::ONE])).collect()
    }
    fn contains_emitter(&self, min: Vec3, max: Vec3) -> bool {
        crate::scene::Aabb::new(EMITTER - 0.01, EMITTER + 0.01)
            .overlaps(&crate::scene::Aabb { min, max })
    }
}

/// `emitter_depth`: the cells holding the emitter split down to it and the
/// prune test (which a constant field always passes) keeps them; elsewhere
/// the octree stays at `min_depth`; 0 turns the rule off.
#[test]
fn emitter_cells_refine_to_emitter_depth_and_are_not_pruned() {
    let build = |e: u32, prune: Option<f32>| {
        build_adaptive(
            &ConstantWithEmitter,
            &AdaptiveSettings {
                geometry: false,
                emitter_depth: e,
                prediction_tolerance: Some(0.1),
                prune_tolerance: prune,
                ..geometry_only(common(Vec3::ZERO, Vec3::ONE, GradientMode::None), 5)
            },
        )
        .unwrap()
        .0
    };
    for prune in [None, Some(10.0)] {
        for e in [2, 4, 5] {
            let f = build(e, prune);
            assert_eq!(leaf_depth(&f, EMITTER), e, "depth {e}, prune {prune:?}");
            assert_eq!(leaf_depth(&f, Vec3::new(0.1, 0.9, 0.1)), 1);
        }
        let off = build(0, prune);
        assert_eq!(leaf_depth(&off, EMITTER), 1);
        assert_eq!(off.probe_set().positions.len(), 27);
    }
    // An emitter depth beyond max_depth: the emitter's cells alone go on.
    let f = build_adaptive(
        &RippleWithEmitter,
        &AdaptiveSettings {
            geometry: false,
            emitter_depth: 6,
            prediction_tolerance: Some(0.01),
            ..geometry_only(common(Vec3::ZERO, Vec3::ONE, GradientMode::None), 3)
        },
    )
    .unwrap()
    .0;
    assert_eq!(leaf_depth(&f, EMITTER), 6);
    assert_eq!(leaf_depth(&f, Vec3::new(0.1, 0.9, 0.1)), 3);
    let o = f.octree().unwrap();
    let leaves = o
        .nodes
        .iter()
        .filter(|n| n.first_child == crate::format::layout::NONE);
    for n in leaves {
        // Deeper than max_depth only as a child of an emitter cell (box
        // [0, 1]³, one root: the parent is the aligned box twice the size).
        let size = 2.0 * (n.max - n.min);
        let lo = (n.min / size).floor() * size;
        let parent_holds = RippleWithEmitter.contains_emitter(lo, lo + size);
        assert!(n.depth == 3 || (n.depth > 3 && parent_holds), "{n:?}");
    }
}

/// [`ConstantWithEmitter`]'s emitter in a field that trilinear prediction
/// misses everywhere (a ripple along x), so every cell splits to
/// `max_depth`.
struct RippleWithEmitter;
impl VolumeSource for RippleWithEmitter {
    fn order(&self) -> usize {
        1
    }
    fn capture(&self, p: &[Vec3]) -> Vec<Captured> {
        p.iter()
            .map(|p| exact(vec![Vec3::splat(1.0 + 0.5 * (40.0 * p.x).sin())]))
            .collect()
    }
    fn contains_emitter(&self, min: Vec3, max: Vec3) -> bool {
        ConstantWithEmitter.contains_emitter(min, max)
    }
}
