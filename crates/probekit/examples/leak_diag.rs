//! Splits each leak of a baked cloud into SH truncation, Monte Carlo noise
//! and interpolation (the leak test and the points of `probekit eval`).
//!
//! ```text
//! cargo run --release -p probekit --example leak_diag -- demo.probes [SCENE] \
//!     [--points 400] [--seeds 1] [--hi 16384] [--all]
//! ```
//!
//! For every leak point (only those in regions unless `--all`) it prints:
//! (a) ground truth, (b) the file's interpolation, (c) a `--hi`-sample
//! capture AT the point evaluated for its normal (pure SH truncation error),
//! (d) the same tetrahedron's probes recaptured at `--hi` samples and
//! interpolated with the same weights (interpolation error without noise),
//! (e) the file's probes blended with an exact segment test at the point in
//! place of the cell visibility (what a finer lattice could reach at most),
//! plus each vertex: weight, irradiance in the file and at `--hi`, and
//! whether the segment point→vertex is blocked by geometry. A last line
//! counts the leaks shown and those (e) leaves.
//!
//! The file is queried through [`probekit_runtime::Probes`] (the weights
//! before visibility: the same file loaded with every blend factor off,
//! `LoadOptions::blend`); the `--hi` captures use the capture settings the
//! file records (the scene's for a file without a record).

use glam::Vec3;
use probekit::capture::{Baker, CaptureSettings};
use probekit::eval::{is_leak, leak_threshold};
use probekit::pipeline::recorded_capture;
use probekit::scene::Scene;
use probekit::trace::free_space::segment_clear;
use probekit_runtime::{LoadOptions, ObjectState, ProbeFile, Probes};
use probekit_sh::ShRgb;
use std::error::Error;

mod common;
use common::{arg, eval_seeds, EvalSet};

