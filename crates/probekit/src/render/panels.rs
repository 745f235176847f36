//! Composing the three panels side by side with their labels, the error
//! colour bar, and the overlay's edge lines.

use super::camera::Camera;
use super::shade::Px;
use super::ERROR_SCALE;
use crate::plot::{draw_text, heat, to_srgb};
use glam::Vec3;
use image::{Rgb, RgbImage};

/// Gap between panels, pixels.
pub(super) const GAP: u32 = 4;

const BG: Rgb<u8> = Rgb([30, 30, 34]);

const FG: Rgb<u8> = Rgb([235, 235, 235]);

/// Font scale for panels of width `w`.
fn text_scale(w: u32) -> i64 {
    if w >= 240 {
        2
    } else {
        1
    }
}

/// Height of the label strip above the panels.
pub(super) fn label_strip(w: u32) -> u32 {
    9 * text_scale(w) as u32 + 4
}

/// The three panels, labels, colour bar and numbers.
#[allow(clippy::too_many_arguments)]
pub(super) fn compose(
    px: &[Px],
    error: &[Option<f32>],
    w: u32,
    h: u32,
    exposure: f32,
    rel_rmse: f32,
    max_rel: f32,
    object_pixels: usize,
    probes: usize,
) -> RgbImage {
    let s = text_scale(w);
    let top = label_strip(w);
    let line = 9 * s as u32;
    let footer = 3 * line + 8;
    let total_w = 3 * w + 2 * GAP;
    let mut img = RgbImage::from_pixel(total_w, top + h + footer, BG);
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let p = &px[i];
            img.put_pixel(x, top + y, to_srgb(p.probes * exposure));
            img.put_pixel(w + GAP + x, top + y, to_srgb(p.reference * exposure));
            let e = match error[i] {
                Some(r) => heat(r / ERROR_SCALE),
                None => Vec3::splat(
                    0.35 * (p.reference * exposure)
                        .dot(probekit_sh::LUMINANCE)
                        .clamp(0.0, 1.0),
                ),
            };
            img.put_pixel(2 * (w + GAP) + x, top + y, to_srgb(e));
        }
    }
    // The middle panel path-traces the test objects only; the scene around
    // them is lit by the probes in both panels (module docs).
    for (k, name) in ["probes", "objects path traced", "error"]
        .iter()
        .enumerate()
    {
        draw_text(&mut img, (k as u32 * (w + GAP)) as i64 + 4, 2, name, s, FG);
    }
    draw_text(
        &mut img,
        (w + GAP) as i64 + 4,
        (top + h + 4) as i64,
        "scene: probes",
        s,
        FG,
    );
    // Footer: colour bar under the error panel, numbers below it.
    let (bx, by) = (2 * (w + GAP) + 4, top + h + 4);
    let bw = w.saturating_sub(8).max(1);
    for x in 0..bw {
        let c = to_srgb(heat(x as f32 / (bw.max(2) - 1) as f32));
        for y in by..by + line / 2 + 2 {
            if bx + x < total_w {
                img.put_pixel(bx + x, y, c);
            }
        }
    }
    let ty = (by + line / 2 + 4) as i64;
    draw_text(&mut img, bx as i64, ty, "0", s, FG);
    let scale_label = format!("{:.0}%", ERROR_SCALE * 100.0);
    let sw = crate::plot::font::text_width(&scale_label, s);
    draw_text(&mut img, (bx + bw) as i64 - sw, ty, &scale_label, s, FG);
    let numbers = if object_pixels > 0 {
        format!("RMSE {:.1}%  max {:.0}%", rel_rmse * 100.0, max_rel * 100.0)
    } else {
        "no object pixels".to_string()
    };
    draw_text(&mut img, bx as i64, ty + line as i64 + 2, &numbers, s, FG);
    let info = format!("{probes} probes, exposure x{exposure:.3}");
    draw_text(&mut img, 4, (top + h + 4) as i64, &info, s, FG);
    img
}

/// Draws segment `a`–`b` (world) as a thin line in the panel at `(ox, oy)`,
/// only where it is in front of `depth` (distance from the eye per pixel).
#[allow(clippy::too_many_arguments)]
pub(super) fn draw_edge(
    img: &mut RgbImage,
    ox: u32,
    oy: u32,
    cam: &Camera,
    w: u32,
    h: u32,
    depth: &[f32],
    a: Vec3,
    b: Vec3,
) {
    const NEAR: f32 = 0.02;
    let (mut va, mut vb) = (cam.to_view(a), cam.to_view(b));
    if va.z < NEAR && vb.z < NEAR {
        return;
    }
    // Clip to the near plane.
    if va.z < NEAR {
        va = va + (vb - va) * ((NEAR - va.z) / (vb.z - va.z));
    } else if vb.z < NEAR {
        vb = vb + (va - vb) * ((NEAR - vb.z) / (va.z - vb.z));
    }
    let (pa, pb) = (cam.view_to_pixel(va, w, h), cam.view_to_pixel(vb, w, h));
    let steps = ((pb.0 - pa.0).abs().max((pb.1 - pa.1).abs()).ceil() as usize).clamp(1, 20_000);
    let (r, u, f) = cam.basis();
    for k in 0..=steps {
        let s = k as f32 / steps as f32;
        let (x, y) = (pa.0 + (pb.0 - pa.0) * s, pa.1 + (pb.1 - pa.1) * s);
        if !(x >= 0.0 && y >= 0.0 && x < w as f32 && y < h as f32) {
            continue;
        }
        // Perspective-correct parameter along the 3-D segment.
        let q = (s / vb.z) / ((1.0 - s) / va.z + s / vb.z);
        let v = va + (vb - va) * q;
        let world = cam.eye + r * v.x + u * v.y + f * v.z;
        let dist = (world - cam.eye).length();
        let (xi, yi) = (x as u32, y as u32);
        let d = depth[(yi * w + xi) as usize];
        if dist < d * (1.0 - 2e-3) - 2e-3 {
            let p = img.get_pixel_mut(ox + xi, oy + yi);
            for c in 0..3 {
                p.0[c] = ((p.0[c] as u32 * 2 + [170u32, 225, 255][c] * 3) / 5) as u8;
            }
        }
    }
}
