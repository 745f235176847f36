//! Tests of [`super`]: visible fractions against closed forms (solid angles
//! and areas of half-planes, squares and circular segments) and the
//! shadowed irradiance on a surface against brute-force quadratures over
//! the light that trace their own rays.

use super::*;
use crate::capture::tests::{scene_of, tri};
use crate::scene::{AlphaMode, LightMode, Material, Scene, Triangle};
use std::f64::consts::PI;

/// The parallelogram `corner + s·u + t·v`, `s, t ∈ [0, 1]`, material 0.
fn quad(corner: Vec3, u: Vec3, v: Vec3) -> Vec<Triangle> {
    let (a, b, c, d) = (corner, corner + u, corner + u + v, corner + v);
    vec![tri(a, b, c, 0), tri(a, c, d, 0)]
}

/// The half-plane `z = z0, x ≥ x0` (100 m on a side is "infinite" here).
fn half_plane(z0: f32, x0: f32) -> Vec<Triangle> {
    quad(
        Vec3::new(x0, -100.0, z0),
        Vec3::new(100.0, 0.0, 0.0),
        Vec3::new(0.0, 200.0, 0.0),
    )
}

fn opaque() -> Material {
    Material {
        name: "opaque".into(),
        base_color: Vec3::splat(0.5),
        ..Material::default()
    }
}

/// A scene of `objects` (all of material `mat`) and `lights`, black sky
/// (the capture tests' scene builder).
fn scene_with(objects: Vec<Vec<Triangle>>, mat: Material, lights: Vec<Light>) -> Scene {
    scene_of(objects, vec![mat], lights, Vec3::ZERO)
}

fn light(kind: LightKind, position: Vec3, direction: Vec3, radius: f32) -> Light {
    Light {
        kind,
        position,
        direction,
        color: Vec3::ONE,
        intensity: 10.0,
        radius,
        inner_angle: 0.3,
        outer_angle: 0.6,
        group: None,
        mode: LightMode::Auto,
        angular_diameter: 0.0,
    }
}

fn sun(direction: Vec3, angular_diameter_deg: f32) -> Light {
    Light {
        angular_diameter: angular_diameter_deg.to_radians(),
        ..light(LightKind::Directional, Vec3::ZERO, direction, 0.0)
    }
}

fn assert_near(got: f32, want: f64, tol: f64, what: &str) {
    assert!(
        (got as f64 - want).abs() <= tol,
        "{what}: {got} vs {want} (tolerance {tol})"
    );
}

/// Nothing in the way: every kind of light is wholly visible, with or
/// without a receiver facing it.
#[test]
fn occlusion_open_space_sees_every_kind_whole() {
    let x = Vec3::new(0.3, 0.2, -0.1);
    let lights = [
        light(LightKind::Point, Vec3::new(0.0, 2.0, 0.0), Vec3::NEG_Y, 0.0),
        light(LightKind::Spot, Vec3::new(1.0, 2.0, 0.0), Vec3::NEG_Y, 0.0),
        sun(Vec3::NEG_Y, 0.0),
        sun(Vec3::new(0.2, -1.0, 0.1).normalize(), 10.0),
        light(
            LightKind::Sphere,
            Vec3::new(0.0, 3.0, 1.0),
            Vec3::NEG_Y,
            0.5,
        ),
        light(LightKind::Disk, Vec3::new(0.0, 3.0, 0.0), Vec3::NEG_Y, 0.5),
    ];
    for l in &lights {
        let scene = scene_with(vec![], opaque(), vec![l.clone()]);
        let tracer = Tracer::new(&scene);
        for normal in [None, Some(Vec3::Y)] {
            let f = visible_fraction(&tracer, x, l, normal, 64, 7);
            assert_eq!(f, 1.0, "{:?} with normal {normal:?}", l.kind);
        }
        let all = visible_fractions(
            &tracer,
            &[x, Vec3::new(-2.0, 0.0, 1.0)],
            std::slice::from_ref(l),
            64,
            3,
        );
        assert_eq!(all, vec![1.0, 1.0], "{:?}", l.kind);
    }
    // Inside a sphere light: all of it.
    let s = light(LightKind::Sphere, Vec3::ZERO, Vec3::NEG_Y, 1.0);
    let scene = scene_with(vec![], opaque(), vec![s.clone()]);
    let tracer = Tracer::new(&scene);
    assert_eq!(
        visible_fraction(&tracer, Vec3::new(0.2, 0.1, 0.0), &s, None, 16, 1),
        1.0
    );
}

