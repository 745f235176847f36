use super::*;
use crate::sampling::SampleRng;
use crate::sh::compare::spherical_fibonacci;
use glam::{DVec3, Vec2};
use probekit_sh::convolve::eval_sh;
use probekit_sh::ShRgb;
use std::f64::consts::PI;

const FOUR_PI: f64 = 4.0 * PI;

fn synthetic(w: usize, h: usize, f: impl Fn(Vec3) -> Vec3) -> EnvMap {
    let mut t = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let u = (x as f64 + 0.5) / w as f64;
            let v = (y as f64 + 0.5) / h as f64;
            t.push(f(uv_to_dir(u, v)));
        }
    }
    EnvMap::from_texels(Path::new("synthetic"), w, h, t).unwrap()
}

/// A band-limited (order 4) non-negative radiance with known coefficients.
fn band_limited() -> Vec<Vec3> {
    let mut c: Vec<Vec3> = (0..16)
        .map(|i| {
            let f = i as f32;
            Vec3::new(
                0.3 * (0.7 * f).cos(),
                0.2 * (1.3 * f).sin(),
                -0.15 * (0.4 * f).cos(),
            )
        })
        .collect();
    c[0] = Vec3::new(6.0, 5.0, 4.0); // large DC keeps it positive
    c
}

// ---------- solid angles ----------

#[test]
fn equirect_solid_angles_sum_to_4pi() {
    for (w, h) in [(8, 4), (512, 256), (7, 3)] {
        let m = EnvMap::builtin_sky(w, h);
        let total: f64 = (0..h).map(|y| m.row_solid_angle(y) * w as f64).sum();
        assert!((total - FOUR_PI).abs() < 1e-12, "{w}×{h}: {total}");
    }
}

/// Each row's solid angle against midpoint integration of `cos(lat) dlat dφ`.
#[test]
fn equirect_row_solid_angle_matches_quadrature() {
    let (w, h) = (16, 8);
    let m = EnvMap::builtin_sky(w, h);
    for y in 0..h {
        let lat0 = PI * (0.5 - (y + 1) as f64 / h as f64);
        let dlat = PI / h as f64;
        let n = 10_000;
        let q: f64 = (0..n)
            .map(|i| (lat0 + (i as f64 + 0.5) * dlat / n as f64).cos() * dlat / n as f64)
            .sum::<f64>()
            * (2.0 * PI / w as f64);
        assert!((q - m.row_solid_angle(y)).abs() < 1e-9, "row {y}");
    }
}

fn cube(size: usize, f: impl Fn(Vec3) -> Vec3) -> Cubemap {
    let mut faces: [Vec<Vec3>; 6] = Default::default();
    for face in CubeFace::ALL {
        for y in 0..size {
            for x in 0..size {
                let a = 2.0 * (x as f32 + 0.5) / size as f32 - 1.0;
                let b = 2.0 * (y as f32 + 0.5) / size as f32 - 1.0;
                faces[face as usize].push(f(face.direction(a, b).normalize()));
            }
        }
    }
    Cubemap::from_faces(Path::new("cube"), size, faces).unwrap()
}

#[test]
fn cubemap_solid_angles_sum_to_4pi() {
    for n in [1, 2, 5, 64] {
        let c = cube(n, |_| Vec3::ONE);
        let face: f64 = (0..n)
            .flat_map(|y| (0..n).map(move |x| (x, y)))
            .map(|(x, y)| c.texel_solid_angle(x, y))
            .sum();
        assert!((6.0 * face - FOUR_PI).abs() < 1e-12, "{n}: {}", 6.0 * face);
    }
}

/// One cube texel's solid angle against midpoint integration of
/// `dx dy / (1 + x² + y²)^{3/2}` over the texel.
#[test]
fn cubemap_texel_solid_angle_matches_quadrature() {
    let n = 8;
    let c = cube(n, |_| Vec3::ONE);
    for (x, y) in [(0, 0), (3, 4), (7, 2)] {
        let (x0, y0) = (
            2.0 * x as f64 / n as f64 - 1.0,
            2.0 * y as f64 / n as f64 - 1.0,
        );
        let s = 2.0 / n as f64;
        let k = 400;
        let mut q = 0.0;
        for j in 0..k {
            for i in 0..k {
                let px = x0 + (i as f64 + 0.5) * s / k as f64;
                let py = y0 + (j as f64 + 0.5) * s / k as f64;
                q += (s / k as f64).powi(2) / (1.0 + px * px + py * py).powf(1.5);
            }
        }
        assert!((q - c.texel_solid_angle(x, y)).abs() < 1e-8, "{q}");
    }
}

