use super::objects::{eval_fit, fit_order, fit_sh};
use super::*;
use crate::capture::{bake_points, CaptureSettings};
use crate::format::cloud::{cloud_file, file_validity};
use crate::format::Codec;
use crate::format::Parts;
use crate::scene::{Aabb, Material, Triangle};
use crate::trace::Ray;
use glam::Vec2;
use probekit_sh::project::fibonacci_point;
use probekit_sh::ShRgb;

fn meta() -> String {
    String::new()
}

/// A cloud file of `positions`, every probe holding `sh`.
fn constant_cloud(positions: &[Vec3], sh: &ShRgb) -> ProbeFile {
    let v = crate::format::Validity {
        value: 0.0,
        flags: 0,
    };
    cloud_file(
        positions,
        &vec![sh.clone(); positions.len()],
        &vec![v; positions.len()],
        Codec::F32,
        &meta(),
    )
    .unwrap()
}

/// A uniform sky of radiance `l` and nothing else but one 1 cm triangle
/// 170 m away (a scene needs a triangle); bake box [-1, 1]³.
fn sky_scene(l: Vec3) -> Scene {
    let tri = Triangle {
        positions: [
            Vec3::new(100.0, -100.0, 100.0),
            Vec3::new(100.01, -100.0, 100.0),
            Vec3::new(100.0, -100.0, 100.01),
        ],
        normals: [Vec3::Y; 3],
        uvs: [Vec2::ZERO; 3],
        material: 0,
    };
    let mut s = Scene::from_triangles(
        "sky",
        vec![("speck".into(), vec![tri])],
        vec![Material::default()],
        vec![],
    )
    .unwrap();
    s.environment.color = l;
    s.bake.r#box = Some(Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0)));
    s
}

/// Uniform sky `L`: the path-traced irradiance of any receiver is `πL`
/// (∫ L max(0, n·ω) dω = πL, computed by hand), so the object's pixels in
/// the reference panel are `albedo·L`; probes holding the exact radiance SH
/// of the constant `L` (`c₀₀ = L·√(4π)`, the integral of `L·Y₀₀` over the
/// sphere) must give the same picture.
#[test]
fn uniform_sky_probes_panel_equals_reference_panel() {
    let l = Vec3::new(0.3, 0.5, 0.7);
    let scene = sky_scene(l);
    let mut sh = ShRgb::zeros(3);
    sh.coeffs_mut()[0] = l * (4.0 * std::f32::consts::PI).sqrt();
    let mut pos = Vec::new();
    for k in 0..8 {
        pos.push(Vec3::new(
            if k & 1 == 0 { -1.2 } else { 1.2 },
            if k & 2 == 0 { -1.2 } else { 1.2 },
            if k & 4 == 0 { -1.2 } else { 1.2 },
        ));
    }
    pos.push(Vec3::new(0.1, 0.05, -0.07));
    let file = constant_cloud(&pos, &sh);
    let settings = RenderSettings {
        width: 64,
        height: 48,
        camera: Some(Camera::new(Vec3::new(0.0, 0.3, 2.5), Vec3::ZERO, 40.0).unwrap()),
        samples: 256,
        object: ObjectKind::Spheres {
            grid: (3, 2),
            radius: 0.15,
            normals: 16,
        },
        ..RenderSettings::default()
    };
    let r = render(&scene, &file, &settings, &|_, _| {}).unwrap();
    assert!(r.object_pixels > 50, "{}", r.object_pixels);
    assert!(r.spheres.len() >= 4, "{:?}", r.spheres);
    let want = settings.albedo * l;
    for (i, e) in r.error.iter().enumerate() {
        if e.is_some() {
            let (p, t) = (r.probes_panel[i], r.reference_panel[i]);
            assert!((t - want).abs().max_element() < 0.01, "truth {t} vs {want}");
            assert!(
                (p - want).abs().max_element() < 1e-4,
                "probes {p} vs {want}"
            );
        } else {
            // Background: the sky in both panels.
            assert!((r.reference_panel[i] - l).abs().max_element() < 1e-6);
            assert_eq!(r.probes_panel[i], r.reference_panel[i]);
        }
    }
    assert!(r.rel_rmse < 0.01 && r.max_rel_error < 0.02, "{r:?}");
    assert!(r.exposure.is_finite() && r.exposure > 0.0);
}

