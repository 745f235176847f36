//! The scene file's `[[light]]` keys `mode` and `angular_diameter_degrees`,
//! the checks on them, and their part in the lighting hash.

use super::scene_file::parse;
use super::*;
use std::path::Path;

const SUN: &str = "[[light]]\nkind = \"directional\"\ndirection = [0, -1, 0]\nintensity = 5\n";
const POINT: &str = "[[light]]\nkind = \"point\"\nposition = [0, 1, 0]\nintensity = 5\n";
const SPOT: &str =
    "[[light]]\nkind = \"spot\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\nintensity = 5\n";

/// Parses a scene file with no meshes, its `[[light]]`s written by `text`.
fn scene(text: &str) -> Result<Scene, SceneError> {
    parse(Path::new("lights.toml"), text)
}

/// The error message of a scene that must be refused.
fn refused(text: &str) -> String {
    match scene(text) {
        Ok(_) => panic!("accepted: {text:?}"),
        Err(e) => e.to_string(),
    }
}

/// A point light of zero intensity in `mode`.
fn dark_point(mode: &str) -> String {
    format!("{POINT}mode = \"{mode}\"\n").replace("intensity = 5", "intensity = 0")
}

#[test]
fn each_mode_parses_and_auto_is_the_default() {
    let s = scene(POINT).unwrap();
    assert_eq!(s.lights[0].mode, LightMode::Auto);
    for (name, mode) in [
        ("auto", LightMode::Auto),
        ("baked", LightMode::Baked),
        ("runtime", LightMode::Runtime),
    ] {
        let s = scene(&format!("{SUN}{POINT}mode = \"{name}\"\n")).unwrap();
        assert_eq!(s.lights[0].mode, LightMode::Auto, "{name}");
        assert_eq!(s.lights[1].mode, mode, "{name}");
        assert_eq!(s.lights[1].angular_diameter, 0.0);
    }
}

#[test]
fn bad_light_keys_are_refused_naming_the_light_and_the_key() {
    let cases = [
        (
            format!("{SUN}{POINT}mode = \"runtme\"\n"),
            "light 2",
            "mode",
        ),
        (dark_point("runtime"), "light 1", "intensity"),
        (
            format!("{SUN}mode = \"runtime\"\ncolor = [0, 0, 0]\n"),
            "light 1",
            "color",
        ),
        (
            format!("{SUN}angular_diameter_degrees = 0\n"),
            "light 1",
            "angular_diameter_degrees",
        ),
        (
            format!("{SUN}angular_diameter_degrees = 90\n"),
            "light 1",
            "angular_diameter_degrees",
        ),
        (
            format!("{SUN}angular_diameter_degrees = nan\n"),
            "light 1",
            "angular_diameter_degrees",
        ),
        (
            format!("{SUN}angular_diameter_degrees = -1\n"),
            "light 1",
            "angular_diameter_degrees",
        ),
        (
            format!("{SUN}{POINT}angular_diameter_degrees = 0.5\n"),
            "light 2",
            "angular_diameter_degrees",
        ),
        (
            format!("{SUN}{SPOT}outer_angle_degrees = 0\n"),
            "light 2",
            "outer_angle_degrees",
        ),
    ];
    for (text, light, key) in cases {
        let e = refused(&text);
        assert!(e.contains(light) && e.contains(key), "{text:?} -> {e}");
        assert!(e.contains("lights.toml"), "names the file: {e}");
    }
    let e = refused(&format!("{POINT}mode = \"runtme\"\n"));
    assert!(
        e.contains("light 1: mode 'runtme' is not one of auto, baked, runtime"),
        "{e}"
    );
    let e = refused(&format!("{POINT}angular_diameter_degrees = 0.5\n"));
    assert!(
        e.contains("only directional lights have angular_diameter_degrees"),
        "{e}"
    );
    // The spot rule that was there before still holds.
    for extra in [
        "outer_angle_degrees = 181\n",
        "inner_angle_degrees = 30\nouter_angle_degrees = 20\n",
        "inner_angle_degrees = -1\n",
    ] {
        let e = refused(&format!("{SPOT}{extra}"));
        assert!(
            e.contains("light 1") && e.contains("outer_angle_degrees"),
            "{e}"
        );
    }
    let s = scene(&format!("{SPOT}outer_angle_degrees = 180\n")).unwrap();
    assert!((s.lights[0].outer_angle - std::f32::consts::PI).abs() < 1e-6);
    // A runtime light with light in it is fine; so is a baked one of zero intensity.
    assert!(scene(&format!("{SUN}mode = \"runtime\"\n")).is_ok());
    assert!(scene(&dark_point("baked")).is_ok());
}

#[test]
fn angular_diameter_is_stored_in_radians() {
    let s = scene(&format!("{SUN}angular_diameter_degrees = 0.53\n")).unwrap();
    let want = 0.53f32.to_radians();
    assert!((s.lights[0].angular_diameter - want).abs() < 1e-9);
    assert!((s.lights[0].angular_diameter - 0.009_250_245).abs() < 1e-7);
    assert_eq!(scene(SUN).unwrap().lights[0].angular_diameter, 0.0);
}

#[test]
fn lighting_hash_sees_the_mode_and_the_angular_diameter() {
    let hash = |extra: &str| scene(&format!("{SUN}{extra}")).unwrap().lighting_hash();
    let auto = hash("");
    assert_eq!(auto, hash("mode = \"auto\"\n"));
    assert_ne!(auto, hash("mode = \"baked\"\n"));
    assert_ne!(auto, hash("mode = \"runtime\"\n"));
    assert_ne!(hash("mode = \"baked\"\n"), hash("mode = \"runtime\"\n"));
    assert_ne!(auto, hash("angular_diameter_degrees = 0.53\n"));
    assert_ne!(
        hash("angular_diameter_degrees = 0.53\n"),
        hash("angular_diameter_degrees = 0.54\n")
    );
}
