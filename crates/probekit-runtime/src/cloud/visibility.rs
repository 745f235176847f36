//! Visibility-aware blending: per-probe distance moments on an octahedral
//! map and the Chebyshev visibility test that down-weights probes that
//! cannot see the shaded point (a probe behind a wall).
//!
//! This is the visibility term of DDGI (Majercik, Guertin, Nowrouzezahrai &
//! McGuire, "Dynamic Diffuse Global Illumination with Ray-Traced Irradiance
//! Fields", JCGT 8(2), 2019, §4–5), whose test is the one-sided Chebyshev
//! bound of variance shadow maps (Donnelly & Lauritzen, "Variance Shadow
//! Maps", I3D 2006): with `μ`, `μ2` the mean and mean square of the distance
//! from probe `i` to the first surface in the direction of `p`, and `d` the
//! distance to `p`,
//!
//! ```text
//! v_i(p) = 1                                  if d ≤ μ
//!        = (σ² / (σ² + (d − μ)²))^k           otherwise, σ² = max(μ2 − μ², σ²_min)
//! ```
//!
//! with `k` = 3, then crushed below 0.2 (`v ← v³/0.2²`, as DDGI's reference
//! code does) and floored at [`VISIBILITY_FLOOR`]. The blend weights of the enclosing
//! tetrahedron (or outer cell) become `w_i = b_i·v_i / Σ_j b_j·v_j`. Every
//! ingredient is continuous in `p` (the bilinear filter wraps across the
//! octahedral map's edges, the test is continuous at `d = μ`, the weights
//! that vanish on a tetrahedron face still vanish there), so interpolated
//! lighting stays continuous.
//!
//! # Octahedral map orientation (+Y up)
//! [`oct_encode`] is the standard octahedral projection (Cigolle, Donow,
//! Evangelakos, Mara, McGuire & Meyer, "A Survey of Efficient
//! Representations for Independent Unit Vectors", JCGT 3(2), 2014, §3.6)
//! with **+Y as the pole**: a unit vector is scaled to the octahedron
//! `|x| + |y| + |z| = 1` and projected onto the XZ plane, map coordinate
//! `u = x`, `v = z`; the lower hemisphere (`y < 0`) is folded outwards over
//! the diagonals. So the centre of the map is +Y (up), the four corners are
//! −Y, `(1, 0)` is +X, `(0, 1)` is +Z, and the square's edges are the
//! half-planes `x = 0` or `z = 0` below the horizon. Texel `(col, row)` of an
//! `S × S` map covers `u ∈ [−1 + 2·col/S, −1 + 2·(col+1)/S]`, likewise `v`
//! with `row`; its index is `row·S + col`.
//!
//! The edges fold onto themselves: `(−1, v)` and `(−1, −v)` are the same
//! direction (and so on for the other three edges; all corners are −Y), so
//! the bilinear filter reads a texel just outside the map at column −1,
//! row `j` from column 0, row `S − 1 − j` (the same mirror for the other
//! edges, and the diagonally opposite corner texel at the corners) — the
//! 1-texel border that DDGI copies into its atlas, applied at fetch time.

use crate::format::DistanceMoments;
use crate::prelude::*;
use glam::Vec3;

/// Default distance bias in metres: `d = |p − x_i| − bias`, so a point a few
/// centimetres in front of the surface a probe sees is not judged behind it
/// (texel-averaged depths and f16 rounding are not exact).
pub const DEFAULT_VISIBILITY_BIAS: f32 = 0.05;

/// Default sharpening exponent `k` of the Chebyshev bound (DDGI cubes it).
pub const DEFAULT_VISIBILITY_SHARPNESS: u32 = 3;

/// Largest sharpening exponent ([`VisibilityMaps::set_sharpness`] clamps
/// to it; a load refuses a larger `BlendOverrides::visibility_sharpness`).
pub(crate) const MAX_SHARPNESS: u32 = 16;

