//! The deep-zoom engine: an arbitrary-precision reference orbit, perturbation of every
//! sample against it with rebasing, bilinear approximation (BLA) to skip iterations, and
//! interior detection to stop samples caught by an attracting cycle.
//!
//! [`prepare`] computes what all tiles share (reference orbits, BLA tables) once per scene
//! into a [`Perturbation`]; [`Perturbation::orbit`] and [`Perturbation::orbits`] then
//! iterate samples. Dependencies run one way: `reference` ← `bla` ← `perturb`, with
//! `interior` beside the loop (its tests are what the loop calls at a sample's start, at
//! each turn and for each batch), and `saved` storing `reference`'s orbits in files.
//!
//! | wing | file | holds |
//! |---|---|---|
//! | | `mod.rs` | [`DeepSpec`] (what the engine needs of a scene), [`Scale`], [`prepare`] |
//! | reference | `reference/mod.rs` | [`Reference`]: one orbit in big floats, stored densely as f64 pairs with `FloatExp` for tiny values |
//! | | `reference/fixed.rs` | the step z² + c in fixed point on machine words, optionally shared by a team of threads |
//! | | `reference/team.rs` | which thread of a team computes which part of a step's three squares |
//! | | `reference/comba.rs` | the high half of a square by columns on 64-bit limbs (narrow precisions) |
//! | | `reference/square.rs` | the same in vector lanes on 26-bit digits (wide precisions) |
//! | | `reference/cycle.rs` | Brent's cycle detection, which stops an orbit where it repeats itself exactly |
//! | | `reference/handover.rs` | where the threads of a shared step meet, and when sharing stops |
//! | | `reference/packed.rs` | a long orbit's tail, predictively coded in about a byte per iteration |
//! | | `reference/mpfr.rs` | the step in MPFR (the `mpfr` feature), for comparison |
//! | BLA | `bla/mod.rs` | [`BlaTable`]: second-order steps merged in a tree, their validity radii |
//! | | `bla/tail.rs` | steps of whole blocks past the tree's reach, for long and packed orbits |
//! | | `bla/tests.rs` | merged steps against single steps |
//! | perturbation | `perturb/mod.rs` | a sample's state and the loop's passes (single steps, BLA steps, rebasing) |
//! | | `perturb/drive.rs` | where samples enter, and how they move between number types and lanes |
//! | | `perturb/start.rs` | a sample's start: its delta, the view-wide skip applied, its derivative |
//! | | `perturb/skip.rs` | [`Skip`]: the BLA steps every sample of a view takes, as one polynomial |
//! | | `perturb/series.rs` | [`Series`]: every sample's delta after many iterations as one polynomial of high degree, with bounds |
//! | | `perturb/der.rs` | the derivative as a mantissa pair with its own exponent |
//! | | `perturb/lanes.rs` | single steps of several samples in vector lanes (AVX2, AVX-512, NEON) |
//! | | `perturb/lanes/burst.rs` | the lanes' bursts: plain steps with nothing but an event test, rebases taken in the lane |
//! | | `perturb/turns.rs` | the turn loop round a nucleus's periodic reference |
//! | | `perturb/tail.rs` | the loop through a packed tail |
//! | | `perturb/report.rs` | what a built engine tells its callers (settings, sizes, timings) |
//! | | `perturb/tests.rs` | every driver and shortcut against one sample at a time |
//! | interior | `interior/mod.rs` | the contraction test and Newton's test for attracting cycles, and when detection is on |
//! | | `interior/model.rs` | the quadratic model of a minibrot (renormalisation) |
//! | | `interior/batch_models.rs` | the models of a batch of samples together |
//! | | `interior/probe.rs` | the Newton test as the loop runs it at the end of a turn |
//! | | `interior/disks.rs` | disks of parameters certified interior whole |
//! | files | `saved.rs` | reference files: orbits computed once, read by every unit and frame |
//! | generic | `generic/mod.rs` | [`generic::Engine`]: the deep engine for every formula but z² + c, generic over its stepper |
//! | | `generic/reference.rs` | its reference orbits: the centre's and one orbit of 0 per phase of a hybrid |
//! | | `generic/perturb.rs` | its loop: single steps, rebasing, BLA steps, f64 and FloatExp deltas |
//! | | `generic/lanes.rs` | its single steps for several samples of one family in vector lanes |
//! | | `generic/wide.rs` | the step from a reference value below f64's range, in FloatExp |
//! | | `generic/der.rs` | the real Jacobian times the spacing, with its own exponent |
//! | | `generic/bla.rs` | BLA with real 2×2 matrices, radii from the nonlinear terms and the fold lines |
//! | | `generic/tests.rs` | the generic engine against direct big-float iteration |
//!
//! The big-float helpers the engine shares with `locate` and `compare` are numbers
//! ([`crate::num::bigfloat`], [`crate::num::bigcomplex`]).

