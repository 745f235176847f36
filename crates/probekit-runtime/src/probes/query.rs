//! The diagnostic form of a query ([`Query`], [`Cell`]) and the checks every
//! query makes of its input.

use super::{QueryError, Sh};
use glam::Vec3;

/// Where a query point was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Cell {
    /// Inside tetrahedron `t` of a cloud (its index in the file's `TETS`).
    Tetrahedron(u32),
    /// Outside a cloud's convex hull: lit from the closest point of the
    /// hull, in hull face `f` (numbered in the order the hull faces of the
    /// tetrahedra appear: tetrahedron by tetrahedron, face by face).
    HullFace(u32),
    /// In cell `c` of a volume: for a uniform grid `i + (rx − 1)·(j +
    /// (ry − 1)·k)` (an axis of one probe counts as one cell), for an
    /// octree the leaf's node index. Points outside the box are clamped.
    VolumeCell(u32),
}

/// A query with what produced it, for viewers and diagnostics
/// ([`crate::Probes::query`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Query {
    /// Radiance SH at the point, as [`crate::Probes::sh_at`] gives it.
    pub sh: Sh,
    /// The cell the point was found in.
    pub cell: Cell,
    /// Probe (volume sample) indices of the blend. A cloud uses the first
    /// four: the tetrahedron's probes, or the hull face's three (the fourth
    /// then has weight 0). A volume gives its cell's eight corners in child
    /// bit order (bit 0 the +x corner, bit 1 +y, bit 2 +z).
    pub probes: [u32; 8],
    /// Weights of `probes` (unused slots 0). A cloud: the blend weights
    /// after visibility and the probe factors, summing to 1; where
    /// directional brightness is on, each direction re-weights them
    /// further. A volume: the trilinear weights of the point in its cell
    /// (an octree blend also reaches the samples of finer neighbours).
    pub weights: [f32; 8],
}

/// `position` is finite.
#[inline]
pub(super) fn check_position(position: Vec3, index: usize) -> Result<(), QueryError> {
    if position.is_finite() {
        Ok(())
    } else {
        Err(QueryError::NonFinitePosition { index })
    }
}

/// `normal` scaled to unit length; an error if it is not finite or too
/// short for that (its squared length not a normal `f32`).
#[inline]
pub(super) fn unit_normal(normal: Vec3, index: usize) -> Result<Vec3, QueryError> {
    if !normal.is_finite() {
        return Err(QueryError::NonFiniteNormal { index });
    }
    let len2 = normal.length_squared();
    // NaN cannot occur (finite input); below the smallest normal, or 0.
    if len2 < f32::MIN_POSITIVE {
        return Err(QueryError::ZeroNormal { index });
    }
    if len2.is_finite() {
        Ok(normal / crate::math::sqrt(len2))
    } else {
        // Too long to square: scale first.
        let m = normal.abs().max_element();
        let n = normal / m;
        Ok(n / crate::math::sqrt(n.length_squared()))
    }
}

/// L1 radiance SH (`sh[..4]`) with the hallucinated ZH3 lobe expanded to
/// band 2 ([`probekit_sh::zh3::zh3_hallucinate`], Roughton et al. 2024).
pub(super) fn hallucinate(sh: &[Vec3; 9]) -> [Vec3; 9] {
    let l1 = [sh[0], sh[1], sh[2], sh[3]];
    probekit_sh::zh3::zh3_hallucinate(&l1).to_l2()
}
