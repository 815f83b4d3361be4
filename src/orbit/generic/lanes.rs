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
//! checks every level this CPU has). The derivative and hybrids (whose lanes would be at
//! different phases) run in the scalar loop.

use std::sync::atomic::{AtomicBool, Ordering};

use pulp::{Simd, WithSimd};

use super::Engine;
use super::bla::Table;
use super::der::Jac;
use super::perturb::{Exit, Sample, max_exp};
use crate::formula::Single;
use crate::formula::end::Orbit;
use crate::formula::map::{Map, Num};
use crate::num::FloatExp;
use crate::orbit::{Counters, Numbers};
use crate::simd_level::SimdLevel;

/// Vector passes between two looks at the cancel flag.
const CANCEL_EVERY: u64 = 1 << 12;

/// The sample in an idle lane.
const IDLE: usize = usize::MAX;

/// `a` where the mask `r` is all ones, `b` where it is zero: a select of values by their
/// bits. Written as `if`, the compiler selected the addresses of the two arrays and
/// gathered from them.
#[inline(always)]
fn pick(r: u64, a: f64, b: f64) -> f64 {
    f64::from_bits((a.to_bits() & r) | (b.to_bits() & !r))
}

/// The lanes' state: each lane a [`Sample`] in f64, by field.
struct Lanes<const L: usize> {
    dx: [f64; L],
    dy: [f64; L],
    cx: [f64; L],
    cy: [f64; L],
    t: [usize; L],
    m: [u32; L],
    n: [u32; L],
    stop: [u32; L],
    /// The offset δc in FloatExp (what out-of-line steps add).
    dc_fe: [[FloatExp; 2]; L],
    /// The sample in each lane (IDLE: none).
    pixel: [usize; L],
}

impl<const L: usize> Lanes<L> {
    fn get(&self, k: usize) -> Sample<f64> {
        Sample {
            d: [self.dx[k], self.dy[k]],
            dc: [self.cx[k], self.cy[k]],
            t: self.t[k],
            m: self.m[k],
            n: self.n[k],
            stop: self.stop[k],
        }
    }

    fn set(&mut self, k: usize, s: &Sample<f64>) {
        [self.dx[k], self.dy[k]] = s.d;
        [self.cx[k], self.cy[k]] = s.dc;
        self.t[k] = s.t;
        self.m[k] = s.m;
        self.n[k] = s.n;
        self.stop[k] = s.stop;
    }
}

/// One call of the lanes, run by pulp under the level's target features.
struct Job<'a, M: Map> {
    engine: &'a Engine,
    offsets: &'a [[f64; 2]],
    out: &'a mut [Orbit],
    counters: &'a mut Counters,
    cancel: &'a AtomicBool,
    lanes: usize,
    _map: M,
}

impl<M: Map> WithSimd for Job<'_, M> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, _: S) -> Self::Output {
        let Job { engine, offsets, out, counters, cancel, lanes, .. } = self;
        match lanes {
            16 => engine.lanes::<M, 16>(offsets, out, counters, cancel),
            8 => engine.lanes::<M, 8>(offsets, out, counters, cancel),
            _ => engine.lanes::<M, 4>(offsets, out, counters, cancel),
        }
    }
}

impl Engine {
    /// Iterates many samples of the single family `M` in vector lanes at `simd` (no traps,
    /// no derivative): the results of [`Engine::orbit`], bit for bit.
    pub(super) fn orbits_lanes<M: Map>(
        &self,
        simd: SimdLevel,
        offsets: &[[f64; 2]],
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) {
        // Two vectors' worth of lanes, interleaved to hide the latency of each step.
        let lanes = simd.f64_lanes() * 2;
        simd.arch().dispatch(Job::<M> { engine: self, offsets, out, counters, cancel, lanes, _map: M::default() });
    }

