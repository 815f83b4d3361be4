//! Complex numbers in big floats at a fixed precision, for Newton's method and period
//! detection: the few operations those need, each rounded once to the working precision.

use malachite_float::Float;
use malachite_q::Rational;

use crate::num::bigfloat;
use crate::num::{Decimal, FloatExp};

/// A complex number of two malachite floats, with the precision its operations round to.
#[derive(Debug, Clone, PartialEq)]
pub struct BigC {
    /// Real part.
    pub re: Float,
    /// Imaginary part.
    pub im: Float,
    /// Bits every operation rounds to.
    pub bits: u64,
}

impl BigC {
    /// Zero at `bits`.
    pub fn zero(bits: u64) -> BigC {
        BigC { re: Float::from(0u32), im: Float::from(0u32), bits }
    }

    /// From decimal parts, correctly rounded to `bits`.
    pub fn from_decimals(re: &Decimal, im: &Decimal, bits: u64) -> BigC {
        BigC { re: bigfloat::from_decimal(re, bits), im: bigfloat::from_decimal(im, bits), bits }
    }

    /// From f64 parts (exact).
    pub fn from_f64(re: f64, im: f64, bits: u64) -> BigC {
        let f = |x: f64| Float::from_primitive_float_prec(x, bits.max(64)).0;
        BigC { re: f(re), im: f(im), bits }
    }

    /// The same value at another precision (rounded when narrower).
    pub fn with_bits(&self, bits: u64) -> BigC {
        let f = |x: &Float| Float::from_float_prec_ref(x, bits).0;
        BigC { re: f(&self.re), im: f(&self.im), bits }
    }

    /// self + o.
    pub fn add(&self, o: &BigC) -> BigC {
        let p = self.bits;
        BigC { re: self.re.add_prec_ref_ref(&o.re, p).0, im: self.im.add_prec_ref_ref(&o.im, p).0, bits: p }
    }

    /// self - o.
    pub fn sub(&self, o: &BigC) -> BigC {
        let p = self.bits;
        BigC { re: self.re.sub_prec_ref_ref(&o.re, p).0, im: self.im.sub_prec_ref_ref(&o.im, p).0, bits: p }
    }

    /// One step of c's orbit with its derivative in c, from (z_n, z_n') to
    /// (z_(n+1), z_(n+1)') = (z_n^2 + c, 2 z_n z_n' + 1), with `self` as c and `one` as 1 at
    /// its precision (made once by the caller: every orbit loop of Newton's method and its
    /// checks takes this step).
    pub fn orbit_step(&self, (z, dz): (&BigC, &BigC), one: &BigC) -> (BigC, BigC) {
        (z.square().add(self), z.mul(dz).ldexp(1).add(one))
    }

    /// self * o.
    pub fn mul(&self, o: &BigC) -> BigC {
        let p = self.bits;
        let m = |a: &Float, b: &Float| a.mul_prec_ref_ref(b, p).0;
        let re = m(&self.re, &o.re).sub_prec(m(&self.im, &o.im), p).0;
        let im = m(&self.re, &o.im).add_prec(m(&self.im, &o.re), p).0;
        BigC { re, im, bits: p }
    }

    /// self^2.
    pub fn square(&self) -> BigC {
        let p = self.bits;
        let re = self.re.square_prec_ref(p).0.sub_prec(self.im.square_prec_ref(p).0, p).0;
        let im = self.re.mul_prec_ref_ref(&self.im, p).0 << 1u32;
        BigC { re, im, bits: p }
    }

    /// self^n for n >= 1 as every big-float map takes it: self itself for n = 1, else a
    /// square and then products by self (so that two users of a power agree to the bit).
    pub fn pow(&self, n: u32) -> BigC {
        debug_assert!(n >= 1, "BigC::pow takes n >= 1, not {n}");
        if n <= 1 {
            return self.clone();
        }
        let mut u = self.square();
        for _ in 2..n {
            u = u.mul(self);
        }
        u
    }

