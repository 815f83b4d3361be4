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
