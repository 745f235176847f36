//! # The bake recipe: every setting of a bake, typed, in one place
//!
//! A [`Recipe`] says how to bake a scene: the bake box, how to place the
//! probes ([`Placement`], one variant per method holding only what that
//! method reads), how to capture them ([`Capture`]), which blend data a
//! cloud gets ([`Blend`]), how a volume is laid out ([`VolumeRecipe`]) and
//! the codec. It reads and writes TOML (`docs/recipe.md` lists every key);
//! every default lives in [`Recipe::default`] and nowhere else.
//!
//! Recipes come in layers ([`RecipeLayers`]): the defaults, then a scene
//! file's `[bake]` table (a partial recipe), then a recipe file
//! (`probekit bake --recipe R.toml`), then the command line's flags. Each
//! layer names only the keys it changes; a layer that names another
//! placement (or volume) `method` starts that section afresh from the
//! method's defaults. The resolved recipe is what a bake stores in its file
//! ([`crate::recipe::BakeRecord`]), what `inspect` prints and what `bake
//! --print-recipe` prints; baking again from it gives the same file, byte
//! for byte.
//!
//! An unknown key, a parameter under a method that does not read it, or a
//! value out of range is a [`RecipeError`] that names the key, the method
//! and the valid choices.

mod check;
mod convert;
mod layers;
mod record;

#[cfg(test)]
mod tests;

pub use convert::VolumeSettings;
pub use layers::{RecipeError, RecipeLayers};
pub use record::{BakeRecord, Part, PlacementReport};

use serde::{Deserialize, Serialize};

/// Every setting of a bake (see the module docs and `docs/recipe.md`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Recipe {
    /// Where probes go and evaluation samples: `[[min x, y, z], [max x, y,
    /// z]]` in metres. `None`: the scene's geometry bounds (a resolved
    /// recipe always holds the box it baked in).
    #[serde(rename = "box", skip_serializing_if = "Option::is_none")]
    pub bake_box: Option<[[f32; 3]; 2]>,
    /// Coefficient codec of the file.
    pub codec: CodecName,
    /// How an engine should turn the file's L1 coefficients into
    /// irradiance (stored in the file's header; only for files whose
    /// coefficients are L1: `codec = "l1"` or `capture.order = 2`).
    pub l1_evaluation: L1Evaluation,
    /// Where the probes of a cloud go (`probekit bake`).
    pub placement: Placement,
    /// How each probe's light is captured (clouds and volumes).
    pub capture: Capture,
    /// Which lights are left to run time (clouds and volumes).
    pub lights: Lights,
    /// The data a cloud blends with, against leaks (`probekit bake`).
    pub blend: Blend,
    /// The layout of an irradiance volume (`probekit volume`).
    pub volume: VolumeRecipe,
}

impl Default for Recipe {
    fn default() -> Self {
        Recipe {
            bake_box: None,
            codec: CodecName::F32,
            l1_evaluation: L1Evaluation::Linear,
            placement: Placement::default(),
            capture: Capture::default(),
            lights: Lights::default(),
            blend: Blend::default(),
            volume: VolumeRecipe::default(),
        }
    }
}

/// A coefficient codec by name (`probekit_runtime::format::Codec`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CodecName {
    /// 32-bit floats, lossless.
    #[default]
    F32,
    /// 16-bit floats.
    F16,
    /// Ratio-quantized L1 in 13 bytes per probe (order 2).
    L1,
    /// Stored ZH3 in 16 bytes per probe (decoded to L2).
    Zh3,
    /// Ratio-quantized L2 in 28 bytes per probe (order 3).
    L2,
}

/// How the L1 coefficients of a file are meant to be evaluated
/// (`probekit_runtime::format::L1Mode`, which the file's header records and
/// a loader may override).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum L1Evaluation {
    /// Plain linear SH: the clamped-cosine convolution of bands 0 and 1.
    #[default]
    Linear,
    /// Hallucinated ZH3 (Roughton et al., "ZH3: Quadratic Zonal
    /// Harmonics", I3D 2024): a zonal band-2 lobe about the blended
    /// luminance axis, derived from the L1 coefficients at query time.
    Zh3Hallucinated,
}

