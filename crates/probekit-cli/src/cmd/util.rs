//! Helpers shared by the probe commands: CSV rows, `x,y,z` arguments,
//! loading scenes and probe files with one-line errors.

use anyhow::{anyhow, bail, Context, Result};
use glam::Vec3;
use probekit::format::ProbeFile;
use probekit::scene::Scene;
use std::path::Path;

/// Reads a CSV of `cols` finite numbers per row (header line optional,
/// blank lines and `#` comments skipped). Errors name the file and line.
pub fn read_csv(path: &Path, cols: usize) -> Result<Vec<Vec<f32>>> {
    let name = path.display();
    let text = std::fs::read_to_string(path).with_context(|| format!("{name}"))?;
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let parsed: Result<Vec<f32>, _> = fields.iter().map(|f| f.parse::<f32>()).collect();
        let row = match parsed {
            Ok(r) => r,
            Err(_) if rows.is_empty() && i == 0 => continue, // header
            Err(_) => bail!("{name}: line {}: expected {cols} numbers", i + 1),
        };
        if row.len() != cols {
            bail!(
                "{name}: line {}: expected {cols} numbers, found {}",
                i + 1,
                row.len()
            );
        }
        if row.iter().any(|v| !v.is_finite()) {
            bail!("{name}: line {}: NaN or infinite value", i + 1);
        }
        rows.push(row);
    }
    if rows.is_empty() {
        bail!("{name}: no rows");
    }
    Ok(rows)
}

/// Comma-separated finite numbers; `None` if one is not.
pub fn finite_list(s: &str) -> Option<Vec<f32>> {
    let v: Vec<f32> = (s.split(',').map(|f| f.trim().parse().ok())).collect::<Option<_>>()?;
    v.iter().all(|x| x.is_finite()).then_some(v)
}

/// Parses `x,y,z` (finite).
pub fn parse_vec3(s: &str, what: &str) -> Result<Vec3> {
    match finite_list(s) {
        Some(v) if v.len() == 3 => Ok(Vec3::new(v[0], v[1], v[2])),
        _ => bail!("{what} {s}: expected three finite numbers x,y,z"),
    }
}

/// The default output file of a command run on `scene`: its name without
/// folder and extension (`builtin:NAME` → `NAME`), with `ext`, in the
/// current folder.
pub fn output_named_after(scene: &str, ext: &str) -> std::path::PathBuf {
    let stem = match scene.strip_prefix("builtin:") {
        Some(name) => name.to_string(),
        None => Path::new(scene)
            .file_stem()
            .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned()),
    };
    std::path::PathBuf::from(format!("{stem}.{ext}"))
}

/// Loads a scene (path or `builtin:demo`), printing its warnings to stderr.
pub fn load_scene(name: &str) -> Result<Scene> {
    let scene = Scene::load(name).with_context(|| name.to_string())?;
    for w in &scene.warnings {
        eprintln!("warning: {name}: {w}");
    }
    Ok(scene)
}

/// The scene to use with a probe file: `given` (`--scene`), else the scene
/// the file recorded when it was baked. Refuses one whose lighting hash
/// differs from the file's ([`probekit::format::check_scene`]) unless
/// `allow_other`, then only warns. Returns the scene and the name it was
/// loaded by.
pub fn scene_for_file(
    file: &ProbeFile,
    file_path: &Path,
    given: Option<&str>,
    allow_other: bool,
) -> Result<(Scene, String)> {
    let file_name = file_path.display().to_string();
    let name = match given {
        Some(g) => g.to_string(),
        None => probekit::format::recorded_scene(file.metadata()).ok_or_else(|| {
            anyhow!("{file_name}: the file records no scene it was baked from; give --scene")
        })?,
    };
    let scene = Scene::load(&name).with_context(|| match given {
        Some(_) => name.clone(),
        None => format!("{name} (the scene {file_name} was baked from; give --scene if it moved)"),
    })?;
    for w in &scene.warnings {
        eprintln!("warning: {name}: {w}");
    }
    if let Err(e) = probekit::format::check_scene(file.metadata(), &file_name, &scene, &name) {
        if !allow_other {
            return Err(e.into());
        }
        eprintln!("warning: {e}");
    }
    Ok((scene, name))
}

/// Checks, before a command's long work, that each of its output files
/// can be written ([`probekit::format::check_writable`]): a mistyped folder
/// then costs nothing rather than the bake. `None`s are skipped.
pub fn check_outputs(paths: &[Option<&Path>]) -> Result<()> {
    for p in paths.iter().flatten() {
        probekit::format::check_writable(p).with_context(|| p.display().to_string())?;
    }
    Ok(())
}

/// Loads a `.probes` file.
pub fn load_probes(path: &Path) -> Result<ProbeFile> {
    ProbeFile::load(path).with_context(|| path.display().to_string())
}

/// `[r, g, b]` for JSON.
pub fn rgb(v: Vec3) -> [f32; 3] {
    v.to_array()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_vec3_parses_and_rejects() {
        assert_eq!(
            parse_vec3("1,-2, 3.5", "--at").unwrap(),
            Vec3::new(1.0, -2.0, 3.5)
        );
        for bad in ["1,2", "1,2,x", "1,2,inf", "1,2,3,4"] {
            let e = parse_vec3(bad, "--at").unwrap_err().to_string();
            assert!(e.starts_with("--at ") && e.contains("x,y,z"), "{e}");
        }
    }
}
