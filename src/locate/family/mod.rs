//! Finding locations for every formula family and hybrid (Mandelbrot form): the
//! lowest-period mini in a view (its period by the ball method extended to the family's
//! map, its nucleus by Newton's method on the real 2×2 system z_p(c) = 0, its size and
//! orientation from the cycle) and, for the Mandelbrot family at any power, the simplest
//! Misiurewicz point.
//!
//! The search is z² + c's ([`crate::locate::search`]) with each part made generic:
//! [`period`] bounds the periods, [`nucleus`] solves for the nucleus with the Jacobian by
//! forward-mode derivatives in big floats ([`step`]), and the same periods are tried in the
//! same order within the same budget. z² + c keeps its own code (`find` calls it for that
//! formula, so its output is unchanged); the generic code reduces to it at power 2, which
//! the tests check.

pub mod misiurewicz;
pub mod nucleus;
pub mod period;
pub mod step;

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

/// Periods above the ball method's tried: up to this many times it, at least [`MIN_UPWARD`].
const UPWARD_FACTOR: u32 = 8;
/// See [`UPWARD_FACTOR`].
const MIN_UPWARD: u32 = 64;
/// Periods of the centre's atom domains tried after those.
const MORE_PERIODS: usize = 8;
/// Newton's steps from the centre for the ball method's period.
const NEWTON_STEPS: u32 = 200;
/// Newton's steps for each later period.
const MORE_NEWTON_STEPS: u32 = 64;
/// The big-float work the later periods may take together, in iterations at 128 bits (as
/// z² + c's search; an iteration here, with its two tangents, is counted 4 times).
const MORE_WORK: u64 = 4_000_000;
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
    let top = max_period.min(p.saturating_mul(UPWARD_FACTOR).max(MIN_UPWARD));
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
