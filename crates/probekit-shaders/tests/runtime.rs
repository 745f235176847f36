//! The WGSL cloud, volume and brick-atlas functions against
//! `probekit-runtime` on the same inputs: small files baked in-process from
//! builtin:demo with the default blend data (distance moments, cell
//! visibility, occluder planes, fitted probe weights with their exponents),
//! packed by `probekit_shaders::layout`, queried at random points (inside,
//! outside the probes' hull, outside the box) on a CPU Vulkan adapter (Mesa
//! lavapipe). Each test prints `SKIPPED: no wgpu adapter` and returns when
//! no adapter exists.

// Index loops over coefficients and channels read like the layout tables.
#![allow(clippy::needless_range_loop)]

mod common;

use common::{
    adapter_or_skip, flat, Buffers, Gpu, Report, Rng, MODE_BRICKS, MODE_CLOUD, MODE_VOLUME,
};
use glam::Vec3;
use probekit::pipeline::{bake_volume, Bake};
use probekit::recipe::{GradientModeName, Placement, Recipe, VolumeLayout};
use probekit::scene::Scene;
use probekit::volume::export::{export_bricks, Ktx2Encoding, Ktx2Export};
use probekit_runtime::cloud::{Location, WalkState};
use probekit_runtime::format::{Codec, Coefficients, Gradients, ProbeFile};
use probekit_runtime::sh::codec::{decode_rgb9e5, encode_l1};
use probekit_runtime::sh::zh3::zh3_hallucinated_irradiance;
use probekit_runtime::volume::{Interp, Volume};
use probekit_runtime::ProbeCloud;
use probekit_shaders::layout::{
    cell_code, pack_bricks, pack_cloud, pack_volume_grid, BrickAtlas, BrickEncoding, CLOUD_HULL,
};
use probekit_shaders::{CHECK_IN_FLOATS, CHECK_OUT_FLOATS};

/// Random points per cloud variant and per volume.
const POINTS: usize = 1024;

/// The demo's interior, where the bake box lies.
const BOX_MIN: Vec3 = Vec3::new(0.0, 0.0, 0.0);
const BOX_MAX: Vec3 = Vec3::new(8.0, 3.0, 4.0);

/// A quick capture: few samples and one bounce (the tests compare the
/// shaders with the runtime on the same file, not the file with the scene).
fn quick_recipe() -> Recipe {
    let mut r = Recipe::default();
    r.capture.samples = 64;
    r.capture.bounces = 1;
    r.blend.fit.points_per_probe = 8;
    r.blend.fit.samples = 32;
    r
}

/// A small grid cloud of builtin:demo (a budget of 48 probes) with the
/// default blend data.
fn bake_cloud(scene: &Scene) -> ProbeFile {
    let mut r = quick_recipe();
    r.placement = Placement::Grid {
        budget: Some(48),
        cell: None,
    };
    let bake = Bake::new(scene, "builtin:demo", &r).expect("recipe");
    bake.run(&|_, _, _| {}).expect("cloud bake").file
}

/// A volume of builtin:demo with central-difference gradients.
fn bake_demo_volume(scene: &Scene, layout: VolumeLayout) -> ProbeFile {
    let mut r = quick_recipe();
    r.volume.layout = layout;
    r.volume.gradients.mode = GradientModeName::Central;
    bake_volume(scene, "builtin:demo", &r, &|_, _, _| {})
        .expect("volume bake")
        .0
}

/// `file` with its coefficients stored in the 13-byte L1 codec (bands ≤ 1
/// of each probe) and its gradients, if any, cut to bands ≤ 1.
fn as_l1(file: &ProbeFile) -> ProbeFile {
    let coefficients = &file.probes().unwrap().coefficients;
    let n = (coefficients.order * coefficients.order) as usize;
    let c = coefficients.to_f32().unwrap();
    let mut data = Vec::new();
    for p in c.chunks_exact(n) {
        data.extend_from_slice(&encode_l1(&[p[0], p[1], p[2], p[3]]));
    }
    let mut out = file.clone();
    out.probes_mut().unwrap().coefficients = Coefficients {
        codec: Codec::L1Q13,
        order: 2,
        data,
    };
    if let Some(v) = out.as_volume_mut() {
        v.gradients = v.gradients.as_ref().map(|g| cut_gradients(g, 2));
    }
    out
}

