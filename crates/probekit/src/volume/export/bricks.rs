//! The brick atlas ([`export_bricks`]): the usual GPU form of an adaptive
//! volume (a two-level sparse grid, as in brick maps and Unreal's volumetric
//! lightmaps).
//!
//! An **indirection texture** of `N = roots·2^Di` texels per axis over the
//! box, `Di = max_depth − 2`, and an **atlas** of bricks of `(BRICK_CELLS +
//! 1)³ = 5³` texels. A brick covers one octree node: a node at depth `Di`
//! whose leaves are finer (then its 5 texels per axis are exactly the finest
//! lattice), or a leaf shallower than `Di` (then it covers `2^level`
//! indirection cells per axis, `level = Di − depth`). Texels sit at the
//! node's corners and at multiples of a quarter of it, duplicated on faces
//! shared with neighbouring bricks, so a hardware trilinear fetch inside a
//! brick needs no borders. Indirection texel `(r, g, b, a)`
//! (`R8G8B8A8_UINT`) = the brick's position in the atlas (in bricks) and
//! its `level`. Lookup for a point `p`: `g = (p − min)/(max − min)·N`, `c =
//! ⌊g⌋`, `(b, level) = indirection[c]`, `s = 2^level`, `f = (g −
//! ⌊c/s⌋·s)/s ∈ [0,1]³`, atlas texel coordinate `b·5 + ½ + 4f` (divide by
//! the atlas resolution for normalised coordinates). Coefficients are
//! encoded as in the dense export ([`super::lattice`], one atlas texture
//! per group). Between a coarse brick and finer ones the faces agree at the
//! brick texels (both come from the continuous octree query) and differ by
//! the usual T-junction interpolation in between.

use super::lattice::{encode_sh_textures, with_coefficient_fields};
use super::{export_ktx2, ExportError, Ktx2, Ktx2Encoding, Ktx2Export, TexelFormat};
use crate::volume::{Interp, Volume};
use glam::Vec3;

/// Cells per axis of one brick of [`export_bricks`]; a brick holds
/// `(BRICK_CELLS + 1)³` texels (its faces are duplicated in its neighbours,
/// so hardware trilinear filtering inside a brick needs no border logic).
pub const BRICK_CELLS: u32 = 4;

/// Exports an octree volume as a **brick atlas** (module docs, "Brick
/// atlas"): bricks of `(BRICK_CELLS + 1)³` texels, one per octree node at
/// the indirection depth `Di = max_depth − 2` that has finer leaves and one
/// per shallower leaf, packed into atlas textures (encoded as
/// [`export_ktx2`] does), plus an `R8G8B8A8_UINT` indirection texture of
/// `roots·2^Di` texels per axis. Memory follows the octree's adaptivity instead of
/// its finest level. A uniform volume has no octree: use [`export_ktx2`].
pub fn export_bricks(volume: &Volume, encoding: Ktx2Encoding) -> Result<Ktx2Export, ExportError> {
    bricks_from_plan(volume, &plan_bricks(volume)?, encoding)
}

/// Which bricks an octree's atlas holds and where: the cheap half of
/// [`export_bricks`] (no sampling), enough to size the atlas.
struct BrickPlan {
    /// Indirection texels per axis (`roots · 2^Di`).
    cells: [u32; 3],
    /// Per brick: (level, node coordinates at depth `Di − level`).
    bricks: Vec<(u32, [u32; 3])>,
    /// Per indirection cell (x fastest): (brick, level).
    cell_brick: Vec<(u32, u32)>,
    /// Atlas size in bricks.
    atlas: [usize; 3],
    /// Atlas size in texels.
    res: [u32; 3],
}

fn plan_bricks(volume: &Volume) -> Result<BrickPlan, ExportError> {
    if volume.grid_resolution().is_some() {
        return Err(ExportError::NotAnOctree);
    }
    let depth = volume.max_depth();
    let di = depth.saturating_sub(BRICK_CELLS.trailing_zeros()).min(8);
    let roots = volume.root_grid().unwrap_or([1; 3]);
    if roots.iter().any(|&r| r > 1 << 12) {
        return Err(ExportError::TooLarge(roots));
    }
    let cells = roots.map(|r| r << di);
    let (min, max) = volume.bounds();
    let size = max - min;
    // Which brick each indirection cell uses: (level, node coordinates at
    // depth di − level), numbered in first-use order (deterministic).
    let mut index: std::collections::BTreeMap<(u32, [u32; 3]), u32> = Default::default();
    let mut bricks: Vec<(u32, [u32; 3])> = Vec::new();
    let total: u64 = cells.iter().map(|&c| c as u64).product();
    if total > 1 << 24 {
        return Err(ExportError::TooLarge(cells));
    }
    let mut cell_brick = Vec::with_capacity(total as usize);
    for k in 0..cells[2] {
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                let q = [i, j, k];
                let c = min
                    + Vec3::from_array(std::array::from_fn(|a| {
                        (q[a] as f32 + 0.5) / cells[a] as f32
                    })) * size;
                let level = di - volume.leaf_depth_at(c).min(di);
                let node = q.map(|x| x >> level);
                let b = *index.entry((level, node)).or_insert_with(|| {
                    bricks.push((level, node));
                    (bricks.len() - 1) as u32
                });
                cell_brick.push((b, level));
            }
        }
    }
    let nb = bricks.len();
    let ax = ((nb as f64).cbrt().ceil() as usize).max(1);
    let ay = ((nb as f64 / ax as f64).sqrt().ceil() as usize).max(1);
    let az = nb.div_ceil(ax * ay).max(1);
    if ax > 255 || ay > 255 || az > 255 {
        return Err(ExportError::TooLarge([ax as u32, ay as u32, az as u32]));
    }
    let t = BRICK_CELLS as usize + 1;
    let res = [(ax * t) as u32, (ay * t) as u32, (az * t) as u32];
    if res.iter().map(|&x| x as u64).product::<u64>() > 1 << 26 {
        return Err(ExportError::TooLarge(res));
    }
    Ok(BrickPlan {
        cells,
        bricks,
        cell_brick,
        atlas: [ax, ay, az],
        res,
    })
}

