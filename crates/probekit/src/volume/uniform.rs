//! Uniform volumes: a grid of probes at cell corners (Tatarchuk 2005,
//! "Irradiance Volumes for Games", uniform volume subdivision).

use super::finish::finish;
use super::settings::{check_box, BuildStats, CommonSettings};
use super::source::VolumeSource;
use super::VolumeBuildError;
use crate::format::{ProbeFile, VolumeGrid, VolumeStructure};
use glam::Vec3;

/// Uniform grid with `resolution` probes per axis (each ≥ 2) over the box,
/// probes at cell corners (Tatarchuk 2005, "Uniform Volume Subdivision").
pub fn build_uniform(
    src: &dyn VolumeSource,
    common: &CommonSettings,
    resolution: [u32; 3],
) -> Result<(ProbeFile, BuildStats), VolumeBuildError> {
    check_box(common.min, common.max)?;
    if resolution.iter().any(|&r| r < 2) {
        return Err(VolumeBuildError::BadResolution(resolution));
    }
    let total = resolution.iter().map(|&r| r as u64).product::<u64>();
    if total > 1 << 26 {
        return Err(VolumeBuildError::TooLarge(total));
    }
    let [rx, ry, rz] = resolution.map(|r| r as usize);
    let size = common.max - common.min;
    let mut points = Vec::with_capacity(rx * ry * rz);
    for k in 0..rz {
        for j in 0..ry {
            for i in 0..rx {
                let f = Vec3::new(
                    i as f32 / (rx - 1) as f32,
                    j as f32 / (ry - 1) as f32,
                    k as f32 / (rz - 1) as f32,
                );
                points.push(common.min + f * size);
            }
        }
    }
    let caps = src.capture(&points);
    let mut stats = BuildStats {
        captures: points.len(),
        samples: points.len(),
        leaves: (rx - 1) * (ry - 1) * (rz - 1),
        dilated: 0,
    };
    // Neighbours: the 26 surrounding grid points.
    let idx = |i: usize, j: usize, k: usize| i + rx * (j + ry * k);
    let mut nbrs: Vec<Vec<u32>> = vec![Vec::new(); points.len()];
    for k in 0..rz {
        for j in 0..ry {
            for i in 0..rx {
                for dk in -1i64..=1 {
                    for dj in -1i64..=1 {
                        for di in -1i64..=1 {
                            let (a, b, c) = (i as i64 + di, j as i64 + dj, k as i64 + dk);
                            if (di, dj, dk) == (0, 0, 0)
                                || a < 0
                                || b < 0
                                || c < 0
                                || a >= rx as i64
                                || b >= ry as i64
                                || c >= rz as i64
                            {
                                continue;
                            }
                            nbrs[idx(i, j, k)].push(idx(a as usize, b as usize, c as usize) as u32);
                        }
                    }
                }
            }
        }
    }
    let cell = size / (Vec3::new(rx as f32, ry as f32, rz as f32) - 1.0);
    finish(
        src,
        common,
        points,
        caps,
        &nbrs,
        cell.min_element(),
        &mut stats,
        VolumeStructure::Uniform(VolumeGrid {
            min: common.min,
            max: common.max,
            resolution,
        }),
    )
    .map(|f| (f, stats))
}

/// Probes per axis for a cell size: `ceil(extent / cell) + 1`, at least 2.
pub fn resolution_for_cell(min: Vec3, max: Vec3, cell: f32) -> Result<[u32; 3], VolumeBuildError> {
    check_box(min, max)?;
    if !(cell.is_finite() && cell > 0.0) {
        return Err(VolumeBuildError::BadCell(cell));
    }
    let ext = max - min;
    let mut r = [0u32; 3];
    for a in 0..3 {
        let n = (ext[a] / cell).ceil();
        if n > 4096.0 {
            return Err(VolumeBuildError::TooLarge(n as u64));
        }
        r[a] = (n as u32).max(1) + 1;
    }
    Ok(r)
}
