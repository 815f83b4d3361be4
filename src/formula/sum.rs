//! The families that are a sum of two powers with a coefficient: f(z) = a z² + z^Q or
//! a z² - z^Q, Kalles Fraktaler's "TheRedshiftRider" formulas (types 42 to 50, Q = 3 to 6;
//! type 44 is 2 z² - z³, a fixed at 2). a is a complex number the user chooses (KF's
//! `FactorAR`, `FactorAI`), so the map is a value ([`Sum`] holds a) and not only a type;
//! Q and the sign are the type's, so each family's kernels are still compiled on their own.
//!
//! The map is complex-analytic, so everything the engines need follows from complex
//! arithmetic: the perturbed step is a ((Z + d)² - Z²) ± ((Z + d)^Q - Z^Q), each difference
//! by the binomial expansion in d (nothing cancels), and the Jacobian is the complex
//! derivative f'(z) = 2 a z ± Q z^(Q-1) as a 2×2 matrix.
//!
//! Unlike z^p + c, whose only critical point is 0, f has Q - 1 of them: 0 and the roots of
//! z^(Q-2) = ∓2a/Q. Kalles Fraktaler iterates the orbit of 0 (z_0 = 0, so z_1 = c), and so
//! does deepfield: the picture is the set of c for which that one critical orbit stays
//! bounded, not the connectedness locus of the family, which would follow every critical
//! orbit. The README says so where it lists the families.

use super::map::{Map, Num, nmul, power, power_delta, power_delta_n};
use super::phase::Phase;
use crate::num::bigcomplex::BigC;
use crate::num::real::{Real, cadd, cmul};

/// f(z) = a z² + z^Q (`NEG` false) or a z² - z^Q (`NEG` true).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sum<const Q: u32, const NEG: bool> {
    /// a = re + i im.
    pub a: [f64; 2],
}

/// Q z^(Q-1), the complex derivative of z^Q, for one sample or several in lanes.
#[inline(always)]
fn slope<const Q: u32, N: Num>(z: [N; 2]) -> [N; 2] {
    let mut w = [N::splat(1.0), N::splat(0.0)];
    for _ in 1..Q {
        w = nmul(w, z);
    }
    let k = N::splat(Q as f64);
    [w[0].mul(k), w[1].mul(k)]
}

/// `s` plus `t` (`NEG` false) or minus `t`.
#[inline(always)]
fn combine<const NEG: bool, N: Num>(s: [N; 2], t: [N; 2]) -> [N; 2] {
    if NEG { [s[0].sub(t[0]), s[1].sub(t[1])] } else { [s[0].add(t[0]), s[1].add(t[1])] }
}

impl<const Q: u32, const NEG: bool> Map for Sum<Q, NEG> {
    const POWER: u32 = Q;
    const CONFORMAL: bool = true;

    #[inline(always)]
    fn of(phase: &Phase) -> Self {
        Sum { a: phase.a.get() }
    }

    #[inline(always)]
    fn apply_n<N: Num>(&self, z: [N; 2]) -> [N; 2] {
        let a = [N::splat(self.a[0]), N::splat(self.a[1])];
        combine::<NEG, N>(nmul(a, power::<2, N>(z)), power::<Q, N>(z))
    }

    fn apply_big(&self, z: &BigC) -> BigC {
        let a = BigC::from_f64(self.a[0], self.a[1], z.bits);
        let s = a.mul(&z.square());
        let t = z.pow(Q);
        if NEG { s.sub(&t) } else { s.add(&t) }
    }

    #[inline(always)]
    fn delta<R: Real>(&self, z: [f64; 2], d: [R; 2]) -> [R; 2] {
        let a = [R::from_f64(self.a[0]), R::from_f64(self.a[1])];
        let s = cmul(a, power_delta::<2, R>(z, d));
        let t = power_delta::<Q, R>(z, d);
        if NEG { cadd(s, [-t[0], -t[1]]) } else { cadd(s, t) }
    }

