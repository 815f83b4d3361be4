//! Importers for the palette formats other fractal and graphics programs write: Fractint /
//! XaoS colour maps (`.map`), GIMP gradients (`.ggr`), Ultra Fractal gradients (`.ugr`),
//! Kalles Fraktaler palettes and locations (`.kfp`, `.kfr`) and GMT colour palette tables
//! (`.cpt`). One submodule per format; each documents the format and its quirks.
//!
//! Every importer produces ordinary [`Palette`]s made of stops interpolated in sRGB (the
//! space all five programs blend in), so an imported palette writes out with
//! [`to_toml`](super::to_toml) and reads back unchanged. Stop colours are rounded to 8 bits
//! (what our palette files store). Where the source program's curve between its control
//! points is not a straight line in sRGB (GIMP's curved, sine and sphere segments and HSV
//! colouring, Ultra Fractal's smooth gradients, Kalles Fraktaler's eased key blending,
//! GMT's HSV tables), extra stops are placed adaptively until straight lines between them
//! stay within a quarter of an 8-bit step of the exact curve, so with the rounding the
//! import is within 1/255 of the original everywhere (except within 1e-6 of a segment end
//! where the original curve is vertical, far below the 1/4096 resolution of the lookup
//! table). A hard edge (a discontinuity) becomes two stops [`EDGE`] apart: the colour
//! before the edge at `x - EDGE`, the colour after it at `x` (so `x` itself, as in every
//! one of these programs, takes the colour after the edge).

mod cpt;
mod ggr;
mod kfp;
mod map;
mod ugr;
mod x11;

use std::path::Path;

use super::{Definition, Mode, Palette, Space, Stop};
use crate::source::SourceError;

/// A palette file format we read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Fractint / XaoS colour map (`.map`): up to 256 lines of `R G B`.
    Map,
    /// GIMP gradient (`.ggr`): segments with blend and colouring functions.
    Ggr,
    /// Ultra Fractal gradient file (`.ugr`): several cyclic gradients of 400 positions.
    Ugr,
    /// Kalles Fraktaler palette or location (`.kfp`, `.kfr`): the `Colors:` key list.
    Kfp,
    /// GMT colour palette table (`.cpt`): colour slices over arbitrary z values.
    Cpt,
}

impl Format {
    /// The format a file name's extension names (case-insensitive), if any.
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "map" => Format::Map,
            "ggr" => Format::Ggr,
            "ugr" => Format::Ugr,
            "kfp" | "kfr" => Format::Kfp,
            "cpt" => Format::Cpt,
            _ => return None,
        })
    }

    /// What the format is called, for messages and palette descriptions.
    pub fn name(self) -> &'static str {
        match self {
            Format::Map => "Fractint colour map",
            Format::Ggr => "GIMP gradient",
            Format::Ugr => "Ultra Fractal gradient",
            Format::Kfp => "Kalles Fraktaler palette",
            Format::Cpt => "GMT colour palette table",
        }
    }
}

/// Why an import failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ImportError {
    /// The file could not be read.
    #[error("cannot read palette file {path}: {reason}")]
    Io {
        /// The file.
        path: String,
        /// The OS error.
        reason: String,
    },
    /// The extension names none of the formats we read.
    #[error("{path}: unknown palette format (expected .map, .ggr, .ugr, .kfp, .kfr or .cpt)")]
    UnknownFormat {
        /// The file.
        path: String,
    },
    /// The file is not valid in its format (the error names file, line and column).
    #[error(transparent)]
    Invalid(#[from] SourceError),
    /// The file is valid but holds no palette (no colours, or a `.ugr` with no gradient).
    #[error("{path}: no palette in this file")]
    Empty {
        /// The file.
        path: String,
    },
}

/// Reads every palette in a file (a .ugr holds several gradients; the others one).
pub fn import_file(path: &Path) -> Result<Vec<Palette>, ImportError> {
    let shown = path.display().to_string();
    let format = Format::from_path(path).ok_or_else(|| ImportError::UnknownFormat { path: shown.clone() })?;
    let bytes = std::fs::read(path).map_err(|e| ImportError::Io { path: shown.clone(), reason: e.to_string() })?;
    // These formats date from before UTF-8 was common (Latin-1 names in old GIMP and Ultra
    // Fractal files): undecodable bytes become U+FFFD rather than failing the import.
    let text = String::from_utf8_lossy(&bytes);
    import_text(format, &shown, &text)
}