#[test]
fn cube_face_directions_round_trip() {
    for d in spherical_fibonacci(500) {
        let (face, a, b) = CubeFace::of_direction(d);
        assert!(a.abs() <= 1.0 + 1e-6 && b.abs() <= 1.0 + 1e-6);
        let back = face.direction(a, b).normalize();
        assert!((back - d).length() < 1e-5, "{d} {back}");
    }
    // face centres are the axes, in DirectX/glTF order
    let axes = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    for (f, axis) in CubeFace::ALL.iter().zip(axes) {
        assert_eq!(f.direction(0.0, 0.0), axis);
    }
}

// ---------- projection ----------

/// Projection of a band-limited map reproduces its coefficients (texel
/// quadrature error only), for both layouts.
#[test]
fn projection_of_band_limited_map() {
    let truth = band_limited();
    let map = synthetic(256, 128, |d| eval_sh(&truth, d));
    let sh = project_equirect(&map, 4);
    for (i, (a, b)) in sh.coeffs().iter().zip(&truth).enumerate() {
        assert!((*a - *b).length() < 2e-3, "equirect c{i}: {a} vs {b}");
    }
    let c = cube(64, |d| eval_sh(&truth, d));
    let sh = project_cubemap(&c, 4);
    for (i, (a, b)) in sh.coeffs().iter().zip(&truth).enumerate() {
        assert!((*a - *b).length() < 2e-3, "cube c{i}: {a} vs {b}");
    }
}

/// A constant map L gives c00 = L·√(4π) (solid angles sum to 4π exactly)
/// and zero elsewhere (band 2 up to the midpoint-direction quadrature error,
/// which shrinks with texel size).
#[test]
fn projection_of_constant_map() {
    let l = Vec3::new(1.0, 2.0, 0.5);
    let map = synthetic(64, 32, |_| l);
    let sh = project_equirect(&map, 3);
    let expect = l * FOUR_PI.sqrt() as f32;
    assert!((sh.coeffs()[0] - expect).length() < 1e-5);
    for c in &sh.coeffs()[1..4] {
        assert!(c.length() < 1e-5, "{c}");
    }
    for c in &sh.coeffs()[4..] {
        assert!(c.length() < 1e-3 * expect.length(), "{c}");
    }
    let sh = project_cubemap(&cube(8, |_| l), 3);
    assert!((sh.coeffs()[0] - expect).length() < 1e-5);
    for c in &sh.coeffs()[1..] {
        assert!(c.length() < 1e-5, "{c}");
    }
}

#[test]
fn projection_is_deterministic_across_thread_counts() {
    let map = EnvMap::builtin_sky(128, 64);
    let run = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
            .install(|| {
                (
                    project_equirect(&map, 3),
                    reference_irradiance(&map, &spherical_fibonacci(64)),
                )
            })
    };
    let (a, ra) = run(1);
    let (b, rb) = run(2);
    let (c, rc) = run(3);
    assert_eq!(a, b);
    assert_eq!(a, c);
    assert_eq!(ra, rb);
    assert_eq!(ra, rc);
}

// ---------- reference irradiance ----------

#[test]
fn reference_irradiance_constant_map_is_pi() {
    let map = synthetic(256, 128, |_| Vec3::splat(1.0));
    for e in reference_irradiance(&map, &spherical_fibonacci(50)) {
        assert!(
            (e - Vec3::splat(PI as f32)).abs().max_element() < 2e-3,
            "{e}"
        );
    }
}

/// For an L1 radiance, the brute-force irradiance equals the closed form
/// `E(n) = π·a + (2π/3)·b·n` of `L(ω) = a + b·ω`.
#[test]
fn reference_irradiance_of_linear_radiance() {
    let (a, b) = (2.0f32, Vec3::new(0.5, -0.7, 0.3));
    let map = synthetic(256, 128, |d| Vec3::splat(a + b.dot(d)));
    let normals = spherical_fibonacci(40);
    let e = reference_irradiance(&map, &normals);
    for (n, e) in normals.iter().zip(e) {
        let exact = PI as f32 * a + 2.0 * PI as f32 / 3.0 * b.dot(*n);
        assert!((e.x - exact).abs() < 2e-3 * exact, "{e} vs {exact}");
    }
}

