//! Layer stacks: colourings composited in order with tiny-skia, then downsampled.
//!
//! Blending happens where tiny-skia blends: on premultiplied 8-bit sRGB-encoded pixels,
//! with the separable and non-separable modes of the W3C compositing spec (as CSS and
//! image editors blend). A stack of a single opaque "normal" layer needs no blending and
//! stays in linear f32 end to end, which is what keeps 16-bit PNGs truly 16-bit. The final
//! downsampling of supersampled pixels always averages in linear light.

pub mod sheet;
mod table;
pub mod text;

use tiny_skia::{Pixmap, PixmapPaint, PremultipliedColorU8, Transform};

use crate::coloring::{Coloring, Context, Histogram, Mask};
use crate::field::{Needs, Planes};
use crate::palette::color::{Srgb8Encoder, linear_to_srgb, linear_to_srgb8, srgb8_to_linear};
use crate::trap::Trap;
use crate::trap::TrapKind;

/// How a layer combines with what is below it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BlendMode {
    /// Source over.
    #[default]
    Normal,
    /// Multiply.
    Multiply,
    /// Screen.
    Screen,
    /// Overlay.
    Overlay,
    /// Darken.
    Darken,
    /// Lighten.
    Lighten,
    /// Difference.
    Difference,
    /// Soft light.
    SoftLight,
    /// Hard light.
    HardLight,
    /// Colour dodge.
    ColorDodge,
    /// Colour burn.
    ColorBurn,
    /// Exclusion.
    Exclusion,
    /// Additive.
    Plus,
}

impl BlendMode {
    /// Every mode, in the order menus list them.
    pub const ALL: [BlendMode; 13] = [
        BlendMode::Normal,
        BlendMode::Multiply,
        BlendMode::Screen,
        BlendMode::Overlay,
        BlendMode::Darken,
        BlendMode::Lighten,
        BlendMode::Difference,
        BlendMode::SoftLight,
        BlendMode::HardLight,
        BlendMode::ColorDodge,
        BlendMode::ColorBurn,
        BlendMode::Exclusion,
        BlendMode::Plus,
    ];

    /// The mode's name in scene files (its serde name, declared once by the derive).
    pub fn name(self) -> String {
        toml::Value::try_from(self).ok().and_then(|v| v.as_str().map(str::to_string)).unwrap_or_default()
    }

    fn skia(self) -> tiny_skia::BlendMode {
        use tiny_skia::BlendMode as B;
        match self {
            BlendMode::Normal => B::SourceOver,
            BlendMode::Multiply => B::Multiply,
            BlendMode::Screen => B::Screen,
            BlendMode::Overlay => B::Overlay,
            BlendMode::Darken => B::Darken,
            BlendMode::Lighten => B::Lighten,
            BlendMode::Difference => B::Difference,
            BlendMode::SoftLight => B::SoftLight,
            BlendMode::HardLight => B::HardLight,
            BlendMode::ColorDodge => B::ColorDodge,
            BlendMode::ColorBurn => B::ColorBurn,
            BlendMode::Exclusion => B::Exclusion,
            BlendMode::Plus => B::Plus,
        }
    }
}

/// A colouring with its blend mode and opacity.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// What it paints.
    pub coloring: Coloring,
    /// How it blends.
    pub blend: BlendMode,
    /// Its opacity in [0, 1].
    pub opacity: f32,
    /// Where it applies (None: everywhere).
    pub mask: Option<Mask>,
}

/// A layer that colours from a trap plane of another kind than the planes hold (see
/// [`Stack::check_traps`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "layer {layer} colours from trap {trap}'s {} data, but the planes hold {}",
    wanted.name(),
    match found { Some(kind) => format!("{} data for trap {trap}", kind.name()), None => format!("no trap {trap}") }
)]
pub struct TrapMismatch {
    /// The layer, counted from 1 at the bottom as in the scene file.
    pub layer: usize,
    /// The trap's index.
    pub trap: usize,
    /// What the layer colours from.
    pub wanted: TrapKind,
    /// What the planes hold for that trap, if anything.
    pub found: Option<TrapKind>,
}

