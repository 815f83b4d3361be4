//! Work units: `render --tile K/N` run as separate processes (as a Slurm job array, a
//! Kubernetes Indexed Job or GNU parallel would run them) and `deepfield assemble` give the
//! bytes of the same render done in one piece, shallow (supersampled) and deep; assembling
//! refuses incomplete, repeated or mixed sets.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use super::util::scratch;

fn deepfield(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_deepfield")).args(args).current_dir(dir).output().expect("run deepfield")
}

fn ok(o: Output) -> Output {
    assert!(o.status.success(), "exit {:?}: {}", o.status.code(), String::from_utf8_lossy(&o.stderr));
    o
}

/// Renders `scene` whole and as `n` units (in parallel processes), assembles, and compares.
fn units_assemble_to_the_whole(name: &str, scene: &str, extra: &[&str], n: u32) -> PathBuf {
    let dir = scratch(&format!("units-{name}"));
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let mut args = vec!["render", "scene.toml", "-o", "whole.png"];
    args.extend_from_slice(extra);
    ok(deepfield(&args, &dir));
    let children: Vec<_> = (0..n)
        .map(|k| {
            let (tile, out) = (format!("{k}/{n}"), format!("unit-{k}.png"));
            let mut args = vec!["render", "scene.toml", "--tile", &tile, "-o", &out, "--threads", "1"];
            args.extend_from_slice(extra);
            Command::new(env!("CARGO_BIN_EXE_deepfield")).args(&args).current_dir(&dir).spawn().unwrap()
        })
        .collect();
    for c in children {
        let o = c.wait_with_output().unwrap();
        assert!(o.status.success(), "a unit failed");
    }
    // Given out of order: assemble sorts them.
    let mut args = vec!["assemble".to_string(), "-o".into(), "assembled.png".into()];
    args.extend((0..n).rev().map(|k| format!("unit-{k}.png")));
    let args: Vec<&str> = args.iter().map(|s| s.as_str()).collect();
    ok(deepfield(&args, &dir));
    let (a, b) = (std::fs::read(dir.join("whole.png")).unwrap(), std::fs::read(dir.join("assembled.png")).unwrap());
    assert!(a == b, "{name}: the assembled PNG differs from the whole render ({} vs {} bytes)", b.len(), a.len());
    dir
}

#[test]
fn shallow_supersampled_units_assemble_to_the_whole_render() {
    let scene = "version = 1\n[view]\ncenter = [\"-0.745\", \"0.112\"]\nzoom = \"300\"\nwidth = 97\nheight = 61\n[render]\naa = 2\n[iteration]\nmax = 800\n[[layer]]\nkind = \"smooth\"\npalette = \"classic\"\n[[layer]]\nkind = \"distance\"\nblend = \"multiply\"\n";
    units_assemble_to_the_whole("shallow", scene, &[], 4);
    // A 16-bit PNG too.
    units_assemble_to_the_whole("shallow-16", scene, &["--bits", "16"], 3);
}

#[test]
fn deep_units_assemble_to_the_whole_render() {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/julia-deep-e310.toml")).unwrap();
    units_assemble_to_the_whole("deep", &text, &["--size", "80x45"], 5);
}

#[test]
fn incomplete_repeated_or_mixed_units_are_refused() {
    let scene = "version = 1\n[view]\nwidth = 40\nheight = 30\n[iteration]\nmax = 200\n";
    let dir = units_assemble_to_the_whole("refusals", scene, &[], 3);
    let other = "version = 1\n[view]\nwidth = 40\nheight = 30\n[iteration]\nmax = 201\n";
    std::fs::write(dir.join("other.toml"), other).unwrap();
    ok(deepfield(&["render", "other.toml", "--tile", "2/3", "-o", "other-2.png"], &dir));
    for (units, needle) in [
        (&["unit-0.png", "unit-1.png"][..], "unit 2 of 3 is missing"),
        (&["unit-0.png", "unit-1.png", "unit-1.png", "unit-2.png"][..], "given twice"),
        (&["unit-0.png", "unit-1.png", "other-2.png"][..], "another render"),
        (&["unit-0.png", "unit-1.png", "whole.png"][..], "not a work unit"),
    ] {
        let mut args = vec!["assemble", "-o", "bad.png"];
        args.extend_from_slice(units);
        let o = deepfield(&args, &dir);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(needle), "expected `{needle}`: {err}");
        assert!(!dir.join("bad.png").exists());
    }
    let o = deepfield(&["render", "scene.toml", "--tile", "3/3", "-o", "x.png"], &dir);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("0 <= K < N"));
}

