//! The recipe flags shared by `bake` and `volume`: a recipe file, single
//! keys, and printing the resolved recipe.

use anyhow::{Context, Result};
use clap::Args;
use probekit::recipe::{Recipe, RecipeLayers};
use probekit::scene::Scene;
use std::path::PathBuf;

/// `--samples`, `--order`, `--seed`: the capture keys a user reaches for
/// first.
#[derive(Debug, Args)]
pub struct CaptureArgs {
    /// Receiver directions per probe (default 1024).
    #[arg(long, help_heading = "Capture")]
    pub samples: Option<u32>,
    /// SH bands stored: 2 = L1, 3 = L2 (default 3).
    #[arg(long, help_heading = "Capture")]
    pub order: Option<usize>,
    /// Random seed: the same seed gives the same bytes (default 1).
    #[arg(long, help_heading = "Capture")]
    pub seed: Option<u64>,
}

impl CaptureArgs {
    /// The recipe keys these options set, appended to `keys`.
    pub fn push_keys(&self, keys: &mut Vec<(&'static str, toml::Value)>) {
        let int = |v: u64| toml::Value::Integer(v as i64);
        if let Some(s) = self.samples {
            keys.push(("capture.samples", int(s.into())));
        }
        if let Some(o) = self.order {
            keys.push(("capture.order", int(o as u64)));
        }
        if let Some(s) = self.seed {
            keys.push(("capture.seed", int(s)));
        }
    }
}

/// `--recipe`, `--set`, `--print-recipe`.
#[derive(Debug, Args)]
pub struct RecipeArgs {
    /// A recipe file (TOML, every key in docs/recipe.md) merged over the
    /// scene's `[bake]` table; the flags above override both.
    #[arg(long, value_name = "FILE.toml", help_heading = "Recipe")]
    pub recipe: Option<PathBuf>,
    /// One recipe key, last and strongest (repeatable): `--set
    /// blend.cell_visibility=6`, `--set placement.tolerance=0.01`.
    #[arg(long, value_name = "KEY=VALUE", help_heading = "Recipe")]
    pub set: Vec<String>,
    /// Print the fully resolved recipe (TOML) and exit without baking;
    /// `--recipe` with it bakes the same file again.
    #[arg(long, help_heading = "Recipe")]
    pub print_recipe: bool,
}

impl RecipeArgs {
    /// The recipe of a bake of `scene` (named `scene_name`): the defaults,
    /// the scene's `[bake]`, the recipe file, `flags` (the command's own
    /// options, as `(key, value)`), then `--set`.
    pub fn resolve(
        &self,
        scene_name: &str,
        scene: &Scene,
        flags: Vec<(&str, toml::Value)>,
    ) -> Result<Recipe> {
        let mut layers = RecipeLayers::new();
        layers.push_scene(scene_name, scene);
        self.resolve_layers(layers, flags)
    }

    /// [`RecipeArgs::resolve`] over `layers` (the defaults and the
    /// scene's layers, lowest first).
    pub fn resolve_layers(
        &self,
        mut layers: RecipeLayers,
        flags: Vec<(&str, toml::Value)>,
    ) -> Result<Recipe> {
        if let Some(path) = &self.recipe {
            let name = path.display().to_string();
            let text = std::fs::read_to_string(path).with_context(|| name.clone())?;
            layers.push_toml(&name, &text)?;
        }
        for (key, value) in flags {
            layers.push_value(&format!("--{}", flag_name(key)), key, value);
        }
        for s in &self.set {
            layers.push_assignment(s)?;
        }
        Ok(layers.resolve()?)
    }
}

/// The option that sets recipe key `key` (`capture.samples` → `samples`).
fn flag_name(key: &str) -> &str {
    key.rsplit('.').next().unwrap_or(key)
}