/// Gradients cut to the first `order` bands.
fn cut_gradients(g: &Gradients, order: u32) -> Gradients {
    let (gn, m) = ((g.order * g.order) as usize, (order * order) as usize);
    Gradients {
        order,
        data: g
            .data
            .chunks_exact(gn)
            .flat_map(|c| c[..m].iter().copied())
            .collect(),
    }
}

/// Random points in the box grown by `pad` (outside the hull and the box
/// too), each with a unit normal.
fn random_points(rng: &mut Rng, lo: Vec3, hi: Vec3, pad: f32) -> Vec<(Vec3, Vec3)> {
    (0..POINTS)
        .map(|_| {
            let p = Vec3::new(
                rng.range(lo.x - pad, hi.x + pad),
                rng.range(lo.y - pad, hi.y + pad),
                rng.range(lo.z - pad, hi.z + pad),
            );
            (p, rng.unit())
        })
        .collect()
}

/// The check kernel's input: p, n, then mode-specific floats.
fn input(points: &[(Vec3, Vec3)], extra: impl Fn(usize) -> [f32; 2]) -> Vec<f32> {
    let mut v = vec![0.0f32; points.len() * CHECK_IN_FLOATS];
    for (i, (p, n)) in points.iter().enumerate() {
        let a = &mut v[i * CHECK_IN_FLOATS..];
        a[0..3].copy_from_slice(&p.to_array());
        a[3..6].copy_from_slice(&n.to_array());
        a[6..8].copy_from_slice(&extra(i));
    }
    v
}

fn l1_of(sh: &[Vec3; 9]) -> [Vec3; 4] {
    [sh[0], sh[1], sh[2], sh[3]]
}

/// The closest point of triangle `t` to `p`, found independently of both
/// implementations: the projection onto the plane if it falls inside, else
/// the closest of the three edge segments (f64).
fn closest_on_triangle(p: Vec3, t: [Vec3; 3]) -> Vec3 {
    let [a, b, c] = t.map(|v| v.as_dvec3());
    let p = p.as_dvec3();
    let n = (b - a).cross(c - a);
    let q = p - n * (p - a).dot(n) / n.dot(n);
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|&(u, v)| (v - u).cross(q - u).dot(n) >= 0.0);
    if inside {
        return q.as_vec3();
    }
    let seg = |u: glam::DVec3, v: glam::DVec3| {
        let t = ((p - u).dot(v - u) / (v - u).length_squared()).clamp(0.0, 1.0);
        u + (v - u) * t
    };
    [seg(a, b), seg(b, c), seg(c, a)]
        .into_iter()
        .min_by(|x, y| x.distance(p).total_cmp(&y.distance(p)))
        .unwrap()
        .as_vec3()
}

/// How many cases took each path, so that the test proves what it covers.
#[derive(Default, Debug)]
struct Coverage {
    outside_hull: usize,
    planes: usize,
    lattice_records: usize,
    one_probe: usize,
}

