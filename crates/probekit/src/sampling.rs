//! The crate's one random number generator ([`SampleRng`]) and its samplers,
//! used by the path tracer, placement, Delaunay insertion order and the
//! blend-data bakes. Samplers are in pbrt's style: each sampler comes
//! in threes — `sample_x(u)` maps uniform random numbers `u ∈ [0,1)²` to a
//! sample, `x_pdf` is its density (per steradian for directions, per unit
//! area for points), and the random numbers are always passed in so the
//! caller controls determinism (Pharr, Jakob & Humphreys, *Physically Based
//! Rendering*, 4th ed., §A.5 "Sampling Multidimensional Functions").
//!
//! Random numbers come from [`SampleRng`], a counter-based generator keyed by
//! `(seed, stream, index)`: a probe's samples depend only on the bake seed,
//! the probe's global index and the sample index, never on which thread runs
//! them or in what order. Primary directions use the R2 low-discrepancy
//! sequence ([`r2_point`], Roberts 2018, "The Unreasonable Effectiveness of
//! Quasirandom Sequences") with a per-probe Cranley–Patterson rotation, which
//! keeps every point uniformly distributed (so estimates stay unbiased) while
//! stratifying the sphere.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// `1/(4π)`, the density of a uniform direction on the sphere.
pub const INV_FOUR_PI: f32 = 1.0 / (4.0 * PI);

/// The 64-bit finaliser of SplitMix64 (Steele, Lea & Flood 2014, "Fast
/// splittable pseudorandom number generators"): a bijective avalanche mix.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// SplitMix64's state increment (the odd integer nearest 2⁶⁴/φ): each step
/// adds it to the state and returns [`mix64`] of the sum.
pub const SPLITMIX_GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

/// Hashes a key of three integers to 64 well-mixed bits.
#[inline]
pub fn hash3(a: u64, b: u64, c: u64) -> u64 {
    let h = mix64(a ^ SPLITMIX_GAMMA);
    let h = mix64(h ^ b.wrapping_mul(0xd6e8_feb8_6659_fd93));
    mix64(h ^ c.wrapping_mul(0xa076_1d64_78bd_642f))
}

/// A small counter-based random number generator: SplitMix64 started from a
/// hash of `(seed, stream, index)`. Two generators with the same key produce
/// the same numbers; different keys give statistically independent streams.
#[derive(Clone, Debug)]
pub struct SampleRng {
    state: u64,
}

impl SampleRng {
    /// The generator for sample `index` of stream `stream` (for a probe
    /// capture: the probe's global index) under bake seed `seed`.
    pub fn new(seed: u64, stream: u64, index: u64) -> Self {
        Self {
            state: hash3(seed, stream, index),
        }
    }

    /// The plain SplitMix64 generator started at `state` (no key hashing):
    /// its first number is `mix64(state + SPLITMIX_GAMMA)`. For the
    /// places that need one fixed stream (the tetrahedralization's shuffle
    /// and walks, a rig's surface samples).
    pub fn from_state(state: u64) -> Self {
        Self { state }
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(SPLITMIX_GAMMA);
        mix64(self.state)
    }

    /// A uniform float in `[0, 1)` (24 random mantissa bits).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// A uniform double in `[0, 1)` (53 random mantissa bits).
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Two uniform floats in `[0, 1)²`.
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let a = self.next_f32();
        Vec2::new(a, self.next_f32())
    }
}

/// Point `i` of the R2 sequence in `[0,1)²` shifted (Cranley–Patterson
/// rotation) by `offset ∈ [0,1)²`: `frac(offset + ½ + i·(1/g, 1/g²))` with
/// `g` the plastic number (Roberts 2018). Computed in f64 so indices in the
/// billions stay accurate.
pub fn r2_point(i: u64, offset: Vec2) -> Vec2 {
    const G: f64 = 1.324_717_957_244_746;
    const A1: f64 = 1.0 / G;
    const A2: f64 = 1.0 / (G * G);
    let x = (0.5 + offset.x as f64 + A1 * i as f64).fract();
    let y = (0.5 + offset.y as f64 + A2 * i as f64).fract();
    // Guard the open upper end against rounding to 1.0 in f32.
    Vec2::new(
        (x as f32).min(ONE_MINUS_EPSILON),
        (y as f32).min(ONE_MINUS_EPSILON),
    )
}

