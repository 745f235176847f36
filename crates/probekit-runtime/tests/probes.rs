//! `Probes`, the one query shape for clouds, volumes and rigs-only files,
//! against computations written out here from the definitions:
//!
//! * the coefficients of every file are an affine function of position,
//!   which barycentric (cloud), trilinear, Taylor and tricubic (volume, with
//!   the exact gradients) interpolation all reproduce exactly, so the SH at
//!   a point must be the field there (outside a cloud's box hull: the field
//!   at the closest hull point, the clamped point);
//! * irradiance from the explicit real SH basis of bands 0–2 (Condon–Shortley
//!   phase, written out below) and the clamped-cosine factors `π, 2π/3, π/4`
//!   (Ramamoorthi & Hanrahan 2001), not divided by π;
//! * hallucinated ZH3 as Roughton et al. describe it (zonal axis the L1
//!   luminance direction, zonal coefficient `c₀(0.08 r + 0.6 r²)`), written
//!   out below, and cross-checked against a numerical integral.

// Coefficient loops index the result and the reference alike.
#![allow(clippy::needless_range_loop)]

mod common;

use common::{cm, p, pm, vm, Rng};
use glam::Vec3;
use probekit_runtime::cloud::{face_neighbors, lattice_tets, TetMesh};
use probekit_runtime::format::{
    Coefficients, Gradients, ProbeSet, Rig, RigFile, RigModel, TetSection, VolumeFile, VolumeGrid,
    VolumeStructure,
};
use probekit_runtime::{
    Interp, L1Mode, LoadError, LoadOptions, ObjectState, ProbeFile, ProbeFileKind, Probes,
    QueryError,
};
use std::f32::consts::PI;

/// The field's coefficient `k` at `p`: `a_k + b_k·p`, RGB differing.
fn field(p: Vec3, k: usize, order: u32) -> Vec3 {
    let kf = k as f32;
    // A DC large enough that every channel stays positive over [−1, 3]³.
    let a = if k == 0 {
        Vec3::new(3.0, 2.5, 2.0)
    } else {
        Vec3::new(0.3 - 0.05 * kf, 0.1 * (kf % 3.0) - 0.1, 0.2 / (1.0 + kf))
    };
    let scale = if order == 2 { 0.2 } else { 0.1 };
    let g = [
        Vec3::new(0.3, -0.2, 0.1),
        Vec3::new(-0.1, 0.25, 0.05),
        Vec3::new(0.05, 0.1, -0.3),
    ];
    let b = |ch: usize| Vec3::new(g[0][ch], g[1][ch], g[2][ch]) * scale * (1.0 + 0.3 * kf);
    a + Vec3::new(b(0).dot(p), b(1).dot(p), b(2).dot(p))
}

/// `∂ field_k / ∂ axis`.
fn field_gradient(axis: usize, k: usize, order: u32) -> Vec3 {
    let e = Vec3::AXES[axis];
    field(e, k, order) - field(Vec3::ZERO, k, order)
}

fn lattice() -> Vec<Vec3> {
    let mut p = Vec::new();
    for k in 0..3 {
        for j in 0..3 {
            for i in 0..3 {
                p.push(Vec3::new(i as f32, j as f32, k as f32));
            }
        }
    }
    p
}

fn coeffs(positions: &[Vec3], order: u32) -> Vec<Vec3> {
    let n = (order * order) as usize;
    positions
        .iter()
        .flat_map(|&p| (0..n).map(move |k| field(p, k, order)))
        .collect()
}

/// A rig on a unit box: gradient model, order 2, four samples.
fn rig() -> Rig {
    Rig {
        name: "box".into(),
        model: RigModel::Gradient,
        order: 2,
        bbox_min: Vec3::ZERO,
        bbox_max: Vec3::ONE,
        bounding_radius: 0.0,
        samples: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
        fitting: (0..16).map(|i| ((i * 5 % 7) as f32 - 3.0) / 7.0).collect(),
        transitions: Vec::new(),
    }
}

