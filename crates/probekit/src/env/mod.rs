//! Environment maps: loading, sampling, SH projection and reference irradiance.
//!
//! An environment map holds linear-RGB **radiance** arriving at a point from
//! every direction. Two layouts are supported:
//!
//! - [`EnvMap`]: equirectangular, in the three.js convention of
//!   [`probekit_sh`]'s crate docs (row 0 at the top; pixel centre `(u, v)` in
//!   `[0,1]²`, `φ = 2π(u − ½)`, latitude `= π(½ − v)`,
//!   `d = (cos lat·cos φ, sin lat, cos lat·sin φ)`). Loaded from Radiance
//!   `.hdr` (the `image` crate) or OpenEXR `.exr` (the `exr` crate).
//! - [`Cubemap`]: six square faces in the DirectX/glTF order
//!   `+X, −X, +Y, −Y, +Z, −Z` (see [`cubemap`] for file names and the texel
//!   → direction table).
//!
//! Both know the **exact** solid angle of each texel, so projection
//! ([`project_equirect`], [`project_cubemap`]) and the brute-force reference
//! ([`reference_irradiance`]) are quadratures with exact weights over the
//! piecewise-constant (nearest-texel) interpretation of the map.
//!
//! Wherever an environment path is accepted, the name [`BUILTIN_SKY`]
//! (`builtin:sky`) selects the procedural sky of [`EnvMap::builtin_sky`].
//!
//! ## Bad input
//! Loading never panics on bad files; it returns an [`EnvError`] that names
//! the path and the problem. Texels must be finite and non-negative: a NaN,
//! infinite or negative texel is an error ([`EnvError::BadTexel`]), not
//! silently clamped, because it usually means a broken file or lossy
//! (DWAA/DWAB) compression artefacts the user should know about.

pub mod cubemap;
mod load;
pub mod project;
pub mod sampler;

pub use cubemap::{CubeFace, Cubemap};
pub use project::{
    project_cubemap, project_equirect, reference_irradiance, reference_irradiance_texels,
    Environment, WeightedTexel,
};
pub use sampler::EnvSampler;

use glam::Vec3;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// The name that selects the built-in procedural sky ([`EnvMap::builtin_sky`])
/// wherever an environment path is accepted.
pub const BUILTIN_SKY: &str = "builtin:sky";

/// Default resolution of `builtin:sky` (width; height is half): 512×256,
/// the resolution of the real maps in `shared/data/env`.
pub const BUILTIN_SKY_WIDTH: usize = 512;

/// Why an environment map could not be loaded or used. Every variant names
/// the offending path.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum EnvError {
    /// The file or folder could not be opened or read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// The extension is not one of `.hdr`, `.exr` (or `.png` for cube faces).
    #[error("{}: unsupported file type (expected .hdr or .exr, a cubemap folder, or builtin:sky)", path.display())]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
    /// The image decoder rejected the file (not an image, truncated, corrupt).
    #[error("{}: not a readable image: {message}", path.display())]
    Decode {
        /// The file.
        path: PathBuf,
        /// The decoder's message.
        message: String,
    },
    /// The EXR uses a compression that could not be decoded.
    #[error("{}: cannot decode EXR compressed with {compression}: {message}; re-save it with ZIP or PIZ compression", path.display())]
    ExrCompression {
        /// The file.
        path: PathBuf,
        /// The compression's name as the EXR header gives it, e.g. `DWAA`.
        compression: String,
        /// The decoder's message.
        message: String,
    },
    /// The map has no texels.
    #[error("{}: zero-size map ({width}×{height})", path.display())]
    ZeroSize {
        /// The file.
        path: PathBuf,
        /// Width in texels.
        width: usize,
        /// Height in texels.
        height: usize,
    },
    /// An equirectangular map whose width is not twice its height, or a
    /// non-square / mismatched cube face.
    #[error("{}: bad dimensions: {message}", path.display())]
    BadShape {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A texel is NaN, infinite or negative.
    #[error("{}: texel ({x}, {y}) is {value:?}: radiance must be finite and non-negative (negative texels often come from lossy DWAA/DWAB compression; clamp them and re-save)", path.display())]
    BadTexel {
        /// The file.
        path: PathBuf,
        /// Column.
        x: usize,
        /// Row (0 = top).
        y: usize,
        /// The texel's RGB value.
        value: [f32; 3],
    },
    /// A cubemap folder lacks a face.
    #[error("{}: cubemap face {face} missing (expected one of {expected})", path.display())]
    MissingFace {
        /// The folder.
        path: PathBuf,
        /// The face, e.g. `+X`.
        face: &'static str,
        /// The accepted file names.
        expected: String,
    },
}

