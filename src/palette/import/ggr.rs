//! GIMP gradients (`.ggr`).
//!
//! The format (GIMP's `devel-docs/ggr.txt`, read as `gimp_gradient_load` reads it): a line
//! `GIMP Gradient`, an optional `Name: ...` line, the number of segments, then one line per
//! segment: `left middle right  r0 g0 b0 a0  r1 g1 b1 a1  blend coloring
//! [left_color_type right_color_type]` (11 floats, then 2 or 4 integers). Segments follow
//! each other from 0 to 1; `middle` lies between `left` and `right`.
//!
//! Colours are sRGB-encoded (R'G'B') floats in [0, 1]: `gimp_gradient_get_color_at` blends
//! them as they are in its default "perceptual RGB" mode and converts them from sRGB to
//! linear only for its optional "linear RGB" mode. So our palette is in space `srgb` and
//! reproduces GIMP's default. Mode `clamp` (a GIMP gradient runs once from 0 to 1).
//!
//! Inside a segment GIMP maps the position to `pos` in [0, 1] (and the middle to `m`),
//! turns it into a blend factor, and mixes the end colours with it:
//! - 0 linear: `pos/m / 2` up to the middle, then `1/2 + (pos-m)/(1-m) / 2`;
//! - 1 curved: `pos^(ln 0.5 / ln m)`;
//! - 2 sine: `(sin(-pi/2 + pi * linear) + 1) / 2`;
//! - 3 sphere increasing: `sqrt(1 - (linear - 1)^2)`;
//! - 4 sphere decreasing: `1 - sqrt(1 - linear^2)`;
//! - 5 step: 0 before the middle, 1 from it on (a hard edge).
//!
//! Colouring 0 mixes R, G, B; 1 (HSV counter-clockwise) and 2 (HSV clockwise) convert both
//! ends to HSV (`gimp_rgb_to_hsv`), mix saturation and value, and turn the hue the stated
//! way round (all the way round when both hues are equal, as GIMP does). Opacity always
//! mixes linearly with the factor. All of this is done exactly and sampled into stops (see
//! the parent module: within 1/255 everywhere, exact at segment ends).
//!
//! Endpoint colour types 1-4 take the colour from GIMP's context (foreground, background,
//! or either made transparent); with no context we use GIMP's default colours, foreground
//! black and background white, with opacity 0 for the transparent types. A jump in colour
//! between one segment's right end and the next one's left end is a hard edge; the
//! boundary itself takes the next segment's colour, as in GIMP.

use super::{Ctx, ImportError, Rgba, StopList, hsv_to_rgb, int_word, lines, palette_name, rgb_to_hsv, words};
use crate::palette::{Mode, Palette};

/// GIMP's `EPSILON` in `gimpgradient.c`.
const EPSILON: f64 = 1e-10;

/// How far segment ends may be from where they should be (GIMP writes six decimals).
const SLACK: f64 = 1e-6;

/// A blend function.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Blend {
    Linear,
    Curved,
    Sine,
    SphereIncreasing,
    SphereDecreasing,
    Step,
}

/// A colouring type.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Coloring {
    Rgb,
    HsvCcw,
    HsvCw,
}

/// One segment, positions as in the file.
#[derive(Debug, Clone, Copy)]
struct Segment {
    left: f64,
    middle: f64,
    right: f64,
    left_color: Rgba,
    right_color: Rgba,
    blend: Blend,
    coloring: Coloring,
}

impl Segment {
    /// The colour at gradient position `x` (`gimp_gradient_get_color_at`, perceptual RGB).
    fn at(&self, x: f64) -> Rgba {
        let len = self.right - self.left;
        let (middle, pos) = if len < EPSILON {
            (0.5, 0.5)
        } else {
            ((self.middle - self.left) / len, ((x - self.left) / len).clamp(0.0, 1.0))
        };
        self.mix(factor(self.blend, middle, pos))
    }

