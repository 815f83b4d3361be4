//! Kernel throughput in iterations per second, on the view of `scenes/seahorse-valley.toml`
//! (seahorse valley, escape-time detail everywhere, 5000 max iterations, 2x2 samples).
//!
//! `cargo bench --bench kernels` prints time per call and iterations per second (the
//! "item/s" rows count only iterations the orbit loops performed). `n_only` is the headline
//! figure; `smooth_only`, `with_distance` and `with_trap` show what each extra costs, and so
//! that a scene colouring by smooth iteration alone pays for neither the derivative nor traps.
//! `single_steps_one_thread` and `smooth_one_thread` set the perturbation engine's single
//! steps (its vector lanes) beside the direct kernel, on the same samples and one thread;
//! `descent_e6_single_steps_one_thread` and `descent_e6_direct_one_thread` do the same at
//! zoom 1e6 of the seahorse descent, where samples run long.

use std::sync::atomic::AtomicBool;

use deepfield::field::{self, FieldParams, Needs};
use deepfield::orbit::interior::Detection;
use deepfield::render;
use deepfield::scene::{EngineChoice, Scene};
use deepfield::trap::{Shape, Trap};
use divan::counter::ItemsCount;
use rayon::prelude::*;

mod common;

fn main() {
    divan::main();
}

const SCENE: &str = "scenes/seahorse-valley.toml";

/// The benchmark's scene, at this run's size ([`common::side`]).
fn scene() -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(SCENE);
    let text = std::fs::read_to_string(&path).expect("scene");
    let file = Scene::parse_file(SCENE, &text).expect("parses");
    let mut scene =
        Scene::validate(file, SCENE, &text, path.parent().unwrap(), deepfield::io::load_bitmap).expect("valid");
    (scene.width, scene.height) = (common::side(scene.width), common::side(scene.height));
    scene
}

fn params(needs: Needs) -> FieldParams {
    let scene = scene();
    let mut p = deepfield::render::field_params(&scene, Default::default());
    p.needs = needs;
    p.orbit.derivative = p.needs.de;
    p
}

/// Computes every sample row in strips of 16 rows; returns the iterations performed.
fn run(params: &FieldParams, parallel: bool) -> u64 {
    let cancel = AtomicBool::new(false);
    let rows = params.grid.height;
    let strip = |k: u32| field::compute_strip(params, k * 16..((k + 1) * 16).min(rows), &cancel).unwrap().iterations;
    let strips = rows.div_ceil(16);
    if parallel { (0..strips).into_par_iter().map(strip).sum() } else { (0..strips).map(strip).sum() }
}

fn bench_with(bencher: divan::Bencher<'_, '_>, needs: Needs, parallel: bool) {
    let params = params(needs);
    let iterations = run(&params, parallel);
    bencher.counter(ItemsCount::new(iterations)).bench(|| run(&params, parallel));
}

/// N only, all threads: the headline figure.
#[divan::bench(sample_count = 10)]
fn n_only(bencher: divan::Bencher<'_, '_>) {
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
#[divan::bench(sample_count = 5)]
fn with_trap(bencher: divan::Bencher<'_, '_>) {
    let trap = Trap::Geometric(Shape::Point { at: [0.0, 0.0] });
    bench_with(bencher, Needs { nf: true, traps: vec![trap], ..Needs::default() }, true);
}

/// A pool of one thread: what a one-thread figure runs in, so that no strip's chunks go to
/// other threads.
fn one_thread<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a pool").install(f)
}

/// N and NF on one thread: the direct kernel's figure to set beside
/// [`single_steps_one_thread`].
#[divan::bench(sample_count = 10)]
fn smooth_one_thread(bencher: divan::Bencher<'_, '_>) {
    let params = params(Needs { nf: true, ..Needs::default() });
    let iterations = one_thread(|| run(&params, false));
    bencher.counter(ItemsCount::new(iterations)).bench(|| one_thread(|| run(&params, false)));
}

/// The field parameters of `scene` through the perturbation engine (`perturb-f64`) with BLA
/// and interior detection off, computing `needs`: every iteration a single step (but for
/// rebases), taken in the vector lanes. Only the scene's first layer is kept, so that the
/// deep engine carries a derivative only where `needs` asks for one.
fn single_steps(mut scene: Scene, needs: Needs) -> FieldParams {
    (scene.engine, scene.bla, scene.interior_detection) = (EngineChoice::PerturbF64, None, Detection::Off);
    scene.stack.layers.truncate(1);
    let plan = render::engine::plan(&scene).expect("perturbation addresses the view");
    let cancel = AtomicBool::new(false);
    let (mut params, _) =
        render::prepare_field(&scene, &plan, render::Options::default(), &cancel, &|_| {}).expect("prepared");
    let deep = params.deep.as_ref().expect("the perturbation engine runs");
    assert_eq!(deep.derivative(), needs.de, "the deep engine carries a derivative only if asked");
    params.needs = needs;
    params
}

/// The same samples, N and NF, through the perturbation engine's single steps on one thread.
/// Its iterations per second against [`smooth_one_thread`]'s are the lanes' single-step rate
/// against the direct kernel's on this CPU, where samples are short (about 116 iterations
/// each, a rebase every 25): the cost of starting and finishing samples weighs here.
#[divan::bench(sample_count = 5)]
fn single_steps_one_thread(bencher: divan::Bencher<'_, '_>) {
    let params = single_steps(scene(), Needs { nf: true, ..Needs::default() });
    let iterations = one_thread(|| run(&params, false));
    bencher.counter(ItemsCount::new(iterations)).bench(|| one_thread(|| run(&params, false)));
}

/// The seahorse descent at zoom 1e6 (the view of `scripts/descent-trade.sh`), where `auto`
/// first leaves direct f64 for perturbation: 256×192 samples, 5000 iterations, long orbits
/// (about 2000 iterations a sample, a rebase every 50).
const DESCENT_E6: &str = r##"
version = 1
[view]
center = ["-0.743643887037158704752191506114774", "0.131825904205311970493132056385139"]
zoom = "1e6"
width = 256
height = 192
[iteration]
max = 5000
[[layer]]
kind = "smooth"
palette = "classic"
"##;

fn descent_e6() -> Scene {
    let file = Scene::parse_file("descent-e6", DESCENT_E6).expect("parses");
    let mut scene =
        Scene::validate(file, "descent-e6", DESCENT_E6, std::path::Path::new("."), deepfield::io::load_bitmap)
            .expect("valid");
    (scene.width, scene.height) = (common::side(scene.width), common::side(scene.height));
    scene
}

/// N only at zoom 1e6 through the direct kernel on one thread: the figure to set beside
/// [`descent_e6_single_steps_one_thread`].
#[divan::bench(sample_count = 10)]
fn descent_e6_direct_one_thread(bencher: divan::Bencher<'_, '_>) {
    let scene = descent_e6();
    let mut params = deepfield::render::field_params(&scene, Default::default());
    params.needs = Needs::default();
    let iterations = one_thread(|| run(&params, false));
    bencher.counter(ItemsCount::new(iterations)).bench(|| one_thread(|| run(&params, false)));
}

/// The same samples, N only, through the perturbation engine's single steps on one thread:
/// the lanes' rate where samples run long and their start and finish weigh little.
#[divan::bench(sample_count = 5)]
fn descent_e6_single_steps_one_thread(bencher: divan::Bencher<'_, '_>) {
    let params = single_steps(descent_e6(), Needs::default());
    let iterations = one_thread(|| run(&params, false));
    bencher.counter(ItemsCount::new(iterations)).bench(|| one_thread(|| run(&params, false)));
}
