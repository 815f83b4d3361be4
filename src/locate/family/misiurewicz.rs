//! Misiurewicz points of the Mandelbrot family at any power d: parameters whose critical
//! orbit is eventually periodic, z_(k+p) = z_k, by Newton's method with the complex
//! derivative (z_(n+1)' = d z_n^(d-1) z_n' + 1), as `crate::locate::misiurewicz` does for
//! d = 2.
//!
//! Only the conformal families have them in this form: Newton's method on
//! z_(k+p) - z_k needs one complex derivative, and the candidates below use z^d's symmetry.
//! A folded family's orbit meets the fold lines, where the map has no derivative, and its
//! preperiodic parameters are not isolated points of the plane in general (a fold makes
//! z_(k+p) = z_k two real conditions that can hold along curves); `find --misiurewicz`
//! refuses them by name.
//!
//! Candidates: for each period p the first preperiod k >= 2 whose first-order distance
//! |z_(k+p) - z_k| / |z'_(k+p) - z'_k| from the view's centre is inside the view, where the
//! orbit steps into the cycle: z_(k+p-1) nearer to ω z_(k-1) for a d-th root of unity
//! ω ≠ 1 than to z_(k-1) itself (z^d maps both to the same point; where ω = 1 the root
//! has a lower preperiod). Tried in order of k + p with Newton's method, the first root in
//! the view whose own orbit has preperiod k >= 2 wins. z² + c's search also places copies
//! of the whole set's simplest points in the view's minibrot when these find nothing; that
//! is not done here, and the search then says that nothing was found.

use rayon::prelude::*;

use crate::formula::Formula;
use crate::locate::misiurewicz::{Orbit, classify};
use crate::num::FloatExp;
use crate::num::bigcomplex::BigC;

use super::step::step;

/// One step of c's orbit with its complex derivative: (f(z) + c, f'(z) z' + 1). For a
/// conformal formula only.
fn orbit_step(formula: Formula, c: &BigC, n: u32, z: &BigC, dz: &BigC) -> (BigC, BigC) {
    let one = BigC::from_f64(1.0, 0.0, c.bits);
    let (f, d) = step(formula.phase(n), z);
    let a = d.factor().expect("a conformal formula's derivative is one complex number");
    (f.add(c), a.mul(dz).add(&one))
}

/// The orbit of c, `n` steps (ended early above `bound`).
pub fn orbit(formula: Formula, c: &BigC, n: usize, bound: Option<FloatExp>) -> Orbit {
    Orbit::by(c, n, bound, |i, z, dz| orbit_step(formula, c, i, z, dz))
}

/// Newton's method for a root of z_(k+p) - z_k from `start`, at its precision; None unless
/// it converges within `max_steps`.
pub fn newton(formula: Formula, start: &BigC, preperiod: u32, period: u32, max_steps: u32) -> Option<BigC> {
    let bits = start.bits;
    let tolerance = FloatExp::new(1.0, 16 - bits as i32);
    let mut c = start.clone();
    for _ in 0..max_steps {
        let (mut z, mut dz) = (BigC::zero(bits), BigC::zero(bits));
        let (mut zk, mut dzk) = (BigC::zero(bits), BigC::zero(bits));
        for n in 0..preperiod + period {
            (z, dz) = orbit_step(formula, &c, n, &z, &dz);
            if n + 1 == preperiod {
                (zk, dzk) = (z.clone(), dz.clone());
            }
        }
        let df = dz.sub(&dzk);
        if df.abs().is_zero() {
            return None;
        }
        let delta = z.sub(&zk).div(&df);
        c = c.sub(&delta);
        if delta.abs() <= tolerance * FloatExp::ONE.max(c.abs()) {
            return Some(c);
        }
        if c.abs().partial_cmp(&FloatExp::from(4.0)) != Some(std::cmp::Ordering::Less) {
            return None;
        }
    }
    None
}

/// The smallest preperiod k <= `max_preperiod` and period p <= `max_period` for which `c`
/// is a root of z_(k+p) = z_k to its precision (`crate::locate::misiurewicz::orbit_type`
/// under `formula`).
pub fn orbit_type(formula: Formula, c: &BigC, max_preperiod: u32, max_period: u32) -> Option<(u32, u32)> {
    classify(c, &orbit(formula, c, (max_preperiod + max_period) as usize, None), max_preperiod, max_period)
}

