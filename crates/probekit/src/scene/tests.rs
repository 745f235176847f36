use super::geometry::check_winding;
use super::*;
use glam::{Quat, Vec4};
use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};

use super::tests_support::shared_data;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    fs::write(&p, text).unwrap();
    p
}

/// Signed volume by the divergence theorem: Σ (p0 · (p1 × p2)) / 6 over outward triangles.
fn signed_volume(tris: &[Triangle]) -> f64 {
    tris.iter()
        .map(|t| {
            let [a, b, c] = t.positions.map(|p| p.as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

#[test]
fn fnv1a_matches_published_test_vectors() {
    // Test vectors from the FNV reference (draft-eastlake-fnv, FNV-1a 64-bit).
    let mut h = Fnv1a::new();
    assert_eq!(h.0, 0xcbf29ce484222325);
    h.bytes(b"a");
    assert_eq!(h.0, 0xaf63dc4c8601ec8c);
    let mut h = Fnv1a::new();
    h.bytes(b"foobar");
    assert_eq!(h.0, 0x85944171f73967e8);
}

#[test]
fn srgb_decode_matches_reference_values() {
    assert_eq!(srgb_to_linear(0.0), 0.0);
    assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
    // 128/255 decodes to 0.21586 (IEC 61966-2-1 tables).
    assert!((srgb_to_linear(128.0 / 255.0) - 0.215_86).abs() < 1e-4);
    assert!((srgb_to_linear(0.04045) - 0.04045 / 12.92).abs() < 1e-7);
}

#[test]
fn box_triangles_are_closed_and_face_outward() {
    let (lo, hi) = (Vec3::new(-1.0, 0.5, 2.0), Vec3::new(0.5, 2.0, 2.25));
    let tris = demo::box_triangles(lo, hi, 0);
    assert_eq!(tris.len(), 12);
    let vol = signed_volume(&tris);
    let expected = (hi - lo).as_dvec3();
    assert!(
        (vol - expected.x * expected.y * expected.z).abs() < 1e-9,
        "{vol}"
    );
    let c = 0.5 * (lo + hi);
    for t in &tris {
        let centroid = (t.positions[0] + t.positions[1] + t.positions[2]) / 3.0;
        assert!(t.geometric_normal().dot(centroid - c) > 0.0);
    }
    let (ok, bad) = check_winding(&tris);
    assert_eq!(bad, 0);
    assert!(ok.iter().all(|o| *o));
}

#[test]
fn demo_scene_is_closed_consistent_and_described() {
    let s = Scene::builtin_demo();
    assert_eq!(s.triangles.len(), demo::BOXES.len() * 12);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert!((0..s.triangles.len() as u32).all(|t| s.winding_consistent(t)));
    // Every object is a closed 2-manifold: each undirected edge used exactly twice, once each way.
    for o in &s.objects {
        let tris = &s.triangles[o.first as usize..(o.first + o.count) as usize];
        let mut directed: HashMap<(u64, u64), i32> = HashMap::new();
        let key = |p: Vec3| {
            ((p.x * 1000.0).round() as i64 * 1_000_003 + (p.y * 1000.0).round() as i64) * 1_000_003
                + (p.z * 1000.0).round() as i64
        };
        for t in tris {
            for e in 0..3 {
                let (a, b) = (
                    key(t.positions[e]) as u64,
                    key(t.positions[(e + 1) % 3]) as u64,
                );
                *directed.entry((a, b)).or_default() += 1;
            }
        }
        for (&(a, b), &n) in &directed {
            assert_eq!(n, 1, "{}: edge used twice the same way", o.name);
            assert_eq!(directed.get(&(b, a)), Some(&1), "{}: open edge", o.name);
        }
        assert!(signed_volume(tris) > 0.0, "{} faces inward", o.name);
    }
    assert_eq!(s.bounds.min, Vec3::splat(-0.2));
    assert_eq!(s.bounds.max, Vec3::new(8.2, 3.2, 4.2));
    let bb = s.bake_box();
    assert_eq!((bb.min, bb.max), (Vec3::ZERO, Vec3::new(8.0, 3.0, 4.0)));
    let names: Vec<&str> = s.regions.iter().map(|r| r.name.as_str()).collect();
    for n in ["room_a", "room_b", "closet", "wall"] {
        assert!(names.contains(&n), "{n}");
    }
    assert!(s.lights.iter().any(|l| l.kind == LightKind::Sphere));
    assert!(s.lights.iter().any(|l| l.kind == LightKind::Directional));
    assert!(s.environment.color.max_element() > 0.0);
    assert!(s.emissive_triangles.is_empty());
    // Red floor: the triangles facing +y at y = 0 use a red material.
    let floor_up = s
        .triangles
        .iter()
        .find(|t| t.positions.iter().all(|p| p.y == 0.0) && t.geometric_normal().y > 0.5)
        .unwrap();
    let red = s.materials[floor_up.material as usize].base_color;
    assert!(red.x > 3.0 * red.y && red.x > 3.0 * red.z);
    // Loading by name gives the same content.
    let by_name = Scene::load(BUILTIN_DEMO).unwrap();
    assert_eq!(by_name.lighting_hash(), s.lighting_hash());
}

#[test]
fn lighting_hash_is_stable_and_sensitive_to_light_only() {
    let a = Scene::builtin_demo();
    let b = Scene::builtin_demo();
    assert_eq!(a.lighting_hash(), b.lighting_hash());
    let mut c = b.clone();
    c.lights[0].intensity *= 1.0001;
    assert_ne!(a.lighting_hash(), c.lighting_hash());
    let mut moved = b.clone();
    moved.lights[0].position.x += 0.01;
    assert_ne!(a.lighting_hash(), moved.lighting_hash());
    let mut d = b.clone();
    d.triangles[7].positions[1].x += 1e-6;
    assert_ne!(a.lighting_hash(), d.lighting_hash());
    // How to bake and where to evaluate are not lighting.
    let mut e = b.clone();
    e.regions[0].name.push('x');
    e.regions.pop();
    e.bake.samples = Some(17);
    e.bake.seed = Some(99);
    e.bake.bounces = Some(1);
    e.bake.r#box = Some(Aabb::new(Vec3::ZERO, Vec3::ONE));
    assert_eq!(a.lighting_hash(), e.lighting_hash());
}

#[test]
fn lighting_hash_reads_the_environment_map_by_content_not_path() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    // Two byte-identical maps under different names, and a different one.
    let sky = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 1\n\x80\x80\x80\x81";
    fs::write(d.join("sky.hdr"), sky).unwrap();
    fs::write(d.join("copy.hdr"), sky).unwrap();
    let mut other = sky.to_vec();
    *other.last_mut().unwrap() = 0x82;
    fs::write(d.join("other.hdr"), other).unwrap();
    let scene = |map: &str, extra: &str| {
        let text = format!("[[mesh]]\npath = \"tri.obj\"\n[environment]\nmap = \"{map}\"\n{extra}");
        write(d, "s.toml", &text);
        Scene::load(d.join("s.toml")).unwrap()
    };
    let base = scene("sky.hdr", "");
    assert_eq!(base.lighting_hash(), scene("copy.hdr", "").lighting_hash());
    let abs = d.join("sky.hdr").canonicalize().unwrap();
    assert_eq!(
        base.lighting_hash(),
        scene(abs.to_str().unwrap(), "").lighting_hash()
    );
    assert_ne!(base.lighting_hash(), scene("other.hdr", "").lighting_hash());
    // `[bake]` and `[[region]]` do not change it.
    let with_bake = scene(
        "sky.hdr",
        "[bake]\nsamples = 64\nseed = 3\nbox = [[0,0,0],[1,1,1]]\n[[region]]\nname = \"a\"\nmin = [0,0,0]\nmax = [1,1,1]\n",
    );
    assert_eq!(base.lighting_hash(), with_bake.lighting_hash());
    // The same scene file loaded through a relative path from another folder.
    let sub = d.join("sub");
    fs::create_dir(&sub).unwrap();
    let rel = sub.join("..").join("s.toml");
    write(
        d,
        "s.toml",
        "[[mesh]]\npath = \"tri.obj\"\n[environment]\nmap = \"sky.hdr\"\n",
    );
    assert_eq!(
        base.lighting_hash(),
        Scene::load(rel).unwrap().lighting_hash()
    );
}

#[test]
fn texture_sampling_is_bilinear_with_repeat() {
    let t = Texture {
        width: 2,
        height: 1,
        texels: vec![Vec4::ZERO, Vec4::ONE],
    };
    // Texel centres at u = 0.25 and 0.75.
    assert_eq!(t.sample(Vec2::new(0.25, 0.5)), Vec4::ZERO);
    assert_eq!(t.sample(Vec2::new(0.75, 0.5)), Vec4::ONE);
    assert!(
        (t.sample(Vec2::new(0.5, 0.5)) - Vec4::splat(0.5))
            .abs()
            .max_element()
            < 1e-6
    );
    // u = 0 lies halfway between texel 1 (wrapped) and texel 0.
    assert!(
        (t.sample(Vec2::new(0.0, 0.5)) - Vec4::splat(0.5))
            .abs()
            .max_element()
            < 1e-6
    );
    assert_eq!(t.sample(Vec2::new(1.25, 7.5)), Vec4::ZERO);
}

#[test]
fn sphere_light_radiance_integrates_to_its_intensity() {
    // Radiant intensity towards +z of a uniform sphere = ∫ L cosθ dA over the visible hemisphere;
    // integrate numerically over the sphere surface (midpoint rule in θ, φ).
    let l = Light {
        kind: LightKind::Sphere,
        position: Vec3::ZERO,
        direction: Vec3::NEG_Y,
        color: Vec3::ONE,
        intensity: 7.0,
        radius: 0.3,
        inner_angle: 0.0,
        outer_angle: 0.0,
        group: None,
        mode: crate::scene::LightMode::Auto,
        angular_diameter: 0.0,
    };
    let lr = l.radiance().x as f64;
    let r = l.radius as f64;
    let (nt, np) = (400, 64);
    let mut sum = 0.0;
    for i in 0..nt {
        let th = (i as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
        let da = r
            * r
            * th.sin()
            * (std::f64::consts::FRAC_PI_2 / nt as f64)
            * (2.0 * std::f64::consts::PI / np as f64);
        sum += np as f64 * lr * th.cos() * da;
    }
    assert!((sum - 7.0).abs() < 1e-3, "{sum}");
}

#[test]
fn spot_falloff_follows_khr_ramp() {
    let mut l = Scene::builtin_demo().lights[0].clone();
    l.kind = LightKind::Spot;
    l.inner_angle = 10f32.to_radians();
    l.outer_angle = 30f32.to_radians();
    assert_eq!(l.spot_falloff(1.0), 1.0);
    assert_eq!(l.spot_falloff(40f32.to_radians().cos()), 0.0);
    let c = 20f32.to_radians().cos();
    let x = (c - 30f32.to_radians().cos()) / (10f32.to_radians().cos() - 30f32.to_radians().cos());
    assert!((l.spot_falloff(c) - x * x).abs() < 1e-6);
}

const CUBE_OBJ: &str = "\
mtllib m.mtl
o cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
usemtl wall
f 1/1 4/4 3/3 2/2
f 5/1 6/2 7/3 8/4
f 1/1 2/2 6/3 5/4
f 4/1 8/2 7/3 3/4
f 1/1 5/2 8/3 4/4
f 2/1 3/2 7/3 6/4
";

const MTL: &str = "\
newmtl wall
Kd 0.5 0.25 0.125
map_Kd tex.png
newmtl glass
Kd 1 1 1
d 0.3
newmtl tinted
Kd 1 1 1
Tr 0.75
newmtl lamp
Kd 0.8 0.8 0.8
Ke 17 12 4
";

fn write_png(dir: &Path) {
    let mut img = image::RgbaImage::new(2, 2);
    for (_, _, p) in img.enumerate_pixels_mut() {
        *p = image::Rgba([128, 255, 0, 255]);
    }
    img.save(dir.join("tex.png")).unwrap();
}

#[test]
fn obj_quads_materials_textures_and_transparency() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "m.mtl", MTL);
    write_png(dir.path());
    let obj = format!(
        "{CUBE_OBJ}o pane\nv 3 0 0\nv 4 0 0\nv 4 1 0\nusemtl glass\nf -3 -2 -1\n\
         o tint\nv 5 0 0\nv 6 0 0\nv 6 1 0\nusemtl tinted\nf -3 -2 -1\n\
         o lamp\nv 0 2 0\nv 0 2 1\nv 1 2 1\nv 1 2 0\nusemtl lamp\nf -4 -3 -2 -1\n"
    );
    let p = write(dir.path(), "c.obj", &obj);
    let s = Scene::load(&p).unwrap();
    assert_eq!(s.triangles.len(), 12 + 1 + 1 + 2);
    // The cube is closed and outward facing, quads fan-triangulated consistently.
    let cube = &s.objects[0];
    assert_eq!(cube.count, 12);
    assert!((signed_volume(&s.triangles[..12]) - 1.0).abs() < 1e-9);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let wall = s.materials.iter().position(|m| m.name == "wall").unwrap() as u32;
    let m = &s.materials[wall as usize];
    assert_eq!(m.base_color, Vec3::new(0.5, 0.25, 0.125));
    let tex = &s.textures[m.base_color_texture.unwrap() as usize];
    assert_eq!((tex.width, tex.height), (2, 2));
    let albedo = s.albedo(wall, Vec2::new(0.3, 0.3));
    assert!(
        (albedo - Vec3::new(0.5 * 0.215_86, 0.25, 0.0))
            .abs()
            .max_element()
            < 1e-4
    );
    // uv flip: vt (0,0) -> (0,1).
    assert_eq!(s.triangles[0].uvs[0], Vec2::new(0.0, 1.0));
    let glass = s.materials.iter().position(|m| m.name == "glass").unwrap() as u32;
    assert_eq!(s.materials[glass as usize].alpha_mode, AlphaMode::Blend);
    assert!((s.opacity(glass, Vec2::ZERO) - 0.3).abs() < 1e-6);
    let tinted = s.materials.iter().position(|m| m.name == "tinted").unwrap() as u32;
    assert!((s.opacity(tinted, Vec2::ZERO) - 0.25).abs() < 1e-6);
    assert_eq!(s.opacity(wall, Vec2::ZERO), 1.0);
    let lamp = s.materials.iter().position(|m| m.name == "lamp").unwrap() as u32;
    assert_eq!(s.emission(lamp, Vec2::ZERO), Vec3::new(17.0, 12.0, 4.0));
    assert_eq!(s.emissive_triangles.len(), 2);
    let area: f32 = s.emissive_triangles.iter().map(|e| e.area).sum();
    assert!((area - 1.0).abs() < 1e-6);
}

#[test]
fn inconsistent_winding_is_counted_and_flagged() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "m.mtl", MTL);
    write_png(dir.path());
    // Flip one triangle of a closed, consistently wound box (the face "1 2 6" -> "1 6 2").
    let mut obj = String::from(
        "o box\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n",
    );
    let faces = [
        [1, 4, 3],
        [1, 3, 2],
        [5, 6, 7],
        [5, 7, 8],
        [1, 2, 6],
        [1, 6, 5],
        [4, 8, 7],
        [4, 7, 3],
        [1, 5, 8],
        [1, 8, 4],
        [2, 3, 7],
        [2, 7, 6],
    ];
    let consistent: String = faces
        .iter()
        .map(|f| format!("f {} {} {}\n", f[0], f[1], f[2]))
        .collect();
    let p = write(dir.path(), "ok.obj", &format!("{obj}{consistent}"));
    let s = Scene::load(&p).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert!((signed_volume(&s.triangles) - 1.0).abs() < 1e-9);
    let mut flipped = faces;
    flipped[4] = [1, 6, 2];
    for f in flipped {
        obj.push_str(&format!("f {} {} {}\n", f[0], f[1], f[2]));
    }
    let p = write(dir.path(), "bad.obj", &obj);
    let s = Scene::load(&p).unwrap();
    let w = s
        .warnings
        .iter()
        .find_map(|w| match w {
            SceneWarning::InconsistentWinding {
                edges, triangles, ..
            } => Some((*edges, *triangles)),
            _ => None,
        })
        .expect("winding warning");
    // The flipped triangle's 3 edges, and it plus its 3 neighbours flagged.
    assert_eq!(w, (3, 4));
    assert!(!s.winding_consistent(4));
    assert_eq!((0..12).filter(|&t| !s.winding_consistent(t)).count(), 4);
    assert!(w.0 > 0 && s.warnings[0].to_string().contains("inconsistent winding"));
}

