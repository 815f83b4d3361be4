//! Searching a view for a location to zoom to: the lowest-period minibrot in it, or the
//! simplest Misiurewicz point in it, each with the zoom that frames it.
//!
//! Minibrot: the ball method gives the lowest period p of a nucleus in the view's disc,
//! Newton's method from the view's centre finds that nucleus, and the size estimate frames
//! it. Misiurewicz point: one pass over the centre's orbit (with its derivative in c)
//! gives, for every preperiod k and period p in range, the Newton step length
//! |z_(k+p) - z_k| / |z'_(k+p) - z'_k| — a first-order distance from the centre to a root
//! of z_(k+p) = z_k. The candidates closer than the view's radius are tried in order of
//! k + p (the simplest first), and the first whose Newton root lies in the view and whose
//! orbit really has preperiod k and period p wins.

use crate::num::{Decimal, FloatExp};

use super::big::BigC;
use super::nucleus::{self, Minibrot};
use super::{misiurewicz, period};

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
    /// Newton's method found no nucleus of the period in the view.
    #[error(
        "the view holds a nucleus of period {period}, but Newton's method from the view's centre did not reach it (move the centre closer)"
    )]
    NoNucleus {
        /// The period detected.
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
    let bits = crate::orbit::bigfloat::precision_for(log10_radius);
    (BigC::from_decimals(&center[0], &center[1], bits), FloatExp::exp10(log10_radius))
}

/// The lowest-period minibrot whose nucleus lies in the disc of `radius` about `center`
/// (the view's centre and half-height, `center` at the precision the view needs).
pub fn minibrot_in_view(center: &BigC, radius: FloatExp, max_period: u32) -> Result<Minibrot, SearchError> {
    let p = period::ball_period(center, radius, max_period).ok_or(SearchError::NoPeriod { max_period })?;
    nucleus::minibrot(center, p).ok_or(SearchError::NoNucleus { period: p })
}

/// The simplest Misiurewicz point (smallest preperiod + period) within `radius` of
/// `center`, with preperiod at most `max_preperiod` and period at most `max_period`.
pub fn misiurewicz_in_view(
    center: &BigC,
    radius: FloatExp,
    max_preperiod: u32,
    max_period: u32,
) -> Result<MisiurewiczPoint, SearchError> {
    let none = SearchError::NoMisiurewicz { max_preperiod, max_period };
    let candidates = newton_distances(center, max_preperiod, max_period);
    let mut near: Vec<(u32, u32, FloatExp)> = candidates.into_iter().filter(|&(_, _, d)| d < radius).collect();
    near.sort_by_key(|&(k, p, _)| (k + p, p));
    for &(k, p, _) in near.iter().take(MAX_NEWTON_TRIES) {
        let Some(point) = misiurewicz::newton(center, k, p, 64) else { continue };
        if point.sub(center).abs() > radius {
            continue;
        }
        if misiurewicz::orbit_type(&point, k, p) == Some((k, p)) {
            return Ok(MisiurewiczPoint { point, preperiod: k, period: p });
        }
    }
    Err(none)
}

/// For every preperiod k in 1..=`max_preperiod` and period p in 1..=`max_period`, the
/// first-order distance from `c` to a root of z_(k+p) = z_k: |f| / |f'| with
/// f = z_(k+p) - z_k. The orbit runs in `c`'s precision; differences are taken in 53 bits
/// unless they cancel (near a root, where they are small compared with z): then in big floats.
fn newton_distances(c: &BigC, max_preperiod: u32, max_period: u32) -> Vec<(u32, u32, FloatExp)> {
    let n = (max_preperiod + max_period) as usize;
    let bits = c.bits;
    let one = BigC::from_f64(1.0, 0.0, bits);
    let (mut z, mut dz) = (BigC::zero(bits), BigC::zero(bits));
    let mut orbit = Vec::with_capacity(n + 1);
    orbit.push((z.clone(), z.to_fe(), dz.to_fe()));
    for _ in 0..n {
        dz = z.mul(&dz).ldexp(1).add(&one);
        z = z.square().add(c);
        let escaped = z.abs() > FloatExp::from(1e10);
        orbit.push((z.clone(), z.to_fe(), dz.to_fe()));
        if escaped {
            break;
        }
    }
    let mut out = Vec::new();
    for k in 1..=max_preperiod as usize {
        for p in 1..=max_period as usize {
            let Some((zkp, zkp_fe, dkp)) = orbit.get(k + p) else { break };
            let (zk, zk_fe, dk) = &orbit[k];
            // In 53 bits unless the difference cancels (near a root): then in big floats.
            let d = [zkp_fe[0] - zk_fe[0], zkp_fe[1] - zk_fe[1]];
            let f53 = (d[0] * d[0] + d[1] * d[1]).sqrt();
            let scale = FloatExp::ONE.max(zk_fe[0].abs().max(zk_fe[1].abs()));
            let f = if f53 > scale.mul_f64(1e-9) { f53 } else { zkp.sub(zk).abs() };
            let df = [dkp[0] - dk[0], dkp[1] - dk[1]];
            let dfa = (df[0] * df[0] + df[1] * df[1]).sqrt();
            if !dfa.is_zero() {
                out.push((k as u32, p as u32, f / dfa));
            }
        }
    }
    out
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

    #[test]
    fn no_minibrot_of_low_period_in_a_tiny_view_off_the_set() {
        let c = BigC::from_f64(0.5, 0.5, 128);
        assert_eq!(minibrot_in_view(&c, FloatExp::from(1e-6), 50), Err(SearchError::NoPeriod { max_period: 50 }));
    }
}