/// An equirectangular linear-RGB radiance map (three.js convention, see the
/// [module docs](self)). `texels[y * width + x]`, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvMap {
    width: usize,
    height: usize,
    texels: Vec<Vec3>,
}

impl EnvMap {
    /// Wraps texels (`texels.len() == width * height`, row 0 at the top).
    /// `path` is only used in error messages.
    ///
    /// Errors: zero size, a length mismatch, or a NaN/infinite/negative texel.
    pub fn from_texels(
        path: &Path,
        width: usize,
        height: usize,
        texels: Vec<Vec3>,
    ) -> Result<Self, EnvError> {
        if width == 0 || height == 0 {
            return Err(EnvError::ZeroSize {
                path: path.to_path_buf(),
                width,
                height,
            });
        }
        if texels.len() != width * height {
            return Err(EnvError::BadShape {
                path: path.to_path_buf(),
                message: format!("{} texels for {width}×{height}", texels.len()),
            });
        }
        validate_texels(path, width, &texels)?;
        Ok(Self {
            width,
            height,
            texels,
        })
    }

    /// Loads an environment: `builtin:sky`, a cubemap folder (resampled to
    /// equirect, see [`EnvMap::from_cubemap_dir`]), or an equirect `.hdr` /
    /// `.exr` file. EXR: the first RGB(A) layer as f32; compressions the
    /// `exr` crate cannot decode give [`EnvError::ExrCompression`], naming
    /// the compression and suggesting ZIP or PIZ.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, EnvError> {
        let path = path.as_ref();
        if path.as_os_str() == BUILTIN_SKY {
            return Ok(Self::builtin_sky(BUILTIN_SKY_WIDTH, BUILTIN_SKY_WIDTH / 2));
        }
        if path.is_dir() {
            return Self::from_cubemap_dir(path);
        }
        let (w, h, texels) = load::load_image(path)?;
        Self::from_texels(path, w, h, texels)
    }

    /// Loads a cubemap folder ([`Cubemap::load_dir`]) and resamples it to an
    /// equirect map of width `4·face` (nearest cube texel per equirect
    /// texel centre). For projection prefer [`project_cubemap`] on the
    /// [`Cubemap`] itself, which uses exact cube-texel solid angles.
    pub fn from_cubemap_dir(dir: impl AsRef<Path>) -> Result<Self, EnvError> {
        let cube = Cubemap::load_dir(dir.as_ref())?;
        Ok(cube.to_equirect(4 * cube.size()))
    }

    /// Width in texels (longitude).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in texels (latitude, row 0 = top = +Y).
    pub fn height(&self) -> usize {
        self.height
    }

    /// All texels, row-major, row 0 at the top.
    pub fn texels(&self) -> &[Vec3] {
        &self.texels
    }

    /// Texel at column `x`, row `y`.
    pub fn texel(&self, x: usize, y: usize) -> Vec3 {
        self.texels[y * self.width + x]
    }

    /// Unit direction through the centre of texel `(x, y)` (three.js convention).
    pub fn texel_direction(&self, x: usize, y: usize) -> Vec3 {
        let u = (x as f64 + 0.5) / self.width as f64;
        let v = (y as f64 + 0.5) / self.height as f64;
        uv_to_dir(u, v)
    }

    /// Exact solid angle (steradians) of any texel in row `y`:
    /// `ΔΩ = Δφ·(sin lat_top − sin lat_bottom)`, `Δφ = 2π / width`. The rows
    /// sum to exactly `4π` (telescoping), unlike the common `cos lat·ΔφΔθ`.
    pub fn row_solid_angle(&self, y: usize) -> f64 {
        let lat_top = PI * (0.5 - y as f64 / self.height as f64);
        let lat_bot = PI * (0.5 - (y + 1) as f64 / self.height as f64);
        2.0 * PI / self.width as f64 * (lat_top.sin() - lat_bot.sin())
    }

    /// Radiance from unit direction `dir`, bilinearly interpolated between
    /// texel centres, wrapping in longitude and clamping in latitude.
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        let (u, v) = dir_to_uv(dir);
        let fx = u * self.width as f64 - 0.5;
        let fy = (v * self.height as f64 - 0.5).clamp(0.0, (self.height - 1) as f64);
        let x0 = fx.floor();
        let tx = (fx - x0) as f32;
        let y0 = fy.floor() as usize;
        let ty = (fy - y0 as f64) as f32;
        let y1 = (y0 + 1).min(self.height - 1);
        let w = self.width as i64;
        let xa = (x0 as i64).rem_euclid(w) as usize;
        let xb = (x0 as i64 + 1).rem_euclid(w) as usize;
        let top = self.texel(xa, y0).lerp(self.texel(xb, y0), tx);
        let bot = self.texel(xa, y1).lerp(self.texel(xb, y1), tx);
        top.lerp(bot, ty)
    }

    /// The texel `(x, y)` containing direction `dir` (nearest texel, no interpolation).
    pub fn texel_of(&self, dir: Vec3) -> (usize, usize) {
        let (u, v) = dir_to_uv(dir);
        let x = ((u * self.width as f64).floor() as i64).rem_euclid(self.width as i64) as usize;
        let y = ((v * self.height as f64).floor() as i64).clamp(0, self.height as i64 - 1) as usize;
        (x, y)
    }

    /// Halves the resolution by exact solid-angle-weighted 2×2 box averaging:
    /// each new texel is `Σ L_i ΔΩ_i / Σ ΔΩ_i` over its four children, so
    /// `Σ L ΔΩ` (and the L0 coefficient) is preserved exactly. Odd sizes
    /// are not halved along that axis.
    pub fn downsample_2x2(&self) -> EnvMap {
        let nw = if self.width % 2 == 0 {
            self.width / 2
        } else {
            self.width
        };
        let nh = if self.height % 2 == 0 {
            self.height / 2
        } else {
            self.height
        };
        let (sx, sy) = (self.width / nw, self.height / nh);
        let mut texels = Vec::with_capacity(nw * nh);
        for y in 0..nh {
            let weights: Vec<f64> = (0..sy).map(|k| self.row_solid_angle(y * sy + k)).collect();
            let wsum: f64 = weights.iter().sum::<f64>() * sx as f64;
            for x in 0..nw {
                let mut acc = glam::DVec3::ZERO;
                for (k, w) in weights.iter().enumerate() {
                    for j in 0..sx {
                        acc += self.texel(x * sx + j, y * sy + k).as_dvec3() * *w;
                    }
                }
                texels.push((acc / wsum).as_vec3());
            }
        }
        EnvMap {
            width: nw,
            height: nh,
            texels,
        }
    }

    /// Writes the map as a 32-bit float RGB OpenEXR (ZIP compression).
    pub fn save_exr(&self, path: impl AsRef<Path>) -> Result<(), EnvError> {
        load::save_exr(path.as_ref(), self.width, &self.texels)
    }

    /// Writes the map as Radiance RGBE `.hdr` (8-bit shared exponent: about
    /// 0.4–0.8 % relative precision per channel).
    pub fn save_hdr(&self, path: impl AsRef<Path>) -> Result<(), EnvError> {
        load::save_hdr(path.as_ref(), self.width, &self.texels)
    }

    /// The built-in procedural sky (`builtin:sky`), `width × height` texels.
    ///
    /// A plausible clear sky for demos and tests, not a physical model: above
    /// the horizon a blend from a pale horizon `(1.0, 1.05, 1.15)` to a blue
    /// zenith `(0.25, 0.45, 1.0)` by `(sin lat)^0.5`; below it a dark
    /// brown ground `(0.18, 0.15, 0.12)` fading slightly with depth; and a sun
    /// disk of angular radius 2° and radiance `(2000, 1900, 1700)` at
    /// elevation 35°, azimuth φ = 60° (direction
    /// `(cos35°·cos60°, sin35°, cos35°·sin60°)`). The sun disk is
    /// supersampled 4×4 per texel so its edge is antialiased.
    /// Sizes of 0 are raised to 1.
    pub fn builtin_sky(width: usize, height: usize) -> EnvMap {
        let (width, height) = (width.max(1), height.max(1));
        let sun = sun_direction();
        let cos_sun = (SUN_RADIUS_DEG.to_radians()).cos();
        let mut texels = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                let mut acc = Vec3::ZERO;
                const S: usize = 4;
                for j in 0..S {
                    for i in 0..S {
                        let u = (x as f64 + (i as f64 + 0.5) / S as f64) / width as f64;
                        let v = (y as f64 + (j as f64 + 0.5) / S as f64) / height as f64;
                        let d = uv_to_dir(u, v);
                        let mut l = sky_gradient(d);
                        if d.dot(sun) >= cos_sun {
                            l = Vec3::new(2000.0, 1900.0, 1700.0);
                        }
                        acc += l;
                    }
                }
                texels.push(acc / (S * S) as f32);
            }
        }
        EnvMap {
            width,
            height,
            texels,
        }
    }
}

