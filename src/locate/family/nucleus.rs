//! The nucleus of a mini of any formula by Newton's method on the real 2×2 system
//! z_p(c) = 0, and the mini's size and orientation.
//!
//! With c = a + ib, F(a, b) = (Re z_p, Im z_p) and its Jacobian J_p = ∂(Re z_p, Im z_p) /
//! ∂(a, b) carried through the orbit by forward-mode differentiation in big floats
//! ([`super::step`]): J_(n+1) = Df(z_n) J_n + I, J_0 = 0. Newton's step is
//! c <- c - J_p⁻¹ z_p, solved in big floats. For the Mandelbrot family J_p is the complex
//! derivative and the step is z² + c's c - z_p / z_p'; for the folded families J_p is a
//! general real matrix (Claude Heiland-Allen's notes on Newton's method for the Burning
//! Ship take the same real Jacobian). Where det J_p vanishes to the working precision the
//! step is refused (Newton's method has no direction there) and the search says so.
//!
//! The size comes from the cycle as for z² + c (Claude Heiland-Allen's "Minibrot size
//! estimates"), with p the degree of the map that follows z_p ≈ 0: near the nucleus,
//! z_p ≈ L F(ε) + D δ, L the product of the maps' Jacobians along z_1 .. z_(p-1), F the map
//! of degree d and D = J_p, δ = c - nucleus; a change of coordinates w = A z with
//! |A|^(d-1) = |L| makes that w^d + A D δ, a copy of the whole set with parameter A D δ. So
//! the mini's size is 1 / (|L|^(1/(d-1)) |D|), z² + c's 1 / (|β| |λ|²) at d = 2. The
//! moduli are taken as |det|^(1/2): exact for L, which is conformal or anti-conformal like
//! every Df, and for D in the Mandelbrot family; for the folded families D is a general
//! matrix, |det D|^(1/2) its mean scale, and the mini is stretched by the ratio of D's
//! singular values besides. The orientation is that of the complex estimate
//! 1 / (λ^(1/(d-1)) D) with λ and D the first columns of L and D (d z along a, as complex
//! numbers): exact for the Mandelbrot family, for the others the direction the mini's own
//! real axis is turned to, up to its stretch.

use malachite_float::Float;

use crate::formula::Formula;
use crate::num::FloatExp;
use crate::num::bigcomplex::BigC;

use super::step::step;

/// A mini found: its nucleus, period, size and orientation.
#[derive(Debug, Clone, PartialEq)]
pub struct Mini {
    /// The nucleus (z_p = 0 to the working precision).
    pub nucleus: BigC,
    /// Its period.
    pub period: u32,
    /// The mini's scale in the plane (module docs).
    pub size: FloatExp,
    /// The direction its own real axis is turned to, in radians.
    pub angle: f64,
}

/// How one run of Newton's method ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Newton {
    /// It settled at this root of z_p = 0.
    Root(BigC),
    /// det J_p vanished to the working precision at some step.
    Singular,
    /// It did not settle, diverged or left its leash.
    Lost,
}

/// z_p of c with the Jacobian's columns ∂z_p/∂a and ∂z_p/∂b (as complex numbers), and
/// the same at every n < p through `each` (n, z_n, columns).
fn orbit(formula: Formula, c: &BigC, period: u32, mut each: impl FnMut(u32, &BigC, &[BigC; 2])) -> (BigC, [BigC; 2]) {
    let bits = c.bits;
    let (one, i) = (BigC::from_f64(1.0, 0.0, bits), BigC::from_f64(0.0, 1.0, bits));
    let mut z = BigC::zero(bits);
    let mut j = [BigC::zero(bits), BigC::zero(bits)];
    for n in 0..period {
        if n > 0 {
            each(n, &z, &j);
        }
        let (f, d) = step(formula.phase(n), &z);
        j = [d.apply(&j[0]).add(&one), d.apply(&j[1]).add(&i)];
        z = f.add(c);
    }
    (z, j)
}

