//! The generic engine's single steps in vector lanes: `L` samples of one family in flight
//! as `[f64; L]` arrays ([`Num`]), compiled per family and per instruction set (pulp's
//! dispatch enables AVX2 or AVX-512, and the lane loops become vector instructions), a
//! finished lane refilled with the next sample at once.
//!
//! One sample's loop (`perturb.rs`) spends most of its time waiting on the latency of each
//! step's products, which depend on the step before; L independent samples side by side
//! fill that wait. Each pass, every lane loads its reference value Z_m (each lane has its
//! own index), and one vector computation gives the end tests (escape, the limit, a rebase
//! where |Z + δ| < |δ|), the BLA test (the shortest step from m holds |δ|: the table's
//! [`Table::can_step`](super::bla::Table::can_step)) and the single step δ' = f(Z + δ) -
//! f(Z) + δc ([`Map::delta_n`]). A lane that meets none of those events takes that step; a
//! lane that meets one (or sits at its track's next out-of-line index) runs the scalar
//! loop's own pass, [`Engine::iteration`], once: the out-of-line step, the BLA step or the
//! end, exactly as the scalar loop does it. A sample whose delta leaves f64's range goes on
//! in the scalar loop (FloatExp) to its end.
//!
//! A rebase (|Z + δ| < |δ|) is not such an event where the scalar loop takes it in f64
//! (`rebase_delta_f64`'s bounds, tested in the lanes): the lane's step then reads Z_0 = 0
//! with its full value as the delta, in the same vector computation (a select before the
//! step), and goes on from index 1 of the orbit of 0. Deep in the Burning Ship a sample
//! rebases every 10–20 steps, and with 16 lanes in flight nearly every pass had a lane
//! leave for the scalar pass.
//!
//! So every sample takes the steps the scalar loop takes, in the same order, with the same
//! IEEE operations ([`Map::delta_n`] is [`Map::delta`] over lanes; a test holds them to the
//! same bits), and N and z_n are the scalar engine's bits on every SIMD level (a test
//! checks every level this CPU has). With the derivative, each lane also steps the f64
//! mantissa of its Jacobian as [`Jac::step`] does (a result outside the range that step
//! keeps in f64 is an event too), so distance estimates run at the lanes' speed. Hybrids
//! (whose lanes would be at different phases) run in the scalar loop.
//!
//! The lanes' state is held field by field in arrays whose elements are all 64 bits wide
//! (masks included), and a lane's index on its track as the address of its reference value:
//! one-byte masks were packed and unpacked around every compare, and the read of Z_m through
//! a track, an index and a bounds test per lane cost more than the step's arithmetic.
//! `unsafe` here is that one read, through the address (at most the track's last index, as
//! the read says).
#![allow(unsafe_code)]

use std::sync::atomic::{AtomicBool, Ordering};

use pulp::{Simd, WithSimd};

use super::Engine;
use super::bla::Table;
use super::der::Jac;
use super::perturb::{Exit, LEAST, Sample, max_exp};
use crate::formula::end::Orbit;
use crate::formula::map::{Map, Num, Ops};
use crate::formula::phase::MAX_PHASES;
use crate::formula::{Cycle, Phase, Single, Stepper};
use crate::num::FloatExp;
use crate::orbit::{Counters, Numbers};
use crate::simd_level::{LaneJob, SimdLevel};

/// Vector passes between two looks at the cancel flag.
const CANCEL_EVERY: u64 = 1 << 12;

/// The sample in an idle lane.
const IDLE: usize = usize::MAX;

/// Most reference orbits a view has: the orbits of 0 of a hybrid's phases, and a Julia
/// set's centre.
const TRACKS: usize = MAX_PHASES + 1;

/// Scalar passes a hybrid's sample may take to reach the lanes' phase before it is
/// finished in the scalar loop instead (single steps reach it in fewer than the cycle's
/// length; only BLA steps whose lengths keep missing it could take more).
const ALIGN_TRIES: u32 = 64;

/// `a` where the mask `r` is all ones, `b` where it is zero: a select of values by their
/// bits. Written as `if`, the compiler selected the addresses of the two arrays and
/// gathered from them.
#[inline(always)]
fn pick(r: u64, a: f64, b: f64) -> f64 {
    f64::from_bits((a.to_bits() & r) | (b.to_bits() & !r))
}

