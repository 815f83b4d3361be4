//! GMT colour palette tables (`.cpt`).
//!
//! The format, as GMT's CPT reader (`gmt_support.c`) and the GMT documentation describe
//! it: each line is a z-slice `z0 colour0 z1 colour1 [L|U|B] [;label]`, slices in
//! increasing z, each starting where the one before ends (GMT rejects gaps). A colour is
//! three numbers `R G B` (0-255), or one word: `R/G/B`, `#rrggbb`, a grey level `0-255`,
//! `H-S-V` (hue 0-360, saturation and value 0-1), a colour name, or `-` (a slice that is
//! not painted); a word may end in `@T`, a transparency in percent. `#` lines are
//! comments, except that a comment containing `COLOR_MODEL = RGB | HSV` (or `+RGB`,
//! `+HSV`, `rgb`, `hsv`) sets the model: in the HSV model the three numbers are `H S V`
//! and colours are interpolated in HSV (hue taken as written, not the short way round);
//! in the RGB model they are interpolated in RGB. Lines starting `B`, `F` or `N`
//! (background, foreground and NaN colours) are ignored: our palettes have no such colours.
//!
//! We normalise z from the first slice's `z0` (position 0) to the last slice's `z1`
//! (position 1), space `srgb` (GMT's RGB values are sRGB-encoded bytes, blended as they
//! are), mode `clamp` (outside the table GMT uses the B and F colours; we hold the end
//! colours). Where a slice's `colour0` differs from the previous slice's `colour1` the
//! colour jumps: a hard edge, the value `z0` itself taking the new slice's colour (GMT's
//! lookup puts a value equal to a slice's `z1` in the next slice). HSV slices are sampled
//! into stops (within 1/255); RGB slices need only their ends. A slice marked `-` becomes
//! transparent white (GMT leaves it unpainted, showing the page).
//!
//! Categorical tables (every data line `key colour`, GMT's `categorical.cpt`, `paired.cpt`
//! and the `*S.cpt` tables of Crameri's Scientific Colour Maps) become hard-edged
//! palettes: one equal band per key, in the order the file lists them (the only order the
//! format gives; keys may be words). A table mixing the two kinds of line is refused.
//!
//! Not supported, each with a clear error: CMYK colours and `COLOR_MODEL = CMYK`, pattern
//! fills, and z values that are not plain numbers (GMT also accepts dates and
//! `dd:mm:ss`). Colour names: the X11 names GMT accepts (`seagreen3`, `gray80`,
//! `mediumaquamarine`, 658 of them: the X.Org database, spaces removed, case folded).

use super::{Ctx, ImportError, Rgba, StopList, hsv_to_rgb, palette_name, rgb_to_hsv, words};
use crate::palette::{Mode, Palette};

use super::x11::X11_NAMES;

/// A colour as written.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Color {
    /// Red, green, blue in [0, 1], opacity.
    Rgb([f64; 3], f64),
    /// Hue in turns, saturation, value, opacity.
    Hsv([f64; 3], f64),
    /// `-`: not painted.
    Skip,
}

impl Color {
    fn rgba(self) -> Rgba {
        match self {
            Color::Rgb(c, a) => [c[0], c[1], c[2], a],
            Color::Hsv(hsv, a) => {
                let c = hsv_to_rgb(hsv);
                [c[0], c[1], c[2], a]
            }
            Color::Skip => [1.0, 1.0, 1.0, 0.0],
        }
    }

    /// Hue (turns), saturation, value, opacity.
    fn hsva(self) -> [f64; 4] {
        match self {
            Color::Rgb(c, a) => {
                let h = rgb_to_hsv(c);
                [h[0], h[1], h[2], a]
            }
            Color::Hsv(h, a) => [h[0], h[1], h[2], a],
            Color::Skip => [0.0, 0.0, 1.0, 0.0],
        }
    }
}

/// A z-slice.
#[derive(Debug, Clone, Copy)]
struct Slice {
    z0: f64,
    c0: Color,
    z1: f64,
    c1: Color,
}

