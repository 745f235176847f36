//! What the volume builder captures from: the [`VolumeSource`] abstraction
//! (the path-traced capture of a scene plugs in here) and [`LightsDemo`], an
//! analytic source made of sphere lights and occluding slabs.

use crate::scene::Aabb;
use crate::sh::lights::sphere_light_sh_and_gradient;
use crate::sh::ShRgb;
use glam::Vec3;

/// One captured sample.
#[derive(Clone, Debug, PartialEq)]
pub struct Captured {
    /// Radiance SH at the point.
    pub sh: ShRgb,
    /// Validity in `[0, 1]` (fraction of rays that did not hit back faces;
    /// 1 = fully valid). Samples under the builder's threshold are dilated.
    pub validity: f32,
    /// The source captured at a point moved out of geometry (virtual
    /// offset) rather than at the requested point; the builder stores the
    /// sample at the requested point (grid/octree corner) and flags it
    /// `VALIDITY_VIRTUAL_OFFSET`.
    pub virtual_offset: bool,
    /// Monte Carlo standard error of each coefficient of `sh` (RGB, same
    /// layout), if the source knows it (`None`: exact, or unknown). The
    /// adaptive builder refines only where a prediction miss exceeds the
    /// tolerance by more than `noise_k` of these (combined).
    pub std_error: Option<Vec<Vec3>>,
}

/// A scene the volume builder can sample. Calls are batched so that an
/// implementation can capture in parallel; results must not depend on the
/// batch composition or thread count (determinism).
pub trait VolumeSource: Sync {
    /// SH order (bands) of [`Self::capture`]'s results.
    fn order(&self) -> usize;

    /// Radiance SH and validity at each point, in order.
    fn capture(&self, points: &[Vec3]) -> Vec<Captured>;

    /// Whether scene geometry intersects the box `[min, max]` (Greger et
    /// al.'s subdivision heuristic, after Tatarchuk 2005). Default: no geometry.
    fn contains_geometry(&self, _min: Vec3, _max: Vec3) -> bool {
        false
    }

    /// Whether an emitter (an emissive surface, or a positional light's
    /// sphere of its radius) overlaps the box `[min, max]`; such cells are
    /// refined further (see
    /// [`super::AdaptiveSettings::emitter_depth`]). Default: none.
    fn contains_emitter(&self, _min: Vec3, _max: Vec3) -> bool {
        false
    }

    /// Harmonic mean `N / Σ 1/dᵢ` of the ray distances to the scene from `p`
    /// (Tatarchuk 2005 after Pharr & Humphreys); `f32::INFINITY` where nothing is
    /// hit. Default: infinity.
    fn depth_harmonic_mean(&self, _p: Vec3) -> f32 {
        f32::INFINITY
    }

    /// Central-difference gradients at `points` (Tatarchuk 2005: "project 6
    /// additional irradiance functions" at `p ± step·eᵢ`), layout
    /// `[(p·3 + axis)·order² + c]` (per metre): `(c(p + h eᵢ) − c(p − h eᵢ)) / 2h`.
    /// The default captures the 6 points with [`Self::capture`]; a Monte
    /// Carlo source should override it to use the same random numbers for
    /// the 6 captures of one sample (common random numbers), or the noise
    /// divided by `2h` swamps the gradient.
    fn central_gradients(&self, points: &[Vec3], step: f32) -> Vec<Vec3> {
        let probe = central_points(points, step);
        let caps = self.capture(&probe);
        central_difference(&caps, self.order(), step)
    }

    /// Closed-form spatial gradients at `points`, layout
    /// `[(p·3 + axis)·order² + c]` (per metre), if the source knows them.
    fn analytic_gradients(&self, _points: &[Vec3]) -> Option<Vec<Vec3>> {
        None
    }
}

/// The 6 points `p + h e₀, p − h e₀, p + h e₁, …` per point, in that order.
pub(crate) fn central_points(points: &[Vec3], step: f32) -> Vec<Vec3> {
    let mut probe = Vec::with_capacity(points.len() * 6);
    for p in points {
        for a in 0..3 {
            let mut e = Vec3::ZERO;
            e[a] = step;
            probe.push(*p + e);
            probe.push(*p - e);
        }
    }
    probe
}

/// Central differences from captures laid out as [`central_points`].
pub(crate) fn central_difference(caps: &[Captured], order: usize, step: f32) -> Vec<Vec3> {
    let n = order * order;
    let count = caps.len() / 6;
    let mut g = vec![Vec3::ZERO; count * 3 * n];
    for s in 0..count {
        for a in 0..3 {
            let (plus, minus) = (&caps[s * 6 + 2 * a], &caps[s * 6 + 2 * a + 1]);
            let (pc, mc) = (plus.sh.coeffs(), minus.sh.coeffs());
            if pc.len() != n || mc.len() != n {
                // Wrong order: leave NaN so the builder reports SourceOrder.
                g[(s * 3 + a) * n..(s * 3 + a + 1) * n].fill(Vec3::NAN);
                continue;
            }
            for k in 0..n {
                g[(s * 3 + a) * n + k] = (pc[k] - mc[k]) / (2.0 * step);
            }
        }
    }
    g
}

/// A sphere light (uniform emitter).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereLight {
    /// Centre (metres).
    pub center: Vec3,
    /// Radius (metres).
    pub radius: f32,
    /// Emitted radiance (linear RGB).
    pub radiance: Vec3,
}

/// An opaque axis-aligned slab `[lo, hi]` along `axis` (0 = x, 1 = y, 2 = z),
/// infinite in the two other axes: it blocks every light on its other side
/// (a coarse occluder, tests only: partially hidden lights are not clipped)
/// and points inside it capture as invalid (black, validity 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slab {
    /// Axis normal to the slab.
    pub axis: usize,
    /// Lower face coordinate.
    pub lo: f32,
    /// Upper face coordinate.
    pub hi: f32,
}

