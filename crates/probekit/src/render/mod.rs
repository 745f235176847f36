//! # Pictures of a bake: probes vs path-traced ground truth
//!
//! [`render`] draws a scene from a [`Camera`] three times, side by side:
//!
//! 1. **probes** — primary rays through the [`Tracer`]; every scene surface
//!    is shaded `emission + albedo/π · E_probes(p, n)` (irradiance from the
//!    probes at the hit point, moved 1 cm along the facing normal, for the
//!    facing shading normal), so the probes' lighting shows on the walls too
//!    (walls without a cloud's visibility weighting, distance moments and
//!    cell visibility alike: 1 cm from a wall, the
//!    wall itself fills the probes' distance texels at grazing angles and
//!    the Chebyshev test would drop probes that do see the point — the
//!    runtime applies no DDGI-style normal bias yet; static geometry is lit
//!    by lightmaps in an engine, the test object keeps the weighting);
//!    the test object (albedo [`RenderSettings::albedo`]) is lit only by the
//!    probes.
//! 2. **objects path traced** — the same (the scene still lit by the
//!    probes: the label says so), with the test object's irradiance from
//!    ground-truth path tracing ([`Baker::reference_irradiance`]; how it is
//!    sampled and interpolated: [`objects`]). The object is not in the scene
//!    for either: it receives light and casts no shadow, as probes see it.
//! 3. **error** — relative error `|E_probes − E_truth| / max(|E_truth|,
//!    0.01·mean|E_truth|)` (RGB vector lengths) on the object's pixels as a
//!    heat map from 0 to [`ERROR_SCALE`], the rest of the scene dimmed grey;
//!    a colour bar with the object's rel. RMSE and max below it.
//!
//! Partly transparent surfaces (glass) are composited front to back
//! (`opacity` of the surface's colour, the rest from behind it). Rays that
//! escape see the environment (uniform colour, or the map's nearest texel).
//!
//! Tone mapping: one exposure for all panels, chosen so that the 95th
//! percentile of the path-traced panel's luminance maps to 0.8, then sRGB
//! ([`crate::plot::to_srgb`]). With [`RenderSettings::show_probes`] every
//! probe is a small sphere shaded `E_own(n)/π` (its own SH's irradiance for
//! the sphere normal) and, for clouds, every tetrahedron edge is a thin line,
//! both depth-tested against the scene and object (lines are drawn only
//! where they are in front of what the pixel shows).
//!
//! Rows are rendered in parallel (rayon) and each row uses its own walk
//! state, so the image is the same for any thread count.

pub mod camera;
pub mod objects;

#[cfg(test)]
mod tests;

pub use camera::Camera;
pub use objects::{place_spheres, Sphere, TestObject};

use crate::capture::{BakeError, Baker, ReferenceSettings};
use crate::env::{EnvError, EnvMap};
use crate::plot::{draw_text, heat, save_png, to_srgb, PlotError};
use crate::scene::{Scene, SceneError};
use crate::trace::{Ray, Tracer};
use glam::{Quat, Vec3};
use image::{Rgb, RgbImage};
use probekit_runtime::cloud::WalkState;
use probekit_runtime::{Interp, ProbeCloud, ProbeFile, ProbeFileKind, Volume};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Relative error drawn as the top of the heat map (white) in the error panel.
pub const ERROR_SCALE: f32 = 0.5;
/// Largest panel side, pixels.
pub const MAX_SIDE: u32 = 8192;