/// The palette in a `.cpt` file.
pub(super) fn parse(ctx: &Ctx<'_>) -> Result<Vec<Palette>, ImportError> {
    let mut hsv_model = false;
    let mut slices: Vec<Slice> = Vec::new();
    let mut categories: Vec<Color> = Vec::new();
    for (start, line) in super::lines(ctx.text) {
        let body = line.trim_start();
        let indent = line.len() - body.len();
        if body.is_empty() {
            continue;
        }
        if let Some(comment) = body.strip_prefix('#') {
            if let Some(k) = comment.find("COLOR_MODEL") {
                let value = comment[k + "COLOR_MODEL".len()..].trim_start().trim_start_matches('=').trim();
                let at = start + indent + 1 + k;
                hsv_model = match value {
                    "RGB" | "+RGB" | "rgb" => false,
                    "HSV" | "+HSV" | "hsv" => true,
                    "CMYK" | "+CMYK" | "cmyk" => return Err(ctx.err(at, "CMYK colour tables are not supported")),
                    _ => return Err(ctx.err(at, format!("unknown COLOR_MODEL `{value}` (expected RGB or HSV)"))),
                };
            }
            continue;
        }
        if matches!(body.as_bytes(), [b'B' | b'F' | b'N', next, ..] if next.is_ascii_whitespace()) {
            continue;
        }
        let data = body.split(';').next().unwrap_or("");
        let mut w: Vec<(usize, &str)> = words(data).into_iter().map(|(o, s)| (start + indent + o, s)).collect();
        if matches!(w.last(), Some((_, "L" | "U" | "B"))) && matches!(w.len(), 5 | 9) {
            w.pop();
        }
        if w.is_empty() {
            // Only a `;label` (found by fuzzing: it once indexed an empty line).
            continue;
        }
        let slice = match w.len() {
            4 => Slice { z0: z(ctx, w[0])?, c0: word_color(ctx, w[1])?, z1: z(ctx, w[2])?, c1: word_color(ctx, w[3])? },
            8 => Slice {
                z0: z(ctx, w[0])?,
                c0: triple(ctx, &w[1..4], hsv_model)?,
                z1: z(ctx, w[4])?,
                c1: triple(ctx, &w[5..8], hsv_model)?,
            },
            2 => {
                if !slices.is_empty() {
                    return Err(
                        ctx.err(w[0].0, "a `key colour` line in a table of z-slices (GMT allows one kind only)")
                    );
                }
                categories.push(word_color(ctx, w[1])?);
                continue;
            }
            10 => return Err(ctx.err(w[0].0, "CMYK colours are not supported")),
            n => {
                return Err(
                    ctx.err(w[0].0, format!("expected `z0 colour z1 colour` or `z0 R G B z1 R G B`, found {n} fields"))
                );
            }
        };
        if !categories.is_empty() {
            return Err(ctx.err(w[0].0, "a z-slice in a categorical table (GMT allows one kind only)"));
        }
        let z1_at = if w.len() == 4 { w[2].0 } else { w[4].0 };
        if slice.z1 <= slice.z0 {
            return Err(ctx.err(z1_at, format!("z1 = {} must be above z0 = {}", slice.z1, slice.z0)));
        }
        if let Some(prev) = slices.last() {
            let slack = 1e-9 * prev.z1.abs().max(slice.z0.abs()).max(1.0);
            if (slice.z0 - prev.z1).abs() > slack {
                return Err(ctx.err(
                    w[0].0,
                    format!(
                        "this slice starts at {} but the one before ends at {}: slices must follow on",
                        slice.z0, prev.z1
                    ),
                ));
            }
        }
        slices.push(slice);
    }
    if !categories.is_empty() {
        return Ok(vec![categorical(ctx, &categories)]);
    }
    let (Some(first), Some(last)) = (slices.first(), slices.last()) else { return Ok(Vec::new()) };
    let (lo, hi) = (first.z0, last.z1);
    let norm = |z: f64| ((z - lo) / (hi - lo)).clamp(0.0, 1.0);
    let mut stops = StopList::default();
    let mut prev_end: Option<Rgba> = None;
    for (k, s) in slices.iter().enumerate() {
        let a = if k == 0 { 0.0 } else { norm(s.z0) };
        let b = if k + 1 == slices.len() { 1.0 } else { norm(s.z1) };
        let s = *s;
        let f = move |t: f64| -> Rgba {
            let w = if b > a { ((t - a) / (b - a)).clamp(0.0, 1.0) } else { 0.0 };
            if hsv_model && s.c0 != Color::Skip {
                let (p, q) = (s.c0.hsva(), s.c1.hsva());
                let v: [f64; 4] = std::array::from_fn(|i| p[i] + (q[i] - p[i]) * w);
                let c = hsv_to_rgb([v[0], v[1], v[2]]);
                [c[0], c[1], c[2], v[3]]
            } else {
                let (p, q) = (s.c0.rgba(), s.c1.rgba());
                std::array::from_fn(|i| p[i] + (q[i] - p[i]) * w)
            }
        };
        match prev_end {
            None => stops.push(0.0, f(a)),
            Some(end) => stops.edge(a, end, f(a)),
        }
        if b > a {
            stops.sample(&f, a, b);
        }
        prev_end = Some(f(b));
    }
    let stops = stops.finish(prev_end.unwrap_or([0.0, 0.0, 0.0, 1.0]));
    let detail = if hsv_model { "HSV" } else { "" };
    Ok(vec![ctx.palette(palette_name(&ctx.stem), detail, Mode::Clamp, stops)])
}

