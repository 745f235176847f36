//! Tests of ZH3 against independent quadrature and brute-force searches.

use super::*;
use crate::basis::{Y00, Y1};
use crate::convolve::{eval_sh, irradiance_l2};
use crate::numeric::fibonacci_sphere;
use proptest::prelude::*;

fn unit(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z).try_normalize().unwrap_or(Vec3::X)
}

/// L2 coefficients of a zonal signal about `axis` with per-channel zonal
/// coefficients `z[l]`, built by evaluating the zonal function itself on a
/// quadrature (not by `zh_to_sh`): project `Σ_l z_l Y_l0(axis·ω)`.
fn zonal_signal_by_quadrature(axis: Vec3, z: [Vec3; 3]) -> [Vec3; 9] {
    let dirs = fibonacci_sphere(20_000);
    let w = 4.0 * std::f64::consts::PI / dirs.len() as f64;
    let mut c = [glam::DVec3::ZERO; 9];
    for d in &dirs {
        let t = axis.as_dvec3().dot(*d);
        let y = [
            0.5 / std::f64::consts::PI.sqrt(),
            (3.0 / (4.0 * std::f64::consts::PI)).sqrt() * t,
            (5.0 / (16.0 * std::f64::consts::PI)).sqrt() * (3.0 * t * t - 1.0),
        ];
        let f = z[0].as_dvec3() * y[0] + z[1].as_dvec3() * y[1] + z[2].as_dvec3() * y[2];
        let b = eval_l2(d.as_vec3());
        for i in 0..9 {
            c[i] += f * (b[i] as f64) * w;
        }
    }
    c.map(|v| v.as_vec3())
}

#[test]
fn recovers_zonal_signal_built_by_quadrature() {
    let axis = unit(0.3, -0.8, 0.5);
    let z = [
        Vec3::new(2.0, 1.5, 1.0),
        Vec3::new(0.9, 0.6, -0.2),
        Vec3::new(0.4, -0.3, 0.25),
    ];
    let l2 = zonal_signal_by_quadrature(axis, z);
    for fit in [
        fit_zh3_shared(&l2),
        fit_zh3_per_channel(&l2),
        solve_zh3_axis(&l2, AxisWeights::Luminance),
        solve_zh3_axis(&l2, AxisWeights::Equal),
    ] {
        assert!(
            (fit.zonal - z[2]).length() < 2e-3,
            "{} vs {}",
            fit.zonal,
            z[2]
        );
        let back = fit.to_l2();
        for i in 0..9 {
            assert!((back[i] - l2[i]).length() < 2e-3, "coefficient {i}");
        }
    }
}

proptest! {
    /// ZH3 reproduces any zonal L2 signal exactly (random axis, random
    /// zonal coefficients; the luminance band-1 vector is kept away from 0
    /// so the axis is defined).
    #[test]
    fn reproduces_any_zonal_l2(
        ax in -1.0f32..1.0, ay in -1.0f32..1.0, az in -1.0f32..1.0,
        z0 in prop::array::uniform3(0.5f32..3.0),
        z1 in prop::array::uniform3(0.2f32..1.0),
        g1 in 1.0f32..2.0,
        s1 in prop::array::uniform3(prop::bool::ANY),
        z2 in prop::array::uniform3(-1.0f32..1.0),
    ) {
        let axis = unit(ax, ay, az);
        // Green dominates the luminance so its band-1 vector cannot cancel.
        let mut z1v = Vec3::from(z1);
        z1v.y = g1;
        for ch in [0, 2] { if s1[ch] { z1v[ch] = -z1v[ch]; } }
        let zh = [Vec3::from(z0), z1v, Vec3::from(z2)];
        let mut l2 = [Vec3::ZERO; 9];
        for ch in 0..3 {
            let mut c = [0.0f32; 9];
            zh_to_sh(&[zh[0][ch], zh[1][ch], zh[2][ch]], axis, &mut c);
            for i in 0..9 { l2[i][ch] = c[i]; }
        }
        for fit in [
            fit_zh3_shared(&l2),
            fit_zh3_per_channel(&l2),
            solve_zh3_axis(&l2, AxisWeights::Luminance),
            solve_zh3_axis(&l2, AxisWeights::Equal),
        ] {
            let back = fit.to_l2();
            for i in 0..9 {
                prop_assert!((back[i] - l2[i]).length() < 1e-4, "coefficient {} {} vs {}", i, back[i], l2[i]);
            }
        }
    }
}

