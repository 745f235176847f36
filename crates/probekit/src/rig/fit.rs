//! Least-squares fitting of a rig to a mesh (Yuan et al. 2011 §2.2).
//!
//! The design matrix `M` (samples × parameters) has `M[j][k]` = weight of
//! model function `k` at sample `j`, from
//! [`probekit_runtime::rig::rig_weights`] (the runtime's own evaluation, so
//! fitting and evaluation agree). The fitting matrix is the Moore–Penrose
//! pseudo-inverse `L = M⁺`, equal to `(MᵀM)⁻¹Mᵀ` when `M` has full column
//! rank, computed in f64 by SVD (nalgebra). **Rank deficiency**: singular
//! values below [`PINV_RCOND`]` · σ_max` are treated as zero, giving the
//! minimum-norm least-squares solution (a lattice node no sample touches
//! gets parameter 0; it then has no weight at any sample either).

use super::{mesh::Mesh, sample, RigSetupError, RigSpec};
use glam::Vec3;
use nalgebra::DMatrix;
use probekit_runtime::format::{ProbeFile, Rig, RigFile, RigModel};
use probekit_runtime::rig::{rig_weights, RigState, MAX_WEIGHTS};

/// Relative singular-value cut-off of the pseudo-inverse. 1e-9 sits far
/// above f64 round-off (`max(N, K)·ε ≈ 1e-13`), so numerically dependent
/// columns are dropped, and far below the smallest singular value of any
/// well-posed rig on a real mesh (≳ 1e-3 · σ_max), so those are kept exact.
pub const PINV_RCOND: f64 = 1e-9;

/// The least-squares design matrix (samples × parameters) for `model` on
/// box `[lo, hi]`, in f64.
pub fn design_matrix(model: RigModel, lo: Vec3, hi: Vec3, samples: &[Vec3]) -> DMatrix<f64> {
    let k = model.parameter_count().unwrap_or(0) as usize;
    let mut m = DMatrix::zeros(samples.len(), k);
    let mut w = [(0u32, 0.0f32); MAX_WEIGHTS];
    for (j, p) in samples.iter().enumerate() {
        let n = rig_weights(model, lo, hi, *p, &mut w);
        for &(i, v) in &w[..n] {
            m[(j, i as usize)] += v as f64;
        }
    }
    m
}

/// The pseudo-inverse `M⁺` by SVD with the [`PINV_RCOND`] cut-off, and the
/// numerical rank.
pub fn pseudo_inverse(m: &DMatrix<f64>) -> (DMatrix<f64>, usize) {
    let svd = m.clone().svd(true, true);
    let smax = svd.singular_values.iter().cloned().fold(0.0, f64::max);
    let tol = PINV_RCOND * smax;
    let rank = svd.singular_values.iter().filter(|&&s| s > tol).count();
    let (u, vt) = (svd.u.expect("u requested"), svd.v_t.expect("vᵀ requested"));
    let mut pinv = DMatrix::zeros(m.ncols(), m.nrows());
    for (i, &s) in svd.singular_values.iter().enumerate() {
        if s > tol {
            // pinv += v_i · u_iᵀ / s_i
            pinv += (vt.row(i).transpose() * u.column(i).transpose()) / s;
        }
    }
    (pinv, rank)
}

/// A rig fitted to one mesh: the `.probes` record plus the sample normals
/// and the numerical rank of the fit.
#[derive(Clone, Debug)]
pub struct FittedRig {
    /// What the file stores (model, order, box, sample points, fitting
    /// matrix, transition table).
    pub rig: Rig,
    /// The spec it was built from.
    pub spec: RigSpec,
    /// Unit surface normal at each sample point.
    pub sample_normals: Vec<Vec3>,
    /// Numerical rank of the design matrix (≤ parameters).
    pub rank: usize,
}

impl FittedRig {
    /// Distributes `samples` points on `mesh` (seeded), builds the design
    /// matrix for `spec` and precomputes `L` once. The transition table is
    /// left empty ([`super::split::transition_table`] fills it).
    pub fn fit(
        mesh: &Mesh,
        spec: RigSpec,
        order: usize,
        samples: usize,
        seed: u64,
        name: &str,
    ) -> Result<Self, RigSetupError> {
        mesh.validate()?;
        if !(1..=probekit_sh::MAX_ORDER).contains(&order) {
            return Err(RigSetupError::Order(order));
        }
        if samples == 0 || samples > super::MAX_SAMPLES {
            return Err(RigSetupError::Samples);
        }
        if spec.parameter_count() > super::MAX_PARAMETERS {
            return Err(RigSetupError::TooManyParameters(spec.parameter_count()));
        }
        let pts = sample::distribute_samples(mesh, samples, seed);
        let (lo, hi) = mesh.bbox();
        let positions: Vec<Vec3> = pts.iter().map(|s| s.position).collect();
        let (_, radius) = mesh.bounding_sphere();
        let mut fitted = Self::fit_points(
            spec,
            order,
            lo,
            hi,
            positions,
            pts.iter().map(|s| s.normal).collect(),
            name,
        );
        fitted.rig.bounding_radius = radius;
        Ok(fitted)
    }

