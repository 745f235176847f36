//! Cubemaps: six square faces in the DirectX/glTF order `+X, −X, +Y, −Y, +Z, −Z`.
//!
//! ## Files
//! A cubemap folder holds one image per face, named `px, nx, py, ny, pz, nz`
//! (`p` = positive, `n` = negative) with extension `.hdr`, `.exr` or `.png`
//! (PNG is sRGB-decoded to linear), e.g. `px.hdr … nz.hdr`. All faces must
//! be square and of one size.
//!
//! ## Texel → direction
//! For face texel `(x, y)` of an `N×N` face (row 0 at the top), with
//! `a = 2(x+½)/N − 1` (left → right) and `b = 2(y+½)/N − 1` (top → bottom),
//! the (unnormalised) direction is the DirectX / OpenGL cube-map table
//! (D3D11 functional spec §5.7.4; identical to glTF/KTX2):
//!
//! | face | direction |
//! |------|-----------|
//! | +X | `( 1, −b, −a)` |
//! | −X | `(−1, −b,  a)` |
//! | +Y | `( a,  1,  b)` |
//! | −Y | `( a, −1, −b)` |
//! | +Z | `( a, −b,  1)` |
//! | −Z | `(−a, −b, −1)` |
//!
//! ## Exact texel solid angles
//! On the face plane at distance 1 the area element is
//! `dΩ = dx dy / (1 + x² + y²)^{3/2}`, whose antiderivative is
//! `A(x, y) = atan2(x·y, √(x² + y² + 1))`; a texel `[x0,x1]×[y0,y1]` subtends
//! `A(x0,y0) − A(x0,y1) − A(x1,y0) + A(x1,y1)` (e.g. Driscoll, *Cubemap
//! texel solid angle*, 2012; AMD CubeMapGen). The six faces sum to `4π`.

use super::{load::load_image, validate_texels, EnvError, EnvMap};
use glam::Vec3;
use std::path::Path;

/// One face of a cube, in DirectX/glTF order (the discriminant is the face index).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CubeFace {
    /// +X
    PosX = 0,
    /// −X
    NegX = 1,
    /// +Y
    PosY = 2,
    /// −Y
    NegY = 3,
    /// +Z
    PosZ = 4,
    /// −Z
    NegZ = 5,
}

impl CubeFace {
    /// All faces in DirectX/glTF order.
    pub const ALL: [CubeFace; 6] = [
        CubeFace::PosX,
        CubeFace::NegX,
        CubeFace::PosY,
        CubeFace::NegY,
        CubeFace::PosZ,
        CubeFace::NegZ,
    ];

    /// File stem of the face in a cubemap folder: `px`, `nx`, `py`, `ny`, `pz`, `nz`.
    pub fn file_stem(self) -> &'static str {
        ["px", "nx", "py", "ny", "pz", "nz"][self as usize]
    }

    /// Human name: `+X` … `-Z`.
    pub fn label(self) -> &'static str {
        ["+X", "-X", "+Y", "-Y", "+Z", "-Z"][self as usize]
    }

    /// Unnormalised direction of face coordinates `(a, b)` in `[-1,1]²`
    /// (`a` left → right, `b` top → bottom); table in the module docs.
    pub fn direction(self, a: f32, b: f32) -> Vec3 {
        match self {
            CubeFace::PosX => Vec3::new(1.0, -b, -a),
            CubeFace::NegX => Vec3::new(-1.0, -b, a),
            CubeFace::PosY => Vec3::new(a, 1.0, b),
            CubeFace::NegY => Vec3::new(a, -1.0, -b),
            CubeFace::PosZ => Vec3::new(a, -b, 1.0),
            CubeFace::NegZ => Vec3::new(-a, -b, -1.0),
        }
    }

    /// The face a direction hits and its face coordinates `(a, b)` (inverse of
    /// [`CubeFace::direction`]).
    pub fn of_direction(d: Vec3) -> (CubeFace, f32, f32) {
        let ad = d.abs();
        if ad.x >= ad.y && ad.x >= ad.z {
            if d.x > 0.0 {
                (CubeFace::PosX, -d.z / ad.x, -d.y / ad.x)
            } else {
                (CubeFace::NegX, d.z / ad.x, -d.y / ad.x)
            }
        } else if ad.y >= ad.z {
            if d.y > 0.0 {
                (CubeFace::PosY, d.x / ad.y, d.z / ad.y)
            } else {
                (CubeFace::NegY, d.x / ad.y, -d.z / ad.y)
            }
        } else if d.z > 0.0 {
            (CubeFace::PosZ, d.x / ad.z, -d.y / ad.z)
        } else {
            (CubeFace::NegZ, -d.x / ad.z, -d.y / ad.z)
        }
    }
}

/// A linear-RGB radiance cubemap: six `size × size` faces in DirectX/glTF
/// order, each row-major with row 0 at the top (module docs give the
/// texel → direction table and the solid-angle formula).
#[derive(Clone, Debug, PartialEq)]
pub struct Cubemap {
    size: usize,
    faces: [Vec<Vec3>; 6],
}

