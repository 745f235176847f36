//! What a `.probes` file holds, for `probekit inspect`: a typed summary
//! ([`FileSummary`]) that serialises to JSON and prints as a few lines for
//! people ([`FileSummary`]'s `Display`).

use crate::format::{layout::VALIDITY_INVALID, FormatError, ProbeFile};
use crate::format::{L1Mode, ProbeFileKind};
use crate::recipe::{BakeRecord, Part, PlacementReport, Recipe};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt;

/// A probe file in numbers. Kind-specific parts are `None` for other kinds.
#[derive(Clone, Debug, Serialize)]
pub struct FileSummary {
    /// `cloud`, `cloud-part` (a shard part of a sharded bake, without
    /// tetrahedra), `volume` or `rigs` (irradiance rigs without probes).
    pub kind: &'static str,
    /// Probes (volume samples).
    pub probes: usize,
    /// Tetrahedra (clouds).
    pub tetrahedra: usize,
    /// Hull tetrahedra flat up to rounding ([`crate::delaunay::hull_slivers`]).
    pub hull_slivers: usize,
    /// Probes at the position of another that no tetrahedron uses
    /// ([`crate::delaunay::unused_probes`]).
    pub unused_probes: usize,
    /// `sh{order}/{codec}`.
    pub basis: String,
    /// For L1 files (order 2): how the header says an engine evaluates the
    /// coefficients, `linear` or `zh3-hallucinated` (`None` for other orders).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub l1_evaluation: Option<&'static str>,
    /// Probes flagged invalid by the capture.
    pub invalid: usize,
    /// File size in bytes.
    pub bytes: u64,
    /// Bytes per section, by section name.
    pub bytes_by_section: BTreeMap<String, u64>,
    /// Light group names (`LGRP`).
    pub groups: Vec<String>,
    /// Run-time lights (`LITE`): per light its kind, position (or
    /// direction) and light group, and the probes whose occlusion of it is
    /// stored (`OCCL`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub runtime_lights: Vec<serde_json::Value>,
    /// Distance moments (`VISM`): `{"resolution","max_distance"}`.
    pub visibility: Option<serde_json::Value>,
    /// Cell visibility: `{"subdivision","cells","stored_cells","planes"}`.
    pub cell_visibility: Option<serde_json::Value>,
    /// Fitted probe weights: `{"min","median","max","below_half","above_two",
    /// "brightness_exponent","directional_exponent"}`.
    pub probe_weights: Option<serde_json::Value>,
    /// The resolved recipe the file was baked with (`probekit bake
    /// --recipe` with it bakes the same file again).
    pub recipe: Option<Recipe>,
    /// What placement did (probe count, held-out error, light shells).
    pub placed: Option<PlacementReport>,
    /// The scene the file was baked from, as it was named.
    pub scene: Option<String>,
    /// The scene's lighting hash, as recorded.
    pub scene_hash: Option<String>,
    /// A shard part's place in the whole bake.
    pub part: Option<Part>,
    /// Irradiance rigs in the file.
    pub rigs: usize,
    /// A volume's `leaves`, `resolution`, `roots`, `max_depth` and
    /// `gradients` ([`crate::volume::inspect_json`]), as top-level keys.
    #[serde(flatten)]
    pub volume: Option<BTreeMap<String, serde_json::Value>>,
}

/// The `runtime_lights` of [`FileSummary`].
fn runtime_lights_json(file: &ProbeFile) -> Vec<serde_json::Value> {
    use probekit_runtime::rig::Light;
    let Some(r) = file.probes().and_then(|p| p.runtime_lights.as_ref()) else {
        return Vec::new();
    };
    r.lights
        .iter()
        .enumerate()
        .map(|(l, rl)| {
            let probes = r
                .occlusion
                .entries()
                .iter()
                .filter(|e| e[0] as usize == l)
                .count();
            let kind = match rl.light {
                Light::Sphere { .. } => "sphere",
                Light::Point { .. } => "point",
                Light::Spot { .. } => "spot",
                Light::Disk { .. } => "disk",
                Light::Directional { .. } => "directional",
            };
            serde_json::json!({
                "kind": kind,
                "group": rl.group,
                "position": rl.light.position().map(|p| p.to_array()),
                "probes": probes,
            })
        })
        .collect()
}

