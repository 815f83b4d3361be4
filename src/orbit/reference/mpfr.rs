//! The reference orbit's step in MPFR (through rug), behind the `mpfr` cargo feature: the
//! C library most deep-zoom engines iterate their references with, for comparison
//! (`cargo bench --bench reference --features mpfr`) and as the big-float backend where
//! fixed point does not apply. The default build never uses it: it needs m4 and a C
//! compiler to build GMP and MPFR, and their LGPL licence.

use malachite_base::num::conversion::traits::IntegerMantissaAndExponent;
use malachite_float::Float;
use malachite_nz::natural::Natural;
use rug::Assign;

use crate::num::FloatExp;

/// An orbit of z -> z^2 + c in MPFR floats at a fixed precision.
#[derive(Debug, Clone)]
pub struct MpfrOrbit {
    x: rug::Float,
    y: rug::Float,
    cx: rug::Float,
    cy: rug::Float,
    xx: rug::Float,
    yy: rug::Float,
}

/// A malachite float as an MPFR float of `bits`: its integer mantissa's limbs and its
/// exponent, exactly (then rounded once to `bits`).
fn to_mpfr(v: &Float, bits: u32) -> rug::Float {
    if v.is_zero() || !v.is_finite() {
        return rug::Float::new(bits);
    }
    let (m, e): (Natural, i64) = v.integer_mantissa_and_exponent();
    let int = rug::Integer::from_digits(&m.to_limbs_asc(), rug::integer::Order::Lsf);
    let f = rug::Float::with_val(bits, int) << e.clamp(i32::MIN as i64, i32::MAX as i64) as i32;
    if v.is_sign_negative() { -f } else { f }
}

/// An MPFR float as FloatExp (53 bits, round to nearest).
fn to_floatexp(v: &rug::Float) -> FloatExp {
    if v.is_zero() || !v.is_finite() {
        return FloatExp::ZERO;
    }
    let exp = v.get_exp().unwrap_or(0);
    let mant = rug::Float::with_val(53, v >> exp).to_f64();
    FloatExp::new(mant, exp)
}

impl MpfrOrbit {
    /// The orbit from `start` with parameter `c`, at `bits` of precision.
    pub fn new(start: &[Float; 2], c: &[Float; 2], bits: u64) -> MpfrOrbit {
        let b = bits.min(u32::MAX as u64) as u32;
        MpfrOrbit {
            x: to_mpfr(&start[0], b),
            y: to_mpfr(&start[1], b),
            cx: to_mpfr(&c[0], b),
            cy: to_mpfr(&c[1], b),
            xx: rug::Float::new(b),
            yy: rug::Float::new(b),
        }
    }

    /// The current z.
    pub fn get(&self) -> [FloatExp; 2] {
        [to_floatexp(&self.x), to_floatexp(&self.y)]
    }

    /// One step, z <- z^2 + c, without allocating.
    pub fn step(&mut self) {
        self.xx.assign(self.x.square_ref());
        self.yy.assign(self.y.square_ref());
        // y <- 2 x y + cy
        self.y *= &self.x;
        self.y <<= 1u32;
        self.y += &self.cy;
        // x <- x^2 - y^2 + cx
        self.x.assign(&self.xx - &self.yy);
        self.x += &self.cx;
    }
}
