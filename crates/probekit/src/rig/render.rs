//! Pictures of rigs (as in figures 1 and 7 of Yuan et al. 2011): a small CPU rasterizer
//! (orthographic view, z-buffer, per-vertex colours interpolated across
//! triangles) writing PNG through `image`.

use super::mesh::Mesh;
use crate::plot::{draw_text, heat, save_png, to_srgb};
use glam::Vec3;
use image::{Rgb, RgbImage};
use std::path::Path;

/// Panel size in pixels.
pub const PANEL_W: u32 = 320;
/// Panel height in pixels (including the label strip).
pub const PANEL_H: u32 = 220;
const LABEL_H: u32 = 20;

/// Why a picture could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{path}: cannot write image: {message}")]
pub struct RenderError {
    /// The output file.
    pub path: String,
    /// What failed.
    pub message: String,
}

/// View direction (from the object towards the eye) of every panel: front
/// right, above.
pub const VIEW_DIR: Vec3 = Vec3::new(0.55, 0.45, 0.7);

/// Rasterizes `mesh` with per-vertex `colors` (linear 0..1, gamma applied
/// here) into `img` at panel origin `(ox, oy)`.
pub fn draw_mesh(img: &mut RgbImage, ox: u32, oy: u32, mesh: &Mesh, colors: &[Vec3]) {
    let f = VIEW_DIR.normalize();
    let right = Vec3::Y.cross(f).normalize();
    let up = f.cross(right);
    let (c, r) = mesh.bounding_sphere();
    let (w, h) = (PANEL_W as f32, (PANEL_H - LABEL_H) as f32);
    let scale = 0.5 * w.min(h) / r * 0.98;
    let proj = |p: Vec3| {
        let q = p - c;
        Vec3::new(
            w * 0.5 + q.dot(right) * scale,
            h * 0.5 - q.dot(up) * scale,
            q.dot(f),
        )
    };
    let pts: Vec<Vec3> = mesh.positions.iter().map(|p| proj(*p)).collect();
    let mut z = vec![f32::NEG_INFINITY; (PANEL_W * PANEL_H) as usize];
    for t in &mesh.indices {
        let [a, b, cc] = t.map(|i| pts[i as usize]);
        let area = (b.x - a.x) * (cc.y - a.y) - (b.y - a.y) * (cc.x - a.x);
        if area.abs() < 1e-9 {
            continue;
        }
        let x0 = a.x.min(b.x).min(cc.x).floor().max(0.0) as i32;
        let x1 = a.x.max(b.x).max(cc.x).ceil().min(w - 1.0) as i32;
        let y0 = a.y.min(b.y).min(cc.y).floor().max(0.0) as i32;
        let y1 = a.y.max(b.y).max(cc.y).ceil().min(h - 1.0) as i32;
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
                let w0 = ((b.x - px) * (cc.y - py) - (b.y - py) * (cc.x - px)) / area;
                let w1 = ((cc.x - px) * (a.y - py) - (cc.y - py) * (a.x - px)) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let depth = w0 * a.z + w1 * b.z + w2 * cc.z;
                let zi = (y as u32 * PANEL_W + x as u32) as usize;
                if depth <= z[zi] {
                    continue;
                }
                z[zi] = depth;
                let col = colors[t[0] as usize] * w0
                    + colors[t[1] as usize] * w1
                    + colors[t[2] as usize] * w2;
                img.put_pixel(ox + x as u32, oy + LABEL_H + y as u32, to_srgb(col));
            }
        }
    }
}

/// Writes `text` at `(x, y)` in `color`, 2× scaled 5×7 font
/// ([`crate::plot::draw_text`]).
fn label(img: &mut RgbImage, x: u32, y: u32, text: &str, color: Rgb<u8>) {
    draw_text(img, x as i64, y as i64, text, 2, color);
}

/// One column of the comparison figure: a name, per-vertex irradiance and
/// (for rigs) the per-vertex error in grey levels.
pub struct Column<'a> {
    /// Label.
    pub name: String,
    /// Per-vertex irradiance (not divided by π).
    pub irradiance: &'a [Vec3],
    /// Per-vertex error in grey levels, `None` for the reference.
    pub error_grey: Option<Vec<f32>>,
}

/// Figure 1: top row the mesh lit by each column (reflected radiance
/// `E/π ÷ l_white`, albedo 1), bottom row the error heat maps (black 0 →
/// white ≥ `heat_max` grey levels).
pub fn comparison_figure(
    path: &Path,
    mesh: &Mesh,
    columns: &[Column],
    l_white: f32,
    heat_max: f32,
) -> Result<(), RenderError> {
    let n = columns.len() as u32;
    let mut img = RgbImage::from_pixel(PANEL_W * n, PANEL_H * 2 + LABEL_H, Rgb([40, 40, 44]));
    for (i, col) in columns.iter().enumerate() {
        let ox = i as u32 * PANEL_W;
        let shade: Vec<Vec3> = col
            .irradiance
            .iter()
            .map(|e| *e / std::f32::consts::PI / l_white)
            .collect();
        draw_mesh(&mut img, ox, 0, mesh, &shade);
        label(&mut img, ox + 6, 3, &col.name, Rgb([235, 235, 235]));
        if let Some(err) = &col.error_grey {
            let colors: Vec<Vec3> = err.iter().map(|g| heat(g / heat_max)).collect();
            draw_mesh(&mut img, ox, PANEL_H, mesh, &colors);
            let max = err.iter().cloned().fold(0.0f32, f32::max);
            label(
                &mut img,
                ox + 6,
                PANEL_H + 3,
                &format!("max {max:.1} grey"),
                Rgb([235, 235, 235]),
            );
        } else {
            label(
                &mut img,
                ox + 6,
                PANEL_H + 3,
                "reference",
                Rgb([235, 235, 235]),
            );
        }
    }
    // Legend of the heat map along the bottom.
    let y0 = PANEL_H * 2 + 2;
    let w = (PANEL_W * n).min(400);
    for x in 0..w {
        let c = to_srgb(heat(x as f32 / (w - 1) as f32));
        for y in y0..y0 + 6 {
            img.put_pixel(x + 4, y, c);
        }
    }
    label(
        &mut img,
        w + 10,
        y0 - 2,
        &format!("0..{heat_max} grey levels"),
        Rgb([235, 235, 235]),
    );
    save(&img, path)
}

