//! `--blend KEY=VALUE`: overrides of a cloud's stored blend for diagnosis,
//! shared by `query` and `eval`.

use super::util::{check_exponent, cloud_flag_on_volume};
use anyhow::{anyhow, bail, Result};
use probekit::query::Predictor;

/// The `--blend` option (`#[command(flatten)]`).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct BlendArgs {
    /// Clouds: override the blend stored in the file, for diagnosis
    /// (repeatable): `visibility=off` (no distance moments nor cell
    /// visibility), `cell-visibility=off`, `probe-weights=off` (and both
    /// brightness exponents 0), `bias=METRES` (visibility test's distance
    /// bias, default 0.05), `sharpness=K` (Chebyshev exponent, default 3, at
    /// most 16), `brightness=A` (brightness exponent α, 0 to 4; default the
    /// file's), `directional=G` (directional brightness exponent γ, 0 to 4;
    /// default the file's).
    #[arg(long = "blend", value_name = "KEY=VALUE", help_heading = "Diagnosis")]
    pub blend: Vec<String>,
}

/// The overrides `--blend` asks for.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BlendOverrides {
    /// Blend without distance moments and cell visibility.
    pub no_visibility: bool,
    /// Blend without cell visibility.
    pub no_cell_visibility: bool,
    /// Blend without fitted probe weights (and brightness exponents 0).
    pub no_probe_weights: bool,
    /// Distance bias of the visibility test, metres.
    pub bias: Option<f32>,
    /// Chebyshev visibility exponent.
    pub sharpness: Option<u32>,
    /// Brightness exponent α.
    pub brightness: Option<f32>,
    /// Directional brightness exponent γ.
    pub directional: Option<f32>,
}

impl BlendArgs {
    /// The overrides, each value checked (before any work).
    pub fn parsed(&self) -> Result<BlendOverrides> {
        let mut o = BlendOverrides::default();
        for item in &self.blend {
            let bad = |why: &str| anyhow!("--blend {item}: {why}");
            let (key, value) = item
                .split_once('=')
                .ok_or_else(|| bad("expected KEY=VALUE, e.g. visibility=off"))?;
            let off = || match value {
                "off" => Ok(true),
                "on" => Ok(false),
                _ => Err(bad("expected on or off")),
            };
            let number = || value.parse::<f32>().map_err(|_| bad("expected a number"));
            match key {
                "visibility" => o.no_visibility = off()?,
                "cell-visibility" => o.no_cell_visibility = off()?,
                "probe-weights" => o.no_probe_weights = off()?,
                "bias" => {
                    let b = number()?;
                    if !b.is_finite() {
                        return Err(bad("expected a finite distance in metres"));
                    }
                    o.bias = Some(b);
                }
                "sharpness" => {
                    let k: u32 = value.parse().map_err(|_| bad("expected 0 to 16"))?;
                    if k > 16 {
                        return Err(bad("expected 0 to 16"));
                    }
                    o.sharpness = Some(k);
                }
                "brightness" => {
                    let a = number()?;
                    check_exponent("--blend brightness", a)?;
                    o.brightness = Some(a);
                }
                "directional" => {
                    let g = number()?;
                    check_exponent("--blend directional", g)?;
                    o.directional = Some(g);
                }
                _ => bail!(
                    "--blend {item}: `{key}` is not a blend override; choose visibility, \
                     cell-visibility, probe-weights, bias, sharpness, brightness or directional"
                ),
            }
        }
        Ok(o)
    }

    /// Checks the overrides and applies them to a cloud predictor; given
    /// with a volume they are an error rather than ignored.
    pub fn apply(&self, p: &mut Predictor) -> Result<BlendOverrides> {
        let o = self.parsed()?;
        if !self.blend.is_empty() && matches!(p, Predictor::Volume(..)) {
            return Err(cloud_flag_on_volume("--blend"));
        }
        o.set(p);
        Ok(o)
    }
}

impl BlendOverrides {
    /// Applies the overrides to a cloud predictor (a volume has none).
    pub fn set(&self, p: &mut Predictor) {
        if let Predictor::Cloud(c) = p {
            c.set_visibility(!self.no_visibility);
            c.set_cell_visibility(!self.no_visibility && !self.no_cell_visibility);
            c.set_probe_weighting(!self.no_probe_weights);
            if let Some(b) = self.bias {
                c.set_visibility_bias(b);
            }
            if let Some(k) = self.sharpness {
                if let Some(m) = c.visibility_maps_mut() {
                    m.set_sharpness(k);
                }
            }
            // The file's exponents belong to its fitted weights.
            let zero = self.no_probe_weights.then_some(0.0);
            if let Some(a) = self.brightness.or(zero) {
                let in_range = c.set_brightness_weighting(a).is_ok();
                debug_assert!(in_range, "checked by BlendArgs::parsed");
            }
            if let Some(g) = self.directional.or(zero) {
                let in_range = c.set_directional_brightness(g).is_ok();
                debug_assert!(in_range, "checked by BlendArgs::parsed");
            }
        }
    }
}
