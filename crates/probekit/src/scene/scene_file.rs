//! The `.toml` scene file (specified in `docs/scene-format.md`): `[[mesh]]`, `[[light]]`,
//! `[environment]`, `[bake]`, `[[region]]`. Paths are relative to the scene file.

use super::{
    load_mesh_file, Aabb, BakeSettings, EnvironmentDesc, Light, LightKind, LightMode, Parts,
    Region, Scene, SceneError, SceneExtras,
};
use glam::{Mat4, Quat, Vec3};
use serde::Deserialize;
use std::path::Path;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default)]
    mesh: Vec<MeshEntry>,
    #[serde(default)]
    light: Vec<LightEntry>,
    environment: Option<EnvEntry>,
    bake: Option<BakeEntry>,
    #[serde(default)]
    region: Vec<RegionEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshEntry {
    path: String,
    translation: Option<[f32; 3]>,
    rotation: Option<[f32; 4]>,
    scale: Option<[f32; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightEntry {
    kind: String,
    position: Option<[f32; 3]>,
    direction: Option<[f32; 3]>,
    color: Option<[f32; 3]>,
    intensity: f32,
    radius: Option<f32>,
    inner_angle_degrees: Option<f32>,
    outer_angle_degrees: Option<f32>,
    group: Option<String>,
    mode: Option<String>,
    angular_diameter_degrees: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvEntry {
    color: Option<[f32; 3]>,
    map: Option<String>,
    intensity: Option<f32>,
    rotation_y_degrees: Option<f32>,
}

/// `[bake]`: a partial recipe. Its own keys are checked here; the rest
/// are checked against the recipe when a bake resolves it.
#[derive(Deserialize)]
struct BakeEntry {
    r#box: Option<[[f32; 3]; 2]>,
    samples: Option<u32>,
    bounces: Option<u32>,
    seed: Option<u64>,
    #[serde(flatten)]
    recipe: toml::Table,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RegionEntry {
    name: String,
    min: [f32; 3],
    max: [f32; 3],
}

pub(crate) fn load(path: &Path) -> Result<Scene, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|e| SceneError::MissingFile {
        path: path.into(),
        referenced_by: None,
        message: e.to_string(),
    })?;
    parse(path, &text)
}

/// Parses scene-file text; `path` names the file in errors and anchors relative paths.
pub(crate) fn parse(path: &Path, text: &str) -> Result<Scene, SceneError> {
    let bad = |message: String| SceneError::SceneFile {
        path: path.into(),
        message,
    };
    let file: SceneFile = toml::from_str(text).map_err(|e| bad(e.to_string().trim().to_owned()))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let finite3 = |v: [f32; 3], what: &str| -> Result<Vec3, SceneError> {
        let v = Vec3::from(v);
        if v.is_finite() {
            Ok(v)
        } else {
            Err(bad(format!("{what} is not finite")))
        }
    };

    let mut parts = Parts::default();
    for (i, m) in file.mesh.iter().enumerate() {
        let what = format!("mesh {} ('{}')", i + 1, m.path);
        let mesh_path = base.join(&m.path);
        let t = finite3(
            m.translation.unwrap_or([0.0; 3]),
            &format!("{what}: translation"),
        )?;
        let s = finite3(m.scale.unwrap_or([1.0; 3]), &format!("{what}: scale"))?;
        if s.x == 0.0 || s.y == 0.0 || s.z == 0.0 {
            return Err(bad(format!("{what}: scale has a zero component")));
        }
        let q = m.rotation.unwrap_or([0.0, 0.0, 0.0, 1.0]);
        let q = Quat::from_xyzw(q[0], q[1], q[2], q[3]);
        if !q.is_finite() || q.length() < 1e-6 {
            return Err(bad(format!(
                "{what}: rotation must be a non-zero quaternion [x, y, z, w]"
            )));
        }
        let world_from_mesh = Mat4::from_scale_rotation_translation(s, q.normalize(), t);
        let ext = mesh_path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        if !matches!(ext.as_deref(), Some("gltf" | "glb" | "obj")) {
            return Err(SceneError::UnknownFileType { path: mesh_path });
        }
        if !mesh_path.is_file() {
            return Err(SceneError::MissingFile {
                path: mesh_path,
                referenced_by: Some(path.into()),
                message: "no such file".into(),
            });
        }
        let loaded = load_mesh_file(&mesh_path)?;
        parts.append(loaded, world_from_mesh);
    }

    for (i, l) in file.light.iter().enumerate() {
        let what = format!("light {}", i + 1);
        let kind = match l.kind.as_str() {
            "point" => LightKind::Point,
            "spot" => LightKind::Spot,
            "directional" => LightKind::Directional,
            "sphere" => LightKind::Sphere,
            "disk" => LightKind::Disk,
            other => {
                return Err(bad(format!(
                    "{what}: unknown kind '{other}' (point, spot, directional, sphere, disk)"
                )))
            }
        };
        if !l.intensity.is_finite() || l.intensity < 0.0 {
            return Err(bad(format!("{what}: intensity must be finite and ≥ 0")));
        }
        let color = finite3(l.color.unwrap_or([1.0; 3]), &format!("{what}: color"))?;
        if color.min_element() < 0.0 {
            return Err(bad(format!("{what}: color must be ≥ 0")));
        }
        let needs_position = kind != LightKind::Directional;
        let position = match l.position {
            Some(p) => finite3(p, &format!("{what}: position"))?,
            None if needs_position => {
                return Err(bad(format!("{what}: {} light needs position", l.kind)))
            }
            None => Vec3::ZERO,
        };
        let needs_direction = matches!(
            kind,
            LightKind::Directional | LightKind::Spot | LightKind::Disk
        );
        let direction = match l.direction {
            Some(d) => {
                let d = finite3(d, &format!("{what}: direction"))?;
                if d.length() < 1e-12 {
                    return Err(bad(format!("{what}: direction is zero")));
                }
                d.normalize()
            }
            None if needs_direction => {
                return Err(bad(format!("{what}: {} light needs direction", l.kind)))
            }
            None => Vec3::NEG_Y,
        };
        let radius = match kind {
            LightKind::Sphere | LightKind::Disk => {
                let r = l
                    .radius
                    .ok_or_else(|| bad(format!("{what}: {} light needs radius", l.kind)))?;
                if !(r.is_finite() && r > 0.0) {
                    return Err(bad(format!("{what}: radius must be > 0")));
                }
                r
            }
            _ => 0.0,
        };
        let inner = l.inner_angle_degrees.unwrap_or(0.0);
        let outer = l.outer_angle_degrees.unwrap_or(45.0);
        if kind == LightKind::Spot && outer.is_finite() && outer <= 0.0 {
            return Err(bad(format!(
                "{what}: outer_angle_degrees must be in (0, 180], got {outer}"
            )));
        }
        if kind == LightKind::Spot
            && !(inner.is_finite()
                && outer.is_finite()
                && 0.0 <= inner
                && inner <= outer
                && outer <= 180.0)
        {
            return Err(bad(format!(
                "{what}: need 0 ≤ inner_angle_degrees ≤ outer_angle_degrees ≤ 180"
            )));
        }
        let mode = match &l.mode {
            None => LightMode::Auto,
            Some(name) => LightMode::from_name(name).ok_or_else(|| {
                bad(format!(
                    "{what}: mode '{name}' is not one of auto, baked, runtime"
                ))
            })?,
        };
        if mode == LightMode::Runtime {
            if l.intensity <= 0.0 {
                return Err(bad(format!("{what}: a runtime light needs intensity > 0")));
            }
            if color.max_element() <= 0.0 {
                return Err(bad(format!(
                    "{what}: a runtime light needs a color that is not all zero"
                )));
            }
        }
        let angular_diameter = match l.angular_diameter_degrees {
            None => 0.0,
            Some(_) if kind != LightKind::Directional => {
                return Err(bad(format!(
                    "{what}: only directional lights have angular_diameter_degrees"
                )))
            }
            Some(a) if a.is_finite() && a > 0.0 && a < 90.0 => a.to_radians(),
            Some(a) => {
                return Err(bad(format!(
                    "{what}: angular_diameter_degrees must be finite and in (0, 90), got {a}"
                )))
            }
        };
        parts.lights.push(Light {
            kind,
            position,
            direction,
            color,
            intensity: l.intensity,
            radius,
            inner_angle: if kind == LightKind::Spot {
                inner.to_radians()
            } else {
                0.0
            },
            outer_angle: if kind == LightKind::Spot {
                outer.to_radians()
            } else {
                0.0
            },
            group: l.group.clone(),
            mode,
            angular_diameter,
        });
    }

    let mut extras = SceneExtras::default();
    if let Some(e) = &file.environment {
        let mut env = EnvironmentDesc::default();
        if let Some(c) = e.color {
            env.color = finite3(c, "environment color")?;
            if env.color.min_element() < 0.0 {
                return Err(bad("environment color must be ≥ 0".into()));
            }
        }
        if let Some(m) = &e.map {
            let p = base.join(m);
            if !p.is_file() {
                return Err(SceneError::MissingFile {
                    path: p,
                    referenced_by: Some(path.into()),
                    message: "no such file".into(),
                });
            }
            env.map = Some(p);
        }
        env.intensity = e.intensity.unwrap_or(1.0);
        if !(env.intensity.is_finite() && env.intensity >= 0.0) {
            return Err(bad("environment intensity must be finite and ≥ 0".into()));
        }
        env.rotation_y_degrees = e.rotation_y_degrees.unwrap_or(0.0);
        if !env.rotation_y_degrees.is_finite() {
            return Err(bad("environment rotation_y_degrees is not finite".into()));
        }
        extras.environment = env;
    }
    if let Some(b) = &file.bake {
        let mut s = BakeSettings {
            samples: b.samples,
            bounces: b.bounces,
            seed: b.seed,
            recipe: b.recipe.clone(),
            ..Default::default()
        };
        if let Some([lo, hi]) = b.r#box {
            let (lo, hi) = (finite3(lo, "bake box")?, finite3(hi, "bake box")?);
            if lo.cmpgt(hi).any() {
                return Err(bad("bake box: min must be ≤ max in every axis".into()));
            }
            s.r#box = Some(Aabb::new(lo, hi));
        }
        if s.samples == Some(0) {
            return Err(bad("bake samples must be ≥ 1".into()));
        }
        extras.bake = s;
    }
    for r in &file.region {
        let (lo, hi) = (
            finite3(r.min, &format!("region '{}': min", r.name))?,
            finite3(r.max, &format!("region '{}': max", r.name))?,
        );
        if lo.cmpgt(hi).any() {
            return Err(bad(format!("region '{}': min must be ≤ max", r.name)));
        }
        extras.regions.push(Region {
            name: r.name.clone(),
            min: lo,
            max: hi,
        });
    }
    Scene::from_parts(path, parts, extras)
}
