//! The families that are a sum of two powers with a coefficient: f(z) = a W² + W^Q or
//! a W² - W^Q, W = z or W = z with parts folded (`IN`, as `formula::map`'s fold before the
//! power). Kalles Fraktaler's "TheRedshiftRider" formulas are W = z (types 42 to 50, Q = 3 to
//! 6; type 44 is 2 z² - z³, a fixed at 2), with a complex number the user chooses (KF's
//! `FactorAR`, `FactorAI`); its "HPDZ Buffalo" (41) is W² - W, W = |x| + i|y| (a = 1). So the
//! map is a value ([`Sum`] holds a) and not only a type; the fold, Q and the sign are the
//! type's, so each family's kernels are still compiled on their own.
//!
//! After the fold the map is complex-analytic in W, so everything the engines need follows
//! from complex arithmetic: the perturbed step is a ((W + e)² - W²) ± ((W + e)^Q - W^Q), e =
//! the folded delta by `diffabs` (exact through the fold lines), each difference by the
//! binomial expansion (nothing cancels), and the Jacobian is the complex derivative
//! g = 2 a W ± Q W^(Q-1) after the fold's reflection, the matrix of g times diag(sgn x,
//! sgn y) for the parts folded.
//!
//! Unlike z^p + c, whose only critical point is 0, f has Q - 1 of them: 0 and the roots of
//! z^(Q-2) = ∓2a/Q (HPDZ Buffalo: W = 1/2, at |x| = 1/2 on the real axis). Kalles
//! Fraktaler iterates the orbit of 0 (z_0 = 0, so z_1 = c), and so does deepfield: the
//! picture is the set of c for which that one critical orbit stays bounded, not the
//! connectedness locus of the family, which would follow every critical orbit.
//! `docs/formulas.md` says so where it lists the families.

use super::map::{
    FOLD_IM, FOLD_NONE, FOLD_RE, Map, Num, fold, fold_big, fold_delta, fold_delta_n, nmul, power, power_delta,
    power_delta_n,
};
use super::phase::Phase;
use super::product::slope;
use crate::num::bigcomplex::BigC;
use crate::num::real::{Real, cadd, cmul};

/// f(z) = a W² + W^Q (`NEG` false) or a W² - W^Q (`NEG` true), W = z with the parts `IN`
/// names folded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sum<const IN: u8, const Q: u32, const NEG: bool> {
    /// a = re + i im.
    pub a: [f64; 2],
}

/// `s` plus `t` (`NEG` false) or minus `t`.
#[inline(always)]
fn combine<const NEG: bool, N: Num>(s: [N; 2], t: [N; 2]) -> [N; 2] {
    if NEG { [s[0].sub(t[0]), s[1].sub(t[1])] } else { [s[0].add(t[0]), s[1].add(t[1])] }
}

impl<const IN: u8, const Q: u32, const NEG: bool> Map for Sum<IN, Q, NEG> {
    const POWER: u32 = if Q > 2 { Q } else { 2 };
    const CONFORMAL: bool = IN == FOLD_NONE;

    #[inline(always)]
    fn of(phase: &Phase) -> Self {
        Sum { a: phase.a.get() }
    }

    #[inline(always)]
    fn apply_n<N: Num>(&self, z: [N; 2]) -> [N; 2] {
        let w = fold(IN, z);
        let a = [N::splat(self.a[0]), N::splat(self.a[1])];
        combine::<NEG, N>(nmul(a, power::<2, N>(w)), power::<Q, N>(w))
    }

    fn apply_big(&self, z: &BigC) -> BigC {
        let w = fold_big(IN, z.clone());
        let a = BigC::from_f64(self.a[0], self.a[1], z.bits);
        let s = a.mul(&w.square());
        let t = w.pow(Q);
        if NEG { s.sub(&t) } else { s.add(&t) }
    }

    #[inline(always)]
    fn delta<R: Real>(&self, z: [f64; 2], d: [R; 2]) -> [R; 2] {
        let e = fold_delta(IN, z, d);
        let w = fold(IN, z);
        let a = [R::from_f64(self.a[0]), R::from_f64(self.a[1])];
        let s = cmul(a, power_delta::<2, R>(w, e));
        let t = power_delta::<Q, R>(w, e);
        if NEG { cadd(s, [-t[0], -t[1]]) } else { cadd(s, t) }
    }

