//! Colouring from raw data: recolouring reproduces renders byte for byte, the orbit
//! statistics colourings read are right, and the colouring commands refuse bad input
//! clearly.

use std::path::Path;
use std::process::{Command, Output};
use std::sync::atomic::AtomicBool;

use deepfield::coloring::{Histogram, Mask, MaskQuantity};
use deepfield::field::{self, ChannelSet, TrapPlane};
use deepfield::formula::end::INTERIOR;
use deepfield::palette::color::linear_to_srgb8 as srgb8;
use deepfield::render;

use super::util::{Lcg, scene, scratch};

fn deepfield(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_deepfield")).args(args).current_dir(dir).output().expect("run deepfield")
}

fn ok(o: &Output) {
    assert!(o.status.success(), "exit {:?}: {}", o.status.code(), String::from_utf8_lossy(&o.stderr));
}

/// Exit code 2 with `needle` in the message, no panic.
fn refused(o: &Output, needle: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    assert!(err.contains(needle), "expected `{needle}` in: {err}");
    assert!(!err.contains("panicked"), "{err}");
}

const VIEW: &str = "version = 1\n[view]\ncenter = [\"-0.7436\", \"0.1318\"]\nzoom = \"300\"\nwidth = 72\nheight = 54\n[iteration]\nmax = 600\n";

/// Render to PNG + EXR, then recolour the EXR with its stored scene: identical PNG bytes.
#[test]
fn recolour_reproduces_the_render_exactly() {
    let stacks = [
        (
            "stack",
            "[render]\naa = 2\n[[layer]]\nkind = \"smooth\"\npalette = \"sunset\"\ntransfer = \"sqrt\"\n[[layer]]\nkind = \"slope\"\nblend = \"soft-light\"\n[layer.mask]\nquantity = \"distance\"\nbelow = 4.0\nfeather = 2.0\n[[layer]]\nkind = \"boundary\"\nopacity = 0.5\n",
        ),
        (
            "histogram",
            "[[layer]]\nkind = \"histogram\"\npalette = \"magma\"\n[[layer]]\nkind = \"binary\"\nblend = \"overlay\"\nopacity = 0.3\n",
        ),
        (
            "traps",
            "[output]\nbits = 16\n[[layer]]\nkind = \"stripe\"\npalette = \"gold\"\n[[layer]]\nkind = \"trap\"\nshape = \"line\"\nblend = \"multiply\"\n[[layer]]\nkind = \"interior\"\npalette = \"ocean\"\n[[layer]]\nkind = \"bitmap\"\nimage = \"BITMAP\"\nsize = 0.1\ncenter = [-0.74, 0.13]\n",
        ),
        ("angle", "[[layer]]\nkind = \"angle\"\npalette = \"iq-rainbow\"\ndensity = 2.0\n"),
        (
            "ifs",
            "[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"ifs\"\nblend = \"screen\"\nfold_offset = [-0.5, -0.4, -1.3]\n",
        ),
    ];
    let bitmap = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bitmaps/star.png");
    for (name, layers) in stacks {
        let dir = scratch(&format!("recolour-{name}"));
        let text = format!("{VIEW}{}", layers.replace("BITMAP", &bitmap.display().to_string()));
        std::fs::write(dir.join("s.toml"), text).unwrap();
        ok(&deepfield(&["render", "s.toml", "-o", "direct.png", "--exr", "data.exr", "-q"], &dir));
        ok(&deepfield(&["recolor", "data.exr", "-o", "again.png"], &dir));
        let (a, b) = (std::fs::read(dir.join("direct.png")).unwrap(), std::fs::read(dir.join("again.png")).unwrap());
        assert!(a == b, "{name}: recolour differs from the render");
        // Recolouring with a scene file gives the bytes a render of that scene gives.
        let other = format!(
            "{VIEW}{}",
            "[[layer]]\nkind = \"smooth\"\npalette = \"ice\"\n[[layer]]\nkind = \"distance\"\nblend = \"multiply\"\n"
        );
        std::fs::write(dir.join("other.toml"), &other).unwrap();
        if !layers.contains("aa = 2") {
            ok(&deepfield(&["render", "other.toml", "-o", "other-direct.png", "-q"], &dir));
            ok(&deepfield(&["recolor", "data.exr", "--scene", "other.toml", "-o", "other-re.png"], &dir));
            let a = std::fs::read(dir.join("other-direct.png")).unwrap();
            assert!(a == std::fs::read(dir.join("other-re.png")).unwrap(), "{name}: --scene recolour differs");
        }
    }
}