/// Samples and encodes the atlas of `plan` (see [`export_bricks`]).
fn bricks_from_plan(
    volume: &Volume,
    plan: &BrickPlan,
    encoding: Ktx2Encoding,
) -> Result<Ktx2Export, ExportError> {
    let BrickPlan {
        cells,
        ref bricks,
        ref cell_brick,
        atlas: [ax, ay, az],
        res,
    } = *plan;
    let nb = bricks.len();
    let (min, max) = volume.bounds();
    let size = max - min;
    let t = BRICK_CELLS as usize + 1;
    let (rx, ry) = (res[0] as usize, res[1] as usize);
    let mut pts = vec![min; rx * ry * res[2] as usize];
    for (b, &(level, node)) in bricks.iter().enumerate() {
        let (bx, by, bz) = (b % ax, (b / ax) % ay, b / (ax * ay));
        let n = Vec3::from_array(cells.map(|c| c as f32));
        let extent = size * ((1u32 << level) as f32 / n);
        let origin = min + Vec3::from_array(node.map(|x| x as f32)) * extent;
        for w in 0..t {
            for v in 0..t {
                for u in 0..t {
                    let f = Vec3::new(u as f32, v as f32, w as f32) / BRICK_CELLS as f32;
                    let (x, y, z) = (bx * t + u, by * t + v, bz * t + w);
                    pts[x + rx * (y + ry * z)] = (origin + f * extent).min(max);
                }
            }
        }
    }
    let n = volume.coeffs_per_sample();
    let mut sh = vec![Vec3::ZERO; pts.len() * n];
    volume.sample_sh_batch(&pts, Interp::Trilinear, &mut sh)?;
    let (mut textures, bounds) = encode_sh_textures(&sh, n, res, encoding)?;
    let mut ind = Vec::with_capacity(cell_brick.len() * 4);
    for &(b, level) in cell_brick {
        let b = b as usize;
        ind.extend_from_slice(&[
            (b % ax) as u8,
            ((b / ax) % ay) as u8,
            (b / (ax * ay)) as u8,
            level as u8,
        ]);
    }
    textures.insert(
        0,
        (
            "indirection_rgba8ui.ktx2".to_string(),
            Ktx2 {
                format: TexelFormat::Rgba8Uint,
                size: cells,
                kvd: vec![("KTXwriter".to_string(), "probekit".to_string())],
                data: ind,
            },
        ),
    );
    let atlas_bytes: usize = textures.iter().skip(1).map(|(_, t)| t.data.len()).sum();
    let sidecar = serde_json::json!({
        "format": "probekit-volume-bricks",
        "box": {"min": min.to_array(), "max": max.to_array()},
        "indirection": {
            "file": "indirection_rgba8ui.ktx2",
            "resolution": cells,
            "texel": "r,g,b = brick coordinates in the atlas (in bricks), a = level: the brick covers 2^level indirection cells per axis",
        },
        "brick_cells": BRICK_CELLS,
        "brick_texels": BRICK_CELLS + 1,
        "bricks": nb,
        "atlas_bricks": [ax, ay, az],
        "atlas_resolution": res,
        "atlas_bytes": atlas_bytes,
        "lookup": "c = floor(uvw*N) (uvw = (p-min)/(max-min), N = indirection resolution); (b, level) = indirection[c]; s = 2^level; o = floor(c/s)*s; f = (uvw*N - o)/s in [0,1]^3; atlas texel coordinate = b*(brick_cells+1) + 0.5 + f*brick_cells (texels); divide by atlas_resolution for normalized coordinates",
    });
    Ok(Ktx2Export {
        sidecar: with_coefficient_fields(sidecar, volume.order(), encoding, &bounds, &textures),
        textures,
    })
}

/// The smaller of the two KTX2 layouts: a uniform volume at its own
/// resolution; an octree as a brick atlas ([`export_bricks`]) when its atlas
/// holds fewer texels than the finest-level lattice, else resampled densely
/// ([`export_ktx2`]). Bricks duplicate their faces (5³ texels per 4³ cells),
/// so an octree that is nearly full at its finest level is smaller dense.
pub fn export_auto(volume: &Volume, encoding: Ktx2Encoding) -> Result<Ktx2Export, ExportError> {
    if volume.grid_resolution().is_some() {
        return export_ktx2(volume, encoding, None);
    }
    let plan = plan_bricks(volume)?;
    let atlas: u64 = plan.res.iter().map(|&r| r as u64).product();
    let roots = volume.root_grid().unwrap_or([1; 3]);
    let dense: u64 = roots
        .iter()
        .map(|&r| ((r as u64) << volume.max_depth().min(10)) + 1)
        .product();
    if atlas < dense {
        bricks_from_plan(volume, &plan, encoding)
    } else {
        export_ktx2(volume, encoding, None)
    }
}