/// Same from text already read (origin names the file in errors; the stem names palettes).
pub fn import_text(format: Format, origin: &str, text: &str) -> Result<Vec<Palette>, ImportError> {
    let path = Path::new(origin);
    let file = path.file_name().map_or_else(|| origin.to_string(), |f| f.to_string_lossy().into_owned());
    let stem = path.file_stem().map_or_else(|| origin.to_string(), |f| f.to_string_lossy().into_owned());
    let ctx = Ctx { origin, text, file, stem, format };
    let palettes = match format {
        Format::Map => map::parse(&ctx)?,
        Format::Ggr => ggr::parse(&ctx)?,
        Format::Ugr => ugr::parse(&ctx)?,
        Format::Kfp => kfp::parse(&ctx)?,
        Format::Cpt => cpt::parse(&ctx)?,
    };
    if palettes.is_empty() {
        return Err(ImportError::Empty { path: origin.to_string() });
    }
    Ok(palettes)
}

/// What an importer knows about its input.
struct Ctx<'a> {
    /// The file as named in errors.
    origin: &'a str,
    /// Its text.
    text: &'a str,
    /// Its file name (for descriptions).
    file: String,
    /// Its stem (for palette names).
    stem: String,
    /// Its format.
    format: Format,
}

impl Ctx<'_> {
    /// An error at byte `offset` of the text.
    fn err(&self, offset: usize, message: impl Into<String>) -> ImportError {
        ImportError::Invalid(SourceError::at(self.origin, self.text, Some(offset..offset), message))
    }

    /// An error about the file as a whole (no position).
    fn err_file(&self, message: impl Into<String>) -> ImportError {
        ImportError::Invalid(SourceError::at(self.origin, self.text, None, message))
    }

    /// "Imported from FILE (FORMAT[, detail])".
    fn description(&self, detail: &str) -> String {
        let sep = if detail.is_empty() { "" } else { ", " };
        format!("Imported from {} ({}{sep}{detail}).", self.file, self.format.name())
    }

    /// A palette over `stops` in sRGB.
    fn palette(&self, name: String, detail: &str, mode: Mode, stops: Vec<Stop>) -> Palette {
        Palette::with(name, self.description(detail), Space::Srgb, mode, Definition::Stops(stops))
    }
}

/// Lines of `text` with the byte offset each starts at (line ends `\n` or `\r\n` removed).
fn lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut start = 0;
    text.split_inclusive('\n').map(move |raw| {
        let at = start;
        start += raw.len();
        (at, raw.trim_end_matches('\n').trim_end_matches('\r'))
    })
}

/// Whitespace-separated words of `line` with their byte offsets within it.
fn words(line: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, c) in line.char_indices() {
        match (c.is_whitespace(), start) {
            (true, Some(s)) => {
                out.push((s, &line[s..i]));
                start = None;
            }
            (false, None) => start = Some(i),
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, &line[s..]));
    }
    out
}

/// A palette name from free text: lowercase words joined by hyphens ("Blue Fire 2" →
/// "blue-fire-2"); "imported" when nothing is left.
fn palette_name(text: &str) -> String {
    let mut out = String::new();
    for word in text.split(|c: char| !c.is_alphanumeric()).filter(|w| !w.is_empty()) {
        if !out.is_empty() {
            out.push('-');
        }
        out.extend(word.chars().flat_map(char::to_lowercase));
    }
    if out.is_empty() { "imported".to_string() } else { out }
}

/// sRGB-encoded red, green, blue and opacity, each nominally in [0, 1].
type Rgba = [f64; 4];

/// Distance between the two stops of a hard edge.
pub const EDGE: f64 = 1e-9;

/// How far the straight lines between sampled stops may stray from the exact curve (per
/// channel, before rounding to 8 bits).
const SAMPLE_TOL: f64 = 0.25 / 255.0;

/// Sampling stops refining below this width (a 250th of a lookup-table step).
const MIN_WIDTH: f64 = 1e-6;

/// Clamps to [0, 1], NaN to 0.
fn unit(v: f64) -> f64 {
    if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) }
}

/// A colour component rounded to the 8-bit value our palette files store (exactly the
/// `f32` that [`color::parse_hex`](super::color::parse_hex) reads back).
fn to8(v: f64) -> f32 {
    (unit(v) * 255.0).round() as u8 as f32 / 255.0
}

/// Stops under construction: positions strictly increasing, colours rounded to 8 bits.
#[derive(Default)]
struct StopList(Vec<Stop>);

impl StopList {
    fn stop(pos: f64, c: Rgba) -> Stop {
        Stop { pos, srgb: [to8(c[0]), to8(c[1]), to8(c[2])], opacity: unit(c[3]) as f32 }
    }

