//! tiny-skia's blend of an opaque layer over an opaque base, as one table per blend mode and
//! opacity.
//!
//! A layer is drawn over the stack with tiny-skia's `draw_pixmap`, whose pattern shader
//! runs the floating-point ("highp") raster pipeline: per pixel, a gather, the opacity's
//! scale, a load of the destination, the blend and a store, eight lanes at a time. Every
//! blend mode a layer can have is separable: a channel's result depends only on that
//! channel's source and destination bytes and on the two alphas. Where the layer's pixel
//! and the base's are both opaque (alpha 255: most layers, and the base always starts
//! opaque), the result is therefore a function of two bytes, and one draw of a 256×256
//! pixmap by tiny-skia itself tabulates it: the table holds tiny-skia's own bytes (its
//! rounding, its reciprocal estimates on this CPU), not a second implementation of its
//! formulas. Blending a 4K two-layer recolour through the table takes three look-ups per
//! pixel instead of the pipeline's stages (which were an eighth of that recolour's
//! instructions). Pixels that are not both opaque still go through tiny-skia.

use std::cell::RefCell;

use tiny_skia::{Pixmap, PixmapPaint, PremultipliedColorU8, Transform};

/// tiny-skia's result for an opaque source byte `s` drawn over an opaque destination byte
/// `d`, at `s * 256 + d`, for every channel, and the result's alpha (the same for every
/// pair: both inputs are opaque).
pub struct BlendTable {
    codes: Box<[u8; 65536]>,
    alpha: u8,
}

impl BlendTable {
    /// Tabulates `mode` at `opacity` by drawing every (source, destination) byte pair with
    /// tiny-skia. None if tiny-skia cannot allocate the 256×256 pixmaps.
    pub fn build(mode: tiny_skia::BlendMode, opacity: f32) -> Option<Self> {
        let mut src = Pixmap::new(256, 256)?;
        let mut dst = Pixmap::new(256, 256)?;
        for (k, (s, d)) in src.pixels_mut().iter_mut().zip(dst.pixels_mut().iter_mut()).enumerate() {
            let (hi, lo) = ((k >> 8) as u8, k as u8);
            // Red and blue carry the pair one way round, green the other, so both orders
            // of every channel position are drawn and checked to agree below.
            *s = PremultipliedColorU8::from_rgba(hi, lo, hi, 255)?;
            *d = PremultipliedColorU8::from_rgba(lo, hi, lo, 255)?;
        }
        let paint = PixmapPaint { opacity, blend_mode: mode, quality: tiny_skia::FilterQuality::Nearest };
        dst.draw_pixmap(0, 0, src.as_ref(), &paint, Transform::identity(), None);
        let mut codes = Box::new([0u8; 65536]);
        let alpha = dst.pixels()[0].alpha();
        for (code, p) in codes.iter_mut().zip(dst.pixels()) {
            *code = p.red();
        }
        // Separability, checked rather than assumed: blue saw the same pairs as red, green
        // the swapped ones, and every pixel's alpha is the same.
        for (k, p) in dst.pixels().iter().enumerate() {
            if p.blue() != p.red() || p.green() != codes[(k & 255) << 8 | k >> 8] || p.alpha() != alpha {
                return None;
            }
        }
        Some(BlendTable { codes, alpha })
    }

    /// Blends `layer` over `base` (RGBA bytes, premultiplied, the same length), every pixel
    /// of both opaque (alpha 255): the caller knows, having painted the one and blended the
    /// other. Returns whether the result is opaque too.
    pub fn blend_opaque(&self, base: &mut [u8], layer: &[u8]) -> bool {
        debug_assert!(layer.chunks_exact(4).chain(base.chunks_exact(4)).all(|p| p[3] == 255));
        let t = &*self.codes;
        for (d, s) in base.chunks_exact_mut(4).zip(layer.chunks_exact(4)) {
            let at = |c: usize| t[(s[c] as usize) << 8 | d[c] as usize];
            let out = [at(0), at(1), at(2), self.alpha];
            d.copy_from_slice(&out);
        }
        self.alpha == 255
    }
}

/// The table of `mode` at `opacity`, built once per thread and kept (a stack has a few
/// layers; the last few tables are enough). None where the mode is not separable.
pub fn with_table<R>(mode: tiny_skia::BlendMode, opacity: f32, f: impl FnOnce(Option<&BlendTable>) -> R) -> R {
    type Entry = (tiny_skia::BlendMode, u32, Option<BlendTable>);
    thread_local! {
        static TABLES: RefCell<Vec<Entry>> = const { RefCell::new(Vec::new()) };
    }
    const KEEP: usize = 8;
    TABLES.with_borrow_mut(|tables| {
        let key = (mode, opacity.to_bits());
        let i = match tables.iter().position(|(m, o, _)| (*m, *o) == key) {
            Some(i) => i,
            None => {
                if tables.len() == KEEP {
                    tables.remove(0);
                }
                tables.push((mode, key.1, BlendTable::build(mode, opacity)));
                tables.len() - 1
            }
        };
        f(tables[i].2.as_ref())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Random opaque pixels (a fixed xorshift sequence).
    fn pixmap(seed: u64, w: u32, h: u32) -> Pixmap {
        let mut p = Pixmap::new(w, h).expect("pixmap");
        let mut x = seed;
        for px in p.pixels_mut() {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let c = |k: u32| (x >> (8 * k)) as u8;
            *px = PremultipliedColorU8::from_rgba(c(0), c(1), c(2), 255).expect("opaque");
        }
        p
    }

    /// For every mode a layer can have and a range of opacities, the table gives tiny-skia's
    /// bytes for opaque layers over opaque bases of random colours (every channel
    /// independent, so a mode that mixed channels would fail here).
    #[test]
    fn tables_give_tiny_skias_bytes() {
        for (m, mode) in crate::compose::BlendMode::ALL.map(crate::compose::BlendMode::skia).into_iter().enumerate() {
            for (o, &opacity) in [1.0f32, 0.6, 0.25, 0.999, 0.01, 0.0].iter().enumerate() {
                let table = BlendTable::build(mode, opacity).expect("separable");
                let seed = 1 + (m * 8 + o) as u64;
                let (layer, mut want) = (pixmap(seed, 97, 61), pixmap(seed ^ 0xABCD, 97, 61));
                let mut got = want.clone();
                want.draw_pixmap(
                    0,
                    0,
                    layer.as_ref(),
                    &PixmapPaint { opacity, blend_mode: mode, quality: tiny_skia::FilterQuality::Nearest },
                    Transform::identity(),
                    None,
                );
                table.blend_opaque(got.data_mut(), layer.data());
                assert_eq!(got.data(), want.data(), "{mode:?} at opacity {opacity}");
            }
        }
    }
}