/// About `n` cell-centred points of a uniform grid over `b`, x fastest:
/// cell edge `∛(V / n)`, each axis `round(extent / edge)` cells, at least 2
/// (the sizing rule of grid placement, which sits above the renderer).
fn grid(b: &Aabb, n: usize) -> Vec<Vec3> {
    let size = b.size();
    let cell = (size.x * size.y * size.z / n as f32).cbrt();
    let [nx, ny, nz] = size
        .to_array()
        .map(|s| ((s / cell).round() as usize).max(2));
    let mut out = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let f = Vec3::new(
                    (i as f32 + 0.5) / nx as f32,
                    (j as f32 + 0.5) / ny as f32,
                    (k as f32 + 0.5) / nz as f32,
                );
                out.push(b.min + f * size);
            }
        }
    }
    out
}

/// The demo scene with a tiny grid bake: the picture has object pixels,
/// finite numbers, the documented size, and the same bytes with one thread.
#[test]
fn small_demo_render_has_object_pixels_and_finite_numbers() {
    let scene = Scene::builtin_demo();
    let pts = grid(&scene.bake_box(), 24);
    let cs = CaptureSettings {
        samples: 64,
        bounces: 1,
        ..CaptureSettings::default()
    };
    let out = bake_points(&scene, &pts, &cs, &|_, _| {}).unwrap();
    let validity: Vec<_> = out.validity.iter().map(file_validity).collect();
    let file = cloud_file(
        &out.captured_positions,
        &out.sh,
        &validity,
        Codec::F32,
        &meta(),
    )
    .unwrap();
    let settings = RenderSettings {
        width: 64,
        height: 48,
        samples: 64,
        bounces: 1,
        show_probes: true,
        object: ObjectKind::Spheres {
            grid: (3, 2),
            radius: 0.15,
            normals: 16,
        },
        ..RenderSettings::default()
    };
    let r = render(&scene, &file, &settings, &|_, _| {}).unwrap();
    assert!(r.object_pixels > 0 && !r.spheres.is_empty());
    assert!(r.rel_rmse.is_finite() && r.max_rel_error.is_finite() && r.rel_rmse > 0.0);
    assert!(r.exposure.is_finite());
    assert!(r.probes_panel.iter().all(|c| c.is_finite()));
    assert_eq!(r.image.width(), 3 * 64 + 2 * GAP);
    assert_eq!(r.image.height(), 48 + label_strip(64) + 3 * 9 + 8);
    for s in &r.spheres {
        assert!(scene.bake_box().contains(s.center));
    }
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| render(&scene, &file, &settings, &|_, _| {}).unwrap());
    assert!(one.image == r.image, "image depends on the thread count");
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("r.png");
    r.save_png(&p).unwrap();
    let back = image::open(&p).unwrap().into_rgb8();
    assert!(back == r.image);
}

/// Bad input: zero size, a shard part (no tetrahedra), a bad camera.
#[test]
fn bad_input_is_a_typed_error() {
    let scene = sky_scene(Vec3::ONE);
    let sh = ShRgb::zeros(2);
    let pos: Vec<Vec3> = (0..5).map(|i| fibonacci_point(i, 5)).collect();
    let good = constant_cloud(&pos, &sh);
    let zero = RenderSettings {
        width: 0,
        ..RenderSettings::default()
    };
    assert!(matches!(
        render(&scene, &good, &zero, &|_, _| {}),
        Err(RenderError::BadSize { .. })
    ));
    let mut part = good.clone();
    part.cloud_mut().tetrahedra = None;
    let small = RenderSettings {
        width: 8,
        height: 8,
        ..RenderSettings::default()
    };
    assert!(matches!(
        render(&scene, &part, &small, &|_, _| {}),
        Err(RenderError::Probes(_))
    ));
    assert!(matches!(
        Camera::new(Vec3::ZERO, Vec3::ZERO, 60.0),
        Err(RenderError::BadCamera(_))
    ));
    assert!(Camera::new(Vec3::ZERO, Vec3::X, 0.0).is_err());
}

