//! The cloud blend's fast path against a straightforward implementation of
//! the same rules (the blend as first written: brightness factors by `powf`
//! per probe, Chebyshev visibility of the normalized direction, the
//! directional blend evaluating every probe at the twelve directions and
//! projecting back): weights and SH agree to 1e-5 relative on random clouds
//! with every combination of blend sections, inside and outside the hull.

mod common;

use common::clouds::{random_cloud, Blend};
use common::Rng;
use glam::Vec3;
use probekit_runtime::cloud::directional::{self, DirectionTable, DIRECTIONS};
use probekit_runtime::cloud::visibility::{
    chebyshev_visibility, sample_oct_bilinear, MIN_VISIBILITY_VARIANCE,
};
use probekit_runtime::cloud::{CellPlanes, Location, ProbeCloud, WalkState, HIDDEN_MASS_FLOOR};
use probekit_runtime::sh::LUMINANCE;

/// The blend rules written out directly over a cloud's public parts.
struct Reference<'a> {
    cloud: &'a ProbeCloud,
    /// `Ē_i`: luminance of each probe's DC coefficient.
    luminance: Vec<f32>,
    /// `L_i(d)`: luminance of each probe's irradiance at the 12 directions.
    directional: Vec<[f32; DIRECTIONS]>,
    table: DirectionTable,
}

impl<'a> Reference<'a> {
    fn new(cloud: &'a ProbeCloud) -> Self {
        let table = DirectionTable::new();
        let n = cloud.probe_count();
        Reference {
            cloud,
            luminance: (0..n)
                .map(|i| LUMINANCE.dot(cloud.probe_sh(i)[0]))
                .collect(),
            directional: (0..n).map(|i| table.luminance(cloud.probe_sh(i))).collect(),
            table,
        }
    }

    /// Chebyshev visibility of `p` from probe `i`.
    fn chebyshev(&self, i: usize, p: Vec3) -> f32 {
        let maps = self.cloud.visibility_maps().unwrap();
        let pos = self.cloud.mesh().positions()[i];
        let map = maps.probe_map(i);
        let v = p - pos;
        let len = v.length();
        let d = len - maps.bias();
        if map.is_empty() || d.is_nan() || d <= 0.0 || len <= 0.0 {
            return 1.0;
        }
        let [mu, mu2] = sample_oct_bilinear(map, maps.resolution(), v / len);
        chebyshev_visibility(d, mu, mu2, MIN_VISIBILITY_VARIANCE, maps.sharpness())
    }

    fn brightness_factors(&self, probes: &[u32; 4], bary: &[f32; 4]) -> [f32; 4] {
        let mut f = [1.0f32; 4];
        let alpha = self.cloud.brightness_weighting();
        if alpha <= 0.0 {
            return f;
        }
        let lum = |k: usize| self.luminance[probes[k] as usize];
        let e: [f32; 4] = core::array::from_fn(|k| if bary[k] != 0.0 { lum(k) } else { 0.0 });
        let top = e.iter().copied().fold(0.0f32, f32::max);
        if !(top > 0.0 && top.is_finite()) {
            return f;
        }
        for k in 0..4 {
            if bary[k] != 0.0 {
                f[k] = e[k].max(1e-3 * top).powf(-alpha);
            }
        }
        f
    }

    fn probe_factors(&self, probes: &[u32; 4], bary: &[f32; 4]) -> [f32; 4] {
        let mut f = self.brightness_factors(probes, bary);
        if self.cloud.probe_weighting_enabled() {
            let s = self.cloud.probe_weights().unwrap();
            for k in 0..4 {
                if bary[k] != 0.0 {
                    f[k] *= s[probes[k] as usize];
                }
            }
        }
        f
    }