#[test]
fn bad_input_gives_typed_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let e = Scene::load(d.join("scene.fbx")).unwrap_err();
    assert!(matches!(e, SceneError::UnknownFileType { .. }), "{e}");
    let e = Scene::load(d.join("nope.obj")).unwrap_err();
    assert!(matches!(e, SceneError::MissingFile { .. }), "{e}");
    assert!(e.to_string().contains("nope.obj"));
    let p = write(d, "broken.gltf", "{ this is not json");
    let e = Scene::load(&p).unwrap_err();
    assert!(matches!(e, SceneError::Gltf { .. }), "{e}");
    let p = write(d, "broken.glb", "glTF\u{2}\u{0}garbage");
    assert!(matches!(
        Scene::load(&p).unwrap_err(),
        SceneError::Gltf { .. }
    ));
    let p = write(
        d,
        "missingmtl.obj",
        "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let e = Scene::load(&p).unwrap_err();
    assert!(
        matches!(&e, SceneError::MissingFile { path, .. } if path.ends_with("gone.mtl")),
        "{e}"
    );
    let p = write(
        d,
        "nan.obj",
        "o bad_mesh\nv 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let e = Scene::load(&p).unwrap_err();
    assert!(
        matches!(&e, SceneError::NonFinite { mesh, .. } if mesh.contains("bad_mesh")),
        "{e}"
    );
    let p = write(d, "inf.obj", "o m\nv 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n");
    assert!(matches!(
        Scene::load(&p).unwrap_err(),
        SceneError::NonFinite { .. }
    ));
    // A file without triangles loads (a scene of lights and sky alone is a real
    // use); what needs a bake box then asks for one.
    let p = write(d, "empty.obj", "# nothing\n");
    let s = Scene::load(&p).unwrap();
    assert!(s.triangles.is_empty());
    assert_eq!(s.bake_box().check_bake_box(), Err(BakeBoxError::NoGeometry));
    let p = write(
        d,
        "degen.obj",
        "o m\nv 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\nf 1 1 4\n",
    );
    let s = Scene::load(&p).unwrap();
    assert_eq!(s.triangles.len(), 1);
    assert!(s
        .warnings
        .iter()
        .any(|w| matches!(w, SceneWarning::DegenerateTriangles { count: 2, .. })));
    let p = write(
        d,
        "onlydegen.obj",
        "o m\nv 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
    );
    assert!(Scene::load(&p).unwrap().triangles.is_empty());
    let p = write(d, "badface.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n");
    assert!(Scene::load(&p).is_err());
}

#[test]
fn scene_file_errors_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let cases: [(&str, &str); 9] = [
        ("[[mesh]]\npath = \"missing.obj\"\n", "missing.obj"),
        ("[[mesh]]\npath = \"tri.obj\"\ncolour = 1\n", "unknown field"),
        ("[[mesh]]\npath = \"tri.obj\"\n[[light]]\nkind = \"laser\"\nintensity = 1\n", "laser"),
        ("[[mesh]]\npath = \"tri.obj\"\n[[light]]\nkind = \"sphere\"\nposition = [0,1,0]\nintensity = 1\n", "radius"),
        ("[[mesh]]\npath = \"tri.obj\"\n[[light]]\nkind = \"directional\"\nintensity = 1\n", "direction"),
        ("[[mesh]]\npath = \"tri.obj\"\n[environment]\nmap = \"sky.hdr\"\n", "sky.hdr"),
        ("[[mesh]]\npath = \"tri.obj\"\n[bake]\nbox = [[1,1,1],[0,0,0]]\n", "min"),
        ("[[mesh]]\npath = \"tri.obj\"\nrotation = [0,0,0,0]\n", "quaternion"),
        ("[[mesh]\n", "TOML"),
    ];
    for (text, needle) in cases {
        let p = write(d, "s.toml", text);
        let e = Scene::load(&p).unwrap_err().to_string();
        assert!(
            e.to_lowercase().contains(&needle.to_lowercase())
                || (needle == "TOML" && e.contains("s.toml")),
            "{text:?} -> {e}"
        );
        assert!(
            e.contains(d.file_name().unwrap().to_str().unwrap()),
            "names the file: {e}"
        );
    }
}

