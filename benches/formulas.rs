//! Throughput of every kind of formula family's kernels, in iterations per second.
//!
//! `cargo bench --bench formulas` prints, per formula, the direct f64 kernel on its
//! Mandelbrot form's whole view (centre 0, zoom 1, 1024x768, 1000 iterations; the sets'
//! interiors run until Brent's check proves them periodic), all threads, every SIMD level
//! this CPU has, the widest first (`direct`), and on the scalar level (`direct_scalar`);
//! `deep` the perturbation engine on a view at zoom 1e30 of the formula's boundary. The
//! "item/s" rows count the iterations the loops performed.

use std::sync::atomic::AtomicBool;

use deepfield::field;
use deepfield::render;
use deepfield::scene::Scene;
use deepfield::simd_level::SimdLevel;
use divan::counter::ItemsCount;
use rayon::prelude::*;

mod common;

fn main() {
    divan::main();
}

/// One formula of each shape: a conformal power, both folds before the power, both after,
/// one after, a conjugate, a fold of one part with a conjugate, a hybrid.
const FORMULAS: [&str; 7] = [
    "mandelbrot^3",
    "burning-ship",
    "buffalo",
    "celtic",
    "mandelbar",
    "perpendicular-burning-ship",
    "burning-ship,mandelbrot^3",
];

/// The formula's scene at this run's size ([`common::side`]).
fn scene(formula: &str, zoom: &str, center: [&str; 2], max_iter: u32) -> Scene {
    let side = |n| common::side(n);
    let text = format!(
        "version = 1\n[formula]\nkind = \"{formula}\"\n[view]\ncenter = [\"{}\", \"{}\"]\nzoom = \"{zoom}\"\nwidth = {}\nheight = {}\n[iteration]\nmax = {max_iter}\n",
        center[0],
        center[1],
        side(1024),
        side(768)
    );
    let file = Scene::parse_file("bench", &text).expect("parses");
    Scene::validate(file, "bench", &text, std::path::Path::new("."), deepfield::io::load_bitmap).expect("valid")
}

/// Computes every sample row in strips of 16 rows in parallel; returns the iterations.
fn run(params: &field::FieldParams) -> u64 {
    let cancel = AtomicBool::new(false);
    let rows = params.grid.height;
    (0..rows.div_ceil(16))
        .into_par_iter()
        .map(|k| field::compute_strip(params, k * 16..((k + 1) * 16).min(rows), &cancel).unwrap().iterations)
        .sum()
}

fn direct_on(bencher: divan::Bencher<'_, '_>, formula: &str, simd: SimdLevel) {
    let scene = scene(formula, "1", ["0", "0"], 1000);
    let mut params = render::field_params(&scene, Default::default());
    params.orbit.simd = simd;
    let iterations = run(&params);
    bencher.counter(ItemsCount::new(iterations)).bench(|| run(&params));
}

#[divan::bench(args = FORMULAS, sample_count = 10)]
fn direct(bencher: divan::Bencher<'_, '_>, formula: &str) {
    direct_on(bencher, formula, SimdLevel::detect());
}

#[divan::bench(args = FORMULAS, sample_count = 5)]
fn direct_scalar(bencher: divan::Bencher<'_, '_>, formula: &str) {
    direct_on(bencher, formula, SimdLevel::Scalar);
}
