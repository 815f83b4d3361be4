//! The perturbation loop: every sample iterated as a delta against the reference orbit.
//!
//! With the reference Z_m and a sample's full value z = Z_m + δ, the map z -> z^2 + c
//! becomes δ -> (2 Z_m + δ) δ + δc (δc = the sample's offset from the reference parameter,
//! zero for Julia sets, whose delta lives in z_0). The loop is written once, generic over
//! the delta's number type ([`Real`]: f64, or `FloatExp` for deltas below 2^-480 in views
//! past the f64 range); the driver switches a sample between the two as its delta crosses
//! the range where every term of the step is a normal f64.
//!
//! Rebasing (Zhuoran): when |Z_m + δ| < |δ| the sample is closer to 0 than to the
//! reference, so it continues from the start of an orbit of 0 with δ = the full value.
//! For the Mandelbrot set that orbit is the reference itself (Z_0 = 0); a Julia reference
//! starts at the view's centre, so Julia sets rebase onto a second reference, the critical
//! orbit 0, c, c^2 + c, ... One reference then serves every sample, and the loop also
//! rebases when a sample outlives its reference (the reference escaped). Pauldelbrot's
//! glitch criterion |Z_m + δ| < 1e-3 |Z_m| is checked after the rebase test as a safety
//! net: it is counted, and a sample it flags is rebased (fixed) rather than painted.
//!
//! The derivative (for distance estimates) is carried scaled by the sample spacing, as an
//! f64 mantissa pair with its own binary exponent, renormalised when it leaves 2^+-500: it
//! overflows f64 long before deltas do (it grows like 4^n where |z| lingers near 2).
//! Traps observe z = Z_m + δ in f64 at every iteration, so BLA (which skips iterations) is
//! off when traps are on.
//!
//! With interior detection ([`super::interior`]) each sample also carries |dz/dz|^2, the
//! squared modulus of its orbit's derivative with respect to its own start, and stops as
//! interior once that falls below the threshold: a single step multiplies it by 4 |z|^2
//! (the |z|^2 of the escape test), a BLA step by the squared modulus of the step's Jacobian
//! in the delta, and a rebase leaves it alone (the sample's z does not change, only the
//! reference index). Where the reference is one period of a nucleus, each end of a turn
//! may also try Newton's method for an attracting cycle (`Perturbation::newton_probe`),
//! and before any sample of a batch is iterated, disks of parameters in the minibrot's
//! cardioid and bulbs are certified interior whole (`Perturbation::certified_disks`).
//! It is off with traps, which must see every iteration.
//!
//! Where the reference is one period of a nucleus, samples near the minibrot go round it
//! turn after turn (rebase at Z_p, a single step, one period-aligned BLA step from Z_1 back
//! to Z_p): those passes run in a loop of their own (`Perturbation::turns`) that does the
//! same operations in the same order without searching the table at Z_1 each time.
//!
//! This file holds the sample's state, the drivers and the loop's passes (`op`); beside it:
//! where a sample starts (`start`), the view-wide skip (`skip`), the derivative's
//! representation (`der`), the turn loop (`turns`), the packed tail's loop (`tail`), the
//! vector lanes (`lanes`), and interior detection's Newton test (`probe`), quadratic model
//! (`model`, `batch_models`) and certified disks (`disks`).

pub(in crate::orbit) mod der;
mod lanes;
mod report;
mod skip;
pub(in crate::orbit) mod start;
mod tail;
mod turns;

use std::sync::atomic::AtomicBool;

use super::bla::{BlaTable, Step};
use super::interior::model::Model;
use super::interior::probe::Probe;
use super::interior::{Check, Contraction, Decision, Detection};
use super::reference::Reference;
use crate::formula::end::Orbit;
use crate::num::real::{cadd, cconv, cmul, cto_f64, norm2};
use crate::num::{FloatExp, Real};
use crate::simd_level::SimdLevel;
use crate::trap::{Trap, TrapState};
use der::{DER_HI, DER_LO, DER_TINY_Z2, Der};
pub use skip::Skip;

/// The longest cycle interior detection's Newton test looks for, in periods of a nucleus's
/// reference (bulbs of the minibrot up to this period).
pub(in crate::orbit) const MAX_CYCLE_PERIODS: u32 = 8;
/// A sample's [`Probe::at`] once it is to try no more Newton tests.
pub(in crate::orbit) const NEVER: u32 = u32::MAX;
/// A Newton test of k turns from the quadratic model's cycle is tried only where the
/// iteration limit holds this many of them ([`model::MAX_PERIODS`]).
pub(in crate::orbit) const MODEL_TURNS_SPARE: u64 = 16;
/// A rebase to a full value below this (max norm) moves a sample from f64 to FloatExp in the
/// hybrid mode: the next step is δ^2 + δc (Z_0 = 0), and δ^2 must stay a normal f64 well
/// above the offset δc, which at these depths is below the f64 range.
const DOWN: f64 = f64::from_bits((1023 - 500) << 52);
/// Deltas above this move a sample from FloatExp back to f64: every term of the step
/// (δ^2 included) is then a normal f64. (Switching at 2^-896, where only δ itself is
/// normal, `deepfield compare` at zoom 1e320 found N off by one on 5% of pixels.)
const UP: f64 = f64::from_bits((1023 - 480) << 52);
/// Pauldelbrot's criterion, squared: |Z + δ|^2 < GLITCH2 |Z|^2 flags a glitch.
const GLITCH2: f64 = 1e-6;
/// Which number types the deltas use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Numbers {
    /// f64 only (views whose sample spacing is well inside the f64 range).
    F64,
    /// FloatExp while a delta is below 2^-480, f64 above.
    FloatExp,
}

/// Counts of what the loop did, summed over samples.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counters {
    /// Iterations the samples advanced (perturbation steps plus BLA-skipped iterations).
    pub iterations: u64,
    /// Perturbation steps performed one at a time.
    pub steps: u64,
    /// Steps taken in FloatExp.
    pub floatexp_steps: u64,
    /// BLA steps applied.
    pub bla_steps: u64,
    /// Iterations covered by BLA steps.
    pub bla_iterations: u64,
    /// Of the BLA steps, those over whole blocks of a packed tail ([`crate::orbit::bla::TailSteps`]).
    pub tail_steps: u64,
    /// Rebases to the start of an orbit of 0.
    pub rebases: u64,
    /// Samples Pauldelbrot's criterion flagged (each was fixed by rebasing).
    pub glitches: u64,
    /// Samples interior detection stopped before the iteration limit.
    pub interior: u64,
    /// Of those, samples Newton's test found (the rest: the contraction criterion).
    pub newton: u64,
    /// Of those, samples in disks of parameters certified at once, which took no iteration
    /// ([`super::interior::disk_attracting`]).
    pub disks: u64,
}

impl Counters {
    /// Adds `o`.
    pub fn add(&mut self, o: &Counters) {
        self.iterations += o.iterations;
        self.steps += o.steps;
        self.floatexp_steps += o.floatexp_steps;
        self.bla_steps += o.bla_steps;
        self.bla_iterations += o.bla_iterations;
        self.tail_steps += o.tail_steps;
        self.rebases += o.rebases;
        self.glitches += o.glitches;
        self.interior += o.interior;
        self.newton += o.newton;
        self.disks += o.disks;
    }
}