/// Point `i` of the Sobol' (0,2)-sequence in `[0,1)²`, randomised by the
/// digital shift `scramble` (XOR on the 32-bit binary fractions): the first
/// two dimensions of Sobol's sequence, the van der Corput sequence in base
/// 2 and the dimension whose generator matrix is Pascal's triangle mod 2
/// (Kollig & Keller, "Efficient Multidimensional Sampling", 2002; pbrt-v3
/// `Sobol2D`). Every aligned block of `2^k` consecutive points is a
/// `(0, k, 2)`-net, for any shift: each elementary interval of area `2^-k`
/// holds exactly one point, so a sum over the block stratifies both
/// coordinates at once. The shift keeps each point uniform over the square.
pub fn sobol02_point(i: u32, scramble: [u32; 2]) -> Vec2 {
    let x = i.reverse_bits() ^ scramble[0];
    let mut y = 0u32;
    let mut v = 1u32 << 31;
    let mut n = i;
    while n != 0 {
        if n & 1 != 0 {
            y ^= v;
        }
        n >>= 1;
        v ^= v >> 1;
    }
    let y = y ^ scramble[1];
    // The top 24 bits: exact in f32 and below one.
    let f = |b: u32| (b >> 8) as f32 * (1.0 / (1u32 << 24) as f32);
    Vec2::new(f(x), f(y))
}

/// The digital shift of [`sobol02_point`] for dimension pair `k` of the
/// random key `key` (a SplitMix64 mix of both).
pub fn sobol02_scramble(key: u64, k: u64) -> [u32; 2] {
    let h = mix64(key ^ mix64(k.wrapping_add(1).wrapping_mul(SPLITMIX_GAMMA)));
    [h as u32, (h >> 32) as u32]
}

/// The largest f32 below one; uniform samples are clamped to it.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// A uniformly distributed unit direction (pbrt-v4 `SampleUniformSphere`):
/// `z = 1 − 2u₀`, `φ = 2πu₁`.
pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`sample_uniform_sphere`]: `1/(4π)` per steradian.
pub fn uniform_sphere_pdf() -> f32 {
    INV_FOUR_PI
}

/// A point on the unit disk by Shirley & Chiu's concentric mapping (1997,
/// "A Low Distortion Map Between Disk and Square"), uniform in area.
pub fn sample_uniform_disk_concentric(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, 0.25 * PI * (o.y / o.x))
    } else {
        (o.y, 0.5 * PI - 0.25 * PI * (o.x / o.y))
    };
    Vec2::new(r * theta.cos(), r * theta.sin())
}

/// Density of [`sample_uniform_disk_concentric`]: `1/π` per unit area.
pub fn uniform_disk_pdf() -> f32 {
    1.0 / PI
}

/// A cosine-distributed direction on the hemisphere about +Z (Malley's
/// method: a uniform disk point lifted to the hemisphere).
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = sample_uniform_disk_concentric(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Density of [`sample_cosine_hemisphere`] for a direction with
/// `cos θ = cos_theta` to +Z: `max(cos θ, 0)/π`.
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) / PI
}

/// `1 − cos θ_max` of the cone subtended by a sphere, from `sin²θ_max =
/// (r/d)²`, computed without cancellation as `sin²/(1 + cos)` (tiny lights
/// far away would otherwise lose every digit in f32).
pub fn cone_one_minus_cos(sin2_theta_max: f32) -> f32 {
    let s2 = sin2_theta_max.clamp(0.0, 1.0);
    s2 / (1.0 + (1.0 - s2).sqrt())
}