/// The solid-angle-weighted 2×2 downsample preserves total flux exactly and
/// changes the reference irradiance of the sun sky by < 0.1 % (RMS).
#[test]
fn downsample_for_reference_is_accurate() {
    let map = EnvMap::builtin_sky(512, 256);
    let half = map.downsample_2x2();
    assert_eq!((half.width(), half.height()), (256, 128));
    let flux = |m: &EnvMap| -> DVec3 {
        (0..m.height())
            .map(|y| {
                (0..m.width())
                    .map(|x| m.texel(x, y).as_dvec3())
                    .sum::<DVec3>()
                    * m.row_solid_angle(y)
            })
            .sum()
    };
    let (f0, f1) = (flux(&map), flux(&half));
    assert!((f0 - f1).length() < 1e-5 * f0.length(), "{f0} {f1}");
    let normals = spherical_fibonacci(256);
    let e0 = reference_irradiance(&map, &normals);
    let e1 = reference_irradiance(&half, &normals);
    let err = crate::sh::compare::relative_rmse(&e1, &e0).unwrap();
    assert!(err < 1e-3, "downsample error {err}");
}

// ---------- sampling the map ----------

#[test]
fn bilinear_radiance() {
    let map = EnvMap::builtin_sky(32, 16);
    // at texel centres it returns the texel
    for (x, y) in [(0, 0), (5, 7), (31, 15), (16, 8)] {
        let r = map.radiance(map.texel_direction(x, y));
        assert!(
            (r - map.texel(x, y)).length() < 1e-3 * (1.0 + r.length()),
            "{x},{y}"
        );
    }
    // a linear function of longitude u between two centres interpolates linearly,
    // and wraps across the φ = ±π seam
    let t: Vec<Vec3> = (0..4 * 2).map(|i| Vec3::splat((i % 4) as f32)).collect();
    let m = EnvMap::from_texels(Path::new("t"), 4, 2, t).unwrap();
    let mid = |x: f64| m.radiance(uv_to_dir(x / 4.0, 0.25)).x;
    assert!((mid(1.0) - 0.5).abs() < 1e-4); // between texel 0 (0) and 1 (1)
    assert!((mid(0.0) - 1.5).abs() < 1e-4); // seam: between texel 3 (3) and 0 (0)
}

#[test]
fn builtin_sky_is_plausible() {
    let m = EnvMap::builtin_sky(256, 128);
    let sun = m.radiance(sun_direction());
    let zenith = m.radiance(Vec3::Y);
    let ground = m.radiance(-Vec3::Y);
    assert!(sun.x > 100.0 * zenith.x);
    assert!(zenith.z > zenith.x, "blue zenith");
    assert!(ground.length() < zenith.length());
    assert!(m
        .texels()
        .iter()
        .all(|t| t.is_finite() && t.min_element() >= 0.0));
    let named = EnvMap::load(BUILTIN_SKY).unwrap();
    assert_eq!(named.width(), BUILTIN_SKY_WIDTH);
}

