//! Irradiance rigs at run time (Yuan, Nowrouzezahrai & Sloan, *Irradiance
//! Rigs*, JGT 2011, §2): a rig holds a few SH vectors (its parameters) that
//! model how radiance SH varies over a rigid object. Every frame the engine
//! samples its lighting (probe cloud, volume, analytic lights) at the rig's
//! sample points, calls [`RigState::update`] (`parameters = L × samples`, the
//! fitting matrix `L` baked by `probekit::rig`), and evaluates irradiance per
//! vertex with [`RigState::irradiance`]. Neither allocates.
//!
//! ## The model `M(p, c)`
//!
//! Positions are in the mesh's own coordinates (the engine subtracts the
//! object's placement; rigs are for rigid objects). Each axis is normalised
//! to the mesh bounding box, `u = (p − min)/(max − min) ∈ [0, 1]` (an axis of
//! zero extent gives `u = ½`), and `t = 2u − 1 ∈ [−1, 1]`.
//!
//! | model | parameters | `SH(p)` |
//! |---|---|---|
//! | [`RigModel::Constant`] | 1 | `c₀` |
//! | [`RigModel::Gradient`] | 4 | `c₀ + t_x c₁ + t_y c₂ + t_z c₃` (SH + gradient, *Irradiance Rigs* §2.1) |
//! | [`RigModel::Tensor`] | `n_x·n_y·n_z` | `Σ_{ijk} f_i(x) g_j(y) h_k(z) c_{i + n_x (j + n_y k)}` |
//!
//! Per axis of a tensor rig: [`AxisModel::Constant`] is `{1}`,
//! [`AxisModel::Gradient`] is `{1, t}`, [`AxisModel::Lattice`]`(N)` is `N`
//! hat functions with nodes at `u_i = i/(N − 1)` (linear interpolation;
//! `u` is clamped to `[0, 1]`, so outside the box the lattice extends
//! constantly; `N = 1` is the constant). An all-lattice tensor rig is the
//! trilinear lattice of the paper; `[Lattice(3), Gradient, Constant]` is its
//! mixed car rig with 6 SH vectors. The gradient terms extrapolate linearly.
//!
//! The baker builds its least-squares design matrix from [`rig_weights`], so
//! fitting and evaluation cannot disagree.

mod lights;
mod split;

pub use lights::{Light, SphereTable, DISK_POLYGON_EDGES, SPHERE_TABLE_SIZE};
pub use split::{rig_weight, transition_distance, SplitRig, TRANSITION_BAND};

use crate::format::{AxisModel, Rig, RigModel};
use crate::math;
use crate::prelude::*;
use glam::Vec3;
use probekit_sh::{basis::num_coeffs, convolve, MAX_COEFFS, MAX_ORDER};

/// Most non-zero model functions at one point: two per axis (a hat pair or
/// `{1, t}`), so 2³ for a tensor rig; the gradient rig has 4.
pub const MAX_WEIGHTS: usize = 8;

/// A rig that cannot be used: what is wrong with it or with the input.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RigError {
    /// The rig's SH order is outside `1..=MAX_ORDER`.
    #[error("rig SH order {0} outside 1..=8")]
    Order(u32),
    /// The model has no parameters, or too many to count.
    #[error("rig model has an invalid parameter count")]
    ParameterCount,
    /// The fitting matrix is not `parameters × samples`.
    #[error("rig fitting matrix has {got} entries, expected {expected} (parameters × samples)")]
    FittingShape {
        /// `parameters × samples`.
        expected: usize,
        /// What the rig holds.
        got: usize,
    },
    /// [`RigState::update`] got a different number of sample coefficients.
    #[error("rig update got {got} SH coefficients, expected {expected} (samples × order²)")]
    SampleShape {
        /// `samples × order²`.
        expected: usize,
        /// What was passed.
        got: usize,
    },
    /// The bounding box is not finite or has `min > max`.
    #[error("rig bounding box is empty or not finite")]
    BoundingBox,
    /// [`SplitRig::update`] got an object transform that is not finite or
    /// not invertible.
    #[error("the object's transform is not finite or not invertible")]
    Transform,
}

/// Normalised box coordinate `u ∈ [0, 1]` of `x` on an axis `[lo, hi]`
/// (`½` when the axis has zero extent). Not clamped.
#[inline]
fn unit(x: f32, lo: f32, hi: f32) -> f32 {
    let e = hi - lo;
    if e > 0.0 {
        (x - lo) / e
    } else {
        0.5
    }
}

