//! The perturbation loop: every sample iterated as a delta against the reference orbit.
//!
//! With the reference Z_m and a sample's full value z = Z_m + δ, the map z -> z^2 + c
//! becomes δ -> (2 Z_m + δ) δ + δc (δc = the sample's offset from the reference parameter,
//! zero for Julia sets, whose delta lives in z_0). The loop is written once, generic over
//! the delta's number type ([`Real`]: f64, or `FloatExp` below 1e-300); the driver switches
//! a sample between the two as its delta crosses the f64-safe range.
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

use super::bla::{Bla, BlaTable};
use super::reference::Reference;
use crate::field::Orbit;
use crate::num::real::{cadd, cconv, cmul, cto_f64, norm2};
use crate::num::{FloatExp, Real};
use crate::trap::{Trap, TrapState};

/// A rebase to a full value below this (max norm) moves a sample from f64 to FloatExp in the
/// hybrid mode: the next step is δ^2 + δc (Z_0 = 0), and δ^2 must stay a normal f64 well
/// above the offset δc, which at these depths is below the f64 range.
const DOWN: f64 = f64::from_bits((1023 - 500) << 52);
/// Deltas above this move a sample from FloatExp back to f64: every term of the step
/// (δ^2 included) is then a normal f64. (At 2^-480, where only δ itself is normal,
/// `deepfield compare` at zoom 1e320 found N off by one on 5% of pixels.)
const UP: f64 = f64::from_bits((1023 - 480) << 52);
/// Pauldelbrot's criterion, squared: |Z + δ|^2 < GLITCH2 |Z|^2 flags a glitch.
const GLITCH2: f64 = 1e-6;
/// The derivative's mantissa is renormalised when its largest part leaves [2^-500, 2^500].
const DER_HI: f64 = f64::from_bits((1023 + 500) << 52);
const DER_LO: f64 = f64::from_bits((1023 - 500) << 52);

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
    /// Rebases to the start of an orbit of 0.
    pub rebases: u64,
    /// Samples Pauldelbrot's criterion flagged (each was fixed by rebasing).
    pub glitches: u64,
}

impl Counters {
    /// Adds `o`.
    pub fn add(&mut self, o: &Counters) {
        self.iterations += o.iterations;
        self.steps += o.steps;
        self.floatexp_steps += o.floatexp_steps;
        self.bla_steps += o.bla_steps;
        self.bla_iterations += o.bla_iterations;
        self.rebases += o.rebases;
        self.glitches += o.glitches;
    }
}

/// The orbits and tables the loop runs against, shared by all samples.
#[derive(Debug)]
pub struct Perturbation {
    /// [primary reference, orbit of 0 used after rebasing]; Mandelbrot has only the first
    /// (its reference starts at 0 and serves both).
    pub refs: Vec<Reference>,
    /// BLA tables per reference in FloatExp and f64 (None: BLA off).
    pub bla_fe: [Option<BlaTable<FloatExp>>; 2],
    /// The same tables for f64 deltas.
    pub bla_f64: [Option<BlaTable<f64>>; 2],
    /// True for Mandelbrot (δc is the sample offset; the derivative adds the spacing).
    pub mandelbrot: bool,
    /// Sample spacing.
    pub spacing: FloatExp,
    /// Largest iteration index.
    pub max_iter: u32,
    /// Escape radius squared.
    pub escape2: f64,
    /// Carry the derivative.
    pub derivative: bool,
    /// Delta number types.
    pub numbers: Numbers,
}

/// A sample's state in number type D.
#[derive(Debug, Clone, Copy)]
struct Sample<D> {
    dz: [D; 2],
    dc: [D; 2],
    m: u32,
    which: usize,
    n: u32,
}

impl<D: Real> Sample<D> {
    fn convert<E: Real>(&self) -> Sample<E> {
        Sample { dz: cconv(self.dz), dc: cconv(self.dc), m: self.m, which: self.which, n: self.n }
    }
}

