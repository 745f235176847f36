//! `probekit export --format bevy` as Bevy renders it: the exported KTX2 is
//! sampled the way Bevy's shader samples an irradiance volume, at random
//! points and normals, and compared with the non-negative least-squares
//! ambient cube of the runtime's irradiance at the same points (probekit's
//! own answer in the basis Bevy can hold), with the unconstrained cube and
//! with the SH irradiance itself. `cargo test -p probekit-cli --test
//! cli_bevy -- --nocapture` prints one table row per volume.

mod common;

use common::run;
use glam::{Affine3A, Quat, Vec3};
use probekit::format::ProbeFile;
use probekit::sampling::{sample_uniform_sphere, SampleRng};
use probekit::volume::export::Ktx2;
use probekit::volume::{Interp, Volume};
use probekit_sh::ambient_cube::AmbientCube;
use serde_json::Value;
use std::f32::consts::PI;
use std::path::{Path, PathBuf};

/// Bevy's irradiance-volume lookup for one volume, ported from bevyengine/bevy
/// commit 4805ca79 (`crates/bevy_pbr/src/light_probe/irradiance_volume.wesl`
/// lines 53–76: texture size, unit-cube position, half-texel clamp, the
/// negative-half and one-third offsets, `Σ N²·rgb · intensity`; the
/// world-to-probe transform of `crates/bevy_pbr/src/light_probe.wesl` lines
/// 122–128). With one volume its blend weight cancels (lines 81–83). The
/// texture fetch is wgpu's linear filter with clamp-to-edge addressing.
struct BevyVolume {
    /// Texture size in texels (`Rx, 2Ry, 3Rz`).
    size: [u32; 3],
    /// Decoded texels, x fastest.
    texels: Vec<Vec3>,
    /// World to the probe's unit cube (the inverse of its `Transform`).
    light_from_world: Affine3A,
    /// `IrradianceVolume::intensity`.
    intensity: f32,
}

/// RGB9E5 after the Vulkan specification (`VK_FORMAT_E5B9G9R9_UFLOAT_PACK32`,
/// "Shared Exponent"): `channel = mantissa · 2^(exponent − 15 − 9)`.
fn decode_rgb9e5(bits: u32) -> Vec3 {
    let scale = 2f32.powi((bits >> 27) as i32 - 24);
    Vec3::new(
        (bits & 0x1ff) as f32,
        ((bits >> 9) & 0x1ff) as f32,
        ((bits >> 18) & 0x1ff) as f32,
    ) * scale
}

fn vec3(v: &Value) -> Vec3 {
    Vec3::from_array(std::array::from_fn(|a| v[a].as_f64().unwrap() as f32))
}

impl BevyVolume {
    /// The texture at `ktx2` placed by `sidecar`'s `light_probe_transform`,
    /// with `IrradianceVolume::intensity = intensity`.
    fn load(ktx2: &Path, sidecar: &Value, intensity: f32) -> Self {
        let tex = Ktx2::from_bytes(&std::fs::read(ktx2).unwrap()).unwrap();
        assert_eq!(tex.format.vk_format(), 123, "E5B9G9R9_UFLOAT_PACK32");
        let texels = tex
            .data
            .chunks_exact(4)
            .map(|b| decode_rgb9e5(u32::from_le_bytes(b.try_into().unwrap())))
            .collect();
        let t = &sidecar["light_probe_transform"];
        let q = &t["rotation"];
        let rotation = Quat::from_xyzw(
            q[0].as_f64().unwrap() as f32,
            q[1].as_f64().unwrap() as f32,
            q[2].as_f64().unwrap() as f32,
            q[3].as_f64().unwrap() as f32,
        );
        let world_from_light = Affine3A::from_scale_rotation_translation(
            vec3(&t["scale"]),
            rotation,
            vec3(&t["translation"]),
        );
        Self {
            size: tex.size,
            texels,
            light_from_world: world_from_light.inverse(),
            intensity,
        }
    }

