//! Text for labels on sheets and previews: glyphs rasterised with ab_glyph from the DejaVu
//! Sans font shipped in `assets/fonts/` (Bitstream Vera licence), blended onto a tiny-skia
//! pixmap in premultiplied sRGB bytes, as tiny-skia stores them. tiny-skia has no text of
//! its own; ab_glyph is small, pure Rust and exact enough for labels.

use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};
use tiny_skia::{Pixmap, PremultipliedColorU8};

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

fn font() -> FontRef<'static> {
    // The font is compiled in and checked by the tests: failing to parse it is a build defect.
    FontRef::try_from_slice(FONT).expect("the shipped font parses")
}

/// Width in pixels of `text` at `size` pixels.
pub fn text_width(text: &str, size: f32) -> f32 {
    let f = font();
    let sf = f.as_scaled(PxScale::from(size));
    let mut w = 0.0;
    let mut prev = None;
    for ch in text.chars() {
        let id = sf.glyph_id(ch);
        if let Some(p) = prev {
            w += sf.kern(p, id);
        }
        w += sf.h_advance(id);
        prev = Some(id);
    }
    w
}

/// Draws `text` with its top-left corner at (x, y), `size` pixels high, in an opaque sRGB
/// colour (bytes); coverage is blended source-over.
pub fn draw_text(pixmap: &mut Pixmap, text: &str, x: f32, y: f32, size: f32, rgb: [u8; 3]) {
    let f = font();
    let sf = f.as_scaled(PxScale::from(size));
    let (w, h) = (pixmap.width() as i32, pixmap.height() as i32);
    let baseline = y + sf.ascent();
    let mut caret = x;
    let mut prev = None;
    let pixels = pixmap.pixels_mut();
    for ch in text.chars() {
        let id = sf.glyph_id(ch);
        if let Some(p) = prev {
            caret += sf.kern(p, id);
        }
        let glyph = id.with_scale_and_position(PxScale::from(size), point(caret, baseline));
        caret += sf.h_advance(id);
        prev = Some(id);
        let Some(outline) = f.outline_glyph(glyph) else { continue };
        let b = outline.px_bounds();
        outline.draw(|gx, gy, cover| {
            let (px, py) = (b.min.x as i32 + gx as i32, b.min.y as i32 + gy as i32);
            if px < 0 || py < 0 || px >= w || py >= h {
                return;
            }
            let dst = &mut pixels[(py * w + px) as usize];
            let a = cover.clamp(0.0, 1.0);
            let mix = |s: u8, d: u8| (s as f32 * a + d as f32 * (1.0 - a) + 0.5) as u8;
            let alpha = mix(255, dst.alpha());
            let c = [mix(rgb[0], dst.red()), mix(rgb[1], dst.green()), mix(rgb[2], dst.blue())];
            *dst = PremultipliedColorU8::from_rgba(c[0].min(alpha), c[1].min(alpha), c[2].min(alpha), alpha)
                .unwrap_or(*dst);
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_covers_pixels_where_it_is_drawn() {
        let mut p = Pixmap::new(80, 24).unwrap();
        p.fill(tiny_skia::Color::BLACK);
        draw_text(&mut p, "Hi", 2.0, 2.0, 16.0, [255, 255, 255]);
        let lit = p.pixels().iter().filter(|c| c.red() > 128).count();
        assert!(lit > 20, "{lit}");
        // Nothing right of the text's advance.
        let end = (2.0 + text_width("Hi", 16.0)).ceil() as usize + 1;
        assert!(p.pixels().iter().enumerate().all(|(i, c)| i % 80 < end || c.red() == 0));
        assert!(text_width("Hi", 16.0) > text_width("i", 16.0));
    }
}
