//! Which diffuse-lighting basis reproduces an environment's irradiance best?
//!
//! [`compare_bases`] computes, for each basis, the relative RMSE of its
//! reconstructed irradiance against the brute-force cosine convolution of the
//! map ([`reference_irradiance_texels`]) over uniformly spread normals
//! (spherical Fibonacci, [`spherical_fibonacci`]):
//!
//! `rel. RMSE = sqrt(mean |E_approx − E_ref|²) / sqrt(mean |E_ref|²)`,
//! the means running over normals and the three channels.
//!
//! The SH-based bases all start from the map's L2 **radiance** projection
//! with exact texel solid angles (L1 = its first four coefficients). Each
//! basis has one function below (`eval_<key>`).
//!
//! | key | what |
//! |-----|------|
//! | `l1` | L1 SH, clamped-cosine convolution (Ramamoorthi & Hanrahan 2001) |
//! | `l1_geomerics` | L1 with the non-negative Geomerics reconstruction |
//! | `zh3_hallucinated` | ZH3 from L1 with the hallucinated zonal L2 term |
//! | `zh3_shared` | ZH3, one luminance axis shared by the channels |
//! | `zh3_per_channel` | ZH3 with an axis per channel |
//! | `zh3_solved` | ZH3 with the error-minimising axis (luminance weights) |
//! | `l2` | L2 SH, clamped-cosine convolution |
//! | `l2_windowed` | L2 after the window chosen by `choose_window_for` |
//! | `ambient_cube` | least-squares ambient cube fitted to the reference irradiance |

use crate::env::{reference_irradiance_texels, Environment};
use glam::Vec3;
use serde::Serialize;

/// Minimum number of normals the comparison is specified for.
pub const MIN_NORMALS: usize = 4096;

/// Relative irradiance RMSE per basis (`None`/`null` = basis not available in
/// this build). Field order is the JSON key order.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BasisErrors {
    /// L1 SH.
    pub l1: Option<f64>,
    /// L1, Geomerics reconstruction.
    pub l1_geomerics: Option<f64>,
    /// Hallucinated ZH3.
    pub zh3_hallucinated: Option<f64>,
    /// ZH3 with a shared luminance axis.
    pub zh3_shared: Option<f64>,
    /// ZH3 with per-channel axes.
    pub zh3_per_channel: Option<f64>,
    /// ZH3 with the solved axis.
    pub zh3_solved: Option<f64>,
    /// L2 SH.
    pub l2: Option<f64>,
    /// Windowed L2 SH.
    pub l2_windowed: Option<f64>,
    /// Ambient cube.
    pub ambient_cube: Option<f64>,
}

/// Quantized bytes per probe of each basis (same keys as [`BasisErrors`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BasisBytes {
    /// L1 SH.
    pub l1: Option<usize>,
    /// L1, Geomerics reconstruction (stores L1).
    pub l1_geomerics: Option<usize>,
    /// Hallucinated ZH3 (stores L1).
    pub zh3_hallucinated: Option<usize>,
    /// ZH3 with a shared axis.
    pub zh3_shared: Option<usize>,
    /// ZH3 with per-channel axes.
    pub zh3_per_channel: Option<usize>,
    /// ZH3 with the solved axis.
    pub zh3_solved: Option<usize>,
    /// L2 SH.
    pub l2: Option<usize>,
    /// Windowed L2 SH (stores L2).
    pub l2_windowed: Option<usize>,
    /// Ambient cube.
    pub ambient_cube: Option<usize>,
}

/// The window applied for `l2_windowed`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WindowInfo {
    /// Window name, e.g. `"lanczos"`.
    pub kind: String,
    /// Window strength parameter.
    pub strength: f64,
}

/// Result of [`compare_bases`]; serialises to the JSON of `probekit sh --compare --json`:
/// `{"bases":{"l1":e,...},"bytes":{"l1":13,...},"window":{"kind":..,"strength":..}}`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BasisComparison {
    /// Relative irradiance RMSE per basis.
    pub bases: BasisErrors,
    /// Quantized bytes per probe per basis.
    pub bytes: BasisBytes,
    /// The window used for `l2_windowed` (`null` when unavailable).
    pub window: Option<WindowInfo>,
}