/// A point or spot light behind a big opaque wall is invisible; one on the
/// near side is not; a glass pane of opacity α passes `1 − α`.
#[test]
fn occlusion_wall_blocks_point_lights_and_glass_passes_one_minus_alpha() {
    let wall = quad(
        Vec3::new(-50.0, -50.0, 0.0),
        Vec3::new(100.0, 0.0, 0.0),
        Vec3::new(0.0, 100.0, 0.0),
    );
    let x = Vec3::new(0.1, 0.2, -1.0);
    let behind = light(
        LightKind::Point,
        Vec3::new(0.3, -0.1, 1.0),
        Vec3::NEG_Y,
        0.0,
    );
    let spot = light(LightKind::Spot, Vec3::new(-0.4, 0.1, 2.0), Vec3::NEG_Z, 0.0);
    let near = light(
        LightKind::Point,
        Vec3::new(0.3, -0.1, -2.0),
        Vec3::NEG_Y,
        0.0,
    );
    let scene = scene_with(vec![wall.clone()], opaque(), vec![]);
    let tracer = Tracer::new(&scene);
    assert_eq!(visible_fraction(&tracer, x, &behind, None, 1, 0), 0.0);
    assert_eq!(visible_fraction(&tracer, x, &spot, None, 1, 0), 0.0);
    assert_eq!(visible_fraction(&tracer, x, &near, None, 1, 0), 1.0);
    let alpha = 0.3f32;
    let glass = Material {
        alpha,
        alpha_mode: AlphaMode::Blend,
        base_color: Vec3::ZERO,
        ..Material::default()
    };
    let scene = scene_with(vec![wall], glass, vec![]);
    let tracer = Tracer::new(&scene);
    assert_near(
        visible_fraction(&tracer, x, &behind, None, 1, 0),
        1.0 - alpha as f64,
        1e-6,
        "through glass",
    );
}

/// A sphere light (centre on +Z at 5 m, radius 1) seen from the origin
/// behind the half-plane `z = 2.5, x ≥ 0`: the plane's edge crosses the
/// line of sight to the centre, so it hides exactly half the cone the
/// sphere subtends (256 rays). A centred square of half-width `h` inside
/// the cone hides `Ω_square / Ω_cone` with `Ω_square = 4 atan(h² / (d
/// √(2h² + d²)))` (1024 rays: its curved edge in the sampled (cos θ, φ)
/// square stratifies less well than the half-plane's straight one).
#[test]
fn occlusion_sphere_light_half_plane_and_square_match_solid_angles() {
    let s = light(
        LightKind::Sphere,
        Vec3::new(0.0, 0.0, 5.0),
        Vec3::NEG_Y,
        1.0,
    );
    let scene = scene_with(vec![half_plane(2.5, 0.0)], opaque(), vec![s.clone()]);
    let tracer = Tracer::new(&scene);
    for key in [1, 2, 3] {
        let f = visible_fraction(&tracer, Vec3::ZERO, &s, None, 256, key);
        assert_near(f, 0.5, 0.02, "half-plane");
    }
    let (h, d) = (0.3f64, 2.5f64);
    let hf = h as f32;
    let square = quad(
        Vec3::new(-hf, -hf, d as f32),
        Vec3::new(2.0 * hf, 0.0, 0.0),
        Vec3::new(0.0, 2.0 * hf, 0.0),
    );
    let scene = scene_with(vec![square], opaque(), vec![s.clone()]);
    let tracer = Tracer::new(&scene);
    let omega_square = 4.0 * (h * h / (d * (2.0 * h * h + d * d).sqrt())).atan();
    let omega_cone = 2.0 * PI * (1.0 - (1.0 - 1.0 / 25.0f64).sqrt());
    let want = 1.0 - omega_square / omega_cone;
    let f = visible_fraction(&tracer, Vec3::ZERO, &s, None, 1024, 9);
    assert_near(f, want, 0.02, "square");
}

