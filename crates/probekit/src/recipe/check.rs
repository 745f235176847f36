//! The recipe's keys (by section and method) and value ranges, with errors
//! that name the key, the method and the valid choices.

use super::layers::RecipeError;
use super::{
    CellVisibility, Exponent, GradientModeName, L1Evaluation, Placement, Recipe, VolumeLayout,
};
use toml::{Table, Value};

/// Top-level keys.
const TOP: [&str; 8] = [
    "box",
    "codec",
    "l1_evaluation",
    "placement",
    "capture",
    "lights",
    "blend",
    "volume",
];
/// `[lights]` keys.
const LIGHTS: [&str; 5] = [
    "split",
    "max_per_probe",
    "occlusion_samples",
    "decision_points",
    "resolved",
];
/// `[capture]` keys.
const CAPTURE: [&str; 8] = [
    "samples",
    "bounces",
    "order",
    "seed",
    "russian_roulette_depth",
    "indirect_only",
    "groups",
    "validity",
];
/// `[capture.validity]` keys.
const VALIDITY: [&str; 5] = [
    "backface_threshold",
    "virtual_offset",
    "offset_margin",
    "pre_pass_rays",
    "max_offset_steps",
];
/// `[blend]` keys.
const BLEND: [&str; 7] = [
    "distance_moments",
    "cell_visibility",
    "occluder_planes",
    "probe_weights",
    "brightness_exponent",
    "directional_exponent",
    "fit",
];
/// `[blend.fit]` keys.
const FIT: [&str; 4] = [
    "points_per_probe",
    "samples",
    "regularization",
    "absolute_weight",
];
/// `[volume.gradients]` keys.
const GRADIENTS: [&str; 3] = ["mode", "step", "order"];

/// The keys placement `method` reads (besides `method`).
fn placement_keys(method: &str) -> Option<&'static [&'static str]> {
    Some(match method {
        "grid" => &["budget", "cell"],
        "manual" => &["positions"],
        "adaptive" => &["budget", "tolerance", "light_shells"],
        "spawn-and-merge" | "spawn-merge" => &[
            "budget",
            "initial",
            "contrast",
            "directions",
            "merge_distance",
            "spawn_distance",
            "min_distance",
            "max_iterations",
        ],
        "gradient-ascent" => &[
            "budget",
            "indirect_only",
            "step",
            "min_step",
            "max_iterations",
            "dark_clusters",
        ],
        _ => return None,
    })
}

/// The keys volume layout `method` reads (besides `method` and
/// `gradients`).
fn volume_keys(method: &str) -> Option<&'static [&'static str]> {
    Some(match method {
        "uniform" => &["cell", "resolution"],
        "octree" => &[
            "min_depth",
            "max_depth",
            "roots",
            "tolerance",
            "prune",
            "relative_floor",
            "geometry",
            "geometry_depth",
            "emitter_depth",
            "noise_k",
            "balance",
            "depth_factor",
            "gradient_threshold",
        ],
        _ => return None,
    })
}

/// The `method` of the section at `key`, as `table` holds it.
pub(super) fn section_method(_key: &str, table: &Table) -> Option<String> {
    table
        .get("method")
        .and_then(Value::as_str)
        .map(str::to_string)
}

fn key_error(layer: &str, key: &str, message: String) -> RecipeError {
    RecipeError::Key {
        layer: layer.to_string(),
        key: key.to_string(),
        message,
    }
}

