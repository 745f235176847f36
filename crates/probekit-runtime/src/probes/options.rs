//! [`LoadOptions`]: what is chosen once, when a file is loaded.

use crate::format::L1Mode;
use crate::volume::Interp;

/// Choices made once, at load time, for every query of a [`crate::Probes`]
/// (no setters on a shared handle: two views of one file with different
/// choices are two loads). [`LoadOptions::default`] evaluates the file as
/// baked.
///
/// ```
/// use probekit_runtime::{Interp, LoadOptions};
/// let mut options = LoadOptions::default();
/// options.interpolation = Interp::Tricubic;
/// options.blend.directional_exponent = Some(0.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct LoadOptions {
    /// How a volume interpolates between its samples (ignored by clouds).
    /// Default [`Interp::Trilinear`]; [`Interp::Taylor`] and
    /// [`Interp::Tricubic`] need a volume with gradients (loading a volume
    /// without them fails).
    pub interpolation: Interp,
    /// How L1 (order-2) coefficients become irradiance; `None` (the
    /// default) takes the file's [`crate::format::ProbeFile::l1_mode`].
    /// Ignored for coefficients of any other order.
    pub l1_mode: Option<L1Mode>,
    /// Changes to a cloud's blend, for diagnostics and comparisons (the
    /// default changes nothing; ignored by volumes).
    pub blend: BlendOverrides,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            interpolation: Interp::Trilinear,
            l1_mode: None,
            blend: BlendOverrides::default(),
        }
    }
}

/// Overrides of what a cloud file stores for its blend (`None`: as the file
/// says). The blend itself is described in [`crate::cloud::ProbeCloud`]'s
/// `weights_at`; each field here switches off (or re-tunes) one factor of
/// it, to see what that factor does.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct BlendOverrides {
    /// Chebyshev visibility from the distance moments (`VISM`): on when the
    /// file has them.
    pub distance_moments: Option<bool>,
    /// Cell visibility bits and occluder planes (`CVSP`, `CPLN`): on when
    /// the file has them.
    pub cell_visibility: Option<bool>,
    /// Fitted per-probe weights (`PWGT`): on when the file has them.
    pub probe_weights: Option<bool>,
    /// Brightness exponent `α`, 0 to 4 (0: off): the file's, stored with
    /// its probe weights, or 0.
    pub brightness_exponent: Option<f32>,
    /// Directional brightness exponent `γ`, 0 to 4 (0: off): the file's, or
    /// 0.
    pub directional_exponent: Option<f32>,
    /// Distance bias of the Chebyshev test in metres (finite): default
    /// [`crate::cloud::visibility::DEFAULT_VISIBILITY_BIAS`].
    pub visibility_bias: Option<f32>,
    /// Sharpening exponent of the Chebyshev test, 0 to 16 (0: the test
    /// passes every probe): default
    /// [`crate::cloud::visibility::DEFAULT_VISIBILITY_SHARPNESS`].
    pub visibility_sharpness: Option<u32>,
}