/// Why a picture could not be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// Width or height zero or too large.
    #[error("image size {width}x{height}: width and height must be between 1 and {MAX_SIDE}")]
    BadSize {
        /// Requested panel width.
        width: u32,
        /// Requested panel height.
        height: u32,
    },
    /// The camera is unusable.
    #[error("camera: {0}")]
    BadCamera(String),
    /// The probe file is neither a cloud with tetrahedra nor a volume.
    #[error("probes: {0}")]
    Probes(String),
    /// Settings out of range.
    #[error("invalid render settings: {0}")]
    BadSettings(String),
    /// Path tracing the ground truth failed.
    #[error(transparent)]
    Bake(#[from] BakeError),
    /// The test mesh could not be loaded.
    #[error("test object: {0}")]
    Object(#[from] SceneError),
    /// The environment map could not be loaded.
    #[error("environment map: {0}")]
    Env(#[from] EnvError),
    /// The PNG could not be written.
    #[error(transparent)]
    Write(#[from] PlotError),
    /// No view has room for the test objects: no automatic view from free
    /// space inside the bake box, or not the given camera's.
    #[error(
        "no place for the test objects: no view from free space inside the bake box (or from \
         the given camera) has room for them in free space"
    )]
    NoView,
}

/// The test object placed in the scene.
#[derive(Clone, Debug, PartialEq)]
pub enum ObjectKind {
    /// A grid of spheres in free space where the camera sees them
    /// ([`place_spheres`]).
    Spheres {
        /// Columns × rows of the grid.
        grid: (usize, usize),
        /// Radius, metres (reduced to 8 % of the bake box's smallest side).
        radius: f32,
        /// Ground-truth normals per sphere (spherical Fibonacci).
        normals: usize,
    },
    /// A mesh file (OBJ, glTF, GLB; world coordinates as in the file),
    /// loaded with [`Scene::load`].
    Mesh(PathBuf),
}

impl Default for ObjectKind {
    fn default() -> Self {
        ObjectKind::Spheres {
            grid: (3, 2),
            radius: 0.15,
            normals: 64,
        }
    }
}

/// What to draw and how carefully.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Width of each panel, pixels (the PNG is about three times as wide).
    pub width: u32,
    /// Height of each panel, pixels (plus a label strip and a footer).
    pub height: u32,
    /// The camera; `None` picks one with [`Camera::auto`].
    pub camera: Option<Camera>,
    /// The test object.
    pub object: ObjectKind,
    /// Draw the probes (and a cloud's tetrahedra).
    pub show_probes: bool,
    /// Ground truth: most path samples per point (stops earlier at 1 %
    /// precision, not before `min(256, samples)`).
    pub samples: u32,
    /// Ground truth: scattering events per path (use the bake's).
    pub bounces: u32,
    /// Ground truth: random seed.
    pub seed: u64,
    /// Diffuse albedo of the test object.
    pub albedo: f32,
    /// Clouds: brightness exponent of the test object's blend
    /// ([`ProbeCloud::set_brightness_weighting`]; `None`, the default: the
    /// one the file stores with its probe weights, 0 without). Volumes
    /// ignore it.
    pub brightness_weight: Option<f32>,
    /// Clouds: directional brightness exponent of the test object's blend
    /// ([`ProbeCloud::set_directional_brightness`]; `None`, the default:
    /// the one the file stores with its probe weights, 0 without). Volumes
    /// ignore it.
    pub directional_brightness: Option<f32>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 480,
            height: 320,
            camera: None,
            object: ObjectKind::default(),
            show_probes: false,
            samples: 1024,
            bounces: 3,
            seed: 1,
            albedo: 0.8,
            brightness_weight: None,
            directional_brightness: None,
        }
    }
}

/// A finished picture with the numbers behind it.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The composed image (three labelled panels and a footer).
    pub image: RgbImage,
    /// Panel width, pixels.
    pub width: u32,
    /// Panel height, pixels.
    pub height: u32,
    /// The camera used.
    pub camera: Camera,
    /// Linear radiance of the probes panel, row-major (`width × height`).
    pub probes_panel: Vec<Vec3>,
    /// Linear radiance of the path-traced panel.
    pub reference_panel: Vec<Vec3>,
    /// Per pixel: the relative error where the test object is seen, else `None`.
    pub error: Vec<Option<f32>>,
    /// Pixels showing the test object.
    pub object_pixels: usize,
    /// `sqrt(Σ|E_probes − E_truth|² / Σ|E_truth|²)` over object pixels (0 if none).
    pub rel_rmse: f32,
    /// Largest per-pixel relative error (0 if no object pixels).
    pub max_rel_error: f32,
    /// Number of probes (volume samples) in the file.
    pub probes: usize,
    /// Exposure applied before sRGB (multiplier on linear radiance).
    pub exposure: f32,
    /// Test spheres placed (empty for a mesh).
    pub spheres: Vec<Sphere>,
    /// Things worth telling the user (e.g. no room for the test spheres).
    pub warnings: Vec<String>,
}