/// A camera inside the demo's floor slab, facing into it, has no room for
/// the test spheres: an error that says so, not a picture of the scene alone.
#[test]
fn camera_inside_geometry_is_no_place_for_the_objects() {
    let scene = Scene::builtin_demo();
    let pos: Vec<Vec3> = (0..5)
        .map(|i| 4.0 * fibonacci_point(i, 5) + Vec3::new(4.0, 1.5, 2.0))
        .collect();
    let mut sh = ShRgb::zeros(2);
    sh.coeffs_mut()[0] = Vec3::ONE;
    let file = constant_cloud(&pos, &sh);
    let settings = RenderSettings {
        width: 16,
        height: 12,
        samples: 16,
        camera: Some(
            Camera::new(Vec3::new(4.0, -0.1, 2.0), Vec3::new(4.0, -0.1, 3.0), 60.0).unwrap(),
        ),
        ..RenderSettings::default()
    };
    let e = render(&scene, &file, &settings, &|_, _| {}).err();
    assert!(matches!(e, Some(RenderError::NoView)), "{e:?}");
}

/// The SH fit reproduces a polynomial of degree 4 (which lies in bands
/// 0..=4) from 64 Fibonacci samples, checked at other directions against
/// the polynomial itself.
#[test]
fn sphere_fit_reproduces_degree_four_polynomials() {
    let f = |n: Vec3| {
        Vec3::new(
            1.0 + 0.5 * n.x + n.y * n.z,
            0.3 + n.x.powi(4) - 0.2 * n.y,
            2.0 - n.z * n.z * n.x,
        )
    };
    let k = 64;
    let order = fit_order(k);
    assert_eq!(order, 5);
    let dirs: Vec<Vec3> = (0..k).map(|i| fibonacci_point(i, k)).collect();
    let vals: Vec<Vec3> = dirs.iter().map(|d| f(*d)).collect();
    let c = fit_sh(&dirs, &vals, order);
    for i in 0..50 {
        let d = fibonacci_point(i, 50);
        let got = eval_fit(&c, order, d);
        assert!((got - f(d)).abs().max_element() < 1e-3, "{got} vs {}", f(d));
    }
}

/// Camera round trip: the ray through the projection of a point passes
/// through the point; ray-sphere hits lie on the sphere.
#[test]
fn camera_projection_and_sphere_hits() {
    let cam = Camera::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(-1.0, 0.5, 0.0), 50.0).unwrap();
    let (w, h) = (200, 100);
    for p in [
        Vec3::new(0.0, 1.0, 1.0),
        Vec3::new(-2.0, 0.0, -1.0),
        Vec3::new(0.5, 1.5, 0.0),
    ] {
        let (x, y) = cam.view_to_pixel(cam.to_view(p), w, h);
        let r = cam.ray(x, y, w, h);
        let want = (p - cam.eye).normalize();
        assert!(
            (r.direction - want).length() < 1e-4,
            "{} vs {want}",
            r.direction
        );
    }
    let s = Sphere {
        center: Vec3::new(0.0, 0.0, -5.0),
        radius: 1.0,
    };
    let t = s
        .intersect(&Ray::new(Vec3::new(0.3, 0.2, 0.0), -Vec3::Z))
        .unwrap();
    let p = Vec3::new(0.3, 0.2, -t);
    assert!(((p - s.center).length() - 1.0).abs() < 1e-5);
    assert!(s
        .intersect(&Ray::new(Vec3::new(1.01, 0.0, 0.0), -Vec3::Z))
        .is_none());
}