/// A disk light (centre on +Z at 5 m, radius 1, facing the origin): the
/// half-plane `z = 4, x ≥ 0` hides half its area; `x ≥ 0.32` hides the
/// circular segment `q.x ≥ 0.4` (central projection onto a parallel
/// plane scales by 4/5), of area `acos(0.4) − 0.4 √0.84` of π. Behind
/// the disk or in its plane nothing arrives.
#[test]
fn occlusion_disk_light_half_and_segment_match_areas() {
    let d = light(LightKind::Disk, Vec3::new(0.0, 0.0, 5.0), Vec3::NEG_Z, 1.0);
    let scene = scene_with(vec![half_plane(4.0, 0.0)], opaque(), vec![d.clone()]);
    let tracer = Tracer::new(&scene);
    let f = visible_fraction(&tracer, Vec3::ZERO, &d, None, 256, 4);
    assert_near(f, 0.5, 0.02, "half disk");
    assert_eq!(
        visible_fraction(&tracer, Vec3::new(0.0, 0.0, 6.0), &d, None, 64, 4),
        0.0
    );
    assert_eq!(
        visible_fraction(&tracer, Vec3::new(2.0, 0.0, 5.0), &d, None, 64, 4),
        0.0
    );
    let scene = scene_with(vec![half_plane(4.0, 0.32)], opaque(), vec![d.clone()]);
    let tracer = Tracer::new(&scene);
    let segment = (0.4f64.acos() - 0.4 * 0.84f64.sqrt()) / PI;
    let f = visible_fraction(&tracer, Vec3::ZERO, &d, None, 1024, 5);
    assert_near(f, 1.0 - segment, 0.02, "segment");
}

/// A sun of angular diameter 10° straight above (+Z) behind the
/// half-plane `z = 1, x ≥ 0`: half its disc is hidden from a point under
/// the edge; from 0.5 m either side, all or none (the cone is 0.09 m wide
/// at the plane). A sharp sun gives exactly 0 or 1.
#[test]
fn occlusion_directional_cone_half_hidden_and_sharp_sun_is_zero_or_one() {
    let soft = sun(Vec3::NEG_Z, 10.0);
    let sharp = sun(Vec3::NEG_Z, 0.0);
    let scene = scene_with(vec![half_plane(1.0, 0.0)], opaque(), vec![]);
    let tracer = Tracer::new(&scene);
    for key in [1, 2] {
        let f = visible_fraction(&tracer, Vec3::ZERO, &soft, None, 256, key);
        assert_near(f, 0.5, 0.02, "half sun");
    }
    let (open, shut) = (Vec3::new(-0.5, 0.0, 0.0), Vec3::new(0.5, 0.0, 0.0));
    assert_eq!(visible_fraction(&tracer, open, &soft, None, 64, 1), 1.0);
    assert_eq!(visible_fraction(&tracer, shut, &soft, None, 64, 1), 0.0);
    assert_eq!(visible_fraction(&tracer, open, &sharp, None, 64, 1), 1.0);
    assert_eq!(visible_fraction(&tracer, shut, &sharp, None, 64, 1), 0.0);
}

/// The capture's shadow rays stop at other sphere and disk lights: a lamp
/// between a point and a light hides the light, never itself.
#[test]
fn occlusion_other_area_lights_block_like_the_capture() {
    let lamp = light(
        LightKind::Sphere,
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::NEG_Y,
        0.5,
    );
    let point = light(LightKind::Point, Vec3::new(0.0, 4.0, 0.0), Vec3::NEG_Y, 0.0);
    let panel = light(LightKind::Disk, Vec3::new(3.0, 2.0, 0.0), Vec3::NEG_Y, 0.5);
    let high_sun = sun(Vec3::new(-3.0, -2.0, 0.0).normalize(), 0.0);
    let scene = scene_with(
        vec![],
        opaque(),
        vec![lamp.clone(), point.clone(), panel.clone(), high_sun.clone()],
    );
    let tracer = Tracer::new(&scene);
    assert_eq!(
        visible_fraction(&tracer, Vec3::ZERO, &point, None, 1, 0),
        0.0
    );
    assert_eq!(
        visible_fraction(&tracer, Vec3::ZERO, &lamp, None, 64, 0),
        1.0
    );
    assert_eq!(
        visible_fraction(&tracer, Vec3::ZERO, &panel, None, 64, 0),
        1.0
    );
    // the sun is straight behind the disk panel
    assert_eq!(
        visible_fraction(&tracer, Vec3::ZERO, &high_sun, None, 1, 0),
        0.0
    );
}