/// The non-zero functions of one axis model at normalised coordinate `u`:
/// writes `(index, value)` pairs and returns how many (1 or 2).
#[inline]
pub fn axis_weights(model: AxisModel, u: f32, out: &mut [(u32, f32); 2]) -> usize {
    match model {
        AxisModel::Constant => {
            out[0] = (0, 1.0);
            1
        }
        AxisModel::Gradient => {
            out[0] = (0, 1.0);
            out[1] = (1, 2.0 * u - 1.0);
            2
        }
        AxisModel::Lattice(n) if n <= 1 => {
            out[0] = (0, 1.0);
            1
        }
        AxisModel::Lattice(n) => {
            let s = if u.is_nan() { 0.0 } else { u.clamp(0.0, 1.0) } * (n - 1) as f32;
            let i = (math::floor(s) as u32).min(n - 2);
            let f = s - i as f32;
            out[0] = (i, 1.0 - f);
            out[1] = (i + 1, f);
            2
        }
    }
}

/// The non-zero model functions `(parameter index, weight)` of rig `model`
/// on box `[bbox_min, bbox_max]` at mesh-space point `p` (module docs);
/// returns how many entries of `out` were written (≤ [`MAX_WEIGHTS`]).
/// `SH(p) = Σ weight · c[index]`. Used both by the baker's fit and by
/// [`RigState::sh_at`].
pub fn rig_weights(
    model: RigModel,
    bbox_min: Vec3,
    bbox_max: Vec3,
    p: Vec3,
    out: &mut [(u32, f32); MAX_WEIGHTS],
) -> usize {
    let u = [
        unit(p.x, bbox_min.x, bbox_max.x),
        unit(p.y, bbox_min.y, bbox_max.y),
        unit(p.z, bbox_min.z, bbox_max.z),
    ];
    match model {
        RigModel::Constant => {
            out[0] = (0, 1.0);
            1
        }
        RigModel::Gradient => {
            out[0] = (0, 1.0);
            for a in 0..3 {
                out[a + 1] = (a as u32 + 1, 2.0 * u[a] - 1.0);
            }
            4
        }
        RigModel::Tensor(axes) => {
            let mut w = [[(0u32, 0.0f32); 2]; 3];
            let mut n = [0usize; 3];
            for a in 0..3 {
                n[a] = axis_weights(axes[a], u[a], &mut w[a]);
            }
            let (nx, ny) = (axes[0].count().max(1), axes[1].count().max(1));
            let mut m = 0;
            for wz in &w[2][..n[2]] {
                for wy in &w[1][..n[1]] {
                    for wx in &w[0][..n[0]] {
                        out[m] = (wx.0 + nx * (wy.0 + ny * wz.0), wx.1 * wy.1 * wz.1);
                        m += 1;
                    }
                }
            }
            m
        }
    }
}

/// A rig ready for per-frame use: its model, box, fitting matrix and the
/// current parameters (`parameters × order²` radiance SH, RGB).
#[derive(Clone, Debug)]
pub struct RigState {
    model: RigModel,
    order: usize,
    bbox_min: Vec3,
    bbox_max: Vec3,
    samples: usize,
    params_count: usize,
    fitting: Vec<f32>,
    params: Vec<Vec3>,
}

impl RigState {
    /// Prepares `rig` (from a `.probes` file or the baker) for updates; all
    /// buffers are allocated here, none later. Parameters start at zero.
    pub fn new(rig: &Rig) -> Result<Self, RigError> {
        if rig.order == 0 || rig.order as usize > MAX_ORDER {
            return Err(RigError::Order(rig.order));
        }
        let k = rig
            .model
            .parameter_count()
            .filter(|&k| k > 0)
            .ok_or(RigError::ParameterCount)? as usize;
        let ok = rig.bbox_min.is_finite()
            && rig.bbox_max.is_finite()
            && rig.bbox_min.cmple(rig.bbox_max).all();
        if !ok {
            return Err(RigError::BoundingBox);
        }
        let n = rig.samples.len();
        let expected = k.checked_mul(n).ok_or(RigError::ParameterCount)?;
        if rig.fitting.len() != expected {
            return Err(RigError::FittingShape {
                expected,
                got: rig.fitting.len(),
            });
        }
        let order = rig.order as usize;
        Ok(Self {
            model: rig.model,
            order,
            bbox_min: rig.bbox_min,
            bbox_max: rig.bbox_max,
            samples: n,
            params_count: k,
            fitting: rig.fitting.clone(),
            params: vec![Vec3::ZERO; k * num_coeffs(order)],
        })
    }

