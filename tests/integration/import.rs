//! Palette import: every format's fixture in `tests/fixtures/palettes/` read through the
//! public API, with colours checked against values worked out by hand from each format's
//! definition (see the fixtures' README), plus bad files, round trips and robustness.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use deepfield::palette::import::{EDGE, Format, ImportError, import_file, import_text};
use deepfield::palette::{Definition, Mode, Palette, Space, Stop, color, parse, to_toml};

use super::util::scratch;

/// Colours may differ from the exact value by at most one 8-bit step.
const TOL: f64 = 1.0 / 255.0;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/palettes").join(name)
}

fn import(name: &str) -> Vec<Palette> {
    import_file(&fixture(name)).unwrap_or_else(|e| panic!("{e}"))
}

fn stops(p: &Palette) -> &[Stop] {
    match &p.definition {
        Definition::Stops(s) => s,
        Definition::Cosine(_) => panic!("{} is not made of stops", p.name),
    }
}

/// The stop at exactly `pos`.
fn stop(p: &Palette, pos: f64) -> Stop {
    *stops(p).iter().find(|s| s.pos == pos).unwrap_or_else(|| panic!("{}: no stop at {pos}", p.name))
}

/// `#rrggbb` of 8-bit values.
fn hex(rgb: [u8; 3]) -> [f32; 3] {
    rgb.map(|v| v as f32 / 255.0)
}

/// Checks the palette's colour at `t` (sRGB, through `Palette::at`) against `want` (sRGB
/// components in [0, 1], then opacity).
fn check(p: &Palette, t: f64, want: [f64; 4]) {
    let c = p.at(t);
    let got = [
        color::linear_to_srgb(c[0]) as f64,
        color::linear_to_srgb(c[1]) as f64,
        color::linear_to_srgb(c[2]) as f64,
        c[3] as f64,
    ];
    for k in 0..4 {
        assert!(
            (got[k] - want[k]).abs() <= TOL,
            "{} at {t}: channel {k} is {} (all {got:?}), expected {} (all {want:?})",
            p.name,
            got[k],
            want[k]
        );
    }
}

fn rgb(r: f64, g: f64, b: f64) -> [f64; 4] {
    [r, g, b, 1.0]
}

#[test]
fn fractint_map() {
    let p = import("sample.map");
    assert_eq!(p.len(), 1);
    let p = &p[0];
    assert_eq!(p.name, "sample");
    assert_eq!(p.description, "Imported from sample.map (Fractint colour map, 8 entries).");
    assert_eq!((p.space, p.mode), (Space::Srgb, Mode::Repeat));
    // Entry k of 8 at k / 8, exactly; a closing stop repeats entry 0.
    assert_eq!(stops(p).len(), 9);
    assert_eq!(stop(p, 2.0 / 8.0).srgb, hex([255, 128, 0]));
    assert_eq!(stop(p, 5.0 / 8.0).srgb, hex([0, 128, 255]));
    assert_eq!(stop(p, 1.0).srgb, hex([0, 0, 0]));
    check(p, 3.0 / 8.0, rgb(1.0, 1.0, 0.0));
    // Half way between entries: the mean of their sRGB values.
    check(p, 1.5 / 8.0, rgb(1.0, 64.0 / 255.0, 0.0));
    check(p, 4.5 / 8.0, rgb(0.0, (255.0 + 128.0) / 2.0 / 255.0, 0.5));
    // Past the last entry the map wraps back to entry 0.
    check(p, 7.5 / 8.0, rgb(0.5, 0.5, 0.5));
    check(p, 1.0 + 3.0 / 8.0, rgb(1.0, 1.0, 0.0));
}

/// GIMP's `gimp_gradient_calc_linear_factor`, for the hand-worked values below.
fn gimp_linear(m: f64, p: f64) -> f64 {
    if p <= m { 0.5 * p / m } else { 0.5 + 0.5 * (p - m) / (1.0 - m) }
}

