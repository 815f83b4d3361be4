//! A lower bound on the periods of the minis in a disc of parameters (the ball method), and
//! the periods of the atom domains that hold a point, for every formula (Mandelbrot form).
//!
//! Iterate the disc's centre c exactly and carry a radius r_n that bounds how far any
//! parameter of the disc has moved from it: |z_n(c + d) - z_n(c)| <= r_n for |d| <= r. For
//! z² + c, r_1 = r and r_(n+1) = r_n (2 |z_n| + r_n) + r. A nucleus of period p is exactly a
//! parameter with z_p = 0, so a nucleus of period p inside the disc puts 0 within r_p of
//! z_p: the first n at which the bounded disc around z_n contains 0 is a lower bound on the
//! periods of the nuclei in the parameter disc. Where the disc is small beside the
//! structure in it the bound is nearly tight and n is the period of a nucleus inside or very
//! near it; where the disc is large (shallow views near the set's boundary) the bound can be
//! far below the lowest period there (8 in seahorse valley at radius 0.033, where Newton's
//! method from a 13 x 13 grid of starts over the disc reaches no nucleus in it below period
//! 25), and the search ([`super::search`]) goes on from it. This is the "box period" method
//! of Robert P. Munafo's Mandelbrot encyclopedia, with a disc in place of the box as in
//! Claude Heiland-Allen's notes on finding minibrots.
//!
//! The same bound holds for every family, because each of its four steps is Lipschitz in
//! the Euclidean norm: a fold (|x| for x) moves no point farther from another (||a| - |b|| <=
//! |a - b| in each part), a negation is an isometry, and the power satisfies |(w + e)^p -
//! w^p| <= (|w| + |e|)^p - |w|^p (the binomial expansion and the triangle inequality), with
//! |w| = |z| after a fold. So r_(n+1) = (|z_n| + r_n)^p - |z_n|^p + r, p the power of
//! iteration n's phase, which is z² + c's recurrence at p = 2 (to the bit, as a test checks).
//!
//! This is preferred to an atom-domain test on the Newton step J_n⁻¹ z_n (the first n whose
//! step is shorter than the disc): that test needs J_n to be invertible, and near the fold
//! lines, where the folded families have their richest structure, it is often nearly
//! singular; the ball bound needs no derivative and is rigorous for every family and hybrid.

use crate::formula::{Cycle, Formula, Stepper};
use crate::num::FloatExp;
use crate::num::bigcomplex::BigC;

/// (|z| + r)^p - |z|^p without cancellation, by Horner's rule in r over the binomial
/// expansion: r (C(p,1) |z|^(p-1) + r (C(p,2) |z|^(p-2) + ... + r C(p,p))). At p = 2 that is
/// r (2 |z| + r), z² + c's own recurrence, operation for operation.
fn growth(z: FloatExp, r: FloatExp, p: u32) -> FloatExp {
    let mut t = FloatExp::ONE;
    for k in (1..p).rev() {
        let mut term = FloatExp::from(crate::formula::map::binomial(p, k));
        for _ in 0..p - k {
            term = term * z;
        }
        t = term + t * r;
    }
    r * t
}

/// The first n <= `max_period` at which the disc of radius `radius` about `center`, iterated
/// by `formula`'s maps (z_0 = 0, c the parameter), contains 0; None when none does (or the
/// disc escapes first: then it holds no nucleus of a higher period either).
pub fn ball_period(formula: Formula, center: &BigC, radius: FloatExp, max_period: u32) -> Option<u32> {
    let s = Cycle(formula);
    let mut z = BigC::zero(center.bits);
    let mut r = FloatExp::ZERO;
    for n in 1..=max_period {
        r = growth(z.abs(), r, formula.phase(n - 1).power) + radius;
        z = s.apply_big(n - 1, &z).add(center);
        let size = z.abs();
        if size < r {
            return Some(n);
        }
        if size > FloatExp::from(1e8) && size > r.mul_f64(4.0) {
            return None;
        }
    }
    None
}