/// The 27-probe lattice over [0, 2]³ as a Kuhn-tetrahedralized cloud.
fn cloud_file(order: u32) -> ProbeFile {
    let pos = lattice();
    let tets = lattice_tets([3; 3]);
    let neighbours = face_neighbors(&tets).unwrap();
    let mesh = TetMesh::new(pos.clone(), tets.clone(), neighbours.clone()).unwrap();
    let barycentric = (0..tets.len() as u32)
        .map(|t| {
            let b = mesh.bary(t);
            b.rows.map(|r| [r.x, r.y, r.z, -r.dot(b.origin)])
        })
        .collect();
    let mut f = ProbeFile::cloud(pos.clone(), order, &coeffs(&pos, order)).unwrap();
    cm(&mut f).tetrahedra = Some(TetSection {
        vertices: tets,
        neighbours,
        barycentric,
    });
    *f.rigs_mut() = vec![rig()];
    f.validate().unwrap();
    f
}

/// The same lattice as a uniform-grid volume with the field's gradients.
fn volume_file(order: u32) -> ProbeFile {
    let pos = lattice();
    let n = (order * order) as usize;
    let c = Coefficients::from_f32(order, &coeffs(&pos, order)).unwrap();
    let mut f = VolumeFile::new(
        ProbeSet::new(pos.clone(), c),
        VolumeStructure::Uniform(VolumeGrid {
            min: Vec3::ZERO,
            max: Vec3::splat(2.0),
            resolution: [3, 3, 3],
        }),
    );
    f.gradients = Some(Gradients {
        order,
        data: (0..pos.len())
            .flat_map(|_| {
                (0..3).flat_map(move |a| (0..n).map(move |k| field_gradient(a, k, order)))
            })
            .collect(),
    });
    let f = ProbeFile::Volume(f);
    f.validate().unwrap();
    f
}

fn rigs_only_file() -> ProbeFile {
    ProbeFile::Rigs(RigFile {
        rigs: vec![rig()],
        metadata: String::new(),
    })
}

fn load(f: &ProbeFile, options: LoadOptions) -> Probes {
    Probes::from_bytes(&f.to_bytes().unwrap(), options).unwrap()
}

/// Real SH of bands 0–2 at unit `d`, index `l(l+1)+m`, Condon–Shortley
/// phase (Sloan, "Stupid SH tricks", appendix A2).
fn basis(d: Vec3) -> [f32; 9] {
    let c0 = 0.5 * (1.0 / PI).sqrt();
    let c1 = (3.0 / (4.0 * PI)).sqrt();
    let c2 = 0.5 * (15.0 / PI).sqrt();
    let c20 = 0.25 * (5.0 / PI).sqrt();
    let c22 = 0.25 * (15.0 / PI).sqrt();
    let (x, y, z) = (d.x, d.y, d.z);
    [
        c0,
        -c1 * y,
        c1 * z,
        -c1 * x,
        c2 * x * y,
        -c2 * y * z,
        c20 * (3.0 * z * z - 1.0),
        -c2 * x * z,
        c22 * (x * x - y * y),
    ]
}

/// `E(n) = Σ_lm Â_l c_lm Y_lm(n)`, `Â = π, 2π/3, π/4`.
fn irradiance_ref(sh: &[Vec3], n: Vec3) -> Vec3 {
    let y = basis(n);
    let a = [PI, 2.0 * PI / 3.0, PI / 4.0];
    sh.iter()
        .enumerate()
        .map(|(k, &c)| {
            c * y[k]
                * a[if k == 0 {
                    0
                } else if k < 4 {
                    1
                } else {
                    2
                }]
        })
        .sum()
}

