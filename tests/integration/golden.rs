//! Golden images, one per colouring mode, rendered through the library's render path.
//!
//! Tolerance: at most 0.5% of channel values may differ from the golden image by more than
//! 2 levels (of 255), and none by more than 24. Everything is computed in IEEE arithmetic
//! with the same operations on every machine; the slack only covers libm differences in
//! ln/pow/atan2 between platforms. A test that compares several images compares them all
//! before failing: each image outside the tolerance has its actual render written to the
//! scratch folder, and the one failure lists them all with their paths.
//! `DEEPFIELD_BLESS=1 cargo test` regenerates goldens.

use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::atomic::AtomicBool;

use deepfield::field::{ChannelSet, TrapPlane};
use deepfield::io::PngEncoder;
use deepfield::render::{self, Options};

use super::util::{scene, scratch};

/// Renders a scene to 8-bit RGB bytes through the real render path.
pub fn render_rgb8(text: &str, threads: usize) -> (u32, u32, Vec<u8>) {
    let s = scene(text);
    let enc = PngEncoder::new(8);
    let out = Mutex::new(Vec::new());
    let cancel = AtomicBool::new(false);
    let prepare = |strip: &render::RenderedStrip| Ok(enc.encode(&strip.rgb));
    let plan = render::engine::plan(&s).expect("an engine");
    render::render(
        &s,
        &plan,
        Options { threads, exr_channels: ChannelSet::default(), ..Options::default() },
        &cancel,
        &|_| {},
        &prepare,
        |_, bytes| {
            out.lock().unwrap().extend_from_slice(&bytes);
            Ok(())
        },
    )
    .expect("render");
    (s.width, s.height, out.into_inner().unwrap())
}

/// Renders `text` and compares it with the golden image `name`; on a mismatch writes the
/// actual image to the scratch folder and returns what differs (None: within tolerance,
/// or blessed).
fn mismatch(name: &str, text: &str) -> Option<String> {
    let (w, h, actual) = render_rgb8(text, 2);
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden").join(format!("{name}.png"));
    if std::env::var_os("DEEPFIELD_BLESS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        image::save_buffer(&path, &actual, w, h, image::ColorType::Rgb8).unwrap();
        return None;
    }
    let expected = match image::open(&path) {
        Ok(image) => image.to_rgb8(),
        Err(e) => {
            return Some(format!("golden {} missing ({e}); run with DEEPFIELD_BLESS=1 to create it", path.display()));
        }
    };
    let save_actual = || {
        let dir = scratch(&format!("golden-{name}"));
        let out = dir.join(format!("{name}.actual.png"));
        image::save_buffer(&out, &actual, w, h, image::ColorType::Rgb8).unwrap();
        out
    };
    if expected.dimensions() != (w, h) {
        let out = save_actual();
        return Some(format!(
            "{name}: size {w}x{h}, golden {}x{}; actual image: {}",
            expected.width(),
            expected.height(),
            out.display()
        ));
    }
    let diffs: Vec<u8> = expected.as_raw().iter().zip(&actual).map(|(a, b)| a.abs_diff(*b)).collect();
    let over = diffs.iter().filter(|&&d| d > 2).count();
    let worst = diffs.iter().copied().max().unwrap_or(0);
    if over * 200 > diffs.len() || worst > 24 {
        let out = save_actual();
        return Some(format!(
            "{name}: {over} values differ by more than 2 (worst {worst}); actual image: {}",
            out.display()
        ));
    }
    None
}

/// Compares every `(name, scene text)` case, then fails once, listing each image outside
/// the tolerance (so one run shows every broken golden, not only the first).
fn goldens<N: AsRef<str>, T: AsRef<str>>(cases: impl IntoIterator<Item = (N, T)>) {
    let mut count = 0;
    let mut failures = Vec::new();
    for (name, text) in cases {
        count += 1;
        failures.extend(mismatch(name.as_ref(), text.as_ref()));
    }
    assert!(failures.is_empty(), "{} of {count} golden images differ:\n{}", failures.len(), failures.join("\n"));
}