/// Angular radius of the built-in sky's sun disk, degrees.
const SUN_RADIUS_DEG: f32 = 2.0;

/// Direction of the built-in sky's sun (elevation 35°, φ = 60°).
pub fn sun_direction() -> Vec3 {
    let (el, az) = (35f32.to_radians(), 60f32.to_radians());
    Vec3::new(el.cos() * az.cos(), el.sin(), el.cos() * az.sin())
}

fn sky_gradient(d: Vec3) -> Vec3 {
    if d.y >= 0.0 {
        let t = d.y.sqrt();
        Vec3::new(1.0, 1.05, 1.15).lerp(Vec3::new(0.25, 0.45, 1.0), t)
    } else {
        Vec3::new(0.18, 0.15, 0.12) * (1.0 - 0.3 * (-d.y))
    }
}

/// Direction of the point `(u, v)` in `[0,1]²` of an equirect map (three.js convention).
pub fn uv_to_dir(u: f64, v: f64) -> Vec3 {
    let phi = 2.0 * PI * (u - 0.5);
    let lat = PI * (0.5 - v);
    glam::DVec3::new(lat.cos() * phi.cos(), lat.sin(), lat.cos() * phi.sin()).as_vec3()
}

/// `(u, v)` in `[0,1]²` of unit direction `dir` (inverse of [`uv_to_dir`]).
pub fn dir_to_uv(dir: Vec3) -> (f64, f64) {
    let d = dir.as_dvec3();
    let phi = d.z.atan2(d.x);
    let lat = d.y.clamp(-1.0, 1.0).asin();
    (phi / (2.0 * PI) + 0.5, 0.5 - lat / PI)
}

pub(crate) fn validate_texels(path: &Path, width: usize, texels: &[Vec3]) -> Result<(), EnvError> {
    for (i, t) in texels.iter().enumerate() {
        if !t.is_finite() || t.min_element() < 0.0 {
            return Err(EnvError::BadTexel {
                path: path.to_path_buf(),
                x: i % width,
                y: i / width,
                value: t.to_array(),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