/// One row of the comparison table.
#[derive(Clone, Debug, PartialEq)]
pub struct ComparisonRow {
    /// JSON key of the basis.
    pub key: &'static str,
    /// Relative RMSE, if measured.
    pub error: Option<f64>,
    /// Bytes per probe, if known.
    pub bytes: Option<usize>,
}

impl BasisComparison {
    /// The rows in the fixed key order.
    pub fn rows(&self) -> Vec<ComparisonRow> {
        let (e, b) = (&self.bases, &self.bytes);
        let row = |key, error, bytes| ComparisonRow { key, error, bytes };
        vec![
            row("l1", e.l1, b.l1),
            row("l1_geomerics", e.l1_geomerics, b.l1_geomerics),
            row("zh3_hallucinated", e.zh3_hallucinated, b.zh3_hallucinated),
            row("zh3_shared", e.zh3_shared, b.zh3_shared),
            row("zh3_per_channel", e.zh3_per_channel, b.zh3_per_channel),
            row("zh3_solved", e.zh3_solved, b.zh3_solved),
            row("l2", e.l2, b.l2),
            row("l2_windowed", e.l2_windowed, b.l2_windowed),
            row("ambient_cube", e.ambient_cube, b.ambient_cube),
        ]
    }

    /// A readable aligned table (percent errors; `n/a` where not measured).
    pub fn table(&self) -> String {
        let mut s = format!("{:<18} {:>12} {:>7}\n", "basis", "rel. RMSE", "bytes");
        for r in self.rows() {
            let e = r
                .error
                .map(|e| format!("{:.3} %", e * 100.0))
                .unwrap_or_else(|| "n/a".into());
            let b = r
                .bytes
                .map(|b| b.to_string())
                .unwrap_or_else(|| "n/a".into());
            s += &format!("{:<18} {:>12} {:>7}\n", r.key, e, b);
        }
        match &self.window {
            Some(w) => s += &format!("window: {} (strength {})\n", w.kind, w.strength),
            None => s += "window: n/a\n",
        }
        s
    }
}

/// `n` unit vectors spread uniformly over the sphere (spherical Fibonacci
/// lattice: `z_i = 1 − (2i+1)/n`, `φ_i = i·π(3 − √5)`; Swinbank & Purser 2006).
pub fn spherical_fibonacci(n: usize) -> Vec<Vec3> {
    probekit_sh::fibonacci_sphere(n)
}

/// `sqrt(mean |a − r|²) / sqrt(mean |r|²)` over all entries and channels
/// (`None` when the reference is all zero or the lengths differ).
pub fn relative_rmse(approx: &[Vec3], reference: &[Vec3]) -> Option<f64> {
    if approx.len() != reference.len() || reference.is_empty() {
        return None;
    }
    let mut num = 0.0f64;
    let mut den = 0.0f64;
    for (a, r) in approx.iter().zip(reference) {
        num += (*a - *r).as_dvec3().length_squared();
        den += r.as_dvec3().length_squared();
    }
    (den > 0.0).then(|| (num / den).sqrt())
}

/// Everything a basis needs: the projected radiance SH, the normals and the
/// reference irradiance at them (over [`Environment::reference_texels`]: maps
/// wider than 256 texels are 2×2-averaged first, < 0.1 % change, see
/// [`crate::env::project::REFERENCE_MAX_WIDTH`]).
#[derive(Clone, Debug)]
pub struct ComparisonInputs {
    /// L1 radiance SH (first four coefficients of `l2`).
    pub l1: [Vec3; 4],
    /// L2 radiance SH of the map.
    pub l2: [Vec3; 9],
    /// The evaluation normals.
    pub normals: Vec<Vec3>,
    /// Brute-force irradiance at each normal.
    pub reference: Vec<Vec3>,
}

impl ComparisonInputs {
    /// Projects `env` to L2 and computes the reference irradiance at `normals`
    /// spherical-Fibonacci normals.
    pub fn new<E: Environment + ?Sized>(env: &E, normals: usize) -> Self {
        let sh = env.project(3);
        let l2: [Vec3; 9] = sh.coeffs().try_into().expect("order 3 has 9 coefficients");
        let l1 = [l2[0], l2[1], l2[2], l2[3]];
        let normals = spherical_fibonacci(normals);
        let reference = reference_irradiance_texels(&env.reference_texels(), &normals);
        Self {
            l1,
            l2,
            normals,
            reference,
        }
    }