#[test]
fn gimp_gradient_every_blend_and_colouring() {
    let p = import("sample.ggr");
    let p = &p[0];
    assert_eq!(p.name, "sample");
    assert_eq!(p.description, "Imported from sample.ggr (GIMP gradient, \"Deepfield test\").");
    assert_eq!((p.space, p.mode), (Space::Srgb, Mode::Clamp));
    // Segment k covers [k/8, (k+1)/8); `at(k, local)` is the position `local` of the way in.
    let at = |k: usize, local: f64| (k as f64 + local) / 8.0;

    // 0: linear, middle at 0.4 of the segment, black to white.
    let f = gimp_linear(0.4, 0.2);
    assert_eq!(f, 0.25);
    check(p, at(0, 0.2), rgb(f, f, f));
    let f = gimp_linear(0.4, 0.8);
    check(p, at(0, 0.8), rgb(f, f, f));
    // Hard edge at 1/8: white ends segment 0, red starts segment 1.
    assert_eq!(stop(p, 0.125 - EDGE).srgb, hex([255, 255, 255]));
    assert_eq!(stop(p, 0.125).srgb, hex([255, 0, 0]));

    // 1: curved, middle at 0.3: factor pos^(ln 0.5 / ln 0.3); red to blue, opacity 1 to 0.5.
    for local in [0.1, 0.5, 0.9] {
        let f = (0.5f64.ln() / 0.3f64.ln() * f64::ln(local)).exp();
        check(p, at(1, local), [1.0 - f, 0.0, f, 1.0 - 0.5 * f]);
    }
    assert_eq!(stop(p, 0.25 - EDGE).opacity, 0.5);

    // 2: sine, middle at 0.5; black to green.
    for local in [0.25, 0.5, 0.8] {
        let f = ((-PI / 2.0 + PI * local).sin() + 1.0) / 2.0;
        check(p, at(2, local), rgb(0.0, f, 0.0));
    }
    // 3: sphere increasing; black to yellow.
    for local in [0.2f64, 0.5, 0.9] {
        let f = (1.0 - (local - 1.0) * (local - 1.0)).sqrt();
        check(p, at(3, local), rgb(f, f, 0.0));
    }
    // 4: sphere decreasing; black to cyan.
    for local in [0.1f64, 0.5, 0.8] {
        let f = 1.0 - (1.0 - local * local).sqrt();
        check(p, at(4, local), rgb(0.0, f, f));
    }
    // 5: step at the middle; red, then blue from the middle (11/16) on.
    check(p, at(5, 0.25), rgb(1.0, 0.0, 0.0));
    check(p, at(5, 0.75), rgb(0.0, 0.0, 1.0));
    assert_eq!(stop(p, 0.6875 - EDGE).srgb, hex([255, 0, 0]));
    assert_eq!(stop(p, 0.6875).srgb, hex([0, 0, 255]));

    // 6: HSV counter-clockwise, red (hue 0) to blue (hue 2/3), linear: hue = 2/3 f.
    check(p, at(6, 0.25), rgb(1.0, 1.0, 0.0)); // hue 1/6: yellow
    check(p, at(6, 0.5), rgb(0.0, 1.0, 0.0)); // hue 1/3: green
    // 7: HSV clockwise, red to blue the other way: hue = 1 - f/3; opacity 1 to 0.
    check(p, at(7, 0.25), [1.0, 0.0, 0.5, 0.75]); // hue 11/12
    check(p, at(7, 0.5), [1.0, 0.0, 1.0, 0.5]); // hue 5/6: magenta
    // The last stop is the last segment's right end.
    let last = *stops(p).last().unwrap();
    assert_eq!((last.pos, last.srgb, last.opacity), (1.0, hex([0, 0, 255]), 0.0));
}

#[test]
fn ultra_fractal_gradients() {
    let p = import("sample.ugr");
    assert_eq!(p.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(), vec!["sunset", "smooth-blues"]);
    let (sunset, blues) = (&p[0], &p[1]);
    assert_eq!(sunset.description, "Imported from sample.ugr (Ultra Fractal gradient, \"Sunset strip\").");
    assert_eq!((sunset.space, sunset.mode), (Space::Srgb, Mode::Repeat));

    // Colours are R + 256 G + 65536 B; index N sits at N / 400, index -50 at 350.
    assert_eq!(stop(sunset, 0.0).srgb, hex([0, 0, 128])); // 8388608 = 0x800000
    assert_eq!(stop(sunset, 0.25).srgb, hex([255, 0, 0])); // 255
    assert_eq!(stop(sunset, 0.625).srgb, hex([255, 255, 0])); // 65535
    assert_eq!(stop(sunset, 0.875).srgb, hex([255, 255, 255])); // 16777215
    // Opacity 255 at 0, 0 at 200 (position 0.5), and back up across the wrap.
    assert_eq!(stop(sunset, 0.5).opacity, 0.0);
    // At index 200 the colour is 2/3 of the way from red (100) to yellow (250).
    assert_eq!(stop(sunset, 0.5).srgb, hex([255, 170, 0]));
    // Index 50: half way navy to red, opacity 3/4.
    check(sunset, 50.0 / 400.0, [127.5 / 255.0, 0.0, 64.0 / 255.0, 0.75]);
    // Index 375: half way from white (350) to navy (400 = 0); opacity 175/200 of the way back up.
    check(sunset, 375.0 / 400.0, [127.5 / 255.0, 127.5 / 255.0, 191.5 / 255.0, 0.875]);
    // Closing stop equals index 0.
    let last = *stops(sunset).last().unwrap();
    assert_eq!((last.pos, last.srgb, last.opacity), (1.0, hex([0, 0, 128]), 1.0));

    // Smooth: exact at the control points (black 0, blue 100, cyan 300).
    check(blues, 0.0, rgb(0.0, 0.0, 0.0));
    check(blues, 0.25, rgb(0.0, 0.0, 1.0));
    check(blues, 0.75, rgb(0.0, 1.0, 1.0));
    // Index 200, half way from blue (100) to cyan (300) on the Hermite spline with
    // Catmull-Rom slopes m0 = (cyan - black) / 300 and m1 = (black(400) - blue) / 300:
    // G = 0.5 + 0.125 * 200 / 300 = 0.58333, B = 1 + 0.125 * 200 / 300 * 2 clamped to 1.
    check(blues, 0.5, rgb(0.0, 0.5 + 25.0 / 300.0, 1.0));
}

