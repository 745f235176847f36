//! What a baked file records about its bake: the scene (as named and by
//! lighting hash), the resolved recipe, what placement did, and for a shard
//! part which slice it holds. Stored as JSON in the file's `META` section;
//! nothing in it changes between identical bakes (no time, no host).

use super::Recipe;
use crate::scene::Scene;
use serde::{Deserialize, Serialize};

/// The `META` JSON of a file baked by probekit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BakeRecord {
    /// Version of probekit that baked the file.
    pub tool_version: String,
    /// The scene as it was named (a path as typed, or `builtin:NAME`), so
    /// later commands can default to it.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub scene: String,
    /// The scene's lighting hash ([`Scene::lighting_hash_hex`]).
    pub scene_hash: String,
    /// The resolved recipe: baking the scene again with it gives this file.
    pub recipe: Recipe,
    /// What placement did (clouds).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub placed: Option<PlacementReport>,
    /// The slice a shard part holds (parts only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part: Option<Part>,
}

/// What placement did, as a file records it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlacementReport {
    /// Probes placed (before the capture's virtual offset).
    pub count: usize,
    /// Adaptive placement with light shells `auto`: the held-out relative
    /// RMSE without and with shells (the lower one was kept).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub held_out_error: Option<[f32; 2]>,
    /// Adaptive placement: whether the kept placement used light shells.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light_shells: Option<bool>,
}

/// The slice of a sharded bake a part file holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Part {
    /// This part's shard index, from 0.
    pub shard: usize,
    /// Shards in all.
    pub shards: usize,
    /// Global index of the part's first probe.
    pub first_index: usize,
    /// Probes in the part.
    pub count: usize,
    /// Probes of the whole bake.
    pub total: usize,
}

impl BakeRecord {
    /// A record stamped with this crate's version, for `scene` as named.
    pub fn new(scene_name: &str, scene: &Scene, recipe: Recipe) -> Self {
        BakeRecord {
            tool_version: env!("CARGO_PKG_VERSION").to_string(),
            scene: scene_name.to_string(),
            scene_hash: scene.lighting_hash_hex(),
            recipe,
            placed: None,
            part: None,
        }
    }

    /// A record of a bake from a source that is no scene (an analytic one,
    /// `builtin:lights-demo`): no lighting hash to check against.
    pub fn without_scene(source_name: &str, recipe: Recipe) -> Self {
        BakeRecord {
            tool_version: env!("CARGO_PKG_VERSION").to_string(),
            scene: source_name.to_string(),
            scene_hash: String::new(),
            recipe,
            placed: None,
            part: None,
        }
    }

    /// Compact JSON for the file's `META` section (keys in a fixed order,
    /// floats as their shortest decimal: equal records give equal bytes).
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    /// The record in a file's `META` text; `None` when it is not one (a
    /// file of another tool).
    pub fn from_json(text: &str) -> Option<Self> {
        serde_json::from_str(text).ok()
    }
}
