//! Searching a view for a location to zoom to: the lowest-period minibrot in it, or the
//! simplest Misiurewicz point in it, each with the zoom that frames it.
//!
//! Minibrot: the ball method gives a lower bound p on the periods of the nuclei in the
//! view's disc, Newton's method from the view's centre looks for a nucleus of period p,
//! then of the periods above it, and the size estimate frames the first found. Only a
//! nucleus of exactly the period sought that lies in the disc is taken: Newton's method
//! for period p also converges to nuclei of the periods dividing p and to nuclei outside
//! the view, whose "size" for p means nothing.
//!
//! Misiurewicz point: the centre's orbit (with its derivative in c), computed once, gives,
//! for every period p in range (the periods shared between the cores), the first
//! preperiod k >= 2 whose Newton step length
//! |z_(k+p) - z_k| / |z'_(k+p) - z'_k| — a first-order distance from the centre to a root
//! of z_(k+p) = z_k — is inside the view, leaving out the roots that belong to a lower
//! preperiod (nuclei among them). The candidates are tried in order of k + p (the simplest
//! first) with Newton's method, at the view's precision plus the bits the candidate's
//! derivative amplifies rounding by, and the first whose root lies in the view and whose
//! orbit really has preperiod k and period p wins. At depth that extra precision is what
//! makes the root and its check possible: bench-e1086's centre at 1e60 needs ~200 more bits.
//! Around a minibrot those distances see nothing (every orbit there nearly repeats with its
//! period); where they find no point, the minibrot's copies of the whole set's simplest
//! points are tried, placed by renormalisation and the size estimate.

use rayon::prelude::*;

use crate::formula::Formula;
use crate::num::{Decimal, FloatExp};

use super::nucleus::{self, Minibrot};
use super::{misiurewicz, period};
use crate::num::bigcomplex::BigC;

/// A Misiurewicz point found in a view.
#[derive(Debug, Clone, PartialEq)]
pub struct MisiurewiczPoint {
    /// The point.
    pub point: BigC,
    /// Preperiod k (z_(k+p) = z_k, k smallest).
    pub preperiod: u32,
    /// Period p.
    pub period: u32,
}

/// Why a search found nothing.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SearchError {
    /// No nucleus of period up to the limit lies in the view.
    #[error("no minibrot of period up to {max_period} lies in this view (zoom in, or raise --max-period)")]
    NoPeriod {
        /// The largest period tried.
        max_period: u32,
    },
    /// Newton's method from the view's centre reached no nucleus in the view.
    #[error(
        "Newton's method from the view's centre reached no minibrot inside the view (the ball method puts the lowest period there at {period} or more): move the centre closer to one, or zoom in"
    )]
    NoNucleus {
        /// The ball method's period: a lower bound on the view's lowest.
        period: u32,
    },
    /// No Misiurewicz point in range lies in the view.
    #[error(
        "no Misiurewicz point of preperiod up to {max_preperiod} and period up to {max_period} lies in this view (raise --max-preperiod or --max-period, or move the centre closer)"
    )]
    NoMisiurewicz {
        /// The largest preperiod tried.
        max_preperiod: u32,
        /// The largest period tried.
        max_period: u32,
    },
}

/// Candidates tried by Newton's method in a Misiurewicz search before giving up.
const MAX_NEWTON_TRIES: usize = 24;

/// The radius (half-height) of a view that frames a minibrot of `size`: the whole
/// Mandelbrot set, of size 1 about its nucleus 0, spans -2 .. 0.47 along the real axis and
/// ±1.15 along the imaginary one, so 2.2 sizes either way hold it at any orientation.
pub fn framing_radius(size: FloatExp) -> FloatExp {
    size.mul_f64(2.2)
}

/// The zoom (as log10; the image height spans 4 / zoom) that frames a minibrot of `size`.
pub fn framing_log10_zoom(size: FloatExp) -> f64 {
    2f64.log10() - framing_radius(size).log2() * std::f64::consts::LOG10_2
}

/// A disc to search, from its centre as decimals and its radius as a decimal logarithm:
/// the centre in big floats at the precision a view of that radius needs, and the radius.
pub fn disc(center: &[Decimal; 2], log10_radius: f64) -> (BigC, FloatExp) {
    let bits = crate::num::bigfloat::precision_for(log10_radius);
    (BigC::from_decimals(&center[0], &center[1], bits), FloatExp::exp10(log10_radius))
}

