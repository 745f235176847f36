//! The analytic / rig split (Yuan et al. 2011 §3) and the error metrics.
//!
//! **Error table.** For a fitted rig on its mesh (placed at the origin),
//! a reference sphere light of radius [`REF_LIGHT_RADIUS`]` · R` (`R` the
//! bounding-sphere radius) is put at distance `x·R` from the centre along
//! each of [`table_directions`]; the rig is updated from the light's SH at
//! its samples and evaluated at every vertex. The tabulated error at `x` is
//! the largest over directions and vertices of
//! `255 · |E_rig − E_SH| / E_ref(x)` ([`rig_error_for_light`]: `E_SH` is the
//! light's own SH evaluated at the vertex, so the table measures the rig's
//! spatial error, which vanishes far away, not the SH truncation), where `E_ref(x)` is the exact
//! irradiance at the bounding-sphere point nearest the light with normal
//! facing it. That is the error in 8-bit grey levels (`255·ρ|ΔE|/π ÷
//! L_white`, `ρ = 1`) of a light normalised so that its reflected radiance at
//! that point is white — the role of the paper's `N(r)`, which maps any light
//! onto the unitized one. Distances are stored as `x` (bounding radii from
//! the centre).
//!
//! **Transition distance of a light.** Errors are linear in intensity, so a
//! real light at `x` has error `g(x) = e(x) · (E_ref,light(x)/π) / L_white`
//! grey levels, `E_ref,light` its own exact irradiance at the nearest
//! bounding-sphere point when moved along its direction to `x`. `g` falls
//! with distance; binary search over the table brackets where `g` crosses the
//! target and linear interpolation inside the bracket gives `x*`. Lights with
//! `x < x*` are analytic, `x* ≤ x < `[`TRANSITION_BAND`]` · x*` are
//! cross-faded (rig weight rising linearly from 0 to 1), the rest go through
//! the rig.

use super::fit::FittedRig;
use super::mesh::Mesh;
use super::source::ProbeSource;
use crate::lights::{Light, SphereTable};
use glam::Vec3;
use probekit_runtime::format::Transition;
use probekit_runtime::rig::RigState;
use probekit_runtime::ObjectState;

/// Radius of the table's reference sphere light, in bounding radii.
pub const REF_LIGHT_RADIUS: f32 = 0.05;
/// The cross-fade band: lights between `x*` and `TRANSITION_BAND · x*`.
pub const TRANSITION_BAND: f32 = 1.25;

/// The directions the error table is measured along: the 6 axis directions
/// and the 8 box diagonals.
pub fn table_directions() -> Vec<Vec3> {
    let mut v = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    for i in 0..8 {
        let s = |b: i32| if i & b != 0 { 1.0 } else { -1.0 };
        v.push(Vec3::new(s(1), s(2), s(4)).normalize());
    }
    v
}

/// `count` table distances, geometric from 1.1 to 48 bounding radii.
pub fn table_distances(count: usize) -> Vec<f32> {
    let (a, b) = (1.1f32, 48.0f32);
    let n = count.max(2);
    (0..n)
        .map(|i| a * (b / a).powf(i as f32 / (n - 1) as f32))
        .collect()
}

/// Which way a light is evaluated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Zone {
    /// Per vertex, exactly (horizon-clipped table for spheres).
    Analytic,
    /// Cross-faded; the value is the rig's weight in `(0, 1)`.
    Transition(f32),
    /// Through the rig.
    Rig,
}

impl Zone {
    /// Weight of the rig path (0 analytic, 1 rig).
    pub fn rig_weight(self) -> f32 {
        match self {
            Zone::Analytic => 0.0,
            Zone::Transition(w) => w,
            Zone::Rig => 1.0,
        }
    }
}

/// Reusable per-frame buffers: the runtime state and the sample SH.
#[derive(Clone, Debug)]
pub struct Frame {
    /// The runtime rig.
    pub state: RigState,
    /// SH at the samples, sample-major.
    pub sample_sh: Vec<Vec3>,
}

impl Frame {
    /// Buffers for `fitted`.
    pub fn new(fitted: &FittedRig) -> Self {
        let state = fitted.state();
        let n = state.sample_count() * state.order() * state.order();
        Self {
            state,
            sample_sh: vec![Vec3::ZERO; n],
        }
    }

