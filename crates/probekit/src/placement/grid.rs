//! The uniform grid: its sizing rule and its cell-centred points.

use super::{PlacementError, MAX_PROBES};
use crate::scene::Aabb;
use glam::Vec3;

/// The smallest grid: 2 cells per axis.
pub const MIN_GRID: usize = 8;

/// Cells per axis of the cell-centred grid over `b` with cells of edge
/// `cell` metres (when given), else about `budget` cells: cell edge
/// `∛(V / budget)`, each axis `round(extent / edge)`, at least 2. The one
/// sizing rule of every grid placement (`bake`, the sweeps, `eval
/// --compare grid`). Refuses a flat or empty box, a budget below
/// [`MIN_GRID`] (rather than baking 8 probes for `--grid 1`), a
/// non-positive cell and grids above [`MAX_PROBES`].
pub fn grid_resolution(
    b: &Aabb,
    cell: Option<f32>,
    budget: Option<usize>,
) -> Result<[usize; 3], PlacementError> {
    b.check_bake_box()?;
    let size = b.size();
    let cell = match (cell, budget) {
        (Some(c), _) if c.is_finite() && c > 0.0 => c,
        (Some(c), _) => {
            return Err(PlacementError::BadParameter(format!(
                "grid cell {c} must be a positive length in metres"
            )))
        }
        (None, Some(n)) if n >= MIN_GRID => (size.x * size.y * size.z / n as f32).cbrt(),
        (None, Some(n)) => {
            return Err(PlacementError::BadParameter(format!(
                "grid of {n} probes: a grid has at least 2 probes per axis, {MIN_GRID} in all"
            )))
        }
        (None, None) => {
            return Err(PlacementError::BadParameter(
                "grid needs a cell size or a budget".into(),
            ))
        }
    };
    // `as` saturates, so a tiny cell gives a huge count, refused below.
    let dims = size
        .to_array()
        .map(|s| ((s / cell).round() as usize).max(2));
    let count = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    match count {
        Some(n) if n <= MAX_PROBES => Ok(dims),
        _ => Err(PlacementError::TooMany {
            what: format!("grid of {}×{}×{}", dims[0], dims[1], dims[2]),
            count: count.unwrap_or(usize::MAX),
        }),
    }
}

/// Cell-centred uniform grid over `b` sized by [`grid_resolution`], x
/// fastest, then y, then z. No point lies on the box faces.
pub fn grid_points(
    b: &Aabb,
    cell: Option<f32>,
    budget: Option<usize>,
) -> Result<Vec<Vec3>, PlacementError> {
    let [nx, ny, nz] = grid_resolution(b, cell, budget)?;
    let size = b.size();
    let mut out = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let f = Vec3::new(
                    (i as f32 + 0.5) / nx as f32,
                    (j as f32 + 0.5) / ny as f32,
                    (k as f32 + 0.5) / nz as f32,
                );
                out.push(b.min + f * size);
            }
        }
    }
    Ok(out)
}
