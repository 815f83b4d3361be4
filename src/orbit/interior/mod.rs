//! Interior detection in the perturbation engines: a sample whose orbit has contracted by a
//! factor the iteration limit makes decisive, or that Newton's method shows attracted by a
//! cycle, is stopped and reported as interior.
//!
//! Along an orbit z_k the derivative with respect to its own start (z_1 = c for the
//! Mandelbrot set, z_0 for Julia sets) is dz_n/dz_start = prod 2 z_k, and through a BLA step
//! of l iterations it is multiplied by that step's Jacobian in the delta,
//! d(δ_{m+l})/d(δ_m) = A + 2 A2 δ + AB δc (A itself for a first-order step). An orbit
//! attracted by a cycle of multiplier λ (|λ| < 1) contracts geometrically, |λ| per period;
//! this is the interior checking of Claude Heiland-Allen's Mandelbrot notes and of
//! Fraktaler-3 ("stop when |dz/dz| is small"). Only the modulus is used, so what is carried
//! is the real number |dz/dz|^2 = prod 4 |z_k|^2 (one multiply per step; the escape test
//! already computed |z_k|^2).
//!
//! # The criterion
//!
//! An escaping orbit can contract too, for a while: one that crawls through the gate of a
//! parabolic point (parameters just outside a cusp) is slowed there, and its derivative
//! falls to about 16 ε (c = 1/4 + ε, from the flow w' = w^2 + ε: ∂w(t)/∂w(0) =
//! g(w(t))/g(w(0))) while it escapes after about π/√ε iterations. Measured on the cusp of
//! the main cardioid (ε = 1e-4 .. 1e-10), the root of the period-3 bulb and outside the main
//! cardioid: min_n |dz_n/dz_1|^2 · N^4 >= 1.2e4 for every escaping orbit (N its escape
//! index), the cusp the worst case (a minibrot's cusp is the same with N counted in periods,
//! so its N is P times longer for the same dip); of 150 000 random escaping parameters (limit
//! 10^5) none dipped below 1e-12 at all. A fixed
//! threshold is therefore wrong at some iteration limit (1e-12 calls c = 1/4 + 1e-8,
//! which escapes at 31418, interior). The threshold here is |dz/dz|^2 < min(1e-12,
//! max_iter^-4): an orbit that dips below it either never escapes or escapes later than
//! (1.2e4)^(1/4) ≈ 10 times the iteration limit, so N is INTERIOR either way.
//!
//! Julia sets need one more condition. A sample near a preimage of the critical point 0
//! has a tiny derivative from its start (2 z_k with z_k near 0) whatever becomes of it;
//! where the parameter c is inside the Mandelbrot set's interior that preimage lies in a
//! Fatou component with the sample (an exterior sample cannot come near it), but for c
//! outside it or on its boundary the filled Julia set has no interior and such samples
//! escape soon (c = 0.28 + 0.008i: a dip of 9.4e-6 and an escape at 42). So a Julia set is
//! checked only when its critical orbit (the reference orbit of 0 the engine has anyway)
//! meets the Mandelbrot criterion at c, [`orbit_contracts`].
//!
//! # Newton's test
//!
//! The contraction needs log(threshold) / log|λ| periods: hundreds for |λ| = 0.9, more than
//! the limit allows near a component's edge. In a view centred on a nucleus (the reference
//! is one period p, and every sample comes back near 0 at the end of each turn) the loop
//! also tries, at those ends, Newton's method for an attracting cycle of period k p
//! ([`newton_attracting`], the test of interior distance estimation): an attracting cycle
//! at c is a proof that c is interior (Kantorovich's theorem certifies it), found within a
//! few periods for |λ| up to about 1 - 1e-5. The contraction criterion still decides
//! everywhere else.
//!
//! # Disks
//!
//! Samples inside a minibrot's cardioid or one of its bulbs need not each be iterated and
//! tested: [`disk_attracting`] extends Newton's certificate from the parameter at a disk's
//! centre to the whole disk, with the value's and the multiplier's first derivatives in
//! the parameter (carried through the turn) and a margin for the rest that it checks at
//! the disk's edge. The engine tiles a batch of samples with such disks, halving it
//! across its longer side until a part's disk passes (`Perturbation::certified_disks`, in
//! `orbit/perturb/disks.rs`); what no disk covers is iterated and tested as above. At the
//! 1e102 minibrot view, 92% of the interior samples lie in certified disks.
//!
//! A sample whose one-period quadratic model escapes (its parameter lies outside the
//! model's Mandelbrot set) leaves detection from its start: no Newton test, and its |dz/dz|^2 is no longer
//! followed ([`Contraction::dropped`]). Detection only ever saves time (a sample it does
//! not stop runs to the limit, with the same N), so such a judgement can cost time where
//! the model is wrong, never a wrong pixel.
//!
//! # Representation
//!
//! `mant · 2^exp`, the mantissa kept in a window [`LO`, [`Check::hi`]] by renormalisation
//! (rare: the window is about 1800 bits wide at the default escape radius). The top of the
//! window leaves room for one step's factor, 4 |z|^2 <= 4 R^2 (R the escape radius), so a
//! step is one multiply with no test; the bottom leaves room for a factor of 4 [`TINY2`].
//! Factors below that (|z| < 2^-101, an orbit passing near 0) and BLA steps whose factor or
//! product leaves the window are applied exactly in `FloatExp`. The loop tests the window
//! once per pass, and the threshold costs no second comparison: `lo`, the bottom of the
//! window for the current exponent, is raised to threshold / 2^exp.

