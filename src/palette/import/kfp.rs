//! Kalles Fraktaler palettes and locations (`.kfp`, `.kfr`).
//!
//! Both are the same text (`CFraktalSFT::ToText` in KF's `Parameter.cpp`): lines
//! `Key: value`, read by [`crate::kf_text`] as for a location (a malformed line, or
//! `Colors` or `ColorOffset` given twice, is an error); a palette file is a location file
//! loaded without its location. The colours are the `Colors:` line, a comma-separated
//! list of byte values, three per key colour, usually with a trailing comma. We also read
//! `ColorOffset:` (0..1023, the palette's rotation in 1024ths); every other key
//! (iterations, `IterDiv`, slopes, the multi-wave colouring `MultiColor`/`MultiColors`,
//! textures...) is ignored.
//!
//! Channel order is blue, green, red. KF's key colours are `COLOR14 { r, g, b }` structs,
//! written and read as `r,g,b` in that order, but the field named `r` holds blue and `b`
//! holds red: the colour dialog fills a key from the Windows colour chooser's `COLORREF`
//! with `c.b = cc[0]` (red byte) and `c.r = cc[2]` (blue byte), paints keys with
//! `RGB(c.b, c.g, c.r)`, and `SetColor` copies `r` to byte 0 of the BGR bitmap (blue) and
//! `b` to byte 2 (red), all in `main_color.cpp` / `fraktal_sft.cpp`. So each triple in the
//! file is `B,G,R`, sRGB-encoded bytes (space `srgb`).
//!
//! KF spreads the `N` keys evenly over a cyclic table of 1024 colours (`ApplyColors`):
//! entry `i` sits at `x = i N / 1024` between key `p = floor(x)` and key `p + 1` (the last
//! key blends back into the first), with an eased weight `w = sin((x - p - 1/2) pi) / 2 +
//! 1/2`, not a linear one. We place key `k` at position `k / N`, exactly its colour,
//! sample the eased blend between keys (within 1/255; KF itself truncates the table to
//! bytes), close with key 0 at 1.0, and use mode `repeat`. `ColorOffset` becomes the
//! palette offset `ColorOffset / 1024` (KF looks up table entry `index + ColorOffset`).

use super::{Ctx, ImportError, Rgba, StopList, palette_name};
use crate::kf_text::{Entry, KfText};
use crate::palette::{Mode, Palette};

/// Entries in KF's colour table.
const TABLE: f64 = 1024.0;

/// The palette in a `.kfp` or `.kfr` file.
pub(super) fn parse(ctx: &Ctx<'_>) -> Result<Vec<Palette>, ImportError> {
    let lines = KfText::parse(ctx.text, &["Colors", "ColorOffset"]).map_err(|e| ctx.err(e.at(), e.to_string()))?;
    let keys = lines.get("Colors").map(|e| colors(ctx, e)).transpose()?;
    let mut offset = 0.0;
    if let Some(e) = lines.get("ColorOffset") {
        let word = e.value;
        let v: i64 =
            word.parse().map_err(|_| ctx.err(e.value_at, format!("expected a whole number, found `{word}`")))?;
        // KF resets an offset outside 0..1023 to 0.
        offset = if (0..1024).contains(&v) { v as f64 / TABLE } else { 0.0 };
    }
    let Some(keys) = keys else {
        return Err(ctx.err_file("no `Colors:` line: not a Kalles Fraktaler palette or location"));
    };
    if keys.is_empty() {
        return Ok(Vec::new());
    }
    let n = keys.len();
    let rgba = |c: [f64; 3]| -> Rgba { [c[0], c[1], c[2], 1.0] };
    let f = |t: f64| -> Rgba {
        let x = t * n as f64;
        let p = (x.floor().max(0.0) as usize).min(n - 1);
        let w = ((x - p as f64 - 0.5) * std::f64::consts::PI).sin() / 2.0 + 0.5;
        let (a, b) = (keys[p], keys[(p + 1) % n]);
        rgba(std::array::from_fn(|c| a[c] + (b[c] - a[c]) * w))
    };
    let mut stops = StopList::default();
    for k in 0..n {
        stops.sample(&f, k as f64 / n as f64, (k + 1) as f64 / n as f64);
    }
    let stops = stops.finish(rgba(keys[0]));
    let detail = format!("{n} key colour{}", if n == 1 { "" } else { "s" });
    Ok(vec![ctx.palette(palette_name(&ctx.stem), &detail, Mode::Repeat, stops).adjusted(offset, 1.0)])
}

