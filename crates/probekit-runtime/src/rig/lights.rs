//! Lights that drive a rig: their radiance SH at a point (what a rig is
//! updated from) and their exact irradiance at a surface point (what the
//! near-light path of the rig split evaluates per vertex), one
//! implementation for the baker and the runtime.
//!
//! Units: intensity in W/sr per RGB channel (radiometric, no 683 lm/W); a
//! sphere or disk light of radius `r` has radiance `I/(π r²)`; a
//! directional light gives irradiance `E` on a surface facing it.
//! Irradiance is `E = ∫ L(ω) max(0, n·ω) dω`, not divided by π. No light
//! is shadowed (the object does not occlude itself).

use crate::prelude::*;
use core::f32::consts::PI;
use glam::Vec3;
use probekit_sh::lights::{
    directional_sh, point_sh, sphere_light_irradiance_horizon_clipped, sphere_light_sh,
    spot_attenuation, spot_sh,
};
#[cfg(not(feature = "std"))]
use probekit_sh::math::FloatMath;
use probekit_sh::MAX_COEFFS;

/// Edges of the polygon that stands in for a disk light in its exact
/// irradiance (its radius scaled so that the polygon has the disk's area):
/// below 0.1 % relative error except very close to the disk seen edge-on.
pub const DISK_POLYGON_EDGES: usize = 48;

/// Side of the default [`SphereTable`]: 128 × 128 entries, the size of the
/// texture *Irradiance Rigs* (Yuan, Nowrouzezahrai & Sloan, JGT 2011, §3.2)
/// gives its analytic path.
pub const SPHERE_TABLE_SIZE: usize = 128;

/// One light of a rig scene (positions and directions in the frame the
/// rig is evaluated in, metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// A sphere of radius `radius` and radiant intensity `intensity`:
    /// radiance `I/(π r²)`.
    Sphere {
        /// Centre (m).
        position: Vec3,
        /// Radius (m), > 0.
        radius: f32,
        /// Intensity × colour (W/sr).
        intensity: Vec3,
    },
    /// A point light.
    Point {
        /// Position (m).
        position: Vec3,
        /// Intensity × colour (W/sr).
        intensity: Vec3,
    },
    /// A glTF (`KHR_lights_punctual`) spot light
    /// ([`probekit_sh::lights::spot_attenuation`]).
    Spot {
        /// Position (m).
        position: Vec3,
        /// Unit axis, the way light travels.
        direction: Vec3,
        /// Inner cone half-angle (degrees).
        inner_deg: f32,
        /// Outer cone half-angle (degrees).
        outer_deg: f32,
        /// On-axis intensity × colour (W/sr).
        intensity: Vec3,
    },
    /// A one-sided Lambertian disk facing `direction`, radiance `I/(π r²)`.
    Disk {
        /// Centre (m).
        position: Vec3,
        /// Unit normal, the way light travels.
        direction: Vec3,
        /// Radius (m), > 0.
        radius: f32,
        /// Intensity along the normal × colour (W/sr).
        intensity: Vec3,
    },
    /// Light from infinitely far away (the sun): the same SH everywhere,
    /// irradiance `E·max(0, n·(−direction))`.
    Directional {
        /// Unit vector, the way light travels.
        direction: Vec3,
        /// Irradiance on a surface facing the light × colour (W/m²).
        irradiance: Vec3,
    },
}

impl Light {
    /// The light's position (centre, m); `None` for a directional light.
    pub fn position(&self) -> Option<Vec3> {
        match *self {
            Light::Sphere { position, .. }
            | Light::Point { position, .. }
            | Light::Spot { position, .. }
            | Light::Disk { position, .. } => Some(position),
            Light::Directional { .. } => None,
        }
    }

    /// The same light moved to `p` (a directional light is unchanged).
    pub fn moved_to(mut self, p: Vec3) -> Light {
        match &mut self {
            Light::Sphere { position, .. }
            | Light::Point { position, .. }
            | Light::Spot { position, .. }
            | Light::Disk { position, .. } => *position = p,
            Light::Directional { .. } => {}
        }
        self
    }

    /// The light's radius (m; 0 for point, spot and directional lights).
    pub fn radius(&self) -> f32 {
        match *self {
            Light::Sphere { radius, .. } | Light::Disk { radius, .. } => radius,
            _ => 0.0,
        }
    }