#[test]
fn sampler_pdf_is_consistent_and_unbiased() {
    let map = EnvMap::builtin_sky(64, 32);
    let s = EnvSampler::new(&map);
    // ∫ pdf dω = 1, by exact texel quadrature of the piecewise-constant pdf
    let mut total = 0.0;
    for y in 0..map.height() {
        for x in 0..map.width() {
            total += s.pdf(map.texel_direction(x, y)) as f64 * map.row_solid_angle(y);
        }
    }
    assert!((total - 1.0).abs() < 1e-4, "{total}");
    // E[L cos⁺ / pdf] = brute-force irradiance (independent: reference_irradiance)
    let n = Vec3::new(0.3, 0.8, 0.2).normalize();
    let truth = reference_irradiance(&map, &[n])[0].as_dvec3();
    let flux_total: f64 = map
        .weighted_texels()
        .iter()
        .map(|t| t.flux.dot(probekit_sh::LUMINANCE) as f64)
        .sum();
    let k = 64 * 1024;
    let mut est = DVec3::ZERO;
    let mut rng = SampleRng::from_state(0x9E3779B97F4A7C15u64);
    for _ in 0..k {
        let (d, l, pdf) = s.sample(Vec2::new(rng.next_f32(), rng.next_f32()));
        assert!((d.length() - 1.0).abs() < 1e-4);
        let p2 = s.pdf(d);
        assert!((p2 - pdf).abs() <= 1e-3 * pdf, "pdf {pdf} vs {p2}");
        // luminance / pdf is the total luminance flux for every sample
        let ratio = l.dot(probekit_sh::LUMINANCE) as f64 / pdf as f64;
        assert!(
            (ratio - flux_total).abs() < 1e-3 * flux_total,
            "{ratio} {flux_total}"
        );
        est += (l * n.dot(d).max(0.0) / pdf).as_dvec3();
    }
    est /= k as f64;
    let rel = (est - truth).length() / truth.length();
    assert!(rel < 0.02, "estimate {est} vs {truth}");
}

#[test]
fn sampler_black_map_is_uniform() {
    let map = synthetic(16, 8, |_| Vec3::ZERO);
    let s = EnvSampler::new(&map);
    let (_, _, pdf) = s.sample(Vec2::new(0.3, 0.7));
    assert!((pdf as f64 - 1.0 / FOUR_PI).abs() < 1e-6);
}

// ---------- files ----------

fn patterned(w: usize, h: usize) -> EnvMap {
    let truth = band_limited();
    synthetic(w, h, |d| eval_sh(&truth, d) * 0.5)
}

/// The same image as EXR (f32) and RGBE HDR loads to the same texels within
/// RGBE precision, and to the same SH.
#[test]
fn exr_and_hdr_of_same_image_agree() {
    let dir = tempfile::tempdir().unwrap();
    let map = patterned(64, 32);
    let (pe, ph) = (dir.path().join("a.exr"), dir.path().join("a.hdr"));
    map.save_exr(&pe).unwrap();
    map.save_hdr(&ph).unwrap();
    let (e, h) = (EnvMap::load(&pe).unwrap(), EnvMap::load(&ph).unwrap());
    assert_eq!(e, map, "EXR f32 is lossless");
    assert_eq!((h.width(), h.height()), (64, 32));
    // RGBE: 8-bit mantissas under the largest channel's exponent, so each
    // channel's error is below max(channel) / 128.
    for (a, b) in h.texels().iter().zip(map.texels()) {
        assert!(
            (*a - *b).abs().max_element() <= b.max_element() / 128.0,
            "{a} vs {b}"
        );
    }
    let (se, sh) = (project_equirect(&e, 3), project_equirect(&h, 3));
    let c0 = se.coeffs()[0].length();
    for (a, b) in se.coeffs().iter().zip(sh.coeffs()) {
        assert!((*a - *b).length() < 5e-3 * c0, "{a} vs {b}");
    }
}

fn expect_err(path: &Path) -> EnvError {
    let e = EnvMap::load(path).expect_err("bad input must fail");
    let msg = e.to_string();
    assert!(
        msg.contains(&path.display().to_string()),
        "message names the file: {msg}"
    );
    assert!(!msg.contains('\n'), "one line: {msg}");
    e
}

