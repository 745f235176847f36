//! `probekit convert PROBES --codec C -o OUT.probes [--json]`: re-encode a
//! file's coefficients, reporting the size change and the irradiance error
//! the codec adds: relative RMSE over probes × 64 Fibonacci normals,
//! `sqrt(Σ|E' − E|²) / sqrt(Σ|E|²)` (RGB), E from the clamped-cosine
//! convolution of the radiance SH before and after.

use super::util::load_probes;
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use probekit::format::{encode_coefficients, write_probe_file, Codec};
use std::path::PathBuf;

/// Arguments of `probekit convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// Input `.probes` file.
    pub probes: PathBuf,
    /// Target codec: f32, f16, l1, zh3 or l2.
    #[arg(long)]
    pub codec: String,
    /// Output file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print `{"bytes_before","bytes_after","rel_rmse"}`.
    #[arg(long)]
    pub json: bool,
}

/// Runs `probekit convert`.
pub fn run(a: &ConvertArgs) -> Result<()> {
    let name = a.probes.display().to_string();
    let codec = Codec::from_name(&a.codec)
        .ok_or_else(|| anyhow!("--codec {}: expected f32, f16, l1, zh3 or l2", a.codec))?;
    let mut file = load_probes(&a.probes)?;
    let before_bytes: u64 = file.bytes_by_section()?.values().sum();
    let Some(probes) = file.probes() else {
        bail!("{name}: a rigs file holds no probe coefficients to convert");
    };
    let order = probes.coefficients.order;
    let n0 = probes.coefficients.coeffs_per_probe();
    let before = probes.coefficients.to_f32().with_context(|| name.clone())?;
    let enc = encode_coefficients(codec, order, &before).with_context(|| name.clone())?;
    let after = enc.to_f32().with_context(|| name.clone())?;
    let n1 = enc.coeffs_per_probe();
    let (mut err, mut norm) = (0.0f64, 0.0f64);
    for (b, c) in before.chunks(n0).zip(after.chunks(n1)) {
        for i in 0..64 {
            let n = probekit_sh::fibonacci_point(i, 64);
            let e0 = probekit_sh::irradiance(b, n);
            let e1 = probekit_sh::irradiance(c, n);
            err += (e1 - e0).length_squared() as f64;
            norm += e0.length_squared() as f64;
        }
    }
    let rel = if norm > 0.0 { (err / norm).sqrt() } else { 0.0 };
    if let Some(p) = file.probes_mut() {
        p.coefficients = enc;
    }
    let out = a.output.display().to_string();
    let after_bytes: u64 = file
        .bytes_by_section()
        .with_context(|| out.clone())?
        .values()
        .sum();
    write_probe_file(&a.output, &file).with_context(|| out.clone())?;
    if a.json {
        println!(
            "{}",
            serde_json::json!({ "bytes_before": before_bytes, "bytes_after": after_bytes, "rel_rmse": rel })
        );
    } else {
        println!("{out}: {before_bytes} → {after_bytes} bytes, irradiance rel. RMSE {rel:.5}");
    }
    Ok(())
}
