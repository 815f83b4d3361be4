//! Finding locations for every formula family and hybrid (Mandelbrot form): the
//! lowest-period mini in a view (its period by the ball method extended to the family's
//! map, its nucleus by Newton's method on the real 2×2 system z_p(c) = 0, its size and
//! orientation from the cycle) and, for the Mandelbrot family at any power, the simplest
//! Misiurewicz point.
//!
//! The search is z² + c's ([`crate::locate::search`]) with each part made generic: the
//! periods are bounded as for z² + c ([`crate::locate::period`] serves every formula),
//! [`nucleus`] solves for the nucleus with the Jacobian by
//! forward-mode derivatives in big floats ([`step`]), and the same periods are tried in the
//! same order within the same budget. z² + c keeps its own code (`find` calls it for that
//! formula, so its output is unchanged); the generic code reduces to it at power 2, which
//! the tests check.

pub mod misiurewicz;
pub mod nucleus;
pub mod step;

use super::period;
// The later periods are tried as z² + c's search tries them, within the same budget (an
// iteration here, with its two tangents, is counted 4 times).
use super::search::{MORE_NEWTON_STEPS, MORE_PERIODS, MORE_WORK, upward_top};
use crate::formula::Formula;
use crate::num::FloatExp;
use crate::num::bigcomplex::BigC;

pub use nucleus::{Mini, Newton};

/// A Misiurewicz point found in a view.
#[derive(Debug, Clone, PartialEq)]
pub struct MisiurewiczPoint {
    /// The point.
    pub point: BigC,
    /// Preperiod k.
    pub preperiod: u32,
    /// Period p.
    pub period: u32,
}

/// Why a search of a formula's view found nothing, or was not made.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FindError {
    /// No nucleus of period up to the limit lies in the view.
    #[error("no mini of period up to {max_period} lies in this view (zoom in, or raise --max-period)")]
    NoPeriod {
        /// The largest period tried.
        max_period: u32,
    },
    /// Newton's method reached no nucleus in the view.
    #[error(
        "Newton's method from the view's centre reached no mini inside the view (the ball method puts the lowest period there at {period} or more){}: move the centre closer to one, or zoom in",
        if *singular { "; at some periods the Jacobian of z_p in c was singular, where Newton's method has no step" } else { "" }
    )]
    NoNucleus {
        /// The ball method's period.
        period: u32,
        /// Some try stopped at a singular Jacobian.
        singular: bool,
    },
    /// No Misiurewicz point within the limits lies in the view.
    #[error(
        "no Misiurewicz point of preperiod up to {max_preperiod} and period up to {max_period} lies in this view (raise --max-preperiod or --max-period, or move the centre closer)"
    )]
    NoMisiurewicz {
        /// The largest preperiod tried.
        max_preperiod: u32,
        /// The largest period tried.
        max_period: u32,
    },
    /// Misiurewicz points are searched for the Mandelbrot family alone.
    #[error(
        "find --misiurewicz searches the Mandelbrot family (mandelbrot at powers 2 to 10, one power at a time), whose maps are conformal; {formula} is {why}"
    )]
    NotConformal {
        /// The formula, as written.
        formula: String,
        /// What it is instead.
        why: &'static str,
    },
}

/// Newton's steps from the centre for the ball method's period.
const NEWTON_STEPS: u32 = 200;
/// How far Newton's method may stray, in radii of the view.
const LEASH: f64 = 16.0;

/// Newton's method for `period` from `center`, on a leash, as a mini inside the disc; with
/// the steps taken, and whether it stopped at a singular Jacobian.
fn attempt(formula: Formula, center: &BigC, radius: FloatExp, period: u32, steps: u32) -> (Option<Mini>, u32, bool) {
    let (end, taken) = nucleus::newton(formula, center, period, steps, Some(radius.mul_f64(LEASH)));
    match end {
        Newton::Root(c) => (nucleus::refined(formula, c, center, period, Some(radius)), taken, false),
        Newton::Singular => (None, taken, true),
        Newton::Lost => (None, taken, false),
    }
}

