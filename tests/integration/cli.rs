//! The command line as a user meets it: bad input, determinism, round trips, outputs.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use super::util::scratch;

fn deepfield(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_deepfield")).args(args).current_dir(dir).output().expect("run deepfield")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Files in `dir` other than the inputs the test wrote.
fn outputs(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.ends_with(".toml"))
        .collect();
    v.sort();
    v
}

const SMALL: &str = "version = 1\n[view]\ncenter = [\"-0.75\", \"0.1\"]\nzoom = \"2\"\nwidth = 64\nheight = 48\n";

/// Bad input: exit code 2, a message with `needle` (and `file:line:col` where one
/// exists), no panic, and no output file left behind.
fn rejects(name: &str, scene: Option<&str>, extra: &[&str], needle: &str) {
    let dir = scratch(&format!("cli-{name}"));
    let mut args = vec!["render"];
    if let Some(text) = scene {
        write(&dir, "scene.toml", text);
        args.push("scene.toml");
    }
    args.extend_from_slice(extra);
    args.extend_from_slice(&["-o", "out.png", "--exr", "out.exr"]);
    let o = deepfield(&args, &dir);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{name}: exit code; stderr: {err}");
    assert!(err.contains(needle), "{name}: expected `{needle}` in: {err}");
    assert!(!err.contains("panicked"), "{name}: panic: {err}");
    assert!(outputs(&dir).is_empty(), "{name}: left files {:?}", outputs(&dir));
}

#[test]
fn unknown_key_names_line_and_column() {
    rejects("unknown-key", Some("version = 1\n[view]\nwidht = 3\n"), &[], "scene.toml:3:1");
}

#[test]
fn malformed_number_names_line_and_column() {
    rejects("bad-number", Some("version = 1\n[view]\ncenter = [\"-0.7.5\", \"0\"]\n"), &[], "scene.toml:3:10");
    rejects("zoom-text", Some("version = 1\n[view]\nzoom = \"deep\"\n"), &[], "scene.toml:3:8");
    rejects("zoom-type", Some("version = 1\n[view]\nzoom = 5\n"), &[], "scene.toml:3:8");
    rejects("zoom-flag", None, &["--zoom", "abc"], "not a decimal number");
}

#[test]
fn zero_or_absurd_sizes_are_refused() {
    rejects("zero-width", Some("version = 1\n[view]\nwidth = 0\n"), &[], "scene.toml:3:9");
    rejects("huge-width", Some("version = 1\n[view]\nwidth = 100000000\n"), &[], "width must be in");
    rejects("zero-size-flag", None, &["--size", "0x10"], "WIDTHxHEIGHT");
    rejects(
        "absurd-samples",
        Some("version = 1\n[view]\nwidth = 100000\nheight = 100000\n[render]\naa = 16\n"),
        &[],
        "samples",
    );
}

#[test]
fn numbers_beyond_what_a_view_needs_are_refused_before_anything_is_allocated() {
    rejects("far-centre", None, &["--center=1e99999999999,0"], "too far from the origin");
    rejects(
        "far-julia-c",
        Some("version = 1\n[formula]\nkind = \"julia\"\nc = [\"0\", \"-3e9\"]\n"),
        &[],
        "scene.toml:4:5",
    );
    rejects("too-deep", None, &["--zoom", "1e1000000000", "--size", "8x6"], "zoom is limited to 1e100000000");
    rejects("too-deep-scene", Some("version = 1\n[view]\nradius = \"1e-200000000\"\n"), &[], "scene.toml:3:10");
}

#[test]
fn zero_max_iterations_are_refused() {
    rejects("max-iter-0", Some("version = 1\n[iteration]\nmax = 0\n"), &[], "scene.toml:3:7");
    rejects("max-iter-flag", None, &["--max-iter", "0"], "max-iter");
}

#[test]
fn missing_files_are_refused() {
    rejects("missing-scene", None, &["nope.toml"], "no such scene file");
    rejects(
        "missing-palette",
        Some(&format!("{SMALL}[[layer]]\nkind = \"smooth\"\npalette = \"nope\"\n")),
        &[],
        "unknown palette `nope`",
    );
    rejects("missing-palette-flag", Some(SMALL), &["--palette", "nope"], "unknown palette");
    rejects(
        "missing-bitmap",
        Some(&format!("{SMALL}[[layer]]\nkind = \"bitmap\"\nimage = \"nope.png\"\n")),
        &[],
        "cannot load bitmap",
    );
}

#[test]
fn unwritable_output_is_refused() {
    let dir = scratch("cli-unwritable");
    write(&dir, "scene.toml", SMALL);
    let o = deepfield(&["render", "scene.toml", "-o", "no/such/dir/out.png"], &dir);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("does not exist"), "{}", stderr(&o));
    assert!(outputs(&dir).is_empty());
}

#[test]
fn engines_forced_beyond_their_range_are_refused_with_a_reason() {
    let deep = "version = 1\n[view]\ncenter = [\"-0.75\", \"0.1\"]\nzoom = \"1e14\"\n";
    rejects("too-deep", Some(deep), &["--engine", "f64"], "too deep for the f64 engine");
    let deeper = "version = 1\n[view]\ncenter = [\"-2\", \"0\"]\nzoom = \"1e320\"\n";
    rejects("too-deep-deltas", Some(deeper), &["--engine", "perturb-f64"], "f64 deltas underflow");
    rejects("bad-engine", Some("version = 1\n[render]\nengine = \"gmp\"\n"), &[], "scene.toml:3:10");
    rejects("bad-tolerance", Some("version = 1\n[render]\nbla_tolerance = 2.0\n"), &[], "scene.toml:3:17");
}