/// Reference files: computed once, read by a render and by every work unit, the bytes are
/// those of computing in place (Mandelbrot at 1e321, the same with its orbit packed after
/// 1000 iterations, and a Julia set at 1e310, two orbits); a file for another view, a
/// damaged file, and a file given to a shallow scene are refused.
#[test]
fn reference_files_serve_renders_and_units_byte_for_byte() {
    let mut dirs = Vec::new();
    let views = [
        ("liiiines.toml", "48x36", None),
        ("liiiines.toml", "48x36", Some("1000")),
        ("julia-deep-e310.toml", "40x30", None),
    ];
    for (name, scene, dense) in views {
        let dir = scratch(&format!("units-reference-{name}-{}", dense.unwrap_or("dense")));
        let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)).unwrap();
        std::fs::write(dir.join("scene.toml"), &text).unwrap();
        let size = ["--size", scene];
        let packed: Vec<&str> = dense.map_or(vec![], |n| vec!["--dense-orbit", n]);
        ok(deepfield(&[&["reference", "scene.toml", "-o", "scene.dfr"][..], &size, &packed].concat(), &dir));
        ok(deepfield(&[&["render", "scene.toml", "-o", "computed.png"][..], &size, &packed].concat(), &dir));
        ok(deepfield(
            &[&["render", "scene.toml", "--reference", "scene.dfr", "-o", "read.png"][..], &size].concat(),
            &dir,
        ));
        let same = |a: &str, b: &str| std::fs::read(dir.join(a)).unwrap() == std::fs::read(dir.join(b)).unwrap();
        assert!(same("computed.png", "read.png"), "{name}: the render from the file differs");
        for k in 0..3 {
            let (tile, out) = (format!("{k}/3"), format!("unit-{k}.png"));
            let args = ["render", "scene.toml", "--reference", "scene.dfr", "--tile", &tile, "-o", &out];
            ok(deepfield(&[&args[..], &size].concat(), &dir));
        }
        ok(deepfield(&["assemble", "unit-0.png", "unit-1.png", "unit-2.png", "-o", "assembled.png"], &dir));
        assert!(same("computed.png", "assembled.png"), "{name}: units from the file differ");
        dirs.push(dir);
    }
    let bytes = |d: &std::path::PathBuf| std::fs::metadata(d.join("scene.dfr")).unwrap().len();
    assert!(bytes(&dirs[1]) * 3 < bytes(&dirs[0]), "the packed orbit's file is a fraction of the dense one's");
    let dir = &dirs[0];
    let refused = |args: &[&str], needle: &str| {
        let o = deepfield(args, dir);
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(needle), "expected `{needle}`: {err}");
    };
    refused(
        &["render", "scene.toml", "--reference", "scene.dfr", "--max-iter", "12000", "-o", "x.png"],
        "its max_iter is 12500, the scene's 12000",
    );
    refused(&["render", "scene.toml", "--reference", "scene.dfr", "--zoom", "1e330", "-o", "x.png"], "bits");
    let mut bytes = std::fs::read(dir.join("scene.dfr")).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 1;
    std::fs::write(dir.join("damaged.dfr"), &bytes).unwrap();
    refused(&["render", "scene.toml", "--reference", "damaged.dfr", "-o", "x.png"], "checksum");
    std::fs::write(dir.join("cut.dfr"), &bytes[..mid]).unwrap();
    refused(&["render", "scene.toml", "--reference", "cut.dfr", "-o", "x.png"], "not a deepfield reference file");
    refused(&["render", "--reference", "scene.dfr", "-o", "x.png"], "uses no reference orbit");
    refused(&["reference", "-o", "x.dfr"], "nothing to write");
    assert!(!dir.join("x.png").exists() && !dir.join("x.dfr").exists());
}