pub mod bla;
pub mod generic;
pub mod interior;
pub mod perturb;
pub mod reference;
pub mod saved;

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use malachite_base::num::conversion::traits::FromSciString;
use malachite_float::Float;
use malachite_q::Rational;

pub use bla::BlaTable;
pub use perturb::{Counters, Numbers, Perturbation, Series, Skip};
pub use reference::Reference;

use crate::cancel::Cancelled;
use crate::num::bigfloat;
use crate::num::{Decimal, FloatExp};
use crate::simd_level::SimdLevel;

/// The default BLA tolerance ε (relative size of the dropped nonlinear term per step).
/// Chosen with `deepfield compare` on 4000 pixels of bench-e50 (docs/engine-notes.md): at 1e-12 the NF
/// error's 99th percentile was 1.1e-3 and seven pixels in 4000 had a wrong N; at 1e-14 it is
/// 7.6e-5, inside the 1e-4 target, with as few wrong N as without BLA, for ~10% more time.
pub const DEFAULT_BLA_TOLERANCE: f64 = 1e-14;

/// How the view's scale was written (kept exact for the sample spacing).
#[derive(Debug, Clone, PartialEq)]
pub enum Scale {
    /// The image height spans 4 / zoom.
    Zoom(Decimal),
    /// Half the image height.
    Radius(Decimal),
}

impl Scale {
    /// The spacing between samples when `rows` sample rows span the view's height,
    /// computed exactly and rounded once.
    pub fn spacing(&self, rows: u32) -> FloatExp {
        bigfloat::to_floatexp(&self.spacing_big(rows, 64))
    }

    /// The spacing between samples at `bits` of precision (rounded once).
    pub fn spacing_big(&self, rows: u32, bits: u64) -> Float {
        let parse = |d: &Decimal| {
            let t = d.text().trim();
            Rational::from_sci_string(t.strip_prefix('+').unwrap_or(t)).unwrap_or_default()
        };
        let radius = match self {
            Scale::Zoom(z) => Rational::from(2u32) / parse(z),
            Scale::Radius(r) => parse(r),
        };
        let spacing = radius * Rational::from(2u32) / Rational::from(rows);
        Float::from_rational_prec(spacing, bits).0
    }
}

/// What the deep engine needs to know about a scene.
#[derive(Debug, Clone)]
pub struct DeepSpec {
    /// View centre (the reference point).
    pub center: [Decimal; 2],
    /// Julia parameter, or None for the Mandelbrot set.
    pub julia: Option<[Decimal; 2]>,
    /// Sample spacing.
    pub spacing: FloatExp,
    /// The largest sample offset from the centre, in units of the spacing.
    pub max_offset: f64,
    /// Largest iteration index.
    pub max_iter: u32,
    /// Escape radius.
    pub escape_radius: f64,
    /// Carry the derivative.
    pub derivative: bool,
    /// BLA tolerance, or None for no BLA.
    pub bla: Option<f64>,
    /// Stop samples whose orbit has contracted onto an attracting cycle and report them as
    /// interior: always, never, or where the view shows interior ([`interior::decide`]).
    pub interior: interior::Detection,
    /// Delta number types.
    pub numbers: Numbers,
    /// The instruction set the reference orbit's squares run with (the same bits on every
    /// one).
    pub simd: SimdLevel,
    /// Reference orbits computed earlier for this view (a reference file, see [`saved`]);
    /// None computes them.
    pub references: Option<std::sync::Arc<Vec<Reference>>>,
    /// Store at most this many reference iterations densely and pack the rest (`render
    /// --dense-orbit`); None: the engine's rule ([`dense_split`]).
    pub dense_orbit: Option<u32>,
}

/// Iteration limits up to this store the whole reference orbit densely: 16 bytes per
/// iteration, plus BLA tables of about 100 (f64) or 450 (FloatExp) bytes per iteration over
/// the first [`DENSE_PART`] and a few past it (steps of whole blocks, [`bla::TailSteps`]).
pub const MAX_DENSE_ITERATIONS: u32 = 1 << 25;

