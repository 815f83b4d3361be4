//! Recolouring speed (`deepfield::render::recolor_rgb8`, what `deepfield recolor` runs for
//! 8-bit output): raw planes already in memory -> 8-bit sRGB output bytes, at
//! 3840x2160 (one sample per pixel), the target being under 0.3 s on 2 cores.
//!
//! The planes are those of `scenes/seahorse-valley.toml`'s view rendered at 3840x2160 with
//! 1000 iterations (computed once, before timing). `cargo bench --bench recolor` times:
//! - `smooth`: one smooth-iteration layer (the default look);
//! - `seahorse_stack`: that scene's two layers (smooth with log transfer, soft distance
//!   multiplied at 60%), which composite through tiny-skia;
//! - `histogram`: histogram equalisation (sorts every escape count first).

use std::sync::OnceLock;
use std::sync::atomic::AtomicBool;

use deepfield::field::{self, Planes};
use deepfield::io::PngEncoder;
use deepfield::scene::Scene;
use divan::counter::ItemsCount;
use rayon::prelude::*;

mod common;

fn main() {
    divan::main();
}

/// Seahorse valley at 3840x2160 when measuring.
fn view() -> String {
    let (w, h) = (common::side(3840), common::side(2160));
    format!(
        "version = 1\n[view]\ncenter = [\"-0.74515\", \"0.11255\"]\nzoom = \"3600\"\nwidth = {w}\nheight = {h}\n[iteration]\nmax = 1000\n"
    )
}

fn scene(layers: &str) -> Scene {
    let text = format!("{}{layers}", view());
    let file = Scene::parse_file("bench", &text).expect("parses");
    Scene::validate(file, "bench", &text, std::path::Path::new("."), deepfield::io::load_bitmap).expect("valid")
}

/// The planes every colouring may read (N, NF, T, DE), 32-row strips.
fn planes() -> &'static [Planes] {
    static P: OnceLock<Vec<Planes>> = OnceLock::new();
    P.get_or_init(|| {
        let s = scene("[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"distance\"\n[[layer]]\nkind = \"angle\"\n");
        let params = deepfield::render::field_params(&s, Default::default());
        let cancel = AtomicBool::new(false);
        (0..s.height.div_ceil(32))
            .into_par_iter()
            .map(|k| field::compute_strip(&params, k * 32..((k + 1) * 32).min(s.height), &cancel).unwrap().planes)
            .collect()
    })
}

fn bench_layers(bencher: divan::Bencher<'_, '_>, layers: &str) {
    let s = scene(layers);
    let planes = planes();
    // The bytes are those of the general path (linear pixels, then encoded): checked here.
    let enc = PngEncoder::new(8);
    let slow: Vec<Vec<u8>> = deepfield::render::recolor(&s.stack, planes, 1)
        .expect("planes of the scene")
        .par_iter()
        .map(|p| enc.encode(p))
        .collect();
    assert!(
        slow == deepfield::render::recolor_rgb8(&s.stack, planes, 1).expect("planes of the scene"),
        "fast path differs"
    );
    bencher
        .counter(ItemsCount::new((s.width * s.height) as u64))
        .bench(|| deepfield::render::recolor_rgb8(&s.stack, planes, 1));
}

/// One smooth-iteration layer.
#[divan::bench(sample_count = 10)]
fn smooth(bencher: divan::Bencher<'_, '_>) {
    bench_layers(bencher, "[[layer]]\nkind = \"smooth\"\npalette = \"classic\"\ntransfer = \"log\"\ndensity = 0.5\n");
}

/// The seahorse scene's stack: smooth + soft distance (multiply, 60%).
#[divan::bench(sample_count = 10)]
fn seahorse_stack(bencher: divan::Bencher<'_, '_>) {
    bench_layers(
        bencher,
        "[[layer]]\nkind = \"smooth\"\npalette = \"classic\"\ntransfer = \"log\"\ndensity = 0.5\n[[layer]]\nkind = \"distance\"\nk = 0.5\nblend = \"multiply\"\nopacity = 0.6\n",
    );
}

/// Histogram equalisation.
#[divan::bench(sample_count = 10)]
fn histogram(bencher: divan::Bencher<'_, '_>) {
    bench_layers(bencher, "[[layer]]\nkind = \"histogram\"\n");
}
