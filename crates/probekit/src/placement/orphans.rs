//! Orphan pockets: free space inside a tetrahedron (or beyond a hull face)
//! that sees none of its probes, found on a lattice and filled largest
//! pocket first.

use super::leaks::spaced;
use super::{PlacementError, State};
use crate::delaunay::{tetrahedralize, HULL};
use crate::scene::Aabb;
use crate::trace::free_space::{is_open, push_off_surfaces, segment_clear};
use crate::trace::Tracer;
use glam::Vec3;
use rayon::prelude::*;

/// Spacing of the points [`orphan_points`] tests in each tetrahedron,
/// metres.
pub const ORPHAN_SPACING: f32 = 0.1;

/// Subdivisions of a tetrahedron's lattice in [`orphan_points`], at most.
const ORPHAN_MAX_SUBDIVISION: u32 = 8;

/// Points that see none of the probes of their tetrahedron are looked for
/// this far from surfaces and more, metres: `probekit eval`'s points keep
/// 1 cm.
const ORPHAN_TEST_CLEARANCE: f32 = 0.01;

/// Probes for the pockets of free space that see none of the four probes
/// of their tetrahedron, for the Delaunay tetrahedralization of `points`,
/// in a deterministic order. In such a pocket every visibility-aware blend
/// has only hidden probes to choose from, so the light of the far side of a
/// wall is all it can give.
///
/// The edge test of leak prevention ([`leak_points`](super::leak_points)) finds a wall that crosses an
/// edge; a wall's *end* or a corner (a closet's, say) can reach into a
/// tetrahedron without crossing any of its edges, leaving such a pocket
/// behind it. In every tetrahedron, and on every face of the hull (beyond
/// which a point blends the face's three probes), this tests the points of
/// a barycentric lattice about [`ORPHAN_SPACING`] apart (at most 8
/// subdivisions of its longest edge) that are in open space ([`is_open`]) at
/// 1 cm from surfaces, as `probekit eval`'s points are: one whose segments
/// to all the cell's probes are blocked is pushed off nearby surfaces until
/// it keeps `clearance` (the probes' own; [`push_off_surfaces`]) and becomes
/// a candidate probe there, unless that fails or another probe or kept
/// candidate is within [`ORPHAN_SPACING`]. The candidates come largest
/// pocket first: ordered greedily by how many of the orphaned lattice points
/// each sees within [`ORPHAN_COVER_RADIUS`] that the ones before it do not.
pub fn orphan_points(
    tracer: &Tracer,
    points: &[Vec3],
    clearance: f32,
) -> Result<Vec<Vec3>, PlacementError> {
    use probekit_runtime::cloud::cell_visibility::{lattice_numerators, lattice_position};
    let tri = tetrahedralize(points)?;
    // The tetrahedra, and the hull's faces: outside the hull a point blends
    // the three probes of the face below it (the outer cells), so a face
    // point that sees none of those three is orphaned there.
    let mut cells: Vec<Vec<u32>> = tri.tets.iter().map(|t| t.to_vec()).collect();
    for (t, nb) in tri.tets.iter().zip(&tri.neighbors) {
        for i in (0..4).filter(|&i| nb[i] == HULL) {
            cells.push((0..4).filter(|&j| j != i).map(|j| t[j]).collect());
        }
    }
    let cands: Vec<(Vec3, Option<Vec3>)> = cells
        .par_iter()
        .flat_map_iter(|t| {
            let v: Vec<Vec3> = t.iter().map(|&k| points[k as usize]).collect();
            let longest = (0..v.len())
                .flat_map(|i| (i + 1..v.len()).map(move |j| (i, j)))
                .map(|(i, j)| v[i].distance(v[j]))
                .fold(0.0f32, f32::max);
            let k = ((longest / ORPHAN_SPACING).ceil() as u32).clamp(1, ORPHAN_MAX_SUBDIVISION);
            lattice_numerators(v.len(), k)
                .into_iter()
                .filter(|n| n.iter().all(|&c| c < k))
                .map(|n| lattice_position(t, points, &n, k))
                .filter(|&p| {
                    v.iter().all(|&q| !segment_clear(tracer, p, q))
                        && is_open(tracer, p, ORPHAN_TEST_CLEARANCE)
                })
                .map(|p| (p, push_off_surfaces(tracer, p, clearance)))
                .collect::<Vec<_>>()
        })
        .collect();
    let orphans: Vec<Vec3> = cands.iter().map(|c| c.0).collect();
    let spaced = spaced(
        points,
        cands
            .iter()
            .filter_map(|c| c.1)
            .map(|p| (p, ORPHAN_SPACING)),
        ORPHAN_SPACING,
    );
    Ok(by_pocket_coverage(tracer, spaced, &orphans))
}

