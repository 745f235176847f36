//! glTF 2.0 loader (`.gltf` + external buffers, `.glb`) on the `gltf` crate.
//!
//! Mapping: `baseColorFactor` (+ texture, sRGB-decoded) → albedo and alpha; `alphaMode`
//! BLEND/MASK (+ `alphaCutoff`, default 0.5) → [`AlphaMode`]; `emissiveFactor` (+ texture,
//! sRGB-decoded) × `KHR_materials_emissive_strength` → emitted radiance; `KHR_lights_punctual`
//! point/spot (candela) and directional (lux) lights, which shine along the node's −Z.
//! Node transforms are applied; mirroring transforms reverse the vertex order (glTF 2.0 §3.7.4).

use super::{
    srgb_to_linear, AlphaMode, Light, LightKind, Material, Parts, SceneError, SceneWarning,
    Texture, Triangle,
};
use glam::{Mat4, Vec2, Vec3, Vec4};
use std::collections::HashMap;
use std::path::Path;

pub(crate) fn load(path: &Path) -> Result<Parts, SceneError> {
    let gltf_err = |message: String| SceneError::Gltf {
        path: path.into(),
        message,
    };
    // A `.glb` must start with the binary container's magic; else the glTF
    // crate would parse it as JSON and report a JSON error.
    let is_glb = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if is_glb {
        let mut magic = [0u8; 4];
        let read = std::fs::File::open(path)
            .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut magic));
        if read.is_err() || &magic != b"glTF" {
            return Err(gltf_err(
                "not a binary glTF (bad magic: a .glb file starts with \"glTF\")".into(),
            ));
        }
    }
    // Open the document first so a missing external buffer or image is reported by name.
    let doc = gltf::Gltf::open(path).map_err(|e| gltf_err(e.to_string()))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let check_uri = |uri: &str| -> Result<(), SceneError> {
        if uri.starts_with("data:") {
            return Ok(());
        }
        let decoded = percent_decode(uri);
        let p = base.join(&decoded);
        if !p.is_file() {
            return Err(SceneError::MissingFile {
                path: p,
                referenced_by: Some(path.into()),
                message: "no such file".into(),
            });
        }
        Ok(())
    };
    for b in doc.buffers() {
        if let gltf::buffer::Source::Uri(uri) = b.source() {
            check_uri(uri)?;
        }
    }
    for i in doc.images() {
        if let gltf::image::Source::Uri { uri, .. } = i.source() {
            check_uri(uri)?;
        }
    }
    let (document, buffers, images) = gltf::import(path).map_err(|e| gltf_err(e.to_string()))?;
    let file = path.display().to_string();
    let mut parts = Parts::default();

    // Textures are decoded once per (image, colour space).
    let mut tex_cache: HashMap<usize, u32> = HashMap::new();
    let mut texture_of = |parts: &mut Parts, image: usize| -> Result<u32, SceneError> {
        if let Some(&t) = tex_cache.get(&image) {
            return Ok(t);
        }
        let data = images.get(image).ok_or_else(|| SceneError::Texture {
            path: path.into(),
            message: format!("image {image} missing"),
        })?;
        let tex = decode_image(data).map_err(|message| SceneError::Texture {
            path: path.into(),
            message: format!("image {image}: {message}"),
        })?;
        parts.textures.push(tex);
        let idx = parts.textures.len() as u32 - 1;
        tex_cache.insert(image, idx);
        Ok(idx)
    };

    // Base-colour texture coordinate set per material (we keep one uv set per vertex).
    let mut uv_set = Vec::new();
    for m in document.materials() {
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, a] = pbr.base_color_factor();
        let base_color_texture = match pbr.base_color_texture() {
            Some(info) => Some(texture_of(&mut parts, info.texture().source().index())?),
            None => None,
        };
        uv_set.push(pbr.base_color_texture().map_or(0, |i| i.tex_coord()));
        let emissive_texture = match m.emissive_texture() {
            Some(info) => Some(texture_of(&mut parts, info.texture().source().index())?),
            None => None,
        };
        let strength = m.emissive_strength().unwrap_or(1.0);
        let alpha_mode = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask {
                cutoff: m.alpha_cutoff().unwrap_or(0.5),
            },
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        };
        parts.materials.push(Material {
            name: m
                .name()
                .map(str::to_owned)
                .unwrap_or_else(|| format!("material{}", m.index().unwrap_or(0))),
            base_color: Vec3::new(r, g, b),
            base_color_texture,
            alpha: a,
            alpha_mode,
            emissive: Vec3::from(m.emissive_factor()) * strength,
            emissive_texture,
            double_sided: m.double_sided(),
        });
    }
    // Primitives without a material use the glTF default material (white, opaque).
    let default_material = parts.materials.len() as u32;
    parts.materials.push(Material {
        name: "gltf-default".into(),
        base_color: Vec3::ONE,
        ..Material::default()
    });

    let scene = document
        .default_scene()
        .or_else(|| document.scenes().next());
    let roots: Vec<gltf::Node> = match &scene {
        Some(s) => s.nodes().collect(),
        None => {
            // No scene: every node that is nobody's child is a root.
            let mut is_child = vec![false; document.nodes().len()];
            for n in document.nodes() {
                for c in n.children() {
                    if let Some(f) = is_child.get_mut(c.index()) {
                        *f = true;
                    }
                }
            }
            document.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    let mut stack: Vec<(gltf::Node, Mat4)> =
        roots.into_iter().map(|n| (n, Mat4::IDENTITY)).collect();
    let mut visited = 0usize;
    while let Some((node, parent)) = stack.pop() {
        visited += 1;
        if visited > 1_000_000 {
            return Err(gltf_err("node hierarchy too deep or cyclic".into()));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            let normal_m = world.inverse().transpose();
            let flip = world.determinant() < 0.0;
            for prim in mesh.primitives() {
                let obj_name = format!(
                    "{file}: {}#{}",
                    node.name().or(mesh.name()).unwrap_or("mesh"),
                    prim.index()
                );
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    parts.warnings.push(SceneWarning::Ignored {
                        file: file.clone(),
                        what: format!("{obj_name}: non-triangle primitive ({:?})", prim.mode()),
                    });
                    continue;
                }
                let material = prim
                    .material()
                    .index()
                    .map_or(default_material, |i| i as u32);
                let set = uv_set.get(material as usize).copied().unwrap_or(0);
                let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                let Some(pos) = reader.read_positions() else {
                    parts.warnings.push(SceneWarning::Ignored {
                        file: file.clone(),
                        what: format!("{obj_name}: primitive without positions"),
                    });
                    continue;
                };
                let pos: Vec<Vec3> = pos.map(Vec3::from).collect();
                let nrm: Option<Vec<Vec3>> =
                    reader.read_normals().map(|n| n.map(Vec3::from).collect());
                let uvs: Option<Vec<Vec2>> = reader
                    .read_tex_coords(set)
                    .map(|t| t.into_f32().map(Vec2::from).collect());
                let indices: Vec<u32> = match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => (0..pos.len() as u32).collect(),
                };
                let mut tris = Vec::with_capacity(indices.len() / 3);
                for f in indices.chunks_exact(3) {
                    let idx = [f[0] as usize, f[1] as usize, f[2] as usize];
                    if idx.iter().any(|&i| i >= pos.len()) {
                        return Err(gltf_err(format!("{obj_name}: index out of range")));
                    }
                    let mut t = Triangle {
                        positions: idx.map(|i| pos[i]),
                        normals: match &nrm {
                            Some(n) if idx.iter().all(|&i| i < n.len()) => idx.map(|i| n[i]),
                            _ => [Vec3::ZERO; 3],
                        },
                        uvs: match &uvs {
                            Some(u) if idx.iter().all(|&i| i < u.len()) => idx.map(|i| u[i]),
                            _ => [Vec2::ZERO; 3],
                        },
                        material,
                    };
                    super::transform_triangle(&mut t, &world, &normal_m, flip);
                    tris.push(t);
                }
                parts.objects.push((obj_name, tris));
            }
        }
        if let Some(light) = node.light() {
            let position = world.transform_point3(Vec3::ZERO);
            let direction = world
                .transform_vector3(Vec3::NEG_Z)
                .normalize_or(Vec3::NEG_Z);
            let (kind, inner, outer) = match light.kind() {
                gltf::khr_lights_punctual::Kind::Point => (LightKind::Point, 0.0, 0.0),
                gltf::khr_lights_punctual::Kind::Directional => (LightKind::Directional, 0.0, 0.0),
                gltf::khr_lights_punctual::Kind::Spot {
                    inner_cone_angle,
                    outer_cone_angle,
                } => (LightKind::Spot, inner_cone_angle, outer_cone_angle),
            };
            parts.lights.push(Light {
                kind,
                position,
                direction: if matches!(kind, LightKind::Point) {
                    Vec3::NEG_Y
                } else {
                    direction
                },
                color: Vec3::from(light.color()),
                intensity: light.intensity(),
                radius: 0.0,
                inner_angle: inner,
                outer_angle: outer,
                group: None,
                mode: crate::scene::LightMode::Auto,
                angular_diameter: 0.0,
            });
        }
        for child in node.children() {
            stack.push((child, world));
        }
    }
    Ok(parts)
}

