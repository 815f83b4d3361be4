//! The deep engine for every formula but z² + c: reference orbits in big floats,
//! perturbation with rebasing, f64 and FloatExp deltas, bilinear approximation with real
//! 2×2 matrices, and the derivative as a real Jacobian.
//!
//! z² + c has its own engine beside this one (fixed-point references, second-order BLA
//! with near-period stages, vector lanes, interior detection), built around the one map.
//! Every other family of [`crate::formula`] (Multibrot powers, Burning Ship, Buffalo,
//! Celtic, Mandelbar and their partial and perpendicular variants, hybrids of them) is a
//! composition of folds, a power and a negation, and this engine is written once for all
//! of them, generic over [`Stepper`]: [`prepare`] turns the runtime [`Formula`] into its
//! compiled stepper ([`crate::with_stepper!`]) once per call, and each loop is compiled
//! per family, so no formula is interpreted in the hot loop (only the rare steps from
//! reference values below f64's range read the phase's shape, `wide.rs`).
//!
//! | file | holds |
//! |---|---|
//! | `mod.rs` | [`Engine`], [`prepare`] and what the engine reports |
//! | `reference.rs` | the reference orbits (one orbit of 0 per phase of a hybrid), f64 with FloatExp for wide values |
//! | `perturb.rs` | the loop: single steps, rebasing, BLA steps, f64/FloatExp switching |
//! | `lanes.rs` | the loop's single steps for many samples in vector lanes (a hybrid's lanes in phase, one family a pass), events in `perturb.rs`'s pass |
//! | `wide.rs` | the step from a reference value f64 cannot stand for, in FloatExp |
//! | `der.rs` | the Jacobian times the spacing, with its own exponent |
//! | `bla.rs` | BLA tables: 2×2 steps merged in a tree, radii from the nonlinear terms and the fold lines |
//! | `tests.rs` | the engine against direct big-float iteration |
//!
//! Of [`DeepSpec`], this engine reads the centre, the Julia parameter, the spacing, the
//! largest offset, the iteration limit, the escape radius, the derivative, the BLA
//! tolerance and the number types. Interior detection, the SIMD level of the quadratic
//! references, reference files and the dense-orbit split are the quadratic engine's, and
//! are ignored here (every orbit is stored densely).

mod bla;
mod der;
mod lanes;
mod perturb;
mod reference;
mod wide;

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use rayon::prelude::*;

use super::{Counters, DeepSpec, Numbers, ReferenceProgress, reference_bits};
use crate::cancel::Cancelled;
use crate::formula::end::Orbit;
use crate::formula::{Formula, Stepper};
use crate::num::FloatExp;
use crate::num::bigcomplex::BigC;
use crate::simd_level::SimdLevel;
use crate::trap::{Trap, TrapState};
use bla::Table;
use reference::Track;

/// A prepared view: its reference orbits and BLA tables, shared by every sample.
#[derive(Debug)]
pub struct Engine {
    formula: Formula,
    /// The reference orbits: for the Mandelbrot form the orbits of 0 by phase offset (the
    /// first is the primary reference); for a Julia set the centre's orbit, then those.
    tracks: Vec<Track>,
    /// Where the orbits of 0 begin in `tracks`.
    zeros: usize,
    /// The formula's cycle length.
    period: u32,
    /// BLA tables per track, f64 (empty: BLA off).
    t64: Vec<Table<f64>>,
    /// BLA tables per track, FloatExp (empty: BLA off, or f64 deltas only).
    tfe: Vec<Table<FloatExp>>,
    mandelbrot: bool,
    spacing: FloatExp,
    max_iter: u32,
    escape2: f64,
    derivative: bool,
    numbers: Numbers,
    /// A FloatExp delta whose exponent is above this moves to f64.
    up_exp: i32,
    /// A rebase to a full value whose exponent is below this moves to FloatExp.
    down_exp: i32,
    /// A rebase from a full value whose parts are at least this (and nonzero) is computed
    /// in f64 (`perturb.rs`, `rebase_f64`): 2^-(1022/p - 56), p the largest power.
    rebase_low: f64,
    bits: u64,
    orbit_seconds: f64,
    tables_seconds: f64,
}

