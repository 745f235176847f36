//! Everything checked before a port is bound: the probe file, the scene
//! (the one given, else the one the file recorded) and their lighting hashes.

use crate::query::Probes;
use crate::{ViewConfig, ViewError};
use probekit::scene::Scene;
use probekit_runtime::format::layout::{VALIDITY_INVALID, VALIDITY_VIRTUAL_OFFSET};
use probekit_runtime::ProbeFile;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A probe file and its scene, checked and ready to serve ([`open`]).
pub struct Viewer {
    pub(crate) data: Arc<ViewData>,
    pub(crate) warnings: Vec<String>,
}

impl Viewer {
    /// What the checks warned about: the recorded scene not found (the page
    /// shows the probes alone), another scene allowed by
    /// `allow_other_scene`, the scene loader's warnings.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }
}

/// What the server shares between its threads.
pub(crate) struct ViewData {
    /// The probe file as named.
    pub file_name: String,
    pub file: ProbeFile,
    pub probes: Probes,
    /// The scene, when one was found and loaded.
    pub scene: Option<Arc<Scene>>,
    /// The scene as named (given or recorded), even when not loaded.
    pub scene_name: Option<String>,
    /// What the file recorded: `scene` and `scene_hash` of its metadata.
    pub recorded_scene: Option<String>,
    pub recorded_hash: Option<String>,
    /// The banner the page shows (no scene; another scene), if any.
    pub banner: Option<String>,
    /// Mean over the probes of their irradiance averaged over all normals,
    /// as luminance (the floor of the leak test).
    pub mean_irradiance: f32,
    pub truth_samples: u32,
}

/// The probe state the page marks: 0 valid, 1 invalid, 2 moved by the
/// virtual offset (an invalid probe counts as invalid even if moved).
pub(crate) fn probe_state(file: &ProbeFile, i: usize) -> u8 {
    let validity = file.probes().and_then(|p| p.validity.as_ref());
    match validity.and_then(|v| v.get(i)) {
        Some(v) if v.flags & VALIDITY_INVALID != 0 => 1,
        Some(v) if v.flags & VALIDITY_VIRTUAL_OFFSET != 0 => 2,
        _ => 0,
    }
}

/// A key of the file's metadata JSON (`scene`, `scene_hash`), read by key
/// so that whatever else the record holds does not matter.
fn metadata_key(metadata: &str, key: &str) -> Option<String> {
    let v: serde_json::Value = serde_json::from_str(metadata).ok()?;
    v.get(key)?
        .as_str()
        .filter(|s| !s.is_empty())
        .map(str::to_string)
}

/// Where a recorded scene name may be found: as recorded (relative to the
/// current folder), then relative to the probe file's folder. `None` when
/// neither exists (builtin scenes always exist).
fn find_recorded(name: &str, file: &Path) -> Option<PathBuf> {
    if name.starts_with("builtin:") {
        return Some(PathBuf::from(name));
    }
    let as_named = PathBuf::from(name);
    if as_named.exists() {
        return Some(as_named);
    }
    let beside = file.parent()?.join(name);
    beside.exists().then_some(beside)
}

