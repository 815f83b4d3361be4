//! Comparison sheets: the same raw data coloured several ways, laid out in a labelled grid,
//! with optional overlays drawn with tiny-skia (a scale bar giving a length in the complex
//! plane, a marker at a point such as a Julia parameter).

use tiny_skia::{Color, Paint, PathBuilder, Pixmap, PixmapPaint, Rect, Stroke, Transform};

use super::text::{draw_text, text_width};
use crate::palette::color::linear_to_srgb8;

/// One cell: a label and its image (linear RGB, `width * height` pixels).
#[derive(Debug, Clone)]
pub struct Cell {
    /// Drawn at the cell's bottom-left.
    pub label: String,
    /// The pixels.
    pub rgb: Vec<[f32; 3]>,
}

/// Drawn over every cell.
#[derive(Debug, Clone, Default)]
pub struct Overlays {
    /// A scale bar: its length in pixels and its label.
    pub scale_bar: Option<(f32, String)>,
    /// A marker at this pixel position (x right, y down).
    pub marker: Option<[f32; 2]>,
}

/// Gap between cells, in pixels.
const GAP: u32 = 6;

/// Lays `cells` (each `width` x `height`) out `columns` to a row over a dark background.
pub fn sheet(cells: &[Cell], width: u32, height: u32, columns: u32, overlays: &Overlays) -> Option<Pixmap> {
    let columns = columns.clamp(1, cells.len().max(1) as u32);
    let rows = (cells.len() as u32).div_ceil(columns).max(1);
    let mut out = Pixmap::new(columns * width + (columns + 1) * GAP, rows * height + (rows + 1) * GAP)?;
    out.fill(Color::from_rgba8(24, 24, 28, 255));
    let label_size = (height as f32 / 14.0).clamp(11.0, 22.0);
    for (i, cell) in cells.iter().enumerate() {
        let mut pix = Pixmap::new(width, height)?;
        for (dst, c) in pix.pixels_mut().iter_mut().zip(&cell.rgb) {
            *dst = tiny_skia::PremultipliedColorU8::from_rgba(
                linear_to_srgb8(c[0]),
                linear_to_srgb8(c[1]),
                linear_to_srgb8(c[2]),
                255,
            )
            .unwrap_or(*dst);
        }
        draw_overlays(&mut pix, overlays, label_size);
        label(&mut pix, &cell.label, label_size);
        let (col, row) = (i as u32 % columns, i as u32 / columns);
        let (x, y) = (GAP + col * (width + GAP), GAP + row * (height + GAP));
        out.draw_pixmap(x as i32, y as i32, pix.as_ref(), &PixmapPaint::default(), Transform::identity(), None);
    }
    Some(out)
}

/// A label on a translucent dark box at the bottom-left corner.
fn label(pix: &mut Pixmap, text: &str, size: f32) {
    let pad = size * 0.3;
    let w = text_width(text, size) + 2.0 * pad;
    let h = size * 1.25 + pad;
    let y = pix.height() as f32 - h;
    if let Some(r) = Rect::from_xywh(0.0, y, w.min(pix.width() as f32), h) {
        let mut paint = Paint::default();
        paint.set_color(Color::from_rgba8(0, 0, 0, 170));
        pix.fill_rect(r, &paint, Transform::identity(), None);
    }
    draw_text(pix, text, pad, y + pad * 0.5, size, [255, 255, 255]);
}

