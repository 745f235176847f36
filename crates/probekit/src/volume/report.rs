//! What a volume bake looks like, per octree depth: `probekit volume --plot`.

use crate::format::Parts;
use crate::format::ProbeFile;
use crate::plot::{line_chart, PlotError};
use std::path::Path;

/// Counts at one octree depth.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DepthRow {
    /// Octree depth (0 = the whole box; a uniform grid is all depth 0).
    pub depth: u32,
    /// Leaves at this depth.
    pub leaves: usize,
    /// Samples whose finest adjacent leaf is at this depth (each sample
    /// counted once, at the deepest leaf it is a corner of).
    pub samples: usize,
    /// Fraction of the box's volume covered by leaves at this depth.
    pub volume_fraction: f64,
}

/// Per-depth leaf and sample counts of a volume file, depths `0..=deepest`
/// (rows for depths without leaves have zero counts). A uniform grid (no
/// octree) is one row at depth 0 with every cell a leaf.
pub fn depth_rows(file: &ProbeFile) -> Vec<DepthRow> {
    let Some(oct) = &file.octree() else {
        let cells = file
            .grid()
            .as_ref()
            .map(|g| {
                g.resolution
                    .iter()
                    .map(|&r| (r as usize).saturating_sub(1))
                    .product()
            })
            .unwrap_or(0);
        return vec![DepthRow {
            depth: 0,
            leaves: cells,
            samples: file.positions().len(),
            volume_fraction: 1.0,
        }];
    };
    let deepest = oct.nodes.iter().map(|n| n.depth).max().unwrap_or(0);
    let mut rows: Vec<DepthRow> = (0..=deepest)
        .map(|d| DepthRow {
            depth: d,
            ..Default::default()
        })
        .collect();
    let mut finest = vec![None::<u32>; file.positions().len()];
    for n in oct.nodes.iter().filter(|n| n.sample_count > 0) {
        let r = &mut rows[n.depth as usize];
        r.leaves += 1;
        r.volume_fraction += 0.125f64.powi(n.depth as i32);
        let lo = n.sample_offset as usize;
        for &s in &oct.samples[lo..lo + n.sample_count as usize] {
            let f = &mut finest[s as usize];
            *f = Some(f.map_or(n.depth, |d| d.max(n.depth)));
        }
    }
    for d in finest.into_iter().flatten() {
        rows[d as usize].samples += 1;
    }
    rows
}

/// Draws [`depth_rows`] as a line chart: leaves and samples per depth
/// (log₁₀ of count + 1, so empty depths show as 0) — where the octree spent
/// its samples, to tune `--max-depth` and the tolerances.
pub fn plot_depths(file: &ProbeFile, path: &Path, title: &str) -> Result<(), PlotError> {
    let rows = depth_rows(file);
    let series = |f: &dyn Fn(&DepthRow) -> usize| -> Vec<(f64, f64)> {
        rows.iter()
            .map(|r| (r.depth as f64, ((f(r) + 1) as f64).log10()))
            .collect()
    };
    line_chart(
        path,
        title,
        &[
            ("leaves".to_string(), series(&|r| r.leaves)),
            ("samples (finest leaf)".to_string(), series(&|r| r.samples)),
        ],
        "octree depth",
        "log10(count + 1)",
        false,
    )
}
