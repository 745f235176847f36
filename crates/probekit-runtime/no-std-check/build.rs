//! Writes `$OUT_DIR/grid.probes`, the field of `src/field.rs`, with the std
//! build of probekit-runtime.

#[path = "src/field.rs"]
mod field;

use glam::Vec3;
use probekit_runtime::format::{
    Coefficients, ProbeFile, ProbeSet, VolumeFile, VolumeGrid, VolumeStructure,
};
use std::f32::consts::PI;

fn main() {
    println!("cargo:rerun-if-changed=src/field.rs");
    let (min, max) = (Vec3::from(field::MIN), Vec3::from(field::MAX));
    let [rx, ry, rz] = field::RESOLUTION;
    let (mut positions, mut coeffs) = (Vec::new(), Vec::new());
    // Probe (i, j, k) at index i + rx·(j + ry·k).
    for k in 0..rz {
        for j in 0..ry {
            for i in 0..rx {
                let t = Vec3::new(i as f32, j as f32, k as f32)
                    / Vec3::new(rx as f32 - 1.0, ry as f32 - 1.0, rz as f32 - 1.0);
                let p = min + (max - min) * t;
                // Radiance SH of a + b·ω_y: c₀₀ = √(4π)·a (Y₀₀ = 1/√(4π)) and
                // c₁,₋₁ = −√(4π/3)·b (Y₁,₋₁ = −√(3/4π)·y, ∫ y² dω = 4π/3).
                let a = Vec3::from(field::uniform(p.to_array()));
                let b = Vec3::from(field::UP_GAIN);
                coeffs.extend([
                    a * (4.0 * PI).sqrt(),
                    -b * (4.0 * PI / 3.0).sqrt(),
                    Vec3::ZERO,
                    Vec3::ZERO,
                ]);
                positions.push(p);
            }
        }
    }
    let coefficients = Coefficients::from_f32(2, &coeffs).expect("order-2 coefficients");
    let file = ProbeFile::Volume(VolumeFile::new(
        ProbeSet::new(positions, coefficients),
        VolumeStructure::Uniform(VolumeGrid {
            min,
            max,
            resolution: field::RESOLUTION,
        }),
    ));
    let bytes = file.to_bytes().expect("a valid volume file");
    let out = std::path::PathBuf::from(std::env::var_os("OUT_DIR").expect("OUT_DIR"));
    std::fs::write(out.join("grid.probes"), bytes).expect("write grid.probes");
}