    /// Adds a stop; one at or before the last stop's position replaces that stop's colour.
    fn push(&mut self, pos: f64, c: Rgba) {
        let stop = Self::stop(pos, c);
        match self.0.last_mut() {
            Some(last) if pos <= last.pos => *last = Stop { pos: last.pos, ..stop },
            _ => self.0.push(stop),
        }
    }

    /// The colour jumps from `before` to `after` at `pos` (`pos` takes `after`): two stops
    /// [`EDGE`] apart, or one if both round to the same stop.
    fn edge(&mut self, pos: f64, before: Rgba, after: Rgba) {
        let (b, a) = (Self::stop(pos, before), Self::stop(pos, after));
        if (b.srgb, b.opacity) != (a.srgb, a.opacity) && self.0.last().is_none_or(|l| l.pos < pos - EDGE) {
            self.push(pos - EDGE, before);
        }
        self.push(pos, after);
    }

    /// Stops for the continuous curve `f` over [a, b): one at `a`, then as many inside as
    /// keep straight lines in sRGB within [`SAMPLE_TOL`] of `f` (none where `f` is itself
    /// a straight line). `b` is left to the caller (the next piece, an edge or the end).
    fn sample(&mut self, f: &dyn Fn(f64) -> Rgba, a: f64, b: f64) {
        let g = |t: f64| f(t).map(unit);
        let (fa, fb) = (g(a), g(b));
        self.push(a, fa);
        self.refine(&g, (a, fa), (b, fb));
    }

    fn refine(&mut self, f: &dyn Fn(f64) -> Rgba, (a, fa): (f64, Rgba), (b, fb): (f64, Rgba)) {
        if b - a < MIN_WIDTH {
            return;
        }
        let straight = [0.25, 0.5, 0.75].iter().all(|&s| {
            let v = f(a + (b - a) * s);
            (0..4).all(|k| (v[k] - (fa[k] + (fb[k] - fa[k]) * s)).abs() <= SAMPLE_TOL)
        });
        if straight {
            return;
        }
        let m = 0.5 * (a + b);
        let fm = f(m);
        self.refine(f, (a, fa), (m, fm));
        self.push(m, fm);
        self.refine(f, (m, fm), (b, fb));
    }

    /// The stops, closed with a stop at 1.0 of colour `end`.
    fn finish(mut self, end: Rgba) -> Vec<Stop> {
        self.push(1.0, end);
        if self.0.len() == 1 {
            // Only possible if everything sat at 1.0; keep the palette valid.
            let only = self.0[0];
            self.0.insert(0, Stop { pos: 0.0, ..only });
        }
        self.0
    }
}