/// `a, b or c`.
fn choices(keys: &[&str]) -> String {
    match keys {
        [] => "nothing".into(),
        [one] => format!("`{one}`"),
        [init @ .., last] => format!(
            "{} or `{last}`",
            init.iter()
                .map(|k| format!("`{k}`"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Checks `keys` of the section `section` against `allowed`.
fn check_plain(layer: &str, section: &str, t: &Table, allowed: &[&str]) -> Result<(), RecipeError> {
    for k in t.keys() {
        if !allowed.contains(&k.as_str()) {
            let key = format!("{section}.{k}");
            return Err(key_error(
                layer,
                &key,
                format!(
                    "`{key}` is not a recipe key; [{section}] has {}",
                    choices(allowed)
                ),
            ));
        }
    }
    Ok(())
}

/// The table at `key` of `t`, or an error when it is not a table.
fn sub<'a>(
    layer: &str,
    t: &'a Table,
    key: &str,
    path: &str,
) -> Result<Option<&'a Table>, RecipeError> {
    match t.get(key) {
        None => Ok(None),
        Some(Value::Table(s)) => Ok(Some(s)),
        Some(_) => Err(key_error(
            layer,
            path,
            format!("`{path}` is a table: write [{path}] with its keys under it"),
        )),
    }
}

/// Checks the keys of one layer, `merged` being the recipe below it (for
/// the methods in effect).
pub(super) fn check_keys(layer: &str, table: &Table, merged: &Table) -> Result<(), RecipeError> {
    for k in table.keys() {
        if TOP.contains(&k.as_str()) {
            continue;
        }
        // A section's key at the top (`samples` for `capture.samples`).
        let home = [
            ("capture", &CAPTURE[..]),
            ("lights", &LIGHTS[..]),
            ("blend", &BLEND[..]),
            ("volume.gradients", &GRADIENTS[..]),
        ]
        .iter()
        .find(|(_, keys)| keys.contains(&k.as_str()))
        .map(|(s, _)| *s)
        .or_else(|| {
            Placement::METHODS
                .iter()
                .any(|m| placement_keys(m).is_some_and(|ks| ks.contains(&k.as_str())))
                .then_some("placement")
        });
        let hint = match home {
            Some(s) => format!("; did you mean `{s}.{k}`?"),
            None => format!("; a recipe has {}", choices(&TOP)),
        };
        return Err(key_error(
            layer,
            k,
            format!("`{k}` is not a recipe key{hint}"),
        ));
    }
    if let Some(p) = sub(layer, table, "placement", "placement")? {
        let below = merged
            .get("placement")
            .and_then(Value::as_table)
            .and_then(|t| section_method("placement", t));
        let method = section_method("placement", p).or(below).unwrap_or_default();
        let Some(keys) = placement_keys(&method) else {
            return Err(key_error(
                layer,
                "placement.method",
                format!(
                    "`{method}` is not a placement method; choose {}",
                    choices(&Placement::METHODS)
                ),
            ));
        };
        for k in p.keys().filter(|k| *k != "method") {
            if !keys.contains(&k.as_str()) {
                let readers: Vec<&str> = Placement::METHODS
                    .iter()
                    .copied()
                    .filter(|m| placement_keys(m).is_some_and(|ks| ks.contains(&k.as_str())))
                    .collect();
                let who = if readers.is_empty() {
                    "no placement reads it".to_string()
                } else {
                    format!("{} placement reads it", readers.join(" and "))
                };
                return Err(key_error(
                    layer,
                    &format!("placement.{k}"),
                    format!(
                        "`placement.{k}`: {method} placement does not read it ({who}); \
                         {method} placement reads {}",
                        choices(keys)
                    ),
                ));
            }
        }
    }
    if let Some(c) = sub(layer, table, "capture", "capture")? {
        check_plain(layer, "capture", c, &CAPTURE)?;
        if let Some(v) = sub(layer, c, "validity", "capture.validity")? {
            check_plain(layer, "capture.validity", v, &VALIDITY)?;
        }
    }
    if let Some(l) = sub(layer, table, "lights", "lights")? {
        check_plain(layer, "lights", l, &LIGHTS)?;
    }
    if let Some(b) = sub(layer, table, "blend", "blend")? {
        check_plain(layer, "blend", b, &BLEND)?;
        if let Some(f) = sub(layer, b, "fit", "blend.fit")? {
            check_plain(layer, "blend.fit", f, &FIT)?;
        }
    }
    if let Some(v) = sub(layer, table, "volume", "volume")? {
        let below = merged
            .get("volume")
            .and_then(Value::as_table)
            .and_then(|t| section_method("volume", t));
        let method = section_method("volume", v).or(below).unwrap_or_default();
        let Some(keys) = volume_keys(&method) else {
            return Err(key_error(
                layer,
                "volume.method",
                format!(
                    "`{method}` is not a volume layout; choose {}",
                    choices(&VolumeLayout::METHODS)
                ),
            ));
        };
        for k in v.keys().filter(|k| *k != "method" && *k != "gradients") {
            if !keys.contains(&k.as_str()) {
                let other = if method == "uniform" {
                    "octree"
                } else {
                    "uniform"
                };
                let who = if volume_keys(other).is_some_and(|ks| ks.contains(&k.as_str())) {
                    format!("the {other} layout reads it")
                } else {
                    "no volume reads it".to_string()
                };
                return Err(key_error(
                    layer,
                    &format!("volume.{k}"),
                    format!(
                        "`volume.{k}`: a {method} volume does not read it ({who}); a {method} \
                         volume reads {}",
                        choices(keys)
                    ),
                ));
            }
        }
        if let Some(g) = sub(layer, v, "gradients", "volume.gradients")? {
            check_plain(layer, "volume.gradients", g, &GRADIENTS)?;
        }
    }
    Ok(())
}

/// An out-of-range value.
fn bad(key: &str, message: String) -> RecipeError {
    RecipeError::Value {
        layer: String::new(),
        key: key.to_string(),
        message,
    }
}

/// `x` finite and `> 0`.
fn positive(key: &str, x: f32) -> Result<(), RecipeError> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(bad(key, format!("{x}: expected a positive number")))
    }
}

/// `x` finite and `≥ 0`.
fn non_negative(key: &str, x: f32) -> Result<(), RecipeError> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(bad(key, format!("{x}: expected a number ≥ 0")))
    }
}