/// All ones where `b`, else zero: a lane's mask, as wide as its values (masks one byte
/// wide were packed and unpacked around every vector compare).
#[inline(always)]
fn mask(b: bool) -> u64 {
    0u64.wrapping_sub(b as u64)
}

/// True where `x` is 0 or at least 2^-1000: an offset whose f64 step the rebase bounds hold.
#[inline(always)]
fn normal(x: f64) -> bool {
    (x == 0.0) | (x.abs() >= LEAST)
}

/// [`pick`] for indices.
#[inline(always)]
fn pick_i(r: u64, a: i64, b: i64) -> i64 {
    ((a as u64 & r) | (b as u64 & !r)) as i64
}

/// The lanes' state: each lane a [`Sample`] in f64, by field, every field 64 bits wide so
/// that the lanes' tests and updates are vectors of one width. A lane's index on its track
/// is held as the address of its reference value, so that the read of Z_m is one load.
struct Lanes<const L: usize> {
    dx: [f64; L],
    dy: [f64; L],
    cx: [f64; L],
    cy: [f64; L],
    /// The track (0 or 1).
    t: [u64; L],
    /// The address of Z_m on the lane's track.
    at: [i64; L],
    /// The address of Z_stop (the end test is `at >= stop`).
    stop: [i64; L],
    n: [i64; L],
    /// The BLA table's first look for the lane's track ([`Table::gate`]).
    gate: [f64; L],
    /// All ones for a lane with a sample in it.
    live: [u64; L],
    /// All ones where both parts of δc are [`normal`] (a rebase bound).
    normal_c: [u64; L],
    /// The offset δc in FloatExp (what out-of-line steps add).
    dc_fe: [[FloatExp; 2]; L],
    /// The sample in each lane (IDLE: none).
    pixel: [usize; L],
    /// With the derivative: each lane's Jacobian ([`Jac`], whose f64 matrix the lanes hold
    /// in `jm` while they step it, and what a step adds to its diagonal in `jadd`).
    jac: [Jac; L],
    jm: [[[f64; L]; 2]; 2],
    jadd: [f64; L],
    /// Each track's Z_0, as an address.
    base: [i64; TRACKS],
    /// Each track's gate.
    gates: [f64; TRACKS],
}

impl<const L: usize> Lanes<L> {
    /// The index on lane `k`'s track of the address `a`.
    fn index(&self, k: usize, a: i64) -> u32 {
        ((a - self.base[self.t[k] as usize]) / 16) as u32
    }

    fn get(&self, k: usize) -> Sample<f64> {
        Sample {
            d: [self.dx[k], self.dy[k]],
            dc: [self.cx[k], self.cy[k]],
            t: self.t[k] as usize,
            m: self.index(k, self.at[k]),
            n: self.n[k] as u32,
            stop: self.index(k, self.stop[k]),
        }
    }

    fn set(&mut self, k: usize, s: &Sample<f64>) {
        let base = self.base[s.t];
        [self.dx[k], self.dy[k]] = s.d;
        [self.cx[k], self.cy[k]] = s.dc;
        self.t[k] = s.t as u64;
        self.at[k] = base + 16 * i64::from(s.m);
        self.stop[k] = base + 16 * i64::from(s.stop);
        self.n[k] = s.n.into();
        self.gate[k] = self.gates[s.t];
        self.normal_c[k] = mask(normal(s.dc[0]) & normal(s.dc[1]));
    }

    /// Lane `k`'s Jacobian, with the matrix the lanes stepped.
    fn jac(&self, k: usize) -> Jac {
        let mut j = self.jac[k];
        j.set_matrix([[self.jm[0][0][k], self.jm[0][1][k]], [self.jm[1][0][k], self.jm[1][1][k]]]);
        j
    }

    fn set_jac(&mut self, k: usize, j: Jac) {
        let (m, add) = j.parts();
        for (r, row) in m.iter().enumerate() {
            for (c, &x) in row.iter().enumerate() {
                self.jm[r][c][k] = x;
            }
        }
        self.jadd[k] = add;
        self.jac[k] = j;
    }
}

/// The loop's constants.
struct Consts {
    escape2: f64,
    max_iter: i64,
    /// `rebase_delta_f64`'s bound on the parts of a full value (`Engine::rebase_low`).
    low: f64,
    /// True where deltas may move to FloatExp.
    fe_numbers: bool,
    /// A Jacobian's start (I × spacing), the placeholder of lanes without the derivative.
    start: Jac,
}

