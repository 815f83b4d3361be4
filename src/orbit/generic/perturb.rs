//! The perturbation loop of the generic engine: every sample iterated as a delta against a
//! reference orbit, δ_(k+1) = f_k(Z_m + δ_k) - f_k(Z_m) + δc, with the difference taken
//! by the formula's own [`Stepper::delta`] (binomial expansion of the power, `diffabs`
//! through the folds: no cancellation at any depth).
//!
//! Rebasing (Zhuoran): when |Z_m + δ| < |δ| the sample is nearer 0 than its reference,
//! so it goes on from the start of an orbit of 0 with its full value as the delta; the
//! same happens when the reference ends (it escaped, or reached the limit on another
//! orbit). The orbit of 0 is the one whose phases match the sample's next iteration
//! ([`super::reference`]). One reference then serves every sample: no glitch detection.
//!
//! Deltas are f64 where every term of a step is a normal f64, FloatExp below that (views
//! past 1e-300), as the quadratic engine's loop switches (`perturb/drive.rs`): a FloatExp
//! delta whose exponent climbs above 2^(-960/p) moves to f64, and a rebase to a full value
//! below 2^(-1000/p) moves back (the next step is δ^p + δc, and δ^p must stay normal and
//! well above δc); p is the formula's largest power. The offset goes back to FloatExp from
//! its original, never from its f64 rounding.
//!
//! The hot loop handles reference indices before the track's `stop` (its next wide value or
//! its end); at `stop` one iteration runs in FloatExp out of line (`Engine::special`), and
//! so does every rebase's step (from Z_0 = 0: δ^p + δc, which may need FloatExp's range).
//! Traps observe z = Z_m + δ at every iteration n >= 1, so there is no BLA with traps.

use std::sync::atomic::{AtomicBool, Ordering};

use super::Engine;
use super::bla::Table;
use super::der::Jac;
use super::wide;
use crate::formula::Stepper;
use crate::formula::end::Orbit;
use crate::num::real::{cadd, cconv, cto_f64, norm2};
use crate::num::{FloatExp, Real};
use crate::orbit::{Counters, Numbers};
use crate::trap::{Trap, TrapState};

/// Iterations between looks at the cancel flag (single steps only; the flag abandons the
/// sample, whose result the caller then discards).
const CANCEL_MASK: u32 = (1 << 12) - 1;

/// A sample's state with deltas in D.
#[derive(Debug, Clone, Copy)]
pub(super) struct Sample<D> {
    /// δ against Z_m of the current track.
    pub(super) d: [D; 2],
    /// The offset δc (zero for Julia sets; in f64 it may have underflowed).
    pub(super) dc: [D; 2],
    /// The track followed.
    pub(super) t: usize,
    /// Index on that track.
    pub(super) m: u32,
    /// Iteration index of the sample.
    pub(super) n: u32,
    /// The track's next index the hot loop does not handle.
    pub(super) stop: u32,
}

/// How a run in one number type ended.
pub(super) enum Exit {
    Done(Orbit),
    F64(Sample<f64>),
    Fe(Sample<FloatExp>),
}

/// The largest binary exponent of a pair (very negative for zero).
#[inline(always)]
pub(super) fn max_exp<D: Real>(d: [D; 2]) -> i32 {
    d[0].to_fe().exponent().max(d[1].to_fe().exponent())
}

/// 2^-1000: the least magnitude (besides 0) of an offset and of a result that the f64
/// rebase step takes (the lanes test the same bound).
pub(super) const LEAST: f64 = f64::from_bits((1023 - 1000) << 52);

/// f_n(0 + full) - f_n(0) + dc in f64 where that has the bits of the FloatExp rebase step
/// (see `Engine::rebase_f64`), `low` = 2^-T for the largest power; None elsewhere.
#[inline(always)]
fn rebase_delta_f64<S: Stepper>(st: &S, n: u32, full: [f64; 2], dc: [f64; 2], low: f64) -> Option<[f64; 2]> {
    let big = |x: f64| x.abs() >= low;
    let normal = |x: f64| x == 0.0 || x.abs() >= LEAST;
    if !(big(full[0]) && big(full[1]) && normal(dc[0]) && normal(dc[1])) {
        return None;
    }
    let d = cadd(st.delta::<f64>(n, [0.0; 2], full), dc);
    (d[0].abs() >= LEAST && d[1].abs() >= LEAST).then_some(d)
}

