//! The scene's geometry for the page, as the loader sees it: its triangles
//! with their shading normals, each material's base colour and opacity
//! (glass translucent), and at every vertex the probes' irradiance for its
//! normal — so the page can shade surfaces by the probes. Large triangles
//! are subdivided (up to [`MAX_TRIANGLES`] in all) so that per-vertex
//! irradiance follows the probes' field across a wall.

use crate::query::{Probes, QueryError};
use glam::Vec3;
use probekit::scene::{AlphaMode, Scene};

/// Most triangles sent after subdivision (about 13 MB of vertices).
pub const MAX_TRIANGLES: usize = 200_000;
/// Finest subdivision: edges of about this length (metres).
pub const FINEST_EDGE: f32 = 0.1;
/// Floats per vertex: position 3, normal 3, colour RGBA 4, irradiance 3.
pub const VERTEX_FLOATS: usize = 13;
/// How far off the surface, along its normal, the per-vertex irradiance
/// is queried (metres): the probes' field just in front of the surface.
pub const SURFACE_OFFSET: f32 = 0.02;

/// Segments per edge of each triangle: the smallest edge target `t ≥
/// FINEST_EDGE` (found by bisection) for which `Σ ⌈longest edge / t⌉²` stays
/// within [`MAX_TRIANGLES`] (at least 1 segment each).
fn segments(scene: &Scene) -> Vec<u32> {
    let longest: Vec<f32> = scene
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.positions;
            (a - b).length().max((b - c).length()).max((c - a).length())
        })
        .collect();
    let count = |edge: f32| -> usize {
        longest
            .iter()
            .map(|&l| {
                let n = (l / edge).ceil().clamp(1.0, 256.0) as usize;
                n * n
            })
            .sum()
    };
    let mut edge = FINEST_EDGE;
    if count(edge) > MAX_TRIANGLES {
        let (mut lo, mut hi) = (FINEST_EDGE, FINEST_EDGE);
        while count(hi) > MAX_TRIANGLES && hi < 1e6 {
            lo = hi;
            hi *= 2.0;
        }
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if count(mid) > MAX_TRIANGLES {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        edge = hi;
    }
    longest
        .iter()
        .map(|&l| (l / edge).ceil().clamp(1.0, 256.0) as u32)
        .collect()
}

/// The display colour (linear base colour times the texture's mean) and
/// opacity of a material.
fn material_color(scene: &Scene, material: u32) -> [f32; 4] {
    let Some(m) = scene.materials.get(material as usize) else {
        return [0.8, 0.8, 0.8, 1.0];
    };
    let mut rgb = m.base_color;
    let mut alpha = m.alpha;
    if let Some(t) = m
        .base_color_texture
        .and_then(|i| scene.textures.get(i as usize))
    {
        let mean = t.mean();
        rgb *= mean.truncate();
        alpha *= mean.w;
    }
    let opacity = match m.alpha_mode {
        AlphaMode::Opaque => 1.0,
        AlphaMode::Mask { cutoff } => {
            if alpha >= cutoff {
                1.0
            } else {
                0.0
            }
        }
        AlphaMode::Blend => alpha.clamp(0.0, 1.0),
    };
    // Emitters show their emission on top of their colour.
    let rgb = rgb + m.emissive.min(Vec3::ONE);
    [rgb.x, rgb.y, rgb.z, opacity]
}