    fn weights_at(&self, p: Vec3, state: &mut WalkState) -> ([u32; 4], [f32; 4]) {
        let c = self.cloud;
        let maps = c.visibility_maps().filter(|_| c.visibility_enabled());
        let on = c.cell_visibility_enabled();
        let cells = c.cell_visibility_bits().filter(|_| on);
        let planes = c.cell_planes().filter(|_| on);
        let mesh = c.mesh();
        let (probes, bary, cv, used) = match mesh.locate(p, state) {
            Location::Inside { tet, weights } => {
                let probes = mesh.tets()[tet as usize];
                let cv = match planes.and_then(|pl| pl.plane(tet)) {
                    Some(plane) => {
                        let pos = mesh.positions();
                        CellPlanes::visibility(plane, p, &probes.map(|i| pos[i as usize]))
                    }
                    None => cells.map_or([1.0; 4], |c| c.tet(tet, &weights)),
                };
                (probes, weights, cv, 4)
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
        if maps.is_some() {
            for k in 0..4 {
                if bary[k] != 0.0 {
                    v[k] = self.chebyshev(probes[k] as usize, p);
                }
            }
        }
        let normalized = |w: [f32; 4]| {
            let sum: f32 = w.iter().sum();
            (sum.is_finite() && sum > 0.0).then(|| w.map(|x| x / sum))
        };
        let f = self.probe_factors(&probes, &bary);
        let bcv = core::array::from_fn(|k| bary[k] * cv[k] * v[k] * f[k]);
        let has_cells = cells.is_some() || planes.is_some();
        let mass: f32 = (0..used).map(|k| bary[k] * cv[k]).sum();
        let all_hidden = has_cells && mass == 0.0;
        let darkest = || {
            let lum = |k: usize| self.luminance[probes[k] as usize];
            let k = (0..used).min_by(|&a, &b| lum(a).total_cmp(&lum(b)).then(a.cmp(&b)))?;
            let mut w = [0.0; 4];
            w[k] = 1.0;
            Some(w)
        };
        let r = normalized(bcv);
        if has_cells && mass > 0.0 && mass < HIDDEN_MASS_FLOOR {
            if let (Some(r), Some(d)) = (r, darkest()) {
                let t = mass / HIDDEN_MASS_FLOOR;
                return (
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
        (probes, w)
    }

    /// The directional blend of bands ≤ 2: every probe's irradiance at the
    /// twelve directions, blended per direction, projected back to SH.
    fn directional_blend(&self, probes: &[u32; 4], weights: &[f32; 4], out: &mut [Vec3]) {
        let active = weights.map(|w| w > 0.0);
        let lum = probes.map(|i| &self.directional[i as usize]);
        let gamma = self.cloud.directional_brightness();
        let f = directional::factors(lum, *weights, gamma);
        let e: [[Vec3; DIRECTIONS]; 4] = core::array::from_fn(|k| {
            if active[k] {
                self.table
                    .irradiance(self.cloud.probe_sh(probes[k] as usize))
            } else {
                [Vec3::ZERO; DIRECTIONS]
            }
        });
        let blended: [Vec3; DIRECTIONS] = core::array::from_fn(|d| {
            let (mut sum, mut acc) = (0.0f32, Vec3::ZERO);
            for k in 0..4 {
                if active[k] {
                    let u = weights[k] * f[d][k];
                    sum += u;
                    acc += e[k][d] * u;
                }
            }
            if sum > 0.0 && sum.is_finite() {
                acc / sum
            } else {
                (0..4).fold(Vec3::ZERO, |a, k| a + e[k][d] * weights[k])
            }
        });
        self.table.project(&blended, out);
    }

    fn sh_at(&self, p: Vec3, state: &mut WalkState, out: &mut [Vec3]) {
        let n = self.cloud.coeffs_per_probe();
        let m = out.len().min(n);
        out.iter_mut().for_each(|c| *c = Vec3::ZERO);
        let (probes, weights) = self.weights_at(p, state);
        let first = if self.cloud.directional_brightness() > 0.0 {
            self.directional_blend(&probes, &weights, &mut out[..m]);
            m.min(directional::DIRECTIONAL_COEFFS)
        } else {
            0
        };
        for (&i, &w) in probes.iter().zip(&weights) {
            if w == 0.0 {
                continue;
            }
            let src = &self.cloud.probe_sh(i as usize)[first..m];
            for (o, c) in out[first..m].iter_mut().zip(src) {
                *o += *c * w;
            }
        }
    }
}

/// Random points of the lattice's box grown by 3 on every side (a fifth or
/// so outside the hull), some in coherent runs.
fn points(dims: [u32; 3], count: usize, rng: &mut Rng) -> Vec<Vec3> {
    let hi = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) - 1.0;
    let mut out = Vec::with_capacity(count);
    while out.len() < count {
        let start = (rng.vec3() * 0.5 + 0.5) * (hi + 6.0) - 3.0;
        let step = rng.vec3() * 0.05;
        for k in 0..8 {
            out.push(start + step * k as f32);
        }
    }
    out
}

/// `got` and `want` agree to `rel` of `scale`.
fn close(got: &[Vec3], want: &[Vec3], rel: f32, scale: f32) -> bool {
    got.iter()
        .zip(want)
        .all(|(g, w)| (*g - *w).abs().max_element() <= rel * scale.max(1e-20))
}

/// The size of the terms an SH blend of `probes` with `weights` sums: the
/// largest `|w_k|·|c_k|` and the result's own largest coefficient. `f32`
/// rounding is relative to them: where the directional blend damps a probe
/// a thousand times brighter than the result, both paths sum terms of that
/// probe's size and round at 10⁻⁷ of it.
fn scale(cloud: &ProbeCloud, probes: &[u32; 4], weights: &[f32; 4], want: &[Vec3]) -> f32 {
    let terms = (0..4)
        .map(|k| {
            let c = cloud.probe_sh(probes[k] as usize);
            weights[k].abs() * c.iter().map(|v| v.abs().max_element()).fold(0.0, f32::max)
        })
        .fold(0.0, f32::max);
    want.iter()
        .map(|c| c.abs().max_element())
        .fold(terms, f32::max)
}

/// Compares `cloud` with the reference at 200 points; returns how many of
/// them the directional factors changed (against the same cloud with
/// directional brightness off) by more than 10⁻³ of the SH's size.
fn check(cloud: &ProbeCloud, dims: [u32; 3], rng: &mut Rng, what: &str) -> usize {
    let mut flat = cloud.clone();
    flat.set_directional_brightness(0.0).unwrap();
    let mut changed = 0;
    let mut s3 = WalkState::new();
    let reference = Reference::new(cloud);
    let n = cloud.coeffs_per_probe();
    let (mut s1, mut s2) = (WalkState::new(), WalkState::new());
    let mut got = vec![Vec3::ZERO; n];
    let mut want = vec![Vec3::ZERO; n];
    for p in points(dims, 200, rng) {
        let (gp, gw) = cloud.weights_at(p, &mut s1);
        let (wp, ww) = reference.weights_at(p, &mut s2);
        assert_eq!(gp, wp, "{what}: probes at {p}");
        for k in 0..4 {
            assert!(
                (gw[k] - ww[k]).abs() <= 1e-5,
                "{what}: weights at {p}: {gw:?} vs {ww:?}"
            );
        }
        cloud.sh_at(p, &mut s1, &mut got);
        reference.sh_at(p, &mut s2, &mut want);
        assert!(
            close(&got, &want, 1e-5, scale(cloud, &wp, &ww, &want)),
            "{what}: SH at {p}:\n{got:?}\nvs\n{want:?}"
        );
        let mut plain = vec![Vec3::ZERO; n];
        flat.sh_at(p, &mut s3, &mut plain);
        if !close(&got, &plain, 1e-3, scale(cloud, &wp, &ww, &want)) {
            changed += 1;
        }
    }
    changed
}

#[test]
fn every_blend_matches_the_reference() {
    let mut rng = Rng(0xB1E4D);
    for case in 0..60 {
        let dims = [
            2 + rng.below(4) as u32,
            2 + rng.below(4) as u32,
            2 + rng.below(3) as u32,
        ];
        let order = [1, 2, 3, 3, 4][rng.below(5)];
        let blend = Blend::random(&mut rng);
        let cloud = random_cloud(dims, order, blend, &mut rng);
        let what = format!("case {case} {dims:?} order {order} {blend:?}");
        check(&cloud, dims, &mut rng, &what);
    }
}

#[test]
fn the_default_bake_blend_matches_the_reference_at_every_exponent() {
    let mut rng = Rng(0xDEFA);
    for alpha in [0.0, 0.5, 1.0, 2.5] {
        for gamma in [0.25, 0.5, 0.7, 1.0, 2.0] {
            let dims = [4, 4, 3];
            let cloud = random_cloud(dims, 3, Blend::all(alpha, gamma), &mut rng);
            let changed = check(&cloud, dims, &mut rng, &format!("α {alpha} γ {gamma}"));
            // The clouds' probes differ by up to four decades of brightness:
            // the directional factors act at a share of the points.
            assert!(changed >= 10, "α {alpha} γ {gamma}: {changed} of 200");
        }
    }
}
