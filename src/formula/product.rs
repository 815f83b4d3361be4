//! The families that are a product of two maps rather than one composition: with u = z^PRE,
//! f(z) = u^A (|Re u| + i|Im u|)^B. Kalles Fraktaler's Mothbrot a×b (types 54 to 68) is
//! PRE = 1, z^a (|x| + i|y|)^b; its SimonBrot 4th and 6th (33, 40) are Mothbrot 2×2 and 3×3
//! under other names; its SimonBrot2 4th (51) is PRE = 2, A = B = 1: u (|Re u| + i|Im u|),
//! u = z². (`scripts/kf-product-families.py` checks these forms against KF's own lines.)
//!
//! The four things the engines need of a map ([`Map`]) follow from the product: the value
//! from the two factors P = u^A and Q = g^B, g = |Re u| + i|Im u|; the perturbed step by the
//! product rule, (P + dP)(Q + dQ) - PQ = dP (Q + dQ) + P dQ, where dP and dQ are the
//! binomial expansions of the factors' own deltas and the fold's delta is [`diffabs`]'s, so
//! nothing cancels; the Jacobian as (A u^(A-1) Q + P B g^(B-1) S) · PRE z^(PRE-1), complex
//! numbers as 2×2 matrices and S = diag(sgn Re u, sgn Im u) the fold's. It is not the
//! product of a complex number and a reflection, as every composition's is
//! (`formula::map`), but the sum of two such maps.

use super::map::{FOLD_BOTH, Map, Num, diffabs, fold, fold_big, nmul, power, power_delta, power_delta_n};
use super::phase::Phase;
use crate::num::bigcomplex::BigC;
use crate::num::real::{Real, cadd, cmul};

/// The product family u^A (|Re u| + i|Im u|)^B with u = z^PRE.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Product<const PRE: u32, const A: u32, const B: u32>;

/// n w^(n-1) for one sample or several in lanes: the complex derivative of w^n.
#[inline(always)]
pub(super) fn slope<N: Num>(n: u32, w: [N; 2]) -> [N; 2] {
    let mut a = [N::splat(1.0), N::splat(0.0)];
    for _ in 1..n {
        a = nmul(a, w);
    }
    let k = N::splat(n as f64);
    [a[0].mul(k), a[1].mul(k)]
}

impl<const PRE: u32, const A: u32, const B: u32> Map for Product<PRE, A, B> {
    const POWER: u32 = PRE * (A + B);
    const CONFORMAL: bool = false;

    #[inline(always)]
    fn of(_: &Phase) -> Self {
        Product
    }

    #[inline(always)]
    fn apply_n<N: Num>(&self, z: [N; 2]) -> [N; 2] {
        let u = power::<PRE, N>(z);
        nmul(power::<A, N>(u), power::<B, N>(fold(FOLD_BOTH, u)))
    }

    fn apply_big(&self, z: &BigC) -> BigC {
        let u = z.pow(PRE);
        u.pow(A).mul(&fold_big(FOLD_BOTH, u).pow(B))
    }

    #[inline(always)]
    fn delta<R: Real>(&self, z: [f64; 2], d: [R; 2]) -> [R; 2] {
        let u = power::<PRE, f64>(z);
        let du = if PRE == 1 { d } else { power_delta::<PRE, R>(z, d) };
        let g = fold(FOLD_BOTH, u);
        let dg = [diffabs(u[0], du[0]), diffabs(u[1], du[1])];
        let p = power::<A, f64>(u);
        let q = power::<B, f64>(g);
        let dp = if A == 1 { du } else { power_delta::<A, R>(u, du) };
        let dq = if B == 1 { dg } else { power_delta::<B, R>(g, dg) };
        let q_moved = cadd([R::from_f64(q[0]), R::from_f64(q[1])], dq);
        cadd(cmul(dp, q_moved), cmul([R::from_f64(p[0]), R::from_f64(p[1])], dq))
    }

    #[inline(always)]
    fn delta_n<N: Num>(&self, z: [N; 2], d: [N; 2]) -> [N; 2] {
        let u = power::<PRE, N>(z);
        let du = if PRE == 1 { d } else { power_delta_n::<PRE, N>(z, d) };
        let g = fold(FOLD_BOTH, u);
        let dg = [u[0].diffabs(du[0]), u[1].diffabs(du[1])];
        let p = power::<A, N>(u);
        let q = power::<B, N>(g);
        let dp = if A == 1 { du } else { power_delta_n::<A, N>(u, du) };
        let dq = if B == 1 { dg } else { power_delta_n::<B, N>(g, dg) };
        let q_moved = [q[0].add(dq[0]), q[1].add(dq[1])];
        let a = nmul(dp, q_moved);
        let b = nmul(p, dq);
        [a[0].add(b[0]), a[1].add(b[1])]
    }

