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
mod gltf_load;
mod obj_load;
mod scene_file;

use glam::{Mat4, Vec2, Vec3, Vec4};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The name under which [`Scene::load`] returns the built-in demo scene ([`Scene::builtin_demo`]).
pub const BUILTIN_DEMO: &str = "builtin:demo";

/// An axis-aligned box, `min` ≤ `max` componentwise, in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (min = +∞, max = −∞); growing it by any point gives that point.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// A box from two corners (ordered componentwise, so any two opposite corners work).
    pub fn new(a: Vec3, b: Vec3) -> Self {
        Aabb {
            min: a.min(b),
            max: a.max(b),
        }
    }

    /// Grows the box to contain `p`.
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// True when the box contains no point (some `min > max`).
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// True when `p` lies inside or on the boundary.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// True when the closed boxes share a point (touching counts).
    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.cmple(other.max).all() && self.max.cmpge(other.min).all()
    }

    /// `max − min`.
    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }

    /// The centre point.
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Checks that the box can hold a bake: finite, and longer than 0 along
    /// every axis. [`Aabb::EMPTY`] (what [`Scene::bake_box`] gives for a
    /// scene without geometry and without a `[bake] box`) is refused as
    /// [`BakeBoxError::NoGeometry`]. Every placement, volume and evaluation
    /// checks its box with this before any work, so a flat scene (one floor
    /// quad) is refused the same way everywhere.
    pub fn check_bake_box(&self) -> Result<(), BakeBoxError> {
        if *self == Aabb::EMPTY {
            return Err(BakeBoxError::NoGeometry);
        }
        let size = self.size();
        if !(self.min.is_finite() && self.max.is_finite() && size.min_element() > 0.0) {
            return Err(BakeBoxError::Flat {
                min: self.min,
                max: self.max,
            });
        }
        Ok(())
    }
}

/// Why a box cannot hold a bake ([`Aabb::check_bake_box`]).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BakeBoxError {
    /// The scene has no geometry to bound a bake and names no `[bake] box`.
    #[error(
        "no bake box: the scene has no geometry to take one from; give one as `[bake] box` in \
         the scene file"
    )]
    NoGeometry,
    /// The box is not finite or has no extent along some axis (a scene of one
    /// floor quad, without a `[bake] box`).
    #[error(
        "the bake box {min} – {max} is empty or flat (every side must be longer than 0); \
         give a `[bake] box` in the scene file"
    )]
    Flat {
        /// Smallest corner, metres.
        min: Vec3,
        /// Largest corner, metres.
        max: Vec3,
    },
}

/// One triangle in world space, with everything needed to shade a hit on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// Vertex positions in metres. The geometric normal is `(p1 − p0) × (p2 − p0)`
    /// (counter-clockwise seen from the front).
    pub positions: [Vec3; 3],
    /// Unit per-vertex shading normals; the unit geometric normal repeated when the source has
    /// none (or gives a zero / non-finite one).
    pub normals: [Vec3; 3],
    /// Per-vertex texture coordinates in the glTF convention (`(0,0)` = top-left of the image);
    /// zero when the source has none.
    pub uvs: [Vec2; 3],
    /// Index into [`Scene::materials`].
    pub material: u32,
}

impl Triangle {
    /// The unnormalised geometric normal `(p1 − p0) × (p2 − p0)`; its length is twice the area.
    pub fn geometric_normal_unnormalized(&self) -> Vec3 {
        let [a, b, c] = self.positions;
        (b - a).cross(c - a)
    }

    /// The unit geometric normal (zero for a degenerate triangle).
    pub fn geometric_normal(&self) -> Vec3 {
        self.geometric_normal_unnormalized().normalize_or_zero()
    }

    /// Area in m².
    pub fn area(&self) -> f32 {
        0.5 * self.geometric_normal_unnormalized().length()
    }

    /// The point with barycentric weights `(1 − b1 − b2, b1, b2)` for vertices 0, 1, 2.
    pub fn point(&self, b1: f32, b2: f32) -> Vec3 {
        let [a, b, c] = self.positions;
        (1.0 - b1 - b2) * a + b1 * b + b2 * c
    }

    /// Interpolated texture coordinate at barycentrics `(b1, b2)` (weights as in [`Triangle::point`]).
    pub fn uv(&self, b1: f32, b2: f32) -> Vec2 {
        let [a, b, c] = self.uvs;
        (1.0 - b1 - b2) * a + b1 * b + b2 * c
    }
}

