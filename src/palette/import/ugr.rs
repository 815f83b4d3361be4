//! Ultra Fractal gradient files (`.ugr`).
//!
//! A file holds any number of entries `name { ... }`. An entry's `gradient:` section has
//! `title="..."`, `smooth=yes|no`, optionally `rotation=N`, then control points
//! `index=N color=D`; an optional `opacity:` section has its own `smooth=` and points
//! `index=N opacity=A` (0 transparent to 255 opaque; no section means opaque). `;` starts a
//! comment to the end of the line. Sections other than these two (a parameter file's
//! `fractal:`, `layer:`, ...) are skipped, so gradients copied out of `.upr` files import
//! too; each `gradient:` section makes one palette.
//!
//! Colour `D` is a Windows `COLORREF`: the decimal integer `R + 256 G + 65536 B`, red in
//! the low byte. (Checked three ways: JWildfire's `UgrGradientReader` takes the low byte as
//! red; a Chaotica-to-UF converter writes `int(255 r) + (int(255 g) << 8) + (int(255 b) <<
//! 16)`; and Ultra Fractal's default gradient, `index=0 color=8716288 index=100
//! color=16121855 index=200 color=46591 index=300 color=156`, reads as navy 0x000085,
//! near-white, orange 0xFFB500 and dark red 0x9C0000 only in that order.) Values are
//! sRGB-encoded bytes; space `srgb`.
//!
//! Positions: a gradient has 400 indices around a circle (index value 1.0 wraps to the
//! start), so index `N` is position `N / 400`, taken modulo 400 (files may hold negative
//! indices or ones past 399). Gradients are cyclic: mode `repeat`, and between the last
//! control point and the first one plus 400 the colours blend across the wrap, with a
//! closing stop at 1.0 equal to the colour at index 0.
//!
//! `smooth=no` blends linearly between control points (exact here). `smooth=yes` is Ultra
//! Fractal's spline, whose exact form is not documented: we use a cyclic cubic Hermite
//! spline through the control points with Catmull-Rom tangents (the slope between the two
//! neighbours), clamped to [0, 1], sampled into stops; it passes exactly through every
//! control point but may differ slightly from Ultra Fractal between them. `rotation` only
//! turns the gradient on screen and is ignored.

use std::collections::BTreeMap;

use super::{Ctx, ImportError, Rgba, StopList, palette_name};
use crate::palette::{Mode, Palette, Stop};

/// Positions around an Ultra Fractal gradient.
const INDICES: i64 = 400;

/// A token of the file.
#[derive(Debug, Clone, PartialEq)]
enum Token<'a> {
    Open,
    Close,
    /// `name:` (a section).
    Section(&'a str),
    /// `key=value`, quotes removed, with the value's offset.
    Pair(&'a str, &'a str, usize),
    /// Anything else.
    Word(&'a str),
}

/// Splits the text into tokens with their byte offsets.
fn tokens<'a>(ctx: &Ctx<'a>) -> Result<Vec<(usize, Token<'a>)>, ImportError> {
    let text = ctx.text;
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        if c.is_ascii_whitespace() {
            i += 1;
        } else if c == b';' {
            while i < bytes.len() && bytes[i] != b'\n' {
                i += 1;
            }
        } else if c == b'{' || c == b'}' {
            out.push((i, if c == b'{' { Token::Open } else { Token::Close }));
            i += 1;
        } else {
            let start = i;
            let mut eq = None;
            while i < bytes.len() && !bytes[i].is_ascii_whitespace() && !matches!(bytes[i], b'{' | b'}' | b';') {
                if bytes[i] == b'=' && eq.is_none() {
                    eq = Some(i);
                    if bytes.get(i + 1) == Some(&b'"') {
                        let close = text[i + 2..]
                            .find('"')
                            .ok_or_else(|| ctx.err(i + 1, "this quoted value has no closing `\"`"))?;
                        let end = i + 2 + close;
                        out.push((start, Token::Pair(&text[start..i], &text[i + 2..end], i + 2)));
                        i = end + 1;
                        break;
                    }
                }
                i += 1;
            }
            if matches!(out.last(), Some((s, Token::Pair(..))) if *s == start) {
                continue;
            }
            let word = &text[start..i];
            out.push((
                start,
                match eq {
                    Some(e) => Token::Pair(&text[start..e], &text[e + 1..i], e + 1),
                    None if word.len() > 1 && word.ends_with(':') => Token::Section(&word[..word.len() - 1]),
                    None => Token::Word(word),
                },
            ));
        }
    }
    Ok(out)
}

