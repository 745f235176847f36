//! The scene's lighting hash ([`Scene::lighting_hash`]) and the FNV-1a hasher
//! behind it.

use super::{AlphaMode, Scene};
use glam::Vec3;

impl Scene {
    /// The **lighting hash**: a stable 64-bit hash of what lights the probes and nothing
    /// else, so that two scenes with the same hash give the same light anywhere. FNV-1a
    /// (64-bit, offset basis 0xcbf29ce484222325, prime 0x100000001b3) over the little-endian
    /// bytes of, in order: every triangle (9 position, 9 normal, 6 uv floats, material u32),
    /// every material (name bytes, base colour, alpha, alpha mode tag + cutoff, emissive,
    /// texture indices or u32::MAX, double-sided byte), every texture (width, height, texels),
    /// every light (kind tag, position, direction, colour, intensity, radius, angles, group
    /// name, mode tag, angular diameter), the environment (colour, intensity, rotation, and
    /// the map file's bytes — by content, not by path).
    ///
    /// Not hashed: where the scene was loaded from (a relative and an absolute path, or a run
    /// from another folder, hash the same), warnings, the `[bake]` table (box, samples,
    /// bounces, seed: how to bake, not what is lit) and `[[region]]`s (names for evaluation).
    /// A file baked from the scene stores this hash; `eval`, `render` and `rig --probes`
    /// refuse a scene whose hash differs. An environment map that cannot be read hashes by
    /// its path (loading it will fail with its own error).
    pub fn lighting_hash(&self) -> u64 {
        let mut h = Fnv1a::new();
        h.u64(self.triangles.len() as u64);
        for t in &self.triangles {
            for p in t.positions.iter().chain(t.normals.iter()) {
                h.vec3(*p);
            }
            for uv in &t.uvs {
                h.f32(uv.x);
                h.f32(uv.y);
            }
            h.u32(t.material);
        }
        h.u64(self.materials.len() as u64);
        for m in &self.materials {
            h.str(&m.name);
            h.vec3(m.base_color);
            h.f32(m.alpha);
            match m.alpha_mode {
                AlphaMode::Opaque => h.u32(0),
                AlphaMode::Mask { cutoff } => {
                    h.u32(1);
                    h.f32(cutoff)
                }
                AlphaMode::Blend => h.u32(2),
            }
            h.vec3(m.emissive);
            h.u32(m.base_color_texture.unwrap_or(u32::MAX));
            h.u32(m.emissive_texture.unwrap_or(u32::MAX));
            h.bytes(&[m.double_sided as u8]);
        }
        h.u64(self.textures.len() as u64);
        for t in &self.textures {
            h.u32(t.width);
            h.u32(t.height);
            for texel in &t.texels {
                for c in texel.to_array() {
                    h.f32(c);
                }
            }
        }
        h.u64(self.lights.len() as u64);
        for l in &self.lights {
            h.u32(l.kind as u32);
            h.vec3(l.position);
            h.vec3(l.direction);
            h.vec3(l.color);
            h.f32(l.intensity);
            h.f32(l.radius);
            h.f32(l.inner_angle);
            h.f32(l.outer_angle);
            match &l.group {
                Some(g) => {
                    h.u32(1);
                    h.str(g)
                }
                None => h.u32(0),
            }
            h.u32(l.mode as u32);
            h.f32(l.angular_diameter);
        }
        let e = &self.environment;
        h.vec3(e.color);
        match &e.map {
            Some(p) => match std::fs::read(p) {
                Ok(bytes) => {
                    h.u32(1);
                    h.u64(bytes.len() as u64);
                    h.bytes(&bytes)
                }
                Err(_) => {
                    h.u32(2);
                    h.str(&p.to_string_lossy())
                }
            },
            None => h.u32(0),
        }
        h.f32(e.intensity);
        h.f32(e.rotation_y_degrees);
        h.0
    }

    /// [`Scene::lighting_hash`] as 16 lowercase hex digits, as files store it.
    pub fn lighting_hash_hex(&self) -> String {
        format!("{:016x}", self.lighting_hash())
    }
}

/// FNV-1a, 64-bit (Fowler, Noll, Vo; IETF draft-eastlake-fnv).
pub(crate) struct Fnv1a(pub(crate) u64);

impl Fnv1a {
    pub(crate) fn new() -> Self {
        Fnv1a(0xcbf2_9ce4_8422_2325)
    }
    pub(crate) fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= x as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    pub(crate) fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn f32(&mut self, v: f32) {
        self.u32(v.to_bits());
    }
    pub(crate) fn vec3(&mut self, v: Vec3) {
        self.f32(v.x);
        self.f32(v.y);
        self.f32(v.z);
    }
    pub(crate) fn str(&mut self, s: &str) {
        self.u64(s.len() as u64);
        self.bytes(s.as_bytes());
    }
}