#[test]
fn kalles_fraktaler_palette() {
    let p = import("sample.kfp");
    let p = &p[0];
    assert_eq!(p.name, "sample");
    assert_eq!(p.description, "Imported from sample.kfp (Kalles Fraktaler palette, 4 key colours).");
    assert_eq!((p.space, p.mode, p.offset, p.density), (Space::Srgb, Mode::Repeat, 0.5, 1.0));
    // Keys are B,G,R triples: black, white, red (0,0,255), azure (255,128,0 -> 0,128,255).
    assert_eq!(stop(p, 0.0).srgb, hex([0, 0, 0]));
    assert_eq!(stop(p, 0.25).srgb, hex([255, 255, 255]));
    assert_eq!(stop(p, 0.5).srgb, hex([255, 0, 0]));
    assert_eq!(stop(p, 0.75).srgb, hex([0, 128, 255]));
    assert_eq!(stop(p, 1.0).srgb, hex([0, 0, 0]));
    // KF blends keys with w = sin((frac - 1/2) pi) / 2 + 1/2. Raw positions (offset 0):
    let raw = p.clone().adjusted(0.0, 1.0);
    let w = |frac: f64| ((frac - 0.5) * PI).sin() / 2.0 + 0.5;
    check(&raw, 0.125, rgb(0.5, 0.5, 0.5));
    let k = w(0.25);
    check(&raw, 0.3125, rgb(1.0, 1.0 - k, 1.0 - k));
    let k = w(0.75);
    check(&raw, 0.9375, rgb(0.0, (1.0 - k) * 128.0 / 255.0, 1.0 - k));
    // ColorOffset 512 of 1024: the palette starts half way round.
    check(p, 0.0, rgb(1.0, 0.0, 0.0));
}

/// HSV (hue in degrees) to RGB, worked out from the usual sector formulas.
fn hsv(h: f64, s: f64, v: f64) -> [f64; 4] {
    let h6 = h / 60.0;
    let i = h6.floor();
    let f = h6 - i;
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    let c = match i as i32 {
        0 => [v, t, p],
        1 => [q, v, p],
        2 => [p, v, t],
        3 => [p, q, v],
        4 => [t, p, v],
        _ => [v, p, q],
    };
    rgb(c[0], c[1], c[2])
}