/// Runs the cloud check on `cloud` (packed as it is) and compares with the
/// runtime; returns what the points covered.
fn compare_cloud(gpu: &Gpu, name: &str, cloud: &ProbeCloud, rep: &mut Report) -> Coverage {
    let packed = pack_cloud(cloud).expect("pack");
    // Two thirds in the probes' bounding box (mostly inside the hull), a
    // third in the box grown by 30 cm (outer cells, beyond the box).
    let mut rng = Rng(0x5eed_c10d);
    let pos = cloud.mesh().positions();
    let (lo, hi) = pos
        .iter()
        .fold((pos[0], pos[0]), |(l, h), &p| (l.min(p), h.max(p)));
    let mut points = random_points(&mut rng, lo, hi, 0.0);
    points.truncate(2 * POINTS / 3);
    points.extend(random_points(&mut rng, BOX_MIN, BOX_MAX, 0.3));
    points.truncate(POINTS);
    let mut cov = Coverage::default();
    let mut cpu = Vec::new();
    for &(p, n) in &points {
        let mut st = WalkState::new();
        let loc = cloud.mesh().locate(p, &mut st);
        let (probes, w) = cloud.weights_at(p, &mut st);
        let k = cloud.coeffs_per_probe().min(9);
        let mut sh = [Vec3::ZERO; 9];
        cloud.sh_at(p, &mut st, &mut sh[..k]);
        let e = cloud.irradiance(p, n, &mut st);
        let ez = zh3_hallucinated_irradiance(&l1_of(&sh), n);
        match loc {
            Location::Outside { .. } => cov.outside_hull += 1,
            Location::Inside { tet, .. } => {
                if cloud.cell_planes().and_then(|pl| pl.plane(tet)).is_some() {
                    cov.planes += 1;
                } else if cloud
                    .cell_visibility_bits()
                    .is_some_and(|c| c.tet_has_record(tet))
                {
                    cov.lattice_records += 1;
                }
            }
        }
        if w.iter().filter(|&&x| x == 1.0).count() == 1 {
            cov.one_probe += 1;
        }
        cpu.push((cell_code(&loc), probes, w, sh, e, ez));
    }
    let inp = input(&points, |i| {
        let code = cpu[i].0;
        [(code & !CLOUD_HULL) as f32, (code >> 31) as f32]
    });
    let out = gpu.run(
        MODE_CLOUD,
        &inp,
        &Buffers {
            cloud: packed.words,
            ..Default::default()
        },
    );
    let unit = 1e-3
        * (0..cloud.probe_count())
            .map(|i| cloud.probe_sh(i)[0].abs().max_element())
            .fold(0.0f32, f32::max);
    let mut located_elsewhere = 0;
    for (i, (code, probes, w, sh, e, ez)) in cpu.iter().enumerate() {
        let o = &out[i * CHECK_OUT_FLOATS..(i + 1) * CHECK_OUT_FLOATS];
        let tag = |what: &str| format!("{name}: {what}");
        rep.unit = 0.0;
        rep.check(&tag("probes"), i, &o[0..4], &probes.map(|p| p as f32), 0.0);
        rep.unit = 1.0;
        rep.check(&tag("pk_cloud_weights"), i, &o[4..8], w, 2e-5);
        rep.unit = unit;
        rep.check(&tag("pk_cloud_sh"), i, &o[8..35], &flat(sh), 5e-5);
        rep.check(
            &tag("pk_cloud_irradiance"),
            i,
            &o[35..38],
            &e.to_array(),
            5e-5,
        );
        // Hallucinated ZH3 divides by the blended DC term: in a dark cell
        // float rounding of the blend (summation order) grows by |L1|/L0.
        rep.check(
            &tag("pk_cloud_irradiance_zh3"),
            i,
            &o[38..41],
            &ez.to_array(),
            5e-4,
        );
        let located = o[41] as u32 | ((o[42] as u32) << 31);
        if located == *code {
            rep.check(
                &tag("pk_cloud_locate + pk_cloud_sh"),
                i,
                &o[43..70],
                &flat(sh),
                5e-5,
            );
        } else {
            // Another cell is a tie only if it holds the point as well: a
            // tetrahedron whose coordinates are all ≥ −tolerance, or a hull
            // face whose closest point is as close as the runtime's.
            located_elsewhere += 1;
            let p = points[i].0;
            let mesh = cloud.mesh();
            let dist = |c: u32| {
                let f = c & !CLOUD_HULL;
                let q = mesh
                    .hull_face_probes(f)
                    .unwrap()
                    .map(|k| mesh.positions()[k as usize]);
                closest_on_triangle(p, q).distance(p)
            };
            let ok = match (located & CLOUD_HULL != 0, *code & CLOUD_HULL != 0) {
                (false, false) => {
                    let l = mesh.bary(located).coords(p);
                    l.iter().all(|&x| x >= -2e-5)
                }
                (true, true) => (dist(located) - dist(*code)).abs() <= 1e-5 * (1.0 + dist(*code)),
                _ => false,
            };
            if !ok && rep.failures.len() < 20 {
                rep.failures.push(format!(
                    "{name}: pk_cloud_locate, case {i}: cell {located:#x} does not hold {p}, the runtime's {code:#x} does"
                ));
            }
        }
    }
    println!(
        "{name}: {cov:?}; pk_cloud_locate found another cell holding the point (a tie on a \
         shared face, edge or vertex) for {located_elsewhere} of {POINTS} points"
    );
    cov
}