/// The lowest-period mini of `formula` whose nucleus lies within `radius` of `center`, as
/// far as Newton's method from the centre reaches: the ball method's period, then the
/// periods above it (up to 8 times it, at least 64), then the later periods of the centre's
/// atom domains, within a fixed budget of big-float work, as
/// [`crate::locate::search::minibrot_in_view`] tries them for z² + c.
pub fn minibrot_in_view(formula: Formula, center: &BigC, radius: FloatExp, max_period: u32) -> Result<Mini, FindError> {
    let p = period::ball_period(formula, center, radius, max_period).ok_or(FindError::NoPeriod { max_period })?;
    let (m, _, mut singular) = attempt(formula, center, radius, p, NEWTON_STEPS);
    if let Some(m) = m {
        return Ok(m);
    }
    let mut left = MORE_WORK;
    let mut more = |q: u32| {
        let cost = 4 * u64::from(q) * (center.bits.max(128) / 128);
        let steps = MORE_NEWTON_STEPS.min(u32::try_from(left / cost.max(1)).unwrap_or(u32::MAX));
        if steps == 0 {
            return None;
        }
        let (m, taken, s) = attempt(formula, center, radius, q, steps);
        left -= u64::from(taken) * cost;
        singular |= s;
        m
    };
    let top = upward_top(p, max_period);
    let found = (p + 1..=top).find_map(&mut more);
    let found = found.or_else(|| {
        period::atom_periods(formula, center, top, max_period, MORE_PERIODS).into_iter().find_map(&mut more)
    });
    found.ok_or(FindError::NoNucleus { period: p, singular })
}

/// Whether `formula` is one [`misiurewicz_in_view`] searches: a single phase of the
/// Mandelbrot family.
pub fn check_conformal(formula: Formula) -> Result<(), FindError> {
    let why = if !formula.is_conformal() {
        "not conformal (its folds or the negation of one part make its derivative a real 2x2 matrix, and its preperiodic parameters are not isolated points in general)"
    } else if formula.phases().len() > 1 {
        "a hybrid (its phases shift along the orbit, so z^d's symmetry that the candidates use does not hold)"
    } else if formula.phases()[0].kind.sum().is_some() {
        "a sum a z^2 ± z^q (it lacks z^d's symmetry, which the candidates use)"
    } else {
        return Ok(());
    };
    Err(FindError::NotConformal { formula: formula.to_string(), why })
}

/// Limits for a Misiurewicz search when none are given: z² + c's rule
/// ([`crate::locate::search::misiurewicz_limits`]) with the formula's ball period.
pub fn misiurewicz_limits(formula: Formula, center: &BigC, radius: FloatExp) -> (u32, u32) {
    let max = crate::locate::search::MAX_AUTO_PERIOD;
    let p = period::ball_period(formula, center, radius, max).unwrap_or(max);
    (p.saturating_mul(2).clamp(5000, 2 * max), p.clamp(64, max))
}

/// Candidates tried by Newton's method before giving up.
const MAX_NEWTON_TRIES: usize = 24;
/// Bits beyond the view's and the candidate's derivative given to Newton's method.
const NEWTON_MARGIN_BITS: u64 = 64;

/// The simplest Misiurewicz point (smallest preperiod + period) of a Mandelbrot-family
/// `formula` within `radius` of `center` ([`misiurewicz`] module docs).
pub fn misiurewicz_in_view(
    formula: Formula,
    center: &BigC,
    radius: FloatExp,
    max_preperiod: u32,
    max_period: u32,
) -> Result<MisiurewiczPoint, FindError> {
    check_conformal(formula)?;
    let mut near = misiurewicz::candidates(formula, center, radius, max_preperiod, max_period);
    near.sort_by_key(|c| (c.preperiod + c.period, c.period));
    let root = |c: &misiurewicz::Candidate| {
        let (k, p) = (c.preperiod, c.period);
        let bits = center.bits + c.log2_derivative.max(0.0).ceil() as u64 + NEWTON_MARGIN_BITS;
        let point = misiurewicz::newton(formula, &center.with_bits(bits), k, p, 64)?;
        if point.sub(center).abs() > radius {
            return None;
        }
        let (preperiod, period) = misiurewicz::orbit_type(formula, &point, k, p).filter(|&(k, _)| k >= 2)?;
        Some(MisiurewiczPoint { point, preperiod, period })
    };
    near.iter().take(MAX_NEWTON_TRIES).find_map(root).ok_or(FindError::NoMisiurewicz { max_preperiod, max_period })
}

#[cfg(test)]
mod tests {
    use malachite_float::Float;

    use super::*;
    use crate::compare::kf_maps::{Dual, kf_step_dual};
    use crate::formula::{Kind, Phase};

    fn formula(kind: Kind, power: u32) -> Formula {
        Formula::single(Phase::new(kind, power))
    }

