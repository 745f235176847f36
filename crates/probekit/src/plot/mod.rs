//! The project's one plotting helper: bar charts and line charts as PNG.
//!
//! Drawn with the `image` crate and a hand-made 5×7 bitmap font ([`font`]),
//! so no system fonts (and no font crate) are needed and output is identical
//! on every machine. Files are written to a temporary sibling and renamed, so
//! a reader never sees a half-written PNG.

pub mod colour;
pub mod font;

pub use colour::{heat, to_srgb};
pub use font::draw_text;

use image::{Rgb, RgbImage};
use std::path::{Path, PathBuf};

/// Why a plot could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlotError {
    /// Writing or renaming the file failed.
    #[error("{}: cannot write plot: {message}", path.display())]
    Write {
        /// The output file.
        path: PathBuf,
        /// What failed.
        message: String,
    },
    /// The data cannot be plotted (mismatched lengths, no finite values,
    /// non-positive x on a log axis).
    #[error("{}: cannot plot: {message}", path.display())]
    BadData {
        /// The output file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

const W: u32 = 1000;
const H: u32 = 600;
const WHITE: Rgb<u8> = Rgb([255, 255, 255]);
const BLACK: Rgb<u8> = Rgb([20, 20, 20]);
const GRID: Rgb<u8> = Rgb([225, 225, 225]);
/// Series colours (colour-blind-safe Okabe–Ito palette).
const PALETTE: [Rgb<u8>; 8] = [
    Rgb([0, 114, 178]),
    Rgb([213, 94, 0]),
    Rgb([0, 158, 115]),
    Rgb([204, 121, 167]),
    Rgb([230, 159, 0]),
    Rgb([86, 180, 233]),
    Rgb([120, 120, 120]),
    Rgb([240, 228, 66]),
];

struct Canvas {
    img: RgbImage,
}

impl Canvas {
    fn new() -> Self {
        Self {
            img: RgbImage::from_pixel(W, H, WHITE),
        }
    }

    fn put(&mut self, x: i64, y: i64, c: Rgb<u8>) {
        if x >= 0 && y >= 0 && (x as u32) < W && (y as u32) < H {
            self.img.put_pixel(x as u32, y as u32, c);
        }
    }

    fn rect(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, c: Rgb<u8>) {
        for y in y0.min(y1)..=y0.max(y1) {
            for x in x0.min(x1)..=x0.max(x1) {
                self.put(x, y, c);
            }
        }
    }

    /// Line of width `t` pixels (Bresenham with a square brush).
    fn line(&mut self, (x0, y0): (i64, i64), (x1, y1): (i64, i64), t: i64, c: Rgb<u8>) {
        let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
        let (sx, sy) = (if x0 < x1 { 1 } else { -1 }, if y0 < y1 { 1 } else { -1 });
        let (mut x, mut y, mut err) = (x0, y0, dx + dy);
        let r = t / 2;
        loop {
            self.rect(x - r, y - r, x - r + t - 1, y - r + t - 1, c);
            if x == x1 && y == y1 {
                break;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x += sx;
            }
            if e2 <= dx {
                err += dx;
                y += sy;
            }
        }
    }

    /// Text with its top-left at `(x, y)`, glyphs scaled by `s`; `vertical`
    /// draws it rotated 90° counter-clockwise (reading bottom to top), with
    /// `(x, y)` then the bottom-left.
    fn text(&mut self, x: i64, y: i64, s: &str, scale: i64, c: Rgb<u8>, vertical: bool) {
        if !vertical {
            font::draw_text(&mut self.img, x, y, s, scale, c);
            return;
        }
        let adv = (font::GLYPH_W as i64 + 1) * scale;
        for (i, ch) in s.chars().enumerate() {
            let g = font::glyph(ch);
            for (row, bits) in g.iter().enumerate() {
                for col in 0..font::GLYPH_W as i64 {
                    if bits >> (font::GLYPH_W as i64 - 1 - col) & 1 == 1 {
                        let (px, py) = (i as i64 * adv + col * scale, row as i64 * scale);
                        self.rect(x + py, y - px - scale + 1, x + py + scale - 1, y - px, c);
                    }
                }
            }
        }
    }

    fn save(&self, path: &Path) -> Result<(), PlotError> {
        save_png(&self.img, path)
    }
}

/// Writes `img` as a PNG to a temporary sibling of `path` and renames it into
/// place, so a reader never sees a half-written file. The one PNG writer of
/// the project's pictures (plots, rig figures, renders).
pub fn save_png(img: &RgbImage, path: &Path) -> Result<(), PlotError> {
    let err = |m: String| PlotError::Write {
        path: path.to_path_buf(),
        message: m,
    };
    let name = path
        .file_name()
        .ok_or_else(|| err("not a file name".into()))?
        .to_string_lossy()
        .into_owned();
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    img.save_with_format(&tmp, image::ImageFormat::Png)
        .map_err(|e| err(e.to_string()))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        err(e.to_string())
    })
}