/// One gradient as read.
#[derive(Debug, Default)]
struct Gradient {
    entry: String,
    title: String,
    smooth: bool,
    colors: BTreeMap<i64, [f64; 3]>,
    opacity_smooth: bool,
    opacity: BTreeMap<i64, f64>,
}

/// The palettes in a `.ugr` file, one per gradient, in file order.
pub(super) fn parse(ctx: &Ctx<'_>) -> Result<Vec<Palette>, ImportError> {
    let toks = tokens(ctx)?;
    let mut gradients: Vec<Gradient> = Vec::new();
    let mut i = 0;
    while i < toks.len() {
        // Entry name: the words before `{`.
        let name_start = i;
        while i < toks.len() && !matches!(toks[i].1, Token::Open | Token::Close) {
            i += 1;
        }
        match toks.get(i) {
            None => return Err(ctx.err(toks[name_start].0, "expected `{` after this entry name")),
            Some((at, Token::Close)) => return Err(ctx.err(*at, "`}` without a matching `{`")),
            _ => {}
        }
        let open_at = toks[i].0;
        let entry = match (toks.get(name_start), i > name_start) {
            (Some((s, _)), true) => ctx.text[*s..open_at].trim().to_string(),
            _ => String::new(),
        };
        i += 1;
        let mut section = String::new();
        let mut pending: Option<(usize, i64)> = None;
        let mut has_gradient = false;
        loop {
            let Some((at, tok)) = toks.get(i).cloned() else {
                return Err(ctx.err(open_at, "this `{` is never closed"));
            };
            i += 1;
            match tok {
                Token::Close => break,
                Token::Open => return Err(ctx.err(at, "unexpected `{` inside an entry")),
                Token::Section(s) => {
                    if let Some((p, _)) = pending.take() {
                        return Err(ctx.err(p, "this `index=` has no value after it"));
                    }
                    section = s.to_ascii_lowercase();
                    if section == "gradient" {
                        gradients.push(Gradient { entry: entry.clone(), ..Gradient::default() });
                        has_gradient = true;
                    } else if section == "opacity" && !has_gradient {
                        return Err(ctx.err(at, "an `opacity:` section must follow a `gradient:` section"));
                    }
                }
                Token::Word(w) if section == "gradient" || section == "opacity" => {
                    return Err(ctx.err(at, format!("expected `key=value`, found `{w}`")));
                }
                Token::Word(_) => {}
                Token::Pair(key, value, vat) if section == "gradient" || section == "opacity" => {
                    let g = gradients.last_mut().expect("a gradient section was opened");
                    let key = key.to_ascii_lowercase();
                    let yes_no = || match value.to_ascii_lowercase().as_str() {
                        "yes" => Ok(true),
                        "no" => Ok(false),
                        _ => Err(ctx.err(vat, format!("expected `yes` or `no`, found `{value}`"))),
                    };
                    let number = |lo: i64, hi: i64, what: &str| {
                        value
                            .parse::<i64>()
                            .ok()
                            .filter(|v| (lo..=hi).contains(v))
                            .ok_or_else(|| ctx.err(vat, format!("expected {what} ({lo} to {hi}), found `{value}`")))
                    };
                    let value_key = if section == "gradient" { "color" } else { "opacity" };
                    match key.as_str() {
                        "index" => {
                            if let Some((p, _)) = pending {
                                return Err(ctx.err(p, format!("this `index=` has no `{value_key}=` after it")));
                            }
                            pending = Some((at, number(-1_000_000, 1_000_000, "an index")?));
                        }
                        k if k == value_key => {
                            let Some((_, index)) = pending.take() else {
                                return Err(ctx.err(at, format!("`{value_key}=` must follow an `index=`")));
                            };
                            let index = index.rem_euclid(INDICES);
                            if section == "gradient" {
                                let d = number(0, 0xFF_FFFF, "a colour")?;
                                let rgb = [d & 0xFF, (d >> 8) & 0xFF, (d >> 16) & 0xFF].map(|b| b as f64 / 255.0);
                                g.colors.insert(index, rgb);
                            } else {
                                g.opacity.insert(index, number(0, 255, "an opacity")? as f64 / 255.0);
                            }
                        }
                        "smooth" if section == "gradient" => g.smooth = yes_no()?,
                        "smooth" => g.opacity_smooth = yes_no()?,
                        "title" if section == "gradient" => g.title = value.to_string(),
                        _ => {}
                    }
                }
                Token::Pair(..) => {}
            }
        }
        if let Some((p, _)) = pending {
            return Err(ctx.err(p, "this `index=` has no value after it"));
        }
    }
    let mut used: Vec<String> = Vec::new();
    let mut out = Vec::new();
    for g in gradients {
        if g.colors.is_empty() {
            continue;
        }
        let base = palette_name(if !g.entry.is_empty() {
            &g.entry
        } else if !g.title.is_empty() {
            &g.title
        } else {
            &ctx.stem
        });
        let mut name = base.clone();
        let mut n = 1;
        while used.contains(&name) {
            n += 1;
            name = format!("{base}-{n}");
        }
        used.push(name.clone());
        let detail = if g.title.is_empty() { format!("\"{}\"", g.entry) } else { format!("\"{}\"", g.title) };
        out.push(ctx.palette(name, &detail, Mode::Repeat, stops(&g)));
    }
    Ok(out)
}