    fn map(&self, f: impl Fn(Vec3) -> Vec3) -> Vec<Vec3> {
        self.normals.iter().map(|n| f(*n)).collect()
    }
}

/// Compares every basis on environment `env` (an [`crate::env::EnvMap`] or
/// [`crate::env::Cubemap`]) over `normals` spherical-Fibonacci normals (the
/// issue asks for at least [`MIN_NORMALS`]). Cost is dominated by the
/// reference: `normals × texels` multiply-adds.
pub fn compare_bases<E: Environment + ?Sized>(env: &E, normals: usize) -> BasisComparison {
    let inputs = ComparisonInputs::new(env, normals);
    compare_inputs(&inputs)
}

/// [`compare_bases`] on precomputed inputs.
pub fn compare_inputs(i: &ComparisonInputs) -> BasisComparison {
    let err = |v: Option<Vec<Vec3>>| v.and_then(|v| relative_rmse(&v, &i.reference));
    let (l2w, window) = match eval_l2_windowed(i) {
        Some((v, w)) => (Some(v), Some(w)),
        None => (None, None),
    };
    BasisComparison {
        bases: BasisErrors {
            l1: err(Some(eval_l1(i))),
            l1_geomerics: err(eval_l1_geomerics(i)),
            zh3_hallucinated: err(eval_zh3_hallucinated(i)),
            zh3_shared: err(eval_zh3_shared(i)),
            zh3_per_channel: err(eval_zh3_per_channel(i)),
            zh3_solved: err(eval_zh3_solved(i)),
            l2: err(Some(eval_l2(i))),
            l2_windowed: err(l2w),
            ambient_cube: err(eval_ambient_cube(i)),
        },
        bytes: basis_bytes(),
        window,
    }
}

/// L1 SH irradiance (clamped-cosine convolution).
fn eval_l1(i: &ComparisonInputs) -> Vec<Vec3> {
    i.map(|n| probekit_sh::irradiance_l1(&i.l1, n))
}

/// L2 SH irradiance (clamped-cosine convolution).
fn eval_l2(i: &ComparisonInputs) -> Vec<Vec3> {
    i.map(|n| probekit_sh::irradiance_l2(&i.l2, n))
}

fn eval_l1_geomerics(i: &ComparisonInputs) -> Option<Vec<Vec3>> {
    Some(i.map(|n| probekit_sh::geomerics::irradiance_geomerics_l1(&i.l1, n)))
}

fn eval_zh3_hallucinated(i: &ComparisonInputs) -> Option<Vec<Vec3>> {
    Some(i.map(|n| probekit_sh::zh3::zh3_hallucinated_irradiance(&i.l1, n)))
}

fn eval_zh3_shared(i: &ComparisonInputs) -> Option<Vec<Vec3>> {
    let z = probekit_sh::zh3::fit_zh3_shared(&i.l2);
    Some(i.map(|n| z.irradiance(n)))
}

fn eval_zh3_per_channel(i: &ComparisonInputs) -> Option<Vec<Vec3>> {
    let z = probekit_sh::zh3::fit_zh3_per_channel(&i.l2);
    Some(i.map(|n| z.irradiance(n)))
}

fn eval_zh3_solved(i: &ComparisonInputs) -> Option<Vec<Vec3>> {
    let z = probekit_sh::zh3::solve_zh3_axis(&i.l2, probekit_sh::zh3::AxisWeights::Luminance);
    Some(i.map(|n| z.irradiance(n)))
}

fn eval_l2_windowed(i: &ComparisonInputs) -> Option<(Vec<Vec3>, WindowInfo)> {
    let w = probekit_sh::window::choose_window_for(&i.l2);
    let mut c = i.l2;
    w.apply(&mut c);
    let info = WindowInfo {
        kind: w.name().to_string(),
        strength: f64::from(w.strength),
    };
    Some((i.map(|n| probekit_sh::irradiance_l2(&c, n)), info))
}

/// Fitted to the reference irradiance at the evaluation normals (least squares).
fn eval_ambient_cube(i: &ComparisonInputs) -> Option<Vec<Vec3>> {
    let cube = probekit_sh::ambient_cube::AmbientCube::fit_from_samples(&i.normals, &i.reference);
    Some(i.map(|n| cube.irradiance(n)))
}