fn text_width(s: &str, scale: i64) -> i64 {
    font::text_width(s, scale)
}

/// "Nice" tick step covering `range` in about `n` steps (1, 2 or 5 × 10^k).
fn nice_step(range: f64, n: f64) -> f64 {
    let raw = (range / n).max(f64::MIN_POSITIVE);
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    let nice = if f <= 1.0 {
        1.0
    } else if f <= 2.0 {
        2.0
    } else if f <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * mag
}

/// Compact number label: up to 4 significant digits, scientific when tiny/huge.
fn fmt_num(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.1e}");
    }
    let s = format!(
        "{:.*}",
        (3 - a.log10().floor() as i64).clamp(0, 6) as usize,
        v
    );
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

// Plot area margins.
const LEFT: i64 = 110;
const RIGHT: i64 = 30;
const TOP: i64 = 60;

fn title_and_axes(c: &mut Canvas, title: &str, y_label: &str, bottom: i64) {
    let tw = text_width(title, 3);
    c.text((W as i64 - tw) / 2, 15, title, 3, BLACK, false);
    let lw = text_width(y_label, 2);
    c.text(12, TOP + (bottom - TOP + lw) / 2, y_label, 2, BLACK, true);
}

/// Draws y grid lines and labels for `[0, ymax]` between pixel rows
/// `bottom` and `TOP`; returns the y value → pixel row mapping's `ymax`.
fn y_axis(c: &mut Canvas, ymin: f64, ymax: f64, bottom: i64) -> (f64, f64) {
    let step = nice_step(ymax - ymin, 6.0);
    let lo = (ymin / step).floor() * step;
    let hi = (ymax / step).ceil() * step;
    let hi = if hi <= lo { lo + step } else { hi };
    let to_px = |v: f64| bottom - ((v - lo) / (hi - lo) * (bottom - TOP) as f64).round() as i64;
    let mut v = lo;
    while v <= hi + step * 1e-6 {
        let y = to_px(v);
        c.line((LEFT, y), (W as i64 - RIGHT, y), 1, GRID);
        let s = fmt_num(v);
        c.text(LEFT - 8 - text_width(&s, 2), y - 7, &s, 2, BLACK, false);
        v += step;
    }
    (lo, hi)
}

/// Draws y grid lines at the decades `10^lo ..= 10^hi` (`lo`, `hi` whole
/// log10 values) between pixel rows `bottom` and `TOP`, with faint lines at
/// 2× and 5× each decade.
fn log_y_axis(c: &mut Canvas, lo: f64, hi: f64, bottom: i64) {
    let to_px = |v: f64| bottom - ((v - lo) / (hi - lo) * (bottom - TOP) as f64).round() as i64;
    let mut k = lo;
    while k <= hi + 1e-9 {
        let y = to_px(k);
        c.line((LEFT, y), (W as i64 - RIGHT, y), 1, GRID);
        let s = fmt_num(10f64.powf(k));
        c.text(LEFT - 8 - text_width(&s, 2), y - 7, &s, 2, BLACK, false);
        if k < hi {
            for m in [2.0f64, 5.0] {
                let y = to_px(k + m.log10());
                c.line((LEFT, y), (LEFT + 8, y), 1, BLACK);
            }
        }
        k += 1.0;
    }
}

