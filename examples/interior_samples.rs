//! Each sample of a deep view iterated alone, with interior detection on: which interior
//! samples run to the iteration limit (detection stops none of them), which stop early
//! only after long work, and what each kind costs. A sample alone gets no certified disk
//! (`Perturbation::orbits` tiles a call's samples with them), so the interior costs more
//! here than in a render; what it shows is where single samples spend their time.
//!
//! `cargo run --release --example interior_samples -- [SCENE]` (default
//! `scenes/minibrot-e102.toml`): one line per sample at the limit (pixel, iterations,
//! seconds), the 30 slowest of those stopped early, and the sums of thread time.
#![allow(clippy::print_stdout)] // printing the measurement is the point
use std::time::Instant;

use deepfield::formula::end::{INTERIOR, Orbit};
use deepfield::orbit::Counters;
use deepfield::orbit::interior::Detection;
use deepfield::simd_level::SimdLevel;
use rayon::prelude::*;

#[path = "support/deep_view.rs"]
#[allow(dead_code)]
mod deep_view;
use deep_view::{engine, scene};

fn main() {
    let path = std::env::args().nth(1).unwrap_or("scenes/minibrot-e102.toml".into());
    let (on, offsets, w) = engine(&scene(&path, Detection::On));
    let simd = SimdLevel::detect();
    let per: Vec<(usize, u32, u64, u64, f64)> = offsets
        .par_iter()
        .enumerate()
        .map(|(k, x)| {
            let mut out = vec![Orbit::interior(); 1];
            let mut c = Counters::default();
            let t = Instant::now();
            on.orbits(std::slice::from_ref(x), &mut out, &mut c, simd, &deepfield::cancel::NEVER);
            (k, out[0].n, c.iterations, c.interior, t.elapsed().as_secs_f64())
        })
        .collect();
    let mut limit = 0;
    let mut tot_ext = 0.0;
    let mut tot_int = 0.0;
    let mut tot_lim = 0.0;
    let mut tot_early_slow = 0.0;
    let mut slow = Vec::new();
    for &(k, n, it, early, s) in &per {
        if n != INTERIOR {
            tot_ext += s;
        } else {
            tot_int += s;
            if early == 0 {
                limit += 1;
                tot_lim += s;
                println!(
                    "limit sample {k}: pixel ({}, {}) iterations {it} {s:.4} s offset {:?}",
                    k % w,
                    k / w,
                    offsets[k]
                );
            } else if s > 1e-4 {
                tot_early_slow += s;
                slow.push((s, k, it));
            }
        }
    }
    slow.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
    for (s, k, it) in slow.iter().take(30) {
        println!("stopped early {k}: pixel ({}, {}) iterations {it} {s:.4} s", k % w, k / w);
    }
    println!(
        "thread time of samples alone: exterior {tot_ext:.3} s, interior {tot_int:.3} s, of it {limit} samples \
         at the limit {tot_lim:.3} s and {} stopped early after more than 0.1 ms {tot_early_slow:.3} s",
        slow.len()
    );
}
