//! Light groups (`LGRP`) and run-time relighting.
//!
//! A bake with `--groups` stores, besides the total radiance SH `T` of every
//! probe (`COEF`), one radiance SH `G_g` per light group `g` (a `group` key on
//! the scene's lights; `"default"`, `"emissive"` and `"environment"` for
//! lights without one, emissive triangles and the sky). Every emitter belongs
//! to exactly one group, and radiance is linear in the emitted power
//! (the rendering equation is linear in `Le`), so `T = Σ_g G_g` up to
//! rounding, and scaling group `g`'s emission by an RGB factor `s_g` scales
//! its share of the probe radiance by the same factor — direct and indirect
//! light alike ("light decoupling", Sukys 2014, §3.1.2).
//!
//! [`Relighter`] computes `T' = T + Σ_g (s_g − 1)·G_g`, which equals
//! `Σ_g s_g·G_g` when `T = Σ_g G_g` and gives `T` itself, bit for bit, when
//! every scale is 1 (so codec rounding of the groups never perturbs an
//! unscaled file).

use super::codec::Coefficients;
use super::error::FormatError;
use super::layout::SectionId;
use super::ProbeFile;
use crate::prelude::*;
use glam::Vec3;

/// The radiance SH of one light group at every probe.
#[derive(Clone, Debug, PartialEq)]
pub struct LightGroup {
    /// Group name (UTF-8, non-empty, unique in the file).
    pub name: String,
    /// Radiance SH per probe, in the order of the file's positions; same
    /// decoded order as the file's `coefficients`, codec free to differ.
    pub coefficients: Coefficients,
}

impl ProbeFile {
    /// The light group named `name`, if the file holds one.
    pub fn group(&self, name: &str) -> Option<&LightGroup> {
        self.groups().iter().find(|g| g.name == name)
    }

    /// The stored light groups, in file order (empty for rigs).
    pub fn groups(&self) -> &[LightGroup] {
        self.probes().map_or(&[], |p| &p.groups)
    }

    /// The names of the stored light groups, in file order.
    pub fn group_names(&self) -> impl Iterator<Item = &str> {
        self.groups().iter().map(|g| g.name.as_str())
    }

    /// The file's coefficients relit: each `(name, rgb)` scales light group
    /// `name` by `rgb` (groups not named keep scale 1), as
    /// `T + Σ_g (s_g − 1)·G_g` (module docs). Returned as lossless `f32`
    /// coefficients of the file's order. Errors: a name the file does not
    /// hold ([`FormatError::UnknownGroup`]), a non-finite scale
    /// ([`FormatError::NonFinite`]). Allocates; for per-frame use build a
    /// [`Relighter`] once.
    pub fn relit(&self, scales: &[(&str, Vec3)]) -> Result<Coefficients, FormatError> {
        let r = Relighter::new(self)?;
        let s = r.scales_for(scales)?;
        let mut out = vec![Vec3::ZERO; self.probe_count() * r.coeffs_per_probe()];
        r.relight_into(&s, &mut out)?;
        Coefficients::from_f32(r.order, &out)
    }
}

/// Decoded total and per-group SH of a file, ready to recombine with new
/// group scales at run time without allocating (`relight_into`,
/// `relight_probe`). The formula is in the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct Relighter {
    order: u32,
    total: Vec<Vec3>,
    names: Vec<String>,
    groups: Vec<Vec<Vec3>>,
}

impl Relighter {
    /// Decodes the file's coefficients and light groups (to `f32`).
    /// Rigs have no probes to relight: [`FormatError::MissingSection`]
    /// naming `COEF`.
    pub fn new(file: &ProbeFile) -> Result<Self, FormatError> {
        let file = file
            .probes()
            .ok_or(FormatError::MissingSection(SectionId::COEFFICIENTS))?;
        let order = file.coefficients.order;
        let total = file.coefficients.to_f32()?;
        let mut names = Vec::with_capacity(file.groups.len());
        let mut groups = Vec::with_capacity(file.groups.len());
        for g in &file.groups {
            if g.coefficients.order != order || g.coefficients.len() != file.coefficients.len() {
                return Err(FormatError::CountMismatch {
                    id: SectionId::LIGHT_GROUPS,
                    expected: total.len() as u64,
                    actual: (g.coefficients.len() * g.coefficients.coeffs_per_probe()) as u64,
                });
            }
            names.push(g.name.clone());
            groups.push(g.coefficients.to_f32()?);
        }
        Ok(Self {
            order,
            total,
            names,
            groups,
        })
    }