impl Rendered {
    /// Writes the image as PNG (atomically, [`save_png`]).
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<(), RenderError> {
        Ok(save_png(&self.image, path.as_ref())?)
    }
}

/// The probes, ready to answer irradiance queries.
enum Source {
    Cloud(ProbeCloud),
    Volume(Volume),
}

impl Source {
    /// Cloud when the file has tetrahedra, volume when its kind says so
    /// (the same dispatch as `probekit query`).
    fn from_file(file: &ProbeFile) -> Result<Self, RenderError> {
        if file.tetrahedra.is_some() {
            ProbeCloud::from_file(file)
                .map(Source::Cloud)
                .map_err(|e| RenderError::Probes(e.to_string()))
        } else if file.kind == ProbeFileKind::Volume {
            Volume::from_file(file)
                .map(Source::Volume)
                .map_err(|e| RenderError::Probes(e.to_string()))
        } else {
            Err(RenderError::Probes(
                "the file has no tetrahedra and is not a volume (an unmerged shard part?)".into(),
            ))
        }
    }

    fn irradiance(&self, p: Vec3, n: Vec3, ws: &mut WalkState) -> Vec3 {
        match self {
            Source::Cloud(c) => c.irradiance(p, n, ws),
            Source::Volume(v) => v.irradiance(p, n, Interp::Trilinear).unwrap_or(Vec3::ZERO),
        }
    }
}

/// What a ray escaping the scene sees.
enum Sky {
    Uniform(Vec3),
    Map {
        map: EnvMap,
        scale: f32,
        map_from_world: Quat,
    },
}

impl Sky {
    fn new(scene: &Scene) -> Result<Self, RenderError> {
        let e = &scene.environment;
        Ok(match &e.map {
            None => Sky::Uniform(e.color * e.intensity),
            Some(path) => Sky::Map {
                map: EnvMap::load(path)?,
                scale: e.intensity,
                map_from_world: Quat::from_rotation_y(e.rotation_y_degrees.to_radians()).inverse(),
            },
        })
    }

    fn radiance(&self, d: Vec3) -> Vec3 {
        match self {
            Sky::Uniform(c) => *c,
            Sky::Map {
                map,
                scale,
                map_from_world,
            } => {
                let (x, y) = map.texel_of(*map_from_world * d);
                map.texel(x, y) * *scale
            }
        }
    }
}

/// One drawn probe: position, radius, radiance SH.
struct Glyph {
    center: Vec3,
    sh: Vec<Vec3>,
}

/// Probe spheres and edges for `show_probes`.
struct Overlay {
    glyphs: Vec<Glyph>,
    radius: f32,
    edges: Vec<(Vec3, Vec3)>,
}

impl Overlay {
    fn new(file: &ProbeFile, source: &Source, bake_box: &crate::scene::Aabb) -> Self {
        let n = file.positions.len().max(1);
        let vol = bake_box.size();
        let spacing = (vol.x.max(1e-3) * vol.y.max(1e-3) * vol.z.max(1e-3) / n as f32).cbrt();
        let radius = (0.12 * spacing).min(0.08);
        let glyphs = match source {
            Source::Cloud(c) => c
                .mesh()
                .positions()
                .iter()
                .enumerate()
                .map(|(i, p)| Glyph {
                    center: *p,
                    sh: c.probe_sh(i).to_vec(),
                })
                .collect(),
            Source::Volume(v) => {
                let k = v.coeffs_per_sample();
                let coeffs = file.coefficients.to_f32().unwrap_or_default();
                file.positions
                    .iter()
                    .enumerate()
                    .filter_map(|(i, p)| {
                        coeffs.get(i * k..(i + 1) * k).map(|c| Glyph {
                            center: *p,
                            sh: c.to_vec(),
                        })
                    })
                    .collect()
            }
        };
        let mut edges = Vec::new();
        if let Source::Cloud(c) = source {
            let mut set = std::collections::BTreeSet::new();
            for t in c.mesh().tets() {
                for a in 0..4 {
                    for b in a + 1..4 {
                        let (i, j) = (t[a].min(t[b]), t[a].max(t[b]));
                        set.insert((i, j));
                    }
                }
            }
            let pos = c.mesh().positions();
            edges = set
                .into_iter()
                .map(|(i, j)| (pos[i as usize], pos[j as usize]))
                .collect();
        }
        Overlay {
            glyphs,
            radius,
            edges,
        }
    }
}