#[test]
fn cloud_blend_matches_runtime() {
    let Some(adapter) = adapter_or_skip() else {
        return;
    };
    let gpu = Gpu::new(&adapter, "pk_check_cloud");
    let scene = Scene::builtin_demo();
    let file = bake_cloud(&scene);
    assert!(
        file.as_cloud().unwrap().blend.distance_moments.is_some()
            && file.as_cloud().unwrap().blend.cell_visibility.is_some()
            && file.as_cloud().unwrap().blend.cell_planes.is_some()
            && file.as_cloud().unwrap().blend.probe_weights.is_some()
            && file.as_cloud().unwrap().blend.directional_exponent > 0.0,
        "the default bake stores every kind of blend data"
    );
    println!(
        "cloud: {} probes, α = {}, γ = {}",
        file.probe_count(),
        file.as_cloud().unwrap().blend.brightness_exponent,
        file.as_cloud().unwrap().blend.directional_exponent
    );
    let mut rep = Report::default();
    let baked = ProbeCloud::from_file(&file).unwrap();
    let cov = compare_cloud(&gpu, "baked", &baked, &mut rep);
    assert!(
        cov.outside_hull > 0 && cov.planes > 0 && cov.lattice_records > 0,
        "the points cover outer cells, planes and lattice records: {cov:?}"
    );
    let variant = |f: &dyn Fn(&mut ProbeCloud)| {
        let mut c = baked.clone();
        f(&mut c);
        c
    };
    let variants: [(&str, ProbeCloud); 6] = [
        (
            "α 0.7, γ 0.7 (powers)",
            variant(&|c| {
                c.set_brightness_weighting(0.7).unwrap();
                c.set_directional_brightness(0.7).unwrap();
            }),
        ),
        (
            "α 1, γ 1, no moments",
            variant(&|c| {
                c.set_visibility(false);
                c.set_brightness_weighting(1.0).unwrap();
                c.set_directional_brightness(1.0).unwrap();
            }),
        ),
        (
            "γ 0.25, no cell visibility",
            variant(&|c| {
                c.set_cell_visibility(false);
                c.set_directional_brightness(0.25).unwrap();
            }),
        ),
        (
            "lattice bits only, plain blend",
            variant(&|c| {
                c.set_cell_planes(None).unwrap();
                c.set_visibility(false);
                c.set_probe_weighting(false);
                c.set_brightness_weighting(0.0).unwrap();
                c.set_directional_brightness(0.0).unwrap();
            }),
        ),
        (
            "everything off",
            variant(&|c| {
                c.set_visibility(false);
                c.set_cell_visibility(false);
                c.set_probe_weighting(false);
                c.set_brightness_weighting(0.0).unwrap();
                c.set_directional_brightness(0.0).unwrap();
            }),
        ),
        (
            "L1 codec (13 bytes), as stored",
            ProbeCloud::from_file(&as_l1(&file)).unwrap(),
        ),
    ];
    for (name, cloud) in &variants {
        compare_cloud(&gpu, name, cloud, &mut rep);
    }
    rep.finish("cloud");
}

/// Runs the volume check on a uniform volume file and compares every
/// interpolation with the runtime.
fn compare_volume(gpu: &Gpu, name: &str, file: &ProbeFile, rep: &mut Report) {
    let vol = Volume::from_file(file).unwrap();
    let packed = pack_volume_grid(file).expect("pack");
    let (lo, hi) = vol.bounds();
    let mut rng = Rng(0x0b0e_55ed);
    let points = random_points(&mut rng, lo, hi, 0.3);
    let out = gpu.run(
        MODE_VOLUME,
        &input(&points, |_| [0.0; 2]),
        &Buffers {
            sh: packed.coefficients,
            gradients: packed.gradients,
            grid: packed.grid,
            ..Default::default()
        },
    );
    let n = vol.coeffs_per_sample().min(9);
    let unit = 1e-3
        * file
            .probes()
            .unwrap()
            .coefficients
            .to_f32()
            .unwrap()
            .iter()
            .step_by(vol.coeffs_per_sample())
            .map(|c| c.abs().max_element())
            .fold(0.0f32, f32::max);
    for (i, &(p, nrm)) in points.iter().enumerate() {
        let o = &out[i * CHECK_OUT_FLOATS..(i + 1) * CHECK_OUT_FLOATS];
        for (k, (interp, label)) in [
            (Interp::Trilinear, "trilinear"),
            (Interp::Taylor, "Taylor"),
            (Interp::Tricubic, "tricubic"),
        ]
        .into_iter()
        .enumerate()
        {
            let mut buf = [Vec3::ZERO; 64];
            vol.sample_sh(p, interp, &mut buf).unwrap();
            let mut sh = [Vec3::ZERO; 9];
            sh[..n].copy_from_slice(&buf[..n]);
            let e = vol.irradiance(p, nrm, interp).unwrap();
            let ez = zh3_hallucinated_irradiance(&l1_of(&sh), nrm);
            rep.unit = unit;
            let tag = |what: &str| format!("{name}: {what} {label}");
            rep.check(
                &tag("pk_volume_sample"),
                i,
                &o[27 * k..27 * k + 27],
                &flat(&sh),
                5e-5,
            );
            rep.check(
                &tag("irradiance"),
                i,
                &o[81 + 3 * k..84 + 3 * k],
                &e.to_array(),
                5e-5,
            );
            rep.check(
                &tag("pk_volume_irradiance_zh3"),
                i,
                &o[90 + 3 * k..93 + 3 * k],
                &ez.to_array(),
                5e-5,
            );
        }
    }
}

