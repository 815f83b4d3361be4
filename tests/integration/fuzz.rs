//! A fast seeded subset of the deep-view fuzzer (`scripts/fuzz-deep.sh` runs it for as long
//! as asked): one generated view of each kind, nobody tuned to, every engine configuration
//! and every instruction set this CPU has against direct big-float iteration, held to the
//! bar of `compare::fuzz` (no N mismatch outside ill-conditioned pixels, NF error median
//! <= 1e-6 and 99th percentile <= 1e-4, distance error median <= 1e-6, nothing non-finite,
//! every instruction set the same bits).

use std::sync::atomic::AtomicBool;

use deepfield::compare::fuzz::{self, BAR};
use deepfield::compare::views::{self, ViewKind, ViewSpec};
use deepfield::formula::Formula;
use deepfield::simd_level::SimdLevel;

/// Generates a view of `kind` (the first of a few draws that finds one) and checks it;
/// returns the configurations checked.
fn fuzz(kind: ViewKind, seed: u64, log10_zoom: f64, max_iter: u32) -> Vec<String> {
    fuzz_formula(Formula::default(), kind, seed, log10_zoom, max_iter)
}

/// [`fuzz`] for any formula.
fn fuzz_formula(formula: Formula, kind: ViewKind, seed: u64, log10_zoom: f64, max_iter: u32) -> Vec<String> {
    let spec = ViewSpec { kind, log10_zoom, max_iter, width: 32, height: 24, formula };
    let view = (0..16).find_map(|d| views::generate(seed, d, &spec)).unwrap_or_else(|| panic!("no {kind:?} view"));
    let verdict =
        fuzz::check(&view.scene, view.formula, 12, &SimdLevel::usable(), BAR, &AtomicBool::new(false)).expect("ran");
    let names: Vec<&str> = verdict.rows.iter().map(|r| r.engine.as_str()).collect();
    eprintln!("{}: {names:?}", view.name);
    assert!(names.iter().any(|n| n.contains("bla")) && names.iter().any(|n| !n.contains("bla")), "{names:?}");
    assert!(verdict.failures.is_empty(), "{}:\n{}\n{}", view.name, verdict.failures.join("\n"), view.toml);
    names.iter().map(|n| n.to_string()).collect()
}

/// Either side of the zoom (1e5) where `auto` leaves direct f64: shallower, direct f64 is one
/// of the configurations held to the bar; deeper, it is not `auto`'s and is left out.
#[test]
fn generated_views_either_side_of_the_direct_f64_line() {
    let shallow = fuzz(ViewKind::Misiurewicz, 41, 4.0, 20_000);
    assert!(shallow.iter().any(|n| n == "f64"), "{shallow:?}");
    let deeper = fuzz(ViewKind::Misiurewicz, 42, 7.0, 20_000);
    assert!(!deeper.iter().any(|n| n == "f64"), "{deeper:?}");
}

#[test]
fn generated_misiurewicz_views_at_1e40_and_1e700() {
    fuzz(ViewKind::Misiurewicz, 11, 40.0, 100_000);
    fuzz(ViewKind::Misiurewicz, 12, 700.0, 100_000);
}

#[test]
fn generated_minibrot_descent_and_early_escape_views() {
    fuzz(ViewKind::Minibrot, 21, 25.0, 30_000);
    fuzz(ViewKind::Descent, 22, 25.0, 30_000);
    fuzz(ViewKind::EarlyEscape, 23, 25.0, 30_000);
}

#[test]
fn generated_views_at_the_f64_floatexp_line_and_julia_sets() {
    fuzz(ViewKind::FloatExpLine, 31, 300.0, 100_000);
    fuzz(ViewKind::Julia, 32, 60.0, 100_000);
}

/// The boundary-descent kinds that work for any formula, on z² + c (whose engines exist
/// today): a Julia set whose c is on the boundary, and a view on the real axis.
#[test]
fn generated_boundary_descent_views_of_z2_plus_c() {
    fuzz(ViewKind::JuliaBoundary, 33, 20.0, 100_000);
    fuzz(ViewKind::RealAxis, 34, 20.0, 100_000);
}

/// Other formulas' kinds, views nobody tuned to: a Burning Ship boundary descent past the
/// f64 exponent range (FloatExp deltas, folds), and a hybrid's Julia set.
#[test]
fn generated_views_of_other_formulas() {
    let ship = Formula::parse("burning-ship", None).expect("a family");
    fuzz_formula(ship, ViewKind::Boundary, 51, 320.0, 30_000);
    let hybrid = Formula::parse("burning-ship,mandelbrot^3", None).expect("a hybrid");
    fuzz_formula(hybrid, ViewKind::JuliaBoundary, 52, 40.0, 30_000);
}