/// The orbits and tables the loop runs against, shared by all samples.
#[derive(Debug)]
pub struct Perturbation {
    /// [primary reference, orbit of 0 used after rebasing]; Mandelbrot has only the first
    /// (its reference starts at 0 and serves both).
    /// Shared (`Arc`) with every [`Perturbation::with_spacing`] of it.
    pub(in crate::orbit) refs: std::sync::Arc<Vec<Reference>>,
    /// BLA tables per reference in FloatExp and f64 (None: BLA off).
    pub(in crate::orbit) bla_fe: std::sync::Arc<[Option<BlaTable<FloatExp>>; 2]>,
    /// The same tables for f64 deltas.
    pub(in crate::orbit) bla_f64: std::sync::Arc<[Option<BlaTable<f64>>; 2]>,
    /// The largest |δc| (plane units) the tables and `skip` were built for: the view's
    /// extent, spacing × largest offset (times the reach asked for, see
    /// `render::Options::deep_reach`).
    pub(in crate::orbit) extent: FloatExp,
    /// Where the raster's centre lies from the reference point (plane units): zero for a
    /// render of its own; a viewer panning about an older reference sets it.
    pub(in crate::orbit) origin: [FloatExp; 2],
    /// True for Mandelbrot (δc is the sample offset; the derivative adds the spacing).
    pub(in crate::orbit) mandelbrot: bool,
    /// Sample spacing.
    pub(in crate::orbit) spacing: FloatExp,
    /// Largest iteration index.
    pub(in crate::orbit) max_iter: u32,
    /// Escape radius squared.
    pub(in crate::orbit) escape2: f64,
    /// Carry the derivative.
    pub(in crate::orbit) derivative: bool,
    /// Interior detection's threshold and window (see [`super::interior`]); None: off (not
    /// asked for, or a Julia set whose parameter is not inside the Mandelbrot set).
    pub(in crate::orbit) interior: Option<Check>,
    /// What the scene asked of interior detection.
    pub(in crate::orbit) interior_asked: Detection,
    /// What was decided, and why.
    pub(in crate::orbit) interior_decision: Decision,
    /// For a nucleus's reference of period p: Λ = f^(p-1)'(c) = 2 Z_1 · 2 Z_2 ⋯ 2 Z_(p-1),
    /// the coefficient of the quadratic model f^p(w) ≈ f^p(0) + Λ w² near 0 that interior
    /// detection's first Newton test starts from.
    pub(in crate::orbit) renormal: Option<[FloatExp; 2]>,
    /// With [`Perturbation::renormal`]: K = Λ ∂Z_p/∂c at the nucleus, which takes a sample's
    /// offset δc to the quadratic model's parameter c' = K δc to first order
    /// (`Perturbation::compute_model_scale`; set once the engine is built).
    pub(in crate::orbit) model_scale: Option<[FloatExp; 2]>,
    /// Delta number types.
    pub(in crate::orbit) numbers: Numbers,
    /// The BLA steps every sample takes first (None: BLA off, or no step is valid for all).
    pub(in crate::orbit) skip: Option<Skip>,
    /// BLA is tried only while |δ|^2 is at most this (f64 phase); above it a sample takes
    /// single steps, which run in vector lanes (see [`single_step_threshold`]); 0 with
    /// BLA off.
    pub(in crate::orbit) single_d2: f64,
    /// Take the turns of a nucleus's reference (rebase at its end, a single step, one
    /// period-aligned step back to the end) in a loop of their own; false runs them through
    /// the general loop, which gives the same bits (for tests and measurements).
    pub(in crate::orbit) turn_loop: bool,
    /// Find the samples of a batch that lie in the minibrot's cardioid or bulbs together, by
    /// disks of parameters certified interior (`Perturbation::certified_disks`): true by
    /// default; false iterates each sample, for comparing the two.
    pub(in crate::orbit) disks: bool,
    /// Seconds the reference orbit(s) took.
    pub(in crate::orbit) orbit_seconds: f64,
    /// Seconds the BLA tables took.
    pub(in crate::orbit) tables_seconds: f64,
}

impl Perturbation {
    /// The same engine for a raster of another `spacing` over the same or a smaller extent
    /// (a coarse preview pass of the same view): the reference orbits, tables and common
    /// steps are shared, since they depend on the centre and on the extent of the offsets,
    /// not on the spacing. None when the raster (about [`Perturbation::origin`]) reaches
    /// beyond the extent they were built for, or its spacing needs more bits than the
    /// reference has.
    pub fn with_spacing(&self, spacing: FloatExp, max_offset: f64) -> Option<Perturbation> {
        // `precision_for` keeps 96 bits below the spacing; a zoom-in may use 16 of them
        // (the reference then still errs by less than 2^-80 of a sample spacing).
        let bits = crate::num::bigfloat::precision_for(spacing.log2() / std::f64::consts::LOG2_10);
        let origin = (self.origin[0] * self.origin[0] + self.origin[1] * self.origin[1]).sqrt();
        if origin + spacing.mul_f64(max_offset) > self.extent || bits > self.refs[0].bits() + 16 {
            return None;
        }
        Some(Perturbation {
            refs: self.refs.clone(),
            bla_fe: self.bla_fe.clone(),
            bla_f64: self.bla_f64.clone(),
            spacing,
            orbit_seconds: 0.0,
            tables_seconds: 0.0,
            ..*self
        })
    }

    /// The same engine for a raster centred `origin` (plane units) away from the reference
    /// point: a pan that keeps the old reference. None when `origin` lies outside the
    /// extent; [`Perturbation::with_spacing`] then checks the raster's own reach.
    pub fn with_origin(&self, origin: [FloatExp; 2]) -> Option<Perturbation> {
        let r = (origin[0] * origin[0] + origin[1] * origin[1]).sqrt();
        (r < self.extent).then(|| Perturbation {
            refs: self.refs.clone(),
            bla_fe: self.bla_fe.clone(),
            bla_f64: self.bla_f64.clone(),
            origin,
            ..*self
        })
    }
}

/// The steps whose radii set where a sample stops looking for BLA steps: level 3, steps of
/// 16 iterations (see [`single_step_threshold`]).
pub const SINGLE_STEP_LEVEL: usize = 3;

/// The fraction of the median radius of [`SINGLE_STEP_LEVEL`]'s steps above which a sample
/// stops looking for BLA steps (until its next rebase).
pub const SINGLE_STEP_FRACTION: f64 = 0.3;

/// `single_d2` for these f64 tables: the median radius of their steps of 16 iterations,
/// times [`SINGLE_STEP_FRACTION`], squared; 0 without tables (or without valid steps).
///
/// Above it, BLA offers a sample only short steps at most indices: 16 single steps in the
/// vector lanes (about 1 ns each) cost less than one scalar lookup and second-order step
/// (about 20 ns), so the sample goes to the lanes. The median, not the largest radius:
/// second-order radii vary by orders of magnitude along an orbit (up to sqrt(ε |Z|)), and a
/// threshold at the largest kept samples in scalar single steps wherever BLA had nothing.
/// Measured at 800x600 (`deepfield render --stats`, two threads, alternating settings; this
/// VM's timings vary by ±20%): against 0.1 times the largest radius of 2-iteration steps,
/// bench-e14 0.29-0.35 s → 0.19-0.25 s, bench-e50 and liiiines within the noise (median
/// of 8-step radii at fraction 1 and of 16-step radii at fraction 1 were similar).
pub fn single_step_threshold(tables: &[Option<BlaTable<f64>>]) -> f64 {
    let mut r2: Vec<f64> =
        tables.iter().flatten().flat_map(|t| t.radii2(SINGLE_STEP_LEVEL)).filter(|&r| r > 0.0).collect();
    if r2.is_empty() {
        return 0.0;
    }
    let mid = r2.len() / 2;
    let (_, median, _) = r2.select_nth_unstable_by(mid, f64::total_cmp);
    *median * SINGLE_STEP_FRACTION * SINGLE_STEP_FRACTION
}

/// A reference value in the delta's number type: at full range where that is FloatExp
/// (`fe`: the value with its exponent kept, below f64's range too), else the stored f64.
#[inline(always)]
fn reference_value<D: Real>(f: impl FnOnce() -> [f64; 2], fe: impl FnOnce() -> [FloatExp; 2]) -> [D; 2] {
    if D::NAME == FloatExp::NAME {
        cconv(fe())
    } else {
        let g = f();
        [D::from_f64(g[0]), D::from_f64(g[1])]
    }
}

/// A sample found interior (by Newton's test where `newton` says so): counted, and its end.
#[inline(always)]
fn found_interior<D>(local: &mut Counters, newton: bool) -> Option<Exit<D>> {
    local.interior += 1;
    local.newton += u64::from(newton);
    Some(Exit::Done(Orbit::interior()))
}