    /// Adds `weight ×` the light's radiance SH at `p` (`order` bands, at
    /// most [`probekit_sh::MAX_ORDER`]) to `out[..order²]`. Sphere:
    /// *Irradiance Rigs* appendix A1 ([`sphere_light_sh`]); point, spot and
    /// directional: a delta (Sloan, *Stupid SH Tricks*, 2008). A disk enters
    /// as the sphere of equal projected area `π r² cos θ_e` and equal
    /// radiance (exact far away, approximate near it), zero behind it.
    /// Does nothing when `out` is shorter than `order²` or the order is out
    /// of range.
    pub fn add_sh(&self, order: usize, p: Vec3, weight: f32, out: &mut [Vec3]) {
        let n2 = order * order;
        if order == 0 || n2 > MAX_COEFFS || out.len() < n2 {
            return;
        }
        let mut tmp = [Vec3::ZERO; MAX_COEFFS];
        let tmp_n = &mut tmp[..n2];
        match *self {
            Light::Sphere {
                position,
                radius,
                intensity,
            } => sphere_light_sh(order, p, position, radius, intensity, tmp_n),
            Light::Point {
                position,
                intensity,
            } => point_sh(order, p, position, intensity, tmp_n),
            Light::Spot {
                position,
                direction,
                inner_deg,
                outer_deg,
                intensity,
            } => spot_sh(
                order, p, position, direction, inner_deg, outer_deg, intensity, tmp_n,
            ),
            Light::Disk {
                position,
                direction,
                radius,
                intensity,
            } => {
                let w = p - position;
                let d = w.length();
                let ce = if d > 0.0 { w.dot(direction) / d } else { 0.0 };
                if ce <= 0.0 {
                    return;
                }
                // Same radiance I/(π r²) on the smaller sphere.
                let req = radius * ce.sqrt();
                sphere_light_sh(order, p, position, req, intensity * ce, tmp_n);
            }
            Light::Directional {
                direction,
                irradiance,
            } => directional_sh(order, -direction, irradiance, tmp_n),
        }
        for (o, t) in out[..n2].iter_mut().zip(tmp_n.iter()) {
            *o += *t * weight;
        }
    }

    /// Exact irradiance at surface point `p` with unit normal `n`. Sphere:
    /// the horizon-clipped form factor
    /// ([`sphere_light_irradiance_horizon_clipped`], Snyder 1996) times its
    /// radiance, `πL` inside it; point and spot: `I·max(0, n·ω)/d²` (spot
    /// times its cone attenuation); directional: `E·max(0, n·(−dir))`; disk:
    /// Lambert's formula for a [`DISK_POLYGON_EDGES`]-gon of the disk's
    /// area clipped to the horizon (Arvo, *Applications of Irradiance
    /// Tensors*, SIGGRAPH 1995). With `table`, a sphere is looked up in it
    /// (a renderer's analytic path, *Irradiance Rigs* §3.2) and a disk as
    /// the sphere of equal projected area and radiance in the same table.
    pub fn irradiance(&self, p: Vec3, n: Vec3, table: Option<&SphereTable>) -> Vec3 {
        match *self {
            Light::Sphere {
                position,
                radius,
                intensity,
            } => {
                let w = position - p;
                let d = w.length();
                let l = intensity / (PI * radius * radius);
                if d <= radius {
                    return l * PI;
                }
                let (ct, s) = (n.dot(w) / d, radius / d);
                let f = match table {
                    Some(t) => t.lookup(ct, s),
                    None => sphere_light_irradiance_horizon_clipped(ct, s),
                };
                l * f
            }
            Light::Point {
                position,
                intensity,
            } => {
                let w = position - p;
                let d2 = w.length_squared();
                if d2 <= 0.0 {
                    return Vec3::ZERO;
                }
                intensity * (n.dot(w).max(0.0) / (d2 * d2.sqrt()))
            }
            Light::Spot {
                position,
                direction,
                inner_deg,
                outer_deg,
                intensity,
            } => {
                let w = position - p;
                let d2 = w.length_squared();
                if d2 <= 0.0 {
                    return Vec3::ZERO;
                }
                let d = d2.sqrt();
                let att = spot_attenuation(
                    direction.dot(-w / d),
                    inner_deg.to_radians(),
                    outer_deg.to_radians(),
                );
                intensity * (att * n.dot(w).max(0.0) / (d2 * d))
            }
            Light::Disk {
                position,
                direction,
                radius,
                intensity,
            } => {
                let w = p - position;
                let d = w.length();
                if w.dot(direction) <= 0.0 || d <= 0.0 {
                    return Vec3::ZERO;
                }
                let l = intensity / (PI * radius * radius);
                match table {
                    Some(t) => {
                        let req = radius * (w.dot(direction) / d).sqrt();
                        l * t.lookup(-n.dot(w) / d, (req / d).min(1.0))
                    }
                    None => l * disk_polygon_irradiance(p, n, position, direction, radius),
                }
            }
            Light::Directional {
                direction,
                irradiance,
            } => irradiance * n.dot(-direction).max(0.0),
        }
    }
}