pub(in crate::orbit) mod batch_models;
mod disks;
pub(in crate::orbit) mod model;
pub(in crate::orbit) mod probe;

use std::cmp::Ordering;

use super::reference::Reference;
use crate::num::real::{cadd, cconv, cmul, norm2};
use crate::num::{FloatExp, Real};

/// Bottom of the mantissa's window: times a factor of at least 4 [`TINY2`] it stays normal.
pub const LO: f64 = f64::from_bits((1023 - 800) << 52);
/// |z|^2 below this (|z| < 2^-101) is applied apart: in f64 the product could underflow.
/// (The same bound as the derivative's, `DER_TINY_Z2`.)
pub const TINY2: f64 = f64::from_bits((1023 - 202) << 52);

/// The threshold on |dz/dz|^2 for an iteration limit: min(1e-12, max_iter^-4) (module docs).
pub fn threshold(max_iter: u32) -> FloatExp {
    let m = FloatExp::from(max_iter.max(1) as f64);
    let m2 = m * m;
    FloatExp::from(1.0) / (m2 * m2).max(FloatExp::from(1e12))
}

/// What interior detection needs to know about a view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Check {
    /// The threshold on |dz/dz|^2 ([`threshold`]).
    pub below2: FloatExp,
    /// Top of the mantissa's window: times a step's largest factor, 4 R^2, it stays finite.
    pub hi: f64,
    /// Binary exponent of the mantissa after a renormalisation (the middle of the window).
    mid: i32,
}

impl Check {
    /// The check for an iteration limit and escape radius R (2 ..= 1e150).
    pub fn new(max_iter: u32, escape_radius: f64) -> Check {
        // 4 R^2 <= 2^k; the window's top 2^(1022 - k).
        let k = (4.0 * escape_radius * escape_radius).log2().ceil() as i32;
        let top = (1022 - k).clamp(-700, 1000);
        let bottom = LO.log2() as i32;
        let hi = f64::from_bits(((1023 + top) as u64) << 52);
        Check { below2: threshold(max_iter), hi, mid: (top + bottom) / 2 }
    }

    /// A check that never fires (interior detection off; its window is the default escape
    /// radius's).
    pub const OFF: Check = Check { below2: FloatExp::ZERO, hi: f64::from_bits((1023 + 988) << 52), mid: 94 };
}

/// |dz/dz|^2 of a sample = `mant` · 2^`exp`.
///
/// Steps only multiply ([`Contraction::step`], [`Contraction::bla_step`]); the loop asks
/// [`Contraction::interior`] at the top of its next pass (the vector lanes in the same
/// comparison as their other events), which decides where the mantissa left its window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contraction {
    /// The mantissa: within [`LO`, `hi`] between passes.
    pub mant: f64,
    /// Its binary exponent.
    pub exp: i32,
    /// The mantissa below which the value may be under the threshold: threshold / 2^exp,
    /// clamped to [`LO`, `hi`].
    pub lo: f64,
}

impl Contraction {
    /// The state of a sample that carries none (interior detection off).
    pub const IDLE: Contraction = Contraction { mant: 1.0, exp: 0, lo: 0.0 };

    /// The value `v` (>= 0), the mantissa in the middle of the window.
    pub fn new(v: FloatExp, check: Check) -> Contraction {
        let exp = if v.is_zero() { 0 } else { v.exponent() - check.mid };
        let lo = check.below2.ldexp(-exp).max(FloatExp::from(LO)).min(FloatExp::from(check.hi));
        // Within the window the exponents fit f64; a zero value is below any threshold.
        Contraction { mant: v.ldexp(-exp).to_f64(), exp, lo: lo.to_f64() }
    }

    /// The state of a sample whose contraction is no longer followed (it has left interior
    /// detection: its steps may or may not multiply it further): 2^(2^30), which no run of
    /// steps within an iteration limit can bring below a threshold, except an orbit that
    /// lands on 0 exactly (a superattracting cycle: interior indeed).
    pub fn dropped(check: Check) -> Contraction {
        // `Contraction::new` of that value, without its FloatExp arithmetic (a sample that
        // leaves detection at its start takes this): the mantissa 2^mid, and the threshold
        // 2^(2^30 - mid) times below the window, clamped to its bottom.
        let mant = f64::from_bits(((1023 + check.mid) as u64) << 52);
        Contraction { mant, exp: (1 << 30) - check.mid, lo: LO.min(check.hi) }
    }

    /// The value, exactly.
    pub fn value(self) -> FloatExp {
        FloatExp::new(self.mant, self.exp)
    }

    /// True when the mantissa has left its window or come below `lo`.
    #[inline(always)]
    pub fn unsettled(self, check: Check) -> bool {
        !(self.mant >= self.lo && self.mant <= check.hi)
    }

    /// One perturbation step from the full value `z`, whose |z|^2 in its own arithmetic is
    /// `f2`: the mantissa times 4 f2 in f64 for f2 at least [`TINY2`] (as the vector lanes
    /// compute it). Below that (where an orbit passes near 0, once a period inside a
    /// minibrot) the product is taken in f64 only where it and `f2` are normal numbers, else
    /// recomputed from `z` in FloatExp (`f2` may have underflowed).
    #[inline(always)]
    pub fn step<D: Real>(&mut self, z: [D; 2], f2: D, check: Check) {
        let f = f2.to_f64();
        let p = self.mant * (f * 4.0);
        if f >= TINY2 || (f >= f64::MIN_POSITIVE && p >= f64::MIN_POSITIVE) {
            self.mant = p;
        } else {
            self.times(norm2(cconv::<D, FloatExp>(z)).ldexp(2), check);
        }
    }