    /// self with the real part, the imaginary part or both replaced by their magnitudes: the
    /// folds of the Burning Ship's relatives. (A negative zero stays as it is: only a part
    /// below zero changes.)
    pub fn fold_parts(self, re: bool, im: bool) -> BigC {
        let abs = |f: Float, on: bool| if on && f < 0u32 { -f } else { f };
        BigC { re: abs(self.re, re), im: abs(self.im, im), bits: self.bits }
    }

    /// The principal square root (non-negative real part; the imaginary part takes the sign
    /// of self's).
    pub fn sqrt(&self) -> BigC {
        let p = self.bits;
        let m = self.re.square_prec_ref(p).0.add_prec(self.im.square_prec_ref(p).0, p).0.sqrt_prec(p).0;
        let half = |x: Float| (x >> 1u32).sqrt_prec(p).0;
        let re = half(m.add_prec_ref_ref(&self.re, p).0);
        let im = half(m.sub_prec_ref_ref(&self.re, p).0);
        let im = if self.im.is_sign_negative() { -im } else { im };
        BigC { re, im, bits: p }
    }

    /// -self.
    pub fn neg(&self) -> BigC {
        BigC { re: -self.re.clone(), im: -self.im.clone(), bits: self.bits }
    }

    /// self * 2^k (exact).
    pub fn ldexp(&self, k: i32) -> BigC {
        BigC { re: self.re.clone() << k, im: self.im.clone() << k, bits: self.bits }
    }

    /// self / o (zero when o is zero).
    pub fn div(&self, o: &BigC) -> BigC {
        let p = self.bits;
        let d = o.re.square_prec_ref(p).0.add_prec(o.im.square_prec_ref(p).0, p).0;
        if d.is_zero() {
            return BigC::zero(p);
        }
        let m = |a: &Float, b: &Float| a.mul_prec_ref_ref(b, p).0;
        let re = m(&self.re, &o.re).add_prec(m(&self.im, &o.im), p).0.div_prec(d.clone(), p).0;
        let im = m(&self.im, &o.re).sub_prec(m(&self.re, &o.im), p).0.div_prec(d, p).0;
        BigC { re, im, bits: p }
    }

    /// The value as FloatExp parts (53 bits each).
    pub fn to_fe(&self) -> [FloatExp; 2] {
        [bigfloat::to_floatexp(&self.re), bigfloat::to_floatexp(&self.im)]
    }

    /// |self| as FloatExp (to about 53 bits).
    pub fn abs(&self) -> FloatExp {
        let [a, b] = self.to_fe();
        (a * a + b * b).sqrt()
    }

    /// The parts as exact rationals (zero for non-finite parts).
    pub fn to_rationals(&self) -> [Rational; 2] {
        let r = |x: &Float| Rational::try_from(x).unwrap_or_default();
        [r(&self.re), r(&self.im)]
    }

    /// The parts as decimal text with enough digits to hold every bit of the precision,
    /// plus `extra` digits.
    pub fn to_decimals(&self, extra: u64) -> [Decimal; 2] {
        let digits = (self.bits as f64 * std::f64::consts::LOG10_2).ceil() as u64 + extra;
        let [re, im] = self.to_rationals();
        [Decimal::from_rational(&re, digits), Decimal::from_rational(&im, digits)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arithmetic_is_complex_arithmetic() {
        let a = BigC::from_f64(1.5, -2.0, 128);
        let b = BigC::from_f64(0.25, 0.5, 128);
        let f = |c: &BigC| c.to_fe().map(|v| v.to_f64());
        assert_eq!(f(&a.mul(&b)), [1.5 * 0.25 + 2.0 * 0.5, 1.5 * 0.5 - 2.0 * 0.25]);
        assert_eq!(f(&a.square()), [1.5 * 1.5 - 4.0, 2.0 * 1.5 * -2.0]);
        assert_eq!(f(&a.mul(&b).div(&b)), f(&a));
        assert_eq!(f(&a.ldexp(3)), [12.0, -16.0]);
        assert_eq!(a.abs().to_f64(), 2.5);
        let r = BigC::from_f64(-3.0, -4.0, 128).sqrt();
        assert_eq!(f(&r), [1.0, -2.0]);
        let [re, im] = BigC::from_f64(-0.125, 3.0, 64).to_decimals(0);
        assert_eq!((re.text(), im.text()), ("-0.125", "3"));
    }
}
