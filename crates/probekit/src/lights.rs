//! Analytic lights: sphere, point, spot, disk and directional lights, their
//! radiance SH at a point and their exact irradiance at a surface point
//! (the reference and the analytic path of irradiance rigs, Yuan,
//! Nowrouzezahrai & Sloan 2011, §3.2), and the conversion from the scene's
//! lights. Rigs and the capture's tests evaluate lights through them.
//!
//! Units are those of the scene format (`docs/scene-format.md`): intensity in
//! candela, radiometric (no 683 lm/W), a sphere or disk light of radius `r`
//! has radiance `I/(π r²)`. Irradiance is `E = ∫ L max(0, n·ω) dω`, not
//! divided by π.

use crate::scene::{Light as SceneLight, LightKind};
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
    /// (what a renderer's analytic path does, Yuan et al. 2011 §3.2), and the disk
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
/// and `sin α = r/d ∈ [0, 1]` (Yuan et al. 2011 §3.2: "a 128 × 128 texture"),
/// bilinear lookup. Built from
/// [`sphere_light_irradiance_horizon_clipped`] (unit radiance).
#[derive(Clone, Debug)]
pub struct SphereTable {
    size: usize,
    data: Vec<f32>,
}

/// Side of the default table (Yuan et al. 2011 §3.2).
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

/// Converts one scene light ([`SceneLight`], units of
/// `docs/scene-format.md`) to an analytic light: intensity × colour; spot angles
/// from radians to degrees; a directional light's lux becomes its
/// irradiance. `None` for a sphere or disk of radius ≤ 0 (no radiance
/// defined), which the rig's `lights_from_scene` reports.
pub fn from_scene_light(l: &SceneLight) -> Option<Light> {
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
}
