//! The perturbed step from a reference value f64 cannot stand for (a *wide* value, see
//! [`super::reference`]): f(Z + δ) - f(Z) with Z in FloatExp.
//!
//! [`crate::formula::map::Map::delta`] takes Z in f64, which is exact for almost every
//! reference value. Where a part of Z is nonzero below f64's range (a reference just off
//! the Burning Ship's real axis at depth: Im Z ~ 1e-400), its rounding to 0 loses the sign
//! that a fold's `diffabs` decides on, and where |Z| is so small that its powers underflow
//! the binomial expansion loses its linear term. This step is the same composition (fold,
//! power, fold, negation, as in `formula::map`) read from the phase's shape at run time and
//! evaluated wholly in FloatExp (a product family's, `formula::product`, and a sum's,
//! `formula::sum`, likewise): it runs only at the few wide indices of an orbit, where
//! interpreting the shape costs nothing that matters.

use crate::formula::Phase;
use crate::formula::kind::SumShape;
use crate::formula::map::{FOLD_IM, FOLD_RE, IM_BY_X, IM_BY_Y, SIGN_IM, SIGN_RE, binomial};
use crate::num::FloatExp;
use crate::num::real::{cadd, cmul};

/// |X + d| - |X| without cancellation (Claude Heiland-Allen's `diffabs`), X in FloatExp.
fn diffabs(x: FloatExp, d: FloatExp) -> FloatExp {
    let zero = FloatExp::ZERO;
    let s = x + d;
    if x >= zero {
        if s >= zero { d } else { -(d + x.ldexp(1)) }
    } else if s > zero {
        d + x.ldexp(1)
    } else {
        -d
    }
}

/// The delta of a signed fold of the imaginary part ([`IM_BY_X`], [`IM_BY_Y`] in `fold`):
/// s' |U + d| - s |U| for U = `u`, its delta `du`, and s, s' the signs of x, y or xy at Z
/// = `z` and at Z + `d` (`formula::map::signed_diffabs` in FloatExp).
fn signed_delta(fold: u8, z: [FloatExp; 2], d: [FloatExp; 2], u: FloatExp, du: FloatExp) -> FloatExp {
    let zero = FloatExp::ZERO;
    let negative = |v: [FloatExp; 2]| (fold & IM_BY_X != 0 && v[0] < zero) != (fold & IM_BY_Y != 0 && v[1] < zero);
    let (before, after) = (negative(z), negative([z[0] + d[0], z[1] + d[1]]));
    let (v, neg) = if before == after { (diffabs(u, du), before) } else { ((u + du).abs() + u.abs(), after) };
    if neg { -v } else { v }
}

/// Folds the parts `fold` names.
fn fold(fold: u8, z: [FloatExp; 2]) -> [FloatExp; 2] {
    [if fold & FOLD_RE != 0 { z[0].abs() } else { z[0] }, if fold & FOLD_IM != 0 { z[1].abs() } else { z[1] }]
}

/// The folded delta of the parts `fold` names, against the unfolded value `z`.
fn fold_delta(fold: u8, z: [FloatExp; 2], d: [FloatExp; 2]) -> [FloatExp; 2] {
    [
        if fold & FOLD_RE != 0 { diffabs(z[0], d[0]) } else { d[0] },
        if fold & FOLD_IM != 0 { diffabs(z[1], d[1]) } else { d[1] },
    ]
}

/// f(Z + d) - f(Z) for the map of `phase`, wholly in FloatExp; `u`: U = W^p from the big
/// floats where the reference has it (its signs decide a fold after the power), else
/// computed here.
pub(super) fn delta(phase: Phase, z: [FloatExp; 2], u: Option<[FloatExp; 2]>, d: [FloatExp; 2]) -> [FloatExp; 2] {
    if let Some(factors) = phase.kind.factors() {
        return product_delta(factors, z, u, d);
    }
    if let Some(shape) = phase.kind.sum() {
        return sum_delta(phase.a.get(), shape, z, d);
    }
    let (fin, p, fout, sign) = phase.kind.shape(phase.power);
    let dw = fold_delta(fin, z, d);
    let w = fold(fin, z);
    let (wp, raw) = power_delta(w, dw, p);
    let u = u.unwrap_or(wp);
    let mut du = fold_delta(fout, u, raw);
    if fout & (IM_BY_X | IM_BY_Y) != 0 {
        du[1] = signed_delta(fout, z, d, u[1], raw[1]);
    }
    match sign {
        SIGN_IM => [du[0], -du[1]],
        SIGN_RE => [-du[0], du[1]],
        _ => du,
    }
}