/// How light shells are used by adaptive placement.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LightShellsName {
    /// No shell candidates around lights.
    Off,
    /// Shell candidates around every positional light.
    On,
    /// Place both ways and keep the lower held-out error.
    #[default]
    Auto,
}

/// Where the probes of a cloud go: one variant per method, each with only
/// the parameters that method reads.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Placement {
    /// A uniform grid of cell centres over the bake box (at least 2 cells
    /// per axis): about `budget` probes, or cells of edge `cell` metres.
    Grid {
        /// Approximate probe count (default 256 when `cell` is absent).
        #[serde(skip_serializing_if = "Option::is_none")]
        budget: Option<usize>,
        /// Cell edge, metres (instead of `budget`).
        #[serde(skip_serializing_if = "Option::is_none")]
        cell: Option<f32>,
    },
    /// The positions in a CSV file (`x,y,z` per row, metres), kept as given
    /// except those inside geometry.
    Manual {
        /// The CSV file, as given (relative to the current folder).
        positions: String,
    },
    /// Error-driven refinement: probes go where interpolating the current
    /// probes disagrees most with captured light, until `budget` or
    /// `tolerance`.
    Adaptive {
        /// Most probes: a hard cap, leak-prevention probes included.
        budget: usize,
        /// Stop when the relative RMSE estimated on the placement's own
        /// captured pool falls below this.
        tolerance: f32,
        /// Candidate shells around small lights.
        light_shells: LightShellsName,
    },
    /// Spawn-and-merge placement (Sukys 2014): an initial grid, then
    /// probes spawned between contrasting pairs and merged where similar.
    #[serde(alias = "spawn-merge")]
    SpawnAndMerge {
        /// Spawning stops at this many probes (the final leak pass may add
        /// a tenth more, at least 4).
        budget: usize,
        /// Probes of the initial grid (default `budget / 2`).
        #[serde(skip_serializing_if = "Option::is_none")]
        initial: Option<usize>,
        /// Contrast threshold in (0, 1).
        contrast: f32,
        /// Sampling directions of the contrast: 6 or 26.
        directions: u32,
        /// Merge similar pairs shorter than this, metres (default 1.05
        /// initial cells).
        #[serde(skip_serializing_if = "Option::is_none")]
        merge_distance: Option<f32>,
        /// Spawn between contrasting pairs no longer than this, metres
        /// (default 2 initial cells).
        #[serde(skip_serializing_if = "Option::is_none")]
        spawn_distance: Option<f32>,
        /// Spawned probes at least this far from both ends, metres (default
        /// a quarter cell).
        #[serde(skip_serializing_if = "Option::is_none")]
        min_distance: Option<f32>,
        /// Most spawn/merge iterations.
        max_iterations: u32,
    },
    /// Gradient-ascent placement (Sukys 2014): probes of an initial
    /// grid climb the irradiance gradient; dark probes are clustered.
    GradientAscent {
        /// Probes of the initial grid.
        budget: usize,
        /// Climb the gradient of indirect light only.
        indirect_only: bool,
        /// Initial step, a fraction of the grid cell.
        step: f32,
        /// A probe stops once its step is below this fraction of the cell.
        min_step: f32,
        /// Most ascent iterations.
        max_iterations: u32,
        /// k-means clusters replacing dark probes (default one per 8).
        #[serde(skip_serializing_if = "Option::is_none")]
        dark_clusters: Option<usize>,
    },
}

impl Default for Placement {
    fn default() -> Self {
        Placement::adaptive_default()
    }
}

impl Placement {
    /// The method names, as the recipe and the command line spell them.
    pub const METHODS: [&'static str; 5] = [
        "grid",
        "manual",
        "adaptive",
        "spawn-and-merge",
        "gradient-ascent",
    ];