    /// Loads the next sample that needs the lanes into lane `k` (samples that start below
    /// f64's range, or end at once, are finished here); false when none is left (the lane
    /// is idle).
    #[allow(clippy::too_many_arguments)]
    fn refill<M: Map, const L: usize>(
        &self,
        s: &mut Lanes<L>,
        k: usize,
        next: &mut usize,
        offsets: &[[f64; 2]],
        out: &mut [Orbit],
        der: &mut Jac,
        local: &mut Counters,
        cancel: &AtomicBool,
    ) -> bool {
        let st = Single(M::default());
        while *next < offsets.len() {
            let p = *next;
            *next += 1;
            let Some((smp, dc_fe)) = self.start(offsets[p]) else {
                out[p] = Orbit::interior();
                continue;
            };
            match self.first(smp, dc_fe) {
                Exit::F64(f) => {
                    s.set(k, &f);
                    s.dc_fe[k] = dc_fe;
                    s.pixel[k] = p;
                    return true;
                }
                e => {
                    out[p] =
                        self.drive::<_, false>(&st, e, der, dc_fe, &self.t64, &self.tfe, &[], &mut [], local, cancel);
                }
            }
        }
        s.pixel[k] = IDLE;
        s.set(k, &Sample { d: [0.0; 2], dc: [0.0; 2], t: 0, m: 0, n: 0, stop: u32::MAX });
        false
    }