/// (W^p, (W + dw)^p - W^p), the difference by Horner's rule over the binomial expansion.
fn power_delta(w: [FloatExp; 2], dw: [FloatExp; 2], p: u32) -> ([FloatExp; 2], [FloatExp; 2]) {
    // Powers W^0 .. W^p.
    let mut pw = vec![[FloatExp::ONE, FloatExp::ZERO]];
    for k in 1..=p as usize {
        pw.push(cmul(pw[k - 1], w));
    }
    let mut t = [FloatExp::ONE, FloatExp::ZERO];
    for k in (1..p).rev() {
        let c = binomial(p, k);
        let a = pw[(p - k) as usize];
        t = cadd(cmul(t, dw), [a[0].mul_f64(c), a[1].mul_f64(c)]);
    }
    (pw[p as usize], cmul(t, dw))
}

/// f(Z + d) - f(Z) for the product family u^A (|Re u| + i|Im u|)^B, u = Z^PRE
/// (`formula::product`), by the product rule: dP (Q + dQ) + P dQ. `u`: u with the signs
/// the big floats give, where the reference has it.
fn product_delta(
    (pre, a, b): (u32, u32, u32),
    z: [FloatExp; 2],
    u: Option<[FloatExp; 2]>,
    d: [FloatExp; 2],
) -> [FloatExp; 2] {
    let (zp, du) = power_delta(z, d, pre);
    let u = u.unwrap_or(zp);
    let g = fold(FOLD_RE | FOLD_IM, u);
    let dg = fold_delta(FOLD_RE | FOLD_IM, u, du);
    let (p, dp) = power_delta(u, du, a);
    let (q, dq) = power_delta(g, dg, b);
    cadd(cmul(dp, cadd(q, dq)), cmul(p, dq))
}

/// f(Z + d) - f(Z) for the sum a W² ± W^Q, W = Z folded (`formula::sum`): a ((W + e)² -
/// W²) ± ((W + e)^Q - W^Q), e the folded delta, each difference by the binomial expansion.
fn sum_delta(a: [f64; 2], shape: SumShape, z: [FloatExp; 2], d: [FloatExp; 2]) -> [FloatExp; 2] {
    let SumShape { fold_in, q, neg } = shape;
    let (w, e) = (fold(fold_in, z), fold_delta(fold_in, z, d));
    let (_, s) = power_delta(w, e, 2);
    let (_, t) = power_delta(w, e, q);
    let s = cmul([FloatExp::from(a[0]), FloatExp::from(a[1])], s);
    if neg { [s[0] - t[0], s[1] - t[1]] } else { cadd(s, t) }
}

/// An f64 value with the signs of `v`'s parts (a part below f64's range becomes the least
/// normal f64 of its sign): what a Jacobian at `v` needs, whose folds read only signs where
/// a part is that small.
pub(super) fn signed_f64(v: [FloatExp; 2]) -> [f64; 2] {
    v.map(|x| {
        let f = x.to_f64();
        if f == 0.0 && !x.is_zero() { f64::MIN_POSITIVE.copysign(x.mantissa()) } else { f }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::Formula;
    use crate::num::bigcomplex::BigC;

    /// Against the difference of two big-float steps, at a value with a part far below
    /// f64's range, for families with folds before and after the power.
    #[test]
    fn the_wide_step_is_the_difference_of_two_big_float_steps() {
        let bits = 4000;
        for name in [
            "burning-ship",
            "buffalo^3",
            "celtic^4",
            "perpendicular-buffalo",
            "mandelbar^3",
            "mandelbrot^5",
            "cubic-quasi-perpendicular",
            "4th-celtic-false-quasi-heart",
            "4th-imag-quasi-perpendicular",
            "redshift-rider-1",
            "redshift-rider-9",
            "hpdz-buffalo",
        ] {
            let phase = Formula::parse(name, None).unwrap().with_a([-0.6, 1.1]).phases()[0];
            for (z, d) in [
                (
                    [FloatExp::from(-1.25), FloatExp::exp10(-400.0)],
                    [FloatExp::exp10(-420.0), FloatExp::exp10(-399.0).mul_f64(-3.0)],
                ),
                (
                    [FloatExp::exp10(-500.0), FloatExp::from(0.75)],
                    [FloatExp::exp10(-480.0).mul_f64(-1.0), FloatExp::exp10(-490.0)],
                ),
                (
                    [FloatExp::exp10(-300.0), FloatExp::exp10(-301.0).mul_f64(-2.0)],
                    [FloatExp::exp10(-302.0), FloatExp::exp10(-300.0)],
                ),
            ] {
                let got = delta(phase, z, None, d);
                let big = |v: [FloatExp; 2]| {
                    let f = |x: FloatExp| {
                        malachite_float::Float::from_primitive_float_prec(x.mantissa(), bits).0 << x.exponent()
                    };
                    BigC { re: f(v[0]), im: f(v[1]), bits }
                };
                let step = |v: &BigC| crate::with_map!(phase, m: M => m.apply_big(v), unreachable!());
                let want = step(&big(z).add(&big(d))).sub(&step(&big(z))).to_fe();
                let scale = want[0].abs().max(want[1].abs());
                for k in 0..2 {
                    let err = (got[k] - want[k]).abs();
                    assert!(err <= scale.mul_f64(1e-12), "{name} {z:?} {d:?}: {got:?} != {want:?}");
                }
            }
        }
    }
}
