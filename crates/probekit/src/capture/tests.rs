//! Capture tests against closed forms.
//!
//! Statistical tolerances come from the estimator's own spread: each check
//! runs the capture with several seeds and allows 5 standard errors of the
//! mean across seeds (plus a float floor), so a wrong factor fails while
//! noise does not.

use super::*;
use crate::scene::{
    AlphaMode, BakeSettings, EnvironmentDesc, Light, LightKind, Material, Parts, SceneExtras,
    Triangle,
};
use glam::Vec2;
use probekit_sh::zonal::zh_to_sh;
use std::f64::consts::PI;
use std::path::Path;

pub(crate) fn tri(a: Vec3, b: Vec3, c: Vec3, material: u32) -> Triangle {
    let n = (b - a).cross(c - a).normalize();
    Triangle {
        positions: [a, b, c],
        normals: [n; 3],
        uvs: [Vec2::ZERO; 3],
        material,
    }
}

/// A closed axis-aligned box; faces point outward, or inward when `inward`.
pub(crate) fn box_tris(min: Vec3, max: Vec3, inward: bool, material: u32) -> Vec<Triangle> {
    let c = (min + max) * 0.5;
    let h = (max - min) * 0.5;
    let mut out = Vec::new();
    for a in 0..3 {
        let (ua, va) = ((a + 1) % 3, (a + 2) % 3);
        for s in [-1.0f32, 1.0] {
            let e = |i: usize| Vec3::AXES[i];
            let fc = c + e(a) * h[a] * s;
            let u = e(ua) * h[ua];
            let v = e(va) * h[va];
            let mut q = [fc - u - v, fc + u - v, fc + u + v, fc - u + v];
            // u × v = +e_a: counter-clockwise seen from +e_a
            if (s < 0.0) != inward {
                q.reverse();
            }
            out.push(tri(q[0], q[1], q[2], material));
            out.push(tri(q[0], q[2], q[3], material));
        }
    }
    out
}

pub(crate) fn material(albedo: f32, emissive: f32) -> Material {
    Material {
        name: format!("a{albedo}e{emissive}"),
        base_color: Vec3::splat(albedo),
        emissive: Vec3::splat(emissive),
        ..Material::default()
    }
}

pub(crate) fn scene_of(
    objects: Vec<Vec<Triangle>>,
    materials: Vec<Material>,
    lights: Vec<Light>,
    sky: Vec3,
) -> Scene {
    let mut objects = objects;
    // Scenes must have triangles: a 1 mm black speck 1 km away stands in for
    // "empty space".
    let speck = materials.len() as u32;
    let mut materials = materials;
    materials.push(material(0.0, 0.0));
    let far = Vec3::new(1000.0, 1000.0, 1000.0);
    objects.push(vec![tri(
        far,
        far + Vec3::X * 1e-3,
        far + Vec3::Y * 1e-3,
        speck,
    )]);
    let parts = Parts {
        objects: objects
            .into_iter()
            .enumerate()
            .map(|(i, t)| (format!("o{i}"), t))
            .collect(),
        materials,
        lights,
        ..Parts::default()
    };
    let extras = SceneExtras {
        environment: EnvironmentDesc {
            color: sky,
            ..EnvironmentDesc::default()
        },
        bake: BakeSettings::default(),
        regions: Vec::new(),
    };
    Scene::from_parts(Path::new("test"), parts, extras).expect("test scene")
}

pub(crate) fn light(
    kind: LightKind,
    position: Vec3,
    direction: Vec3,
    intensity: f32,
    radius: f32,
) -> Light {
    Light {
        kind,
        position,
        direction,
        color: Vec3::ONE,
        intensity,
        radius,
        inner_angle: 0.0,
        outer_angle: 0.0,
        group: None,
        mode: crate::scene::LightMode::Auto,
        angular_diameter: 0.0,
    }
}

/// Mean and standard error of the mean over runs, per coefficient (red channel).
/// Empty space, black sky, one sphere light (centre `c`, radius `r`,
/// `intensity` candela).
fn lone_sphere_light(c: Vec3, r: f32, intensity: f32) -> Scene {
    scene_of(
        vec![],
        vec![],
        vec![light(LightKind::Sphere, c, Vec3::NEG_Y, intensity, r)],
        Vec3::ZERO,
    )
}

pub(crate) fn mean_se(runs: &[Vec<f64>]) -> (Vec<f64>, Vec<f64>) {
    let k = runs.len() as f64;
    let n = runs[0].len();
    let mut m = vec![0.0; n];
    let mut se = vec![0.0; n];
    for i in 0..n {
        m[i] = runs.iter().map(|r| r[i]).sum::<f64>() / k;
        let v = runs.iter().map(|r| (r[i] - m[i]).powi(2)).sum::<f64>() / (k - 1.0);
        se[i] = (v / k).sqrt();
    }
    (m, se)
}

pub(crate) fn assert_close(got: &[f64], se: &[f64], want: &[f64], floor: f64, what: &str) {
    for i in 0..want.len() {
        let tol = 5.0 * se[i] + floor;
        assert!(
            (got[i] - want[i]).abs() <= tol,
            "{what}: coefficient {i}: {} vs closed form {} (tolerance {tol})",
            got[i],
            want[i]
        );
    }
}

pub(crate) fn red(sh: &ShRgb) -> Vec<f64> {
    sh.coeffs().iter().map(|c| c.x as f64).collect()
}

/// Legendre P_l(x) by the three-term recurrence.
fn legendre(l: usize, x: f64) -> f64 {
    let (mut p0, mut p1) = (1.0, x);
    if l == 0 {
        return 1.0;
    }
    for k in 2..=l {
        let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
        p0 = p1;
        p1 = p2;
    }
    p1
}

