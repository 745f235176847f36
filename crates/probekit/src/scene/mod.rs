//! # Scenes: what the baker sees
//!
//! A [`Scene`] is a flat list of world-space triangles with materials, the lights, the environment
//! description, bake defaults and named regions. It is loaded from
//!
//! * glTF 2.0 (`.gltf` with external or embedded buffers, `.glb`), see [`Scene::load`];
//! * Wavefront OBJ + MTL (`.obj`);
//! * probekit's scene file (`.toml`), which composes meshes and adds lights, environment,
//!   bake settings and regions — the format is specified in `docs/scene-format.md`;
//! * the built-in demo scene, by the name [`BUILTIN_DEMO`] (`"builtin:demo"`), see [`demo`].
//!
//! Conventions (see [`probekit_sh`]'s crate docs): right-handed, +Y up, metres, linear RGB.
//! Units are photometric in name and radiometric in value: 1 cd is one unit of radiant
//! intensity, 1 lx one unit of irradiance, with no 683 lm/W factor, so lights, emissive
//! surfaces (radiance) and environment maps (radiance) add up directly.
//!
//! Texture coordinates follow glTF: `(0, 0)` is the top-left texel of the image, `v` grows
//! downwards. OBJ's `vt` (origin bottom-left) is converted with `v ← 1 − v` on load.
//!
//! Loading never panics on bad input: it returns a [`SceneError`] that names the file and what
//! is wrong. Recoverable problems (degenerate triangles, inconsistent winding, ignored
//! primitives) become [`SceneWarning`]s in [`Scene::warnings`].

pub mod demo;
mod geometry;
mod gltf_load;
mod hash;
mod light;
mod loading;
mod material;
mod obj_load;
mod scene_file;

pub use geometry::{Aabb, BakeBoxError, MeshObject, Triangle};
pub(crate) use hash::Fnv1a;
pub use light::{EmissiveTriangle, Light, LightKind, LightMode};
pub(crate) use loading::{load_mesh_file, transform_triangle, Parts, SceneExtras};
pub use loading::{SceneError, SceneWarning};
pub use material::{srgb_to_linear, AlphaMode, Material, Texture};

use glam::{Vec2, Vec3};
use std::path::PathBuf;

/// The name under which [`Scene::load`] returns the built-in demo scene ([`Scene::builtin_demo`]).
pub const BUILTIN_DEMO: &str = "builtin:demo";

/// What the scene says about the environment (the radiance arriving from infinitely far away
/// where a ray escapes). Loading the map is the job of the `env` module.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentDesc {
    /// Uniform sky radiance, linear RGB; used when `map` is `None`. Black if the scene has no
    /// `[environment]`.
    pub color: Vec3,
    /// Equirectangular radiance map (three.js convention), already resolved relative to the scene file.
    pub map: Option<PathBuf>,
    /// Multiplier on the map (or on `color`).
    pub intensity: f32,
    /// Rotation of the map about +Y, degrees (positive = counter-clockwise seen from above).
    pub rotation_y_degrees: f32,
}

impl Default for EnvironmentDesc {
    fn default() -> Self {
        EnvironmentDesc {
            color: Vec3::ZERO,
            map: None,
            intensity: 1.0,
            rotation_y_degrees: 0.0,
        }
    }
}

/// The scene file's `[bake]` table: a partial bake recipe
/// (`probekit::recipe`), which a recipe file and command-line flags
/// override. `box`, `samples`, `bounces` and `seed` are also read here
/// (the last three are shorthands of `capture.samples`, `capture.bounces`
/// and `capture.seed`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BakeSettings {
    /// Where to place probes and evaluate (default: the geometry's bounds, see [`Scene::bake_box`]).
    pub r#box: Option<Aabb>,
    /// Samples per probe.
    pub samples: Option<u32>,
    /// Indirect bounces.
    pub bounces: Option<u32>,
    /// Random seed.
    pub seed: Option<u64>,
    /// The other keys of the table as written (`placement`, `capture`,
    /// `blend`, `codec`, `volume`): the recipe layer checks them.
    pub recipe: toml::Table,
}

/// A named axis-aligned part of the scene, for per-region reports.
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    /// Name as given in the scene file.
    pub name: String,
    /// Smallest corner, metres.
    pub min: Vec3,
    /// Largest corner, metres.
    pub max: Vec3,
}

impl Region {
    /// The region as an [`Aabb`].
    pub fn aabb(&self) -> Aabb {
        Aabb::new(self.min, self.max)
    }
}

/// A loaded scene: world-space triangles, materials, lights, environment, bake settings, regions.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Where it came from (file path, or `builtin:demo`).
    pub source: PathBuf,
    /// All triangles, world space, degenerate ones removed.
    pub triangles: Vec<Triangle>,
    /// Materials, indexed by [`Triangle::material`].
    pub materials: Vec<Material>,
    /// Decoded textures, indexed by [`Material::base_color_texture`] / [`Material::emissive_texture`].
    pub textures: Vec<Texture>,
    /// Source objects (contiguous triangle ranges).
    pub objects: Vec<MeshObject>,
    /// Analytic lights.
    pub lights: Vec<Light>,
    /// Triangles whose material emits, with areas (next-event estimation on meshes).
    pub emissive_triangles: Vec<EmissiveTriangle>,
    /// Environment description.
    pub environment: EnvironmentDesc,
    /// Bake defaults.
    pub bake: BakeSettings,
    /// Named regions.
    pub regions: Vec<Region>,
    /// Bounds of all triangles.
    pub bounds: Aabb,
    /// Problems found on load that did not stop it.
    pub warnings: Vec<SceneWarning>,
    /// Per triangle: false where an edge of it is shared with a triangle running it the same way.
    winding_ok: Vec<bool>,
}

