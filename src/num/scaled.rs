//! `Scaled`: a complex number as an f64 pair with one shared binary exponent.
//!
//! Where a complex quantity runs far outside the f64 range but only its size as a whole
//! matters (the second derivative of a minibrot's return map in Newton's interior test,
//! which bounds how fast the first derivative can move), one exponent for both parts costs
//! one normalisation per operation, where [`FloatExp`] pairs normalise each real product
//! and sum: a complex product is then one f64 complex product and one exponent read,
//! instead of four products, two sums and six normalisations. The price is that the
//! smaller part keeps only the precision of the larger: the error is relative to the whole
//! complex value, which is all such uses need.
//!
//! The larger part of the mantissa pair is kept in [1, 2) (or both parts 0), so products
//! of two values never overflow before they are renormalised.

use std::ops::{Add, Mul};

use super::FloatExp;

/// (m0 + i m1) * 2^e with max(|m0|, |m1|) in [1, 2), or zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scaled {
    m: [f64; 2],
    e: i32,
}

/// Sums whose exponents differ by more than this keep the larger operand unchanged (the
/// smaller is below the larger's last bit, relative to the complex value).
const ALIGN_LIMIT: i32 = 120;

/// 2^k as an f64 for -1022 <= k <= 1023.
#[inline(always)]
fn exp2i(k: i32) -> f64 {
    f64::from_bits(((k + 1023) as u64) << 52)
}

impl Scaled {
    /// Zero.
    pub const ZERO: Scaled = Scaled { m: [0.0; 2], e: 0 };

    /// (m0 + i m1) * 2^e for finite parts; infinite or NaN parts are kept as they are (the
    /// value is then not a number, as a sum or product with them would be).
    #[inline(always)]
    pub fn new(m: [f64; 2], e: i32) -> Scaled {
        let big = m[0].abs().max(m[1].abs());
        if big == 0.0 || !big.is_finite() {
            return Scaled { m, e: if big == 0.0 { 0 } else { e } };
        }
        let field = ((big.to_bits() >> 52) & 0x7ff) as i32;
        if field == 0 {
            return Scaled::from_subnormal(m, e);
        }
        Scaled::normalised(m, field - 1023, e)
    }

    /// m * 2^-k, exponent e + k, for the larger part of m in [2^k, 2^(k+1)).
    #[inline(always)]
    fn normalised(m: [f64; 2], k: i32, e: i32) -> Scaled {
        let s = exp2i(-k);
        Scaled { m: [m[0] * s, m[1] * s], e: e.saturating_add(k) }
    }

    /// [`Scaled::new`] for a subnormal larger part: scaled into the normal range first (out
    /// of line and without recursion, so that `new` inlines).
    #[cold]
    #[inline(never)]
    fn from_subnormal(m: [f64; 2], e: i32) -> Scaled {
        let s = exp2i(64);
        let m = [m[0] * s, m[1] * s];
        let field = ((m[0].abs().max(m[1].abs()).to_bits() >> 52) & 0x7ff) as i32;
        Scaled::normalised(m, field - 1023, e.saturating_sub(64))
    }

    /// An f64 pair.
    #[inline(always)]
    pub fn from_f64(v: [f64; 2]) -> Scaled {
        Scaled::new(v, 0)
    }

    /// True for zero.
    #[inline(always)]
    pub fn is_zero(self) -> bool {
        self.m[0] == 0.0 && self.m[1] == 0.0
    }

    /// The square.
    #[inline(always)]
    pub fn square(self) -> Scaled {
        self * self
    }

    /// self * 2^k.
    #[inline(always)]
    pub fn ldexp(self, k: i32) -> Scaled {
        if self.is_zero() { self } else { Scaled { m: self.m, e: self.e.saturating_add(k) } }
    }

    /// The parts as [`FloatExp`].
    pub fn to_fe(self) -> [FloatExp; 2] {
        [FloatExp::new(self.m[0], self.e), FloatExp::new(self.m[1], self.e)]
    }

    /// A [`FloatExp`] pair, on the larger part's exponent (a part more than
    /// 120 binades below it is below its last bit and becomes 0).
    pub fn from_fe(v: [FloatExp; 2]) -> Scaled {
        let e = match (v[0].is_zero(), v[1].is_zero()) {
            (true, true) => return Scaled::ZERO,
            (false, true) => v[0].exponent(),
            (true, false) => v[1].exponent(),
            (false, false) => v[0].exponent().max(v[1].exponent()),
        };
        let part = |x: FloatExp| {
            let d = x.exponent().saturating_sub(e);
            if x.is_zero() || d < -ALIGN_LIMIT { 0.0 } else { x.mantissa() * exp2i(d) }
        };
        Scaled::new([part(v[0]), part(v[1])], e)
    }