/// A zoom-out sequence: keyframes from the outermost (direct f64 at zoom 3e6) to the
/// scene's own view (1e321), every perturbing one from the deepest frame's reference
/// orbits: the deepest keyframe is `render --exr` byte for byte, a shallower one is
/// `render --exr --reference` of its zoom byte for byte, and `--units` renders a subset.
#[test]
fn zoom_sequences_share_the_deepest_reference() {
    let dir = scratch("units-zoom");
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/liiiines.toml")).unwrap();
    std::fs::write(dir.join("scene.toml"), &text).unwrap();
    let size = ["--size", "32x24"];
    let zoom = ["zoom", "scene.toml", "--frames", "8", "--factor", "1e45", "-o", "frames", "--stats", "-q"];
    let o = ok(deepfield(&[&zoom[..], &size].concat(), &dir));
    let stats = String::from_utf8_lossy(&o.stdout);
    assert!(stats.contains("keyframes   8 of 8") && stats.contains("once"), "{stats}");
    let names: Vec<String> = (0..8).map(|k| format!("frames/{k:05}.exr")).collect();
    for n in &names {
        assert!(dir.join(n).is_file(), "{n} missing");
    }
    ok(deepfield(&[&["render", "scene.toml", "--exr", "deep.exr", "-o", "deep.png"][..], &size].concat(), &dir));
    let same = |a: &str, b: &str| std::fs::read(dir.join(a)).unwrap() == std::fs::read(dir.join(b)).unwrap();
    assert!(same("frames/00007.exr", "deep.exr"), "the deepest keyframe differs from render --exr");
    // Keyframe 5 is two factors out: zoom 3.16254e321 / 1e90.
    ok(deepfield(&[&["reference", "scene.toml", "-o", "deep.dfr"][..], &size].concat(), &dir));
    let z5 = format!("316254{}", "0".repeat(226));
    let render5 =
        ["render", "scene.toml", "--zoom", &z5, "--reference", "deep.dfr", "--exr", "five.exr", "-o", "five.png"];
    ok(deepfield(&[&render5[..], &size].concat(), &dir));
    assert!(same("frames/00005.exr", "five.exr"), "keyframe 5 differs from render --reference at its zoom");
    let unit = ["zoom", "scene.toml", "--frames", "8", "--factor", "1e45", "--units", "2..4", "-o", "unit"];
    let o = ok(deepfield(&[&unit[..], &size].concat(), &dir));
    // Progress gives each keyframe's zoom in short (3.16254e321 / 1e45^5), not its 97 digits.
    let progress = String::from_utf8_lossy(&o.stderr);
    assert!(progress.contains("keyframe 2 of 8: zoom 3.163e96 ("), "{progress}");
    let mut written: Vec<String> = std::fs::read_dir(dir.join("unit"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    written.sort();
    assert_eq!(written, ["00002.exr", "00003.exr"]);
    assert!(same("unit/00003.exr", "frames/00003.exr"));
}

/// `deepfield frames`: the last frame of a zoom in is the deepest keyframe recoloured, byte
/// for byte; frames rendered as two work units are the frames rendered at once; with
/// `--video` the frames go to ffmpeg's standard input as raw RGB (a stand-in ffmpeg on
/// the PATH records what it is given), and without ffmpeg the run is refused, leaving no
/// file.
#[test]
fn frames_come_from_the_keyframes() {
    let dir = scratch("units-frames");
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/seahorse-valley.toml")).unwrap();
    std::fs::write(dir.join("scene.toml"), &text).unwrap();
    ok(deepfield(&["zoom", "scene.toml", "--size", "48x32", "--frames", "4", "-o", "keys", "-q"], &dir));
    ok(deepfield(&["frames", "keys", "--fps", "5", "-o", "all", "-q"], &dir));
    let mut names: Vec<String> =
        std::fs::read_dir(dir.join("all")).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into()).collect();
    names.sort();
    assert_eq!(names.len(), 15, "3 s at 5 frames per second: {names:?}");
    let rgb = |p: &str| {
        let img = image::open(dir.join(p)).unwrap().to_rgb8();
        (img.dimensions(), img.into_raw())
    };
    ok(deepfield(&["recolor", "keys/00003.exr", "-o", "deepest.png"], &dir));
    assert_eq!(rgb("all/frame-00014.png"), rgb("deepest.png"), "the last frame is not the deepest keyframe");
    // Consecutive frames change a little, not wholesale.
    let (a, b) = (rgb("all/frame-00007.png").1, rgb("all/frame-00008.png").1);
    let mean = a.iter().zip(&b).map(|(x, y)| x.abs_diff(*y) as f64).sum::<f64>() / a.len() as f64;
    assert!(mean > 0.0 && mean < 40.0, "mean change between frames {mean}");
    // Two work units.
    ok(deepfield(&["frames", "keys", "--fps", "5", "--units", "0..6", "-o", "split", "-q", "--threads", "1"], &dir));
    ok(deepfield(&["frames", "keys", "--fps", "5", "--units", "6..15", "-o", "split", "-q"], &dir));
    for n in &names {
        let same = std::fs::read(dir.join("all").join(n)).unwrap() == std::fs::read(dir.join("split").join(n)).unwrap();
        assert!(same, "{n} differs between one run and two units");
    }
    // A stand-in ffmpeg: counts the bytes it reads and writes its arguments to the output.
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let fake = bin.join("ffmpeg");
    std::fs::write(&fake, "#!/bin/sh\nfor a; do last=$a; done\necho \"$@\" > \"$last\"\nwc -c >> \"$last\"\n").unwrap();
    std::process::Command::new("chmod").arg("+x").arg(&fake).status().unwrap();
    let with_path = |path: &str, args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_deepfield")).args(args).current_dir(&dir).env("PATH", path).output().unwrap()
    };
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let o = with_path(&path, &["frames", "keys", "--fps", "5", "--video", "zoom.mp4", "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let log = std::fs::read_to_string(dir.join("zoom.mp4")).unwrap();
    assert!(log.contains("-s 48x32") && log.contains("-pix_fmt rgb24") && log.contains("-r 5"), "{log}");
    assert_eq!(log.lines().last().unwrap().trim(), (15 * 48 * 32 * 3).to_string(), "{log}");
    let o = with_path("/nonexistent", &["frames", "keys", "--video", "none.mp4", "-q"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("ffmpeg is not on the PATH"));
    assert!(!dir.join("none.mp4").exists());
    let leftovers = std::fs::read_dir(&dir)
        .unwrap()
        .filter(|e| e.as_ref().unwrap().file_name().to_string_lossy().contains("partial"));
    assert_eq!(leftovers.count(), 0, "a temporary video was left behind");
    // Bad input.
    let o = deepfield(&["frames", "all", "-o", "x", "-q"], &dir);
    assert_eq!(o.status.code(), Some(2), "a folder without keyframes");
    assert!(String::from_utf8_lossy(&o.stderr).contains("at least two keyframes"));
    let o = deepfield(&["frames", "keys", "--size", "40x40", "-o", "x", "-q"], &dir);
    assert_eq!(o.status.code(), Some(2), "another aspect ratio");
}

/// `deepfield zoom --exponential-map 2`: log-polar strips sized for the frames (2307 x 255
/// columns and rows for 320 x 180 at 2 x 2 samples) plus the flat centre; the frames
/// `deepfield frames` makes from them show what the frames from flat keyframes show (mean
/// difference a few levels, where frames a step of zoom apart differ by tens), and a map
/// without `--size` is refused.
#[test]
fn exponential_maps_make_the_same_video_as_keyframes() {
    let dir = scratch("units-expmap");
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/seahorse-valley.toml")).unwrap();
    std::fs::write(dir.join("scene.toml"), &text).unwrap();
    let size = ["--size", "160x90", "--aa", "2"];
    ok(deepfield(&[&["zoom", "scene.toml", "--frames", "4", "-o", "keys", "-q"][..], &size].concat(), &dir));
    let map = ["zoom", "scene.toml", "--frames", "4", "--exponential-map", "2", "-o", "map", "-q"];
    ok(deepfield(&[&map[..], &size].concat(), &dir));
    let header = |p: &str| {
        ok(deepfield(&["recolor", p, "-o", &format!("{p}.png")], &dir));
        image::open(dir.join(format!("{p}.png"))).unwrap().to_rgb8().dimensions()
    };
    assert_eq!(header("map/00000.exr"), (1154, 127));
    assert_eq!(header("map/center.exr"), (92, 92));
    ok(deepfield(&["frames", "keys", "--fps", "4", "-o", "flat", "-q"], &dir));
    ok(deepfield(&["frames", "map", "--size", "160x90", "--fps", "4", "-o", "polar", "-q"], &dir));
    let px = |p: String| image::open(dir.join(p)).unwrap().to_rgb8().into_raw();
    let mean = |a: &[u8], b: &[u8]| a.iter().zip(b).map(|(x, y)| x.abs_diff(*y) as f64).sum::<f64>() / a.len() as f64;
    for f in [0, 4, 8, 11] {
        let (a, b) = (px(format!("flat/frame-{f:05}.png")), px(format!("polar/frame-{f:05}.png")));
        let d = mean(&a, &b);
        assert!(d < 12.0, "frame {f}: the map's frame differs from the keyframes' by {d} on average");
    }
    let far = mean(&px("flat/frame-00004.png".into()), &px("polar/frame-00008.png".into()));
    assert!(far > 20.0, "frames a step of zoom apart differ by only {far}: the comparison cannot tell");
    let o = deepfield(&["frames", "map", "-o", "x", "-q"], &dir);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--size"));
    // The perturbation engine places a strip's samples as direct iteration does.
    for engine in ["f64", "perturb-floatexp"] {
        let out = format!("strip-{engine}.png");
        let args =
            ["render", "scene.toml", "--exponential-map", "2", "--size", "288x32", "--engine", engine, "-o", &out];
        ok(deepfield(&args, &dir));
    }
    let d = mean(&px("strip-f64.png".into()), &px("strip-perturb-floatexp.png".into()));
    assert!(d < 0.5, "the perturbed strip differs from the direct one by {d} on average");
}

/// Raw-data work units: `render --tile K/N --exr` in separate processes and `assemble -o
/// whole.exr` give the EXR of the render done in one piece byte for byte (supersampled
/// with bands that do not start on the file's 16-line blocks, and deep), and a histogram
/// layer, which one unit cannot colour, is coloured after assembly: `recolor` of the
/// assembled file is the whole render's PNG. Without --exr such a unit is refused; a
/// missing or repeated unit is refused.
#[test]
fn exr_units_assemble_to_the_whole_raw_data() {
    let dir = scratch("units-exr");
    let shallow = "version = 1\n[view]\ncenter = [\"-0.745\", \"0.11\"]\nzoom = \"200\"\nwidth = 70\nheight = 45\n[render]\naa = 2\n[[layer]]\nkind = \"histogram\"\n[[layer]]\nkind = \"distance\"\nblend = \"multiply\"\n";
    std::fs::write(dir.join("shallow.toml"), shallow).unwrap();
    let deep = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/liiiines.toml")).unwrap();
    std::fs::write(dir.join("deep.toml"), deep).unwrap();
    let same = |a: &str, b: &str| std::fs::read(dir.join(a)).unwrap() == std::fs::read(dir.join(b)).unwrap();
    for (name, n, size) in [("shallow", 3u32, "70x45"), ("deep", 4, "64x40")] {
        let scene = format!("{name}.toml");
        let whole = ["render", &scene, "--size", size, "-o", "whole.png", "--exr", "whole.exr", "-q"];
        ok(deepfield(&whole, &dir));
        let children: Vec<_> = (0..n)
            .map(|k| {
                let (tile, png, exr) = (format!("{k}/{n}"), format!("u{k}.png"), format!("u{k}.exr"));
                let args = ["render", &scene, "--size", size, "--tile", &tile, "-o", &png, "--exr", &exr, "-q"];
                Command::new(env!("CARGO_BIN_EXE_deepfield")).args(args).current_dir(&dir).spawn().unwrap()
            })
            .collect();
        for c in children {
            assert!(c.wait_with_output().unwrap().status.success(), "{name}: a unit failed");
        }
        let mut units: Vec<String> = (0..n).rev().map(|k| format!("u{k}.exr")).collect();
        let mut args: Vec<String> = vec!["assemble".into(), "-o".into(), "assembled.exr".into()];
        args.extend(units.iter().cloned());
        ok(deepfield(&args.iter().map(String::as_str).collect::<Vec<_>>(), &dir));
        assert!(same("assembled.exr", "whole.exr"), "{name}: the assembled EXR differs from the whole render's");
        ok(deepfield(&["recolor", "assembled.exr", "-o", "recoloured.png"], &dir));
        assert!(same("recoloured.png", "whole.png"), "{name}: recolouring the assembled data differs from the render");
        units.pop();
        let o = deepfield(
            &[&["assemble", "-o", "x.exr"][..], &units.iter().map(String::as_str).collect::<Vec<_>>()].concat(),
            &dir,
        );
        assert_eq!(o.status.code(), Some(2), "{name}: a missing unit");
        assert!(String::from_utf8_lossy(&o.stderr).contains("is missing"));
        assert!(!dir.join("x.exr").exists());
    }
    let o = deepfield(&["render", "shallow.toml", "--tile", "0/3", "-o", "x.png"], &dir);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("add --exr"));
}
