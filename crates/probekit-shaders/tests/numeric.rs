//! Runs the WGSL library (kernel `pk_check`, mode 0) through `wgpu` on a CPU
//! Vulkan adapter (Mesa lavapipe, installed by `.ci/run`) and compares every
//! result with the Rust evaluation of `probekit-sh` on random inputs. Prints
//! `SKIPPED: no wgpu adapter` and returns when no adapter exists.
//!
//! The volume sampler is checked against an independent fact rather than a
//! second implementation: trilinear interpolation reproduces an affine
//! function of position exactly, so probes holding `a + B·p` must sample to
//! `a + B·clamp(pos)`.

// Index loops over coefficients and channels read like the layout tables.
#![allow(clippy::needless_range_loop)]

use glam::Vec3;
use probekit_sh::ambient_cube::AmbientCube;
use probekit_sh::codec::{
    decode_ambient_cube, decode_l1, decode_l2, decode_zh3, encode_ambient_cube, encode_l1,
    encode_l2, encode_zh3,
};
use probekit_sh::convolve::{eval_sh, irradiance_l1, irradiance_l2};
use probekit_sh::geomerics::irradiance_geomerics_l1;
use probekit_sh::zh3::{zh3_hallucinate, zh3_hallucinated_irradiance, Zh3};
use probekit_shaders::{CHECK_IN_FLOATS, CHECK_OUT_FLOATS};

mod common;
use common::{adapter_or_skip, flat, Buffers, Gpu, Report, Rng, MODE_LIBRARY};

const CASES: usize = 256;

/// A uniform volume (`PkVolumeGrid`): box corners and probes per axis.
#[derive(Clone, Copy)]
struct Grid {
    min: Vec3,
    max: Vec3,
    resolution: [u32; 3],
}

/// An ordinary grid, and one with a single probe (and an empty extent) on x.
const GRIDS: [Grid; 2] = [
    Grid {
        min: Vec3::new(-1.0, 0.0, 2.0),
        max: Vec3::new(3.0, 2.5, 5.0),
        resolution: [3, 2, 4],
    },
    Grid {
        min: Vec3::new(0.5, -1.0, 0.0),
        max: Vec3::new(0.5, 2.0, 1.0),
        resolution: [1, 3, 2],
    },
];

/// Magnitude of case `case`'s SH: 1e-3 … 1e3, so that the RGB9E5 DC of the
/// codecs runs through many exponents.
fn sh_scale(case: usize) -> f32 {
    10f32.powi((case % 7) as i32 - 3)
}

/// Plausible radiance L2 SH of magnitude [`sh_scale`]: positive DC, other
/// coefficients a fraction of it; some cases exercise the edge branches (no
/// band 1, a negative DC channel).
fn random_sh(rng: &mut Rng, case: usize) -> [Vec3; 9] {
    let c0 = Vec3::new(
        rng.range(0.2, 2.0),
        rng.range(0.2, 2.0),
        rng.range(0.2, 2.0),
    ) * sh_scale(case);
    let mut c = [Vec3::ZERO; 9];
    c[0] = c0;
    for (i, ci) in c.iter_mut().enumerate().skip(1) {
        let s = if i < 4 { 0.9 } else { 0.6 };
        *ci = Vec3::new(
            rng.range(-s, s) * c0.x,
            rng.range(-s, s) * c0.y,
            rng.range(-s, s) * c0.z,
        );
    }
    match case % 17 {
        0 => {
            for ci in &mut c[1..4] {
                *ci = Vec3::ZERO;
            }
        }
        5 => c[0].z = -0.3 * sh_scale(case),
        _ => {}
    }
    c
}

