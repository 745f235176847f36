//! Lights that drive a rig, their SH at a point (the rig's input), and their
//! exact irradiance at a surface point (the reference and the analytic path
//! of seed 000 §3.2).
//!
//! Units are those of the scene format (issue 4): intensity in candela,
//! radiometric (no 683 lm/W), a sphere or disk light of radius `r` has
//! radiance `I/(π r²)`. Irradiance is `E = ∫ L max(0, n·ω) dω`, not divided by π.

use crate::scene::{LightKind, Scene};
use glam::Vec3;
use probekit_sh::lights::{
    directional_sh, point_sh, sphere_light_irradiance_horizon_clipped, sphere_light_sh,
    spot_attenuation, spot_sh,
};
use probekit_sh::MAX_COEFFS;
use std::f32::consts::PI;

/// Edges of the polygon that stands in for a disk light in the exact
/// irradiance (its radius is scaled so the polygon has the disk's area).
/// The relative error in irradiance of the polygon is below 0.1 % except
/// where the disk is very close and seen edge-on.
pub const DISK_POLYGON_EDGES: usize = 48;

/// One light of a rig scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// A sphere of radius `radius` (m) and radiant intensity `intensity`
    /// (W/sr per RGB channel): radiance `I/(π r²)`.
    Sphere {
        /// Centre (world, m).
        position: Vec3,
        /// Radius (m), > 0.
        radius: f32,
        /// Intensity × colour (W/sr).
        intensity: Vec3,
    },
    /// A point light.
    Point {
        /// Position (world, m).
        position: Vec3,
        /// Intensity × colour (W/sr).
        intensity: Vec3,
    },
    /// A glTF spot light ([`probekit_sh::lights::spot_attenuation`]).
    Spot {
        /// Position (world, m).
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
        /// Centre (world, m).
        position: Vec3,
        /// Unit normal, the way light travels.
        direction: Vec3,
        /// Radius (m), > 0.
        radius: f32,
        /// Intensity along the normal × colour (W/sr).
        intensity: Vec3,
    },
    /// Light from infinitely far away (the sun). Spatially constant, so a rig
    /// of any type represents its SH exactly and it always goes through the
    /// rig (zone `rig`: infinite distance). Its exact irradiance is
    /// `E·max(0, n·(−direction))` — **no shadowing**, like every light here
    /// (the object does not occlude itself, the scene does not occlude it).
    Directional {
        /// Unit vector, the way light travels.
        direction: Vec3,
        /// Irradiance on a surface facing the light × colour (lux, radiometric).
        irradiance: Vec3,
    },
}

impl Light {
    /// The light's position (centre); `None` for a directional light
    /// (infinitely far away).
    pub fn position(&self) -> Option<Vec3> {
        match *self {
            Light::Sphere { position, .. }
            | Light::Point { position, .. }
            | Light::Spot { position, .. }
            | Light::Disk { position, .. } => Some(position),
            Light::Directional { .. } => None,
        }
    }

    /// The same light moved to `position` (a directional light is unchanged).
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

    /// The light's radius (0 for point and spot lights).
    pub fn radius(&self) -> f32 {
        match *self {
            Light::Sphere { radius, .. } | Light::Disk { radius, .. } => radius,
            _ => 0.0,
        }
    }