    /// A BLA step: the value times |m|^2, m the step's Jacobian in the delta. In f64 when
    /// |m|^2 and the product are normal and the product is within the window's top (the
    /// common case), else in FloatExp.
    #[inline(always)]
    pub fn bla_step<D: Real>(&mut self, m: [D; 2], check: Check) {
        let f = norm2(m).to_f64();
        let p = self.mant * f;
        if f.is_normal() && (f64::MIN_POSITIVE..=check.hi).contains(&p) {
            self.mant = p;
        } else {
            self.times(norm2(cconv::<D, FloatExp>(m)), check);
        }
    }

    /// The value times `factor`, exactly, renormalised (a value below the threshold is left
    /// unsettled).
    #[cold]
    #[inline(never)]
    fn times(&mut self, factor: FloatExp, check: Check) {
        *self = Contraction::new(self.value() * factor, check);
    }

    /// Once unsettled: true when the value is below the threshold (the sample is
    /// interior), else the mantissa is brought back to the middle of the window.
    #[cold]
    #[inline(never)]
    fn settle(&mut self, check: Check) -> bool {
        let v = self.value();
        if v < check.below2 {
            return true;
        }
        *self = Contraction::new(v, check);
        false
    }

    /// What the loop asks at the top of a pass: true when the sample is interior.
    #[inline(always)]
    pub fn interior(&mut self, check: Check) -> bool {
        self.unsettled(check) && self.settle(check)
    }
}

/// True when a reference orbit contracts below the threshold from Z_1 before it ends, by
/// the same steps as a sample's: its point is then taken to be interior. For the critical
/// orbit of a Julia set's parameter c (the reference orbit of 0: Z_0 = 0, Z_1 = c, ...)
/// that puts c inside the Mandelbrot set's interior, where the Julia set's interior
/// samples are recognised safely (module docs). An orbit that escapes never contracts.
pub fn orbit_contracts(orbit: &Reference, check: Check, max_iter: u32) -> bool {
    if orbit.escaped() {
        return false;
    }
    let mut c = Contraction::new(FloatExp::ONE, check);
    orbit.values_through_cycle(1, max_iter).any(|z| {
        c.step(z, norm2(z), check);
        c.interior(check)
    })
}

/// f^p at a point: the value and its first and second derivatives there.
#[derive(Debug, Clone, Copy)]
pub struct Turn {
    /// f^p(w).
    pub z: [f64; 2],
    /// d(f^p)/dw.
    pub d1: [FloatExp; 2],
    /// d^2(f^p)/dw^2, when it was requested.
    pub d2: Option<[FloatExp; 2]>,
}

/// Newton's method for an attracting cycle: `map` gives f^p and its derivatives at w (None
/// where it cannot follow the orbit; the second derivative only when its flag asks, which
/// it does once the previous step was below the square root of [`NEWTON_BALL`] of |w|). From `w`, w <- w - F(w) / F'(w) with F(w) = f^p(w) - w,
/// at most [`NEWTON_STEPS`] times; true as soon as Kantorovich's theorem, with a Lipschitz
/// bound L = 2 |F''(w)| for F' near w, proves a fixed point w* of f^p within 2 |step| of w
/// (h = |step| L / |F'(w)| <= 1/10) and bounds its multiplier below 1: |f^p'(w*)| <=
/// |f^p'(w)| + 2 |step| L < 1; false as soon as it bounds it above 1. The residual is
/// counted with [`NEWTON_NOISE`] of |w| added (the rounding and BLA steps, relative accuracy
/// 1e-14, that f^p is computed with). The bound is used only on a ball below
/// [`NEWTON_BALL`] of |w| and where F' moved from the previous iterate (or from the first
/// iterate whose ball was that small) by at most [`STEADY`] of what L allows: the first
/// Newton steps from a far start can land where F'' is a thousand times smaller than a
/// little way off (before these conditions, a sample that escapes after 268 periods, within
/// 1e-9 of a spacing of a minibrot's edge, was taken for interior at its second step of a
/// 7-turn Newton, 0.8 |w| from the first).
///
/// This is the test behind interior distance estimation (Claude Heiland-Allen's
/// mandelbrot-numerics, `m_d_interior_de`: the periodic point by Newton's method, then
/// |λ| <= 1), made a proof of interior: for the Mandelbrot set an attracting cycle at
/// parameter c puts c inside a hyperbolic component, whose critical orbit never escapes.
/// Near 0, where it is used, f^p is a quadratic-like map f^(p-1)(c) + Λ w^2 (Λ =
/// f^(p-1)'(c)), whose second derivative 2 Λ = λ / w* hardly varies over the ball, so
/// doubling it for L is ample. With the noise floor at 1e-12 |w|, multipliers up to about
/// 1 - 1e-5 can be certified; those nearer 1 are left to the contraction criterion.
pub fn newton_attracting(w: [f64; 2], map: impl FnMut([f64; 2], bool) -> Option<Turn>) -> bool {
    newton_cycle(w, map).is_some()
}