/// A categorical table: one band per key, hard edges between them.
fn categorical(ctx: &Ctx<'_>, colours: &[Color]) -> Palette {
    let n = colours.len() as f64;
    let mut stops = StopList::default();
    stops.push(0.0, colours[0].rgba());
    for (k, pair) in colours.windows(2).enumerate() {
        stops.edge((k + 1) as f64 / n, pair[0].rgba(), pair[1].rgba());
    }
    let last = colours[colours.len() - 1].rgba();
    ctx.palette(palette_name(&ctx.stem), "categorical", Mode::Clamp, stops.finish(last))
}

/// A z value.
fn z(ctx: &Ctx<'_>, (at, word): (usize, &str)) -> Result<f64, ImportError> {
    word.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| ctx.err(at, format!("expected a z value (a plain number), found `{word}`")))
}

/// A number in `lo..=hi`.
fn number(ctx: &Ctx<'_>, at: usize, word: &str, lo: f64, hi: f64, what: &str) -> Result<f64, ImportError> {
    word.parse::<f64>()
        .ok()
        .filter(|v| (lo..=hi).contains(v))
        .ok_or_else(|| ctx.err(at, format!("expected {what} ({lo} to {hi}), found `{word}`")))
}

/// Three numbers: `R G B` (0-255) or, in the HSV model, `H S V`.
fn triple(ctx: &Ctx<'_>, w: &[(usize, &str)], hsv: bool) -> Result<Color, ImportError> {
    if hsv {
        let h = number(ctx, w[0].0, w[0].1, 0.0, 360.0, "a hue")?;
        let s = number(ctx, w[1].0, w[1].1, 0.0, 1.0, "a saturation")?;
        let v = number(ctx, w[2].0, w[2].1, 0.0, 1.0, "a value")?;
        Ok(Color::Hsv([h / 360.0, s, v], 1.0))
    } else {
        let mut c = [0.0; 3];
        for (k, (at, word)) in w.iter().enumerate() {
            c[k] = number(ctx, *at, word, 0.0, 255.0, "a colour value")? / 255.0;
        }
        Ok(Color::Rgb(c, 1.0))
    }
}