/// Stops for a gradient: one at every control point (colour or opacity) and at 0, sampled
/// in between where the gradient is smooth, closed at 1.0 with the colour at index 0.
fn stops(g: &Gradient) -> Vec<Stop> {
    let colors: Vec<(f64, [f64; 3])> = g.colors.iter().map(|(&i, &c)| (i as f64, c)).collect();
    let opacity: Vec<(f64, [f64; 1])> = g.opacity.iter().map(|(&i, &a)| (i as f64, [a])).collect();
    let f = |t: f64| -> Rgba {
        let x = t * INDICES as f64;
        let c = cyclic(&colors, g.smooth, x);
        let a = if opacity.is_empty() { 1.0 } else { cyclic(&opacity, g.opacity_smooth, x)[0] };
        [c[0], c[1], c[2], a]
    };
    let mut breaks: Vec<i64> = g.colors.keys().chain(g.opacity.keys()).copied().collect();
    breaks.push(0);
    breaks.sort_unstable();
    breaks.dedup();
    let mut list = StopList::default();
    for (k, &b) in breaks.iter().enumerate() {
        let next = breaks.get(k + 1).copied().unwrap_or(INDICES);
        list.sample(&f, b as f64 / INDICES as f64, next as f64 / INDICES as f64);
    }
    list.finish(f(0.0))
}

/// The value at `x` (in [0, 400)) of control points `points` (sorted, positions in [0,
/// 400)) placed around a circle of 400: linear between neighbours, or a Catmull-Rom
/// Hermite spline when `smooth`.
fn cyclic<const N: usize>(points: &[(f64, [f64; N])], smooth: bool, x: f64) -> [f64; N] {
    let n = points.len();
    if n == 1 {
        return points[0].1;
    }
    let period = INDICES as f64;
    // Point k's position unwrapped around the circle (k may run from -1 to n + 1).
    let at = |k: isize| -> (f64, [f64; N]) {
        let m = k.rem_euclid(n as isize) as usize;
        let turns = k.div_euclid(n as isize) as f64;
        (points[m].0 + turns * period, points[m].1)
    };
    // The interval [k, k + 1] holding x (k = -1: before the first point, after the wrap).
    let k = points.iter().rposition(|p| p.0 <= x).map_or(-1, |k| k as isize);
    let (x0, v0) = at(k);
    let (x1, v1) = at(k + 1);
    let h = x1 - x0;
    let t = if h > 0.0 { (x - x0) / h } else { 0.0 };
    if !smooth {
        return std::array::from_fn(|c| v0[c] + (v1[c] - v0[c]) * t);
    }
    let (xp, vp) = at(k - 1);
    let (xn, vn) = at(k + 2);
    let (t2, t3) = (t * t, t * t * t);
    let (h00, h10, h01, h11) = (2.0 * t3 - 3.0 * t2 + 1.0, t3 - 2.0 * t2 + t, -2.0 * t3 + 3.0 * t2, t3 - t2);
    std::array::from_fn(|c| {
        let m0 = (v1[c] - vp[c]) / (x1 - xp);
        let m1 = (vn[c] - v0[c]) / (xn - x0);
        h00 * v0[c] + h10 * h * m0 + h01 * v1[c] + h11 * h * m1
    })
}

#[cfg(test)]
mod tests {
    use super::super::{Format, import_text};
    use super::*;
    use crate::palette::{Definition, Space};

    const DEFAULT: &str = "; Ultra Fractal's default gradient\n\
        Default {\ngradient:\n  title=\"Default gradient\" smooth=no rotation=1\n  \
        index=0 color=8716288 index=100 color=16121855\n  index=200 color=46591 index=300 color=156\n\
        opacity:\n  smooth=no index=0 opacity=255\n}\n";