    /// The first-order distances |J_n⁻¹ z_n| from `c` to a root of z_n = 0, n = 1 ..= p, by
    /// Kalles Fraktaler's expansions in big floats with the Jacobian by dual numbers
    /// (`compare::kf_maps`, which shares no code with the engines' maps or with Newton's
    /// method here); None for an n where J_n is singular.
    fn distances(f: Formula, c: &BigC, p: u32) -> Vec<Option<FloatExp>> {
        let bits = c.bits;
        let cd = [Dual::variable(c.re.clone(), 0), Dual::variable(c.im.clone(), 1)];
        let zero = || Dual::constant(Float::from(0u32));
        let mut z = [zero(), zero()];
        let fe = crate::num::bigfloat::to_floatexp;
        (0..p)
            .map(|n| {
                z = kf_step_dual(f.phase(n), &z, &cd, bits).expect("a KF formula").z;
                let [x, y] = [&z[0], &z[1]];
                let (a, b, cc, d) = (fe(&x.d[0]), fe(&x.d[1]), fe(&y.d[0]), fe(&y.d[1]));
                let det = a * d - b * cc;
                if det.is_zero() {
                    return None;
                }
                let (vx, vy) = (fe(&x.v), fe(&y.v));
                let (sx, sy) = ((d * vx - b * vy) / det, (a * vy - cc * vx) / det);
                Some((sx * sx + sy * sy).sqrt())
            })
            .collect()
    }

    /// Checks a mini found in the disc (`center`, `radius`) by its own orbit under KF's
    /// formulas: inside the disc; z_p a root to far below the mini's size; and no earlier
    /// z_n one (each first-order distance above the size): the period is the lowest.
    fn check(f: Formula, center: &BigC, radius: FloatExp, m: &Mini) {
        assert!(m.nucleus.sub(center).abs() <= radius, "{f}: outside the view");
        let d = distances(f, &m.nucleus, m.period);
        let last = d[m.period as usize - 1].expect("J_p invertible");
        assert!(last < m.size.mul_f64(1e-12), "{f} period {}: |J⁻¹ z_p| {last:?}, size {:?}", m.period, m.size);
        for (n, dn) in d[..m.period as usize - 1].iter().enumerate() {
            let dn = dn.unwrap_or(FloatExp::from(f64::INFINITY));
            assert!(dn > m.size, "{f}: z_{} nearly 0 ({dn:?}) at a nucleus of period {}", n + 1, m.period);
        }
    }

    fn fixed(re: f64, im: f64, r: f64) -> (BigC, FloatExp) {
        (BigC::from_f64(re, im, 128), FloatExp::from(r))
    }