/// Smallest variance `σ²_min` used by the Chebyshev test, in m² (1 cm
/// standard deviation): a texel seeing one flat wall head-on has `μ2 = μ²`
/// up to rounding, and a zero variance would make the test a hard step.
pub const MIN_VISIBILITY_VARIANCE: f32 = 1e-4;

/// Below this visibility the value is crushed towards 0 as `v³/c²`
/// (continuous at `c`): a few percent of a bright probe's light is still
/// clearly visible in a dark room, so tiny weights are pushed further down.
/// The threshold 0.2 and the cubic curve are DDGI's reference
/// implementation's (Majercik et al. 2019, supplementary GLSL; RTXGI
/// `DDGIGetVolumeIrradiance`).
pub const VISIBILITY_CRUSH: f32 = 0.2;

/// Smallest visibility a probe gets, so the weights of a point that no probe
/// sees never all vanish (lighting stays defined and continuous).
pub const VISIBILITY_FLOOR: f32 = 1e-4;

mod octahedral;

// The functions the bake also uses (feature `write`).
#[cfg(feature = "write")]
pub use octahedral::{
    chebyshev_bound, chebyshev_visibility, oct_decode, oct_encode, oct_texel_center,
    sample_oct_bilinear,
};
#[cfg(not(feature = "write"))]
pub(crate) use octahedral::{chebyshev_visibility, sample_oct_bilinear};

/// Decoded distance moments of every probe of a cloud, with the settings of
/// the Chebyshev test. Built from a file's [`DistanceMoments`] (`VISM`) or
/// directly from `[μ, μ2]` texels (metres).
#[derive(Clone, Debug, PartialEq)]
pub struct VisibilityMaps {
    resolution: u32,
    max_distance: f32,
    moments: Vec<[f32; 2]>,
    bias: f32,
    sharpness: u32,
    min_variance: f32,
}

impl VisibilityMaps {
    /// Maps of `resolution²` texels per probe, `moments` holding `[μ, μ2]`
    /// (metres, m²) probe after probe, texel layout as [`DistanceMoments`];
    /// default bias, sharpness and minimum variance. `None` if the
    /// resolution is 0 or the length is not a multiple of `resolution²`.
    pub fn new(resolution: u32, max_distance: f32, moments: Vec<[f32; 2]>) -> Option<Self> {
        let per = (resolution as usize).checked_mul(resolution as usize)?;
        if per == 0 || moments.len() % per != 0 {
            return None;
        }
        Some(Self {
            resolution,
            max_distance,
            moments,
            bias: DEFAULT_VISIBILITY_BIAS,
            sharpness: DEFAULT_VISIBILITY_SHARPNESS,
            min_variance: MIN_VISIBILITY_VARIANCE,
        })
    }

    /// Decodes a file's `VISM` section (already validated by the reader).
    pub fn from_moments(m: &DistanceMoments) -> Option<Self> {
        Self::new(m.resolution, m.max_distance, m.decode())
    }

    /// Texels per side of each probe's map.
    pub fn resolution(&self) -> u32 {
        self.resolution
    }

    /// Distance clamp used by the bake (metres): rays that hit nothing count
    /// as this far.
    pub fn max_distance(&self) -> f32 {
        self.max_distance
    }

    /// Number of probes with a map.
    pub fn probe_count(&self) -> usize {
        self.moments.len() / (self.resolution as usize * self.resolution as usize)
    }

    /// The `[μ, μ2]` texels of probe `i` (empty if out of range).
    pub fn probe_map(&self, i: usize) -> &[[f32; 2]] {
        let per = self.resolution as usize * self.resolution as usize;
        self.moments.get(i * per..(i + 1) * per).unwrap_or(&[])
    }

    /// Distance bias in metres ([`DEFAULT_VISIBILITY_BIAS`]).
    pub fn bias(&self) -> f32 {
        self.bias
    }

    baker_only! {
        /// Sets the distance bias (metres; non-finite values are ignored).
        fn set_bias(&mut self, bias: f32) {
            if bias.is_finite() {
                self.bias = bias;
            }
        }
    }