/// HSV (hue in turns) to RGB, as GIMP's `gimp_hsv_to_rgb` and GMT's `gmt_hsv_to_rgb` do it.
fn hsv_to_rgb([h, s, v]: [f64; 3]) -> [f64; 3] {
    if s == 0.0 {
        return [v, v, v];
    }
    let h = (h - h.floor()) * 6.0;
    let i = (h as usize).min(5);
    let f = h - i as f64;
    let (w, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    match i {
        0 => [v, t, w],
        1 => [q, v, w],
        2 => [w, v, t],
        3 => [w, q, v],
        4 => [t, w, v],
        _ => [v, w, q],
    }
}

/// RGB to HSV (hue in turns), as GIMP's `gimp_rgb_to_hsv` does it: a colour whose
/// channels differ by at most 0.0001 is grey, with hue and saturation 0.
fn rgb_to_hsv([r, g, b]: [f64; 3]) -> [f64; 3] {
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let delta = max - min;
    if delta <= 0.0001 {
        return [0.0, 0.0, max];
    }
    let h = if r == max {
        let h = (g - b) / delta;
        if h < 0.0 { h + 6.0 } else { h }
    } else if g == max {
        2.0 + (b - r) / delta
    } else {
        4.0 + (r - g) / delta
    };
    [h / 6.0, delta / max, max]
}

/// A word that should have been a decimal integer.
#[derive(Debug, thiserror::Error)]
#[error("expected {what} (a whole number), found `{word}`")]
struct NotAnInteger {
    /// What the number is.
    what: String,
    /// The word found.
    word: String,
}

/// Parses a decimal integer word, `what` the number is.
fn int_word(word: &str, what: &str) -> Result<i64, NotAnInteger> {
    word.parse::<i64>().map_err(|_| NotAnInteger { what: what.to_string(), word: word.to_string() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_from_extensions() {
        assert_eq!(Format::from_path(Path::new("a/b/fire.MAP")), Some(Format::Map));
        assert_eq!(Format::from_path(Path::new("x.ggr")), Some(Format::Ggr));
        assert_eq!(Format::from_path(Path::new("x.ugr")), Some(Format::Ugr));
        assert_eq!(Format::from_path(Path::new("x.kfp")), Some(Format::Kfp));
        assert_eq!(Format::from_path(Path::new("x.kfr")), Some(Format::Kfp));
        assert_eq!(Format::from_path(Path::new("x.cpt")), Some(Format::Cpt));
        assert_eq!(Format::from_path(Path::new("x.png")), None);
        assert_eq!(Format::from_path(Path::new("noext")), None);
        assert!(matches!(import_file(Path::new("x.png")), Err(ImportError::UnknownFormat { .. })));
        assert!(matches!(import_file(Path::new("/no/such/file.map")), Err(ImportError::Io { .. })));
    }

    #[test]
    fn names() {
        assert_eq!(palette_name("Blue Fire 2"), "blue-fire-2");
        assert_eq!(palette_name("  __Sunrise--(GIMP)  "), "sunrise-gimp");
        assert_eq!(palette_name("Café_Noir"), "café-noir");
        assert_eq!(palette_name("!!!"), "imported");
    }

    #[test]
    fn words_and_lines_keep_offsets() {
        let text = "a b\r\n  cd\te\n\nlast";
        let ls: Vec<_> = lines(text).collect();
        assert_eq!(ls, vec![(0, "a b"), (5, "  cd\te"), (12, ""), (13, "last")]);
        assert_eq!(words("  cd\te "), vec![(2, "cd"), (5, "e")]);
    }

    #[test]
    fn hsv_matches_gimp() {
        for rgb in [[1.0, 0.0, 0.0], [0.2, 0.6, 0.4], [0.9, 0.1, 0.7], [0.3, 0.3, 0.3], [0.0, 0.5, 1.0]] {
            let back = hsv_to_rgb(rgb_to_hsv(rgb));
            assert!((0..3).all(|k| (back[k] - rgb[k]).abs() < 1e-12), "{rgb:?} -> {back:?}");
        }
        assert_eq!(rgb_to_hsv([0.0, 0.0, 1.0]), [4.0 / 6.0, 1.0, 1.0]);
        assert_eq!(hsv_to_rgb([0.5, 1.0, 1.0]), [0.0, 1.0, 1.0]);
        assert_eq!(hsv_to_rgb([1.0, 1.0, 1.0]), [1.0, 0.0, 0.0]);
    }

    #[test]
    fn sampling_follows_curves_and_keeps_lines_bare() {
        let mut s = StopList::default();
        s.sample(&|t| [t, t, t, 1.0], 0.0, 1.0);
        let stops = s.finish([1.0; 4]);
        assert_eq!(stops.len(), 2, "a straight line needs no inner stops");

        let curve = |t: f64| [t.sqrt(), (t * 3.0).sin().abs(), t * t, 1.0];
        let mut s = StopList::default();
        s.sample(&curve, 0.0, 1.0);
        let stops = s.finish(curve(1.0));
        for i in 0..=2000 {
            let t = i as f64 / 2000.0;
            if t < MIN_WIDTH {
                continue;
            }
            let k = stops.iter().rposition(|s| s.pos <= t).unwrap();
            let (a, b) = (stops[k], stops[(k + 1).min(stops.len() - 1)]);
            let w = if b.pos > a.pos { (t - a.pos) / (b.pos - a.pos) } else { 0.0 };
            let want = curve(t);
            for c in 0..3 {
                let got = a.srgb[c] as f64 + (b.srgb[c] as f64 - a.srgb[c] as f64) * w;
                assert!((got - want[c]).abs() < 1.0 / 255.0, "t = {t}, channel {c}: {got} vs {}", want[c]);
            }
        }
    }

    #[test]
    fn edges() {
        let mut s = StopList::default();
        s.push(0.0, [0.0, 0.0, 0.0, 1.0]);
        s.edge(0.5, [0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 1.0]);
        s.edge(0.7, [1.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 1.0]);
        let stops = s.finish([1.0, 0.0, 0.0, 1.0]);
        let pos: Vec<f64> = stops.iter().map(|s| s.pos).collect();
        assert_eq!(pos, vec![0.0, 0.5 - EDGE, 0.5, 0.7, 1.0]);
        assert_eq!(stops[1].srgb, [0.0; 3]);
        assert_eq!(stops[2].srgb, [1.0, 0.0, 0.0]);
    }
}
