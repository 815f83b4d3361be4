//! `deepfield compare --peer`: another program's raw EXR scored at the same sampled pixels
//! as the engines. The peer here is deepfield's own EXR of the view rewritten as
//! Fraktaler-3 and fractall-rust write theirs (N biased by 1024, the bias in an
//! `IterationsBias` attribute), so its row must equal the engine's that made it; a peer off
//! by one iteration everywhere must be wrong everywhere; a malformed `--peer` and a file of
//! another size are refused by name.

use std::path::Path;
use std::process::{Command, Output};

use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec, Text,
    WritableImage,
};

use super::util::scratch;

const SCENE: &str = "version = 1\n[view]\ncenter = [\"-0.75\", \"0.1\"]\nzoom = \"2\"\nwidth = 64\nheight = 48\n";

fn deepfield(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_deepfield")).args(args).current_dir(dir).output().expect("run deepfield")
}

/// Writes `n` (plus `shift` where it escaped, then biased by 1024) and `nf` as a peer's
/// EXR of `width` × `height` samples.
fn write_peer(path: &Path, (width, height): (usize, usize), n: &[u32], nf: &[f32], shift: u32) {
    let biased: Vec<u32> = n.iter().map(|&v| if v == u32::MAX { v } else { v + shift + 1024 }).collect();
    let mut attrs = LayerAttributes::default();
    attrs.other.insert(Text::from("IterationsBias"), AttributeValue::I32(1024));
    let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    channels.push(AnyChannel::new("N", FlatSamples::U32(biased)));
    channels.push(AnyChannel::new("NF", FlatSamples::F32(nf.to_vec())));
    let layer = Layer::new((width, height), attrs, Encoding::UNCOMPRESSED, AnyChannels::sort(channels));
    Image::from_layer(layer).write().to_file(path).expect("peer EXR written");
}

fn rows(o: &Output) -> Vec<serde_json::Value> {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap().as_array().unwrap().clone()
}

#[test]
fn a_peers_values_are_scored_beside_the_engine_that_made_them() {
    let dir = scratch("peer");
    std::fs::write(dir.join("scene.toml"), SCENE).unwrap();
    let o =
        deepfield(&["render", "scene.toml", "--engine", "f64", "--exr", "own.exr", "--channels", "N,NF", "-q"], &dir);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let raw = deepfield::io::read_exr_planes(&dir.join("own.exr"), usize::MAX).unwrap();
    let (n, nf): (Vec<u32>, Vec<f32>) =
        (raw.strips.iter().flat_map(|s| s.n.clone()).collect(), raw.strips.iter().flat_map(|s| s.nf.clone()).collect());
    assert!(n.contains(&u32::MAX) && n.iter().any(|&v| v != u32::MAX), "interior and exterior in view");
    write_peer(&dir.join("peer.exr"), (64, 48), &n, &nf, 0);
    write_peer(&dir.join("late.exr"), (64, 48), &n, &nf, 1);
    let args = ["compare", "scene.toml", "--samples", "60", "--only", "f64", "--json"];
    let o = deepfield(&[&args[..], &["--peer", "same=peer.exr", "--peer", "late=late.exr"]].concat(), &dir);
    let rows = rows(&o);
    let row = |name: &str| rows.iter().find(|r| r["engine"] == name).unwrap_or_else(|| panic!("{name} in {rows:?}"));
    let (engine, same, late) = (row("f64"), row("peer same"), row("peer late"));
    for key in ["n_mismatch_fraction", "nf_error_p50", "nf_error_p99", "compared"] {
        assert_eq!(same[key], engine[key], "{key}: {same} against {engine}");
    }
    assert_eq!(engine["n_mismatch_fraction"], 0.0, "{engine}");
    // Every escaping sample one iteration late: every compared escaping pixel is wrong.
    assert!(late["n_mismatch_fraction"].as_f64().unwrap() > 0.5, "{late}");
    // No time and no distance estimate of a peer's: null in JSON, "-" in the table.
    assert!(same["seconds"].is_null() && same["de_error_p99"].is_null() && same["de_scored"] == 0, "{same}");
    let o = deepfield(&["compare", "scene.toml", "--samples", "5", "--only", "f64", "--peer", "same=peer.exr"], &dir);
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text.lines().find(|l| l.starts_with("peer same")).unwrap_or_else(|| panic!("{text}"));
    assert!(line.split_whitespace().nth(2) == Some("-"), "{text}");
}

#[test]
fn a_peer_that_does_not_fit_is_refused_by_name() {
    let dir = scratch("peer-bad");
    std::fs::write(dir.join("scene.toml"), SCENE).unwrap();
    write_peer(&dir.join("small.exr"), (32, 24), &[1; 32 * 24], &[0.5; 32 * 24], 0);
    for (spec, needle) in [
        ("small.exr", "expected NAME=FILE"),
        ("x=small.exr", "--peer x: small.exr: it holds 32x24 samples, the view 64x48"),
        ("x=missing.exr", "missing.exr"),
    ] {
        let o = deepfield(&["compare", "scene.toml", "--samples", "5", "--only", "f64", "--peer", spec], &dir);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{spec}: {err}");
        assert!(err.contains(needle), "{spec}: expected `{needle}` in {err}");
    }
}
