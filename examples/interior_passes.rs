//! One kind of pass over a deep view's samples, repeated: for profilers and instruction
//! counters (`perf record`, valgrind's cachegrind), which see one process, where
//! `interior_cost` alternates several kinds of pass in one.
//!
//! `cargo run --release --example interior_passes -- KIND ROUNDS [CHUNK] [SCENE]`
//!
//! KIND: `all` (every sample, interior detection on), `ext` (the exterior samples alone,
//! detection off) or `exton` (the exterior alone, detection on). The reference orbit and
//! tables are computed first, then one pass of every sample with detection on (it finds
//! the exterior samples; `ROUNDS` 0 counts this setup alone), then `ROUNDS` passes of
//! KIND. Samples run in calls of CHUNK (default 8192) on the thread pool, as renders run
//! them. SCENE defaults to `scenes/minibrot-e102.toml`.
#![allow(clippy::print_stdout)] // printing the measurement is the point
use deepfield::formula::end::{INTERIOR, Orbit};
use deepfield::orbit::interior::Detection;
use deepfield::orbit::{Counters, Perturbation};
use deepfield::render::{self, Options};
use deepfield::scene::Scene;
use deepfield::simd_level::SimdLevel;
use rayon::prelude::*;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

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
/// Iterates `offsets` in parallel calls of `chunk` samples: the orbits, the counters and
/// the seconds.
fn iterate(p: &Perturbation, offsets: &[[f64; 2]], chunk: usize) -> (Vec<Orbit>, Counters, f64) {
    let start = Instant::now();
    let simd = SimdLevel::detect();
    let done: Vec<(Vec<Orbit>, Counters)> = offsets
        .par_chunks(chunk)
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
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let what = args.get(1).map_or("all", String::as_str);
    let rounds: usize = args.get(2).map_or(3, |r| r.parse().expect("ROUNDS"));
    let chunk: usize = args.get(3).map_or(8192, |c| c.parse().expect("CHUNK"));
    let path = args.get(4).map_or("scenes/minibrot-e102.toml", String::as_str);
    let (on, offsets) = engine(&scene(path, Detection::On));
    let (off, _) = engine(&scene(path, Detection::Off));
    let (first, _, _) = iterate(&on, &offsets, chunk);
    let exterior: Vec<[f64; 2]> =
        offsets.iter().zip(&first).filter(|(_, o)| o.n != INTERIOR).map(|(x, _)| *x).collect();
    for _ in 0..rounds {
        let (_, c, s) = match what {
            "all" => iterate(&on, &offsets, chunk),
            "ext" => iterate(&off, &exterior, chunk),
            "exton" => iterate(&on, &exterior, chunk),
            other => panic!("KIND is all, ext or exton, not {other}"),
        };
        println!("{what} {s:.3} s {:.3e} it, {} early, {} disks", c.iterations as f64, c.interior, c.disks);
    }
}