    /// The probe budget every budgeted method starts from.
    pub const DEFAULT_BUDGET: usize = 256;

    /// Adaptive placement with its defaults.
    pub fn adaptive_default() -> Self {
        Placement::Adaptive {
            budget: Self::DEFAULT_BUDGET,
            tolerance: 0.02,
            light_shells: LightShellsName::Auto,
        }
    }

    /// `method`'s defaults (`manual` with an empty positions path, which
    /// [`Recipe::validate`] refuses until one is given); `None` for an
    /// unknown method.
    pub fn defaults_of(method: &str) -> Option<Self> {
        Some(match method {
            "grid" => Placement::Grid {
                budget: None,
                cell: None,
            },
            "manual" => Placement::Manual {
                positions: String::new(),
            },
            "adaptive" => Self::adaptive_default(),
            "spawn-and-merge" | "spawn-merge" => Placement::SpawnAndMerge {
                budget: Self::DEFAULT_BUDGET,
                initial: None,
                contrast: 0.2,
                directions: 26,
                merge_distance: None,
                spawn_distance: None,
                min_distance: None,
                max_iterations: 8,
            },
            "gradient-ascent" => Placement::GradientAscent {
                budget: Self::DEFAULT_BUDGET,
                indirect_only: false,
                step: 0.5,
                min_step: 0.05,
                max_iterations: 8,
                dark_clusters: None,
            },
            _ => return None,
        })
    }

    /// The method's name ([`Placement::METHODS`]).
    pub fn method(&self) -> &'static str {
        match self {
            Placement::Grid { .. } => "grid",
            Placement::Manual { .. } => "manual",
            Placement::Adaptive { .. } => "adaptive",
            Placement::SpawnAndMerge { .. } => "spawn-and-merge",
            Placement::GradientAscent { .. } => "gradient-ascent",
        }
    }

    /// The probe budget, for the methods that take one (a grid's
    /// approximate count; `None` for a grid sized by `cell`).
    pub fn budget(&self) -> Option<usize> {
        match self {
            Placement::Grid { budget, cell } => match (budget, cell) {
                (Some(b), _) => Some(*b),
                (None, None) => Some(Self::DEFAULT_BUDGET),
                (None, Some(_)) => None,
            },
            Placement::Manual { .. } => None,
            Placement::Adaptive { budget, .. }
            | Placement::SpawnAndMerge { budget, .. }
            | Placement::GradientAscent { budget, .. } => Some(*budget),
        }
    }
}

/// How each probe's light is captured by the path tracer.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Capture {
    /// Receiver directions per probe.
    pub samples: u32,
    /// Scattering events per path (0: light from emitters only).
    pub bounces: u32,
    /// SH bands stored: 2 = L1, 3 = L2 (up to 8).
    pub order: usize,
    /// Random seed: the same seed gives the same bytes.
    pub seed: u64,
    /// Scattering events before Russian roulette may end a path.
    pub russian_roulette_depth: u32,
    /// Store indirect light only (an engine adds direct light itself).
    pub indirect_only: bool,
    /// Also store one SH per light group (`group` key of lights), for
    /// relighting at run time.
    pub groups: bool,
    /// Probe validity and the virtual offset out of geometry.
    pub validity: Validity,
}

impl Default for Capture {
    fn default() -> Self {
        Capture {
            samples: 1024,
            bounces: 3,
            order: 3,
            seed: 1,
            russian_roulette_depth: 3,
            indirect_only: false,
            groups: false,
            validity: Validity::default(),
        }
    }
}