/// `--layer` and `--palette` build the stack on the command line.
#[test]
fn recolour_layers_from_the_command_line() {
    let dir = scratch("recolour-flags");
    std::fs::write(dir.join("s.toml"), format!("{VIEW}[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"distance\"\n"))
        .unwrap();
    ok(&deepfield(&["render", "s.toml", "-o", "a.png", "--exr", "data.exr", "-q"], &dir));
    let want = format!(
        "{VIEW}[[layer]]\nkind = \"smooth\"\npalette = \"lava\"\ndensity = 0.02\n[[layer]]\nkind = \"slope\"\nblend = \"multiply\"\n[layer.mask]\nquantity = \"distance\"\nbelow = 5.0\n"
    );
    std::fs::write(dir.join("want.toml"), want).unwrap();
    ok(&deepfield(&["render", "want.toml", "-o", "want.png", "-q"], &dir));
    ok(&deepfield(
        &[
            "recolor",
            "data.exr",
            "--layer",
            "smooth:palette=fire,density=0.02",
            "--layer",
            "slope:blend=multiply,mask.quantity=distance,mask.below=5",
            "--palette",
            "lava",
            "-o",
            "got.png",
        ],
        &dir,
    ));
    assert!(std::fs::read(dir.join("want.png")).unwrap() == std::fs::read(dir.join("got.png")).unwrap());

    // Palette cycling: the same bytes as a render with the phase in the scene.
    std::fs::write(
        dir.join("cycled.toml"),
        format!("{VIEW}[render]\ncycle = 0.3\n[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"distance\"\n"),
    )
    .unwrap();
    ok(&deepfield(&["render", "cycled.toml", "-o", "cycled.png", "-q"], &dir));
    ok(&deepfield(&["recolor", "data.exr", "--cycle", "0.3", "-o", "cycled-re.png"], &dir));
    let cycled = std::fs::read(dir.join("cycled.png")).unwrap();
    assert!(cycled == std::fs::read(dir.join("cycled-re.png")).unwrap());
    assert!(cycled != std::fs::read(dir.join("a.png")).unwrap(), "cycling changed nothing");

    // Errors: unknown kind, unknown key, unknown palette, a layer the data cannot serve.
    refused(&deepfield(&["recolor", "data.exr", "--layer", "plasma"], &dir), "unknown layer kind `plasma`");
    refused(&deepfield(&["recolor", "data.exr", "--layer", "smooth:colour=red"], &dir), "colour");
    refused(
        &deepfield(&["recolor", "data.exr", "--palette", "no-such-palette"], &dir),
        "unknown palette `no-such-palette`",
    );
    refused(&deepfield(&["recolor", "data.exr", "--layer", "stripe"], &dir), "no Stripe data for trap 0");
    ok(&deepfield(&["render", "s.toml", "-o", "n.png", "--exr", "n.exr", "--channels", "N,NF", "-q"], &dir));
    refused(&deepfield(&["recolor", "n.exr", "--layer", "binary", "-o", "x.png"], &dir), "no T channel");
    std::fs::write(dir.join("big.toml"), VIEW.replace("width = 72", "width = 80")).unwrap();
    refused(&deepfield(&["recolor", "data.exr", "--scene", "big.toml", "-o", "x.png"], &dir), "holds 72 x 54 samples");
    // A file cut short is found out while the strips stream (after the header read
    // well): refused as bad input, and no PNG is left behind.
    let bytes = std::fs::read(dir.join("data.exr")).unwrap();
    std::fs::write(dir.join("cut.exr"), &bytes[..bytes.len() * 2 / 3]).unwrap();
    refused(&deepfield(&["recolor", "cut.exr", "-o", "x.png"], &dir), "cut.exr");
    assert!(!dir.join("x.png").exists());
}

