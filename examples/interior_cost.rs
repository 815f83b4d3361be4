//! What interior detection saves on a deep view: the seconds its samples take with
//! detection on and off, against the seconds of its exterior samples alone (the target:
//! a view with interior should cost about what its exterior costs).
//!
//! `cargo run --release --example interior_cost -- scenes/minibrot-e102.toml [ROUNDS] [--quick]`
//!
//! The reference orbit and BLA tables are computed once per setting, outside the timings.
//! A first pass with detection off finds the exterior samples (N below the limit); then,
//! ROUNDS times (default 3), alternating: every sample with detection on, every sample with
//! detection off, and the exterior samples alone with detection off and on. Samples run in
//! chunks of 8192 on the thread pool (one thread per core), as renders run them. Prints
//! seconds and iterations of each, and checks that both settings give the same N.
//! `--quick` leaves out every run of all samples with detection off (minutes at a limit of
//! 10^7) and finds the exterior samples with detection on instead.
#![allow(clippy::print_stdout)] // printing the measurement is the point

use deepfield::formula::end::INTERIOR;
use deepfield::orbit::Counters;
use deepfield::orbit::interior::Detection;
use deepfield::simd_level::SimdLevel;

#[path = "support/deep_view.rs"]
mod deep_view;
use deep_view::{engine, iterate, scene};

/// Samples per call, as renders make them.
const CHUNK: usize = 8192;

fn report(what: &str, c: &Counters, seconds: f64) {
    println!(
        "{what:<32} {seconds:>9.3} s  {:>10.3e} iterations  {:>8} stopped early ({} in disks)",
        c.iterations as f64, c.interior, c.disks
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).map_or("scenes/minibrot-e102.toml", String::as_str);
    let rounds: u32 = args.get(2).filter(|a| *a != "--quick").map_or(3, |r| r.parse().expect("ROUNDS"));
    let quick = args.iter().any(|a| a == "--quick");
    let (on, offsets, _) = engine(&scene(path, Detection::On));
    let (off, _, _) = engine(&scene(path, Detection::Off));
    println!("{path}: {} samples, SIMD {}", offsets.len(), SimdLevel::detect().describe());
    let (first, c, seconds) = iterate(if quick { &on } else { &off }, &offsets, CHUNK);
    report(if quick { "all samples, detection on" } else { "all samples, detection off" }, &c, seconds);
    let exterior: Vec<[f64; 2]> =
        offsets.iter().zip(&first).filter(|(_, o)| o.n != INTERIOR).map(|(x, _)| *x).collect();
    println!("exterior: {} samples ({:.1}%)", exterior.len(), 100.0 * exterior.len() as f64 / offsets.len() as f64);
    for _ in 0..rounds {
        let (orbits, c, seconds) = iterate(&on, &offsets, CHUNK);
        report("all samples, detection on", &c, seconds);
        let same = orbits.iter().zip(&first).all(|(a, b)| a.n == b.n);
        assert!(same, "detection on and off give different N");
        if !quick {
            let (_, c, seconds) = iterate(&off, &offsets, CHUNK);
            report("all samples, detection off", &c, seconds);
        }
        let (_, c, seconds) = iterate(&off, &exterior, CHUNK);
        report("exterior alone, detection off", &c, seconds);
        let (_, c, seconds) = iterate(&on, &exterior, CHUNK);
        report("exterior alone, detection on", &c, seconds);
    }
}