    #[inline(always)]
    fn delta_n<N: Num>(&self, z: [N; 2], d: [N; 2]) -> [N; 2] {
        let e = fold_delta_n(IN, z, d);
        let w = fold(IN, z);
        let a = [N::splat(self.a[0]), N::splat(self.a[1])];
        combine::<NEG, N>(nmul(a, power_delta_n::<2, N>(w, e)), power_delta_n::<Q, N>(w, e))
    }

    #[inline(always)]
    fn jacobian_n<N: Num>(&self, z: [N; 2]) -> [[N; 2]; 2] {
        let one = N::splat(1.0);
        let w = fold(IN, z);
        let a = [N::splat(self.a[0]), N::splat(self.a[1])];
        let g = combine::<NEG, N>(nmul(a, slope::<N>(2, w)), slope::<N>(Q, w));
        // The fold's reflection first: column j times the sign of the part it folds.
        let si = if IN & FOLD_RE != 0 { z[0].sgn() } else { one };
        let sj = if IN & FOLD_IM != 0 { z[1].sgn() } else { one };
        [[g[0].mul(si), g[1].neg().mul(sj)], [g[1].mul(si), g[0].mul(sj)]]
    }
}

/// g = 2 a W ± q W^(q-1) in big floats at `w.bits` (W the folded point), for Newton's method.
pub fn derivative_big(q: u32, neg: bool, a: [f64; 2], w: &BigC) -> BigC {
    let two_a = BigC::from_f64(2.0 * a[0], 2.0 * a[1], w.bits);
    let s = two_a.mul(w);
    let k = BigC::from_f64(q as f64, 0.0, w.bits);
    let t = if q == 1 { k } else { w.pow(q - 1).mul(&k) };
    if neg { s.sub(&t) } else { s.add(&t) }
}