    /// The end colours mixed with blend factor `f`.
    fn mix(&self, f: f64) -> Rgba {
        let (l, r) = (self.left_color, self.right_color);
        let alpha = l[3] + (r[3] - l[3]) * f;
        let rgb = match self.coloring {
            Coloring::Rgb => [l[0] + (r[0] - l[0]) * f, l[1] + (r[1] - l[1]) * f, l[2] + (r[2] - l[2]) * f],
            Coloring::HsvCcw | Coloring::HsvCw => {
                let [lh, ls, lv] = rgb_to_hsv([l[0], l[1], l[2]]);
                let [rh, rs, rv] = rgb_to_hsv([r[0], r[1], r[2]]);
                let mut h = lh;
                if self.coloring == Coloring::HsvCcw {
                    if lh < rh {
                        h += (rh - lh) * f;
                    } else {
                        h += (1.0 - (lh - rh)) * f;
                        if h > 1.0 {
                            h -= 1.0;
                        }
                    }
                } else if rh < lh {
                    h -= (lh - rh) * f;
                } else {
                    h -= (1.0 - (rh - lh)) * f;
                    if h < 0.0 {
                        h += 1.0;
                    }
                }
                hsv_to_rgb([h, ls + (rs - ls) * f, lv + (rv - lv) * f])
            }
        };
        [rgb[0], rgb[1], rgb[2], alpha]
    }
}

/// GIMP's blend factor at `pos` in [0, 1] of a segment whose middle is at `middle`.
fn factor(blend: Blend, middle: f64, pos: f64) -> f64 {
    let linear = |middle: f64, pos: f64| {
        if pos <= middle {
            if middle < EPSILON { 0.0 } else { 0.5 * pos / middle }
        } else {
            let (pos, middle) = (pos - middle, 1.0 - middle);
            if middle < EPSILON { 1.0 } else { 0.5 + 0.5 * pos / middle }
        }
    };
    match blend {
        Blend::Linear => linear(middle, pos),
        Blend::Curved => {
            if middle < EPSILON {
                1.0
            } else if 1.0 - middle < EPSILON {
                0.0
            } else {
                (-std::f64::consts::LN_2 * pos.ln() / middle.ln()).exp()
            }
        }
        Blend::Sine => ((-std::f64::consts::FRAC_PI_2 + std::f64::consts::PI * linear(middle, pos)).sin() + 1.0) / 2.0,
        Blend::SphereIncreasing => {
            let p = linear(middle, pos) - 1.0;
            (1.0 - p * p).max(0.0).sqrt()
        }
        Blend::SphereDecreasing => {
            let p = linear(middle, pos);
            1.0 - (1.0 - p * p).max(0.0).sqrt()
        }
        Blend::Step => {
            if pos >= middle {
                1.0
            } else {
                0.0
            }
        }
    }
}

/// The palette in a `.ggr` file.
pub(super) fn parse(ctx: &Ctx<'_>) -> Result<Vec<Palette>, ImportError> {
    let mut lines = lines(ctx.text).peekable();
    match lines.next() {
        Some((_, l)) if l.trim_end() == "GIMP Gradient" => {}
        _ => return Err(ctx.err(0, "not a GIMP gradient: the first line must be `GIMP Gradient`")),
    }
    let mut title = String::new();
    if let Some((_, l)) = lines.peek()
        && let Some(name) = l.strip_prefix("Name:")
    {
        title = name.trim().to_string();
        lines.next();
    }
    let (count_at, count_line) = lines.next().unwrap_or((ctx.text.len(), ""));
    let count = match words(count_line).as_slice() {
        [(at, w)] => {
            let n = int_word(w, "the number of segments").map_err(|e| ctx.err(count_at + at, e.to_string()))?;
            if n < 1 {
                return Err(ctx.err(count_at + at, format!("a gradient needs at least one segment, not {n}")));
            }
            n as usize
        }
        _ => return Err(ctx.err(count_at, "expected the number of segments alone on this line")),
    };
    let mut segments = Vec::with_capacity(count.min(4096));
    for k in 0..count {
        let Some((start, line)) = lines.next() else {
            return Err(ctx.err(ctx.text.len(), format!("the file ends after {k} of its {count} segments")));
        };
        let seg = segment(ctx, start, line)?;
        let expected_left = segments.last().map_or(0.0, |s: &Segment| s.right);
        if (seg.left - expected_left).abs() > SLACK {
            let what = if k == 0 {
                "the first segment must start at 0".to_string()
            } else {
                format!("segment {} must start where the one before ends ({expected_left})", k + 1)
            };
            return Err(ctx.err(start + words(line)[0].0, format!("{what}, not at {}", seg.left)));
        }
        segments.push(seg);
    }
    let last = segments.last().map_or(1.0, |s| s.right);
    if last < 1.0 - SLACK {
        return Err(ctx.err_file(format!("the last segment ends at {last}: segments must cover 0 to 1")));
    }
    let mut stops = StopList::default();
    let mut prev_end: Option<Rgba> = None;
    for (k, seg) in segments.iter().enumerate() {
        // Each segment covers [its left end, the next one's left end); the last one reaches 1.
        let a = if k == 0 { 0.0 } else { seg.left.clamp(0.0, 1.0) };
        let b = segments.get(k + 1).map_or(1.0, |s| s.left.clamp(0.0, 1.0));
        if b <= a {
            continue;
        }
        let start = seg.at(a);
        match prev_end {
            None => stops.push(0.0, start),
            Some(end) => stops.edge(a, end, start),
        }
        if seg.blend == Blend::Step {
            if seg.middle > a && seg.middle < b {
                stops.edge(seg.middle, seg.mix(0.0), seg.mix(1.0));
            }
        } else {
            stops.sample(&|x| seg.at(x), a, b);
        }
        prev_end = Some(seg.at(b));
    }
    let stops = stops.finish(prev_end.unwrap_or([0.0, 0.0, 0.0, 1.0]));
    let detail = if title.is_empty() { String::new() } else { format!("\"{title}\"") };
    Ok(vec![ctx.palette(palette_name(&ctx.stem), &detail, Mode::Clamp, stops)])
}