/// The scaled derivative mant * 2^exp (= dz/dc times the spacing), and what a step adds.
#[derive(Debug, Clone, Copy)]
struct Der {
    mant: [f64; 2],
    exp: i32,
    add: f64,
}

impl Der {
    fn to_fe(self) -> [FloatExp; 2] {
        [FloatExp::new(self.mant[0], self.exp), FloatExp::new(self.mant[1], self.exp)]
    }

    fn from_fe(v: [FloatExp; 2], add_fe: FloatExp) -> Der {
        let big = if v[0].is_zero() {
            v[1]
        } else if v[1].is_zero() || v[0].abs() > v[1].abs() {
            v[0]
        } else {
            v[1]
        };
        let exp = if big.is_zero() { 0 } else { big.exponent() };
        let mant = [v[0].ldexp(-exp).to_f64(), v[1].ldexp(-exp).to_f64()];
        Der { mant, exp, add: add_fe.ldexp(-exp).to_f64() }
    }

    #[inline(always)]
    fn renormalise(&mut self, add_fe: FloatExp) {
        let big = self.mant[0].abs().max(self.mant[1].abs());
        if !(DER_LO..=DER_HI).contains(&big) && big != 0.0 {
            *self = Der::from_fe(self.to_fe(), add_fe);
        }
    }

    fn to_f64(self) -> [f64; 2] {
        let v = self.to_fe();
        [v[0].to_f64(), v[1].to_f64()]
    }
}

/// How a run of the loop in one number type ended.
enum Exit<D> {
    Done(Orbit),
    Switch(Sample<D>),
}

impl Perturbation {
    /// Iterates the sample at `offset` (in units of the spacing, from the reference point),
    /// letting traps observe every z_k, k >= 1. Returns the orbit's end; z_n is exact to f64
    /// and dz_n is the derivative times the spacing.
    pub fn orbit(&self, offset: [f64; 2], traps: &[Trap], states: &mut [TrapState], counters: &mut Counters) -> Orbit {
        let d = [self.spacing.mul_f64(offset[0]), self.spacing.mul_f64(offset[1])];
        let zero = FloatExp::ZERO;
        let (start, add_fe) = if self.mandelbrot {
            (Sample { dz: d, dc: d, m: 1, which: 0, n: 1 }, self.spacing)
        } else {
            (Sample { dz: d, dc: [zero; 2], m: 0, which: 0, n: 0 }, zero)
        };
        let mut der = Der::from_fe([self.spacing, zero], add_fe);
        let use_bla = traps.is_empty();
        let tables_fe = if use_bla { [self.bla_fe[0].as_ref(), self.bla_fe[1].as_ref()] } else { [None, None] };
        let tables_64 = if use_bla { [self.bla_f64[0].as_ref(), self.bla_f64[1].as_ref()] } else { [None, None] };
        let hybrid = self.numbers == Numbers::FloatExp;
        let max_abs = |v: [FloatExp; 2]| v[0].abs().max(v[1].abs());
        let mut fe_state = (hybrid && max_abs(d) < FloatExp::from(DOWN)).then_some(start);
        let mut f64_state: Sample<f64> = start.convert();
        loop {
            if let Some(s) = fe_state.take() {
                match self.run::<FloatExp>(s, &mut der, add_fe, tables_fe, traps, states, counters, hybrid) {
                    Exit::Done(o) => return o,
                    Exit::Switch(s) => f64_state = s.convert(),
                }
            }
            match self.run::<f64>(f64_state, &mut der, add_fe, tables_64, traps, states, counters, hybrid) {
                Exit::Done(o) => return o,
                // The offset goes back to FloatExp from the original, never from its f64
                // rounding: below 2^-1022 that keeps only a few bits.
                Exit::Switch(s) => fe_state = Some(Sample { dc: start.dc, ..s.convert() }),
            }
        }
    }