/// A colour written as one word.
fn word_color(ctx: &Ctx<'_>, (at, word): (usize, &str)) -> Result<Color, ImportError> {
    let (base, alpha) = match word.split_once('@') {
        Some((base, t)) => {
            (base, 1.0 - number(ctx, at + base.len() + 1, t, 0.0, 100.0, "a transparency in percent")? / 100.0)
        }
        None => (word, 1.0),
    };
    if base == "-" {
        return Ok(Color::Skip);
    }
    if let Some(hex) = base.strip_prefix('#') {
        if hex.len() == 6 && hex.bytes().all(|b| b.is_ascii_hexdigit()) {
            let c = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).map_or(0.0, |v| v as f64 / 255.0);
            return Ok(Color::Rgb([c(0), c(2), c(4)], alpha));
        }
        return Err(ctx.err(at, format!("expected a colour `#rrggbb`, found `{base}`")));
    }
    let parts = |sep: char| -> Vec<(usize, &str)> {
        let mut off = at;
        base.split(sep)
            .map(|p| {
                let r = (off, p);
                off += p.len() + 1;
                r
            })
            .collect()
    };
    if base.contains('/') {
        let p = parts('/');
        if p.len() == 4 {
            return Err(ctx.err(at, "CMYK colours are not supported"));
        }
        if p.len() != 3 {
            return Err(ctx.err(at, format!("expected a colour `R/G/B`, found `{base}`")));
        }
        let mut c = [0.0; 3];
        for (k, (o, s)) in p.iter().enumerate() {
            c[k] = number(ctx, *o, s, 0.0, 255.0, "a colour value")? / 255.0;
        }
        return Ok(Color::Rgb(c, alpha));
    }
    if base.starts_with(|c: char| c.is_ascii_digit() || c == '.') && base.contains('-') {
        let p = parts('-');
        if p.len() != 3 {
            return Err(ctx.err(at, format!("expected a colour `H-S-V`, found `{base}`")));
        }
        let h = number(ctx, p[0].0, p[0].1, 0.0, 360.0, "a hue")?;
        let s = number(ctx, p[1].0, p[1].1, 0.0, 1.0, "a saturation")?;
        let v = number(ctx, p[2].0, p[2].1, 0.0, 1.0, "a value")?;
        return Ok(Color::Hsv([h / 360.0, s, v], alpha));
    }
    if base.starts_with(|c: char| c.is_ascii_digit() || c == '.') {
        let g = number(ctx, at, base, 0.0, 255.0, "a grey level")? / 255.0;
        return Ok(Color::Rgb([g; 3], alpha));
    }
    let lower = base.to_ascii_lowercase();
    match X11_NAMES.binary_search_by(|(n, _)| (*n).cmp(lower.as_str())) {
        Ok(k) => Ok(Color::Rgb(X11_NAMES[k].1.map(|v| v as f64 / 255.0), alpha)),
        Err(_) => Err(ctx.err(
            at,
            format!("unknown colour `{base}` (use R/G/B, #rrggbb, H-S-V, a grey level, or an X11 colour name such as `seagreen3`)"),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::super::{EDGE, Format, import_text};
    use crate::palette::{Definition, Mode, Space, color};

    fn stops(text: &str) -> Vec<crate::palette::Stop> {
        let p = import_text(Format::Cpt, "x.cpt", text).unwrap().remove(0);
        assert_eq!((p.space, p.mode), (Space::Srgb, Mode::Clamp));
        let Definition::Stops(s) = p.definition else { panic!() };
        s
    }

    #[test]
    fn slices_edges_and_colour_forms() {
        let s = stops(
            "# a test\n# COLOR_MODEL = RGB\n-10 0 0 0 0 255 0 0\n0 0/0/255 5 #00ff00 L ; label\n\
             5 white 10 128\nB 0 0 0\nF 255 255 255\nN 128 128 128\n",
        );
        let pos: Vec<f64> = s.iter().map(|s| s.pos).collect();
        assert_eq!(pos, vec![0.0, 0.5 - EDGE, 0.5, 0.75 - EDGE, 0.75, 1.0]);
        let hex: Vec<String> = s.iter().map(|s| color::to_hex(s.srgb)).collect();
        assert_eq!(hex, vec!["#000000", "#ff0000", "#0000ff", "#00ff00", "#ffffff", "#808080"]);
    }

    #[test]
    fn continuous_slices_share_a_stop() {
        let s = stops("0 red 1 blue\n1 blue 3 0-1-1@50\n");
        let pos: Vec<f64> = s.iter().map(|s| s.pos).collect();
        // Blue to red given as H-S-V in the RGB model: blended in RGB, no inner stops.
        assert_eq!(pos, vec![0.0, 1.0 / 3.0, 1.0]);
        assert_eq!(s[1].srgb, [0.0, 0.0, 1.0]);
        assert_eq!((s[0].opacity, s[1].opacity, s[2].opacity), (1.0, 1.0, 0.5));
        assert_eq!(s[2].srgb, [1.0, 0.0, 0.0]);
    }

    #[test]
    fn hsv_model_interpolates_hue() {
        let text = "# COLOR_MODEL = HSV\n0 0 1 1 1 240 1 1\n";
        let p = import_text(Format::Cpt, "x.cpt", text).unwrap().remove(0);
        assert!(p.description.contains("HSV"));
        // Half way the hue is 120 (green), written as is (not the short way through magenta).
        let c = p.at(0.5).map(color::linear_to_srgb);
        assert!(c[1] > 0.99 && c[0] < 0.01 && c[2] < 0.01, "{c:?}");
        // A quarter: hue 60, yellow.
        let c = p.at(0.25).map(color::linear_to_srgb);
        assert!(c[0] > 0.99 && c[1] > 0.99 && c[2] < 0.01, "{c:?}");
    }

    /// A line holding only a label has no fields: skipped, not indexed (a fuzzer's find).
    #[test]
    fn label_only_lines_are_skipped() {
        let p = import_text(Format::Cpt, "x.cpt", "0 red 1 blue\n ;just a label\n1 blue 2 red\n").unwrap();
        assert_eq!(p.len(), 1);
    }

    #[test]
    fn categorical_tables_become_hard_edged_bands_in_file_order() {
        let text = "# COLOR_MODEL = RGB\n0 red ;first\n1 0/0/255\nWater #00ff00\n";
        let p = import_text(Format::Cpt, "x.cpt", text).unwrap().remove(0);
        assert!(p.description.contains("categorical"), "{}", p.description);
        let at = |t: f64| p.at(t).map(|v| (color::linear_to_srgb(v) * 255.0).round() as u8);
        assert_eq!(at(0.1)[..3], [255, 0, 0]);
        assert_eq!(at(0.3)[..3], [255, 0, 0]);
        assert_eq!(at(0.34)[..3], [0, 0, 255]);
        assert_eq!(at(0.66)[..3], [0, 0, 255]);
        assert_eq!(at(0.67)[..3], [0, 255, 0]);
        assert_eq!(at(1.0)[..3], [0, 255, 0]);
    }

    #[test]
    fn x11_colour_names_as_gmt_spells_them() {
        let text = "0 mediumaquamarine 1 mediumaquamarine\n1 SeaGreen3 2 seagreen3\n2 gray80 3 grey\n";
        let p = import_text(Format::Cpt, "x.cpt", text).unwrap().remove(0);
        let at = |t: f64| p.at(t).map(|v| (color::linear_to_srgb(v) * 255.0).round() as u8);
        assert_eq!(at(0.1)[..3], [102, 205, 170]);
        assert_eq!(at(0.5)[..3], [67, 205, 128]);
        assert_eq!(at(0.67)[..3], [204, 204, 204]);
        assert_eq!(at(1.0)[..3], [190, 190, 190]);
    }

    #[test]
    fn errors_name_line_and_column() {
        let bad = [
            ("0 0 0 0 1 255 255 256\n", "x.cpt:1:19:", "0 to 255"),
            ("0 red 1 blue\n2 red 3 blue\n", "x.cpt:2:1:", "follow on"),
            ("0 red 1 chartreuse9\n", "x.cpt:1:9:", "unknown colour"),
            ("0 red 0 blue\n", "x.cpt:1:7:", "above"),
            ("0 red 1\n", "x.cpt:1:1:", "3 fields"),
            ("# COLOR_MODEL = CMYK\n", "x.cpt:1:3:", "CMYK"),
            ("0 1/2/3/4 1 red\n", "x.cpt:1:3:", "CMYK"),
            ("0 red\n0 red 1 blue\n", "x.cpt:2:1:", "categorical"),
            ("0 red 1 blue\n1 red\n", "x.cpt:2:1:", "key colour"),
            ("Ocean 1/2\n", "x.cpt:1:7:", "R/G/B"),
            ("0 10/20/x 1 red\n", "x.cpt:1:9:", "`x`"),
            ("0 red@150 1 red\n", "x.cpt:1:7:", "transparency"),
            ("2012-01-01 red 2013-01-01 blue\n", "x.cpt:1:1:", "plain number"),
            ("0 400-1-1 1 red\n", "x.cpt:1:3:", "hue"),
        ];
        for (text, at, what) in bad {
            let e = import_text(Format::Cpt, "x.cpt", text).unwrap_err().to_string();
            assert!(e.starts_with(at) && e.contains(what), "{text:?}: {e}");
        }
        assert!(matches!(
            import_text(Format::Cpt, "x.cpt", "# only comments\nB black\n"),
            Err(super::super::ImportError::Empty { .. })
        ));
    }
}