/// Extra bytes a solved ZH3 axis needs (8:8 octahedral encoding).
const SOLVED_AXIS_BYTES: usize = 2;

fn basis_bytes() -> BasisBytes {
    use probekit_sh::codec::{AMBIENT_CUBE_BYTES, L1_BYTES, L2_BYTES, ZH3_BYTES};
    BasisBytes {
        l1: Some(L1_BYTES),
        l1_geomerics: Some(L1_BYTES),
        zh3_hallucinated: Some(L1_BYTES),
        zh3_shared: Some(ZH3_BYTES),
        zh3_per_channel: Some(ZH3_BYTES),
        // The solved axis is not derivable from L1, so it must be stored:
        // +2 bytes (8:8 octahedral) beyond the 16-byte ZH3 layout.
        zh3_solved: Some(ZH3_BYTES + SOLVED_AXIS_BYTES),
        l2: Some(L2_BYTES),
        l2_windowed: Some(L2_BYTES),
        ambient_cube: Some(AMBIENT_CUBE_BYTES),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::EnvMap;

    #[test]
    fn fibonacci_is_uniform() {
        let n = spherical_fibonacci(4096);
        assert!(n.iter().all(|d| (d.length() - 1.0).abs() < 1e-5));
        // mean of a uniform distribution is 0; mean of y² is 1/3
        let mean: Vec3 = n.iter().copied().sum::<Vec3>() / n.len() as f32;
        assert!(mean.length() < 1e-3, "{mean}");
        let y2: f32 = n.iter().map(|d| d.y * d.y).sum::<f32>() / n.len() as f32;
        assert!((y2 - 1.0 / 3.0).abs() < 1e-3);
    }

    #[test]
    fn relative_rmse_by_hand() {
        let r = [Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let a = [Vec3::new(1.1, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        // sqrt(0.01/2) / sqrt(2/2)
        let e = relative_rmse(&a, &r).unwrap();
        assert!((e - (0.005f64).sqrt()).abs() < 1e-6, "{e}");
        assert!(relative_rmse(&a, &[Vec3::ZERO; 2]).is_none());
    }

    /// For a map whose radiance is exactly an L1 function, L1 and L2 reproduce
    /// the brute-force irradiance (up to texel quadrature error) and the
    /// table / JSON have the documented shape.
    #[test]
    fn l1_map_is_reproduced() {
        let (w, h) = (128, 64);
        let mut t = Vec::new();
        let probe = EnvMap::builtin_sky(w, h);
        for y in 0..h {
            for x in 0..w {
                let d = probe.texel_direction(x, y);
                t.push(Vec3::new(1.0 + 0.5 * d.y, 1.0 - 0.3 * d.x, 1.0 + 0.2 * d.z));
            }
        }
        let map = EnvMap::from_texels(std::path::Path::new("synthetic"), w, h, t).unwrap();
        let c = compare_bases(&map, MIN_NORMALS);
        assert!(c.bases.l1.unwrap() < 2e-3, "{:?}", c.bases);
        assert!(c.bases.l2.unwrap() < 2e-3, "{:?}", c.bases);
        let json = serde_json::to_value(&c).unwrap();
        for key in [
            "l1",
            "l1_geomerics",
            "zh3_hallucinated",
            "zh3_shared",
            "zh3_per_channel",
            "zh3_solved",
            "l2",
            "l2_windowed",
            "ambient_cube",
        ] {
            assert!(json["bases"].get(key).is_some(), "missing {key}");
            assert!(json["bytes"].get(key).is_some(), "missing {key}");
        }
        assert!(json.get("window").is_some());
        assert!(c.table().lines().count() >= 10);
    }

    /// On the builtin sky (a small bright sun) L2 beats L1.
    #[test]
    fn l2_beats_l1_on_sky() {
        let map = EnvMap::builtin_sky(128, 64);
        let c = compare_bases(&map, MIN_NORMALS);
        let (l1, l2) = (c.bases.l1.unwrap(), c.bases.l2.unwrap());
        assert!(l2 < l1, "l1 {l1} l2 {l2}");
        assert!(l2 > 0.0);
    }
}