/// Without a band-1 vector the L1-derived axes are undefined (they fall
/// back to +Y), but the solve still finds the zonal axis exactly.
#[test]
fn solve_recovers_zonal_signal_without_band1() {
    let axis = unit(0.6, -0.2, 0.77);
    let mut l2 = [Vec3::ZERO; 9];
    for (ch, z2) in [0.4f32, -0.3, 0.2].into_iter().enumerate() {
        let mut c = [0.0f32; 9];
        zh_to_sh(&[1.0, 0.0, z2], axis, &mut c);
        for i in 0..9 {
            l2[i][ch] = c[i];
        }
    }
    for w in [AxisWeights::Equal, AxisWeights::Luminance] {
        let back = solve_zh3_axis(&l2, w).to_l2();
        for i in 0..9 {
            assert!((back[i] - l2[i]).length() < 1e-5, "coefficient {i}");
        }
    }
    assert_eq!(fit_zh3_shared(&l2).axes[0], Vec3::Y);
}

/// ZH3 irradiance (fast path) against brute-force cosine integration of the
/// ZH3 radiance reconstructed from its expansion.
#[test]
fn irradiance_matches_brute_force() {
    let zh = Zh3 {
        l1: [
            Vec3::new(1.0, 1.2, 0.9),
            Vec3::new(0.2, -0.1, 0.3),
            Vec3::new(-0.3, 0.2, 0.1),
            Vec3::new(0.1, 0.1, -0.2),
        ],
        zonal: Vec3::new(0.3, -0.2, 0.5),
        axes: [
            unit(1.0, 0.2, 0.0),
            unit(0.0, 1.0, 0.3),
            unit(-0.4, 0.1, 1.0),
        ],
    };
    let l2 = zh.to_l2();
    let dirs = fibonacci_sphere(60_000);
    let w = 4.0 * std::f64::consts::PI / dirs.len() as f64;
    for n in fibonacci_sphere(9) {
        let mut e = glam::DVec3::ZERO;
        for d in &dirs {
            let c = n.dot(*d);
            if c > 0.0 {
                // radiance from the ZH3 definition, not from to_l2
                let mut l = glam::DVec3::ZERO;
                let b = eval_l2(d.as_vec3());
                for i in 0..4 {
                    l += zh.l1[i].as_dvec3() * b[i] as f64;
                }
                for ch in 0..3 {
                    l[ch] += (zh.zonal[ch] * y20(zh.axes[ch].dot(d.as_vec3()))) as f64;
                }
                e += l * c * w;
            }
        }
        let got = zh.irradiance(n.as_vec3()).as_dvec3();
        assert!((got - e).length() < 3e-3, "{got} vs {e}");
        let via_l2 = irradiance_l2(&l2, n.as_vec3()).as_dvec3();
        assert!((got - via_l2).length() < 1e-4);
        let rad = eval_sh(&l2, n.as_vec3());
        assert!(rad.is_finite());
    }
}

/// Hallucinated ZH3 against an independent evaluation: the paper's formula
/// written out by hand (luminance axis, ratio, curve fit) and expanded to
/// L2 via `zh_to_sh`, evaluated with the L2 fast path.
#[test]
fn hallucinated_matches_independent_evaluation() {
    let l1 = [
        Vec3::new(1.2, 1.0, 0.8),
        Vec3::new(-0.3, -0.2, -0.1),
        Vec3::new(0.4, 0.5, 0.2),
        Vec3::new(0.1, -0.2, 0.05),
    ];
    // By hand: luminance vector, axis, ratios.
    let lum = |c: Vec3| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    let lv = Vec3::new(-lum(l1[3]), -lum(l1[1]), lum(l1[2]));
    let axis = lv / lv.length();
    let mut l2 = [Vec3::ZERO; 9];
    l2[..4].copy_from_slice(&l1);
    for ch in 0..3 {
        let v = Vec3::new(-l1[3][ch], -l1[1][ch], l1[2][ch]);
        let r = (v.dot(axis)).abs() / l1[0][ch];
        let z = l1[0][ch] * (0.08 * r + 0.6 * r * r);
        let mut c = [0.0f32; 9];
        zh_to_sh(&[0.0, 0.0, z], axis, &mut c);
        for i in 4..9 {
            l2[i][ch] = c[i];
        }
    }
    for n in fibonacci_sphere(40) {
        let n = n.as_vec3();
        let a = zh3_hallucinated_irradiance(&l1, n);
        let b = irradiance_l2(&l2, n);
        assert!((a - b).length() < 1e-5, "{a} vs {b}");
        let c = zh3_hallucinate(&l1).irradiance(n);
        assert!((a - c).length() < 1e-5);
    }
}