/// A deep view whose reference repeats itself exactly (inside the main cardioid: the orbit
/// settles on an attracting fixed point, which the rounding reaches within a few hundred
/// iterations) stores it only to that repeat, whatever the limit, and `--stats` says so;
/// its samples stop in the dense part (interior, by the contraction criterion), so no steps
/// of blocks are built. A view with a limit past the 2^25 iterations stored densely whose
/// reference neither repeats nor escapes (just past the cusp, where the orbit crawls for
/// about 10^9 iterations) renders with the rest of its reference packed, and `--stats`
/// says how the orbit is stored. `--dense-orbit` packs a shorter orbit the same way, and
/// the picture is the same as with the whole orbit stored densely when BLA is off (the
/// same values, stepped one iteration at a time).
#[test]
fn limits_past_the_dense_orbit_pack_the_rest() {
    let dir = scratch("cli-packed");
    let interior = "version = 1\n[view]\ncenter = [\"-0.1\", \"0.1\"]\nzoom = \"1e14\"\nwidth = 8\nheight = 6\n";
    write(&dir, "interior.toml", interior);
    let o = deepfield(&["render", "interior.toml", "--max-iter", "33554433", "-o", "i.png", "--stats", "-q"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &stderr(&o);
    assert!(text.contains("it repeats itself exactly") && !text.contains("packed"), "{text}");
    assert!(!text.contains("blocks"), "{text}");
    let crawl =
        "version = 1\n[view]\ncenter = [\"0.25000000000000001\", \"0\"]\nzoom = \"1e14\"\nwidth = 2\nheight = 2\n";
    write(&dir, "crawl.toml", crawl);
    let o = deepfield(&["render", "crawl.toml", "--max-iter", "33554433", "-o", "c.png", "--stats", "-q"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &stderr(&o);
    assert!(text.contains("33554433 iterations, 1048576 stored densely and 32505857 packed"), "{text}");
    let e50 = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/bench-e50.toml")).unwrap();
    write(&dir, "e50.toml", &e50);
    let common = ["render", "e50.toml", "--size", "24x18", "--no-bla", "-q", "--stats"];
    let dense = deepfield(&[&common[..], &["-o", "dense.png"]].concat(), &dir);
    let packed = deepfield(&[&common[..], &["-o", "packed.png", "--dense-orbit", "700"]].concat(), &dir);
    assert!(dense.status.success() && packed.status.success(), "{}", stderr(&packed));
    let text = String::from_utf8_lossy(&packed.stdout).to_string() + &stderr(&packed);
    assert!(text.contains("700 stored densely and"), "{text}");
    assert_eq!(std::fs::read(dir.join("dense.png")).unwrap(), std::fs::read(dir.join("packed.png")).unwrap());
}

/// Past the first 2^20 iterations samples take steps of whole blocks, and those begin at
/// the same index with the same steps whether the orbit there is stored densely or packed:
/// a view by the cusp of the main cardioid (c = 1/4 + 5e-12, every orbit escaping after
/// about 1.4 million iterations) gives the same bytes both ways with BLA on (PNG and the
/// EXR's raw channels), `--stats` says that blocks were built and steps taken through the
/// packed tail, and the samples escaped past 2^20 iterations, after those steps.
#[test]
fn steps_of_blocks_are_the_same_dense_and_packed() {
    let dir = scratch("cli-blocks");
    let cusp = "version = 1\n[view]\ncenter = [\"0.250000000005\", \"0\"]\nzoom = \"1e18\"\nwidth = 8\nheight = 6\n[iteration]\nmax = 2000000\n";
    write(&dir, "cusp.toml", cusp);
    let common = ["render", "cusp.toml", "--stats", "-q", "--exr"];
    let dense = deepfield(&[&common[..], &["dense.exr", "-o", "dense.png"]].concat(), &dir);
    let packed =
        deepfield(&[&common[..], &["packed.exr", "-o", "packed.png", "--dense-orbit", "1048576"]].concat(), &dir);
    assert!(dense.status.success() && packed.status.success(), "{}", stderr(&packed));
    let [dense, packed] = [dense, packed].map(|o| String::from_utf8_lossy(&o.stdout).to_string() + &stderr(&o));
    assert!(dense.contains("-iteration blocks from iteration 1048576"), "{dense}");
    assert!(
        packed.contains("stored densely and") && packed.contains("-iteration blocks from iteration 1048576"),
        "{packed}"
    );
    assert!(!packed.contains("(0 of the steps through the packed tail)"), "{packed}");
    let read = |name: &str| std::fs::read(dir.join(name)).unwrap();
    assert_eq!(read("dense.png"), read("packed.png"));
    assert_eq!(read("dense.exr"), read("packed.exr"));
    let img = exr::prelude::read_all_flat_layers_from_file(dir.join("packed.exr")).unwrap();
    let n = img.layer_data[0].channel_data.list.iter().find(|c| c.name.to_string() == "N").unwrap();
    let exr::prelude::FlatSamples::U32(values) = &n.sample_data else { panic!("N must be u32") };
    assert!(values.iter().all(|&v| v > 1 << 20 && v != u32::MAX), "every sample escapes past 2^20: {values:?}");
}

/// Deep views render with the perturbation engine the choice names, and the statistics
/// say so (engine, reason, glitch count).
#[test]
fn deep_views_render_with_perturbation_and_report_it() {
    let dir = scratch("cli-deep");
    let scene = "version = 1\n[view]\ncenter = [\"-1.99999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999837485382669331911167033522316925\", \"0\"]\nzoom = \"1e330\"\nwidth = 48\nheight = 32\n[iteration]\nmax = 4000\n[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"distance\"\nblend = \"multiply\"\n";
    write(&dir, "scene.toml", scene);
    let o = deepfield(&["render", "scene.toml", "-o", "a.png", "--stats-json", "s.json"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    assert_eq!(json["engine"], "perturb-floatexp");
    assert!(json["engine_reason"].as_str().unwrap().contains("below the f64-safe"));
    assert_eq!(json["glitched_pixels"], 0);
    assert!(json["deep"]["reference_bits"].as_u64().unwrap() > 1096);
    // The generic engine (every family but z² + c) counts its steps too: a Burning Ship
    // view at 1e30 takes single steps, BLA steps and rebases, and --stats says how many.
    let o = deepfield(
        &[
            "render",
            "--formula",
            "burning-ship",
            "--center=-0.7992241941043727780907714492699964879292,-0.8948712007261344556031963401559132320635",
            "--zoom",
            "1e20",
            "--size",
            "32x24",
            "--max-iter",
            "3000",
            "-o",
            "b.png",
            "--stats-json",
            "b.json",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("b.json")).unwrap()).unwrap();
    assert_eq!(json["engine"], "perturb-f64");
    let deep = &json["deep"];
    assert!(deep["steps"].as_u64().unwrap() > 0, "{json}");
    assert!(deep["bla_steps"].as_u64().unwrap() > 0, "{json}");
}

/// Interior detection: by default on a view centred on a minibrot (to a limit of at least
/// 100 of its periods), `--interior-detection
/// off` and `on` override it (and the PNG carries the scene key), `--stats` and
/// `--stats-json` say what was decided and how many samples stopped early, the picture is
/// the same either way, and a key that is not a boolean is refused with its place.
#[test]
fn interior_detection_is_a_scene_key_and_a_flag_shown_in_statistics() {
    let dir = scratch("cli-interior");
    let scene = "version = 1\n[view]\ncenter = [\"-0.83031842675693053553109980802050591726924580592100415017586803599827560339120465373468510811787516730515186454892834980632246054605795\", \"0.23612476396680780363307856325882633547132442124365456398110558858530832926040168389957117374824216611986058042279006600832794659929318\"]\nradius = \"1.2e-102\"\nwidth = 32\nheight = 24\n[iteration]\nmax = 200000\n";
    write(&dir, "scene.toml", scene);
    let mut pictures = Vec::new();
    for (flag, decision, text) in [
        (None, "auto-on", "detection on (by default"),
        (Some("off"), "off", "detection off (render.interior_detection = false)"),
        (Some("on"), "on", "detection on (requested)"),
    ] {
        let png = format!("{decision}.png");
        let mut args = vec!["render", "scene.toml", "-o", &png, "--stats", "--stats-json", "s.json"];
        if let Some(f) = flag {
            args.extend_from_slice(&["--interior-detection", f]);
        }
        let o = deepfield(&args, &dir);
        assert!(o.status.success(), "{}", stderr(&o));
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(stdout.contains(text), "{flag:?}: {stdout}");
        let json: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("s.json")).unwrap()).unwrap();
        assert_eq!(json["deep"]["interior_detection"], decision, "{json}");
        let stopped = json["deep"]["interior_samples"].as_u64().unwrap();
        assert_eq!(stopped > 100, flag != Some("off"), "{flag:?}: {stopped} samples stopped early");
        let newton = json["deep"]["interior_newton_samples"].as_u64().unwrap();
        assert!(newton <= stopped && (newton > 0) == (stopped > 0), "{flag:?}: {newton} by Newton's test");
        let embedded = deepfield::io::read_png_scene(&dir.join(&png)).unwrap().unwrap();
        let key = flag.map(|f| format!("interior_detection = {}", f == "on"));
        assert_eq!(embedded.contains("interior_detection"), key.is_some(), "{embedded}");
        assert!(key.is_none_or(|k| embedded.contains(&k)), "{embedded}");
        pictures.push(image::open(dir.join(&png)).unwrap().into_rgb8().into_raw());
    }
    assert!(pictures.iter().all(|p| p == &pictures[0]), "the picture depends on interior detection");
    // 14 periods of the nucleus: too few for detection to pay, so not by default.
    let o =
        deepfield(&["render", "scene.toml", "-o", "few.png", "--max-iter", "20000", "--stats-json", "s.json"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("s.json")).unwrap()).unwrap();
    assert_eq!(json["deep"]["interior_detection"], "auto-few-periods", "{json}");
    rejects("interior-type", Some("version = 1\n[render]\ninterior_detection = \"yes\"\n"), &[], "scene.toml:3:22");
    rejects("interior-flag", None, &["--interior-detection", "maybe"], "--interior-detection");
}

/// A Kalles Fraktaler location renders as a scene.
#[test]
fn kfr_locations_are_scenes() {
    let dir = scratch("cli-kfr");
    let kfr = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bench-e14.kfr");
    let o = deepfield(&["render", kfr.to_str().unwrap(), "--size", "32x24", "-o", "k.png"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    write(&dir, "bad.kfr", "Re: -0.75\nIm: 0.1x\nZoom: 1\n");
    let o = deepfield(&["render", "bad.kfr", "-o", "b.png"], &dir);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("bad.kfr:2:5"), "{}", stderr(&o));
    assert!(!dir.join("b.png").exists());
    // The location's colours come with it: the file is its own palette.
    let embedded = deepfield::io::read_png_scene(&dir.join("k.png")).unwrap().expect("scene chunk");
    assert!(embedded.contains("bench-e14.kfr") && embedded.contains("kind = \"smooth\""), "{embedded}");
    // An old-style file stretched by `Ratio` (as Kalles Fraktaler's 1e1086 benchmark is)
    // renders, stretched.
    let old = "Re: -0.75\r\nIm: 0.1\r\nZoom: 2\r\nIterations: 200\r\nIterDiv: 0.5\r\nRotate: 0.000000\r\n\
               Ratio: 381.176471\r\nColors: 0,0,0,41,35,190,132,225,108,\r\nInteriorColor: 0,0,255,\r\n";
    write(&dir, "old.kfr", old);
    let o = deepfield(&["render", "old.kfr", "--size", "32x24", "-o", "o.png"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let embedded = deepfield::io::read_png_scene(&dir.join("o.png")).unwrap().expect("scene chunk");
    assert!(embedded.contains("stretch_amount = -0.04"), "{embedded}");
    assert!(embedded.contains("interior = \"#ff0000\""), "B,G,R: {embedded}");
    // A bad colour in the file is reported where it is, as the palette it is.
    write(&dir, "c.kfr", "Re: 0\nIm: 0\nZoom: 1\nColors: 1,2,x,\n");
    let o = deepfield(&["render", "c.kfr", "--size", "8x6", "-o", "c.png"], &dir);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("c.kfr:4:13"), "{}", stderr(&o));
    assert!(!dir.join("c.png").exists());
}

/// `deepfield compare` prints one row per engine with the documented keys; on a shallow
/// view its ground truth agrees with direct f64 iteration.
#[test]
fn compare_measures_engines_against_the_truth() {
    let dir = scratch("cli-compare");
    write(&dir, "scene.toml", SMALL);
    let o = deepfield(&["compare", "scene.toml", "--samples", "60", "--json"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rows = rows.as_array().unwrap();
    let names: Vec<&str> = rows.iter().map(|r| r["engine"].as_str().unwrap()).collect();
    assert!(
        names.contains(&"f32") && names.contains(&"f64") && names.contains(&"perturb-floatexp bla 1e-6"),
        "{names:?}"
    );
    for r in rows {
        for key in [
            "seconds",
            "iterations_per_second",
            "n_mismatch_fraction",
            "nf_error_p50",
            "nf_error_p99",
            "de_error_p50",
            "de_error_p99",
        ] {
            assert!(r[key].as_f64().is_some_and(f64::is_finite), "{key} in {r}");
        }
        // The errors above are over escaped pixels, and say over how many.
        for key in ["nf_scored", "de_scored"] {
            assert!(r[key].as_u64().is_some_and(|n| n > 0 && n <= r["compared"].as_u64().unwrap()), "{key} in {r}");
        }
    }
    let f64_row = rows.iter().find(|r| r["engine"] == "f64").unwrap();
    assert_eq!(f64_row["n_mismatch_fraction"], 0.0, "{f64_row}");
    assert!(f64_row["nf_error_p99"].as_f64().unwrap() < 1e-6, "{f64_row}");
    let o = deepfield(
        &[
            "compare",
            "scene.toml",
            "--samples",
            "10",
            "--csv",
            "--sample-only",
            "--only",
            "f32,bla 1e-6",
            "--pixels",
            "px.csv",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    // One line per sampled pixel, with the truth and each engine's N and NF; at this zoom
    // the perturbation engines' N is the truth's.
    let px = std::fs::read_to_string(dir.join("px.csv")).unwrap();
    let lines: Vec<Vec<&str>> = px.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(lines.len(), 11, "{px}");
    let head = [
        "x",
        "y",
        "n_true",
        "nf_true",
        "near_circle",
        "ill_conditioned",
        "nf_ill_conditioned",
        "de_ill_conditioned",
        "f32 n",
    ];
    assert_eq!(lines[0][..9], head, "{px}");
    for l in &lines[1..] {
        assert_eq!(l.len(), 14, "{px}");
        assert!(l[10] == l[2] && l[12] == l[2], "{px}");
    }
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.starts_with("engine,seconds,iterations_per_second,n_mismatch_fraction,"), "{text}");
    let names: Vec<&str> = text.lines().skip(1).map(|l| l.split(',').next().unwrap()).collect();
    assert_eq!(names, ["f32", "perturb-f64 bla 1e-6", "perturb-floatexp bla 1e-6"], "{text}");
    let o = deepfield(&["compare", "scene.toml", "--samples", "10", "--only", "nothing-like-this"], &dir);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--only nothing-like-this"), "{}", stderr(&o));
}

/// Past the f64 range `compare` lists only the FloatExp engines, and the default BLA
/// tolerance matches its big-float truth.
#[test]
fn compare_at_depth_lists_the_engines_that_can_address_it() {
    let dir = scratch("cli-compare-deep");
    let center = "-1.99999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999837485382669331911167033522316925,1.3717805209060941414572912854135e-211";
    let args = ["compare", "--center", center, "--zoom", "1e320", "--size", "40x30", "--max-iter", "12500"];
    let o = deepfield(&[&args[..], &["--samples", "12", "--sample-only", "--json"]].concat(), &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let names: Vec<&str> = rows.as_array().unwrap().iter().map(|r| r["engine"].as_str().unwrap()).collect();
    assert_eq!(names, ["perturb-floatexp", "perturb-floatexp bla 1e-14", "perturb-floatexp bla 1e-6"]);
    for r in rows.as_array().unwrap().iter().take(2) {
        assert_eq!(r["n_mismatch_fraction"], 0.0, "{r}");
        assert!(r["nf_error_p99"].as_f64().unwrap() < 1e-6, "{r}");
    }
}

#[test]
fn other_bad_values_are_located() {
    rejects("bad-kind", Some("version = 1\n[formula]\nkind = \"mandelbrat\"\n"), &[], "scene.toml:3:8");
    rejects("julia-no-c", Some("version = 1\n[formula]\nkind = \"julia\"\n"), &[], "needs its parameter");
    rejects(
        "bad-layer-key",
        Some(&format!("{SMALL}[[layer]]\nkind = \"smooth\"\nwidth = 2.0\n")),
        &[],
        "scene.toml:9:9",
    );
    rejects("bad-version", Some("version = 2\n"), &[], "scene.toml:1:11");
    rejects("bad-escape", Some("version = 1\n[iteration]\nescape_radius = 1.0\n"), &[], "escape_radius");
    rejects("bad-channel", Some(SMALL), &["--channels", "N,XYZ"], "unknown channel");
    rejects("toml-syntax", Some("version = 1\n[view\n"), &[], "scene.toml:2:");
}

#[test]
fn same_bytes_whatever_the_thread_count() {
    let layers = "[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"boundary\"\nblend = \"multiply\"\n";
    same_bytes("cli-determinism", &format!("{SMALL}[render]\naa = 2\n{layers}"));
    // The perturbation engine too (reference, BLA, samples in the vector lanes or the scalar loop).
    let deep = "version = 1\n[view]\ncenter = [\"-1.99999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999837485382669331911167033522316925\", \"1.3717805209060941414572912854135e-211\"]\nzoom = \"1e120\"\nwidth = 61\nheight = 37\n[iteration]\nmax = 5000\n";
    same_bytes("cli-determinism-deep", &format!("{deep}{layers}"));
    // A view deep enough (about 1900 bits) that its reference's steps are shared by a team
    // of threads, and its tables are built on every thread.
    let e533 = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/bench-e533.toml")).unwrap();
    let small = e533.replace("width = 800", "width = 41").replace("height = 600", "height = 23");
    same_bytes("cli-determinism-team", &small.replace("max = 120000", "max = 20000"));
}

/// Every instruction set this CPU has (`--simd`, scalar included) renders the same PNG
/// bytes, shallow (the direct kernels, with a geometric trap on the vectorised trap path)
/// and deep (the perturbation lanes); `--stats` names the level used.
#[test]
fn same_bytes_on_every_simd_level_this_cpu_has() {
    let layers = "[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"distance\"\nblend = \"multiply\"\n";
    let trap = "[[layer]]\nkind = \"trap\"\nshape = \"circle\"\nradius = 0.5\nblend = \"screen\"\n";
    let deep = "version = 1\n[view]\ncenter = [\"-1.99999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999837485382669331911167033522316925\", \"1.3717805209060941414572912854135e-211\"]\nzoom = \"1e120\"\nwidth = 61\nheight = 37\n[iteration]\nmax = 5000\n";
    // A hybrid in the direct kernel's lanes (no trap: a trap sends it to the scalar kernel).
    let hybrid = "version = 1\n[formula]\nkind = \"burning-ship,mandelbrot^3\"\n[view]\ncenter = [\"-0.5\", \"-0.3\"]\nzoom = \"0.8\"\nwidth = 64\nheight = 48\n";
    let levels = deepfield::simd_level::SimdLevel::usable();
    for (name, scene) in [
        ("shallow", format!("{SMALL}{layers}{trap}")),
        ("deep", format!("{deep}{layers}")),
        ("hybrid", format!("{hybrid}{layers}")),
    ] {
        let dir = scratch(&format!("cli-simd-{name}"));
        write(&dir, "scene.toml", &scene);
        let mut pngs = Vec::new();
        for level in &levels {
            let png = format!("{}.png", level.name());
            let o = deepfield(&["render", "scene.toml", "--simd", level.name(), "--stats", "-o", &png], &dir);
            assert!(o.status.success(), "{}", stderr(&o));
            let stats = String::from_utf8_lossy(&o.stdout);
            assert!(stats.contains(level.describe()), "{name} {}: {stats}", level.name());
            pngs.push((level.name(), std::fs::read(dir.join(png)).unwrap()));
        }
        for (level, bytes) in &pngs[1..] {
            assert!(*bytes == pngs[0].1, "{name}: --simd {level} differs from scalar");
        }
    }
    // Recolouring: the colouring's vectorised passes (a log transfer, the soft distance's
    // fifth root, palette coordinates) at every level give the render's bytes.
    let dir = scratch("cli-simd-recolor");
    let looks = "[[layer]]\nkind = \"smooth\"\ntransfer = \"log\"\ndensity = 0.7\n[[layer]]\nkind = \"distance\"\nblend = \"multiply\"\nopacity = 0.6\n";
    write(&dir, "scene.toml", &format!("{SMALL}{looks}"));
    let o = deepfield(&["render", "scene.toml", "--simd", "scalar", "-o", "render.png", "--exr", "data.exr"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let want = std::fs::read(dir.join("render.png")).unwrap();
    for level in &levels {
        let png = format!("recolor-{}.png", level.name());
        let o = deepfield(&["recolor", "data.exr", "--simd", level.name(), "--stats", "-o", &png], &dir);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(String::from_utf8_lossy(&o.stdout).contains(level.describe()), "recolor --simd {}", level.name());
        assert!(
            std::fs::read(dir.join(&png)).unwrap() == want,
            "recolor --simd {} differs from the render",
            level.name()
        );
    }
}

fn same_bytes(name: &str, scene: &str) {
    let dir = scratch(name);
    write(&dir, "scene.toml", scene);
    let mut pngs = Vec::new();
    let mut exrs = Vec::new();
    for t in ["1", "2", "3"] {
        let (png, exr) = (format!("t{t}.png"), format!("t{t}.exr"));
        let o = deepfield(&["render", "scene.toml", "--threads", t, "-o", &png, "--exr", &exr], &dir);
        assert!(o.status.success(), "{}", stderr(&o));
        pngs.push(std::fs::read(dir.join(png)).unwrap());
        exrs.push(std::fs::read(dir.join(exr)).unwrap());
    }
    assert!(pngs.windows(2).all(|w| w[0] == w[1]), "PNG bytes depend on --threads");
    assert!(exrs.windows(2).all(|w| w[0] == w[1]), "EXR bytes depend on --threads");
}

/// A sum's coefficient a goes with the image: `--stats` names it, the PNG's scene holds it
/// and re-renders to the same bytes, and another a draws another picture.
#[test]
fn a_sums_coefficient_goes_with_the_image() {
    let dir = scratch("cli-sum-a");
    let args = ["render", "--formula", "redshift-rider-2", "--size", "48x36", "--zoom", "0.8", "--center=0,0"];
    let o = deepfield(&[&args[..], &["--formula-a=-0.5,0.3", "--stats", "-o", "a.png"]].concat(), &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let stats = String::from_utf8_lossy(&o.stdout);
    assert!(stats.contains("redshift-rider-2 with a = -0.5+0.3i"), "{stats}");
    let embedded = deepfield::io::read_png_scene(&dir.join("a.png")).unwrap().expect("scene chunk");
    assert!(embedded.contains("a = [-0.5, 0.3]"), "{embedded}");
    let o = deepfield(&["render", "a.png", "-o", "b.png"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = deepfield(&[&args[..], &["-o", "c.png"]].concat(), &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let read = |f: &str| std::fs::read(dir.join(f)).unwrap();
    assert_eq!(read("a.png"), read("b.png"), "re-rendering the embedded scene changed the image");
    assert_ne!(read("a.png"), read("c.png"), "a = 1 drew the picture of a = -0.5 + 0.3i");
}

#[test]
fn png_round_trip_reproduces_the_image() {
    let dir = scratch("cli-roundtrip");
    write(&dir, "scene.toml", &format!("{SMALL}[[layer]]\nkind = \"smooth\"\npalette = \"twilight\"\n"));
    let o =
        deepfield(&["render", "scene.toml", "-o", "a.png", "--max-iter", "321", "--zoom", "3.5", "--bits", "16"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = deepfield(&["render", "a.png", "-o", "b.png"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let (a, b) = (std::fs::read(dir.join("a.png")).unwrap(), std::fs::read(dir.join("b.png")).unwrap());
    assert_eq!(a, b, "re-rendering the embedded scene changed the image");
    let img = image::open(dir.join("a.png")).unwrap();
    assert_eq!(img.color(), image::ColorType::Rgb16);
}

#[test]
fn exr_holds_the_named_channels_and_the_scene() {
    let dir = scratch("cli-exr");
    write(&dir, "scene.toml", SMALL);
    let o = deepfield(&["render", "scene.toml", "-o", "a.png", "--exr", "a.exr", "--aa", "2"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let meta = exr::meta::MetaData::read_from_file(dir.join("a.exr"), false).unwrap();
    let h = &meta.headers[0];
    let names: Vec<String> = h.channels.list.iter().map(|c| c.name.to_string()).collect();
    assert_eq!(names, ["DEX", "DEY", "N", "NF", "T"]);
    assert_eq!(h.layer_size.0, 128, "EXR holds every sample (64 px x aa 2)");
    let scene = deepfield::io::read_exr_scene(&dir.join("a.exr")).unwrap().expect("scene in header");
    assert!(scene.contains("aa = 2"), "{scene}");
    // N read back agrees with the engine.
    let img = exr::prelude::read_all_flat_layers_from_file(dir.join("a.exr")).unwrap();
    let n = img.layer_data[0].channel_data.list.iter().find(|c| c.name.to_string() == "N").unwrap();
    let exr::prelude::FlatSamples::U32(values) = &n.sample_data else { panic!("N must be u32") };
    assert_eq!(values.len(), 128 * 96);
    assert!(values.contains(&u32::MAX) && values.iter().any(|&v| v < 100));

    let o = deepfield(&["render", "scene.toml", "-o", "b.png", "--exr", "b.exr", "--channels", "N,T"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let meta = exr::meta::MetaData::read_from_file(dir.join("b.exr"), false).unwrap();
    let names: Vec<String> = meta.headers[0].channels.list.iter().map(|c| c.name.to_string()).collect();
    assert_eq!(names, ["N", "T"]);
}

#[test]
fn stats_json_has_the_documented_keys() {
    let dir = scratch("cli-stats");
    write(&dir, "scene.toml", SMALL);
    let o = deepfield(&["render", "scene.toml", "-o", "a.png", "--stats", "--stats-json", "s.json"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("iterations/s"));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("s.json")).unwrap()).unwrap();
    for k in ["engine", "pixels", "iterations", "wall_seconds", "iterations_per_second"] {
        assert!(v.get(k).is_some(), "missing {k} in {v}");
    }
    assert_eq!(v["pixels"], 64 * 48);
    assert_eq!(v["engine"], "f64");
    assert!(v["iterations"].as_u64().unwrap() > 0);
}

/// The deep engine's keys: a view past 1e300 reports its reference and its BLA tables,
/// period-aligned steps included (the shipped liiiines view at a small size).
#[test]
fn stats_json_reports_the_deep_engine() {
    let dir = scratch("cli-stats-deep");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/liiiines.toml");
    let o = deepfield(&["render", scene, "--size", "40x30", "-o", "a.png", "--stats-json", "s.json"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("s.json")).unwrap()).unwrap();
    let d = &v["deep"];
    for k in ["reference_bits", "reference_iterations", "orbit_seconds", "tables_seconds", "bla_bytes", "rebases"] {
        assert!(d.get(k).is_some(), "missing deep.{k} in {v}");
    }
    assert!(d["aligned_steps"].as_u64().unwrap() > 0, "{v}");
    assert!(d["aligned_stages"].as_u64().unwrap() >= 1, "{v}");
    assert!(d["bla_steps"].as_u64().unwrap() > 0, "{v}");
}

#[test]
fn flags_alone_describe_a_julia_scene() {
    let dir = scratch("cli-flags");
    let o = deepfield(
        &["render", "--julia-c=-0.8,0.156", "--center", "0,0", "--zoom", "1.2", "--size", "40x30", "-o", "j.png"],
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let scene = deepfield::io::read_png_scene(&dir.join("j.png")).unwrap().unwrap();
    assert!(scene.contains("kind = \"julia\"") && scene.contains("-0.8"), "{scene}");
}

#[test]
fn ctrl_c_cancels_cleanly_and_leaves_no_file() {
    let dir = scratch("cli-cancel");
    // A long render: deep in seahorse valley, many iterations, big image.
    let args = ["render", "--center=-0.7436438870371587,0.1318259042053", "--zoom", "1e8", "--max-iter", "1000000"];
    let child = Command::new(env!("CARGO_BIN_EXE_deepfield"))
        .args(args)
        .args(["--size", "4000x3000", "-o", "big.png", "--exr", "big.exr"])
        .current_dir(&dir)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until the outputs are open (their temporary files exist), then press Ctrl-C.
    let start = std::time::Instant::now();
    while !outputs(&dir).iter().any(|n| n.ends_with(".partial")) {
        assert!(start.elapsed().as_secs() < 60, "render never opened its outputs");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    std::thread::sleep(std::time::Duration::from_millis(200));
    let kill = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    assert!(outputs(&dir).is_empty(), "left {:?}", outputs(&dir));
}

#[test]
fn png_round_trip_finds_the_bitmap_from_another_folder() {
    let dir = scratch("cli-roundtrip-bitmap");
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/trap.png");
    std::fs::copy(&fixture, dir.join("trap.png")).unwrap();
    write(&dir, "scene.toml", &format!("{SMALL}[[layer]]\nkind = \"bitmap\"\nimage = \"trap.png\"\nsize = 2.0\n"));
    let o = deepfield(&["render", "scene.toml", "-o", "a.png"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let elsewhere = scratch("cli-roundtrip-bitmap-elsewhere");
    let a = dir.join("a.png");
    let o = deepfield(&["render", a.to_str().unwrap(), "-o", "b.png"], &elsewhere);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(elsewhere.join("b.png")).unwrap());
}

#[test]
fn colliding_or_folder_outputs_are_refused_before_rendering() {
    let dir = scratch("cli-collide");
    write(&dir, "scene.toml", SMALL);
    std::fs::create_dir(dir.join("folder")).unwrap();
    for (args, needle) in [
        (vec!["render", "scene.toml", "-o", "folder"], "it is a folder"),
        (vec!["render", "scene.toml", "-o", "x.png", "--exr", "x.png"], "name the same file"),
        (vec!["render", "scene.toml", "-o", "x.png", "--stats-json", "no/such/s.json"], "does not exist"),
    ] {
        let o = deepfield(&args, &dir);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
        assert_eq!(outputs(&dir), ["folder"], "{args:?} left files");
    }
    // Re-rendering a PNG in its own folder without -o would overwrite it.
    let o = deepfield(&["render", "scene.toml", "-o", "a.png"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let before = std::fs::read(dir.join("a.png")).unwrap();
    let o = deepfield(&["render", "a.png", "--size", "10x10"], &dir);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("would overwrite the input"), "{}", stderr(&o));
    assert_eq!(std::fs::read(dir.join("a.png")).unwrap(), before);
}

#[test]
fn many_threads_and_unicode_paths_work() {
    let dir = scratch("cli-unicode").join("日本語");
    std::fs::create_dir_all(&dir).unwrap();
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/trap.png");
    std::fs::copy(&fixture, dir.join("星.png")).unwrap();
    write(&dir, "scene.toml", &format!("{SMALL}[[layer]]\nkind = \"bitmap\"\nimage = \"星.png\"\n"));
    let o = deepfield(&["render", "scene.toml", "-o", "a.png", "--exr", "a.exr", "--threads", "40"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let scene = deepfield::io::read_exr_scene(&dir.join("a.exr")).unwrap().expect("scene");
    assert!(scene.contains("星.png"), "{scene}");
}

#[test]
fn exr_rgb_channels_hold_the_composited_linear_colour() {
    let dir = scratch("cli-exr-rgb");
    write(&dir, "scene.toml", SMALL);
    let o = deepfield(&["render", "scene.toml", "-o", "a.png", "--exr", "a.exr", "--channels", "N,RGB"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = exr::prelude::read_all_flat_layers_from_file(dir.join("a.exr")).unwrap();
    let layer = &img.layer_data[0];
    let names: Vec<String> = layer.channel_data.list.iter().map(|c| c.name.to_string()).collect();
    assert_eq!(names, ["B", "G", "N", "R"]);
    let red = layer.channel_data.list.iter().find(|c| c.name.to_string() == "R").unwrap();
    let exr::prelude::FlatSamples::F16(red) = &red.sample_data else { panic!("R must be half") };
    let png = image::open(dir.join("a.png")).unwrap().to_rgb8();
    for (k, p) in png.pixels().enumerate() {
        let encoded = deepfield::palette::color::linear_to_srgb8(red[k].to_f32());
        assert!(encoded.abs_diff(p[0]) <= 1, "pixel {k}: EXR {encoded} vs PNG {}", p[0]);
    }
}

/// `deepfield find`: the airplane's minibrot (period 3, nucleus -1.7548776662466927...,
/// published) from a view on the antenna, written as a scene that renders; c = i (preperiod
/// 2, period 2) as a Misiurewicz point; and a refusal where nothing is in range.
#[test]
fn find_prints_the_minibrot_or_misiurewicz_point_of_a_view_as_a_scene() {
    let dir = scratch("cli-find");
    let o = deepfield(&["find", "--center=-1.752,0", "--zoom", "100", "-o", "found.toml"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(dir.join("found.toml")).unwrap();
    assert!(text.contains("minibrot of period 3,"), "{text}");
    assert!(text.contains("\"-1.754877666246692760049508896358528"), "{text}");
    let o = deepfield(&["render", "found.toml", "--size", "32x24", "-o", "found.png"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));

    let o = deepfield(&["find", "--center=0.01,1.02", "--zoom", "20", "--misiurewicz"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("preperiod 2 and period 2"), "{text}");

    // At depth the limits follow the view's lowest minibrot period (1282 here).
    let e1086 = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bench-e1086.toml");
    let o = deepfield(&["find", e1086.to_str().unwrap(), "--zoom", "1e30", "--misiurewicz"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("preperiod 283 and period 324"), "{}", stderr(&o));

    let o = deepfield(&["find", "--center=0.5,0.5", "--zoom", "1e6", "--max-period", "40"], &dir);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("no minibrot of period up to 40"), "{}", stderr(&o));
}

/// `deepfield find` on the other formulas: the Burning Ship's period-3 miniship on the real
/// axis (the real slice is z² + c's, so its nucleus is the airplane's,
/// -1.7548776662466927600495088963585286918946...), written as a scene with its formula
/// that renders; a Julia form and Misiurewicz points of a folded family are refused by
/// name, with a non-zero exit.
#[test]
fn find_searches_every_formula_and_refuses_what_does_not_apply() {
    let dir = scratch("cli-find-family");
    write(
        &dir,
        "ship.toml",
        "version = 1\n[formula]\nkind = \"burning-ship\"\n[view]\ncenter = [\"-1.752\", \"0.0005\"]\nzoom = \"100\"\n",
    );
    let o = deepfield(&["find", "ship.toml", "-o", "found.toml"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(dir.join("found.toml")).unwrap();
    assert!(text.contains("mini of period 3,"), "{text}");
    assert!(text.contains("kind = \"burning-ship\""), "{text}");
    assert!(text.contains("\"-1.754877666246692760049508896358528"), "{text}");
    let o = deepfield(&["render", "found.toml", "--size", "32x24", "-o", "found.png"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));

    let o =
        deepfield(&["find", "--formula", "mandelbrot^3", "--center=0.34,1.27", "--zoom", "30", "--misiurewicz"], &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("preperiod 2 and period 1"), "{}", stderr(&o));

    let refused = |args: &[&str], needle: &str| {
        let o = deepfield(args, &dir);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    };
    refused(&["find", "--formula", "burning-ship", "--julia-c=-0.5,0.1"], "burning-ship's Julia form");
    refused(&["find", "ship.toml", "--misiurewicz"], "burning-ship is not conformal");
    refused(&["find", "--formula", "mandelbrot,mandelbrot^3", "--misiurewicz"], "is a hybrid");
}

/// Formula families: bad names and powers are located errors; engines and files built for
/// z² + c alone refuse the others by name, with nothing written.
#[test]
fn formula_families_are_checked_and_refused_where_they_do_not_apply() {
    rejects("bad-family", Some("version = 1\n[formula]\nkind = \"burning-boat\"\n"), &[], "scene.toml:3:8");
    rejects("bad-power", Some("version = 1\n[formula]\nkind = \"buffalo\"\npower = 9\n"), &[], "scene.toml:4:9");
    rejects("bad-power-flag", None, &["--formula", "celtic", "--power", "7"], "powers 2 to 5, not 7");
    // The coefficient a: only with a family that takes one, and finite.
    rejects(
        "a-without-sum",
        Some("version = 1\n[formula]\nkind = \"celtic\"\na = [0.5, 0.0]\n"),
        &[],
        "scene.toml:4:5",
    );
    rejects(
        "a-infinite",
        Some("version = 1\n[formula]\nkind = \"redshift-rider-1\"\na = [inf, 0.0]\n"),
        &[],
        "scene.toml:4:5",
    );
    rejects("a-flag", None, &["--formula", "redshift-rider-4", "--formula-a", "1,x"], "not RE,IM");
    rejects("a-flag-family", None, &["--formula-a", "1,2"], "has none");
    rejects("gpu-family", None, &["--formula", "burning-ship", "--engine", "gpu"], "z^2 + c only, not burning-ship");
    rejects(
        "interior-family",
        Some("version = 1\n[formula]\nkind = \"mandelbar\"\n[render]\ninterior_detection = true\n"),
        &[],
        "z^2 + c only, not mandelbar",
    );
    let dir = scratch("cli-reference-family");
    let o = deepfield(&["reference", "--formula", "burning-ship", "--zoom", "1e20", "-o", "ref.dfr"], &dir);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("formula is burning-ship"), "{}", stderr(&o));
    assert!(outputs(&dir).is_empty(), "left {:?}", outputs(&dir));
    let o = deepfield(&["formulas"], &dir);
    let table = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0));
    for k in deepfield::formula::kind::KINDS {
        assert!(table.lines().any(|l| l.split_whitespace().next() == Some(k.name)), "{} not listed", k.name);
    }
}
