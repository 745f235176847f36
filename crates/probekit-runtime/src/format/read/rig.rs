//! The rigs section: one record per irradiance rig (model, SH order,
//! bounding box, name, sample points, fitting matrix, transitions).

use super::{bytes_for, pod_vec, u32_at, vec3s, Sec};
use crate::format::error::FormatError;
use crate::format::layout::{SectionId, RIG_HEADER_LEN, SECTION_HEADER_LEN};
use crate::format::{AxisModel, Rig, RigModel, Transition};
use crate::prelude::*;
use glam::Vec3;

fn parse_axis(model: u32, count: u32, id: SectionId, rig: u64) -> Result<AxisModel, FormatError> {
    let bad = |reason| FormatError::InvalidValue {
        id,
        element: rig,
        reason,
    };
    match (model, count) {
        (0, 1) => Ok(AxisModel::Constant),
        (1, 2) => Ok(AxisModel::Gradient),
        (2, n) if n >= 1 => Ok(AxisModel::Lattice(n)),
        (0..=2, _) => Err(bad("rig axis count does not match its model")),
        _ => Err(bad("unknown rig axis model")),
    }
}

pub(super) fn parse_rigs(s: &Sec<'_>) -> Result<Vec<Rig>, FormatError> {
    let [count, ..] = s.header()?;
    // Every record takes at least RIG_HEADER_LEN bytes: bound the capacity.
    let mut rigs = Vec::with_capacity((count as usize).min(s.bytes.len() / RIG_HEADER_LEN));
    let mut pos = SECTION_HEADER_LEN;
    for r in 0..count as u64 {
        let w = |k: usize| {
            pos.checked_add(4 * k)
                .and_then(|o| u32_at(s.bytes, o))
                .ok_or(FormatError::SectionSize {
                    id: s.id,
                    expected: (pos + RIG_HEADER_LEN) as u64,
                    actual: s.bytes.len() as u64,
                })
        };
        let mut h = [0u32; RIG_HEADER_LEN / 4];
        for (k, slot) in h.iter_mut().enumerate() {
            *slot = w(k)?;
        }
        let model = match h[0] {
            0 => RigModel::Constant,
            1 => RigModel::Gradient,
            2 => RigModel::Tensor([
                parse_axis(h[1], h[4], s.id, r)?,
                parse_axis(h[2], h[5], s.id, r)?,
                parse_axis(h[3], h[6], s.id, r)?,
            ]),
            _ => {
                return Err(FormatError::InvalidValue {
                    id: s.id,
                    element: r,
                    reason: "unknown rig model",
                })
            }
        };
        let order = h[7];
        let samples = h[8];
        let params = h[9];
        let transitions = h[10];
        let name_len = h[11];
        if order == 0 || order as usize > probekit_sh::MAX_ORDER {
            return Err(FormatError::InvalidValue {
                id: s.id,
                element: r,
                reason: "rig SH order outside 1..=8",
            });
        }
        if model.parameter_count() != Some(params) {
            return Err(FormatError::InvalidValue {
                id: s.id,
                element: r,
                reason: "rig parameter count does not match its model",
            });
        }
        let f = |k: usize| f32::from_bits(h[k]);
        let bbox_min = Vec3::new(f(12), f(13), f(14));
        let bbox_max = Vec3::new(f(15), f(16), f(17));
        // 0: unknown (the box's circumscribed sphere is used).
        let bounding_radius = f(18);
        let start = pos + RIG_HEADER_LEN;
        let sizes = [
            Some(name_len as usize),
            bytes_for(samples, 12),
            bytes_for(params, 4).and_then(|p| p.checked_mul(samples as usize)),
            bytes_for(transitions, 8),
        ];
        let ([name, pts, fit, tr], end) = s.arrays_at(start, sizes, false)?;
        let name = s.name(name)?;
        rigs.push(Rig {
            name,
            model,
            order,
            bbox_min,
            bbox_max,
            bounding_radius,
            samples: vec3s(pts),
            fitting: pod_vec(fit),
            transitions: pod_vec::<[f32; 2]>(tr)
                .into_iter()
                .map(|[distance, error]| Transition { distance, error })
                .collect(),
        });
        pos = end;
    }
    if pos != s.bytes.len() {
        return Err(s.size_error(pos as u64));
    }
    Ok(rigs)
}