/// One pixel's result.
#[derive(Clone, Copy)]
struct Px {
    probes: Vec3,
    reference: Vec3,
    /// `(E_probes, E_truth)` where the object is the nearest thing seen.
    object: Option<(Vec3, Vec3)>,
    /// Distance to what the pixel shows (for depth-tested lines).
    depth: f32,
}

/// Renders the three panels (see the module docs). `progress(done, total)`
/// is called as ground-truth points and then rows finish.
pub fn render(
    scene: &Scene,
    file: &ProbeFile,
    settings: &RenderSettings,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Rendered, RenderError> {
    let (w, h) = (settings.width, settings.height);
    if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
        return Err(RenderError::BadSize {
            width: w,
            height: h,
        });
    }
    if settings.samples == 0 {
        return Err(RenderError::BadSettings(
            "samples must be at least 1".into(),
        ));
    }
    if !(settings.albedo.is_finite() && settings.albedo >= 0.0) {
        return Err(RenderError::BadSettings("albedo must be ≥ 0".into()));
    }
    let mut source = Source::from_file(file)?;
    if let (Source::Cloud(c), Some(a)) = (&mut source, settings.brightness_weight) {
        c.set_brightness_weighting(a)
            .map_err(|e| RenderError::BadSettings(e.to_string()))?;
    }
    if let (Source::Cloud(c), Some(g)) = (&mut source, settings.directional_brightness) {
        c.set_directional_brightness(g)
            .map_err(|e| RenderError::BadSettings(e.to_string()))?;
    }
    // Walls are shaded without visibility or brightness weighting of either
    // kind (module
    // docs): a second view of the cloud with them off, only when the first
    // has one on.
    let unweighted = match &source {
        Source::Cloud(c)
            if c.visibility_enabled()
                || c.cell_visibility_enabled()
                || c.brightness_weighting() > 0.0
                || c.directional_brightness() > 0.0 =>
        {
            let mut c = c.clone();
            c.set_visibility(false);
            c.set_cell_visibility(false);
            c.set_brightness_weighting(0.0)
                .map_err(|e| RenderError::BadSettings(e.to_string()))?;
            c.set_directional_brightness(0.0)
                .map_err(|e| RenderError::BadSettings(e.to_string()))?;
            Some(Source::Cloud(c))
        }
        _ => None,
    };
    let wall_source = unweighted.as_ref().unwrap_or(&source);
    let sky = Sky::new(scene)?;
    let baker = Baker::new(scene)?;
    let tracer = baker.tracer();
    let bake_box = scene.bake_box();
    let aspect = w as f32 / h as f32;
    bake_box
        .check_bake_box()
        .map_err(|e| RenderError::BadSettings(e.to_string()))?;
    if let ObjectKind::Spheres {
        radius, normals, ..
    } = &settings.object
    {
        if *normals < 4 || !(radius.is_finite() && *radius > 0.0) {
            return Err(RenderError::BadSettings(
                "spheres need a positive radius and at least 4 normals".into(),
            ));
        }
    }
    let sphere_radius = match &settings.object {
        ObjectKind::Spheres { radius, .. } => {
            radius.min(0.08 * bake_box.size().min_element().max(1e-3))
        }
        ObjectKind::Mesh(_) => 0.0,
    };
    let mesh_scene = match &settings.object {
        ObjectKind::Mesh(path) => Some(Scene::load(path)?),
        ObjectKind::Spheres { .. } => None,
    };
    // What a view can show: the spheres it has room for, or whether the
    // mesh's centre is in sight and in frame.
    let fits = |cam: &Camera| -> usize {
        match (&settings.object, &mesh_scene) {
            (ObjectKind::Spheres { grid, .. }, _) => place_spheres(
                tracer,
                cam,
                aspect,
                &bake_box,
                sphere_radius,
                grid.0,
                grid.1,
            )
            .len(),
            (_, Some(m)) => usize::from(cam.sees(tracer, m.bounds.center(), aspect)),
            _ => 0,
        }
    };
    let camera = match settings.camera {
        Some(c) => Camera::new(c.eye, c.target, c.fov_y_degrees)?,
        None => Camera::auto(tracer, &bake_box, aspect, &fits).ok_or(RenderError::NoView)?,
    };
    let refs = ReferenceSettings {
        relative_precision: 0.01,
        min_samples: settings.samples.min(256),
        max_samples: settings.samples,
        bounces: settings.bounces,
        seed: settings.seed,
        ..ReferenceSettings::default()
    };
    let warnings = Vec::new();
    let (object, spheres, truth_total) = match (&settings.object, &mesh_scene) {
        (ObjectKind::Spheres { grid, normals, .. }, _) => {
            let spheres = place_spheres(
                tracer,
                &camera,
                aspect,
                &bake_box,
                sphere_radius,
                grid.0,
                grid.1,
            );
            if spheres.is_empty() {
                return Err(RenderError::NoView);
            }
            let total = spheres.len() * normals + h as usize;
            let obj = TestObject::spheres(&baker, spheres.clone(), *normals, &refs, &|d| {
                progress(d, total)
            })?;
            (obj, spheres, spheres_total(total, h))
        }
        (ObjectKind::Mesh(path), None) => {
            return Err(RenderError::BadSettings(format!(
                "test mesh {} was not loaded",
                path.display()
            )))
        }
        (ObjectKind::Mesh(_), Some(mesh_scene)) => {
            let total = mesh_scene.triangles.len() * 3 + h as usize;
            let obj = TestObject::mesh(&baker, mesh_scene, &refs, &|d| {
                progress(d.min(total), total)
            })?;
            (obj, Vec::new(), spheres_total(total, h))
        }
    };
    let total = truth_total + h as usize;
    let overlay = settings
        .show_probes
        .then(|| Overlay::new(file, &source, &bake_box));
    // Per-row candidate probe spheres (screen-space bounding boxes).
    let mut row_glyphs: Vec<Vec<u32>> = vec![Vec::new(); h as usize];
    if let Some(ov) = &overlay {
        let th = (0.5 * camera.fov_y_degrees.to_radians()).tan();
        for (i, g) in ov.glyphs.iter().enumerate() {
            let v = camera.to_view(g.center);
            if v.z <= ov.radius {
                // Behind or around the eye: test it on every row.
                for r in row_glyphs.iter_mut() {
                    r.push(i as u32);
                }
                continue;
            }
            let (_, py) = camera.view_to_pixel(v, w, h);
            let pr = ov.radius / (v.z - ov.radius) / th * 0.5 * h as f32 + 2.0;
            let (y0, y1) = (
                (py - pr).floor().max(0.0),
                (py + pr).ceil().min(h as f32 - 1.0),
            );
            if y1 < 0.0 || y0 > h as f32 - 1.0 {
                continue;
            }
            for r in &mut row_glyphs[y0 as usize..=y1 as usize] {
                r.push(i as u32);
            }
        }
    }
    let rows_done = AtomicUsize::new(0);
    let pixels: Vec<Vec<Px>> = {
        use rayon::prelude::*;
        (0..h)
            .into_par_iter()
            .map(|y| {
                let mut ws = WalkState::new();
                let row = (0..w)
                    .map(|x| {
                        let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5, w, h);
                        shade_pixel(
                            &ray,
                            tracer,
                            scene,
                            (&source, wall_source),
                            &sky,
                            &object,
                            overlay.as_ref().map(|o| (o, &row_glyphs[y as usize][..])),
                            settings.albedo,
                            &mut ws,
                        )
                    })
                    .collect();
                let d = rows_done.fetch_add(1, Ordering::Relaxed) + 1;
                progress(truth_total + d, total);
                row
            })
            .collect()
    };
    let px: Vec<Px> = pixels.into_iter().flatten().collect();
    // Metrics over object pixels.
    let objs: Vec<(Vec3, Vec3)> = px.iter().filter_map(|p| p.object).collect();
    let mean_truth = if objs.is_empty() {
        0.0
    } else {
        objs.iter().map(|(_, t)| t.length() as f64).sum::<f64>() / objs.len() as f64
    } as f32;
    let floor = (0.01 * mean_truth).max(1e-12);
    let rel = |(p, t): (Vec3, Vec3)| (p - t).length() / t.length().max(floor);
    let (mut se, mut st) = (0.0f64, 0.0f64);
    let mut max_rel = 0.0f32;
    for &(p, t) in &objs {
        se += (p - t).length_squared() as f64;
        st += t.length_squared() as f64;
        max_rel = max_rel.max(rel((p, t)));
    }
    let rel_rmse = if st > 0.0 {
        (se / st).sqrt() as f32
    } else {
        0.0
    };
    let error: Vec<Option<f32>> = px.iter().map(|p| p.object.map(rel)).collect();
    // Exposure from the reference panel's 95th percentile luminance.
    let mut lums: Vec<f32> = px
        .iter()
        .map(|p| p.reference.dot(probekit_sh::LUMINANCE))
        .filter(|l| l.is_finite())
        .collect();
    lums.sort_by(f32::total_cmp);
    let p95 = lums
        .get(((0.95 * lums.len() as f32) as usize).min(lums.len().saturating_sub(1)))
        .copied()
        .unwrap_or(0.0);
    let exposure = if p95 > 0.0 { 0.8 / p95 } else { 1.0 };
    let mut image = compose(
        &px,
        &error,
        w,
        h,
        exposure,
        rel_rmse,
        max_rel,
        objs.len(),
        file.positions.len(),
    );
    if let Some(ov) = &overlay {
        let depth: Vec<f32> = px.iter().map(|p| p.depth).collect();
        let top = label_strip(w);
        for panel in 0..2 {
            let ox = panel * (w + GAP);
            for &(a, b) in &ov.edges {
                draw_edge(&mut image, ox, top, &camera, w, h, &depth, a, b);
            }
        }
    }
    Ok(Rendered {
        image,
        width: w,
        height: h,
        camera,
        probes_panel: px.iter().map(|p| p.probes).collect(),
        reference_panel: px.iter().map(|p| p.reference).collect(),
        error,
        object_pixels: objs.len(),
        rel_rmse,
        max_rel_error: max_rel,
        probes: file.positions.len(),
        exposure,
        spheres,
        warnings,
    })
}