/// Periods above the ball method's that [`minibrot_in_view`] tries one by one: up to this
/// many times it (and at least up to [`MIN_UPWARD`]).
pub(super) const UPWARD_FACTOR: u32 = 8;
/// See [`UPWARD_FACTOR`].
pub(super) const MIN_UPWARD: u32 = 64;
/// Periods of the centre's atom domains tried after those ([`period::atom_periods`]).
pub(super) const MORE_PERIODS: usize = 8;
/// Newton's steps from the view's centre for each period after the ball method's (where
/// the centre lies in a nucleus's basin it converges within a few dozen).
pub(super) const MORE_NEWTON_STEPS: u32 = 64;
/// What those Newton searches may cost together at most, in big-float iterations at 128
/// bits (an iteration at b bits counted b / 128 times): about a second. Each is charged the
/// steps it took (most that fail leave their leash within a few), and the last one gets the
/// steps the budget still holds; at depth, where each step costs more, fewer are tried.
pub(super) const MORE_WORK: u64 = 4_000_000;

/// The last period tried one by one above the ball method's `p`: [`UPWARD_FACTOR`] times
/// it, at least [`MIN_UPWARD`], at most `max_period`.
pub(super) fn upward_top(p: u32, max_period: u32) -> u32 {
    max_period.min(p.saturating_mul(UPWARD_FACTOR).max(MIN_UPWARD))
}

/// The lowest-period minibrot whose nucleus lies in the disc of `radius` about `center`
/// (the view's centre and half-height, `center` at the precision the view needs), as far as
/// Newton's method from the centre reaches.
///
/// The ball method's period p bounds from below the periods of the nuclei in the disc (a
/// nucleus of period q inside puts 0 within the bound at iteration q), and Newton's method
/// for period p from the centre looks for one. Only a nucleus of period exactly p inside
/// the disc is taken: Newton's method also reaches nuclei outside the view, and near a
/// bulb's root or a cusp those of a period dividing p (0 for every p; [`nucleus::minibrot`]).
/// The bound is not always attained (it is loose where the disc is large beside the
/// structure in it: a view of radius 0.033 at -0.75 + 0.1i has 8 for its bound, and Newton's
/// method from a 13 x 13 grid of starts over it reaches no nucleus in it below period 25;
/// at the tip of a minibrot of period P the nuclei it reaches for the bound lie outside
/// the view, and the periods of those inside step by P), so where Newton's method finds
/// none, the periods above p are tried in turn (up to eight times p, at least 64), then
/// the later periods of the centre's atom domains, within a fixed budget of big-float work
/// (about a second at 128 bits, less at depth, where each try costs more), each try charged
/// the steps it took; the first nucleus found in the disc is returned.
pub fn minibrot_in_view(center: &BigC, radius: FloatExp, max_period: u32) -> Result<Minibrot, SearchError> {
    let p = period::ball_period(Formula::default(), center, radius, max_period)
        .ok_or(SearchError::NoPeriod { max_period })?;
    if let Some(m) = nucleus::minibrot_within(center, p, radius) {
        return Ok(m);
    }
    let mut left = MORE_WORK;
    let mut attempt = |q: u32| nucleus::minibrot_budgeted(center, q, MORE_NEWTON_STEPS, radius, &mut left);
    let top = upward_top(p, max_period);
    let later = || period::atom_periods(Formula::default(), center, top, max_period, MORE_PERIODS);
    (p + 1..=top)
        .find_map(&mut attempt)
        .or_else(|| later().into_iter().find_map(&mut attempt))
        .ok_or(SearchError::NoNucleus { period: p })
}

/// Periods searched by [`misiurewicz_limits`] at most, and preperiods at most twice that.
pub const MAX_AUTO_PERIOD: u32 = 4096;