#[test]
fn uniform_volume_matches_runtime() {
    let Some(adapter) = adapter_or_skip() else {
        return;
    };
    let gpu = Gpu::new(&adapter, "pk_check_volume");
    let scene = Scene::builtin_demo();
    let file = bake_demo_volume(
        &scene,
        VolumeLayout::Uniform {
            cell: None,
            resolution: Some([6, 3, 4]),
        },
    );
    assert!(
        file.as_volume().and_then(|v| v.grid()).is_some()
            && file
                .as_volume()
                .unwrap()
                .gradients
                .as_ref()
                .is_some_and(|g| g.order == 3)
    );
    let mut rep = Report::default();
    compare_volume(&gpu, "L2, L2 gradients", &file, &mut rep);
    let mut cut = file.clone();
    cut.as_volume_mut().unwrap().gradients = file
        .as_volume()
        .unwrap()
        .gradients
        .as_ref()
        .map(|g| cut_gradients(g, 2));
    compare_volume(&gpu, "L2, L1 gradients", &cut, &mut rep);
    compare_volume(&gpu, "L1 codec", &as_l1(&file), &mut rep);
    rep.finish("uniform volume");
}

/// The atlas lookup written from the export's sidecar description
/// (`"lookup"`: normalized coordinates with texel centres at k + ½), with
/// the texels decoded as the sidecar's `"layout"` says: the CPU reference
/// of `pk_bricks_sh_l2`.
struct AtlasReference<'a> {
    min: Vec3,
    max: Vec3,
    cells: [u32; 3],
    atlas: [u32; 3],
    n: usize,
    quantized: bool,
    bounds: Vec<f32>,
    indirection: &'a [u8],
    textures: Vec<&'a [u8]>,
}

