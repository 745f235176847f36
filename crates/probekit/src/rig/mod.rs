//! Irradiance rigs, the baker's side (Yuan, Nowrouzezahrai & Sloan,
//! *Irradiance Rigs*, JGT 2011).
//!
//! A rig models how radiance SH varies over a rigid object, fitted to its
//! actual mesh by least squares (§2.2), and lights near the object are taken
//! out of the rig and evaluated analytically where the rig would be visibly
//! wrong (§3). Pieces:
//!
//! - [`RigSpec`]: `constant`, `gradient`, `lattice:NXxNYxNZ`,
//!   `mixed:X,Y,Z` (per axis `c`, `g` or `lN`); the model itself and its
//!   evaluation live in [`probekit_runtime::rig`] (module docs there).
//! - [`mesh`]: the [`mesh::Mesh`] input, the built-in car and character, and
//!   meshes from OBJ/glTF/TOML files through the scene loader.
//! - [`sample`]: evenly spread surface samples (farthest point + Lloyd).
//! - [`fit`]: the design matrix and `L = M⁺` (SVD, rank-deficiency cut-off
//!   documented there), giving a [`fit::FittedRig`] = the `.probes` record.
//! - [`lights`]: the light sets of rig scenes (the built-in demo, the cost
//!   test, a loaded scene's analytic lights); the lights themselves, their SH
//!   at a point, their exact irradiance and the 128 × 128 horizon-clipped
//!   sphere table are [`crate::lights`].
//! - [`source`]: a baked probe cloud or volume as a lighting source.
//! - [`split`]: the error tables, per-light transition distances, the
//!   analytic/transition/rig evaluation and the error metrics.
//! - [`render`]: the comparison and zone pictures.
//! - [`run`]: one experiment end to end (what `probekit rig` runs), and
//!   [`report`], what it prints of it.

pub mod fit;
pub mod lights;
pub mod mesh;
pub mod render;
pub mod report;
pub mod run;
pub mod sample;
pub mod source;
pub mod split;

use probekit_runtime::format::{AxisModel, RigModel};
use std::fmt;
use std::str::FromStr;

/// Largest lattice size per axis accepted by [`RigSpec`] parsing (a rig of
/// thousands of SH vectors is not a rig any more).
pub const MAX_AXIS_SAMPLES: u32 = 64;

/// Most sample points per rig: sampling costs O(N²) (farthest point and
/// Lloyd over 8·N candidates) and the fit O(N·K²).
pub const MAX_SAMPLES: usize = 8192;

/// Most SH vectors per rig (the SVD is dense, O(N·K²)).
pub const MAX_PARAMETERS: usize = 1024;

/// Problems setting up a rig: bad spec, mesh, scene or parameters.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RigSetupError {
    /// The rig spec string could not be parsed.
    #[error("bad rig spec {spec:?}: {reason}")]
    Spec {
        /// What was given.
        spec: String,
        /// What is wrong.
        reason: &'static str,
    },
    /// The mesh is unusable.
    #[error("bad mesh: {0}")]
    Mesh(&'static str),
    /// `builtin:` name that does not exist.
    #[error("unknown built-in {0:?} (builtin:car, builtin:character, builtin:rig-demo, builtin:paper-cost)")]
    UnknownBuiltin(String),
    /// The scene (or mesh file) could not be loaded: the scene loader's
    /// message, which names the file.
    #[error("bad scene: {0}")]
    Scene(String),
    /// The baked probe file could not be loaded or queried (names the file).
    #[error("bad probe file: {0}")]
    Probes(String),
    /// SH order outside `1..=8`.
    #[error("SH order {0} outside 1..=8")]
    Order(usize),
    /// Zero samples, or more than [`MAX_SAMPLES`].
    #[error("a rig needs 1..=8192 sample points")]
    Samples,
    /// More SH vectors than [`MAX_PARAMETERS`].
    #[error("rig has {0} SH vectors; at most 1024 are supported")]
    TooManyParameters(usize),
}

/// A rig type as written on the command line (see module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RigSpec {
    /// `constant`: one SH vector (the object-centre probe, least-squares fitted).
    Constant,
    /// `gradient`: SH plus three gradient vectors.
    Gradient,
    /// `lattice:NXxNYxNZ` or `mixed:X,Y,Z`: tensor product per axis.
    Tensor {
        /// Per-axis models (x, y, z of the mesh's box).
        axes: [AxisModel; 3],
        /// Written as `mixed:` (else `lattice:`).
        mixed: bool,
    },
}

