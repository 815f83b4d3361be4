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
    base: [i64; 2],
    /// Each track's gate.
    gates: [f64; 2],
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

/// One call of the lanes, run by pulp under the level's target features.
struct Job<'a, M: Map, const DER: bool> {
    engine: &'a Engine,
    offsets: &'a [[f64; 2]],
    out: &'a mut [Orbit],
    counters: &'a mut Counters,
    cancel: &'a AtomicBool,
    lanes: usize,
    _map: M,
}

impl<M: Map, const DER: bool> WithSimd for Job<'_, M, DER> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, _: S) -> Self::Output {
        let Job { engine, offsets, out, counters, cancel, lanes, .. } = self;
        match lanes {
            16 => engine.lanes::<M, DER, 16>(offsets, out, counters, cancel),
            8 => engine.lanes::<M, DER, 8>(offsets, out, counters, cancel),
            _ => engine.lanes::<M, DER, 4>(offsets, out, counters, cancel),
        }
    }
}

impl Engine {
    /// Iterates many samples of the single family `M` in vector lanes at `simd` (no traps;
    /// the Jacobian where `DER`): the results of [`Engine::orbit`], bit for bit.
    pub(super) fn orbits_lanes<M: Map, const DER: bool>(
        &self,
        simd: SimdLevel,
        offsets: &[[f64; 2]],
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) {
        // Two vectors' worth of lanes, interleaved to hide the latency of each step.
        let lanes = simd.f64_lanes() * 2;
        simd.arch().dispatch(Job::<M, DER> { engine: self, offsets, out, counters, cancel, lanes, _map: M::default() });
    }

    /// Loads the next sample that needs the lanes into lane `k` (samples that start below
    /// f64's range, or end at once, are finished here); false when none is left (the lane
    /// is idle).
    #[allow(clippy::too_many_arguments)]
    fn refill<M: Map, const DER: bool, const L: usize>(
        &self,
        s: &mut Lanes<L>,
        k: usize,
        next: &mut usize,
        offsets: &[[f64; 2]],
        out: &mut [Orbit],
        local: &mut Counters,
        cancel: &AtomicBool,
    ) -> bool {
        while *next < offsets.len() {
            let p = *next;
            *next += 1;
            let Some((smp, dc_fe)) = self.start(offsets[p]) else {
                out[p] = Orbit::interior();
                continue;
            };
            // Each sample's Jacobian starts at I × spacing.
            let mut der = Jac::new(self.spacing, self.mandelbrot);
            match self.first(smp, dc_fe) {
                Exit::F64(f) => {
                    s.set(k, &f);
                    if DER {
                        s.set_jac(k, der);
                    }
                    s.dc_fe[k] = dc_fe;
                    s.pixel[k] = p;
                    s.live[k] = mask(true);
                    return true;
                }
                e => out[p] = self.finish::<M, DER>(e, &mut der, dc_fe, local, cancel),
            }
        }
        s.pixel[k] = IDLE;
        s.live[k] = 0;
        s.set(k, &Sample { d: [0.0; 2], dc: [0.0; 2], t: 0, m: 0, n: 0, stop: u32::MAX >> 8 });
        false
    }

    /// Runs a sample from `e` to its end in the scalar loop (f64 and FloatExp as its delta
    /// asks): a sample that leaves the lanes' number type.
    fn finish<M: Map, const DER: bool>(
        &self,
        e: Exit,
        der: &mut Jac,
        dc_fe: [FloatExp; 2],
        local: &mut Counters,
        cancel: &AtomicBool,
    ) -> Orbit {
        let st = Single(M::default());
        self.drive::<_, DER>(&st, e, der, dc_fe, &self.t64, &self.tfe, &[], &mut [], local, cancel)
    }

