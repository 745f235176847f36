//! Occluder planes of a cloud's cells (the `CPLN` section): where one flat
//! slab of surfaces (an interior wall or floor) is all that hides a cell's
//! probes from its points, a plane stands for the cell's visibility
//! lattice ([`super::cell_visibility`]) exactly and everywhere in the cell.

use super::cell_visibility::CellVisibilityError;
use crate::sampling::SampleRng;
use crate::trace::free_space::segment_clear;
use crate::trace::{Ray, Tracer};
use glam::Vec3;
use probekit_runtime::cloud::cell_visibility::{
    lattice_numerators, lattice_position, CellVisibility,
};
use probekit_runtime::cloud::{CellPlanes, ProbeCloud, TetMesh};
use probekit_runtime::format::ProbeFile;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Largest thickness, metres, of the slab of surfaces an occluder plane
/// ([`bake_cell_planes`]) may stand for: an interior wall or floor, not a
/// room.
pub const MAX_PLANE_SLAB: f32 = 0.6;

/// Smallest `|cos|` between a hit's surface normal and the plane's normal
/// (about 10°).
const PLANE_NORMAL_COS: f32 = 0.985;

/// Random points of a cell, beyond its lattice, at which a candidate plane
/// must agree with an exact segment test to each corner.
pub const PLANE_CHECK_POINTS: u32 = 32;

/// Margin, metres, around the slab within which a point's side of the plane
/// is not checked and a corner may not lie.
const SLAB_MARGIN: f32 = 1e-3;

/// The surface point and geometric normal where the ray `a → b` first meets
/// geometry before `b`, if it does.
fn first_hit(tracer: &Tracer<'_>, a: Vec3, b: Vec3) -> Option<(Vec3, Vec3)> {
    let d = b - a;
    let len = d.length();
    if len.is_nan() || len <= 1e-6 {
        return None;
    }
    let dir = d / len;
    tracer
        .closest_hit(&Ray::new(a, dir), len)
        .map(|h| (a + dir * h.t, h.geometric_normal))
}