/// Ground-truth points of a progress total that also counts `h` rows.
fn spheres_total(total: usize, h: u32) -> usize {
    total - h as usize
}

/// Shades one primary ray for both panels.
#[allow(clippy::too_many_arguments)]
fn shade_pixel(
    ray: &Ray,
    tracer: &Tracer,
    scene: &Scene,
    (source, wall_source): (&Source, &Source),
    sky: &Sky,
    object: &TestObject,
    overlay: Option<(&Overlay, &[u32])>,
    albedo: f32,
    ws: &mut WalkState,
) -> Px {
    let inv_pi = std::f32::consts::FRAC_1_PI;
    // The nearest foreground thing: test object or a probe sphere.
    let obj = object.hit(ray, f32::INFINITY);
    let mut fg_t = obj.map_or(f32::INFINITY, |o| o.t);
    let mut object = obj.map(|o| (source.irradiance(o.point, o.normal, ws), o.truth));
    let mut fg: Option<(Vec3, Vec3)> =
        object.map(|(e, t)| (albedo * inv_pi * e, albedo * inv_pi * t));
    if let Some((ov, cands)) = overlay {
        for &i in cands {
            let g = &ov.glyphs[i as usize];
            let s = Sphere {
                center: g.center,
                radius: ov.radius,
            };
            if let Some(t) = s.intersect(ray) {
                if t < fg_t {
                    fg_t = t;
                    let n = (ray.at(t) - g.center).normalize();
                    let c = probekit_sh::irradiance(&g.sh, n) * inv_pi;
                    fg = Some((c, c));
                    object = None;
                }
            }
        }
    }
    // Scene layers in front of the foreground, front to back.
    let (mut col, mut trans) = (Vec3::ZERO, 1.0f32);
    let mut depth = fg_t;
    let mut r = *ray;
    let mut travelled = 0.0f32;
    let mut escaped = false;
    for _ in 0..16 {
        let Some(hit) = tracer.closest_hit(&r, fg_t - travelled) else {
            escaped = true;
            break;
        };
        let nf = hit.facing_normal();
        let ns = if hit.shading_normal.dot(nf) < 0.0 {
            -hit.shading_normal
        } else {
            hit.shading_normal
        };
        let e = wall_source.irradiance(hit.point + 0.01 * nf, ns, ws);
        let c =
            scene.emission(hit.material, hit.uv) + scene.albedo(hit.material, hit.uv) * inv_pi * e;
        col += trans * hit.opacity * c;
        trans *= 1.0 - hit.opacity;
        let dist = (hit.point - ray.origin).length();
        if hit.opacity >= 0.5 && dist < depth {
            depth = dist;
        }
        if trans < 1e-3 {
            break;
        }
        travelled = dist;
        r = hit.continue_ray(r.direction);
    }
    let (probes, reference) = match (escaped, fg) {
        (true, Some((a, b))) => (col + trans * a, col + trans * b),
        (true, None) => {
            let bg = trans * sky.radiance(ray.direction);
            (col + bg, col + bg)
        }
        (false, _) => (col, col),
    };
    // The object counts for the metrics only where it is seen (not hidden
    // behind an almost opaque layer).
    let object = if escaped && trans >= 0.5 {
        object
    } else {
        None
    };
    Px {
        probes,
        reference,
        object,
        depth,
    }
}