/// One golden image.
fn golden(name: &str, text: &str) {
    goldens([(name, text)]);
}

const VIEW: &str = "[view]\ncenter = [\"-0.75\", \"0\"]\nzoom = \"1.5\"\nwidth = 96\nheight = 72\n";

#[test]
fn golden_smooth_iteration() {
    golden(
        "smooth",
        &format!("version = 1\n{VIEW}[[layer]]\nkind = \"smooth\"\npalette = \"classic\"\ndensity = 0.1\n"),
    );
}

#[test]
fn golden_smooth_supersampled() {
    golden(
        "smooth-aa3",
        &format!(
            "version = 1\n{VIEW}[render]\naa = 3\n[[layer]]\nkind = \"smooth\"\npalette = \"fire\"\ntransfer = \"sqrt\"\ndensity = 0.3\n"
        ),
    );
}

#[test]
fn golden_soft_distance() {
    golden(
        "distance",
        "version = 1\n[formula]\nkind = \"julia\"\nc = [\"0\", \"1\"]\n[view]\ncenter = [\"0\", \"0\"]\nzoom = \"1.4\"\nwidth = 80\nheight = 80\n[[layer]]\nkind = \"distance\"\nk = 0.5\n",
    );
}

#[test]
fn golden_boundary_over_smooth_multiply() {
    golden(
        "boundary-multiply",
        &format!(
            "version = 1\n{VIEW}[[layer]]\nkind = \"smooth\"\npalette = \"ocean\"\n[[layer]]\nkind = \"boundary\"\nwidth = 1.5\ncolor = \"#202020\"\nblend = \"multiply\"\nopacity = 0.9\n"
        ),
    );
}

#[test]
fn golden_geometric_trap() {
    golden(
        "trap-cross",
        &format!(
            "version = 1\n{VIEW}[[layer]]\nkind = \"trap\"\nshape = \"cross\"\ncenter = [0.0, 0.0]\nangle = 30\npalette = \"electric\"\ndensity = 2.0\n"
        ),
    );
}

#[test]
fn golden_bitmap_trap() {
    golden(
        "bitmap-trap",
        "version = 1\n[formula]\nkind = \"julia\"\nc = [\"-0.8\", \"0.156\"]\n[view]\ncenter = [\"0\", \"0\"]\nzoom = \"1.3\"\nwidth = 96\nheight = 72\n[[layer]]\nkind = \"distance\"\n[[layer]]\nkind = \"bitmap\"\nimage = \"scenes/bitmaps/star.png\"\ncenter = [0.0, 0.3]\nsize = 0.5\nthreshold = 0.5\n",
    );
}

/// The bitmap trap takes the exact texel colour of the first sample above the threshold:
/// with `tests/fixtures/trap.png` (left half opaque red, right half transparent) covering
/// [-2, 2]^2, every Mandelbrot pixel whose c (= z_1, the first sample) lies well inside the
/// left half is exactly opaque red, and no pixel takes any colour but red or nothing.
#[test]
fn bitmap_trap_samples_the_shipped_bitmap_exactly() {
    let text = "version = 1\n[view]\ncenter = [\"0\", \"0\"]\nradius = \"2\"\nwidth = 64\nheight = 64\n[[layer]]\nkind = \"bitmap\"\nimage = \"tests/fixtures/trap.png\"\nsize = 4.0\n";
    let s = scene(text);
    let params = render::field_params(&s, ChannelSet::default());
    let strip = deepfield::field::compute_strip(&params, 0..64, &AtomicBool::new(false)).unwrap();
    let TrapPlane::Color(c) = &strip.planes.traps[0] else { panic!("bitmap trap plane") };
    let red = [1.0f32, 0.0, 0.0, 1.0];
    for j in 0..64u32 {
        for i in 0..64u32 {
            let x = params.grid.point(i, j)[0];
            let got = c[(j * 64 + i) as usize];
            if x < -0.2 {
                assert_eq!(got, red, "pixel ({i},{j}) at x = {x}");
            }
            assert!(got == red || got[3] == 0.0 || got[1] == 0.0 && got[2] == 0.0, "pixel ({i},{j}): {got:?}");
        }
    }
}

