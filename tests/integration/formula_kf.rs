//! Every row of the table of formula families is Kalles Fraktaler's formula: for each
//! (family, power) of `formula::kind::KINDS`, the composed map (`formula::map::Ops`, through
//! `with_map!`) against `compare::kf_maps`, which writes KF 2.15's reference lines term by
//! term, at a grid of points with parts exactly zero, negative and of mixed sizes:
//!
//! - f64 (`M::apply`): within 1e-14 of the terms' size, (|x| + |y|)^p (plus |a| (|x| + |y|)²
//!   for a sum a z² ± z^p), of the exact value
//!   (KF's expansion at 4000 bits, where every operation on these inputs is exact);
//! - big floats at 200 bits (`M::apply_big`), at inputs that are not f64 values: within a
//!   few units of the 200th bit of the terms' size of the exact value, as KF's expansion
//!   at 200 bits is;
//! - c enters as KF adds it (`+ Cr`, `Ci - ...`): the expansion with c is the one without,
//!   plus c, exactly;
//! - the Jacobian (`M::jacobian`) against the expansion's, differentiated term by term,
//!   within 1e-14 of its size p (|x| + |y|)^(p-1), wherever no fold's argument is exactly
//!   zero (a kink: the map has no derivative there, and the two may take different
//!   one-sided ones).

use deepfield::compare::kf_maps::{kf_jacobian, kf_step};
use deepfield::formula::Phase;
use deepfield::formula::kind::KINDS;
use deepfield::formula::map::Map;
use deepfield::num::bigcomplex::BigC;
use malachite_float::Float;

/// Parts of the points: zero, negative and positive, small and large, and the ±1 where
/// |x| = |y| puts Buffalo's and Celtic's folds of Re z² at zero.
const PARTS: [f64; 11] = [0.0, 0.3, -0.3, 1.0, -1.0, 1.1, -0.75, 0.05, -1.9, 1e-5, -2.5e-3];

/// Exact at these inputs: 200-bit parts to the 10th power need 2000 bits, and the
/// coefficients and sums a few more.
const EXACT: u64 = 4000;

fn big(x: f64) -> Float {
    Float::from_primitive_float_prec(x, 64).0
}

fn to_f64(x: &Float) -> f64 {
    deepfield::num::bigfloat::to_floatexp(x).to_f64()
}

/// |a - b| as an f64.
fn gap(a: &Float, b: &Float) -> f64 {
    to_f64(&a.sub_prec_ref_ref(b, EXACT).0).abs()
}

/// A 200-bit value near x that is no f64 (zero stays zero).
fn widen(x: f64, k: u32) -> Float {
    let x = big(x);
    let tail = x.mul_prec_ref_val(big(f64::from(k) * 0.123_456_789 + 0.1), 200).0 >> 70u32;
    x.add_prec(tail, 200).0
}

fn points() -> Vec<[f64; 2]> {
    PARTS.iter().flat_map(|&x| PARTS.iter().map(move |&y| [x, y])).collect()
}