    /// Updates the rig from `source`, called with a world position and the
    /// sample's SH slice to add into (the lighting-source hook: analytic
    /// lights, or a baked probe cloud/volume sampled at the point). The
    /// rig's samples are placed at `at`.
    pub fn update_from(
        &mut self,
        fitted: &FittedRig,
        at: Vec3,
        mut source: impl FnMut(Vec3, &mut [Vec3]),
    ) {
        let n2 = self.state.order() * self.state.order();
        self.sample_sh.fill(Vec3::ZERO);
        for (p, out) in fitted
            .rig
            .samples
            .iter()
            .zip(self.sample_sh.chunks_exact_mut(n2))
        {
            source(*p + at, out);
        }
        self.state
            .update(&self.sample_sh)
            .expect("buffer sized for the rig");
    }
}

/// Updates `frame` from `lights`, each weighted by its rig weight
/// (`weights[i]`; 1 for all lights with the split off).
pub fn update_from_lights(
    frame: &mut Frame,
    fitted: &FittedRig,
    at: Vec3,
    lights: &[Light],
    weights: &[f32],
) {
    let order = frame.state.order();
    frame.update_from(fitted, at, |p, out| {
        for (l, &w) in lights.iter().zip(weights) {
            if w > 0.0 {
                l.add_sh(order, p, w, out);
            }
        }
    });
}

/// Updates `frame` from `lights` (weighted as in [`update_from_lights`])
/// plus, when given, the baked file `probes` sampled at each sample point
/// (always fully in the rig). `walk` is the object's query state, kept
/// between frames.
#[allow(clippy::too_many_arguments)]
pub fn update_from_sources(
    frame: &mut Frame,
    fitted: &FittedRig,
    at: Vec3,
    lights: &[Light],
    weights: &[f32],
    probes: Option<&ProbeSource>,
    walk: &mut ObjectState,
) {
    let order = frame.state.order();
    frame.update_from(fitted, at, |p, out| {
        for (l, &w) in lights.iter().zip(weights) {
            if w > 0.0 {
                l.add_sh(order, p, w, out);
            }
        }
        if let Some(src) = probes {
            src.add_sh(p, 1.0, walk, out);
        }
    });
}

/// Adds the baked file's irradiance (truncated to `order` bands),
/// evaluated at each vertex of `mesh` placed at `at` with its normal, to
/// `out`: the baked part of the exact reference ([`super::source`]).
pub fn add_probe_irradiance(
    mesh: &Mesh,
    at: Vec3,
    probes: &ProbeSource,
    order: usize,
    walk: &mut ObjectState,
    out: &mut [Vec3],
) {
    for ((o, p), n) in out.iter_mut().zip(&mesh.positions).zip(&mesh.normals) {
        *o += probes.irradiance(*p + at, *n, order, walk);
    }
}

/// Exact per-vertex irradiance of all lights for `mesh` placed at `at`.
pub fn exact_irradiance(mesh: &Mesh, at: Vec3, lights: &[Light]) -> Vec<Vec3> {
    mesh.positions
        .iter()
        .zip(&mesh.normals)
        .map(|(p, n)| lights.iter().map(|l| l.irradiance(*p + at, *n, None)).sum())
        .collect()
}

/// Per-vertex irradiance with the split: the rig (already updated with the
/// rig weights) plus `(1 − w)` × the analytic evaluation of each light with
/// rig weight `w < 1` (sphere lights through `table`). Writes `out`.
pub fn split_irradiance(
    frame: &Frame,
    mesh: &Mesh,
    at: Vec3,
    lights: &[Light],
    weights: &[f32],
    table: &SphereTable,
    out: &mut [Vec3],
) {
    for ((o, p), n) in out.iter_mut().zip(&mesh.positions).zip(&mesh.normals) {
        let mut e = frame.state.irradiance(*p, *n);
        for (l, &w) in lights.iter().zip(weights) {
            if w < 1.0 {
                e += l.irradiance(*p + at, *n, Some(table)) * (1.0 - w);
            }
        }
        *o = e;
    }
}