/// Yuan et al. 2011 (Irradiance Rigs), A1: a sphere light of radiance L subtending a
/// cap of half-angle α has zonal coefficients
/// `z_l = 2π L ∫_{cos α}^1 Y_l0(x) dx`, here by composite Simpson.
fn sphere_light_zonal(l_rad: f64, cos_alpha: f64, order: usize) -> Vec<f32> {
    (0..order)
        .map(|l| {
            let k = ((2 * l + 1) as f64 / (4.0 * PI)).sqrt();
            let n = 2000;
            let h = (1.0 - cos_alpha) / n as f64;
            let mut s = 0.0;
            for i in 0..=n {
                let x = cos_alpha + i as f64 * h;
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                s += w * k * legendre(l, x);
            }
            (2.0 * PI * l_rad * s * h / 3.0) as f32
        })
        .collect()
}

pub(crate) fn quick(samples: u32, bounces: u32, order: usize, seed: u64) -> CaptureSettings {
    CaptureSettings {
        samples,
        bounces,
        order,
        seed,
        ..CaptureSettings::default()
    }
}

#[test]
fn sphere_light_in_empty_space_matches_zonal_closed_form() {
    let (c, r, intensity) = (Vec3::new(0.6, 1.5, -0.8), 0.4f32, 20.0f32);
    let scene = lone_sphere_light(c, r, intensity);
    let baker = Baker::new(&scene).unwrap();
    let order = 4;
    let runs: Vec<Vec<f64>> = (0..8)
        .map(|seed| {
            red(&baker
                .capture(Vec3::ZERO, 0, &quick(512, 3, order, seed))
                .unwrap()
                .sh)
        })
        .collect();
    let (m, se) = mean_se(&runs);
    let d = c.length() as f64;
    let cos_alpha = (1.0 - (r as f64 / d).powi(2)).sqrt();
    let l_rad = intensity as f64 / (PI * (r as f64).powi(2));
    let zh = sphere_light_zonal(l_rad, cos_alpha, order);
    let mut want = vec![0.0f32; order * order];
    zh_to_sh(&zh, c.normalize(), &mut want);
    let want: Vec<f64> = want.iter().map(|v| *v as f64).collect();
    assert_close(&m, &se, &want, 1e-3 * want[0].abs(), "sphere light SH");
    // and the analytic sphere light of probekit_sh::lights agrees too
    let mut lib = vec![Vec3::ZERO; order * order];
    probekit_sh::lights::sphere::sphere_light_sh(
        order,
        Vec3::ZERO,
        c,
        r,
        Vec3::splat(intensity),
        &mut lib,
    );
    let lib: Vec<f64> = lib.iter().map(|v| v.x as f64).collect();
    assert_close(
        &m,
        &se,
        &lib,
        1e-3 * want[0].abs(),
        "sphere light vs probekit_sh::lights",
    );
    // the estimator really is light-sampled: relative spread of c00 per run is small
    assert!(
        se[0] < 0.01 * want[0],
        "c00 standard error {} too large",
        se[0]
    );
}

/// A probe requested inside a sphere light is pushed out past its surface
/// (or, without virtual offset, flagged invalid), and what it then captures
/// matches the closed form for the point it was moved to: the light's DC
/// `L·2π(1 − cos α)·Y00` seen from distance `d`, with `sin α = r / d`.
#[test]
fn probe_inside_a_sphere_light_is_pushed_out_or_flagged() {
    let (c, r, intensity) = (Vec3::new(0.0, 1.0, 0.0), 0.3f32, 10.0f32);
    let scene = lone_sphere_light(c, r, intensity);
    let baker = Baker::new(&scene).unwrap();
    let s = quick(256, 1, 3, 1);
    let got = baker
        .capture(c + Vec3::new(0.05, 0.02, 0.0), 0, &s)
        .unwrap();
    let d = got.position.distance(c);
    assert!(d > r, "still inside: {d}");
    assert!(got.validity.offset_applied && got.validity.valid);
    let sin_a = (r / d) as f64;
    let l = intensity as f64 / (PI * (r * r) as f64);
    let dc = l * 2.0 * PI * (1.0 - (1.0 - sin_a * sin_a).sqrt()) * 0.5 / PI.sqrt();
    let g = got.sh.coeffs()[0].x as f64;
    assert!((g - dc).abs() < 0.03 * dc, "DC {g} vs closed form {dc}");
    let mut off = s.clone();
    off.validity.virtual_offset = false;
    let stuck = baker.capture(c, 0, &off).unwrap();
    assert_eq!(stuck.position, c);
    assert!(!stuck.validity.valid);
}

#[test]
fn point_light_reference_irradiance_is_inverse_square_cosine() {
    let lp = Vec3::new(0.0, 2.0, 0.0);
    let scene = scene_of(
        vec![],
        vec![],
        vec![light(LightKind::Point, lp, Vec3::NEG_Y, 8.0, 0.0)],
        Vec3::ZERO,
    );
    let baker = Baker::new(&scene).unwrap();
    let s = ReferenceSettings::default();
    for (i, theta) in [0.0f32, 0.5, 1.2, 2.0].into_iter().enumerate() {
        let n = Vec3::new(theta.sin(), theta.cos(), 0.0);
        let r = baker
            .reference_irradiance(Vec3::ZERO, n, i as u64, &s)
            .unwrap();
        let want = 8.0 / 4.0 * theta.cos().max(0.0);
        assert!(
            (r.irradiance.x - want).abs() < 1e-5,
            "θ={theta}: {} vs {want}",
            r.irradiance.x
        );
    }
}

