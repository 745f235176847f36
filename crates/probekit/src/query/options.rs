//! [`QueryOptions`]: what `probekit query`, `eval`, `render` and `rig`
//! choose about loading a file (a volume's interpolation, a cloud's blend
//! overrides, light-group scales), parsed from their command-line values
//! and checked against the file's kind before any work: a choice the file
//! would ignore is an error, not a silent no-op.

use glam::Vec3;
use probekit_runtime::cloud::MAX_BRIGHTNESS_EXPONENT;
use probekit_runtime::format::{FormatError, Relighter};
use probekit_runtime::{
    BlendOverrides, Interp, LoadError, LoadOptions, ProbeFile, ProbeFileKind, Probes,
};
use thiserror::Error;

/// The blend override keys of [`parse_blend`], in the order the error for
/// an unknown key lists them.
const BLEND_KEYS: &str = "visibility, cell-visibility, probe-weights, bias, sharpness, \
                          brightness or directional";

/// Largest Chebyshev sharpness a blend override takes.
const MAX_SHARPNESS: u32 = 16;

/// Why a command's load options are refused. The messages name the
/// command-line flag the value came from.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum QueryOptionError {
    /// A `--blend` item that is not `KEY=VALUE` with a known key and a
    /// value of the key's kind.
    #[error("--blend {item}: {why}")]
    Blend {
        /// The item as given.
        item: String,
        /// What is wrong with it.
        why: String,
    },
    /// A brightness exponent outside `0..=`[`MAX_BRIGHTNESS_EXPONENT`] (or
    /// not a number).
    #[error("{flag} {value}: expected 0 to {max}", max = MAX_BRIGHTNESS_EXPONENT)]
    Exponent {
        /// The flag (and key) that gave it.
        flag: String,
        /// The value.
        value: f32,
    },
    /// An interpolation name [`Interp::from_name`] does not know.
    #[error("--interp {0}: expected trilinear, taylor, tricubic, idw or leaf-trilinear")]
    UnknownInterp(String),
    /// A `--group-scale` item that is not `NAME=s` or `NAME=r:g:b` (finite).
    #[error("--group-scale {0}: expected NAME=s or NAME=r:g:b")]
    GroupScale(String),
    /// A cloud's blend choice (named by its flag) given with a volume.
    #[error("{0} applies to probe clouds; this file is an irradiance volume")]
    CloudOnly(String),
    /// A volume's interpolation given with a probe cloud.
    #[error(
        "--interp {0} applies to irradiance volumes; this file is a probe cloud (it \
         interpolates by its tetrahedra)"
    )]
    InterpOnCloud(String),
    /// Light-group scales given for a file without light groups.
    #[error("--group-scale needs a file baked with --groups (it has no light groups)")]
    NoGroups,
    /// The scales cannot relight the file (an unknown group name, say).
    #[error("--group-scale (groups: {groups}): {source}")]
    Relight {
        /// The file's group names, comma-separated.
        groups: String,
        /// What the relighting refused.
        source: FormatError,
    },
    /// The file cannot be loaded with these options.
    #[error(transparent)]
    Load(#[from] LoadError),
}

/// A command's choices about loading a file, parsed and checked
/// ([`QueryOptions::parse`]); [`QueryOptions::load`] loads a file with
/// them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct QueryOptions {
    /// A volume's interpolation, with the name it was given by (`None`:
    /// trilinear, and any kind of file).
    pub interpolation: Option<(Interp, String)>,
    /// Overrides of a cloud's blend (the default: none, and any kind of
    /// file).
    pub blend: BlendOverrides,
    /// Light-group scales `(name, rgb)`, applied in place after loading
    /// ([`Probes::relight`]).
    pub group_scales: Vec<(String, Vec3)>,
}

impl QueryOptions {
    /// Parses the values of `--interp` ([`parse_interp`]), `--blend`
    /// ([`parse_blend`]) and `--group-scale` ([`parse_group_scales`]).
    pub fn parse(
        interp: Option<&str>,
        blend: &[String],
        group_scales: &[String],
    ) -> Result<Self, QueryOptionError> {
        Ok(Self {
            interpolation: match interp {
                Some(s) => Some((parse_interp(s)?, s.to_string())),
                None => None,
            },
            blend: parse_blend(blend)?,
            group_scales: parse_group_scales(group_scales)?,
        })
    }