/// Writes a bar chart PNG (1000×600): one bar per `(label, value)`, the value
/// printed above its bar, labels written vertically under the bars.
/// Non-finite values are drawn as an empty slot marked `n/a`.
///
/// Errors: `labels` and `values` of different lengths, no finite value, or a
/// file that cannot be written.
pub fn bar_chart(
    path: impl AsRef<Path>,
    title: &str,
    labels: &[String],
    values: &[f64],
    y_label: &str,
) -> Result<(), PlotError> {
    let path = path.as_ref();
    let bad = |m: &str| PlotError::BadData {
        path: path.to_path_buf(),
        message: m.into(),
    };
    if labels.len() != values.len() {
        return Err(bad("labels and values differ in length"));
    }
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.is_empty() {
        return Err(bad("no finite values"));
    }
    let label_px = labels.iter().map(|l| text_width(l, 2)).max().unwrap_or(0);
    let bottom = H as i64 - 20 - label_px.min(260);
    let mut c = Canvas::new();
    title_and_axes(&mut c, title, y_label, bottom);
    // 8 % headroom so the value printed above the tallest bar stays inside
    let ymax = finite.iter().copied().fold(0.0f64, f64::max) * 1.08;
    let ymin = finite.iter().copied().fold(0.0f64, f64::min);
    let (lo, hi) = y_axis(
        &mut c,
        ymin,
        if ymax > ymin { ymax } else { ymin + 1.0 },
        bottom,
    );
    let to_px = |v: f64| bottom - ((v - lo) / (hi - lo) * (bottom - TOP) as f64).round() as i64;
    let n = values.len() as i64;
    let slot = (W as i64 - RIGHT - LEFT) / n.max(1);
    let bw = (slot * 6 / 10).max(2);
    for (i, (l, v)) in labels.iter().zip(values).enumerate() {
        let x0 = LEFT + i as i64 * slot + (slot - bw) / 2;
        let colour = PALETTE[i % PALETTE.len()];
        let cx = x0 + bw / 2;
        if v.is_finite() {
            c.rect(x0, to_px(*v), x0 + bw, to_px(0.0f64.max(lo)), colour);
            let s = fmt_num(*v);
            c.text(
                cx - text_width(&s, 2) / 2,
                to_px(*v) - 20,
                &s,
                2,
                BLACK,
                false,
            );
        } else {
            c.text(
                cx - text_width("n/a", 2) / 2,
                bottom - 20,
                "n/a",
                2,
                BLACK,
                false,
            );
        }
        c.text(cx - 7, bottom + 8 + text_width(l, 2), l, 2, BLACK, true);
    }
    c.line((LEFT, TOP), (LEFT, bottom), 2, BLACK);
    c.line(
        (LEFT, to_px(0.0f64.max(lo))),
        (W as i64 - RIGHT, to_px(0.0f64.max(lo))),
        2,
        BLACK,
    );
    c.save(path)
}

/// Writes a line chart PNG (1000×600): each series a polyline with square
/// markers in its own colour, a legend at the top right; `log_x` puts x on a
/// base-10 log scale (decade ticks), otherwise linear. Points with a
/// non-finite coordinate are skipped.
///
/// Errors: no finite point, `log_x` with a non-positive x, or a file that
/// cannot be written.
pub fn line_chart(
    path: impl AsRef<Path>,
    title: &str,
    series: &[(String, Vec<(f64, f64)>)],
    x_label: &str,
    y_label: &str,
    log_x: bool,
) -> Result<(), PlotError> {
    line_chart_log(path, title, series, x_label, y_label, log_x, false)
}

