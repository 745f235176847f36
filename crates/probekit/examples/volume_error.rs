//! Error against memory for irradiance volumes on `builtin:lights-demo`:
//! relative RMS irradiance error over random points and normals (reference:
//! the analytic sphere-light SH at the point), against the `.probes` bytes.
//! `cargo run --release -p probekit --example volume_error [-- --plot FILE.png]`
//! (with `--plot`, also a line chart of error against bytes).
//!
//! Each volume is baked as `probekit volume builtin:lights-demo` bakes it
//! ([`probekit::pipeline::bake_volume_from`] with a recipe: closed-form
//! gradients, samples below validity 0.5 dilated; the file records its
//! recipe) and queried through [`probekit_runtime::Probes`].

use glam::Vec3;
use probekit::pipeline::bake_volume_from;
use probekit::recipe::{BakeRecord, GradientModeName, Recipe, VolumeLayout};
use probekit::volume::{Interp, LightsDemo, VolumeSource};
use probekit_runtime::{LoadOptions, ObjectState, ProbeFile, Probes};

/// The source's name, as `probekit volume` records it.
const LIGHTS_DEMO: &str = "builtin:lights-demo";

/// The volume `layout` over the demo's box with closed-form gradients,
/// baked by the pipeline.
fn bake(demo: &LightsDemo, layout: VolumeLayout) -> ProbeFile {
    let (min, max) = LightsDemo::demo_box();
    let mut recipe = Recipe {
        bake_box: Some([min.to_array(), max.to_array()]),
        ..Recipe::default()
    };
    recipe.capture.order = demo.order;
    recipe.volume.layout = layout;
    recipe.volume.gradients.mode = GradientModeName::Analytic;
    recipe.validate().expect("a valid recipe");
    let record = BakeRecord::without_scene(LIGHTS_DEMO, recipe.clone());
    bake_volume_from(demo, &recipe.recorded_box(), &recipe, 0.5, record)
        .expect("bake")
        .0
}

fn main() {
    let demo = LightsDemo::demo(3);
    let (min, max) = LightsDemo::demo_box();
    let mut s = 12345u64;
    let mut rnd = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut pts = Vec::new();
    let mut normals = Vec::new();
    while pts.len() < 4000 {
        let p = min + Vec3::new(rnd(), rnd(), rnd()) * (max - min);
        // Skip points inside the slab and inside the lights (not lit space).
        if (p.x > 0.9 && p.x < 1.1)
            || demo
                .lights
                .iter()
                .any(|l| (p - l.center).length() < l.radius * 1.5)
        {
            continue;
        }
        let n = Vec3::new(rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0);
        if n.length() < 0.1 || n.length() > 1.0 {
            continue;
        }
        pts.push(p);
        normals.push(n.normalize());
    }
    let reference: Vec<Vec3> = pts
        .iter()
        .zip(&normals)
        .map(|(p, n)| probekit::sh::irradiance(demo.capture(&[*p])[0].sh.coeffs(), *n))
        .collect();
    let denom: f64 = reference
        .iter()
        .map(|e| e.length_squared() as f64)
        .sum::<f64>();
    let mut rows = Vec::new();
    for r in [5u32, 9, 13, 17] {
        let layout = VolumeLayout::Uniform {
            cell: None,
            resolution: Some([r; 3]),
        };
        rows.push((format!("uniform {r}³"), bake(&demo, layout)));
    }
    for (a, b, tol) in [(1u32, 4u32, 0.25f32), (2, 5, 0.25), (2, 5, 0.1)] {
        let layout = VolumeLayout::Octree {
            min_depth: a,
            max_depth: b,
            roots: None,
            tolerance: tol,
            prune: tol * 0.4,
            relative_floor: 0.0,
            geometry: true,
            geometry_depth: u32::MAX,
            emitter_depth: Some(0),
            noise_k: 0.0,
            balance: false,
            depth_factor: 1.0,
            gradient_threshold: None,
        };
        rows.push((format!("adaptive {a}..{b} tol {tol}"), bake(&demo, layout)));
    }
    println!("| volume | samples | bytes (no gradients) | bytes (with gradients) | trilinear | Taylor | tricubic |");
    println!("|---|---|---|---|---|---|---|");
    let mut series: Vec<(String, Vec<(f64, f64)>)> = [
        "uniform trilinear",
        "uniform tricubic (+gradients)",
        "adaptive trilinear",
        "adaptive tricubic (+gradients)",
    ]
    .iter()
    .map(|s| (s.to_string(), Vec::new()))
    .collect();
    for (name, f) in rows {
        let with: u64 = f.bytes_by_section().unwrap().values().sum();
        let mut nog = f.clone();
        if let Some(v) = nog.as_volume_mut() {
            v.gradients = None;
        }
        let without: u64 = nog.bytes_by_section().unwrap().values().sum();
        let mut errs = Vec::new();
        for interp in [Interp::Trilinear, Interp::Taylor, Interp::Tricubic] {
            let mut options = LoadOptions::default();
            options.interpolation = interp;
            let v = Probes::from_file(&f, options).unwrap();
            let mut state = ObjectState::new();
            let num: f64 = pts
                .iter()
                .zip(&normals)
                .zip(&reference)
                .map(|((p, n), e)| {
                    let got = Vec3::from(v.irradiance(&mut state, *p, *n).unwrap());
                    (got - *e).length_squared() as f64
                })
                .sum();
            errs.push((num / denom).sqrt());
        }
        let base = if name.starts_with("uniform") { 0 } else { 2 };
        series[base].1.push((without as f64, errs[0]));
        series[base + 1].1.push((with as f64, errs[2]));
        println!(
            "| {name} | {} | {without} | {with} | {:.4} | {:.4} | {:.4} |",
            f.probe_count(),
            errs[0],
            errs[1],
            errs[2]
        );
    }
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--plot") {
        let path = args.get(i + 1).expect("--plot FILE.png");
        probekit::plot::line_chart(
            path,
            "Volume error vs memory (lights-demo)",
            &series,
            "bytes of the .probes file",
            "relative RMS irradiance error",
            true,
        )
        .expect("write plot");
    }
}