/// Computes the reference orbits of a view for `formula` and (with `spec.bla`) their BLA
/// tables.
pub fn prepare(
    spec: &DeepSpec,
    formula: Formula,
    cancel: &AtomicBool,
    progress: Option<ReferenceProgress<'_>>,
) -> Result<Engine, Cancelled> {
    let started = Instant::now();
    let bits = reference_bits(spec);
    let center = BigC::from_decimals(&spec.center[0], &spec.center[1], bits);
    let julia = spec.julia.as_ref().map(|j| BigC::from_decimals(&j[0], &j[1], bits));
    let max_power = formula.phases().iter().map(|p| p.power).max().unwrap_or(2);
    let silent = |_: u64, _: u64| {};
    let progress: ReferenceProgress<'_> = progress.unwrap_or(&silent);
    let radius = reference::reference_radius(spec.escape_radius);
    let tracks = crate::with_stepper!(formula, s => reference::compute_all(
        &s, &formula, &center, julia.as_ref(), spec.max_iter, radius, max_power, progress, cancel
    ))?;
    let orbit_seconds = started.elapsed().as_secs_f64();
    let mandelbrot = spec.julia.is_none();
    let (mut t64, mut tfe) = (Vec::new(), Vec::new());
    if let Some(eps) = spec.bla {
        let how = bla::Build {
            eps,
            dc_max: if mandelbrot { spec.spacing.mul_f64(spec.max_offset) } else { FloatExp::ZERO },
            escape_radius: spec.escape_radius,
            mandelbrot,
            floatexp: spec.numbers == Numbers::FloatExp,
        };
        let built: Vec<_> = crate::with_stepper!(formula, s => tracks
            .par_iter()
            .enumerate()
            .map(|(k, t)| {
                // Orbits of 0 start their trees at index 1 (nothing is linear at Z_0 = 0).
                let origin = if mandelbrot || k > 0 { 1 } else { 0 };
                bla::build(&s, &formula, t, origin, &how)
            })
            .collect());
        for (a, b) in built {
            t64.push(a);
            tfe.extend(b);
        }
    }
    let period = formula.phases().len() as u32;
    Ok(Engine {
        formula,
        zeros: if mandelbrot { 0 } else { 1 },
        tracks,
        period,
        t64,
        tfe,
        mandelbrot,
        spacing: spec.spacing,
        max_iter: spec.max_iter,
        escape2: spec.escape_radius * spec.escape_radius,
        derivative: spec.derivative,
        numbers: spec.numbers,
        up_exp: -(960 / max_power as i32),
        down_exp: -(1000 / max_power as i32),
        rebase_low: f64::from_bits(((1023 - (1022 / max_power as i32 - 56)) as u64) << 52),
        bits,
        orbit_seconds,
        tables_seconds: started.elapsed().as_secs_f64() - orbit_seconds,
    })
}

impl Engine {
    /// Iterates the sample at `offset` (in units of the spacing, from the view's centre),
    /// letting traps observe every z_k, k >= 1 (no BLA then). Returns the orbit's end: N,
    /// z_N, and with the derivative the [`gradient_dz`](crate::formula::map::gradient_dz)
    /// of the Jacobian times the spacing.
    pub fn orbit(
        &self,
        offset: [f64; 2],
        traps: &[Trap],
        states: &mut [TrapState],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) -> Orbit {
        let bla = traps.is_empty();
        crate::with_stepper!(self.formula, st => if self.derivative {
            self.sample::<_, true>(&st, offset, traps, states, counters, cancel, bla)
        } else {
            self.sample::<_, false>(&st, offset, traps, states, counters, cancel, bla)
        })
    }

    /// Iterates many samples without traps, on this thread; the same results as
    /// [`Engine::orbit`], bit for bit, at every `simd` level (samples run in vector lanes at
    /// levels above scalar). Once `cancel` is raised
    /// the rest are left as they are.
    pub fn orbits(
        &self,
        offsets: &[[f64; 2]],
        out: &mut [Orbit],
        counters: &mut Counters,
        simd: SimdLevel,
        cancel: &AtomicBool,
    ) {
        if simd != SimdLevel::Scalar {
            if self.derivative {
                self.orbits_lanes::<true>(simd, offsets, out, counters, cancel);
            } else {
                self.orbits_lanes::<false>(simd, offsets, out, counters, cancel);
            }
            return;
        }
        crate::with_stepper!(self.formula, st => if self.derivative {
            self.each::<_, true>(&st, offsets, out, counters, cancel)
        } else {
            self.each::<_, false>(&st, offsets, out, counters, cancel)
        })
    }

    pub(super) fn each<S: Stepper, const DER: bool>(
        &self,
        st: &S,
        offsets: &[[f64; 2]],
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) {
        for (o, &offset) in out.iter_mut().zip(offsets) {
            if cancel.load(std::sync::atomic::Ordering::Relaxed) {
                return;
            }
            *o = self.sample::<S, DER>(st, offset, &[], &mut [], counters, cancel, true);
        }
    }

    /// The formula.
    pub fn formula(&self) -> Formula {
        self.formula
    }

    /// Length of the primary reference orbit (iterations stored).
    pub fn reference_len(&self) -> u32 {
        self.tracks[0].last()
    }

    /// The number of reference orbits (one per phase of a hybrid, plus the centre's for a
    /// Julia set).
    pub fn references(&self) -> usize {
        self.tracks.len()
    }

    /// True when the primary reference escaped before the iteration limit.
    pub fn reference_escaped(&self) -> bool {
        self.tracks[0].escaped
    }

    /// Precision of the reference orbits in bits.
    pub fn bits(&self) -> u64 {
        self.bits
    }

    /// Levels of the primary reference's BLA tree (0 without BLA).
    pub fn bla_levels(&self) -> usize {
        self.t64.first().map_or(0, Table::depth)
    }

    /// BLA steps stored, over every reference (f64 tables).
    pub fn bla_steps(&self) -> usize {
        self.t64.iter().map(Table::len).sum()
    }

    /// Steps from dip to dip of the references' orbits (f64 tables; see `bla`), and the
    /// most stages of dips of any.
    pub fn dip_steps(&self) -> (usize, usize) {
        self.t64.iter().map(Table::dip_steps).fold((0, 0), |(n, k), (a, b)| (n + a, k.max(b)))
    }

    /// Seconds the reference orbits took.
    pub fn orbit_seconds(&self) -> f64 {
        self.orbit_seconds
    }

    /// Seconds the BLA tables took.
    pub fn tables_seconds(&self) -> f64 {
        self.tables_seconds
    }
}

#[cfg(test)]
mod tests;
