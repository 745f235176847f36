//! `probekit export VOLUME --format ktx2|bevy -o OUT [--encoding f16|quantized]
//! [--layout auto|bricks|dense] [--resolution X,Y,Z]`.
//!
//! `ktx2`: a directory of KTX2 3D textures plus `volume.json`
//! (`probekit::volume::export`); an octree exports as a brick atlas when
//! that is smaller than its dense finest-level lattice. `bevy`: one `.ktx2` for Bevy's
//! `IrradianceVolume` plus `OUT.json` with the `LightProbe` transform and the
//! intensity for Bevy's default exposure (docs/bevy.md).

use anyhow::{bail, Context, Result};
use clap::Args;
use probekit::format::{write_atomic, ProbeFile};
use probekit::volume::export::{
    export_auto, export_bevy, export_bricks, export_ktx2, write_ktx2_export, Ktx2Encoding,
};
use probekit::volume::Volume;
use std::path::PathBuf;

/// Arguments of `probekit export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// A volume `.probes` file.
    pub volume: PathBuf,
    /// `ktx2` (directory) or `bevy` (one .ktx2 file).
    #[arg(long)]
    pub format: String,
    /// Output directory (ktx2) or file (bevy).
    #[arg(short, long)]
    pub output: PathBuf,
    /// `f16` (default) or `quantized`; ktx2 only.
    #[arg(long)]
    pub encoding: Option<String>,
    /// `bricks` (an octree as a brick atlas plus indirection texture),
    /// `dense` (resampled at its finest level) or `auto` (the smaller of
    /// the two for an octree, the default; a uniform volume is always
    /// dense); ktx2 only.
    #[arg(long)]
    pub layout: Option<String>,
    /// Voxels per axis `X,Y,Z`, at least 2 each (bevy only; default one
    /// voxel per probe of a uniform volume, or an octree's finest lattice,
    /// `roots·2^depth + 1`, within 2^21 voxels).
    #[arg(long, value_delimiter = ',')]
    pub resolution: Option<Vec<u32>>,
}

/// Runs `probekit export`.
pub fn run(a: &ExportArgs) -> Result<()> {
    let name = a.volume.display().to_string();
    let file = ProbeFile::load(&a.volume).with_context(|| name.clone())?;
    // Each option belongs to one output: given with another, an error
    // rather than ignored.
    let is_cloud = file.as_cloud().is_some_and(|c| c.tetrahedra.is_some());
    let kind = if is_cloud {
        "a probe cloud's json/csv"
    } else {
        a.format.as_str()
    };
    for (given, flag, applies) in [
        (a.encoding.is_some(), "--encoding", "ktx2"),
        (a.layout.is_some(), "--layout", "ktx2"),
        (a.resolution.is_some(), "--resolution", "bevy"),
    ] {
        if given && kind != applies {
            bail!("{name}: {flag} applies to a volume's --format {applies}, not to {kind} export");
        }
    }
    if is_cloud {
        return export_cloud(a, &file);
    }
    let v = Volume::from_file(&file).with_context(|| name.clone())?;
    match a.format.as_str() {
        "ktx2" => {
            let enc = match a.encoding.as_deref().unwrap_or("f16") {
                "f16" => Ktx2Encoding::F16,
                "quantized" => Ktx2Encoding::Quantized,
                o => bail!("{name}: --encoding {o}: expected f16 or quantized"),
            };
            let ex = match a.layout.as_deref().unwrap_or("auto") {
                "auto" => export_auto(&v, enc),
                "bricks" => export_bricks(&v, enc),
                "dense" => export_ktx2(&v, enc, None),
                o => bail!("{name}: --layout {o}: expected auto, bricks or dense"),
            }
            .with_context(|| name.clone())?;
            write_ktx2_export(&ex, &a.output).with_context(|| a.output.display().to_string())?;
            println!(
                "{}: {} textures + volume.json",
                a.output.display(),
                ex.textures.len()
            );
        }
        "bevy" => {
            let res = match &a.resolution {
                Some(r) if r.len() == 3 => Some([r[0], r[1], r[2]]),
                Some(_) => bail!("{name}: --resolution needs 3 numbers X,Y,Z"),
                None => None,
            };
            let ex = export_bevy(&v, res).with_context(|| name.clone())?;
            let out = a.output.display().to_string();
            write_atomic(&a.output, &ex.texture.to_bytes()).with_context(|| out.clone())?;
            let side = a.output.with_extension("json");
            let text = serde_json::to_string_pretty(&ex.sidecar).expect("JSON value");
            write_atomic(&side, text.as_bytes()).with_context(|| side.display().to_string())?;
            println!(
                "{out}: Bevy irradiance volume {:?} voxels on {}; LightProbe transform and \
                 intensity ({} at Bevy's default exposure) in {}",
                ex.resolution,
                ex.lattice.describe(),
                ex.sidecar["intensity_for_bevy_default_exposure"],
                side.display()
            );
        }
        o => bail!("{name}: --format {o}: expected ktx2 or bevy"),
    }
    Ok(())
}