#[test]
fn gmt_table_hsv_and_hard_edges() {
    let p = import("sample.cpt");
    let p = &p[0];
    assert_eq!(p.name, "sample");
    assert_eq!(p.description, "Imported from sample.cpt (GMT colour palette table, HSV).");
    assert_eq!((p.space, p.mode), (Space::Srgb, Mode::Clamp));
    // z from -100 to 100 maps to 0..1; slices break at 0.25, 0.5, 0.75.
    // Slice 1 in HSV: hue 0 to 120; at z = -75 the hue is 60.
    check(p, 0.125, hsv(60.0, 1.0, 1.0));
    check(p, 0.2, hsv(96.0, 1.0, 1.0));
    // Hard edge at z = -50: green, then dark blue.
    assert_eq!(stop(p, 0.25 - EDGE).srgb, hex([0, 255, 0]));
    assert_eq!(stop(p, 0.25).srgb, hex([0, 0, 128]));
    check(p, 0.375, hsv(240.0, 1.0, 0.75));
    // Continuous at z = 0 (blue both sides): one stop.
    assert_eq!(stop(p, 0.5).srgb, hex([0, 0, 255]));
    assert!(!stops(p).iter().any(|s| s.pos == 0.5 - EDGE));
    // Blue (240-1-1) to white (HSV 0, 0, 1) interpolated in HSV: at z = 25 hue 120, s 0.5.
    check(p, 0.625, hsv(120.0, 0.5, 1.0));
    // Hard edge at z = 50: white, then grey 0-0-0.5.
    assert_eq!(stop(p, 0.75 - EDGE).srgb, hex([255, 255, 255]));
    assert_eq!(stop(p, 0.75).srgb, hex([128, 128, 128]));
    // Grey to magenta in HSV: hue 0 -> 300 as written, s 0 -> 1, v 0.5 -> 1.
    check(p, 0.875, hsv(150.0, 0.5, 0.75));
    check(p, 1.0, hsv(300.0, 1.0, 1.0));
    // Clamp: beyond the ends hold the end colours (B and F lines are not used).
    check(p, 1.5, hsv(300.0, 1.0, 1.0));
    check(p, -0.5, rgb(1.0, 0.0, 0.0));
}

#[test]
fn imported_palettes_round_trip_through_toml() {
    for name in ["sample.map", "sample.ggr", "sample.ugr", "sample.kfp", "sample.cpt"] {
        for p in import(name) {
            let text = to_toml(&p);
            let back = parse(&format!("{}.toml", p.name), &text).unwrap_or_else(|e| panic!("{name}: {e}\n{text}"));
            assert_eq!(back, p, "{name}: {}", p.name);
        }
    }
}

#[test]
fn bad_files_name_file_line_and_column() {
    let dir = scratch("import-bad-files");
    let cases = [
        ("bad.map", "0 0 0\n1 x 2\n", ":2:3:"),
        ("bad.ggr", "GIMP Gradient\nName: x\n1\n0 0.5 1 0 0 0 1 1 1 1 1 9 0\n", ":4:25:"),
        ("bad.ugr", "g {\ngradient:\n  index=0 color=blue\n}\n", ":3:17:"),
        ("bad.kfp", "Iterations: 10\r\nColors: 1,2,3,4,5,600,\r\n", ":2:19:"),
        ("bad.cpt", "0 red 1 blue\n1 blue 2 0/0/300\n", ":2:14:"),
    ];
    for (file, text, at) in cases {
        let path = dir.join(file);
        std::fs::write(&path, text).unwrap();
        let e = import_file(&path).unwrap_err();
        assert!(matches!(e, ImportError::Invalid(_)), "{file}: {e:?}");
        let msg = e.to_string();
        assert!(msg.starts_with(&format!("{}{at} ", path.display())), "{file}: {msg}");
    }
    let txt = dir.join("palette.txt");
    std::fs::write(&txt, "0 0 0\n").unwrap();
    assert!(matches!(import_file(&txt), Err(ImportError::UnknownFormat { .. })));
    assert!(matches!(import_file(&dir.join("missing.ggr")), Err(ImportError::Io { .. })));
    let empty = dir.join("empty.ugr");
    std::fs::write(&empty, "; no gradients\n").unwrap();
    assert!(matches!(import_file(&empty), Err(ImportError::Empty { .. })));
    // Bytes that are not UTF-8 (a Latin-1 name) do not stop an import.
    let latin = dir.join("latin.ggr");
    std::fs::write(&latin, b"GIMP Gradient\nName: Caf\xe9\n1\n0 0.5 1 0 0 0 1 1 1 1 1 0 0\n").unwrap();
    assert_eq!(import_file(&latin).unwrap()[0].name, "latin");
}

#[test]
fn damaged_fixtures_never_panic() {
    // Every prefix of every fixture, and every fixture with one line removed, imports or
    // fails with an error; nothing panics.
    for name in ["sample.map", "sample.ggr", "sample.ugr", "sample.kfp", "sample.cpt"] {
        let text = std::fs::read_to_string(fixture(name)).unwrap();
        let format = Format::from_path(Path::new(name)).unwrap();
        for cut in (0..=text.len()).filter(|&i| text.is_char_boundary(i)) {
            let _ = import_text(format, name, &text[..cut]);
        }
        let lines: Vec<&str> = text.split_inclusive('\n').collect();
        for skip in 0..lines.len() {
            let damaged: String = lines.iter().enumerate().filter(|(i, _)| *i != skip).map(|(_, l)| *l).collect();
            let _ = import_text(format, name, &damaged);
        }
    }
}