    /// Fits `spec` to given sample points (box `[lo, hi]`).
    pub fn fit_points(
        spec: RigSpec,
        order: usize,
        lo: Vec3,
        hi: Vec3,
        positions: Vec<Vec3>,
        normals: Vec<Vec3>,
        name: &str,
    ) -> Self {
        let model = spec.model();
        let m = design_matrix(model, lo, hi, &positions);
        let (pinv, rank) = pseudo_inverse(&m);
        // Row-major parameters × samples.
        let mut fitting = Vec::with_capacity(pinv.nrows() * pinv.ncols());
        for k in 0..pinv.nrows() {
            for j in 0..pinv.ncols() {
                fitting.push(pinv[(k, j)] as f32);
            }
        }
        Self {
            rig: Rig {
                name: name.to_string(),
                model,
                order: order as u32,
                bbox_min: lo,
                bbox_max: hi,
                // The sphere `split` measures light distances from; the
                // mesh's own where `fit` knows the mesh (else unknown).
                bounding_radius: 0.0,
                samples: positions,
                fitting,
                transitions: Vec::new(),
            },
            spec,
            sample_normals: normals,
            rank,
        }
    }

    /// A runtime state for this rig (the same code an engine runs).
    pub fn state(&self) -> RigState {
        RigState::new(&self.rig).expect("a fitted rig is always well formed")
    }
}