/// Bad palette files are located; unknown palette and colouring names are listed.
#[test]
fn palette_and_colouring_errors_are_clear() {
    let dir = scratch("palette-errors");
    std::fs::write(
        dir.join("bad.toml"),
        "name = \"bad\"\n[[stop]]\npos = 0.0\ncolor = \"#000000\"\n[[stop]]\npos = 1.5\ncolor = \"#ffffff\"\n",
    )
    .unwrap();
    std::fs::write(dir.join("s.toml"), format!("{VIEW}[[layer]]\nkind = \"smooth\"\npalette = \"bad.toml\"\n"))
        .unwrap();
    refused(&deepfield(&["render", "s.toml", "-o", "o.png"], &dir), "bad.toml:5:1");
    std::fs::write(dir.join("t.toml"), format!("{VIEW}[[layer]]\nkind = \"smooth\"\npalette = \"nope\"\n")).unwrap();
    refused(&deepfield(&["render", "t.toml", "-o", "o.png"], &dir), "t.toml:11:11: unknown palette `nope`");
    std::fs::write(dir.join("u.toml"), format!("{VIEW}[[layer]]\nkind = \"plasma\"\n")).unwrap();
    refused(
        &deepfield(&["render", "u.toml", "-o", "o.png"], &dir),
        "u.toml:10:8: unknown layer kind `plasma`; expected one of \"smooth\", \"histogram\"",
    );
    std::fs::write(
        dir.join("v.toml"),
        format!("{VIEW}[[layer]]\nkind = \"smooth\"\n[layer.mask]\nquantity = \"hue\"\n"),
    )
    .unwrap();
    refused(&deepfield(&["render", "v.toml", "-o", "o.png"], &dir), "v.toml:12:12: unknown mask quantity `hue`");
    refused(&deepfield(&["sheet", "--colorings", "smooth,plasma", "-o", "o.png"], &dir), "unknown colouring `plasma`");
    refused(&deepfield(&["palettes", "show", "nope"], &dir), "unknown palette `nope`");
    assert!(!dir.join("o.png").exists());
}

/// A sheet has one cell per colouring and palette, in a grid.
#[test]
fn sheets_lay_out_every_cell() {
    let dir = scratch("sheet");
    std::fs::write(dir.join("s.toml"), VIEW).unwrap();
    let o = deepfield(
        &[
            "sheet",
            "s.toml",
            "--colorings",
            "smooth,histogram,slope",
            "--palettes",
            "fire,ice",
            "--scale-bar",
            "--marker",
            "-0.7436,0.1318",
            "-q",
            "-o",
            "sheet.png",
        ],
        &dir,
    );
    ok(&o);
    let img = image::open(dir.join("sheet.png")).unwrap();
    // 6 cells, 3 columns (ceil sqrt 6), 6-pixel gaps.
    assert_eq!((img.width(), img.height()), (3 * 72 + 4 * 6, 2 * 54 + 3 * 6));
    let o = deepfield(&["sheet", "--list"], &dir);
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("stripe"));
}

/// `palettes list` and `palettes show`.
#[test]
fn palette_commands() {
    let dir = scratch("palettes-cmd");
    let o = deepfield(&["palettes", "list"], &dir);
    ok(&o);
    let listed = String::from_utf8_lossy(&o.stdout).lines().count();
    assert!(listed >= 24, "{listed} palettes");
    ok(&deepfield(&["palettes", "show", "sunset", "--size", "100x10"], &dir));
    let img = image::open(dir.join("sunset.png")).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (100, 10));
    // The strip's left end is the first stop's colour.
    assert_eq!(img.get_pixel(0, 5).0, [0x1b, 0x0b, 0x3a]);

    // Import: a GIMP gradient to our format, then used by a scene; a .ugr holds several.
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/palettes");
    let ggr = fixtures.join("sample.ggr");
    ok(&deepfield(&["palettes", "import", ggr.to_str().unwrap(), "-o", "gimp.toml"], &dir));
    std::fs::write(dir.join("s.toml"), format!("{VIEW}[[layer]]\nkind = \"smooth\"\npalette = \"gimp.toml\"\n"))
        .unwrap();
    ok(&deepfield(&["render", "s.toml", "-o", "s.png", "-q"], &dir));
    let ugr = fixtures.join("sample.ugr");
    ok(&deepfield(&["palettes", "import", ugr.to_str().unwrap(), "-o", "uf"], &dir));
    assert_eq!(std::fs::read_dir(dir.join("uf")).unwrap().count(), 2);
    ok(&deepfield(&["palettes", "show", ugr.to_str().unwrap(), "-o", "uf.png"], &dir));
    std::fs::write(dir.join("bad.map"), "0 0 0\n255 x 0\n").unwrap();
    refused(&deepfield(&["palettes", "import", "bad.map"], &dir), "bad.map:2:");
}