struct Inputs {
    input: Vec<f32>,
    sh: Vec<[Vec3; 9]>,
    n: Vec<Vec3>,
    zh: Vec<Zh3>,
    cube: Vec<AmbientCube>,
    idx: Vec<[usize; 4]>,
    w: Vec<[f32; 4]>,
    pos: Vec<Vec3>,
    /// Affine model of the grid probes: coefficient value a + B·p.
    affine: ([Vec3; 9], [[Vec3; 3]; 9]),
    grid_sh: Vec<f32>,
    words: Vec<u32>,
    offsets: [u32; 4],
}

fn grid_probe_position(g: &Grid, i: usize) -> Vec3 {
    let [rx, ry, rz] = g.resolution.map(|r| r as usize);
    let (x, y, z) = (i % rx, (i / rx) % ry, i / (rx * ry));
    assert!(z < rz);
    let t = |k: usize, r: usize| {
        if r > 1 {
            k as f32 / (r - 1) as f32
        } else {
            0.0
        }
    };
    g.min + (g.max - g.min) * Vec3::new(t(x, rx), t(y, ry), t(z, rz))
}

fn affine_eval(a: &([Vec3; 9], [[Vec3; 3]; 9]), p: Vec3) -> [Vec3; 9] {
    let mut out = [Vec3::ZERO; 9];
    for i in 0..9 {
        out[i] = a.0[i] + a.1[i][0] * p.x + a.1[i][1] * p.y + a.1[i][2] * p.z;
    }
    out
}

fn make_inputs(g: &Grid) -> Inputs {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let nprobes = g.resolution.iter().product::<u32>() as usize;
    let mut affine = ([Vec3::ZERO; 9], [[Vec3::ZERO; 3]; 9]);
    for i in 0..9 {
        affine.0[i] = Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        for ax in 0..3 {
            affine.1[i][ax] = Vec3::new(
                rng.range(-0.5, 0.5),
                rng.range(-0.5, 0.5),
                rng.range(-0.5, 0.5),
            );
        }
    }
    let mut grid_sh = Vec::with_capacity(nprobes * 27);
    for p in 0..nprobes {
        for c in affine_eval(&affine, grid_probe_position(g, p)) {
            grid_sh.extend_from_slice(&c.to_array());
        }
    }

    let mut inp = Inputs {
        input: vec![0.0; CASES * CHECK_IN_FLOATS],
        sh: vec![],
        n: vec![],
        zh: vec![],
        cube: vec![],
        idx: vec![],
        w: vec![],
        pos: vec![],
        affine,
        grid_sh,
        words: vec![],
        offsets: [0; 4],
    };
    // Codec regions start at deliberately unaligned byte offsets.
    let l1_off = 1usize;
    let zh3_off = l1_off + 13 * CASES + 2;
    let l2_off = zh3_off + 16 * CASES + 1;
    let cube_off = l2_off + 28 * CASES + 3;
    let end = cube_off + 24 * CASES;
    let mut bytes = vec![0u8; end.next_multiple_of(4) + 32];
    for case in 0..CASES {
        let sh = random_sh(&mut rng, case);
        let n = rng.unit();
        let axis = rng.unit();
        let zonal = Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        ) * sh_scale(case);
        let l1: [Vec3; 4] = sh[..4].try_into().unwrap();
        let zh = Zh3 {
            l1,
            zonal,
            axes: [axis; 3],
        };
        let mut faces = [Vec3::ZERO; 6];
        for f in &mut faces {
            *f = Vec3::new(
                rng.range(0.0, 3.0),
                rng.range(0.0, 3.0),
                rng.range(0.0, 3.0),
            );
        }
        let cube = AmbientCube { faces };
        let idx = [0; 4].map(|_| rng.below(nprobes));
        let w = [0; 4].map(|_| rng.range(0.05, 1.0));
        let ws: f32 = w.iter().sum();
        let w = w.map(|x| x / ws);
        let pad = (g.max - g.min) * 0.15 + Vec3::splat(0.1);
        let lo = g.min - pad;
        let hi = g.max + pad;
        let pos = Vec3::new(
            rng.range(lo.x, hi.x),
            rng.range(lo.y, hi.y),
            rng.range(lo.z, hi.z),
        );

        let a = &mut inp.input[case * CHECK_IN_FLOATS..(case + 1) * CHECK_IN_FLOATS];
        a[0..3].copy_from_slice(&n.to_array());
        for k in 0..9 {
            a[3 + 3 * k..6 + 3 * k].copy_from_slice(&sh[k].to_array());
        }
        a[30..33].copy_from_slice(&zonal.to_array());
        a[33..36].copy_from_slice(&axis.to_array());
        for k in 0..6 {
            a[36 + 3 * k..39 + 3 * k].copy_from_slice(&faces[k].to_array());
        }
        for k in 0..4 {
            a[54 + k] = idx[k] as f32;
            a[58 + k] = w[k];
        }
        a[62..65].copy_from_slice(&pos.to_array());

        bytes[l1_off + 13 * case..][..13].copy_from_slice(&encode_l1(&l1));
        bytes[zh3_off + 16 * case..][..16].copy_from_slice(&encode_zh3(&zh));
        bytes[l2_off + 28 * case..][..28].copy_from_slice(&encode_l2(&sh));
        bytes[cube_off + 24 * case..][..24].copy_from_slice(&encode_ambient_cube(&cube));

        inp.sh.push(sh);
        inp.n.push(n);
        inp.zh.push(zh);
        inp.cube.push(cube);
        inp.idx.push(idx);
        inp.w.push(w);
        inp.pos.push(pos);
    }
    inp.words = bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    inp.offsets = [l1_off, zh3_off, l2_off, cube_off].map(|o| o as u32);
    inp
}

