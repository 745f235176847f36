//! Materials: Lambertian albedo, alpha and emission, and their textures.

use glam::{Vec2, Vec3, Vec4};

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
    /// Index into [`Scene::textures`](super::Scene::textures) of the base-colour texture (already linear RGB + alpha),
    /// multiplied with `base_color` and `alpha`.
    pub base_color_texture: Option<u32>,
    /// Alpha factor (glTF `baseColorFactor.a`, OBJ `d` or `1 − Tr`).
    pub alpha: f32,
    /// How alpha becomes opacity.
    pub alpha_mode: AlphaMode,
    /// Emitted radiance factor, linear RGB (glTF `emissiveFactor` × `KHR_materials_emissive_strength`,
    /// OBJ `Ke`). Radiance in the scene's units (W/(sr·m²) with 1 cd = 1 W/sr).
    pub emissive: Vec3,
    /// Index into [`Scene::textures`](super::Scene::textures) of the emissive texture (linear RGB), multiplied with `emissive`.
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