/// An ordered stack of layers over an opaque background.
#[derive(Debug, Clone, PartialEq)]
pub struct Stack {
    /// Bottom first.
    pub layers: Vec<Layer>,
    /// Background colour, linear RGB.
    pub background: [f32; 3],
}

impl Stack {
    /// Refuses trap planes (their kinds, trap by trap) that do not hold what a layer
    /// colours from: such a layer would paint nothing, without a word. Planes computed
    /// for the stack's own scene always pass; planes read from elsewhere (an EXR of
    /// another scene) may not.
    pub fn check_traps(&self, kinds: &[TrapKind]) -> Result<(), TrapMismatch> {
        for (k, layer) in self.layers.iter().enumerate() {
            if let Some((trap, wanted)) = layer.coloring.trap_plane()
                && kinds.get(trap) != Some(&wanted)
            {
                return Err(TrapMismatch { layer: k + 1, trap, wanted, found: kinds.get(trap).copied() });
            }
        }
        Ok(())
    }

    /// Everything the layers read.
    pub fn needs(&self, traps: &[Trap]) -> Needs {
        let mut needs = Needs::default();
        for l in &self.layers {
            let n = l.coloring.needs();
            needs.nf |= n.nf;
            needs.t |= n.t;
            needs.de |= n.de;
            if let Some(m) = &l.mask {
                let (nf, t, de) = m.needs();
                needs.nf |= nf;
                needs.t |= t;
                needs.de |= de;
            }
        }
        needs.traps = traps.to_vec();
        needs
    }

    /// True when some layer needs image-wide data ([`Stack::context`]) before colouring.
    pub fn is_global(&self) -> bool {
        self.layers.iter().any(|l| l.coloring.is_global())
    }