    /// The runtime's load options for a file of kind `kind`, refusing what
    /// that kind would ignore: an interpolation for anything but a volume,
    /// blend overrides for a volume.
    pub fn load_options(&self, kind: ProbeFileKind) -> Result<LoadOptions, QueryOptionError> {
        let volume = kind == ProbeFileKind::Volume;
        let mut options = LoadOptions::default();
        if let Some((interp, name)) = &self.interpolation {
            if !volume {
                return Err(QueryOptionError::InterpOnCloud(name.clone()));
            }
            options.interpolation = *interp;
        }
        if self.blend != BlendOverrides::default() {
            if volume {
                return Err(QueryOptionError::CloudOnly("--blend".into()));
            }
            options.blend = self.blend;
        }
        Ok(options)
    }

    /// Loads `file` with [`QueryOptions::load_options`] for its kind and
    /// relights it by the group scales, in place, as an engine does (a
    /// cloud keeps the blend of its baked light).
    pub fn load(&self, file: &ProbeFile) -> Result<Probes, QueryOptionError> {
        let mut probes = Probes::from_file(file, self.load_options(file.kind())?)?;
        if !self.group_scales.is_empty() {
            if file.groups().is_empty() {
                return Err(QueryOptionError::NoGroups);
            }
            let mut relight = || -> Result<(), FormatError> {
                let relighter = Relighter::new(file)?;
                let named: Vec<(&str, Vec3)> = (self.group_scales.iter())
                    .map(|(n, s)| (n.as_str(), *s))
                    .collect();
                probes.relight(&relighter, &relighter.scales_for(&named)?)
            };
            relight().map_err(|source| QueryOptionError::Relight {
                groups: file.group_names().collect::<Vec<_>>().join(", "),
                source,
            })?;
        }
        Ok(probes)
    }
}

/// A volume interpolation by name: `trilinear`, `taylor`, `tricubic`, `idw`
/// or `leaf-trilinear` ([`Interp::from_name`]).
pub fn parse_interp(name: &str) -> Result<Interp, QueryOptionError> {
    Interp::from_name(name).ok_or_else(|| QueryOptionError::UnknownInterp(name.to_string()))
}

/// Checks a brightness exponent given by `flag`: `0..=`
/// [`MAX_BRIGHTNESS_EXPONENT`], what the runtime accepts (NaN refused).
pub fn check_exponent(flag: &str, value: f32) -> Result<f32, QueryOptionError> {
    if (0.0..=MAX_BRIGHTNESS_EXPONENT).contains(&value) {
        Ok(value)
    } else {
        Err(QueryOptionError::Exponent {
            flag: flag.to_string(),
            value,
        })
    }
}

/// The blend overrides of `--blend KEY=VALUE` items, in any order, each
/// value checked: `visibility=off` (no distance moments nor cell
/// visibility), `cell-visibility=off`, `probe-weights=off` (and both
/// brightness exponents 0 unless given: the file's exponents belong to its
/// fitted weights), `bias=METRES` (finite), `sharpness=K` (0 to 16),
/// `brightness=A` and `directional=G` (0 to 4); `on` for the switches
/// asks for the factor (as the file has it). No items: no overrides.
pub fn parse_blend(items: &[String]) -> Result<BlendOverrides, QueryOptionError> {
    let (mut visibility, mut cells, mut weights) = (None, None, None);
    let mut o = BlendOverrides::default();
    for item in items {
        let bad = |why: &str| QueryOptionError::Blend {
            item: item.clone(),
            why: why.to_string(),
        };
        let (key, value) = item
            .split_once('=')
            .ok_or_else(|| bad("expected KEY=VALUE, e.g. visibility=off"))?;
        let on = || match value {
            "on" => Ok(true),
            "off" => Ok(false),
            _ => Err(bad("expected on or off")),
        };
        let number = || value.parse::<f32>().map_err(|_| bad("expected a number"));
        match key {
            "visibility" => visibility = Some(on()?),
            "cell-visibility" => cells = Some(on()?),
            "probe-weights" => weights = Some(on()?),
            "bias" => {
                let b = number()?;
                if !b.is_finite() {
                    return Err(bad("expected a finite distance in metres"));
                }
                o.visibility_bias = Some(b);
            }
            "sharpness" => {
                let k = value.parse().ok().filter(|&k| k <= MAX_SHARPNESS);
                o.visibility_sharpness = Some(k.ok_or_else(|| bad("expected 0 to 16"))?);
            }
            "brightness" => {
                o.brightness_exponent = Some(check_exponent("--blend brightness", number()?)?);
            }
            "directional" => {
                o.directional_exponent = Some(check_exponent("--blend directional", number()?)?);
            }
            _ => {
                return Err(bad(&format!(
                    "`{key}` is not a blend override; choose {BLEND_KEYS}"
                )))
            }
        }
    }
    // Without visibility, cell visibility is off too, whatever its own key.
    o.distance_moments = visibility;
    o.cell_visibility = if visibility == Some(false) {
        Some(false)
    } else {
        cells
    };
    o.probe_weights = weights;
    if weights == Some(false) {
        o.brightness_exponent = o.brightness_exponent.or(Some(0.0));
        o.directional_exponent = o.directional_exponent.or(Some(0.0));
    }
    Ok(o)
}

