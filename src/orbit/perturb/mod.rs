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
//! This file holds the sample's state and the loop's passes (`op`); beside it: the drivers
//! (`drive`), where a sample starts (`start`), the view-wide skip (`skip`), the
//! derivative's representation (`der`), the turn loop (`turns`), the packed tail's loop
//! (`tail`), the vector lanes (`lanes`) and what the engine reports (`report`). Interior
//! detection's Newton test, quadratic models and certified disks are their own wing,
//! [`crate::orbit::interior`].

pub(in crate::orbit) mod der;
mod drive;
mod lanes;
mod report;
mod series;
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
pub use series::Series;
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
    /// Samples that started from the view's series ([`Series`]).
    pub series: u64,
    /// Iterations those samples skipped by it.
    pub series_iterations: u64,
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
        self.series += o.series;
        self.series_iterations += o.series_iterations;
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
    /// extent, spacing × largest offset (times the requested reach, see
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
    /// requested, or a Julia set whose parameter is not inside the Mandelbrot set).
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
    /// The view's series, where it reaches past `skip` (see [`Series`]).
    pub(in crate::orbit) series: Option<Series>,
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
    /// Whether samples carry the derivative (a distance estimate is wanted).
    pub fn derivative(&self) -> bool {
        self.derivative
    }

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
/// Measured at 800x600 (`deepfield render --stats`, two threads, alternating settings; that
/// machine's timings vary by ±20%): against 0.1 times the largest radius of 2-iteration steps,
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
        let mut end = s.m >= r.last();
        if end && let Some(w) = r.cycle() {
            // The orbit repeats from here: Z_m = Z_(m - w) exactly, so the sample goes on
            // from there with the same delta (and `zm` is that value already).
            s.m -= w;
            end = false;
        }
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
mod tests;