fn draw_overlays(pix: &mut Pixmap, o: &Overlays, size: f32) {
    let mut white = Paint::default();
    white.set_color(Color::WHITE);
    white.anti_alias = true;
    let mut black = white.clone();
    black.set_color(Color::from_rgba8(0, 0, 0, 200));
    let stroke = |w: f32| Stroke { width: w, ..Stroke::default() };
    if let Some((len, text)) = &o.scale_bar {
        let w = pix.width() as f32;
        let (x1, y) = (w - size * 0.8, size * 1.2);
        let x0 = x1 - len;
        let mut pb = PathBuilder::new();
        pb.move_to(x0, y - size * 0.35);
        pb.line_to(x0, y);
        pb.line_to(x1, y);
        pb.line_to(x1, y - size * 0.35);
        if let Some(path) = pb.finish() {
            pix.stroke_path(&path, &black, &stroke(4.0), Transform::identity(), None);
            pix.stroke_path(&path, &white, &stroke(2.0), Transform::identity(), None);
        }
        let tw = text_width(text, size * 0.8);
        let tx = (x0 + x1 - tw) * 0.5;
        if let Some(r) = Rect::from_xywh(tx - 3.0, y + 3.0, tw + 6.0, size * 1.05) {
            pix.fill_rect(r, &black, Transform::identity(), None);
        }
        draw_text(pix, text, tx, y + 4.0, size * 0.8, [255, 255, 255]);
    }
    if let Some([x, y]) = o.marker {
        let r = size * 0.6;
        let mut pb = PathBuilder::new();
        pb.push_circle(x, y, r);
        for (dx, dy) in [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)] {
            pb.move_to(x + dx * r * 0.5, y + dy * r * 0.5);
            pb.line_to(x + dx * r * 1.6, y + dy * r * 1.6);
        }
        if let Some(path) = pb.finish() {
            pix.stroke_path(&path, &black, &stroke(3.5), Transform::identity(), None);
            pix.stroke_path(&path, &white, &stroke(1.5), Transform::identity(), None);
        }
    }
}

/// A scale bar about a quarter of the image wide: (length in pixels, label), for a pixel
/// spacing of 10^`log10_spacing` in the plane and an image `width` pixels wide. The
/// length is 1, 2 or 5 times a power of ten.
pub fn scale_bar(log10_spacing: f64, width: u32) -> (f32, String) {
    let target = log10_spacing + (width as f64 / 4.0).log10();
    let k = target.floor();
    let m = 10f64.powf(target - k);
    let nice = if m >= 5.0 {
        5.0
    } else if m >= 2.0 {
        2.0
    } else {
        1.0
    };
    let px = nice * 10f64.powf(k - log10_spacing);
    let label =
        if (-3.0..=3.0).contains(&k) { format!("{}", nice * 10f64.powi(k as i32)) } else { format!("{nice}e{k}") };
    (px as f32, label)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_bars_are_nice_lengths() {
        // Spacing 0.01 per pixel, 400 px: a quarter is 1.0 in the plane = 100 px.
        assert_eq!(scale_bar(-2.0, 400), (100.0, "1".to_string()));
        // Spacing 1e-300, 1000 px: a quarter is 2.5e-298 -> 2e-298, 200 px.
        let (px, text) = scale_bar(-300.0, 1000);
        assert!((px - 200.0).abs() < 1e-3, "{px}");
        assert_eq!(text, "2e-298");
        let (px, _) = scale_bar(-1234.5, 640);
        assert!(px > 640.0 / 10.0 && px <= 640.0 / 4.0 + 1e-3);
    }

    #[test]
    fn cells_are_laid_out_in_a_grid() {
        let red = Cell { label: "a".into(), rgb: vec![[1.0, 0.0, 0.0]; 20 * 10] };
        let blue = Cell { label: "b".into(), rgb: vec![[0.0, 0.0, 1.0]; 20 * 10] };
        let s = sheet(&[red.clone(), blue, red], 20, 10, 2, &Overlays::default()).unwrap();
        assert_eq!((s.width(), s.height()), (2 * 20 + 3 * GAP, 2 * 10 + 3 * GAP));
        let at = |x: u32, y: u32| s.pixel(x, y).unwrap();
        assert_eq!((at(GAP + 15, GAP + 1).red(), at(GAP + 15, GAP + 1).blue()), (255, 0));
        assert_eq!(at(2 * GAP + 20 + 15, GAP + 1).blue(), 255);
        assert_eq!(at(GAP + 15, 2 * GAP + 10 + 1).red(), 255);
    }
}