/// A direction uniformly distributed in the cone about +Z whose half-angle
/// has `1 − cos θ_max = one_minus_cos_max` (pbrt-v4 `SampleUniformCone`, in
/// the cancellation-free variable `1 − cos θ`). Used to sample sphere lights
/// by the solid angle they subtend.
pub fn sample_uniform_cone(u: Vec2, one_minus_cos_max: f32) -> Vec3 {
    let omc = u.x * one_minus_cos_max; // 1 − cos θ, uniform in [0, 1 − cos θ_max]
    let cos_t = 1.0 - omc;
    let sin_t = (omc * (2.0 - omc)).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

/// Density of [`sample_uniform_cone`]: `1/(2π(1 − cos θ_max))` per steradian
/// inside the cone (the caller checks membership).
pub fn uniform_cone_pdf(one_minus_cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * one_minus_cos_max)
}

/// Barycentric coordinates `(b0, b1, b2)` of a point uniformly distributed
/// over a triangle (square-root parameterisation, Osada et al. 2002 "Shape
/// distributions", eq. 1). Its area density is `1/area`.
pub fn sample_uniform_triangle(u: Vec2) -> Vec3 {
    let su = u.x.sqrt();
    let b0 = 1.0 - su;
    let b1 = u.y * su;
    Vec3::new(b0, b1, (1.0 - b0 - b1).max(0.0))
}

/// The power heuristic with exponent 2 for multiple importance sampling
/// (Veach & Guibas 1995, "Optimally Combining Sampling Techniques for Monte
/// Carlo Rendering", §4): the weight of a sample drawn `nf` times from
/// density `f_pdf` against `ng` draws from `g_pdf`.
pub fn power_heuristic(nf: f32, f_pdf: f32, ng: f32, g_pdf: f32) -> f32 {
    let f = nf * f_pdf;
    let g = ng * g_pdf;
    if f.is_infinite() {
        return 1.0;
    }
    let (f2, g2) = (f * f, g * g);
    if f2 + g2 == 0.0 {
        return 0.0;
    }
    f2 / (f2 + g2)
}

/// An orthonormal frame whose third axis is unit `n` (Duff et al. 2017,
/// "Building an Orthonormal Basis, Revisited", branchless).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// First tangent.
    pub x: Vec3,
    /// Second tangent.
    pub y: Vec3,
    /// The axis (`n`).
    pub z: Vec3,
}

impl Frame {
    /// The frame around unit vector `n`.
    pub fn from_z(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let x = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let y = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Self { x, y, z: n }
    }

    /// A local vector (frame coordinates) in world space.
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first points of the unscrambled (0,2)-sequence are the
    /// textbook ones, and every aligned block of `2^k` points (k ≤ 8) of a
    /// scrambled sequence puts exactly one point in each elementary
    /// interval `[a/2^j, (a+1)/2^j) × [b/2^(k−j), (b+1)/2^(k−j))`, counted
    /// here by brute force.
    #[test]
    fn sobol02_points_form_nets_for_any_scramble() {
        let first: Vec<Vec2> = (0..4).map(|i| sobol02_point(i, [0, 0])).collect();
        assert_eq!(
            first,
            [
                Vec2::new(0.0, 0.0),
                Vec2::new(0.5, 0.5),
                Vec2::new(0.25, 0.75),
                Vec2::new(0.75, 0.25)
            ]
        );
        for key in [0u64, 1, 0xdead_beef] {
            let sc = sobol02_scramble(key, 3);
            for k in 0..=8u32 {
                let n = 1u32 << k;
                for block in [0u32, 5] {
                    let pts: Vec<Vec2> = (0..n).map(|i| sobol02_point(block * n + i, sc)).collect();
                    for j in 0..=k {
                        let (nx, ny) = (1u32 << j, 1u32 << (k - j));
                        let mut cells = vec![0u32; n as usize];
                        for p in &pts {
                            assert!(p.x >= 0.0 && p.x < 1.0 && p.y >= 0.0 && p.y < 1.0);
                            let (cx, cy) = ((p.x * nx as f32) as u32, (p.y * ny as f32) as u32);
                            cells[(cx * ny + cy) as usize] += 1;
                        }
                        assert!(cells.iter().all(|&c| c == 1), "k {k} j {j} key {key}");
                    }
                }
            }
        }
        // Different keys and pairs scramble differently.
        assert_ne!(sobol02_scramble(1, 0), sobol02_scramble(1, 1));
        assert_ne!(sobol02_scramble(1, 0), sobol02_scramble(2, 0));
    }