#[test]
fn sphere_and_disk_reference_irradiance_match_closed_forms() {
    // Sphere wholly above the horizon: E = π L sin²α cos θ = I cos θ / d².
    // Disk on the normal's axis facing the point: E = π L r² / (r² + h²).
    let sphere = Vec3::new(0.0, 2.0, 0.0);
    let disk = Vec3::new(0.0, -1.5, 0.0);
    let scene = scene_of(
        vec![],
        vec![],
        vec![
            light(LightKind::Sphere, sphere, Vec3::NEG_Y, 10.0, 0.3),
            light(LightKind::Disk, disk, Vec3::Y, 5.0, 0.5),
        ],
        Vec3::ZERO,
    );
    let baker = Baker::new(&scene).unwrap();
    let s = ReferenceSettings {
        relative_precision: 0.002,
        ..ReferenceSettings::default()
    };
    let theta = 0.4f32;
    let n = Vec3::new(theta.sin(), theta.cos(), 0.0);
    let r = baker.reference_irradiance(Vec3::ZERO, n, 0, &s).unwrap();
    let want = 10.0 / 4.0 * theta.cos() as f64;
    let got = r.irradiance.x as f64;
    assert!(
        (got - want).abs() < 5.0 * r.std_error.x as f64 + 1e-4,
        "sphere: {got} vs {want}"
    );
    let r = baker
        .reference_irradiance(Vec3::ZERO, Vec3::NEG_Y, 1, &s)
        .unwrap();
    let l = 5.0 / (PI * 0.25);
    let want = PI * l * 0.25 / (0.25 + 1.5 * 1.5);
    let got = r.irradiance.x as f64;
    assert!(
        (got - want).abs() < 5.0 * r.std_error.x as f64 + 1e-4,
        "disk: {got} vs {want}"
    );
}

#[test]
fn directional_and_spot_lights_follow_their_definitions() {
    let spot_pos = Vec3::new(0.0, 3.0, 0.0);
    let mut spot = light(LightKind::Spot, spot_pos, Vec3::NEG_Y, 30.0, 0.0);
    spot.inner_angle = 0.2;
    spot.outer_angle = 0.6;
    let mut sun = light(
        LightKind::Directional,
        Vec3::ZERO,
        Vec3::new(1.0, -1.0, 0.0).normalize(),
        7.0,
        0.0,
    );
    sun.group = Some("sun".into());
    let scene = scene_of(vec![], vec![], vec![spot, sun], Vec3::ZERO);
    let baker = Baker::new(&scene).unwrap();
    // a point 1 m off the axis at the spot's foot: angle atan(1/3) = 0.3217 rad, in the ramp
    let p = Vec3::new(1.0, 0.0, 0.0);
    let r = baker
        .reference_irradiance(p, Vec3::Y, 0, &ReferenceSettings::default())
        .unwrap();
    let to_spot = spot_pos - p;
    let d2 = to_spot.length_squared() as f64;
    let cos_axis = (3.0 / d2.sqrt()) as f32;
    let (ci, co) = (0.2f32.cos(), 0.6f32.cos());
    let ramp = ((cos_axis - co) / (ci - co)).powi(2) as f64; // KHR_lights_punctual
    let sun_e = 7.0 * std::f64::consts::FRAC_1_SQRT_2; // lux · cos 45°
    let want = 30.0 / d2 * ramp * (3.0 / d2.sqrt()) + sun_e;
    assert!(
        (r.irradiance.x as f64 - want).abs() < 1e-4 * want,
        "{} vs {want}",
        r.irradiance.x
    );
    // delta lights in SH: E·Y_lm(ω_l); the group split holds the sun alone
    let s = CaptureSettings {
        groups: true,
        ..quick(64, 0, 3, 1)
    };
    let cap = baker.capture(Vec3::new(5.0, 0.0, 0.0), 0, &s).unwrap();
    let sun_sh = &cap.groups.iter().find(|(n, _)| n == "sun").unwrap().1;
    let mut y = [0.0f32; 9];
    probekit_sh::eval_basis(3, Vec3::new(-1.0, 1.0, 0.0).normalize(), &mut y);
    for (c, yv) in sun_sh.coeffs().iter().zip(y) {
        assert!((c.x - 7.0 * yv).abs() < 1e-5, "{} vs {}", c.x, 7.0 * yv);
    }
}

#[test]
fn glass_passes_one_minus_opacity_for_shadow_and_path_rays() {
    // A pane of opacity 0.3 at y = 1 between the receiver and the lights.
    let alpha = 0.3f32;
    let glass = Material {
        alpha,
        alpha_mode: AlphaMode::Blend,
        base_color: Vec3::ZERO,
        ..Material::default()
    };
    let (a, b, c, d) = (
        Vec3::new(-5.0, 1.0, -5.0),
        Vec3::new(5.0, 1.0, -5.0),
        Vec3::new(5.0, 1.0, 5.0),
        Vec3::new(-5.0, 1.0, 5.0),
    );
    let pane = vec![tri(a, b, c, 0), tri(a, c, d, 0)];
    // off the pane's diagonal: a shadow ray exactly through the shared edge
    // would cross both triangles (the tracer documents this)
    let pl = Vec3::new(0.3, 2.0, -0.8);
    let scene = scene_of(
        vec![pane],
        vec![glass],
        vec![
            light(LightKind::Point, pl, Vec3::NEG_Y, 4.0, 0.0),
            light(
                LightKind::Sphere,
                Vec3::new(1.0, 3.0, 0.0),
                Vec3::NEG_Y,
                9.0,
                0.5,
            ),
        ],
        Vec3::ZERO,
    );
    let baker = Baker::new(&scene).unwrap();
    let s = ReferenceSettings {
        relative_precision: 0.003,
        ..ReferenceSettings::default()
    };
    let r = baker
        .reference_irradiance(Vec3::ZERO, Vec3::Y, 0, &s)
        .unwrap();
    let ds = Vec3::new(1.0, 3.0, 0.0);
    let point = 4.0 / pl.length_squared() as f64 * (2.0 / pl.length() as f64);
    let sphere = 9.0 / ds.length_squared() as f64 * (3.0 / ds.length() as f64);
    let want = (1.0 - alpha as f64) * (point + sphere);
    let got = r.irradiance.x as f64;
    assert!(
        (got - want).abs() < 5.0 * r.std_error.x as f64 + 1e-4,
        "{got} vs {want}"
    );
}

