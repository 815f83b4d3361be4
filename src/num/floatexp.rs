//! `FloatExp`: an f64 mantissa with a wide binary exponent, for numbers below 1e-308.
//!
//! Deep views put pixel offsets (and the first perturbation deltas) far below the smallest
//! f64. `FloatExp` keeps a normalised mantissa m with 1 <= |m| < 2 (or m = 0) and an i32
//! exponent e, value m * 2^e: 53 bits of precision and a range of 2^(+-2^31). Products
//! multiply mantissas and add exponents; sums align the smaller operand by a power of two
//! (exact) and renormalise. Every operation is correctly rounded in the mantissa, so where
//! f64 could represent the operands and the result, `FloatExp` gives the same value as f64.
//!
//! Normalisation reads and rewrites the f64 exponent bits directly: it is on the hot path of
//! deep iterations, and `frexp`-style library calls are several times slower.

use std::cmp::Ordering;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Exponent used for zero: far below any real value, so that comparisons by exponent work.
const ZERO_EXP: i32 = i32::MIN / 4;
/// Sums whose exponents differ by more than this keep the larger operand unchanged.
const ALIGN_LIMIT: i32 = 64;

/// m * 2^e with 1 <= |m| < 2, or zero.
#[derive(Debug, Clone, Copy)]
pub struct FloatExp {
    m: f64,
    e: i32,
}

/// 2^e as an f64 for -1022 <= e <= 1023.
#[inline(always)]
fn exp2i(e: i32) -> f64 {
    debug_assert!((-1022..=1023).contains(&e));
    f64::from_bits(((e + 1023) as u64) << 52)
}

impl FloatExp {
    /// Zero.
    pub const ZERO: FloatExp = FloatExp { m: 0.0, e: ZERO_EXP };
    /// One.
    pub const ONE: FloatExp = FloatExp { m: 1.0, e: 0 };

    /// m * 2^e for any finite m.
    #[inline]
    pub fn new(m: f64, e: i32) -> Self {
        if m == 0.0 {
            return Self::ZERO;
        }
        if !m.is_finite() {
            return FloatExp { m, e: 0 };
        }
        let field = ((m.to_bits() >> 52) & 0x7ff) as i32;
        if field == 0 {
            return Self::from_subnormal(m, e);
        }
        Self::normalised(m, field, e)
    }

    /// [`FloatExp::new`] for a normal m whose exponent field is `field`.
    #[inline(always)]
    fn normalised(m: f64, field: i32, e: i32) -> Self {
        let mant = f64::from_bits((m.to_bits() & !(0x7ff << 52)) | (1023 << 52));
        FloatExp { m: mant, e: e.saturating_add(field - 1023) }
    }

    /// [`FloatExp::new`] for a subnormal m: scaled into the normal range first. Kept out of
    /// line, and not calling `new` again, so that `new` has no recursion and inlines into
    /// the loops that call it.
    #[cold]
    #[inline(never)]
    fn from_subnormal(m: f64, e: i32) -> Self {
        let m = m * exp2i(64);
        Self::normalised(m, ((m.to_bits() >> 52) & 0x7ff) as i32, e.saturating_sub(64))
    }

    /// The mantissa (1 <= |m| < 2, or 0).
    #[inline]
    pub fn mantissa(self) -> f64 {
        self.m
    }

    /// The binary exponent (meaningless for zero).
    #[inline]
    pub fn exponent(self) -> i32 {
        self.e
    }

    /// True for zero.
    #[inline]
    pub fn is_zero(self) -> bool {
        self.m == 0.0
    }

    /// Nearest f64 (0 below the subnormal range, infinite above f64::MAX).
    #[inline]
    pub fn to_f64(self) -> f64 {
        if self.e >= -1022 {
            if self.e > 1023 { self.m * f64::INFINITY } else { self.m * exp2i(self.e) }
        } else if self.e >= -1022 - 60 {
            // Two steps so that the subnormal result is rounded once.
            self.m * exp2i(self.e + 60) * exp2i(-60)
        } else {
            0.0 * self.m
        }
    }

    /// |self|.
    #[inline]
    pub fn abs(self) -> Self {
        FloatExp { m: self.m.abs(), e: self.e }
    }

    /// self * 2^k.
    #[inline]
    pub fn ldexp(self, k: i32) -> Self {
        if self.m == 0.0 { self } else { FloatExp { m: self.m, e: self.e.saturating_add(k) } }
    }

    /// self * k for an f64 k (cheaper than converting k).
    #[inline]
    pub fn mul_f64(self, k: f64) -> Self {
        FloatExp::new(self.m * k, self.e)
    }

    /// sqrt(self) for self >= 0.
    #[inline]
    pub fn sqrt(self) -> Self {
        if self.m <= 0.0 {
            return FloatExp::ZERO;
        }
        let half = self.e.div_euclid(2);
        let odd = self.e.rem_euclid(2) as f64;
        FloatExp::new((self.m * (1.0 + odd)).sqrt(), half)
    }

    /// The larger of two values.
    #[inline]
    pub fn max(self, o: FloatExp) -> Self {
        if o > self { o } else { self }
    }

    /// The smaller of two values.
    #[inline]
    pub fn min(self, o: FloatExp) -> Self {
        if o < self { o } else { self }
    }

    /// log2|self| (negative infinity for zero).
    pub fn log2(self) -> f64 {
        if self.m == 0.0 { f64::NEG_INFINITY } else { self.e as f64 + self.m.abs().log2() }
    }

    /// 10^x for any finite x, e.g. pixel spacings beyond the f64 range.
    pub fn exp10(x: f64) -> Self {
        let l2 = x * std::f64::consts::LOG2_10;
        let e = l2.floor();
        FloatExp::new((l2 - e).exp2(), e as i32)
    }
}

