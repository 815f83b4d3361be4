//! The deep-view fuzzer's check: every engine configuration on a generated view against
//! direct big-float iteration, held to the accuracy bar.
//!
//! A configuration is a perturbation engine (f64 deltas where the spacing allows them,
//! FloatExp deltas always; direct f64 where the view is shallow enough), with BLA at the
//! scene's tolerance and without BLA, each run with every instruction set the CPU has. The
//! instruction sets must agree bit for bit (they do the same arithmetic); each engine's
//! values at the sampled pixels are then scored against the truth as `deepfield compare`
//! scores them, with the same exemptions (orbits passing within 1e-9 of the escape circle,
//! pixels whose true N changes within 1e-9 of a pixel or whose orbit spreads 1e-9 of a pixel
//! to a unit (chaotic), and, for NF and distance errors,
//! pixels whose true NF changes by more than 1e-4 within 1e-9 of a pixel, and for distance
//! errors alone, pixels whose true distance-estimate vector moves by more than 1e-4 of its
//! length within 1e-9 of a pixel). The bar, per
//! configuration: no N mismatch, NF error median <= 1e-6 and 99th percentile <= 1e-4,
//! distance-estimate error median <= 1e-6, and no NaN or infinity in any value.

use std::sync::atomic::AtomicBool;

use super::{
    Measured, Row, RunError, Variant, VariantKind, mark_ill_conditioned, run, sample_pixels, score, suspects, truths,
};
use crate::formula::Formula;
use crate::formula::end::INTERIOR;
use crate::render::engine::{self, EngineKind};
use crate::scene::Scene;
use crate::simd_level::SimdLevel;

/// The accuracy bar every configuration must meet.
#[derive(Debug, Clone, Copy)]
pub struct Bar {
    /// Largest fraction of compared pixels with a wrong N.
    pub n_mismatch: f64,
    /// Largest NF error median.
    pub nf_p50: f64,
    /// Largest NF error 99th percentile.
    pub nf_p99: f64,
    /// Largest distance-estimate error median.
    pub de_p50: f64,
}

/// The bar of the module docs.
pub const BAR: Bar = Bar { n_mismatch: 0.0, nf_p50: 1e-6, nf_p99: 1e-4, de_p50: 1e-6 };

/// What the check found on one view.
#[derive(Debug, Clone)]
pub struct Verdict {
    /// One row per engine configuration (scored on the first instruction set).
    pub rows: Vec<Row>,
    /// What broke the bar, one line each (empty: the view passes).
    pub failures: Vec<String>,
}

/// The configurations checked on `scene`: `compare`'s variants without the loose BLA
/// tolerance (a speed setting shown beside the default, not held to the bar), the f32 and
/// GPU kernels (not exact engines), and with one more: the first perturbation
/// configuration with BLA, its reference packed after [`PACKED_AFTER`] iterations.
pub fn configurations(scene: &Scene) -> Vec<Variant> {
    let mut out: Vec<Variant> = super::variants(scene)
        .into_iter()
        .filter(|v| match v.kind {
            VariantKind::Engine(EngineKind::Perturb { bla: Some(eps), .. }) => {
                eps != super::LOOSE_BLA_TOLERANCE || scene.bla == Some(super::LOOSE_BLA_TOLERANCE)
            }
            // Direct f64 only where `auto` chooses it: deeper, a forced f64 is a speed
            // setting (`compare` shows what it costs in accuracy), not an exact engine.
            VariantKind::Engine(EngineKind::Direct) => engine::plan_for(scene, crate::scene::EngineChoice::Auto)
                .is_ok_and(|plan| matches!(plan.kind, EngineKind::Direct)),
            VariantKind::Engine(_) => true,
            VariantKind::F32 | VariantKind::Gpu(_) => false,
        })
        .collect();
    // The first perturbation configuration with BLA again, its reference stored densely
    // for PACKED_AFTER iterations and packed after (as limits past 2^25 store it).
    let packed = out.iter().find(|v| matches!(v.kind, VariantKind::Engine(EngineKind::Perturb { bla: Some(_), .. })));
    if let Some(v) = packed.filter(|_| scene.max_iter > PACKED_AFTER) {
        let name = format!("{} packed after {PACKED_AFTER}", v.name);
        out.push(Variant { name, dense_orbit: Some(PACKED_AFTER), ..v.clone() });
    }
    out
}

/// Where the packed configuration's dense reference ends: early, so that most of the
/// samples' iterations run through the packed tail.
pub const PACKED_AFTER: u32 = 256;

/// Checks every configuration of `scene` on `pixels` sampled pixels, each with every
/// instruction set in `levels`, against the truth of `scene` iterating `formula` and `bar`.
pub fn check(
    scene: &Scene,
    formula: Formula,
    pixels: u32,
    levels: &[SimdLevel],
    bar: Bar,
    cancel: &AtomicBool,
) -> Result<Verdict, RunError> {
    let sampled = sample_pixels(scene, pixels);
    let mut failures = Vec::new();
    let variants = configurations(scene);
    let mut measured: Vec<Measured> = Vec::new();
    for v in &variants {
        let mut first: Option<Measured> = None;
        for &level in levels {
            let m = run(scene, v, &sampled, true, level, cancel)?;
            match &first {
                None => first = Some(m),
                Some(f) => {
                    let bits = |x: &Measured| -> Vec<[u32; 4]> {
                        x.values.iter().map(|&(n, a, b, c)| [n, a.to_bits(), b.to_bits(), c.to_bits()]).collect()
                    };
                    if bits(f) != bits(&m) {
                        failures.push(format!("{}: {} gives other values than {}", v.name, level, levels[0]));
                    }
                }
            }
        }
        let m = first.ok_or(RunError::Cancelled)?;
        for (k, &(n, nf, dx, dy)) in m.values.iter().enumerate() {
            if n != INTERIOR && !(nf.is_finite() && dx.is_finite() && dy.is_finite()) {
                failures.push(format!("{}: pixel {:?} has NF {nf}, DE ({dx}, {dy})", v.name, sampled[k]));
            }
        }
        measured.push(m);
    }
    let mut truth = truths(scene, formula, &sampled, cancel, &|_| {})?;
    let suspect = suspects(&measured, &truth, scene.escape_radius, scene.transform);
    mark_ill_conditioned(scene, formula, &sampled, &mut truth, &suspect, cancel)?;
    let rows: Vec<Row> = variants
        .iter()
        .zip(&measured)
        .map(|(v, m)| score(&v.name, m, &truth, scene.escape_radius, scene.transform))
        .collect();
    for r in &rows {
        // An error over no pixel is NaN and measures nothing (the row's `nf_scored` and
        // `de_scored` say so); over any pixel, NaN fails.
        let mut fail = |what: &str, value: f64, limit: f64, over: usize| {
            if over > 0 && (value.is_nan() || value > limit) {
                failures.push(format!("{}: {what} {value:.3e} > {limit:e}", r.engine));
            }
        };
        fail("N mismatch", r.n_mismatch_fraction, bar.n_mismatch, r.compared);
        fail("NF p50", r.nf_error_p50, bar.nf_p50, r.nf_scored);
        fail("NF p99", r.nf_error_p99, bar.nf_p99, r.nf_scored);
        fail("DE p50", r.de_error_p50, bar.de_p50, r.de_scored);
    }
    Ok(Verdict { rows, failures })
}