    /// The image-wide data the layers need, from every strip of the image.
    pub fn context<'a>(&self, strips: impl IntoIterator<Item = &'a Planes> + Clone) -> Context {
        let histogram = self
            .layers
            .iter()
            .any(|l| matches!(l.coloring, Coloring::Histogram { .. }))
            .then(|| Histogram::build(strips));
        Context { histogram, ..Context::default() }
    }

    /// Composites the stack for every sample: opaque linear RGB.
    pub fn composite(&self, planes: &Planes, aa: u32, ctx: &Context) -> Vec<[f32; 3]> {
        let bg = self.background;
        if let Some(layer) = self.single_opaque() {
            let mut out = vec![[0.0f32; 3]; planes.len()];
            layer.coloring.paint_runs(planes, aa, ctx, layer.mask.as_ref(), &mut |start, run| {
                for (o, c) in out[start..start + run.len()].iter_mut().zip(run) {
                    let t = 1.0 - c[3];
                    *o = [c[0] + bg[0] * t, c[1] + bg[1] * t, c[2] + bg[2] * t];
                }
            });
            return out;
        }
        // The base is opaque (background first), so its pixels need no demultiplying.
        self.blend(planes, aa, ctx, |base| {
            base.pixels()
                .iter()
                .map(|p| [srgb8_to_linear(p.red()), srgb8_to_linear(p.green()), srgb8_to_linear(p.blue())])
                .collect()
        })
        .unwrap_or_else(|| vec![bg; planes.len()])
    }

    /// The composited samples as 8-bit sRGB bytes (R, G, B per sample), exactly what
    /// encoding [`Stack::composite`]'s output with [`linear_to_srgb8`] gives, without the
    /// round trip through linear light where tiny-skia already holds sRGB bytes. The fast
    /// path of recolouring at one sample per pixel.
    pub fn composite_rgb8(&self, planes: &Planes, ctx: &Context) -> Vec<u8> {
        let bg = self.background;
        if let Some(layer) = self.single_opaque() {
            let mut out = vec![0u8; planes.len() * 3];
            let enc = Srgb8Encoder::get();
            layer.coloring.paint_runs(planes, 1, ctx, layer.mask.as_ref(), &mut |start, run| {
                for (o, c) in out[3 * start..3 * (start + run.len())].chunks_exact_mut(3).zip(run) {
                    let t = 1.0 - c[3];
                    o[0] = enc.encode(c[0] + bg[0] * t);
                    o[1] = enc.encode(c[1] + bg[1] * t);
                    o[2] = enc.encode(c[2] + bg[2] * t);
                }
            });
            return out;
        }
        self.blend(planes, 1, ctx, |base| {
            let mut out = vec![0u8; planes.len() * 3];
            for (o, p) in out.chunks_exact_mut(3).zip(base.data().chunks_exact(4)) {
                o.copy_from_slice(&p[..3]);
            }
            out
        })
        .unwrap_or_else(|| bg.map(linear_to_srgb8).repeat(planes.len()))
    }

    /// The one layer of a stack that needs no blending, if that is what the stack is.
    fn single_opaque(&self) -> Option<&Layer> {
        match self.layers.as_slice() {
            [layer] if layer.blend == BlendMode::Normal && layer.opacity == 1.0 => Some(layer),
            _ => None,
        }
    }

    /// Every layer blended by tiny-skia over the background, in premultiplied sRGB bytes:
    /// an opaque pixmap, handed to `read` (None for an empty raster). The two pixmaps are
    /// the thread's own, kept from strip to strip (every pixel of both is written before it
    /// is read), so a strip allocates, zeroes and page-faults none.
    fn blend<R>(&self, planes: &Planes, aa: u32, ctx: &Context, read: impl FnOnce(&Pixmap) -> R) -> Option<R> {
        thread_local! {
            static SCRATCH: std::cell::RefCell<Vec<Pixmap>> = const { std::cell::RefCell::new(Vec::new()) };
        }
        let (w, h) = (planes.width as u32, planes.rows as u32);
        let take = || {
            SCRATCH
                .with_borrow_mut(|s| s.iter().position(|p| (p.width(), p.height()) == (w, h)).map(|i| s.swap_remove(i)))
                .or_else(|| Pixmap::new(w, h))
        };
        let (mut base, mut layer) = (take()?, take()?);
        self.blend_into(planes, aa, ctx, &mut base, &mut layer);
        let out = read(&base);
        // The last strip's two are what the thread keeps (a strip of another size replaces them).
        SCRATCH.with_borrow_mut(|s| {
            s.clear();
            s.extend([base, layer]);
        });
        Some(out)
    }

    /// [`Stack::blend`] into the given pixmaps (of the planes' size; their contents do not
    /// matter): the result in `base`.
    fn blend_into(&self, planes: &Planes, aa: u32, ctx: &Context, base: &mut Pixmap, layer_pixmap: &mut Pixmap) {
        let bg = self.background;
        let bg8 = tiny_skia::Color::from_rgba(linear_to_srgb(bg[0]), linear_to_srgb(bg[1]), linear_to_srgb(bg[2]), 1.0)
            .unwrap_or(tiny_skia::Color::BLACK);
        // The background is filled in only where no opaque bottom layer replaces it (below).
        if self.layers.is_empty() {
            base.fill(bg8);
        }
        // Whether every pixel of `base` is opaque, which the table blend needs.
        let mut base_opaque = true;
        let enc = Srgb8Encoder::get();
        for (i, layer) in self.layers.iter().enumerate() {
            let dst = layer_pixmap.data_mut();
            let mut opaque = true;
            layer.coloring.paint_runs(planes, aa, ctx, layer.mask.as_ref(), &mut |start, run| {
                let out = &mut dst[4 * start..4 * (start + run.len())];
                if run.iter().all(|c| c[3] >= 1.0) {
                    // Every sample opaque (most layers): three codes and 255 each, in one
                    // tight loop (what `to_premultiplied_srgb8` gives at alpha 1).
                    for (o, c) in out.chunks_exact_mut(4).zip(run) {
                        let [r, g, b] = opaque_srgb8(*c, enc);
                        o.copy_from_slice(&[r, g, b, 255]);
                    }
                    return;
                }
                for (o, &c) in out.chunks_exact_mut(4).zip(run) {
                    let p = to_premultiplied_srgb8(c, enc);
                    opaque &= p.alpha() == 255;
                    o.copy_from_slice(&[p.red(), p.green(), p.blue(), p.alpha()]);
                }
            });
            // An opaque bottom layer drawn normally covers the background exactly: source
            // over an opaque pixel is the pixel, so the layer becomes the base as it is.
            if i == 0 {
                if opaque && layer.blend == BlendMode::Normal && layer.opacity == 1.0 {
                    std::mem::swap(base, layer_pixmap);
                    continue;
                }
                base.fill(bg8);
            }
            // Opaque over opaque: tiny-skia's bytes from its table (`table`), else its pipeline.
            let (mode, opacity) = (layer.blend.skia(), layer.opacity);
            let tabled = (opaque && base_opaque)
                .then(|| {
                    table::with_table(mode, opacity, |t| {
                        t.map(|t| t.blend_opaque(base.data_mut(), layer_pixmap.data()))
                    })
                })
                .flatten();
            base_opaque = match tabled {
                Some(opaque_after) => opaque_after,
                None => {
                    let paint = PixmapPaint { opacity, blend_mode: mode, quality: tiny_skia::FilterQuality::Nearest };
                    base.draw_pixmap(0, 0, layer_pixmap.as_ref(), &paint, Transform::identity(), None);
                    base.pixels().iter().all(|p| p.alpha() == 255)
                }
            };
        }
    }
}

