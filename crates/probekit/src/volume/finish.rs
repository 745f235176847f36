//! Finishing a build, shared by both builders: dilating valid samples into
//! invalid ones, gradients, and the file's assembly; truncating gradients to
//! fewer bands; the relative SH distance of every threshold.

use super::settings::{BuildStats, CommonSettings, GradientMode, DEFAULT_STEP_FRACTION};
use super::source::{Captured, VolumeSource};
use super::VolumeBuildError;
use crate::format::{
    layout::{VALIDITY_INVALID, VALIDITY_VIRTUAL_OFFSET},
    Coefficients, Gradients, ProbeFile, ProbeSet, Validity, VolumeFile, VolumeStructure,
};
use glam::Vec3;

/// Relative SH distance used by every threshold: `‖a − b‖₂ / (|DC(ref)| + ε)`
/// over all RGB coefficients, `ε` = 1e-4.
pub fn relative_difference(a: &[Vec3], b: &[Vec3], reference: &[Vec3]) -> f32 {
    let d: f32 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).length_squared())
        .sum();
    d.sqrt() / (reference[0].length() + 1e-4)
}

/// Dilation, gradients and file assembly shared by both builders.
#[allow(clippy::too_many_arguments)]
pub(super) fn finish(
    src: &dyn VolumeSource,
    common: &CommonSettings,
    points: Vec<Vec3>,
    caps: Vec<Captured>,
    nbrs: &[Vec<u32>],
    finest_cell: f32,
    stats: &mut BuildStats,
    structure: VolumeStructure,
) -> Result<ProbeFile, VolumeBuildError> {
    let order = src.order();
    let n = order * order;
    let mut coeffs: Vec<Vec3> = Vec::with_capacity(points.len() * n);
    for c in &caps {
        if c.sh.coeffs().len() != n {
            return Err(VolumeBuildError::SourceOrder);
        }
        coeffs.extend_from_slice(c.sh.coeffs());
    }
    let valid: Vec<bool> = caps
        .iter()
        .map(|c| c.validity.is_finite() && c.validity >= common.validity_threshold)
        .collect();
    let weights: Vec<f32> = caps.iter().map(|c| c.validity.clamp(0.0, 1.0)).collect();
    stats.dilated = dilate(&mut coeffs, n, &valid, &weights, nbrs)?;
    let gradients = match common.gradients {
        GradientMode::None => None,
        GradientMode::Analytic => Some(
            src.analytic_gradients(&points)
                .ok_or(VolumeBuildError::NoAnalyticGradients)?,
        ),
        GradientMode::Central { step } => {
            let step = if step > 0.0 {
                step
            } else {
                DEFAULT_STEP_FRACTION * finest_cell
            };
            stats.captures += points.len() * 6;
            Some(src.central_gradients(&points, step))
        }
    };
    if let Some(g) = &gradients {
        if g.len() != points.len() * 3 * n || g.iter().any(|v| !v.is_finite()) {
            return Err(VolumeBuildError::SourceOrder);
        }
    }
    let validity = caps
        .iter()
        .zip(&valid)
        .map(|(c, &ok)| Validity {
            value: if c.validity.is_finite() {
                c.validity
            } else {
                0.0
            },
            flags: if ok { 0 } else { VALIDITY_INVALID }
                | if c.virtual_offset {
                    VALIDITY_VIRTUAL_OFFSET
                } else {
                    0
                },
        })
        .collect();
    let probes = ProbeSet {
        validity: Some(validity),
        ..ProbeSet::new(points, Coefficients::from_f32(order as u32, &coeffs)?)
    };
    let file = ProbeFile::Volume(VolumeFile {
        gradients: gradients.map(|data| Gradients {
            order: order as u32,
            data,
        }),
        ..VolumeFile::new(probes, structure)
    });
    file.validate()?;
    Ok(file)
}

/// Keeps only the first `order` bands of a volume's stored gradients (the
/// runtime interpolates the other bands trilinearly, under Taylor and
/// tricubic alike). Gradients cost `3·order²` RGB vectors per
/// sample, 3× the L2 coefficients themselves; most of the irradiance's
/// change is in the low bands (BENCHMARKS.md, "Gradient order"). A file
/// without gradients (or not a volume), or with `order` at least theirs,
/// is left unchanged.
pub fn truncate_gradients(file: &mut ProbeFile, order: u32) -> Result<(), VolumeBuildError> {
    let Some(g) = file.as_volume_mut().and_then(|v| v.gradients.as_mut()) else {
        return Ok(());
    };
    if order == 0 {
        return Err(VolumeBuildError::BadGradientOrder(order));
    }
    if order >= g.order {
        return Ok(());
    }
    let (old, new) = ((g.order * g.order) as usize, (order * order) as usize);
    if g.data.len() % old != 0 {
        return Err(VolumeBuildError::SourceOrder);
    }
    g.data = g
        .data
        .chunks_exact(old)
        .flat_map(|c| c[..new].iter().copied())
        .collect();
    g.order = order;
    file.validate()?;
    Ok(())
}

/// Replaces every invalid sample by the validity-weighted average of its
/// valid (or already dilated) neighbours, ring by ring (Jacobi order, so the
/// result does not depend on sample order). Dilated samples take part in
/// later rings with half the weight of their sources. Returns the number of
/// samples replaced; fails only if no sample is valid.
pub fn dilate(
    coeffs: &mut [Vec3],
    n: usize,
    valid: &[bool],
    validity: &[f32],
    nbrs: &[Vec<u32>],
) -> Result<usize, VolumeBuildError> {
    let count = valid.len();
    let mut known: Vec<Option<f32>> = (0..count)
        .map(|i| valid[i].then_some(validity[i].max(1e-3)))
        .collect();
    let todo = known.iter().filter(|k| k.is_none()).count();
    if todo == 0 {
        return Ok(0);
    }
    if todo == count {
        return Err(VolumeBuildError::NoValidSamples);
    }
    let mut replaced = 0;
    loop {
        let mut updates = Vec::new();
        for i in 0..count {
            if known[i].is_some() {
                continue;
            }
            let mut acc = vec![Vec3::ZERO; n];
            let mut wsum = 0.0f32;
            for &j in &nbrs[i] {
                if let Some(w) = known[j as usize] {
                    wsum += w;
                    for k in 0..n {
                        acc[k] += coeffs[j as usize * n + k] * w;
                    }
                }
            }
            if wsum > 0.0 {
                acc.iter_mut().for_each(|a| *a /= wsum);
                let w = 0.5 * wsum / nbrs[i].len().max(1) as f32;
                updates.push((i, acc, w));
            }
        }
        if updates.is_empty() {
            // Disconnected invalid samples: nothing reaches them.
            return Err(VolumeBuildError::NoValidSamples);
        }
        for (i, acc, w) in updates {
            coeffs[i * n..(i + 1) * n].copy_from_slice(&acc);
            known[i] = Some(w.max(1e-6));
            replaced += 1;
        }
        if replaced == todo {
            return Ok(replaced);
        }
    }
}
