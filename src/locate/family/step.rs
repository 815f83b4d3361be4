//! One step of a formula's map in big floats with its derivative, for Newton's method on
//! any family: f(z) and the linear map Df(z) that carries a tangent vector through it.
//!
//! Forward-mode differentiation through the four steps of `formula::map` (fold, power,
//! fold, negate), each taken in big floats at the orbit's precision: a fold negates the
//! tangent's component where the folded part is negative (its derivative taken as +1 at
//! 0, as the engines take it), the power multiplies the tangent, as a complex number, by
//! p w^(p-1), and the negation negates a component. So Df is a complex multiplication
//! between two sign flips of the components: conformal (a complex number) for the
//! Mandelbrot family, conformal or anti-conformal (a complex number times a reflection)
//! for every family; only the sums of such maps that the derivative in c accumulates are
//! general 2×2 matrices. A product family's (`formula::product`) is such a sum already:
//! α t + β S t, t = e v, with S the fold of u = z^PRE.

use malachite_float::Float;

use crate::formula::map::{FOLD_BOTH, FOLD_IM, FOLD_RE, IM_BY_X, IM_BY_Y, SIGN_IM, SIGN_RE, fold_big};
use crate::formula::{Phase, sum};
use crate::num::FloatExp;
use crate::num::bigcomplex::BigC;

/// The derivative of one step at a point.
#[derive(Debug, Clone)]
pub enum Derivative {
    /// A composition's: v -> flip_out(a flip_in(v)).
    Composition {
        /// p w^(p-1), w the folded point.
        a: BigC,
        /// Components the first fold negates (folded and negative).
        flip_in: [bool; 2],
        /// Components the second fold and the negation negate together.
        flip_out: [bool; 2],
    },
    /// A product's (`formula::product`): v -> α t + β flip(t), t = e v.
    Product {
        /// PRE z^(PRE-1), the derivative of u = z^PRE.
        e: BigC,
        /// A u^(A-1) Q.
        alpha: BigC,
        /// P B g^(B-1).
        beta: BigC,
        /// The parts of u that are negative (the fold of u negates them).
        flip: [bool; 2],
    },
}

/// `x`, negated where `flip`.
fn signed(x: &Float, flip: bool) -> Float {
    if flip { -x.clone() } else { x.clone() }
}

/// `v` with the components `flip` names negated.
fn flipped(v: &BigC, flip: [bool; 2]) -> BigC {
    BigC { re: signed(&v.re, flip[0]), im: signed(&v.im, flip[1]), bits: v.bits }
}

impl Derivative {
    /// Df v.
    pub fn apply(&self, v: &BigC) -> BigC {
        match self {
            Derivative::Composition { a, flip_in, flip_out } => flipped(&a.mul(&flipped(v, *flip_in)), *flip_out),
            Derivative::Product { e, alpha, beta, flip } => {
                let t = e.mul(v);
                alpha.mul(&t).add(&beta.mul(&flipped(&t, *flip)))
            }
        }
    }

    /// Df as a 2×2 matrix in FloatExp, rows first (its columns are Df 1 and Df i).
    pub fn matrix(&self) -> [[FloatExp; 2]; 2] {
        let bits = match self {
            Derivative::Composition { a, .. } => a.bits,
            Derivative::Product { alpha, .. } => alpha.bits,
        };
        let one = BigC::from_f64(1.0, 0.0, bits);
        let i = BigC::from_f64(0.0, 1.0, bits);
        let ([a, c], [b, d]) = (self.apply(&one).to_fe(), self.apply(&i).to_fe());
        [[a, b], [c, d]]
    }

    /// Whether Df is a complex number (no reflection between the flips; a product's never
    /// is taken to be).
    pub fn conformal(&self) -> bool {
        match self {
            Derivative::Composition { flip_in, flip_out, .. } => flip_in[0] == flip_in[1] && flip_out[0] == flip_out[1],
            Derivative::Product { .. } => false,
        }
    }

    /// a, the complex factor between a composition's flips; None for a product, whose
    /// derivative is no one complex number.
    pub fn factor(&self) -> Option<&BigC> {
        match self {
            Derivative::Composition { a, .. } => Some(a),
            Derivative::Product { .. } => None,
        }
    }
}

/// n w^(n-1) in big floats.
fn slope_big(w: &BigC, n: u32) -> BigC {
    let k = BigC::from_f64(n as f64, 0.0, w.bits);
    if n == 1 { k } else { w.pow(n - 1).mul(&k) }
}