/// Each colouring algorithm of the layer stack, one golden each.
#[test]
fn golden_colourings() {
    let cases: &[(&str, &str)] = &[
        ("histogram", "kind = \"histogram\"\npalette = \"sunset\"\n"),
        ("smooth-cbrt", "kind = \"smooth\"\npalette = \"iq-rainbow\"\ntransfer = \"cbrt\"\ndensity = 0.5\n"),
        ("smooth-loglog", "kind = \"smooth\"\npalette = \"aurora\"\ntransfer = \"log-log\"\ndensity = 2.0\n"),
        ("distance-linear", "kind = \"distance\"\nstyle = \"linear\"\ndensity = 0.1\npalette = \"ice\"\n"),
        ("distance-log", "kind = \"distance\"\nstyle = \"log\"\ndensity = 0.4\npalette = \"magma\"\n"),
        ("slope", "kind = \"slope\"\nangle = 30\nheight = 1.5\nstrength = 0.8\n"),
        ("binary", "kind = \"binary\"\ncolors = [\"#f0e0c0\", \"#302010\"]\n"),
        ("angle", "kind = \"angle\"\npalette = \"rainbow\"\n"),
        ("stripe", "kind = \"stripe\"\nfrequency = 4\npalette = \"gold\"\ndensity = 1.5\n"),
        (
            "interior-trap",
            "kind = \"interior\"\npalette = \"emerald\"\nshape = \"circle\"\nradius = 0.3\ndensity = 3.0\n",
        ),
        ("ifs", "kind = \"ifs\"\npalette = \"electric\"\nscale = 0.8\nslice = 0.2\n"),
    ];
    goldens(cases.iter().map(|(name, layer)| {
        (format!("coloring-{name}"), format!("version = 1\n{VIEW}[iteration]\nmax = 300\n[[layer]]\n{layer}"))
    }));
}

/// A layer mask: slope lighting only within 3 pixels of the set, over smooth iteration.
#[test]
fn golden_mask() {
    golden(
        "mask-slope-near-boundary",
        &format!(
            "version = 1\n{VIEW}[[layer]]\nkind = \"smooth\"\npalette = \"desert\"\n[[layer]]\nkind = \"slope\"\nblend = \"multiply\"\n[layer.mask]\nquantity = \"distance\"\nbelow = 3.0\nfeather = 2.0\n"
        ),
    );
}

/// The animated bitmap trap of Inigo Quilez's "Bitmap Orbit Traps": frame 1 of a 2-frame sheet (the star bitmap cut in two).
#[test]
fn golden_sprite_frame() {
    golden(
        "bitmap-frame",
        "version = 1\n[formula]\nkind = \"julia\"\nc = [\"-0.8\", \"0.156\"]\n[view]\ncenter = [\"0\", \"0\"]\nzoom = \"1.3\"\nwidth = 96\nheight = 72\n[[layer]]\nkind = \"distance\"\n[[layer]]\nkind = \"bitmap\"\nimage = \"scenes/bitmaps/star.png\"\ncenter = [0.0, 0.3]\nsize = 0.5\nthreshold = 0.5\nframes = 2\nframe = 1\n",
    );
}

/// Every blend mode: a soft-distance layer at 80% over smooth iteration.
#[test]
fn golden_blend_modes() {
    let modes = [
        "normal",
        "multiply",
        "screen",
        "overlay",
        "darken",
        "lighten",
        "difference",
        "soft-light",
        "hard-light",
        "color-dodge",
        "color-burn",
        "exclusion",
        "plus",
    ];
    goldens(modes.map(|mode| {
        (
            format!("blend-{mode}"),
            format!(
                "version = 1\n{VIEW}[[layer]]\nkind = \"smooth\"\npalette = \"twilight\"\n[[layer]]\nkind = \"distance\"\nk = 0.3\npalette = \"copper\"\nblend = \"{mode}\"\nopacity = 0.8\n"
            ),
        )
    }));
}