/// A closed box, faces inward, albedo a and emission Le everywhere.
fn furnace(a: f32, le: f32) -> Scene {
    scene_of(
        vec![box_tris(
            Vec3::splat(-1.0),
            Vec3::new(1.0, 1.5, 0.8),
            true,
            0,
        )],
        vec![material(a, le)],
        vec![],
        Vec3::ZERO,
    )
}

#[test]
fn furnace_gives_geometric_series_per_bounce_count() {
    let (a, le) = (0.6f32, 1.5f32);
    let scene = furnace(a, le);
    let baker = Baker::new(&scene).unwrap();
    let y00 = (1.0 / (4.0 * PI)).sqrt();
    for bounces in [0u32, 1, 3] {
        let runs: Vec<Vec<f64>> = (0..6)
            .map(|seed| {
                let s = CaptureSettings {
                    split_direct: true,
                    ..quick(512, bounces, 2, seed)
                };
                let c = baker.capture(Vec3::new(0.1, 0.2, -0.1), 7, &s).unwrap();
                assert!(c.validity.valid && !c.validity.offset_applied);
                // direct is the emission seen straight: Le
                let d00 = c.direct.as_ref().unwrap().coeffs()[0].x as f64;
                assert!(
                    (d00 / y00 / (4.0 * PI) - le as f64).abs() < 0.03 * le as f64,
                    "direct {d00}"
                );
                red(&c.sh)
            })
            .collect();
        let (m, se) = mean_se(&runs);
        let l: f64 = (0..=bounces)
            .map(|k| le as f64 * (a as f64).powi(k as i32))
            .sum();
        // isotropic radiance L: c00 = L·4π·Y00 = L·sqrt(4π); the rest vanish
        let want = [l * 4.0 * PI * y00, 0.0, 0.0, 0.0];
        assert_close(
            &m,
            &se,
            &want,
            2e-3 * want[0],
            &format!("furnace B={bounces}"),
        );
    }
}

#[test]
fn furnace_converges_to_le_over_one_minus_a_with_russian_roulette() {
    let (a, le) = (0.5f32, 1.0f32);
    let scene = furnace(a, le);
    let baker = Baker::new(&scene).unwrap();
    let runs: Vec<Vec<f64>> = (0..6)
        .map(|seed| {
            red(&baker
                .capture(Vec3::ZERO, 1, &quick(512, 1000, 1, seed))
                .unwrap()
                .sh)
        })
        .collect();
    let (m, se) = mean_se(&runs);
    let want = le as f64 / (1.0 - a as f64) * (4.0 * PI).sqrt();
    assert_close(&m, &se, &[want], 2e-3 * want, "converged furnace");
}

#[test]
fn uniform_sky_in_empty_space_is_constant_radiance() {
    let sky = Vec3::new(0.2, 0.5, 1.0);
    let scene = scene_of(vec![], vec![], vec![], sky);
    let baker = Baker::new(&scene).unwrap();
    let c = baker.capture(Vec3::ZERO, 0, &quick(1024, 3, 3, 1)).unwrap();
    let want = (4.0 * PI).sqrt() as f32;
    assert!((c.sh.coeffs()[0] - sky * want).abs().max_element() < 1e-4);
    for k in 1..9 {
        // Only quadrature error is left: R2 points reach below 1 % of c00
        // at 1024 directions, where independent random ones spread ~3 %.
        let tol = 1e-2 * c.sh.coeffs()[0];
        assert!(
            c.sh.coeffs()[k].abs().cmplt(tol).all(),
            "{k}: {}",
            c.sh.coeffs()[k]
        );
    }
}

#[test]
fn environment_map_capture_matches_projection() {
    use crate::env::{project::project_equirect, EnvMap};
    let (w, h) = (32usize, 16usize);
    let mut texels = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let bright = if (3..6).contains(&y) && (20..24).contains(&x) {
                40.0
            } else {
                0.3
            };
            texels.push(Vec3::new(bright, bright * 0.5, 0.1 + x as f32 * 0.01));
        }
    }
    let map = EnvMap::from_texels(Path::new("synthetic"), w, h, texels).unwrap();
    let scene = scene_of(vec![], vec![], vec![], Vec3::ZERO);
    let mut baker = Baker::new(&scene).unwrap();
    baker.set_environment_map(&map, 1.0, 0.0);
    let order = 3;
    let runs: Vec<Vec<f64>> = (0..6)
        .map(|seed| {
            red(&baker
                .capture(Vec3::ZERO, 0, &quick(512, 3, order, seed))
                .unwrap()
                .sh)
        })
        .collect();
    let (m, se) = mean_se(&runs);
    let want = red(&project_equirect(&map, order));
    assert_close(&m, &se, &want, 0.01 * want[0].abs(), "environment map");
}

