//! Bake metadata: the `META` section's JSON. Holds what is needed to tell
//! two bakes apart and to reproduce one (scene hash, settings, placement
//! method and parameters, tool version) and nothing that changes between
//! identical bakes (no wall-clock time, no host name), so the same bake
//! gives the same bytes.

use serde::{Deserialize, Serialize};

/// How the probes were placed.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Placement {
    /// `grid`, `manual`, `spawn-merge`, `gradient-ascent`, `adaptive`,
    /// `uniform` or `octree` (volumes), ...
    pub method: String,
    /// The method's parameters as given (budget, tolerance, cell size ...).
    #[serde(default)]
    pub parameters: serde_json::Value,
}

/// The JSON stored in the `META` section. Keys serialize in a fixed order
/// (struct order; maps inside `serde_json::Value` are sorted), so equal
/// metadata gives equal bytes.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BakeMetadata {
    /// Version of probekit that wrote the file.
    pub tool_version: String,
    /// The scene as it was named on the command line (a path as typed, or
    /// `builtin:NAME`), so that `eval`, `render` and `rig --probes` can
    /// default to it. Empty when unknown.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub scene: String,
    /// The scene's lighting hash ([`crate::scene::Scene::lighting_hash`],
    /// 16 hex digits): what lights the probes, by content.
    pub scene_hash: String,
    /// Placement method and parameters.
    pub placement: Placement,
    /// Bake settings (SH order, samples, seed, bounces, codec, ...).
    #[serde(default)]
    pub settings: serde_json::Value,
}

impl BakeMetadata {
    /// Metadata stamped with this crate's version.
    pub fn new(scene_hash: String, placement: Placement, settings: serde_json::Value) -> Self {
        Self {
            tool_version: env!("CARGO_PKG_VERSION").to_string(),
            scene: String::new(),
            scene_hash,
            placement,
            settings,
        }
    }

    /// Compact JSON for [`ProbeFile::metadata`](super::ProbeFile::metadata).
    pub fn to_json(&self) -> String {
        // Serializing plain structs and `Value`s cannot fail.
        serde_json::to_string(self).unwrap_or_default()
    }

    /// Parses the `META` text of a file (`None` if it is not this shape,
    /// e.g. a file from another tool).
    pub fn from_json(text: &str) -> Option<Self> {
        serde_json::from_str(text).ok()
    }

    /// This metadata with the scene recorded as named (`builtin:demo`, a
    /// path as typed) and its lighting hash.
    pub fn with_scene(mut self, name: &str, scene: &crate::scene::Scene) -> Self {
        self.scene = name.to_string();
        self.scene_hash = scene.lighting_hash_hex();
        self
    }
}

/// A probe file used with a scene whose lighting differs from the one it
/// was baked from ([`check_scene`]).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "{file} was baked from {baked_scene} (lighting hash {baked_hash}), not from {scene} \
     (lighting hash {scene_hash}); give the scene it was baked from, or --allow-other-scene"
)]
pub struct SceneMismatch {
    /// The probe file, as named.
    pub file: String,
    /// The scene the file recorded (`unknown` when it recorded none).
    pub baked_scene: String,
    /// The lighting hash the file recorded.
    pub baked_hash: String,
    /// The scene given, as named.
    pub scene: String,
    /// Its lighting hash.
    pub scene_hash: String,
}

/// The `scene` and `scene_hash` a file's metadata records: the top-level
/// keys of every bake record (`probekit::recipe::BakeRecord`, and the
/// metadata of files from before it).
fn recorded(metadata: &str) -> Option<(String, String)> {
    let v: serde_json::Value = serde_json::from_str(metadata).ok()?;
    let text = |k: &str| v.get(k).and_then(|x| x.as_str()).unwrap_or("").to_string();
    Some((text("scene"), text("scene_hash")))
}

/// The scene a probe file's metadata recorded (as it was named when
/// baking), if any.
pub fn recorded_scene(metadata: &str) -> Option<String> {
    recorded(metadata)
        .map(|(scene, _)| scene)
        .filter(|s| !s.is_empty())
}

/// Checks that `scene` (named `scene_name`) lights the probes as the scene
/// `file_name` was baked from: equal lighting hashes
/// ([`crate::scene::Scene::lighting_hash`]). A file that recorded no hash
/// (written by another tool) passes: there is nothing to compare.
pub fn check_scene(
    metadata: &str,
    file_name: &str,
    scene: &crate::scene::Scene,
    scene_name: &str,
) -> Result<(), SceneMismatch> {
    check_scene_hash(metadata, file_name, &scene.lighting_hash_hex(), scene_name)
}

/// [`check_scene`] with the scene's lighting hash (16 hex digits) given.
pub fn check_scene_hash(
    metadata: &str,
    file_name: &str,
    hash: &str,
    scene_name: &str,
) -> Result<(), SceneMismatch> {
    let Some((baked_scene, baked_hash)) = recorded(metadata) else {
        return Ok(());
    };
    let hash = hash.to_string();
    if baked_hash.is_empty() || baked_hash == hash {
        return Ok(());
    }
    Err(SceneMismatch {
        file: file_name.into(),
        baked_scene: if baked_scene.is_empty() {
            "an unrecorded scene".into()
        } else {
            baked_scene
        },
        baked_hash,
        scene: scene_name.into(),
        scene_hash: hash,
    })
}

/// A stable 64-bit content hash (FNV-1a), as 16 lowercase hex digits.
/// Identifies inputs; not cryptographic.
pub fn scene_hash(bytes: &[u8]) -> String {
    // FNV-1a 64: offset basis and prime from Fowler, Noll and Vo's
    // specification (draft-eastlake-fnv).
    let mut h: u64 = 0xCBF2_9CE4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01B3);
    }
    format!("{h:016x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_published_vectors() {
        // Test vectors of the FNV reference code (fnv.c, test_fnv.c).
        assert_eq!(scene_hash(b""), "cbf29ce484222325");
        assert_eq!(scene_hash(b"a"), "af63dc4c8601ec8c");
        assert_eq!(scene_hash(b"foobar"), "85944171f73967e8");
    }

    #[test]
    fn metadata_json_is_deterministic_and_round_trips() {
        let settings = serde_json::json!({"seed": 7, "order": 3, "bounces": 2});
        let m = BakeMetadata::new(
            scene_hash(b"scene"),
            Placement {
                method: "adaptive".into(),
                parameters: serde_json::json!({"budget": 500, "tolerance": 0.05}),
            },
            settings,
        );
        let a = m.to_json();
        // Built with keys in another order: same text.
        let settings2 = serde_json::json!({"order": 3, "bounces": 2, "seed": 7});
        let m2 = BakeMetadata {
            settings: settings2,
            ..m.clone()
        };
        assert_eq!(a, m2.to_json());
        assert!(a.contains(r#""method":"adaptive""#));
        assert!(!a.contains("time"));
        assert_eq!(BakeMetadata::from_json(&a), Some(m));
        assert_eq!(BakeMetadata::from_json("not json"), None);
    }
}