/// Analytic source: sphere lights (closed-form SH and SH gradients,
/// `probekit_sh::lights::sphere_light_sh_and_gradient`) behind optional
/// slabs that cut the light field with a discontinuity. `builtin:lights-demo`
/// of the CLI until scenes land.
#[derive(Clone, Debug, PartialEq)]
pub struct LightsDemo {
    /// SH order of captures.
    pub order: usize,
    /// The lights.
    pub lights: Vec<SphereLight>,
    /// The occluders.
    pub slabs: Vec<Slab>,
}

impl LightsDemo {
    /// The demo scene of `builtin:lights-demo`: a 4 m room-sized box
    /// `[-2, 2]³` lit by a warm and a cool sphere light, with a slab at
    /// `x ∈ [0.9, 1.1]` shadowing the warm light from the `x > 1.1` side.
    pub fn demo(order: usize) -> Self {
        Self {
            order,
            lights: vec![
                SphereLight {
                    center: Vec3::new(-1.0, 1.2, 0.3),
                    radius: 0.25,
                    radiance: Vec3::new(8.0, 6.0, 3.5),
                },
                SphereLight {
                    center: Vec3::new(1.5, -0.5, -1.0),
                    radius: 0.3,
                    radiance: Vec3::new(1.0, 2.0, 4.0),
                },
            ],
            slabs: vec![Slab {
                axis: 0,
                lo: 0.9,
                hi: 1.1,
            }],
        }
    }

    /// The demo's bounding box.
    pub fn demo_box() -> (Vec3, Vec3) {
        (Vec3::splat(-2.0), Vec3::splat(2.0))
    }

    fn inside_slab(&self, p: Vec3) -> bool {
        self.slabs
            .iter()
            .any(|s| p[s.axis] > s.lo && p[s.axis] < s.hi)
    }

    fn visible(&self, p: Vec3, l: &SphereLight) -> bool {
        self.slabs.iter().all(|s| {
            let (a, b) = (p[s.axis], l.center[s.axis]);
            !((a <= s.lo && b >= s.hi) || (a >= s.hi && b <= s.lo))
        })
    }

    /// Value (and gradient, layout `[axis·n + c]`) at one point.
    fn eval(&self, p: Vec3, value: &mut [Vec3], grad: Option<&mut [Vec3]>) {
        let n = self.order * self.order;
        value.fill(Vec3::ZERO);
        let mut gacc = vec![Vec3::ZERO; 3 * n];
        if !self.inside_slab(p) {
            let mut v = vec![Vec3::ZERO; n];
            let mut g = vec![[Vec3::ZERO; 3]; n];
            for l in self.lights.iter().filter(|l| self.visible(p, l)) {
                sphere_light_sh_and_gradient(
                    self.order, p, l.center, l.radius, l.radiance, &mut v, &mut g,
                );
                for c in 0..n {
                    value[c] += v[c];
                    for a in 0..3 {
                        gacc[a * n + c] += g[c][a];
                    }
                }
            }
        }
        if let Some(out) = grad {
            out.copy_from_slice(&gacc);
        }
    }
}

impl VolumeSource for LightsDemo {
    fn order(&self) -> usize {
        self.order
    }

    fn capture(&self, points: &[Vec3]) -> Vec<Captured> {
        let n = self.order * self.order;
        points
            .iter()
            .map(|&p| {
                let mut v = vec![Vec3::ZERO; n];
                self.eval(p, &mut v, None);
                Captured {
                    sh: ShRgb::from_coeffs(v).expect("square length"),
                    validity: if self.inside_slab(p) { 0.0 } else { 1.0 },
                    virtual_offset: false,
                    std_error: None,
                }
            })
            .collect()
    }

    /// A light's ball (its radius around its centre) overlaps the box.
    fn contains_emitter(&self, min: Vec3, max: Vec3) -> bool {
        let cell = Aabb { min, max };
        self.lights.iter().any(|l| {
            let r = Vec3::splat(l.radius);
            Aabb {
                min: l.center - r,
                max: l.center + r,
            }
            .overlaps(&cell)
        })
    }

    fn contains_geometry(&self, min: Vec3, max: Vec3) -> bool {
        self.slabs
            .iter()
            .any(|s| min[s.axis] < s.hi && max[s.axis] > s.lo)
    }

    /// Closed form for infinite slabs: rays towards a plane at distance `d`
    /// travel `d / cos θ`, so `Σ 1/dᵢ / N → (1/4π)∫_hemisphere cos θ / d dω =
    /// 1/(4d)` per plane; rays away from every plane escape (`1/d = 0`).
    fn depth_harmonic_mean(&self, p: Vec3) -> f32 {
        let mut inv = 0.0f32;
        if self.inside_slab(p) {
            return 0.0;
        }
        for s in &self.slabs {
            let d = if p[s.axis] <= s.lo {
                s.lo - p[s.axis]
            } else {
                p[s.axis] - s.hi
            };
            inv += 1.0 / (4.0 * d.max(1e-6));
        }
        if inv > 0.0 {
            1.0 / inv
        } else {
            f32::INFINITY
        }
    }

    fn analytic_gradients(&self, points: &[Vec3]) -> Option<Vec<Vec3>> {
        let n = self.order * self.order;
        let mut out = vec![Vec3::ZERO; points.len() * 3 * n];
        let mut v = vec![Vec3::ZERO; n];
        for (p, g) in points.iter().zip(out.chunks_exact_mut(3 * n)) {
            self.eval(*p, &mut v, Some(g));
        }
        Some(out)
    }
}
