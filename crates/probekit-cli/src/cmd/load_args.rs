//! `--interp` and `--blend`: how `query` and `eval` load a file (a volume's
//! interpolation, a cloud's blend overrides for diagnosis), parsed and
//! checked by [`probekit::query::QueryOptions`].

use anyhow::Result;
use probekit::query::QueryOptions;

/// The options (`#[command(flatten)]`).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct LoadArgs {
    /// Volumes: trilinear (default), taylor, tricubic, idw or
    /// leaf-trilinear (an error with a probe cloud, which interpolates by
    /// its tetrahedra).
    #[arg(long)]
    pub interp: Option<String>,
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

impl LoadArgs {
    /// The options with `--group-scale`'s values, each checked (before any
    /// work).
    pub fn options(&self, group_scales: &[String]) -> Result<QueryOptions> {
        Ok(QueryOptions::parse(
            self.interp.as_deref(),
            &self.blend,
            group_scales,
        )?)
    }
}