/// Hallucinated ZH3 of L1 `l1` expanded to L2 (Roughton et al. 2024): the
/// axis the normalized band-1 vector of the luminance
/// (`0.2126 R + 0.7152 G + 0.0722 B`), in xyz `(−c₃, −c₁, c₂)`; per channel
/// `r = |v·axis| / c₀`, zonal `z = c₀(0.08 r + 0.6 r²)`, rotated to band 2
/// as `c₂ₘ = z·sqrt(4π/5)·Y₂ₘ(axis)`.
fn hallucinated_ref(l1: &[Vec3; 4]) -> [Vec3; 9] {
    let lum = Vec3::new(0.2126, 0.7152, 0.0722);
    let v = |ch: usize| Vec3::new(-l1[3][ch], -l1[1][ch], l1[2][ch]);
    let lv = v(0) * lum.x + v(1) * lum.y + v(2) * lum.z;
    let axis = lv.normalize();
    let y = basis(axis);
    let mut out = [Vec3::ZERO; 9];
    out[..4].copy_from_slice(l1);
    for ch in 0..3 {
        let c0 = l1[0][ch];
        let r = v(ch).dot(axis).abs() / c0;
        let z = c0 * (0.08 * r + 0.6 * r * r);
        for k in 4..9 {
            out[k][ch] = z * (4.0 * PI / 5.0).sqrt() * y[k];
        }
    }
    out
}

fn points(rng: &mut Rng, count: usize) -> Vec<(Vec3, Vec3)> {
    (0..count)
        .map(|_| {
            // [−0.5, 2.5]³: mostly inside, some outside the box.
            let p = (rng.vec3() * 1.5) + Vec3::ONE;
            let n = rng.vec3().normalize_or(Vec3::Y);
            (p, n)
        })
        .collect()
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol * b.abs().max_element().max(1.0)
}

#[test]
fn cloud_sh_and_irradiance_are_the_field_and_its_convolution() {
    for order in [2, 3] {
        let probes = load(&cloud_file(order), LoadOptions::default());
        assert_eq!(probes.kind(), ProbeFileKind::Cloud);
        assert_eq!(probes.probe_count(), 27);
        let mut state = ObjectState::new();
        let n = (order * order) as usize;
        for (p, normal) in points(&mut Rng(3), 200) {
            let q = p.clamp(Vec3::ZERO, Vec3::splat(2.0));
            let want: Vec<Vec3> = (0..n).map(|k| field(q, k, order)).collect();
            let sh = probes.sh_at(&mut state, p).unwrap();
            for k in 0..9 {
                let w = want.get(k).copied().unwrap_or(Vec3::ZERO);
                assert!(
                    close(Vec3::from(sh[k]), w, 1e-5),
                    "{p} k={k}: {:?} {w}",
                    sh[k]
                );
            }
            let e = probes.irradiance(&mut state, p, normal * 3.0).unwrap();
            let want_e = irradiance_ref(&want, normal);
            assert!(
                close(Vec3::from(e), want_e, 1e-5),
                "{p} {normal}: {e:?} {want_e}"
            );
        }
    }
}

#[test]
fn volume_every_interpolation_reproduces_the_field() {
    for interp in [Interp::Trilinear, Interp::Taylor, Interp::Tricubic] {
        let mut options = LoadOptions::default();
        options.interpolation = interp;
        let probes = load(&volume_file(3), options);
        assert_eq!(probes.interpolation(), Some(interp));
        let mut state = ObjectState::new();
        for (p, normal) in points(&mut Rng(5), 200) {
            let q = p.clamp(Vec3::ZERO, Vec3::splat(2.0));
            let want: Vec<Vec3> = (0..9).map(|k| field(q, k, 3)).collect();
            let sh = probes.sh_at(&mut state, p).unwrap();
            for k in 0..9 {
                assert!(
                    close(Vec3::from(sh[k]), want[k], 2e-5),
                    "{interp:?} {p} k={k}"
                );
            }
            let e = probes.irradiance(&mut state, p, normal).unwrap();
            assert!(
                close(Vec3::from(e), irradiance_ref(&want, normal), 2e-5),
                "{interp:?} {p}"
            );
        }
    }
}