/// A sample's state in number type D.
#[derive(Debug, Clone, Copy)]
pub(in crate::orbit) struct Sample<D> {
    pub(in crate::orbit) dz: [D; 2],
    pub(in crate::orbit) dc: [D; 2],
    pub(in crate::orbit) m: u32,
    pub(in crate::orbit) which: usize,
    pub(in crate::orbit) n: u32,
    /// The delta went above `single_d2`: single steps only, until the next rebase.
    pub(in crate::orbit) single: bool,
    /// |dz/dz|^2 from the orbit's start (interior detection; unused without it).
    pub(in crate::orbit) shrink: Contraction,
    /// Interior detection's Newton test ([`Perturbation::newton_probe`]).
    pub(in crate::orbit) probe: Probe,
}

impl<D: Real> Sample<D> {
    fn convert<E: Real>(&self) -> Sample<E> {
        let (m, which, n, single, shrink, probe) = (self.m, self.which, self.n, self.single, self.shrink, self.probe);
        Sample { dz: cconv(self.dz), dc: cconv(self.dc), m, which, n, single, shrink, probe }
    }
}

/// A sample on its way through the vector lanes: its output index, state, derivative, the
/// offset at full range, and whether the lanes stopped it for a derivative renormalisation.
#[derive(Debug, Clone, Copy)]
struct Held {
    k: usize,
    s: Sample<f64>,
    der: Der,
    dc_fe: [FloatExp; 2],
    renorm: bool,
}

/// Where a sample is: in its FloatExp or its f64 phase.
enum Phase {
    Fe(Sample<FloatExp>),
    F64(Sample<f64>),
}

/// How a run of the loop in one number type ended.
enum Exit<D> {
    Done(Orbit),
    Switch(Sample<D>),
    /// The sample is at a single step above `single_d2` (f64 phase): the vector lanes take it.
    Vector(Sample<D>),
}

/// How a sample's scalar run ended.
enum Ended {
    Done(Orbit),
    /// Handed to the vector lanes, about to take a single step.
    Vector(Sample<f64>),
}

/// The loop's fixed inputs in number type D.
#[derive(Clone, Copy)]
struct Ctx<'a, D> {
    tables: [Option<&'a BlaTable<D>>; 2],
    add_fe: FloatExp,
    hybrid: bool,
    /// Hand samples above `single_d2` to the vector lanes.
    vector: bool,
    /// The render's cancel flag, for the build of the steps of whole blocks past the BLA
    /// tree ([`BlaTable::lookup_in`]): a sample whose build was cancelled is abandoned.
    cancel: &'a AtomicBool,
}

/// A sample in flight in the interleaved f64 loop.
#[derive(Clone, Copy)]
struct Lane {
    k: usize,
    s: Sample<f64>,
    der: Der,
    start_n: u32,
    dc_fe: [FloatExp; 2],
}

/// Samples the interleaved loop keeps in flight: their dependency chains (each step waits
/// for the previous one's multiply-adds) overlap in the out-of-order core. Measured by
/// alternating binaries (liiiines, 1e50 view): 2 lanes beat 1, 3, 4 and 8 (4 lanes: 25%
/// slower; the lanes' state no longer stays in registers). Stepping the two lanes as two
/// local variables rather than through the array gained another 10-15% (bench-e50 at
/// 400x300: 2.75 s against 3.08 s; 3 lanes as locals: 3.0 s).
const LANES: usize = 2;

impl Perturbation {
    /// Interior detection's check (one that never fires when it is off).
    fn check(&self) -> Check {
        self.interior.unwrap_or(Check::OFF)
    }

