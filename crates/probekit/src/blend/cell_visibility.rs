//! Baking per-cell visibility bits (the `CVSP` section) of a probe cloud:
//! for every tetrahedron and hull face of the cloud's mesh, each corner
//! probe, and each point of the cell's lattice of subdivision `k`, whether
//! the segment from the probe to the point crosses a surface. The layout and
//! the run-time interpolation are in [`probekit_runtime::cloud::cell_visibility`].
//!
//! This goes beyond leak prevention by inserting probes where tetrahedron
//! edges cross geometry (Sukys 2014; Cupisz GDC 2012): edges can all be free while a wall's
//! corner still cuts through a cell, and a budget rarely allows probes on
//! both sides of every wall. The bits let the run time drop, inside the
//! cell, exactly the probes the geometry hides, at the cell's own scale; the
//! distance moments (`VISM`) add the fine scale near each probe.
//!
//! Deterministic: each cell's record depends only on the mesh and the scene,
//! and cells are baked in parallel into their own slots.
//!
//! The occluder planes fitted to these bits are [`super::cell_planes`].

use crate::trace::free_space::segment_clear;
use crate::trace::Tracer;
use glam::Vec3;
use probekit_runtime::cloud::cell_visibility::{
    lattice_numerators, lattice_position, record_from, CellVisibility, DEFAULT_CELL_SUBDIVISION,
    MAX_CELL_SUBDIVISION,
};
use probekit_runtime::cloud::{ProbeCloud, TetMesh};
use probekit_runtime::format::ProbeFile;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use thiserror::Error;

/// Why cell visibility cannot be baked.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum CellVisibilityError {
    /// The subdivision is outside `1..=8`.
    #[error("cell visibility subdivision {0} is outside 1..={MAX_CELL_SUBDIVISION}")]
    Subdivision(u32),
    /// The file has no tetrahedra (a volume, or an unmerged shard part), or
    /// they do not form a valid mesh.
    #[error(transparent)]
    Mesh(#[from] probekit_runtime::cloud::ProbeCloudError),
}

/// Lattice spacing, metres, that [`auto_subdivision`] aims for along the
/// edges of a typical cell: about the thickness of an interior wall and a
/// half, so that a wall cutting a cell has lattice points close to both of
/// its sides.
pub const CELL_LATTICE_SPACING: f32 = 0.25;

/// The lattice subdivision `k` for `mesh` when none is given (`probekit bake
/// --cell-visibility auto`, the default): `ceil(L / `[`CELL_LATTICE_SPACING`]`)`
/// clamped to [`DEFAULT_CELL_SUBDIVISION`]`..=`[`MAX_CELL_SUBDIVISION`],
/// `L` the [`typical_cell_edge`]. Coarse clouds have large cells, and a
/// lattice of the default `k` = 4 there lets a probe behind a wall keep part
/// of its weight at points next to the wall (BENCHMARKS.md, "Cell lattice
/// from the cell size"); clear cells store no record, so a finer lattice
/// costs only where geometry cuts a cell. A mesh without tetrahedra of
/// positive volume gets the default.
pub fn auto_subdivision(mesh: &TetMesh) -> u32 {
    let Some(edge) = typical_cell_edge(mesh) else {
        return DEFAULT_CELL_SUBDIVISION;
    };
    let k = (edge / CELL_LATTICE_SPACING).ceil();
    if k >= MAX_CELL_SUBDIVISION as f32 {
        MAX_CELL_SUBDIVISION
    } else {
        (k as u32).max(DEFAULT_CELL_SUBDIVISION)
    }
}

/// The volume-weighted median of the tetrahedra's mean edge lengths,
/// metres: half of the cloud's volume lies in cells whose six edges average
/// at most this, so it is the size of the cell a random point in the hull
/// falls in (adaptive clouds crowd small cells next to lights, which a plain
/// median over cells would count). `None` when no tetrahedron has a positive
/// finite volume. Deterministic (ties keep mesh order).
pub fn typical_cell_edge(mesh: &TetMesh) -> Option<f32> {
    const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];
    let p = mesh.positions();
    let mut cells: Vec<(f32, f64)> = mesh
        .tets()
        .iter()
        .map(|t| {
            let v = t.map(|i| p[i as usize]);
            let edge = EDGES.iter().map(|&(a, b)| v[a].distance(v[b])).sum::<f32>() / 6.0;
            let volume = ((v[1] - v[0]).dot((v[2] - v[0]).cross(v[3] - v[0])) as f64).abs() / 6.0;
            (edge, volume)
        })
        .filter(|(e, v)| e.is_finite() && v.is_finite() && *v > 0.0)
        .collect();
    let total: f64 = cells.iter().map(|c| c.1).sum();
    if cells.is_empty() {
        return None;
    }
    // A stable sort: equal lengths keep mesh order.
    cells.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut seen = 0.0;
    for (edge, volume) in &cells {
        seen += volume;
        if seen >= 0.5 * total {
            return Some(*edge);
        }
    }
    cells.last().map(|c| c.0)
}