/// With a longer limit, the first this many iterations are stored densely (with BLA
/// tables, under half a GB at any depth) and the rest packed (a Mandelbrot reference is
/// held dense to [`MAX_DENSE_ITERATIONS`] first, in case it turns out to be one period of
/// a nucleus, which then stays dense), 1.0–1.4 bytes per
/// iteration as measured ([`reference::packed`]): 1e9 iterations in under 2 GB. The steps of whole
/// blocks past the dense part add at most 2^20 steps and 2^19 cursors: 130 MB with f64
/// deltas, 350 MB with FloatExp (both number types' steps), by their sizes.
pub const DENSE_PART: u32 = 1 << 20;

/// How much of a reference orbit is stored densely for an iteration limit, as
/// ([`reference::Stepping::dense_limit`], [`reference::Stepping::hold`]): all of it up to
/// [`MAX_DENSE_ITERATIONS`]; past that [`DENSE_PART`], held dense to
/// [`MAX_DENSE_ITERATIONS`] first. `forced` (`render --dense-orbit`) sets the limit with
/// no hold, to test the packed tail on short orbits.
pub fn dense_split(max_iter: u32, forced: Option<u32>) -> (Option<u32>, Option<u32>) {
    match forced {
        // At least Z_0 and Z_1 dense: a rebased sample takes its step from Z_0 and goes on
        // from index 1 in the dense part.
        Some(n) => ((n < max_iter).then_some(n.max(1)), None),
        None if max_iter > MAX_DENSE_ITERATIONS => (Some(DENSE_PART), Some(MAX_DENSE_ITERATIONS)),
        None => (None, None),
    }
}

/// Progress of the shared work: (reference iterations done, of at most this many).
pub type ReferenceProgress<'a> = &'a (dyn Fn(u64, u64) + Sync);

/// The precision of a view's reference orbits: 96 bits below its sample spacing.
pub fn reference_bits(spec: &DeepSpec) -> u64 {
    bigfloat::precision_for(spec.spacing.log2() / std::f64::consts::LOG2_10)
}

/// The period test's threshold of a view (see [`reference::Stepping::periodic_below`]):
/// 2^-20 of a sample spacing, for Mandelbrot references from 0; None for Julia sets.
pub fn periodic_below(spec: &DeepSpec) -> Option<FloatExp> {
    spec.julia.is_none().then(|| spec.spacing.mul_f64(2f64.powi(-20)))
}

/// How the references of a view are stepped (see [`reference::Stepping`]): a Mandelbrot
/// reference from 0 that comes back within 2^-20 of a sample spacing (first order) of 0 is
/// one period of a nucleus's orbit; past the dense part ([`dense_split`]) the orbit is
/// packed.
fn stepping(spec: &DeepSpec, share: bool) -> reference::Stepping {
    let (dense_limit, hold) = dense_split(spec.max_iter, spec.dense_orbit);
    reference::Stepping {
        share,
        simd: spec.simd,
        periodic_below: periodic_below(spec),
        dense_limit,
        hold,
        cut_cycles: true,
    }
}

/// Computes the reference orbit(s) of a view: the centre's orbit (Mandelbrot), or for a
/// Julia set the centre's and 0's (samples rebase onto the latter).
pub fn references(
    spec: &DeepSpec,
    progress: ReferenceProgress<'_>,
    cancel: &AtomicBool,
) -> Result<Vec<Reference>, Cancelled> {
    let bits = reference_bits(spec);
    let big = |d: &[Decimal; 2]| [bigfloat::from_decimal(&d[0], bits), bigfloat::from_decimal(&d[1], bits)];
    let zero = [Float::from(0u32), Float::from(0u32)];
    let center = big(&spec.center);
    let total = spec.max_iter as u64 * if spec.julia.is_some() { 2 } else { 1 };
    // Progress of each orbit, summed (the Julia set's two are computed side by side).
    let done = [AtomicU64::new(0), AtomicU64::new(0)];
    let report = |k: usize, n: u32| {
        done[k].store(n as u64, Ordering::Relaxed);
        progress(done[0].load(Ordering::Relaxed) + done[1].load(Ordering::Relaxed), total);
    };
    let run = |k: usize, start: &[Float; 2], c: &[Float; 2], share: bool| {
        let steps = stepping(spec, share);
        Reference::compute(start, c, spec.max_iter, spec.escape_radius, bits, steps, &|n| report(k, n), cancel)
    };
    let refs = match &spec.julia {
        // One orbit: it may share its steps with a helper thread.
        None => vec![run(0, &zero, &center, true)?],
        Some(c) => {
            // Two orbits: one thread each.
            let c = big(c);
            let (a, b) = rayon::join(|| run(0, &center, &c, false), || run(1, &zero, &c, false));
            vec![a?, b?]
        }
    };
    progress(total, total);
    Ok(refs)
}