    #[inline(always)]
    fn lanes<M: Map, const DER: bool, const L: usize>(
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
        let start = Jac::new(self.spacing, self.mandelbrot);
        let mut local = Counters::default();
        // A single family has one track, or two for a Julia set (the centre's orbit and the
        // orbit of 0).
        debug_assert!(self.tracks.len() <= 2 && !self.tracks.is_empty());
        let track = |t: usize| &self.tracks[t.min(self.tracks.len() - 1)];
        let base = [0, 1].map(|t| track(t).z.as_ptr().expose_provenance() as i64);
        // The BLA tables' first look per track; -inf: no table, no step.
        let gates = [0, 1].map(|t| tables.get(t).map_or(f64::NEG_INFINITY, Table::gate));
        let mut s = Lanes::<L> {
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
        };
        let mut next = 0;
        let mut active = 0;
        for k in 0..L {
            active += self.refill::<M, DER, L>(&mut s, k, &mut next, offsets, out, &mut local, cancel) as usize;
        }
        let (escape2, max_iter) = (self.escape2, i64::from(self.max_iter));
        // A rebase in the lanes (see the module doc): where it lands, and the bounds under
        // which its f64 step has the scalar loop's bits (`rebase_delta_f64`). It lands on
        // index 1, so the orbit of 0 must have one.
        let (zero_track, low) = (self.zeros as u64, self.rebase_low);
        let (at1, stop1) = (base[self.zeros] + 16, base[self.zeros] + 16 * i64::from(self.tracks[self.zeros].stop(1)));
        let gate0 = gates[self.zeros];
        let rebase_here = mask(self.tracks[self.zeros].last() >= 1);
        let fe_numbers = self.numbers == Numbers::FloatExp;
        let mut passes = 0u64;
        let mut steps = 0u64;
        let mut rebases = [0u64; L];
        while active > 0 {
            // Every live lane that meets no event below takes a single step.
            steps += active as u64;
            let mut zx = [0.0; L];
            let mut zy = [0.0; L];
            for k in 0..L {
                debug_assert!(s.index(k, s.at[k]) <= self.tracks[s.t[k] as usize].last());
                // SAFETY: every lane's address is its track's Z_m with m at most the track's
                // last index (m <= stop <= last for a live lane, which `Track::stop` and the
                // rebase onto index 1 of an orbit that has it keep; an idle lane reads Z_0 of
                // track 0), exposed above from the track's values.
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
            let step = M::delta_n([ax, ay], [bx, by]);
            let nx = step[0].add(s.cx);
            let ny = step[1].add(s.cy);
            // With the derivative, `Jac::step` at z = Z + δ (the rebase's step too): J' = Jf J
            // + I (times the spacing), as `mat_mul` computes it; a lane whose J' leaves the
            // f64 range `Jac::step` keeps (or is NaN) is an event, for the scalar pass.
            let mut jn = [[[0.0; L]; 2]; 2];
            let mut jac_ok = [!0u64; L];
            if DER {
                let jf = M::jacobian_n([fx, fy]);
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
            for k in 0..L {
                let f64_rebase =
                    mask((fx[k].abs() >= low) & (fy[k].abs() >= low) & (nx[k].abs() >= LEAST) & (ny[k].abs() >= LEAST))
                        & s.normal_c[k]
                        & rebase_here;
                let end = mask((s.at[k] >= s.stop[k]) | (r2[k] > escape2) | (s.n[k] >= max_iter));
                let e = (end | (near[k] & !f64_rebase) | !jac_ok[k]) & s.live[k];
                event[k] = e;
                rebased[k] = near[k] & !e & s.live[k];
                any |= e;
            }
            if fe_numbers {
                // Below the switch to FloatExp deltas the scalar loop's rebase moves there.
                for k in 0..L {
                    if rebased[k] != 0 && max_exp([nx[k], ny[k]]) < self.down_exp {
                        (event[k], rebased[k], any) = (!0, 0, !0);
                    }
                }
            }
            // The BLA test: the table's first look (`Table::gate`) in the lanes, the rest
            // only for the lanes that pass it.
            let mut maybe = [0u64; L];
            let mut look = 0u64;
            for k in 0..L {
                maybe[k] = !event[k] & !near[k] & s.live[k] & mask(d2[k] < s.gate[k]);
                look |= maybe[k];
            }
            if look != 0 {
                for k in 0..L {
                    if maybe[k] != 0
                        && tables[s.t[k] as usize].can_step(s.index(k, s.at[k]), d2[k], self.max_iter - s.n[k] as u32)
                    {
                        event[k] = !0;
                        any = !0;
                    }
                }
            }
            if any != 0 {
                for k in 0..L {
                    if event[k] == 0 {
                        continue;
                    }
                    steps -= 1;
                    let mut smp = s.get(k);
                    let mut der = if DER { s.jac(k) } else { start };
                    let dc_fe = s.dc_fe[k];
                    let on = match self.iteration::<_, f64, DER>(
                        &st,
                        &mut smp,
                        &mut der,
                        dc_fe,
                        tables,
                        &[],
                        &mut [],
                        &mut local,
                    ) {
                        None => Ok(smp),
                        Some(Exit::F64(f)) => Ok(f),
                        Some(Exit::Done(o)) => Err(o),
                        Some(e @ Exit::Fe(_)) => Err(self.finish::<M, DER>(e, &mut der, dc_fe, &mut local, cancel)),
                    };
                    let done = match on {
                        Ok(f) => {
                            s.set(k, &f);
                            if DER {
                                s.set_jac(k, der);
                            }
                            continue;
                        }
                        Err(o) => o,
                    };
                    out[s.pixel[k]] = done;
                    if !self.refill::<M, DER, L>(&mut s, k, &mut next, offsets, out, &mut local, cancel) {
                        active -= 1;
                    }
                }
            }
            // Every other live lane takes its single step (from Z_0 of the orbit of 0 where
            // it rebased, on to index 1 there), by masks: as `if`, the updates were compiled
            // to masked stores that the next pass's loads of the same arrays waited on.
            for k in 0..L {
                let go = !event[k] & s.live[k];
                let r = rebased[k];
                s.dx[k] = pick(go, nx[k], s.dx[k]);
                s.dy[k] = pick(go, ny[k], s.dy[k]);
                if DER {
                    for r in 0..2 {
                        for c in 0..2 {
                            s.jm[r][c][k] = pick(go, jn[r][c][k], s.jm[r][c][k]);
                        }
                    }
                }
                s.at[k] = pick_i(r, at1, s.at[k] + (go & 16) as i64);
                s.n[k] += (go & 1) as i64;
                s.stop[k] = pick_i(r, stop1, s.stop[k]);
                s.t[k] = (s.t[k] & !r) | (zero_track & r);
                s.gate[k] = pick(r, gate0, s.gate[k]);
                rebases[k] = rebases[k].wrapping_sub(r);
            }
            passes += 1;
            if passes.is_multiple_of(CANCEL_EVERY) && cancel.load(Ordering::Relaxed) {
                break;
            }
        }
        let rebases: u64 = rebases.iter().sum();
        local.steps += steps;
        local.iterations += steps;
        local.rebases += rebases;
        counters.add(&local);
    }
}
