//! [`RigReport`]: what `probekit rig` prints of an experiment, for people
//! ([`std::fmt::Display`]) and as one JSON object (serde).

use super::mesh::Mesh;
use super::run::RunReport;
use super::source::ProbeSource;
use super::split::Zone;
use super::RigSpec;
use crate::lights::Light;
use glam::Vec3;
use probekit_runtime::ProbeFileKind;
use serde::Serialize;
use std::fmt;

/// One rig experiment ([`super::run::run`]) as `probekit rig` reports it:
/// the rig, its error against the exact lighting, its light zones and the
/// cost of a frame. Serialised (`--json`), the fields below without
/// [`RigReport::details`]; displayed, a few lines that add the baked file,
/// the error against per-vertex SH, the transition table and each light's
/// zone.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RigReport {
    /// The rig type (`constant`, `gradient`, `lattice:NXxNYxNZ`, `mixed:…`).
    pub rig: String,
    /// SH vectors of the rig.
    pub parameters: usize,
    /// Sample points on the mesh.
    pub samples: usize,
    /// Per-vertex relative RMSE against the exact irradiance.
    pub rel_rmse: f32,
    /// Largest per-vertex error, grey levels.
    pub max_error_grey_levels: f32,
    /// Lights per zone.
    pub lights: ZoneCounts,
    /// Median time of a frame (rig update and per-vertex evaluation), ns.
    pub ns_per_frame: u64,
    /// What only the text form shows.
    #[serde(skip)]
    pub details: RigDetails,
}

/// Lights per zone of the analytic/rig split.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct ZoneCounts {
    /// Evaluated per vertex, exactly.
    pub analytic: usize,
    /// Cross-faded between the two.
    pub transition: usize,
    /// Through the rig.
    pub rig: usize,
}

/// The part of a [`RigReport`] only its text form shows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RigDetails {
    /// The mesh as named on the command line.
    pub mesh: String,
    /// Where its origin was placed (world, metres).
    pub at: Vec3,
    /// The analytic lights.
    pub light_count: usize,
    /// The baked file that lit the rig too: `(kind, path, SH order)`.
    pub baked: Option<(String, String, usize)>,
    /// The white level of the grey levels (reflected radiance).
    pub white: f32,
    /// Error against per-vertex SH of the same lights: `(rel. RMSE, max
    /// grey levels)`.
    pub vs_sh: (f32, f32),
    /// The transition table (split on): `(distance / R, grey levels)` per
    /// row.
    pub error_table: Vec<(f32, f32)>,
    /// Each light with the split on: its distance to the object's
    /// bounding sphere's centre and its transition distance (both in
    /// bounding radii `R`), and its zone.
    pub light_zones: Vec<(f32, f32, Zone)>,
    /// Median time of a frame, ns (unrounded).
    pub ns_per_frame: f64,
    /// Median time of evaluating every light analytically per vertex, ns.
    pub ns_brute_force: f64,
}

impl RigReport {
    /// The report of `run`, the experiment of rig `spec` on `mesh` (named
    /// `mesh_name`, placed at `at`) among `lights` and, when given, the
    /// baked file `baked` (its path and the loaded source).
    pub fn new(
        spec: &RigSpec,
        mesh_name: &str,
        mesh: &Mesh,
        at: Vec3,
        lights: &[Light],
        baked: Option<(&str, &ProbeSource)>,
        run: &RunReport,
    ) -> Self {
        let (analytic, transition, rig) = run.zone_counts();
        let (centre, radius) = mesh.bounding_sphere();
        let light_zones = if run.thresholds.is_empty() {
            Vec::new()
        } else {
            (lights.iter().zip(&run.thresholds).zip(&run.zones))
                .map(|((l, &th), &zone)| {
                    let x = l
                        .position()
                        .map_or(f32::INFINITY, |p| p.distance(centre + at) / radius);
                    (x, th, zone)
                })
                .collect()
        };
        let baked = baked.map(|(path, source)| {
            let kind = match source.probes().kind() {
                ProbeFileKind::Volume => "volume",
                _ => "cloud",
            };
            (kind.to_string(), path.to_string(), source.order())
        });
        Self {
            rig: spec.to_string(),
            parameters: spec.parameter_count(),
            samples: run.fitted.rig.samples.len(),
            rel_rmse: run.stats.rel_rmse,
            max_error_grey_levels: run.stats.max_grey,
            lights: ZoneCounts {
                analytic,
                transition,
                rig,
            },
            ns_per_frame: run.ns_per_frame.round() as u64,
            details: RigDetails {
                mesh: mesh_name.to_string(),
                at,
                light_count: lights.len(),
                baked,
                white: run.stats.l_white,
                vs_sh: (run.stats_vs_sh.rel_rmse, run.stats_vs_sh.max_grey),
                error_table: if light_zones.is_empty() {
                    Vec::new()
                } else {
                    (run.fitted.rig.transitions.iter())
                        .map(|t| (t.distance, t.error))
                        .collect()
                },
                light_zones,
                ns_per_frame: run.ns_per_frame,
                ns_brute_force: run.ns_brute_force,
            },
        }
    }
}

impl fmt::Display for RigReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let d = &self.details;
        let z = &self.lights;
        writeln!(
            f,
            "rig {} on {} at {}: {} SH vectors, {} samples",
            self.rig, d.mesh, d.at, self.parameters, self.samples
        )?;
        writeln!(
            f,
            "  lights: {} analytic, {} transition, {} rig (of {})",
            z.analytic, z.transition, z.rig, d.light_count
        )?;
        if let Some((kind, path, order)) = &d.baked {
            writeln!(f, "  baked {kind} {path} (order {order}) through the rig")?;
        }
        writeln!(
            f,
            "  per-vertex error vs exact: rel RMSE {:.4}, max {:.2} grey levels (white {:.4})",
            self.rel_rmse, self.max_error_grey_levels, d.white
        )?;
        writeln!(
            f,
            "  spatial error vs per-vertex SH of the same lights: rel RMSE {:.4}, max {:.2} grey \
             levels",
            d.vs_sh.0, d.vs_sh.1
        )?;
        if !d.light_zones.is_empty() {
            let table: Vec<String> = (d.error_table.iter())
                .map(|(distance, error)| format!("{distance:.2}:{error:.3}"))
                .collect();
            writeln!(
                f,
                "  error table (distance/R : grey levels, unitized light): {}",
                table.join(" ")
            )?;
            for (i, (x, th, zone)) in d.light_zones.iter().enumerate() {
                writeln!(
                    f,
                    "  light {i}: at {x:.2} R, transition at {th:.2} R, {zone:?}"
                )?;
            }
        }
        writeln!(
            f,
            "  frame: {:.0} ns (rig update + per-vertex), brute-force analytic {:.0} ns, ratio {:.2}",
            d.ns_per_frame,
            d.ns_brute_force,
            d.ns_brute_force / d.ns_per_frame.max(1.0)
        )
    }
}