/// Gap between panels, pixels.
const GAP: u32 = 4;
const BG: Rgb<u8> = Rgb([30, 30, 34]);
const FG: Rgb<u8> = Rgb([235, 235, 235]);

/// Font scale for panels of width `w`.
fn text_scale(w: u32) -> i64 {
    if w >= 240 {
        2
    } else {
        1
    }
}

/// Height of the label strip above the panels.
fn label_strip(w: u32) -> u32 {
    9 * text_scale(w) as u32 + 4
}

/// The three panels, labels, colour bar and numbers.
#[allow(clippy::too_many_arguments)]
fn compose(
    px: &[Px],
    error: &[Option<f32>],
    w: u32,
    h: u32,
    exposure: f32,
    rel_rmse: f32,
    max_rel: f32,
    object_pixels: usize,
    probes: usize,
) -> RgbImage {
    let s = text_scale(w);
    let top = label_strip(w);
    let line = 9 * s as u32;
    let footer = 3 * line + 8;
    let total_w = 3 * w + 2 * GAP;
    let mut img = RgbImage::from_pixel(total_w, top + h + footer, BG);
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let p = &px[i];
            img.put_pixel(x, top + y, to_srgb(p.probes * exposure));
            img.put_pixel(w + GAP + x, top + y, to_srgb(p.reference * exposure));
            let e = match error[i] {
                Some(r) => heat(r / ERROR_SCALE),
                None => Vec3::splat(
                    0.35 * (p.reference * exposure)
                        .dot(probekit_sh::LUMINANCE)
                        .clamp(0.0, 1.0),
                ),
            };
            img.put_pixel(2 * (w + GAP) + x, top + y, to_srgb(e));
        }
    }
    // The middle panel path-traces the test objects only; the scene around
    // them is lit by the probes in both panels (module docs).
    for (k, name) in ["probes", "objects path traced", "error"]
        .iter()
        .enumerate()
    {
        draw_text(&mut img, (k as u32 * (w + GAP)) as i64 + 4, 2, name, s, FG);
    }
    draw_text(
        &mut img,
        (w + GAP) as i64 + 4,
        (top + h + 4) as i64,
        "scene: probes",
        s,
        FG,
    );
    // Footer: colour bar under the error panel, numbers below it.
    let (bx, by) = (2 * (w + GAP) + 4, top + h + 4);
    let bw = w.saturating_sub(8).max(1);
    for x in 0..bw {
        let c = to_srgb(heat(x as f32 / (bw.max(2) - 1) as f32));
        for y in by..by + line / 2 + 2 {
            if bx + x < total_w {
                img.put_pixel(bx + x, y, c);
            }
        }
    }
    let ty = (by + line / 2 + 4) as i64;
    draw_text(&mut img, bx as i64, ty, "0", s, FG);
    let scale_label = format!("{:.0}%", ERROR_SCALE * 100.0);
    let sw = crate::plot::font::text_width(&scale_label, s);
    draw_text(&mut img, (bx + bw) as i64 - sw, ty, &scale_label, s, FG);
    let numbers = if object_pixels > 0 {
        format!("RMSE {:.1}%  max {:.0}%", rel_rmse * 100.0, max_rel * 100.0)
    } else {
        "no object pixels".to_string()
    };
    draw_text(&mut img, bx as i64, ty + line as i64 + 2, &numbers, s, FG);
    let info = format!("{probes} probes, exposure x{exposure:.3}");
    draw_text(&mut img, 4, (top + h + 4) as i64, &info, s, FG);
    img
}