/// The run-time light split: which lights' direct light is left out of the
/// probes' SH and evaluated exactly at run time, times each probe's stored
/// occlusion of it (`docs/scene-format.md`, "Light modes").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Lights {
    /// Split lights as their `mode` says; false bakes every light.
    pub split: bool,
    /// Most run-time lights that may reach one probe (K); beyond it,
    /// whole lights are demoted to baked, lowest contribution first.
    pub max_per_probe: u32,
    /// Stratified shadow rays per probe and light for the visible fraction
    /// of a sphere, a disk or a sun with an angular diameter.
    pub occlusion_samples: u32,
    /// Held-out points on which `auto` lights are decided: half uniform in
    /// the bake box, half drawn in 1 m balls around the positional lights,
    /// each weighted by the volume it stands for.
    pub decision_points: u32,
    /// The bake's choice per scene light, in the scene's order: `runtime`,
    /// `baked`, or `demoted` (written by the bake into the file's record;
    /// a recipe that gives it is followed instead of deciding again).
    /// Empty: decide.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub resolved: Vec<ResolvedMode>,
}

impl Default for Lights {
    fn default() -> Self {
        Lights {
            split: true,
            max_per_probe: 4,
            occlusion_samples: 64,
            decision_points: 2000,
            resolved: Vec::new(),
        }
    }
}

impl Lights {
    /// Scene light indices (0-based, increasing) that `resolved` records
    /// as run-time: the lights whose direct light a file's SH leaves out.
    pub fn runtime_indices(&self) -> Vec<usize> {
        (self.resolved.iter().enumerate())
            .filter(|(_, m)| **m == ResolvedMode::Runtime)
            .map(|(i, _)| i)
            .collect()
    }
}

/// Where a light ended up after the bake's choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ResolvedMode {
    /// Its light is in the SH.
    Baked,
    /// Its direct light is evaluated at run time.
    Runtime,
    /// A candidate of the split that the bake kept baked (its held-out
    /// choice or K per probe): captured apart, its direct light added back
    /// to the SH. Baking again with the choice repeats that, so the file
    /// is the same byte for byte.
    Demoted,
}

/// Probe validity: probes inside geometry are moved out or flagged.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Validity {
    /// A probe is invalid when more than this fraction of its rays hit back
    /// faces.
    pub backface_threshold: f32,
    /// Move invalid probes out of geometry before capturing.
    pub virtual_offset: bool,
    /// Distance beyond the back face to move to, metres.
    pub offset_margin: f32,
    /// Rays of the validity pre-pass.
    pub pre_pass_rays: u32,
    /// Most offset moves per probe.
    pub max_offset_steps: u32,
}

impl Default for Validity {
    fn default() -> Self {
        Validity {
            backface_threshold: 0.25,
            virtual_offset: true,
            offset_margin: 0.02,
            pre_pass_rays: 256,
            max_offset_steps: 3,
        }
    }
}

/// The cell lattice of cell visibility: a subdivision, `auto`, or none.
/// Written `"auto"` or a number.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CellVisibility {
    /// `"auto"`: 4 to 8 from the cell size.
    #[default]
    Auto,
    /// A fixed subdivision 1 to 8; 0 bakes none.
    Subdivision(u32),
}

/// A blend exponent: a number, or `auto` (chosen by the weight fit).
/// Written `"auto"` or a number.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Exponent {
    /// `"auto"`: the fit chooses 0, 0.5 or 1 by cross-validation.
    #[default]
    Auto,
    /// This exponent, 0 to 4.
    Value(f32),
}

/// `"auto"` or a number, as a recipe writes [`CellVisibility`] and
/// [`Exponent`].
#[derive(Deserialize)]
#[serde(untagged)]
enum AutoOr {
    Text(String),
    Number(f64),
}

impl AutoOr {
    fn read<E: serde::de::Error>(self) -> Result<Option<f64>, E> {
        match self {
            AutoOr::Number(x) => Ok(Some(x)),
            AutoOr::Text(s) if s == "auto" => Ok(None),
            AutoOr::Text(s) => Err(E::custom(format!("\"{s}\": expected \"auto\" or a number"))),
        }
    }
}

impl Serialize for CellVisibility {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            CellVisibility::Auto => s.serialize_str("auto"),
            CellVisibility::Subdivision(k) => s.serialize_u32(*k),
        }
    }
}