fn lum(v: Vec3) -> f32 {
    probekit_sh::LUMINANCE.dot(v)
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let file_name = args
        .first()
        .cloned()
        .unwrap_or_else(|| "demo.probes".into());
    let scene_name = args
        .get(1)
        .filter(|a| !a.starts_with("--"))
        .cloned()
        .unwrap_or_else(|| "builtin:demo".into());
    let npts: usize = arg(&args, "--points", 400);
    let hi: u32 = arg(&args, "--hi", 16384);
    let all = args.iter().any(|a| a == "--all");
    let seeds: String = arg(&args, "--seeds", "1".to_string());
    let scene = Scene::load(std::path::Path::new(&scene_name))?;
    let baker = Baker::new(&scene)?;
    let file = ProbeFile::load(&file_name)?;
    let probes = Probes::from_file(&file, LoadOptions::default())?;
    let cloud = probes.cloud().ok_or("not a cloud")?;
    // The same file blended with its barycentric weights alone.
    let mut plain = LoadOptions::default();
    plain.blend.distance_moments = Some(false);
    plain.blend.cell_visibility = Some(false);
    plain.blend.probe_weights = Some(false);
    plain.blend.brightness_exponent = Some(0.0);
    plain.blend.directional_exponent = Some(0.0);
    let barycentric = Probes::from_file(&file, plain)?;
    let EvalSet {
        points: pts,
        truth,
        mean,
    } = eval_seeds(&baker, &scene, npts, &seeds)?;
    let mut state = ObjectState::new();
    let predicted = pts
        .iter()
        .map(|p| {
            Ok(Vec3::from(
                probes.irradiance(&mut state, p.position, p.normal)?,
            ))
        })
        .collect::<Result<Vec<_>, Box<dyn Error>>>()?;
    // The file's own capture at `--hi` samples.
    let mut s = recorded_capture(&file).unwrap_or_else(|| CaptureSettings::from_scene(&scene));
    s.samples = hi;
    let order = probes.order() as usize;
    let sh_of = |i: usize| ShRgb::from_coeffs(cloud.probe_sh(i).to_vec()).expect("order²");
    println!(
        "mean truth luminance {mean:.4}; leak floor 0.01·mean = {:.4}",
        0.01 * mean
    );
    let (mut shown, mut exact_left) = (0usize, 0usize);
    for (i, p) in pts.iter().enumerate() {
        let (t, e) = (truth[i], predicted[i]);
        if !is_leak(e, t, mean) {
            continue;
        }
        let regions = scene.region_names_at(p.position);
        if regions.is_empty() && !all {
            continue;
        }
        let at = baker.capture(p.position, 9_000_000 + i as u64, &s)?;
        let q = probes.query(&mut state, p.position)?;
        let w = &q.weights[..4];
        // The same cell's barycentric (or outer-cell) weights before visibility.
        let b = barycentric.query(&mut state, p.position)?;
        let bary = &b.weights[..4];
        let verts: Vec<usize> = q.probes[..4].iter().map(|&k| k as usize).collect();
        let vpos: Vec<Vec3> = verts.iter().map(|&k| file.positions()[k]).collect();
        let caps = baker.capture_many(&vpos, 9_100_000 + 4 * i, &s, &|_, _| {})?;
        let mut d = ShRgb::zeros(order);
        for k in 0..4 {
            if w[k] != 0.0 {
                d.add_scaled(&caps[k].sh, w[k]);
            }
        }
        // (e): the file's probes blended with the cell visibility replaced
        // by an exact segment test at the point (moments kept).
        let mut ex = ShRgb::zeros(order);
        let mut ex_sum = 0.0;
        for k in 0..4 {
            let vis = cloud
                .visibility_maps()
                .map_or(1.0, |m| m.visibility(verts[k], vpos[k], p.position));
            if bary[k] > 0.0 && segment_clear(baker.tracer(), vpos[k], p.position) {
                ex.add_scaled(&sh_of(verts[k]), bary[k] * vis);
                ex_sum += bary[k] * vis;
            }
        }
        let exact = (ex_sum > 0.0).then(|| {
            ex.scale(1.0 / ex_sum);
            ex.irradiance(p.normal)
        });
        // No visible probe counts as a leak (nothing to blend).
        let exact_leaks = match exact {
            Some(e) => is_leak(e, t, mean),
            None => true,
        };
        shown += 1;
        exact_left += usize::from(exact_leaks);
        let c = at.sh.irradiance(p.normal);
        let dd = d.irradiance(p.normal);
        println!(
            "point {i} {:?} p={:.3?} n={:.2?}\n  (a) truth {:.4} (b) file interp {:.4} (c) SH@point {hi} {:.4} (d) hi-sample interp {:.4} (e) exact-visibility interp {}   [leak threshold {:.4}]",
            regions,
            p.position,
            p.normal,
            lum(t),
            lum(e),
            lum(c),
            lum(dd),
            exact.map_or("none visible".to_string(), |e| format!(
                "{:.4}{}",
                lum(e),
                if exact_leaks { " (leaks)" } else { "" }
            )),
            leak_threshold(t, mean)
        );
        for k in 0..4 {
            if w[k] == 0.0 {
                continue;
            }
            let q = vpos[k];
            let len = (q - p.position).length();
            let blocked = !segment_clear(baker.tracer(), p.position, q);
            let vis = cloud
                .visibility_maps()
                .map_or(1.0, |m| m.visibility(verts[k], q, p.position));
            println!(
                "    v{} {:.3?} w={:.3} (bary {:.3} vis {:.2e}) dist={:.2} E_file={:.4} E_hi={:.4} blocked={}",
                verts[k],
                q,
                w[k],
                bary[k],
                vis,
                len,
                lum(sh_of(verts[k]).irradiance(p.normal)),
                lum(caps[k].sh.irradiance(p.normal)),
                blocked
            );
        }
    }
    println!("{shown} leaks shown; {exact_left} of them leak with exact visibility (e)");
    Ok(())
}