    /// Pearson chi-square of direction samples against a density, binned in
    /// `(cos θ, φ)` cells whose expected counts are integrated from `pdf` by
    /// a fine midpoint rule (pbrt-v4 `util/sampling_test.cpp` approach).
    /// Returns `(chi2, degrees of freedom)`.
    fn chi_square_dir(
        sample: impl Fn(Vec2) -> Vec3,
        pdf: impl Fn(Vec3) -> f64,
        n: usize,
        z_range: (f64, f64),
    ) -> (f64, usize) {
        const NT: usize = 16;
        const NP: usize = 16;
        const SUB: usize = 24;
        let (z0, z1) = z_range;
        let mut counts = [[0u32; NP]; NT];
        let mut rng = SampleRng::new(7, 1, 2);
        for _ in 0..n {
            let d = sample(rng.next_2d());
            assert!((d.length() - 1.0).abs() < 1e-4, "not unit: {d}");
            let t = ((d.z as f64 - z0) / (z1 - z0) * NT as f64).floor();
            assert!((-1.0..=NT as f64).contains(&t), "z {} outside range", d.z);
            let t = (t.max(0.0) as usize).min(NT - 1);
            let phi = (d.y as f64)
                .atan2(d.x as f64)
                .rem_euclid(2.0 * std::f64::consts::PI);
            let p = ((phi / (2.0 * std::f64::consts::PI) * NP as f64) as usize).min(NP - 1);
            counts[t][p] += 1;
        }
        let mut chi2 = 0.0;
        let mut cells = 0;
        let mut total_p = 0.0;
        for (ti, row) in counts.iter().enumerate() {
            for (pi, &c) in row.iter().enumerate() {
                // integrate pdf over the cell: dω = dz dφ
                let dz = (z1 - z0) / (NT * SUB) as f64;
                let dp = 2.0 * std::f64::consts::PI / (NP * SUB) as f64;
                let mut p = 0.0;
                for a in 0..SUB {
                    let z = z0 + (ti * SUB + a) as f64 * dz + 0.5 * dz;
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    for b in 0..SUB {
                        let phi = (pi * SUB + b) as f64 * dp + 0.5 * dp;
                        let d = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                        p += pdf(d) * dz * dp;
                    }
                }
                total_p += p;
                let e = p * n as f64;
                assert!(e > 5.0, "cell expectation too small for chi-square: {e}");
                chi2 += (c as f64 - e).powi(2) / e;
                cells += 1;
            }
        }
        assert!((total_p - 1.0).abs() < 2e-3, "pdf integrates to {total_p}");
        (chi2, cells - 1)
    }

    /// Chi-square statistic must stay below df + 5·sqrt(2·df) (normal
    /// approximation; ~3e-7 false-failure rate, and the RNG is deterministic).
    fn assert_chi2((chi2, df): (f64, usize)) {
        let limit = df as f64 + 5.0 * (2.0 * df as f64).sqrt();
        assert!(chi2 < limit, "chi2 {chi2} >= {limit} (df {df})");
    }

    /// `from_state` is plain SplitMix64: the first outputs of Vigna's
    /// reference `splitmix64.c` seeded with 1234567 (the published test
    /// vector), and `next_f64`/`next_f32` take their top 53/24 bits.
    #[test]
    fn from_state_is_reference_splitmix64() {
        let mut rng = SampleRng::from_state(1_234_567);
        let expected = [
            6_457_827_717_110_365_317u64,
            3_203_168_211_198_807_973,
            9_817_491_932_198_370_423,
            4_593_380_528_125_082_431,
            16_408_922_859_458_223_821,
        ];
        for e in expected {
            assert_eq!(rng.next_u64(), e);
        }
        let mut a = SampleRng::from_state(1_234_567);
        assert_eq!(
            a.next_f64(),
            (expected[0] >> 11) as f64 / 9_007_199_254_740_992.0
        );
        assert_eq!(a.next_f32(), (expected[1] >> 40) as f32 / 16_777_216.0);
        // The keyed constructor starts from the hash of its key.
        let mut k = SampleRng::new(1, 2, 3);
        let mut s = SampleRng::from_state(hash3(1, 2, 3));
        assert_eq!(k.next_u64(), s.next_u64());
    }