/// The iterations after `after` (up to `max_period`; at most `count` of them) at which the
/// orbit of `center` under `formula` comes nearer to 0 than at any earlier one: the periods
/// of the atom domains that hold `center` (Claude Heiland-Allen's notes on atom domains),
/// whose nuclei Newton's method from `center` tends to reach. The orbit is followed until it
/// leaves |z| <= 2 (then it comes near 0 no more).
pub fn atom_periods(formula: Formula, center: &BigC, after: u32, max_period: u32, count: usize) -> Vec<u32> {
    let s = Cycle(formula);
    let mut z = BigC::zero(center.bits);
    let mut least = FloatExp::from(f64::INFINITY);
    let mut out = Vec::new();
    for n in 1..=max_period {
        z = s.apply_big(n - 1, &z).add(center);
        let size = z.abs();
        if size > FloatExp::from(2.0) {
            break;
        }
        if size < least {
            least = size;
            if n > after {
                out.push(n);
                if out.len() == count {
                    break;
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::{Kind, Phase};

    #[test]
    fn finds_the_periods_of_known_components() {
        let at = |re: f64, im: f64, r: f64| {
            ball_period(Formula::default(), &BigC::from_f64(re, im, 128), FloatExp::from(r), 1000)
        };
        // The main cardioid (period 1), the period-2 bulb, the airplane (3) and the rabbit (3).
        assert_eq!(at(0.0, 0.0, 0.1), Some(1));
        assert_eq!(at(-1.0, 0.0, 0.05), Some(2));
        assert_eq!(at(-1.7549, 0.0, 1e-3), Some(3));
        assert_eq!(at(-0.1226, 0.7449, 1e-3), Some(3));
        // Far outside the set: nothing.
        assert_eq!(at(2.0, 2.0, 0.01), None);
    }

    #[test]
    fn atom_periods_of_a_point_in_the_period_doubling_cascade() {
        // On the real axis at -1.4, between the period-8 nucleus (-1.3815) and the
        // Feigenbaum point (-1.4012): the orbit comes nearest to 0 at the doubling periods.
        let z2 = Formula::default();
        let c = BigC::from_f64(-1.4, 0.0, 128);
        assert_eq!(atom_periods(z2, &c, 0, 1000, 5), vec![1, 2, 4, 8, 16]);
        assert_eq!(atom_periods(z2, &c, 8, 1000, 1), vec![16]);
        // An escaping orbit stops: c = 1 leaves |z| <= 2 at its third iteration.
        assert_eq!(atom_periods(z2, &BigC::from_f64(1.0, 0.0, 128), 0, 1000, 10), vec![1]);
    }

    /// At power 2 the growth is z² + c's recurrence r (2 |z| + r), bit for bit.
    #[test]
    fn at_power_2_the_growth_is_the_quadratic_recurrence() {
        for (z, r) in [(0.7, 0.01), (1.3e-30, 2.9e-31), (3.0, 1e-300), (0.0, 0.5)] {
            let (z, r) = (FloatExp::from(z), FloatExp::from(r));
            let want = r * (FloatExp::from(2.0) * z + r);
            let got = growth(z, r, 2);
            assert_eq!((got.mantissa(), got.exponent()), (want.mantissa(), want.exponent()));
        }
    }

    /// The growth term is the exact difference of powers.
    #[test]
    fn growth_is_the_difference_of_powers() {
        for p in 2..=10 {
            let (z, r) = (0.7f64, 0.01f64);
            let want = (z + r).powi(p as i32) - z.powi(p as i32);
            let got = growth(FloatExp::from(z), FloatExp::from(r), p).to_f64();
            assert!((got - want).abs() < 1e-13, "{p}: {got} {want}");
        }
    }

    /// The Burning Ship's period-3 miniship on the real axis near -1.7549 (the real slice
    /// is z² + c's), its period-1 component about 0, and nothing far outside.
    #[test]
    fn burning_ship_periods() {
        let ship = Formula::single(Phase::new(Kind::BurningShip, 2));
        let at = |re: f64, im: f64, r: f64| ball_period(ship, &BigC::from_f64(re, im, 128), FloatExp::from(r), 1000);
        assert_eq!(at(-1.7549, 0.0, 1e-3), Some(3));
        assert_eq!(at(0.0, 0.0, 0.1), Some(1));
        assert_eq!(at(2.0, 2.0, 0.01), None);
    }
}
