//! Minibrots: the nucleus of a given period by Newton's method in big floats, and the
//! minibrot's size and orientation for framing it.
//!
//! A nucleus of period p is a root of z_p(c) = 0 (z_0 = 0, z_(n+1) = z_n^2 + c); Newton's
//! step is c <- c - z_p / z_p' with z_(n+1)' = 2 z_n z_n' + 1. The size and orientation come
//! from Claude Heiland-Allen's size estimate ("Minibrot size estimates"): with
//! l_n = prod_(k=1..n) 2 z_k and b = 1 + sum_(n=1..p-1) 1 / l_n, the complex number
//! 1 / (b l_(p-1)^2) has the minibrot's radius (half the distance from the nucleus to its
//! cusp, roughly) as modulus and the rotation of its cusp as argument.

use crate::num::FloatExp;

use crate::num::bigcomplex::BigC;

/// A minibrot found: its nucleus, period and size.
#[derive(Debug, Clone, PartialEq)]
pub struct Minibrot {
    /// The nucleus (z_p = 0 to the working precision).
    pub nucleus: BigC,
    /// Its period.
    pub period: u32,
    /// |size|: the scale of the minibrot in the plane.
    pub size: FloatExp,
    /// The direction of its cusp (the size estimate's argument), in radians.
    pub angle: f64,
}

/// Newton's method for the nucleus of period `period` from `start`, at `start`'s precision.
/// Returns the nucleus when the steps converge (the last step below 2^(16 - bits) relative)
/// within `max_steps`; None otherwise.
pub fn newton(start: &BigC, period: u32, max_steps: u32) -> Option<BigC> {
    newton_leashed(start, period, max_steps, None).0
}

/// [`newton`], giving up once an iterate is farther than `leash` from `start`; with the
/// number of steps it took.
fn newton_leashed(start: &BigC, period: u32, max_steps: u32, leash: Option<FloatExp>) -> (Option<BigC>, u32) {
    let bits = start.bits;
    let mut c = start.clone();
    let one = BigC::from_f64(1.0, 0.0, bits);
    let tolerance = FloatExp::new(1.0, 16 - bits as i32);
    for taken in 1..=max_steps {
        let (mut z, mut dz) = (BigC::zero(bits), BigC::zero(bits));
        for _ in 0..period {
            (z, dz) = c.orbit_step((&z, &dz), &one);
        }
        if dz.abs().is_zero() {
            return (None, taken);
        }
        let step = z.div(&dz);
        c = c.sub(&step);
        let scale = FloatExp::ONE.max(c.abs());
        if step.abs() <= tolerance * scale {
            return (Some(c), taken);
        }
        // Diverged (or NaN: then the comparison is false too).
        if c.abs().partial_cmp(&FloatExp::from(4.0)) != Some(std::cmp::Ordering::Less) {
            return (None, taken);
        }
        if leash.is_some_and(|l| c.sub(start).abs() > l) {
            return (None, taken);
        }
    }
    (None, max_steps)
}

/// A complex number as its modulus and argument (radians). Both parts are divided by the
/// modulus before the argument is taken: at depth they lie far below f64's range, where
/// they would round to zeros and the argument to 0 or ±π.
fn polar(s: [FloatExp; 2]) -> (FloatExp, f64) {
    let modulus = (s[0] * s[0] + s[1] * s[1]).sqrt();
    (modulus, (s[1] / modulus).to_f64().atan2((s[0] / modulus).to_f64()))
}

/// The complex size estimate of the minibrot whose nucleus is `c` (period `period`).
pub fn size(c: &BigC, period: u32) -> [FloatExp; 2] {
    let mut z = BigC::zero(c.bits);
    crate::orbit::interior::size_estimate((1..period).map(|_| {
        z = z.square().add(c);
        z.to_fe()
    }))
}

/// Newton's steps from a start before [`minibrot`] gives up.
const NEWTON_STEPS: u32 = 200;