    /// Sharpening exponent ([`DEFAULT_VISIBILITY_SHARPNESS`]).
    pub fn sharpness(&self) -> u32 {
        self.sharpness
    }

    baker_only! {
        /// Sets the sharpening exponent (clamped to `0..=16`; 0 disables the test).
        fn set_sharpness(&mut self, k: u32) {
            self.sharpness = k.min(MAX_SHARPNESS);
        }
    }

    /// Minimum variance `σ²_min` of the test, m² ([`MIN_VISIBILITY_VARIANCE`]).
    pub fn min_variance(&self) -> f32 {
        self.min_variance
    }

    baker_only! {
        /// Sets the minimum variance `σ²_min` (m²; non-finite or negative values
        /// are ignored).
        fn set_min_variance(&mut self, v: f32) {
            if v.is_finite() && v >= 0.0 {
                self.min_variance = v;
            }
        }
    }

    /// Chebyshev visibility of point `p` from probe `i` at `probe_pos`, in
    /// `[VISIBILITY_FLOOR, 1]` (see the [module docs](self)). 1 for a probe
    /// without a map. No allocation.
    pub fn visibility(&self, i: usize, probe_pos: Vec3, p: Vec3) -> f32 {
        let map = self.probe_map(i);
        let v = p - probe_pos;
        let len = v.length();
        let d = len - self.bias;
        if map.is_empty() || d.is_nan() || d <= 0.0 || len <= 0.0 {
            return 1.0;
        }
        // The octahedral encoding scales by the L1 norm: no need to normalize.
        let [mu, mu2] = sample_oct_bilinear(map, self.resolution, v);
        chebyshev_visibility(d, mu, mu2, self.min_variance, self.sharpness)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;
    use proptest::prelude::*;

    fn unit(v: [f32; 3]) -> Option<Vec3> {
        let d = Vec3::from_array(v);
        (d.length() > 1e-3).then(|| d.normalize())
    }

    /// A deterministic pseudo-random map of `res²` texels in `[0, 1]²`.
    fn random_map(res: u32, seed: u64) -> Vec<[f32; 2]> {
        let mut s = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..res * res).map(|_| [next(), next()]).collect()
    }

    #[test]
    fn orientation_is_plus_y_at_the_centre() {
        assert!((oct_encode(Vec3::Y) - Vec2::ZERO).length() < 1e-6);
        assert!((oct_encode(Vec3::X) - Vec2::X).length() < 1e-6);
        assert!((oct_encode(Vec3::Z) - Vec2::Y).length() < 1e-6);
        assert!((oct_encode(-Vec3::X) + Vec2::X).length() < 1e-6);
        let c = oct_encode(-Vec3::Y);
        assert!((c.abs() - Vec2::ONE).length() < 1e-6, "{c}");
        // Every corner decodes to −Y; an edge point and its mirror agree.
        for c in [
            Vec2::new(1.0, 1.0),
            Vec2::new(-1.0, 1.0),
            Vec2::new(1.0, -1.0),
        ] {
            assert!((oct_decode(c) + Vec3::Y).length() < 1e-6);
        }
        let (a, b) = (
            oct_decode(Vec2::new(-1.0, 0.3)),
            oct_decode(Vec2::new(-1.0, -0.3)),
        );
        assert!((a - b).length() < 1e-6);
    }

    #[test]
    fn filter_returns_texel_values_at_texel_centres_and_constants_everywhere() {
        let res = 6;
        let map = random_map(res, 7);
        for row in 0..res {
            for col in 0..res {
                let d = oct_decode(oct_texel_center(res, col, row));
                let got = sample_oct_bilinear(&map, res, d);
                let want = map[(row * res + col) as usize];
                assert!((got[0] - want[0]).abs() < 1e-4 && (got[1] - want[1]).abs() < 1e-4);
            }
        }
        let flat = vec![[0.25, 0.5]; (res * res) as usize];
        for i in 0..500 {
            let d = probekit_sh::fibonacci_point(i, 500);
            let got = sample_oct_bilinear(&flat, res, d);
            assert!((got[0] - 0.25).abs() < 1e-6 && (got[1] - 0.5).abs() < 1e-6);
        }
    }