#[test]
fn hallucinated_handles_degenerate_input() {
    let flat = [Vec3::splat(1.0 / Y00), Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
    let e = zh3_hallucinated_irradiance(&flat, Vec3::Z);
    assert!((e - Vec3::splat(std::f32::consts::PI)).length() < 1e-5);
    let neg = [Vec3::splat(-1.0), Vec3::splat(0.2), Vec3::ZERO, Vec3::ZERO];
    assert!(zh3_hallucinated_irradiance(&neg, Vec3::Y).is_finite());
    // A delta: ratio r = √3 along the axis.
    let d = unit(0.2, 0.7, -0.4);
    let delta = [
        Vec3::splat(Y00),
        Vec3::splat(-Y1 * d.y),
        Vec3::splat(Y1 * d.z),
        Vec3::splat(-Y1 * d.x),
    ];
    let z = zh3_hallucinate(&delta).zonal.x;
    let r = 3f32.sqrt();
    assert!((z - Y00 * (0.08 * r + 0.6 * r * r)).abs() < 1e-5);
}

/// The closed-form error equals brute-force quadrature of the squared
/// irradiance difference over the sphere.
#[test]
fn closed_form_error_matches_quadrature() {
    let l2 = random_l2(7);
    let zh = fit_zh3_shared(&l2);
    let w = Vec3::new(0.2126, 0.7152, 0.0722);
    let closed = weighted_irradiance_error(&zh.to_l2(), &l2, w);
    let closed2 = zh3_axis_error(&l2, zh.axes[0], AxisWeights::Luminance);
    let quad = quadrature_error(&zh, &l2, w);
    assert!(
        (closed - quad).abs() < 1e-3 * quad.max(1e-6),
        "{closed} vs {quad}"
    );
    assert!(
        (closed2 - quad).abs() < 1e-3 * quad.max(1e-6),
        "{closed2} vs {quad}"
    );
}

fn quadrature_error(zh: &Zh3, l2: &[Vec3; 9], w: Vec3) -> f64 {
    let dirs = fibonacci_sphere(20_000);
    let mut e = 0.0;
    for d in &dirs {
        let n = d.as_vec3();
        let diff = (zh.irradiance(n) - irradiance_l2(l2, n)).as_dvec3();
        e += (diff * diff).dot(w.as_dvec3());
    }
    e * 4.0 * std::f64::consts::PI / dirs.len() as f64
}

/// Deterministic pseudo-random L2 radiance of a non-negative-ish environment.
fn random_l2(seed: u64) -> [Vec3; 9] {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 33) as f64 / (1u64 << 31) as f64) as f32 * 2.0 - 1.0
    };
    let mut c = [Vec3::ZERO; 9];
    c[0] = Vec3::new(2.0 + next(), 2.0 + next(), 2.0 + next());
    for ci in c.iter_mut().skip(1) {
        *ci = Vec3::new(next(), next(), next()) * 0.8;
    }
    c
}

/// The solved axis is never worse than the shared luminance axis,
/// measured by brute-force quadrature with the same weights.
#[test]
fn solved_axis_not_worse_than_shared_by_quadrature() {
    let mut strictly_better = 0;
    for seed in 0..12 {
        let l2 = random_l2(seed);
        let shared = fit_zh3_shared(&l2);
        for w in [AxisWeights::Equal, AxisWeights::Luminance] {
            let solved = solve_zh3_axis(&l2, w);
            let es = quadrature_error(&shared, &l2, w.weights());
            let ev = quadrature_error(&solved, &l2, w.weights());
            assert!(
                ev <= es * (1.0 + 1e-3) + 1e-7,
                "seed {seed}: solved {ev} > shared {es}"
            );
            if ev < 0.9 * es {
                strictly_better += 1;
            }
            // The solved axis is a stationary point: nearby axes are not better.
            let a = solved.axes[0];
            let base = zh3_axis_error(&l2, a, w);
            for p in fibonacci_sphere(12) {
                let b = (a + p.as_vec3() * 0.02).normalize();
                assert!(zh3_axis_error(&l2, b, w) >= base - 1e-6 * (1.0 + base));
            }
        }
    }
    assert!(
        strictly_better > 0,
        "the solve never improved on the shared axis"
    );
}

/// The solved axis is the global optimum: no axis of a dense brute-force
/// search (20 000 Fibonacci axes) has a lower closed-form error.
#[test]
fn solved_axis_matches_brute_force_search() {
    let axes: Vec<Vec3> = fibonacci_sphere(20_000)
        .iter()
        .map(|d| d.as_vec3())
        .collect();
    for seed in 20..26 {
        let l2 = random_l2(seed);
        for w in [AxisWeights::Equal, AxisWeights::Luminance] {
            let solved = zh3_axis_error(&l2, solve_zh3_axis(&l2, w).axes[0], w);
            let brute = axes
                .iter()
                .map(|a| zh3_axis_error(&l2, *a, w))
                .fold(f64::INFINITY, f64::min);
            assert!(
                solved <= brute * (1.0 + 1e-4) + 1e-9,
                "seed {seed}: solved {solved} > brute force {brute}"
            );
        }
    }
}

/// The quadratic form used by the solver equals the band-2 function.
#[test]
fn band2_matrix_matches_basis() {
    let b = [0.3f32, -0.7, 0.5, 0.2, -0.4];
    let m = band2_matrix(&b.map(|x| x as f64));
    for d in fibonacci_sphere(30) {
        let direct: f32 = (0..5).map(|k| b[k] * eval_l2(d.as_vec3())[4 + k]).sum();
        let quad = d.dot(mat_vec(&m, d));
        assert!((direct as f64 - quad).abs() < 1e-5);
    }
}