/// The geometry buffer (little-endian): `b"PKVG"`, u32 version 1, u32
/// vertex count `V`, u32 index count `I`, then `V ×`
/// [`VERTEX_FLOATS`] `f32` and `I` `u32` (three per triangle, counter-
/// clockwise as in the scene). Fully transparent (masked-out) triangles are
/// left out.
pub fn build(scene: &Scene, probes: &Probes) -> Result<Vec<u8>, QueryError> {
    let segs = segments(scene);
    let mut positions: Vec<Vec3> = Vec::new();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut colors: Vec<[f32; 4]> = Vec::new();
    let mut query: Vec<(Vec3, Vec3)> = Vec::new();
    let mut indices: Vec<u32> = Vec::new();
    for (t, &n) in scene.triangles.iter().zip(&segs) {
        let color = material_color(scene, t.material);
        if color[3] <= 0.0 {
            continue;
        }
        let geo = t.geometric_normal();
        let base = positions.len() as u32;
        // Vertex (i, j) of the subdivision: barycentric (1 − (i+j)/n, i/n, j/n).
        let row_start = |i: u32| -> u32 { i * (n + 1) - i * (i.saturating_sub(1)) / 2 };
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (b1, b2) = (i as f32 / n as f32, j as f32 / n as f32);
                let b0 = 1.0 - b1 - b2;
                let p = t.positions[0] * b0 + t.positions[1] * b1 + t.positions[2] * b2;
                let sn = t.normals[0] * b0 + t.normals[1] * b1 + t.normals[2] * b2;
                let sn = sn.try_normalize().unwrap_or(geo);
                // Query in front of the side the shading normal faces.
                let side = if geo.dot(sn) < 0.0 { -geo } else { geo };
                positions.push(p);
                normals.push(sn);
                colors.push(color);
                query.push((p + side * SURFACE_OFFSET, sn));
            }
        }
        for i in 0..n {
            for j in 0..(n - i) {
                let v = |i: u32, j: u32| base + row_start(i) + j;
                indices.extend([v(i, j), v(i + 1, j), v(i, j + 1)]);
                if j + 1 < n - i {
                    indices.extend([v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)]);
                }
            }
        }
    }
    let irradiance = probes.irradiance_many(&query)?;
    let mut out = Vec::with_capacity(16 + positions.len() * VERTEX_FLOATS * 4 + indices.len() * 4);
    out.extend_from_slice(b"PKVG");
    for v in [1u32, positions.len() as u32, indices.len() as u32] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for k in 0..positions.len() {
        let e = irradiance[k].max(Vec3::ZERO);
        let floats = positions[k]
            .to_array()
            .into_iter()
            .chain(normals[k].to_array())
            .chain(colors[k])
            .chain(e.to_array());
        for f in floats {
            out.extend_from_slice(&f.to_le_bytes());
        }
    }
    for i in indices {
        out.extend_from_slice(&i.to_le_bytes());
    }
    Ok(out)
}

/// The scene's lights for the page: kind, position, direction (the way
/// the light travels), colour, intensity, radius.
pub fn lights(scene: &Scene) -> serde_json::Value {
    use probekit::scene::LightKind;
    let list: Vec<serde_json::Value> = scene
        .lights
        .iter()
        .map(|l| {
            let kind = match l.kind {
                LightKind::Point => "point",
                LightKind::Spot => "spot",
                LightKind::Directional => "directional",
                LightKind::Sphere => "sphere",
                LightKind::Disk => "disk",
            };
            serde_json::json!({
                "kind": kind,
                "position": l.position.to_array(),
                "direction": l.direction.to_array(),
                "color": l.color.to_array(),
                "intensity": l.intensity,
                "radius": l.radius,
                "group": l.group,
            })
        })
        .collect();
    serde_json::Value::Array(list)
}

/// The built-in car mesh (`builtin:car` of probekit's rigs) as flat arrays:
/// `{"positions":[x,y,z,…],"normals":[…],"indices":[…]}`, metres, origin on
/// the ground under its middle, long in x.
pub fn car() -> serde_json::Value {
    let m = probekit::rig::mesh::car();
    let flat = |v: &[Vec3]| -> Vec<f32> { v.iter().flat_map(|p| p.to_array()).collect() };
    let idx: Vec<u32> = m.indices.iter().flatten().copied().collect();
    serde_json::json!({
        "positions": flat(&m.positions),
        "normals": flat(&m.normals),
        "indices": idx,
    })
}