    #[test]
    fn uniform_sphere_chi_square() {
        assert_chi2(chi_square_dir(
            sample_uniform_sphere,
            |_| uniform_sphere_pdf() as f64,
            200_000,
            (-1.0, 1.0),
        ));
    }

    #[test]
    fn cosine_hemisphere_chi_square() {
        assert_chi2(chi_square_dir(
            sample_cosine_hemisphere,
            |d| cosine_hemisphere_pdf(d.z) as f64,
            200_000,
            (0.0, 1.0),
        ));
    }

    #[test]
    fn cone_chi_square_and_pdf() {
        // half-angle 40°: 1 − cos 40°
        let omc = 1.0 - 40f32.to_radians().cos();
        let zmin = 1.0 - omc as f64;
        assert_chi2(chi_square_dir(
            |u| sample_uniform_cone(u, omc),
            |d| {
                if (d.z as f64) >= zmin {
                    uniform_cone_pdf(omc) as f64
                } else {
                    0.0
                }
            },
            200_000,
            (zmin, 1.0),
        ));
    }

    #[test]
    fn cone_one_minus_cos_is_accurate_for_tiny_lights() {
        // r = 1 mm at 100 m: sin² = 1e-10, 1 − cos ≈ sin²/2 (f64 reference).
        let s2 = 1e-10f64;
        let exact = 1.0 - (1.0 - s2).sqrt();
        let got = cone_one_minus_cos(s2 as f32) as f64;
        assert!((got - exact).abs() / exact < 1e-5, "{got} vs {exact}");
        // and a large cone against f64
        let s2 = 0.64f64;
        let exact = 1.0 - (1.0 - s2).sqrt();
        assert!((cone_one_minus_cos(s2 as f32) as f64 - exact).abs() < 1e-6);
    }

    #[test]
    fn disk_moments_and_radial_chi_square() {
        let mut rng = SampleRng::new(3, 4, 5);
        let n = 100_000;
        let (mut mx, mut my, mut mr2) = (0.0f64, 0.0f64, 0.0f64);
        const NB: usize = 20;
        let mut bins = [0u32; NB];
        for _ in 0..n {
            let p = sample_uniform_disk_concentric(rng.next_2d());
            let r2 = p.length_squared() as f64;
            assert!(r2 <= 1.0 + 1e-6);
            mx += p.x as f64;
            my += p.y as f64;
            mr2 += r2;
            // uniform in area ⇔ r² uniform in [0,1]
            bins[((r2 * NB as f64) as usize).min(NB - 1)] += 1;
        }
        let nf = n as f64;
        // E[x] = E[y] = 0 with σ = sqrt(1/4/n); E[r²] = 1/2 with σ = sqrt(1/12/n)
        assert!((mx / nf).abs() < 5.0 * (0.25 / nf).sqrt());
        assert!((my / nf).abs() < 5.0 * (0.25 / nf).sqrt());
        assert!((mr2 / nf - 0.5).abs() < 5.0 * (1.0 / 12.0 / nf).sqrt());
        let e = nf / NB as f64;
        let chi2: f64 = bins.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
        let df = (NB - 1) as f64;
        assert!(chi2 < df + 5.0 * (2.0 * df).sqrt(), "chi2 {chi2}");
        assert!((uniform_disk_pdf() * PI - 1.0).abs() < 1e-6);
    }