    /// SH order (bands) of the coefficients.
    pub fn order(&self) -> u32 {
        self.order
    }

    /// Coefficients per probe (`order²`).
    pub fn coeffs_per_probe(&self) -> usize {
        (self.order as usize).saturating_mul(self.order as usize)
    }

    /// Number of probes.
    pub fn probe_count(&self) -> usize {
        self.total
            .len()
            .checked_div(self.coeffs_per_probe())
            .unwrap_or(0)
    }

    /// Group names, in file order; index `k` pairs with `scales[k]`.
    pub fn group_names(&self) -> &[String] {
        &self.names
    }

    /// Index of the group named `name`.
    pub fn group_index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// One scale per group (file order) from `(name, rgb)` pairs; unnamed
    /// groups get 1. Errors on an unknown name or a non-finite scale.
    pub fn scales_for(&self, named: &[(&str, Vec3)]) -> Result<Vec<Vec3>, FormatError> {
        let mut s = vec![Vec3::ONE; self.names.len()];
        for (k, &(name, rgb)) in named.iter().enumerate() {
            if !rgb.is_finite() {
                return Err(FormatError::NonFinite {
                    id: SectionId::LIGHT_GROUPS,
                    element: k as u64,
                });
            }
            let i = self
                .group_index(name)
                .ok_or_else(|| FormatError::UnknownGroup(name.to_string()))?;
            s[i] = rgb;
        }
        Ok(s)
    }

    /// Writes probe `i`'s relit radiance SH into `out[..order²]`:
    /// `T_i + Σ_g (scales[g] − 1)·G_{g,i}` (groups with scale exactly 1 are
    /// skipped). Needs one scale per group and `i < probe_count()`. No allocation.
    pub fn relight_probe(
        &self,
        i: usize,
        scales: &[Vec3],
        out: &mut [Vec3],
    ) -> Result<(), FormatError> {
        let n = self.coeffs_per_probe();
        self.check_scales(scales)?;
        let range = i
            .checked_mul(n)
            .and_then(|a| Some(a..a.checked_add(n)?))
            .filter(|r| r.end <= self.total.len())
            .ok_or(FormatError::IndexOutOfRange {
                id: SectionId::LIGHT_GROUPS,
                element: i as u64,
                value: i as u64,
                limit: self.probe_count() as u64,
            })?;
        let out = out.get_mut(..n).ok_or(FormatError::Unrepresentable(
            "output slice shorter than order²",
        ))?;
        out.copy_from_slice(&self.total[range.clone()]);
        for (g, &s) in self.groups.iter().zip(scales) {
            if s == Vec3::ONE {
                continue;
            }
            let k = s - Vec3::ONE;
            for (o, c) in out.iter_mut().zip(&g[range.clone()]) {
                *o += k * *c;
            }
        }
        Ok(())
    }

    /// Relights every probe into `out` (`probe_count() · order²` long, probe
    /// after probe), e.g. a `ProbeCloud`'s coefficient buffer. No allocation.
    pub fn relight_into(&self, scales: &[Vec3], out: &mut [Vec3]) -> Result<(), FormatError> {
        self.check_scales(scales)?;
        if out.len() != self.total.len() {
            return Err(FormatError::CountMismatch {
                id: SectionId::LIGHT_GROUPS,
                expected: self.total.len() as u64,
                actual: out.len() as u64,
            });
        }
        out.copy_from_slice(&self.total);
        for (g, &s) in self.groups.iter().zip(scales) {
            if s == Vec3::ONE {
                continue;
            }
            let k = s - Vec3::ONE;
            for (o, c) in out.iter_mut().zip(g) {
                *o += k * *c;
            }
        }
        Ok(())
    }

    fn check_scales(&self, scales: &[Vec3]) -> Result<(), FormatError> {
        if scales.len() != self.names.len() {
            return Err(FormatError::CountMismatch {
                id: SectionId::LIGHT_GROUPS,
                expected: self.names.len() as u64,
                actual: scales.len() as u64,
            });
        }
        if let Some(k) = scales.iter().position(|s| !s.is_finite()) {
            return Err(FormatError::NonFinite {
                id: SectionId::LIGHT_GROUPS,
                element: k as u64,
            });
        }
        Ok(())
    }
}