    /// `textureSampleLevel(…, uvw, 0)` with a linear filter and
    /// clamp-to-edge addressing: the 8 texels around `uvw·size − ½`.
    fn sample(&self, uvw: Vec3) -> Vec3 {
        let size = self.size.map(|s| s as i64);
        let mut base = [0i64; 3];
        let mut frac = [0f32; 3];
        for a in 0..3 {
            let x = uvw[a] * size[a] as f32 - 0.5;
            base[a] = x.floor() as i64;
            frac[a] = x - x.floor();
        }
        let mut out = Vec3::ZERO;
        for corner in 0..8 {
            let mut w = 1.0;
            let mut idx = [0usize; 3];
            for a in 0..3 {
                let b = (corner >> a) & 1;
                w *= if b == 1 { frac[a] } else { 1.0 - frac[a] };
                idx[a] = (base[a] + b as i64).clamp(0, size[a] - 1) as usize;
            }
            let [w0, h0] = [self.size[0] as usize, self.size[1] as usize];
            out += self.texels[idx[0] + w0 * (idx[1] + h0 * idx[2])] * w;
        }
        out
    }

    /// `irradiance_volume_light(world, N)` for this one volume: what Bevy
    /// multiplies by the diffuse colour (and then by the exposure).
    fn light(&self, world: Vec3, n: Vec3) -> Vec3 {
        let atlas_resolution = Vec3::from_array(self.size.map(|s| s as f32));
        // textureDimensions / (1, 2, 3), in integers.
        let resolution = Vec3::new(
            self.size[0] as f32,
            (self.size[1] / 2) as f32,
            (self.size[2] / 3) as f32,
        );
        let unit_pos = self.light_from_world.transform_point3(world);
        let stp = ((unit_pos + 0.5) * resolution).clamp(Vec3::splat(0.5), resolution - 0.5);
        let uvw = stp / atlas_resolution;
        let neg = |c: f32| if c < 0.0 { 0.5 } else { 0.0 };
        let rgb_x = self.sample(uvw + Vec3::new(0.0, neg(n.x), 0.0));
        let rgb_y = self.sample(uvw + Vec3::new(0.0, neg(n.y), 1.0 / 3.0));
        let rgb_z = self.sample(uvw + Vec3::new(0.0, neg(n.z), 2.0 / 3.0));
        let nn = n * n;
        (rgb_x * nn.x + rgb_y * nn.y + rgb_z * nn.z) * self.intensity
    }
}

/// Relative differences `|bevy − want| / |want|` (RGB lengths) over random
/// points in the volume's box with random unit normals, for three `want`s
/// at each point, all E/π of the runtime's trilinear radiance SH there:
/// `cube` through the non-negative least-squares ambient cube (what the
/// export stores at a voxel: the resampling and RGB9E5 rounding), `ls`
/// through the unconstrained least-squares cube (adds the loss of negative
/// faces), `sh` the SH irradiance itself (adds the ambient cube's basis
/// error). Plus the medians of `|want|` (`cube`) and `|bevy|`.
struct Stats {
    cube: Quantiles,
    ls: Quantiles,
    sh: Quantiles,
    median_want: f32,
    median_bevy: f32,
}

/// Median and 90th percentile of the relative difference, and the
/// relative RMSE `sqrt(Σ|bevy − want|² / Σ|want|²)` (the metric of
/// `probekit sh --compare`).
struct Quantiles {
    median: f32,
    p90: f32,
    rel_rmse: f32,
}

fn median(mut v: Vec<f32>) -> f32 {
    v.sort_by(f32::total_cmp);
    v[v.len() / 2]
}

/// Quantiles of the relative difference of `bevy` from `want`; a floor of
/// 10⁻³ × the median `|want|` keeps a black point from dividing by zero.
fn quantiles(bevy: &[Vec3], want: &[Vec3]) -> Quantiles {
    let floor = 1e-3 * median(want.iter().map(|w| w.length()).collect());
    let mut rel: Vec<f32> = bevy
        .iter()
        .zip(want)
        .map(|(b, w)| (*b - *w).length() / w.length().max(floor))
        .collect();
    rel.sort_by(f32::total_cmp);
    let err: f64 = bevy
        .iter()
        .zip(want)
        .map(|(b, w)| (*b - *w).as_dvec3().length_squared())
        .sum();
    let norm: f64 = want.iter().map(|w| w.as_dvec3().length_squared()).sum();
    Quantiles {
        median: rel[rel.len() / 2],
        p90: rel[rel.len() * 9 / 10],
        rel_rmse: (err / norm).sqrt() as f32,
    }
}