impl<'de> Deserialize<'de> for CellVisibility {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        match AutoOr::deserialize(d)?.read()? {
            None => Ok(CellVisibility::Auto),
            Some(x) if x >= 0.0 && x.fract() == 0.0 && x <= u32::MAX as f64 => {
                Ok(CellVisibility::Subdivision(x as u32))
            }
            Some(x) => Err(serde::de::Error::custom(format!(
                "{x}: expected \"auto\", 0 (none) or a subdivision 1 to 8"
            ))),
        }
    }
}

impl Serialize for Exponent {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Exponent::Auto => s.serialize_str("auto"),
            Exponent::Value(v) => s.serialize_f32(*v),
        }
    }
}

impl<'de> Deserialize<'de> for Exponent {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(match AutoOr::deserialize(d)?.read()? {
            None => Exponent::Auto,
            Some(x) => Exponent::Value(x as f32),
        })
    }
}

/// The data a probe cloud blends with, against light leaking through
/// walls (see `docs/recipe.md` for what each costs and buys).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Blend {
    /// Texels per side of each probe's octahedral distance-moment map
    /// (Chebyshev visibility, 1 to 64); 0: none.
    pub distance_moments: u32,
    /// Per-cell visibility lattice: `"auto"` (4 to 8 from the cell size), a
    /// subdivision 1 to 8, or 0 for none.
    pub cell_visibility: CellVisibility,
    /// Fit occluder planes to cells one flat wall cuts (with cell
    /// visibility only).
    pub occluder_planes: bool,
    /// Fit per-probe blend weights to path-traced training points.
    pub probe_weights: bool,
    /// Brightness exponent of the blend, fitted with the weights: `"auto"`
    /// or 0 to 4 (probe weights only).
    pub brightness_exponent: Exponent,
    /// Directional brightness exponent, 0 to 4 (probe weights only).
    pub directional_exponent: f32,
    /// The probe-weight fit.
    pub fit: Fit,
}

impl Default for Blend {
    fn default() -> Self {
        Blend {
            distance_moments: 8,
            cell_visibility: CellVisibility::Auto,
            occluder_planes: true,
            probe_weights: true,
            brightness_exponent: Exponent::Auto,
            directional_exponent: 0.5,
            fit: Fit::default(),
        }
    }
}

impl Blend {
    /// No blend data: the cloud blends with plain barycentric weights.
    pub fn none() -> Self {
        Blend {
            distance_moments: 0,
            cell_visibility: CellVisibility::Subdivision(0),
            occluder_planes: false,
            probe_weights: false,
            ..Blend::default()
        }
    }
}

/// The probe-weight fit (`blend.probe_weights`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Fit {
    /// Training points per probe.
    pub points_per_probe: u32,
    /// Path-traced samples per training point.
    pub samples: u32,
    /// Regularization ρ (≥ 0): larger keeps the weights nearer 1.
    pub regularization: f32,
    /// Weight β of the absolute error beside the relative one (≥ 0).
    pub absolute_weight: f32,
}

impl Default for Fit {
    fn default() -> Self {
        Fit {
            points_per_probe: 16,
            samples: 64,
            regularization: 1e-5,
            absolute_weight: 1.0,
        }
    }
}

/// The layout of an irradiance volume (`probekit volume`): its method's
/// keys sit in `[volume]` itself, the gradients in `[volume.gradients]`.
/// (Unknown keys are refused by the recipe's key check, which knows the
/// method in effect.)
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct VolumeRecipe {
    /// Uniform grid or adaptive octree.
    #[serde(flatten)]
    pub layout: VolumeLayout,
    /// Per-sample SH gradients.
    pub gradients: Gradients,
}