    #[inline(always)]
    fn delta_n<N: Num>(&self, z: [N; 2], d: [N; 2]) -> [N; 2] {
        let a = [N::splat(self.a[0]), N::splat(self.a[1])];
        combine::<NEG, N>(nmul(a, power_delta_n::<2, N>(z, d)), power_delta_n::<Q, N>(z, d))
    }

    #[inline(always)]
    fn jacobian_n<N: Num>(&self, z: [N; 2]) -> [[N; 2]; 2] {
        let a = [N::splat(self.a[0]), N::splat(self.a[1])];
        let g = combine::<NEG, N>(nmul(a, slope::<2, N>(z)), slope::<Q, N>(z));
        [[g[0], g[1].neg()], [g[1], g[0]]]
    }
}

/// f'(z) = 2 a z ± Q z^(Q-1) in big floats at `z.bits`, for Newton's method.
pub fn derivative_big(q: u32, neg: bool, a: [f64; 2], z: &BigC) -> BigC {
    let two_a = BigC::from_f64(2.0 * a[0], 2.0 * a[1], z.bits);
    let s = two_a.mul(z);
    let t = z.pow(q - 1).mul(&BigC::from_f64(q as f64, 0.0, z.bits));
    if neg { s.sub(&t) } else { s.add(&t) }
}