#[test]
fn interpolation_needing_gradients_is_refused_at_load_without_them() {
    let mut f = volume_file(3);
    vm(&mut f).gradients = None;
    let mut options = LoadOptions::default();
    options.interpolation = Interp::Tricubic;
    let err = Probes::from_bytes(&f.to_bytes().unwrap(), options).unwrap_err();
    assert!(matches!(err, LoadError::Volume(_)), "{err}");
}

#[test]
fn l1_hallucinated_zh3_matches_the_written_out_formula() {
    for file in [cloud_file(2), volume_file(2)] {
        let mut options = LoadOptions::default();
        options.l1_mode = Some(L1Mode::Zh3Hallucinated);
        let zh3 = load(&file, options);
        assert_eq!(zh3.l1_mode(), L1Mode::Zh3Hallucinated);
        let linear = load(&file, LoadOptions::default());
        assert_eq!(linear.l1_mode(), L1Mode::Linear);
        let (mut s1, mut s2) = (ObjectState::new(), ObjectState::new());
        for (p, normal) in points(&mut Rng(9), 100) {
            let q = p.clamp(Vec3::ZERO, Vec3::splat(2.0));
            let l1: [Vec3; 4] = core::array::from_fn(|k| field(q, k, 2));
            let want = hallucinated_ref(&l1);
            let sh = zh3.sh_at(&mut s1, p).unwrap();
            for k in 0..9 {
                assert!(
                    close(Vec3::from(sh[k]), want[k], 2e-5),
                    "{p} k={k}: {:?} {}",
                    sh[k],
                    want[k]
                );
            }
            let e = Vec3::from(zh3.irradiance(&mut s1, p, normal).unwrap());
            assert!(close(e, irradiance_ref(&want, normal), 2e-5), "{p}");
            let e_lin = Vec3::from(linear.irradiance(&mut s2, p, normal).unwrap());
            assert!(close(e_lin, irradiance_ref(&l1, normal), 2e-5), "{p}");
        }
    }
}

/// The closed-form factors against a numerical integral of
/// `L(ω)·max(0, n·ω)` over a Fibonacci sphere, so that the reference above
/// does not only agree with itself.
#[test]
fn reference_irradiance_is_the_integral_of_the_clamped_cosine() {
    let l1: [Vec3; 4] = core::array::from_fn(|k| field(Vec3::new(0.4, 1.7, 0.9), k, 2));
    let sh = hallucinated_ref(&l1);
    let count = 200_000;
    let golden = PI * (3.0 - 5f32.sqrt());
    for normal in [Vec3::Y, Vec3::new(0.3, -0.5, 0.8).normalize()] {
        let mut sum = glam::DVec3::ZERO;
        for i in 0..count {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / count as f32;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f32;
            let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            let y = basis(d);
            let radiance: Vec3 = sh.iter().zip(y).map(|(&c, y)| c * y).sum();
            sum += (radiance * normal.dot(d).max(0.0)).as_dvec3();
        }
        let integral = (sum * (4.0 * std::f64::consts::PI / count as f64)).as_vec3();
        let closed = irradiance_ref(&sh, normal);
        assert!(close(integral, closed, 1e-3), "{integral} {closed}");
    }
}

#[test]
fn batches_equal_single_queries() {
    for file in [cloud_file(3), volume_file(3)] {
        let probes = load(&file, LoadOptions::default());
        let pts = points(&mut Rng(11), 50);
        let ps: Vec<Vec3> = pts.iter().map(|x| x.0).collect();
        let ns: Vec<Vec3> = pts.iter().map(|x| x.1).collect();
        let mut e = vec![[0.0; 3]; ps.len()];
        let mut sh = vec![[[0.0; 3]; 9]; ps.len()];
        let mut state = ObjectState::new();
        probes
            .irradiance_many(&mut state, &ps, &ns, &mut e)
            .unwrap();
        probes.sh_at_many(&mut state, &ps, &mut sh).unwrap();
        let mut cold = ObjectState::new();
        for i in 0..ps.len() {
            assert_eq!(e[i], probes.irradiance(&mut cold, ps[i], ns[i]).unwrap());
            assert_eq!(sh[i], probes.sh_at(&mut cold, ps[i]).unwrap());
        }
    }
}