/// The occluder plane of the tetrahedron with corners `corners` (see
/// [`probekit_runtime::cloud::CellPlanes`]), or `None` when one plane does
/// not explain its visibility:
///
/// 1. Every blocked segment between a corner and a lattice point of
///    subdivision `k` is traced both ways; the first hits give surface
///    points and normals. All normals must be parallel (within about 10°,
///    either orientation) to their sign-aligned mean `n`.
/// 2. The hits span the slab `n·x ∈ [lo, hi]`, at most [`MAX_PLANE_SLAB`]
///    thick; the plane is its mid-plane `n·x = (lo + hi)/2`, and no corner
///    may lie in the slab.
/// 3. The plane's side test must reproduce every lattice bit and, at
///    [`PLANE_CHECK_POINTS`] random points of the cell (from `seed` and
///    `cell`), an exact segment test to every corner; points in the slab are
///    not checked (free space there lies beyond the wall's end, where the
///    other points decide).
///
/// A wall that ends inside the cell, a corner of two walls or furniture
/// beside the wall fails one of these, and the cell keeps its lattice.
fn fit_cell_plane(
    tracer: &Tracer<'_>,
    probes: &[u32; 4],
    positions: &[Vec3],
    lattice: &[[u32; 4]],
    k: u32,
    seed: u64,
    cell: u64,
) -> Option<[f32; 4]> {
    let corners = probes.map(|i| positions[i as usize]);
    let points: Vec<Vec3> = lattice
        .iter()
        .map(|n| lattice_position(probes, positions, n, k))
        .collect();
    let mut bits = vec![[true; 4]; points.len()];
    let mut hits = Vec::new();
    for (l, (q, n)) in points.iter().zip(lattice).enumerate() {
        for v in 0..4 {
            if n[v] == k || segment_clear(tracer, corners[v], *q) {
                continue;
            }
            bits[l][v] = false;
            hits.extend(first_hit(tracer, corners[v], *q));
            hits.extend(first_hit(tracer, *q, corners[v]));
        }
    }
    let (_, n0) = *hits.first()?;
    let mut sum = Vec3::ZERO;
    for &(_, n) in &hits {
        let c = n.dot(n0);
        if c.abs() < PLANE_NORMAL_COS {
            return None;
        }
        sum += n * c.signum();
    }
    let n = sum.normalize_or_zero();
    if n == Vec3::ZERO || hits.iter().any(|h| h.1.dot(n).abs() < PLANE_NORMAL_COS) {
        return None;
    }
    let (lo, hi) = hits
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), h| {
            let s = n.dot(h.0);
            (lo.min(s), hi.max(s))
        });
    if hi - lo > MAX_PLANE_SLAB || !(hi - lo).is_finite() {
        return None;
    }
    let d = 0.5 * (lo + hi);
    let half = 0.5 * (hi - lo) + SLAB_MARGIN;
    let side = |x: Vec3| n.dot(x) - d;
    let corner_side = corners.map(side);
    if corner_side.iter().any(|s| s.abs() <= half) {
        return None;
    }
    let agrees = |q: Vec3, seen: &dyn Fn(usize) -> bool| {
        let s = side(q);
        s.abs() <= half || (0..4).all(|v| ((s >= 0.0) == (corner_side[v] >= 0.0)) == seen(v))
    };
    if !points.iter().zip(&bits).all(|(q, b)| agrees(*q, &|v| b[v])) {
        return None;
    }
    let mut rng = SampleRng::new(seed, 0x4350_4c4e, cell);
    for _ in 0..PLANE_CHECK_POINTS {
        // Uniform in the tetrahedron: normalized exponential weights.
        let e: [f32; 4] = core::array::from_fn(|_| -(1.0 - rng.next_f32()).max(1e-12).ln());
        let total: f32 = e.iter().sum();
        let q = (0..4).map(|v| corners[v] * (e[v] / total)).sum::<Vec3>();
        if !agrees(q, &|v| segment_clear(tracer, corners[v], q)) {
            return None;
        }
    }
    Some([n.x, n.y, n.z, d])
}

/// Seed of the random check points of [`bake_cell_planes`] (`probekit bake`
/// uses this one, so a file's planes depend on its mesh and scene alone).
pub const CELL_PLANE_SEED: u64 = 0x5052_4f42;

/// Bakes occluder planes ([`probekit_runtime::cloud::CellPlanes`], the
/// `CPLN` section) for the tetrahedra of `mesh` that `cells` (baked on the
/// same mesh) stores a record for, at the same lattice: a plane where one
/// flat wall explains the cell's visibility, none elsewhere. A cell gets a
/// plane when every blocked segment between a corner and a lattice point,
/// traced both ways, hits surfaces parallel to one plane (within about
/// 10°), the slab they span is at most [`MAX_PLANE_SLAB`] thick with no
/// corner in it, and the slab's mid-plane reproduces every lattice bit and
/// an exact segment test at [`PLANE_CHECK_POINTS`] random points of the
/// cell (from `seed` and the cell's index). `progress(done, total)` counts
/// those tetrahedra.
/// Deterministic: each cell's plane depends only on the mesh, the scene and
/// `seed`.
pub fn bake_cell_planes(
    tracer: &Tracer<'_>,
    mesh: &TetMesh,
    cells: &CellVisibility,
    seed: u64,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<CellPlanes, CellVisibilityError> {
    let tets = mesh.tets();
    if cells.tet_count() != tets.len() {
        return Err(CellVisibilityError::Mesh(
            probekit_runtime::cloud::ProbeCloudError::CellVisibilityMismatch {
                tets: cells.tet_count(),
                hull_faces: cells.hull_face_count(),
                mesh_tets: tets.len(),
                mesh_hull_faces: mesh.hull_face_count(),
            },
        ));
    }
    let k = cells.subdivision();
    let lattice = lattice_numerators(4, k);
    let todo: Vec<u32> = (0..tets.len() as u32)
        .filter(|&t| cells.tet_has_record(t))
        .collect();
    let done = AtomicUsize::new(0);
    let found: Vec<Option<[f32; 4]>> = todo
        .par_iter()
        .map(|&t| {
            let plane = fit_cell_plane(
                tracer,
                &tets[t as usize],
                mesh.positions(),
                &lattice,
                k,
                seed,
                t as u64,
            );
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, todo.len());
            plane
        })
        .collect();
    let (ids, planes): (Vec<u32>, Vec<[f32; 4]>) = todo
        .iter()
        .zip(found)
        .filter_map(|(&t, p)| p.map(|p| (t, p)))
        .unzip();
    Ok(CellPlanes::new(tets.len(), ids, planes).expect("unit normals, increasing cells"))
}