/// One segment line.
fn segment(ctx: &Ctx<'_>, start: usize, line: &str) -> Result<Segment, ImportError> {
    let w = words(line);
    if w.len() < 13 {
        let at = start + w.last().map_or(0, |(o, s)| o + s.len());
        return Err(ctx.err(
            at,
            format!(
                "a segment line has 11 numbers and 2 or 4 whole numbers \
                 (left middle right, r g b a twice, blend coloring [left-type right-type]); found {} words",
                w.len()
            ),
        ));
    }
    let mut f = [0.0; 11];
    for (k, (at, word)) in w.iter().take(11).enumerate() {
        f[k] = word
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| ctx.err(start + at, format!("expected a number, found `{word}`")))?;
    }
    let int = |k: usize, what: &str, max: i64| -> Result<i64, ImportError> {
        let (at, word) = w[k];
        let v = int_word(word, what).map_err(|e| ctx.err(start + at, e.to_string()))?;
        if !(0..=max).contains(&v) {
            return Err(ctx.err(start + at, format!("{what} {v} is not one GIMP knows (0 to {max})")));
        }
        Ok(v)
    };
    let blend = match int(11, "blend function", 5)? {
        0 => Blend::Linear,
        1 => Blend::Curved,
        2 => Blend::Sine,
        3 => Blend::SphereIncreasing,
        4 => Blend::SphereDecreasing,
        _ => Blend::Step,
    };
    let coloring = match int(12, "coloring type", 2)? {
        0 => Coloring::Rgb,
        1 => Coloring::HsvCcw,
        _ => Coloring::HsvCw,
    };
    let (left_type, right_type) =
        if w.len() >= 15 { (int(13, "endpoint color type", 4)?, int(14, "endpoint color type", 4)?) } else { (0, 0) };
    let [left, middle, right] = [f[0], f[1], f[2]];
    if !(-SLACK..=1.0 + SLACK).contains(&left) || !(-SLACK..=1.0 + SLACK).contains(&right) || right < left {
        return Err(
            ctx.err(start + w[0].0, format!("segment ends {left} and {right} must satisfy 0 <= left <= right <= 1"))
        );
    }
    if middle < left || middle > right {
        return Err(ctx.err(start + w[1].0, format!("the middle {middle} is not between the ends {left} and {right}")));
    }
    Ok(Segment {
        left,
        middle,
        right,
        left_color: endpoint([f[3], f[4], f[5], f[6]], left_type),
        right_color: endpoint([f[7], f[8], f[9], f[10]], right_type),
        blend,
        coloring,
    })
}