/// How a cloud lights points beyond its probes' convex hull, as the JSON
/// export states it beside the hull faces.
const OUTER_RULE: &str = "a point outside the convex hull of the probes takes the blend of the \
    hull face holding its closest hull point, with that point's barycentric weights in the face \
    (continuous across the hull)";

/// Clouds: `--format json` writes `{"probes":[{"position":[x,y,z],
/// "sh":[[r,g,b],...]}],"tetrahedra":[[a,b,c,d],...],"outer_cells":
/// {"rule":..., "hull_faces":[[a,b,c],...]}}` (the hull faces counter-clockwise
/// seen from outside, from which points beyond the hull are lit:
/// [`probekit_runtime::cloud::Location::Outside`]); `--format csv` a header
/// `x,y,z,c0_r,c0_g,c0_b,...` and one row per probe (radiance SH).
fn export_cloud(a: &ExportArgs, file: &ProbeFile) -> Result<()> {
    let name = a.volume.display().to_string();
    let Some(cloud_file) = file.as_cloud() else {
        bail!("{name}: not a probe cloud");
    };
    let c = &cloud_file.probes.coefficients;
    let coeffs = c.to_f32().with_context(|| name.clone())?;
    let n = c.coeffs_per_probe();
    let out = a.output.display().to_string();
    let text = match a.format.as_str() {
        "json" => {
            let probes: Vec<serde_json::Value> = cloud_file
                .probes
                .positions
                .iter()
                .zip(coeffs.chunks(n))
                .map(|(p, c)| {
                    let sh: Vec<[f32; 3]> = c.iter().map(|v| v.to_array()).collect();
                    serde_json::json!({ "position": p.to_array(), "sh": sh })
                })
                .collect();
            let tets = cloud_file.tetrahedra.as_ref().map(|t| t.vertices.clone());
            let cloud = probekit_runtime::cloud::ProbeCloud::from_file(file)
                .with_context(|| name.clone())?;
            let mesh = cloud.mesh();
            let hull: Vec<[u32; 3]> = (0..mesh.hull_face_count() as u32)
                .filter_map(|f| mesh.hull_face_probes(f))
                .collect();
            serde_json::json!({
                "probes": probes,
                "tetrahedra": tets,
                "outer_cells": { "rule": OUTER_RULE, "hull_faces": hull },
            })
            .to_string()
        }
        "csv" => {
            let mut s = String::from("x,y,z");
            for k in 0..n {
                s += &format!(",c{k}_r,c{k}_g,c{k}_b");
            }
            s.push('\n');
            for (p, c) in cloud_file.probes.positions.iter().zip(coeffs.chunks(n)) {
                s += &format!("{},{},{}", p.x, p.y, p.z);
                for v in c {
                    s += &format!(",{},{},{}", v.x, v.y, v.z);
                }
                s.push('\n');
            }
            s
        }
        o => bail!("{name}: --format {o}: a probe cloud exports as json or csv"),
    };
    write_atomic(&a.output, text.as_bytes()).with_context(|| out.clone())?;
    println!("{out}: {} probes", file.positions().len());
    Ok(())
}