/// A uniform grid or an adaptive octree.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "kebab-case", deny_unknown_fields)]
pub enum VolumeLayout {
    /// Probes at the corners of a uniform grid: cells of edge `cell`
    /// metres, or `resolution` probes per axis.
    Uniform {
        /// Cell edge, metres.
        #[serde(skip_serializing_if = "Option::is_none")]
        cell: Option<f32>,
        /// Probes per axis (each ≥ 2).
        #[serde(skip_serializing_if = "Option::is_none")]
        resolution: Option<[u32; 3]>,
    },
    /// An adaptive octree forest over near-cubic root cells, refined where
    /// interpolation mispredicts captured light.
    Octree {
        /// Depth every root is refined to.
        min_depth: u32,
        /// Deepest refinement.
        max_depth: u32,
        /// Root cells per axis (default near-cubic from the box).
        #[serde(skip_serializing_if = "Option::is_none")]
        roots: Option<[u32; 3]>,
        /// Refine a cell whose prediction error exceeds this many noise
        /// levels.
        tolerance: f32,
        /// Prune children that predict within this relative error.
        prune: f32,
        /// Relative error floor, in noise units.
        relative_floor: f32,
        /// Refine cells that hold geometry down to `geometry_depth`.
        geometry: bool,
        /// Depth of the geometry refinement.
        geometry_depth: u32,
        /// Depth of the refinement around emitters (default `max_depth`).
        #[serde(skip_serializing_if = "Option::is_none")]
        emitter_depth: Option<u32>,
        /// Noise multiple `k` of the capture's noise estimate.
        noise_k: f32,
        /// Keep neighbouring leaves within one level.
        balance: bool,
        /// Depth-weighted error factor (0: off).
        depth_factor: f32,
        /// Refine where the gradient exceeds this (none by default).
        #[serde(skip_serializing_if = "Option::is_none")]
        gradient_threshold: Option<f32>,
    },
}

impl Default for VolumeLayout {
    fn default() -> Self {
        VolumeLayout::defaults_of("octree").unwrap_or(VolumeLayout::Uniform {
            cell: None,
            resolution: None,
        })
    }
}

impl VolumeLayout {
    /// The method names.
    pub const METHODS: [&'static str; 2] = ["uniform", "octree"];

    /// `method`'s defaults; `None` for an unknown method.
    pub fn defaults_of(method: &str) -> Option<Self> {
        Some(match method {
            "uniform" => VolumeLayout::Uniform {
                cell: None,
                resolution: None,
            },
            "octree" => VolumeLayout::Octree {
                min_depth: 1,
                max_depth: 4,
                roots: None,
                tolerance: 1.0,
                prune: 0.1,
                relative_floor: 4.0,
                geometry: true,
                geometry_depth: 2,
                emitter_depth: None,
                noise_k: 2.0,
                balance: true,
                depth_factor: 0.0,
                gradient_threshold: None,
            },
            _ => return None,
        })
    }

    /// The method's name.
    pub fn method(&self) -> &'static str {
        match self {
            VolumeLayout::Uniform { .. } => "uniform",
            VolumeLayout::Octree { .. } => "octree",
        }
    }
}

/// Per-sample SH gradients of a volume (Tatarchuk 2005's Taylor step).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Gradients {
    /// `none`, `central` (differences of 6 extra captures) or `analytic`
    /// (closed-form sources only).
    pub mode: GradientModeName,
    /// Central differences' offset, metres (default a fraction of the
    /// finest cell).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step: Option<f32>,
    /// Keep gradients of the first bands only (1 to the capture order).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<u32>,
}

/// How volume gradients are computed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum GradientModeName {
    /// No gradients.
    #[default]
    None,
    /// Central differences of captures.
    Central,
    /// The source's closed form.
    Analytic,
}

impl Recipe {
    /// The recipe as TOML, floats written as the shortest decimal that reads
    /// back to the same `f32` (so a printed recipe bakes the same file).
    pub fn to_toml(&self) -> String {
        // Through JSON: serde_json writes an f32 as its shortest decimal,
        // which the TOML writer then keeps.
        let json = serde_json::to_string(self).unwrap_or_default();
        let value: toml::Value =
            serde_json::from_str(&json).unwrap_or(toml::Value::Table(toml::Table::new()));
        toml::to_string(&value).unwrap_or_default()
    }
}