/// Figure 7: the mesh lit with the split, beside the lights' zones
/// (analytic red, transition yellow, rig blue) drawn as discs at their
/// projected positions, with the object's bounding circle.
pub fn zones_figure(
    path: &Path,
    mesh_world: &Mesh,
    irradiance: &[Vec3],
    l_white: f32,
    lights: &[(Vec3, f32)],
) -> Result<(), RenderError> {
    let side = 2 * PANEL_W;
    let mut img = RgbImage::from_pixel(side * 2, side, Rgb([40, 40, 44]));
    // Left: the lit object (scaled up 2× by drawing into a big panel).
    let shade: Vec<Vec3> = irradiance
        .iter()
        .map(|e| *e / std::f32::consts::PI / l_white)
        .collect();
    let mut panel = RgbImage::from_pixel(PANEL_W, PANEL_H, Rgb([40, 40, 44]));
    draw_mesh(&mut panel, 0, 0, mesh_world, &shade);
    let big = image::imageops::resize(
        &panel,
        side,
        side * PANEL_H / PANEL_W,
        image::imageops::FilterType::Triangle,
    );
    image::imageops::overlay(&mut img, &big, 0, 0);
    label(&mut img, 6, 3, "split lighting", Rgb([235, 235, 235]));
    // Right: top-down map (x right, z down) of the lights around the object.
    let (c, r) = mesh_world.bounding_sphere();
    let extent = lights
        .iter()
        .map(|(p, _)| Vec3::new(p.x - c.x, 0.0, p.z - c.z).length())
        .fold(2.0 * r, f32::max)
        * 1.1;
    let s = 0.5 * side as f32 / extent;
    let to_px = |p: Vec3| {
        (
            side as f32 * 1.5 + (p.x - c.x) * s,
            side as f32 * 0.5 + (p.z - c.z) * s,
        )
    };
    let disc = |img: &mut RgbImage, (cx, cy): (f32, f32), rad: f32, col: Rgb<u8>, ring: bool| {
        let rr = rad.ceil() as i32 + 1;
        for dy in -rr..=rr {
            for dx in -rr..=rr {
                let d = ((dx * dx + dy * dy) as f32).sqrt();
                let inside = if ring {
                    (d - rad).abs() < 1.0
                } else {
                    d <= rad
                };
                let (x, y) = (cx as i32 + dx, cy as i32 + dy);
                if inside && x >= side as i32 && x < 2 * side as i32 && y >= 0 && y < side as i32 {
                    img.put_pixel(x as u32, y as u32, col);
                }
            }
        }
    };
    // The object's footprint (vertices from above) and bounding circle.
    for p in &mesh_world.positions {
        disc(&mut img, to_px(*p), 1.0, Rgb([150, 150, 150]), false);
    }
    disc(&mut img, to_px(c), r * s, Rgb([200, 200, 200]), true);
    for &(p, w) in lights {
        let col = if w <= 0.0 {
            Rgb([230, 60, 50])
        } else if w >= 1.0 {
            Rgb([70, 130, 240])
        } else {
            Rgb([240, 210, 40])
        };
        disc(&mut img, to_px(p), 6.0, col, false);
    }
    label(
        &mut img,
        side + 6,
        3,
        "top view: analytic",
        Rgb([230, 60, 50]),
    );
    label(&mut img, side + 6, 23, "transition", Rgb([240, 210, 40]));
    label(&mut img, side + 6, 43, "rig", Rgb([70, 130, 240]));
    save(&img, path)
}

fn save(img: &RgbImage, path: &Path) -> Result<(), RenderError> {
    save_png(img, path).map_err(|e| RenderError {
        path: path.display().to_string(),
        message: match e {
            crate::plot::PlotError::Write { message, .. } => message,
            other => other.to_string(),
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::mesh;

    /// The rasterizer covers the car's silhouette: a constant white colour
    /// fills a plausible fraction of the panel, and the z-buffer shows the
    /// nearest face (a two-colour car shows only the facing side's colour at
    /// the panel centre).
    #[test]
    fn rasterizer_fills_silhouette_and_keeps_nearest() {
        let car = mesh::car();
        let mut img = RgbImage::new(PANEL_W, PANEL_H);
        let f = VIEW_DIR.normalize();
        let colors: Vec<Vec3> = car
            .normals
            .iter()
            .map(|n| {
                if n.dot(f) > 0.0 {
                    Vec3::ONE
                } else {
                    Vec3::new(1.0, 0.0, 0.0)
                }
            })
            .collect();
        draw_mesh(&mut img, 0, 0, &car, &colors);
        let lit = img.pixels().filter(|p| p.0 != [0, 0, 0]).count() as f32;
        let frac = lit / (PANEL_W * PANEL_H) as f32;
        assert!(frac > 0.1 && frac < 0.8, "{frac}");
        let red = img.pixels().filter(|p| p.0 == [255, 0, 0]).count() as f32;
        assert!(red / lit < 0.05, "back faces visible: {}", red / lit);
    }
}