/// [`newton_attracting`], returning the iterate at which the attracting cycle was certified
/// (its point lies within twice that iterate's Newton step).
pub fn newton_cycle(mut w: [f64; 2], mut map: impl FnMut([f64; 2], bool) -> Option<Turn>) -> Option<[f64; 2]> {
    // The previous iterate and its f^p' (to check the Lipschitz bound against), and the
    // first iterate whose ball was small (the same check over a longer stretch).
    let mut before: Option<([f64; 2], [FloatExp; 2])> = None;
    let mut first_small: Option<([f64; 2], [FloatExp; 2])> = None;
    let mut near = false;
    for _ in 0..NEWTON_STEPS {
        let t = map(w, near)?;
        let f = cconv::<f64, FloatExp>([t.z[0] - w[0], t.z[1] - w[1]]);
        let slope = [t.d1[0] - FloatExp::ONE, t.d1[1]];
        let s2 = norm2(slope);
        if s2.is_zero() {
            return None;
        }
        // F / F' = F conj(F') / |F'|^2.
        let q = cmul(f, [slope[0], -slope[1]]);
        let step = [q[0] / s2, q[1] / s2];
        let size = norm2(cconv::<f64, FloatExp>(w)).sqrt();
        let reach = norm2(step).sqrt() + size.mul_f64(NEWTON_NOISE) / s2.sqrt();
        near = reach <= size.mul_f64(NEWTON_BALL.sqrt());
        let Some(d2) = t.d2 else {
            before = Some((w, t.d1));
            w = [w[0] - step[0].to_f64(), w[1] - step[1].to_f64()];
            if !(w[0].is_finite() && w[1].is_finite()) {
                return None;
            }
            continue;
        };
        let lip = norm2(d2).sqrt().ldexp(1);
        // The bound needs F'' steady over the ball: a ball small beside |w| (f^p's features
        // near 0 are on the scale of w), and F' changing from an earlier iterate by no more
        // than STEADY of what the bound says. That iterate is the previous one, or the first whose
        // ball was small: once Newton has converged, consecutive iterates are a rounding
        // apart and the change of F' between them is the noise of f^p's derivative, which
        // no bound can be held to; for a multiplier near 1 (|F'| small) the certificate's
        // ball is only small enough there, so without the longer stretch it never passes.
        let small = reach <= size.mul_f64(NEWTON_BALL);
        let steady_since = |(v, d): ([f64; 2], [FloatExp; 2])| {
            let dw = norm2(cconv::<f64, FloatExp>([w[0] - v[0], w[1] - v[1]])).sqrt();
            norm2([t.d1[0] - d[0], t.d1[1] - d[1]]).sqrt() <= (lip * dw).mul_f64(STEADY)
        };
        let steady = before.is_some_and(steady_since) || first_small.is_some_and(steady_since);
        before = Some((w, t.d1));
        if small && first_small.is_none() {
            first_small = before;
        }
        if small && steady && reach * lip <= s2.sqrt().mul_f64(0.1) {
            // A fixed point is certified: attracting, repelling, or not yet told apart.
            let (lambda, spread) = (norm2(t.d1).sqrt(), (reach * lip).ldexp(1));
            if lambda + spread < FloatExp::ONE {
                return Some(w);
            }
            if lambda - spread > FloatExp::ONE {
                return None;
            }
        }
        w = [w[0] - step[0].to_f64(), w[1] - step[1].to_f64()];
        if !(w[0].is_finite() && w[1].is_finite()) {
            return None;
        }
    }
    None
}

/// How a turn's value at a point depends on the parameter: ∂f^p/∂c and ∂(f^p)'/∂c there.
#[derive(Debug, Clone, Copy)]
pub struct Sensitivity {
    /// ∂f^p(w)/∂c.
    pub dc: [FloatExp; 2],
    /// ∂²f^p(w)/∂w∂c: how the multiplier moves with the parameter.
    pub dwc: [FloatExp; 2],
}