/// [`line_chart`] with a choice of log scale per axis: `log_y` puts y on a
/// base-10 log scale too (decade ticks, the range widened to whole decades).
///
/// Errors: as [`line_chart`], and `log_y` with a non-positive y.
pub fn line_chart_log(
    path: impl AsRef<Path>,
    title: &str,
    series: &[(String, Vec<(f64, f64)>)],
    x_label: &str,
    y_label: &str,
    log_x: bool,
    log_y: bool,
) -> Result<(), PlotError> {
    let path = path.as_ref();
    let bad = |m: &str| PlotError::BadData {
        path: path.to_path_buf(),
        message: m.into(),
    };
    let pts: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|(_, p)| p.iter().copied())
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    if pts.is_empty() {
        return Err(bad("no finite points"));
    }
    if log_x && pts.iter().any(|(x, _)| *x <= 0.0) {
        return Err(bad("log x axis needs positive x values"));
    }
    if log_y && pts.iter().any(|(_, y)| *y <= 0.0) {
        return Err(bad("log y axis needs positive y values"));
    }
    let fx = |x: f64| if log_x { x.log10() } else { x };
    let fy = |y: f64| if log_y { y.log10() } else { y };
    let bottom = H as i64 - 70;
    let mut c = Canvas::new();
    title_and_axes(&mut c, title, y_label, bottom);
    let (mut ymin, mut ymax) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(fy(p.1)), b.max(fy(p.1)))
        });
    let (lo, hi) = if log_y {
        let lo = ymin.floor();
        let hi = ymax.ceil().max(lo + 1.0);
        log_y_axis(&mut c, lo, hi, bottom);
        (lo, hi)
    } else {
        ymin = ymin.min(0.0);
        if ymax <= ymin {
            ymax = ymin + 1.0;
        }
        y_axis(&mut c, ymin, ymax, bottom)
    };
    let (mut xmin, mut xmax) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(fx(p.0)), b.max(fx(p.0)))
        });
    if log_x {
        xmin = xmin.floor();
        xmax = xmax.ceil();
    }
    if xmax <= xmin {
        xmax = xmin + 1.0;
    }
    let right = W as i64 - RIGHT;
    let to_x =
        |x: f64| LEFT + ((fx(x) - xmin) / (xmax - xmin) * (right - LEFT) as f64).round() as i64;
    let to_y = |y: f64| bottom - ((fy(y) - lo) / (hi - lo) * (bottom - TOP) as f64).round() as i64;
    // x ticks
    let ticks: Vec<f64> = if log_x {
        (xmin as i64..=xmax as i64)
            .map(|k| 10f64.powi(k as i32))
            .collect()
    } else {
        let step = nice_step(xmax - xmin, 8.0);
        let mut v = (xmin / step).ceil() * step;
        let mut t = Vec::new();
        while v <= xmax + step * 1e-6 {
            t.push(v);
            v += step;
        }
        t
    };
    for t in ticks {
        let x = to_x(t);
        c.line((x, TOP), (x, bottom), 1, GRID);
        let s = fmt_num(t);
        c.text(x - text_width(&s, 2) / 2, bottom + 10, &s, 2, BLACK, false);
    }
    let xl = text_width(x_label, 2);
    c.text(
        LEFT + (right - LEFT - xl) / 2,
        bottom + 38,
        x_label,
        2,
        BLACK,
        false,
    );
    c.line((LEFT, TOP), (LEFT, bottom), 2, BLACK);
    c.line((LEFT, bottom), (right, bottom), 2, BLACK);
    for (k, (name, p)) in series.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let good: Vec<(i64, i64)> = p
            .iter()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|(x, y)| (to_x(*x), to_y(*y)))
            .collect();
        for w in good.windows(2) {
            c.line(w[0], w[1], 3, colour);
        }
        for (x, y) in &good {
            c.rect(x - 4, y - 4, x + 4, y + 4, colour);
        }
        let ly = TOP + 10 + k as i64 * 24;
        let lx = right - 20 - text_width(name, 2) - 40;
        c.rect(lx, ly + 2, lx + 28, ly + 10, colour);
        c.text(lx + 36, ly, name, 2, BLACK, false);
    }
    c.save(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(p: &Path) -> RgbImage {
        image::open(p).unwrap().into_rgb8()
    }

    #[test]
    fn bar_chart_draws_bars_of_proportional_height() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bars.png");
        let labels: Vec<String> = ["a", "b"].iter().map(|s| s.to_string()).collect();
        bar_chart(&p, "T", &labels, &[1.0, 2.0], "y").unwrap();
        let img = decode(&p);
        assert_eq!(img.dimensions(), (W, H));
        // measure each bar's height in its first palette colour
        let height = |c: Rgb<u8>| {
            (0..H)
                .filter(|&y| (0..W).any(|x| *img.get_pixel(x, y) == c))
                .count() as f64
        };
        let (h1, h2) = (height(PALETTE[0]), height(PALETTE[1]));
        assert!(h1 > 10.0);
        assert!((h2 / h1 - 2.0).abs() < 0.05, "{h1} {h2}");
        // no temp file left behind
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn line_chart_and_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("lines.png");
        let s = vec![
            (
                "l1".to_string(),
                vec![(10.0, 0.3), (100.0, 0.2), (1000.0, 0.1)],
            ),
            (
                "l2".to_string(),
                vec![(10.0, 0.2), (100.0, 0.1), (1000.0, 0.05)],
            ),
        ];
        line_chart(&p, "error vs probes", &s, "probes", "rel. RMSE", true).unwrap();
        let img = decode(&p);
        assert!(img.pixels().any(|c| *c == PALETTE[1]));
        let bad = vec![("x".to_string(), vec![(0.0, 1.0)])];
        assert!(matches!(
            line_chart(&p, "t", &bad, "x", "y", true),
            Err(PlotError::BadData { .. })
        ));
        assert!(matches!(
            bar_chart(&p, "t", &["a".to_string()], &[1.0, 2.0], "y"),
            Err(PlotError::BadData { .. })
        ));
        let missing = dir.path().join("no/such/dir/x.png");
        assert!(matches!(
            bar_chart(&missing, "t", &["a".to_string()], &[1.0], "y"),
            Err(PlotError::Write { .. })
        ));
    }

    #[test]
    fn log_log_chart_draws_a_power_law_straight() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("loglog.png");
        // y = x / 100: a straight line on log-log axes, not on a linear y axis.
        let s = vec![(
            "s".to_string(),
            vec![(1.0, 0.01), (10.0, 0.1), (100.0, 1.0)],
        )];
        line_chart_log(&p, "t", &s, "x", "y", true, true).unwrap();
        let img = decode(&p);
        let right = W as i64 - RIGHT;
        let mean_row = |f: f64| {
            let x = (LEFT as f64 + f * (right - LEFT) as f64).round() as u32;
            let rows: Vec<u32> = (0..H)
                .filter(|&y| *img.get_pixel(x, y) == PALETTE[0])
                .collect();
            assert!(!rows.is_empty(), "no line at column {x}");
            rows.iter().sum::<u32>() as f64 / rows.len() as f64
        };
        let (a, b, c) = (mean_row(0.25), mean_row(0.5), mean_row(0.75));
        assert!((b - 0.5 * (a + c)).abs() < 2.0, "{a} {b} {c}");
        // Two decades over the plot height: a quarter of the width is half a decade.
        let bottom = H as i64 - 70;
        let half_decade = (bottom - TOP) as f64 / 4.0;
        assert!(((a - c) - half_decade * 2.0).abs() < 3.0, "{a} {c}");
        let bad = vec![("x".to_string(), vec![(1.0, 0.0)])];
        assert!(matches!(
            line_chart_log(&p, "t", &bad, "x", "y", false, true),
            Err(PlotError::BadData { .. })
        ));
    }

    #[test]
    fn number_labels() {
        assert_eq!(fmt_num(0.25), "0.25");
        assert_eq!(fmt_num(12.0), "12");
        assert_eq!(fmt_num(0.0), "0");
        assert_eq!(nice_step(10.0, 5.0), 2.0);
        assert_eq!(nice_step(0.3, 6.0), 0.05);
    }
}