/// A preperiod and period worth Newton's method.
#[derive(Debug, Clone, Copy)]
pub struct Candidate {
    /// k.
    pub preperiod: u32,
    /// p.
    pub period: u32,
    /// log2 |z'_(k+p) - z'_k| at the centre.
    pub log2_derivative: f64,
}

/// Whether a step of z^d from `b` reached `a`'s image along a different branch: the angle
/// from b to a is nearer a non-zero multiple of 2π/d than 0.
fn other_branch(a: [FloatExp; 2], b: [FloatExp; 2], d: u32) -> bool {
    let arg = |v: [FloatExp; 2]| {
        let n = (v[0] * v[0] + v[1] * v[1]).sqrt();
        if n.is_zero() { 0.0 } else { (v[1] / n).to_f64().atan2((v[0] / n).to_f64()) }
    };
    let sector = std::f64::consts::TAU / d as f64;
    let turn = (arg(a) - arg(b)).rem_euclid(std::f64::consts::TAU);
    let nearest = (turn / sector).round() as u32 % d;
    nearest != 0
}

/// For each period p, the first preperiod k >= 2 whose first-order distance is within
/// `radius` and whose orbit steps into the cycle there (module docs).
pub fn candidates(formula: Formula, c: &BigC, radius: FloatExp, max_preperiod: u32, max_period: u32) -> Vec<Candidate> {
    let d = formula.phases()[0].power;
    let orbit = orbit(formula, c, (max_preperiod + max_period) as usize, Some(FloatExp::from(2.0)));
    let first = |p: usize| {
        (2..=max_preperiod as usize).take_while(|&k| k + p < orbit.len()).find_map(|k| {
            let df = orbit.slope(k + p, k);
            if df.is_zero() || orbit.gap(k + p, k) / df >= radius {
                return None;
            }
            if !other_branch(orbit.point(k + p - 1), orbit.point(k - 1), d) {
                return None;
            }
            Some(Candidate { preperiod: k as u32, period: p as u32, log2_derivative: df.log2() })
        })
    };
    (1..=max_period as usize).into_par_iter().filter_map(first).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::{Kind, Phase};

    /// At power 2 the orbit type and Newton's method are z² + c's.
    #[test]
    fn at_power_2_it_is_the_quadratic_search() {
        let f = Formula::default();
        let start = BigC::from_f64(0.02, 0.98, 200);
        let c = newton(f, &start, 2, 2, 100).unwrap();
        let want = crate::locate::misiurewicz::newton(&start, 2, 2, 100).unwrap();
        assert!(c.sub(&want).abs() < FloatExp::exp10(-50.0));
        assert_eq!(orbit_type(f, &c, 40, 8), Some((2, 2)));
    }

    /// z³ + c's Misiurewicz points of preperiod 2 and period 1 are the roots of
    /// (c³ + c)³ + c = c³ + c other than 0: ±0.3406250193166064 ± 1.2712298784187057i (the
    /// polynomial's roots, by numpy). Newton's method from beside one reaches it, and its
    /// orbit, by plain cubing, is preperiodic with exactly (2, 1).
    #[test]
    fn a_cubic_misiurewicz_point() {
        let f = Formula::single(Phase::new(Kind::Mandelbrot, 3));
        let c = newton(f, &BigC::from_f64(0.33, 1.28, 200), 2, 1, 100).expect("converges");
        let [x, y] = c.to_fe().map(FloatExp::to_f64);
        assert!((x - 0.340_625_019_316_606_4).abs() < 1e-13 && (y - 1.271_229_878_418_705_7).abs() < 1e-13, "{x} {y}");
        assert_eq!(orbit_type(f, &c, 10, 4), Some((2, 1)));
        let cube = |z: &BigC| z.mul(z).mul(z).add(&c);
        let (z1, z2) = (c.clone(), cube(&c));
        assert!(cube(&z2).sub(&z2).abs() < FloatExp::exp10(-50.0));
        assert!(z2.sub(&z1).abs() > FloatExp::from(0.1));
    }

    #[test]
    fn branches_of_z_cubed() {
        let p = |x: f64, y: f64| [FloatExp::from(x), FloatExp::from(y)];
        assert!(!other_branch(p(1.0, 0.1), p(1.0, 0.0), 3));
        let w = std::f64::consts::TAU / 3.0;
        assert!(other_branch(p(w.cos(), w.sin()), p(1.0, 0.0), 3));
        assert!(other_branch(p(-1.0, 0.0), p(1.0, 0.0), 2));
    }
}
