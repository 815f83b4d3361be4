//! The period of the lowest-period minibrot in a disc of parameters: the ball method.
//!
//! Iterate the disc's centre c exactly and carry a radius r_n that bounds how far any
//! parameter of the disc has moved from it: |z_n(c + d) - z_n(c)| <= r_n for |d| <= r, with
//! r_1 = r and r_(n+1) = r_n (2 |z_n| + r_n) + r. The first n at which the bounded disc
//! around z_n contains 0 is the period of a nucleus inside (or very near) the parameter disc,
//! since a nucleus of period p is exactly a parameter with z_p = 0. This is the "box
//! period" method of Robert P. Munafo's Mandelbrot encyclopedia, with a disc in place of
//! the box as in Claude Heiland-Allen's notes on finding minibrots.

use crate::num::FloatExp;

use super::big::BigC;

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
}