fn compare(volume: &Volume, bevy: &BevyVolume, points: usize) -> Stats {
    let (min, max) = volume.bounds();
    let mut rng = SampleRng::from_state(0x5EED);
    let mut sh = vec![Vec3::ZERO; volume.coeffs_per_sample()];
    let (mut got, mut cube, mut ls, mut exact) = (vec![], vec![], vec![], vec![]);
    for _ in 0..points {
        let p = min + Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * (max - min);
        let n = sample_uniform_sphere(rng.next_2d());
        volume.sample_sh(p, Interp::Trilinear, &mut sh).unwrap();
        got.push(bevy.light(p, n));
        cube.push(AmbientCube::fit_from_sh_nonnegative(&sh).irradiance(n) / PI);
        ls.push(AmbientCube::fit_from_sh(&sh).irradiance(n) / PI);
        exact.push(probekit_sh::irradiance(&sh, n) / PI);
    }
    Stats {
        cube: quantiles(&got, &cube),
        ls: quantiles(&got, &ls),
        sh: quantiles(&got, &exact),
        median_want: median(cube.iter().map(|w| w.length()).collect()),
        median_bevy: median(got.iter().map(|b| b.length()).collect()),
    }
}

/// Bakes `scene` with `bake` options into `dir/name.probes`, exports it for
/// Bevy, and returns the volume, the sidecar and the texture's path.
fn bake_and_export(dir: &Path, scene: &str, name: &str, bake: &[&str]) -> Exported {
    let probes = dir.join(format!("{name}.probes"));
    let mut args = vec!["volume", scene, "-o", probes.to_str().unwrap()];
    args.extend_from_slice(bake);
    let o = run(dir, &args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ktx2 = dir.join(format!("{name}.ktx2"));
    let o = run(
        dir,
        &[
            "export",
            probes.to_str().unwrap(),
            "--format",
            "bevy",
            "-o",
            ktx2.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let sidecar: Value =
        serde_json::from_slice(&std::fs::read(ktx2.with_extension("json")).unwrap()).unwrap();
    let volume = Volume::from_file(&ProbeFile::load(&probes).unwrap()).unwrap();
    (volume, sidecar, ktx2)
}

/// What [`bake_and_export`] returns.
type Exported = (Volume, Value, PathBuf);

/// Compares 4000 random points of `name`'s export and prints its table row.
fn measure(dir: &Path, scene: &str, name: &str, bake: &[&str]) -> (Stats, Exported) {
    let (volume, sidecar, ktx2) = bake_and_export(dir, scene, name, bake);
    let bevy = BevyVolume::load(&ktx2, &sidecar, 1.0);
    let s = compare(&volume, &bevy, 4000);
    let r = &sidecar["resolution"];
    let pct = |x: f32| format!("{:.2} %", 100.0 * x);
    println!(
        "| {name} | {} | {}×{}×{} | {} / {} / {} | {} / {} | {} / {} |",
        volume.sample_count(),
        r[0],
        r[1],
        r[2],
        pct(s.cube.median),
        pct(s.cube.p90),
        pct(s.cube.rel_rmse),
        pct(s.ls.median),
        pct(s.ls.rel_rmse),
        pct(s.sh.median),
        pct(s.sh.rel_rmse),
    );
    (s, (volume, sidecar, ktx2))
}

/// Prints the header of the rows [`measure`] prints.
fn header() {
    println!(
        "| volume | samples | voxels | vs the exported cube: median / p90 / rel. RMSE | \
         vs the least-squares cube: median / rel. RMSE | vs the SH irradiance: median / rel. RMSE |"
    );
}

/// Uniform volumes exported on their probes: Bevy's lookup differs from
/// the ambient cube of the runtime's answer by RGB9E5 rounding and by the
/// non-negative fit not being linear in the SH (a cube fitted between two
/// probes is not quite the blend of theirs): median ≤ 1 % at 8³ probes
/// (just under 1 % at 6³, where the sphere lights vary most between
/// probes); an
/// octree on its finest lattice, and the path-traced demo room, likewise.
#[test]
fn lights_demo_sampled_as_bevy_does_matches_the_runtimes_ambient_cube() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    header();
    let lights = "builtin:lights-demo";
    measure(
        d,
        lights,
        "lights-demo uniform 6³",
        &["--layout", "uniform", "--resolution", "6,6,6"],
    );
    let uniform = &["--layout", "uniform", "--resolution", "8,8,8"];
    let (u, _) = measure(d, lights, "lights-demo uniform 8³", uniform);
    assert!(u.cube.median <= 0.01, "uniform median {}", u.cube.median);
    let (a, (volume, ..)) = measure(d, lights, "lights-demo adaptive", &["--layout", "octree"]);
    assert!(volume.root_grid().is_some());
    assert!(a.cube.median <= 0.01, "adaptive median {}", a.cube.median);
    let (r, _) = measure(
        d,
        "builtin:demo",
        "demo uniform 6³",
        &["--layout", "uniform", "--resolution", "6,6,6"],
    );
    assert!(r.cube.median <= 0.01, "demo median {}", r.cube.median);
}

/// The Cornell box (skipped without `../shared/data`): the same comparison
/// for a uniform and an adaptive bake, and what a Bevy user sees at the
/// default exposure — the sidecar's intensity for it puts probekit's value
/// on screen; intensity 1 there is a thousand times darker (black).
#[test]
fn cornell_box_sampled_as_bevy_does_matches_and_is_lit_at_the_default_exposure() {
    let toml = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/scenes/cornell_box/cornell_box.toml");
    if !toml.exists() {
        eprintln!("skipped: {} is absent", toml.display());
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = toml.to_str().unwrap();
    header();
    let uniform = ["--layout", "uniform", "--resolution", "6,6,6"];
    let (u, (volume, sidecar, ktx2)) = measure(dir.path(), scene, "cornell uniform 6³", &uniform);
    assert!(u.cube.median <= 0.01, "uniform median {}", u.cube.median);
    let (a, _) = measure(
        dir.path(),
        scene,
        "cornell adaptive",
        &["--layout", "octree"],
    );
    assert!(a.cube.median <= 0.01, "adaptive median {}", a.cube.median);
    // On screen (before tone mapping) at Bevy's default exposure, a white
    // diffuse surface shows exposure · light (light includes the intensity).
    let exposure = 2f32.powf(-9.7) / 1.2; // Exposure::default().exposure()
    let recommended = sidecar["intensity_for_bevy_default_exposure"]
        .as_f64()
        .unwrap() as f32;
    for (intensity, lit) in [(recommended, true), (1.0, false)] {
        let bevy = BevyVolume::load(&ktx2, &sidecar, intensity);
        let s = compare(&volume, &bevy, 500);
        let on_screen = s.median_bevy * exposure;
        if lit {
            // probekit's own value, 0.03–2 in the Cornell box.
            assert!(
                (on_screen / s.median_want - 1.0).abs() < 0.02 && on_screen > 0.02,
                "{on_screen}"
            );
        } else {
            assert!(on_screen < 0.002, "{on_screen}");
        }
    }
}

/// The sidecar names both intensities (and no bare `intensity` to mistake
/// for either), the command's line gives the one for the default exposure,
/// and a resolution below 2 voxels on an axis is one line of error with
/// nothing written.
#[test]
fn sidecar_names_both_intensities_and_a_one_voxel_axis_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, sidecar, ktx2) = bake_and_export(
        d,
        "builtin:lights-demo",
        "v",
        &["--layout", "uniform", "--resolution", "3,3,3"],
    );
    assert_eq!(sidecar["intensity_in_scene_units"], 1.0);
    let at_default = sidecar["intensity_for_bevy_default_exposure"]
        .as_f64()
        .unwrap();
    // 1 / Exposure::default().exposure() = 1.2 · 2^9.7.
    assert!(
        (at_default - 1.2 * 2f64.powf(9.7)).abs() < 0.01,
        "{at_default}"
    );
    assert!(sidecar.get("intensity").is_none());
    assert_eq!(
        sidecar["lattice"],
        "the volume's probes (one voxel per probe)"
    );
    let o = run(
        d,
        &["export", "v.probes", "--format", "bevy", "-o", "again.ktx2"],
    );
    let line = String::from_utf8(o.stdout).unwrap();
    assert!(line.contains("998.1 at Bevy's default exposure"), "{line}");
    assert!(ktx2.exists());
    common::fails_one_line(
        d,
        &[
            "export",
            "v.probes",
            "--format",
            "bevy",
            "-o",
            "thin.ktx2",
            "--resolution",
            "1,3,3",
        ],
        "at least 2 voxels per axis",
    );
    assert!(!d.join("thin.ktx2").exists() && !d.join("thin.json").exists());
}