    /// Views from boundary descents (the fuzzer's, seeded) to 1e5 and 1e7: whatever mini
    /// the search finds there is checked; every family finds at least one.
    fn descended(f: Formula) -> Vec<(BigC, FloatExp)> {
        use crate::compare::boundary::descend;
        use crate::compare::views::Rng;
        let mut out = Vec::new();
        for seed in 1..=4 {
            let mut rng = Rng::new(seed);
            let start = BigC::from_f64(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), 64);
            let depth = if seed % 2 == 0 { 5.0 } else { 7.0 };
            if let Some(v) = descend(&mut rng, f, None, start, FloatExp::from(1.5), depth, 20_000) {
                out.push((
                    v.center.with_bits(crate::num::bigfloat::precision_for(-depth - 2.0)),
                    v.radius.mul_f64(2.0),
                ));
            }
        }
        out
    }

    fn search(f: Formula, views: &[(BigC, FloatExp)]) -> usize {
        let mut found = 0;
        for (c, r) in views {
            match minibrot_in_view(f, c, *r, 100_000) {
                Ok(m) => {
                    check(f, c, *r, &m);
                    found += 1;
                }
                Err(e) => assert!(matches!(e, FindError::NoNucleus { .. } | FindError::NoPeriod { .. }), "{f}: {e}"),
            }
        }
        found
    }

    #[test]
    fn nuclei_of_the_folded_families_are_periodic_points_of_the_lowest_period() {
        for (kind, power) in [(Kind::BurningShip, 2), (Kind::Mandelbar, 2), (Kind::Celtic, 2), (Kind::Mandelbrot, 3)] {
            let f = formula(kind, power);
            let mut views = vec![fixed(-1.752, 0.0005, 0.01)];
            if power == 3 {
                views = vec![fixed(0.34, 1.27, 0.07), fixed(0.0, 0.9, 0.2)];
            }
            let found = search(f, &views);
            assert_eq!(found, views.len(), "{f}: the fixed views hold a mini");
            let found = search(f, &descended(f));
            assert!(found >= 1, "{f}: no mini in any descended view");
        }
    }

    /// A sum a z² ± z^q with a complex a: the minis found in descended views are periodic
    /// points of their period (`check`, by KF's own expansion), and its Misiurewicz points
    /// are refused by name.
    #[test]
    fn nuclei_of_a_sum_with_a_coefficient() {
        let f = Formula::parse("redshift-rider-2", None).unwrap().with_a([0.8, 0.3]);
        let found = search(f, &descended(f));
        assert!(found >= 1, "{f}: no mini in any descended view");
        assert!(matches!(check_conformal(f), Err(FindError::NotConformal { .. })));
    }

    /// |z_(k+p) - z_k| / |z'_(k+p) - z'_k| for every k + p <= n, by KF's expansions in dual
    /// numbers (the derivative along a, the complex derivative of a conformal map): the
    /// first-order distances from c to roots of z_(k+p) = z_k.
    fn misiurewicz_distances(f: Formula, c: &BigC, n: u32) -> Vec<Vec<FloatExp>> {
        let bits = c.bits;
        let cd = [Dual::variable(c.re.clone(), 0), Dual::variable(c.im.clone(), 1)];
        let zero = || Dual::constant(Float::from(0u32));
        let mut z = [zero(), zero()];
        let mut orbit = vec![BigC::zero(bits)];
        let mut slope = vec![BigC::zero(bits)];
        for i in 0..n {
            z = kf_step_dual(f.phase(i), &z, &cd, bits).expect("a KF formula").z;
            orbit.push(BigC { re: z[0].v.clone(), im: z[1].v.clone(), bits });
            slope.push(BigC { re: z[0].d[0].clone(), im: z[1].d[0].clone(), bits });
        }
        (0..n as usize)
            .map(|k| {
                (1..=n as usize - k)
                    .map(|p| orbit[k + p].sub(&orbit[k]).abs() / slope[k + p].sub(&slope[k]).abs())
                    .collect()
            })
            .collect()
    }

    /// A Misiurewicz point of the Mandelbrot family at power 3 or 4, found in a view, is by
    /// KF's own iteration a root of z_(k+p) = z_k to its precision, and of no z_(k'+p') =
    /// z_k' with k' <= k, p' <= p and (k', p') lower.
    #[test]
    fn misiurewicz_points_of_higher_powers_have_exactly_their_preperiod_and_period() {
        // Beside roots of (c^d + c)^d + c = c^d + c and z_4 = z_3 (numpy's roots of the
        // polynomials): (2, 1) and (3, 1) at powers 3 and 4, unless the search finds a simpler
        // point in the view; whatever it finds is checked.
        let views = [(3, 0.345, 1.275, 0.05), (3, -0.712, 0.515, 0.03), (4, 0.295, 1.08, 0.05), (4, -1.14, 0.27, 0.02)];
        let mut found = 0;
        for (power, re, im, r) in views {
            let f = formula(Kind::Mandelbrot, power);
            let (c, r) = fixed(re, im, r);
            let Ok(m) = misiurewicz_in_view(f, &c, r, 200, 40) else { continue };
            found += 1;
            assert!(m.point.sub(&c).abs() <= r);
            let (k, p) = (m.preperiod as usize, m.period as usize);
            assert!(k >= 2, "{f}: preperiod {k}");
            let d = misiurewicz_distances(f, &m.point, (k + p) as u32);
            let root = FloatExp::new(1.0, 32 - m.point.bits as i32);
            assert!(d[k][p - 1] < root, "{f} ({k}, {p}): {:?}", d[k][p - 1]);
            for kk in 0..=k {
                for pp in 1..=p {
                    if (kk, pp) != (k, p) {
                        assert!(d[kk][pp - 1] > FloatExp::from(1e-20), "{f} ({k}, {p}) is also ({kk}, {pp})");
                    }
                }
            }
        }
        assert!(found >= 3, "{found} of the views hold a Misiurewicz point");
        // The folded families and hybrids are refused by name.
        let e = misiurewicz_in_view(formula(Kind::BurningShip, 2), &BigC::zero(128), FloatExp::ONE, 10, 10);
        assert!(matches!(&e, Err(FindError::NotConformal { formula, .. }) if formula == "burning-ship"), "{e:?}");
        let hybrid = Formula::parse("mandelbrot,mandelbrot^3", None).unwrap();
        assert!(matches!(check_conformal(hybrid), Err(FindError::NotConformal { .. })));
    }
}
