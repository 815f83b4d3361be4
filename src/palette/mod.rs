//! Palettes: colour stops (or a cosine formula) interpolated in a chosen space, sampled
//! through a lookup table.
//!
//! A palette is defined by stops (position, sRGB colour, opacity) or by Inigo Quilez's
//! cosine formula `a + b cos(2 pi (c t + d))`, the space in which neighbouring stops are
//! blended (OKLab by default: perceptually even ramps without the muddy midpoints of sRGB
//! blending; OKLCH to sweep hue; sRGB or linear light to match other programs), what happens
//! outside [0, 1) (repeat, mirror, clamp), and an offset and density applied before that:
//! position = t * density + offset. Cycling a palette is moving its offset.
//!
//! Colouring asks for millions of samples, so each palette is baked once into a table of
//! linear-light RGBA and sampled with linear interpolation between table entries.
//!
//! Palettes shipped in `palettes/` are compiled into the binary, so a palette name works
//! from any working directory; any other TOML file in the same format is loaded by path,
//! and [`import`] reads the formats other programs write.

pub mod color;
mod file;
pub mod import;

use std::sync::Arc;

use crate::simd_level::SimdLevel;

pub use file::{PaletteError, builtin, builtin_names, load, parse, to_toml};

/// Space in which neighbouring stops are interpolated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Space {
    /// OKLab (perceptual).
    #[default]
    Oklab,
    /// OKLCH: OKLab in polar form; hue turns the short way round between stops.
    Oklch,
    /// sRGB-encoded values.
    Srgb,
    /// Linear-light RGB.
    Linear,
}

impl Space {
    /// The name used in palette files.
    pub fn name(self) -> &'static str {
        match self {
            Space::Oklab => "oklab",
            Space::Oklch => "oklch",
            Space::Srgb => "srgb",
            Space::Linear => "linear",
        }
    }
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

impl Mode {
    /// The name used in palette files.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Repeat => "repeat",
            Mode::Mirror => "mirror",
            Mode::Clamp => "clamp",
        }
    }
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

/// Inigo Quilez's cosine palette: sRGB colour `a + b cos(2 pi (c t + d))`, per channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cosine {
    /// Bias.
    pub a: [f64; 3],
    /// Amplitude.
    pub b: [f64; 3],
    /// Frequency (cycles over [0, 1]); whole numbers keep `repeat` seamless.
    pub c: [f64; 3],
    /// Phase in cycles.
    pub d: [f64; 3],
}

impl Cosine {
    /// sRGB-encoded colour at `t`, clamped to [0, 1].
    pub fn at(&self, t: f64) -> [f32; 3] {
        std::array::from_fn(|k| {
            let v = self.a[k] + self.b[k] * (std::f64::consts::TAU * (self.c[k] * t + self.d[k])).cos();
            v.clamp(0.0, 1.0) as f32
        })
    }
}

/// What defines a palette's colours.
#[derive(Debug, Clone, PartialEq)]
pub enum Definition {
    /// Stops, positions strictly increasing, the first at 0.
    Stops(Vec<Stop>),
    /// A cosine formula (opaque).
    Cosine(Cosine),
}

const LUT_SIZE: usize = 4096;

/// A palette ready for sampling.
#[derive(Debug, Clone, PartialEq)]
pub struct Palette {
    /// Its name.
    pub name: String,
    /// One sentence on what it looks like.
    pub description: String,
    /// Interpolation space.
    pub space: Space,
    /// Out-of-range behaviour.
    pub mode: Mode,
    /// Added to every position (cycles), after the density.
    pub offset: f64,
    /// Positions are multiplied by this (stretch: < 1 widens the bands).
    pub density: f64,
    /// Its colours.
    pub definition: Definition,
    /// A fixed-size table: look-ups with an index clamped below its size need no bounds check.
    lut: Arc<[[f32; 4]; LUT_SIZE]>,
}

impl Palette {
    /// Builds a palette from validated stops (offset 0, density 1).
    pub fn new(name: impl Into<String>, space: Space, mode: Mode, stops: Vec<Stop>) -> Self {
        Self::with(name, String::new(), space, mode, Definition::Stops(stops))
    }