#[test]
fn bad_queries_are_typed_errors() {
    let probes = load(&cloud_file(3), LoadOptions::default());
    let mut s = ObjectState::new();
    let p = Vec3::ONE;
    for bad in [Vec3::NAN, Vec3::new(0.0, f32::INFINITY, 0.0)] {
        assert_eq!(
            probes.sh_at(&mut s, bad),
            Err(QueryError::NonFinitePosition { index: 0 })
        );
        assert_eq!(
            probes.irradiance(&mut s, p, bad),
            Err(QueryError::NonFiniteNormal { index: 0 })
        );
    }
    assert_eq!(
        probes.irradiance(&mut s, p, Vec3::ZERO),
        Err(QueryError::ZeroNormal { index: 0 })
    );
    assert_eq!(
        probes.irradiance(&mut s, p, Vec3::splat(1e-30)),
        Err(QueryError::ZeroNormal { index: 0 })
    );
    // Huge but finite normals are fine.
    assert!(probes.irradiance(&mut s, p, Vec3::splat(3e38)).is_ok());
    // Batches: the index of the first bad query, and mismatched lengths.
    let ps = [p, p, Vec3::NAN];
    let ns = [Vec3::Y; 3];
    let mut out = [[0.0; 3]; 3];
    assert_eq!(
        probes.irradiance_many(&mut s, &ps, &ns, &mut out),
        Err(QueryError::NonFinitePosition { index: 2 })
    );
    assert!(matches!(
        probes.irradiance_many(&mut s, &ps, &ns[..2], &mut out),
        Err(QueryError::LengthMismatch { .. })
    ));
    let mut sh = [[[0.0; 3]; 9]; 2];
    assert!(matches!(
        probes.sh_at_many(&mut s, &ps, &mut sh),
        Err(QueryError::LengthMismatch { .. })
    ));
    // Rig indices.
    assert_eq!(probes.rig_count(), 1);
    assert_eq!(probes.rig_index("box"), Some(0));
    assert!(matches!(
        probes.rig(1),
        Err(QueryError::NoSuchRig { index: 1, count: 1 })
    ));
    assert!(probes.split_rig(0).is_ok());
    assert!(matches!(
        probes.split_rig(1),
        Err(QueryError::NoSuchRig { index: 1, count: 1 })
    ));
    assert!(matches!(
        probes.rig_irradiance(7, p, Vec3::Y),
        Err(QueryError::NoSuchRig { index: 7, count: 1 })
    ));
    assert_eq!(
        probes.rig_irradiance(0, p, Vec3::ZERO),
        Err(QueryError::ZeroNormal { index: 0 })
    );
}

#[test]
fn rigs_only_files_load_and_refuse_position_queries() {
    let probes = load(&rigs_only_file(), LoadOptions::default());
    assert_eq!(probes.kind(), ProbeFileKind::Rig);
    assert_eq!(probes.probe_count(), 0);
    let mut s = ObjectState::new();
    assert_eq!(probes.sh_at(&mut s, Vec3::ZERO), Err(QueryError::NoProbes));
    // The kind of file comes before the input's faults.
    assert_eq!(probes.sh_at(&mut s, Vec3::NAN), Err(QueryError::NoProbes));
    assert_eq!(probes.query(&mut s, Vec3::NAN), Err(QueryError::NoProbes));
    let mut out = [[[0.0; 3]; 9]; 1];
    assert_eq!(
        probes.sh_at_many(&mut s, &[Vec3::NAN], &mut out),
        Err(QueryError::NoProbes)
    );
    assert_eq!(
        probes.irradiance(&mut s, Vec3::ZERO, Vec3::Y),
        Err(QueryError::NoProbes)
    );
    assert_eq!(probes.rig_count(), 1);
    assert!(probes.rig_irradiance(0, Vec3::splat(0.5), Vec3::Y).is_ok());
}