    #[inline(always)]
    fn jacobian_n<N: Num>(&self, z: [N; 2]) -> [[N; 2]; 2] {
        let u = power::<PRE, N>(z);
        let g = fold(FOLD_BOTH, u);
        // d f / d u = mat(α) + mat(β) S: α = A u^(A-1) Q, β = P B g^(B-1).
        let alpha = nmul(slope::<N>(A, u), power::<B, N>(g));
        let beta = nmul(power::<A, N>(u), slope::<N>(B, g));
        let (sx, sy) = (u[0].sgn(), u[1].sgn());
        let m = [
            [alpha[0].add(beta[0].mul(sx)), alpha[1].neg().sub(beta[1].mul(sy))],
            [alpha[1].add(beta[1].mul(sx)), alpha[0].add(beta[0].mul(sy))],
        ];
        if PRE == 1 {
            return m;
        }
        // Times du / dz = mat(PRE z^(PRE-1)).
        let e = slope::<N>(PRE, z);
        [
            [m[0][0].mul(e[0]).add(m[0][1].mul(e[1])), m[0][1].mul(e[0]).sub(m[0][0].mul(e[1]))],
            [m[1][0].mul(e[0]).add(m[1][1].mul(e[1])), m[1][1].mul(e[0]).sub(m[1][0].mul(e[1]))],
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::checks;

    type Moth11 = Product<1, 1, 1>;
    type Moth23 = Product<1, 2, 3>;
    type Moth51 = Product<1, 5, 1>;
    type Simon2 = Product<2, 1, 1>;

    const POINTS: [[f64; 2]; 7] =
        [[0.3, -0.7], [-1.1, 0.2], [0.05, 0.9], [-0.4, -0.35], [1.3, 1e-3], [-2e-3, 0.6], [0.5, -0.52]];

    /// The deltas include one that crosses a fold line of u.
    const DELTAS: [[f64; 2]; 5] = [[1e-3, -2e-3], [-0.5, 0.1], [2e-9, 7e-9], [-0.31, 0.8], [0.0, 1.4]];

    fn check_delta<M: Map + Default>() {
        checks::check_delta(&M::default(), &POINTS, &DELTAS, 1e-14);
    }

    fn check_jacobian<M: Map + Default>() {
        checks::check_jacobian(&M::default(), &POINTS);
    }

    /// The f64 map against the big-float one, and both against the product written out
    /// with std's complex-free arithmetic: z^a by repeated products, (|x| + i|y|)^b likewise.
    fn check_value<M: Map + Default>(pre: u32, a: u32, b: u32) {
        let mulc = |p: [f64; 2], q: [f64; 2]| [p[0] * q[0] - p[1] * q[1], p[0] * q[1] + p[1] * q[0]];
        let pow = |w: [f64; 2], n: u32| (0..n).fold([1.0, 0.0], |acc, _| mulc(acc, w));
        for z in POINTS {
            let u = pow(z, pre);
            let want = mulc(pow(u, a), pow([u[0].abs(), u[1].abs()], b));
            let f = M::default().apply(z);
            let big = checks::parse(&M::default().apply_big(&BigC::from_f64(z[0], z[1], 200)));
            for k in 0..2 {
                let tol = 1e-13 * (1.0 + want[k].abs());
                assert!(
                    (f[k] - want[k]).abs() <= tol && (big[k] - want[k]).abs() <= tol,
                    "{z:?}: {f:?} {big:?} {want:?}"
                );
            }
        }
    }

    #[test]
    fn delta_is_the_difference_of_two_steps() {
        check_delta::<Moth11>();
        check_delta::<Moth23>();
        check_delta::<Moth51>();
        check_delta::<Simon2>();
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        check_jacobian::<Moth11>();
        check_jacobian::<Moth23>();
        check_jacobian::<Moth51>();
        check_jacobian::<Simon2>();
    }

    #[test]
    fn values_are_the_written_out_products() {
        check_value::<Moth11>(1, 1, 1);
        check_value::<Moth23>(1, 2, 3);
        check_value::<Moth51>(1, 5, 1);
        check_value::<Simon2>(2, 1, 1);
        assert_eq!(Moth23::POWER, 5);
        assert_eq!(Simon2::POWER, 4);
    }
}
