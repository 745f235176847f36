//! `PkVolumeGrid`, `pk_sh_coeffs` and `pk_sh_gradients`: a uniform volume
//! for `pk_volume_sample` of `shaders/probekit_buffers.wgsl`.

use super::{check_size, LayoutError};
use probekit_runtime::format::VolumeStructure;
use probekit_runtime::{ProbeFile, Volume};

/// Floats per probe in `pk_sh_coeffs`: 9 RGB coefficients (L2; an L1
/// volume's band 2 is zero, higher bands are dropped).
pub const VOLUME_PROBE_FLOATS: usize = 27;
/// Floats per probe in `pk_sh_gradients`: 3 axes × 9 RGB coefficients.
pub const VOLUME_GRADIENT_FLOATS: usize = 81;

/// A uniform volume packed for the shaders.
#[derive(Clone, Debug, PartialEq)]
pub struct PackedVolumeGrid {
    /// The `PkVolumeGrid` uniform (48 bytes: min @0, max @16, resolution
    /// @32, gradient_coeffs @44).
    pub grid: [u8; 48],
    /// `pk_sh_coeffs`: probe `p`, coefficient `i`, channel `ch` at
    /// `p·27 + i·3 + ch`.
    pub coefficients: Vec<f32>,
    /// `pk_sh_gradients`: probe `p`, axis `a`, coefficient `i`, channel
    /// `ch` at `p·81 + a·27 + i·3 + ch` (per metre; zero past the stored
    /// gradient order; one zero probe when the volume has none, so the
    /// binding is never empty).
    pub gradients: Vec<f32>,
}

/// Packs a uniform volume file (one the runtime's [`Volume::from_file`]
/// accepts, with a `GRID` section) for `pk_volume_sample`.
pub fn pack_volume_grid(file: &ProbeFile) -> Result<PackedVolumeGrid, LayoutError> {
    Volume::from_file(file)?;
    let file = file.as_volume().ok_or(LayoutError::NotAGrid)?;
    let VolumeStructure::Uniform(g) = &file.structure else {
        return Err(LayoutError::NotAGrid);
    };
    let c = &file.probes.coefficients;
    let n = (c.order * c.order) as usize;
    let count = file.probes.positions.len();
    check_size("volume gradient", count * VOLUME_GRADIENT_FLOATS)?;
    let coeffs = c.to_f32()?;
    let mut coefficients = vec![0.0f32; count * VOLUME_PROBE_FLOATS];
    for p in 0..count {
        for i in 0..n.min(9) {
            let c = coeffs[p * n + i].to_array();
            coefficients[p * VOLUME_PROBE_FLOATS + 3 * i..][..3].copy_from_slice(&c);
        }
    }
    let mut gradient_coeffs = 0;
    let mut gradients = vec![0.0f32; count.max(1) * VOLUME_GRADIENT_FLOATS];
    if let Some(gr) = &file.gradients {
        let gn = (gr.order * gr.order) as usize;
        gradient_coeffs = gn.min(9) as u32;
        for p in 0..count {
            for a in 0..3 {
                for i in 0..gn.min(9) {
                    let c = gr.data[(p * 3 + a) * gn + i].to_array();
                    gradients[p * VOLUME_GRADIENT_FLOATS + 27 * a + 3 * i..][..3]
                        .copy_from_slice(&c);
                }
            }
        }
    }
    let mut grid = [0u8; 48];
    for (k, x) in g.min.to_array().iter().enumerate() {
        grid[4 * k..4 * k + 4].copy_from_slice(&x.to_le_bytes());
    }
    for (k, x) in g.max.to_array().iter().enumerate() {
        grid[16 + 4 * k..20 + 4 * k].copy_from_slice(&x.to_le_bytes());
    }
    for (k, r) in g.resolution.iter().enumerate() {
        grid[32 + 4 * k..36 + 4 * k].copy_from_slice(&r.to_le_bytes());
    }
    grid[44..48].copy_from_slice(&gradient_coeffs.to_le_bytes());
    Ok(PackedVolumeGrid {
        grid,
        coefficients,
        gradients,
    })
}
