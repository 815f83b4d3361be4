//! The ball method's lower bound on the periods of the minis in a disc of parameters, for
//! any formula, and the periods of the atom domains that hold a point.
//!
//! z² + c's bound ([`crate::locate::period`]) carries a radius r_n with
//! |z_n(c + d) - z_n(c)| <= r_n for every |d| <= r. The same bound holds for every family,
//! because each of its four steps is Lipschitz in the Euclidean norm: a fold (|x| for x)
//! moves no point farther from another (||a| - |b|| <= |a - b| in each part), a negation is
//! an isometry, and the power satisfies |(w + e)^p - w^p| <= (|w| + |e|)^p - |w|^p (the
//! binomial expansion and the triangle inequality), with |w| = |z| after a fold. So
//! r_(n+1) = (|z_n| + r_n)^p - |z_n|^p + r, p the power of iteration n's phase, and a mini
//! whose nucleus (z_q = 0) lies in the disc puts 0 within r_q of z_q: the first n at which
//! |z_n| < r_n is a lower bound on the periods of the nuclei in the disc, exactly as for
//! z² + c (to which it reduces at p = 2).
//!
//! This is preferred to an atom-domain test on the Newton step J_n⁻¹ z_n (the first n whose
//! step is shorter than the disc): that test needs J_n to be invertible, and near the fold
//! lines, where the folded families have their richest structure, it is often nearly
//! singular; the ball bound needs no derivative, is rigorous for every family and hybrid,
//! and is the test `find` already uses for z² + c, so the two agree where both apply.

use crate::formula::{Cycle, Formula, Stepper};
use crate::num::FloatExp;
use crate::num::bigcomplex::BigC;

/// (|z| + r)^p - |z|^p without cancellation: sum over k = 1..p of C(p, k) |z|^(p-k) r^k.
fn growth(z: FloatExp, r: FloatExp, p: u32) -> FloatExp {
    let mut sum = FloatExp::ZERO;
    for k in 1..=p {
        let c = crate::formula::map::binomial(p, k);
        let mut t = FloatExp::from(c);
        for _ in 0..p - k {
            t = t * z;
        }
        for _ in 0..k {
            t = t * r;
        }
        sum = sum + t;
    }
    sum
}

/// The first n <= `max_period` at which the disc of radius `radius` about `center`, iterated
/// by `formula`'s maps (Mandelbrot form: z_0 = 0, c the parameter), contains 0; None when
/// none does or the disc escapes first.
pub fn ball_period(formula: Formula, center: &BigC, radius: FloatExp, max_period: u32) -> Option<u32> {
    let s = Cycle(formula);
    let mut z = BigC::zero(center.bits);
    let mut r = FloatExp::ZERO;
    for n in 1..=max_period {
        let phase = formula.phase(n - 1);
        r = growth(z.abs(), r, phase.power) + radius;
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

/// The iterations after `after` (up to `max_period`, at most `count`) at which the orbit of
/// `center` comes nearer to 0 than at any earlier one: the periods of the atom domains that
/// hold it, whose nuclei Newton's method from `center` tends to reach. The orbit is followed
/// until |z| > 2.
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

    /// At power 2 the bound is z² + c's, step for step.
    #[test]
    fn at_power_2_it_is_the_quadratic_ball_method() {
        for (re, im, r) in [(-1.7549, 0.0, 1e-3), (-0.1226, 0.7449, 1e-3), (-0.75, 0.1, 3.3e-2), (0.0, 0.0, 0.1)] {
            let c = BigC::from_f64(re, im, 128);
            let r = FloatExp::from(r);
            let want = crate::locate::period::ball_period(&c, r, 1000);
            assert_eq!(ball_period(Formula::default(), &c, r, 1000), want, "{re} {im}");
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
        let ship = Formula::single(Phase { kind: Kind::BurningShip, power: 2 });
        let at = |re: f64, im: f64, r: f64| ball_period(ship, &BigC::from_f64(re, im, 128), FloatExp::from(r), 1000);
        assert_eq!(at(-1.7549, 0.0, 1e-3), Some(3));
        assert_eq!(at(0.0, 0.0, 0.1), Some(1));
        assert_eq!(at(2.0, 2.0, 0.01), None);
    }
}