/// The key colours of a `Colors:` line: `B,G,R,` triples.
fn colors(ctx: &Ctx<'_>, line: &Entry<'_>) -> Result<Vec<[f64; 3]>, ImportError> {
    let mut bytes = Vec::new();
    let mut pos = line.value_at;
    let parts: Vec<&str> = line.value.split(',').collect();
    for (k, part) in parts.iter().enumerate() {
        let word = part.trim();
        let word_at = pos + (part.len() - part.trim_start().len());
        pos += part.len() + 1;
        if word.is_empty() && k == parts.len() - 1 {
            break; // the trailing comma KF writes
        }
        let v: u32 =
            word.parse().map_err(|_| ctx.err(word_at, format!("expected a colour value 0-255, found `{word}`")))?;
        if v > 255 {
            return Err(ctx.err(word_at, format!("colour value {v} is outside 0-255")));
        }
        bytes.push(v as f64 / 255.0);
    }
    if bytes.len() % 3 != 0 {
        let message = format!("`Colors:` holds {} values, not a whole number of B,G,R triples", bytes.len());
        return Err(ctx.err(line.colon_at + 1, message));
    }
    Ok(bytes.chunks(3).map(|c| [c[2], c[1], c[0]]).collect())
}

#[cfg(test)]
mod tests {
    use super::super::{Format, import_text};
    use crate::palette::{Definition, Mode, Space, color};

    #[test]
    fn keys_are_bgr_and_eased() {
        let text = "Re: 0\r\nIm: 0\r\nZoom: 1\r\nIterations: 100\r\nColorOffset: 256\r\n\
                    Colors: 0,0,255,255,0,0,\r\nSmooth: 1\r\nMultiColors: \r\n";
        let p = import_text(Format::Kfp, "dir/Two Keys.kfr", text).unwrap().remove(0);
        assert_eq!(p.name, "two-keys");
        assert_eq!((p.space, p.mode, p.offset, p.density), (Space::Srgb, Mode::Repeat, 0.25, 1.0));
        let Definition::Stops(s) = &p.definition else { panic!() };
        assert_eq!((s[0].pos, s[0].srgb), (0.0, [1.0, 0.0, 0.0]), "first key is red (B,G,R = 0,0,255)");
        let half = s.iter().find(|s| s.pos == 0.5).unwrap();
        assert_eq!(half.srgb, [0.0, 0.0, 1.0], "second key is blue");
        assert_eq!(s.last().unwrap().pos, 1.0);
        assert_eq!(s.last().unwrap().srgb, [1.0, 0.0, 0.0]);
        // Eased, not linear: a quarter of the way from red to blue (x = 0.5 between keys 0
        // and 1) the weight is sin(0)/2 + 1/2 = 1/2; at x = 0.25 it is sin(-pi/4)/2 + 1/2.
        let plain = p.clone().adjusted(0.0, 1.0);
        let w = (-std::f64::consts::FRAC_PI_4).sin() / 2.0 + 0.5;
        let c = plain.at(0.125);
        let r = color::linear_to_srgb(c[0]) as f64;
        assert!((r - (1.0 - w)).abs() < 1.0 / 255.0, "{r} vs {}", 1.0 - w);
        // ColorOffset 256 of 1024 shifts by a quarter: t = 0 shows what was at 0.25.
        assert_eq!(p.at(0.0), plain.at(0.25));
    }

    #[test]
    fn errors_name_line_and_column() {
        let bad = [
            ("Colors: 1,2,x,\r\n", "x.kfp:1:13:", "`x`"),
            ("Zoom: 1\nColors: 1,2,300,\n", "x.kfp:2:13:", "outside"),
            ("Colors: 1,2,3,4,\n", "x.kfp:1:8:", "triples"),
            ("Colors: 1,,3,\n", "x.kfp:1:11:", "found ``"),
            ("Colors: 1,2,3,\nColorOffset: many\n", "x.kfp:2:14:", "whole number"),
            ("Zoom: 1\n  no colon\nColors: 1,2,3,\n", "x.kfp:2:3:", "Key: value"),
            ("Colors: 1,2,3,\nColors: 4,5,6,\n", "x.kfp:2:1:", "twice"),
        ];
        for (text, at, what) in bad {
            let e = import_text(Format::Kfp, "x.kfp", text).unwrap_err().to_string();
            assert!(e.starts_with(at) && e.contains(what), "{text:?}: {e}");
        }
        let e = import_text(Format::Kfp, "x.kfp", "Re: 0\nIm: 0\n").unwrap_err().to_string();
        assert!(e.starts_with("x.kfp: ") && e.contains("Colors"), "{e}");
        assert!(matches!(
            import_text(Format::Kfp, "x.kfp", "Colors: \n"),
            Err(super::super::ImportError::Empty { .. })
        ));
    }
}