/// Summarises `file`.
pub fn summarize(file: &ProbeFile) -> Result<FileSummary, FormatError> {
    let by = file.bytes_by_section()?;
    let bytes = by.values().sum();
    let meta = BakeRecord::from_json(file.metadata());
    let part = meta.as_ref().and_then(|m| m.part);
    let invalid = file
        .probes()
        .and_then(|p| p.validity.as_ref())
        .map_or(0, |v| {
            v.iter().filter(|x| x.flags & VALIDITY_INVALID != 0).count()
        });
    let kind = match (file.kind(), &part) {
        (ProbeFileKind::Volume, _) => "volume",
        (ProbeFileKind::Rig, _) => "rigs",
        (_, Some(_)) => "cloud-part",
        _ => "cloud",
    };
    let volume = if kind == "volume" {
        crate::volume::inspect_json(file).ok().and_then(|v| {
            let mut o: BTreeMap<String, serde_json::Value> = serde_json::from_value(v).ok()?;
            for k in ["kind", "probes", "basis", "bytes", "bytes_by_section"] {
                o.remove(k);
            }
            Some(o)
        })
    } else {
        None
    };
    let cloud = file.as_cloud();
    let tets = cloud.and_then(|c| c.tetrahedra.as_ref());
    let blend = cloud.map(|c| &c.blend);
    // A rigs file has no probes: the basis of its (first) rig, as f32.
    let (order, codec) = match file.probes() {
        Some(p) => (p.coefficients.order, p.coefficients.codec.name()),
        None => (file.rigs().first().map_or(1, |r| r.order), "f32"),
    };
    Ok(FileSummary {
        kind,
        probes: file.positions().len(),
        tetrahedra: tets.map_or(0, |t| t.vertices.len()),
        hull_slivers: tets.map_or(0, |t| {
            crate::delaunay::hull_slivers(file.positions(), &t.vertices, &t.neighbours)
        }),
        unused_probes: tets.map_or(0, |t| {
            crate::delaunay::unused_probes(file.positions().len(), &t.vertices).len()
        }),
        basis: format!("sh{order}/{codec}"),
        l1_evaluation: (order == 2).then_some(match file.l1_mode() {
            L1Mode::Linear => "linear",
            L1Mode::Zh3Hallucinated => "zh3-hallucinated",
        }),
        invalid,
        bytes,
        bytes_by_section: by.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
        groups: file.group_names().map(str::to_string).collect(),
        runtime_lights: runtime_lights_json(file),
        visibility: blend.and_then(|b| b.distance_moments.as_ref()).map(
            |v| serde_json::json!({ "resolution": v.resolution, "max_distance": v.max_distance }),
        ),
        cell_visibility: blend.and_then(|b| b.cell_visibility.as_ref()).map(|c| {
            serde_json::json!({
                "subdivision": c.subdivision(),
                "cells": c.tet_count() + c.hull_face_count(),
                "stored_cells": c.record_count(),
                "planes": blend.and_then(|b| b.cell_planes.as_ref()).map_or(0, |p| p.len()),
            })
        }),
        probe_weights: blend
            .and_then(|b| b.probe_weights.as_ref().map(|w| (b, w)))
            .filter(|(_, w)| !w.is_empty())
            .map(|(b, w)| {
                let mut s = w.clone();
                s.sort_by(f32::total_cmp);
                serde_json::json!({
                    "min": s[0],
                    "median": s[s.len() / 2],
                    "max": s[s.len() - 1],
                    "below_half": s.iter().filter(|&&x| x < 0.5).count(),
                    "above_two": s.iter().filter(|&&x| x > 2.0).count(),
                    "brightness_exponent": b.brightness_exponent,
                    "directional_exponent": b.directional_exponent,
                })
            }),
        recipe: meta.as_ref().map(|m| m.recipe.clone()),
        placed: meta.as_ref().and_then(|m| m.placed.clone()),
        scene: meta
            .as_ref()
            .map(|m| m.scene.clone())
            .filter(|s| !s.is_empty()),
        scene_hash: meta
            .as_ref()
            .map(|m| m.scene_hash.clone())
            .filter(|s| !s.is_empty()),
        part,
        rigs: file.rigs().len(),
        volume,
    })
}

