//! Single-thread kernel speed (N only) on one view, best of 15 runs:
//! `cargo run --release --example kernel_speed -- CX CY RADIUS MAX_ITER`.
#![allow(clippy::print_stdout)] // printing the measurement is the point
use std::sync::atomic::AtomicBool;

use deepfield::field::{self, FieldParams, Needs, SampleGrid};
use deepfield::formula::Family;

fn main() {
    let a: Vec<f64> = std::env::args().skip(1).map(|s| s.parse().expect("number")).collect();
    let [cx, cy, radius, max_iter] = a[..] else { panic!("CX CY RADIUS MAX_ITER") };
    let grid = SampleGrid {
        center: [cx, cy],
        radius,
        width: 640,
        height: 480,
        transform: Default::default(),
        projection: Default::default(),
    };
    let p = FieldParams::new(Family::Mandelbrot, max_iter as u32, 65536.0, Needs::default(), grid);
    let cancel = AtomicBool::new(false);
    let mut best = 0.0f64;
    let mut per_sample = 0.0;
    let reps: usize = std::env::var("REPS").ok().and_then(|r| r.parse().ok()).unwrap_or(15);
    for _ in 0..reps {
        let t = std::time::Instant::now();
        let its: u64 =
            (0..30).map(|k| field::compute_strip(&p, k * 16..k * 16 + 16, &cancel).unwrap().iterations).sum();
        best = best.max(its as f64 / t.elapsed().as_secs_f64());
        per_sample = its as f64 / (640.0 * 480.0);
    }
    println!("{:.3} G iterations/s (one thread), {per_sample:.0} iterations per sample", best / 1e9);
}
