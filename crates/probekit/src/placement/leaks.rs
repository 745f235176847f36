//! Leak prevention (Sukys 2014, "Light probe cloud generation for games";
//! Cupisz, "Light probe interpolation using tetrahedral tessellations", GDC
//! 2012): probes on both sides of every tetrahedron edge that crosses
//! geometry, and the crossing extent that measures what is left.

use super::{PlacementError, State};
use crate::delaunay::tetrahedralize;
use crate::scene::Aabb;
use crate::trace::{Ray, Tracer};
use glam::Vec3;
use std::collections::BTreeSet;

/// Leak-prevention parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeakSettings {
    /// Passes of trace–insert–retetrahedralize.
    pub iterations: u32,
    /// Offset of an inserted probe from the hit, as a fraction of the edge length.
    pub offset_fraction: f32,
    /// Offset bounds, metres.
    pub min_offset: f32,
    /// Largest offset, metres.
    pub max_offset: f32,
    /// Hits with `|cos(edge, normal)|` below this are skipped (surface-parallel).
    pub min_cos: f32,
    /// No new probe closer than this fraction of the offset to another probe.
    pub min_distance_fraction: f32,
}

impl Default for LeakSettings {
    fn default() -> Self {
        Self {
            iterations: 2,
            offset_fraction: 0.1,
            min_offset: 0.05,
            max_offset: 0.4,
            min_cos: 0.2,
            min_distance_fraction: 0.8,
        }
    }
}

/// Unique edges of tetrahedra, as sorted index pairs in increasing order.
pub fn tet_edges(tets: &[[u32; 4]]) -> Vec<(u32, u32)> {
    let mut set = BTreeSet::new();
    for t in tets {
        for i in 0..4 {
            for j in i + 1..4 {
                let (a, b) = (t[i].min(t[j]), t[i].max(t[j]));
                set.insert((a, b));
            }
        }
    }
    set.into_iter().collect()
}

/// Number of tetrahedron edges of the Delaunay tetrahedralization of
/// `points` that cross geometry, and their crossing extent: for each such
/// edge, the free length on both sides over which interpolation spans the
/// surface (distance from each end point to the first surface seen from it),
/// summed, in metres. Leak prevention shrinks the extent.
pub fn crossing_extent(tracer: &Tracer, points: &[Vec3]) -> Result<(usize, f32), PlacementError> {
    let tri = tetrahedralize(points)?;
    let mut count = 0;
    let mut extent = 0.0f64;
    for (a, b) in tet_edges(&tri.tets) {
        let (pa, pb) = (points[a as usize], points[b as usize]);
        let d = pb - pa;
        let len = d.length();
        if len <= 0.0 {
            continue;
        }
        let dir = d / len;
        if let Some(h) = tracer.closest_hit(&Ray::new(pa, dir), len) {
            count += 1;
            let back = tracer
                .closest_hit(&Ray::new(pb, -dir), len)
                .map_or(len - h.t, |h2| h2.t);
            extent += (h.t + back) as f64;
        }
    }
    Ok((count, extent as f32))
}

/// Points leak prevention would insert for the Delaunay tetrahedralization of
/// `points` (one pass; see the module docs), in a deterministic order.
pub fn leak_points(
    tracer: &Tracer,
    points: &[Vec3],
    ls: &LeakSettings,
) -> Result<Vec<Vec3>, PlacementError> {
    let tri = tetrahedralize(points)?;
    let mut cands = Vec::new();
    for (a, b) in tet_edges(&tri.tets) {
        let (pa, pb) = (points[a as usize], points[b as usize]);
        let d = pb - pa;
        let len = d.length();
        if len <= 1e-6 {
            continue;
        }
        let dir = d / len;
        let off = (ls.offset_fraction * len).clamp(ls.min_offset, ls.max_offset);
        for (o, dd) in [(pa, dir), (pb, -dir)] {
            if let Some(h) = tracer.closest_hit(&Ray::new(o, dd), len) {
                let n = h.facing_normal();
                if n.dot(dd).abs() < ls.min_cos {
                    continue;
                }
                // Not beyond the probe the ray started from.
                let o2 = off.min(0.5 * h.t);
                cands.push((h.point + n * o2, o2));
            }
        }
    }
    Ok(spaced(
        points,
        cands
            .into_iter()
            .map(|(p, o)| (p, ls.min_distance_fraction * o)),
        ls.max_offset,
    ))
}

/// The candidates `(p, r)` kept in order when no existing point of `points`
/// and no candidate kept before lies within `r` of `p` (a spatial hash of
/// cell `cell`, which must be at least the largest `r`); non-finite ones are
/// dropped.
pub(super) fn spaced(
    points: &[Vec3],
    cands: impl Iterator<Item = (Vec3, f32)>,
    cell: f32,
) -> Vec<Vec3> {
    let cell = cell.max(1e-3);
    let key = |p: Vec3| {
        let q = (p / cell).floor();
        (q.x as i64, q.y as i64, q.z as i64)
    };
    let mut hash: std::collections::HashMap<(i64, i64, i64), Vec<Vec3>> = Default::default();
    for &p in points {
        hash.entry(key(p)).or_default().push(p);
    }
    let mut out = Vec::new();
    for (p, r) in cands {
        if !p.is_finite() {
            continue;
        }
        let k = key(p);
        let mut near = false;
        'n: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(v) = hash.get(&(k.0 + dx, k.1 + dy, k.2 + dz)) {
                        if v.iter().any(|q| q.distance_squared(p) < r * r) {
                            near = true;
                            break 'n;
                        }
                    }
                }
            }
        }
        if !near {
            hash.entry(k).or_default().push(p);
            out.push(p);
        }
    }
    out
}

impl State<'_, '_> {
    /// One or more passes of leak prevention; at most `limit` probes added.
    pub(super) fn fix_leaks(
        &mut self,
        ls: &LeakSettings,
        limit: usize,
    ) -> Result<(), PlacementError> {
        self.fix_leaks_within(ls, limit, None)
    }

    /// [`Self::fix_leaks`], keeping only probes inside `bounds` (when given):
    /// the far side of an edge that crosses an outer wall is outside the
    /// building, where a probe sees the sky and sun, and the virtual offset
    /// can push a capture through a thin wall.
    pub(super) fn fix_leaks_within(
        &mut self,
        ls: &LeakSettings,
        limit: usize,
        bounds: Option<&Aabb>,
    ) -> Result<(), PlacementError> {
        let inside = |p: &Vec3| bounds.map_or(true, |b| b.contains(*p));
        let mut added_total = 0;
        for _ in 0..ls.iterations {
            if added_total >= limit {
                break;
            }
            let mut new = leak_points(self.baker.tracer(), &self.positions, ls)?;
            let n = new.len();
            new.retain(inside);
            self.stats.rejected_inside += n - new.len();
            if new.is_empty() {
                break;
            }
            let got = self.admit(new, inside, limit - added_total)?;
            added_total += got;
            self.stats.leak_probes += got;
        }
        Ok(())
    }
}