impl RigSpec {
    /// The runtime model.
    pub fn model(self) -> RigModel {
        match self {
            RigSpec::Constant => RigModel::Constant,
            RigSpec::Gradient => RigModel::Gradient,
            RigSpec::Tensor { axes, .. } => RigModel::Tensor(axes),
        }
    }

    /// Number of SH vectors.
    pub fn parameter_count(self) -> usize {
        self.model().parameter_count().unwrap_or(0) as usize
    }
}

impl fmt::Display for RigSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RigSpec::Constant => write!(f, "constant"),
            RigSpec::Gradient => write!(f, "gradient"),
            RigSpec::Tensor { axes, mixed: false } => {
                let n = axes.map(|a| a.count());
                write!(f, "lattice:{}x{}x{}", n[0], n[1], n[2])
            }
            RigSpec::Tensor { axes, mixed: true } => {
                let s = axes.map(|a| match a {
                    AxisModel::Constant => "c".to_string(),
                    AxisModel::Gradient => "g".to_string(),
                    AxisModel::Lattice(n) => format!("l{n}"),
                });
                write!(f, "mixed:{},{},{}", s[0], s[1], s[2])
            }
        }
    }
}

impl FromStr for RigSpec {
    type Err = RigSetupError;

    /// Parses `constant`, `gradient`, `lattice:NXxNYxNZ` (each `1..=64`) or
    /// `mixed:X,Y,Z` with `X` one of `c`, `g`, `lN` (`N` in `1..=64`).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = |reason| RigSetupError::Spec {
            spec: s.to_string(),
            reason,
        };
        let count = |t: &str| -> Result<u32, RigSetupError> {
            let n: u32 = t
                .trim()
                .parse()
                .map_err(|_| err("a lattice size is not a number"))?;
            if n == 0 || n > MAX_AXIS_SAMPLES {
                return Err(err("a lattice size must be in 1..=64"));
            }
            Ok(n)
        };
        match s.trim() {
            "constant" => return Ok(RigSpec::Constant),
            "gradient" => return Ok(RigSpec::Gradient),
            _ => {}
        }
        if let Some(rest) = s.trim().strip_prefix("lattice:") {
            let parts: Vec<&str> = rest.split(['x', 'X']).collect();
            if parts.len() != 3 {
                return Err(err("lattice needs three sizes, NXxNYxNZ"));
            }
            let mut axes = [AxisModel::Constant; 3];
            for (a, p) in axes.iter_mut().zip(parts) {
                *a = AxisModel::Lattice(count(p)?);
            }
            return Ok(RigSpec::Tensor { axes, mixed: false });
        }
        if let Some(rest) = s.trim().strip_prefix("mixed:") {
            let parts: Vec<&str> = rest.split(',').map(str::trim).collect();
            if parts.len() != 3 {
                return Err(err("mixed needs three axis models, X,Y,Z"));
            }
            let mut axes = [AxisModel::Constant; 3];
            for (a, p) in axes.iter_mut().zip(parts) {
                *a = match p {
                    "c" => AxisModel::Constant,
                    "g" => AxisModel::Gradient,
                    _ => match p.strip_prefix('l') {
                        Some(n) => AxisModel::Lattice(count(n)?),
                        None => return Err(err("an axis model is c, g or lN")),
                    },
                };
            }
            return Ok(RigSpec::Tensor { axes, mixed: true });
        }
        Err(err(
            "expected constant, gradient, lattice:NXxNYxNZ or mixed:X,Y,Z",
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_parse_round_trip_and_reject() {
        for s in [
            "constant",
            "gradient",
            "lattice:8x4x2",
            "mixed:l3,g,c",
            "mixed:c,l5,g",
        ] {
            let r: RigSpec = s.parse().unwrap();
            assert_eq!(r.to_string(), s);
        }
        assert_eq!(
            "mixed:l3,g,c".parse::<RigSpec>().unwrap().parameter_count(),
            6
        );
        assert_eq!(
            "lattice:8x4x2"
                .parse::<RigSpec>()
                .unwrap()
                .parameter_count(),
            64
        );
        assert_eq!("gradient".parse::<RigSpec>().unwrap().parameter_count(), 4);
        for bad in [
            "lattice:8x4",
            "lattice:0x1x1",
            "lattice:ax1x1",
            "lattice:65x1x1",
            "mixed:l3,g",
            "mixed:l3,q,c",
            "mixed:l0,g,c",
            "cubic",
            "",
        ] {
            assert!(
                matches!(bad.parse::<RigSpec>(), Err(RigSetupError::Spec { .. })),
                "{bad}"
            );
        }
    }
}
