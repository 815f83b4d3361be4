//! The deep-view fuzzer: generated views nobody tuned the engine to, every engine
//! configuration and instruction set against direct big-float iteration, for as long as
//! asked. Every view that breaks the accuracy bar is written as a scene file that
//! reproduces it (`deepfield compare FILE --sample-only` shows the rows again).
//!
//! ```sh
//! cargo run --release --example deep_fuzz -- --seconds 3600 --out fuzz-failures
//! scripts/fuzz-deep.sh 3600            # the same, with a log
//! ```
//!
//! Flags: `--seed S` (default 1), `--seconds T` (default 60), `--count N` (stop after N
//! views), `--out DIR` (default `fuzz-failures`), `--pixels K` (sampled pixels per view,
//! default 24), `--size WxH` (default 64x48), `--min-depth D` and `--max-depth D` (log10 of the
//! shallowest and deepest zoom, default 15 and 2000), `--max-iter N` (default 1000000), `--kinds a,b` (default all:
//! descent, minibrot, misiurewicz, early-escape, floatexp-line, julia, boundary, julia-boundary,
//! mini, real-axis; for a formula other than z² + c only the last four, which work for any
//! formula), `--formula F` (a family, `NAME^P`, or a hybrid `a,b^3`; default z² + c; the
//! views' Julia forms come from `julia-boundary`), `--a RE,IM` (the coefficient of a formula
//! that takes one, `redshift-rider-*`; default 1,0), `--list-formulas` (print every family at
//! every power, one a line, and stop; `scripts/fuzz-deep.sh --formulas` loops over them).
//!
//! Boundary descents sample the view at every step of the way down (by perturbation about
//! one big-float orbit a step past zoom 1e9), so the any-formula kinds go no deeper than
//! 1e400 (`ANY_FORMULA_DEPTH`).
#![allow(clippy::print_stdout)] // printing the findings is the point

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use deepfield::compare::fuzz::{self, BAR};
use deepfield::compare::views::{self, Rng, ViewKind, ViewSpec};
use deepfield::formula::Formula;
use deepfield::formula::kind::KINDS;

/// The deepest zoom (log10) the boundary-descent kinds are drawn at.
const ANY_FORMULA_DEPTH: f64 = 400.0;
use deepfield::simd_level::SimdLevel;

struct Flags {
    seed: u64,
    seconds: f64,
    count: u32,
    out: std::path::PathBuf,
    pixels: u32,
    size: (u32, u32),
    min_depth: f64,
    max_depth: f64,
    max_iter: u32,
    kinds: Option<Vec<ViewKind>>,
    formula: Formula,
}

fn flags() -> Result<Flags, String> {
    let mut f = Flags {
        seed: 1,
        seconds: 60.0,
        count: u32::MAX,
        out: "fuzz-failures".into(),
        pixels: 24,
        size: (64, 48),
        min_depth: 15.0,
        max_depth: 2000.0,
        max_iter: 1_000_000,
        kinds: None,
        formula: Formula::default(),
    };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut it = args.iter();
    let mut coef: Option<[f64; 2]> = None;
    let a_flag = "--a";
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or(format!("{a} needs a value"));
        let bad = |a: &str| format!("{a}: not a number");
        match a.as_str() {
            "--seed" => f.seed = value()?.parse().map_err(|_| bad(a))?,
            "--seconds" => f.seconds = value()?.parse().map_err(|_| bad(a))?,
            "--count" => f.count = value()?.parse().map_err(|_| bad(a))?,
            "--out" => f.out = value()?.into(),
            "--pixels" => f.pixels = value()?.parse().map_err(|_| bad(a))?,
            "--min-depth" => f.min_depth = value()?.parse().map_err(|_| bad(a))?,
            "--max-depth" => f.max_depth = value()?.parse().map_err(|_| bad(a))?,
            "--max-iter" => f.max_iter = value()?.parse().map_err(|_| bad(a))?,
            "--size" => {
                let v = value()?;
                let (w, h) = v.split_once('x').ok_or(format!("--size {v}: not WxH"))?;
                f.size = (w.parse().map_err(|_| bad(a))?, h.parse().map_err(|_| bad(a))?);
            }
            "--kinds" => {
                let v = value()?;
                f.kinds = Some(
                    v.split(',')
                        .map(|k| {
                            ViewKind::ALL.into_iter().find(|x| x.name() == k).ok_or(format!("--kinds: no kind {k}"))
                        })
                        .collect::<Result<_, _>>()?,
                );
            }
            "--formula" => f.formula = Formula::parse(value()?, None).map_err(|e| format!("--formula: {e}"))?,
            "--a" => {
                let v = value()?;
                let (re, im) = v.split_once(',').ok_or(format!("--a {v}: not RE,IM"))?;
                coef = Some([re.parse().map_err(|_| bad(a_flag))?, im.parse().map_err(|_| bad(a_flag))?]);
            }
            "--list-formulas" => {
                for k in KINDS {
                    for p in k.min_power..=k.max_power {
                        let phase = deepfield::formula::Phase::new(k.kind, p);
                        println!("{phase}");
                    }
                }
                std::process::exit(0);
            }
            other => return Err(format!("unknown flag {other}")),
        }
    }
    if let Some(a) = coef {
        if f.formula.a().is_none() {
            return Err(format!("--a: {} has no coefficient", f.formula));
        }
        f.formula = f.formula.with_a(a);
    }
    Ok(f)
}