/// Brute-force shadowed irradiance of a sphere light (radiance `l_e`) at
/// `x` with normal `n`: midpoint rule over the cap in (cos θ, φ) about the
/// axis to the centre (equal solid angle per cell), each cell's direction
/// traced to the sphere (own ray/sphere intersection) with the tracer's
/// segment transmittance.
fn sphere_quadrature(tracer: &Tracer, x: Vec3, n: Vec3, c: Vec3, r: f64, l_e: f64) -> (f64, f64) {
    let (ax, dist) = ((c - x).normalize().as_dvec3(), (c - x).length() as f64);
    let (t1, t2) = ax.any_orthonormal_pair();
    let cos_max = (1.0 - (r / dist).powi(2)).sqrt();
    let m = 160;
    let d_omega = 2.0 * PI * (1.0 - cos_max) / (m * 4 * m) as f64;
    let (mut shadowed, mut open) = (0.0, 0.0);
    for i in 0..m {
        let ct = cos_max + (1.0 - cos_max) * (i as f64 + 0.5) / m as f64;
        let st = (1.0 - ct * ct).sqrt();
        for j in 0..4 * m {
            let ph = 2.0 * PI * (j as f64 + 0.5) / (4 * m) as f64;
            let w = ax * ct + (t1 * ph.cos() + t2 * ph.sin()) * st;
            let cos = n.as_dvec3().dot(w);
            if cos <= 0.0 {
                continue;
            }
            // nearest root of |x + t w − c| = r
            let b = w.dot(ax * dist);
            let t = b - (b * b - dist * dist + r * r).max(0.0).sqrt();
            let target = x + (w * t).as_vec3();
            let v = tracer.transmittance(x, target).x as f64;
            shadowed += l_e * cos * v * d_omega;
            open += l_e * cos * d_omega;
        }
    }
    (shadowed, open)
}

/// Brute-force shadowed irradiance of a one-sided disk light facing `x`:
/// midpoint rule over equal-area polar cells of the disk, each point traced
/// with the tracer's segment transmittance, `L cos θ cos θ_l / d² dA`.
#[allow(clippy::too_many_arguments)]
fn disk_quadrature(
    tracer: &Tracer,
    x: Vec3,
    n: Vec3,
    c: Vec3,
    axis: Vec3,
    r: f64,
    l_e: f64,
) -> (f64, f64) {
    let (t1, t2) = axis.any_orthonormal_pair();
    let m = 160;
    let d_a = PI * r * r / (m * 4 * m) as f64;
    let (mut shadowed, mut open) = (0.0, 0.0);
    for i in 0..m {
        let rho = r * ((i as f64 + 0.5) / m as f64).sqrt();
        for j in 0..4 * m {
            let ph = 2.0 * PI * (j as f64 + 0.5) / (4 * m) as f64;
            let q = c + (t1 * ph.cos() as f32 + t2 * ph.sin() as f32) * rho as f32;
            let v = (q - x).as_dvec3();
            let d2 = v.length_squared();
            let w = v / d2.sqrt();
            let (cos, cos_l) = (n.as_dvec3().dot(w), -axis.as_dvec3().dot(w));
            if cos <= 0.0 || cos_l <= 0.0 {
                continue;
            }
            let g = l_e * cos * cos_l / d2 * d_a;
            shadowed += g * tracer.transmittance(x, q).x as f64;
            open += g;
        }
    }
    (shadowed, open)
}

