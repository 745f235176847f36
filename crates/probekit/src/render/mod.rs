//! # Pictures of a bake: probes vs path-traced ground truth
//!
//! [`render`] draws a scene from a [`Camera`] three times, side by side:
//!
//! 1. **probes** — primary rays through the [`Tracer`](crate::trace::Tracer); every scene surface
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
mod panels;
mod shade;

#[cfg(test)]
mod tests;

pub use camera::Camera;
pub use objects::{place_spheres, Sphere, TestObject};

use crate::capture::{BakeError, Baker, ReferenceSettings};
use crate::env::EnvError;
use crate::plot::{save_png, PlotError};
use crate::scene::{Scene, SceneError};
use glam::Vec3;
use image::RgbImage;
use panels::{compose, draw_edge, label_strip, GAP};
use probekit_runtime::{BlendOverrides, LoadOptions, ObjectState, ProbeFile, Probes};
use shade::{shade_pixel, Overlay, Px, Sky};
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
    /// The probe file cannot be loaded for queries: neither a cloud with
    /// tetrahedra nor a volume, or a blend override out of range.
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
    /// Clouds: overrides of the test object's blend (the default: the
    /// blend the file stores, as an engine loads it; volumes ignore them).
    /// The walls are shaded without visibility and brightness weighting
    /// whatever these say (module docs).
    pub blend: BlendOverrides,
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
            blend: BlendOverrides::default(),
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
    let probes = load_probes(file, settings.blend)?;
    // Walls are shaded without visibility or brightness weighting of either
    // kind (module docs): a second load of the cloud with them off, only
    // when the first has one on.
    let unweighted = match probes.cloud() {
        Some(c)
            if c.visibility_enabled()
                || c.cell_visibility_enabled()
                || c.brightness_weighting() > 0.0
                || c.directional_brightness() > 0.0 =>
        {
            let mut blend = settings.blend;
            blend.distance_moments = Some(false);
            blend.cell_visibility = Some(false);
            blend.brightness_exponent = Some(0.0);
            blend.directional_exponent = Some(0.0);
            Some(load_probes(file, blend)?)
        }
        _ => None,
    };
    let wall_probes = unweighted.as_ref().unwrap_or(&probes);
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
        .then(|| Overlay::new(file, &probes, &bake_box));
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
                let mut ws = ObjectState::new();
                let row = (0..w)
                    .map(|x| {
                        let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5, w, h);
                        shade_pixel(
                            &ray,
                            tracer,
                            scene,
                            (&probes, wall_probes),
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
        file.positions().len(),
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
        probes: file.positions().len(),
        exposure,
        spheres,
        warnings,
    })
}

/// `file` loaded as an engine loads it, with `blend`'s overrides; a file
/// without probes to query (a shard part, rigs only) is an error.
fn load_probes(file: &ProbeFile, blend: BlendOverrides) -> Result<Probes, RenderError> {
    let mut options = LoadOptions::default();
    options.blend = blend;
    let probes =
        Probes::from_file(file, options).map_err(|e| RenderError::Probes(e.to_string()))?;
    if probes.probe_count() == 0 {
        return Err(RenderError::Probes(
            "the file holds no probes to query (rigs only)".into(),
        ));
    }
    Ok(probes)
}

/// Ground-truth points of a progress total that also counts `h` rows.
fn spheres_total(total: usize, h: u32) -> usize {
    total - h as usize
}