/// The rig through `Probes` against its definition: after an update with
/// sample SH, irradiance is the convolution of the rig's own SH.
#[test]
fn rig_queries_follow_their_update() {
    let mut probes = load(&cloud_file(3), LoadOptions::default());
    let samples: Vec<Vec3> = (0..4)
        .flat_map(|s| (0..4).map(move |k| field(Vec3::splat(s as f32 * 0.3), k, 2)))
        .collect();
    probes.update_rig(0, &samples).unwrap();
    assert!(matches!(
        probes.update_rig(0, &samples[..3]),
        Err(QueryError::Rig(_))
    ));
    let rig = probes.rig(0).unwrap();
    for (p, n) in points(&mut Rng(13), 20) {
        let mut sh = [Vec3::ZERO; 4];
        rig.sh_at(p, &mut sh);
        let e = Vec3::from(probes.rig_irradiance(0, p, n).unwrap());
        assert!(close(e, irradiance_ref(&sh, n), 1e-5), "{p}");
    }
}

#[test]
fn truncated_and_bit_flipped_files_are_load_errors() {
    let bytes = cloud_file(3).to_bytes().unwrap();
    for len in [0, 4, 16, bytes.len() / 2, bytes.len() - 1] {
        assert!(matches!(
            Probes::from_bytes(&bytes[..len], LoadOptions::default()),
            Err(LoadError::Format(_))
        ));
    }
    let mut rng = Rng(17);
    for _ in 0..200 {
        let mut b = bytes.clone();
        let i = rng.below(b.len());
        b[i] ^= 1 << rng.below(8);
        // A flip anywhere is caught (checksums) or, in the header's free
        // bits, harmless: never a panic.
        let _ = Probes::from_bytes(&b, LoadOptions::default());
    }
}

#[test]
fn blend_overrides_take_effect_at_load() {
    let f = cloud_file(3);
    let mut options = LoadOptions::default();
    options.blend.directional_exponent = Some(9.0);
    assert!(matches!(
        Probes::from_bytes(&f.to_bytes().unwrap(), options),
        Err(LoadError::Cloud(_))
    ));
    let mut options = LoadOptions::default();
    options.blend.visibility_bias = Some(f32::NAN);
    assert!(matches!(
        Probes::from_bytes(&f.to_bytes().unwrap(), options),
        Err(LoadError::VisibilityBias(_))
    ));
}

/// A file built in memory goes through the reader's checks: an order the
/// runtime cannot query, or indices out of range, are load errors.
#[test]
fn files_built_in_memory_are_checked_at_load() {
    let mut f = cloud_file(3);
    let n = p(&f).positions.len();
    pm(&mut f).coefficients =
        Coefficients::from_f32(9, &vec![Vec3::ONE; n * 81]).unwrap_or(Coefficients {
            codec: probekit_runtime::format::Codec::F32,
            order: 9,
            data: vec![0; n * 81 * 12],
        });
    assert!(Probes::from_file(&f, LoadOptions::default()).is_err());
    let mut f = cloud_file(3);
    cm(&mut f).tetrahedra.as_mut().unwrap().vertices[0][0] = 1000;
    assert!(Probes::from_file(&f, LoadOptions::default()).is_err());
    assert!(Probes::from_file(&cloud_file(3), LoadOptions::default()).is_ok());
}

/// One `Probes` queried from several threads, each with its own state,
/// answers as a single thread does.
#[test]
fn one_probes_many_threads() {
    fn shared<T: Send + Sync>(_: &T) {}
    let probes = load(&cloud_file(3), LoadOptions::default());
    shared(&probes);
    shared(&ObjectState::new());
    let pts = points(&mut Rng(19), 100);
    let mut s = ObjectState::new();
    let want: Vec<[f32; 3]> = pts
        .iter()
        .map(|&(p, n)| probes.irradiance(&mut s, p, n).unwrap())
        .collect();
    std::thread::scope(|scope| {
        for t in 0..4 {
            let (probes, pts, want) = (&probes, &pts, &want);
            scope.spawn(move || {
                let mut s = ObjectState::new();
                for (i, &(p, n)) in pts.iter().enumerate().skip(t) {
                    assert_eq!(probes.irradiance(&mut s, p, n).unwrap(), want[i]);
                }
            });
        }
    });
}