/// Irradiance at `p` (normal `n`) from a unit-radiance disk (centre `c`,
/// unit normal `dn`, radius `r`) by Lambert's formula
/// `E = ½ Σ acos(v̂ᵢ·v̂ᵢ₊₁) n·(v̂ᵢ × v̂ᵢ₊₁)/|v̂ᵢ × v̂ᵢ₊₁|` over the polygon
/// clipped to the plane of `n` through `p` (Arvo 1995).
fn disk_polygon_irradiance(p: Vec3, n: Vec3, c: Vec3, dn: Vec3, r: f32) -> f32 {
    let k = DISK_POLYGON_EDGES;
    // Area-preserving polygon radius: k/2 · R² sin(2π/k) = π r².
    let rp = r * (2.0 * PI / (k as f32 * (2.0 * PI / k as f32).sin())).sqrt();
    let (t1, t2) = dn.any_orthonormal_pair();
    let mut poly = [Vec3::ZERO; 2 * DISK_POLYGON_EDGES];
    let mut m = 0;
    let vert = |i: usize| {
        let a = core::f32::consts::TAU * i as f32 / k as f32;
        c + (t1 * a.cos() + t2 * a.sin()) * rp - p
    };
    // Sutherland–Hodgman against n·v ≥ 0.
    for i in 0..k {
        let (a, b) = (vert(i), vert((i + 1) % k));
        let (da, db) = (n.dot(a), n.dot(b));
        if da >= 0.0 {
            poly[m] = a;
            m += 1;
        }
        if (da >= 0.0) != (db >= 0.0) {
            poly[m] = a + (b - a) * (da / (da - db));
            m += 1;
        }
    }
    if m < 3 {
        return 0.0;
    }
    let mut e = 0.0f32;
    for i in 0..m {
        let (a, b) = (poly[i].normalize(), poly[(i + 1) % m].normalize());
        let cr = a.cross(b);
        let len = cr.length();
        if len > 1e-12 {
            e += a.dot(b).clamp(-1.0, 1.0).acos() * n.dot(cr) / len;
        }
    }
    (0.5 * e).abs()
}

/// Horizon-clipped irradiance of a unit-radiance sphere light tabulated over
/// `cos θ ∈ [−1, 1]` (normal to light centre) and `sin α = r/d ∈ [0, 1]`,
/// looked up bilinearly: the texture of *Irradiance Rigs* §3.2, built from
/// [`sphere_light_irradiance_horizon_clipped`].
#[derive(Clone, Debug)]
pub struct SphereTable {
    size: usize,
    data: Vec<f32>,
}

impl SphereTable {
    /// A `size × size` table (`size` at least 2): row `j` is
    /// `sin α = j/(size − 1)`, column `i` is `cos θ = −1 + 2i/(size − 1)`.
    pub fn new(size: usize) -> Self {
        let size = size.max(2);
        let mut data = Vec::with_capacity(size * size);
        for j in 0..size {
            let s = j as f32 / (size - 1) as f32;
            for i in 0..size {
                let ct = -1.0 + 2.0 * i as f32 / (size - 1) as f32;
                data.push(sphere_light_irradiance_horizon_clipped(ct, s));
            }
        }
        Self { size, data }
    }

    /// Entries per side (rows and columns).
    pub fn size(&self) -> usize {
        self.size
    }

    /// The `size²` entries, row after row (row `j`, column `i` at
    /// `j·size + i`; [`SphereTable::new`]): the unit-radiance irradiance
    /// (no unit: a form factor times π, at most π).
    pub fn values(&self) -> &[f32] {
        &self.data
    }

    /// Unit-radiance irradiance at `(cos θ, sin α)`, bilinear (arguments
    /// clamped to the table's range; NaN reads as the range's start).
    pub fn lookup(&self, cos_theta: f32, sin_alpha: f32) -> f32 {
        let m = (self.size - 1) as f32;
        let x = ((cos_theta + 1.0) * 0.5).clamp(0.0, 1.0) * m;
        let y = sin_alpha.clamp(0.0, 1.0) * m;
        let (x, y) = (
            if x.is_nan() { 0.0 } else { x },
            if y.is_nan() { 0.0 } else { y },
        );
        let (i, j) = (
            (x as usize).min(self.size - 2),
            (y as usize).min(self.size - 2),
        );
        let (fx, fy) = (x - i as f32, y - j as f32);
        let at = |i: usize, j: usize| self.data.get(j * self.size + i).copied().unwrap_or(0.0);
        let a = at(i, j) + (at(i + 1, j) - at(i, j)) * fx;
        let b = at(i, j + 1) + (at(i + 1, j + 1) - at(i, j + 1)) * fx;
        a + (b - a) * fy
    }
}

impl Default for SphereTable {
    /// The [`SPHERE_TABLE_SIZE`]² table.
    fn default() -> Self {
        Self::new(SPHERE_TABLE_SIZE)
    }
}
