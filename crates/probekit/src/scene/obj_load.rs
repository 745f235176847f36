//! Wavefront OBJ + MTL loader on the `tobj` crate (which handles negative indices and
//! triangulates polygons by fans).
//!
//! Mapping: `Kd` → albedo, `map_Kd` → base-colour texture (sRGB-decoded), `Ke` → emitted
//! radiance, `d` (or `1 − Tr` when `d` is absent) → alpha with [`AlphaMode::Blend`] when below 1.
//! `vt` is flipped to the glTF convention (`v ← 1 − v`).

use super::{srgb_to_linear, AlphaMode, Material, Parts, SceneError, Texture, Triangle};
use glam::{Vec2, Vec3, Vec4};
use std::path::{Path, PathBuf};

pub(crate) fn load(path: &Path) -> Result<Parts, SceneError> {
    let obj_err = |message: String| SceneError::Obj {
        path: path.into(),
        message,
    };
    let text = std::fs::read(path).map_err(|e| SceneError::MissingFile {
        path: path.into(),
        referenced_by: None,
        message: e.to_string(),
    })?;
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    // Check material libraries first so a missing one is reported by name.
    let mut mtl_dirs: Vec<PathBuf> = Vec::new();
    for line in String::from_utf8_lossy(&text).lines() {
        let line = line.trim_start();
        if let Some(rest) = line.strip_prefix("mtllib") {
            if !rest.starts_with(char::is_whitespace) {
                continue;
            }
            let name = rest.trim();
            if name.is_empty() {
                continue;
            }
            let p = base.join(name);
            if !p.is_file() {
                return Err(SceneError::MissingFile {
                    path: p,
                    referenced_by: Some(path.into()),
                    message: "no such file".into(),
                });
            }
            mtl_dirs.push(p.parent().unwrap_or(&base).to_path_buf());
        }
    }
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) = tobj::load_obj(path, &opts).map_err(|e| obj_err(format!("{e}")))?;
    let materials = materials.map_err(|e| obj_err(format!("material library: {e}")))?;
    let tex_base = mtl_dirs.first().cloned().unwrap_or(base);
    let file = path.display().to_string();

    let mut parts = Parts::default();
    for m in &materials {
        let d = m.dissolve.or_else(|| {
            m.unknown_param
                .get("Tr")
                .and_then(|v| v.split_whitespace().next()?.parse::<f32>().ok())
                .map(|tr| 1.0 - tr)
        });
        let alpha = d.unwrap_or(1.0);
        let base_color_texture = match &m.diffuse_texture {
            Some(name) if !name.trim().is_empty() => {
                let tex = load_texture(&tex_base.join(name.trim()), path)?;
                parts.textures.push(tex);
                Some(parts.textures.len() as u32 - 1)
            }
            _ => None,
        };
        let emissive = m
            .emissive
            .or_else(|| {
                m.unknown_param.get("Ke").and_then(|v| {
                    let f: Vec<f32> = v
                        .split_whitespace()
                        .filter_map(|x| x.parse().ok())
                        .collect();
                    (f.len() >= 3).then(|| [f[0], f[1], f[2]])
                })
            })
            .map(Vec3::from)
            .unwrap_or(Vec3::ZERO);
        parts.materials.push(Material {
            name: m.name.clone(),
            base_color: m.diffuse.map(Vec3::from).unwrap_or(Vec3::splat(0.8)),
            base_color_texture,
            alpha: alpha.clamp(0.0, 1.0),
            alpha_mode: if alpha < 1.0 {
                AlphaMode::Blend
            } else {
                AlphaMode::Opaque
            },
            emissive: emissive.max(Vec3::ZERO),
            emissive_texture: None,
            double_sided: false,
        });
    }

    for model in &models {
        let mesh = &model.mesh;
        let name = format!("{file}: {}", model.name);
        let material = mesh.material_id.map_or(u32::MAX, |m| m as u32);
        let pos = |i: u32| -> Option<Vec3> {
            let i = i as usize * 3;
            mesh.positions
                .get(i..i + 3)
                .map(|p| Vec3::new(p[0], p[1], p[2]))
        };
        let mut tris = Vec::with_capacity(mesh.indices.len() / 3);
        for (f, face) in mesh.indices.chunks_exact(3).enumerate() {
            let mut positions = [Vec3::ZERO; 3];
            for k in 0..3 {
                positions[k] = pos(face[k])
                    .ok_or_else(|| obj_err(format!("{name}: vertex index out of range")))?;
            }
            let mut normals = [Vec3::ZERO; 3];
            if mesh.normal_indices.len() == mesh.indices.len() {
                for (k, normal) in normals.iter_mut().enumerate() {
                    let i = mesh.normal_indices[3 * f + k] as usize * 3;
                    if let Some(n) = mesh.normals.get(i..i + 3) {
                        *normal = Vec3::new(n[0], n[1], n[2]);
                    }
                }
            }
            let mut uvs = [Vec2::ZERO; 3];
            if mesh.texcoord_indices.len() == mesh.indices.len() {
                for (k, uv) in uvs.iter_mut().enumerate() {
                    let i = mesh.texcoord_indices[3 * f + k] as usize * 2;
                    if let Some(t) = mesh.texcoords.get(i..i + 2) {
                        *uv = Vec2::new(t[0], 1.0 - t[1]);
                    }
                }
            }
            tris.push(Triangle {
                positions,
                normals,
                uvs,
                material,
            });
        }
        parts.objects.push((name, tris));
    }
    Ok(parts)
}

/// Loads an 8-bit (sRGB) or HDR (linear) image as a texture.
fn load_texture(p: &Path, referenced_by: &Path) -> Result<Texture, SceneError> {
    if !p.is_file() {
        return Err(SceneError::MissingFile {
            path: p.into(),
            referenced_by: Some(referenced_by.into()),
            message: "no such file".into(),
        });
    }
    let img = image::open(p).map_err(|e| SceneError::Texture {
        path: p.into(),
        message: e.to_string(),
    })?;
    let hdr = matches!(
        img.color(),
        image::ColorType::Rgb32F | image::ColorType::Rgba32F
    );
    let rgba = img.to_rgba32f();
    let (width, height) = rgba.dimensions();
    let texels = rgba
        .pixels()
        .map(|p| {
            let c = |v: f32| if hdr { v } else { srgb_to_linear(v) };
            Vec4::new(c(p[0]), c(p[1]), c(p[2]), p[3])
        })
        .collect();
    Ok(Texture {
        width,
        height,
        texels,
    })
}