#[test]
fn bad_inputs_give_typed_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // missing file
    assert!(matches!(
        expect_err(&d.join("missing.hdr")),
        EnvError::Io { .. }
    ));
    // text named .hdr
    std::fs::write(d.join("text.hdr"), "hello, I am not an image\n").unwrap();
    assert!(matches!(
        expect_err(&d.join("text.hdr")),
        EnvError::Decode { .. }
    ));
    // truncated .hdr and .exr
    let map = patterned(64, 32);
    map.save_hdr(d.join("full.hdr")).unwrap();
    map.save_exr(d.join("full.exr")).unwrap();
    for (full, cut) in [("full.hdr", "cut.hdr"), ("full.exr", "cut.exr")] {
        let bytes = std::fs::read(d.join(full)).unwrap();
        std::fs::write(d.join(cut), &bytes[..bytes.len() / 2]).unwrap();
        let e = expect_err(&d.join(cut));
        assert!(matches!(e, EnvError::Decode { .. }), "{cut}: {e}");
    }
    // empty file
    std::fs::write(d.join("empty.exr"), b"").unwrap();
    assert!(matches!(
        expect_err(&d.join("empty.exr")),
        EnvError::Decode { .. }
    ));
    // unsupported extension
    std::fs::write(d.join("x.jpg"), b"").unwrap();
    assert!(matches!(
        expect_err(&d.join("x.jpg")),
        EnvError::UnsupportedFormat { .. }
    ));
    // NaN, infinite and negative texels
    for (name, bad) in [
        ("nan.exr", Vec3::new(f32::NAN, 0.0, 0.0)),
        ("inf.exr", Vec3::new(0.0, f32::INFINITY, 0.0)),
        ("neg.exr", Vec3::new(0.0, 0.0, -0.5)),
    ] {
        let mut t = map.texels().to_vec();
        t[3 * 64 + 5] = bad;
        load::save_exr(&d.join(name), 64, &t).unwrap();
        match expect_err(&d.join(name)) {
            EnvError::BadTexel { x, y, .. } => assert_eq!((x, y), (5, 3)),
            e => panic!("{name}: {e}"),
        }
    }
    // zero size, in a file and in memory
    std::fs::write(
        d.join("zero.hdr"),
        "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 0 +X 0\n",
    )
    .unwrap();
    assert!(matches!(
        expect_err(&d.join("zero.hdr")),
        EnvError::ZeroSize { .. }
    ));
    assert!(matches!(
        EnvMap::from_texels(Path::new("z"), 0, 0, vec![]),
        Err(EnvError::ZeroSize { .. })
    ));
    assert!(matches!(
        Cubemap::from_faces(Path::new("z"), 0, Default::default()),
        Err(EnvError::ZeroSize { .. })
    ));
}

/// Patches an EXR's `compression` attribute value (1 byte after
/// `compression\0compression\0` and the 4-byte size).
fn patch_compression(bytes: &mut [u8], value: u8) {
    let key = b"compression\0compression\0";
    let at = bytes
        .windows(key.len())
        .position(|w| w == key)
        .expect("compression attribute")
        + key.len();
    assert_eq!(&bytes[at..at + 4], &1u32.to_le_bytes());
    bytes[at + 4] = value;
}

/// DWAA (8) / DWAB (9) data that cannot be decoded, and a compression id the
/// crate does not implement at all (10 = HTJ2K), name the compression and
/// suggest ZIP or PIZ.
#[test]
fn undecodable_exr_compression_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let map = patterned(64, 32);
    let src = dir.path().join("zip.exr");
    map.save_exr(&src).unwrap();
    let bytes = std::fs::read(&src).unwrap();
    for (value, name) in [(8u8, "DWAA"), (9, "DWAB")] {
        let mut b = bytes.clone();
        patch_compression(&mut b, value);
        let p = dir.path().join(format!("{name}.exr"));
        std::fs::write(&p, b).unwrap();
        let e = expect_err(&p);
        let msg = e.to_string();
        assert!(matches!(e, EnvError::ExrCompression { .. }), "{msg}");
        assert!(
            msg.contains(name) && msg.contains("ZIP") && msg.contains("PIZ"),
            "{msg}"
        );
    }
}

// ---------- cubemap folders ----------

#[test]
fn cubemap_folder_loads_and_projects_like_equirect() {
    let dir = tempfile::tempdir().unwrap();
    let truth = band_limited();
    let c = cube(32, |d| eval_sh(&truth, d));
    for f in CubeFace::ALL {
        load::save_exr(
            &dir.path().join(format!("{}.exr", f.file_stem())),
            32,
            c.face(f),
        )
        .unwrap();
    }
    let loaded = Cubemap::load_dir(dir.path()).unwrap();
    assert_eq!(loaded, c);
    let sh = project_cubemap(&loaded, 3);
    let eq = EnvMap::load(dir.path()).unwrap(); // resampled to equirect
    assert_eq!(eq.width(), 128);
    let she = project_equirect(&eq, 3);
    for ((a, b), t) in sh.coeffs().iter().zip(she.coeffs()).zip(&truth) {
        assert!((*a - *t).length() < 3e-3, "cube {a} vs {t}");
        // nearest resampling is coarse: looser bound
        assert!((*b - *t).length() < 0.05, "resampled {b} vs {t}");
    }
    // a missing face is named
    std::fs::remove_file(dir.path().join("nz.exr")).unwrap();
    let e = Cubemap::load_dir(dir.path()).unwrap_err();
    assert!(e.to_string().contains("-Z"), "{e}");
}