/// Where a lane that rebases lands: index 1 of the orbit of 0 of the pass's phase
/// (`Engine::rebase_step`), as the lanes hold it.
#[derive(Clone, Copy)]
struct Landing {
    track: u64,
    at1: i64,
    stop1: i64,
    gate: f64,
    /// All ones where that orbit has an index 1 (else the rebase is the scalar pass's).
    here: u64,
}

/// The samples not yet taken, the results, and the scalar passes' counts.
struct Run<'a> {
    offsets: &'a [[f64; 2]],
    out: &'a mut [Orbit],
    /// The next sample to take.
    next: usize,
    local: Counters,
    cancel: &'a AtomicBool,
}

/// What every pass updates, apart from [`Run`] so that a single family's loop keeps it in
/// registers (nothing out of line sees it).
struct Tally<const L: usize> {
    /// Lanes with a sample.
    active: usize,
    /// Single steps taken in the lanes.
    steps: u64,
    /// Rebases taken in each lane (counted apart, so that the count stays a vector).
    rebases: [u64; L],
}

/// How a pass hands the lanes that meet an event to the scalar loop ([`Engine::events`]).
trait Events<const DER: bool, const L: usize> {
    fn take(&self, engine: &Engine, s: &mut Lanes<L>, event: &[u64; L], tally: &mut Tally<L>, run: &mut Run<'_>);
}

/// A single family's events, compiled into its pass.
struct InLine<'a, S> {
    st: S,
    consts: &'a Consts,
}

impl<S: Stepper, const DER: bool, const L: usize> Events<DER, L> for InLine<'_, S> {
    #[inline(always)]
    fn take(&self, engine: &Engine, s: &mut Lanes<L>, event: &[u64; L], tally: &mut Tally<L>, run: &mut Run<'_>) {
        engine.events::<S, DER, L>(&self.st, s, event, self.consts, 0, tally, run);
    }
}

/// A hybrid's events, out of line (one function for every phase's pass), `then` the phase
/// of the next pass.
struct OutOfLine<'a> {
    consts: &'a Consts,
    then: u32,
}

impl<const DER: bool, const L: usize> Events<DER, L> for OutOfLine<'_> {
    #[inline(always)]
    fn take(&self, engine: &Engine, s: &mut Lanes<L>, event: &[u64; L], tally: &mut Tally<L>, run: &mut Run<'_>) {
        engine.events_cycle::<DER, L>(s, event, self.consts, self.then, tally, run);
    }
}

/// One call of the lanes for a single family ([`LaneJob`]: under the level's target
/// features, at its one width).
struct Job<'a, M: Map, const DER: bool> {
    engine: &'a Engine,
    offsets: &'a [[f64; 2]],
    out: &'a mut [Orbit],
    counters: &'a mut Counters,
    cancel: &'a AtomicBool,
    map: M,
}

impl<M: Map, const DER: bool> LaneJob for Job<'_, M, DER> {
    type Output = ();

    #[inline(always)]
    fn run<S: Simd, const L: usize>(self, _: S) {
        let Job { engine, offsets, out, counters, cancel, map } = self;
        engine.lanes::<M, DER, L>(map, offsets, out, counters, cancel);
    }
}

/// One call of the lanes for a hybrid ([`LaneJob`]: one width per level, so that the
/// table's functions, one per family, are compiled once per level and derivative).
struct CycleJob<'a, const DER: bool> {
    engine: &'a Engine,
    offsets: &'a [[f64; 2]],
    out: &'a mut [Orbit],
    counters: &'a mut Counters,
    cancel: &'a AtomicBool,
}

impl<const DER: bool> LaneJob for CycleJob<'_, DER> {
    type Output = ();

    #[inline(always)]
    fn run<S: Simd, const L: usize>(self, simd: S) {
        let CycleJob { engine, offsets, out, counters, cancel } = self;
        engine.lanes_cycle::<S, DER, L>(simd, offsets, out, counters, cancel);
    }
}