/// J⁻¹ f for J with columns `j` (complex numbers as real 2-vectors), in big floats; None
/// where det J is zero or below 2^(16 - bits) of |J|² (singular to the working precision).
fn solve(j: &[BigC; 2], f: &BigC) -> Option<[Float; 2]> {
    let p = f.bits;
    let m = |a: &Float, b: &Float| a.mul_prec_ref_ref(b, p).0;
    let det = m(&j[0].re, &j[1].im).sub_prec(m(&j[1].re, &j[0].im), p).0;
    let scale = j[0].abs() * j[1].abs();
    let d = crate::num::bigfloat::to_floatexp(&det).abs();
    // Also refuses a NaN (every comparison with it is false).
    if d.partial_cmp(&(scale * FloatExp::new(1.0, 16 - p as i32))) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let x = m(&j[1].im, &f.re).sub_prec(m(&j[1].re, &f.im), p).0.div_prec(det.clone(), p).0;
    let y = m(&j[0].re, &f.im).sub_prec(m(&j[0].im, &f.re), p).0.div_prec(det, p).0;
    Some([x, y])
}

/// |J⁻¹ f|: the first-order distance from c to a zero of the function whose value is f
/// and Jacobian J; None where J is singular.
pub fn first_order_distance(j: &[BigC; 2], f: &BigC) -> Option<FloatExp> {
    let [x, y] = solve(j, f)?;
    Some(BigC { re: x, im: y, bits: f.bits }.abs())
}

/// Newton's method for a root of z_p = 0 from `start`, at its precision, given up after
/// `max_steps` or once an iterate is farther than `leash` from `start`; with the steps taken.
pub fn newton(formula: Formula, start: &BigC, period: u32, max_steps: u32, leash: Option<FloatExp>) -> (Newton, u32) {
    let bits = start.bits;
    let tolerance = FloatExp::new(1.0, 16 - bits as i32);
    let mut c = start.clone();
    for taken in 1..=max_steps {
        let (z, j) = orbit(formula, &c, period, |_, _, _| {});
        let Some([x, y]) = solve(&j, &z) else { return (Newton::Singular, taken) };
        let delta = BigC { re: x, im: y, bits };
        c = c.sub(&delta);
        if delta.abs() <= tolerance * FloatExp::ONE.max(c.abs()) {
            return (Newton::Root(c), taken);
        }
        // Diverged (or NaN: then the comparison is false too).
        if c.abs().partial_cmp(&FloatExp::from(4.0)) != Some(std::cmp::Ordering::Less) {
            return (Newton::Lost, taken);
        }
        if leash.is_some_and(|l| c.sub(start).abs() > l) {
            return (Newton::Lost, taken);
        }
    }
    (Newton::Lost, max_steps)
}

/// The smallest n < `period` at which `c`, a root of z_period = 0 to Newton's tolerance, is
/// a root of z_n = 0 too (its first-order distance |J_n⁻¹ z_n| is within 2^(32 - bits) of
/// |c|): a nucleus of the lower period n, which Newton's method for p reaches as it does for
/// z² + c. Every n is tried, not only the divisors of p: in a hybrid, z_n = 0 restarts the
/// orbit with the phases shifted.
pub fn lower_period(formula: Formula, c: &BigC, period: u32) -> Option<u32> {
    let tolerance = FloatExp::new(1.0, 32 - c.bits as i32) * FloatExp::ONE.max(c.abs());
    let mut found = None;
    orbit(formula, c, period, |n, z, j| {
        if found.is_none() && first_order_distance(j, z).is_some_and(|d| d <= tolerance) {
            found = Some(n);
        }
    });
    found
}

/// A 2×2 FloatExp matrix, rows first.
type Mat = [[FloatExp; 2]; 2];

fn mat_mul(a: &Mat, b: &Mat) -> Mat {
    let e = |r: usize, k: usize| a[r][0] * b[0][k] + a[r][1] * b[1][k];
    [[e(0, 0), e(0, 1)], [e(1, 0), e(1, 1)]]
}

fn det(m: &Mat) -> FloatExp {
    (m[0][0] * m[1][1] - m[0][1] * m[1][0]).abs()
}

/// The argument of re + i im (radians), at any exponent.
fn arg(re: FloatExp, im: FloatExp) -> f64 {
    let n = (re * re + im * im).sqrt();
    if n.is_zero() {
        return 0.0;
    }
    (im / n).to_f64().atan2((re / n).to_f64())
}