    /// Builds a palette from any definition (offset 0, density 1).
    pub fn with(
        name: impl Into<String>,
        description: impl Into<String>,
        space: Space,
        mode: Mode,
        definition: Definition,
    ) -> Self {
        let lut: [[f32; 4]; LUT_SIZE] = std::array::from_fn(|i| {
            let t = i as f64 / (LUT_SIZE - 1) as f64;
            match &definition {
                Definition::Stops(stops) => interpolate(stops, space, t),
                Definition::Cosine(c) => {
                    let s = c.at(t).map(color::srgb_to_linear);
                    [s[0], s[1], s[2], 1.0]
                }
            }
        });
        Self {
            name: name.into(),
            description: description.into(),
            space,
            mode,
            offset: 0.0,
            density: 1.0,
            definition,
            lut: Arc::new(lut),
        }
    }

    /// The same palette with another offset and density (the table is shared).
    pub fn adjusted(mut self, offset: f64, density: f64) -> Self {
        self.offset = offset;
        self.density = density;
        self
    }

    /// The stops (a cosine palette is sampled at 33 evenly spaced stops).
    pub fn stops(&self) -> Vec<Stop> {
        match &self.definition {
            Definition::Stops(s) => s.clone(),
            Definition::Cosine(c) => (0..=32)
                .map(|k| {
                    let pos = k as f64 / 32.0;
                    Stop { pos, srgb: c.at(pos), opacity: 1.0 }
                })
                .collect(),
        }
    }

    /// Linear-light RGBA (not premultiplied) at position `t`, after the palette's density,
    /// offset and mode.
    #[inline(always)]
    pub fn at(&self, t: f64) -> [f32; 4] {
        self.at_coordinate(self.coordinate(t))
    }

    /// Where position `t` falls in the palette's table, after its density, offset and mode:
    /// a coordinate in [0, table length - 1] for [`Palette::at_coordinate`].
    #[inline(always)]
    pub fn coordinate(&self, t: f64) -> f64 {
        coordinate(self.mode, self.density, self.offset, t)
    }

    /// [`Palette::coordinate`] of every position of a run, in place, under `simd`'s
    /// instruction set ([`SimdLevel::map`]): branch-free for the repeating and clamped
    /// modes, so the loop vectorises (exact operations: the same bits at every width).
    pub fn coordinates(&self, simd: SimdLevel, v: &mut [f64]) {
        let (mode, density, offset) = (self.mode, self.density, self.offset);
        simd.map(v, |t| coordinate(mode, density, offset, t));
    }

    /// The colour at a table coordinate from [`Palette::coordinate`]: the two neighbouring
    /// entries, interpolated.
    #[inline(always)]
    pub fn at_coordinate(&self, f: f64) -> [f32; 4] {
        // Through i32: the same index for every coordinate (0 ..= LUT_SIZE - 1; NaN is 0 either
        // way), and x86-64 converts to i32 in one instruction where u64 takes a dozen.
        let i = ((f as i32).max(0) as usize).min(LUT_SIZE - 2);
        let w = (f - i as f64) as f32;
        let (a, b) = (self.lut[i], self.lut[i + 1]);
        [a[0] + (b[0] - a[0]) * w, a[1] + (b[1] - a[1]) * w, a[2] + (b[2] - a[2]) * w, a[3] + (b[3] - a[3]) * w]
    }
}

/// The table coordinate of position `t` (see [`Palette::coordinate`]).
#[inline(always)]
fn coordinate(mode: Mode, density: f64, offset: f64, t: f64) -> f64 {
    let t = t * density + offset;
    let u = match mode {
        Mode::Repeat => t - floor(t),
        Mode::Mirror => {
            let r = t.rem_euclid(2.0);
            if r > 1.0 { 2.0 - r } else { r }
        }
        Mode::Clamp => t.clamp(0.0, 1.0),
    };
    let u = if u.is_finite() { u } else { 0.0 };
    u * (LUT_SIZE - 1) as f64
}

/// floor(t), exact, without a libm call (the crate is built for baseline x86-64, where
/// `f64::floor` is a function call) and without a branch or an integer conversion (which
/// AVX2 lacks for 64-bit integers), so that loops over it vectorise: below 2^52, adding and
/// subtracting 2^52 rounds |t| to a whole number; above, every f64 is whole already.
#[inline(always)]
fn floor(t: f64) -> f64 {
    const BIG: f64 = 4_503_599_627_370_496.0;
    let a = t.abs();
    let r = if a < BIG { ((a + BIG) - BIG).copysign(t) } else { t };
    // NaN stays NaN (no comparison holds).
    if r > t { r - 1.0 } else { r }
}