/// A hybrid's pass of one phase over the lanes ([`Engine::pass`] with that phase's family).
type PassFn<S, const L: usize> =
    fn(S, &Engine, &Phase, &mut Lanes<L>, &Consts, Landing, u32, &mut Tally<L>, &mut Run<'_>);

/// One phase's pass, out of line (one function per family in the table, so that no loop
/// holds every family's code), its body compiled under the level's target features by
/// pulp's `vectorize`.
#[inline(never)]
fn cycle_pass<S: Simd, M: Map, const DER: bool, const L: usize>(
    simd: S,
    engine: &Engine,
    phase: &Phase,
    s: &mut Lanes<L>,
    consts: &Consts,
    land: Landing,
    then: u32,
    tally: &mut Tally<L>,
    run: &mut Run<'_>,
) {
    struct Op<'a, 'b, M, const DER: bool, const L: usize> {
        engine: &'a Engine,
        s: &'a mut Lanes<L>,
        consts: &'a Consts,
        land: Landing,
        then: u32,
        tally: &'a mut Tally<L>,
        run: &'a mut Run<'b>,
        map: M,
    }
    impl<M: Map, const DER: bool, const L: usize> WithSimd for Op<'_, '_, M, DER, L> {
        type Output = ();
        #[inline(always)]
        fn with_simd<S: Simd>(self, _: S) {
            let Op { engine, s, consts, land, then, tally, run, map } = self;
            engine.pass::<M, DER, L>(&map, s, consts, land, tally, run, &OutOfLine { consts, then });
        }
    }
    simd.vectorize(Op::<M, DER, L> { engine, s, consts, land, then, tally, run, map: M::of(phase) });
}

impl Engine {
    /// Iterates many samples in vector lanes at `simd` (no traps; the Jacobian where
    /// `DER`): the results of [`Engine::orbit`], bit for bit. A single family's lanes run
    /// its one map; a hybrid's lanes all step the same phase at each pass.
    pub(super) fn orbits_lanes<const DER: bool>(
        &self,
        simd: SimdLevel,
        offsets: &[[f64; 2]],
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) {
        let phases = self.formula.phases();
        if phases.len() > 1 {
            return self.orbits_cycle::<DER>(simd, offsets, out, counters, cancel);
        }
        crate::with_map!(phases[0], m: M => {
            let job = Job::<M, DER> { engine: self, offsets, out, counters, cancel, map: m };
            if let Err(Job { offsets, out, counters, cancel, .. }) = simd.run_lanes(job) {
                self.each::<_, DER>(&Single(m), offsets, out, counters, cancel);
            }
        }, unreachable!("a validated formula has compiled code"))
    }

    /// [`Engine::orbits_lanes`] for a hybrid; a level without lanes runs the scalar loop.
    fn orbits_cycle<const DER: bool>(
        &self,
        simd: SimdLevel,
        offsets: &[[f64; 2]],
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) {
        let job = CycleJob::<DER> { engine: self, offsets, out, counters, cancel };
        if let Err(CycleJob { offsets, out, counters, cancel, .. }) = simd.run_lanes(job) {
            self.each::<_, DER>(&Cycle(self.formula), offsets, out, counters, cancel);
        }
    }

    /// Loads the next sample that needs the lanes into lane `k`, its next iteration of
    /// phase `then` (samples that start below f64's range, or end first, are finished
    /// here); false when none is left (the lane is idle).
    fn refill<S: Stepper, const DER: bool, const L: usize>(
        &self,
        st: &S,
        s: &mut Lanes<L>,
        k: usize,
        then: u32,
        run: &mut Run<'_>,
    ) -> bool {
        while run.next < run.offsets.len() {
            let p = run.next;
            run.next += 1;
            let Some((smp, dc_fe)) = self.start(run.offsets[p]) else {
                run.out[p] = Orbit::interior();
                continue;
            };
            // Each sample's Jacobian starts at I × spacing.
            let mut der = Jac::new(self.spacing, self.mandelbrot);
            let on = match self.first(smp, dc_fe) {
                Exit::F64(f) => self.align::<S, DER>(st, f, &mut der, dc_fe, then, &mut run.local, run.cancel),
                e => Err(self.finish::<S, DER>(st, e, &mut der, dc_fe, &mut run.local, run.cancel)),
            };
            match on {
                Ok(f) => {
                    s.set(k, &f);
                    if DER {
                        s.set_jac(k, der);
                    }
                    s.dc_fe[k] = dc_fe;
                    s.pixel[k] = p;
                    s.live[k] = mask(true);
                    return true;
                }
                Err(o) => run.out[p] = o,
            }
        }
        s.pixel[k] = IDLE;
        s.live[k] = 0;
        s.set(k, &Sample { d: [0.0; 2], dc: [0.0; 2], t: 0, m: 0, n: 0, stop: u32::MAX >> 8 });
        false
    }

    /// Runs a sample from `e` to its end in the scalar loop (f64 and FloatExp as its delta
    /// asks): a sample that leaves the lanes' number type.
    fn finish<S: Stepper, const DER: bool>(
        &self,
        st: &S,
        e: Exit,
        der: &mut Jac,
        dc_fe: [FloatExp; 2],
        local: &mut Counters,
        cancel: &AtomicBool,
    ) -> Orbit {
        self.drive::<_, DER>(st, e, der, dc_fe, &self.t64, &self.tfe, &[], &mut [], local, cancel)
    }

    /// Takes a hybrid's sample on with the scalar loop's passes until its next iteration
    /// is of phase `then`, the phase the lanes step next (a BLA step or an out-of-line
    /// step moves a sample's phase; single steps and rebases keep it in step with the
    /// lanes'). Every pass is one the scalar loop takes too, so nothing is lost or changed.
    /// Err: the sample ended (a sample that has not reached the phase after
    /// [`ALIGN_TRIES`] passes is finished in the scalar loop). A single family's phase is
    /// always the lanes'.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn align<S: Stepper, const DER: bool>(
        &self,
        st: &S,
        mut f: Sample<f64>,
        der: &mut Jac,
        dc_fe: [FloatExp; 2],
        then: u32,
        local: &mut Counters,
        cancel: &AtomicBool,
    ) -> Result<Sample<f64>, Orbit> {
        if st.period() == 1 {
            return Ok(f);
        }
        for _ in 0..ALIGN_TRIES {
            if f.n % self.period == then {
                return Ok(f);
            }
            f = self.once::<S, DER>(st, f, der, dc_fe, local, cancel)?;
        }
        Err(self.finish::<S, DER>(st, Exit::F64(f), der, dc_fe, local, cancel))
    }

    /// One pass of the scalar loop ([`Engine::iteration`]) for a sample of the lanes:
    /// Ok, the sample after it, still in f64; Err, the sample ended (a sample whose delta
    /// left f64's range is finished in the scalar loop first).
    #[inline(always)]
    fn once<S: Stepper, const DER: bool>(
        &self,
        st: &S,
        mut f: Sample<f64>,
        der: &mut Jac,
        dc_fe: [FloatExp; 2],
        local: &mut Counters,
        cancel: &AtomicBool,
    ) -> Result<Sample<f64>, Orbit> {
        match self.iteration::<S, f64, DER>(st, &mut f, der, dc_fe, &self.t64, &[], &mut [], local) {
            None => Ok(f),
            Some(Exit::F64(g)) => Ok(g),
            Some(Exit::Done(o)) => Err(o),
            Some(e @ Exit::Fe(_)) => Err(self.finish::<S, DER>(st, e, der, dc_fe, local, cancel)),
        }
    }

    /// The lanes, empty, with the view's tracks.
    fn empty_lanes<const L: usize>(&self) -> Lanes<L> {
        debug_assert!(!self.tracks.is_empty() && self.tracks.len() <= TRACKS);
        let track = |t: usize| &self.tracks[t.min(self.tracks.len() - 1)];
        let base: [i64; TRACKS] = std::array::from_fn(|t| track(t).z.as_ptr().expose_provenance() as i64);
        // The BLA tables' first look per track; -inf: no table, no step.
        let gates: [f64; TRACKS] = std::array::from_fn(|t| self.t64.get(t).map_or(f64::NEG_INFINITY, Table::gate));
        let start = Jac::new(self.spacing, self.mandelbrot);
        Lanes::<L> {
            dx: [0.0; L],
            dy: [0.0; L],
            cx: [0.0; L],
            cy: [0.0; L],
            t: [0; L],
            at: [base[0]; L],
            stop: [i64::MAX; L],
            n: [0; L],
            gate: [f64::NEG_INFINITY; L],
            live: [0; L],
            normal_c: [0; L],
            dc_fe: [[FloatExp::ZERO; 2]; L],
            pixel: [IDLE; L],
            jac: [start; L],
            jm: [[[0.0; L]; 2]; 2],
            jadd: [0.0; L],
            base,
            gates,
        }
    }

    /// Where a lane that rebases before an iteration of phase `g` lands: index 1 of that
    /// phase's orbit of 0.
    fn landing(&self, base: &[i64; TRACKS], gates: &[f64; TRACKS], g: u32) -> Landing {
        let t = self.zeros + g as usize;
        Landing {
            track: t as u64,
            at1: base[t] + 16,
            stop1: base[t] + 16 * i64::from(self.tracks[t].stop(1)),
            gate: gates[t],
            here: mask(self.tracks[t].last() >= 1),
        }
    }

    fn consts(&self) -> Consts {
        Consts {
            escape2: self.escape2,
            max_iter: i64::from(self.max_iter),
            low: self.rebase_low,
            fe_numbers: self.numbers == Numbers::FloatExp,
            start: Jac::new(self.spacing, self.mandelbrot),
        }
    }

    /// The lanes filled with the first samples (whose next iteration is of phase 0), and
    /// the loop's state.
    fn begin<'a, S: Stepper, const DER: bool, const L: usize>(
        &self,
        st: &S,
        offsets: &'a [[f64; 2]],
        out: &'a mut [Orbit],
        cancel: &'a AtomicBool,
    ) -> (Lanes<L>, Run<'a>, Tally<L>) {
        let mut s = self.empty_lanes::<L>();
        let mut run = Run { offsets, out, next: 0, local: Counters::default(), cancel };
        let mut tally = Tally { active: 0, steps: 0, rebases: [0; L] };
        for k in 0..L {
            tally.active += self.refill::<_, DER, L>(st, &mut s, k, 0, &mut run) as usize;
        }
        (s, run, tally)
    }

    /// Adds the loop's counts to `counters`.
    fn close<const L: usize>(tally: &Tally<L>, run: Run<'_>, counters: &mut Counters) {
        let mut local = run.local;
        local.steps += tally.steps;
        local.iterations += tally.steps;
        local.rebases += tally.rebases.iter().sum::<u64>();
        counters.add(&local);
    }

    /// A single family's lanes: every pass steps its map.
    #[inline(always)]
    fn lanes<M: Map, const DER: bool, const L: usize>(
        &self,
        map: M,
        offsets: &[[f64; 2]],
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) {
        if cancel.load(Ordering::Relaxed) {
            return;
        }
        // A single family has one track, or two for a Julia set (the centre's orbit and the
        // orbit of 0).
        debug_assert!(self.tracks.len() <= 2);
        let st = Single(map);
        let (mut s, mut run, mut tally) = self.begin::<_, DER, L>(&st, offsets, out, cancel);
        let consts = self.consts();
        let events = InLine { st, consts: &consts };
        let land = self.landing(&s.base, &s.gates, 0);
        let mut passes = 0u64;
        while tally.active > 0 {
            self.pass::<M, DER, L>(&map, &mut s, &consts, land, &mut tally, &mut run, &events);
            passes += 1;
            if passes.is_multiple_of(CANCEL_EVERY) && cancel.load(Ordering::Relaxed) {
                break;
            }
        }
        Self::close(&tally, run, counters);
    }

    /// A hybrid's lanes: at each pass every lane's next iteration has the same phase, and
    /// the pass steps that phase's family (each a function of its own, called through a
    /// table). A sample joins the lanes, or comes back from a scalar pass, at the phase of
    /// the pass after ([`Engine::align`]).
    #[inline(always)]
    fn lanes_cycle<S: Simd, const DER: bool, const L: usize>(
        &self,
        simd: S,
        offsets: &[[f64; 2]],
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) {
        if cancel.load(Ordering::Relaxed) {
            return;
        }
        let st = Cycle(self.formula);
        let phases = self.formula.phases();
        let mut passes = [cycle_pass::<S, Ops<0, 2, 0, 0>, DER, L> as PassFn<S, L>; MAX_PHASES];
        for (pass, &phase) in passes.iter_mut().zip(phases) {
            *pass = crate::with_map!(phase, M => cycle_pass::<S, M, DER, L> as PassFn<S, L>,
                unreachable!("a validated formula has compiled code"));
        }
        let (mut s, mut run, mut tally) = self.begin::<_, DER, L>(&st, offsets, out, cancel);
        let lands: [Landing; MAX_PHASES] =
            std::array::from_fn(|g| self.landing(&s.base, &s.gates, (g as u32) % self.period));
        let consts = self.consts();
        let (mut g, mut count) = (0u32, 0u64);
        while tally.active > 0 {
            let then = if g + 1 == self.period { 0 } else { g + 1 };
            (passes[g as usize])(
                simd,
                self,
                &phases[g as usize],
                &mut s,
                &consts,
                lands[g as usize],
                then,
                &mut tally,
                &mut run,
            );
            g = then;
            count += 1;
            if count.is_multiple_of(CANCEL_EVERY) && cancel.load(Ordering::Relaxed) {
                break;
            }
        }
        Self::close(&tally, run, counters);
    }

    /// The lanes that meet an event (where `event` is all ones) each run the scalar
    /// loop's pass once ([`Engine::iteration`], with `st` the formula), then, for a hybrid,
    /// the passes that bring them to phase `then`, the lanes' next; a sample that ends is
    /// written out and its lane takes the next.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn events<S: Stepper, const DER: bool, const L: usize>(
        &self,
        st: &S,
        s: &mut Lanes<L>,
        event: &[u64; L],
        consts: &Consts,
        then: u32,
        tally: &mut Tally<L>,
        run: &mut Run<'_>,
    ) {
        for j in 0..L {
            if event[j] == 0 {
                continue;
            }
            tally.steps -= 1;
            let mut der = if DER { s.jac(j) } else { consts.start };
            let dc_fe = s.dc_fe[j];
            let on = self
                .once::<S, DER>(st, s.get(j), &mut der, dc_fe, &mut run.local, run.cancel)
                .and_then(|f| self.align::<S, DER>(st, f, &mut der, dc_fe, then, &mut run.local, run.cancel));
            let done = match on {
                Ok(f) => {
                    s.set(j, &f);
                    if DER {
                        s.set_jac(j, der);
                    }
                    continue;
                }
                Err(o) => o,
            };
            run.out[s.pixel[j]] = done;
            if !self.refill::<S, DER, L>(st, s, j, then, run) {
                tally.active -= 1;
            }
        }
    }

    /// [`Engine::events`] for a hybrid, out of line: one function for every phase's pass.
    #[inline(never)]
    fn events_cycle<const DER: bool, const L: usize>(
        &self,
        s: &mut Lanes<L>,
        event: &[u64; L],
        consts: &Consts,
        then: u32,
        tally: &mut Tally<L>,
        run: &mut Run<'_>,
    ) {
        self.events::<Cycle, DER, L>(&Cycle(self.formula), s, event, consts, then, tally, run);
    }

    /// One pass over the lanes with family `M` (the map of every live lane's next
    /// iteration); `events` takes the lanes that meet an event ([`Engine::events`]).
    #[inline(always)]
    fn pass<M: Map, const DER: bool, const L: usize>(
        &self,
        map: &M,
        s: &mut Lanes<L>,
        consts: &Consts,
        land: Landing,
        tally: &mut Tally<L>,
        run: &mut Run<'_>,
        events: &impl Events<DER, L>,
    ) {
        let tables = &self.t64[..];
        // Every live lane that meets no event below takes a single step.
        tally.steps += tally.active as u64;
        let mut zx = [0.0; L];
        let mut zy = [0.0; L];
        for k in 0..L {
            debug_assert!(s.index(k, s.at[k]) <= self.tracks[s.t[k] as usize].last());
            // SAFETY: every lane's address is its track's Z_m with m at most the track's
            // last index (m <= stop <= last for a live lane, which `Track::stop` and the
            // rebase onto index 1 of an orbit that has it keep; an idle lane reads Z_0 of
            // track 0), exposed in `empty_lanes` from the track's values.
            let z = unsafe { *std::ptr::with_exposed_provenance::<[f64; 2]>(s.at[k] as usize) };
            (zx[k], zy[k]) = (z[0], z[1]);
        }
        // The scalar pass's values: z = Z + δ, |z|², |δ|², and the single step; a lane
        // nearer 0 than its delta steps from Z_0 = 0 with its full value as the delta.
        let fx = zx.add(s.dx);
        let fy = zy.add(s.dy);
        let r2 = fx.mul(fx).add(fy.mul(fy));
        let d2 = s.dx.mul(s.dx).add(s.dy.mul(s.dy));
        let mut near = [0u64; L];
        let (mut ax, mut ay, mut bx, mut by) = (zx, zy, s.dx, s.dy);
        for k in 0..L {
            let r = mask(r2[k] < d2[k]);
            near[k] = r;
            ax[k] = pick(r, 0.0, zx[k]);
            ay[k] = pick(r, 0.0, zy[k]);
            bx[k] = pick(r, fx[k], s.dx[k]);
            by[k] = pick(r, fy[k], s.dy[k]);
        }
        let step = map.delta_n([ax, ay], [bx, by]);
        let nx = step[0].add(s.cx);
        let ny = step[1].add(s.cy);
        // With the derivative, `Jac::step` at z = Z + δ (the rebase's step too): J' = Jf J
        // + I (times the spacing), as `mat_mul` computes it; a lane whose J' leaves the
        // f64 range `Jac::step` keeps (or is NaN) is an event, for the scalar pass.
        let mut jn = [[[0.0; L]; 2]; 2];
        let mut jac_ok = [!0u64; L];
        if DER {
            let jf = map.jacobian_n([fx, fy]);
            let (lo, hi) = Jac::RANGE;
            for k in 0..L {
                let e = |r: usize, c: usize| jf[r][0][k] * s.jm[0][c][k] + jf[r][1][k] * s.jm[1][c][k];
                let m = [[e(0, 0) + s.jadd[k], e(0, 1)], [e(1, 0), e(1, 1) + s.jadd[k]]];
                let a = [m[0][0].abs(), m[0][1].abs(), m[1][0].abs(), m[1][1].abs()];
                let within = (a[0] <= hi) & (a[1] <= hi) & (a[2] <= hi) & (a[3] <= hi);
                let big = (a[0] >= lo) | (a[1] >= lo) | (a[2] >= lo) | (a[3] >= lo);
                jac_ok[k] = mask(within & big);
                for r in 0..2 {
                    for c in 0..2 {
                        jn[r][c][k] = m[r][c];
                    }
                }
            }
        }
        let mut event = [0u64; L];
        let mut rebased = [0u64; L];
        let mut any = 0u64;
        for j in 0..L {
            let f64_rebase = mask(
                (fx[j].abs() >= consts.low)
                    & (fy[j].abs() >= consts.low)
                    & (nx[j].abs() >= LEAST)
                    & (ny[j].abs() >= LEAST),
            ) & s.normal_c[j]
                & land.here;
            let end = mask((s.at[j] >= s.stop[j]) | (r2[j] > consts.escape2) | (s.n[j] >= consts.max_iter));
            let e = (end | (near[j] & !f64_rebase) | !jac_ok[j]) & s.live[j];
            event[j] = e;
            rebased[j] = near[j] & !e & s.live[j];
            any |= e;
        }
        if consts.fe_numbers {
            // Below the switch to FloatExp deltas the scalar loop's rebase moves there.
            for j in 0..L {
                if rebased[j] != 0 && max_exp([nx[j], ny[j]]) < self.down_exp {
                    (event[j], rebased[j], any) = (!0, 0, !0);
                }
            }
        }
        // The BLA test: the table's first look (`Table::gate`) in the lanes, the rest
        // only for the lanes that pass it.
        let mut maybe = [0u64; L];
        let mut look = 0u64;
        for j in 0..L {
            maybe[j] = !event[j] & !near[j] & s.live[j] & mask(d2[j] < s.gate[j]);
            look |= maybe[j];
        }
        if look != 0 {
            for j in 0..L {
                if maybe[j] != 0
                    && tables[s.t[j] as usize].can_step(s.index(j, s.at[j]), d2[j], self.max_iter - s.n[j] as u32)
                {
                    event[j] = !0;
                    any = !0;
                }
            }
        }
        if any != 0 {
            events.take(self, s, &event, tally, run);
        }
        // Every other live lane takes its single step (from Z_0 of the orbit of 0 where
        // it rebased, on to index 1 there), by masks: as `if`, the updates were compiled
        // to masked stores that the next pass's loads of the same arrays waited on.
        for j in 0..L {
            let go = !event[j] & s.live[j];
            let r = rebased[j];
            s.dx[j] = pick(go, nx[j], s.dx[j]);
            s.dy[j] = pick(go, ny[j], s.dy[j]);
            if DER {
                for r in 0..2 {
                    for c in 0..2 {
                        s.jm[r][c][j] = pick(go, jn[r][c][j], s.jm[r][c][j]);
                    }
                }
            }
            s.at[j] = pick_i(r, land.at1, s.at[j] + (go & 16) as i64);
            s.n[j] += (go & 1) as i64;
            s.stop[j] = pick_i(r, land.stop1, s.stop[j]);
            s.t[j] = (s.t[j] & !r) | (land.track & r);
            s.gate[j] = pick(r, land.gate, s.gate[j]);
            tally.rebases[j] = tally.rebases[j].wrapping_sub(r);
        }
    }
}