/// Newton's certificate ([`newton_attracting`]) extended from one parameter to a disk of
/// them: true when every parameter within `rho` of the centre has an attracting fixed
/// point of f^p, so the whole disk lies in a hyperbolic component (interior). `w` is the
/// point [`newton_cycle`] certified at the centre; `map(w, shift)` gives f^p at w for the
/// parameter centre + shift (f64, plane units), with its second derivative and its
/// [`Sensitivity`].
///
/// For a parameter c in the disk, F_c(w) = f_c^p(w) - w at the centre's point is at most
/// the centre's residual, the rounding ([`NEWTON_NOISE`]) and the value's shift, taken as
/// [`DISK_MARGIN`] times its first-order part |∂f^p/∂c| rho; |F_c'| is at least |f^p' - 1|
/// less the multiplier's shift, likewise [`DISK_MARGIN`] |∂f^p'/∂c| rho (plus
/// [`DISK_TURN_FLOOR`] for its rounding). With the Lipschitz bound L = 2 |F''| as in
/// Newton's certificate, Kantorovich's theorem (h = η L / |F_c'| <= 1/4, η the residual
/// over the slope) gives each c a unique fixed point within t* = 2 η / (1 + sqrt(1 - 2 h))
/// of w, whose multiplier is at most |f^p'| plus the multiplier's shift plus L t*.
///
/// The bounds are checked where they could fail: at the ball's edge (w + 2 η) f^p' must
/// have moved by at most three quarters of what L allows and |F''| be below three quarters
/// of L; at the disk's edge (the parameter centre + rho) the value and the multiplier must
/// have moved from the centre's by their first-order parts give or take a fifth of them
/// (what the margin allows, less room for the next order; the terms left out are of second
/// order, the same size in every direction).
///
/// This is Newton's certificate made to cover many samples at once: a view centred on a
/// minibrot tiles its cardioid and bulbs with such disks (`Perturbation::orbits`), and each sample in
/// a certified disk is interior without an iteration of its own.
pub fn disk_attracting(
    w: [f64; 2],
    rho: f64,
    mut map: impl FnMut([f64; 2], [f64; 2]) -> Option<(Turn, Sensitivity)>,
) -> bool {
    let abs = |v: [FloatExp; 2]| norm2(v).sqrt();
    let Some((t, s)) = map(w, [0.0; 2]) else { return false };
    let Some(d2) = t.d2 else { return false };
    let r = FloatExp::from(rho);
    let size = abs(cconv::<f64, FloatExp>(w));
    let noise = size.mul_f64(NEWTON_NOISE);
    let (shift, turn) = (abs(s.dc) * r, abs(s.dwc) * r);
    let turn_bound = turn.mul_f64(DISK_MARGIN) + FloatExp::from(DISK_TURN_FLOOR);
    let resid = abs(cconv::<f64, FloatExp>([t.z[0] - w[0], t.z[1] - w[1]])) + noise + shift.mul_f64(DISK_MARGIN);
    let slope = abs([t.d1[0] - FloatExp::ONE, t.d1[1]]) - turn_bound;
    if slope.partial_cmp(&FloatExp::ZERO) != Some(Ordering::Greater) {
        return false;
    }
    let lip = abs(d2).ldexp(1);
    let eta = resid / slope;
    let h = (eta * lip / slope).to_f64();
    if h.is_nan() || h > 0.25 {
        return false;
    }
    let reach = eta.mul_f64(2.0 / (1.0 + (1.0 - 2.0 * h).sqrt()));
    if (abs(t.d1) + turn_bound + lip * reach).partial_cmp(&FloatExp::ONE) != Some(Ordering::Less) {
        return false;
    }
    // The ball's edge: F' and F'' as steady as L says.
    let edge = eta.ldexp(1);
    let Some((te, _)) = map([w[0] + edge.to_f64(), w[1]], [0.0; 2]) else { return false };
    let Some(d2_edge) = te.d2 else { return false };
    let moved = abs([te.d1[0] - t.d1[0], te.d1[1] - t.d1[1]]);
    if moved > (lip * edge).mul_f64(STEADY) || abs(d2_edge) > lip.mul_f64(STEADY) {
        return false;
    }
    // The disk's edge: what the first-order terms leave out within the margin.
    let Some((tc, _)) = map(w, [rho, 0.0]) else { return false };
    let value = cconv::<f64, FloatExp>([tc.z[0] - t.z[0], tc.z[1] - t.z[1]]);
    let value_rest = [value[0] - s.dc[0] * r, value[1] - s.dc[1] * r];
    let turn_rest = [tc.d1[0] - t.d1[0] - s.dwc[0] * r, tc.d1[1] - t.d1[1] - s.dwc[1] * r];
    let fifth = (DISK_MARGIN - 1.0) * 0.8;
    abs(value_rest) <= shift.mul_f64(fifth) + noise
        && abs(turn_rest) <= turn.mul_f64(fifth) + FloatExp::from(DISK_TURN_FLOOR / 2.0)
}

/// How much of its first-order part a disk certificate allows for the change of f^p's
/// value and multiplier across the disk ([`disk_attracting`]).
pub const DISK_MARGIN: f64 = 1.25;
/// An absolute allowance for the rounding of a multiplier (f^p' near 1 in size, computed
/// with a relative error near 1e-14) in the disk certificate.
pub const DISK_TURN_FLOOR: f64 = 1e-9;

/// The fewest periods of a nucleus's reference the iteration limit must hold for detection
/// to run by default.
pub const AUTO_MIN_PERIODS: u64 = 100;

/// Newton's steps at most, per attempt.
pub const NEWTON_STEPS: u32 = 24;
/// The relative error of f^p(w) allowed for in Newton's certificate.
pub const NEWTON_NOISE: f64 = 1e-12;
/// The largest ball (relative to |w|) over which Newton's certificate takes F'' as steady.
pub const NEWTON_BALL: f64 = 1e-6;
/// The share of the Lipschitz bound L = 2 |F''(w)| by which F' may have changed between
/// two of Newton's iterates for the certificate to take L as holding over its ball (the
/// disk certificate's check at its ball's edge allows the same). Near 0 f^p is
/// quadratic-like, F'' nearly constant, so F' changes by about |F''| |Δw| = L/2 |Δw|
/// between iterates: a share of a half put every such check on a coin's edge (on the
/// minibrot-e102 view, 49% of the certificates passed at the second iterate, the rest at
/// the third to the fifteenth or later); three quarters passes them at the second, and
/// still refuses where F'' along the way averaged more than half again its size at the
/// iterate.
pub const STEADY: f64 = 0.75;