/// `n ≥ min`.
fn at_least(key: &str, n: usize, min: usize) -> Result<(), RecipeError> {
    if n >= min {
        Ok(())
    } else {
        Err(bad(key, format!("{n}: expected at least {min}")))
    }
}

/// An exponent in `0..=4`.
fn exponent(key: &str, x: f32) -> Result<(), RecipeError> {
    if (0.0..=4.0).contains(&x) {
        Ok(())
    } else {
        Err(bad(key, format!("{x}: expected an exponent from 0 to 4")))
    }
}

impl Recipe {
    /// Checks every value's range; errors name the key and what is valid.
    pub fn validate(&self) -> Result<(), RecipeError> {
        if let Some([lo, hi]) = self.bake_box {
            let finite = lo.iter().chain(&hi).all(|x| x.is_finite());
            if !finite || (0..3).any(|a| hi[a] <= lo[a]) {
                return Err(bad(
                    "box",
                    format!(
                        "{lo:?} – {hi:?}: expected finite [min, max] with min < max on every axis"
                    ),
                ));
            }
        }
        self.validate_placement()?;
        let l = &self.lights;
        if !(1..=probekit_runtime::format::layout::MAX_RUNTIME_LIGHTS as u32)
            .contains(&l.max_per_probe)
        {
            return Err(bad(
                "lights.max_per_probe",
                format!("{}: expected 1 to 255", l.max_per_probe),
            ));
        }
        if l.occlusion_samples == 0 {
            return Err(bad(
                "lights.occlusion_samples",
                "0: expected at least 1".into(),
            ));
        }
        if l.decision_points == 0 {
            return Err(bad(
                "lights.decision_points",
                "0: expected at least 1".into(),
            ));
        }
        let c = &self.capture;
        if c.samples == 0 {
            return Err(bad("capture.samples", "0: expected at least 1".into()));
        }
        if !(1..=probekit_sh::MAX_ORDER).contains(&c.order) {
            return Err(bad(
                "capture.order",
                format!(
                    "{}: expected 1 to {} bands (3 = L2)",
                    c.order,
                    probekit_sh::MAX_ORDER
                ),
            ));
        }
        let stored_order = self.codec.codec().fixed_order().unwrap_or(c.order as u32);
        if self.l1_evaluation != L1Evaluation::Linear && stored_order != 2 {
            return Err(bad(
                "l1_evaluation",
                format!(
                    "\"zh3-hallucinated\" evaluates L1 coefficients, and this recipe stores order \
                     {stored_order}: use codec = \"l1\" or capture.order = 2, or \"linear\""
                ),
            ));
        }
        let v = &c.validity;
        if !(0.0..=1.0).contains(&v.backface_threshold) {
            return Err(bad(
                "capture.validity.backface_threshold",
                format!("{}: expected a fraction from 0 to 1", v.backface_threshold),
            ));
        }
        non_negative("capture.validity.offset_margin", v.offset_margin)?;
        at_least(
            "capture.validity.pre_pass_rays",
            v.pre_pass_rays as usize,
            1,
        )?;
        let b = &self.blend;
        if b.distance_moments > 64 {
            return Err(bad(
                "blend.distance_moments",
                format!(
                    "{}: expected 0 (none) to 64 texels per side",
                    b.distance_moments
                ),
            ));
        }
        if let CellVisibility::Subdivision(k) = b.cell_visibility {
            if k > 8 {
                return Err(bad(
                    "blend.cell_visibility",
                    format!("{k}: expected \"auto\", 0 (none) or a subdivision 1 to 8"),
                ));
            }
        }
        if let Exponent::Value(a) = b.brightness_exponent {
            exponent("blend.brightness_exponent", a)?;
        }
        exponent("blend.directional_exponent", b.directional_exponent)?;
        at_least(
            "blend.fit.points_per_probe",
            b.fit.points_per_probe as usize,
            1,
        )?;
        at_least("blend.fit.samples", b.fit.samples as usize, 1)?;
        non_negative("blend.fit.regularization", b.fit.regularization)?;
        non_negative("blend.fit.absolute_weight", b.fit.absolute_weight)?;
        self.validate_volume()
    }

