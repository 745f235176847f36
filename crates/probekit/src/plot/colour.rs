//! Colour helpers shared by every picture: linear → sRGB and a heat map.

use glam::Vec3;
use image::Rgb;

/// Linear RGB in `[0, 1]` (clamped) to 8-bit sRGB, with the piecewise sRGB
/// transfer function of IEC 61966-2-1 (12.92·v below 0.0031308, else
/// 1.055·v^(1/2.4) − 0.055).
pub fn to_srgb(c: Vec3) -> Rgb<u8> {
    let f = |v: f32| {
        let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
        let s = if v <= 0.003_130_8 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0).round() as u8
    };
    Rgb([f(c.x), f(c.y), f(c.z)])
}

/// A heat-map colour (linear RGB) for `t ∈ [0, 1]` (clamped): black → blue →
/// red → yellow → white, linear between five stops.
pub fn heat(t: f32) -> Vec3 {
    let stops = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.0, 0.05, 0.6),
        Vec3::new(0.8, 0.0, 0.05),
        Vec3::new(1.0, 0.8, 0.0),
        Vec3::new(1.0, 1.0, 1.0),
    ];
    let t = if t.is_nan() { 0.0 } else { t };
    let s = t.clamp(0.0, 1.0) * (stops.len() - 1) as f32;
    let i = (s as usize).min(stops.len() - 2);
    stops[i].lerp(stops[i + 1], s - i as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent values: the sRGB curve at 0, 1, the linear-segment end
    /// and 0.5 (0.5^(1/2.4)·1.055 − 0.055 = 0.7354 → 188), and the heat
    /// map's ends and monotone luminance.
    #[test]
    fn srgb_and_heat() {
        assert_eq!(to_srgb(Vec3::ZERO).0, [0, 0, 0]);
        assert_eq!(to_srgb(Vec3::ONE).0, [255, 255, 255]);
        assert_eq!(to_srgb(Vec3::splat(0.5)).0, [188, 188, 188]);
        assert_eq!(to_srgb(Vec3::splat(2.0)).0, [255, 255, 255]);
        assert_eq!(to_srgb(Vec3::splat(f32::NAN)).0, [0, 0, 0]);
        assert_eq!(heat(0.0), Vec3::ZERO);
        assert_eq!(heat(1.0), Vec3::ONE);
        let lum = |v: Vec3| v.dot(probekit_sh::LUMINANCE);
        let mut prev = -1.0;
        for k in 0..=20 {
            let l = lum(heat(k as f32 / 20.0));
            assert!(l >= prev - 0.06, "heat luminance drops at {k}");
            prev = l;
        }
    }
}