/// Decodes glTF image data to linear RGBA: colour channels are sRGB-decoded (base colour and
/// emissive textures are sRGB in glTF), alpha stays linear; 16-bit and float data are taken as
/// already linear-ish encodings of the same (16-bit integer: sRGB-decoded too; float: linear).
fn decode_image(data: &gltf::image::Data) -> Result<Texture, String> {
    use gltf::image::Format as F;
    let (w, h) = (data.width, data.height);
    let n = w as usize * h as usize;
    let px = &data.pixels;
    let (channels, bytes_per): (usize, usize) = match data.format {
        F::R8 => (1, 1),
        F::R8G8 => (2, 1),
        F::R8G8B8 => (3, 1),
        F::R8G8B8A8 => (4, 1),
        F::R16 => (1, 2),
        F::R16G16 => (2, 2),
        F::R16G16B16 => (3, 2),
        F::R16G16B16A16 => (4, 2),
        F::R32G32B32FLOAT => (3, 4),
        F::R32G32B32A32FLOAT => (4, 4),
    };
    if px.len() < n * channels * bytes_per {
        return Err("pixel data shorter than width × height".into());
    }
    let read = |i: usize| -> f32 {
        match bytes_per {
            1 => px[i] as f32 / 255.0,
            2 => u16::from_le_bytes([px[2 * i], px[2 * i + 1]]) as f32 / 65535.0,
            _ => f32::from_le_bytes([px[4 * i], px[4 * i + 1], px[4 * i + 2], px[4 * i + 3]]),
        }
    };
    let srgb = bytes_per < 4;
    let mut texels = Vec::with_capacity(n);
    for p in 0..n {
        let c = |k: usize| read(p * channels + k);
        let (r, g, b, a) = match channels {
            1 => (c(0), c(0), c(0), 1.0),
            2 => (c(0), c(0), c(0), c(1)),
            3 => (c(0), c(1), c(2), 1.0),
            _ => (c(0), c(1), c(2), c(3)),
        };
        let lin = |v: f32| if srgb { srgb_to_linear(v) } else { v };
        texels.push(Vec4::new(lin(r), lin(g), lin(b), a));
    }
    Ok(Texture {
        width: w,
        height: h,
        texels,
    })
}

/// Minimal percent-decoding of a relative URI (glTF URIs may escape spaces etc.).
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let Ok(v) = u8::from_str_radix(&s[i + 1..i + 3], 16) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}