/// Limits for a Misiurewicz search of a view when none are given: periods up to the view's
/// lowest minibrot period P (the ball method) and preperiods up to 2P, at least 64 and 5000
/// and at most [`MAX_AUTO_PERIOD`] and twice that. The simplest Misiurewicz points of deep
/// views lie within those: at bench-e1086's centre (P = 1282 at 1e30, 2578 at 1e60) they are
/// (283, 324) and (1227, 1296), at deep-e318's at 1e40 (P = 1676) (1657, 836), at
/// floral-fantasy's at 1e30 (P = 260) (244, 1). Returns (max preperiod, max period).
pub fn misiurewicz_limits(center: &BigC, radius: FloatExp) -> (u32, u32) {
    let p = period::ball_period(Formula::default(), center, radius, MAX_AUTO_PERIOD).unwrap_or(MAX_AUTO_PERIOD);
    (p.saturating_mul(2).clamp(5000, 2 * MAX_AUTO_PERIOD), p.clamp(64, MAX_AUTO_PERIOD))
}

/// Bits Newton's method and the check of a candidate get beyond the view's precision and
/// the candidate's derivative (the factor by which its orbit amplifies rounding).
const NEWTON_MARGIN_BITS: u64 = 64;

/// The simplest Misiurewicz point (smallest preperiod + period) within `radius` of
/// `center`, with preperiod at most `max_preperiod` and period at most `max_period`, as
/// the first-order distances from the centre rank them (module docs); where those find
/// none, the copy in the view's lowest-period minibrot of one of the whole set's simplest
/// points (its tip -2, ±i, or -1.5437...), as renormalisation places them.
pub fn misiurewicz_in_view(
    center: &BigC,
    radius: FloatExp,
    max_preperiod: u32,
    max_period: u32,
) -> Result<MisiurewiczPoint, SearchError> {
    let none = SearchError::NoMisiurewicz { max_preperiod, max_period };
    let mut near = candidates(center, radius, max_preperiod, max_period);
    near.sort_by_key(|c| (c.preperiod + c.period, c.period));
    let inside = |c: &Candidate| misiurewicz_root(center, center, radius, *c);
    near.iter()
        .take(MAX_NEWTON_TRIES)
        .find_map(inside)
        .or_else(|| copies_in_minibrot(center, radius, max_preperiod, max_period))
        .ok_or(none)
}

/// Newton's method for a Misiurewicz point of the candidate's preperiod and period from
/// `start`, at its precision plus the bits the candidate's derivative amplifies rounding by;
/// the root where it lies within `radius` of `center` and its orbit is a Misiurewicz
/// point's, with the preperiod and period the orbit really has. Those may be lower than the
/// candidate's: every root of z_(k'+p') = z_k' with k' <= k and p' dividing p is a root of
/// z_(k+p) = z_k too (a copy in a satellite component lands on a cycle of half the copy's
/// period, [`copies_in_minibrot`]). A nucleus is a root as well (preperiod 0, or 1 where
/// z_(1+p) = z_1 = c), and is refused.
fn misiurewicz_root(start: &BigC, center: &BigC, radius: FloatExp, c: Candidate) -> Option<MisiurewiczPoint> {
    let (k, p) = (c.preperiod, c.period);
    let bits = start.bits + c.log2_derivative.max(0.0).ceil() as u64 + NEWTON_MARGIN_BITS;
    let point = misiurewicz::newton(&start.with_bits(bits), k, p, 64)?;
    if point.sub(center).abs() > radius {
        return None;
    }
    let (preperiod, period) = misiurewicz::orbit_type(&point, k, p).filter(|&(k, _)| k >= 2)?;
    Some(MisiurewiczPoint { point, preperiod, period })
}

/// Misiurewicz points of the whole Mandelbrot set whose copies [`copies_in_minibrot`] looks
/// for: the tip -2 (preperiod 2, period 1), i and -i (2, 2), and the band-merging point
/// -1.5436890126920764 (3, 1).
const WHOLE_SET_POINTS: [([f64; 2], u32, u32); 4] =
    [([-2.0, 0.0], 2, 1), ([0.0, 1.0], 2, 2), ([0.0, -1.0], 2, 2), ([-1.543_689_012_692_076_4, 0.0], 3, 1)];