    fn ctx<'a, D: Real>(
        &'a self,
        tables: &'a [Option<BlaTable<D>>; 2],
        bla: bool,
        add_fe: FloatExp,
        cancel: &'a AtomicBool,
    ) -> Ctx<'a, D> {
        let tables = if bla { [tables[0].as_ref(), tables[1].as_ref()] } else { [None, None] };
        Ctx { tables, add_fe, hybrid: self.numbers == Numbers::FloatExp, vector: false, cancel }
    }

    /// Iterates the sample at `offset` (in units of the spacing, from the reference point),
    /// letting traps observe every z_k, k >= 1. Returns the orbit's end; z_n is exact to f64
    /// and dz_n is the derivative times the spacing. `cancel`: the render's flag; once it is
    /// raised the orbit may be cut short (a cancelled render keeps no sample), though only
    /// where the steps of whole blocks past the BLA tree were to be built for it.
    pub fn orbit(
        &self,
        offset: [f64; 2],
        traps: &[Trap],
        states: &mut [TrapState],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) -> Orbit {
        let (start, mut der, add_fe) = self.start(offset, None, traps.is_empty(), counters);
        let fe = self.starts_in_floatexp(&start);
        let phase = if fe { Phase::Fe(start) } else { Phase::F64(start.convert()) };
        self.finish(phase, start.dc, &mut der, add_fe, traps, states, counters, cancel)
    }

    /// Iterates many samples without traps. Same results as [`Perturbation::orbit`], bit for
    /// bit, whatever `simd` is: with vectors (AVX2, AVX-512, NEON), single steps above
    /// `single_d2` run several samples to a vector (`perturb/lanes.rs`); with `scalar`,
    /// `LANES` samples at a time in the f64 phase (samples in their FloatExp phase run one at
    /// a time).
    ///
    /// In a view centred on a nucleus with interior detection on, groups of samples that lie
    /// in the minibrot's cardioid or bulbs are first found interior together
    /// (`Perturbation::certified_disks`): the same N as iterating them, since each is
    /// interior.
    ///
    /// `cancel` as for [`Perturbation::orbit`].
    pub fn orbits(
        &self,
        offsets: &[[f64; 2]],
        out: &mut [Orbit],
        counters: &mut Counters,
        simd: SimdLevel,
        cancel: &AtomicBool,
    ) {
        let models = self.sample_models(offsets, simd);
        let Some(done) = self.certified_disks(offsets, models.as_deref(), counters) else {
            return self.orbits_each(offsets, models.as_deref(), out, counters, simd, cancel);
        };
        let rest: Vec<usize> = (0..offsets.len()).filter(|&k| !done[k]).collect();
        let at: Vec<[f64; 2]> = rest.iter().map(|&k| offsets[k]).collect();
        let known: Option<Vec<Model>> = models.map(|m| rest.iter().map(|&k| m[k]).collect());
        let mut each = vec![Orbit::interior(); at.len()];
        self.orbits_each(&at, known.as_deref(), &mut each, counters, simd, cancel);
        for (k, d) in done.iter().enumerate() {
            if *d {
                out[k] = Orbit::interior();
            }
        }
        for (&k, o) in rest.iter().zip(each) {
            out[k] = o;
        }
    }

    /// [`Perturbation::orbits`] for samples each iterated; `known`: their
    /// [`Perturbation::start_model`]s where the batch worked them out.
    fn orbits_each(
        &self,
        offsets: &[[f64; 2]],
        known: Option<&[Model]>,
        out: &mut [Orbit],
        counters: &mut Counters,
        simd: SimdLevel,
        cancel: &AtomicBool,
    ) {
        if lanes::orbits(self, offsets, known, out, counters, simd, cancel) {
            return;
        }
        match (self.derivative, self.interior.is_some()) {
            (false, false) => self.orbits_with::<false, false>(offsets, known, out, counters, cancel),
            (true, false) => self.orbits_with::<true, false>(offsets, known, out, counters, cancel),
            (false, true) => self.orbits_with::<false, true>(offsets, known, out, counters, cancel),
            (true, true) => self.orbits_with::<true, true>(offsets, known, out, counters, cancel),
        }
    }

    /// [`Perturbation::orbits`] with the derivative carried or not (`DER`) and interior
    /// detection on or off (`INT`), compiled apart so that the common case has no branches of
    /// either in its loop.
    fn orbits_with<const DER: bool, const INT: bool>(
        &self,
        offsets: &[[f64; 2]],
        known: Option<&[Model]>,
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) {
        let add_fe = self.add_fe();
        let c64 = self.ctx(&self.bla_f64, true, add_fe, cancel);
        let mut lanes: [Option<Lane>; LANES] = [None; LANES];
        let mut next = 0;
        let mut local = Counters::default();
        loop {
            for slot in lanes.iter_mut() {
                while slot.is_none() && next < offsets.len() {
                    let k = next;
                    next += 1;
                    let (start, mut der, _) = self.start(offsets[k], known.map(|m| m[k]), true, counters);
                    let s = if self.starts_in_floatexp(&start) {
                        let cfe = self.ctx(&self.bla_fe, true, add_fe, cancel);
                        match self.run::<FloatExp>(start, &mut der, cfe, &[], &mut [], counters) {
                            Exit::Done(o) => {
                                out[k] = o;
                                continue;
                            }
                            Exit::Switch(s) | Exit::Vector(s) => s.convert(),
                        }
                    } else {
                        start.convert()
                    };
                    *slot = Some(Lane { k, s, der, start_n: s.n, dc_fe: start.dc });
                }
            }
            if lanes.iter().all(Option::is_none) {
                break;
            }
            // Round robin until a lane finishes; then refill. With both lanes busy they are
            // stepped as two locals, so that their state stays in registers.
            let (l, exit) = match &mut lanes {
                [Some(a), Some(b)] => {
                    let (mut a2, mut b2) = (*a, *b);
                    let r = loop {
                        if let Some(e) = self.op::<f64, DER, INT>(&mut a2.s, &mut a2.der, c64, &[], &mut [], &mut local)
                        {
                            break (0, e);
                        }
                        if let Some(e) = self.op::<f64, DER, INT>(&mut b2.s, &mut b2.der, c64, &[], &mut [], &mut local)
                        {
                            break (1, e);
                        }
                    };
                    (*a, *b) = (a2, b2);
                    r
                }
                _ => {
                    let l = lanes.iter().position(Option::is_some).unwrap_or(0);
                    let Some(lane) = &mut lanes[l] else { continue };
                    (l, self.steps::<f64, DER, INT>(&mut lane.s, &mut lane.der, c64, &[], &mut [], &mut local))
                }
            };
            if let Some(lane) = &mut lanes[l] {
                local.iterations += (lane.s.n - lane.start_n) as u64;
                out[lane.k] = match exit {
                    Exit::Done(o) => o,
                    Exit::Switch(s) => {
                        let fe = Sample { dc: lane.dc_fe, ..s.convert() };
                        self.finish(Phase::Fe(fe), lane.dc_fe, &mut lane.der, add_fe, &[], &mut [], counters, cancel)
                    }
                    Exit::Vector(_) => unreachable!("the two-lane loop never asks for the vector lanes"),
                };
            }
            lanes[l] = None;
        }
        counters.add(&local);
    }

    /// What the derivative adds per step (the spacing for the Mandelbrot set).
    fn add_fe(&self) -> FloatExp {
        if self.mandelbrot { self.spacing } else { FloatExp::ZERO }
    }

    /// Runs sample `k` from its start until it ends (written to `out`) or reaches a single
    /// step in single-step mode, where it is returned for the vector lanes.
    fn begin(
        &self,
        k: usize,
        offset: [f64; 2],
        known: Option<Model>,
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) -> Option<Held> {
        let (start, der, _) = self.start(offset, known, true, counters);
        let phase = if self.starts_in_floatexp(&start) { Phase::Fe(start) } else { Phase::F64(start.convert()) };
        self.hand_over(phase, k, start.dc, der, out, counters, cancel)
    }

    /// Runs a sample (output index `k`) from `phase` with the lanes in use: writes its orbit
    /// to `out` when it ends, or returns it for the lanes.
    fn hand_over(
        &self,
        phase: Phase,
        k: usize,
        dc_fe: [FloatExp; 2],
        mut der: Der,
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) -> Option<Held> {
        match self.drive(phase, dc_fe, &mut der, self.add_fe(), &[], &mut [], true, counters, cancel) {
            Ended::Done(o) => {
                out[k] = o;
                None
            }
            Ended::Vector(s) => Some(Held { k, s, der, dc_fe, renorm: false }),
        }
    }

    /// Runs a sample from `phase` to its end without the lanes.
    #[allow(clippy::too_many_arguments)]
    fn finish(
        &self,
        phase: Phase,
        dc_fe: [FloatExp; 2],
        der: &mut Der,
        add_fe: FloatExp,
        traps: &[Trap],
        states: &mut [TrapState],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) -> Orbit {
        match self.drive(phase, dc_fe, der, add_fe, traps, states, false, counters, cancel) {
            Ended::Done(o) => o,
            Ended::Vector(_) => unreachable!("drive hands samples to the lanes only when asked"),
        }
    }

    /// Continues a sample the vector lanes handed back: after a renormalisation of its
    /// derivative (`renorm`), or else at an event the lanes do not handle (escape, the
    /// iteration limit, a rebase or glitch, the reference's end, |dz/dz|^2 out of its
    /// window or below the threshold), which one full pass of the scalar loop takes care of
    /// before the sample runs on as [`Perturbation::begin`]'s do.
    fn resume(&self, mut h: Held, out: &mut [Orbit], counters: &mut Counters, cancel: &AtomicBool) -> Option<Held> {
        let add_fe = self.add_fe();
        let phase = if h.renorm {
            h.der.renormalise(add_fe);
            Phase::F64(h.s)
        } else {
            let c64 = self.ctx(&self.bla_f64, true, add_fe, cancel);
            let n0 = h.s.n;
            let mut local = Counters::default();
            let (s, der, l) = (&mut h.s, &mut h.der, &mut local);
            let exit = match (self.derivative, self.interior.is_some()) {
                (false, false) => self.op::<f64, false, false>(s, der, c64, &[], &mut [], l),
                (true, false) => self.op::<f64, true, false>(s, der, c64, &[], &mut [], l),
                (false, true) => self.op::<f64, false, true>(s, der, c64, &[], &mut [], l),
                (true, true) => self.op::<f64, true, true>(s, der, c64, &[], &mut [], l),
            };
            local.iterations = (h.s.n - n0) as u64;
            counters.add(&local);
            match exit {
                None => Phase::F64(h.s),
                Some(Exit::Done(o)) => {
                    out[h.k] = o;
                    return None;
                }
                Some(Exit::Switch(s)) => Phase::Fe(Sample { dc: h.dc_fe, ..s.convert() }),
                Some(Exit::Vector(s)) => Phase::F64(s),
            }
        };
        self.hand_over(phase, h.k, h.dc_fe, h.der, out, counters, cancel)
    }

    /// Runs a sample from `phase` to its end, switching number types as its delta asks (with
    /// `vector`, until it reaches a single step in single-step mode in its f64 phase).
    #[allow(clippy::too_many_arguments)]
    fn drive(
        &self,
        mut phase: Phase,
        dc_fe: [FloatExp; 2],
        der: &mut Der,
        add_fe: FloatExp,
        traps: &[Trap],
        states: &mut [TrapState],
        vector: bool,
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) -> Ended {
        let bla = traps.is_empty();
        let cfe = self.ctx(&self.bla_fe, bla, add_fe, cancel);
        let c64 = Ctx { vector, ..self.ctx(&self.bla_f64, bla, add_fe, cancel) };
        loop {
            phase = match phase {
                Phase::Fe(s) => match self.run::<FloatExp>(s, der, cfe, traps, states, counters) {
                    Exit::Done(o) => return Ended::Done(o),
                    Exit::Switch(s) | Exit::Vector(s) => Phase::F64(s.convert()),
                },
                Phase::F64(s) => match self.run::<f64>(s, der, c64, traps, states, counters) {
                    Exit::Done(o) => return Ended::Done(o),
                    Exit::Vector(s) => return Ended::Vector(s),
                    // The offset goes back to FloatExp from the original, never from its
                    // f64 rounding: below 2^-1022 that keeps only a few bits.
                    Exit::Switch(s) => Phase::Fe(Sample { dc: dc_fe, ..s.convert() }),
                },
            }
        }
    }

    /// The loop in number type D, until the sample ends or (hybrid) needs the other type.
    #[inline(never)]
    fn run<D: Real>(
        &self,
        mut s: Sample<D>,
        der: &mut Der,
        ctx: Ctx<'_, D>,
        traps: &[Trap],
        states: &mut [TrapState],
        counters: &mut Counters,
    ) -> Exit<D> {
        let start_n = s.n;
        // Counted locally and added on exit: the loop's state stays in registers.
        let mut local = Counters::default();
        // Traps must see every iteration: no interior detection with them.
        let int = self.interior.is_some() && traps.is_empty();
        let (sm, l) = (&mut s, &mut local);
        let exit = match (self.derivative, int) {
            (false, false) => self.steps::<D, false, false>(sm, der, ctx, traps, states, l),
            (true, false) => self.steps::<D, true, false>(sm, der, ctx, traps, states, l),
            (false, true) => self.steps::<D, false, true>(sm, der, ctx, traps, states, l),
            (true, true) => self.steps::<D, true, true>(sm, der, ctx, traps, states, l),
        };
        if D::NAME == FloatExp::NAME {
            local.floatexp_steps = local.steps;
        }
        local.iterations = (s.n - start_n) as u64;
        counters.add(&local);
        exit
    }

    /// Passes of the loop until the sample ends or must change number type.
    #[inline(always)]
    fn steps<D: Real, const DER: bool, const INT: bool>(
        &self,
        s: &mut Sample<D>,
        der: &mut Der,
        ctx: Ctx<'_, D>,
        traps: &[Trap],
        states: &mut [TrapState],
        local: &mut Counters,
    ) -> Exit<D> {
        loop {
            if let Some(exit) = self.op::<D, DER, INT>(s, der, ctx, traps, states, local) {
                return exit;
            }
        }
    }

    /// One pass of the loop: the end tests (with `INT` first of all, whether the sample has
    /// been found interior), then a rebase, a BLA step or a perturbation step; at the end
    /// of a reference's dense part with a packed tail after it, the tail's loop
    /// ([`Perturbation::tail`]). Returns the exit when the sample ends or must change number
    /// type.
    #[inline(always)]
    fn op<D: Real, const DER: bool, const INT: bool>(
        &self,
        s: &mut Sample<D>,
        der: &mut Der,
        ctx: Ctx<'_, D>,
        traps: &[Trap],
        states: &mut [TrapState],
        local: &mut Counters,
    ) -> Option<Exit<D>> {
        // The previous step may have brought |dz/dz|^2 below the threshold (or out of its
        // window): decided first, as the vector lanes do before their other events.
        if INT && s.shrink.interior(self.check()) {
            return found_interior(local, false);
        }
        let full_range = D::NAME == FloatExp::NAME;
        let r = &self.refs[s.which];
        let mut zm: [D; 2] = reference_value(|| r.get(s.m), || r.get_fe(s.m));
        let full = cadd(zm, s.dz);
        let z = cto_f64(full);
        if let Some(exit) = self.ends::<D, DER>(s, z, der, traps, states) {
            return Some(exit);
        }
        let end = s.m >= r.last();
        if end && let Some(packed) = r.packed() {
            return self.tail::<D, DER, INT>(s, der, ctx, (zm, full, z), traps, states, local, packed);
        }
        let d2 = norm2(s.dz);
        let f2 = norm2(full);
        let rebase = f2 < d2 || end;
        let glitch = !rebase && f2 < norm2(zm).mul_f64(GLITCH2);
        if rebase || glitch {
            self.rebase(s, full, glitch, local);
            zm = [D::ZERO; 2];
            if INT && end && !full_range && self.newton_probe(s) {
                return found_interior(local, true);
            }
            if ctx.hybrid && !full_range && z[0].abs().max(z[1].abs()) < DOWN {
                return Some(Exit::Switch(*s));
            }
        } else if self.goes_single(s, d2) {
            if ctx.vector {
                return Some(Exit::Vector(*s));
            }
        } else if let Some(t) = ctx.tables[s.which]
            && let Some(found) = t.lookup_in(s.m, d2, self.max_iter - s.n, ctx.cancel)
        {
            let Ok((e, len)) = found else { return Some(Exit::Done(Orbit::interior())) };
            self.apply_step::<D, DER, INT>((e, len), s, d2, der, ctx.add_fe, local);
            if self.turn_loop
                && !full_range
                && traps.is_empty()
                && s.m == r.last()
                && r.period().is_some()
                && r.packed().is_none()
            {
                return self.turns::<D, DER, INT>(s, der, ctx, local);
            }
            return None;
        }
        self.perturb_step::<D, DER, INT>(s, der, ctx, (zm, full, z, f2), local)
    }

    /// One perturbation step from Z_m = `zm`, with the sample's full value z = Z_m + δ,
    /// z in f64 and |z|^2 in `at`: the derivative and |dz/dz|^2 stepped, δ -> (2 Z_m + δ) δ
    /// + δc. Returns the switch to f64 when a FloatExp delta has grown into f64's range.
    #[inline(always)]
    fn perturb_step<D: Real, const DER: bool, const INT: bool>(
        &self,
        s: &mut Sample<D>,
        der: &mut Der,
        ctx: Ctx<'_, D>,
        (zm, full, z, f2): ([D; 2], [D; 2], [f64; 2], D),
        local: &mut Counters,
    ) -> Option<Exit<D>> {
        if DER {
            der.step(z, full, ctx.add_fe);
        }
        if INT && !s.probe.plain {
            s.shrink.step(full, f2, self.check());
        }
        let two = D::from_f64(2.0);
        s.dz = cadd(cmul(cadd([zm[0] * two, zm[1] * two], s.dz), s.dz), s.dc);
        s.m += 1;
        s.n += 1;
        local.steps += 1;
        let full_range = D::NAME == FloatExp::NAME;
        if full_range && ctx.hybrid && s.dz[0].to_f64().abs().max(s.dz[1].to_f64().abs()) > UP {
            return Some(Exit::Switch(*s));
        }
        None
    }

    /// The end tests at a sample's value z, after the traps have seen it (from z_1 on): it
    /// escaped, or it reached the iteration limit (interior).
    #[inline(always)]
    fn ends<D: Real, const DER: bool>(
        &self,
        s: &Sample<D>,
        z: [f64; 2],
        der: &Der,
        traps: &[Trap],
        states: &mut [TrapState],
    ) -> Option<Exit<D>> {
        if s.n >= 1 {
            for (trap, state) in traps.iter().zip(states.iter_mut()) {
                trap.observe(state, z);
            }
        }
        if z[0] * z[0] + z[1] * z[1] > self.escape2 {
            let dz = if DER { der.to_f64() } else { [0.0; 2] };
            return Some(Exit::Done(Orbit { n: s.n, z, dz }));
        }
        if s.n >= self.max_iter {
            return Some(Exit::Done(Orbit::interior()));
        }
        None
    }

    /// A rebase (Zhuoran's: the sample is nearer 0 than the reference, or the reference
    /// ended) or a glitch's: the sample's full value becomes its delta against the start
    /// of the last reference (Z_0 = 0 for the Mandelbrot set and a Julia set's orbit of 0).
    #[inline(always)]
    fn rebase<D: Real>(&self, s: &mut Sample<D>, full: [D; 2], glitch: bool, local: &mut Counters) {
        local.glitches += glitch as u64;
        local.rebases += 1;
        s.dz = full;
        s.m = 0;
        s.which = self.refs.len() - 1;
        s.single = false;
    }

    /// Whether a sample takes single steps rather than looking a BLA step up, in the f64
    /// phase: its delta went above `single_d2` since its last rebase (which clears it), where
    /// BLA steps are rarely valid and the vector lanes take single steps faster. The dense
    /// loop and a packed tail's decide alike, so that a sample steps the same either way.
    #[inline(always)]
    fn goes_single<D: Real>(&self, s: &mut Sample<D>, d2: D) -> bool {
        let single = D::NAME != FloatExp::NAME && (s.single || d2.to_f64() > self.single_d2);
        s.single |= single;
        single
    }

    /// [`Perturbation::apply_bla`], without interior detection's products for a sample that
    /// left detection at its start ([`Probe::plain`]).
    #[inline(always)]
    fn apply_step<D: Real, const DER: bool, const INT: bool>(
        &self,
        step: (Step<'_, D>, u32),
        s: &mut Sample<D>,
        d2: D,
        der: &mut Der,
        add_fe: FloatExp,
        local: &mut Counters,
    ) {
        if INT && s.probe.plain {
            self.apply_bla::<D, DER, false>(step, s, d2, der, add_fe, local);
        } else {
            self.apply_bla::<D, DER, INT>(step, s, d2, der, add_fe, local);
        }
    }

    /// δ -> A δ + B δc + A2 δ^2 + AB δ δc + B2 δc^2 (first order only where that is valid
    /// for |δ|^2 = `d2`), and the derivative by the step's Jacobian: in f64 when its entries
    /// are moderate (the common case), else in FloatExp (they may be huge at depth). With
    /// `INT`, |dz/dz|^2 is multiplied by |d(δ')/d(δ)|^2 (A + 2 A2 δ + AB δc, or A for a
    /// first-order step). The new δ is the same bits whether or not the Jacobian is
    /// computed. The sample moves on by the step's length `len`, and it is counted.
    #[inline(always)]
    fn apply_bla<D: Real, const DER: bool, const INT: bool>(
        &self,
        (e, len): (Step<'_, D>, u32),
        s: &mut Sample<D>,
        d2: D,
        der: &mut Der,
        add_fe: FloatExp,
        local: &mut Counters,
    ) {
        s.m += len;
        s.n += len;
        local.bla_steps += 1;
        local.bla_iterations += u64::from(len);
        let linear = e.linear(d2);
        if !DER && !INT {
            s.dz = if linear { cadd(cmul(e.first.a, s.dz), cmul(e.first.b, s.dc)) } else { e.apply(s.dz, s.dc) };
            return;
        }
        let (dz, m, n) = if linear {
            (cadd(cmul(e.first.a, s.dz), cmul(e.first.b, s.dc)), e.first.a, e.first.b)
        } else {
            e.apply_with_jacobian(s.dz, s.dc)
        };
        if DER {
            der.jacobian(cto_f64(m), cto_f64(n), || (cconv(m), cconv(n)), add_fe);
        }
        s.dz = dz;
        if INT {
            s.shrink.bla_step(m, self.check());
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::AtomicBool;

    use super::*;
    use crate::cancel::NEVER;
    use crate::num::Decimal;
    use crate::orbit::{DeepSpec, Scale, prepare};

    const MINIBROT: [&str; 2] = [
        "-1.768610493014677074503175653270265220239677907588665494837677257575304640978808475274635707362464",
        "0.001266613503868717702066412241102601576193940560471409817185010171762524792588903616691501346028",
    ];
    /// -2 + 1.6e-102 + 1.4e-211 i (the liiiines location), to 1e-330.
    const LIIIINES: [&str; 2] = [
        "-1.99999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999837485382669331911167033522316925483202642018042879214193261311019861349448517336056952538528636093441258319101518468947695052924660781278387926133612368999268678559118848357284879481437613458535637431620616343911585652641236167774248507873",
        "1.37178052090609414145729128541350514525330839736695026708710030908880680107546729978680204559181338295039364573873196577319068006687895587728672855990826461331344843897843243379157581698185171855284714599499709801317677506729468150382879822938996916336090559197836550022966441254042166415444219105895943405807252402353950295056242178258440758e-211",
    ];
    /// The 1e50 benchmark location, to 1e-70: thousands of single steps per sample, with
    /// derivatives that leave their exponent window many times on the way.
    const E50: [&str; 2] = [
        "-0.04947002906310409375169222672735363011874571248822487931810494023264219477268690",
        "-0.67478757584467536401139205313059765633477070682240348069799979479099419834548451",
    ];
    /// The nucleus of a period-1429 minibrot near the all-seeing-eye location (`deepfield
    /// find scenes/locations/all-seeing-eye.toml --zoom 1e70`), size 1.6e-102.
    const EYE_MINIBROT: [&str; 2] = [
        "-0.83031842675693053553109980802050591726924580592100415017586803599827560339120465373468510811787516730515186454892834980632246054605795",
        "0.23612476396680780363307856325882633547132442124365456398110558858530832926040168389957117374824216611986058042279006600832794659929318",
    ];
    const JULIA_CENTER: [&str; 2] = [
        "1.49899848626690059854946357005252043405194888410281635160902340639312066973795336",
        "-0.06597870537952971836904746440551643923003302222753852735309069970961233737180929",
    ];

    /// Where an orbit passes near 0 the Mandelbrot derivative collapses to its added term
    /// (dz -> 2 z dz + 1): a single step from a tiny z, or a BLA step with a tiny multiplier,
    /// must keep that term although it is far below the derivative's f64 mantissa (at depth
    /// it underflows there; bench-e1086 lost its distance estimates this way).
    #[test]
    fn derivative_keeps_its_added_term_where_the_orbit_passes_near_zero() {
        let spacing = FloatExp::new(1.0, -3600);
        let close = |v: [FloatExp; 2], want: [f64; 2]| {
            let got = [v[0].ldexp(3600).to_f64(), v[1].ldexp(3600).to_f64()];
            assert!((got[0] - want[0]).abs() < 1e-12 && (got[1] - want[1]).abs() < 1e-12, "{got:?} != {want:?}");
        };
        // dz/dc ~ 2^3000, so the scaled derivative is ~2^-600 and the spacing is 2^-3000 of it.
        let start = Der::from_fe([FloatExp::new(1.5, -600), FloatExp::new(-0.5, -600)], spacing);
        let tiny = [FloatExp::new(1.0, -3200), FloatExp::new(1.0, -3201)];
        let mut der = start;
        der.step(cto_f64(tiny), tiny, spacing);
        close(der.to_fe(), [1.0, 0.0]);
        // A BLA step whose multiplier is below f64's range and whose added part is 3 + 2i.
        let (m, n) = (tiny, [FloatExp::from(3.0), FloatExp::from(2.0)]);
        let mut der = start;
        der.jacobian(cto_f64(m), cto_f64(n), || (m, n), spacing);
        close(der.to_fe(), [3.0, 2.0]);
        // Away from 0 the f64 path gives 2 z dz (+ a negligible spacing).
        let z = [FloatExp::from(0.5), FloatExp::from(0.25)];
        let mut der = start;
        der.step(cto_f64(z), z, spacing);
        let want = cmul([FloatExp::from(1.0), FloatExp::from(0.5)], start.to_fe());
        let got = der.to_fe();
        for k in 0..2 {
            assert!((got[k].ldexp(600).to_f64() - want[k].ldexp(600).to_f64()).abs() < 1e-15, "{got:?} {want:?}");
        }
    }

    /// The view's common BLA steps, composed as a quadratic in the offset u, against single
    /// perturbation steps of each sample (FloatExp, exact to rounding) at the floral-fantasy
    /// location (c near -2: orbits linger at |z| = 2, where a step's quadratic term is up to
    /// a quarter of its linear one). The composite once dropped the cubic terms of that
    /// composition unchecked and was off by tens of percent at the view's corners.
    #[test]
    fn view_wide_skip_agrees_with_stepping_each_sample() {
        const FLORAL: [&str; 2] = [
            "-1.9990959962659111838532086240451464723873699879106041072875027138225861729613819461216022699999999999999999999999",
            "0.0000002758071979815309980117897130508770848629719975198765589767776483289612775591171197799999999999999999999999",
        ];
        for (eps, radius) in [(1e-8, "1.2869e-85"), (1e-14, "1.2869e-85"), (1e-10, "1e-60")] {
            let (w, h) = (64.0, 48.0);
            let max_offset = f64::hypot(w, h) / 2.0;
            let spec = DeepSpec {
                center: dec(FLORAL),
                julia: None,
                spacing: Scale::Radius(Decimal::parse(radius).unwrap()).spacing(h as u32),
                max_offset,
                max_iter: 12000,
                escape_radius: 65536.0,
                derivative: false,
                bla: Some(eps),
                interior: Detection::Off,
                numbers: Numbers::FloatExp,
                simd: SimdLevel::detect(),
                references: None,
                dense_orbit: None,
            };
            let p = prepare(&spec, &|_, _| {}, &AtomicBool::new(false)).expect("prepared");
            let skip = p.skip.expect("the view has common steps");
            assert!(skip.m > 100, "{radius}: the skip covers {} iterations", skip.m);
            let r = &p.refs[0];
            let mut worst = 0.0f64;
            for k in 0..16 {
                let angle = k as f64 * std::f64::consts::TAU / 16.0;
                let scale = if k % 2 == 0 { 1.0 } else { 0.37 };
                let off = [scale * max_offset * angle.cos(), scale * max_offset * angle.sin()];
                let u = [p.spacing.mul_f64(off[0]), p.spacing.mul_f64(off[1])];
                let mut d = u;
                for m in 1..skip.m {
                    let zm = r.get_fe(m);
                    d = cadd(cmul(cadd([zm[0].ldexp(1), zm[1].ldexp(1)], d), d), u);
                }
                let [k1, k2] = skip.k;
                let composite = cadd(cmul(k1, u), cmul(cmul(k2, u), u));
                let diff = cadd(composite, [-d[0], -d[1]]);
                worst = worst.max((norm2(diff).sqrt() / norm2(d).sqrt()).to_f64());
            }
            // Rounding in ~skip.m single steps, plus ε per composed step at most.
            let allowed = eps * skip.steps as f64 + 1e-13;
            assert!(
                worst <= allowed,
                "{radius} ε {eps}: relative error {worst:e} > {allowed:e} after {} steps",
                skip.steps
            );
        }
    }

    fn dec(v: [&str; 2]) -> [Decimal; 2] {
        [Decimal::parse(v[0]).unwrap(), Decimal::parse(v[1]).unwrap()]
    }

    /// A render cancelled while its samples wait on the build of the steps of whole blocks
    /// (here through a packed tail): the build stops and keeps nothing, the samples are
    /// abandoned rather than single-stepped to the limit, and a later call that is not
    /// cancelled builds the steps and gets the same samples as an engine that was never
    /// cancelled.
    #[test]
    fn a_cancelled_build_of_blocks_abandons_its_samples_and_keeps_nothing() {
        let (w, h) = (8i32, 6i32);
        let max_iter = 400_000;
        let spec = DeepSpec {
            // Inside the main cardioid: every sample runs to the limit, through the tail.
            center: dec(["-0.1", "0.1"]),
            julia: None,
            spacing: Scale::Radius(Decimal::parse("1e-6").unwrap()).spacing(h as u32),
            max_offset: ((w * w + h * h) as f64).sqrt() / 2.0,
            max_iter,
            escape_radius: 2.0,
            derivative: false,
            bla: Some(1e-12),
            interior: Detection::Off,
            numbers: Numbers::F64,
            simd: SimdLevel::detect(),
            references: None,
            dense_orbit: Some(2000),
        };
        let engine = || prepare(&spec, &|_, _| {}, &AtomicBool::new(false)).expect("prepared");
        let offsets: Vec<[f64; 2]> =
            (0..h).flat_map(|j| (0..w).map(move |i| [f64::from(i - w / 2), f64::from(j - h / 2)])).collect();
        let run = |p: &Perturbation, cancel: &AtomicBool, simd: SimdLevel| {
            let mut out = vec![Orbit::interior(); offsets.len()];
            let mut c = Counters::default();
            p.orbits(&offsets, &mut out, &mut c, simd, cancel);
            (out, c)
        };
        let built = |p: &Perturbation| p.bla_f64[0].as_ref().and_then(|t| t.built()).is_some();
        let bits = |o: &Orbit| (o.n, o.z.map(f64::to_bits));
        // Never cancelled, in the scalar loop: what every level must give.
        let (fresh, c_fresh) = run(&engine(), &NEVER, SimdLevel::Scalar);
        let abandoned = offsets.len() as u64 * u64::from(max_iter);
        assert!(c_fresh.iterations > abandoned / 10 * 9, "every sample to about the limit: {}", c_fresh.iterations);
        // The scalar loop and every level's lanes (which hand their samples back to it for
        // the tail's steps) stop alike.
        for simd in SimdLevel::usable() {
            let p = engine();
            assert!(p.refs[0].packed().is_some() && !built(&p), "a packed tail, its blocks not built yet");
            let (_, c) = run(&p, &AtomicBool::new(true), simd);
            assert!(!built(&p), "{simd}: a cancelled build keeps nothing");
            assert_eq!(p.blocks_progress(), None, "{simd}: and shows no progress");
            assert!(c.iterations < abandoned / 10, "{simd}: the samples were abandoned: {} iterations", c.iterations);
            let (again, c) = run(&p, &NEVER, simd);
            assert!(built(&p), "{simd}: built when not cancelled");
            assert_eq!(c, c_fresh, "{simd}: the same counts as never cancelled");
            let same = again.iter().zip(&fresh).all(|(a, b)| bits(a) == bits(b));
            assert!(same, "{simd}: the same samples as never cancelled");
        }
    }

    /// Every sample of a 32x24 view through `orbits` with every instruction set this CPU
    /// runs (the vector lanes of each width, and the two-sample scalar loop) and one at a
    /// time through `orbit`, with interior detection off and on: bit for bit the same
    /// escape, z_n and derivative, and the same iteration, step and interior counts. Interior
    /// detection changes no sample's end but for stopping interior ones earlier (same N,
    /// INTERIOR). Returns the samples found interior by detection, and of those the samples in
    /// certified disks.
    fn same_both_ways(
        center: [&str; 2],
        julia: Option<[&str; 2]>,
        radius: &str,
        max_iter: u32,
        numbers: Numbers,
        bla: Option<f64>,
        dense_limit: Option<u32>,
    ) -> (u64, u64) {
        let (w, h) = (32i32, 24i32);
        let (mut found, mut disks) = (0, 0);
        for derivative in [false, true] {
            let mut without: Option<Vec<Orbit>> = None;
            for interior in [Detection::Off, Detection::On] {
                let spec = DeepSpec {
                    center: dec(center),
                    julia: julia.map(dec),
                    spacing: Scale::Radius(Decimal::parse(radius).unwrap()).spacing(h as u32),
                    max_offset: ((w * w + h * h) as f64).sqrt() / 2.0,
                    max_iter,
                    escape_radius: 2.0,
                    derivative,
                    bla,
                    interior,
                    numbers,
                    simd: SimdLevel::detect(),
                    references: None,
                    dense_orbit: dense_limit,
                };
                let p = prepare(&spec, &|_, _| {}, &AtomicBool::new(false)).expect("prepared");
                let packed = p.refs.iter().any(|r| r.packed().is_some());
                assert_eq!(packed, dense_limit.is_some(), "{radius}: packed as asked");
                let offsets: Vec<[f64; 2]> = (0..h)
                    .flat_map(|j| {
                        (0..w).map(move |i| [i as f64 - w as f64 / 2.0 + 0.5, j as f64 - h as f64 / 2.0 + 0.5])
                    })
                    .collect();
                let mut c_one = Counters::default();
                let mut escaped = 0;
                let one: Vec<Orbit> =
                    offsets.iter().map(|off| p.orbit(*off, &[], &mut [], &mut c_one, &NEVER)).collect();
                let bits = |o: &Orbit| (o.n, o.z.map(f64::to_bits), o.dz.map(f64::to_bits));
                let what = format!("{radius} derivative {derivative} interior {interior:?}");
                // The turns of a nucleus's reference in their own loop and in the general
                // one: the same bits and counts.
                let general = Perturbation {
                    refs: p.refs.clone(),
                    bla_fe: p.bla_fe.clone(),
                    bla_f64: p.bla_f64.clone(),
                    turn_loop: false,
                    ..p
                };
                let mut c_general = Counters::default();
                for (k, off) in offsets.iter().enumerate() {
                    let o = general.orbit(*off, &[], &mut [], &mut c_general, &NEVER);
                    assert_eq!(bits(&o), bits(&one[k]), "{what}: sample {k} differs through the general loop");
                }
                assert_eq!(c_general, c_one, "{what}: counts through the general loop");
                // With disks, the same bits, and the same samples found interior, as each
                // sample iterated; without them, the same counts too.
                let each = Perturbation {
                    refs: p.refs.clone(),
                    bla_fe: p.bla_fe.clone(),
                    bla_f64: p.bla_f64.clone(),
                    disks: false,
                    ..p
                };
                for simd in SimdLevel::usable() {
                    // Every sample through the batch loop, held to its bits alone.
                    let run = |engine: &Perturbation, how: &str| {
                        let mut many = vec![Orbit::interior(); offsets.len()];
                        let mut c = Counters::default();
                        engine.orbits(&offsets, &mut many, &mut c, simd, &NEVER);
                        for k in 0..offsets.len() {
                            assert_eq!(bits(&many[k]), bits(&one[k]), "{what} {simd}{how}: sample {k}");
                        }
                        c
                    };
                    let c_disks = run(&p, " with disks");
                    let counts = |c: &Counters| (c.interior, c.newton);
                    assert_eq!(counts(&c_disks), counts(&c_one), "{what} {simd} with disks");
                    disks += c_disks.disks;
                    let c_many = run(&each, "");
                    // A vector level runs its own lanes, never the scalar loop in their place
                    // (which would pass every comparison above without testing them).
                    let mut lanes_out = vec![Orbit::interior(); offsets.len()];
                    let mut c_lanes = Counters::default();
                    let ran = lanes::orbits(&each, &offsets, None, &mut lanes_out, &mut c_lanes, simd, &NEVER);
                    assert_eq!(ran, simd != SimdLevel::Scalar, "{what} {simd}: its lanes ran");
                    escaped += one.iter().filter(|o| o.n != crate::formula::end::INTERIOR).count() as u32;
                    assert_eq!(c_many.iterations, c_one.iterations, "{what} {simd}: iteration counts");
                    let steps = |c: &Counters| c.steps + c.bla_steps;
                    assert_eq!(steps(&c_many), steps(&c_one), "{what} {simd}: step counts");
                    assert_eq!(c_many.rebases, c_one.rebases, "{what} {simd}: rebases");
                    assert_eq!(c_many.interior, c_one.interior, "{what} {simd}: samples found interior");
                    assert_eq!(c_many.newton, c_one.newton, "{what} {simd}: samples found by Newton's test");
                }
                assert!(escaped > 0 && c_one.steps > 1000, "{radius}: the view must exercise single steps");
                // A packed tail with BLA: samples cross it by its blocks' steps too (the Julia
                // view's tail is its orbit of 0's, which samples follow after a rebase with
                // deltas as large as the orbit, too large for a block's step).
                let tail = packed && bla.is_some() && julia.is_none();
                assert!(c_one.tail_steps > 0 || !tail, "{what}: steps through the packed tail");
                assert!(c_one.tail_steps == 0 || bla.is_some(), "{what}: tail steps without BLA");
                match &without {
                    None => {
                        assert_eq!(c_one.interior, 0, "{what}");
                        without = Some(one);
                    }
                    Some(off) => {
                        for k in 0..offsets.len() {
                            assert_eq!(bits(&one[k]), bits(&off[k]), "{what}: sample {k} differs from detection off");
                        }
                        found += c_one.interior;
                    }
                }
            }
        }
        (found, disks)
    }

    #[test]
    fn lanes_match_one_sample_at_a_time() {
        let eps = Some(crate::orbit::DEFAULT_BLA_TOLERANCE);
        same_both_ways(MINIBROT, None, "2e-30", 6000, Numbers::F64, eps, None);
        same_both_ways(MINIBROT, None, "2e-30", 6000, Numbers::F64, None, None);
        same_both_ways(MINIBROT, None, "1e-12", 3000, Numbers::F64, eps, None);
        same_both_ways(LIIIINES, None, "2e-310", 12500, Numbers::FloatExp, eps, None);
        same_both_ways(E50, None, "2e-50", 263010, Numbers::F64, eps, None);
        // Without BLA, |z| lingers at 2 and the derivative leaves its window in the lanes.
        same_both_ways(LIIIINES, None, "2e-310", 12500, Numbers::FloatExp, None, None);
        same_both_ways(JULIA_CENTER, Some(["-0.7436447860", "0.1318252536"]), "2e-40", 3000, Numbers::F64, eps, None);
        same_both_ways(JULIA_CENTER, Some(["-0.7436447860", "0.1318252536"]), "2e-40", 3000, Numbers::F64, None, None);
        // References packed after a few hundred iterations: the lanes hand samples back at
        // the dense part's end and the scalar loop takes them through the tail.
        same_both_ways(MINIBROT, None, "2e-30", 6000, Numbers::F64, eps, Some(400));
        same_both_ways(LIIIINES, None, "2e-310", 12500, Numbers::FloatExp, eps, Some(900));
        let julia = Some(["-0.7436447860", "0.1318252536"]);
        same_both_ways(JULIA_CENTER, julia, "2e-40", 3000, Numbers::F64, eps, Some(300));
    }

    /// The step the turn loop takes at Z_1 of a nucleus's reference without searching
    /// ([`BlaTable::fixed_step`]) is the one the search finds, for every |δ|^2 below its
    /// bound and every budget that holds it; at the bound, or with a budget one short, the
    /// search finds another.
    #[test]
    fn the_turn_loops_step_is_the_one_the_search_finds() {
        let (w, h) = (32u32, 24u32);
        let spec = DeepSpec {
            center: dec(EYE_MINIBROT),
            julia: None,
            spacing: Scale::Radius(Decimal::parse("1e-102").unwrap()).spacing(h),
            max_offset: f64::from(w * w + h * h).sqrt() / 2.0,
            max_iter: 100_000,
            escape_radius: 2.0,
            derivative: true,
            bla: Some(crate::orbit::DEFAULT_BLA_TOLERANCE),
            interior: Detection::Off,
            numbers: Numbers::F64,
            simd: SimdLevel::detect(),
            references: None,
            dense_orbit: None,
        };
        let p = prepare(&spec, &|_, _| {}, &AtomicBool::new(false)).expect("prepared");
        let r = &p.refs[0];
        assert_eq!(r.period(), Some(r.last()), "one period of the nucleus's orbit");
        let table = p.bla_f64[0].as_ref().expect("tables");
        let (step, len, bound) = table.fixed_step(1).expect("an aligned step from Z_1");
        assert_eq!(1 + len, r.last(), "the step reaches the period's end");
        assert!(bound > 0.0, "{bound}");
        let same = |found: Option<(Step<'_, f64>, u32)>| {
            found.is_some_and(|(s, l)| {
                l == len && std::ptr::eq(s.first, step.first) && std::ptr::eq(s.second, step.second)
            })
        };
        for k in 0..400 {
            let z2 = bound * (1.0 - 1e-15) * 10f64.powf(-f64::from(k) / 10.0);
            for budget in [len, len + 1, u32::MAX] {
                assert!(same(table.lookup(1, z2, budget)), "|z|^2 = {z2:e}, budget {budget}");
            }
        }
        assert!(!same(table.lookup(1, bound, u32::MAX)), "at the bound");
        assert!(!same(table.lookup(1, bound * 0.5, len - 1)), "a budget one short");
    }

    /// The period-1429 minibrot of the all-seeing-eye location (size 1.6e-102): its
    /// interior samples are found by detection in the vector lanes, the two-sample loop and
    /// one at a time alike, with f64 and FloatExp deltas, with and without BLA.
    #[test]
    fn lanes_match_one_sample_at_a_time_with_interior_found() {
        let eps = Some(crate::orbit::DEFAULT_BLA_TOLERANCE);
        for (numbers, bla) in [(Numbers::F64, eps), (Numbers::FloatExp, eps), (Numbers::F64, None)] {
            let (found, disks) = same_both_ways(EYE_MINIBROT, None, "1e-102", 100_000, numbers, bla, None);
            assert!(found > 100, "{numbers:?} {bla:?}: {found} samples found interior");
            // Disks need f64 deltas (Newton's arithmetic).
            assert_eq!(disks > 0, numbers == Numbers::F64, "{numbers:?} {bla:?}: {disks} samples in disks");
        }
        // A nucleus's reference packed before its period ends: no Newton test, found by
        // the contraction alone.
        let (found, _) = same_both_ways(EYE_MINIBROT, None, "1e-102", 100_000, Numbers::F64, eps, Some(700));
        assert!(found > 100, "packed after 700: {found} samples found interior");
        // The whole of a Julia set whose parameter is inside the period-3 bulb (the rabbit).
        let (found, _) = same_both_ways(["0", "0"], Some(["-0.12", "0.75"]), "1.3", 20000, Numbers::F64, eps, None);
        assert!(found > 100, "rabbit: {found} samples found interior");
    }
}