    /// The modulus.
    #[inline(always)]
    pub fn abs(self) -> FloatExp {
        FloatExp::new((self.m[0] * self.m[0] + self.m[1] * self.m[1]).sqrt(), self.e)
    }
}

impl Mul for Scaled {
    type Output = Scaled;

    /// The complex product.
    #[inline(always)]
    fn mul(self, o: Scaled) -> Scaled {
        let (a, b) = (self.m, o.m);
        Scaled::new([a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0]], self.e.saturating_add(o.e))
    }
}

impl Add for Scaled {
    type Output = Scaled;

    /// The sum.
    #[inline(always)]
    fn add(self, o: Scaled) -> Scaled {
        if o.is_zero() {
            return self;
        }
        if self.is_zero() {
            return o;
        }
        let (hi, lo) = if self.e >= o.e { (self, o) } else { (o, self) };
        let d = hi.e.saturating_sub(lo.e);
        if d > ALIGN_LIMIT {
            return hi;
        }
        let s = exp2i(-d);
        Scaled::new([hi.m[0] + lo.m[0] * s, hi.m[1] + lo.m[1] * s], hi.e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative distance of two FloatExp complex values, measured against the larger.
    fn rel(a: [FloatExp; 2], b: [FloatExp; 2]) -> f64 {
        let d = [a[0] - b[0], a[1] - b[1]];
        let n = |v: [FloatExp; 2]| (v[0] * v[0] + v[1] * v[1]).sqrt();
        let big = if n(a) > n(b) { n(a) } else { n(b) };
        if big.is_zero() { 0.0 } else { (n(d) / big).to_f64() }
    }

    fn fe(v: [f64; 2], e: i32) -> [FloatExp; 2] {
        [FloatExp::new(v[0], e), FloatExp::new(v[1], e)]
    }

    fn cmul(a: [FloatExp; 2], b: [FloatExp; 2]) -> [FloatExp; 2] {
        [a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0]]
    }

    /// Products, squares and sums agree with FloatExp arithmetic to a few units of the last
    /// place of the whole value, far outside the f64 range and across parts of very
    /// different sizes; values exactly representable come back exactly.
    #[test]
    fn arithmetic_matches_floatexp_relative_to_the_whole_value() {
        let cases = [
            ([1.5, -0.25], 3000, [-0.75, 3.0], -4000),
            ([1e-30, 7.0], -2_000_000, [3.0, 1e200], 100),
            ([-2.0, 0.0], 0, [0.0, 0.5], 0),
            ([1e-310, 3e-311], -5, [1.0, 1.0], 1_000_000),
        ];
        for (a, ea, b, eb) in cases {
            let (x, y) = (Scaled::new(a, ea), Scaled::new(b, eb));
            let (fx, fy) = (fe(a, ea), fe(b, eb));
            assert!(rel(x.to_fe(), fx) < 1e-15, "{a:?}");
            assert!(rel((x * y).to_fe(), cmul(fx, fy)) < 1e-15, "{a:?} * {b:?}");
            assert!(rel(x.square().to_fe(), cmul(fx, fx)) < 1e-15, "{a:?}^2");
            let sum = [fx[0] + fy[0], fx[1] + fy[1]];
            assert!(rel((x + y).to_fe(), sum) < 1e-15, "{a:?} + {b:?}");
            assert!(rel(x.ldexp(-77).to_fe(), [fx[0].ldexp(-77), fx[1].ldexp(-77)]) == 0.0);
        }
        for (a, e) in [([1.5, -0.25], 3000), ([1e-30, 7.0], -2_000_000), ([-2.0, 0.0], 0), ([0.0, 1e-300], 9)] {
            let f = fe(a, e);
            assert!(rel(Scaled::from_fe(f).to_fe(), f) < 1e-15, "{a:?} from FloatExp");
            let n = (f[0] * f[0] + f[1] * f[1]).sqrt();
            assert!(((Scaled::from_fe(f).abs() - n) / n).to_f64().abs() < 1e-15, "|{a:?}|");
        }
        assert!(Scaled::from_fe([FloatExp::ZERO; 2]).is_zero());
        assert!(Scaled::ZERO.abs().is_zero());
        let v = Scaled::from_f64([3.0, -0.125]) * Scaled::from_f64([0.5, 2.0]);
        assert_eq!(v.to_fe().map(|x| x.to_f64()), [1.75, 5.9375]);
        assert!((Scaled::ZERO + Scaled::ZERO).is_zero());
        assert_eq!(Scaled::ZERO + v, v);
        assert!((Scaled::from_f64([0.0, 0.0]) * v).is_zero());
        // A sum that cancels to (almost) nothing keeps what is left, renormalised.
        let w = Scaled::new([1.0, 0.0], 50) + Scaled::new([-1.0, 1.0], 50);
        assert_eq!(w.to_fe().map(|x| x.ldexp(-50).to_f64()), [0.0, 1.0]);
    }
}