#[test]
fn scene_file_composes_transformed_meshes_lights_and_settings() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::create_dir(d.join("sub")).unwrap();
    write(
        &d.join("sub"),
        "tri.obj",
        "o t\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n",
    );
    write(d, "sky.hdr", "not checked here");
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let text = format!(
        "[[mesh]]\npath = \"sub/tri.obj\"\n\
         [[mesh]]\npath = \"sub/tri.obj\"\ntranslation = [10, 0, 0]\nrotation = [0, {h}, 0, {h}]\nscale = [2, 2, 2]\n\
         [[light]]\nkind = \"spot\"\nposition = [0, 2.5, 0]\ndirection = [0, -2, 0]\ncolor = [1, 0.9, 0.8]\n\
         intensity = 50\ninner_angle_degrees = 10\nouter_angle_degrees = 20\ngroup = \"ceiling\"\n\
         [[light]]\nkind = \"disk\"\nposition = [1, 2, 3]\nradius = 0.5\ndirection = [0, -1, 0]\nintensity = 3\n\
         [environment]\ncolor = [0.1, 0.2, 0.3]\nmap = \"sky.hdr\"\nintensity = 2.0\nrotation_y_degrees = 90\n\
         [bake]\nbox = [[0, 0, 0], [8, 3, 4]]\nsamples = 4096\nbounces = 3\nseed = 1\n\
         [[region]]\nname = \"room\"\nmin = [0, 0, 0]\nmax = [1, 2, 3]\n"
    );
    let p = write(d, "scene.toml", &text);
    let s = Scene::load(&p).unwrap();
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(s.triangles[0].positions[0], Vec3::new(1.0, 0.0, 0.0));
    // Second copy: scale 2, then +90° about y (x -> -z, z -> x), then translate by 10 x.
    let q = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    for (k, v) in [Vec3::X, Vec3::Y, Vec3::Z].into_iter().enumerate() {
        let expect = q * (2.0 * v) + Vec3::new(10.0, 0.0, 0.0);
        assert!((s.triangles[1].positions[k] - expect).length() < 1e-5);
    }
    let hand = [
        Vec3::new(10.0, 0.0, -2.0),
        Vec3::new(10.0, 2.0, 0.0),
        Vec3::new(12.0, 0.0, 0.0),
    ];
    for (p, h) in s.triangles[1].positions.iter().zip(hand) {
        assert!((*p - h).length() < 1e-5);
    }
    let spot = &s.lights[0];
    assert_eq!(spot.kind, LightKind::Spot);
    assert_eq!(spot.direction, Vec3::NEG_Y);
    assert!((spot.inner_angle - 10f32.to_radians()).abs() < 1e-6);
    assert_eq!(spot.group.as_deref(), Some("ceiling"));
    let disk = &s.lights[1];
    assert!((disk.radiance().x - 3.0 / (std::f32::consts::PI * 0.25)).abs() < 1e-5);
    assert_eq!(
        s.environment.map.as_deref(),
        Some(d.join("sky.hdr").as_path())
    );
    assert_eq!(s.environment.intensity, 2.0);
    assert_eq!(s.environment.rotation_y_degrees, 90.0);
    assert_eq!(s.bake.samples, Some(4096));
    assert_eq!(s.bake.bounces, Some(3));
    assert_eq!(s.bake.seed, Some(1));
    assert_eq!(s.bake_box().max, Vec3::new(8.0, 3.0, 4.0));
    assert_eq!(s.regions[0].aabb().max, Vec3::new(1.0, 2.0, 3.0));
}

