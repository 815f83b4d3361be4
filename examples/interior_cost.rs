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

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use deepfield::formula::end::{INTERIOR, Orbit};
use deepfield::orbit::interior::Detection;
use deepfield::orbit::{Counters, Perturbation};
use deepfield::render::{self, Options};
use deepfield::scene::Scene;
use deepfield::simd_level::SimdLevel;
use rayon::prelude::*;

fn scene(path: &str, detection: Detection) -> Scene {
    let text = std::fs::read_to_string(path).expect("scene file");
    let file = Scene::parse_file(path, &text).expect("parses");
    let dir = std::path::Path::new(path).parent().unwrap_or(std::path::Path::new("."));
    let mut s = Scene::validate(file, path, &text, dir, deepfield::io::load_bitmap).expect("valid");
    s.interior_detection = detection;
    s
}

/// The deep engine of `s` and every sample's offset.
fn engine(s: &Scene) -> (Perturbation, Vec<[f64; 2]>) {
    let cancel = AtomicBool::new(false);
    let plan = deepfield::render::engine::plan(s).expect("engine");
    let (params, _) = render::prepare_field(s, &plan, Options::default(), &cancel, &|_| {}).expect("prepared");
    let deep = params.deep.expect("a deep view");
    let g = &params.grid;
    let offsets = (0..g.height).flat_map(|j| (0..g.width).map(move |i| g.offset(i, j))).collect();
    (std::sync::Arc::into_inner(deep).expect("one owner"), offsets)
}

/// Iterates `offsets` in parallel chunks: the orbits, the counters and the seconds.
fn iterate(p: &Perturbation, offsets: &[[f64; 2]]) -> (Vec<Orbit>, Counters, f64) {
    let start = Instant::now();
    let simd = SimdLevel::detect();
    let done: Vec<(Vec<Orbit>, Counters)> = offsets
        .par_chunks(8192)
        .map(|chunk| {
            let mut out = vec![Orbit::interior(); chunk.len()];
            let mut c = Counters::default();
            p.orbits(chunk, &mut out, &mut c, simd, &deepfield::cancel::NEVER);
            (out, c)
        })
        .collect();
    let seconds = start.elapsed().as_secs_f64();
    let mut counters = Counters::default();
    let mut orbits = Vec::with_capacity(offsets.len());
    for (o, c) in done {
        orbits.extend(o);
        counters.add(&c);
    }
    (orbits, counters, seconds)
}

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
    let (on, offsets) = engine(&scene(path, Detection::On));
    let (off, _) = engine(&scene(path, Detection::Off));
    println!("{path}: {} samples, SIMD {}", offsets.len(), SimdLevel::detect().describe());
    let (first, c, seconds) = iterate(if quick { &on } else { &off }, &offsets);
    report(if quick { "all samples, detection on" } else { "all samples, detection off" }, &c, seconds);
    let exterior: Vec<[f64; 2]> =
        offsets.iter().zip(&first).filter(|(_, o)| o.n != INTERIOR).map(|(x, _)| *x).collect();
    println!("exterior: {} samples ({:.1}%)", exterior.len(), 100.0 * exterior.len() as f64 / offsets.len() as f64);
    for _ in 0..rounds {
        let (orbits, c, seconds) = iterate(&on, &offsets);
        report("all samples, detection on", &c, seconds);
        let same = orbits.iter().zip(&first).all(|(a, b)| a.n == b.n);
        assert!(same, "detection on and off give different N");
        if !quick {
            let (_, c, seconds) = iterate(&off, &offsets);
            report("all samples, detection off", &c, seconds);
        }
        let (_, c, seconds) = iterate(&off, &exterior);
        report("exterior alone, detection off", &c, seconds);
        let (_, c, seconds) = iterate(&on, &exterior);
        report("exterior alone, detection on", &c, seconds);
    }
}