/// The smallest proper divisor n of `period` for which `c`, a root of z_period = 0 to
/// Newton's tolerance, is a root of z_n = 0 as well: a nucleus of the lower period n. Newton's
/// method for period p converges to any nucleus whose period divides p (z_n = 0 makes
/// z_kn = 0), 0 itself (the main cardioid's) for every p, and from a start near a cusp or
/// a bulb's root it often does. Told by Newton's step for period n at c, |z_n / z_n'|: at
/// a nucleus of period n it is of the size of the rounding that [`newton`] converged to
/// (allowed 2^16 times that), at a nucleus of period exactly p the first-order distance to
/// a nucleus of period n, many orders of magnitude larger. None where c's period is
/// `period` itself.
pub fn lower_period(c: &BigC, period: u32) -> Option<u32> {
    let bits = c.bits;
    let one = BigC::from_f64(1.0, 0.0, bits);
    let tolerance = FloatExp::new(1.0, 32 - bits as i32) * FloatExp::ONE.max(c.abs());
    let (mut z, mut dz) = (BigC::zero(bits), BigC::zero(bits));
    for n in 1..period {
        (z, dz) = c.orbit_step((&z, &dz), &one);
        if period.is_multiple_of(n) && z.abs() <= tolerance * dz.abs() {
            return Some(n);
        }
    }
    None
}

/// Finds the minibrot of period `period` whose nucleus Newton's method reaches from `start`:
/// Newton at `start`'s precision, then again with enough bits to place the nucleus well
/// inside its own size. None when Newton does not converge, or converges to a nucleus of a
/// lower period ([`lower_period`]; its "size" for `period` would be meaningless).
pub fn minibrot(start: &BigC, period: u32) -> Option<Minibrot> {
    found(start, period, NEWTON_STEPS, None).0
}

/// How far Newton's method may stray from its start, in radii of the disc the nucleus must
/// lie in ([`minibrot_within`]), before it is given up: its iterates approach a nucleus in
/// its basin from nearby, and one that wanders off converges, if at all, elsewhere.
const LEASH: f64 = 16.0;

/// [`minibrot`], for a nucleus within `radius` of `start` only. Newton's method is given up
/// once it strays 16 radii away, and a root outside the disc is refused before its
/// refinement (at depth both take seconds for a root the caller would refuse).
pub fn minibrot_within(start: &BigC, period: u32, radius: FloatExp) -> Option<Minibrot> {
    found(start, period, NEWTON_STEPS, Some(radius)).0
}

/// [`minibrot_within`] out of a budget: `work` is the big-float work left, in iterations at
/// 128 bits (an iteration at b bits counts b / 128 times), and each of Newton's steps,
/// `period` iterations, is taken from it; at most `steps` steps, fewer where the budget
/// holds fewer. The refinement of a nucleus found is not counted.
pub fn minibrot_budgeted(start: &BigC, period: u32, steps: u32, radius: FloatExp, work: &mut u64) -> Option<Minibrot> {
    let cost = u64::from(period) * (start.bits.max(128) / 128);
    let steps = steps.min(u32::try_from(*work / cost.max(1)).unwrap_or(u32::MAX));
    if steps == 0 {
        return None;
    }
    let (m, taken) = found(start, period, steps, Some(radius));
    *work -= u64::from(taken) * cost;
    m
}

/// [`minibrot`] and [`minibrot_within`]: within `radius` of `start` where one is given;
/// with the number of Newton's steps it took (before any refinement).
fn found(start: &BigC, period: u32, steps: u32, radius: Option<FloatExp>) -> (Option<Minibrot>, u32) {
    let leash = radius.map(|r| r.mul_f64(LEASH));
    let (c, taken) = newton_leashed(start, period, steps, leash);
    (c.and_then(|c| refined(c, start, period, radius)), taken)
}