    #[test]
    fn triangle_barycentric_moments() {
        // Uniform on a triangle: barycentrics are Dirichlet(1,1,1):
        // E[b_i] = 1/3, E[b_i²] = 1/6.
        let mut rng = SampleRng::new(11, 0, 0);
        let n = 100_000;
        let mut m1 = [0.0f64; 3];
        let mut m2 = [0.0f64; 3];
        for _ in 0..n {
            let b = sample_uniform_triangle(rng.next_2d());
            assert!(b.min_element() >= 0.0 && (b.x + b.y + b.z - 1.0).abs() < 1e-5);
            for k in 0..3 {
                m1[k] += b[k] as f64;
                m2[k] += (b[k] as f64).powi(2);
            }
        }
        for k in 0..3 {
            let (a, b) = (m1[k] / n as f64, m2[k] / n as f64);
            // σ(b) = sqrt(1/18)/sqrt(n); σ(b²) ≤ 0.2/sqrt(n)
            assert!(
                (a - 1.0 / 3.0).abs() < 5.0 * (1.0f64 / 18.0 / n as f64).sqrt(),
                "{a}"
            );
            assert!((b - 1.0 / 6.0).abs() < 5.0 * 0.2 / (n as f64).sqrt(), "{b}");
        }
    }

    #[test]
    fn r2_points_are_uniform_and_stratified() {
        // 4096 R2 points: every one of 16×16 cells gets 16 ± 3 points
        // (random points would spread as ±4 at one σ).
        let off = Vec2::new(0.37, 0.81);
        let mut cells = [[0u32; 16]; 16];
        for i in 0..4096 {
            let p = r2_point(i, off);
            assert!(p.x >= 0.0 && p.x < 1.0 && p.y >= 0.0 && p.y < 1.0);
            cells[(p.x * 16.0) as usize][(p.y * 16.0) as usize] += 1;
        }
        for row in cells {
            for c in row {
                assert!((13..=19).contains(&c), "cell count {c}");
            }
        }
    }

    #[test]
    fn rng_is_keyed_and_uniform() {
        let a: Vec<u64> = {
            let mut r = SampleRng::new(1, 2, 3);
            (0..4).map(|_| r.next_u64()).collect()
        };
        let b: Vec<u64> = {
            let mut r = SampleRng::new(1, 2, 3);
            (0..4).map(|_| r.next_u64()).collect()
        };
        assert_eq!(a, b);
        let mut c = SampleRng::new(1, 2, 4);
        assert_ne!(a[0], c.next_u64());
        // mean and variance of next_f32: 1/2, 1/12
        let mut r = SampleRng::new(9, 9, 9);
        let n = 100_000;
        let (mut s, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let x = r.next_f32() as f64;
            assert!((0.0..1.0).contains(&x));
            s += x;
            s2 += x * x;
        }
        let m = s / n as f64;
        let v = s2 / n as f64 - m * m;
        assert!((m - 0.5).abs() < 5.0 * (1.0f64 / 12.0 / n as f64).sqrt());
        assert!((v - 1.0 / 12.0).abs() < 2e-3);
    }

    #[test]
    fn frame_is_orthonormal() {
        let mut rng = SampleRng::new(5, 5, 5);
        for _ in 0..1000 {
            let n = sample_uniform_sphere(rng.next_2d());
            let f = Frame::from_z(n);
            assert!((f.x.length() - 1.0).abs() < 1e-5);
            assert!((f.y.length() - 1.0).abs() < 1e-5);
            assert!(f.x.dot(f.y).abs() < 1e-5 && f.x.dot(n).abs() < 1e-5);
            assert!((f.x.cross(f.y) - n).length() < 1e-4, "right-handed");
        }
        // exactly -Z works too
        let f = Frame::from_z(Vec3::NEG_Z);
        assert!((f.x.cross(f.y) - Vec3::NEG_Z).length() < 1e-5);
    }

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        for (a, b) in [(0.3f32, 2.0f32), (1.0, 1.0), (5.0, 0.01)] {
            let w = power_heuristic(1.0, a, 1.0, b) + power_heuristic(1.0, b, 1.0, a);
            assert!((w - 1.0).abs() < 1e-6);
        }
        assert_eq!(power_heuristic(1.0, f32::INFINITY, 1.0, 3.0), 1.0);
        assert_eq!(power_heuristic(1.0, 0.0, 1.0, 0.0), 0.0);
    }
}