/// `Probes::query`'s blend reproduces the point it was asked about: the
/// weighted sum of the blend's probe positions is the point (clamped to the
/// box outside it), as barycentric and trilinear weights must, and the
/// weights sum to 1.
#[test]
fn query_weights_reproduce_the_point() {
    let pos = lattice();
    for file in [cloud_file(3), volume_file(3)] {
        let probes = load(&file, LoadOptions::default());
        let mut s = ObjectState::new();
        for (p, _) in points(&mut Rng(23), 100) {
            let q = probes.query(&mut s, p).unwrap();
            let sum: f32 = q.weights.iter().sum();
            assert!((sum - 1.0).abs() < 1e-5, "{p}: {sum}");
            let at: Vec3 = q
                .probes
                .iter()
                .zip(q.weights)
                .filter(|(_, w)| *w != 0.0)
                .map(|(&i, w)| pos[i as usize] * w)
                .sum();
            let want = p.clamp(Vec3::ZERO, Vec3::splat(2.0));
            assert!(
                (at - want).abs().max_element() < 1e-4,
                "{p}: {at} {:?}",
                q.cell
            );
            assert_eq!(q.sh, probes.sh_at(&mut s, p).unwrap());
        }
    }
}

/// `cloud_file(3)` with every probe's distance moments saying a surface
/// 0.6 m away in every direction (one texel per probe, variance 0).
fn walled_cloud_file() -> ProbeFile {
    use probekit_runtime::format::DistanceMoments;
    let mut f = cloud_file(3);
    let (max, mu) = (4.0f32, 0.6f32);
    let h = |x: f32| half::f16::from_f32(x).to_bits();
    let data = (0..f.probe_count())
        .flat_map(|_| [h(mu / max), h(mu * mu / (max * max))])
        .collect();
    cm(&mut f).blend.distance_moments = Some(DistanceMoments {
        resolution: 1,
        max_distance: max,
        data,
    });
    f.validate().unwrap();
    f
}

/// The Chebyshev sharpness override: 0 switches the test off (the blend
/// is that of a load without distance moments), the default keeps it (a
/// point far from every probe's surfaces blends otherwise), and more than
/// 16 is refused.
#[test]
fn visibility_sharpness_override_takes_effect_at_load() {
    let f = walled_cloud_file();
    let with = |edit: &dyn Fn(&mut LoadOptions)| {
        let mut o = LoadOptions::default();
        edit(&mut o);
        load(&f, o)
    };
    let plain = with(&|o| o.blend.distance_moments = Some(false));
    let off = with(&|o| o.blend.visibility_sharpness = Some(0));
    let tested = with(&|_| {});
    let mut differs = 0;
    let mut rng = Rng(23);
    for (p, _) in points(&mut rng, 50) {
        let q = |probes: &Probes| probes.query(&mut ObjectState::new(), p).unwrap();
        assert_eq!(q(&off).weights, q(&plain).weights, "{p}");
        differs += usize::from(q(&tested).weights != q(&plain).weights);
    }
    assert!(differs > 10, "{differs}");
    let mut o = LoadOptions::default();
    o.blend.visibility_sharpness = Some(17);
    assert!(matches!(
        Probes::from_bytes(&f.to_bytes().unwrap(), o),
        Err(LoadError::VisibilitySharpness(17))
    ));
}

