//! Recipes in layers: defaults, a scene's `[bake]` table, a recipe file,
//! the command line — merged key by key, checked, then typed.

use super::check::{check_keys, section_method};
use super::{Placement, Recipe, VolumeLayout};
use serde::Deserialize;
use thiserror::Error;
use toml::{Table, Value};

/// Why a recipe cannot be used. Each names where the problem is (the
/// layer: a file, `[bake]` of a scene, a flag) and the key.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum RecipeError {
    /// A layer is not valid TOML.
    #[error("{layer}: {message}")]
    Syntax {
        /// The layer (a file, a flag).
        layer: String,
        /// The parser's message.
        message: String,
    },
    /// A key that the recipe does not have, or that the method in effect
    /// does not read; the message names the valid keys.
    #[error("{layer}: {message}")]
    Key {
        /// The layer (a file, a flag).
        layer: String,
        /// The dotted key (`placement.tolerance`).
        key: String,
        /// What is wrong and what is valid.
        message: String,
    },
    /// A value of the wrong type or out of range.
    #[error("{layer}`{key}`: {message}")]
    Value {
        /// Where it came from, with `: ` (empty when the merged recipe is
        /// at fault).
        layer: String,
        /// The dotted key.
        key: String,
        /// What is wrong and what is valid.
        message: String,
    },
}

/// A stack of partial recipes, lowest first (see the module docs of
/// [`super`]). The defaults are always the bottom layer.
#[derive(Clone, Debug, Default)]
pub struct RecipeLayers {
    layers: Vec<(String, Table)>,
}

impl RecipeLayers {
    /// Only the defaults.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a layer from TOML text; `layer` names it in errors (a file
    /// name, `scene.toml [bake]`).
    pub fn push_toml(&mut self, layer: &str, text: &str) -> Result<&mut Self, RecipeError> {
        let table: Table = text
            .parse()
            .map_err(|e: toml::de::Error| RecipeError::Syntax {
                layer: layer.to_string(),
                message: e.to_string().trim().replace('\n', " "),
            })?;
        Ok(self.push_table(layer, table))
    }

    /// Adds a layer.
    pub fn push_table(&mut self, layer: &str, table: Table) -> &mut Self {
        self.layers.push((layer.to_string(), table));
        self
    }