    /// SH order (bands) of the parameters and of the expected samples.
    pub fn order(&self) -> usize {
        self.order
    }

    /// Number of sample points the update expects.
    pub fn sample_count(&self) -> usize {
        self.samples
    }

    /// Number of SH vectors (rig parameters).
    pub fn parameter_count(&self) -> usize {
        self.params_count
    }

    /// The rig's model: which functions of the position weight the
    /// parameters ([`rig_weights`]).
    pub fn model(&self) -> RigModel {
        self.model
    }

    /// The box the model is normalised to, `(min, max)`: the mesh's
    /// bounding box in its own coordinates (m), as the file records it.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.bbox_min, self.bbox_max)
    }

    /// The current parameters: `parameter_count() × order²` radiance SH,
    /// parameter-major.
    pub fn parameters(&self) -> &[Vec3] {
        &self.params
    }

    /// Per-frame fit (*Irradiance Rigs* §2.2): `parameters = L × samples`, where
    /// `sample_sh` holds the radiance SH at every sample point, sample-major
    /// (`sample_sh[j·order² + c]`, same order as the rig's sample points),
    /// each coefficient and channel fitted independently. No allocation.
    pub fn update(&mut self, sample_sh: &[Vec3]) -> Result<(), RigError> {
        let n2 = num_coeffs(self.order);
        let expected = self.samples * n2;
        if sample_sh.len() != expected {
            return Err(RigError::SampleShape {
                expected,
                got: sample_sh.len(),
            });
        }
        for (row, out) in self
            .fitting
            .chunks_exact(self.samples.max(1))
            .zip(self.params.chunks_exact_mut(n2))
        {
            out.fill(Vec3::ZERO);
            for (&w, s) in row.iter().zip(sample_sh.chunks_exact(n2)) {
                for (o, c) in out.iter_mut().zip(s) {
                    *o += *c * w;
                }
            }
        }
        Ok(())
    }

    /// Radiance SH of the rig at mesh-space point `p`, written to
    /// `out[..order²]`. No allocation.
    ///
    /// # Panics
    /// If `out` is shorter than `order²`.
    pub fn sh_at(&self, p: Vec3, out: &mut [Vec3]) {
        let n2 = num_coeffs(self.order);
        let mut w = [(0u32, 0.0f32); MAX_WEIGHTS];
        let m = rig_weights(self.model, self.bbox_min, self.bbox_max, p, &mut w);
        out[..n2].fill(Vec3::ZERO);
        for &(k, wk) in &w[..m] {
            let c = &self.params[k as usize * n2..(k as usize + 1) * n2];
            for (o, ci) in out[..n2].iter_mut().zip(c) {
                *o += *ci * wk;
            }
        }
    }

    /// Irradiance `E(n)` (not divided by π; crate conventions) of the rig at
    /// mesh-space point `p` for unit normal `n`: [`Self::sh_at`] convolved
    /// with the clamped cosine. No allocation.
    pub fn irradiance(&self, p: Vec3, n: Vec3) -> Vec3 {
        let n2 = num_coeffs(self.order);
        let mut sh = [Vec3::ZERO; MAX_COEFFS];
        self.sh_at(p, &mut sh);
        if n2 == 9 {
            let c: &[Vec3; 9] = sh[..9].try_into().expect("9 coefficients");
            convolve::irradiance_l2(c, n)
        } else {
            convolve::irradiance(&sh[..n2], n)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rig(model: RigModel, samples: usize) -> Rig {
        let k = model.parameter_count().unwrap() as usize;
        Rig {
            name: "t".into(),
            model,
            order: 3,
            bbox_min: Vec3::new(-1.0, 0.0, -0.5),
            bbox_max: Vec3::new(3.0, 2.0, 0.5),
            bounding_radius: 0.0,
            samples: vec![Vec3::ZERO; samples],
            fitting: vec![0.0; k * samples],
            transitions: Vec::new(),
        }
    }

    /// Hat functions and gradients sum correctly: the weights of any lattice
    /// form a partition of unity, and a tensor of gradients reproduces the
    /// bilinear function it spans (independent closed forms).
    #[test]
    fn weights_partition_of_unity_and_tensor_products() {
        let lat = RigModel::Tensor([
            AxisModel::Lattice(4),
            AxisModel::Lattice(3),
            AxisModel::Lattice(2),
        ]);
        let (lo, hi) = (Vec3::new(-1.0, 0.0, -0.5), Vec3::new(3.0, 2.0, 0.5));
        let mut w = [(0, 0.0); MAX_WEIGHTS];
        for i in 0..50 {
            let p = lo + (hi - lo) * Vec3::new(i as f32 / 49.0, (i * 7 % 50) as f32 / 49.0, 0.3);
            let m = rig_weights(lat, lo, hi, p, &mut w);
            let s: f32 = w[..m].iter().map(|x| x.1).sum();
            assert!((s - 1.0).abs() < 1e-5);
            // Linear reproduction: Σ w·node_x = u_x · 3.
            let ux: f32 = w[..m].iter().map(|&(k, v)| v * (k % 4) as f32).sum();
            assert!((ux - (p.x + 1.0) / 4.0 * 3.0).abs() < 1e-4);
        }
        let gg = RigModel::Tensor([
            AxisModel::Gradient,
            AxisModel::Gradient,
            AxisModel::Constant,
        ]);
        let p = Vec3::new(2.0, 0.5, 0.1);
        let m = rig_weights(gg, lo, hi, p, &mut w);
        let (tx, ty) = (2.0 * 0.75 - 1.0, 2.0 * 0.25 - 1.0);
        let want = [1.0, tx, ty, tx * ty];
        let mut got = [0.0; 4];
        for &(k, v) in &w[..m] {
            got[k as usize] += v;
        }
        for (a, b) in got.iter().zip(want) {
            assert!((a - b).abs() < 1e-6, "{got:?} vs {want:?}");
        }
    }

    proptest::proptest! {
        /// Any tensor rig's weights are a partition of unity when every
        /// axis is a lattice or constant, and at most MAX_WEIGHTS are written.
        #[test]
        fn lattice_weights_sum_to_one(
            nx in 1u32..9, ny in 1u32..9, nz in 1u32..9,
            x in -2.0f32..4.0, y in -1.0f32..3.0, z in -1.0f32..1.0,
        ) {
            let m = RigModel::Tensor([
                AxisModel::Lattice(nx),
                AxisModel::Lattice(ny),
                AxisModel::Lattice(nz),
            ]);
            let mut w = [(0, 0.0); MAX_WEIGHTS];
            let n = rig_weights(m, Vec3::new(-1.0, 0.0, -0.5), Vec3::new(3.0, 2.0, 0.5), Vec3::new(x, y, z), &mut w);
            let s: f32 = w[..n].iter().map(|v| v.1).sum();
            proptest::prop_assert!((s - 1.0).abs() < 1e-5);
            proptest::prop_assert!(w[..n].iter().all(|v| v.0 < nx * ny * nz && v.1 >= 0.0));
        }
    }

    #[test]
    fn shape_errors_are_typed() {
        let mut r = rig(RigModel::Gradient, 3);
        r.fitting.pop();
        assert!(matches!(
            RigState::new(&r),
            Err(RigError::FittingShape { .. })
        ));
        let r = rig(RigModel::Gradient, 3);
        let mut s = RigState::new(&r).unwrap();
        assert!(matches!(
            s.update(&[Vec3::ZERO; 5]),
            Err(RigError::SampleShape { .. })
        ));
        let mut r = rig(RigModel::Constant, 1);
        r.order = 9;
        assert_eq!(RigState::new(&r).unwrap_err(), RigError::Order(9));
    }

    /// `update` is the matrix product `L × samples`, checked against a
    /// straightforward f64 triple loop.
    #[test]
    fn update_is_matrix_product() {
        let mut r = rig(
            RigModel::Tensor([
                AxisModel::Lattice(3),
                AxisModel::Gradient,
                AxisModel::Constant,
            ]),
            5,
        );
        for (i, f) in r.fitting.iter_mut().enumerate() {
            *f = ((i * 37 % 11) as f32 - 5.0) / 7.0;
        }
        let samples: Vec<Vec3> = (0..5 * 9)
            .map(|i| Vec3::new(i as f32, (i % 7) as f32, -(i as f32) * 0.5))
            .collect();
        let mut s = RigState::new(&r).unwrap();
        s.update(&samples).unwrap();
        for k in 0..6 {
            for c in 0..9 {
                let mut e = [0.0f64; 3];
                for j in 0..5 {
                    let w = r.fitting[k * 5 + j] as f64;
                    for ch in 0..3 {
                        e[ch] += w * samples[j * 9 + c][ch] as f64;
                    }
                }
                let got = s.parameters()[k * 9 + c];
                for ch in 0..3 {
                    assert!((got[ch] as f64 - e[ch]).abs() < 1e-4 * (1.0 + e[ch].abs()));
                }
            }
        }
    }
}