/// A colour in the coordinates of `space`.
fn to_space(space: Space, srgb: [f32; 3]) -> [f32; 3] {
    let lin = srgb.map(color::srgb_to_linear);
    match space {
        Space::Srgb => srgb,
        Space::Linear => lin,
        Space::Oklab => color::linear_to_oklab(lin),
        Space::Oklch => color::oklab_to_oklch(color::linear_to_oklab(lin)),
    }
}

/// Linear light from the coordinates of `space`.
fn from_space(space: Space, v: [f32; 3]) -> [f32; 3] {
    match space {
        Space::Srgb => v.map(color::srgb_to_linear),
        Space::Linear => v,
        Space::Oklab => color::oklab_to_linear(v),
        Space::Oklch => color::oklab_to_linear(color::oklch_to_oklab(v)),
    }
}

/// Exact interpolation between the stops around `t` (in [0, 1]), as linear RGBA.
fn interpolate(stops: &[Stop], space: Space, t: f64) -> [f32; 4] {
    let k = stops.iter().rposition(|s| s.pos <= t).unwrap_or(0);
    let a = stops[k];
    let b = *stops.get(k + 1).unwrap_or(&a);
    let w = if b.pos > a.pos { ((t - a.pos) / (b.pos - a.pos)) as f32 } else { 0.0 };
    let (ca, mut cb) = (to_space(space, a.srgb), to_space(space, b.srgb));
    if space == Space::Oklch {
        // Hue (turns) the short way round; an achromatic end takes the other's hue.
        if ca[1] < 1e-4 {
            return finish(space, [ca[0] + (cb[0] - ca[0]) * w, cb[1] * w, cb[2]], a, b, w);
        }
        if cb[1] < 1e-4 {
            cb[2] = ca[2];
        }
        let dh = cb[2] - ca[2];
        cb[2] = ca[2] + dh - dh.round();
    }
    let mix = [ca[0] + (cb[0] - ca[0]) * w, ca[1] + (cb[1] - ca[1]) * w, ca[2] + (cb[2] - ca[2]) * w];
    finish(space, mix, a, b, w)
}

fn finish(space: Space, mix: [f32; 3], a: Stop, b: Stop, w: f32) -> [f32; 4] {
    let lin = from_space(space, mix);
    let alpha = a.opacity + (b.opacity - a.opacity) * w;
    [lin[0].clamp(0.0, 1.0), lin[1].clamp(0.0, 1.0), lin[2].clamp(0.0, 1.0), alpha]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd_level::testing::{every_level_matches, uniform};

    fn bw(mode: Mode) -> Palette {
        let stops =
            vec![Stop { pos: 0.0, srgb: [0.0; 3], opacity: 1.0 }, Stop { pos: 1.0, srgb: [1.0; 3], opacity: 1.0 }];
        Palette::new("bw", Space::Linear, mode, stops)
    }

    #[test]
    fn every_instruction_set_gives_the_coordinates_of_one_sample_at_a_time() {
        let mut t: Vec<f64> = uniform(3, 1000).into_iter().map(|u| (u - 0.5) * 1e4).collect();
        t.extend([0.0, -0.0, 1.0, -1.0, 0.5, -0.5, 1e17, -1e17, 4.6e18, f64::INFINITY, f64::NAN, 1e300]);
        for mode in [Mode::Repeat, Mode::Mirror, Mode::Clamp] {
            let mut p = bw(mode);
            (p.density, p.offset) = (0.37, 0.1);
            every_level_matches(&t, |x| p.coordinate(x), |l, v| p.coordinates(l, v), &format!("{mode:?}"));
        }
        // The branch-free floor is floor.
        for x in t.iter().chain(&[2.5, -2.5, 3.0, -3.0, 0.9999999999999999, -1e-300]) {
            assert_eq!(floor(*x).to_bits() & !(1 << 63), x.floor().to_bits() & !(1 << 63), "{x}");
        }
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
            for s in &pal.stops() {
                let got = pal.at(s.pos.min(0.999_999_999));
                let want = s.srgb.map(color::srgb_to_linear);
                for k in 0..3 {
                    assert!((got[k] - want[k]).abs() < 2e-3, "{p} at {}", s.pos);
                }
            }
        }
    }
}