/// How far a probe for an orphan pocket counts as serving an orphaned
/// point it sees, metres: [`orphan_points`] orders its candidates by them.
pub const ORPHAN_COVER_RADIUS: f32 = 1.0;

/// `cands` reordered greedily by the orphaned points they serve: first the
/// candidate that sees (a clear segment, within [`ORPHAN_COVER_RADIUS`])
/// the most of `orphans`, then the one that sees the most of those left,
/// and so on (ties to the earlier candidate; those that serve none keep
/// their order at the end). An allowance of a few probes then goes to the
/// largest pockets first — a closet's floor rather than a sliver beside a
/// pillar — instead of to whichever cell came first.
pub(super) fn by_pocket_coverage(tracer: &Tracer, cands: Vec<Vec3>, orphans: &[Vec3]) -> Vec<Vec3> {
    let r2 = ORPHAN_COVER_RADIUS * ORPHAN_COVER_RADIUS;
    let sees: Vec<Vec<u32>> = cands
        .par_iter()
        .map(|&c| {
            (0..orphans.len() as u32)
                .filter(|&i| {
                    let o = orphans[i as usize];
                    o.distance_squared(c) < r2 && segment_clear(tracer, c, o)
                })
                .collect()
        })
        .collect();
    // Lazy greedy: a candidate's gain only falls as points are served, so
    // a heap of stale gains (upper bounds) yields the exact greedy order
    // (highest gain, then lowest index) re-counting only the candidate on
    // top, instead of every candidate in every round.
    use std::cmp::Reverse;
    let mut served = vec![false; orphans.len()];
    let mut taken = vec![false; cands.len()];
    let mut out = Vec::with_capacity(cands.len());
    let mut heap: std::collections::BinaryHeap<(usize, Reverse<usize>)> = sees
        .iter()
        .enumerate()
        .map(|(k, s)| (s.len(), Reverse(k)))
        .collect();
    while let Some((stale, Reverse(k))) = heap.pop() {
        let gain = sees[k].iter().filter(|&&i| !served[i as usize]).count();
        if gain < stale {
            heap.push((gain, Reverse(k)));
            continue;
        }
        if gain == 0 {
            break;
        }
        taken[k] = true;
        for &i in &sees[k] {
            served[i as usize] = true;
        }
        out.push(cands[k]);
    }
    out.extend((0..cands.len()).filter(|&k| !taken[k]).map(|k| cands[k]));
    out
}

impl State<'_, '_> {
    /// Up to `passes` rounds of [`orphan_points`] (inside `bounds`), at most
    /// `limit` probes added in all; returns how many.
    pub(super) fn fix_orphans(
        &mut self,
        clearance: f32,
        passes: u32,
        limit: usize,
        bounds: &Aabb,
    ) -> Result<usize, PlacementError> {
        let mut added = 0;
        for _ in 0..passes {
            if added >= limit {
                break;
            }
            let mut new = orphan_points(self.baker.tracer(), &self.positions, clearance)?;
            new.retain(|p| bounds.contains(*p));
            let got = self.admit(new, |p| bounds.contains(*p), limit - added)?;
            if got == 0 {
                break;
            }
            added += got;
            self.stats.orphan_probes += got;
        }
        Ok(added)
    }
}