/// Relighting in place: the relit SH is the original blend's weights (the
/// baked light's, brightness weighting on) applied to `T + Σ (s_g − 1)·G_g`,
/// written out here; bad scales or a relighter of another file change
/// nothing.
#[test]
fn relight_keeps_the_blend_of_the_baked_light() {
    use probekit_runtime::format::{LightGroup, Relighter};
    let mut f = cloud_file(3);
    let total = coeffs(&p(&f).positions, 3);
    let a: Vec<Vec3> = (total.iter().enumerate())
        .map(|(i, c)| *c * (0.2 + 0.6 * ((i / 9) % 3) as f32 / 2.0))
        .collect();
    let b: Vec<Vec3> = total.iter().zip(&a).map(|(t, x)| *t - *x).collect();
    let total: Vec<Vec3> = a.iter().zip(&b).map(|(x, y)| *x + *y).collect();
    pm(&mut f).coefficients = Coefficients::from_f32(3, &total).unwrap();
    pm(&mut f).groups = [("a", &a), ("b", &b)]
        .map(|(name, c)| LightGroup {
            name: name.into(),
            coefficients: Coefficients::from_f32(3, c).unwrap(),
        })
        .to_vec();
    let mut options = LoadOptions::default();
    options.blend.brightness_exponent = Some(1.0);
    let baked = load(&f, options);
    let mut relit = baked.clone();
    let relighter = Relighter::new(&f).unwrap();
    let scales = [Vec3::new(3.0, 2.0, 0.5), Vec3::ONE];
    relit.relight(&relighter, &scales).unwrap();
    let mut rng = Rng(29);
    for (p, _) in points(&mut rng, 40) {
        let q = baked.query(&mut ObjectState::new(), p).unwrap();
        let mut want = [Vec3::ZERO; 9];
        for (&i, &w) in q.probes.iter().zip(&q.weights) {
            for k in 0..9 {
                let i = i as usize * 9 + k;
                want[k] += w * (total[i] + (scales[0] - Vec3::ONE) * a[i]);
            }
        }
        let got = relit.sh_at(&mut ObjectState::new(), p).unwrap();
        for k in 0..9 {
            assert!(close(Vec3::from_array(got[k]), want[k], 1e-5), "{p} {k}");
        }
    }
    // A cloud loaded from the relit coefficients blends by the relit
    // light instead: not the same (the check above can fail).
    let mut rebuilt = f.clone();
    pm(&mut rebuilt).coefficients = f.relit(&[("a", scales[0])]).unwrap();
    let rebuilt = load(&rebuilt, options);
    let sh = |probes: &Probes, p| probes.sh_at(&mut ObjectState::new(), p).unwrap();
    let moved = (points(&mut rng, 40).iter())
        .filter(|(p, _)| (sh(&rebuilt, *p)[0][0] - sh(&relit, *p)[0][0]).abs() > 1e-3)
        .count();
    assert!(moved > 5, "{moved}");
    // Nothing changes on an error.
    let before = relit.sh_at(&mut ObjectState::new(), Vec3::ONE).unwrap();
    assert!(relit.relight(&relighter, &scales[..1]).is_err());
    let other = Relighter::new(&common::groups_file()).unwrap();
    assert!(relit.relight(&other, &[Vec3::ONE; 2]).is_err());
    assert_eq!(
        relit.sh_at(&mut ObjectState::new(), Vec3::ONE).unwrap(),
        before
    );
}

/// Every stored band of an order-4 file is the field (interpolation of an
/// affine field is exact); the first nine are `sh_at`'s.
#[test]
fn all_bands_are_the_stored_order() {
    for f in [cloud_file(4), volume_file(4)] {
        let probes = load(&f, LoadOptions::default());
        let mut rng = Rng(31);
        for (p, _) in points(&mut rng, 20) {
            let p = p.clamp(Vec3::ZERO, Vec3::splat(2.0));
            let mut all = [Vec3::splat(9.0); 20];
            probes
                .sh_all_bands_at(&mut ObjectState::new(), p, &mut all)
                .unwrap();
            for k in 0..16 {
                assert!(close(all[k], field(p, k, 4), 1e-4), "{p} {k}");
            }
            assert_eq!(&all[16..], &[Vec3::ZERO; 4]);
            let l2 = probes.sh_at(&mut ObjectState::new(), p).unwrap();
            for k in 0..9 {
                assert_eq!(l2[k], all[k].to_array());
            }
        }
    }
}
