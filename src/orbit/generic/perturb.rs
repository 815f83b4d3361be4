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
    d: [D; 2],
    /// The offset δc (zero for Julia sets; in f64 it may have underflowed).
    dc: [D; 2],
    /// The track followed.
    t: usize,
    /// Index on that track.
    m: u32,
    /// Iteration index of the sample.
    n: u32,
    /// The track's next index the hot loop does not handle.
    stop: u32,
}

/// How a run in one number type ended.
enum Exit {
    Done(Orbit),
    F64(Sample<f64>),
    Fe(Sample<FloatExp>),
}

/// The largest binary exponent of a pair (very negative for zero).
#[inline(always)]
fn max_exp<D: Real>(d: [D; 2]) -> i32 {
    d[0].to_fe().exponent().max(d[1].to_fe().exponent())
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
        let u = [self.spacing.mul_f64(offset[0]), self.spacing.mul_f64(offset[1])];
        let (dc_fe, n) = if self.mandelbrot { (u, 1) } else { ([FloatExp::ZERO; 2], 0) };
        if n > self.max_iter {
            return Orbit::interior();
        }
        let s = Sample { d: u, dc: dc_fe, t: 0, m: n, n, stop: self.tracks[0].stop(n) };
        let mut der = Jac::new(self.spacing, self.mandelbrot);
        let (t64, tfe): (&[Table<f64>], &[Table<FloatExp>]) = if bla { (&self.t64, &self.tfe) } else { (&[], &[]) };
        let mut next = if self.numbers == Numbers::FloatExp && max_exp(u) <= self.up_exp {
            Exit::Fe(s)
        } else {
            Exit::F64(self.to_f64(s, dc_fe))
        };
        loop {
            next = match next {
                Exit::Done(o) => return o,
                Exit::F64(s) => self.run::<S, f64, DER>(st, s, &mut der, dc_fe, t64, traps, states, counters, cancel),
                Exit::Fe(s) => {
                    self.run::<S, FloatExp, DER>(st, s, &mut der, dc_fe, tfe, traps, states, counters, cancel)
                }
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
            if s.m >= s.stop {
                let d = cconv(s.d);
                local.iterations += 1;
                match self.special::<S, D, DER>(st, &s, d, dc_fe, der, traps, states, &mut local) {
                    Err(o) => break Exit::Done(o),
                    Ok(moved) => match self.moved(&mut s, moved, dc_fe) {
                        Some(e) => break e,
                        None => continue,
                    },
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
                break Exit::Done(Orbit { n: s.n, z, dz: if DER { der.output(z) } else { [0.0; 2] } });
            }
            if s.n >= self.max_iter {
                break Exit::Done(Orbit::interior());
            }
            let d2 = norm2(s.d);
            if norm2(full) < d2 {
                local.iterations += 1;
                let moved = self.rebase_step::<S, DER>(st, s.n, cconv(full), dc_fe, der, &mut local);
                match self.moved(&mut s, moved, dc_fe) {
                    Some(e) => break e,
                    None => continue,
                }
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
                continue;
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
                break Exit::F64(f);
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