    /// Adds the scene file's `[bake]` table as a layer named `NAME [bake]`
    /// (`box`; `samples`, `bounces` and `seed` as shorthands of the
    /// `capture` keys; every other key as written). Nothing for a scene
    /// without one.
    pub fn push_scene(&mut self, name: &str, scene: &crate::scene::Scene) -> &mut Self {
        let b = &scene.bake;
        let mut table = b.recipe.clone();
        if let Some(bx) = b.r#box {
            table.insert(
                "box".into(),
                to_value(&[bx.min.to_array(), bx.max.to_array()]),
            );
        }
        let mut capture = match table.remove("capture") {
            Some(Value::Table(t)) => t,
            Some(other) => {
                // Left for the key check to refuse as written.
                table.insert("capture".into(), other);
                Table::new()
            }
            None => Table::new(),
        };
        let shorthands = [
            ("samples", b.samples.map(u64::from)),
            ("bounces", b.bounces.map(u64::from)),
            ("seed", b.seed),
        ];
        for (key, v) in shorthands {
            if let Some(v) = v {
                capture.insert(key.into(), Value::Integer(v as i64));
            }
        }
        if !capture.is_empty() && !table.contains_key("capture") {
            table.insert("capture".into(), Value::Table(capture));
        }
        if table.is_empty() {
            return self;
        }
        self.push_table(&format!("{name} [bake]"), table)
    }

    /// Adds one key (`capture.samples`) set to `value`.
    pub fn push_value(&mut self, layer: &str, key: &str, value: Value) -> &mut Self {
        /// `{a = {b = value}}` for `["a", "b"]`.
        fn nested(parts: &[&str], value: Value) -> Value {
            match parts.split_first() {
                None => value,
                Some((first, rest)) => {
                    let mut t = Table::new();
                    t.insert(first.to_string(), nested(rest, value));
                    Value::Table(t)
                }
            }
        }
        let parts: Vec<&str> = key.split('.').collect();
        match nested(&parts, value) {
            Value::Table(t) => self.push_table(layer, t),
            _ => self,
        }
    }

    /// Adds `KEY=VALUE` as written on a command line (`--set
    /// blend.cell_visibility=6`): VALUE is read as a TOML value, or as a
    /// string when it is not one (`--set placement.method=grid`).
    pub fn push_assignment(&mut self, assignment: &str) -> Result<&mut Self, RecipeError> {
        let layer = format!("--set {assignment}");
        let Some((key, value)) = assignment.split_once('=') else {
            return Err(RecipeError::Syntax {
                layer,
                message: "expected KEY=VALUE, e.g. blend.cell_visibility=6".into(),
            });
        };
        let key = key.trim();
        let value = value.trim();
        let parsed = format!("v = {value}")
            .parse::<Table>()
            .ok()
            .and_then(|mut t| t.remove("v"))
            .unwrap_or_else(|| Value::String(value.to_string()));
        Ok(self.push_value(&layer, key, parsed))
    }

    /// Merges the layers over the defaults, checks every key against the
    /// method in effect, and types the result ([`Recipe::validate`] checks
    /// the ranges).
    pub fn resolve(&self) -> Result<Recipe, RecipeError> {
        let mut merged = to_table(&Recipe::default());
        for (layer, table) in &self.layers {
            check_keys(layer, table, &merged)?;
            merge_into(&mut merged, table, "");
        }
        let recipe = Recipe::deserialize(Value::Table(merged)).map_err(|e| {
            let text = e.to_string();
            // toml's value errors end with "in `a.b`".
            let (message, key) = match text.rsplit_once("\nin `") {
                Some((m, k)) => (m.to_string(), k.trim().trim_end_matches('`').to_string()),
                None => (text.clone(), String::new()),
            };
            RecipeError::Value {
                layer: String::new(),
                key,
                message: message.replace('\n', " "),
            }
        })?;
        recipe.validate()?;
        Ok(recipe)
    }
}

/// A value as a TOML value (through JSON, like [`to_table`]).
fn to_value<T: serde::Serialize>(v: &T) -> Value {
    let json = serde_json::to_string(v).unwrap_or_default();
    serde_json::from_str(&json).unwrap_or(Value::Table(Table::new()))
}

/// A value as a TOML table (through JSON, so `f32`s keep their shortest
/// decimal).
pub(super) fn to_table<T: serde::Serialize>(v: &T) -> Table {
    let json = serde_json::to_string(v).unwrap_or_default();
    serde_json::from_str(&json).unwrap_or_default()
}

/// Merges `over` into `base` key by key. A section (`placement`, `volume`)
/// whose `method` changes starts from that method's defaults, so the old
/// method's parameters do not linger.
fn merge_into(base: &mut Table, over: &Table, path: &str) {
    for (k, v) in over {
        let key = if path.is_empty() {
            k.clone()
        } else {
            format!("{path}.{k}")
        };
        match (base.get_mut(k), v) {
            (Some(Value::Table(b)), Value::Table(o)) => {
                if let Some(m) = o.get("method").and_then(Value::as_str) {
                    if section_method(&key, b).as_deref() != Some(m) {
                        if let Some(mut fresh) = method_defaults(&key, m) {
                            // A volume's gradients are not its layout's.
                            if let Some(g) = b.get("gradients") {
                                fresh.insert("gradients".into(), g.clone());
                            }
                            *b = fresh;
                        }
                    }
                }
                merge_into(b, o, &key);
            }
            _ => {
                base.insert(k.clone(), v.clone());
            }
        }
    }
}

/// The defaults of `method` in the section at `key` (`placement` or
/// `volume`), as a table.
fn method_defaults(key: &str, method: &str) -> Option<Table> {
    match key {
        "placement" => Placement::defaults_of(method).map(|p| to_table(&p)),
        "volume" => VolumeLayout::defaults_of(method).map(|l| to_table(&l)),
        _ => None,
    }
}