/// The size and orientation of the mini of `formula` whose nucleus is `c` (period `period`);
/// module docs.
pub fn size(formula: Formula, c: &BigC, period: u32) -> (FloatExp, f64) {
    let one = FloatExp::ONE;
    let mut l: Mat = [[one, FloatExp::ZERO], [FloatExp::ZERO, one]];
    let (_, j) = orbit(formula, c, period, |n, z, _| {
        let (_, d) = step(formula.phase(n), z);
        l = mat_mul(&d.matrix(), &l);
    });
    let degree = formula.phase(period).power as f64;
    let [dr, di] = j[0].to_fe();
    let dm = [[dr, j[1].to_fe()[0]], [di, j[1].to_fe()[1]]];
    let log2 = -(det(&l).log2() / (2.0 * (degree - 1.0)) + det(&dm).log2() / 2.0);
    let size = if log2.is_finite() {
        FloatExp::ONE.ldexp(log2.floor() as i32).mul_f64((log2 - log2.floor()).exp2())
    } else {
        FloatExp::ZERO
    };
    let angle = -(arg(l[0][0], l[1][0]) / (degree - 1.0) + arg(dr, di));
    // In (-π, π], as z² + c's estimate gives it.
    let turned = std::f64::consts::PI - (std::f64::consts::PI - angle).rem_euclid(std::f64::consts::TAU);
    (size, turned)
}

/// A root of Newton's method for `period` as a mini: refused where it lies farther than
/// `radius` from `start` or is a nucleus of a lower period; refined until its precision
/// places it well inside its own size.
pub fn refined(formula: Formula, mut c: BigC, start: &BigC, period: u32, radius: Option<FloatExp>) -> Option<Mini> {
    if radius.is_some_and(|r| c.sub(start).abs() > r) || lower_period(formula, &c, period).is_some() {
        return None;
    }
    loop {
        let (size, angle) = size(formula, &c, period);
        if size.is_zero() {
            return None;
        }
        let needed = (-size.log2()).max(0.0) as u64 + 64;
        if c.bits >= needed {
            return Some(Mini { nucleus: c, period, size, angle });
        }
        match newton(formula, &c.with_bits(needed + 32), period, 64, None).0 {
            Newton::Root(r) => c = r,
            _ => return None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::{Kind, Phase};

    /// For z² + c the real Newton's method reaches z² + c's nuclei, and the size and
    /// direction are z² + c's estimate.
    #[test]
    fn for_z2_it_is_the_complex_newton_and_size() {
        let f = Formula::default();
        for (re, im, p) in [(-1.75, 0.0, 3), (-0.12, 0.74, 3), (-1.31, 0.0, 4)] {
            let start = BigC::from_f64(re, im, 256);
            let Newton::Root(c) = newton(f, &start, p, 100, None).0 else { panic!("{re} {im}") };
            let want = crate::locate::nucleus::newton(&start, p, 100).unwrap();
            assert!(c.sub(&want).abs() < FloatExp::exp10(-60.0), "{re} {im}");
            let (s, a) = size(f, &c, p);
            let m = crate::locate::nucleus::minibrot(&start, p).unwrap();
            assert!((s.log2() - m.size.log2()).abs() < 1e-9, "{re} {im}: {s:?} {:?}", m.size);
            let turn = (a - m.angle).rem_euclid(std::f64::consts::TAU);
            assert!(turn.min(std::f64::consts::TAU - turn) < 1e-9, "{re} {im}: {a} {}", m.angle);
        }
    }

    /// The Burning Ship's period-3 miniship on the real axis (the real slice is z² + c's:
    /// -1.754877666246692760049508896358528691894...), from off the axis.
    #[test]
    fn the_burning_ship_period_3_miniship() {
        let ship = Formula::single(Phase::new(Kind::BurningShip, 2));
        let Newton::Root(c) = newton(ship, &BigC::from_f64(-1.755, 1e-4, 256), 3, 100, None).0 else { panic!() };
        let [x, y] = c.to_fe().map(FloatExp::to_f64);
        assert!((x + 1.754_877_666_246_693).abs() < 1e-15 && y.abs() < 1e-30, "{x} {y}");
        assert_eq!(lower_period(ship, &c, 3), None);
        assert_eq!(lower_period(ship, &c, 6), Some(3));
    }

    /// Where the Jacobian is singular (zero, or columns parallel) the step is refused.
    #[test]
    fn a_singular_jacobian_is_refused() {
        let zero = [BigC::zero(128), BigC::zero(128)];
        assert_eq!(solve(&zero, &BigC::from_f64(1.0, 0.0, 128)), None);
        // Parallel columns: (1, 1) and (2, 2).
        let parallel = [BigC::from_f64(1.0, 1.0, 128), BigC::from_f64(2.0, 2.0, 128)];
        assert_eq!(solve(&parallel, &BigC::from_f64(1.0, 0.0, 128)), None);
    }
}