/// The `PkVolumeGrid` uniform of `g` (min @0, max @16, resolution @32,
/// no gradients).
fn grid_bytes(g: &Grid) -> [u8; 48] {
    let mut b = [0u8; 48];
    let put_f = |b: &mut [u8; 48], at: usize, v: Vec3| {
        for (k, x) in v.to_array().iter().enumerate() {
            b[at + 4 * k..at + 4 * k + 4].copy_from_slice(&x.to_le_bytes());
        }
    };
    put_f(&mut b, 0, g.min);
    put_f(&mut b, 16, g.max);
    for (k, r) in g.resolution.iter().enumerate() {
        b[32 + 4 * k..36 + 4 * k].copy_from_slice(&r.to_le_bytes());
    }
    b
}

#[test]
fn wgsl_matches_rust_on_random_inputs() {
    let Some(adapter) = adapter_or_skip() else {
        return;
    };
    let gpu = Gpu::new(&adapter, "pk_check_library");
    let mut rep = Report::default();
    for g in &GRIDS {
        let inp = make_inputs(g);
        let buffers = Buffers {
            words: inp.words.clone(),
            sh: inp.grid_sh.clone(),
            grid: grid_bytes(g),
            offsets: inp.offsets,
            ..Default::default()
        };
        let out = gpu.run(MODE_LIBRARY, &inp.input, &buffers);
        assert_eq!(out.len(), CASES * CHECK_OUT_FLOATS);
        compare(g, &inp, &out, &mut rep);
    }
    rep.finish("library");
}