    /// Adds `weight ×` the light's radiance SH at `p` (`order` bands) to
    /// `out`. Sphere: *Irradiance Rigs* A1; point/spot/directional: a delta
    /// (Sloan, *Stupid SH Tricks*, 2008; directional: `c_lm = E·Y_lm(−dir)`,
    /// the same at every `p`).
    /// A disk enters the SH as the sphere of equal projected area
    /// `π r_eq² = π r² cos θ_e` and equal radiance (exact far away, an
    /// approximation near the disk; the quadrature of
    /// `probekit_sh::lights::disk_light_sh` costs ~10⁴ evaluations per call,
    /// too slow for every sample every frame), zero behind the disk.
    pub fn add_sh(&self, order: usize, p: Vec3, weight: f32, out: &mut [Vec3]) {
        let n2 = order * order;
        let mut tmp = [Vec3::ZERO; MAX_COEFFS];
        match *self {
            Light::Sphere {
                position,
                radius,
                intensity,
            } => sphere_light_sh(order, p, position, radius, intensity, &mut tmp[..n2]),
            Light::Point {
                position,
                intensity,
            } => point_sh(order, p, position, intensity, &mut tmp[..n2]),
            Light::Spot {
                position,
                direction,
                inner_deg,
                outer_deg,
                intensity,
            } => spot_sh(
                order,
                p,
                position,
                direction,
                inner_deg,
                outer_deg,
                intensity,
                &mut tmp[..n2],
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
                let req = radius * ce.sqrt();
                // Same radiance I/(π r²) on the smaller sphere: scale the intensity.
                sphere_light_sh(order, p, position, req, intensity * ce, &mut tmp[..n2]);
            }
            Light::Directional {
                direction,
                irradiance,
            } => directional_sh(order, -direction, irradiance, &mut tmp[..n2]),
        }
        for (o, t) in out[..n2].iter_mut().zip(&tmp[..n2]) {
            *o += *t * weight;
        }
    }

