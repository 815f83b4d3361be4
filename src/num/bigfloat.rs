//! The arbitrary-precision side of the deep engine: decimal text to big floats, big floats
//! to `FloatExp`, and the big-float step z -> z^2 + c.
//!
//! The engine uses malachite-float (pure Rust, no m4 or GMP at build time). It was chosen by
//! measurement among the pure-Rust crates: `cargo run --release --example reference_speed`
//! prints nanoseconds per reference iteration at 1000 and 10000 bits (docs/engine-notes.md). The tests
//! use a different implementation (astro-float) for their ground truth, so a bug here
//! cannot hide in both.

use malachite_base::num::conversion::traits::{FromSciString, SciMantissaAndExponent};
use malachite_float::Float;
use malachite_q::Rational;

use crate::num::{Decimal, FloatExp};

/// A complex big float.
pub type BigComplex = [Float; 2];

/// The decimal, correctly rounded to `prec` bits.
pub fn from_decimal(d: &Decimal, prec: u64) -> Float {
    let text = d.text().trim();
    let text = text.strip_prefix('+').unwrap_or(text);
    // Decimal validated the text, so it parses; zero is the only safe fallback otherwise.
    let r = Rational::from_sci_string(text).unwrap_or_default();
    Float::from_rational_prec(r, prec).0
}

/// x as a `FloatExp` (rounded to 53 bits; zero for zero or non-finite values).
pub fn to_floatexp(x: &Float) -> FloatExp {
    if x.is_zero() || !x.is_finite() {
        return FloatExp::ZERO;
    }
    let (m, e): (f64, i32) = x.sci_mantissa_and_exponent();
    FloatExp::new(if x.is_sign_negative() { -m } else { m }, e)
}

/// z <- z^2 + c at precision `prec`, in place: one new allocation per step (x y) instead of
/// one per operation; the reference orbit spends most of its time here.
pub fn step_assign(z: &mut BigComplex, c: &BigComplex, prec: u64) {
    let [x, y] = z;
    let xy = x.mul_prec_ref_ref(y, prec).0;
    x.square_prec_assign(prec);
    y.square_prec_assign(prec);
    x.sub_prec_assign_ref(y, prec);
    x.add_prec_assign_ref(&c[0], prec);
    // 2xy + cy: doubling is exact (an exponent change).
    *y = xy << 1u32;
    y.add_prec_assign_ref(&c[1], prec);
}

/// Bits of precision for a view whose sample spacing is 10^log10_spacing: enough to place
/// every sample exactly, plus a margin for the orbit's amplification of rounding errors.
pub fn precision_for(log10_spacing: f64) -> u64 {
    let bits = (-log10_spacing * std::f64::consts::LOG2_10).max(0.0).ceil() as u64;
    (bits + 96).max(128)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimal_round_trip_through_floatexp() {
        let d = Decimal::parse("-1.25e-500").unwrap();
        let f = to_floatexp(&from_decimal(&d, 200));
        assert!(f < FloatExp::ZERO);
        let l10 = f.abs().log2() / std::f64::consts::LOG2_10;
        assert!((l10 - (1.25f64.log10() - 500.0)).abs() < 1e-12);
        let x = to_floatexp(&from_decimal(&Decimal::parse("0.1").unwrap(), 200));
        assert_eq!(x.to_f64(), 0.1);
    }

    #[test]
    fn big_step_matches_f64_on_exact_values() {
        let p = 128;
        let mut n = [Float::from(0.5), Float::from(-0.25)];
        let c = [Float::from(-1.0), Float::from(0.125)];
        step_assign(&mut n, &c, p);
        assert_eq!(to_floatexp(&n[0]).to_f64(), 0.25 - 0.0625 - 1.0);
        assert_eq!(to_floatexp(&n[1]).to_f64(), 2.0 * 0.5 * -0.25 + 0.125);
    }
}