    proptest! {
        #[test]
        fn encode_decode_round_trips(v in prop::array::uniform3(-1.0f32..1.0)) {
            if let Some(d) = unit(v) {
                let e = oct_encode(d);
                prop_assert!(e.x.abs() <= 1.0 && e.y.abs() <= 1.0);
                prop_assert!((oct_decode(e) - d).length() < 1e-5, "{d} -> {e}");
            }
        }

        /// Directions crossing the map's edges (the half-planes x = 0 or
        /// z = 0 below the horizon, and −Y where the corners meet) and
        /// anywhere else: a step of δ radians changes the filtered value by
        /// at most a few texel differences per texel travelled (random
        /// texels in [0, 1]: without the border wrap the jump is O(1)).
        #[test]
        fn bilinear_filter_is_continuous_across_edges(
            res in 1u32..=8,
            seed in 0u64..1000,
            which in 0usize..4,
            a in -1.0f32..1.0,
            b in -1.0f32..-0.01,
            off in prop::array::uniform3(-1.0f32..1.0),
        ) {
            let map = random_map(res, seed);
            let base = match which {
                0 => Vec3::new(a, b, 0.0),          // crosses z = 0 (left/right edges)
                1 => Vec3::new(0.0, b, a),          // crosses x = 0 (top/bottom edges)
                2 => Vec3::new(0.01 * a, -1.0, 0.01 * off[0]), // near −Y (corners)
                _ => Vec3::from_array(off) + Vec3::new(0.0, 0.0, 1e-3), // anywhere
            };
            let Some(d) = unit(base.to_array()) else { return Ok(()); };
            let delta = 1e-3f32;
            let step = Vec3::from_array(off).normalize_or(Vec3::Z) * delta;
            let (d1, d2) = ((d + step).normalize(), (d - step).normalize());
            let (f1, f2) = (sample_oct_bilinear(&map, res, d1), sample_oct_bilinear(&map, res, d2));
            // |Δe| ≤ 4·|Δd| in map units (L1 normalization), S/2 texels per unit.
            let bound = 4.0 * (d1 - d2).length() * res as f32 * 0.5 * 2.0 + 1e-5;
            prop_assert!((f1[0] - f2[0]).abs() <= bound, "{d} {} {} > {bound}", f1[0], f2[0]);
            prop_assert!((f1[1] - f2[1]).abs() <= bound);
        }

        /// Cantelli's inequality: for any distance distribution,
        /// P(X ≥ μ + t) ≤ σ²/(σ² + t²): the bound (no variance floor) is
        /// at least the fraction of rays reaching `d`, counted directly from
        /// the samples.
        #[test]
        fn chebyshev_bounds_the_fraction_of_unoccluded_rays(
            xs in prop::collection::vec(0.0f32..10.0, 1..40),
            d in 0.0f32..12.0,
        ) {
            let n = xs.len() as f64;
            let mu = (xs.iter().map(|&x| x as f64).sum::<f64>() / n) as f32;
            let mu2 = (xs.iter().map(|&x| (x as f64).powi(2)).sum::<f64>() / n) as f32;
            let frac = xs.iter().filter(|&&x| x >= d).count() as f32 / xs.len() as f32;
            let b = chebyshev_bound(d, mu, mu2, 0.0);
            prop_assert!(b + 1e-3 >= frac, "bound {b} < fraction {frac}");
            let v = chebyshev_visibility(d, mu, mu2, 0.0, 3);
            prop_assert!((VISIBILITY_FLOOR..=1.0).contains(&v) && v <= b.max(VISIBILITY_FLOOR) + 1e-6);
            // Monotone: farther is never more visible.
            prop_assert!(chebyshev_visibility(d + 0.5, mu, mu2, 0.0, 3) <= chebyshev_visibility(d, mu, mu2, 0.0, 3));
        }
    }
}
