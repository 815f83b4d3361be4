//! The perturbation engine on the public benchmark locations, at 800x600 (the size rust-fractal-core's own benchmark files use)
//! its targets (liiiines < 1 s, bench-e50 < 2 s on two cores).
//!
//! `cargo bench --bench deep` times the whole raw-data computation of each scene: reference
//! orbit, BLA tables and every sample (no colouring, no files); the "item/s" rows are
//! iterations the samples advanced, BLA-skipped ones included. `deepfield render
//! scenes/NAME.toml --stats` gives the same figures with colouring and output.

use std::sync::atomic::AtomicBool;

use deepfield::field;
use deepfield::render;
use deepfield::scene::Scene;
use divan::counter::ItemsCount;
use rayon::prelude::*;

mod common;

fn main() {
    divan::main();
}

fn scene(name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    let text = std::fs::read_to_string(&path).expect("scene");
    let file = Scene::parse_file(name, &text).expect("parses");
    Scene::validate(file, name, &text, path.parent().unwrap(), deepfield::io::load_bitmap).expect("valid")
}

/// Reference, tables and every sample row, in parallel strips of 16 rows.
fn run(scene: &Scene) -> u64 {
    let cancel = AtomicBool::new(false);
    let plan = deepfield::render::engine::plan(scene).expect("engine");
    let (params, _) =
        render::prepare_field(scene, &plan, render::Options::default(), &cancel, &|_| {}).expect("prepared");
    let rows = params.grid.height;
    let strip = |k: u32| field::compute_strip(&params, k * 16..((k + 1) * 16).min(rows), &cancel).unwrap().iterations;
    (0..rows.div_ceil(16)).into_par_iter().map(strip).sum()
}

fn bench_scene(bencher: divan::Bencher<'_, '_>, name: &str) {
    let mut s = scene(name);
    (s.width, s.height) = (common::side(s.width), common::side(s.height));
    let iterations = run(&s);
    bencher.counter(ItemsCount::new(iterations)).bench(|| run(&s));
}

/// Zoom 3.16e321, 12500 iterations, smooth + distance (target < 1 s).
#[divan::bench(sample_count = 5, sample_size = 1)]
fn liiiines(bencher: divan::Bencher<'_, '_>) {
    bench_scene(bencher, "liiiines.toml");
}

/// Zoom 1e50, 263010 iterations (target < 2 s).
#[divan::bench(sample_count = 3, sample_size = 1)]
fn bench_e50(bencher: divan::Bencher<'_, '_>) {
    bench_scene(bencher, "bench-e50.toml");
}

/// Zoom 1e14, 4036 iterations.
#[divan::bench(sample_count = 5, sample_size = 1)]
fn bench_e14(bencher: divan::Bencher<'_, '_>) {
    bench_scene(bencher, "bench-e14.toml");
}