/// A room 6 m across (inward faces) around `solids` (outward faces), lit
/// by a point light at `light_at`.
fn lit_room(solids: Vec<Vec<Triangle>>, light_at: Vec3) -> Scene {
    let mut objects = vec![box_tris(Vec3::splat(-3.0), Vec3::splat(3.0), true, 0)];
    objects.extend(solids);
    let lamp = light(LightKind::Point, light_at, Vec3::NEG_Y, 5.0, 0.0);
    scene_of(objects, vec![material(0.5, 0.0)], vec![lamp], Vec3::ZERO)
}

/// [`lit_room`] around a solid 1 m block at the origin, the light above it.
fn room_with_block() -> Scene {
    let block = box_tris(Vec3::splat(-0.5), Vec3::splat(0.5), false, 0);
    lit_room(vec![block], Vec3::new(0.0, 2.5, 0.0))
}

#[test]
fn probe_inside_a_solid_block_is_invalid_and_pushed_out() {
    let scene = room_with_block();
    let baker = Baker::new(&scene).unwrap();
    let p = Vec3::new(0.3, 0.1, 0.0); // nearest face x = 0.5
    let mut s = quick(256, 1, 3, 1);
    s.validity.virtual_offset = false;
    let c = baker.capture(p, 0, &s).unwrap();
    assert!(
        !c.validity.valid && c.validity.backface_fraction > 0.99,
        "{:?}",
        c.validity
    );
    assert!((c.validity.nearest_distance - 0.2).abs() < 0.01);
    s.validity.virtual_offset = true;
    let c = baker.capture(p, 0, &s).unwrap();
    assert!(
        c.validity.offset_applied && c.validity.valid,
        "{:?}",
        c.validity
    );
    // Straight across the face x = 0.5 to the margin beyond it, not along
    // the nearest ray (a few degrees off the normal, it would slide along
    // the face and leave a grid's layer).
    let want = Vec3::new(0.5 + s.validity.offset_margin, p.y, p.z);
    assert!(
        c.position.distance(want) < 1e-5,
        "pushed to {}, not {want}",
        c.position
    );
    assert!(c.sh.coeffs()[0].x > 0.0, "the pushed probe sees the light");
}

/// A thin wall (10 cm) whose top touches a slab above it, as a room's
/// dividing wall meets the ceiling: a probe in the wall just under its top
/// is pushed into the slab and back into the wall, and the virtual offset's
/// fallback takes it out through the wall's side into the room.
#[test]
fn probe_in_a_wall_touching_a_slab_ends_in_free_space() {
    let (wall_min, wall_max) = (Vec3::new(-0.05, -3.0, -1.0), Vec3::new(0.05, 2.0, 1.0));
    let (slab_min, slab_max) = (Vec3::new(-3.0, 2.0, -3.0), Vec3::new(3.0, 2.4, 3.0));
    let solids = vec![
        box_tris(wall_min, wall_max, false, 0),
        box_tris(slab_min, slab_max, false, 0),
    ];
    let scene = lit_room(solids, Vec3::new(1.5, 0.0, 0.0));
    let inside = |p: Vec3, lo: Vec3, hi: Vec3| p.cmpgt(lo).all() && p.cmplt(hi).all();
    let baker = Baker::new(&scene).unwrap();
    let s = quick(256, 1, 2, 5);
    for (i, p) in [
        Vec3::new(0.01, 1.99, 0.3),
        Vec3::new(-0.02, 1.985, -0.4),
        Vec3::new(0.0, 1.995, 0.0),
    ]
    .into_iter()
    .enumerate()
    {
        let c = baker.capture(p, i as u64, &s).unwrap();
        let q = c.position;
        assert!(
            c.validity.offset_applied && c.validity.valid,
            "{p} moved to {q}: {:?}",
            c.validity
        );
        assert!(
            !inside(q, wall_min, wall_max) && !inside(q, slab_min, slab_max),
            "{p} moved to {q}, still in geometry"
        );
        assert!(q.distance(p) < 0.2, "{p} moved far, to {q}");
        assert!(c.sh.coeffs()[0].x > 0.0, "{p} at {q} sees no light");
    }
}

/// `capture_positions` predicts where a bake captures its probes, bit for
/// bit, moved ones included (the CLI tetrahedralizes them before spending
/// the capture), and refuses a non-finite point like the capture.
#[test]
fn capture_positions_are_where_the_bake_captures() {
    let scene = room_with_block();
    let baker = Baker::new(&scene).unwrap();
    let s = quick(64, 1, 2, 7);
    let points = [
        Vec3::new(0.3, 0.1, 0.0),  // in the block: moved out
        Vec3::new(-0.2, 0.4, 0.1), // in the block: moved out
        Vec3::new(1.5, 1.0, -1.0),
        Vec3::new(-1.5, 2.0, 1.0),
        Vec3::new(2.0, -2.0, 2.0),
    ];
    let predicted = baker.capture_positions(&points, 3, &s).unwrap();
    let baked = baker.bake_points_from(&points, 3, &s, &|_, _| {}).unwrap();
    assert_eq!(predicted, baked.captured_positions);
    assert!(baked.validity[0].offset_applied && baked.validity[1].offset_applied);
    assert_ne!(predicted[0], points[0]);
    assert_eq!(&predicted[2..], &points[2..]);
    let err = baker
        .capture_positions(&[Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 0.0)], 0, &s)
        .unwrap_err();
    assert!(
        matches!(err, BakeError::NonFinitePosition { index: 1, .. }),
        "{err}"
    );
}

