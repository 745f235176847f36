//! Loading: scene errors and warnings, [`Scene::load`] and the finalising
//! of loaded parts ([`Scene::from_triangles`], validation, winding,
//! emissive triangles, bounds).

use super::geometry::{check_winding, is_degenerate};
use super::{
    demo, gltf_load, obj_load, scene_file, Aabb, BakeSettings, EmissiveTriangle, EnvironmentDesc,
    Light, LightKind, Material, MeshObject, Region, Scene, Texture, Triangle, BUILTIN_DEMO,
};
use glam::{Mat4, Vec2, Vec3};
use std::path::{Path, PathBuf};

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
