//! The derivative a sample carries for distance estimates: dz/dc times the sample
//! spacing, as an f64 mantissa pair with its own binary exponent ([`Der`]), renormalised
//! when the mantissa leaves 2^+-500. The derivative overflows f64 long before the deltas
//! do (it grows like 4^n where |z| lingers near 2), and a FloatExp per product would double
//! the cost of every step; with its own exponent, a step is f64 arithmetic and one range
//! test, and only a result out of range is looked at again (renormalised, or redone in
//! FloatExp where the orbit passed near 0 and a term underflowed).

use crate::num::real::{cadd, cconv, cmul};
use crate::num::{FloatExp, Real};

/// The derivative's mantissa is renormalised when its largest part leaves [2^-500, 2^500].
pub(in crate::orbit) const DER_HI: f64 = f64::from_bits((1023 + 500) << 52);
pub(in crate::orbit) const DER_LO: f64 = f64::from_bits((1023 - 500) << 52);
/// BLA multipliers below this update the derivative in f64 (|A| |mant| < 2^900).
pub(in crate::orbit) const DER_SAFE: f64 = f64::from_bits((1023 + 400) << 52);
/// Where an orbit passes near 0 (|z| below this, or a BLA step whose |A| is below twice
/// this), the f64 update of the derivative can be wrong: 2 z mant may underflow (z itself
/// is 0 in f64 below 2^-1074), and so may the added term, spacing / 2^exp, which is then
/// all that is left of dz -> 2 z dz + 1. bench-e1086 lost its derivative this way on every
/// pixel (distance estimates at the 1e30 cap). Such a wrong result is always outside the
/// renormalisation range, so only there is the step redone in FloatExp.
pub(in crate::orbit) const DER_TINY_Z: f64 = f64::from_bits((1023 - 101) << 52);
/// DER_TINY_Z squared: the vector lanes test |z|^2 (which their escape test computed) and
/// hand such steps to the scalar loop.
pub(in crate::orbit) const DER_TINY_Z2: f64 = f64::from_bits((1023 - 202) << 52);

/// The scaled derivative mant * 2^exp (= dz/dc times the spacing), and what a step adds.
#[derive(Debug, Clone, Copy)]
pub(in crate::orbit) struct Der {
    pub(in crate::orbit) mant: [f64; 2],
    pub(in crate::orbit) exp: i32,
    pub(in crate::orbit) add: f64,
}

impl Der {
    /// The derivative of a sample whose loop carries none.
    pub(in crate::orbit) const UNUSED: Der = Der { mant: [0.0; 2], exp: 0, add: 0.0 };

    pub(in crate::orbit) fn to_fe(self) -> [FloatExp; 2] {
        [FloatExp::new(self.mant[0], self.exp), FloatExp::new(self.mant[1], self.exp)]
    }