#[test]
fn parity_judges_inconsistently_wound_triangles() {
    // solid block with its +x face flipped: those triangles (and neighbours
    // sharing an edge with them) are flagged; parity still says "inside"
    let mut block = box_tris(Vec3::splat(-0.5), Vec3::splat(0.5), false, 0);
    for t in block
        .iter_mut()
        .filter(|t| t.positions.iter().all(|p| p.x > 0.49))
    {
        t.positions.swap(1, 2);
    }
    let scene = scene_of(vec![block], vec![material(0.5, 0.0)], vec![], Vec3::ZERO);
    assert!(
        (0..12).any(|t| !scene.winding_consistent(t)),
        "scene flags the flipped face"
    );
    let baker = Baker::new(&scene).unwrap();
    let mut s = quick(512, 0, 1, 1);
    s.validity.virtual_offset = false;
    let v = baker.capture(Vec3::ZERO, 0, &s).unwrap().validity;
    assert!(v.backface_fraction > 0.99, "{v:?}");
}

#[test]
fn harmonic_mean_distance_in_a_cube_matches_quadrature() {
    // centre of an inward cube of half-size h: d(ω) = h / max|ω_i|, so the
    // harmonic mean is h / E[max|ω_i|]; E by a dense Fibonacci sphere.
    let h = 1.5f32;
    let scene = scene_of(
        vec![box_tris(Vec3::splat(-h), Vec3::splat(h), true, 0)],
        vec![material(0.5, 0.0)],
        vec![],
        Vec3::ZERO,
    );
    let baker = Baker::new(&scene).unwrap();
    let v = baker
        .capture(Vec3::ZERO, 0, &quick(4096, 0, 1, 3))
        .unwrap()
        .validity;
    let n = 200_000;
    let ga = PI * (3.0 - 5f64.sqrt());
    let mut e = 0.0;
    for i in 0..n {
        let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
        let r = (1.0 - z * z).sqrt();
        let (x, y) = (r * (ga * i as f64).cos(), r * (ga * i as f64).sin());
        e += x.abs().max(y.abs()).max(z.abs());
    }
    let want = h as f64 / (e / n as f64);
    assert!(
        (v.harmonic_mean_distance as f64 - want).abs() < 0.005 * want,
        "{} vs {want}",
        v.harmonic_mean_distance
    );
    assert!(v.valid && v.backface_fraction == 0.0);
    assert!((v.nearest_distance - h).abs() < 0.01 * h);
}

fn small_room() -> Scene {
    scene_of(
        vec![
            box_tris(
                Vec3::new(-2.0, 0.0, -2.0),
                Vec3::new(2.0, 2.5, 2.0),
                true,
                0,
            ),
            box_tris(Vec3::new(0.5, 0.0, 0.5), Vec3::new(1.0, 1.0, 1.0), false, 1),
        ],
        vec![material(0.7, 0.0), material(0.4, 0.0)],
        vec![light(
            LightKind::Sphere,
            Vec3::new(-0.5, 2.0, 0.0),
            Vec3::NEG_Y,
            15.0,
            0.15,
        )],
        Vec3::ZERO,
    )
}

fn probe_points() -> Vec<Vec3> {
    (0..7)
        .map(|i| {
            Vec3::new(
                -1.5 + 0.5 * i as f32,
                0.3 + 0.25 * i as f32,
                0.2 * i as f32 - 0.7,
            )
        })
        .collect()
}

fn bits(o: &BakeOutput) -> Vec<u32> {
    o.sh.iter()
        .flat_map(|s| s.coeffs().iter().flat_map(|c| c.to_array()))
        .map(f32::to_bits)
        .collect()
}

