//! Kernel throughput: iterations per second of the f64 kernels on the seahorse valley view
//! (no interior, so every iteration counted is one the loop really performed).
//!
//! `cargo bench --bench kernels` prints time per call and iterations per second
//! ("item/s"). The `smooth_only` vs `with_distance` vs `with_trap` rows show what the
//! derivative and traps cost, and so that a scene which does not ask for them does not pay.

use std::sync::atomic::AtomicBool;

use deepfield::field::{self, FieldParams, Needs, SampleGrid};
use deepfield::formula::Family;
use deepfield::trap::{Shape, Trap};
use divan::counter::ItemsCount;
use rayon::prelude::*;

fn main() {
    divan::main();
}

const W: u32 = 640;
const H: u32 = 480;

fn seahorse(needs: Needs) -> FieldParams {
    let grid = SampleGrid { center: [-0.743643887037151, 0.131825904205330], radius: 2e-6, width: W, height: H };
    FieldParams::new(Family::Mandelbrot, 5000, 65536.0, needs, grid)
}

fn run(params: &FieldParams, parallel: bool) -> u64 {
    let cancel = AtomicBool::new(false);
    let strip = |k: u32| field::compute_strip(params, k * 8..(k + 1) * 8, &cancel).unwrap().iterations;
    if parallel { (0..H / 8).into_par_iter().map(strip).sum() } else { (0..H / 8).map(strip).sum() }
}

fn bench_with(bencher: divan::Bencher<'_, '_>, needs: Needs, parallel: bool) {
    let params = seahorse(needs);
    let iterations = run(&params, parallel);
    bencher.counter(ItemsCount::new(iterations)).bench(|| run(&params, parallel));
}

/// N only, all threads: the headline figure.
#[divan::bench(sample_count = 10)]
fn n_only_parallel(bencher: divan::Bencher<'_, '_>) {
    bench_with(bencher, Needs::default(), true);
}

/// N only, one thread.
#[divan::bench(sample_count = 10)]
fn n_only_one_thread(bencher: divan::Bencher<'_, '_>) {
    bench_with(bencher, Needs::default(), false);
}

/// N and NF (smooth colouring): no derivative, no traps.
#[divan::bench(sample_count = 10)]
fn smooth_only(bencher: divan::Bencher<'_, '_>) {
    bench_with(bencher, Needs { nf: true, ..Needs::default() }, true);
}

/// Smooth iteration plus the distance estimate (derivative tracked).
#[divan::bench(sample_count = 10)]
fn with_distance(bencher: divan::Bencher<'_, '_>) {
    bench_with(bencher, Needs { nf: true, de: true, ..Needs::default() }, true);
}

/// Smooth iteration plus a geometric point trap (scalar kernel).
#[divan::bench(sample_count = 10)]
fn with_trap(bencher: divan::Bencher<'_, '_>) {
    let trap = Trap::Geometric(Shape::Point { at: [0.0, 0.0] });
    bench_with(bencher, Needs { nf: true, traps: vec![trap], ..Needs::default() }, true);
}