    /// The loop in number type D, until the sample ends or (hybrid) needs the other type.
    #[inline(never)]
    fn run<D: Real>(
        &self,
        mut s: Sample<D>,
        der: &mut Der,
        add_fe: FloatExp,
        tables: [Option<&BlaTable<D>>; 2],
        traps: &[Trap],
        states: &mut [TrapState],
        counters: &mut Counters,
        hybrid: bool,
    ) -> Exit<D> {
        let full_range = D::NAME == FloatExp::NAME;
        let two = D::from_f64(2.0);
        let start_n = s.n;
        // Counted locally and added on exit: the loop's state stays in registers.
        let mut local = Counters::default();
        let mut r = &self.refs[s.which];
        let mut table = tables[s.which];
        let exit = loop {
            let mut zm: [D; 2] = if full_range {
                cconv(r.get_fe(s.m))
            } else {
                let g = r.get(s.m);
                [D::from_f64(g[0]), D::from_f64(g[1])]
            };
            let full = cadd(zm, s.dz);
            let z = cto_f64(full);
            if s.n >= 1 {
                for (trap, state) in traps.iter().zip(states.iter_mut()) {
                    trap.observe(state, z);
                }
            }
            if z[0] * z[0] + z[1] * z[1] > self.escape2 {
                let dz = if self.derivative { der.to_f64() } else { [0.0; 2] };
                break Exit::Done(Orbit { n: s.n, z, dz });
            }
            if s.n >= self.max_iter {
                break Exit::Done(Orbit::interior());
            }
            let d2 = norm2(s.dz);
            let f2 = norm2(full);
            let rebase = f2 < d2 || s.m >= r.last();
            let glitch = !rebase && f2 < norm2(zm).mul_f64(GLITCH2);
            if rebase || glitch {
                local.glitches += glitch as u64;
                local.rebases += 1;
                s.dz = full;
                s.m = 0;
                s.which = self.refs.len() - 1;
                r = &self.refs[s.which];
                table = tables[s.which];
                zm = [D::ZERO; 2];
                if hybrid && !full_range && z[0].abs().max(z[1].abs()) < DOWN {
                    break Exit::Switch(s);
                }
            } else if let Some(t) = table
                && let Some((e, len)) = t.lookup(s.m, d2, self.max_iter - s.n)
            {
                self.apply_bla(e, &mut s, der, add_fe);
                s.m += len;
                s.n += len;
                local.bla_steps += 1;
                local.bla_iterations += len as u64;
                continue;
            }
            if self.derivative {
                let [x, y] = z;
                let [a, b] = der.mant;
                der.mant = [2.0 * (x * a - y * b) + der.add, 2.0 * (x * b + y * a)];
                der.renormalise(add_fe);
            }
            s.dz = cadd(cmul(cadd([zm[0] * two, zm[1] * two], s.dz), s.dz), s.dc);
            s.m += 1;
            s.n += 1;
            local.steps += 1;
            if full_range && hybrid && s.dz[0].to_f64().abs().max(s.dz[1].to_f64().abs()) > UP {
                break Exit::Switch(s);
            }
        };
        if full_range {
            local.floatexp_steps = local.steps;
        }
        local.iterations = (s.n - start_n) as u64;
        counters.add(&local);
        exit
    }

    /// δ -> A δ + B δc, and the derivative alike (in FloatExp: A may be huge).
    #[inline(never)]
    fn apply_bla<D: Real>(&self, e: &Bla<D>, s: &mut Sample<D>, der: &mut Der, add_fe: FloatExp) {
        s.dz = cadd(cmul(e.a, s.dz), cmul(e.b, s.dc));
        if self.derivative {
            let a: [FloatExp; 2] = cconv(e.a);
            let b: [FloatExp; 2] = cconv(e.b);
            let d = cadd(cmul(a, der.to_fe()), [b[0] * add_fe, b[1] * add_fe]);
            *der = Der::from_fe(d, add_fe);
        }
    }
}