    #[test]
    fn colours_are_colorref() {
        let p = import_text(Format::Ugr, "x.ugr", DEFAULT).unwrap();
        assert_eq!(p.len(), 1);
        let p = &p[0];
        assert_eq!(p.name, "default");
        assert!(p.description.contains("\"Default gradient\""), "{}", p.description);
        assert_eq!((p.space, p.mode), (Space::Srgb, Mode::Repeat));
        let Definition::Stops(s) = &p.definition else { panic!() };
        let pos: Vec<f64> = s.iter().map(|s| s.pos).collect();
        assert_eq!(pos, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
        let hex: Vec<String> = s.iter().map(|s| crate::palette::color::to_hex(s.srgb)).collect();
        assert_eq!(hex, vec!["#000085", "#fffff5", "#ffb500", "#9c0000", "#000085"]);
    }

    #[test]
    fn several_gradients_wrap_and_opacity() {
        let text = "first {\ngradient:\n title=\"A b\" smooth=no index=-100 color=255 index=100 color=65280\n\
            opacity:\n smooth=no index=0 opacity=0 index=200 opacity=255\n}\n\
            first {\ngradient:\n title=\"Again\" smooth=yes index=50 color=16711680\n}\n";
        let p = import_text(Format::Ugr, "x.ugr", text).unwrap();
        assert_eq!(p.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(), vec!["first", "first-2"]);
        let Definition::Stops(s) = &p[0].definition else { panic!() };
        // Index -100 is 300: red at 0.75, green at 0.25; index 0 lies half way across the wrap.
        let at = |pos: f64| *s.iter().find(|s| s.pos == pos).unwrap();
        assert_eq!(at(0.75).srgb, [1.0, 0.0, 0.0]);
        assert_eq!(at(0.25).srgb, [0.0, 1.0, 0.0]);
        assert_eq!(at(0.0).srgb, [128.0 / 255.0, 128.0 / 255.0, 0.0]);
        assert_eq!(at(0.0).opacity, 0.0);
        assert_eq!(at(0.5).opacity, 1.0);
        assert_eq!(at(0.25).opacity, 0.5);
        assert_eq!(at(1.0), crate::palette::Stop { pos: 1.0, ..at(0.0) });
        // One control point: a constant.
        let Definition::Stops(s) = &p[1].definition else { panic!() };
        assert!(s.iter().all(|s| s.srgb == [0.0, 0.0, 1.0]));
    }

    #[test]
    fn smooth_spline_passes_through_points() {
        let pts = [(0.0, [0.0]), (100.0, [1.0]), (250.0, [0.2])];
        for (x, v) in pts {
            assert!((cyclic(&pts, true, x)[0] - v[0]).abs() < 1e-12);
        }
        // Between points it is smooth: the tangent at 100 is (0.2 - 0) / (250 - 0).
        let d = (cyclic(&pts, true, 100.001)[0] - cyclic(&pts, true, 99.999)[0]) / 0.002;
        assert!((d - 0.2 / 250.0).abs() < 1e-6, "{d}");
        // Across the wrap: between 250 and 400 (= 0).
        let mid = cyclic(&pts, false, 325.0)[0];
        assert!((mid - 0.1).abs() < 1e-12);
    }

    #[test]
    fn errors_name_line_and_column() {
        let bad = [
            ("a {\ngradient:\n index=0 color=red\n}\n", "x.ugr:3:16:", "colour"),
            ("a {\ngradient:\n index=0 color=16777216\n}\n", "x.ugr:3:16:", "colour"),
            ("a {\ngradient:\n color=5\n}\n", "x.ugr:3:2:", "index"),
            ("a {\ngradient:\n index=3 index=4 color=5\n}\n", "x.ugr:3:2:", "no `color=`"),
            ("a {\ngradient:\n smooth=maybe\n}\n", "x.ugr:3:9:", "yes"),
            ("a {\ngradient:\n title=\"x\n}\n", "x.ugr:3:8:", "closing"),
            ("a {\ngradient:\n index=0 color=5\n", "x.ugr:1:3:", "never closed"),
            ("a {\ngradient:\n index=0 color=5\n}\n}\n", "x.ugr:5:1:", "without"),
            ("a {\nopacity:\n index=0 opacity=5\n}\n", "x.ugr:2:1:", "follow"),
            ("a {\ngradient:\n index=0 opacity=5\n}\n", "x.ugr:3:2:", "no value"),
        ];
        for (text, at, what) in bad {
            let e = import_text(Format::Ugr, "x.ugr", text).unwrap_err().to_string();
            assert!(e.starts_with(at) && e.contains(what), "{text:?}: {e}");
        }
        assert!(matches!(
            import_text(Format::Ugr, "x.ugr", "; nothing here\ncomment {\n fractal:\n x=1\n}\n"),
            Err(super::super::ImportError::Empty { .. })
        ));
    }
}