/// A glTF with an external buffer: a quad under a translated + scaled node, a BLEND material
/// with emissive strength, and the three KHR_lights_punctual kinds.
#[test]
fn gltf_nodes_materials_and_punctual_lights() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let pos: [f32; 12] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0];
    let idx: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut bin = Vec::new();
    for p in pos {
        bin.extend_from_slice(&p.to_le_bytes());
    }
    for i in idx {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    fs::write(d.join("quad.bin"), &bin).unwrap();
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [
     {{"type": "point", "color": [1, 0.5, 0.25], "intensity": 20, "name": "bulb"}},
     {{"type": "spot", "intensity": 5, "spot": {{"innerConeAngle": 0.2, "outerConeAngle": 0.5}}}},
     {{"type": "directional", "intensity": 3}}]}}}},
  "buffers": [{{"uri": "quad.bin", "byteLength": {len}}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 12}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}},
    {{"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}}],
  "materials": [{{"name": "lampglass", "pbrMetallicRoughness": {{"baseColorFactor": [0.2, 0.4, 0.6, 0.5]}},
     "alphaMode": "BLEND", "emissiveFactor": [1, 0.5, 0],
     "extensions": {{"KHR_materials_emissive_strength": {{"emissiveStrength": 4}}}}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
  "nodes": [
    {{"children": [1, 2, 3, 4], "translation": [0, 2, 0]}},
    {{"mesh": 0, "scale": [2, 2, 2], "translation": [1, 0, 0]}},
    {{"extensions": {{"KHR_lights_punctual": {{"light": 0}}}}, "translation": [0, 1, 0]}},
    {{"extensions": {{"KHR_lights_punctual": {{"light": 1}}}}, "rotation": [{mh}, 0, 0, {h}]}},
    {{"extensions": {{"KHR_lights_punctual": {{"light": 2}}}}}}],
  "scenes": [{{"nodes": [0]}}],
  "scene": 0
}}"#,
        len = bin.len(),
        mh = -h
    );
    let p = write(d, "quad.gltf", &json);
    let s = Scene::load(&p).unwrap();
    assert_eq!(s.triangles.len(), 2);
    // Node chain: translate (0,2,0) ∘ [translate (1,0,0) ∘ scale 2].
    assert_eq!(s.triangles[0].positions[1], Vec3::new(3.0, 2.0, 0.0));
    assert_eq!(s.triangles[0].positions[2], Vec3::new(3.0, 4.0, 0.0));
    let m = &s.materials[s.triangles[0].material as usize];
    assert_eq!(m.alpha_mode, AlphaMode::Blend);
    assert_eq!(m.base_color, Vec3::new(0.2, 0.4, 0.6));
    assert_eq!(s.opacity(s.triangles[0].material, Vec2::ZERO), 0.5);
    assert_eq!(m.emissive, Vec3::new(4.0, 2.0, 0.0));
    assert_eq!(s.emissive_triangles.len(), 2);
    assert_eq!(s.lights.len(), 3);
    let point = s
        .lights
        .iter()
        .find(|l| l.kind == LightKind::Point)
        .unwrap();
    assert_eq!(point.position, Vec3::new(0.0, 3.0, 0.0));
    assert_eq!(point.intensity, 20.0);
    assert_eq!(point.color, Vec3::new(1.0, 0.5, 0.25));
    assert_eq!(point.group, None);
    // Spot: −90° about x turns local −Z into −Y (pointing down).
    let spot = s.lights.iter().find(|l| l.kind == LightKind::Spot).unwrap();
    assert!(
        (spot.direction - Vec3::NEG_Y).length() < 1e-5,
        "{}",
        spot.direction
    );
    assert_eq!((spot.inner_angle, spot.outer_angle), (0.2, 0.5));
    let sun = s
        .lights
        .iter()
        .find(|l| l.kind == LightKind::Directional)
        .unwrap();
    assert_eq!(sun.direction, Vec3::NEG_Z);
    // A missing external buffer is reported by name.
    fs::remove_file(d.join("quad.bin")).unwrap();
    let e = Scene::load(&p).unwrap_err();
    assert!(
        matches!(&e, SceneError::MissingFile { path, .. } if path.ends_with("quad.bin")),
        "{e}"
    );
}

#[test]
fn shared_scene_files_load() {
    let Some(data) = shared_data() else { return };
    let scenes = data.join("scenes");
    let mut seen = 0;
    for entry in fs::read_dir(&scenes).unwrap() {
        let dir = entry.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        for f in fs::read_dir(&dir).unwrap() {
            let f = f.unwrap().path();
            if f.extension().and_then(|e| e.to_str()) != Some("toml") {
                continue;
            }
            let s = Scene::load(&f).unwrap_or_else(|e| panic!("{e}"));
            seen += 1;
            for w in &s.warnings {
                eprintln!("{}: warning: {w}", f.display());
            }
            assert!(!s.triangles.is_empty());
            assert!(!s.bounds.is_empty());
            let name = dir.file_name().unwrap().to_str().unwrap();
            match name {
                "cornell_box" => {
                    assert_eq!(s.triangles.len(), 36);
                    assert_eq!(s.emissive_triangles.len(), 2);
                    let area: f32 = s.emissive_triangles.iter().map(|e| e.area).sum();
                    assert!((area - 0.47 * 0.38).abs() < 1e-4, "{area}");
                    assert_eq!(s.emissive_triangles[0].radiance, Vec3::new(17.0, 12.0, 4.0));
                }
                "fzk_haus" => {
                    assert_eq!(s.triangles.len(), 34_378);
                    assert_eq!(s.lights.len(), 5);
                    assert_eq!(s.regions.len(), 7);
                    assert!(s.environment.map.as_ref().unwrap().is_file());
                    let glas = s.materials.iter().find(|m| m.name == "Glas").unwrap();
                    assert_eq!((glas.alpha_mode, glas.alpha), (AlphaMode::Blend, 0.12));
                }
                "duplex_apartment" => {
                    assert_eq!(s.triangles.len(), 25_332);
                    assert_eq!(s.lights.len(), 5);
                    assert_eq!(s.regions.len(), 21);
                    let b = s.bake_box();
                    assert_eq!(b.max, Vec3::new(8.8, 6.635, 17.8));
                }
                _ => {}
            }
        }
    }
    assert_eq!(seen, 3);
}

/// `Aabb::overlaps` against a brute-force search for a shared point on a
/// 0.25 grid (the boxes' corners lie on it, so a shared point, if any, is a
/// grid point): touching faces, edges and corners count, disjoint boxes do
/// not, and the test is symmetric.
#[test]
fn aabb_overlap_matches_a_search_for_a_shared_point() {
    let b = |lo: [f32; 3], hi: [f32; 3]| Aabb {
        min: Vec3::from(lo),
        max: Vec3::from(hi),
    };
    let unit = b([0.0; 3], [1.0; 3]);
    let others = [
        b([0.5; 3], [2.0; 3]),
        b([1.0, 0.0, 0.0], [2.0, 1.0, 1.0]),
        b([1.0, 1.0, 0.0], [2.0, 2.0, 1.0]),
        b([1.0; 3], [2.0; 3]),
        b([1.25, 0.0, 0.0], [2.0, 1.0, 1.0]),
        b([0.25, 0.25, -1.0], [0.5, 0.5, -0.25]),
        b([-1.0; 3], [2.0; 3]),
    ];
    let grid = |a: &Aabb| {
        let mut pts = Vec::new();
        for i in -8..=12 {
            for j in -8..=12 {
                for k in -8..=12 {
                    let p = Vec3::new(i as f32, j as f32, k as f32) * 0.25;
                    if a.contains(p) {
                        pts.push(p);
                    }
                }
            }
        }
        pts
    };
    for o in &others {
        let shared = grid(&unit).iter().any(|p| o.contains(*p));
        assert_eq!(unit.overlaps(o), shared, "{o:?}");
        assert_eq!(o.overlaps(&unit), shared, "{o:?}");
    }
}

/// `region_names_at` names exactly the regions whose corners bound the
/// point (compared coordinate by coordinate), in file order; a point outside
/// every region gets none.
#[test]
fn region_names_at_match_the_region_boxes() {
    let scene = Scene::builtin_demo();
    assert!(scene.regions.len() >= 2);
    for r in &scene.regions {
        let c = (r.min + r.max) * 0.5;
        let want: Vec<&str> = scene
            .regions
            .iter()
            .filter(|q| (0..3).all(|a| q.min[a] <= c[a] && c[a] <= q.max[a]))
            .map(|q| q.name.as_str())
            .collect();
        let got = scene.region_names_at(c);
        assert!(got.contains(&r.name.as_str()), "{got:?}");
        assert_eq!(got, want);
    }
    assert!(scene.region_names_at(Vec3::new(1e4, 1e4, 1e4)).is_empty());
}