/// Claude Heiland-Allen's size estimate ("Minibrot size estimates") of the minibrot of
/// period p from its nucleus's orbit z_1 .. z_(p-1): with l_n = prod_(k=1..n) 2 z_k and
/// b = 1 + sum_(n=1..p-1) 1 / l_n, the complex number 1 / (b l_(p-1)^2), whose modulus is
/// the minibrot's radius and argument the rotation of its cusp.
pub fn size_estimate(orbit: impl IntoIterator<Item = [FloatExp; 2]>) -> [FloatExp; 2] {
    let (mut l, mut b) = ([FloatExp::ONE, FloatExp::ZERO], [FloatExp::ONE, FloatExp::ZERO]);
    for z in orbit {
        l = cmul(l, [z[0].ldexp(1), z[1].ldexp(1)]);
        b = cadd(b, cinv(l));
    }
    cinv(cmul(b, cmul(l, l)))
}

/// 1 / a (zero for zero).
pub(super) fn cinv(a: [FloatExp; 2]) -> [FloatExp; 2] {
    let d = norm2(a);
    if d.is_zero() {
        return [FloatExp::ZERO; 2];
    }
    [a[0] / d, -(a[1] / d)]
}

/// What a scene asks for (`[render] interior_detection`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Detection {
    /// `false`: never.
    Off,
    /// `true`: wherever it is safe (for a Julia set, where its parameter is inside the
    /// Mandelbrot set).
    On,
    /// Key absent: where the view shows interior ([`decide`]).
    #[default]
    Auto,
}

/// Whether interior detection runs for a view, and why.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Decision {
    /// Requested (`render.interior_detection = true`).
    On,
    /// On by default: the view's centre is found interior by the same criterion (and, for
    /// a view centred on a nucleus, its minibrot is at least a sample across).
    AutoOn,
    /// Turned off by the scene.
    Off,
    /// Off by default: the view's centre escapes or its orbit does not contract.
    AutoExteriorCentre,
    /// Off by default: the view is centred on a minibrot smaller than a sample.
    AutoMinibrotBelowSample,
    /// Off by default: the view is centred on a nucleus whose period the iteration limit
    /// holds fewer than [`AUTO_MIN_PERIODS`] times.
    AutoFewPeriods,
    /// Off: a Julia set whose parameter is not inside the Mandelbrot set has no interior,
    /// and the criterion is not safe there.
    JuliaNoInterior,
}

impl Decision {
    /// True when detection runs.
    pub fn runs(self) -> bool {
        matches!(self, Decision::On | Decision::AutoOn)
    }

    /// One line for `--stats`.
    pub fn describe(self) -> &'static str {
        match self {
            Decision::On => "on (requested)",
            Decision::AutoOn => "on (by default: the view is centred on interior)",
            Decision::Off => "off (render.interior_detection = false)",
            Decision::AutoExteriorCentre => {
                "off (by default: the view's centre is not interior; render.interior_detection = true turns it on)"
            }
            Decision::AutoMinibrotBelowSample => {
                "off (by default: the view's minibrot is smaller than a sample; render.interior_detection = true turns it on)"
            }
            Decision::AutoFewPeriods => {
                "off (by default: the iteration limit holds fewer than 100 periods of the view's nucleus, too few for it to pay; render.interior_detection = true turns it on)"
            }
            Decision::JuliaNoInterior => {
                "off (the Julia parameter's critical orbit does not contract: the set has no interior)"
            }
        }
    }
}