/// A root of Newton's method for `period` from `start`, as a minibrot: refused where it
/// lies farther than `radius` from the start or is a nucleus of a lower period, and refined
/// until its precision places it well inside its own size.
fn refined(mut c: BigC, start: &BigC, period: u32, radius: Option<FloatExp>) -> Option<Minibrot> {
    let outside = radius.is_some_and(|r| c.sub(start).abs() > r);
    if outside || lower_period(&c, period).is_some() {
        return None;
    }
    loop {
        let (magnitude, angle) = polar(size(&c, period));
        if magnitude.is_zero() {
            return None;
        }
        let needed = (-magnitude.log2()).max(0.0) as u64 + 64;
        if c.bits >= needed {
            return Some(Minibrot { nucleus: c, period, size: magnitude, angle });
        }
        c = newton(&c.with_bits(needed + 32), period, 64)?;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Published nuclei: the period-2 bulb's centre -1, the airplane (period 3,
    /// -1.754877666246692760049508896358528691894606617772793143989283...), the rabbit
    /// (period 3, -0.122561166876653629 + 0.744861766619744237i), and the period-4 bulb on
    /// the period-2 bulb (-1.31070264133683288...).
    #[test]
    fn nuclei_agree_with_published_coordinates() {
        let near = |re: f64, im: f64, p: u32| newton(&BigC::from_f64(re, im, 256), p, 100).expect("converges");
        let close = |c: &BigC, re: &str, im: &str, digits: i32| {
            let want = BigC::from_decimals(
                &crate::num::Decimal::parse(re).unwrap(),
                &crate::num::Decimal::parse(im).unwrap(),
                256,
            );
            let err = c.sub(&want).abs();
            assert!(err < FloatExp::exp10(-(digits as f64)), "{:?} vs {re} {im}: {err:?}", c.to_fe());
        };
        close(&near(-0.9, 0.05, 2), "-1", "0", 70);
        close(&near(-1.75, 0.0, 3), "-1.754877666246692760049508896358528691894606617772793143989283", "0", 60);
        close(&near(-0.12, 0.74, 3), "-0.122561166876653629", "0.744861766619744237", 17);
        close(&near(-1.31, 0.0, 4), "-1.3107026413368328", "0", 16);
    }

    /// Newton's method for period p converges to any nucleus whose period divides p: those
    /// are told apart and refused.
    #[test]
    fn nuclei_of_a_lower_period_are_refused() {
        let airplane = newton(&BigC::from_f64(-1.75, 0.0, 256), 3, 100).unwrap();
        assert_eq!(lower_period(&airplane, 3), None);
        assert_eq!(lower_period(&airplane, 6), Some(3));
        assert_eq!(lower_period(&airplane, 12), Some(3));
        assert_eq!(lower_period(&BigC::zero(256), 540), Some(1));
        let bulb4 = newton(&BigC::from_f64(-1.31, 0.0, 256), 4, 100).unwrap();
        assert_eq!(lower_period(&bulb4, 20), Some(4));
        // From beside the main cardioid's cusp, Newton for period 540 reaches 0: no
        // minibrot. From -1.25 + 0.001i, Newton for 20 reaches the period-4 nucleus.
        assert_eq!(minibrot(&BigC::from_f64(0.25, 0.0, 128), 540), None);
        let to_zero = newton(&BigC::from_f64(0.25, 0.0, 128), 540, 200).unwrap();
        assert!(to_zero.abs() < FloatExp::from(1e-30), "{:?}", to_zero.to_fe());
        assert_eq!(lower_period(&to_zero, 540), Some(1));
        assert_eq!(minibrot(&BigC::from_f64(-1.25, 0.001, 128), 20), None);
    }

    /// Newton's method on a leash: from beside the cusp it wanders off to 0, a quarter away;
    /// held within 1e-3 of its start it gives up, and a disc of 1e-3 refuses the root.
    #[test]
    fn newton_on_a_leash_gives_up_far_from_its_start() {
        let start = BigC::from_f64(0.25, 0.0, 128);
        assert!(newton_leashed(&start, 540, 200, None).0.is_some());
        let (root, taken) = newton_leashed(&start, 540, 200, Some(FloatExp::from(1e-3)));
        assert_eq!(root, None);
        assert!(taken < 20, "{taken} steps");
        let airplane = BigC::from_f64(-1.75, 0.0, 128);
        assert_eq!(minibrot_within(&airplane, 3, FloatExp::from(1e-3)), None);
        let m = minibrot_within(&airplane, 3, FloatExp::from(1e-2)).expect("within 0.0049");
        assert_eq!(m.period, 3);
    }

    /// A search out of a budget is charged the steps it took, and gets no more steps than
    /// the budget holds: from beside the cusp, leashed, it gives up after a few steps of
    /// period 540; a budget of 539 iterations holds none of them, and three of period 3.
    #[test]
    fn a_search_out_of_a_budget_is_charged_what_it_took() {
        let start = BigC::from_f64(0.25, 0.0, 128);
        let r = FloatExp::from(1e-3);
        let mut work = 1_000_000;
        assert_eq!(minibrot_budgeted(&start, 540, 64, r, &mut work), None);
        let (_, taken) = newton_leashed(&start, 540, 64, Some(r.mul_f64(LEASH)));
        assert_eq!(1_000_000 - work, u64::from(taken) * 540);
        let airplane = BigC::from_f64(-1.75, 0.0, 128);
        let mut little = 539;
        let m = minibrot_budgeted(&airplane, 3, 64, FloatExp::from(1e-2), &mut little);
        assert_eq!(m.map(|m| m.period), Some(3));
        let mut none = 539;
        assert_eq!(minibrot_budgeted(&start, 540, 64, r, &mut none), None);
        assert_eq!(none, 539);
    }

    /// A size estimate's direction at any depth: 120 degrees at 2^-2000 as at 1.
    #[test]
    fn the_direction_of_a_size_beyond_f64s_range() {
        for e in [0, -2000] {
            let (modulus, angle) = polar([FloatExp::new(-1.0, e), FloatExp::new(3f64.sqrt(), e)]);
            assert!((modulus.log2() - (e + 1) as f64).abs() < 1e-12, "{e}: {modulus:?}");
            assert!((angle.to_degrees() - 120.0).abs() < 1e-9, "{e}: {}", angle.to_degrees());
        }
    }

    #[test]
    fn sizes_of_known_minibrots() {
        // The period-3 airplane minibrot is about 1/52 the size of the whole set (its
        // estimate is ~0.019, pointing left like the set itself: argument near 0).
        let m = minibrot(&BigC::from_f64(-1.75, 0.0, 128), 3).expect("found");
        let s = m.size.to_f64();
        assert!((0.015..0.025).contains(&s), "size {s}");
        assert!(m.angle.abs() < 0.1, "angle {}", m.angle);
        // A deep one near the 1e1086 benchmark location, checked by its own orbit: z_p
        // returns to 0 within the precision (the Newton correction z_p / z_p' it leaves is
        // below 2^(24 - bits), far below the minibrot's size of ~1e-73).
        let d = |t: &str| crate::num::Decimal::parse(t).unwrap();
        let near = BigC::from_decimals(
            &d(
                "-1.76861049301467707450317565327022652023967790758866549483767725757530464097880847527463570736246404425",
            ),
            &d(
                "0.00126661350386871770206641119224260157619394056047140981718501017176252479258890361669150134602850245",
            ),
            400,
        );
        let p = super::super::period::ball_period(
            crate::formula::Formula::default(),
            &near,
            FloatExp::exp10(-40.0),
            100_000,
        )
        .expect("a period");
        assert_eq!(p, 1282);
        let m = minibrot(&near, p).expect("found");
        assert!((-74.0..-72.0).contains(&(m.size.log2() * std::f64::consts::LOG10_2)), "size {:?}", m.size);
        let bits = m.nucleus.bits;
        let (mut z, mut dz) = (BigC::zero(bits), BigC::zero(bits));
        for _ in 0..m.period {
            dz = z.mul(&dz).ldexp(1).add(&BigC::from_f64(1.0, 0.0, bits));
            z = z.square().add(&m.nucleus);
        }
        let residual = z.div(&dz).abs();
        assert!(residual < FloatExp::new(1.0, 24 - bits as i32), "z_p / z_p' = {residual:?} at {bits} bits");
        assert!(residual < m.size.mul_f64(1e-40), "z_p / z_p' = {residual:?}, size {:?}", m.size);
    }
}