/// The stripe average against a direct f64 computation written here from its definition
/// (terms 0.5 + 0.5 sin(s arg z_k) for k = 1..n, smoothed across bands with NF).
#[test]
fn stripe_average_matches_its_definition() {
    let s = scene(&format!("{VIEW}[[layer]]\nkind = \"stripe\"\nfrequency = 3\n"));
    let params = render::field_params(&s, ChannelSet::default());
    let strip = field::compute_strip(&params, 0..54, &AtomicBool::new(false)).unwrap();
    let TrapPlane::Stripe { value, .. } = &strip.planes.traps[0] else { panic!("stripe plane") };
    let r = s.escape_radius;
    let mut rng = Lcg(7);
    let mut checked = 0;
    for _ in 0..300 {
        let (i, j) = (rng.below(72), rng.below(54));
        let c = params.grid.point(i, j);
        let (mut z, mut terms) = ([0.0f64, 0.0], Vec::new());
        let mut n = 0;
        while n < 600 {
            // The kernel's own rounding (fused multiply-adds): orbits near the set are
            // chaotic, and the statistic is what is tested here, not the orbit.
            let (x, y) = (z[0], z[1]);
            z = [x.mul_add(x, -(y * y)) + c[0], (x + x).mul_add(y, c[1])];
            n += 1;
            terms.push(0.5 + 0.5 * (3.0 * z[1].atan2(z[0])).sin());
            if z[0] * z[0] + z[1] * z[1] > r * r {
                break;
            }
        }
        let k = (j * 72 + i) as usize;
        if strip.planes.n[k] == INTERIOR {
            continue;
        }
        let full = terms.iter().sum::<f64>() / terms.len() as f64;
        let prev = terms[..terms.len() - 1].iter().sum::<f64>() / (terms.len() - 1) as f64;
        let nf = 1.0 - ((0.5 * (z[0] * z[0] + z[1] * z[1]).ln()) / r.ln()).log2();
        let want = prev + (full - prev) * nf;
        assert!((value[k] as f64 - want).abs() < 1e-5, "({i},{j}): {} vs {want}", value[k]);
        checked += 1;
    }
    assert!(checked > 100);
}

/// The perturbation engine's stripe plane agrees with the direct kernel's on a shallow view.
#[test]
fn stripe_average_at_depth_agrees_with_direct() {
    let text = format!("{VIEW}[[layer]]\nkind = \"stripe\"\n");
    let direct = scene(&text);
    let deep = scene(&format!("{}[render]\nengine = \"perturb-f64\"\n", text));
    let plane = |s: &deepfield::scene::Scene| {
        let plan = deepfield::render::engine::plan(s).unwrap();
        let (params, _) =
            render::prepare_field(s, &plan, render::Options::default(), &AtomicBool::new(false), &|_| {}).unwrap();
        let strip = field::compute_strip(&params, 0..54, &AtomicBool::new(false)).unwrap();
        let TrapPlane::Stripe { value, .. } = &strip.planes.traps[0] else { panic!("stripe plane") };
        (strip.planes.n.clone(), value.clone())
    };
    let (na, a) = plane(&direct);
    let (nb, b) = plane(&deep);
    let same_n = na.iter().zip(&nb).filter(|(x, y)| x == y).count();
    assert!(same_n * 100 >= na.len() * 99, "{same_n} of {} N agree", na.len());
    let close =
        a.iter().zip(&b).zip(na.iter().zip(&nb)).filter(|((x, y), (m, n))| m == n && (*x - *y).abs() < 1e-3).count();
    assert!(close * 100 >= same_n * 99, "{close} of {same_n} stripe values agree");
}

/// The IFS layer's plane is the CPU density function at each sample's point (the shader is
/// checked against the same function in gpu.rs), and it does not hold up the vectorised
/// kernel: N is what it is without the layer.
#[test]
fn ifs_plane_is_the_density_at_each_point() {
    let with = scene(&format!("{VIEW}[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"ifs\"\nscale = 0.7\n"));
    let without = scene(&format!("{VIEW}[[layer]]\nkind = \"smooth\"\n"));
    let params = render::field_params(&with, ChannelSet::default());
    let strip = field::compute_strip(&params, 0..54, &AtomicBool::new(false)).unwrap();
    let TrapPlane::Density(d) = &strip.planes.traps[0] else { panic!("IFS plane") };
    let deepfield::trap::Trap::Ifs(p) = &with.traps[0] else { panic!("IFS trap") };
    for j in 0..54 {
        for i in 0..72 {
            let pt = params.grid.point(i, j);
            assert_eq!(d[(j * 72 + i) as usize], deepfield::trap::ifs::density(p, pt[0] as f32, pt[1] as f32));
        }
    }
    assert!(d.iter().any(|&v| v > 0.05), "the field is not empty here");
    let plain =
        field::compute_strip(&render::field_params(&without, ChannelSet::default()), 0..54, &AtomicBool::new(false))
            .unwrap();
    assert_eq!(plain.planes.n, strip.planes.n);
}