/// A rig-only `.probes` file holding `rigs` (no probes), ready for
/// [`ProbeFile::to_bytes`].
pub fn rig_file(rigs: &[FittedRig]) -> ProbeFile {
    ProbeFile::Rigs(RigFile {
        rigs: rigs.iter().map(|r| r.rig.clone()).collect(),
        metadata: String::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::mesh;
    use crate::sampling::SampleRng;

    /// A uniform draw in `[-0.5, 0.5)` from the baking library's generator.
    fn centred(rng: &mut SampleRng) -> f32 {
        rng.next_f32() - 0.5
    }

    /// A lighting field that lies exactly in the model space is recovered
    /// exactly by the fit (through the runtime's update and evaluation), at
    /// the samples and at every mesh vertex.
    #[test]
    fn in_model_field_is_recovered() {
        let car = mesh::car();
        for spec in ["gradient", "lattice:3x2x2", "mixed:l3,g,c", "mixed:l2,g,g"] {
            let spec: RigSpec = spec.parse().unwrap();
            let f = FittedRig::fit(&car, spec, 3, 96, 1, "car").unwrap();
            let k = f.rig.model.parameter_count().unwrap() as usize;
            let mut rng = SampleRng::from_state(42);
            let truth: Vec<Vec3> = (0..k * 9)
                .map(|_| Vec3::new(centred(&mut rng), centred(&mut rng), centred(&mut rng)))
                .collect();
            // Build the sample SH by evaluating the true model independently
            // (a state whose parameters are the truth).
            let eval = |p: Vec3| {
                let m = design_matrix(f.rig.model, f.rig.bbox_min, f.rig.bbox_max, &[p]);
                (0..9)
                    .map(|c| {
                        (0..k).fold(Vec3::ZERO, |s, i| s + truth[i * 9 + c] * m[(0, i)] as f32)
                    })
                    .collect::<Vec<_>>()
            };
            let samples: Vec<Vec3> = f.rig.samples.iter().flat_map(|&p| eval(p)).collect();
            let mut st = f.state();
            st.update(&samples).unwrap();
            assert_eq!(f.rank, k, "{spec:?}");
            for (a, b) in st.parameters().iter().zip(&truth) {
                assert!((*a - *b).abs().max_element() < 2e-4, "{spec:?}: {a} vs {b}");
            }
            let mut out = [Vec3::ZERO; 9];
            for &p in car.positions.iter().step_by(37) {
                st.sh_at(p, &mut out);
                for (a, b) in out.iter().zip(eval(p)) {
                    assert!((*a - b).abs().max_element() < 2e-4);
                }
            }
        }
    }

    /// Least-squares optimality: for random data the SVD fit equals the
    /// solution of the normal equations `MᵀM c = Mᵀy` solved directly in f64
    /// (Cholesky), and its residual is orthogonal to the columns of `M`.
    #[test]
    fn fit_equals_normal_equations() {
        let car = mesh::car();
        let spec: RigSpec = "mixed:l3,g,g".parse().unwrap();
        let f = FittedRig::fit(&car, spec, 1, 200, 3, "car").unwrap();
        let m = design_matrix(f.rig.model, f.rig.bbox_min, f.rig.bbox_max, &f.rig.samples);
        let mut rng = SampleRng::from_state(9);
        let y = nalgebra::DVector::from_fn(m.nrows(), |_, _| centred(&mut rng) as f64);
        let mtm = m.transpose() * &m;
        let direct = mtm.cholesky().unwrap().solve(&(m.transpose() * &y));
        let (pinv, _) = pseudo_inverse(&m);
        let svd = &pinv * &y;
        assert!((&svd - &direct).amax() < 1e-9 * (1.0 + direct.amax()));
        let resid = &y - &m * &svd;
        assert!((m.transpose() * resid).amax() < 1e-9);
        // The f32 fitting matrix stored in the rig agrees.
        for kk in 0..m.ncols() {
            let row = &f.rig.fitting[kk * m.nrows()..(kk + 1) * m.nrows()];
            let c: f64 = row.iter().zip(y.iter()).map(|(a, b)| *a as f64 * b).sum();
            assert!((c - direct[kk]).abs() < 1e-4 * (1.0 + direct.amax()));
        }
    }

    #[test]
    fn oversized_requests_are_typed_errors() {
        let car = mesh::car();
        let big: RigSpec = "lattice:64x64x1".parse().unwrap();
        assert_eq!(
            FittedRig::fit(&car, big, 3, 16, 1, "c").unwrap_err(),
            RigSetupError::TooManyParameters(4096)
        );
        let g: RigSpec = "gradient".parse().unwrap();
        assert_eq!(
            FittedRig::fit(&car, g, 3, 0, 1, "c").unwrap_err(),
            RigSetupError::Samples
        );
        assert_eq!(
            FittedRig::fit(&car, g, 3, 100_000, 1, "c").unwrap_err(),
            RigSetupError::Samples
        );
        assert_eq!(
            FittedRig::fit(&car, g, 9, 16, 1, "c").unwrap_err(),
            RigSetupError::Order(9)
        );
    }

    /// Rigs travel through a `.probes` file unchanged: write, read back, and
    /// the runtime state built from the file gives bit-identical irradiance.
    #[test]
    fn rig_round_trips_through_probes_file() {
        let car = mesh::car();
        let mut a = FittedRig::fit(&car, "mixed:l3,g,c".parse().unwrap(), 3, 64, 2, "car").unwrap();
        a.rig.transitions = vec![
            probekit_runtime::format::Transition {
                distance: 1.5,
                error: 9.0,
            },
            probekit_runtime::format::Transition {
                distance: 3.0,
                error: 2.0,
            },
        ];
        let b = FittedRig::fit(&car, "gradient".parse().unwrap(), 3, 32, 2, "car").unwrap();
        let bytes = rig_file(&[a.clone(), b]).to_bytes().unwrap();
        let back = ProbeFile::from_bytes(&bytes).unwrap();
        assert_eq!(back.rigs().len(), 2);
        assert_eq!(back.rigs()[0], a.rig);
        let samples: Vec<Vec3> = (0..64 * 9)
            .map(|i| Vec3::splat((i % 13) as f32 * 0.1))
            .collect();
        let (mut s1, mut s2) = (a.state(), RigState::new(&back.rigs()[0]).unwrap());
        s1.update(&samples).unwrap();
        s2.update(&samples).unwrap();
        for p in car.positions.iter().step_by(50) {
            assert_eq!(s1.irradiance(*p, Vec3::Y), s2.irradiance(*p, Vec3::Y));
        }
    }

    /// Rank deficiency: samples on a flat plane y = 0 leave the y-gradient
    /// and the upper lattice layer unconstrained. The pseudo-inverse drops
    /// them (rank < parameters), still reproduces in-span data, and is the
    /// minimum-norm solution (unconstrained parameters are zero).
    #[test]
    fn rank_deficient_fit_is_minimum_norm() {
        let pts: Vec<Vec3> = (0..64)
            .map(|i| Vec3::new((i % 8) as f32 / 7.0, 0.0, (i / 8) as f32 / 7.0))
            .collect();
        let spec: RigSpec = "lattice:2x2x2".parse().unwrap();
        let f = FittedRig::fit_points(
            spec,
            1,
            Vec3::ZERO,
            Vec3::ONE,
            pts.clone(),
            vec![Vec3::Y; 64],
            "plane",
        );
        assert_eq!(f.rank, 4);
        // Data = 1 + 2x − z (bilinear on the plane: in the span of the 4 lower nodes).
        let y: Vec<Vec3> = pts
            .iter()
            .map(|p| Vec3::splat(1.0 + 2.0 * p.x - p.z))
            .collect();
        let mut st = f.state();
        st.update(&y).unwrap();
        let par = st.parameters();
        // Lower nodes (j = 0) are indices i + 2·(0 + 2k); upper ones have j = 1.
        for k in 0..2 {
            for i in 0..2 {
                let want = 1.0 + 2.0 * i as f32 - k as f32;
                assert!((par[i + 4 * k].x - want).abs() < 1e-4);
                assert!(
                    par[i + 2 + 4 * k].x.abs() < 1e-5,
                    "unconstrained node not zero"
                );
            }
        }
        let g = FittedRig::fit_points(
            "gradient".parse().unwrap(),
            1,
            Vec3::ZERO,
            Vec3::ONE,
            pts,
            vec![Vec3::Y; 64],
            "p",
        );
        assert_eq!(g.rank, 3);
    }
}