/// Checks one (family, power); returns (worst big-float error in units of 2^-200 of the
/// terms' size, points whose Jacobian was compared).
fn check<M: Map>(phase: Phase) -> (f64, usize) {
    let map = M::of(&phase);
    let p = phase.power as i32;
    let zero = Float::from(0u32);
    let (mut worst, mut compared) = (0.0f64, 0);
    for (k, z) in points().into_iter().enumerate() {
        // The terms' size: (|x| + |y|)^p, and for a sum a W² ± W^q, |a| (|x| + |y|)² + (|x| +
        // |y|)^q.
        let t = z[0].abs() + z[1].abs();
        let (a, q) = match phase.kind.sum() {
            Some(s) => (phase.a.get()[0].hypot(phase.a.get()[1]), s.q as i32),
            None => (0.0, p),
        };
        let size = t.powi(p) + a * t * t + t.powi(q);
        let (x, y) = (big(z[0]), big(z[1]));
        // f64 against the exact value.
        let exact = kf_step(phase, [&x, &y], [&zero, &zero], EXACT).expect("a row of KINDS");
        let got = map.apply(z);
        for i in 0..2 {
            let e = (got[i] - to_f64(&exact[i])).abs();
            assert!(e <= 1e-14 * size, "{phase} f64 at {z:?}: {got:?}, KF {:?}", exact.clone().map(|v| to_f64(&v)));
        }
        // c enters as KF adds it.
        let c = [big(-0.75 + 0.01 * k as f64), big(0.125 - 0.02 * k as f64)];
        let with_c = kf_step(phase, [&x, &y], [&c[0], &c[1]], EXACT).expect("a row of KINDS");
        for i in 0..2 {
            assert_eq!(with_c[i], exact[i].add_prec_ref_ref(&c[i], EXACT).0, "{phase}: c at {z:?}");
        }
        // Big floats at 200 bits, at inputs that are not f64 values.
        let (wx, wy) = (widen(z[0], 2 * k as u32), widen(z[1], 2 * k as u32 + 1));
        let exact = kf_step(phase, [&wx, &wy], [&zero, &zero], EXACT).expect("a row of KINDS");
        let kf200 = kf_step(phase, [&wx, &wy], [&zero, &zero], 200).expect("a row of KINDS");
        let ours = map.apply_big(&BigC { re: wx.clone(), im: wy.clone(), bits: 200 });
        let ulp = size * 2f64.powi(-200);
        for (i, o) in [ours.re, ours.im].iter().enumerate() {
            let (e, e_kf) = (gap(o, &exact[i]), gap(&kf200[i], &exact[i]));
            if size > 0.0 {
                worst = worst.max(e / ulp);
            }
            assert!(e <= 8.0 * ulp, "{phase} big at {z:?}: {} ulps of the terms (KF's own: {})", e / ulp, e_kf / ulp);
            assert!(e_kf <= 8.0 * ulp, "{phase} KF's expansion at 200 bits at {z:?}");
        }
        // The Jacobian, where it exists.
        let j = kf_jacobian(phase, [&x, &y], EXACT).expect("a row of KINDS");
        if j.kink {
            continue;
        }
        compared += 1;
        let ours = map.jacobian(z);
        let dsize = p as f64 * t.powi(p - 1) + 2.0 * a * t + q as f64 * t.powi(q - 1);
        for r in 0..2 {
            for s in 0..2 {
                let want = to_f64(&j.m[r][s]);
                assert!(
                    (ours[r][s] - want).abs() <= 1e-14 * dsize,
                    "{phase} Jacobian [{r}][{s}] at {z:?}: {} vs KF {want}",
                    ours[r][s]
                );
            }
        }
    }
    (worst, compared)
}

#[test]
fn every_row_of_kinds_is_kalles_fraktalers_formula() {
    let mut rows = 0;
    for k in KINDS {
        for power in k.min_power..=k.max_power {
            // The user's coefficient a (KF's FactorAR, FactorAI) at its default and others.
            let coefs: &[[f64; 2]] =
                if k.kind.takes_a() { &[[1.0, 0.0], [-0.6, 0.45], [0.0, 2.5]] } else { &[[1.0, 0.0]] };
            for &a in coefs {
                let phase = Phase::new(k.kind, power).with_a(a);
                let (worst, compared) =
                    deepfield::with_map!(phase, M => check::<M>(phase), panic!("{phase} has no compiled map"));
                eprintln!(
                    "{phase} a = {a:?} (KF type {}): worst {worst:.2} ulps at 200 bits, Jacobian at {compared} points",
                    k.kf_type
                );
                assert!(compared >= points().len() / 3, "{phase}: only {compared} points without a kink");
            }
            rows += 1;
        }
    }
    // Types 0 to 4 (by power), 5-9, 10-13, 15-22, 27-30, then the quasi families 14, 23-26,
    // 31-32 and 34-39, then the products 33, 40, 51 and 54-68, then the sums 41-50.
    assert_eq!(rows, 9 + 4 * 4 + 5 + 4 + 8 + 4 + 1 + 4 + 2 + 6 + 18 + 10);
}
