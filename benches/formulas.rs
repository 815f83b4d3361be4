//! Throughput of every kind of formula family's kernels, in iterations per second.
//!
//! `cargo bench --bench formulas` prints, per formula, the direct f64 kernel on its
//! Mandelbrot form's whole view (centre 0, zoom 1, 1024x768, 1000 iterations; the sets'
//! interiors run until Brent's check proves them periodic), all threads, every SIMD level
//! this CPU has, the widest first (`direct`), and on the scalar level (`direct_scalar`).
//! The "item/s" rows count the iterations the loops performed.
//!
//! `family_direct`, `family_single_steps` and `family_bla` do it for every family at every
//! power (but z² + c): the direct kernel as above (widest level), and the perturbation
//! engine (f64 deltas) on a view of the family's boundary at zoom about 1e30 found by the
//! deep fuzzer's generator, with BLA off (every iteration a single step) and on.

use std::sync::atomic::AtomicBool;
use std::sync::{Mutex, OnceLock};

use deepfield::compare::views::{self, ViewKind, ViewSpec};
use deepfield::field::{self, FieldParams, Needs};
use deepfield::formula::Formula;
use deepfield::formula::kind::{KINDS, Kind};
use deepfield::orbit::interior::Detection;
use deepfield::render;
use deepfield::scene::{EngineChoice, Scene};
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
fn run(params: &FieldParams) -> u64 {
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

/// Every family of [`KINDS`] at every power it comes in, but z² + c (`mandelbrot` at power
/// 2, whose own kernels `cargo bench --bench kernels` measures): the per-family table of
/// `docs/performance.md`. (The names are made once per run and live as long as it.)
fn families() -> Vec<&'static str> {
    static NAMES: OnceLock<Vec<&'static str>> = OnceLock::new();
    NAMES
        .get_or_init(|| {
            let mut out = Vec::new();
            for k in &KINDS {
                for p in k.min_power..=k.max_power {
                    if k.kind == Kind::Mandelbrot && p == 2 {
                        continue;
                    }
                    let name = if p == k.kind.default_power() { k.name.to_string() } else { format!("{}^{p}", k.name) };
                    out.push(&*Box::leak(name.into_boxed_str()));
                }
            }
            out
        })
        .clone()
}

#[divan::bench(args = families(), sample_count = 5)]
fn family_direct(bencher: divan::Bencher<'_, '_>, formula: &str) {
    direct_on(bencher, formula, SimdLevel::detect());
}

/// A view of `formula`'s boundary at zoom about 1e30 (1e7 when only checking), 256×192
/// samples, found by the deep fuzzer's generator (`compare::views`, a random descent of the
/// boundary in big floats from the whole plane) with a fixed seed, so that every run
/// measures the same view; made once per formula and kept for both deep benches.
fn deep_view(formula: &str) -> Scene {
    static VIEWS: Mutex<Vec<(String, Scene)>> = Mutex::new(Vec::new());
    if let Some((_, s)) = VIEWS.lock().unwrap().iter().find(|(f, _)| f == formula) {
        return s.clone();
    }
    let measuring = common::measuring();
    let spec = ViewSpec {
        kind: ViewKind::Boundary,
        log10_zoom: if measuring { 30.0 } else { 7.0 },
        max_iter: if measuring { 20_000 } else { 3_000 },
        width: common::side(256),
        height: common::side(192),
        formula: Formula::parse(formula, None).expect("a family"),
    };
    let view = (0..40)
        .find_map(|draw| views::generate(7, draw, &spec))
        .unwrap_or_else(|| panic!("no boundary view of {formula} in 40 draws"));
    VIEWS.lock().unwrap().push((formula.to_string(), view.scene.clone()));
    view.scene
}

/// The field parameters of `formula`'s deep view through the perturbation engine with f64
/// deltas, N only, interior detection off, BLA at the default tolerance or (`bla` false)
/// off: then every iteration is a single step (in the vector lanes, but for rebases).
fn deep_params(formula: &str, bla: bool) -> FieldParams {
    let mut scene = deep_view(formula);
    scene.engine = EngineChoice::PerturbF64;
    scene.interior_detection = Detection::Off;
    if !bla {
        scene.bla = None;
    }
    scene.stack.layers.truncate(1);
    let plan = render::engine::plan(&scene).expect("perturbation addresses the view");
    let cancel = AtomicBool::new(false);
    let (mut params, _) =
        render::prepare_field(&scene, &plan, render::Options::default(), &cancel, &|_| {}).expect("prepared");
    assert!(params.deep_generic.is_some(), "{formula} runs the generic perturbation engine");
    params.needs = Needs::default();
    params
}

fn deep_on(bencher: divan::Bencher<'_, '_>, formula: &str, bla: bool) {
    let params = deep_params(formula, bla);
    let iterations = run(&params);
    bencher.counter(ItemsCount::new(iterations)).bench(|| run(&params));
}

/// The perturbation engine's single steps per second on `formula`'s deep view, both threads.
#[divan::bench(args = families(), sample_count = 5)]
fn family_single_steps(bencher: divan::Bencher<'_, '_>, formula: &str) {
    deep_on(bencher, formula, false);
}

/// The same view with BLA (ε = 1e-14): iterations per second, the steps BLA merges counted
/// as the iterations they stand for.
#[divan::bench(args = families(), sample_count = 5)]
fn family_bla(bencher: divan::Bencher<'_, '_>, formula: &str) {
    deep_on(bencher, formula, true);
}