    fn validate_placement(&self) -> Result<(), RecipeError> {
        match &self.placement {
            Placement::Grid { budget, cell } => {
                if let (Some(_), Some(_)) = (budget, cell) {
                    return Err(bad(
                        "placement.cell",
                        "a grid takes `budget` (a probe count) or `cell` (a size), not both".into(),
                    ));
                }
                if let Some(b) = budget {
                    at_least("placement.budget", *b, crate::placement::MIN_GRID)?;
                }
                if let Some(c) = cell {
                    positive("placement.cell", *c)?;
                }
            }
            Placement::Manual { positions } => {
                if positions.is_empty() {
                    return Err(bad(
                        "placement.positions",
                        "manual placement needs a positions file (CSV of x,y,z)".into(),
                    ));
                }
            }
            Placement::Adaptive {
                budget, tolerance, ..
            } => {
                at_least("placement.budget", *budget, 8)?;
                non_negative("placement.tolerance", *tolerance)?;
            }
            Placement::SpawnAndMerge {
                budget,
                initial,
                contrast,
                directions,
                merge_distance,
                spawn_distance,
                min_distance,
                ..
            } => {
                at_least("placement.budget", *budget, 8)?;
                if let Some(i) = initial {
                    at_least("placement.initial", *i, 8)?;
                }
                if !(*contrast > 0.0 && *contrast < 1.0) {
                    return Err(bad(
                        "placement.contrast",
                        format!("{contrast}: expected a threshold between 0 and 1"),
                    ));
                }
                if *directions != 6 && *directions != 26 {
                    return Err(bad(
                        "placement.directions",
                        format!("{directions}: expected 6 or 26"),
                    ));
                }
                for (k, d) in [
                    ("placement.merge_distance", merge_distance),
                    ("placement.spawn_distance", spawn_distance),
                    ("placement.min_distance", min_distance),
                ] {
                    if let Some(d) = d {
                        positive(k, *d)?;
                    }
                }
            }
            Placement::GradientAscent {
                budget,
                step,
                min_step,
                ..
            } => {
                at_least("placement.budget", *budget, 8)?;
                positive("placement.min_step", *min_step)?;
                if !(step.is_finite() && step >= min_step) {
                    return Err(bad(
                        "placement.step",
                        format!("{step}: expected a step ≥ min_step ({min_step})"),
                    ));
                }
            }
        }
        Ok(())
    }

    fn validate_volume(&self) -> Result<(), RecipeError> {
        match &self.volume.layout {
            VolumeLayout::Uniform { cell, resolution } => {
                match (cell, resolution) {
                    (Some(_), Some(_)) => {
                        return Err(bad(
                            "volume.cell",
                            "a uniform volume takes `cell` or `resolution`, not both".into(),
                        ))
                    }
                    (None, None) => {
                        return Err(bad(
                            "volume.cell",
                            "a uniform volume needs `cell` (metres) or `resolution` (probes \
                             per axis)"
                                .into(),
                        ))
                    }
                    _ => {}
                }
                if let Some(c) = cell {
                    positive("volume.cell", *c)?;
                }
                if let Some(r) = resolution {
                    if r.iter().any(|&n| n < 2) {
                        return Err(bad(
                            "volume.resolution",
                            format!("{r:?}: every axis needs at least 2 probes"),
                        ));
                    }
                }
            }
            VolumeLayout::Octree {
                min_depth,
                max_depth,
                emitter_depth,
                ..
            } => {
                if min_depth > max_depth || *max_depth > 20 {
                    return Err(bad(
                        "volume.max_depth",
                        format!("{max_depth}: expected min_depth ({min_depth}) ≤ max_depth ≤ 20"),
                    ));
                }
                if emitter_depth.is_some_and(|e| e > 20) {
                    return Err(bad(
                        "volume.emitter_depth",
                        "expected a depth of at most 20".into(),
                    ));
                }
            }
        }
        let g = &self.volume.gradients;
        if let Some(s) = g.step {
            if g.mode != GradientModeName::Central {
                return Err(bad(
                    "volume.gradients.step",
                    "the step is central differences': set `mode = \"central\"`".into(),
                ));
            }
            positive("volume.gradients.step", s)?;
        }
        if let Some(o) = g.order {
            if g.mode == GradientModeName::None {
                return Err(bad(
                    "volume.gradients.order",
                    "gradients are off: set `mode` to \"central\" or \"analytic\"".into(),
                ));
            }
            if o == 0 || o as usize > self.capture.order {
                return Err(bad(
                    "volume.gradients.order",
                    format!("{o}: expected 1 to capture.order ({})", self.capture.order),
                ));
            }
        }
        Ok(())
    }
}