/// The radius within which one perturbed step from Z (|Z| = `az`) is linear to `eps` of its
/// linear part, apart from the fold lines (which the caller keeps the delta off): the
/// dropped terms are a e² and Σ_(k>=2) C(q,k) W^(q-k) e^k (|e| = |d| off the fold lines),
/// which for |d| <= |Z| stay below |d|² (|a| + |Z|^(q-2) (2^q - 1 - q)) (the binomial row's
/// sum from k = 2, with |d|^(k-2) <= |Z|^(k-2); nothing for q = 1), and the linear part is
/// |g| |d| exactly (`g_abs`, the modulus of the complex derivative g = 2 a W ± q W^(q-1):
/// the Jacobian is g after a reflection). So the step holds for |d| < min(|Z|, eps |g| /
/// that bracket); it is 0 at a critical point, where no linear step is valid.
pub fn bla_radius(q: u32, a: [f64; 2], az: f64, g_abs: f64, eps: f64) -> f64 {
    let rows = (1u64 << q) as f64 - 1.0 - q as f64;
    let higher = if rows > 0.0 { az.powi(q as i32 - 2) * rows } else { 0.0 };
    let r = eps * g_abs / (a[0].hypot(a[1]) + higher);
    if r.is_finite() { r.min(az) } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::checks;
    use crate::formula::map::FOLD_BOTH;

    const POINTS: [[f64; 2]; 7] =
        [[0.3, -0.7], [-1.1, 0.2], [0.05, 0.9], [-0.4, -0.35], [1.3, 1e-3], [-2e-3, 0.6], [0.5, -0.52]];

    const DELTAS: [[f64; 2]; 4] = [[1e-3, -2e-3], [-0.5, 0.1], [2e-9, 7e-9], [-0.31, 0.8]];

    /// Coefficients: KF's default, type 44's constant, and complex ones.
    const COEFS: [[f64; 2]; 4] = [[1.0, 0.0], [2.0, 0.0], [-0.7, 0.45], [0.0, -1.3]];

    /// The f64 map, the big-float map and the value written out with plain complex
    /// products agree.
    fn check_value<const IN: u8, const Q: u32, const NEG: bool>(a: [f64; 2]) {
        let m = Sum::<IN, Q, NEG> { a };
        let mulc = |p: [f64; 2], q: [f64; 2]| [p[0] * q[0] - p[1] * q[1], p[0] * q[1] + p[1] * q[0]];
        for z in POINTS {
            let w =
                [if IN & FOLD_RE != 0 { z[0].abs() } else { z[0] }, if IN & FOLD_IM != 0 { z[1].abs() } else { z[1] }];
            let wq = (0..Q).fold([1.0, 0.0], |acc, _| mulc(acc, w));
            let s = mulc(a, mulc(w, w));
            let sign = if NEG { -1.0 } else { 1.0 };
            let want = [s[0] + sign * wq[0], s[1] + sign * wq[1]];
            let f = m.apply(z);
            let big = checks::parse(&m.apply_big(&BigC::from_f64(z[0], z[1], 200)));
            for k in 0..2 {
                let tol = 1e-13 * (1.0 + want[k].abs());
                assert!((f[k] - want[k]).abs() <= tol && (big[k] - want[k]).abs() <= tol, "{a:?} {z:?}");
            }
        }
    }

    fn check_all<const IN: u8, const Q: u32, const NEG: bool>() {
        for a in COEFS {
            let m = Sum::<IN, Q, NEG> { a };
            checks::check_delta(&m, &POINTS, &DELTAS, 4e-14);
            checks::check_jacobian(&m, &POINTS);
            check_value::<IN, Q, NEG>(a);
        }
    }

    #[test]
    fn delta_jacobian_and_value_of_every_sum() {
        check_all::<FOLD_NONE, 3, false>();
        check_all::<FOLD_NONE, 3, true>();
        check_all::<FOLD_NONE, 4, false>();
        check_all::<FOLD_NONE, 4, true>();
        check_all::<FOLD_NONE, 5, false>();
        check_all::<FOLD_NONE, 5, true>();
        check_all::<FOLD_NONE, 6, false>();
        check_all::<FOLD_NONE, 6, true>();
        check_all::<FOLD_BOTH, 1, true>();
    }

    /// Within the radius (and off the fold lines) the step's nonlinear part is at most eps
    /// of its linear part, and at a critical point the radius is 0.
    #[test]
    fn the_radius_bounds_the_nonlinear_terms() {
        fn one<const IN: u8, const Q: u32, const NEG: bool>(a: [f64; 2], z: [f64; 2], eps: f64) {
            let m = Sum::<IN, Q, NEG> { a };
            let jac = m.jacobian(z);
            let mut r = bla_radius(Q, a, z[0].hypot(z[1]), jac[0][0].hypot(jac[1][0]), eps);
            assert!(r > 0.0, "{a:?} {z:?}");
            if IN != FOLD_NONE {
                r = r.min(z[0].abs()).min(z[1].abs()) * 0.999;
            }
            for angle in 0..8 {
                let t = angle as f64 * 0.785;
                let d = [r * t.cos(), r * t.sin()];
                let full = m.delta::<f64>(z, d);
                let lin = [jac[0][0] * d[0] + jac[0][1] * d[1], jac[1][0] * d[0] + jac[1][1] * d[1]];
                let err = (full[0] - lin[0]).hypot(full[1] - lin[1]);
                assert!(err <= eps * lin[0].hypot(lin[1]) * (1.0 + 1e-9), "{a:?} {z:?} {IN} {Q} {NEG}");
            }
        }
        let eps = 1e-3;
        for a in COEFS {
            for z in POINTS {
                one::<FOLD_NONE, 3, false>(a, z, eps);
                one::<FOLD_NONE, 3, true>(a, z, eps);
                one::<FOLD_NONE, 4, true>(a, z, eps);
                one::<FOLD_NONE, 6, false>(a, z, eps);
                one::<FOLD_BOTH, 1, true>(a, z, eps);
            }
        }
        // 2 a z - 3 z² = 0 at z = 2a/3; 2W - 1 = 0 at W = 1/2.
        let a = [0.9, -0.3];
        let c = [2.0 * a[0] / 3.0, 2.0 * a[1] / 3.0];
        let g = |j: crate::formula::map::Mat2| j[0][0].hypot(j[1][0]);
        let at_c = Sum::<FOLD_NONE, 3, true> { a }.jacobian(c);
        assert!(bla_radius(3, a, c[0].hypot(c[1]), g(at_c), eps) < 1e-15);
        let at_half = Sum::<FOLD_BOTH, 1, true> { a: [1.0, 0.0] }.jacobian([-0.5, 0.0]);
        assert_eq!(bla_radius(1, [1.0, 0.0], 0.5, g(at_half), eps), 0.0);
        // The big-float derivative is the Jacobian's complex number.
        let m = Sum::<FOLD_NONE, 5, true> { a };
        for z in POINTS {
            let j = m.jacobian(z);
            let g = checks::parse(&derivative_big(5, true, a, &BigC::from_f64(z[0], z[1], 200)));
            assert!((g[0] - j[0][0]).abs() <= 1e-13 * (1.0 + g[0].abs()), "{z:?}");
            assert!((g[1] - j[1][0]).abs() <= 1e-13 * (1.0 + g[1].abs()), "{z:?}");
        }
    }
}