impl Scene {
    /// False where triangle `tri` shares an edge with a triangle of the same object that runs the
    /// edge the same way (inconsistent winding): a back-face hit on it says nothing about
    /// inside/outside, so validity tests should not count it. False for an out-of-range index.
    pub fn winding_consistent(&self, tri: u32) -> bool {
        self.winding_ok.get(tri as usize).copied().unwrap_or(false)
    }

    /// The box to place probes in and evaluate: `[bake] box` if given, else [`Scene::bounds`].
    pub fn bake_box(&self) -> Aabb {
        self.bake.r#box.unwrap_or(self.bounds)
    }

    /// The first sphere light whose radius plus `margin` (metres) holds `p`,
    /// if any: the inside of a lamp's emitting sphere, which no ray hits
    /// (sphere lights are not geometry) and where no probe may stand and no
    /// evaluation point may fall.
    pub fn sphere_light_at(&self, p: Vec3, margin: f32) -> Option<&Light> {
        self.lights.iter().find(|l| {
            l.kind == LightKind::Sphere
                && l.radius > 0.0
                && p.distance(l.position) < l.radius + margin
        })
    }

    /// The names of the `[[region]]`s whose box holds `p` (boxes may
    /// overlap), in the scene file's order.
    pub fn region_names_at(&self, p: Vec3) -> Vec<&str> {
        self.regions
            .iter()
            .filter(|r| r.aabb().contains(p))
            .map(|r| r.name.as_str())
            .collect()
    }

    /// Diffuse albedo (linear RGB) of `material` at texture coordinate `uv`.
    pub fn albedo(&self, material: u32, uv: Vec2) -> Vec3 {
        let Some(m) = self.materials.get(material as usize) else {
            return Vec3::ZERO;
        };
        match m
            .base_color_texture
            .and_then(|t| self.textures.get(t as usize))
        {
            Some(tex) => m.base_color * tex.sample(uv).truncate(),
            None => m.base_color,
        }
    }

    /// Opacity in [0, 1] of `material` at `uv`: 1 for opaque, alpha for blend, 0/1 for mask
    /// (see [`AlphaMode`]). A fraction `1 − opacity` of light passes straight through.
    pub fn opacity(&self, material: u32, uv: Vec2) -> f32 {
        let Some(m) = self.materials.get(material as usize) else {
            return 1.0;
        };
        if matches!(m.alpha_mode, AlphaMode::Opaque) {
            return 1.0;
        }
        let a = match m
            .base_color_texture
            .and_then(|t| self.textures.get(t as usize))
        {
            Some(tex) => m.alpha * tex.sample(uv).w,
            None => m.alpha,
        };
        match m.alpha_mode {
            AlphaMode::Opaque => 1.0,
            AlphaMode::Blend => a.clamp(0.0, 1.0),
            AlphaMode::Mask { cutoff } => {
                if a >= cutoff {
                    1.0
                } else {
                    0.0
                }
            }
        }
    }

    /// Emitted radiance (linear RGB) of `material` at `uv` (same on both sides of the surface).
    pub fn emission(&self, material: u32, uv: Vec2) -> Vec3 {
        let Some(m) = self.materials.get(material as usize) else {
            return Vec3::ZERO;
        };
        if !m.is_emissive() {
            return Vec3::ZERO;
        }
        match m
            .emissive_texture
            .and_then(|t| self.textures.get(t as usize))
        {
            Some(tex) => m.emissive * tex.sample(uv).truncate(),
            None => m.emissive,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests_support {
    use std::path::{Path, PathBuf};

    /// A scene of closed, outward-facing boxes `(min, max)` (metres), one
    /// object each, one default material: rooms and walls for visibility tests.
    pub(crate) fn boxes_scene(boxes: &[(glam::Vec3, glam::Vec3)]) -> super::Scene {
        let objects = boxes
            .iter()
            .enumerate()
            .map(|(i, &(lo, hi))| (format!("b{i}"), super::demo::box_triangles(lo, hi, 0)))
            .collect();
        super::Scene::from_triangles("boxes", objects, vec![super::Material::default()], vec![])
            .expect("valid boxes")
    }

    /// `$PROBEKIT_DATA_DIR` if set, else `<workspace root>/../shared/data`, or None when
    /// absent (tests that need it skip with a message).
    pub(crate) fn shared_data() -> Option<PathBuf> {
        let p = match std::env::var_os("PROBEKIT_DATA_DIR") {
            Some(p) => PathBuf::from(p),
            None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"),
        };
        if p.is_dir() {
            Some(p)
        } else {
            use std::io::Write;
            // Straight to stderr: the test harness captures eprint!, and a skip must show.
            let _ = writeln!(std::io::stderr(), "SKIPPED: {} not found", p.display());
            None
        }
    }
}

#[cfg(test)]
mod light_tests;
#[cfg(test)]
mod tests;
