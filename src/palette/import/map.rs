//! Fractint / XaoS colour maps (`.map`).
//!
//! The format, as Fractint's `ValidateLuts` (`loadmap.c`) reads it: one colour per line,
//! `R G B` as decimal integers 0..255 (sRGB-encoded, what the VGA DAC was given), read with
//! `sscanf("%u %u %u")`, so anything after the third number is a comment (many maps name
//! the colour there). At most 256 lines are read; later lines are ignored. Fractint keeps
//! only the top 6 bits of each value (the DAC's precision); we keep all 8.
//!
//! Fractint colours by `iteration mod 256`, so a map is cyclic: entry `k` of `n` becomes a
//! stop at position `k / n`, exactly its colour, and a closing stop at 1.0 repeats entry 0
//! (mode `repeat`, space `srgb`, linear blending between entries as colour-cycling
//! programs do when they smooth a map).
//!
//! Where we differ from Fractint, on purpose: a blank line, or one starting with `;` or
//! `#`, is skipped (Fractint would turn it into a repeat of the previous entry; some tools
//! write such header comments); a value above 255 or a line that does not start with three
//! numbers is an error naming line and column (Fractint would silently wrap the value
//! modulo 256 or reuse the previous entry's values); a map with fewer than 256 entries
//! spreads them over the whole palette instead of padding with grey as Fractint does.

use super::{Ctx, ImportError, StopList, lines, palette_name};
use crate::palette::{Mode, Palette};

/// Entries Fractint reads at most.
const MAX_ENTRIES: usize = 256;

/// The palette in a `.map` file.
pub(super) fn parse(ctx: &Ctx<'_>) -> Result<Vec<Palette>, ImportError> {
    let mut entries: Vec<[f64; 3]> = Vec::new();
    for (start, line) in lines(ctx.text) {
        let body = line.trim_start();
        if body.is_empty() || body.starts_with(';') || body.starts_with('#') {
            continue;
        }
        if entries.len() == MAX_ENTRIES {
            break;
        }
        entries.push(entry(ctx, start, line)?);
    }
    if entries.is_empty() {
        return Ok(Vec::new());
    }
    let n = entries.len();
    let rgba = |c: [f64; 3]| [c[0], c[1], c[2], 1.0];
    let mut stops = StopList::default();
    for (k, c) in entries.iter().enumerate() {
        stops.push(k as f64 / n as f64, rgba(*c));
    }
    let stops = stops.finish(rgba(entries[0]));
    let detail = format!("{n} entr{}", if n == 1 { "y" } else { "ies" });
    Ok(vec![ctx.palette(palette_name(&ctx.stem), &detail, Mode::Repeat, stops)])
}

/// `R G B` at the start of `line` (which starts at byte `start` of the text).
fn entry(ctx: &Ctx<'_>, start: usize, line: &str) -> Result<[f64; 3], ImportError> {
    let bytes = line.as_bytes();
    let mut i = 0;
    let mut rgb = [0.0; 3];
    for (k, what) in ["red", "green", "blue"].iter().enumerate() {
        while i < bytes.len() && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        let from = i;
        while i < bytes.len() && bytes[i].is_ascii_digit() {
            i += 1;
        }
        if i == from {
            let found =
                line[from..].split_whitespace().next().map_or("the end of the line".to_string(), |w| format!("`{w}`"));
            return Err(ctx.err(start + from, format!("expected the {what} value (0-255), found {found}")));
        }
        if k < 2 && i < bytes.len() && !bytes[i].is_ascii_whitespace() {
            let c = line[i..].chars().next().unwrap_or(' ');
            return Err(ctx.err(start + i, format!("unexpected `{c}` after the {what} value")));
        }
        let v: u32 = line[from..i].parse().unwrap_or(u32::MAX);
        if v > 255 {
            return Err(ctx.err(start + from, format!("{what} value {} is outside 0-255", &line[from..i])));
        }
        rgb[k] = v as f64 / 255.0;
    }
    Ok(rgb)
}

#[cfg(test)]
mod tests {
    use super::super::{Format, import_text};
    use crate::palette::{Definition, Mode, Space};

    #[test]
    fn entries_are_evenly_spaced_and_cyclic() {
        let text = "; header\n0 0 0 black\n255 0 0\n\n  0 128 255   sky\n# trailing\n";
        let p = import_text(Format::Map, "maps/Blue Fire.map", text).unwrap();
        assert_eq!(p.len(), 1);
        let p = &p[0];
        assert_eq!(p.name, "blue-fire");
        assert_eq!((p.space, p.mode), (Space::Srgb, Mode::Repeat));
        assert!(p.description.contains("Blue Fire.map") && p.description.contains("3 entries"), "{}", p.description);
        let Definition::Stops(stops) = &p.definition else { panic!() };
        let pos: Vec<f64> = stops.iter().map(|s| s.pos).collect();
        assert_eq!(pos, vec![0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0]);
        assert_eq!(stops[1].srgb, [1.0, 0.0, 0.0]);
        assert_eq!(stops[2].srgb, [0.0, 128.0 / 255.0, 1.0]);
        assert_eq!(stops[3].srgb, [0.0; 3]);
    }

    #[test]
    fn reads_at_most_256_entries() {
        let text: String = (0..300).map(|i| format!("{} 0 0\n", i % 256)).collect();
        let p = import_text(Format::Map, "x.map", &text).unwrap();
        let Definition::Stops(stops) = &p[0].definition else { panic!() };
        assert_eq!(stops.len(), 257);
        assert_eq!(stops[255].pos, 255.0 / 256.0);
    }

    #[test]
    fn errors_name_line_and_column() {
        let cases = [
            ("0 0 0\n12 300 4\n", "x.map:2:4:", "outside 0-255"),
            ("0 0 0\n1 2\n", "x.map:2:4:", "blue value"),
            ("0 0 0\nred 2 3\n", "x.map:2:1:", "`red`"),
            ("1 2x 3\n", "x.map:1:4:", "unexpected `x`"),
        ];
        for (text, at, what) in cases {
            let e = import_text(Format::Map, "x.map", text).unwrap_err().to_string();
            assert!(e.starts_with(at) && e.contains(what), "{text:?}: {e}");
        }
        assert!(matches!(
            import_text(Format::Map, "x.map", "; nothing\n\n"),
            Err(super::super::ImportError::Empty { .. })
        ));
    }
}