/// The copy, in the lowest-period minibrot of the view, of one of [`WHOLE_SET_POINTS`]
/// (the first that lies in the view with preperiod and period within the limits).
///
/// The search by first-order distances misses these from a view around a minibrot: there
/// the orbit of every parameter nearly repeats with the minibrot's period P, so the
/// distances for period P are all small and the orbit's step into its cycle is not seen.
/// But a minibrot is a copy of the whole set (Douady and Hubbard's renormalisation): its
/// first-return map near 0 is, in a coordinate, z -> z^2 + c', so a Misiurewicz point
/// c' of preperiod k and period p has a copy of preperiod (k - 1) P + 1 and period p P
/// (the copy's orbit stands at the copy of c' at its first iteration, and every P after),
/// near c_0 + s c' (c_0 the nucleus, s the complex size estimate, whose argument turns the
/// copy as the minibrot is turned). Newton's method from there, at the precision the point's
/// derivative asks, and the same check of the orbit's type.
///
/// The size estimate is made for primitive minibrots. For a satellite that doubles its
/// parent's period (the period-doubling cascade on the real axis, the 1/2 bulbs) it is
/// about twice the scale of its copy, and the copy of the tip lands on a cycle of half the
/// period, the parent's: the period-2 bulb (nucleus -1, estimate 0.5) has the tip's copy at
/// -1.5437 (preperiod 3, period 1), 1.09 estimates from the nucleus where 2 were expected;
/// the period-16 bulb at -1.39695 (estimate 5.6e-3), its copy at -1.40249 (preperiod 17,
/// period 8), 0.99 estimates away. So the copies are looked for at the estimate's scale,
/// then at half of it (a view inside the cascade, at -1.4 and zoom 1e3, has only the
/// second kind).
fn copies_in_minibrot(
    center: &BigC,
    radius: FloatExp,
    max_preperiod: u32,
    max_period: u32,
) -> Option<MisiurewiczPoint> {
    let m = minibrot_in_view(center, radius, max_period).ok()?;
    let nucleus = m.nucleus.with_bits(m.nucleus.bits.max(center.bits));
    // The complex size estimate, s = |s| e^(i angle).
    let (sin, cos) = m.angle.sin_cos();
    let s = [m.size.mul_f64(cos), m.size.mul_f64(sin)];
    // The whole scale first, then half of it (see above).
    let points = [1.0, 0.5].into_iter().flat_map(|f| WHOLE_SET_POINTS.iter().map(move |&(c, k, p)| (f, c, k, p)));
    points.into_iter().find_map(|(f, [x, y], k, p)| {
        // The copy's orbit reaches the copy of c' at iteration 1 and returns every P:
        // preperiod (k - 1) P + 1.
        let (k, p) = ((k - 1).checked_mul(m.period)?.checked_add(1)?, p.checked_mul(m.period)?);
        if k > max_preperiod || p > max_period {
            return None;
        }
        // f s c' = f ((s_re x - s_im y) + i (s_re y + s_im x)).
        let (x, y) = (x * f, y * f);
        let (re, im) = (s[0].mul_f64(x) - s[1].mul_f64(y), s[0].mul_f64(y) + s[1].mul_f64(x));
        let start = nucleus.add(&offset(re, im, nucleus.bits));
        let orbit = misiurewicz::Orbit::of(&start, (k + p) as usize, None);
        let log2_derivative = orbit.slope((k + p) as usize, k as usize).log2();
        misiurewicz_root(&start, center, radius, Candidate { preperiod: k, period: p, log2_derivative })
    })
}

/// re + i im as a big complex number of `bits` (exact: each part is an f64 mantissa and an
/// exponent).
fn offset(re: FloatExp, im: FloatExp, bits: u64) -> BigC {
    let re = BigC::from_f64(re.mantissa(), 0.0, bits).ldexp(re.exponent());
    re.add(&BigC::from_f64(0.0, im.mantissa(), bits).ldexp(im.exponent()))
}

/// A preperiod and period worth Newton's method.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    preperiod: u32,
    period: u32,
    /// log2 |z'_(k+p) - z'_k| at the centre.
    log2_derivative: f64,
}