/// Draws segment `a`–`b` (world) as a thin line in the panel at `(ox, oy)`,
/// only where it is in front of `depth` (distance from the eye per pixel).
#[allow(clippy::too_many_arguments)]
fn draw_edge(
    img: &mut RgbImage,
    ox: u32,
    oy: u32,
    cam: &Camera,
    w: u32,
    h: u32,
    depth: &[f32],
    a: Vec3,
    b: Vec3,
) {
    const NEAR: f32 = 0.02;
    let (mut va, mut vb) = (cam.to_view(a), cam.to_view(b));
    if va.z < NEAR && vb.z < NEAR {
        return;
    }
    // Clip to the near plane.
    if va.z < NEAR {
        va = va + (vb - va) * ((NEAR - va.z) / (vb.z - va.z));
    } else if vb.z < NEAR {
        vb = vb + (va - vb) * ((NEAR - vb.z) / (va.z - vb.z));
    }
    let (pa, pb) = (cam.view_to_pixel(va, w, h), cam.view_to_pixel(vb, w, h));
    let steps = ((pb.0 - pa.0).abs().max((pb.1 - pa.1).abs()).ceil() as usize).clamp(1, 20_000);
    let (r, u, f) = cam.basis();
    for k in 0..=steps {
        let s = k as f32 / steps as f32;
        let (x, y) = (pa.0 + (pb.0 - pa.0) * s, pa.1 + (pb.1 - pa.1) * s);
        if !(x >= 0.0 && y >= 0.0 && x < w as f32 && y < h as f32) {
            continue;
        }
        // Perspective-correct parameter along the 3-D segment.
        let q = (s / vb.z) / ((1.0 - s) / va.z + s / vb.z);
        let v = va + (vb - va) * q;
        let world = cam.eye + r * v.x + u * v.y + f * v.z;
        let dist = (world - cam.eye).length();
        let (xi, yi) = (x as u32, y as u32);
        let d = depth[(yi * w + xi) as usize];
        if dist < d * (1.0 - 2e-3) - 2e-3 {
            let p = img.get_pixel_mut(ox + xi, oy + yi);
            for c in 0..3 {
                p.0[c] = ((p.0[c] as u32 * 2 + [170u32, 225, 255][c] * 3) / 5) as u8;
            }
        }
    }
}