fn main() {
    let f = match flags() {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let kinds = f.kinds.clone().unwrap_or_else(|| ViewKind::for_formula(f.formula));
    if let Some(k) = kinds.iter().find(|k| !f.formula.is_quadratic() && !k.any_formula()) {
        eprintln!(
            "error: --kinds {}: that kind is z² + c's; for {} use {:?}",
            k.name(),
            f.formula,
            ViewKind::ANY_FORMULA.map(|k| k.name())
        );
        std::process::exit(2);
    }
    let levels = SimdLevel::usable();
    let cancel = AtomicBool::new(false);
    let start = Instant::now();
    let mut rng = Rng::new(f.seed);
    let (mut checked, mut failed, mut n_only) = (0u32, 0u32, 0u32);
    println!(
        "formula {}, seed {}, instruction sets {:?}, bar {BAR:?}",
        f.formula,
        f.seed,
        levels.iter().map(|l| l.name()).collect::<Vec<_>>()
    );
    let mut draw = 0u32;
    while checked < f.count && start.elapsed().as_secs_f64() < f.seconds {
        let kind = kinds[draw as usize % kinds.len()];
        // Depths log-uniform from the shallowest to the deepest asked (minibrot descents stop sooner
        // where their periods grow past what the check can iterate).
        let top = match kind {
            ViewKind::Misiurewicz | ViewKind::Julia => f.max_depth,
            k if k.any_formula() => f.max_depth.min(ANY_FORMULA_DEPTH),
            _ => f.max_depth.min(400.0),
        };
        let bottom = f.min_depth.max(1.0);
        let depth = 10f64.powf(rng.uniform(bottom.log10(), top.max(bottom + 1.0).log10()));
        let spec = ViewSpec {
            kind,
            log10_zoom: depth,
            max_iter: f.max_iter,
            width: f.size.0,
            height: f.size.1,
            formula: f.formula,
        };
        draw += 1;
        let Some(view) = views::generate(f.seed, draw, &spec) else { continue };
        let t = Instant::now();
        let verdict = match fuzz::check(&view.scene, view.formula, f.pixels, &levels, BAR, &cancel) {
            Ok(v) => v,
            Err(e) => {
                println!("{}: not checked: {e}", view.name);
                continue;
            }
        };
        checked += 1;
        // NF is scored over the escaped pixels whose N is right: say over how many, and
        // that a view with none checked N only (its NF error is not 0, it is unmeasured).
        let nf_pixels = verdict.rows.iter().map(|r| r.nf_scored).min().unwrap_or(0);
        let nf = if nf_pixels == 0 {
            n_only += 1;
            "N only (no escaped pixel to score NF on)".to_string()
        } else {
            // f64::max skips NaN.
            let worst = verdict.rows.iter().map(|r| r.nf_error_p99).fold(0.0, f64::max);
            format!("NF p99 <= {worst:.1e} over {nf_pixels} px")
        };
        println!(
            "{:<28} zoom 1e{:<7.1} max {:>8} {:>5.1} s  {} configurations, {nf}{}",
            view.name,
            -view.scene.log10_spacing() - (view.scene.height as f64 / 4.0).log10(),
            view.scene.max_iter,
            t.elapsed().as_secs_f64(),
            verdict.rows.len(),
            if verdict.failures.is_empty() { "" } else { "  FAILED" }
        );
        if !verdict.failures.is_empty() {
            failed += 1;
            for line in &verdict.failures {
                println!("    {line}");
            }
            let _ = std::fs::create_dir_all(&f.out);
            let path = f.out.join(format!("{}.toml", view.name));
            let mut header: String = verdict.failures.iter().map(|l| format!("# {l}\n")).collect();
            if verdict.failures.iter().any(|l| l.contains("packed after")) {
                let n = deepfield::compare::fuzz::PACKED_AFTER;
                header += &format!(
                    "# (\"packed after {n}\": the reference packed past {n} iterations, `render --dense-orbit {n}`)\n"
                );
            }
            let text = format!(
                "# Generated by the deep-view fuzzer (formula {}, seed {}, draw {draw}); it broke the bar:\n{header}{}",
                view.formula, f.seed, view.toml
            );
            if let Err(e) = std::fs::write(&path, text) {
                eprintln!("error: {}: {e}", path.display());
            }
        }
    }
    println!(
        "{checked} views checked in {:.0} s, {failed} failed, {n_only} of them N only",
        start.elapsed().as_secs_f64()
    );
    if failed > 0 {
        std::process::exit(1);
    }
}