/// The lattice subdivision to bake cell visibility at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellLattice {
    /// From the cell size ([`auto_subdivision`]); `probekit bake`'s default.
    Auto,
    /// This subdivision (`1..=`[`MAX_CELL_SUBDIVISION`]).
    Fixed(u32),
}

impl CellLattice {
    /// The subdivision for `mesh`.
    pub fn resolve(self, mesh: &TetMesh) -> u32 {
        match self {
            CellLattice::Auto => auto_subdivision(mesh),
            CellLattice::Fixed(k) => k,
        }
    }

    /// The lattice a command line names: `auto` or a subdivision in
    /// `1..=`[`MAX_CELL_SUBDIVISION`]; `None` for anything else (`probekit
    /// bake` reads `0`, no cell visibility, before asking).
    pub fn from_name(s: &str) -> Option<Self> {
        match s {
            "auto" => Some(CellLattice::Auto),
            k => k
                .parse::<u32>()
                .ok()
                .filter(|k| (1..=MAX_CELL_SUBDIVISION).contains(k))
                .map(CellLattice::Fixed),
        }
    }

    /// As the bake metadata records it (`settings.cell_visibility`):
    /// `"auto"` or the subdivision.
    pub fn to_json(self) -> serde_json::Value {
        match self {
            CellLattice::Auto => serde_json::json!("auto"),
            CellLattice::Fixed(k) => serde_json::json!(k),
        }
    }

    /// The lattice a metadata value records ([`CellLattice::to_json`]);
    /// `None` for anything else (`null`: no cell visibility).
    pub fn from_json(v: &serde_json::Value) -> Option<Self> {
        match v {
            serde_json::Value::String(s) if s == "auto" => Some(CellLattice::Auto),
            _ => v
                .as_u64()
                .and_then(|k| u32::try_from(k).ok())
                .map(CellLattice::Fixed),
        }
    }
}

/// One cell's record ([`record_from`]): corner `v`'s bit for lattice point
/// `l` set where the segment from its probe to the point is clear. `lattice`
/// is [`lattice_numerators`] for the cell's corner count.
fn record(
    tracer: &Tracer<'_>,
    probes: &[u32],
    positions: &[Vec3],
    lattice: &[[u32; 4]],
    k: u32,
) -> Vec<u8> {
    let points: Vec<Vec3> = lattice
        .iter()
        .map(|n| lattice_position(probes, positions, n, k))
        .collect();
    record_from(probes.len(), k, |v, l| {
        // The probe itself (numerator k) sees its own position.
        lattice[l][v] == k || segment_clear(tracer, positions[probes[v] as usize], points[l])
    })
}