/// An endpoint colour by type: fixed (as stored), or GIMP's default foreground (black) or
/// background (white), opaque or transparent.
fn endpoint(stored: Rgba, kind: i64) -> Rgba {
    match kind {
        1 => [0.0, 0.0, 0.0, 1.0],
        2 => [0.0, 0.0, 0.0, 0.0],
        3 => [1.0, 1.0, 1.0, 1.0],
        4 => [1.0, 1.0, 1.0, 0.0],
        _ => stored,
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Format, import_text};
    use super::*;
    use crate::palette::{Definition, Space, color};

    fn one(text: &str) -> Palette {
        import_text(Format::Ggr, "grads/Sunset Glow.ggr", text).unwrap().remove(0)
    }

    /// Palette colour at `t` as sRGB floats (through the lookup table).
    fn srgb_at(p: &Palette, t: f64) -> [f64; 4] {
        let c = p.at(t);
        [
            color::linear_to_srgb(c[0]) as f64,
            color::linear_to_srgb(c[1]) as f64,
            color::linear_to_srgb(c[2]) as f64,
            c[3] as f64,
        ]
    }

    #[test]
    fn factors_match_gimp_formulas() {
        // Linear with the middle at 0.25: half way at the middle, then the second half.
        assert_eq!(factor(Blend::Linear, 0.25, 0.125), 0.25);
        assert_eq!(factor(Blend::Linear, 0.25, 0.625), 0.75);
        // Curved: pos^(ln 0.5 / ln m); m = 0.25 gives the square root.
        assert!((factor(Blend::Curved, 0.25, 0.49) - 0.7).abs() < 1e-12);
        assert_eq!(factor(Blend::Curved, 0.25, 0.0), 0.0);
        assert!((factor(Blend::Sine, 0.5, 0.25) - (1.0 - (std::f64::consts::PI / 4.0).cos()) / 2.0).abs() < 1e-12);
        // Sphere: the linear factor 0.25 (or 0.75) on a quarter circle.
        assert!((factor(Blend::SphereIncreasing, 0.5, 0.25) - (1.0f64 - 0.75 * 0.75).sqrt()).abs() < 1e-12);
        assert!((factor(Blend::SphereDecreasing, 0.5, 0.75) - (1.0 - (1.0f64 - 0.75 * 0.75).sqrt())).abs() < 1e-12);
        assert_eq!(factor(Blend::Step, 0.5, 0.4999), 0.0);
        assert_eq!(factor(Blend::Step, 0.5, 0.5), 1.0);
    }

    #[test]
    fn every_blend_and_coloring() {
        // Segment k: blend k, RGB colouring, black to white; then HSV CCW and CW segments.
        let mut text = String::from("GIMP Gradient\nName: Test gradient\n8\n");
        for k in 0..6 {
            let (l, r) = (k as f64 / 8.0, (k + 1) as f64 / 8.0);
            text += &format!("{l:.6} {:.6} {r:.6} 0 0 0 1 1 1 1 1 {k} 0\n", l + 0.0625 * 0.5);
        }
        text += "0.750000 0.812500 0.875000 1 0 0 1 0 0 1 1 0 1 0 0\n";
        text += "0.875000 0.937500 1.000000 1 0 0 1 0 0 1 0.5 0 2 0 0\n";
        let p = one(&text);
        assert_eq!(p.name, "sunset-glow");
        assert!(p.description.contains("\"Test gradient\""), "{}", p.description);
        assert_eq!((p.space, p.mode), (Space::Srgb, Mode::Clamp));
        let Definition::Stops(stops) = &p.definition else { panic!() };
        // Segment ends are stops with their exact colours: white then black at 1/8 (edge).
        let k = stops.iter().position(|s| s.pos == 0.125).unwrap();
        assert_eq!(stops[k].srgb, [0.0; 3]);
        assert_eq!(stops[k - 1].srgb, [1.0; 3]);
        assert_eq!(stops[k - 1].pos, 0.125 - super::super::EDGE);
        // Within 1/255 of GIMP's formulas everywhere (away from the vertical tangents).
        let segs: Vec<Segment> = (0..8)
            .map(|k| {
                let line = text.lines().nth(3 + k).unwrap();
                segment(&ctx_for(&text), 0, line).unwrap()
            })
            .collect();
        for i in 0..1000 {
            let t = (i as f64 + 0.5) / 1000.0;
            let seg = segs[(t * 8.0) as usize];
            let local = t * 8.0 - (t * 8.0).floor();
            if !(0.01..=0.99).contains(&local) {
                continue;
            }
            let want = seg.at(t);
            let got = srgb_at(&p, t);
            for c in 0..4 {
                assert!((got[c] - want[c]).abs() <= 1.0 / 255.0, "t = {t}, channel {c}: {} vs {}", got[c], want[c]);
            }
        }
        // HSV counter-clockwise from red to blue passes magenta? No: counter-clockwise is
        // increasing hue, red (0) -> yellow -> green -> cyan -> blue (2/3): green at 1/3.
        let green = srgb_at(&p, 0.75 + 0.125 * 0.5);
        assert!(green[1] > 0.99 && green[0] < 0.01 && green[2] < 0.01, "{green:?}");
        // Clockwise from red to blue goes through magenta (hue 5/6) at the middle.
        let magenta = srgb_at(&p, 0.875 + 0.125 * 0.5);
        assert!(magenta[0] > 0.99 && magenta[1] < 0.01 && magenta[2] > 0.99, "{magenta:?}");
        assert!((magenta[3] - 0.75).abs() < 1.0 / 255.0);
    }

    fn ctx_for(text: &str) -> Ctx<'_> {
        Ctx { origin: "t.ggr", text, file: "t.ggr".into(), stem: "t".into(), format: Format::Ggr }
    }

    #[test]
    fn endpoint_types_use_gimp_defaults() {
        let p = one("GIMP Gradient\nName: x\n1\n0 0.5 1 0.2 0.4 0.6 1 0.2 0.4 0.6 1 0 0 2 3\n");
        let Definition::Stops(stops) = &p.definition else { panic!() };
        assert_eq!((stops[0].srgb, stops[0].opacity), ([0.0; 3], 0.0));
        assert_eq!((stops.last().unwrap().srgb, stops.last().unwrap().opacity), ([1.0; 3], 1.0));
    }

    #[test]
    fn old_files_have_no_name_line() {
        let p = one("GIMP Gradient\n1\n0 0.5 1 0 0 0 1 1 1 1 1 0 0\n");
        assert!(!p.description.contains('"'));
        let Definition::Stops(stops) = &p.definition else { panic!() };
        assert_eq!(stops.len(), 2);
    }

    #[test]
    fn errors_name_line_and_column() {
        let bad = [
            ("GIMP gradient\n", "x.ggr:1:1:"),
            ("GIMP Gradient\nName: a\nthree\n", "x.ggr:3:1:"),
            ("GIMP Gradient\nName: a\n2\n0 0.5 1 0 0 0 1 1 1 1 1 0 0\n", "x.ggr:5:1:"),
            ("GIMP Gradient\nName: a\n1\n0 0.5 1 0 0 0 1 1 x 1 1 0 0\n", "x.ggr:4:19:"),
            ("GIMP Gradient\nName: a\n1\n0 0.5 1 0 0 0 1 1 1 1 1 6 0\n", "x.ggr:4:25:"),
            ("GIMP Gradient\nName: a\n1\n0 0.5 1 0 0 0 1 1 1 1 1 0 3\n", "x.ggr:4:27:"),
            ("GIMP Gradient\nName: a\n1\n0 0.5 1 0 0 0 1\n", "x.ggr:4:16:"),
            ("GIMP Gradient\nName: a\n2\n0 0.2 0.4 0 0 0 1 1 1 1 1 0 0\n0.5 0.7 1 0 0 0 1 1 1 1 1 0 0\n", "x.ggr:5:1:"),
            ("GIMP Gradient\nName: a\n1\n0 0.7 0.6 0 0 0 1 1 1 1 1 0 0\n", "x.ggr:4:3:"),
        ];
        for (text, at) in bad {
            let e = import_text(Format::Ggr, "x.ggr", text).unwrap_err().to_string();
            assert!(e.starts_with(at), "{text:?}: {e}");
        }
        let e = import_text(Format::Ggr, "x.ggr", "GIMP Gradient\n1\n0 0.2 0.4 0 0 0 1 1 1 1 1 0 0\n").unwrap_err();
        assert!(e.to_string().contains("cover 0 to 1"), "{e}");
    }
}
