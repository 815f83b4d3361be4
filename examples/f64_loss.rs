//! What plain f64 iteration loses at each depth: the table in docs/engine-notes.md.
//!
//! `cargo run --release --example f64_loss [SAMPLES]` renders random pixels of a ladder of
//! zooms centred on the seahorse-valley spiral with the f64 engine (the real render path)
//! and compares them with direct big-float iteration at the exact pixel coordinates
//! (astro-float, the same independent reference the tests use). Prints a Markdown table.
#![allow(clippy::print_stdout)] // printing the measurement is the point

use std::sync::atomic::AtomicBool;

use deepfield::field::{self, ChannelSet};
use deepfield::formula::end::INTERIOR;
use deepfield::scene::Scene;

#[path = "../tests/integration/reference.rs"]
#[allow(dead_code)]
mod reference;

const CENTER: [&str; 2] = ["-0.743643887037158704752191506114774", "0.131825904205311970493132056385139"];

fn main() {
    let samples: u32 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(400);
    println!(
        "| zoom | pixels | N differs | NF error median | NF error max | distance error median | distance error p99 |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (zoom, radius) in
        [("1e2", "2e-2"), ("1e4", "2e-4"), ("1e6", "2e-6"), ("1e8", "2e-8"), ("1e10", "2e-10"), ("1e11", "2e-11")]
    {
        let text = format!(
            "version = 1\n[view]\ncenter = [\"{}\", \"{}\"]\nradius = \"{radius}\"\nwidth = 640\nheight = 480\n[iteration]\nmax = 20000\n",
            CENTER[0], CENTER[1]
        );
        let file = Scene::parse_file("ladder", &text).unwrap();
        let scene =
            Scene::validate(file, "ladder", &text, std::path::Path::new("."), deepfield::io::load_bitmap).unwrap();
        let params = deepfield::render::field_params(&scene, ChannelSet::default_exr());
        let spacing = params.grid.spacing();
        let ln_r = params.orbit.escape_radius.ln();
        let mut seed = 12345u64;
        let mut next = |n: u32| {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 33) % n as u64) as u32
        };
        let (mut compared, mut differ) = (0, 0);
        let (mut nf, mut de) = (Vec::new(), Vec::new());
        for _ in 0..samples {
            let (i, j) = (next(640), next(480));
            let planes = field::compute_strip(&params, j..j + 1, &AtomicBool::new(false)).unwrap().planes;
            let p = reference::pixel(CENTER, radius, 640, 480, i, j, 384);
            let t = reference::orbit(&p, None, 20000, params.orbit.escape_radius, 384);
            if t.near_circle {
                continue;
            }
            compared += 1;
            let k = i as usize;
            let n = planes.n[k];
            if t.n != (n != INTERIOR).then_some(n) {
                differ += 1;
                continue;
            }
            if n == INTERIOR {
                continue;
            }
            let lnz = 0.5 * (t.z[0] * t.z[0] + t.z[1] * t.z[1]).ln();
            nf.push((planes.nf[k] as f64 - (1.0 - (lnz / ln_r).log2()).clamp(0.0, 1.0)).abs());
            let az = t.z[0].hypot(t.z[1]);
            let d_true = az * az.ln() / t.dz[0].hypot(t.dz[1]) / spacing;
            de.push(((planes.dex[k] as f64).hypot(planes.dey[k] as f64) - d_true).abs() / d_true);
        }
        let q = |v: &mut Vec<f64>, f: f64| {
            v.sort_by(|a, b| a.total_cmp(b));
            if v.is_empty() { 0.0 } else { v[((v.len() - 1) as f64 * f) as usize] }
        };
        println!(
            "| {zoom} | {compared} | {:.2}% | {:.1e} | {:.1e} | {:.1e} | {:.1e} |",
            100.0 * differ as f64 / compared as f64,
            q(&mut nf, 0.5),
            q(&mut nf, 1.0),
            q(&mut de, 0.5),
            q(&mut de, 0.99)
        );
    }
}