    #[inline(always)]
    fn lanes<M: Map, const L: usize>(
        &self,
        offsets: &[[f64; 2]],
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) {
        if cancel.load(Ordering::Relaxed) {
            return;
        }
        let st = Single(M::default());
        let tables = &self.t64[..];
        let mut der = Jac::new(self.spacing, self.mandelbrot);
        let mut local = Counters::default();
        let mut s = Lanes::<L> {
            dx: [0.0; L],
            dy: [0.0; L],
            cx: [0.0; L],
            cy: [0.0; L],
            t: [0; L],
            m: [0; L],
            n: [0; L],
            stop: [u32::MAX; L],
            dc_fe: [[FloatExp::ZERO; 2]; L],
            pixel: [IDLE; L],
        };
        let mut next = 0;
        let mut active = 0;
        for k in 0..L {
            active += self.refill::<M, L>(&mut s, k, &mut next, offsets, out, &mut der, &mut local, cancel) as usize;
        }
        let (escape2, max_iter) = (self.escape2, self.max_iter);
        // A rebase in the lanes (see the module doc): where it lands, and the bounds under
        // which its f64 step has the scalar loop's bits (`rebase_delta_f64`).
        let (zero_track, low) = (self.zeros, self.rebase_low);
        let stop1 = self.tracks[zero_track].stop(1);
        let least = f64::from_bits((1023 - 1000) << 52);
        let fe_numbers = self.numbers == Numbers::FloatExp;
        // The BLA tables' first look per track (a single family has one track, or two for
        // a Julia set: the centre's orbit and the orbit of 0); -inf: no table, no step.
        debug_assert!(self.tracks.len() <= 2);
        let gate = |t: usize| tables.get(t).map_or(f64::NEG_INFINITY, Table::gate);
        let gates = [gate(0), gate(1)];
        let mut passes = 0u64;
        let mut steps = 0u64;
        let mut rebases = 0u64;
        while active > 0 {
            let mut zx = [0.0; L];
            let mut zy = [0.0; L];
            for k in 0..L {
                // m <= the track's last index in every lane (an idle lane sits at 0).
                let z = self.tracks[s.t[k]].z[s.m[k] as usize];
                (zx[k], zy[k]) = (z[0], z[1]);
            }
            // The scalar pass's values: z = Z + δ, |z|², |δ|², and the single step; a lane
            // nearer 0 than its delta steps from Z_0 = 0 with its full value as the delta.
            let fx = zx.add(s.dx);
            let fy = zy.add(s.dy);
            let r2 = fx.mul(fx).add(fy.mul(fy));
            let d2 = s.dx.mul(s.dx).add(s.dy.mul(s.dy));
            let mut near = [false; L];
            let (mut ax, mut ay, mut bx, mut by) = (zx, zy, s.dx, s.dy);
            for k in 0..L {
                near[k] = r2[k] < d2[k];
                let r = 0u64.wrapping_sub(near[k] as u64);
                ax[k] = pick(r, 0.0, zx[k]);
                ay[k] = pick(r, 0.0, zy[k]);
                bx[k] = pick(r, fx[k], s.dx[k]);
                by[k] = pick(r, fy[k], s.dy[k]);
            }
            let step = M::delta_n([ax, ay], [bx, by]);
            let nx = step[0].add(s.cx);
            let ny = step[1].add(s.cy);
            let mut event = [false; L];
            let mut rebased = [false; L];
            let mut any = false;
            for k in 0..L {
                // Bitwise, not short-circuit, so that the lanes' tests stay vector compares.
                let normal = |x: f64| (x == 0.0) | (x.abs() >= least);
                let f64_rebase = (fx[k].abs() >= low)
                    & (fy[k].abs() >= low)
                    & normal(s.cx[k])
                    & normal(s.cy[k])
                    & (nx[k].abs() >= least)
                    & (ny[k].abs() >= least);
                let end = (s.m[k] >= s.stop[k]) | (r2[k] > escape2) | (s.n[k] >= max_iter);
                let e = end | (near[k] & !f64_rebase);
                event[k] = e;
                rebased[k] = near[k] & !e & (s.pixel[k] != IDLE);
                any |= e;
            }
            if fe_numbers {
                // Below the switch to FloatExp deltas the scalar loop's rebase moves there.
                for k in 0..L {
                    if rebased[k] && max_exp([nx[k], ny[k]]) < self.down_exp {
                        (event[k], rebased[k], any) = (true, false, true);
                    }
                }
            }
            // The BLA test: the table's first look (`Table::gate`) in the lanes, the rest
            // only for the lanes that pass it.
            let mut maybe = [false; L];
            let mut look = false;
            for k in 0..L {
                let gate = if s.t[k] == 0 { gates[0] } else { gates[1] };
                maybe[k] = !event[k] & !near[k] & (s.pixel[k] != IDLE) & (d2[k] < gate);
                look |= maybe[k];
            }
            if look {
                for k in 0..L {
                    if maybe[k] && tables[s.t[k]].can_step(s.m[k], d2[k], max_iter - s.n[k]) {
                        event[k] = true;
                        any = true;
                    }
                }
            }
            if any {
                for k in 0..L {
                    if !event[k] || s.pixel[k] == IDLE {
                        continue;
                    }
                    let mut smp = s.get(k);
                    let dc_fe = s.dc_fe[k];
                    let done = match self.iteration::<_, f64, false>(
                        &st,
                        &mut smp,
                        &mut der,
                        dc_fe,
                        tables,
                        &[],
                        &mut [],
                        &mut local,
                    ) {
                        None => {
                            s.set(k, &smp);
                            continue;
                        }
                        Some(Exit::F64(f)) => {
                            s.set(k, &f);
                            continue;
                        }
                        Some(Exit::Done(o)) => o,
                        Some(e @ Exit::Fe(_)) => self.drive::<_, false>(
                            &st,
                            e,
                            &mut der,
                            dc_fe,
                            &self.t64,
                            &self.tfe,
                            &[],
                            &mut [],
                            &mut local,
                            cancel,
                        ),
                    };
                    out[s.pixel[k]] = done;
                    if !self.refill::<M, L>(&mut s, k, &mut next, offsets, out, &mut der, &mut local, cancel) {
                        active -= 1;
                    }
                }
            }
            // Every other lane takes its single step (from Z_0 of the orbit of 0 where it
            // rebased, on to index 1 there). One loop per type, so that each is a few vector
            // selects.
            let mut go = [false; L];
            for k in 0..L {
                go[k] = !event[k] & (s.pixel[k] != IDLE);
            }
            for k in 0..L {
                s.dx[k] = if go[k] { nx[k] } else { s.dx[k] };
                s.dy[k] = if go[k] { ny[k] } else { s.dy[k] };
            }
            // The indices by arithmetic rather than `if`: written as selects, they were
            // compiled to masked stores that the next loads of the same arrays waited on.
            for k in 0..L {
                let r = 0u32.wrapping_sub(rebased[k] as u32);
                s.m[k] = ((s.m[k] + go[k] as u32) & !r) | (1 & r);
                s.n[k] += go[k] as u32;
                s.stop[k] = (s.stop[k] & !r) | (stop1 & r);
            }
            for k in 0..L {
                let r = 0usize.wrapping_sub(rebased[k] as usize);
                s.t[k] = (s.t[k] & !r) | (zero_track & r);
            }
            steps += go.iter().filter(|&&g| g).count() as u64;
            rebases += rebased.iter().filter(|&&r| r).count() as u64;
            passes += 1;
            if passes.is_multiple_of(CANCEL_EVERY) && cancel.load(Ordering::Relaxed) {
                break;
            }
        }
        local.steps += steps;
        local.iterations += steps;
        local.rebases += rebases;
        counters.add(&local);
    }
}
