//! The blend weights of a [`ProbeCloud`] at a point: barycentric weights
//! times cell visibility, Chebyshev visibility and the probe factors,
//! renormalized, with the fallbacks for cells hidden from the point.

use super::{ProbeCloud, HIDDEN_MASS_FLOOR};
use crate::cloud::{CellPlanes, Location, WalkState};
use crate::Cell;
use glam::Vec3;

impl ProbeCloud {
    /// Blend weights at `p`: the barycentric weights `b_i` of
    /// [`TetMesh::weights_at`] (tetrahedron or outer cell), times each
    /// probe's cell visibility `c_i(p)` ([`cell_visibility`]: the
    /// tetrahedron's occluder plane where it has one, else its bits) and
    /// Chebyshev visibility `v_i(p)` ([`visibility`]) where present
    /// and on, and the factor `f_i = s_i·Ē_i^−α`: the fitted probe weight
    /// `s_i` ([`ProbeCloud::probe_weights`]) when present and on, and the
    /// brightness factor when [`ProbeCloud::brightness_weighting`] is
    /// on; renormalized:
    /// `b_i·c_i·v_i·f_i / Σ_j b_j·c_j·v_j·f_j`. Where cell visibility hides
    /// every probe of positive barycentric weight from `p` (a pocket behind
    /// a wall's end or a closet's corner), the plain weights would bring in
    /// the light of the wall's far side, so the weight is 1 on the cell's
    /// darkest probe (lowest `Ē_i` of its three or four, the first on a
    /// tie) and 0 elsewhere: a dim pocket rather than a leak (probekit's
    /// BENCHMARKS.md, "Hidden-cell fallback"; the cell's corners of weight
    /// 0 that its bits call visible were tried first and measured worse,
    /// the bits being too coarse there). Where some of it is in sight but
    /// less than [`HIDDEN_MASS_FLOOR`] (`m = Σ_i b_i·c_i` below it), the
    /// renormalized weights `r` would hand the whole weight to the few
    /// probes the bits let through, often partly hidden ones next to the
    /// wall; the weights are then `t·r + (1 − t)·d` with `t = m / floor` and
    /// `d` the darkest probe's, so they reach the fallback continuously as
    /// `m` goes to 0. Where the sum is 0 for another reason (Chebyshev
    /// visibility or the factors) it falls back to `b_i·v_i·f_i`, then
    /// `b_i·f_i`, then `b_i`. Unused slots have weight 0. No allocation.
    ///
    /// [`TetMesh::weights_at`]: crate::cloud::TetMesh::weights_at
    /// [`cell_visibility`]: crate::cloud::cell_visibility
    /// [`visibility`]: crate::cloud::visibility
    pub fn weights_at(&self, p: Vec3, state: &mut WalkState) -> ([u32; 4], [f32; 4]) {
        let (_, probes, weights) = self.blend_at(p, state);
        (probes, weights)
    }

    /// [`ProbeCloud::weights_at`] with the cell the point was found in (a
    /// tetrahedron, or the hull face of its closest hull point).
    pub(crate) fn blend_at(&self, p: Vec3, state: &mut WalkState) -> (Cell, [u32; 4], [f32; 4]) {
        let maps = self.visibility.as_ref().filter(|_| self.visibility_on);
        let cells = self.cells.as_ref().filter(|_| self.cells_on);
        let planes = self.planes.as_deref().filter(|_| self.cells_on);
        let location = self.mesh.locate(p, state);
        if maps.is_none()
            && cells.is_none()
            && planes.is_none()
            && self.brightness <= 0.0
            && !self.probe_weighting_enabled()
        {
            return match location {
                Location::Inside { tet, weights } => (
                    Cell::Tetrahedron(tet),
                    self.mesh.tets()[tet as usize],
                    weights,
                ),
                Location::Outside {
                    hull_face,
                    probes,
                    weights,
                    ..
                } => (
                    Cell::HullFace(hull_face),
                    [probes[0], probes[1], probes[2], 0],
                    [weights[0], weights[1], weights[2], 0.0],
                ),
            };
        }
        let cell = match location {
            Location::Inside { tet, .. } => Cell::Tetrahedron(tet),
            Location::Outside { hull_face, .. } => Cell::HullFace(hull_face),
        };
        let (probes, bary, c, used) = match location {
            Location::Inside { tet, weights } => {
                let probes = self.mesh.tets()[tet as usize];
                let c = match planes.and_then(|pl| pl.plane(tet)) {
                    Some(plane) => {
                        let pos = self.mesh.positions();
                        CellPlanes::visibility(plane, p, &probes.map(|i| pos[i as usize]))
                    }
                    None => cells.map_or([1.0; 4], |c| c.tet(tet, &weights)),
                };
                (probes, weights, c, 4)
            }
            Location::Outside {
                hull_face,
                probes,
                weights,
                ..
            } => (
                [probes[0], probes[1], probes[2], 0],
                [weights[0], weights[1], weights[2], 0.0],
                cells.map_or([1.0; 4], |c| {
                    let v = c.hull_face(hull_face, &weights);
                    [v[0], v[1], v[2], 1.0]
                }),
                3,
            ),
        };
        let mut v = [1.0f32; 4];
        if let Some(maps) = maps {
            let pos = self.mesh.positions();
            for k in 0..4 {
                if bary[k] != 0.0 {
                    let i = probes[k] as usize;
                    v[k] = maps.visibility(i, pos[i], p);
                }
            }
        }
        let normalized = |w: [f32; 4]| {
            let sum: f32 = w.iter().sum();
            (sum.is_finite() && sum > 0.0).then(|| w.map(|x| x / sum))
        };
        let f = self.probe_factors(&probes, &bary);
        let bcv = core::array::from_fn(|k| bary[k] * c[k] * v[k] * f[k]);
        // The barycentric weight cell visibility leaves in sight. At 0 it
        // hides every probe of positive weight from `p` (a pocket behind a
        // wall's end, a corner beyond the hull): the plain blend would carry
        // the far side's light in, so the cell's darkest probe alone instead.
        let has_cells = cells.is_some() || planes.is_some();
        let mass: f32 = (0..used).map(|k| bary[k] * c[k]).sum();
        let all_hidden = has_cells && mass == 0.0;
        let darkest = || {
            let lum = |k: usize| self.luminance[probes[k] as usize];
            let k = (0..used).min_by(|&a, &b| lum(a).total_cmp(&lum(b)).then(a.cmp(&b)))?;
            let mut w = [0.0; 4];
            w[k] = 1.0;
            Some(w)
        };
        // Little of the weight in sight: renormalizing would hand it all to
        // the few (often partly hidden) probes the bits let through; blend
        // towards the darkest probe instead, reaching it continuously as the
        // visible mass goes to 0.
        let r = normalized(bcv);
        if has_cells && mass > 0.0 && mass < HIDDEN_MASS_FLOOR {
            if let (Some(r), Some(d)) = (r, darkest()) {
                let t = mass / HIDDEN_MASS_FLOOR;
                return (
                    cell,
                    probes,
                    core::array::from_fn(|k| t * r[k] + (1.0 - t) * d[k]),
                );
            }
        }
        let w = r
            .or_else(|| all_hidden.then(darkest).flatten())
            .or_else(|| normalized(core::array::from_fn(|k| bary[k] * v[k] * f[k])))
            .or_else(|| normalized(core::array::from_fn(|k| bary[k] * f[k])))
            .unwrap_or(bary);
        (cell, probes, w)
    }
}