/// The sRGB codes of an opaque sample's colour. Grey layers (slope, distance without a
/// palette) encode one value, not three.
#[inline(always)]
fn opaque_srgb8(c: [f32; 4], enc: Srgb8Encoder) -> [u8; 3] {
    if c[0] == c[1] && c[1] == c[2] {
        [enc.encode(c[0]); 3]
    } else {
        [enc.encode(c[0]), enc.encode(c[1]), enc.encode(c[2])]
    }
}

/// Linear premultiplied RGBA to tiny-skia's premultiplied sRGB-encoded bytes.
#[inline(always)]
fn to_premultiplied_srgb8(c: [f32; 4], enc: Srgb8Encoder) -> PremultipliedColorU8 {
    let a = c[3].clamp(0.0, 1.0);
    if a <= 0.0 {
        return PremultipliedColorU8::TRANSPARENT;
    }
    let a8 = (a * 255.0 + 0.5) as u8;
    if a8 == 255 {
        let [r, g, b] = opaque_srgb8(c, enc);
        return PremultipliedColorU8::from_rgba(r, g, b, 255).unwrap_or(PremultipliedColorU8::TRANSPARENT);
    }
    let scale = a8 as f32 / 255.0;
    let premul = |v: f32| ((enc.encode(v / a) as f32 * scale + 0.5) as u8).min(a8);
    PremultipliedColorU8::from_rgba(premul(c[0]), premul(c[1]), premul(c[2]), a8)
        .unwrap_or(PremultipliedColorU8::TRANSPARENT)
}