/// A layer that colours from a trap plane of another kind (planes of a scene whose trap 0
/// is a stripe, recoloured with a distance-trap layer) is refused, naming the layer and the
/// trap, instead of painting nothing.
#[test]
fn a_trap_plane_of_the_wrong_kind_is_refused() {
    let stripes = scene(&format!("{VIEW}[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"stripe\"\n"));
    let traps = scene(&format!("{VIEW}[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"trap\"\nshape = \"circle\"\n"));
    let params = render::field_params(&stripes, ChannelSet::default());
    let strip = field::compute_strip(&params, 0..54, &AtomicBool::new(false)).unwrap();
    let planes = [strip.planes];
    assert!(render::recolor(&stripes.stack, &planes, 1).is_ok());
    let e = render::recolor(&traps.stack, &planes, 1).expect_err("a stripe plane coloured as distances");
    assert_eq!((e.layer, e.trap), (2, 0));
    assert_eq!(
        e.to_string(),
        "layer 2 colours from trap 0's distance data, but the planes hold stripe data for trap 0"
    );
    let e = render::recolor_rgb8(&traps.stack, &planes, 1).expect_err("the same, as bytes");
    assert_eq!((e.layer, e.trap), (2, 0));
}

/// Histogram positions are uniform over the exterior samples: the fraction below q is q.
#[test]
fn histogram_equalises() {
    let s = scene(&format!("{VIEW}[[layer]]\nkind = \"histogram\"\n"));
    let params = render::field_params(&s, ChannelSet::default());
    let planes = field::compute_strip(&params, 0..54, &AtomicBool::new(false)).unwrap().planes;
    let h = Histogram::build([&planes]);
    let pos: Vec<f64> =
        (0..planes.len()).filter(|&k| planes.n[k] != INTERIOR).map(|k| h.position(planes.n[k], planes.nf[k])).collect();
    for q in [0.1, 0.25, 0.5, 0.75, 0.9] {
        let below = pos.iter().filter(|&&p| p < q).count() as f64 / pos.len() as f64;
        assert!((below - q).abs() < 0.08, "fraction below {q}: {below}");
    }
}

/// A masked layer leaves samples outside its range as the layers below made them.
#[test]
fn masks_confine_a_layer() {
    let base = format!("{VIEW}[[layer]]\nkind = \"smooth\"\npalette = \"ice\"\n");
    let masked = format!("{base}[[layer]]\nkind = \"binary\"\n[layer.mask]\nquantity = \"iteration\"\nabove = 200.0\n");
    let (a, b) = (scene(&base), scene(&masked));
    let params = render::field_params(&b, ChannelSet::default());
    let planes = field::compute_strip(&params, 0..54, &AtomicBool::new(false)).unwrap().planes;
    let ca = a.stack.composite(&planes, 1, &Default::default());
    let cb = b.stack.composite(&planes, 1, &Default::default());
    let m = Mask { quantity: MaskQuantity::Iteration, above: 200.0, below: f64::INFINITY, feather: 0.0, invert: false };
    let (mut outside, mut changed) = (0, 0);
    for k in 0..planes.len() {
        let nu = if planes.n[k] == INTERIOR { f64::INFINITY } else { planes.n[k] as f64 + planes.nf[k] as f64 };
        if m.weight(nu) == 0.0 {
            outside += 1;
            // The two-layer stack blends in 8-bit sRGB: unchanged means the same 8-bit colour.
            assert_eq!(ca[k].map(srgb8), cb[k].map(srgb8), "sample {k} outside the mask changed");
        } else if ca[k].map(srgb8) != cb[k].map(srgb8) {
            changed += 1;
        }
    }
    assert!(outside > 100 && changed > 100, "{outside} outside, {changed} changed inside");
}

/// An EXR whose 1.6 KB claim gigabytes of pixels (found by fuzzing the EXR reader: it
/// exhausted memory) is refused before anything is allocated, with the path and why.
#[test]
fn exr_headers_claiming_more_than_the_file_holds_are_refused() {
    let dir = scratch("coloring-exr-claims");
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/fuzz/exr-claims-gigabytes.exr");
    let Err(e) = deepfield::io::read_exr_planes(&fixture, 16) else { panic!("a lying header was read") };
    assert!(e.to_string().contains("more than its"), "{e}");
    let o = deepfield(&["recolor", fixture.to_str().unwrap(), "-o", "x.png"], &dir);
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!dir.join("x.png").exists());
}