/// The radius within which one perturbed step from Z = `z` is linear to `eps` of its
/// linear part: the dropped terms are a d² and Σ_(k>=2) C(Q,k) Z^(Q-k) d^k, which for
/// |d| <= |Z| stay below |d|² (|a| + |Z|^(Q-2) (2^Q - 1 - Q)) (the binomial row's sum from
/// k = 2, with |d|^(k-2) <= |Z|^(k-2)), and the linear part is |f'(Z)| |d| exactly (the map
/// is conformal). So the step holds for |d| < min(|Z|, eps |f'(Z)| / that bracket); it is
/// 0 at a critical point of f, where no linear step is valid.
pub fn bla_radius(q: u32, neg: bool, a: [f64; 2], z: [f64; 2], eps: f64) -> f64 {
    let az = z[0].hypot(z[1]);
    let lin = {
        let [x, y] = z;
        let mut w = [1.0, 0.0];
        for _ in 1..q {
            w = [w[0] * x - w[1] * y, w[0] * y + w[1] * x];
        }
        let t = [q as f64 * w[0], q as f64 * w[1]];
        let s = [2.0 * (a[0] * x - a[1] * y), 2.0 * (a[0] * y + a[1] * x)];
        let g = if neg { [s[0] - t[0], s[1] - t[1]] } else { [s[0] + t[0], s[1] + t[1]] };
        g[0].hypot(g[1])
    };
    let rows = (1u64 << q) as f64 - 1.0 - q as f64;
    let bracket = a[0].hypot(a[1]) + az.powi(q as i32 - 2) * rows;
    let r = eps * lin / bracket;
    if r.is_finite() { r.min(az) } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::checks;

    const POINTS: [[f64; 2]; 7] =
        [[0.3, -0.7], [-1.1, 0.2], [0.05, 0.9], [-0.4, -0.35], [1.3, 1e-3], [-2e-3, 0.6], [0.5, -0.52]];

    const DELTAS: [[f64; 2]; 4] = [[1e-3, -2e-3], [-0.5, 0.1], [2e-9, 7e-9], [-0.31, 0.8]];

    /// Coefficients: KF's default, type 44's constant, and complex ones.
    const COEFS: [[f64; 2]; 4] = [[1.0, 0.0], [2.0, 0.0], [-0.7, 0.45], [0.0, -1.3]];

    /// The f64 map, the big-float map and the value written out with plain complex
    /// products agree.
    fn check_value<const Q: u32, const NEG: bool>(a: [f64; 2]) {
        let m = Sum::<Q, NEG> { a };
        let mulc = |p: [f64; 2], q: [f64; 2]| [p[0] * q[0] - p[1] * q[1], p[0] * q[1] + p[1] * q[0]];
        for z in POINTS {
            let zq = (0..Q).fold([1.0, 0.0], |acc, _| mulc(acc, z));
            let s = mulc(a, mulc(z, z));
            let sign = if NEG { -1.0 } else { 1.0 };
            let want = [s[0] + sign * zq[0], s[1] + sign * zq[1]];
            let f = m.apply(z);
            let big = checks::parse(&m.apply_big(&BigC::from_f64(z[0], z[1], 200)));
            for k in 0..2 {
                let tol = 1e-13 * (1.0 + want[k].abs());
                assert!((f[k] - want[k]).abs() <= tol && (big[k] - want[k]).abs() <= tol, "{a:?} {z:?}");
            }
        }
    }

    fn check_all<const Q: u32, const NEG: bool>() {
        for a in COEFS {
            let m = Sum::<Q, NEG> { a };
            checks::check_delta(&m, &POINTS, &DELTAS, 4e-14);
            checks::check_jacobian(&m, &POINTS);
            check_value::<Q, NEG>(a);
        }
    }

    #[test]
    fn delta_jacobian_and_value_of_every_sum() {
        check_all::<3, false>();
        check_all::<3, true>();
        check_all::<4, false>();
        check_all::<4, true>();
        check_all::<5, false>();
        check_all::<5, true>();
        check_all::<6, false>();
        check_all::<6, true>();
    }

    /// Within the radius the step's nonlinear part is at most eps of its linear part, and
    /// at a critical point the radius is 0.
    #[test]
    fn the_radius_bounds_the_nonlinear_terms() {
        let eps = 1e-3;
        for a in COEFS {
            for (q, neg) in [(3, false), (3, true), (4, true), (6, false)] {
                for z in POINTS {
                    let r = bla_radius(q, neg, a, z, eps);
                    assert!(r > 0.0, "{a:?} {z:?}");
                    let dispatch = |d: [f64; 2]| -> ([f64; 2], [f64; 2]) {
                        let (full, jac) = match (q, neg) {
                            (3, false) => (Sum::<3, false> { a }.delta::<f64>(z, d), Sum::<3, false> { a }.jacobian(z)),
                            (3, true) => (Sum::<3, true> { a }.delta::<f64>(z, d), Sum::<3, true> { a }.jacobian(z)),
                            (4, true) => (Sum::<4, true> { a }.delta::<f64>(z, d), Sum::<4, true> { a }.jacobian(z)),
                            _ => (Sum::<6, false> { a }.delta::<f64>(z, d), Sum::<6, false> { a }.jacobian(z)),
                        };
                        let lin = [jac[0][0] * d[0] + jac[0][1] * d[1], jac[1][0] * d[0] + jac[1][1] * d[1]];
                        (full, lin)
                    };
                    for angle in 0..8 {
                        let t = angle as f64 * 0.785;
                        let d = [r * t.cos(), r * t.sin()];
                        let (full, lin) = dispatch(d);
                        let err = (full[0] - lin[0]).hypot(full[1] - lin[1]);
                        assert!(err <= eps * lin[0].hypot(lin[1]) * (1.0 + 1e-9), "{a:?} {z:?} {q} {neg}");
                    }
                }
            }
        }
        // 2 a z - 3 z² = 0 at z = 2a/3.
        let a = [0.9, -0.3];
        let c = [2.0 * a[0] / 3.0, 2.0 * a[1] / 3.0];
        assert!(bla_radius(3, true, a, c, eps) < 1e-15);
        // The big-float derivative is the Jacobian's complex number.
        let m = Sum::<5, true> { a };
        for z in POINTS {
            let j = m.jacobian(z);
            let g = checks::parse(&derivative_big(5, true, a, &BigC::from_f64(z[0], z[1], 200)));
            assert!((g[0] - j[0][0]).abs() <= 1e-13 * (1.0 + g[0].abs()), "{z:?}");
            assert!((g[1] - j[1][0]).abs() <= 1e-13 * (1.0 + g[1].abs()), "{z:?}");
        }
    }
}