impl fmt::Display for FileSummary {
    /// A few lines for people: kind, counts, basis and size; where it came
    /// from; the blend data it carries.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let kind = match self.kind {
            "cloud" => "probe cloud",
            "cloud-part" => "part of a sharded probe cloud (merge the parts)",
            "volume" => "irradiance volume",
            _ => "irradiance rigs",
        };
        write!(f, "{kind}: ")?;
        if self.kind == "rigs" {
            write!(f, "{} rig(s)", self.rigs)?;
        } else {
            write!(f, "{} probes", self.probes)?;
            if self.invalid > 0 {
                write!(f, " ({} invalid)", self.invalid)?;
            }
            if self.tetrahedra > 0 {
                write!(f, ", {} tetrahedra", self.tetrahedra)?;
            }
            if let Some(v) = &self.volume {
                if let Some(l) = v.get("leaves") {
                    write!(f, ", {l} leaves")?;
                }
            }
            write!(f, ", {}", self.basis.replace('/', " "))?;
            if self.l1_evaluation == Some("zh3-hallucinated") {
                write!(f, " (evaluated with hallucinated ZH3)")?;
            }
        }
        writeln!(f, ", {:.1} KiB", self.bytes as f64 / 1024.0)?;
        if let Some(s) = &self.scene {
            write!(f, "  baked from {s}")?;
            if let Some(h) = &self.scene_hash {
                write!(f, " (lighting hash {h})")?;
            }
            writeln!(f)?;
        }
        if let Some(r) = &self.recipe {
            write!(f, "  placement: {}", r.placement.method())?;
            if let Some(p) = &self.placed {
                write!(f, ", {} probes placed", p.count)?;
            }
            writeln!(f)?;
        }
        let mut blend = Vec::new();
        if let Some(v) = &self.visibility {
            blend.push(format!("distance moments {}²", v["resolution"]));
        }
        if let Some(c) = &self.cell_visibility {
            blend.push(format!(
                "cell visibility k={} ({} of {} cells stored, {} planes)",
                c["subdivision"], c["stored_cells"], c["cells"], c["planes"]
            ));
        }
        if let Some(w) = &self.probe_weights {
            blend.push(format!(
                "probe weights (median {:.2}, brightness exponent {}, directional {})",
                w["median"].as_f64().unwrap_or(0.0),
                w["brightness_exponent"],
                w["directional_exponent"]
            ));
        }
        if !blend.is_empty() {
            writeln!(f, "  blend data: {}", blend.join("; "))?;
        }
        if !self.groups.is_empty() {
            writeln!(f, "  light groups: {}", self.groups.join(", "))?;
        }
        for l in &self.runtime_lights {
            writeln!(
                f,
                "  run-time light: {} (group {}), occlusion stored at {} probes",
                l["kind"].as_str().unwrap_or("?"),
                l["group"].as_str().unwrap_or("?"),
                l["probes"]
            )?;
        }
        if self.rigs > 0 && self.kind != "rigs" {
            writeln!(f, "  {} irradiance rig(s)", self.rigs)?;
        }
        if self.hull_slivers > 0 || self.unused_probes > 0 {
            writeln!(
                f,
                "  {} hull slivers, {} unused probes",
                self.hull_slivers, self.unused_probes
            )?;
        }
        if let Some(r) = &self.recipe {
            writeln!(
                f,
                "  recipe (`bake --recipe` with it bakes this file again):"
            )?;
            for line in r.to_toml().lines() {
                writeln!(f, "    {line}")?;
            }
        }
        Ok(())
    }
}