/// For each period p in 1..=`max_period`, the smallest preperiod k in 2..=`max_preperiod`
/// (a Misiurewicz point has preperiod 2 at least) whose first-order distance from `c` to a
/// root of z_(k+p) = z_k, |f| / |f'| with f = z_(k+p) - z_k, is below `radius`. One pass
/// over the centre's orbit (with its derivative in c), up to where it leaves |z| <= 2: an
/// escaping orbit follows no cycle after that. Differences are taken in 53 bits unless they
/// cancel (near a root, where they are small compared with z): then in big floats.
///
/// A root of z_(k+p) = z_k where z_(k+p-1) = +z_(k-1) is a root of lower preperiod (every
/// nucleus of period p is one of z_(p+1) = z_1, z_(p+2) = z_2, ...), so only candidates
/// where z_(k+p-1) is nearer -z_(k-1) than +z_(k-1) are kept: the step into the cycle.
/// Later preperiods of the same point (z_(k+1+p) = z_(k+1), ...) are not candidates either;
/// Newton's method from them reaches the same point.
fn candidates(c: &BigC, radius: FloatExp, max_preperiod: u32, max_period: u32) -> Vec<Candidate> {
    let orbit = misiurewicz::Orbit::of(c, (max_preperiod + max_period) as usize, Some(FloatExp::from(2.0)));
    // Each period on its own (on every core), in order.
    let first = |p: usize| {
        (2..=max_preperiod as usize).take_while(|&k| k + p < orbit.len()).find_map(|k| {
            let df = orbit.slope(k + p, k);
            if df.is_zero() || orbit.gap(k + p, k) / df >= radius {
                return None;
            }
            let (a, b) = (orbit.point(k + p - 1), orbit.point(k - 1));
            if misiurewicz::norm(a[0] - b[0], a[1] - b[1]) < misiurewicz::norm(a[0] + b[0], a[1] + b[1]) {
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

    #[test]
    fn the_period_3_minibrot_of_a_view_on_the_antenna() {
        // A view of radius 0.01 on the real axis near -1.75 holds the airplane's nucleus
        // -1.754877666246692760049508896358528821 (published).
        let c = BigC::from_f64(-1.752, 0.0, 256);
        let m = minibrot_in_view(&c, FloatExp::from(0.01), 1000).unwrap();
        assert_eq!(m.period, 3);
        let re = m.nucleus.to_fe()[0].to_f64();
        assert!((re + 1.754_877_666_246_693).abs() < 1e-15, "{re}");
        // Its size is about 1/53 of the whole set's (a published estimate: 0.019).
        let s = m.size.to_f64();
        assert!((0.015..0.025).contains(&s), "{s}");
        assert!(framing_radius(m.size).to_f64() > s);
    }

    #[test]
    fn misiurewicz_points_of_a_view() {
        // c = i: preperiod 2, period 2 (published); a view of radius 0.05 about 0.01+1.02i.
        let c = BigC::from_f64(0.01, 1.02, 192);
        let m = misiurewicz_in_view(&c, FloatExp::from(0.05), 16, 8).unwrap();
        assert_eq!((m.preperiod, m.period), (2, 2));
        let [re, im] = m.point.to_fe().map(|x| x.to_f64());
        assert!(re.abs() < 1e-30 && (im - 1.0).abs() < 1e-30, "{re} {im}");
        // c = -2 (preperiod 2, period 1), seen from -1.99.
        let c = BigC::from_f64(-1.99, 0.0, 192);
        let m = misiurewicz_in_view(&c, FloatExp::from(0.02), 16, 8).unwrap();
        assert_eq!((m.preperiod, m.period), (2, 1));
        // Nothing that simple in a tiny view far from both.
        let c = BigC::from_f64(-0.3, 0.3, 192);
        assert!(misiurewicz_in_view(&c, FloatExp::from(1e-6), 3, 2).is_err());
    }

    /// z_0 .. z_n of c's critical orbit, by plain squaring in big floats.
    fn orbit(c: &BigC, n: usize) -> Vec<BigC> {
        let mut z = vec![BigC::zero(c.bits)];
        for _ in 0..n {
            z.push(z[z.len() - 1].square().add(c));
        }
        z
    }

    /// Whether `c` is a nucleus of period exactly `p`, by its own orbit: z_p vanishes to
    /// within `tol` and no earlier z_n (n dividing p) does.
    fn exact_nucleus(c: &BigC, p: u32, tol: f64) -> bool {
        let z = orbit(c, p as usize);
        let small = |n: u32| z[n as usize].abs() < FloatExp::from(tol);
        small(p) && !(1..p).any(|n| p.is_multiple_of(n) && small(n))
    }

    /// Views where Newton's method from the centre for the ball method's period reaches a
    /// nucleus of a period dividing it (the period-4 bulb's for 20, the rabbit's for 33, 0
    /// from the main cardioid's cusp for 540) or one far outside the view: what is
    /// returned is a nucleus of exactly its period inside the view, or an error, never
    /// those.
    #[test]
    fn never_a_nucleus_of_a_lower_period_or_outside_the_view() {
        for (re, im, r) in [
            (-1.25, 0.001, 3.3e-3),
            (-0.1, 0.651, 3.3e-3),
            (0.25, 0.0, 3.3e-5),
            (-0.75, 0.1, 3.3e-2),
            (-0.7453, 0.1127, 3.3e-6),
            (0.3, 0.02, 3.3e-4),
        ] {
            let c = BigC::from_f64(re, im, 192);
            match minibrot_in_view(&c, FloatExp::from(r), 100_000) {
                Ok(m) => {
                    assert!(
                        m.nucleus.sub(&c).abs() <= FloatExp::from(r),
                        "({re}, {im}): {:?} outside",
                        m.nucleus.to_fe()
                    );
                    assert!(exact_nucleus(&m.nucleus, m.period, 1e-30), "({re}, {im}): not of period {}", m.period);
                    assert!(m.size < FloatExp::from(r), "({re}, {im}): size {:?}", m.size);
                }
                Err(e) => assert!(matches!(e, SearchError::NoNucleus { .. }), "({re}, {im}): {e}"),
            }
        }
    }

    /// In the period-doubling cascade at -1.4 the ball method's period, 8, has its nucleus
    /// (-1.3815) outside a view of radius 0.0033; period 16 has its nucleus inside
    /// (-1.3969453597045606..., published). In seahorse valley at -0.75 + 0.1i (radius
    /// 0.033) the ball method's 8 has no nucleus in the view either.
    #[test]
    fn a_higher_period_where_the_ball_methods_has_no_nucleus_in_the_view() {
        let c = BigC::from_f64(-1.4, 0.0, 192);
        let m = minibrot_in_view(&c, FloatExp::from(3.3e-3), 1000).unwrap();
        assert_eq!(m.period, 16);
        let re = m.nucleus.to_fe()[0].to_f64();
        assert!((re + 1.396_945_359_704_560_6).abs() < 1e-15, "{re}");
        assert!(exact_nucleus(&m.nucleus, 16, 1e-40));
        let c = BigC::from_f64(-0.75, 0.1, 192);
        let r = FloatExp::from(3.3e-2);
        assert_eq!(period::ball_period(Formula::default(), &c, r, 1000), Some(8));
        let m = minibrot_in_view(&c, r, 1000).unwrap();
        assert!(m.period > 8 && exact_nucleus(&m.nucleus, m.period, 1e-40), "period {}", m.period);
        assert!(m.nucleus.sub(&c).abs() <= r);
    }

    /// A view of radius 3.3e-20 centred on the tip of a minibrot of period 69 near seahorse
    /// valley (the Misiurewicz point of preperiod 70 and period 69 that `find
    /// --misiurewicz` gives from -0.7453 + 0.1127i at zoom 1e4, to 63 digits): the ball
    /// method's period is 1380 = 20 x 69, and the nuclei of 1380 and 1449 that Newton's
    /// method from the centre reaches lie 12.7 and 3.2 radii away (its nearest nuclei step
    /// by the minibrot's period along its antenna); one of period 1518 lies 0.80 radii from
    /// the centre (Newton's method in mpmath at 160 bits: the first two from the centre,
    /// the third from points of a grid over the disc). The search tries the periods above
    /// 1380 from the centre; charged for each the steps it took rather than the 64 it may
    /// take, it reaches 1518 within its budget, and finds that nucleus; checked by its own
    /// orbit.
    #[test]
    fn a_minibrot_near_the_tip_of_another() {
        let parse = |s: &str| crate::num::Decimal::parse(s).unwrap();
        let re = parse("-0.745364479025458672062596071600162594309826812798577840536768726");
        let im = parse("0.112436757524417052314660847064084632753529873418744313970532617");
        let c = BigC::from_decimals(&re, &im, 192);
        let r = FloatExp::from(3.3e-20);
        assert_eq!(period::ball_period(Formula::default(), &c, r, 100_000), Some(1380));
        let m = minibrot_in_view(&c, r, 100_000).unwrap();
        assert_eq!(m.period, 1518);
        let away = (m.nucleus.sub(&c).abs() / r).to_f64();
        assert!((0.79..0.81).contains(&away), "{away} radii from the centre");
        // Its own orbit: z_1518 within a first-order distance |z / z'| far below its size
        // (6.3e-33) of 0, and z_n of every proper divisor n of 1518 far from it.
        let one = BigC::from_f64(1.0, 0.0, m.nucleus.bits);
        let (mut z, mut dz) = (BigC::zero(m.nucleus.bits), BigC::zero(m.nucleus.bits));
        for n in 1..=m.period {
            (z, dz) = m.nucleus.orbit_step((&z, &dz), &one);
            let distance = z.abs() / dz.abs();
            if n == m.period {
                assert!(distance < FloatExp::from(1e-50), "{distance:?}");
            } else if m.period.is_multiple_of(n) {
                assert!(distance > FloatExp::from(1e-30), "period {n}: {distance:?}");
            }
        }
    }

    /// From a view centred on the airplane's nucleus (period 3) the search by first-order
    /// distances finds nothing (every orbit there nearly repeats with period 3); the copy
    /// of the tip -2 in the airplane minibrot is found, -1.7903274919993457..., preperiod
    /// (2 - 1) 3 + 1 = 4 and period 3, checked by its own orbit.
    #[test]
    fn misiurewicz_points_copied_into_a_minibrot() {
        let c = nucleus::newton(&BigC::from_f64(-1.75, 0.0, 256), 3, 100).unwrap();
        let r = FloatExp::from(0.167);
        let m = misiurewicz_in_view(&c, r, 5000, 64).unwrap();
        assert_eq!((m.preperiod, m.period), (4, 3));
        let re = m.point.to_fe()[0].to_f64();
        assert!((re + 1.790_327_491_999_345_7).abs() < 1e-15, "{re}");
        let z = orbit(&m.point, 8);
        assert!(z[7].sub(&z[4]).abs() < FloatExp::from(1e-50));
        assert!(z[6].sub(&z[3]).abs() > FloatExp::from(0.1));
        // The whole set, from its nucleus 0 (where every first-order distance is 0 / 0): the
        // tip itself, (2, 1).
        let whole = misiurewicz_in_view(&BigC::zero(128), FloatExp::from(3.4), 5000, 64).unwrap();
        assert_eq!((whole.preperiod, whole.period), (2, 1));
    }

    /// A view inside the period-doubling cascade at -1.4 (radius 3.3e-3): the first-order
    /// distances find nothing (the centre is interior), nor do the copies
    /// at the scale of the period-16 bulb's size estimate; at half of it, the copy of the
    /// tip is the 16 -> 8 band-merging point -1.4024921763585643... (Newton's method in
    /// Python's complex floats from -1.40252), preperiod 17 and period 8, not the 16 the copy
    /// was looked for with: checked by its own orbit.
    #[test]
    fn a_misiurewicz_point_copied_into_a_satellite() {
        let c = BigC::from_f64(-1.4, 0.0, 192);
        let m = misiurewicz_in_view(&c, FloatExp::from(3.3e-3), 5000, 64).unwrap();
        assert_eq!((m.preperiod, m.period), (17, 8));
        let re = m.point.to_fe()[0].to_f64();
        assert!((re + 1.402_492_176_358_564_3).abs() < 1e-15, "{re}");
        let z = orbit(&m.point, 26);
        let gap = |i: usize, j: usize| z[i].sub(&z[j]).abs();
        assert!(gap(25, 17) < FloatExp::from(1e-40), "z_25 = z_17");
        assert!(gap(24, 16) > FloatExp::from(1e-3), "z_24 != z_16: preperiod 17");
        assert!(gap(21, 17) > FloatExp::from(1e-3), "z_21 != z_17: period 8, not 4");
    }

    #[test]
    fn no_minibrot_of_low_period_in_a_tiny_view_off_the_set() {
        let c = BigC::from_f64(0.5, 0.5, 128);
        assert_eq!(minibrot_in_view(&c, FloatExp::from(1e-6), 50), Err(SearchError::NoPeriod { max_period: 50 }));
    }
}
