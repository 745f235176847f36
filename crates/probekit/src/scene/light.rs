//! The scene's emitters: analytic lights and emissive triangles.

use glam::Vec3;

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

/// Where a light's direct term is evaluated: in the probes' SH, or exactly
/// at run time with each probe's occlusion of it stored beside the SH
/// (`docs/scene-format.md`, "Light modes").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LightMode {
    /// The bake decides: run time where its held-out estimate says that
    /// lowers the error (small, bright, local lights), baked otherwise.
    #[default]
    Auto,
    /// All of its light goes into the probes' SH.
    Baked,
    /// Its direct light is evaluated at run time (exact unoccluded
    /// irradiance × the probes' blended occlusion); its bounce light stays
    /// in the SH, in its light group.
    Runtime,
}

impl LightMode {
    /// The scene file's name of the mode (`"auto"`, `"baked"`, `"runtime"`).
    pub fn name(self) -> &'static str {
        match self {
            LightMode::Auto => "auto",
            LightMode::Baked => "baked",
            LightMode::Runtime => "runtime",
        }
    }

    /// The mode named `name` in a scene file.
    pub fn from_name(name: &str) -> Option<Self> {
        [LightMode::Auto, LightMode::Baked, LightMode::Runtime]
            .into_iter()
            .find(|m| m.name() == name)
    }
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
    /// Baked, run-time or chosen by the bake ([`LightMode`]).
    pub mode: LightMode,
    /// Directional lights: the angular diameter of the sun's disc (radians,
    /// in (0, π/2)), over which its occlusion is sampled; 0 for a
    /// direction with no extent and for every other kind.
    pub angular_diameter: f32,
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
    /// Index into [`Scene::triangles`](super::Scene::triangles).
    pub triangle: u32,
    /// Area in m².
    pub area: f32,
    /// Mean emitted radiance over the triangle's material (emissive factor × mean of the emissive
    /// texture). The radiance at a point is [`Scene::emission`](super::Scene::emission); this is for choosing lights.
    pub radiance: Vec3,
}