/// On a tilted receiver whose horizon cuts the light, partly shadowed by a
/// half-plane off the line of sight: exact unoccluded irradiance × the
/// cosine-weighted visible fraction against the brute-force shadowed
/// irradiance (sphere and disk lights). The free-space fraction differs,
/// so the weighting is what is checked.
#[test]
fn occlusion_weighted_fraction_times_exact_irradiance_matches_quadrature() {
    let n = Vec3::new(1.0, 0.0, 0.3).normalize();
    let c = Vec3::new(0.0, 0.0, 3.0);
    let sphere = light(LightKind::Sphere, c, Vec3::NEG_Y, 1.5);
    let disk = light(LightKind::Disk, c, Vec3::NEG_Z, 1.5);
    for l in [&sphere, &disk] {
        let scene = scene_with(vec![half_plane(1.5, 0.2)], opaque(), vec![l.clone()]);
        let tracer = Tracer::new(&scene);
        let l_e = l.radiance().x as f64;
        let (want, open) = match l.kind {
            LightKind::Sphere => sphere_quadrature(&tracer, Vec3::ZERO, n, c, 1.5, l_e),
            _ => disk_quadrature(&tracer, Vec3::ZERO, n, c, Vec3::NEG_Z, 1.5, l_e),
        };
        let exact = crate::lights::from_scene_light(l)
            .unwrap()
            .irradiance(Vec3::ZERO, n, None)
            .x as f64;
        // the quadrature itself, against the closed form
        assert!(
            (open - exact).abs() < 0.01 * exact,
            "{:?}: {open} vs {exact}",
            l.kind
        );
        let weighted = visible_fraction(&tracer, Vec3::ZERO, l, Some(n), 1024, 11);
        let got = exact * weighted as f64;
        assert!(
            (got - want).abs() < 0.02 * want,
            "{:?}: {got} vs {want} (fraction {weighted})",
            l.kind
        );
        let free = visible_fraction(&tracer, Vec3::ZERO, l, None, 1024, 11);
        assert!(
            (free - weighted).abs() > 0.05,
            "{:?}: {free} vs {weighted}",
            l.kind
        );
    }
}

/// Receivers turned away: nothing of the light reaches them, so 0.
#[test]
fn occlusion_light_below_the_horizon_gives_zero() {
    let c = Vec3::new(0.0, 0.0, 3.0);
    let lights = [
        light(LightKind::Point, c, Vec3::NEG_Y, 0.0),
        light(LightKind::Sphere, c, Vec3::NEG_Y, 1.0),
        light(LightKind::Disk, c, Vec3::NEG_Z, 1.0),
        sun(Vec3::NEG_Z, 10.0),
    ];
    let scene = scene_with(vec![], opaque(), vec![]);
    let tracer = Tracer::new(&scene);
    for l in &lights {
        assert_eq!(
            visible_fraction(&tracer, Vec3::ZERO, l, Some(Vec3::NEG_Z), 64, 1),
            0.0,
            "{:?}",
            l.kind
        );
    }
}

/// `visible_fractions` is row-major, keyed per (seed, point, light), and
/// bit-identical on 1 and 4 threads.
#[test]
fn occlusion_visible_fractions_same_bits_for_any_thread_count() {
    let lights = vec![
        light(LightKind::Point, Vec3::new(0.5, 0.3, 3.0), Vec3::NEG_Y, 0.0),
        light(
            LightKind::Sphere,
            Vec3::new(0.0, 0.2, 5.0),
            Vec3::NEG_Y,
            1.0,
        ),
        light(LightKind::Disk, Vec3::new(-0.3, 0.0, 4.0), Vec3::NEG_Z, 0.8),
        sun(Vec3::new(0.05, 0.0, -1.0).normalize(), 10.0),
    ];
    let scene = scene_with(
        vec![half_plane(1.0, 0.0), half_plane(2.0, 0.7)],
        opaque(),
        lights.clone(),
    );
    let tracer = Tracer::new(&scene);
    let points: Vec<Vec3> = (0..13)
        .map(|i| Vec3::new(-0.6 + 0.1 * i as f32, 0.05 * (i % 3) as f32, 0.0))
        .collect();
    let run = |k: usize| -> Vec<u32> {
        rayon::ThreadPoolBuilder::new()
            .num_threads(k)
            .build()
            .unwrap()
            .install(|| visible_fractions(&tracer, &points, &lights, 128, 42))
            .into_iter()
            .map(f32::to_bits)
            .collect()
    };
    let one = run(1);
    assert_eq!(one, run(4));
    assert_eq!(one.len(), points.len() * lights.len());
    let vals: Vec<f32> = one.iter().map(|b| f32::from_bits(*b)).collect();
    assert!(vals.iter().any(|&v| v > 0.0 && v < 1.0), "{vals:?}");
    assert!(vals.iter().all(|&v| (0.0..=1.0).contains(&v)));
    for (i, p) in points.iter().enumerate() {
        for (l, li) in lights.iter().enumerate() {
            let key = crate::sampling::hash3(42, i as u64, l as u64);
            let f = visible_fraction(&tracer, *p, li, None, 128, key);
            assert_eq!(vals[i * lights.len() + l].to_bits(), f.to_bits());
        }
    }
}