/// A v for a 2×2 matrix in D.
#[inline(always)]
fn mat_vec<D: Real>(a: &[[D; 2]; 2], v: [D; 2]) -> [D; 2] {
    [a[0][0] * v[0] + a[0][1] * v[1], a[1][0] * v[0] + a[1][1] * v[1]]
}

impl Engine {
    /// Iterates the sample at `offset` (in units of the spacing) to its end. With `bla`
    /// false (traps) every iteration is a single step.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn sample<S: Stepper, const DER: bool>(
        &self,
        st: &S,
        offset: [f64; 2],
        traps: &[Trap],
        states: &mut [TrapState],
        counters: &mut Counters,
        cancel: &AtomicBool,
        bla: bool,
    ) -> Orbit {
        let Some((s, dc_fe)) = self.start(offset) else { return Orbit::interior() };
        let mut der = Jac::new(self.spacing, self.mandelbrot);
        let (t64, tfe): (&[Table<f64>], &[Table<FloatExp>]) = if bla { (&self.t64, &self.tfe) } else { (&[], &[]) };
        let next = self.first(s, dc_fe);
        self.drive::<S, DER>(st, next, &mut der, dc_fe, t64, tfe, traps, states, counters, cancel)
    }

    /// The state of the sample at `offset` before its first iteration, with its offset δc
    /// in FloatExp; None where the iteration limit is below its first index.
    #[inline(always)]
    pub(super) fn start(&self, offset: [f64; 2]) -> Option<(Sample<FloatExp>, [FloatExp; 2])> {
        let u = [self.spacing.mul_f64(offset[0]), self.spacing.mul_f64(offset[1])];
        let (dc_fe, n) = if self.mandelbrot { (u, 1) } else { ([FloatExp::ZERO; 2], 0) };
        if n > self.max_iter {
            return None;
        }
        Some((Sample { d: u, dc: dc_fe, t: 0, m: n, n, stop: self.tracks[0].stop(n) }, dc_fe))
    }

    /// A new sample's first state: f64 unless its offset is below f64's range.
    #[inline(always)]
    pub(super) fn first(&self, s: Sample<FloatExp>, dc_fe: [FloatExp; 2]) -> Exit {
        if self.numbers == Numbers::FloatExp && max_exp(s.d) <= self.up_exp {
            Exit::Fe(s)
        } else {
            Exit::F64(self.to_f64(s, dc_fe))
        }
    }

    /// Runs a sample from `next` to its end, in f64 and FloatExp as its delta asks.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn drive<S: Stepper, const DER: bool>(
        &self,
        st: &S,
        mut next: Exit,
        der: &mut Jac,
        dc_fe: [FloatExp; 2],
        t64: &[Table<f64>],
        tfe: &[Table<FloatExp>],
        traps: &[Trap],
        states: &mut [TrapState],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) -> Orbit {
        loop {
            next = match next {
                Exit::Done(o) => return o,
                Exit::F64(s) => self.run::<S, f64, DER>(st, s, der, dc_fe, t64, traps, states, counters, cancel),
                Exit::Fe(s) => self.run::<S, FloatExp, DER>(st, s, der, dc_fe, tfe, traps, states, counters, cancel),
            };
        }
    }

    /// A FloatExp state in f64 (the offset from its original).
    fn to_f64(&self, s: Sample<FloatExp>, dc_fe: [FloatExp; 2]) -> Sample<f64> {
        Sample { d: cconv(s.d), dc: cconv(dc_fe), ..self.moved_f64(s) }
    }

    /// The indices of a state, in f64 (deltas to be set).
    fn moved_f64(&self, s: Sample<FloatExp>) -> Sample<f64> {
        Sample { d: [0.0; 2], dc: [0.0; 2], t: s.t, m: s.m, n: s.n, stop: s.stop }
    }

    /// The loop in D until the sample ends or needs the other number type.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn run<S: Stepper, D: Real, const DER: bool>(
        &self,
        st: &S,
        mut s: Sample<D>,
        der: &mut Jac,
        dc_fe: [FloatExp; 2],
        tables: &[Table<D>],
        traps: &[Trap],
        states: &mut [TrapState],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) -> Exit {
        let fe = D::NAME == FloatExp::NAME;
        // Counted locally and added on exit, so that the loop's state stays in registers.
        let mut local = Counters::default();
        let exit = loop {
            if let Some(e) = self.iteration::<S, D, DER>(st, &mut s, der, dc_fe, tables, traps, states, &mut local) {
                break e;
            }
            if s.n & CANCEL_MASK == 0 && cancel.load(Ordering::Relaxed) {
                break Exit::Done(Orbit::interior());
            }
        };
        if fe {
            local.floatexp_steps = local.steps;
        }
        counters.add(&local);
        exit
    }

    /// One pass of the loop in D: the out-of-line step at a track's `stop`, or the end
    /// tests, then a rebase, a BLA step or a single step. Some: the sample ended or needs
    /// the other number type. The lanes (`lanes.rs`) run this same pass for a lane whose
    /// sample meets an event, so that both paths take the same steps.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn iteration<S: Stepper, D: Real, const DER: bool>(
        &self,
        st: &S,
        s: &mut Sample<D>,
        der: &mut Jac,
        dc_fe: [FloatExp; 2],
        tables: &[Table<D>],
        traps: &[Trap],
        states: &mut [TrapState],
        local: &mut Counters,
    ) -> Option<Exit> {
        let fe = D::NAME == FloatExp::NAME;
        if s.m >= s.stop {
            let d = cconv(s.d);
            local.iterations += 1;
            match self.special::<S, D, DER>(st, s, d, dc_fe, der, traps, states, local) {
                Err(o) => return Some(Exit::Done(o)),
                Ok(moved) => return self.moved(s, moved, dc_fe),
            }
        }
        let zr = self.tracks[s.t].z[s.m as usize];
        let full = [D::from_f64(zr[0]) + s.d[0], D::from_f64(zr[1]) + s.d[1]];
        let z = cto_f64(full);
        if s.n >= 1 {
            for (trap, state) in traps.iter().zip(states.iter_mut()) {
                trap.observe(state, z);
            }
        }
        if z[0] * z[0] + z[1] * z[1] > self.escape2 {
            return Some(Exit::Done(Orbit { n: s.n, z, dz: if DER { der.output(z) } else { [0.0; 2] } }));
        }
        if s.n >= self.max_iter {
            return Some(Exit::Done(Orbit::interior()));
        }
        let d2 = norm2(s.d);
        if norm2(full) < d2 {
            local.iterations += 1;
            if !fe && let Some(d) = self.rebase_f64(st, s.n, cto_f64(full), cto_f64(s.dc)) {
                local.rebases += 1;
                local.steps += 1;
                if DER {
                    der.step(st.jacobian(s.n, z));
                }
                s.t = self.zeros + (s.n % self.period) as usize;
                s.m = 1;
                s.n += 1;
                s.stop = self.tracks[s.t].stop(1);
                s.d = [D::from_f64(d[0]), D::from_f64(d[1])];
                return None;
            }
            let moved = self.rebase_step::<S, DER>(st, s.n, cconv(full), dc_fe, der, local);
            return self.moved(s, moved, dc_fe);
        }
        if let Some(table) = tables.get(s.t)
            && let Some((step, len)) = table.lookup(s.m, d2, self.max_iter - s.n)
        {
            let ad = mat_vec(&step.a, s.d);
            s.d = if self.mandelbrot { cadd(ad, mat_vec(&step.b, s.dc)) } else { ad };
            if DER {
                der.bla(&step.a, &step.b);
            }
            s.m += len;
            s.n += len;
            local.bla_steps += 1;
            local.bla_iterations += u64::from(len);
            local.iterations += u64::from(len);
            return None;
        }
        if DER {
            // A FloatExp part below f64's range rounds to ±0, whose sign a fold's
            // derivative would misread.
            let at = if fe { wide::signed_f64(cconv(full)) } else { z };
            der.step(st.jacobian(s.n, at));
        }
        s.d = cadd(st.delta(s.n, zr, s.d), s.dc);
        s.m += 1;
        s.n += 1;
        local.steps += 1;
        local.iterations += 1;
        if fe && max_exp(s.d) > self.up_exp {
            let f = Sample { d: cconv(s.d), dc: cconv(dc_fe), t: s.t, m: s.m, n: s.n, stop: s.stop };
            return Some(Exit::F64(f));
        }
        None
    }

    /// Takes a state one iteration on, `moved` = (track, index, delta in FloatExp) from an
    /// out-of-line step; returns the switch to the other number type where the delta asks
    /// for it.
    #[inline(always)]
    fn moved<D: Real>(
        &self,
        s: &mut Sample<D>,
        (t, m, d): (usize, u32, [FloatExp; 2]),
        dc_fe: [FloatExp; 2],
    ) -> Option<Exit> {
        let fe = D::NAME == FloatExp::NAME;
        s.t = t;
        s.m = m;
        s.n += 1;
        s.stop = self.tracks[t].stop(m);
        let e = max_exp(d);
        let at = Sample { d, dc: dc_fe, t, m, n: s.n, stop: s.stop };
        if fe && e > self.up_exp {
            return Some(Exit::F64(self.to_f64(at, dc_fe)));
        }
        if !fe && self.numbers == Numbers::FloatExp && e < self.down_exp {
            return Some(Exit::Fe(at));
        }
        s.d = cconv(d);
        None
    }

    /// One whole iteration at a track's `stop` (a wide value or the track's end), in
    /// FloatExp: the traps and end tests, then a rebase (at the end, or where the sample is
    /// nearer 0) or the step from the wide value ([`wide::delta`]). Err: the sample ended.
    #[cold]
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn special<S: Stepper, D: Real, const DER: bool>(
        &self,
        st: &S,
        s: &Sample<D>,
        d: [FloatExp; 2],
        dc_fe: [FloatExp; 2],
        der: &mut Jac,
        traps: &[Trap],
        states: &mut [TrapState],
        local: &mut Counters,
    ) -> Result<(usize, u32, [FloatExp; 2]), Orbit> {
        let track = &self.tracks[s.t];
        let (zm, u) = track.value_fe(s.m);
        let full = cadd(zm, d);
        let z = cto_f64(full);
        if s.n >= 1 {
            for (trap, state) in traps.iter().zip(states.iter_mut()) {
                trap.observe(state, z);
            }
        }
        if z[0] * z[0] + z[1] * z[1] > self.escape2 {
            return Err(Orbit { n: s.n, z, dz: if DER { der.output(z) } else { [0.0; 2] } });
        }
        if s.n >= self.max_iter {
            return Err(Orbit::interior());
        }
        if s.m >= track.last() || norm2(full) < norm2(d) {
            return Ok(self.rebase_step::<S, DER>(st, s.n, full, dc_fe, der, local));
        }
        local.steps += 1;
        if DER {
            der.step(st.jacobian(s.n, wide::signed_f64(full)));
        }
        let step = wide::delta(self.formula.phase(s.n), zm, u, d);
        Ok((s.t, s.m + 1, cadd(step, dc_fe)))
    }

    /// [`Engine::rebase_step`]'s delta computed in f64, where that gives its bits: None
    /// unless every part of `full` is nonzero and at least 2^-(1022/p - 56), every part of
    /// `dc` is 0 or normal, and every part of the result is nonzero and at least 2^-1000
    /// (and, with FloatExp deltas allowed, not below the switch to them).
    ///
    /// FloatExp's operations are f64's own on mantissas with the exponent apart (a product
    /// rounds once; a sum aligns exactly and rounds once), so they round as f64 does
    /// wherever every value is a normal f64. From δ = full with parts of at least 2^-T, a
    /// product of k parts is at least 2^-kT and a difference that cancels is still at
    /// least 2^-52 of its terms, so every nonzero value of the binomial expansion of degree
    /// p stays above 2^-(pT + 52p) >= 2^-1022 for T <= 1022/p - 52; zeros may differ in
    /// sign, which a nonzero result does not see.
    #[inline(always)]
    fn rebase_f64<S: Stepper>(&self, st: &S, n: u32, full: [f64; 2], dc: [f64; 2]) -> Option<[f64; 2]> {
        let d = rebase_delta_f64(st, n, full, dc, self.rebase_low)?;
        let fe_next = self.numbers == Numbers::FloatExp && max_exp(d) < self.down_exp;
        (!fe_next).then_some(d)
    }

    /// A rebase at iteration `n` (the sample's full value `full` becomes its delta against
    /// Z_0 = 0 of the orbit of 0 whose phase is n's) and the step from there, in FloatExp:
    /// δ = f_n(full) + δc at index 1.
    #[cold]
    #[inline(never)]
    fn rebase_step<S: Stepper, const DER: bool>(
        &self,
        st: &S,
        n: u32,
        full: [FloatExp; 2],
        dc_fe: [FloatExp; 2],
        der: &mut Jac,
        local: &mut Counters,
    ) -> (usize, u32, [FloatExp; 2]) {
        local.rebases += 1;
        local.steps += 1;
        if DER {
            der.step(st.jacobian(n, wide::signed_f64(full)));
        }
        let t = self.zeros + (n % self.period) as usize;
        (t, 1, cadd(st.delta::<FloatExp>(n, [0.0; 2], full), dc_fe))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::kind::KINDS;
    use crate::formula::{Formula, Phase, Single};

    /// The f64 rebase step has the FloatExp step's bits wherever it answers, for every
    /// family at every power, from full values near its lower bound to the escape radius
    /// (signs and sizes mixed, so that parts cancel), and it answers for most of them.
    #[test]
    fn the_f64_rebase_has_the_floatexp_rebases_bits() {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut rand = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for k in KINDS {
            for p in k.min_power..=k.max_power {
                let formula = Formula::single(Phase::new(k.kind, p));
                let low = f64::from_bits(((1023 - (1022 / p as i32 - 56)) as u64) << 52);
                let lg = low.log2();
                let (mut answered, mut tried) = (0, 0);
                crate::with_map!(formula.phases()[0], m: M => {
                    let st = Single(m);
                    for j in 0..3000 {
                        let e = |r: f64| if j % 3 == 0 { lg + r * 8.0 } else { lg + r * (8.0 - lg) };
                        let sign = |r: f64| if r < 0.5 { -1.0 } else { 1.0 };
                        let (a, b) = (e(rand()), e(rand()));
                        let mut full = [sign(rand()) * a.exp2(), sign(rand()) * b.exp2()];
                        if j % 5 == 0 {
                            // Equal sizes: x^2 - y^2 and its kin cancel.
                            full[1] = sign(rand()) * full[0].abs();
                        }
                        let dc = [(lg - 30.0 * rand()).exp2() * sign(rand()), if j % 7 == 0 { 0.0 } else { 1e-200 }];
                        tried += 1;
                        let Some(got) = rebase_delta_f64(&st, 0, full, dc, low) else { continue };
                        answered += 1;
                        let fe = |v: [f64; 2]| [FloatExp::from(v[0]), FloatExp::from(v[1])];
                        let want: [f64; 2] = cconv(cadd(st.delta::<FloatExp>(0, [0.0; 2], fe(full)), fe(dc)));
                        assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "{formula} {full:?} {dc:?}");
                    }
                }, unreachable!());
                assert!(answered * 2 > tried, "{formula}: {answered} of {tried}");
            }
        }
    }
}
