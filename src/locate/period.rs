//! A lower bound on the periods of the minibrots in a disc of parameters (the ball method),
//! and the periods of the atom domains that hold a point.
//!
//! Iterate the disc's centre c exactly and carry a radius r_n that bounds how far any
//! parameter of the disc has moved from it: |z_n(c + d) - z_n(c)| <= r_n for |d| <= r, with
//! r_1 = r and r_(n+1) = r_n (2 |z_n| + r_n) + r. A nucleus of period p is exactly a
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

use crate::num::FloatExp;

use crate::num::bigcomplex::BigC;

/// The first n <= `max_period` at which the disc of radius `radius` about `center`, iterated,
/// contains 0; None when none does (or the disc escapes first: then it holds no nucleus of
/// a higher period either).
pub fn ball_period(center: &BigC, radius: FloatExp, max_period: u32) -> Option<u32> {
    let mut z = BigC::zero(center.bits);
    let mut r = FloatExp::ZERO;
    let two = FloatExp::from(2.0);
    for n in 1..=max_period {
        r = r * (two * z.abs() + r) + radius;
        z = z.square().add(center);
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
/// orbit of `center` comes nearer to 0 than at any earlier one: the periods of the atom
/// domains that hold `center` (Claude Heiland-Allen's notes on atom domains), whose nuclei
/// Newton's method from `center` tends to reach. The orbit is followed until it leaves
/// |z| <= 2 (then it comes near 0 no more).
pub fn atom_periods(center: &BigC, after: u32, max_period: u32, count: usize) -> Vec<u32> {
    let mut z = BigC::zero(center.bits);
    let mut least = FloatExp::from(f64::INFINITY);
    let mut out = Vec::new();
    for n in 1..=max_period {
        z = z.square().add(center);
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

    #[test]
    fn finds_the_periods_of_known_components() {
        let at = |re: f64, im: f64, r: f64| ball_period(&BigC::from_f64(re, im, 128), FloatExp::from(r), 1000);
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
        let c = BigC::from_f64(-1.4, 0.0, 128);
        assert_eq!(atom_periods(&c, 0, 1000, 5), vec![1, 2, 4, 8, 16]);
        assert_eq!(atom_periods(&c, 8, 1000, 1), vec![16]);
        // An escaping orbit stops: c = 1 leaves |z| <= 2 at its third iteration.
        assert_eq!(atom_periods(&BigC::from_f64(1.0, 0.0, 128), 0, 1000, 10), vec![1]);
    }
}