/// Bakes the cell visibility of `mesh` at subdivision `k` (`1..=8`; see
/// [`probekit_runtime::cloud::cell_visibility::DEFAULT_CELL_SUBDIVISION`]):
/// `(k+1)(k+2)(k+3)/6 · 4` segments per tetrahedron and `(k+1)(k+2)/2 · 3`
/// per hull face. `progress(done, total)` is called as cells finish.
pub fn bake_cell_visibility(
    tracer: &Tracer<'_>,
    mesh: &TetMesh,
    k: u32,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<CellVisibility, CellVisibilityError> {
    if !(1..=MAX_CELL_SUBDIVISION).contains(&k) {
        return Err(CellVisibilityError::Subdivision(k));
    }
    let positions = mesh.positions();
    let tets = mesh.tets();
    let faces = mesh.hull_face_count();
    let total = tets.len() + faces;
    let (lattice4, lattice3) = (lattice_numerators(4, k), lattice_numerators(3, k));
    let done = AtomicUsize::new(0);
    let records: Vec<Vec<u8>> = (0..total)
        .into_par_iter()
        .map(|c| {
            let r = if c < tets.len() {
                record(tracer, &tets[c], positions, &lattice4, k)
            } else {
                let f = mesh
                    .hull_face_probes((c - tets.len()) as u32)
                    .expect("hull face index in range");
                record(tracer, &f, positions, &lattice3, k)
            };
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            r
        })
        .collect();
    Ok(CellVisibility::new(k, tets.len(), faces, records.concat())
        .expect("records sized by record_bytes"))
}

/// [`bake_cell_visibility`] of the mesh a cloud file stores (its positions
/// and `TETS`) at `lattice`'s subdivision for that mesh, ready for
/// [`crate::format::CloudBlend::cell_visibility`].
pub fn bake_file_cell_visibility(
    tracer: &Tracer<'_>,
    file: &ProbeFile,
    lattice: CellLattice,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<CellVisibility, CellVisibilityError> {
    let mesh = ProbeCloud::mesh_from_file(file)?;
    bake_cell_visibility(tracer, &mesh, lattice.resolve(&mesh), progress)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::blend::cell_planes::{bake_cell_planes, CELL_PLANE_SEED};
    use crate::scene::Scene;
    use probekit_runtime::cloud::cell_visibility::{record_bytes, record_sees};
    use probekit_runtime::cloud::{ProbeCloud, WalkState};

    pub(crate) fn scene(boxes: &[(Vec3, Vec3)]) -> Scene {
        crate::scene::tests_support::boxes_scene(boxes)
    }

    /// A room `[-2, 2.3] × [0, 2]²` split by a wall at `x ∈ [0, 0.3]`
    /// (the distance moments' two-room test), probes on a 4 × 3 × 3 lattice.
    pub(crate) fn two_rooms() -> (Scene, TetMesh) {
        let room = (Vec3::new(-2.0, 0.0, 0.0), Vec3::new(2.3, 2.0, 2.0));
        let wall = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.3, 2.0, 2.0));
        let mut pos = Vec::new();
        for x in [-1.5f32, -0.5, 0.8, 1.8] {
            for y in [0.4f32, 1.0, 1.6] {
                for z in [0.4f32, 1.0, 1.6] {
                    pos.push(Vec3::new(x, y, z));
                }
            }
        }
        let tri = crate::delaunay::tetrahedralize(&pos).unwrap();
        (scene(&[room, wall]), tri.to_tet_mesh(&pos).unwrap())
    }

    /// Analytic: does the segment `a → b` enter the slab `x ∈ [0, 0.3]`
    /// (the only inner surface; both ends are in the room)?
    pub(crate) fn crosses_wall(a: Vec3, b: Vec3) -> bool {
        let (lo, hi) = (a.x.min(b.x), a.x.max(b.x));
        lo < 0.3 && hi > 0.0
    }

    /// `typical_cell_edge` against an independent estimate: the median,
    /// over uniform random points of the hull, of the mean edge of the
    /// tetrahedron the walk finds them in (sampling in place of sorting by
    /// volume); and the subdivision it gives scales with the cloud.
    #[test]
    fn typical_cell_edge_is_the_cell_size_at_a_random_point() {
        // Jittered probes, denser near one corner, like a cloud crowding a light.
        let mut rng = crate::sampling::SampleRng::new(11, 0, 0);
        let mut pos = Vec::new();
        for i in 0..6 {
            for j in 0..4 {
                for k in 0..5 {
                    let jit = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
                    pos.push(Vec3::new(i as f32, j as f32, k as f32) * 0.8 + jit * 0.3);
                }
            }
        }
        for _ in 0..200 {
            pos.push(Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 0.6);
        }
        let mesh = crate::delaunay::tetrahedralize(&pos)
            .unwrap()
            .to_tet_mesh(&pos)
            .unwrap();
        let edge = typical_cell_edge(&mesh).unwrap();
        let (lo, hi) = pos
            .iter()
            .fold((Vec3::MAX, Vec3::MIN), |(a, b), p| (a.min(*p), b.max(*p)));
        let mut ws = WalkState::new();
        let mut found = Vec::new();
        while found.len() < 20_000 {
            let q = lo + (hi - lo) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            if let probekit_runtime::cloud::Location::Inside { tet, .. } = mesh.locate(q, &mut ws) {
                let v = mesh.tets()[tet as usize].map(|i| pos[i as usize]);
                let mut sum = 0.0;
                for a in 0..4 {
                    for b in a + 1..4 {
                        sum += v[a].distance(v[b]);
                    }
                }
                found.push(sum / 6.0);
            }
        }
        found.sort_by(f32::total_cmp);
        let sampled = found[found.len() / 2];
        assert!(
            (edge / sampled - 1.0).abs() < 0.03,
            "{edge} against {sampled}"
        );
        // The plain median over cells is smaller: the crowded corner's many
        // small cells hold little volume.
        let mut plain: Vec<f32> = Vec::new();
        for t in mesh.tets() {
            let v = t.map(|i| pos[i as usize]);
            plain.push(
                [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
                    .iter()
                    .map(|&(a, b)| v[a].distance(v[b]))
                    .sum::<f32>()
                    / 6.0,
            );
        }
        plain.sort_by(f32::total_cmp);
        assert!(
            plain[plain.len() / 2] < 0.9 * edge,
            "{} {edge}",
            plain[plain.len() / 2]
        );
        // k = ceil(L / spacing), clamped to 4..=8; scaling the cloud scales L.
        for scale in [0.25f32, 1.0, 1.5, 3.0] {
            let p: Vec<Vec3> = pos.iter().map(|x| *x * scale).collect();
            let m = crate::delaunay::tetrahedralize(&p)
                .unwrap()
                .to_tet_mesh(&p)
                .unwrap();
            let l = typical_cell_edge(&m).unwrap();
            assert!(
                (l / (edge * scale) - 1.0).abs() < 1e-4,
                "{l} {edge} {scale}"
            );
            let want = ((l / CELL_LATTICE_SPACING).ceil() as u32).clamp(4, 8);
            assert_eq!(auto_subdivision(&m), want);
            assert_eq!(CellLattice::Auto.resolve(&m), want);
            assert_eq!(CellLattice::Fixed(3).resolve(&m), 3);
        }
        assert_eq!(
            auto_subdivision(&mesh),
            ((edge / 0.25).ceil() as u32).clamp(4, 8)
        );
    }

    /// Command-line names and metadata values are read back as written;
    /// anything else is refused.
    #[test]
    fn cell_lattice_names_and_metadata_round_trip() {
        for l in [
            CellLattice::Auto,
            CellLattice::Fixed(1),
            CellLattice::Fixed(8),
        ] {
            assert_eq!(CellLattice::from_json(&l.to_json()), Some(l));
        }
        assert_eq!(
            CellLattice::from_json(&serde_json::json!(4)),
            Some(CellLattice::Fixed(4))
        );
        assert_eq!(CellLattice::from_name("auto"), Some(CellLattice::Auto));
        assert_eq!(CellLattice::from_name("8"), Some(CellLattice::Fixed(8)));
        for bad in ["0", "9", "-1", "fine", ""] {
            assert_eq!(CellLattice::from_name(bad), None, "{bad}");
        }
        for bad in [
            serde_json::json!(null),
            serde_json::json!("fine"),
            serde_json::json!(-1),
        ] {
            assert_eq!(CellLattice::from_json(&bad), None);
        }
    }

    #[test]
    fn bits_match_the_analytic_wall_test_at_every_lattice_point() {
        let (sc, mesh) = two_rooms();
        let tracer = Tracer::new(&sc);
        for k in [1, 3, 4] {
            let cv = bake_cell_visibility(&tracer, &mesh, k, &|_, _| {}).unwrap();
            assert_eq!(cv.tet_count(), mesh.tets().len());
            assert_eq!(cv.hull_face_count(), mesh.hull_face_count());
            assert_eq!(cv.first_noncanonical(), None);
            // Sparse: some cells clear (no record), some not.
            let cells_total = cv.tet_count() + cv.hull_face_count();
            assert!(cv.record_count() > 0 && cv.record_count() < cells_total);
            let dense = cv.to_dense();
            let pos = mesh.positions();
            let mut hidden = 0;
            let cells = (0..mesh.tets().len())
                .map(|t| mesh.tets()[t].to_vec())
                .chain(
                    (0..mesh.hull_face_count())
                        .map(|h| mesh.hull_face_probes(h as u32).unwrap().to_vec()),
                );
            let (rb4, rb3) = (record_bytes(4, k), record_bytes(3, k));
            let mut offset = 0;
            for probes in cells {
                let n = probes.len();
                let rec = &dense[offset..offset + if n == 4 { rb4 } else { rb3 }];
                offset += rec.len();
                for (l, num) in lattice_numerators(n, k).iter().enumerate() {
                    // The lattice point by its own formula, in f64.
                    let q: glam::DVec3 = probes
                        .iter()
                        .zip(num)
                        .map(|(&p, &c)| pos[p as usize].as_dvec3() * (c as f64 / k as f64))
                        .sum();
                    for (v, &p) in probes.iter().enumerate() {
                        let got = record_sees(rec, n, k, v, l);
                        let want = !crosses_wall(pos[p as usize], q.as_vec3());
                        assert_eq!(got, want, "k {k} cell {probes:?} point {num:?} vertex {v}");
                        hidden += usize::from(!want);
                    }
                }
            }
            assert_eq!(offset, dense.len());
            assert!(hidden > 0, "some cells must straddle the wall");
        }
        assert!(matches!(
            bake_cell_visibility(&tracer, &mesh, 0, &|_, _| {}),
            Err(CellVisibilityError::Subdivision(0))
        ));
        assert!(matches!(
            bake_cell_visibility(&tracer, &mesh, 9, &|_, _| {}),
            Err(CellVisibilityError::Subdivision(9))
        ));
    }

    #[test]
    fn bake_is_deterministic_across_thread_counts() {
        let (sc, mesh) = two_rooms();
        let tracer = Tracer::new(&sc);
        let a = bake_cell_visibility(&tracer, &mesh, 3, &|_, _| {}).unwrap();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let b = one.install(|| bake_cell_visibility(&tracer, &mesh, 3, &|_, _| {}).unwrap());
        assert_eq!(a, b);
    }

    /// The dark room's probes carry radiance 0 and the lit room's 1; with
    /// cell visibility alone (no distance moments) the lit probes' weight at
    /// a dark-room point falls to what the lattice cannot resolve: zero
    /// beyond one lattice step from the wall, and no more than the linear
    /// ramp of the one sub-cell straddling it.
    #[test]
    fn cell_visibility_alone_stops_the_leak_beyond_one_lattice_step() {
        let (sc, mesh) = two_rooms();
        let tracer = Tracer::new(&sc);
        let k = 4;
        let cv = bake_cell_visibility(&tracer, &mesh, k, &|_, _| {}).unwrap();
        let lit: Vec<Vec3> = mesh
            .positions()
            .iter()
            .map(|p| Vec3::splat(if p.x < 0.0 { 1.0 } else { 0.0 }))
            .collect();
        let coeffs: Vec<Vec3> = lit.clone();
        let mut cloud = ProbeCloud::new(mesh.clone(), 1, coeffs).unwrap();
        cloud.set_cell_visibility_bits(Some(cv)).unwrap();
        let mut st = WalkState::new();
        let blend = |cloud: &ProbeCloud, p: Vec3, st: &mut WalkState| {
            let (idx, w) = cloud.weights_at(p, st);
            idx.iter()
                .zip(w)
                .map(|(&i, w)| w * lit[i as usize].x)
                .sum::<f32>()
        };
        let (mut worst_near, mut worst_off) = (0.0f32, 0.0f32);
        for i in 0..200 {
            let f = (i as f32 + 0.5) / 200.0;
            let p = Vec3::new(
                0.31 + 1.4 * f,
                0.2 + 1.6 * (f * 13.0).fract(),
                0.2 + 1.6 * (f * 7.0).fract(),
            );
            cloud.set_cell_visibility(false);
            let off = blend(&cloud, p, &mut st);
            cloud.set_cell_visibility(true);
            let on = blend(&cloud, p, &mut st);
            // One lattice step along the longest cell edge across the wall
            // (1.3 m from x = −0.5 to x = 0.8) is 1.3/k; beyond it, no leak.
            if p.x > 0.3 + 1.3 * 1.5 / k as f32 {
                assert!(on < 1e-6, "{p:?}: {on} (without: {off})");
            } else {
                worst_near = worst_near.max(on);
            }
            worst_off = worst_off.max(off);
        }
        eprintln!("near the wall: worst {worst_near}, without {worst_off}");
        assert!(worst_near < 0.25 * worst_off, "{worst_near} vs {worst_off}");
        // The lit room keeps its light.
        let e = blend(&cloud, Vec3::new(-1.0, 1.0, 1.0), &mut st);
        assert!((e - 1.0).abs() < 1e-5, "{e}");

        // With occluder planes the step is at the wall: no lit probe keeps
        // any weight anywhere in the dark room, right up to the wall.
        let cv = cloud.cell_visibility_bits().unwrap().clone();
        let planes = bake_cell_planes(&tracer, &mesh, &cv, CELL_PLANE_SEED, &|_, _| {}).unwrap();
        cloud.set_cell_planes(Some(planes)).unwrap();
        for i in 0..200 {
            let f = (i as f32 + 0.5) / 200.0;
            let p = Vec3::new(
                0.301 + 1.4 * f * f,
                0.2 + 1.6 * (f * 13.0).fract(),
                0.2 + 1.6 * (f * 7.0).fract(),
            );
            let on = blend(&cloud, p, &mut st);
            assert!(on == 0.0, "{p:?}: {on}");
        }
        let e = blend(&cloud, Vec3::new(-0.01, 1.0, 1.0), &mut st);
        assert!((e - 1.0).abs() < 1e-5, "{e}");
    }
}