/// Per-vertex irradiance of the lights' own SH (`order` bands) evaluated at
/// each vertex, weighted by `weights` (rig weight), plus `(1 − w)` × the
/// exact irradiance: what a perfect spatial model would give. The gap
/// between this and the exact irradiance is the SH truncation, shared by
/// every rig; the gap between a rig and this is the rig's spatial error.
pub fn sh_reference_irradiance(
    mesh: &Mesh,
    at: Vec3,
    lights: &[Light],
    weights: &[f32],
    order: usize,
) -> Vec<Vec3> {
    let n2 = order * order;
    let mut sh = vec![Vec3::ZERO; n2];
    mesh.positions
        .iter()
        .zip(&mesh.normals)
        .map(|(p, n)| {
            sh.fill(Vec3::ZERO);
            let mut e = Vec3::ZERO;
            for (l, &w) in lights.iter().zip(weights) {
                if w > 0.0 {
                    l.add_sh(order, *p + at, w, &mut sh);
                }
                if w < 1.0 {
                    e += l.irradiance(*p + at, *n, None) * (1.0 - w);
                }
            }
            e + probekit_sh::irradiance(&sh, *n)
        })
        .collect()
}

/// Spatial error of `fitted` on `mesh` for one light, in grey levels for a
/// white level `l_white` (reflected radiance): `255 · max_v |E_rig − E_SH| /
/// π / l_white` over vertices and channels, where `E_SH` is the irradiance
/// of the light's own SH at the vertex (so the SH truncation, which no rig
/// can remove, is not counted), the light entirely in the rig, the mesh at
/// the origin. Yuan et al. 2011 §3.1 measures the same "brute force vs rig"
/// difference at the single bounding-sphere point nearest the light; the
/// rig is evaluated on the mesh here instead, where it is used (outside the
/// mesh a lattice extrapolates from nodes that may have no samples).
pub fn rig_error_for_light(
    fitted: &FittedRig,
    frame: &mut Frame,
    mesh: &Mesh,
    light: &Light,
    l_white: f32,
) -> f32 {
    update_from_lights(
        frame,
        fitted,
        Vec3::ZERO,
        std::slice::from_ref(light),
        &[1.0],
    );
    let order = frame.state.order();
    let mut sh = [Vec3::ZERO; probekit_sh::MAX_COEFFS];
    let mut worst = 0.0f32;
    for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
        sh[..order * order].fill(Vec3::ZERO);
        light.add_sh(order, *p, 1.0, &mut sh);
        let reference = probekit_sh::irradiance(&sh[..order * order], *n);
        let d = frame.state.irradiance(*p, *n) - reference;
        worst = worst.max(d.abs().max_element());
    }
    255.0 * worst / std::f32::consts::PI / l_white
}

/// Exact irradiance (largest channel) of `light` moved to distance `x·R`
/// along unit `dir` from `center`, at the bounding-sphere point `center +
/// R·dir` with normal `dir`.
pub fn nearest_point_irradiance(
    light: &Light,
    center: Vec3,
    radius: f32,
    dir: Vec3,
    x: f32,
) -> f32 {
    let l = light.moved_to(center + dir * (x * radius));
    l.irradiance(center + dir * radius, dir, None).max_element()
}

/// The error table of module docs for `fitted` on `mesh`, over `distances`
/// (bounding radii) and `dirs`.
pub fn transition_table(
    fitted: &FittedRig,
    mesh: &Mesh,
    distances: &[f32],
    dirs: &[Vec3],
) -> Vec<Transition> {
    let (c, r) = mesh.bounding_sphere();
    let mut frame = Frame::new(fitted);
    distances
        .iter()
        .map(|&x| {
            let mut e = 0.0f32;
            for &u in dirs {
                let light = Light::Sphere {
                    position: c + u * (x * r),
                    radius: REF_LIGHT_RADIUS * r,
                    intensity: Vec3::ONE,
                };
                let e_ref = nearest_point_irradiance(&light, c, r, u, x);
                // White = the reference's reflected radiance E_ref/π.
                let err = rig_error_for_light(
                    fitted,
                    &mut frame,
                    mesh,
                    &light,
                    e_ref / std::f32::consts::PI,
                );
                e = e.max(err);
            }
            Transition {
                distance: x,
                error: e,
            }
        })
        .collect()
}

