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
//!
//! The lights themselves are the runtime's ([`probekit_runtime::rig::Light`]):
//! the baker's rigs and an engine's run-time split evaluate one
//! implementation. This module adds the conversion from the scene's lights.

pub use probekit_runtime::rig::{Light, SphereTable, DISK_POLYGON_EDGES, SPHERE_TABLE_SIZE};

use crate::scene::{Light as SceneLight, LightKind};

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
    use glam::{DVec3, Vec3};
    use std::f32::consts::PI;

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