/// Computes the reference orbit(s) (unless `spec.references` brings them) and the BLA
/// tables for a scene.
pub fn prepare(
    spec: &DeepSpec,
    progress: ReferenceProgress<'_>,
    cancel: &AtomicBool,
) -> Result<Perturbation, Cancelled> {
    let started = std::time::Instant::now();
    let refs = match &spec.references {
        Some(r) => r.clone(),
        None => std::sync::Arc::new(references(spec, progress, cancel)?),
    };
    let mandelbrot = spec.julia.is_none();
    let orbit_seconds = started.elapsed().as_secs_f64();
    let dc_max = if mandelbrot { spec.spacing.mul_f64(spec.max_offset) } else { FloatExp::ZERO };
    let mut bla_fe = [None, None];
    let mut bla_f64 = [None, None];
    let mut skip = None;
    let mut series = None;
    if let Some(eps) = spec.bla {
        for (k, r) in refs.iter().enumerate() {
            // Orbits of 0 step nonlinearly from Z_0 = 0: their tables start at index 1.
            let origin = if mandelbrot || k == 1 { 1 } else { 0 };
            let floatexp = spec.numbers == Numbers::FloatExp;
            let t = BlaTable::build(r, origin, mandelbrot, eps, dc_max, spec.escape_radius).with_blocks(
                refs.clone(),
                k,
                floatexp,
            );
            if k == 0 {
                // The steps every sample takes first: from Z_1 (Mandelbrot, |δ_1| = |δc|) or
                // Z_0 (Julia, |δ_0| = |offset|), bounded by the largest offset.
                let bound = spec.spacing.mul_f64(spec.max_offset);
                skip = Skip::find(&t, origin, bound, spec.max_iter, eps);
                // Where the tables cannot merge steps for every sample, a series of high
                // degree may still hold for most of them (z^2 + c only).
                let beyond = skip.as_ref().map_or(origin, |k| k.m);
                series = Series::find(
                    r,
                    origin,
                    mandelbrot,
                    bound,
                    spec.spacing,
                    spec.escape_radius,
                    spec.max_iter,
                    eps,
                    spec.derivative,
                    beyond,
                );
            }
            bla_f64[k] = Some(t.to_f64());
            if spec.numbers == Numbers::FloatExp {
                bla_fe[k] = Some(t);
            }
        }
    }
    let single_d2 = perturb::single_step_threshold(&bla_f64);
    let check = interior::Check::new(spec.max_iter, spec.escape_radius);
    let interior_decision = interior::decide(spec.interior, &refs, mandelbrot, spec.spacing, spec.max_iter, check);
    // Λ = 2 Z_1 ⋯ 2 Z_(p-1) of a nucleus's reference (interior detection's quadratic model).
    let renormal = refs[0].period().filter(|&p| mandelbrot && p <= refs[0].last()).map(|p| {
        (1..p).fold([FloatExp::ONE, FloatExp::ZERO], |l, k| {
            let z = refs[0].get_fe(k);
            crate::num::real::cmul(l, [z[0].ldexp(1), z[1].ldexp(1)])
        })
    });
    let mut engine = Perturbation {
        refs,
        bla_fe: std::sync::Arc::new(bla_fe),
        bla_f64: std::sync::Arc::new(bla_f64),
        extent: spec.spacing.mul_f64(spec.max_offset),
        origin: [FloatExp::ZERO; 2],
        mandelbrot,
        spacing: spec.spacing,
        max_iter: spec.max_iter,
        escape2: spec.escape_radius * spec.escape_radius,
        derivative: spec.derivative,
        interior: interior_decision.runs().then_some(check),
        interior_asked: spec.interior,
        interior_decision,
        renormal,
        model_scale: None,
        numbers: spec.numbers,
        skip,
        series,
        single_d2,
        turn_loop: true,
        disks: true,
        orbit_seconds,
        tables_seconds: started.elapsed().as_secs_f64() - orbit_seconds,
    };
    engine.model_scale = engine.compute_model_scale();
    Ok(engine)
}