/// Transition distance `x*` (bounding radii from the centre) of `light` for
/// `target` grey levels, from `table` (module docs): binary search for the
/// bracket where `g` falls to `target`, then linear interpolation. If `g`
/// is below the target at the table's first distance, that distance; if it
/// is still above at the last, the last (the light is analytic within the
/// table's range). A directional light gives 0 (never analytic).
pub fn transition_distance(
    table: &[Transition],
    light: &Light,
    center: Vec3,
    radius: f32,
    l_white: f32,
    target: f32,
) -> f32 {
    // A directional light is infinitely far: always through the rig.
    let Some(position) = light.position() else {
        return 0.0;
    };
    if table.is_empty() {
        return 0.0;
    }
    let dir = (position - center).try_normalize().unwrap_or(Vec3::Y);
    let g = |i: usize| {
        let t = table[i];
        t.error * nearest_point_irradiance(light, center, radius, dir, t.distance)
            / std::f32::consts::PI
            / l_white
    };
    let n = table.len();
    if g(0) <= target {
        return table[0].distance;
    }
    if g(n - 1) > target {
        return table[n - 1].distance;
    }
    // Invariant: g(lo) > target ≥ g(hi).
    let (mut lo, mut hi) = (0usize, n - 1);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if g(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let (glo, ghi) = (g(lo), g(hi));
    let (xlo, xhi) = (table[lo].distance, table[hi].distance);
    xlo + (glo - target) / (glo - ghi) * (xhi - xlo)
}

/// The zone of a light at distance `x` (bounding radii; `f32::INFINITY` for
/// a directional light) with threshold `x*`.
pub fn zone(x: f32, x_star: f32) -> Zone {
    if x < x_star {
        Zone::Analytic
    } else if x < TRANSITION_BAND * x_star {
        Zone::Transition((x - x_star) / ((TRANSITION_BAND - 1.0) * x_star))
    } else {
        Zone::Rig
    }
}

/// Errors of a per-vertex evaluation against the exact one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorStats {
    /// `sqrt(Σ ΔE²) / sqrt(Σ E²)` over vertices and the three channels.
    pub rel_rmse: f32,
    /// Largest `255 · |ΔE|/π / l_white` over vertices and channels.
    pub max_grey: f32,
    /// The white level used (reflected radiance).
    pub l_white: f32,
}

/// The white level of Yuan et al. 2011 §3, taken as the largest exact
/// reflected radiance `E/π` (albedo 1) over vertices and channels.
pub fn white_level(exact: &[Vec3]) -> f32 {
    exact.iter().map(|e| e.max_element()).fold(0.0, f32::max) / std::f32::consts::PI
}