/// [`bake_cell_planes`] for a cloud file's mesh and its cell visibility,
/// with [`CELL_PLANE_SEED`], ready for [`crate::format::CloudBlend::cell_planes`]; `None`
/// when the file has no cell visibility.
pub fn bake_file_cell_planes(
    tracer: &Tracer<'_>,
    file: &ProbeFile,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Option<CellPlanes>, CellVisibilityError> {
    let Some(cells) = file
        .as_cloud()
        .and_then(|c| c.blend.cell_visibility.as_ref())
    else {
        return Ok(None);
    };
    let mesh = ProbeCloud::mesh_from_file(file)?;
    bake_cell_planes(tracer, &mesh, cells, CELL_PLANE_SEED, progress).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blend::cell_visibility::bake_cell_visibility;
    use crate::blend::cell_visibility::tests::{crosses_wall, scene, two_rooms};

    /// Uniform random point of the tetrahedron `c` (normalized exponential
    /// weights), from `rng`.
    fn random_in(c: &[Vec3; 4], rng: &mut SampleRng) -> Vec3 {
        let e: [f32; 4] = core::array::from_fn(|_| -(1.0 - rng.next_f32()).max(1e-12).ln());
        let t: f32 = e.iter().sum();
        (0..4).map(|v| c[v] * (e[v] / t)).sum()
    }

    /// Analytic: does the segment `a → b` meet the box `[lo, hi]` (slab
    /// clipping)?
    fn segment_meets_box(a: Vec3, b: Vec3, lo: Vec3, hi: Vec3) -> bool {
        let d = b - a;
        let (mut t0, mut t1) = (0.0f32, 1.0f32);
        for i in 0..3 {
            if d[i].abs() < 1e-12 {
                if a[i] < lo[i] || a[i] > hi[i] {
                    return false;
                }
            } else {
                let (u, v) = ((lo[i] - a[i]) / d[i], (hi[i] - a[i]) / d[i]);
                t0 = t0.max(u.min(v));
                t1 = t1.min(u.max(v));
            }
        }
        t0 <= t1
    }

    /// Cell visibility at `k` = 4, the planes fitted to it, and the count of
    /// tetrahedra with a record (the candidates for a plane).
    fn planes_at_k4(tracer: &Tracer<'_>, mesh: &TetMesh) -> (CellVisibility, CellPlanes, usize) {
        let cv = bake_cell_visibility(tracer, mesh, 4, &|_, _| {}).unwrap();
        let planes = bake_cell_planes(tracer, mesh, &cv, CELL_PLANE_SEED, &|_, _| {}).unwrap();
        let with_record = (0..mesh.tets().len() as u32)
            .filter(|&t| cv.tet_has_record(t))
            .count();
        (cv, planes, with_record)
    }

    /// A wall through the whole room: every cell with a record straddles it
    /// and gets a plane, the slab's mid-plane `x = 0.15`; the plane's side
    /// test equals the analytic segment test at random points of each cell.
    #[test]
    fn planes_stand_for_a_whole_wall_exactly() {
        let (sc, mesh) = two_rooms();
        let tracer = Tracer::new(&sc);
        let (cv, planes, with_record) = planes_at_k4(&tracer, &mesh);
        assert!(with_record > 0);
        assert_eq!(planes.len(), with_record);
        let pos = mesh.positions();
        let mut rng = SampleRng::new(5, 0, 0);
        let mut checked = 0;
        for (&t, pl) in planes.tets().iter().zip(planes.planes()) {
            assert!(pl[0].abs() > 0.999, "{pl:?}");
            assert!((pl[3] / pl[0] - 0.15).abs() < 1e-3, "{pl:?}");
            let c = mesh.tets()[t as usize].map(|i| pos[i as usize]);
            for _ in 0..100 {
                let q = random_in(&c, &mut rng);
                if (0.0..=0.3).contains(&q.x) {
                    continue;
                }
                let got = CellPlanes::visibility(*pl, q, &c);
                for v in 0..4 {
                    assert_eq!(got[v] == 1.0, !crosses_wall(c[v], q), "cell {t} {q:?} {v}");
                }
                checked += 1;
            }
        }
        assert!(checked > 1000);
        // Deterministic across thread counts.
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let again = one.install(|| {
            bake_cell_planes(&tracer, &mesh, &cv, CELL_PLANE_SEED, &|_, _| {}).unwrap()
        });
        assert_eq!(planes, again);
    }

    /// A wall with a doorway above `z = 1`: cells the wall's end cuts keep
    /// their lattice (no plane), and wherever a plane was kept its side test
    /// agrees with the analytic segment test at random points of the cell;
    /// an L-shaped corner (two walls) gets no plane either.
    #[test]
    fn a_wall_that_ends_in_the_cell_keeps_the_lattice() {
        let room = (Vec3::new(-2.0, 0.0, 0.0), Vec3::new(2.3, 2.0, 2.0));
        let wall = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.3, 2.0, 1.0));
        let (_, mesh) = two_rooms();
        let sc = scene(&[room, wall]);
        let tracer = Tracer::new(&sc);
        let (_, planes, with_record) = planes_at_k4(&tracer, &mesh);
        assert!(!planes.is_empty(), "cells below the doorway");
        assert!(planes.len() < with_record, "cells at the wall's end");
        let pos = mesh.positions();
        let mut rng = SampleRng::new(6, 0, 0);
        let (mut checked, mut wrong) = (0, 0);
        for (&t, pl) in planes.tets().iter().zip(planes.planes()) {
            let c = mesh.tets()[t as usize].map(|i| pos[i as usize]);
            for _ in 0..200 {
                let q = random_in(&c, &mut rng);
                if (0.0..=0.3).contains(&q.x) && q.z <= 1.0 {
                    continue;
                }
                let got = CellPlanes::visibility(*pl, q, &c);
                for v in 0..4 {
                    let seen = !segment_meets_box(c[v], q, wall.0, wall.1);
                    wrong += usize::from((got[v] == 1.0) != seen);
                    checked += 1;
                }
            }
        }
        eprintln!(
            "{} planes of {with_record} cells; {wrong} of {checked} wrong",
            planes.len()
        );
        assert!(checked > 1000);
        assert_eq!(wrong, 0);

        // Two walls meeting at a corner: no cell the corner cuts is planed
        // with a normal off either wall's.
        let wall2 = (Vec3::new(0.0, 0.0, 0.9), Vec3::new(2.3, 2.0, 1.1));
        let sc = scene(&[room, wall, wall2]);
        let tracer = Tracer::new(&sc);
        let (_, planes, _) = planes_at_k4(&tracer, &mesh);
        for pl in planes.planes() {
            assert!(pl[0].abs() > 0.98 || pl[2].abs() > 0.98, "{pl:?}");
        }
    }
}
