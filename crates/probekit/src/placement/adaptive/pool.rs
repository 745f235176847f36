//! The candidate pool: jittered points over the bake box with a layer along
//! its faces, layers along emissive surfaces and shells around positional
//! lights (see the module docs of [`super`]).

use super::scoring::energy;
use super::PROBE_CLEARANCE;
use crate::sampling::SampleRng;
use crate::scene::{Aabb, Light, LightKind, Scene};
use glam::Vec3;
use probekit_sh::project::fibonacci_point;
use probekit_sh::ShRgb;

/// Directions per shell of [`light_shells`].
pub(super) const LIGHT_SHELL_DIRECTIONS: usize = 24;

/// Ratio of successive shell radii in [`light_shells`].
const LIGHT_SHELL_RATIO: f32 = 1.6;

/// Largest shell radius in [`light_shells`], metres.
pub(super) const LIGHT_SHELL_MAX: f32 = 2.5;

/// The innermost shell of [`light_shells`] keeps at least this fraction of
/// the budget's mean probe spacing (`(box volume / budget)^⅓`) from the
/// light. Irradiance falls off as `1/d²`, a convex function, so linear
/// interpolation between a probe close to the light and probes far from it
/// overshoots in between; the geometric shells keep it even only as a set,
/// and a small budget affords the inner shell alone. Measured on the duplex
/// (docs/notes/light-shells.md): at 137 probes one point 0.5 m from a ceiling
/// light, predicted 4.5× its truth, held 60 % of the squared error
/// (rel_rmse 1.66); starting the shells at a quarter of the spacing gave
/// 0.71. At larger budgets the 0.3 m floor decides, as before.
pub(super) const LIGHT_SHELL_INNER: f32 = 0.25;

/// Pool points in the outermost layer of jitter cells sit this far from the
/// box face (metres, just over [`PROBE_CLEARANCE`]; see [`layer_box`] for
/// the faces with an emitter next to them). No probe may be outside
/// the box, so the probes' convex hull ends inside it, and a point between
/// the hull and a wall is lit by the nearest hull face, which can span a
/// whole room or reach across a wall; pool points along the walls let the
/// ranking see that error and put probes there. Measured on builtin:demo
/// (BENCHMARKS.md, "Placement against uniform grids"): without it, a point by room A's lamp and the
/// back wall was predicted at 0.5 % of its truth.
pub(in crate::placement) const BOUNDARY_SNAP: f32 = 1.2 * PROBE_CLEARANCE;

/// The box layer of adaptive placement ([`super::snap_to_layer`]): `bbox`
/// shrunk by [`BOUNDARY_SNAP`] on every face, but by [`PROBE_CLEARANCE`]
/// alone on a face with a vertex of an emissive triangle between it and
/// that layer (the Cornell box's light hangs 1 cm under the ceiling, in the
/// box's top face): there the layer comes as close as a probe may, 4 cm
/// from the light ([`EMITTER_CLEARANCE`] lets it run on under the light),
/// where the irradiance towards the light is still growing fast. Every
/// other face keeps the wider layer, which measured better on the demo
/// (BENCHMARKS.md, "Box layer at the clearance").
pub(super) fn layer_box(scene: &Scene, bbox: &Aabb) -> Aabb {
    let (mut min, mut max) = (
        bbox.min + Vec3::splat(BOUNDARY_SNAP),
        bbox.max - Vec3::splat(BOUNDARY_SNAP),
    );
    let emitters = scene
        .emissive_triangles
        .iter()
        .filter_map(|et| scene.triangles.get(et.triangle as usize));
    for p in emitters.flat_map(|t| t.positions) {
        if !bbox.contains(p) {
            continue;
        }
        for a in 0..3 {
            if p[a] < bbox.min[a] + BOUNDARY_SNAP {
                min[a] = bbox.min[a] + PROBE_CLEARANCE;
            }
            if p[a] > bbox.max[a] - BOUNDARY_SNAP {
                max[a] = bbox.max[a] - PROBE_CLEARANCE;
            }
        }
    }
    Aabb::new(min, max)
}

/// About `n` points jittered in the cells of a grid over `b` (seeded); in
/// the outermost cells the coordinate across the box face is set to the
/// face of `layer` on that side (when given), so the pool has points along
/// the box's walls.
pub(super) fn jittered(b: &Aabb, n: usize, seed: u64, layer: Option<&Aabb>) -> Vec<Vec3> {
    let size = b.size();
    let cell = (size.x * size.y * size.z / n.max(1) as f32).cbrt();
    // `place` refuses flat boxes first; a zero cell would make the grid unbounded.
    if !(cell.is_finite() && cell > 0.0) {
        return Vec::new();
    }
    let dims = (size / cell).ceil().max(Vec3::ONE);
    let (nx, ny, nz) = (dims.x as usize, dims.y as usize, dims.z as usize);
    let mut out = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let idx = (i + nx * (j + ny * k)) as u64;
                let mut rng = SampleRng::new(seed, 0x504f_4f4c, idx);
                let u = Vec3::new(
                    (i as f32 + rng.next_f32()) / nx as f32,
                    (j as f32 + rng.next_f32()) / ny as f32,
                    (k as f32 + rng.next_f32()) / nz as f32,
                );
                let mut p = b.min + u * size;
                if let Some(l) = layer {
                    for (a, (c, m)) in [(i, nx), (j, ny), (k, nz)].into_iter().enumerate() {
                        if c == 0 {
                            p[a] = l.min[a];
                        } else if c + 1 == m {
                            p[a] = l.max[a];
                        }
                    }
                }
                out.push(p);
            }
        }
    }
    out
}