/// Loads `config.probes` and checks it, then finds, loads and checks the
/// scene: `config.scene`, else the one the file recorded. A given scene
/// that does not load, a recorded one that exists but does not load, or one
/// whose lighting hash differs from the file's (unless
/// `config.allow_other_scene`) is an error; a recorded scene that cannot be
/// found, or a file that records none, gives a viewer of the probes alone
/// with a banner.
pub fn open(config: &ViewConfig) -> Result<Viewer, ViewError> {
    if config.truth_samples == 0 {
        return Err(ViewError::Config(
            "truth samples: expected at least 1".into(),
        ));
    }
    let file_name = config.probes.display().to_string();
    let probes_err = |message: String| ViewError::Probes {
        file: file_name.clone(),
        message,
    };
    let file = ProbeFile::load(&config.probes).map_err(|e| probes_err(e.to_string()))?;
    let probes = Probes::from_file(&file).map_err(|e| probes_err(e.to_string()))?;
    if file.positions().is_empty() {
        return Err(probes_err("the file holds no probes".into()));
    }
    let recorded_scene = metadata_key(file.metadata(), "scene");
    let recorded_hash = metadata_key(file.metadata(), "scene_hash");
    let mut warnings = Vec::new();
    let mut banner = None;
    let (scene, scene_name) = match (&config.scene, &recorded_scene) {
        (Some(given), _) => {
            let scene = Scene::load(given).map_err(|e| ViewError::Scene {
                scene: given.clone(),
                message: e.to_string(),
            })?;
            (Some(scene), Some(given.clone()))
        }
        (None, Some(rec)) => match find_recorded(rec, &config.probes) {
            Some(path) => {
                let scene = Scene::load(&path).map_err(|e| ViewError::Scene {
                    scene: format!("{rec} (the scene {file_name} was baked from)"),
                    message: e.to_string(),
                })?;
                (Some(scene), Some(rec.clone()))
            }
            None => {
                let msg = format!(
                    "the scene {file_name} was baked from ({rec}) cannot be found: showing the \
                     probes alone, geometry and truth are off (give --scene)"
                );
                warnings.push(msg.clone());
                banner = Some(msg);
                (None, Some(rec.clone()))
            }
        },
        (None, None) => {
            let msg = format!(
                "{file_name} records no scene: showing the probes alone, geometry and truth \
                 are off (give --scene)"
            );
            warnings.push(msg.clone());
            banner = Some(msg);
            (None, None)
        }
    };
    if let (Some(scene), Some(name)) = (&scene, &scene_name) {
        for w in &scene.warnings {
            warnings.push(format!("{name}: {w}"));
        }
        let hash = scene.lighting_hash_hex();
        if let Some(baked_hash) = recorded_hash.as_ref().filter(|h| **h != hash) {
            let err = ViewError::SceneMismatch {
                file: file_name.clone(),
                baked_scene: recorded_scene
                    .clone()
                    .unwrap_or_else(|| "an unrecorded scene".into()),
                baked_hash: baked_hash.clone(),
                scene: name.clone(),
                scene_hash: hash,
            };
            if !config.allow_other_scene {
                return Err(err);
            }
            let msg = format!("lighting differs from the bake's: {err}");
            warnings.push(msg.clone());
            banner = Some(format!(
                "{name} is not the scene {file_name} was baked from (lighting hash {} ≠ {}): \
                 truth and probes disagree by design",
                scene.lighting_hash_hex(),
                baked_hash
            ));
        }
    }
    let mean_irradiance = mean_irradiance(&file);
    Ok(Viewer {
        data: Arc::new(ViewData {
            file_name,
            file,
            probes,
            scene: scene.map(Arc::new),
            scene_name,
            recorded_scene,
            recorded_hash,
            banner,
            mean_irradiance,
            truth_samples: config.truth_samples,
        }),
        warnings,
    })
}

/// Mean over the file's probes of the luminance of their irradiance
/// averaged over all unit normals. The average of `E(n)` over the sphere is
/// `π·Y₀₀·c₀` (only band 0 survives: `∫Y_lm dn = 0` for `l > 0`, and
/// `Â₀ = π`), so it reads the DC coefficient alone.
fn mean_irradiance(file: &ProbeFile) -> f32 {
    let Some(c) = file.probes().map(|p| &p.coefficients) else {
        return 0.0;
    };
    let Ok(coeffs) = c.to_f32() else {
        return 0.0;
    };
    let per = (c.order * c.order) as usize;
    let n = file.probe_count().max(1);
    let sum: f64 = coeffs
        .chunks_exact(per.max(1))
        .map(|c| probekit_sh::LUMINANCE.dot(c[0]) as f64)
        .sum();
    (sum / n as f64) as f32 * std::f32::consts::PI * probekit_sh::basis::Y00
}
