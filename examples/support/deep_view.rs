//! What the interior-detection examples share: a scene read with interior detection set,
//! its deep engine with every sample's offset, and the samples iterated in parallel calls
//! as renders make them.

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use deepfield::formula::end::Orbit;
use deepfield::orbit::interior::Detection;
use deepfield::orbit::{Counters, Perturbation};
use deepfield::render::{self, Options};
use deepfield::scene::Scene;
use deepfield::simd_level::SimdLevel;
use rayon::prelude::*;

/// The scene at `path` with interior detection set to `detection`.
pub fn scene(path: &str, detection: Detection) -> Scene {
    let text = std::fs::read_to_string(path).expect("scene file");
    let file = Scene::parse_file(path, &text).expect("parses");
    let dir = std::path::Path::new(path).parent().unwrap_or(std::path::Path::new("."));
    let mut s = Scene::validate(file, path, &text, dir, deepfield::io::load_bitmap).expect("valid");
    s.interior_detection = detection;
    s
}

/// The deep engine of `s`, every sample's offset (row by row) and the grid's width.
pub fn engine(s: &Scene) -> (Perturbation, Vec<[f64; 2]>, usize) {
    let cancel = AtomicBool::new(false);
    let plan = deepfield::render::engine::plan(s).expect("engine");
    let (params, _) = render::prepare_field(s, &plan, Options::default(), &cancel, &|_| {}).expect("prepared");
    let deep = params.deep.expect("a deep view");
    let g = &params.grid;
    let offsets = (0..g.height).flat_map(|j| (0..g.width).map(move |i| g.offset(i, j))).collect();
    (std::sync::Arc::into_inner(deep).expect("one owner"), offsets, g.width as usize)
}

/// Iterates `offsets` in parallel calls of `chunk` samples on the thread pool: the orbits,
/// the counters and the seconds.
pub fn iterate(p: &Perturbation, offsets: &[[f64; 2]], chunk: usize) -> (Vec<Orbit>, Counters, f64) {
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