/// A product family's step and derivative, by the operations of `Product::apply_big`.
fn product_step((pre, a, b): (u32, u32, u32), z: &BigC) -> (BigC, Derivative) {
    let u = z.pow(pre);
    let g = fold_big(FOLD_BOTH, u.clone());
    let (p, q) = (u.pow(a), g.pow(b));
    let f = p.mul(&q);
    let flip = [u.re < 0u32, u.im < 0u32];
    let d = Derivative::Product {
        e: slope_big(z, pre),
        alpha: slope_big(&u, a).mul(&q),
        beta: p.mul(&slope_big(&g, b)),
        flip,
    };
    (f, d)
}

/// f(z) for `phase` (c not added) and its derivative at z, in big floats at `z.bits`. f(z)
/// is computed by the same operations as `Map::apply_big`, so the two agree to the bit.
pub fn step(phase: Phase, z: &BigC) -> (BigC, Derivative) {
    if let Some(factors) = phase.kind.factors() {
        return product_step(factors, z);
    }
    if let Some(s) = phase.kind.sum() {
        // A sum a W² ± W^Q is complex-analytic in W: its derivative is one complex number
        // after the fold's flips.
        let f = crate::with_map!(phase, m: M => m.apply_big(z), unreachable!("a sum has compiled code"));
        let negative = |x: &Float| *x < 0u32;
        let flip_in = [s.fold_in & FOLD_RE != 0 && negative(&z.re), s.fold_in & FOLD_IM != 0 && negative(&z.im)];
        let a = sum::derivative_big(s.q, s.neg, phase.a.get(), &flipped(z, flip_in));
        return (f, Derivative::Composition { a, flip_in, flip_out: [false; 2] });
    }
    let (fold_in, p, fold_out, sign) = phase.kind.shape(phase.power);
    let negative = |x: &Float| *x < 0u32;
    let flip_in = [fold_in & FOLD_RE != 0 && negative(&z.re), fold_in & FOLD_IM != 0 && negative(&z.im)];
    let w = flipped(z, flip_in);
    // u = w^p as apply_big takes it (a square, then products), and w^(p-1) on the way.
    let mut below = w.clone();
    let mut u = w.square();
    for _ in 2..p {
        below = u.clone();
        u = u.mul(&w);
    }
    let a = below.mul(&BigC::from_f64(p as f64, 0.0, z.bits));
    // A signed fold of the imaginary part flips it again where x, y or xy of z is negative;
    // where the part read is 0, by the sign of Im u's slope across it (`Map::jacobian`'s rule).
    let (by_x, by_y) = (fold_out & IM_BY_X != 0, fold_out & IM_BY_Y != 0);
    let mut im =
        (fold_out & FOLD_IM != 0 && negative(&u.im)) != ((by_x && negative(&z.re)) != (by_y && negative(&z.im)));
    if by_x && z.re == 0u32 {
        im = (negative(&a.im) != flip_in[0]) != (by_y && negative(&z.im));
    }
    if by_y && z.im == 0u32 {
        im = (negative(&a.re) != flip_in[1]) != (by_x && negative(&z.re));
    }
    let flip_out = [(fold_out & FOLD_RE != 0 && negative(&u.re)) != (sign == SIGN_RE), im != (sign == SIGN_IM)];
    (flipped(&u, flip_out), Derivative::Composition { a, flip_in, flip_out })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::kind::KINDS;

    /// The value is the engines' big-float map to the bit, and the derivative is the
    /// engines' f64 Jacobian (`Map::jacobian`), for every family at every power.
    #[test]
    fn the_step_is_the_engines_map_and_its_jacobian() {
        for k in KINDS {
            for p in k.min_power..=k.max_power {
                let phase = Phase::new(k.kind, p);
                for z in [[0.3, -0.7], [-1.1, 0.2], [-0.4, -0.35], [0.05, 0.9]] {
                    let zb = BigC::from_f64(z[0], z[1], 160);
                    let (f, d) = step(phase, &zb);
                    let want = crate::with_map!(phase, m: M => m.apply_big(&zb), unreachable!());
                    assert_eq!(f, want, "{phase} {z:?}");
                    let j = crate::with_map!(phase, m: M => m.jacobian(z), unreachable!());
                    let m = d.matrix();
                    for (r, row) in m.iter().enumerate() {
                        for (c, v) in row.iter().enumerate() {
                            let (got, want) = (v.to_f64(), j[r][c]);
                            assert!((got - want).abs() <= 1e-12 * (1.0 + want.abs()), "{phase} {z:?} [{r}][{c}]");
                        }
                    }
                    if crate::formula::Formula::single(phase).is_conformal() {
                        assert!(d.conformal(), "{phase}");
                    }
                }
            }
        }
    }
}