    pub(in crate::orbit) fn from_fe(v: [FloatExp; 2], add_fe: FloatExp) -> Der {
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
    pub(in crate::orbit) fn renormalise(&mut self, add_fe: FloatExp) {
        let big = self.mant[0].abs().max(self.mant[1].abs());
        if !(DER_LO..=DER_HI).contains(&big) && big != 0.0 {
            *self = Der::from_fe(self.to_fe(), add_fe);
        }
    }

    pub(in crate::orbit) fn to_f64(self) -> [f64; 2] {
        let v = self.to_fe();
        [v[0].to_f64(), v[1].to_f64()]
    }

    /// self *= f, with nothing added (the derivative of a turn in Newton's test, up to
    /// Λ ~ 1/sqrt(minibrot size) mid-turn): in f64 while |f| is within 2^+-400 (its product
    /// with a mantissa within 2^+-500 neither overflows nor underflows), else in FloatExp.
    #[inline]
    pub(in crate::orbit) fn mul(&mut self, f: [f64; 2]) {
        let big = f[0].abs().max(f[1].abs());
        if big < DER_SAFE && big > 1.0 / DER_SAFE {
            self.mant = cmul(self.mant, f);
            self.renormalise(FloatExp::ZERO);
        } else {
            *self = Der::from_fe(cmul(self.to_fe(), cconv(f)), FloatExp::ZERO);
        }
    }

    /// True when the larger part of the mantissa is outside [DER_LO, DER_HI] (or 0).
    #[inline(always)]
    pub(in crate::orbit) fn out_of_range(&self) -> bool {
        !(DER_LO..=DER_HI).contains(&self.mant[0].abs().max(self.mant[1].abs()))
    }

    /// One perturbation step, der <- 2 z der + what a step adds; `z` is the full value
    /// rounded to f64, `full` the same unrounded. Done in f64, with the renormalisation's
    /// range test as the only test: a result can be wrong only where a term underflowed,
    /// and it is then out of range (the other term is too small to hold it in).
    #[inline(always)]
    pub(in crate::orbit) fn step<D: Real>(&mut self, z: [f64; 2], full: [D; 2], add_fe: FloatExp) {
        let prev = *self;
        let [x, y] = z;
        let [a, b] = self.mant;
        self.mant = [2.0 * (x * a - y * b) + self.add, 2.0 * (x * b + y * a)];
        if self.out_of_range() {
            self.step_slow(prev, z, full, add_fe);
        }
    }

    /// [`Der::step`] once the f64 result is out of range: from a tiny z the step is redone in
    /// FloatExp from `prev`, else the result is renormalised.
    #[cold]
    #[inline(never)]
    pub(in crate::orbit) fn step_slow<D: Real>(&mut self, prev: Der, z: [f64; 2], full: [D; 2], add_fe: FloatExp) {
        if z[0] * z[0] + z[1] * z[1] < DER_TINY_Z2 {
            let f: [FloatExp; 2] = cconv(full);
            let d = cmul([f[0].ldexp(1), f[1].ldexp(1)], prev.to_fe());
            *self = Der::from_fe([d[0] + add_fe, d[1]], add_fe);
        } else {
            self.renormalise(add_fe);
        }
    }

    /// A BLA step's update, der <- m der + n (what a step adds): in f64 when the multipliers
    /// are moderate (the common case), else in FloatExp (they may be huge at depth, or m
    /// tiny where the step passes near 0; as in [`Der::step`], the latter shows as a result
    /// out of range).
    #[inline(always)]
    pub(in crate::orbit) fn jacobian(
        &mut self,
        m: [f64; 2],
        n: [f64; 2],
        fe: impl FnOnce() -> ([FloatExp; 2], [FloatExp; 2]),
        add_fe: FloatExp,
    ) {
        let big = m[0].abs().max(m[1].abs()).max(n[0].abs()).max(n[1].abs());
        if big < DER_SAFE {
            // |m mant| < 2^900: no overflow; the added term is spacing / 2^exp (0 when that
            // underflows, where it is negligible unless m is tiny).
            let prev = *self;
            let d = self.mant;
            let md = [m[0] * d[0] - m[1] * d[1], m[0] * d[1] + m[1] * d[0]];
            self.mant = [md[0] + n[0] * self.add, md[1] + n[1] * self.add];
            if self.out_of_range() {
                if m[0].abs().max(m[1].abs()) < 2.0 * DER_TINY_Z {
                    let (m, n) = fe();
                    *self = prev;
                    self.jacobian_fe(m, n, add_fe);
                } else {
                    self.renormalise(add_fe);
                }
            }
        } else {
            let (m, n) = fe();
            self.jacobian_fe(m, n, add_fe);
        }
    }

    #[cold]
    #[inline(never)]
    pub(in crate::orbit) fn jacobian_fe(&mut self, m: [FloatExp; 2], n: [FloatExp; 2], add_fe: FloatExp) {
        let d = cadd(cmul(m, self.to_fe()), [n[0] * add_fe, n[1] * add_fe]);
        *self = Der::from_fe(d, add_fe);
    }
}
