//! The derivative a sample carries for distance estimates: the real 2×2 Jacobian J of z_n
//! with respect to the sample's parameter (c for the Mandelbrot form, z_0 for Julia sets),
//! times the sample spacing, as an f64 matrix with its own binary exponent ([`Jac`]).
//!
//! A map with folds is not complex-analytic, so its derivative is a real matrix, not a
//! complex number: J_(k+1) = Jf(z_k) J_k + I (Mandelbrot form, J_1 = I) or Jf(z_k) J_k
//! (Julia form, J_0 = I), and a BLA step of the loop moves it as it moves the delta,
//! J -> A J + B. Like the quadratic engine's complex derivative (`perturb/der.rs`) it
//! overflows f64 long before deltas leave their range, so its mantissa is renormalised when
//! it leaves 2^±500, and a step whose f64 result is out of range (an overflow, or an
//! underflow where the orbit passed near 0 and only the added term is left) is redone in
//! FloatExp from the previous value.

use crate::formula::map::{Mat2, gradient_dz, mat_mul};
use crate::num::FloatExp;
use crate::num::real::Real;

/// The mantissa is renormalised when its largest entry leaves [LO, HI].
const HI: f64 = f64::from_bits((1023 + 500) << 52);
const LO: f64 = f64::from_bits((1023 - 500) << 52);

/// A matrix in FloatExp.
pub(super) type MatFe = [[FloatExp; 2]; 2];

/// J × spacing = `m` × 2^`exp`, and what a step adds (the spacing, for the Mandelbrot form)
/// at that exponent.
#[derive(Debug, Clone, Copy)]
pub(super) struct Jac {
    m: Mat2,
    exp: i32,
    add: f64,
    add_fe: FloatExp,
}

/// The FloatExp matrix of an f64 or FloatExp one.
#[inline]
pub(super) fn to_fe<D: Real>(a: &[[D; 2]; 2]) -> MatFe {
    a.map(|row| row.map(|x| x.to_fe()))
}

/// a b in FloatExp.
fn mul_fe(a: &MatFe, b: &MatFe) -> MatFe {
    let e = |i: usize, j: usize| a[i][0] * b[0][j] + a[i][1] * b[1][j];
    [[e(0, 0), e(0, 1)], [e(1, 0), e(1, 1)]]
}

impl Jac {
    /// The Jacobian at a sample's start, I × spacing; `mandelbrot`: each step adds I.
    pub(super) fn new(spacing: FloatExp, mandelbrot: bool) -> Jac {
        let add_fe = if mandelbrot { spacing } else { FloatExp::ZERO };
        let mut j = Jac { m: [[0.0; 2]; 2], exp: 0, add: 0.0, add_fe };
        j.set_fe([[spacing, FloatExp::ZERO], [FloatExp::ZERO, spacing]]);
        j
    }

    /// The f64 part the vector lanes step: the mantissa matrix and what a step adds to its
    /// diagonal (at the matrix's exponent).
    pub(super) fn parts(&self) -> (Mat2, f64) {
        (self.m, self.add)
    }

    /// Sets the mantissa matrix after steps the lanes took, each [`Jac::step`]'s f64 case
    /// (the exponent is unchanged by those).
    pub(super) fn set_matrix(&mut self, m: Mat2) {
        self.m = m;
    }

    /// The range of the largest entry of a step's f64 result that [`Jac::step`] keeps.
    pub(super) const RANGE: (f64, f64) = (LO, HI);

    /// The value in FloatExp.
    fn to_fe(self) -> MatFe {
        self.m.map(|row| row.map(|x| FloatExp::new(x, self.exp)))
    }

    /// Sets the value, renormalised.
    fn set_fe(&mut self, v: MatFe) {
        let exp = v.iter().flatten().filter(|x| !x.is_zero()).map(|x| x.exponent()).max().unwrap_or(0);
        self.m = v.map(|row| row.map(|x| x.ldexp(-exp).to_f64()));
        self.exp = exp;
        self.add = self.add_fe.ldexp(-exp).to_f64();
    }

    /// One step, J -> Jf J (+ I): in f64, redone in FloatExp when the result is out of range.
    #[inline(always)]
    pub(super) fn step(&mut self, jf: Mat2) {
        let mut m = mat_mul(jf, self.m);
        m[0][0] += self.add;
        m[1][1] += self.add;
        let big = m[0][0].abs().max(m[0][1].abs()).max(m[1][0].abs()).max(m[1][1].abs());
        if (LO..=HI).contains(&big) {
            self.m = m;
        } else {
            self.step_slow(jf);
        }
    }

    #[cold]
    #[inline(never)]
    fn step_slow(&mut self, jf: Mat2) {
        self.bla(&jf, &[[1.0, 0.0], [0.0, 1.0]]);
    }

    /// A BLA step's update, J -> A J + B (times what a step adds), in FloatExp (BLA steps
    /// are few).
    pub(super) fn bla<D: Real>(&mut self, a: &[[D; 2]; 2], b: &[[D; 2]; 2]) {
        let mut v = mul_fe(&to_fe(a), &self.to_fe());
        if !self.add_fe.is_zero() {
            let b = to_fe(b);
            for i in 0..2 {
                for j in 0..2 {
                    v[i][j] = v[i][j] + b[i][j] * self.add_fe;
                }
            }
        }
        self.set_fe(v);
    }

    /// The derivative an escaped sample reports at its z: [`gradient_dz`] of J × spacing
    /// (infinite where it leaves f64's range).
    pub(super) fn output(&self, z: [f64; 2]) -> [f64; 2] {
        let g = gradient_dz(z, self.m);
        [FloatExp::new(g[0], self.exp).to_f64(), FloatExp::new(g[1], self.exp).to_f64()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_keep_their_range_and_their_added_term() {
        let spacing = FloatExp::new(1.0, -3000);
        let mut j = Jac::new(spacing, true);
        // Growth by 2^40 per step for 100 steps: far past f64 without the exponent.
        for _ in 0..100 {
            j.step([[2f64.powi(40), 0.0], [0.0, 2f64.powi(40)]]);
        }
        let v = j.to_fe();
        assert!((v[0][0].log2() - (4000.0 - 3000.0)).abs() < 1e-9, "{v:?}");
        // A step from z = 0 leaves only the added term, I × spacing.
        j.step([[0.0; 2]; 2]);
        let v = j.to_fe();
        assert_eq!(v[0][0], spacing);
        assert!(v[0][1].is_zero() && v[1][0].is_zero());
    }
}
