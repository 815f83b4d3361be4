//! Palettes: colour stops interpolated in a chosen space, sampled through a lookup table.
//!
//! A palette is defined by stops (position, sRGB colour, opacity), the space in which
//! neighbouring stops are blended (OKLab by default: perceptually even ramps without the
//! muddy midpoints of sRGB blending) and what happens outside [0, 1). Colouring asks for
//! millions of samples, so each palette is baked once into a table of linear-light RGBA and
//! sampled with linear interpolation between table entries.
//!
//! Palettes shipped in `palettes/` are compiled into the binary, so a palette name works
//! from any working directory; any other TOML file in the same format is loaded by path.

pub mod color;
mod file;

use std::sync::Arc;

pub use file::{PaletteError, builtin_names, load, parse};

/// Space in which neighbouring stops are interpolated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Space {
    /// OKLab (perceptual).
    #[default]
    Oklab,
    /// sRGB-encoded values.
    Srgb,
    /// Linear-light RGB.
    Linear,
}

/// How positions outside [0, 1) map into the palette.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Wrap around.
    #[default]
    Repeat,
    /// Go back and forth.
    Mirror,
    /// Hold the end colours.
    Clamp,
}

/// A colour stop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stop {
    /// Position in [0, 1].
    pub pos: f64,
    /// sRGB-encoded colour.
    pub srgb: [f32; 3],
    /// Opacity in [0, 1].
    pub opacity: f32,
}

const LUT_SIZE: usize = 4096;

/// A palette ready for sampling.
#[derive(Debug, Clone, PartialEq)]
pub struct Palette {
    /// Its name.
    pub name: String,
    /// Interpolation space.
    pub space: Space,
    /// Out-of-range behaviour.
    pub mode: Mode,
    /// The stops, positions strictly increasing, the first at 0.
    pub stops: Vec<Stop>,
    lut: Arc<Vec<[f32; 4]>>,
}

impl Palette {
    /// Builds a palette from validated stops.
    pub fn new(name: impl Into<String>, space: Space, mode: Mode, stops: Vec<Stop>) -> Self {
        let lut = (0..LUT_SIZE).map(|i| interpolate(&stops, space, i as f64 / (LUT_SIZE - 1) as f64)).collect();
        Self { name: name.into(), space, mode, stops, lut: Arc::new(lut) }
    }

    /// Linear-light RGBA (not premultiplied) at position `t`, after the palette's mode.
    #[inline]
    pub fn at(&self, t: f64) -> [f32; 4] {
        let u = match self.mode {
            Mode::Repeat => t - floor(t),
            Mode::Mirror => {
                let r = t.rem_euclid(2.0);
                if r > 1.0 { 2.0 - r } else { r }
            }
            Mode::Clamp => t.clamp(0.0, 1.0),
        };
        let u = if u.is_finite() { u } else { 0.0 };
        let f = u * (LUT_SIZE - 1) as f64;
        let i = (f as usize).min(LUT_SIZE - 2);
        let w = (f - i as f64) as f32;
        let (a, b) = (self.lut[i], self.lut[i + 1]);
        [a[0] + (b[0] - a[0]) * w, a[1] + (b[1] - a[1]) * w, a[2] + (b[2] - a[2]) * w, a[3] + (b[3] - a[3]) * w]
    }
}

/// floor(t) without a libm call (the crate is built for baseline x86-64, where `f64::floor`
/// is a function call); exact for |t| < 2^62, and the palette repeats long before that.
#[inline]
fn floor(t: f64) -> f64 {
    if t.is_nan() || t.abs() >= 4.0e18 {
        return t.floor();
    }
    let f = t as i64 as f64;
    if f > t { f - 1.0 } else { f }
}

/// Exact interpolation between the stops around `t` (in [0, 1]), as linear RGBA.
fn interpolate(stops: &[Stop], space: Space, t: f64) -> [f32; 4] {
    let k = stops.iter().rposition(|s| s.pos <= t).unwrap_or(0);
    let a = stops[k];
    let b = *stops.get(k + 1).unwrap_or(&a);
    let w = if b.pos > a.pos { ((t - a.pos) / (b.pos - a.pos)) as f32 } else { 0.0 };
    let to = |s: Stop| -> [f32; 3] {
        let lin = s.srgb.map(color::srgb_to_linear);
        match space {
            Space::Srgb => s.srgb,
            Space::Linear => lin,
            Space::Oklab => color::linear_to_oklab(lin),
        }
    };
    let (ca, cb) = (to(a), to(b));
    let mix = [ca[0] + (cb[0] - ca[0]) * w, ca[1] + (cb[1] - ca[1]) * w, ca[2] + (cb[2] - ca[2]) * w];
    let lin = match space {
        Space::Srgb => mix.map(color::srgb_to_linear),
        Space::Linear => mix,
        Space::Oklab => color::oklab_to_linear(mix),
    };
    let alpha = a.opacity + (b.opacity - a.opacity) * w;
    [lin[0].clamp(0.0, 1.0), lin[1].clamp(0.0, 1.0), lin[2].clamp(0.0, 1.0), alpha]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bw(mode: Mode) -> Palette {
        let stops =
            vec![Stop { pos: 0.0, srgb: [0.0; 3], opacity: 1.0 }, Stop { pos: 1.0, srgb: [1.0; 3], opacity: 1.0 }];
        Palette::new("bw", Space::Linear, mode, stops)
    }

    #[test]
    fn modes() {
        let p = bw(Mode::Repeat);
        assert!((p.at(0.25)[0] - 0.25).abs() < 1e-6);
        assert!((p.at(1.25)[0] - 0.25).abs() < 1e-6);
        assert!((p.at(-0.75)[0] - 0.25).abs() < 1e-6);
        let m = bw(Mode::Mirror);
        assert!((m.at(1.25)[0] - 0.75).abs() < 1e-6);
        let c = bw(Mode::Clamp);
        assert_eq!(c.at(7.0)[0], 1.0);
        assert_eq!(c.at(f64::NAN)[0], 0.0);
    }

    #[test]
    fn stops_are_hit_exactly() {
        for p in builtin_names() {
            let pal = load(p, None).unwrap();
            for s in &pal.stops {
                let got = pal.at(s.pos.min(0.999_999_999));
                let want = s.srgb.map(color::srgb_to_linear);
                for k in 0..3 {
                    assert!((got[k] - want[k]).abs() < 2e-3, "{p} at {}", s.pos);
                }
            }
        }
    }
}