/// Light-group scales from `--group-scale` values: `NAME=s` or
/// `NAME=r:g:b`, several per value separated by commas.
pub fn parse_group_scales(items: &[String]) -> Result<Vec<(String, Vec3)>, QueryOptionError> {
    let mut out = Vec::new();
    for item in items.iter().flat_map(|a| a.split(',')) {
        let bad = || QueryOptionError::GroupScale(item.to_string());
        let (name, value) = item.split_once('=').ok_or_else(bad)?;
        let parts: Vec<f32> = value
            .split(':')
            .map(|v| v.trim().parse::<f32>().map_err(|_| bad()))
            .collect::<Result<_, _>>()?;
        let rgb = match parts[..] {
            [s] => Vec3::splat(s),
            [r, g, b] => Vec3::new(r, g, b),
            _ => return Err(bad()),
        };
        if name.trim().is_empty() || !rgb.is_finite() {
            return Err(bad());
        }
        out.push((name.trim().to_string(), rgb));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn items(s: &[&str]) -> Vec<String> {
        s.iter().map(|s| s.to_string()).collect()
    }

    /// The overrides of each key, order-independent, and the errors.
    #[test]
    fn blend_items_parse_to_overrides() {
        assert_eq!(parse_blend(&[]).unwrap(), BlendOverrides::default());
        let o = parse_blend(&items(&["cell-visibility=on", "visibility=off"])).unwrap();
        assert_eq!(
            (o.distance_moments, o.cell_visibility),
            (Some(false), Some(false))
        );
        let o = parse_blend(&items(&["probe-weights=off", "brightness=1.5"])).unwrap();
        assert_eq!(o.probe_weights, Some(false));
        assert_eq!(o.brightness_exponent, Some(1.5));
        assert_eq!(o.directional_exponent, Some(0.0));
        let o = parse_blend(&items(&["bias=0.1", "sharpness=4", "visibility=on"])).unwrap();
        assert_eq!(o.visibility_bias, Some(0.1));
        assert_eq!(o.visibility_sharpness, Some(4));
        assert_eq!((o.distance_moments, o.cell_visibility), (Some(true), None));
        for (bad, needle) in [
            ("visibility", "expected KEY=VALUE"),
            ("visibility=maybe", "expected on or off"),
            ("bias=inf", "finite"),
            ("sharpness=17", "0 to 16"),
            ("brightness=5", "--blend brightness 5: expected 0 to 4"),
            ("directional=x", "expected a number"),
            ("colour=red", "`colour` is not a blend override"),
        ] {
            let e = parse_blend(&items(&[bad])).unwrap_err().to_string();
            assert!(e.contains(needle), "{bad}: {e}");
        }
    }

    #[test]
    fn group_scales_and_interpolations_parse() {
        let s = parse_group_scales(&items(&["sun=2,lamp=1:0.5:0", " sky = 0"])).unwrap();
        assert_eq!(s[0], ("sun".into(), Vec3::splat(2.0)));
        assert_eq!(s[1], ("lamp".into(), Vec3::new(1.0, 0.5, 0.0)));
        assert_eq!(s[2], ("sky".into(), Vec3::ZERO));
        for bad in ["sun", "=2", "sun=1:2", "sun=nan"] {
            assert!(parse_group_scales(&items(&[bad])).is_err(), "{bad}");
        }
        assert_eq!(parse_interp("idw").unwrap(), Interp::InverseDistance);
        assert!(parse_interp("cubic").is_err());
    }

    /// A choice the file's kind would ignore is refused.
    #[test]
    fn choices_of_another_kind_are_refused() {
        let o = QueryOptions::parse(Some("tricubic"), &[], &[]).unwrap();
        assert_eq!(
            o.load_options(ProbeFileKind::Volume).unwrap().interpolation,
            Interp::Tricubic
        );
        assert!(matches!(
            o.load_options(ProbeFileKind::Cloud),
            Err(QueryOptionError::InterpOnCloud(_))
        ));
        let o = QueryOptions::parse(None, &items(&["bias=0.2"]), &[]).unwrap();
        assert_eq!(
            o.load_options(ProbeFileKind::Cloud)
                .unwrap()
                .blend
                .visibility_bias,
            Some(0.2)
        );
        let e = o.load_options(ProbeFileKind::Volume).unwrap_err();
        assert!(e.to_string().starts_with("--blend applies to probe clouds"));
    }
}
