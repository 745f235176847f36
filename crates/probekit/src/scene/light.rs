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
    /// Index into [`Scene::triangles`](super::Scene::triangles).
    pub triangle: u32,
    /// Area in m².
    pub area: f32,
    /// Mean emitted radiance over the triangle's material (emissive factor × mean of the emissive
    /// texture). The radiance at a point is [`Scene::emission`](super::Scene::emission); this is for choosing lights.
    pub radiance: Vec3,
}
