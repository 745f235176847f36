//! `probekit sh ENV [--order N] [--json] [--compare] [--plot FILE.png]`.
//!
//! Prints the radiance SH of an environment (an equirect `.hdr`/`.exr`, a
//! cubemap folder, or `builtin:sky`), or with `--compare` the relative
//! irradiance RMSE of each diffuse basis against the brute-force cosine
//! convolution of the map (`probekit::sh::compare`).

use anyhow::{bail, Result};
use clap::Args;
use probekit::env::{Cubemap, EnvMap, Environment};
use probekit::sh::compare::{compare_bases, BasisComparison, MIN_NORMALS};
use probekit::sh::ShRgb;
use std::path::{Path, PathBuf};

/// Arguments of `probekit sh`.
#[derive(Debug, Args)]
pub struct ShArgs {
    /// Environment: an equirect .hdr/.exr (three.js layout), a cubemap folder
    /// (px/nx/py/ny/pz/nz .hdr|.exr|.png), or `builtin:sky`.
    pub env: PathBuf,
    /// Number of SH bands (1..=8; 3 = L2).
    #[arg(long, default_value_t = 3)]
    pub order: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Compare diffuse bases (relative irradiance RMSE over 4096 normals).
    #[arg(long)]
    pub compare: bool,
    /// Also write a bar chart of the comparison to this PNG file.
    #[arg(long, value_name = "FILE.png")]
    pub plot: Option<PathBuf>,
}

/// An environment as loaded: cubemap folders stay cubes so projection uses
/// exact cube-texel solid angles.
enum Loaded {
    Equirect(EnvMap),
    Cube(Cubemap),
}

impl Loaded {
    fn open(path: &Path) -> Result<Self> {
        Ok(if path.is_dir() {
            Loaded::Cube(Cubemap::load_dir(path)?)
        } else {
            Loaded::Equirect(EnvMap::load(path)?)
        })
    }

    fn env(&self) -> &dyn Environment {
        match self {
            Loaded::Equirect(m) => m,
            Loaded::Cube(c) => c,
        }
    }
}

/// Runs `probekit sh`.
pub fn run(args: &ShArgs) -> Result<()> {
    if !(1..=probekit::sh::MAX_ORDER).contains(&args.order) {
        bail!(
            "--order {}: must be between 1 and {}",
            args.order,
            probekit::sh::MAX_ORDER
        );
    }
    let loaded = Loaded::open(&args.env)?;
    let env = loaded.env();
    if args.compare || args.plot.is_some() {
        let cmp = compare_bases(env, MIN_NORMALS);
        if let Some(plot) = &args.plot {
            write_plot(plot, &args.env, &cmp)?;
        }
        if args.compare {
            if args.json {
                println!("{}", serde_json::to_string(&cmp)?);
            } else {
                print!("{}", cmp.table());
            }
            return Ok(());
        }
    }
    let sh = env.project(args.order);
    if args.json {
        println!("{}", coefficients_json(&sh)?);
    } else {
        print!("{}", coefficients_table(&sh));
    }
    Ok(())
}

/// `{"order":N,"coefficients":[[r,g,b],...]}`.
fn coefficients_json(sh: &ShRgb) -> Result<String> {
    #[derive(serde::Serialize)]
    struct Out {
        order: usize,
        coefficients: Vec<[f32; 3]>,
    }
    Ok(serde_json::to_string(&Out {
        order: sh.order(),
        coefficients: sh.coeffs().iter().map(|c| c.to_array()).collect(),
    })?)
}

fn coefficients_table(sh: &ShRgb) -> String {
    let mut s = format!(
        "{:>2} {:>3} {:>13} {:>13} {:>13}\n",
        "l", "m", "R", "G", "B"
    );
    for l in 0..sh.order() {
        for m in -(l as i32)..=(l as i32) {
            let c = sh.coeffs()[probekit::sh::index(l, m)];
            s += &format!(
                "{l:>2} {m:>3} {:>13.6e} {:>13.6e} {:>13.6e}\n",
                c.x, c.y, c.z
            );
        }
    }
    s
}

fn write_plot(plot: &Path, env: &Path, cmp: &BasisComparison) -> Result<()> {
    let rows = cmp.rows();
    let labels: Vec<String> = rows.iter().map(|r| r.key.to_string()).collect();
    let values: Vec<f64> = rows
        .iter()
        .map(|r| r.error.unwrap_or(f64::NAN) * 100.0)
        .collect();
    let name = env
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| env.display().to_string());
    probekit::plot::bar_chart(
        plot,
        &format!("Irradiance error per basis: {name}"),
        &labels,
        &values,
        "relative RMSE (%)",
    )?;
    Ok(())
}