impl From<f64> for FloatExp {
    #[inline]
    fn from(x: f64) -> Self {
        FloatExp::new(x, 0)
    }
}

impl Mul for FloatExp {
    type Output = FloatExp;
    #[inline]
    fn mul(self, o: FloatExp) -> FloatExp {
        let m = self.m * o.m;
        if m == 0.0 {
            return FloatExp::ZERO;
        }
        // 1 <= |m| < 4: one conditional halving renormalises exactly.
        let big = m.abs() >= 2.0;
        let e = self.e.saturating_add(o.e).saturating_add(big as i32);
        FloatExp { m: if big { m * 0.5 } else { m }, e }
    }
}

impl Add for FloatExp {
    type Output = FloatExp;
    #[inline]
    fn add(self, o: FloatExp) -> FloatExp {
        if self.m == 0.0 {
            return o;
        }
        if o.m == 0.0 {
            return self;
        }
        let d = self.e.saturating_sub(o.e);
        if d >= 0 {
            if d > ALIGN_LIMIT { self } else { FloatExp::new(self.m + o.m * exp2i(-d), self.e) }
        } else if d < -ALIGN_LIMIT {
            o
        } else {
            FloatExp::new(self.m * exp2i(d) + o.m, o.e)
        }
    }
}

impl Div for FloatExp {
    type Output = FloatExp;
    #[inline]
    fn div(self, o: FloatExp) -> FloatExp {
        FloatExp::new(self.m / o.m, self.e.saturating_sub(o.e))
    }
}

impl Neg for FloatExp {
    type Output = FloatExp;
    #[inline]
    fn neg(self) -> FloatExp {
        FloatExp { m: -self.m, e: self.e }
    }
}

impl Sub for FloatExp {
    type Output = FloatExp;
    #[inline]
    fn sub(self, o: FloatExp) -> FloatExp {
        self + (-o)
    }
}

impl PartialEq for FloatExp {
    fn eq(&self, o: &Self) -> bool {
        self.m == o.m && (self.m == 0.0 || self.e == o.e)
    }
}

impl PartialOrd for FloatExp {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        let sa = self.m.partial_cmp(&0.0)?;
        let sb = o.m.partial_cmp(&0.0)?;
        if sa != sb || sa == Ordering::Equal {
            return sa.partial_cmp(&sb);
        }
        // Same sign, both non-zero: compare magnitudes by exponent, then mantissa.
        let mag = self.e.cmp(&o.e).then(self.m.abs().partial_cmp(&o.m.abs())?);
        Some(if sa == Ordering::Less { mag.reverse() } else { mag })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic spread of f64 values over many binades, both signs, and zero.
    fn values() -> Vec<f64> {
        let mut v = vec![0.0, 1.0, -1.0, 1.5, 0.75, 3.0, -2.5e-3, 1e300, -1e-300];
        let mut s = 0x1234_5678_9abc_def0u64;
        for _ in 0..400 {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let m = (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
            let e = ((s >> 3) % 120) as i32 - 60;
            v.push(m * 2f64.powi(e));
        }
        v
    }

    #[test]
    fn arithmetic_matches_f64_where_f64_is_exact() {
        let vs = values();
        for &a in &vs {
            assert_eq!(FloatExp::from(a).to_f64(), a);
            for &b in vs.iter().step_by(7) {
                let (fa, fb) = (FloatExp::from(a), FloatExp::from(b));
                // (Products in the subnormal range round twice in FloatExp: excluded.)
                if (a * b).abs() >= f64::MIN_POSITIVE || a * b == 0.0 {
                    assert_eq!((fa * fb).to_f64(), a * b, "{a} * {b}");
                }
                // Sums agree exactly unless the smaller operand is far below the larger's ulp
                // (there FloatExp drops it, f64 rounds it away: same result) ...
                assert_eq!((fa + fb).to_f64(), a + b, "{a} + {b}");
                assert_eq!((fa - fb).to_f64(), a - b, "{a} - {b}");
                assert_eq!(fa.partial_cmp(&fb), a.partial_cmp(&b), "{a} <> {b}");
            }
        }
    }

    #[test]
    fn range_beyond_f64() {
        let tiny = FloatExp::exp10(-1000.0);
        assert!((tiny.log2() / std::f64::consts::LOG2_10 + 1000.0).abs() < 1e-9);
        assert_eq!(tiny.to_f64(), 0.0);
        let sq = tiny * tiny;
        assert!((sq.log2() / std::f64::consts::LOG2_10 + 2000.0).abs() < 1e-9);
        // (1e-1000 * 3) + 1e-1000 = 4e-1000, exactly as at f64 scale.
        let three = tiny.mul_f64(3.0);
        assert_eq!((three + tiny).mantissa(), (tiny.mul_f64(4.0)).mantissa());
        assert!(three > tiny && -three < tiny && FloatExp::ZERO < tiny && -tiny < FloatExp::ZERO);
        assert_eq!(FloatExp::new(1.0, 5000).to_f64(), f64::INFINITY);
        let nine = FloatExp::exp10(-801.0).mul_f64(9.0);
        let r = nine.sqrt() / FloatExp::exp10(-400.5);
        assert!((r.to_f64() - 3.0).abs() < 1e-12, "{r:?}");
        assert_eq!(FloatExp::from(2.0).sqrt().to_f64(), 2f64.sqrt());
        // Subnormal f64 values convert both ways.
        let sub = 3.0 * f64::MIN_POSITIVE * f64::EPSILON;
        assert_eq!(FloatExp::from(sub).to_f64(), sub);
    }
}