/// Antiderivative of the cube-face area element: `atan2(x·y, √(x²+y²+1))`.
fn area_element(x: f64, y: f64) -> f64 {
    (x * y).atan2((x * x + y * y + 1.0).sqrt())
}

impl Cubemap {
    /// Wraps six faces of `size²` texels each. Errors on zero size, a wrong
    /// length or a NaN/infinite/negative texel; `path` is used in messages.
    pub fn from_faces(path: &Path, size: usize, faces: [Vec<Vec3>; 6]) -> Result<Self, EnvError> {
        if size == 0 {
            return Err(EnvError::ZeroSize {
                path: path.to_path_buf(),
                width: 0,
                height: 0,
            });
        }
        for (f, face) in faces.iter().enumerate() {
            if face.len() != size * size {
                return Err(EnvError::BadShape {
                    path: path.to_path_buf(),
                    message: format!(
                        "face {} has {} texels, expected {size}²",
                        CubeFace::ALL[f].label(),
                        face.len()
                    ),
                });
            }
            validate_texels(path, size, face)?;
        }
        Ok(Self { size, faces })
    }

    /// Loads `px/nx/py/ny/pz/nz` `.hdr|.exr|.png` from `dir` (module docs).
    pub fn load_dir(dir: &Path) -> Result<Self, EnvError> {
        let mut faces: [Vec<Vec3>; 6] = Default::default();
        let mut size = None;
        for face in CubeFace::ALL {
            let stem = face.file_stem();
            let file = ["hdr", "exr", "png"]
                .iter()
                .map(|e| dir.join(format!("{stem}.{e}")))
                .find(|p| p.is_file())
                .ok_or_else(|| EnvError::MissingFace {
                    path: dir.to_path_buf(),
                    face: face.label(),
                    expected: format!("{stem}.hdr, {stem}.exr or {stem}.png"),
                })?;
            let (w, h, texels) = load_image(&file)?;
            if w == 0 || h == 0 {
                return Err(EnvError::ZeroSize {
                    path: file,
                    width: w,
                    height: h,
                });
            }
            if w != h || size.is_some_and(|s| s != w) {
                return Err(EnvError::BadShape {
                    path: file,
                    message: format!(
                        "cube face is {w}×{h}; faces must be square and all the same size"
                    ),
                });
            }
            validate_texels(&file, w, &texels)?;
            size = Some(w);
            faces[face as usize] = texels;
        }
        Self::from_faces(dir, size.unwrap_or(0), faces)
    }

    /// Face edge length in texels.
    pub fn size(&self) -> usize {
        self.size
    }

    /// The texels of one face (row-major, row 0 at the top).
    pub fn face(&self, face: CubeFace) -> &[Vec3] {
        &self.faces[face as usize]
    }

    /// Unit direction through the centre of texel `(x, y)` of `face`.
    pub fn texel_direction(&self, face: CubeFace, x: usize, y: usize) -> Vec3 {
        let n = self.size as f32;
        let a = 2.0 * (x as f32 + 0.5) / n - 1.0;
        let b = 2.0 * (y as f32 + 0.5) / n - 1.0;
        face.direction(a, b).normalize()
    }

    /// Exact solid angle (steradians) of texel `(x, y)` on any face (all
    /// faces share it): the area-element formula in the module docs.
    pub fn texel_solid_angle(&self, x: usize, y: usize) -> f64 {
        let n = self.size as f64;
        let x0 = 2.0 * x as f64 / n - 1.0;
        let x1 = 2.0 * (x + 1) as f64 / n - 1.0;
        let y0 = 2.0 * y as f64 / n - 1.0;
        let y1 = 2.0 * (y + 1) as f64 / n - 1.0;
        area_element(x0, y0) - area_element(x0, y1) - area_element(x1, y0) + area_element(x1, y1)
    }

    /// Radiance of the texel containing direction `dir` (nearest texel).
    pub fn radiance_nearest(&self, dir: Vec3) -> Vec3 {
        let (face, a, b) = CubeFace::of_direction(dir);
        let n = self.size;
        let x = (((a + 1.0) * 0.5 * n as f32) as usize).min(n - 1);
        let y = (((b + 1.0) * 0.5 * n as f32) as usize).min(n - 1);
        self.faces[face as usize][y * n + x]
    }

    /// Resamples to an equirect map of `width × width/2` texels, taking the
    /// nearest cube texel at each equirect texel centre.
    pub fn to_equirect(&self, width: usize) -> EnvMap {
        let width = width.max(2);
        let height = width / 2;
        let mut texels = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                let u = (x as f64 + 0.5) / width as f64;
                let v = (y as f64 + 0.5) / height as f64;
                texels.push(self.radiance_nearest(super::uv_to_dir(u, v)));
            }
        }
        EnvMap {
            width,
            height,
            texels,
        }
    }
}