/// Shells of candidates around each positional light (point, spot, sphere,
/// disk): [`LIGHT_SHELL_DIRECTIONS`] spherical-Fibonacci directions at
/// distances growing geometrically by [`LIGHT_SHELL_RATIO`] from just outside
/// the light (and at least `min_radius`, see [`LIGHT_SHELL_INNER`]) to
/// `max_radius` (at most [`LIGHT_SHELL_MAX`]). Direct light falls off as `1/d²`, so the
/// probe spacing that keeps linear interpolation's error even grows in
/// proportion to the distance from the light; a uniform pool is far too sparse
/// near a light to offer such positions. They are only candidates: the greedy
/// ranking decides which become probes.
pub(super) fn light_shells(
    lights: &[Light],
    bbox: &Aabb,
    min_radius: f32,
    max_radius: f32,
) -> Vec<Vec3> {
    let mut out = Vec::new();
    for (li, l) in lights.iter().enumerate() {
        if l.kind == LightKind::Directional || !l.position.is_finite() {
            continue;
        }
        let mut r = (3.0 * l.radius)
            .max(l.radius + 2.0 * PROBE_CLEARANCE)
            .max(0.3)
            .max(min_radius);
        let mut shell = 0usize;
        while r <= max_radius {
            // A different rotation per shell, so shells do not line up.
            let rot = glam::Quat::from_rotation_y(2.399_963 * (shell + li) as f32);
            for k in 0..LIGHT_SHELL_DIRECTIONS {
                let d = rot * fibonacci_point(k, LIGHT_SHELL_DIRECTIONS);
                let p = l.position + r * d;
                if bbox.contains(p) {
                    out.push(p);
                }
            }
            r *= LIGHT_SHELL_RATIO;
            shell += 1;
        }
    }
    out
}

/// Whether [`light_shells`] offers any candidate in `bbox`: some positional
/// light is close enough to the box.
pub(in crate::placement) fn has_shell_lights(scene: &Scene, bbox: &Aabb) -> bool {
    !light_shells(&scene.lights, bbox, 0.0, LIGHT_SHELL_MAX).is_empty()
}

/// Distances of the pool layers in front of and behind emissive surfaces,
/// in units of [`PROBE_CLEARANCE`]. The first is the clearance itself (a
/// point there passes [`has_clearance`] through [`CLEARANCE_TOLERANCE`]):
/// the irradiance next to an area light grows fastest in the last
/// centimetres a probe may reach, and the Cornell box's error at ~7000
/// probes comes mostly from points within 10 cm of its light
/// (BENCHMARKS.md, "Where the Cornell box's error is"; 1.2 before). Points
/// of a layer beyond the box layer (under a ceiling light) go onto it
/// ([`super::snap_to_layer`]).
pub(super) const EMITTER_LAYERS: [f32; 3] = [1.0, 2.5, 5.0];

/// Random stream of the emitter layers' sample points.
const EMITTER_STREAM: u64 = 0x656d_6974; // "emit"

/// Pool points in layers along emissive surfaces: points spread over each
/// emissive triangle (about one per `spacing²` of area, at least one),
/// offset along its normal on both sides by [`EMITTER_LAYERS`]. Next to an
/// area light the irradiance changes within centimetres (a point 3 cm under
/// the Cornell box's ceiling light gets ten times what one 30 cm below
/// does), where a uniform pool rarely has a point; the layers let the error
/// ranking see and fill that. At most `limit` points (evenly thinned), only
/// inside `bbox`. Deterministic.
pub(super) fn emitter_layers(
    scene: &Scene,
    bbox: &Aabb,
    spacing: f32,
    seed: u64,
    limit: usize,
) -> Vec<Vec3> {
    let mut out = Vec::new();
    for et in &scene.emissive_triangles {
        let Some(t) = scene.triangles.get(et.triangle as usize) else {
            continue;
        };
        let n = t.geometric_normal_unnormalized().normalize_or_zero();
        if n == Vec3::ZERO || spacing.is_nan() || spacing <= 0.0 {
            continue;
        }
        let count = ((et.area / (spacing * spacing)).ceil() as usize).clamp(1, 256);
        for k in 0..count {
            let mut rng = SampleRng::new(seed, EMITTER_STREAM ^ et.triangle as u64, k as u64);
            let u = rng.next_2d();
            let (s, v) = (u.x.sqrt(), u.y);
            let [a, b, c] = t.positions;
            let p = a * (1.0 - s) + b * (s * (1.0 - v)) + c * (s * v);
            for f in EMITTER_LAYERS {
                for side in [1.0, -1.0] {
                    let q = p + n * (side * f * PROBE_CLEARANCE);
                    if bbox.contains(q) {
                        out.push(q);
                    }
                }
            }
        }
    }
    if out.len() > limit {
        let step = out.len() as f64 / limit.max(1) as f64;
        out = (0..limit)
            .map(|i| out[(i as f64 * step) as usize])
            .collect();
    }
    out
}

/// Candidate pool and which of its points are probes.
pub(super) struct Pool {
    pub(super) pos: Vec<Vec3>,
    pub(super) sh: Vec<ShRgb>,
    pub(super) energy: Vec<f32>,
    /// Index into the probes, when this pool point is one.
    pub(super) probe: Vec<Option<usize>>,
}

impl Pool {
    /// A pool of captured points, none of them a probe yet; `w` are the
    /// band weights of [`energy`].
    pub(super) fn new(pos: Vec<Vec3>, sh: Vec<ShRgb>, w: &[f32]) -> Self {
        let n = pos.len();
        Pool {
            energy: sh.iter().map(|s| energy(w, s)).collect(),
            pos,
            sh,
            probe: vec![None; n],
        }
    }
}