/// Compares one run of `pk_check` with probekit-sh.
fn compare(g: &Grid, inp: &Inputs, out: &[f32], rep: &mut Report) {
    // GPU arithmetic is not bit-exact (division, pow, FMA contraction), so
    // compare with a relative tolerance; codec decoding is (nearly) exact.
    const TOL: f32 = 1e-5;
    const TOL_POW: f32 = 1e-4;
    for case in 0..CASES {
        let o = &out[case * CHECK_OUT_FLOATS..(case + 1) * CHECK_OUT_FLOATS];
        let sh = &inp.sh[case];
        let n = inp.n[case];
        let l1: [Vec3; 4] = sh[..4].try_into().unwrap();
        let v3 = |k: usize| &o[k..k + 3];
        rep.unit = sh_scale(case);
        rep.check(
            "irradiance_l1",
            case,
            v3(0),
            &irradiance_l1(&l1, n).to_array(),
            TOL,
        );
        rep.check(
            "irradiance_l2",
            case,
            v3(3),
            &irradiance_l2(sh, n).to_array(),
            TOL,
        );
        rep.check(
            "irradiance_geomerics_l1",
            case,
            v3(6),
            &irradiance_geomerics_l1(&l1, n).to_array(),
            TOL_POW,
        );
        rep.check(
            "zh3_hallucinated_irradiance",
            case,
            v3(9),
            &zh3_hallucinated_irradiance(&l1, n).to_array(),
            TOL,
        );
        rep.check(
            "Zh3::irradiance",
            case,
            v3(12),
            &inp.zh[case].irradiance(n).to_array(),
            TOL,
        );
        rep.unit = 1.0;
        rep.check(
            "AmbientCube::irradiance",
            case,
            v3(15),
            &inp.cube[case].irradiance(n).to_array(),
            TOL,
        );
        rep.unit = sh_scale(case);
        let dl1 = decode_l1(&encode_l1(&l1));
        rep.check("decode_l1", case, &o[18..30], &flat(&dl1), TOL);
        let dz = decode_zh3(&encode_zh3(&inp.zh[case]));
        rep.check("decode_zh3.l1", case, &o[30..42], &flat(&dz.l1), TOL);
        rep.check("decode_zh3.zonal", case, v3(42), &dz.zonal.to_array(), TOL);
        rep.unit = 1.0;
        rep.check("decode_zh3.axes", case, v3(45), &dz.axes[0].to_array(), TOL);
        rep.unit = sh_scale(case);
        rep.check(
            "decode_l2",
            case,
            &o[48..75],
            &flat(&decode_l2(&encode_l2(sh))),
            TOL,
        );
        rep.unit = 1.0;
        // Cloud blending: Σ w_k · probe(idx_k) from the grid buffer.
        let mut blend = [Vec3::ZERO; 9];
        for k in 0..4 {
            let p = &inp.grid_sh[27 * inp.idx[case][k]..][..27];
            for (i, b) in blend.iter_mut().enumerate() {
                *b += Vec3::from_slice(&p[3 * i..3 * i + 3]) * inp.w[case][k];
            }
        }
        rep.check("cloud blend", case, &o[75..102], &flat(&blend), TOL);
        // Volume: affine probes ⇒ the affine function at the clamped position.
        let p = inp.pos[case].clamp(g.min, g.max);
        rep.check(
            "volume sample",
            case,
            &o[102..129],
            &flat(&affine_eval(&inp.affine, p)),
            TOL,
        );
        rep.unit = sh_scale(case);
        let hz = zh3_hallucinate(&l1);
        rep.check(
            "zh3_hallucinate.zonal",
            case,
            v3(129),
            &hz.zonal.to_array(),
            TOL,
        );
        rep.unit = 1.0;
        rep.check(
            "zh3_hallucinate.axes",
            case,
            v3(132),
            &hz.axes[0].to_array(),
            TOL,
        );
        rep.unit = sh_scale(case);
        rep.check("eval_sh", case, v3(135), &eval_sh(sh, n).to_array(), TOL);
        let mut b1 = [Vec3::ZERO; 4];
        for i in 0..4 {
            b1[i] = (l1[i] * inp.w[case][0] + dl1[i] * inp.w[case][1])
                + (l1[i] * inp.w[case][2] + dl1[i] * inp.w[case][3]);
        }
        rep.check("blend_l1", case, &o[138..150], &flat(&b1), TOL);
        rep.unit = 1.0;
        let dc = decode_ambient_cube(&encode_ambient_cube(&inp.cube[case]));
        rep.check(
            "decode_ambient_cube",
            case,
            &o[150..168],
            &flat(&dc.faces),
            0.0,
        );
    }
}