impl AtlasReference<'_> {
    fn texel(&self, t: usize) -> [Vec3; 9] {
        let mut sh = [Vec3::ZERO; 9];
        let m = self.n.min(9);
        if !self.quantized {
            for f in 0..3 * m {
                let b = &self.textures[f / 4][8 * t + 2 * (f % 4)..];
                sh[f / 3][f % 3] = half::f16::from_bits(u16::from_le_bytes([b[0], b[1]])).to_f32();
            }
        } else {
            let d = &self.textures[0][4 * t..];
            let dc = decode_rgb9e5(u32::from_le_bytes([d[0], d[1], d[2], d[3]]));
            sh[0] = dc;
            for f in 0..3 * (m - 1) {
                let q = self.textures[1 + f / 4][4 * t + f % 4] as i8;
                let (i, ch) = (1 + f / 3, f % 3);
                sh[i][ch] = (q as f32 / 127.0).max(-1.0) * self.bounds[i - 1] * dc[ch];
            }
        }
        sh
    }

    fn sample(&self, p: Vec3) -> [Vec3; 9] {
        let n = Vec3::from_array(self.cells.map(|c| c as f32));
        let g = (p.clamp(self.min, self.max) - self.min) / (self.max - self.min) * n;
        let c: [u32; 3] =
            std::array::from_fn(|a| (g[a].floor().max(0.0) as u32).min(self.cells[a] - 1));
        let ti = 4 * (c[0] + self.cells[0] * (c[1] + self.cells[1] * c[2])) as usize;
        let texel = &self.indirection[ti..ti + 4];
        let s = 1u32 << texel[3];
        let mut i0 = [0usize; 3];
        let mut fr = [0.0f32; 3];
        for a in 0..3 {
            let o = (c[a] / s * s) as f32;
            let f = ((g[a] - o) / s as f32).clamp(0.0, 1.0);
            // Normalized coordinate (b·5 + ½ + 4f) / R; texel centres at k + ½.
            let x = texel[a] as f32 * 5.0 + 0.5 + 4.0 * f - 0.5;
            let lo = texel[a] as usize * 5;
            i0[a] = (x.floor() as usize).clamp(lo, lo + 3);
            fr[a] = x - i0[a] as f32;
        }
        let mut out = [Vec3::ZERO; 9];
        for corner in 0..8 {
            let mut w = 1.0;
            let mut q = [0usize; 3];
            for a in 0..3 {
                let b = (corner >> a) & 1;
                q[a] = i0[a] + b;
                w *= if b == 1 { fr[a] } else { 1.0 - fr[a] };
            }
            let t = q[0] + self.atlas[0] as usize * (q[1] + self.atlas[1] as usize * q[2]);
            let sh = self.texel(t);
            for k in 0..9 {
                out[k] += sh[k] * w;
            }
        }
        out
    }

    /// World positions of the inner texels (corner and quarter points not on
    /// a brick face) of the brick of every `step`-th indirection cell.
    fn inner_texel_points(&self, step: usize) -> Vec<Vec3> {
        let n = Vec3::from_array(self.cells.map(|c| c as f32));
        let size = self.max - self.min;
        let mut out = Vec::new();
        let count = (self.cells[0] * self.cells[1] * self.cells[2]) as usize;
        for ci in (0..count).step_by(step) {
            let c = [
                ci as u32 % self.cells[0],
                ci as u32 / self.cells[0] % self.cells[1],
                ci as u32 / (self.cells[0] * self.cells[1]),
            ];
            let s = 1u32 << self.indirection[4 * ci + 3];
            let o = Vec3::from_array(c.map(|x| (x / s * s) as f32));
            for w in 1..4 {
                for v in 1..4 {
                    for u in 1..4 {
                        let f = Vec3::new(u as f32, v as f32, w as f32) / 4.0;
                        out.push(self.min + (o + f * s as f32) / n * size);
                    }
                }
            }
        }
        out
    }
}