/// Decides for a view: `refs` its reference orbits (the primary first; for a Julia set the
/// orbit of 0 last), `spacing` its sample spacing.
///
/// By default detection runs where the view shows interior and the limit leaves it
/// something to save: where the view is centred on a nucleus (its reference is one period
/// p) whose minibrot's size estimate is at least a sample spacing and the limit is at least
/// [`AUTO_MIN_PERIODS`] p, or where the view's centre is found interior by the criterion
/// itself (its reference orbit contracts). Elsewhere the default leaves it off: it costs a
/// few operations per step (about 13% of the single-thread time of the exterior-only
/// bench-e50 at 400x300), Newton's test some periods' work per sample tried, and an
/// interior sample it stops has run a few periods already (measured on minibrots of period
/// 25760 and 31967 to 10^6 iterations, 39 and 31 periods: 30-40% slower with detection). A Julia set is checked only where its
/// parameter's critical orbit contracts (module docs), whatever was asked.
pub fn decide(
    asked: Detection,
    refs: &[Reference],
    mandelbrot: bool,
    spacing: FloatExp,
    max_iter: u32,
    check: Check,
) -> Decision {
    if asked == Detection::Off {
        return Decision::Off;
    }
    if !mandelbrot && !orbit_contracts(&refs[refs.len() - 1], check, max_iter) {
        return Decision::JuliaNoInterior;
    }
    if asked == Detection::On {
        return Decision::On;
    }
    let centre = &refs[0];
    match centre.period() {
        Some(p) if norm2(size_estimate(centre.values_fe(1, p - 1))) < spacing * spacing => {
            Decision::AutoMinibrotBelowSample
        }
        Some(p) if (max_iter as u64) < AUTO_MIN_PERIODS * p as u64 => Decision::AutoFewPeriods,
        Some(_) => Decision::AutoOn,
        None if orbit_contracts(centre, check, max_iter) => Decision::AutoOn,
        None => Decision::AutoExteriorCentre,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether the orbit of c (from z_1 = c, stepped as the engine steps it) escapes, or is
    /// found interior, within `max_iter`.
    fn along(c: [f64; 2], max_iter: u32) -> (bool, bool) {
        let check = Check::new(max_iter, 65536.0);
        let mut k = Contraction::new(FloatExp::ONE, check);
        let mut z = c;
        for _ in 1..max_iter {
            if k.interior(check) {
                return (false, true);
            }
            let f2 = z[0] * z[0] + z[1] * z[1];
            if f2 > 65536.0 * 65536.0 {
                return (true, false);
            }
            k.step([FloatExp::from(z[0]), FloatExp::from(z[1])], FloatExp::from(f2), check);
            z = [z[0] * z[0] - z[1] * z[1] + c[0], 2.0 * z[0] * z[1] + c[1]];
        }
        (false, false)
    }

    /// The return map of z -> z^2 + c itself (p = 1): Newton finds the attracting fixed
    /// point inside the main cardioid, even 2e-5 from its edge, and nothing outside it, nor
    /// at its cusp or on its edge.
    #[test]
    fn newton_certifies_attracting_fixed_points_only() {
        let map = |c: [f64; 2]| {
            move |w: [f64; 2], _: bool| -> Option<Turn> {
                let z = [w[0] * w[0] - w[1] * w[1] + c[0], 2.0 * w[0] * w[1] + c[1]];
                let d1 = [FloatExp::from(2.0 * w[0]), FloatExp::from(2.0 * w[1])];
                Some(Turn { z, d1, d2: Some([FloatExp::from(2.0), FloatExp::ZERO]) })
            }
        };
        // c(λ) = λ/2 - λ^2/4 puts the fixed point's multiplier at λ.
        let at = |l: [f64; 2]| [l[0] / 2.0 - (l[0] * l[0] - l[1] * l[1]) / 4.0, l[1] / 2.0 - l[0] * l[1] / 2.0];
        for c in
            [[0.0, 0.0], [-0.5, 0.3], [0.2, 0.0], [-0.7, 0.1], [0.2499, 0.0], at([0.99998, 0.0]), at([0.0, 0.99998])]
        {
            assert!(newton_attracting([c[0] * 0.5, c[1] * 0.5], map(c)), "{c:?}");
        }
        for c in [
            [0.3, 0.0],
            [-0.8, 0.0],
            [-0.75, 0.2],
            [0.25, 0.0],
            [-1.0, 0.0],
            at([1.0, 0.0]),
            at([0.0, 1.0]),
            at([0.0, 1.00001]),
        ] {
            assert!(!newton_attracting([c[0] * 0.5, c[1] * 0.5], map(c)), "{c:?}");
        }
    }

    /// The disk certificate on z -> z^2 + c itself (p = 1, ∂f/∂c = 1): disks about points
    /// of the main cardioid are certified where they lie well inside it and refused where
    /// they reach its edge; every parameter on the edge of every certified disk of a sweep
    /// has an attracting fixed point (|1 - sqrt(1 - 4 c)| < 1).
    #[test]
    fn disks_are_certified_only_inside_the_cardioid() {
        let csqrt = |a: [f64; 2]| {
            let r = a[0].hypot(a[1]);
            [((r + a[0]) / 2.0).sqrt(), ((r - a[0]) / 2.0).sqrt().copysign(a[1])]
        };
        let multiplier = |c: [f64; 2]| {
            let s = csqrt([1.0 - 4.0 * c[0], -4.0 * c[1]]);
            (1.0 - s[0]).hypot(s[1])
        };
        let turn = |c: [f64; 2], w: [f64; 2]| {
            let z = [w[0] * w[0] - w[1] * w[1] + c[0], 2.0 * w[0] * w[1] + c[1]];
            let d1 = [FloatExp::from(2.0 * w[0]), FloatExp::from(2.0 * w[1])];
            Turn { z, d1, d2: Some([FloatExp::from(2.0), FloatExp::ZERO]) }
        };
        let certified = |c: [f64; 2], rho: f64| {
            let Some(w) = newton_cycle([c[0] * 0.5, c[1] * 0.5], |w, _| Some(turn(c, w))) else { return false };
            let one = Sensitivity { dc: [FloatExp::ONE, FloatExp::ZERO], dwc: [FloatExp::ZERO; 2] };
            disk_attracting(w, rho, |w, s| Some((turn([c[0] + s[0], c[1] + s[1]], w), one)))
        };
        assert!(certified([0.0, 0.0], 0.04));
        assert!(certified([-0.1, 0.05], 0.05));
        assert!(certified([-0.4, 0.2], 0.02));
        // Kantorovich's h is 1/2 there: too far from the centre's fixed point to bound.
        assert!(!certified([0.0, 0.0], 0.1));
        assert!(!certified([0.2, 0.0], 0.1), "reaches past the cusp");
        assert!(!certified([-0.7, 0.0], 0.1), "reaches past -3/4");
        assert!(!certified([-0.3, 0.5], 0.2), "reaches past the edge");
        let mut seen = 0;
        for i in 0..40 {
            for j in 0..40 {
                let c = [-0.8 + 1.1 * i as f64 / 40.0, -0.7 + 1.4 * j as f64 / 40.0];
                for rho in [0.003, 0.03, 0.1] {
                    if multiplier(c) >= 1.0 || !certified(c, rho) {
                        continue;
                    }
                    seen += 1;
                    for k in 0..32 {
                        let a = std::f64::consts::TAU * k as f64 / 32.0;
                        let e = [c[0] + rho * a.cos(), c[1] + rho * a.sin()];
                        assert!(multiplier(e) < 1.0, "disk about {c:?} of radius {rho}: {e:?} is outside");
                    }
                }
            }
        }
        assert!(seen > 500, "only {seen} disks certified");
    }

    #[test]
    fn threshold_follows_the_iteration_limit() {
        assert_eq!(threshold(1000).to_f64(), 1e-12);
        assert_eq!(threshold(10).to_f64(), 1e-12);
        let t = threshold(10_000_000).to_f64();
        assert!((t / 1e-28 - 1.0).abs() < 1e-12, "{t:e}");
        assert!(threshold(u32::MAX - 1) > FloatExp::ZERO);
        assert_eq!(Check::OFF, Check { below2: FloatExp::ZERO, ..Check::new(1000, 65536.0) });
    }

    /// Just outside the cusp c = 1/4 an orbit escapes after about π/√ε iterations and its
    /// derivative dips to about 16 ε on the way (below 1e-12 from ε = 1e-8): a fixed
    /// threshold would call it interior, the limit's own never does. Inside, a contracting
    /// orbit is recognised.
    #[test]
    fn crawling_through_a_parabolic_gate_is_not_interior() {
        for eps in [1e-4, 1e-6, 1e-8] {
            for max_iter in [1000, 40_000, 1_000_000] {
                let (escaped, interior) = along([0.25 + eps, 0.0], max_iter);
                assert!(!interior, "c = 1/4 + {eps:e}, limit {max_iter}: called interior");
                let n = (std::f64::consts::PI / eps.sqrt()) as u32;
                assert_eq!(escaped, max_iter > n + n / 10, "c = 1/4 + {eps:e}, limit {max_iter}");
            }
        }
        for c in [[0.0, 0.0], [-0.1, 0.6], [-1.0, 0.1], [0.2499, 0.0], [-1.7549, 0.0]] {
            assert_eq!(along(c, 1_000_000), (false, true), "{c:?}");
        }
    }

    /// A step from a full value with |z|^2 = `f2` (on the real axis), then the loop's test.
    fn step(k: &mut Contraction, f2: FloatExp, check: Check) -> bool {
        k.step([f2.sqrt(), FloatExp::ZERO], f2, check);
        k.interior(check)
    }

    #[test]
    fn window_and_threshold() {
        let check = Check::new(1_000_000, 65536.0);
        let new = |v| Contraction::new(v, check);
        let mut k = new(FloatExp::ONE);
        assert!(!k.unsettled(check));
        // A factor of 2^-100 crosses the threshold (1e-24 = 2^-79.7) at once.
        assert!(step(&mut k, FloatExp::new(1.0, -102), check));
        // Factors of 16: 2^400, renormalised on the way.
        let mut k = new(FloatExp::ONE);
        for _ in 0..100 {
            assert!(!step(&mut k, FloatExp::from(4.0), check));
        }
        assert_eq!(k.value(), FloatExp::new(1.0, 400));
        // Factors of 4 · 1/8 = 1/2: 2^400 to 2^300, then on down to the threshold.
        for _ in 0..100 {
            assert!(!step(&mut k, FloatExp::from(0.125), check));
        }
        assert_eq!(k.value(), FloatExp::new(1.0, 300));
        let mut steps = 0;
        while !step(&mut k, FloatExp::from(0.125), check) {
            steps += 1;
        }
        // 2^300 down to below 1e-24 ≈ 2^-79.7: the 380th halving.
        assert_eq!(steps, 379);
        // Near 0: in f64 while normal, else exactly; a zero factor is interior at once.
        let mut k = new(FloatExp::new(1.0, 400));
        assert!(!step(&mut k, FloatExp::new(1.0, -300), check));
        assert_eq!(k.value(), FloatExp::new(1.0, 102));
        let mut k = new(FloatExp::new(1.0, 3000));
        assert!(!step(&mut k, FloatExp::new(1.0, -2000), check));
        assert_eq!(k.value(), FloatExp::new(1.0, 1002));
        assert!(step(&mut new(FloatExp::ONE), FloatExp::ZERO, check));
        // The largest single step the escape radius allows, and BLA steps beyond the window.
        let mut k = new(FloatExp::new(1.0, 900));
        assert!(!step(&mut k, FloatExp::from(65536.0 * 65536.0), check));
        assert_eq!(k.value(), FloatExp::new(1.0, 934));
        k.bla_step([FloatExp::new(1.0, 2500), FloatExp::ZERO], check);
        assert_eq!(k.value(), FloatExp::new(1.0, 5934));
        k.bla_step([FloatExp::new(1.0, -2965), FloatExp::ZERO], check);
        assert!(!k.interior(check));
        assert_eq!(k.value(), FloatExp::new(1.0, 4));
        k.bla_step([1e-20, 0.0], check);
        assert!(k.interior(check));
        // At the largest escape radius the window is narrower but still holds a step.
        let wide = Check::new(1000, 1e150);
        let mut k = Contraction::new(FloatExp::ONE, wide);
        assert!(!step(&mut k, FloatExp::from(1e300), wide) && k.value().log2() > 996.0);
        // A dropped contraction is the value 2^(2^30), whatever the window.
        for check in [check, wide, Check::new(1, 2.0), Check::new(u32::MAX, 1e150), Check::OFF] {
            assert_eq!(Contraction::dropped(check), Contraction::new(FloatExp::new(1.0, 1 << 30), check));
        }
    }
}
