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

use deepfield::formula::end::INTERIOR;
use deepfield::orbit::interior::Detection;

#[path = "support/deep_view.rs"]
mod deep_view;
use deep_view::{engine, iterate, scene};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let what = args.get(1).map_or("all", String::as_str);
    let rounds: usize = args.get(2).map_or(3, |r| r.parse().expect("ROUNDS"));
    let chunk: usize = args.get(3).map_or(8192, |c| c.parse().expect("CHUNK"));
    let path = args.get(4).map_or("scenes/minibrot-e102.toml", String::as_str);
    let (on, offsets, _) = engine(&scene(path, Detection::On));
    let (off, _, _) = engine(&scene(path, Detection::Off));
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