#[test]
fn same_bits_for_one_and_two_threads() {
    let scene = small_room();
    let pts = probe_points();
    let s = CaptureSettings {
        split_direct: true,
        groups: true,
        ..quick(300, 3, 3, 42)
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| bake_points(&scene, &pts, &s, &|_, _| {}).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(a, b);
    // direct + indirect = total
    for i in 0..pts.len() {
        let (d, ind) = (
            &a.direct.as_ref().unwrap()[i],
            &a.indirect.as_ref().unwrap()[i],
        );
        for k in 0..9 {
            let sum = d.coeffs()[k] + ind.coeffs()[k];
            assert!((sum - a.sh[i].coeffs()[k]).abs().max_element() < 1e-4);
        }
    }
}

#[test]
fn three_shards_reproduce_the_unsharded_bake() {
    let scene = small_room();
    let pts = probe_points();
    // Light groups and the direct/indirect split travel with the shards too.
    let s = CaptureSettings {
        groups: true,
        split_direct: true,
        ..quick(200, 2, 3, 9)
    };
    let whole = bake_points(&scene, &pts, &s, &|_, _| {}).unwrap();
    let mut merged = bake_shard(&scene, &pts, 0, 3, &s, &|_, _| {}).unwrap();
    for k in 1..3 {
        merged
            .append(bake_shard(&scene, &pts, k, 3, &s, &|_, _| {}).unwrap())
            .unwrap();
    }
    assert_eq!(bits(&whole), bits(&merged));
    assert_eq!(whole, merged);
    assert_eq!(merged.groups_indirect[0].1.len(), pts.len());
    // a gap is refused
    let mut a = bake_shard(&scene, &pts, 0, 3, &s, &|_, _| {}).unwrap();
    let c = bake_shard(&scene, &pts, 2, 3, &s, &|_, _| {}).unwrap();
    assert!(a.append(c).is_err());
}

#[test]
fn shard_ranges_partition_in_order() {
    for total in [0usize, 1, 2, 7, 100, 101] {
        for shards in 1..=9 {
            let mut next = 0;
            for k in 0..shards {
                let r = shard_range(total, k, shards).unwrap();
                assert_eq!(r.start, next);
                let len = r.len();
                assert!(len == total / shards || len == total / shards + 1);
                next = r.end;
            }
            assert_eq!(next, total);
        }
    }
    assert!(shard_range(10, 3, 3).is_err());
    assert!(shard_range(10, 0, 0).is_err());
}

#[test]
fn bad_settings_and_points_are_typed_errors() {
    let scene = small_room();
    let baker = Baker::new(&scene).unwrap();
    let s = CaptureSettings {
        order: 9,
        ..CaptureSettings::default()
    };
    assert!(matches!(
        baker.capture(Vec3::ZERO, 0, &s),
        Err(BakeError::BadSettings(_))
    ));
    let s = quick(0, 1, 3, 1);
    assert!(matches!(
        baker.capture(Vec3::ZERO, 0, &s),
        Err(BakeError::BadSettings(_))
    ));
    let s = quick(16, 1, 3, 1);
    assert!(matches!(
        baker.capture(Vec3::new(f32::NAN, 0.0, 0.0), 0, &s),
        Err(BakeError::NonFinitePosition { .. })
    ));
}

#[test]
fn demo_closet_gets_only_indirect_light() {
    let scene = Scene::builtin_demo();
    let baker = Baker::new(&scene).unwrap();
    let s = CaptureSettings {
        split_direct: true,
        ..quick(512, 3, 3, 5)
    };
    let c = baker.capture(Vec3::new(0.6, 1.5, 0.5), 0, &s).unwrap();
    assert!(
        c.validity.valid && !c.validity.offset_applied,
        "{:?}",
        c.validity
    );
    let direct = c.direct.as_ref().unwrap();
    let indirect = c.indirect.as_ref().unwrap();
    // no straight line reaches the closet from the lamp, the sun or the sky
    assert!(
        direct.coeffs().iter().all(|v| *v == Vec3::ZERO),
        "direct {:?}",
        direct.coeffs()[0]
    );
    assert!(
        indirect.coeffs()[0].min_element() > 0.0,
        "indirect {:?}",
        indirect.coeffs()[0]
    );
    // while room A's middle does see the lamp directly
    let a = baker.capture(Vec3::new(2.6, 1.2, 2.0), 1, &s).unwrap();
    assert!(a.direct.unwrap().coeffs()[0].x > 0.0);
}

#[test]
fn environment_rotation_turns_the_sky_counter_clockwise_seen_from_above() {
    use crate::env::EnvMap;
    let (w, h) = (64usize, 32usize);
    let (bx, by) = (40usize, 12usize);
    let mut texels = vec![Vec3::splat(0.01); w * h];
    texels[by * w + bx] = Vec3::splat(5000.0);
    let map = EnvMap::from_texels(Path::new("spot"), w, h, texels).unwrap();
    let d0 = map.texel_direction(bx, by);
    let scene = scene_of(vec![], vec![], vec![], Vec3::ZERO);
    let mut baker = Baker::new(&scene).unwrap();
    for deg in [0.0f32, 90.0, 200.0] {
        baker.set_environment_map(&map, 1.0, deg);
        let c = baker
            .capture(Vec3::ZERO, 0, &quick(512, 0, 2, 1))
            .unwrap()
            .sh;
        let k = c.coeffs();
        // Sloan's basis: Y1,-1 ∝ −y, Y1,0 ∝ z, Y1,1 ∝ −x
        let lobe = Vec3::new(-k[3].x, -k[1].x, k[2].x).normalize();
        // positive angle = right-handed about +Y = counter-clockwise from above
        let (s, co) = deg.to_radians().sin_cos();
        let want = Vec3::new(co * d0.x + s * d0.z, d0.y, -s * d0.x + co * d0.z);
        assert!(lobe.dot(want) > 0.99, "{deg}°: lobe {lobe} vs {want}");
    }
}

#[test]
fn disk_light_capture_matches_quadrature_of_probekit_sh_lights() {
    // an oblique one-sided disk: the capture (area sampling + MIS) against
    // the fixed solid-angle quadrature of probekit_sh::lights::disk_light_sh
    let (c, n, r, i) = (
        Vec3::new(0.4, 1.2, -0.3),
        Vec3::new(-0.3, -1.0, 0.4).normalize(),
        0.5f32,
        12.0f32,
    );
    let scene = scene_of(
        vec![],
        vec![],
        vec![light(LightKind::Disk, c, n, i, r)],
        Vec3::ZERO,
    );
    let baker = Baker::new(&scene).unwrap();
    let order = 3;
    let runs: Vec<Vec<f64>> = (0..8)
        .map(|seed| {
            red(&baker
                .capture(Vec3::ZERO, 0, &quick(512, 0, order, seed))
                .unwrap()
                .sh)
        })
        .collect();
    let (m, se) = mean_se(&runs);
    let mut want = vec![Vec3::ZERO; order * order];
    probekit_sh::lights::disk::disk_light_sh(order, Vec3::ZERO, c, n, r, Vec3::splat(i), &mut want);
    let want: Vec<f64> = want.iter().map(|v| v.x as f64).collect();
    assert!(want[0] > 0.0);
    assert_close(&m, &se, &want, 2e-3 * want[0], "disk light SH");
    // behind the disk: nothing
    let back = baker
        .capture(c + n * -1.0, 1, &quick(256, 0, order, 1))
        .unwrap()
        .sh;
    assert!(back.coeffs().iter().all(|v| *v == Vec3::ZERO));
}

/// A closed room lit by two lights in two groups: a sphere light `"a"` and a
/// coloured point light `"b"` whose colour is multiplied by `b_scale` (0
/// removes it). Delta lights draw no random numbers, so with the same seed
/// every path is the same whatever `b_scale` is.
pub(crate) fn two_group_room(b_scale: Vec3) -> Scene {
    let mut a = light(
        LightKind::Sphere,
        Vec3::new(-0.8, 2.0, 0.3),
        Vec3::NEG_Y,
        12.0,
        0.15,
    );
    a.group = Some("a".into());
    let mut b = light(
        LightKind::Point,
        Vec3::new(1.2, 1.8, -1.0),
        Vec3::NEG_Y,
        8.0,
        0.0,
    );
    b.color = Vec3::new(1.0, 0.5, 0.25) * b_scale;
    b.group = Some("b".into());
    let lights = if b_scale == Vec3::ZERO {
        vec![a]
    } else {
        vec![a, b]
    };
    scene_of(
        vec![
            box_tris(
                Vec3::new(-2.0, 0.0, -2.0),
                Vec3::new(2.0, 2.5, 2.0),
                true,
                0,
            ),
            box_tris(Vec3::new(0.5, 0.0, 0.5), Vec3::new(1.0, 1.0, 1.0), false, 1),
        ],
        vec![material(0.7, 0.0), material(0.4, 0.0)],
        lights,
        Vec3::ZERO,
    )
}

/// `exclude_direct` leaves one group's direct light out of `sh` and nothing
/// else: the excluded capture is the full one less that group's direct SH
/// (same random numbers, so to rounding); what it leaves out matches the
/// sphere light's closed-form SH (`lights::Light::add_sh`, an
/// independent computation) at a probe that sees the whole light; with no
/// bounces and every group excluded nothing is left; an unknown group is an
/// error, not a silent no-op.
#[test]
fn exclude_direct_leaves_out_one_groups_direct_light() {
    let scene = two_group_room(Vec3::ONE);
    let baker = Baker::new(&scene).unwrap();
    let (probes, _) = group_probe_points();
    let full_s = CaptureSettings {
        samples: 4096,
        split_direct: true,
        groups: true,
        ..CaptureSettings::default()
    };
    let ex_s = CaptureSettings {
        exclude_direct: vec!["a".into()],
        ..full_s.clone()
    };
    let full = baker.capture_many(&probes, 0, &full_s, &|_, _| {}).unwrap();
    let ex = baker.capture_many(&probes, 0, &ex_s, &|_, _| {}).unwrap();
    let group = |v: &[(String, ShRgb)]| -> Vec<Vec3> {
        v.iter()
            .find(|(n, _)| n == "a")
            .unwrap()
            .1
            .coeffs()
            .to_vec()
    };
    for (f, e) in full.iter().zip(&ex) {
        let (ga, gi) = (group(&f.groups), group(&f.groups_indirect));
        for k in 0..f.sh.coeffs().len() {
            let want = f.sh.coeffs()[k] - (ga[k] - gi[k]);
            let got = e.sh.coeffs()[k];
            assert!(
                (got - want).abs().max_element() <= 1e-4 * (1.0 + want.abs().max_element()),
                "coefficient {k}: {got} vs {want}"
            );
        }
        // The rest of the result still reports all light.
        assert_eq!(f.direct, e.direct);
        assert_eq!(f.groups, e.groups);
    }
    // Probe 3 at (0.1, 1.9, -0.2) sees the whole sphere light "a": the
    // light left out is its unshadowed SH.
    let a = &scene.lights[0];
    let rl = crate::lights::from_scene_light(a).unwrap();
    let mut analytic = vec![Vec3::ZERO; 9];
    rl.add_sh(3, full[3].position, 1.0, &mut analytic);
    let left_out = full[3].sh.coeffs()[0] - ex[3].sh.coeffs()[0];
    assert!(
        (left_out.x / analytic[0].x - 1.0).abs() < 0.05,
        "{left_out} vs {}",
        analytic[0]
    );
    // No bounces, both groups left out: no light at all.
    let none = CaptureSettings {
        bounces: 0,
        exclude_direct: vec!["a".into(), "b".into()],
        ..CaptureSettings::default()
    };
    let r = baker.capture_many(&probes, 0, &none, &|_, _| {}).unwrap();
    assert!(r
        .iter()
        .all(|c| c.sh.coeffs().iter().all(|v| *v == Vec3::ZERO)));
    let bad = CaptureSettings {
        exclude_direct: vec!["lamp".into()],
        ..CaptureSettings::default()
    };
    match baker.capture_many(&probes, 0, &bad, &|_, _| {}) {
        Err(BakeError::BadSettings(m)) => assert!(m.contains("lamp"), "{m}"),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        baker.capture(probes[0], 0, &bad),
        Err(BakeError::BadSettings(_))
    ));
}

/// Five probes spanning a volume (two tetrahedra) and query points inside it.
pub(crate) fn group_probe_points() -> (Vec<Vec3>, Vec<(Vec3, Vec3)>) {
    let probes = vec![
        Vec3::new(-1.0, 0.5, -1.0),
        Vec3::new(1.2, 0.6, -0.8),
        Vec3::new(-0.6, 0.7, 1.2),
        Vec3::new(0.1, 1.9, -0.2),
        Vec3::new(0.2, 0.4, 0.1),
    ];
    let queries = vec![
        (Vec3::new(-0.2, 0.8, -0.3), Vec3::Y),
        (Vec3::new(0.0, 1.0, 0.0), Vec3::X),
        (
            Vec3::new(-0.3, 0.7, 0.2),
            Vec3::new(0.3, -0.5, 0.8).normalize(),
        ),
    ];
    (probes, queries)
}