/// Packs an export's textures and sidecar for `pk_bricks`, with the CPU
/// reference of the same atlas.
fn pack_export(ex: &Ktx2Export) -> (Vec<u32>, AtlasReference<'_>) {
    let sc = &ex.sidecar;
    let v3 = |v: &serde_json::Value| -> [f32; 3] {
        std::array::from_fn(|a| v[a].as_f64().unwrap() as f32)
    };
    let u3 = |v: &serde_json::Value| -> [u32; 3] {
        std::array::from_fn(|a| v[a].as_u64().unwrap() as u32)
    };
    let order = sc["sh_order"].as_u64().unwrap() as u32;
    let quantized = sc["encoding"] == "quantized";
    let bounds: Vec<f32> = sc["ratio_bounds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b.as_f64().unwrap() as f32)
        .collect();
    let indirection = &ex.textures[0].1.data;
    let textures: Vec<&[u8]> = ex.textures[1..].iter().map(|t| &t.1.data[..]).collect();
    let atlas = BrickAtlas {
        encoding: if quantized {
            BrickEncoding::Quantized
        } else {
            BrickEncoding::F16
        },
        coeffs: order * order,
        min: v3(&sc["box"]["min"]),
        max: v3(&sc["box"]["max"]),
        cells: u3(&sc["indirection"]["resolution"]),
        atlas: u3(&sc["atlas_resolution"]),
        ratio_bounds: &bounds,
        indirection,
        textures: &textures,
    };
    let words = pack_bricks(&atlas).expect("pack bricks");
    let reference = AtlasReference {
        min: Vec3::from_array(atlas.min),
        max: Vec3::from_array(atlas.max),
        cells: atlas.cells,
        atlas: atlas.atlas,
        n: (order * order) as usize,
        quantized,
        bounds: bounds.clone(),
        indirection,
        textures: textures.clone(),
    };
    (words, reference)
}

#[test]
fn octree_bricks_match_runtime() {
    let Some(adapter) = adapter_or_skip() else {
        return;
    };
    let gpu = Gpu::new(&adapter, "pk_check_bricks");
    let scene = Scene::builtin_demo();
    let mut layout = VolumeLayout::defaults_of("octree").unwrap();
    if let VolumeLayout::Octree { max_depth, .. } = &mut layout {
        *max_depth = 4;
    }
    let file = bake_demo_volume(&scene, layout);
    let vol = Volume::from_file(&file).unwrap();
    println!(
        "octree: {} samples, {} leaves, depth ≤ {}, roots {:?}",
        vol.sample_count(),
        vol.leaf_count(),
        vol.max_depth(),
        vol.root_grid()
    );
    let (lo, hi) = vol.bounds();
    let n = vol.coeffs_per_sample().min(9);
    let unit = 1e-3
        * file
            .probes()
            .unwrap()
            .coefficients
            .to_f32()
            .unwrap()
            .iter()
            .step_by(vol.coeffs_per_sample())
            .map(|c| c.abs().max_element())
            .fold(0.0f32, f32::max);
    let mut rep = Report::default();
    // The atlas interpolates the octree query trilinearly between brick
    // texels: exact at the texels up to the encoding, off by the query's
    // departure from trilinear between them (where finer or coarser
    // neighbours' kernels reach in).
    for (encoding, label, tol_texel, tol_runtime, mean_runtime) in [
        (Ktx2Encoding::F16, "f16", 2e-3, 0.2, 1e-2),
        (Ktx2Encoding::Quantized, "quantized", 3e-2, 0.2, 2e-2),
    ] {
        let ex = export_bricks(&vol, encoding).expect("export");
        let (words, reference) = pack_export(&ex);
        let levels: std::collections::BTreeSet<u8> = reference
            .indirection
            .chunks_exact(4)
            .map(|t| t[3])
            .collect();
        println!(
            "{label}: indirection {:?}, atlas {:?}, levels {levels:?}",
            reference.cells, reference.atlas
        );
        assert!(levels.len() > 1, "bricks of more than one level");
        let mut rng = Rng(0x00b4_1cc5);
        let mut points = random_points(&mut rng, lo, hi, 0.2);
        let random = points.len();
        points.extend(
            reference
                .inner_texel_points(7)
                .into_iter()
                .map(|p| (p, rng.unit())),
        );
        let out = gpu.run(
            MODE_BRICKS,
            &input(&points, |_| [0.0; 2]),
            &Buffers {
                bricks: words,
                ..Default::default()
            },
        );
        let mut sum_rel = 0.0f32;
        for (i, &(p, nrm)) in points.iter().enumerate() {
            let o = &out[i * CHECK_OUT_FLOATS..(i + 1) * CHECK_OUT_FLOATS];
            let want = reference.sample(p);
            rep.unit = unit;
            let tag = |what: &str| format!("{label}: {what}");
            rep.check(
                &tag("pk_bricks_sh_l2 vs atlas"),
                i,
                &o[0..27],
                &flat(&want),
                2e-5,
            );
            rep.check(
                &tag("pk_bricks_irradiance vs atlas"),
                i,
                &o[27..30],
                &probekit_runtime::sh::convolve::irradiance_l2(&want, nrm).to_array(),
                2e-5,
            );
            rep.check(
                &tag("pk_bricks_irradiance_zh3 vs atlas"),
                i,
                &o[30..33],
                &zh3_hallucinated_irradiance(&l1_of(&want), nrm).to_array(),
                2e-5,
            );
            let mut buf = [Vec3::ZERO; 64];
            vol.sample_sh(p, Interp::Trilinear, &mut buf).unwrap();
            let mut sh = [Vec3::ZERO; 9];
            sh[..n].copy_from_slice(&buf[..n]);
            if i < random {
                rep.check(
                    &tag("pk_bricks_sh_l2 vs octree query"),
                    i,
                    &o[0..27],
                    &flat(&sh),
                    tol_runtime,
                );
                let e = vol.irradiance(p, nrm, Interp::Trilinear).unwrap();
                rep.check(
                    &tag("pk_bricks_irradiance vs octree query"),
                    i,
                    &o[27..30],
                    &e.to_array(),
                    tol_runtime,
                );
                let d = (Vec3::from_slice(&o[27..30]) - e).abs().max_element();
                sum_rel += d / (unit + e.abs().max_element());
            } else {
                rep.check(
                    &tag("pk_bricks_sh_l2 vs octree query, at texels"),
                    i,
                    &o[0..27],
                    &flat(&sh),
                    tol_texel,
                );
            }
        }
        let mean = sum_rel / random as f32;
        println!("{label}: mean relative irradiance error vs the octree query {mean:.2e}");
        assert!(
            mean < mean_runtime,
            "{label}: mean error {mean} vs the octree query"
        );
    }
    rep.finish("octree bricks");
}