/// [`ErrorStats`] of `approx` against `exact` (`l_white` from
/// [`white_level`] unless given).
pub fn error_stats(approx: &[Vec3], exact: &[Vec3], l_white: Option<f32>) -> ErrorStats {
    let l_white = l_white
        .unwrap_or_else(|| white_level(exact))
        .max(f32::MIN_POSITIVE);
    let (mut se, mut sr, mut worst) = (0.0f64, 0.0f64, 0.0f32);
    for (a, e) in approx.iter().zip(exact) {
        let d = *a - *e;
        se += d.length_squared() as f64;
        sr += e.length_squared() as f64;
        worst = worst.max(d.abs().max_element());
    }
    ErrorStats {
        rel_rmse: if sr > 0.0 {
            (se / sr).sqrt() as f32
        } else {
            0.0
        },
        max_grey: 255.0 * worst / std::f32::consts::PI / l_white,
        l_white,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::{mesh, RigSpec};

    /// Transition distances against brute force: for a real light (radius and
    /// intensity of its own), sweep its distance finely, measuring the
    /// rig's error directly on the mesh (no table), and check that the
    /// threshold found from the table by bisection + interpolation lies where
    /// the brute-force error crosses the target.
    #[test]
    fn transition_distance_matches_brute_force_sweep() {
        let car = mesh::car();
        let fitted = crate::rig::fit::FittedRig::fit(
            &car,
            "gradient".parse::<RigSpec>().unwrap(),
            3,
            128,
            5,
            "car",
        )
        .unwrap();
        let (c, r) = car.bounding_sphere();
        let dir = Vec3::new(1.0, 0.0, 0.0);
        let table = transition_table(&fitted, &car, &table_distances(24), &[dir]);
        // A light with the reference radius along the table's direction; its
        // intensity and the white level set the target crossing.
        let light = Light::Sphere {
            position: c + dir * (3.0 * r),
            radius: REF_LIGHT_RADIUS * r,
            intensity: Vec3::splat(40.0),
        };
        let l_white = 2.0;
        let target = 1.0;
        let x_star = transition_distance(&table, &light, c, r, l_white, target);
        // Brute force: direct error on a fine sweep.
        let mut frame = Frame::new(&fitted);
        let direct = |x: f32, frame: &mut Frame| {
            let l = light.moved_to(c + dir * (x * r));
            rig_error_for_light(&fitted, frame, &car, &l, l_white)
        };
        let xs: Vec<f32> = (0..120)
            .map(|i| 1.1 * (40.0f32 / 1.1).powf(i as f32 / 119.0))
            .collect();
        let errs: Vec<f32> = xs.iter().map(|&x| direct(x, &mut frame)).collect();
        // Outermost crossing of the target on the sweep.
        let k = errs
            .iter()
            .rposition(|&e| e > target)
            .expect("error exceeds the target near the car");
        assert!(k + 1 < xs.len(), "error never falls below target");
        let brute = xs[k] + (errs[k] - target) / (errs[k] - errs[k + 1]) * (xs[k + 1] - xs[k]);
        assert!(
            (x_star / brute - 1.0).abs() < 0.08,
            "table threshold {x_star} vs brute-force sweep {brute}"
        );
        // And the meaning of the threshold: the direct error just beyond it
        // is at most the target (within the interpolation tolerance).
        assert!(direct(x_star * 1.1, &mut frame) <= target * 1.05);
        assert!(direct(x_star * 0.85, &mut frame) > target);
    }

    #[test]
    fn zones_and_crossfade() {
        assert_eq!(zone(1.0, 2.0), Zone::Analytic);
        assert_eq!(zone(3.0, 2.0), Zone::Rig);
        let Zone::Transition(w) = zone(2.25, 2.0) else {
            panic!()
        };
        assert!((w - 0.5).abs() < 1e-6);
    }

    /// With every light in the rig and a constant field (one far, tiny
    /// light), any rig's split evaluation matches the exact answer closely;
    /// with every light analytic it matches to the table's accuracy.
    #[test]
    fn split_paths_agree_with_exact_in_their_limits() {
        let car = mesh::character();
        let fitted = crate::rig::fit::FittedRig::fit(
            &car,
            "lattice:2x2x2".parse::<RigSpec>().unwrap(),
            3,
            64,
            1,
            "c",
        )
        .unwrap();
        let lights = [Light::Sphere {
            position: Vec3::new(0.5, 2.0, 1.0),
            radius: 0.2,
            intensity: Vec3::new(3.0, 2.0, 1.0),
        }];
        let at = Vec3::new(0.0, 0.0, 0.3);
        let exact = exact_irradiance(&car, at, &lights);
        let table = SphereTable::default();
        let mut frame = Frame::new(&fitted);
        let mut out = vec![Vec3::ZERO; car.positions.len()];
        update_from_lights(&mut frame, &fitted, at, &lights, &[0.0]);
        split_irradiance(&frame, &car, at, &lights, &[0.0], &table, &mut out);
        let s = error_stats(&out, &exact, None);
        assert!(s.rel_rmse < 2e-3 && s.max_grey < 1.0, "{s:?}");
        update_from_lights(&mut frame, &fitted, at, &lights, &[1.0]);
        split_irradiance(&frame, &car, at, &lights, &[1.0], &table, &mut out);
        let s_rig = error_stats(&out, &exact, None);
        assert!(
            s_rig.rel_rmse > s.rel_rmse && s_rig.rel_rmse < 0.5,
            "{s_rig:?}"
        );
    }
}