/// How a material's alpha (base colour alpha × texture alpha) turns into opacity.
/// Follows glTF `alphaMode`; OBJ `d < 1` (or `Tr > 0`) maps to [`AlphaMode::Blend`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Fully opaque; alpha is ignored.
    Opaque,
    /// Opaque where alpha ≥ `cutoff`, fully transparent elsewhere (glTF `MASK`, default cutoff 0.5).
    Mask {
        /// The alpha threshold.
        cutoff: f32,
    },
    /// Opacity = alpha: a fraction `1 − alpha` of light passes straight through (glTF `BLEND`,
    /// OBJ `d`), e.g. window glass.
    Blend,
}

/// A Lambertian material with optional transparency and emission.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name from the source file (or a generated one).
    pub name: String,
    /// Linear RGB diffuse albedo factor (glTF `baseColorFactor.rgb`, OBJ `Kd`).
    pub base_color: Vec3,
    /// Index into [`Scene::textures`] of the base-colour texture (already linear RGB + alpha),
    /// multiplied with `base_color` and `alpha`.
    pub base_color_texture: Option<u32>,
    /// Alpha factor (glTF `baseColorFactor.a`, OBJ `d` or `1 − Tr`).
    pub alpha: f32,
    /// How alpha becomes opacity.
    pub alpha_mode: AlphaMode,
    /// Emitted radiance factor, linear RGB (glTF `emissiveFactor` × `KHR_materials_emissive_strength`,
    /// OBJ `Ke`). Radiance in the scene's units (W/(sr·m²) with 1 cd = 1 W/sr).
    pub emissive: Vec3,
    /// Index into [`Scene::textures`] of the emissive texture (linear RGB), multiplied with `emissive`.
    pub emissive_texture: Option<u32>,
    /// glTF `doubleSided` (OBJ: false). Informational: the tracer never culls back faces.
    pub double_sided: bool,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".into(),
            base_color: Vec3::splat(0.8),
            base_color_texture: None,
            alpha: 1.0,
            alpha_mode: AlphaMode::Opaque,
            emissive: Vec3::ZERO,
            emissive_texture: None,
            double_sided: false,
        }
    }
}

impl Material {
    /// True when no texel can make this material less than fully opaque, so the tracer may skip
    /// the per-hit opacity lookup.
    pub fn is_opaque(&self) -> bool {
        match self.alpha_mode {
            AlphaMode::Opaque => true,
            AlphaMode::Blend => self.alpha >= 1.0 && self.base_color_texture.is_none(),
            AlphaMode::Mask { cutoff } => self.alpha >= cutoff && self.base_color_texture.is_none(),
        }
    }

    /// True when the material emits light (some emissive factor component > 0).
    pub fn is_emissive(&self) -> bool {
        self.emissive.max_element() > 0.0
    }
}