/// Averages `aa x aa` blocks of samples (`width` samples per row) in linear light.
pub fn downsample(samples: Vec<[f32; 3]>, width: usize, aa: usize) -> Vec<[f32; 3]> {
    if aa == 1 {
        return samples;
    }
    let rows = samples.len() / width;
    let (ow, oh) = (width / aa, rows / aa);
    let scale = 1.0 / (aa * aa) as f32;
    let mut out = vec![[0.0f32; 3]; ow * oh];
    for (j, out_row) in out.chunks_mut(ow).enumerate() {
        for sj in 0..aa {
            let row = &samples[(j * aa + sj) * width..][..width];
            for (i, o) in out_row.iter_mut().enumerate() {
                for s in &row[i * aa..i * aa + aa] {
                    o[0] += s[0];
                    o[1] += s[1];
                    o[2] += s[2];
                }
            }
        }
        for o in out_row.iter_mut() {
            *o = [o[0] * scale, o[1] * scale, o[2] * scale];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `BlendMode::ALL` lists every mode once (the match fails to compile when a mode is
    /// added and not listed), and each name reads back as its mode.
    #[test]
    fn every_blend_mode_is_listed_and_named() {
        for (k, &m) in BlendMode::ALL.iter().enumerate() {
            let at = match m {
                BlendMode::Normal => 0,
                BlendMode::Multiply => 1,
                BlendMode::Screen => 2,
                BlendMode::Overlay => 3,
                BlendMode::Darken => 4,
                BlendMode::Lighten => 5,
                BlendMode::Difference => 6,
                BlendMode::SoftLight => 7,
                BlendMode::HardLight => 8,
                BlendMode::ColorDodge => 9,
                BlendMode::ColorBurn => 10,
                BlendMode::Exclusion => 11,
                BlendMode::Plus => 12,
            };
            assert_eq!(at, k, "{m:?}");
            let back: BlendMode = toml::Value::String(m.name()).try_into().expect("reads back");
            assert_eq!(back, m);
        }
        assert_eq!(BlendMode::SoftLight.name(), "soft-light");
    }

    /// A stack mixing every path of [`Stack::blend_into`] (an opaque bottom layer taking the
    /// base's place, opaque layers blended through tiny-skia's tables, translucent ones
    /// through its pipeline, a table blend again after those) gives the bytes of drawing
    /// each layer with tiny-skia over the background, one after another.
    #[test]
    fn stacks_give_tiny_skias_bytes() {
        use crate::coloring::{DistanceStyle, Light, Transfer};
        use crate::formula::end::INTERIOR;
        let (w, rows) = (61, 23);
        let needs = Needs { nf: true, de: true, ..Needs::default() };
        let mut planes = Planes::new(w, rows, &needs);
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        for k in 0..w * rows {
            planes.n[k] = if next() < 0.1 { INTERIOR } else { (next() * 400.0) as u32 };
            planes.nf[k] = next() as f32;
            planes.dex[k] = (next() * 6.0 - 3.0) as f32;
            planes.dey[k] = (next() * 6.0 - 3.0) as f32;
        }
        let palette = crate::palette::builtin("classic").expect("classic");
        let layer = |coloring, blend, opacity| Layer { coloring, blend, opacity, mask: None };
        let distance = || Coloring::Distance { style: DistanceStyle::Soft { k: 0.5 }, palette: None, offset: 0.0 };
        let stack = Stack {
            layers: vec![
                layer(
                    Coloring::Smooth {
                        palette,
                        density: 0.3,
                        offset: 0.1,
                        transfer: Transfer::Linear,
                        interior: [0.0, 0.0, 0.0, 1.0],
                    },
                    BlendMode::Normal,
                    1.0,
                ),
                layer(distance(), BlendMode::Multiply, 0.6),
                layer(Coloring::Boundary { width: 2.0, color: [1.0, 0.2, 0.1, 0.7] }, BlendMode::Normal, 1.0),
                layer(distance(), BlendMode::Overlay, 0.35),
                layer(Coloring::Slope { light: Light::new(45.0, 1.5, 0.8) }, BlendMode::Screen, 0.5),
                layer(distance(), BlendMode::ColorBurn, 1.0),
            ],
            background: [0.1, 0.3, 0.2],
        };
        let ctx = Context::default();
        let got = stack.composite_rgb8(&planes, &ctx);

        let enc = Srgb8Encoder::get();
        let bg = stack.background.map(linear_to_srgb);
        let mut want = Pixmap::new(w as u32, rows as u32).expect("pixmap");
        want.fill(tiny_skia::Color::from_rgba(bg[0], bg[1], bg[2], 1.0).expect("colour"));
        for l in &stack.layers {
            let mut pix = Pixmap::new(w as u32, rows as u32).expect("pixmap");
            for (p, c) in pix.pixels_mut().iter_mut().zip(l.coloring.paint(&planes, 1, &ctx, None)) {
                *p = to_premultiplied_srgb8(c, enc);
            }
            let paint = PixmapPaint {
                opacity: l.opacity,
                blend_mode: l.blend.skia(),
                quality: tiny_skia::FilterQuality::Nearest,
            };
            want.draw_pixmap(0, 0, pix.as_ref(), &paint, Transform::identity(), None);
        }
        let want: Vec<u8> = want.data().chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
        assert_eq!(got, want);
    }

    #[test]
    fn downsample_averages_in_linear_light() {
        let s = vec![[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(downsample(s, 2, 2), vec![[0.25, 0.25, 0.25]]);
    }

    #[test]
    fn premultiplied_conversion_is_valid() {
        let p = to_premultiplied_srgb8([0.1, 0.2, 0.3, 0.5], Srgb8Encoder::get());
        assert!(p.red() <= p.alpha() && p.alpha() == 128);
        assert_eq!(to_premultiplied_srgb8([0.0; 4], Srgb8Encoder::get()), PremultipliedColorU8::TRANSPARENT);
    }
}
