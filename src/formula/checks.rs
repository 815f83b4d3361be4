//! Checks that every [`Map`] must pass, shared by the compositions' and the products' unit
//! tests: the perturbed step against the difference of two big-float steps, and the
//! Jacobian against central finite differences.

use super::map::Map;
use crate::num::bigcomplex::BigC;

/// The nearest f64s to a big-float complex number (through its decimal form, so that the
/// check does not lean on the conversions under test).
pub fn parse(b: &BigC) -> [f64; 2] {
    [b.re.to_string().parse().unwrap(), b.im.to_string().parse().unwrap()]
}

/// `M::delta` is f(z + d) - f(z) taken at 200 bits, for every z in `points` and d in
/// `deltas`, within 1e-13 of the result's size plus `rounding` times (|d| + 1): z + d is
/// rounded to f64 before the big-float step, so it is exact only to about 1e-16 of |z|.
pub fn check_delta<M: Map>(m: &M, points: &[[f64; 2]], deltas: &[[f64; 2]], rounding: f64) {
    for &z in points {
        for &d in deltas {
            let got = m.delta::<f64>(z, d);
            let want = m
                .apply_big(&BigC::from_f64(z[0] + d[0], z[1] + d[1], 200))
                .sub(&m.apply_big(&BigC::from_f64(z[0], z[1], 200)));
            let want = parse(&want);
            let tol = 1e-13 * (1.0 + want[0].abs().max(want[1].abs())) + rounding * (d[0].abs() + d[1].abs() + 1.0);
            assert!(
                (got[0] - want[0]).abs() <= tol && (got[1] - want[1]).abs() <= tol,
                "{z:?} {d:?}: {got:?} {want:?}"
            );
        }
    }
}

/// `M::jacobian` is the central finite difference of `M::apply` (step 1e-7) to 1e-5, at
/// every point of `points` (none of them on a fold line).
pub fn check_jacobian<M: Map>(m: &M, points: &[[f64; 2]]) {
    let h = 1e-7;
    for &z in points {
        let j = m.jacobian(z);
        for (col, e) in [[1.0, 0.0], [0.0, 1.0]].into_iter().enumerate() {
            let p = m.apply([z[0] + h * e[0], z[1] + h * e[1]]);
            let minus = m.apply([z[0] - h * e[0], z[1] - h * e[1]]);
            for row in 0..2 {
                let fd = (p[row] - minus[row]) / (2.0 * h);
                assert!(
                    (fd - j[row][col]).abs() < 1e-5 * (1.0 + fd.abs()),
                    "{z:?} [{row}][{col}] {fd} {}",
                    j[row][col]
                );
            }
        }
    }
}