/// A decoded texture: linear RGB + alpha, row 0 at the top, sampled by [`Texture::sample`].
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width × height` texels, row-major from the top row; linear RGB (sRGB-decoded for colour
    /// textures) and linear alpha.
    pub texels: Vec<Vec4>,
}

impl Texture {
    /// Bilinear lookup with repeat wrapping at glTF texture coordinate `uv` (`(0,0)` = top-left
    /// corner of the image, texel centres at `(i + ½)/width`). Non-finite `uv` reads texel (0, 0).
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        let (w, h) = (self.width as usize, self.height as usize);
        if w == 0 || h == 0 {
            return Vec4::ONE;
        }
        let uv = if uv.is_finite() { uv } else { Vec2::ZERO };
        let x = uv.x * w as f32 - 0.5;
        let y = uv.y * h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let wrap = |i: f32, n: usize| -> usize { (i as i64).rem_euclid(n as i64) as usize };
        let (xa, xb) = (wrap(x0, w), wrap(x0 + 1.0, w));
        let (ya, yb) = (wrap(y0, h), wrap(y0 + 1.0, h));
        let t = |xi: usize, yi: usize| self.texels[yi * w + xi];
        let top = t(xa, ya) * (1.0 - fx) + t(xb, ya) * fx;
        let bottom = t(xa, yb) * (1.0 - fx) + t(xb, yb) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// Mean texel value (used for the emitted power of textured emitters).
    pub fn mean(&self) -> Vec4 {
        if self.texels.is_empty() {
            return Vec4::ONE;
        }
        let sum: Vec4 = self.texels.iter().copied().sum();
        sum / self.texels.len() as f32
    }
}

/// The sRGB transfer function's inverse (IEC 61966-2-1): encoded value in [0, 1] → linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The kind of an analytic light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LightKind {
    /// Isotropic point light; `intensity` in candela (radiant intensity).
    Point,
    /// Spot light: a point light restricted to a cone around `direction` with smooth falloff
    /// between `inner_angle` and `outer_angle` (KHR_lights_punctual); `intensity` in candela on axis.
    Spot,
    /// Light from infinitely far away travelling along `direction`; `intensity` in lux
    /// (irradiance on a surface facing it).
    Directional,
    /// Spherical area light of `radius` at `position`, uniform radiance `I / (π r²)` × `color`,
    /// so that its radiant intensity in every direction is `intensity` candela.
    Sphere,
    /// One-sided disk of `radius` at `position`, emitting into the half-space `direction` points to,
    /// uniform radiance `I / (π r²)` × `color` (intensity `I` candela along its axis).
    Disk,
}

/// An analytic light. Units: see the module docs and `docs/scene-format.md`.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// What kind of light.
    pub kind: LightKind,
    /// Position in metres (ignored for [`LightKind::Directional`]).
    pub position: Vec3,
    /// Unit vector: the way the light travels (directional, spot axis, disk normal). For point and
    /// sphere lights it is unused and set to −Y.
    pub direction: Vec3,
    /// Linear RGB colour multiplier.
    pub color: Vec3,
    /// Candela for point, spot, sphere and disk; lux for directional.
    pub intensity: f32,
    /// Radius in metres for sphere and disk lights; 0 otherwise.
    pub radius: f32,
    /// Spot: angle from the axis (radians) inside which the intensity is full.
    pub inner_angle: f32,
    /// Spot: angle from the axis (radians) outside which the intensity is zero.
    pub outer_angle: f32,
    /// Optional light group name, for capturing lights separately (`bake --groups`).
    pub group: Option<String>,
}

impl Light {
    /// Emitted radiance (linear RGB) of a sphere or disk light: `color · I / (π r²)`.
    /// For a sphere this gives radiant intensity `I` in every direction (projected area π r²);
    /// for a disk, `I` along its axis and `I cos θ` off-axis. Zero for other kinds.
    pub fn radiance(&self) -> Vec3 {
        match self.kind {
            LightKind::Sphere | LightKind::Disk if self.radius > 0.0 => {
                self.color * (self.intensity / (std::f32::consts::PI * self.radius * self.radius))
            }
            _ => Vec3::ZERO,
        }
    }

    /// Spot falloff at angle θ from the axis, given `cos θ`: 1 inside `inner_angle`, 0 outside
    /// `outer_angle`, and in between the KHR_lights_punctual reference ramp
    /// `clamp((cos θ − cos outer) / (cos inner − cos outer), 0, 1)` squared. 1 for non-spot lights.
    pub fn spot_falloff(&self, cos_theta: f32) -> f32 {
        if self.kind != LightKind::Spot {
            return 1.0;
        }
        let (ci, co) = (self.inner_angle.cos(), self.outer_angle.cos());
        if cos_theta >= ci {
            return 1.0;
        }
        if cos_theta <= co || ci <= co {
            return 0.0;
        }
        let x = ((cos_theta - co) / (ci - co)).clamp(0.0, 1.0);
        x * x
    }
}

/// An emissive triangle, for next-event estimation (light sampling) on meshes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissiveTriangle {
    /// Index into [`Scene::triangles`].
    pub triangle: u32,
    /// Area in m².
    pub area: f32,
    /// Mean emitted radiance over the triangle's material (emissive factor × mean of the emissive
    /// texture). The radiance at a point is [`Scene::emission`]; this is for choosing lights.
    pub radiance: Vec3,
}

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

/// Bake defaults from the scene file's `[bake]` table; command-line flags override them.
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

/// A contiguous range of [`Scene::triangles`] that came from one source object (an OBJ `o`/`g`
/// group, a glTF mesh primitive, a demo-scene box). Winding is checked per object.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshObject {
    /// `file: object name`.
    pub name: String,
    /// First triangle index.
    pub first: u32,
    /// Number of triangles.
    pub count: u32,
}

/// A problem found on load that did not stop it.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum SceneWarning {
    /// Zero-area triangles were dropped.
    DegenerateTriangles {
        /// The file (or mesh) they came from.
        mesh: String,
        /// How many were dropped.
        count: usize,
    },
    /// Some edges are run the same way by the two triangles sharing them.
    InconsistentWinding {
        /// The file (or mesh) they came from.
        mesh: String,
        /// Number of such edges.
        edges: usize,
        /// Number of triangles touching such an edge (flagged, see [`Scene::winding_consistent`]).
        triangles: usize,
    },
    /// Something in the input was skipped (non-triangle primitives, unsupported extension, …).
    Ignored {
        /// The file it came from.
        file: String,
        /// What was skipped.
        what: String,
    },
}

impl std::fmt::Display for SceneWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SceneWarning::DegenerateTriangles { mesh, count } => {
                write!(f, "{mesh}: dropped {count} degenerate (zero-area) triangle(s)")
            }
            SceneWarning::InconsistentWinding { mesh, edges, triangles } => write!(
                f,
                "{mesh}: {edges} edge(s) run the same way by both triangles sharing them \
                 (inconsistent winding; {triangles} triangle(s) flagged, back-face tests unreliable there)"
            ),
            SceneWarning::Ignored { file, what } => write!(f, "{file}: ignored {what}"),
        }
    }
}

/// Why a scene could not be loaded. Every variant names the file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The extension is none of `.gltf`, `.glb`, `.obj`, `.toml`.
    #[error("{path}: unknown scene file type (expected .gltf, .glb, .obj, .toml or builtin:demo)")]
    UnknownFileType {
        /// The file.
        path: PathBuf,
    },
    /// A file (the scene itself or one it references) does not exist or cannot be read.
    #[error("{path}: cannot read{}: {message}", referenced_by.as_ref().map(|r| format!(" (referenced by {})", r.display())).unwrap_or_default())]
    MissingFile {
        /// The missing file.
        path: PathBuf,
        /// The file that references it, if any.
        referenced_by: Option<PathBuf>,
        /// The operating system's message.
        message: String,
    },
    /// The glTF file is malformed.
    #[error("{path}: broken glTF: {message}")]
    Gltf {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The OBJ or MTL file is malformed.
    #[error("{path}: broken OBJ: {message}")]
    Obj {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A texture could not be decoded.
    #[error("{path}: cannot decode texture: {message}")]
    Texture {
        /// The texture file (or the glTF holding it).
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The scene file is not valid TOML or does not follow `docs/scene-format.md`.
    #[error("{path}: {message}")]
    SceneFile {
        /// The scene file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A vertex position is NaN or infinite.
    #[error("{path}: mesh '{mesh}' has a NaN or infinite vertex position")]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// The mesh (object) name.
        mesh: String,
    },
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

/// What a single-file loader hands back before the scene is finalised (indices are local).
#[derive(Default)]
pub(crate) struct Parts {
    pub objects: Vec<(String, Vec<Triangle>)>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub lights: Vec<Light>,
    pub warnings: Vec<SceneWarning>,
}

impl Parts {
    /// Appends `other`, remapping its material and texture indices, after transforming it by
    /// `world_from_mesh`.
    pub(crate) fn append(&mut self, mut other: Parts, world_from_mesh: Mat4) {
        let mat_base = self.materials.len() as u32;
        let tex_base = self.textures.len() as u32;
        for m in &mut other.materials {
            m.base_color_texture = m.base_color_texture.map(|t| t + tex_base);
            m.emissive_texture = m.emissive_texture.map(|t| t + tex_base);
        }
        let normal_from_mesh = world_from_mesh.inverse().transpose();
        let flip = world_from_mesh.determinant() < 0.0;
        for (name, tris) in &mut other.objects {
            let _ = name;
            for t in tris.iter_mut() {
                t.material += mat_base;
                transform_triangle(t, &world_from_mesh, &normal_from_mesh, flip);
            }
        }
        for l in &mut other.lights {
            l.position = world_from_mesh.transform_point3(l.position);
            if l.kind != LightKind::Point && l.kind != LightKind::Sphere {
                l.direction = world_from_mesh
                    .transform_vector3(l.direction)
                    .normalize_or(l.direction);
            }
        }
        self.objects.extend(other.objects);
        self.materials.extend(other.materials);
        self.textures.extend(other.textures);
        self.lights.extend(other.lights);
        self.warnings.extend(other.warnings);
    }
}

/// Applies a transform to a triangle: points by `m`, normals by `n` (inverse transpose),
/// reversing the vertex order when `m` mirrors so the front face stays the front face.
pub(crate) fn transform_triangle(t: &mut Triangle, m: &Mat4, n: &Mat4, flip: bool) {
    for i in 0..3 {
        t.positions[i] = m.transform_point3(t.positions[i]);
        t.normals[i] = n.transform_vector3(t.normals[i]).normalize_or_zero();
    }
    if flip {
        t.positions.swap(1, 2);
        t.normals.swap(1, 2);
        t.uvs.swap(1, 2);
    }
}

impl Scene {
    /// Loads a scene by file path (`.gltf`, `.glb`, `.obj`, `.toml`) or the name `builtin:demo`.
    pub fn load(path_or_name: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path_or_name.as_ref();
        if path.as_os_str() == BUILTIN_DEMO {
            return Ok(Scene::builtin_demo());
        }
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("toml") => scene_file::load(path),
            Some("gltf") | Some("glb") | Some("obj") => {
                let parts = load_mesh_file(path)?;
                Scene::from_parts(path, parts, SceneExtras::default())
            }
            _ => Err(SceneError::UnknownFileType { path: path.into() }),
        }
    }

    /// Builds a scene from triangles made in code (test scenes, furnaces, benchmarks), with the
    /// same validation as loading: non-finite vertices are an error, degenerate triangles are
    /// dropped with a warning, winding is checked per object, emissive triangles and bounds are
    /// collected. `objects` are `(name, triangles)`; triangle material indices index `materials`
    /// (out-of-range ones get a default grey material). Environment, bake settings and regions
    /// start empty; set the public fields afterwards.
    pub fn from_triangles(
        name: &str,
        objects: Vec<(String, Vec<Triangle>)>,
        materials: Vec<Material>,
        lights: Vec<Light>,
    ) -> Result<Scene, SceneError> {
        let parts = Parts {
            objects,
            materials,
            lights,
            ..Parts::default()
        };
        Scene::from_parts(Path::new(name), parts, SceneExtras::default())
    }

    /// The built-in demo scene (two rooms, a closet; see [`demo`] for the plan).
    pub fn builtin_demo() -> Scene {
        demo::build()
    }

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

    /// The **lighting hash**: a stable 64-bit hash of what lights the probes and nothing
    /// else, so that two scenes with the same hash give the same light anywhere. FNV-1a
    /// (64-bit, offset basis 0xcbf29ce484222325, prime 0x100000001b3) over the little-endian
    /// bytes of, in order: every triangle (9 position, 9 normal, 6 uv floats, material u32),
    /// every material (name bytes, base colour, alpha, alpha mode tag + cutoff, emissive,
    /// texture indices or u32::MAX, double-sided byte), every texture (width, height, texels),
    /// every light (kind tag, position, direction, colour, intensity, radius, angles, group
    /// name), the environment (colour, intensity, rotation, and the map file's bytes — by
    /// content, not by path).
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

    /// Finalises loaded parts: validates positions, drops degenerate triangles, checks winding,
    /// collects emissive triangles, computes bounds.
    pub(crate) fn from_parts(
        path: &Path,
        parts: Parts,
        extras: SceneExtras,
    ) -> Result<Scene, SceneError> {
        let Parts {
            objects,
            mut materials,
            textures,
            lights,
            mut warnings,
        } = parts;
        let mut triangles = Vec::new();
        let mut objs = Vec::new();
        let mut winding_ok = Vec::new();
        // Triangles without a valid material index get a default material.
        let mut default_material: Option<u32> = None;
        for (name, tris) in objects {
            let first = triangles.len() as u32;
            let mut degenerate = 0usize;
            let mut kept = Vec::with_capacity(tris.len());
            for mut t in tris {
                if !t.positions.iter().all(|p| p.is_finite()) {
                    return Err(SceneError::NonFinite {
                        path: path.into(),
                        mesh: name,
                    });
                }
                if is_degenerate(&t) {
                    degenerate += 1;
                    continue;
                }
                let ng = t.geometric_normal();
                for n in &mut t.normals {
                    if !n.is_finite() || n.length_squared() < 1e-12 {
                        *n = ng;
                    } else {
                        *n = n.normalize();
                    }
                }
                for uv in &mut t.uvs {
                    if !uv.is_finite() {
                        *uv = Vec2::ZERO;
                    }
                }
                if t.material as usize >= materials.len() {
                    let d = *default_material.get_or_insert_with(|| {
                        materials.push(Material::default());
                        materials.len() as u32 - 1
                    });
                    t.material = d;
                }
                kept.push(t);
            }
            if degenerate > 0 {
                warnings.push(SceneWarning::DegenerateTriangles {
                    mesh: name.clone(),
                    count: degenerate,
                });
            }
            let (ok, bad_edges) = check_winding(&kept);
            if bad_edges > 0 {
                warnings.push(SceneWarning::InconsistentWinding {
                    mesh: name.clone(),
                    edges: bad_edges,
                    triangles: ok.iter().filter(|o| !**o).count(),
                });
            }
            winding_ok.extend(ok);
            let count = kept.len() as u32;
            triangles.extend(kept);
            if count > 0 {
                objs.push(MeshObject { name, first, count });
            }
        }
        let mut bounds = Aabb::EMPTY;
        for t in &triangles {
            for p in t.positions {
                bounds.grow(p);
            }
        }
        let mut emissive_triangles = Vec::new();
        for (i, t) in triangles.iter().enumerate() {
            let m = &materials[t.material as usize];
            if m.is_emissive() {
                let mean = m
                    .emissive_texture
                    .and_then(|ti| textures.get(ti as usize))
                    .map_or(Vec3::ONE, |tex| tex.mean().truncate());
                emissive_triangles.push(EmissiveTriangle {
                    triangle: i as u32,
                    area: t.area(),
                    radiance: m.emissive * mean,
                });
            }
        }
        Ok(Scene {
            source: path.into(),
            triangles,
            materials,
            textures,
            objects: objs,
            lights,
            emissive_triangles,
            environment: extras.environment,
            bake: extras.bake,
            regions: extras.regions,
            bounds,
            warnings,
            winding_ok,
        })
    }
}

/// What a scene file adds on top of its meshes.
#[derive(Default)]
pub(crate) struct SceneExtras {
    pub environment: EnvironmentDesc,
    pub bake: BakeSettings,
    pub regions: Vec<Region>,
}

/// Loads one mesh file (glTF, GLB or OBJ) into local parts.
pub(crate) fn load_mesh_file(path: &Path) -> Result<Parts, SceneError> {
    if !path.is_file() {
        return Err(SceneError::MissingFile {
            path: path.into(),
            referenced_by: None,
            message: "no such file".into(),
        });
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("gltf") | Some("glb") => gltf_load::load(path),
        Some("obj") => obj_load::load(path),
        _ => Err(SceneError::UnknownFileType { path: path.into() }),
    }
}

/// Zero area in floating point: twice the area is below f32 rounding of the longest edge squared.
fn is_degenerate(t: &Triangle) -> bool {
    let [a, b, c] = t.positions;
    let cross = (b - a).cross(c - a).length();
    let longest = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    cross.is_nan() || cross <= f32::EPSILON * longest || longest == 0.0
}

/// A vertex identified by the exact bits of its position.
type VertexKey = [u32; 3];
/// Per undirected edge (lo, hi): uses lo→hi, uses hi→lo, and the triangles using it.
type EdgeUses = HashMap<(VertexKey, VertexKey), (u32, u32, Vec<u32>)>;

/// Winding check within one object. Vertices are identified by their exact position bits.
/// A manifold edge (used by exactly two triangles) is inconsistent when both run it in the same
/// direction; edges used by three or more triangles (touching solids, T-junction-free fins)
/// cannot be judged and are skipped. Returns (per-triangle ok flag, number of inconsistent edges).
fn check_winding(tris: &[Triangle]) -> (Vec<bool>, usize) {
    let key = |p: Vec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    let mut edges: EdgeUses = HashMap::new();
    for (i, t) in tris.iter().enumerate() {
        for e in 0..3 {
            let a = key(t.positions[e]);
            let b = key(t.positions[(e + 1) % 3]);
            if a == b {
                continue;
            }
            let (lo, hi, forward) = if a < b { (a, b, true) } else { (b, a, false) };
            let entry = edges.entry((lo, hi)).or_insert((0, 0, Vec::new()));
            if forward {
                entry.0 += 1;
            } else {
                entry.1 += 1;
            }
            entry.2.push(i as u32);
        }
    }
    let mut ok = vec![true; tris.len()];
    let mut bad = 0;
    for (_, (f, r, ts)) in edges {
        if f + r == 2 && (f == 2 || r == 2) {
            bad += 1;
            for t in ts {
                ok[t as usize] = false;
            }
        }
    }
    (ok, bad)
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
mod tests;