    /// Exact irradiance at surface point `p` with unit normal `n` (no
    /// occlusion by the object itself). Sphere: the horizon-clipped form
    /// factor ([`sphere_light_irradiance_horizon_clipped`], Snyder 1996);
    /// point and spot: `I·max(0, n·ω)/d²`; directional: `E·max(0, n·(−dir))`
    /// (no shadowing); disk: Lambert's polygon formula
    /// for a [`DISK_POLYGON_EDGES`]-gon clipped to the horizon. `table`, when
    /// given, replaces the sphere's closed form by its 128 × 128 tabulation
    /// (what a renderer's analytic path does, seed 000 §3.2), and the disk
    /// by the sphere of equal projected area and radiance looked up in the
    /// same table (cheap, as a shader would do it; approximate near the disk
    /// — the Frostbite course notes use the same sphere-for-disk horizon
    /// handling; the polygon stays the reference).
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
                        // Equivalent sphere (same projected area, radiance).
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

/// Irradiance from a unit-radiance disk (centre `c`, unit normal `dn`,
/// radius `r`) at `p` with normal `n`, by Lambert's formula
/// `E = ½ Σ_edges acos(v̂ᵢ·v̂ᵢ₊₁) · n·(v̂ᵢ × v̂ᵢ₊₁)/|v̂ᵢ × v̂ᵢ₊₁|` over the
/// polygon clipped against the plane of `n` through `p` (Arvo, *Applications
/// of Irradiance Tensors*, SIGGRAPH 1995, eq. for polygonal luminaires). The
/// sign is fixed so a polygon in front of the receiver gives `E > 0`.
fn disk_polygon_irradiance(p: Vec3, n: Vec3, c: Vec3, dn: Vec3, r: f32) -> f32 {
    let k = DISK_POLYGON_EDGES;
    // Area-preserving polygon radius: k/2 · R² sin(2π/k) = π r².
    let rp = r * (2.0 * PI / (k as f32 * (2.0 * PI / k as f32).sin())).sqrt();
    let (t1, t2) = dn.any_orthonormal_pair();
    let mut poly = [Vec3::ZERO; 2 * DISK_POLYGON_EDGES];
    let mut m = 0;
    // Vertices relative to p, clipped to n·v ≥ 0 (Sutherland–Hodgman).
    let vert = |i: usize| {
        let a = std::f32::consts::TAU * i as f32 / k as f32;
        c + (t1 * a.cos() + t2 * a.sin()) * rp - p
    };
    for i in 0..k {
        let (a, b) = (vert(i), vert((i + 1) % k));
        let (da, db) = (n.dot(a), n.dot(b));
        if da >= 0.0 {
            poly[m] = a;
            m += 1;
        }
        if (da >= 0.0) != (db >= 0.0) {
            let t = da / (da - db);
            poly[m] = a + (b - a) * t;
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

/// Horizon-clipped sphere-light irradiance tabulated over `cos θ ∈ [−1, 1]`
/// and `sin α = r/d ∈ [0, 1]` (seed 000 §3.2: "a 128 × 128 texture"),
/// bilinear lookup. Built from
/// [`sphere_light_irradiance_horizon_clipped`] (unit radiance).
#[derive(Clone, Debug)]
pub struct SphereTable {
    size: usize,
    data: Vec<f32>,
}

/// Side of the default table (seed 000 §3.2).
pub const SPHERE_TABLE_SIZE: usize = 128;

impl SphereTable {
    /// A `size × size` table (`size ≥ 2`). Row `j` is `sin α = j/(size − 1)`,
    /// column `i` is `cos θ = −1 + 2i/(size − 1)`.
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

    /// Bilinear lookup of unit-radiance irradiance at `(cos θ, sin α)`
    /// (arguments clamped to the table's range).
    pub fn lookup(&self, cos_theta: f32, sin_alpha: f32) -> f32 {
        let m = (self.size - 1) as f32;
        let x = ((cos_theta + 1.0) * 0.5).clamp(0.0, 1.0) * m;
        let y = sin_alpha.clamp(0.0, 1.0) * m;
        let (i, j) = (
            (x as usize).min(self.size - 2),
            (y as usize).min(self.size - 2),
        );
        let (fx, fy) = (x - i as f32, y - j as f32);
        let at = |i: usize, j: usize| self.data[j * self.size + i];
        let a = at(i, j) + (at(i + 1, j) - at(i, j)) * fx;
        let b = at(i, j + 1) + (at(i + 1, j + 1) - at(i, j + 1)) * fx;
        a + (b - a) * fy
    }
}

impl Default for SphereTable {
    fn default() -> Self {
        Self::new(SPHERE_TABLE_SIZE)
    }
}

/// `builtin:rig-demo`: eight sphere lights placed around an object near the
/// origin, at a spread of distances (1.5–9 m from the origin), heights,
/// sizes and colours, none aimed at any particular rig. Positions are
/// world coordinates; use `--at` to move the object among them.
pub fn rig_demo_lights() -> Vec<Light> {
    let s = |p: [f32; 3], r: f32, c: [f32; 3], i: f32| Light::Sphere {
        position: Vec3::from(p),
        radius: r,
        intensity: Vec3::from(c) * i,
    };
    vec![
        // A warm key light, high and to the front right.
        s([4.0, 5.0, 3.0], 0.5, [1.0, 0.9, 0.75], 60.0),
        // A cool fill far to the left.
        s([-8.0, 3.0, -2.0], 1.0, [0.6, 0.7, 1.0], 90.0),
        // A lamp post near the rear, across the width.
        s([-2.5, 2.6, 2.2], 0.15, [1.0, 0.8, 0.5], 8.0),
        // A small bright light low beside the front wheel.
        s([2.6, 0.5, -1.6], 0.1, [1.0, 0.3, 0.2], 2.5),
        // Overhead, above the cabin.
        s([0.5, 4.0, -0.3], 0.3, [0.9, 1.0, 0.9], 12.0),
        // Far behind, low.
        s([-2.0, 1.0, -9.0], 0.6, [0.8, 0.8, 1.0], 50.0),
        // Sideways, mid distance, at the width axis.
        s([0.0, 1.2, 4.0], 0.25, [1.0, 1.0, 1.0], 10.0),
        // Ahead, far.
        s([9.0, 2.0, 1.0], 0.8, [1.0, 0.95, 0.9], 70.0),
    ]
}

/// A scene like the paper's demo (seed 000 §4): a 6 × 3 × 6 m room around an
/// object at the origin with 4 primary sphere lights, 8 small bright sphere
/// lights and 192 disk lights on the walls and floor (red left wall, green
/// right wall) standing in for bounced light.
pub fn paper_cost_lights() -> Vec<Light> {
    let mut v = Vec::new();
    for (k, p) in [
        [2.0, 2.6, 2.0],
        [-2.0, 2.6, 2.0],
        [2.0, 2.6, -2.0],
        [-2.0, 2.6, -2.0],
    ]
    .iter()
    .enumerate()
    {
        v.push(Light::Sphere {
            position: Vec3::from(*p),
            radius: 0.2,
            intensity: Vec3::splat(15.0 + k as f32),
        });
    }
    for k in 0..8 {
        let a = std::f32::consts::TAU * k as f32 / 8.0;
        v.push(Light::Sphere {
            position: Vec3::new(1.2 * a.cos(), 0.4 + 0.18 * k as f32, 1.2 * a.sin()),
            radius: 0.03,
            intensity: Vec3::new(1.0, 0.7, 0.4) * 1.5,
        });
    }
    // 192 disks: 48 on the floor, 36 on each of the four walls.
    let disk = |p: Vec3, d: Vec3, c: Vec3| Light::Disk {
        position: p,
        direction: d,
        radius: 0.25,
        intensity: c * 0.4,
    };
    for i in 0..8 {
        for j in 0..6 {
            let p = Vec3::new(
                -2.6 + 5.2 * i as f32 / 7.0,
                0.0,
                -2.5 + 5.0 * j as f32 / 5.0,
            );
            v.push(disk(p, Vec3::Y, Vec3::splat(0.8)));
        }
    }
    for (axis, sign, colour) in [
        (0usize, -1.0f32, Vec3::new(0.9, 0.2, 0.2)),
        (0, 1.0, Vec3::new(0.2, 0.9, 0.2)),
        (2, -1.0, Vec3::splat(0.8)),
        (2, 1.0, Vec3::splat(0.8)),
    ] {
        for i in 0..9 {
            for j in 0..4 {
                let mut p = Vec3::new(0.0, 0.3 + 2.4 * j as f32 / 3.0, 0.0);
                let t = -2.6 + 5.2 * i as f32 / 8.0;
                p[axis] = 3.0 * sign;
                p[2 - axis] = t;
                let mut d = Vec3::ZERO;
                d[axis] = -sign;
                v.push(disk(p, d, colour));
            }
        }
    }
    v
}

/// The lights of a loaded scene as rig lights, with what was left out.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneLights {
    /// The converted analytic lights, in scene order.
    pub lights: Vec<Light>,
    /// One line per thing the rig does not model (emissive triangles, the
    /// environment, degenerate lights), for the caller to print.
    pub warnings: Vec<String>,
    /// The scene's lighting hash ([`Scene::lighting_hash_hex`]) when the
    /// lights came from a loaded scene (not a built-in light set), to check
    /// a probe file against.
    pub lighting_hash: Option<String>,
}

/// Converts one scene light ([`crate::scene::Light`], units of
/// `docs/scene-format.md`) to a rig light: intensity × colour; spot angles
/// from radians to degrees; a directional light's lux becomes its
/// irradiance. `None` for a sphere or disk of radius ≤ 0 (no radiance
/// defined), which [`lights_from_scene`] reports.
pub fn from_scene_light(l: &crate::scene::Light) -> Option<Light> {
    let intensity = l.color * l.intensity;
    Some(match l.kind {
        LightKind::Point => Light::Point {
            position: l.position,
            intensity,
        },
        LightKind::Spot => Light::Spot {
            position: l.position,
            direction: l.direction,
            inner_deg: l.inner_angle.to_degrees(),
            outer_deg: l.outer_angle.to_degrees(),
            intensity,
        },
        LightKind::Directional => Light::Directional {
            direction: l.direction,
            irradiance: intensity,
        },
        LightKind::Sphere if l.radius > 0.0 => Light::Sphere {
            position: l.position,
            radius: l.radius,
            intensity,
        },
        LightKind::Disk if l.radius > 0.0 => Light::Disk {
            position: l.position,
            direction: l.direction,
            radius: l.radius,
            intensity,
        },
        LightKind::Sphere | LightKind::Disk => return None,
    })
}

/// All analytic lights of `scene` as rig lights ([`from_scene_light`]).
/// Emissive triangles and the environment are not rig lights: they are
/// left out with a warning each (bake them into a probe file and pass it
/// as a [`super::source::ProbeSource`] instead).
pub fn lights_from_scene(scene: &Scene) -> SceneLights {
    let name = scene.source.display();
    let mut out = SceneLights {
        lighting_hash: Some(scene.lighting_hash_hex()),
        ..SceneLights::default()
    };
    for (i, l) in scene.lights.iter().enumerate() {
        match from_scene_light(l) {
            Some(r) => out.lights.push(r),
            None => out.warnings.push(format!(
                "{name}: light {i} ({:?}) has radius ≤ 0; ignored",
                l.kind
            )),
        }
    }
    if !scene.emissive_triangles.is_empty() {
        out.warnings.push(format!(
            "{name}: {} emissive triangle(s) ignored (rigs take analytic lights and baked probes)",
            scene.emissive_triangles.len()
        ));
    }
    let env = &scene.environment;
    if env.map.is_some() || (env.color * env.intensity).max_element() > 0.0 {
        out.warnings.push(format!(
            "{name}: environment ignored (rigs take analytic lights and baked probes)"
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// Brute-force irradiance of a uniform unit-radiance region by a fine
    /// midpoint rule over the receiver's hemisphere.
    fn hemisphere_integral(n: DVec3, inside: impl Fn(DVec3) -> bool, res: usize) -> f64 {
        let (t1, t2) = n.any_orthonormal_pair();
        let mut e = 0.0;
        for i in 0..res {
            // cos θ uniform ⇒ equal solid angle per cell; weight by cos θ.
            let ct = (i as f64 + 0.5) / res as f64;
            let st = (1.0 - ct * ct).sqrt();
            for j in 0..4 * res {
                let ph = std::f64::consts::TAU * (j as f64 + 0.5) / (4 * res) as f64;
                let w = n * ct + (t1 * ph.cos() + t2 * ph.sin()) * st;
                if inside(w) {
                    e += ct;
                }
            }
        }
        e * std::f64::consts::TAU / (4 * res * res) as f64
    }

    /// The 128 × 128 table against brute-force numerical integration over the
    /// light's cap (including horizon-clipped configurations).
    #[test]
    fn sphere_table_matches_numerical_integration() {
        let t = SphereTable::default();
        for &(ct, s) in &[
            (1.0f64, 0.3f64),
            (0.5, 0.5),
            (0.2, 0.6),
            (-0.1, 0.4),
            (0.0, 0.8),
            (-0.5, 0.7),
            (0.7, 0.05),
        ] {
            let axis = DVec3::new((1.0 - ct * ct).sqrt(), 0.0, ct);
            let ca = (1.0 - s * s).sqrt();
            // Midpoint rule over the cap itself (uniform in cos β and φ about
            // its axis), integrand max(0, n·ω) with n = +z.
            let (e1, e2) = axis.any_orthonormal_pair();
            let (nb, np) = (300, 600);
            let mut acc = 0.0;
            for i in 0..nb {
                let cb = ca + (1.0 - ca) * (i as f64 + 0.5) / nb as f64;
                let sb = (1.0 - cb * cb).sqrt();
                for j in 0..np {
                    let ph = std::f64::consts::TAU * (j as f64 + 0.5) / np as f64;
                    let w = axis * cb + (e1 * ph.cos() + e2 * ph.sin()) * sb;
                    acc += w.z.max(0.0);
                }
            }
            let reference = acc * (1.0 - ca) * std::f64::consts::TAU / (nb * np) as f64;
            let got = t.lookup(ct as f32, s as f32) as f64;
            let scale = std::f64::consts::PI * s * s;
            assert!(
                (got - reference).abs() < 0.01 * scale + 2e-4,
                "cosθ {ct} sinα {s}: table {got} vs {reference}"
            );
        }
    }

    /// The disk's polygon irradiance against brute-force hemisphere
    /// integration, for a facing disk (closed form `π r²/(r² + h²)` on axis
    /// too) and a clipped, tilted one.
    #[test]
    fn disk_irradiance_matches_numerical_integration() {
        let disk = Light::Disk {
            position: Vec3::new(0.3, 0.0, 1.0),
            direction: Vec3::new(0.0, 0.0, -1.0),
            radius: 0.5,
            intensity: Vec3::splat(PI * 0.25),
        };
        // Unit radiance: I = π r².
        let on_axis = disk.irradiance(Vec3::new(0.3, 0.0, 0.0), Vec3::Z, None).x as f64;
        assert!((on_axis - std::f64::consts::PI * 0.25 / 1.25).abs() < 2e-3);
        for n in [
            Vec3::Z,
            Vec3::new(1.0, 0.0, 0.3).normalize(),
            Vec3::new(-0.9, 0.2, 0.1).normalize(),
        ] {
            let got = disk.irradiance(Vec3::ZERO, n, None).x as f64;
            let c = DVec3::new(0.3, 0.0, 1.0);
            let reference = hemisphere_integral(
                n.as_dvec3(),
                |w| {
                    // Ray from the origin hits the plane z = 1 at t = 1/w.z.
                    w.z > 0.0 && ((w / w.z) - c).length() <= 0.5
                },
                400,
            );
            assert!(
                (got - reference).abs() < 0.01 * reference + 2e-3,
                "{n}: {got} vs {reference}"
            );
        }
    }

    /// The shader-style disk (equivalent sphere through the table) against
    /// the polygon reference: close away from the disk, for tilted views.
    #[test]
    fn disk_equivalent_sphere_is_close_away_from_the_disk() {
        let disk = Light::Disk {
            position: Vec3::ZERO,
            direction: Vec3::Y,
            radius: 0.2,
            intensity: Vec3::ONE,
        };
        let t = SphereTable::default();
        for p in [
            Vec3::new(0.0, 1.5, 0.0),
            Vec3::new(1.0, 1.0, 0.3),
            Vec3::new(-0.4, 2.0, 0.8),
        ] {
            for n in [-p.normalize(), Vec3::new(0.3, -1.0, 0.2).normalize()] {
                let exact = disk.irradiance(p, n, None).x;
                let approx = disk.irradiance(p, n, Some(&t)).x;
                assert!(
                    (approx / exact - 1.0).abs() < 0.03,
                    "{p} {n}: {approx} vs {exact}"
                );
            }
        }
    }

    /// A sphere light's SH and its exact irradiance agree where the L2
    /// approximation is accurate (a small light far away, normal facing it):
    /// two independent routes to the same number.
    #[test]
    fn sphere_sh_agrees_with_exact_far_away() {
        let l = Light::Sphere {
            position: Vec3::new(0.0, 10.0, 0.0),
            radius: 0.2,
            intensity: Vec3::splat(100.0),
        };
        let mut sh = [Vec3::ZERO; 9];
        l.add_sh(3, Vec3::ZERO, 1.0, &mut sh);
        let e_sh = probekit_sh::irradiance(&sh, Vec3::Y).x;
        let e = l.irradiance(Vec3::ZERO, Vec3::Y, None).x;
        assert!((e - 1.0).abs() < 1e-3, "I/d² = 1, got {e}");
        // L2 of a delta facing the normal: 0.955·E-ish; within 10 %.
        assert!((e_sh / e - 1.0).abs() < 0.1, "{e_sh} vs {e}");
    }

    /// Legendre coefficients `a_l = (2l+1)/2 ∫₋₁¹ max(0,t) P_l(t) dt` of the
    /// clamped cosine for l = 0, 1, 2, by a midpoint rule (independent of
    /// the SH code): the L2 irradiance of a delta light of irradiance E is
    /// `E·Σ a_l P_l(n·l)` (addition theorem).
    fn clamped_cosine_legendre() -> [f64; 3] {
        let m = 200_000;
        let p = |l: usize, x: f64| match l {
            0 => 1.0,
            1 => x,
            _ => 0.5 * (3.0 * x * x - 1.0),
        };
        std::array::from_fn(|l| {
            let mut acc = 0.0;
            for i in 0..m {
                let x = -1.0 + 2.0 * (i as f64 + 0.5) / m as f64;
                acc += x.max(0.0) * p(l, x);
            }
            (2 * l + 1) as f64 / 2.0 * acc * 2.0 / m as f64
        })
    }

    /// Issue 7 check (b): a directional light through any rig gives, at
    /// every vertex, the L2 irradiance of a delta, `E·Σ a_l P_l(n·l)` with
    /// the clamped cosine's Legendre coefficients integrated numerically
    /// here; its exact irradiance is `E·max(0, n·l)`; it is always in the
    /// rig zone; and a directional-only scene's rig error is exactly the L2
    /// truncation error (computed here from the two formulas).
    #[test]
    fn directional_light_rig_is_l2_truncation_only() {
        let dir = Vec3::new(0.3, -1.0, 0.45).normalize();
        let e = Vec3::new(2.0, 1.5, 1.0);
        let sun = Light::Directional {
            direction: dir,
            irradiance: e,
        };
        assert_eq!(sun.position(), None);
        let car = crate::rig::mesh::car();
        let at = Vec3::new(3.0, 0.0, -1.0);
        let a = clamped_cosine_legendre();
        let l2 = |t: f64| a[0] + a[1] * t + a[2] * 0.5 * (3.0 * t * t - 1.0);
        let mut want = Vec::new();
        let mut exact = Vec::new();
        for n in &car.normals {
            let t = n.dot(-dir) as f64;
            want.push(e * l2(t) as f32);
            exact.push(e * t.max(0.0) as f32);
            assert_eq!(
                sun.irradiance(Vec3::ZERO, *n, None),
                e * n.dot(-dir).max(0.0)
            );
        }
        for spec in ["constant", "gradient", "mixed:l3,g,c"] {
            let cfg = crate::rig::run::RunConfig {
                spec: spec.parse().unwrap(),
                at,
                samples: 64,
                ..Default::default()
            };
            let r = crate::rig::run::run(&car, "car", &[sun], None, &cfg, false).unwrap();
            assert_eq!(r.zone_counts(), (0, 0, 1), "{spec}");
            for (i, (got, w)) in r.approx.iter().zip(&want).enumerate() {
                assert!(
                    (*got - *w).abs().max_element() < 1e-4 * e.x,
                    "{spec} vertex {i}: {got} vs {w}"
                );
            }
            for (x, w) in r.exact.iter().zip(&exact) {
                assert!((*x - *w).abs().max_element() < 1e-6);
            }
            let trunc = crate::rig::split::error_stats(&want, &exact, None);
            assert!(
                (r.stats.rel_rmse - trunc.rel_rmse).abs() < 1e-4,
                "{spec}: {:?} vs truncation {:?}",
                r.stats,
                trunc
            );
            assert!(r.stats_vs_sh.rel_rmse < 1e-5, "{:?}", r.stats_vs_sh);
        }
    }

    /// Scene lights convert kind by kind (intensity × colour, angles in
    /// degrees); the demo's sun becomes a directional light and its sky a
    /// warning.
    #[test]
    fn scene_lights_convert() {
        let s = crate::scene::Scene::builtin_demo();
        let l = lights_from_scene(&s);
        assert_eq!(l.lights.len(), s.lights.len());
        assert!(l
            .lights
            .iter()
            .any(|x| matches!(x, Light::Directional { .. })));
        assert!(l.lights.iter().any(|x| matches!(x, Light::Sphere { .. })));
        assert!(
            l.warnings.iter().any(|w| w.contains("environment")),
            "{:?}",
            l.warnings
        );
        let spot = crate::scene::Light {
            kind: LightKind::Spot,
            position: Vec3::ONE,
            direction: Vec3::NEG_Y,
            color: Vec3::new(1.0, 0.5, 0.25),
            intensity: 8.0,
            radius: 0.0,
            inner_angle: 0.25,
            outer_angle: 0.5,
            group: None,
        };
        let Some(Light::Spot {
            inner_deg,
            outer_deg,
            intensity,
            ..
        }) = from_scene_light(&spot)
        else {
            panic!("spot expected")
        };
        assert!((inner_deg - 0.25f32.to_degrees()).abs() < 1e-5);
        assert!((outer_deg - 0.5f32.to_degrees()).abs() < 1e-5);
        assert_eq!(intensity, Vec3::new(8.0, 4.0, 2.0));
        let bad = crate::scene::Light {
            kind: LightKind::Sphere,
            ..spot
        };
        assert_eq!(from_scene_light(&bad), None);
    }
}