#[test]
fn shrgb_round_trip_of_projection() {
    // projecting reconstructs evaluation: eval(project(map)) ≈ map for band-limited input
    let truth = ShRgb::from_coeffs(band_limited()[..9].to_vec()).unwrap();
    let map = synthetic(128, 64, |d| truth.eval(d));
    let sh = project_equirect(&map, 3);
    for d in spherical_fibonacci(20) {
        assert!((sh.eval(d) - truth.eval(d)).length() < 5e-3);
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(12))]

    /// Property: projecting any (non-negative) band-limited L2 radiance
    /// sampled on a 128×64 map returns its coefficients, up to the texel
    /// quadrature error.
    #[test]
    fn projection_of_random_band_limited_radiance(
        raw in proptest::collection::vec(-1.0f32..1.0, 24)
    ) {
        let mut c = vec![Vec3::ZERO; 9];
        for i in 1..9 {
            c[i] = Vec3::new(raw[3 * (i - 1)], raw[3 * (i - 1) + 1], raw[3 * (i - 1) + 2]);
        }
        // |Y_lm| <= 0.631 for l <= 2, so this DC keeps the radiance positive
        let bound: Vec3 = c[1..].iter().map(|v| v.abs()).sum::<Vec3>() * 0.7 + Vec3::splat(0.1);
        c[0] = bound / probekit_sh::basis::Y00;
        let map = synthetic(128, 64, |d| eval_sh(&c, d));
        let sh = project_equirect(&map, 3);
        let scale = c.iter().map(|v| v.abs().max_element()).sum::<f32>();
        for (a, b) in sh.coeffs().iter().zip(&c) {
            proptest::prop_assert!((*a - *b).abs().max_element() < 1e-3 * scale, "{} vs {}", a, b);
        }
    }
}

/// Chi-square test of the sampler: samples binned by texel row and by 8
/// column groups against the expected probability `∫ pdf dω` of each bin
/// (computed from `pdf()` at texel centres times the exact solid angles).
#[test]
fn sampler_chi_square() {
    let map = EnvMap::builtin_sky(32, 16);
    let s = EnvSampler::new(&map);
    let (bins_x, bins_y) = (8, 16);
    let mut expected = vec![0.0f64; bins_x * bins_y];
    for y in 0..16 {
        for x in 0..32 {
            let p = s.pdf(map.texel_direction(x, y)) as f64 * map.row_solid_angle(y);
            expected[y * bins_x + x / 4] += p;
        }
    }
    let n = 40_000;
    let mut counts = vec![0.0f64; bins_x * bins_y];
    let mut rng = SampleRng::from_state(0x2545F4914F6CDD1Du64);
    for _ in 0..n {
        let (d, _, _) = s.sample(Vec2::new(rng.next_f32(), rng.next_f32()));
        let (x, y) = map.texel_of(d);
        counts[y * bins_x + x / 4] += 1.0;
    }
    // pool bins with small expectation (standard chi-square practice)
    let (mut chi2, mut dof, mut pool_e, mut pool_c) = (0.0, 0usize, 0.0, 0.0);
    for (e, c) in expected.iter().zip(&counts) {
        let e = e * n as f64;
        if e < 5.0 {
            pool_e += e;
            pool_c += c;
        } else {
            chi2 += (c - e) * (c - e) / e;
            dof += 1;
        }
    }
    if pool_e > 0.0 {
        chi2 += (pool_c - pool_e) * (pool_c - pool_e) / pool_e.max(1.0);
        dof += 1;
    }
    // 99.99th percentile of χ² for `dof − 1` degrees of freedom is below
    // dof + 5.4·sqrt(2·dof) for dof in this range (Wilson–Hilferty).
    let limit = dof as f64 + 5.4 * (2.0 * dof as f64).sqrt();
    println!("chi2 {chi2:.1} over {dof} bins (limit {limit:.1})");
    assert!(chi2 < limit, "chi2 {chi2} over {dof} bins (limit {limit})");
}
