//! The view-wide skip: the run of BLA steps from the reference's start that holds for every
//! sample of the view, composed once into a polynomial in the sample's offset.

use crate::num::FloatExp;
use crate::num::real::{cadd, cmul, norm2};
use crate::orbit::bla::BlaTable;

/// The run of BLA steps from the start of the primary reference that is valid for every
/// sample of the view at once (their deltas are bounded by the largest offset), composed
/// into one quadratic map of the sample's offset u: δ_m = K1 u + K2 u^2. Every sample would
/// take these same steps (or longer ones covering them, equal within the tolerance); taking
/// them once per view skips each sample's first BLA lookups, and at depth its whole FloatExp
/// phase.
///
/// Composing steps as polynomials in u is not the same as applying them to each sample's
/// number: a step's A2 δ^2 and AB δ u hold terms of degree 3 and 4 in u (2 A2 K1 K2 u^3,
/// ...) that a quadratic in u drops. The tables' radii do not bound those (they bound what a
/// step drops from the true iteration, not what a truncated composite drops from the
/// step), and where |A2 δ| is near |A| (orbits lingering near |Z| = 2, e.g. close to c =
/// -2) they are far above ε: composing on regardless displaced every pixel of such views.
/// So [`Skip::find`] carries a bound on the dropped remainder and stops composing before
/// it would exceed ε/4 of the smallest |δ_m| relative to u (see [`Skip::find`]).
#[derive(Debug, Clone, Copy)]
pub struct Skip {
    /// Reference index (and iteration) the samples continue from.
    pub m: u32,
    /// δ_m = K1 u + K2 u^2 (u = δc for the Mandelbrot set, δ_0 for Julia sets), and the
    /// scaled derivative is (K1 + 2 K2 u) times the spacing.
    pub k: [[FloatExp; 2]; 2],
    /// d(δ_m)/d(δ_start) = D1 + D2 u to first order in u (the derivative with respect to the
    /// orbit's start that interior detection carries, [`crate::orbit::interior`]).
    pub d: [[FloatExp; 2]; 2],
    /// BLA steps composed.
    pub steps: u32,
}

impl Skip {
    /// Composes the valid steps of `table` from `start` for offsets up to `u_max`, within
    /// `max_iter`, while the truncation stays within the relative tolerance `eps`.
    ///
    /// With δ = K1 u + K2 u^2 + R(u), a step A δ + B u + A2 δ^2 + AB δ u + B2 u^2 gives
    /// K1' = A K1 + B, K2' = A K2 + A2 K1^2 + AB K1 + B2 and a remainder R' = A R + A2 (2 (K1
    /// u + K2 u^2) R + R^2) + AB u R + A2 (2 K1 K2 u^3 + K2^2 u^4) + AB K2 u^3. Every term of
    /// R has degree 3 or more in u, so a bound E on the sum of its coefficients' moduli
    /// times u_max^degree bounds |R(u)| by E (|u| / u_max)^3 for every |u| <= u_max, and
    /// |R(u)| / |δ(u)| <= E / (|K1| u_max - |K2| u_max^2). That ratio is held to ε / 4.
    pub fn find(table: &BlaTable<FloatExp>, start: u32, u_max: FloatExp, max_iter: u32, eps: f64) -> Option<Skip> {
        let (mut k1, mut k2) = ([FloatExp::ONE, FloatExp::ZERO], [FloatExp::ZERO; 2]);
        let (mut d1, mut d2) = ([FloatExp::ONE, FloatExp::ZERO], [FloatExp::ZERO; 2]);
        let (mut m, mut bound, mut steps) = (start, u_max, 0);
        let mut rem = FloatExp::ZERO;
        let abs = |v: [FloatExp; 2]| norm2(v).sqrt();
        let (u, u2, u3) = (u_max, u_max * u_max, u_max * u_max * u_max);
        let limit = eps / 4.0;
        while let Some((e, len)) = table.lookup_untested(m, bound * bound, max_iter - m) {
            // δ = K1 u + K2 u^2 and c = u (Julia: B = AB = B2 = 0, so c drops out):
            // A δ + B u + A2 δ^2 + AB δ u + B2 u^2 to second order in u.
            let (f, q) = (e.first, e.second);
            let n2 = cadd(cadd(cmul(f.a, k2), cmul(q.a2, cmul(k1, k1))), cadd(cmul(q.ab, k1), q.b2));
            let n1 = cadd(cmul(f.a, k1), f.b);
            let (a, a2, ab) = (abs(f.a), abs(q.a2), abs(q.ab));
            let (k1a, k2a) = (abs(k1), abs(k2));
            let lead = k1a * u + k2a * u2;
            let carried = a * rem + a2 * (lead.ldexp(1) * rem + rem * rem) + ab * u * rem;
            let dropped = a2 * ((k1a * k2a).ldexp(1) * u3 + k2a * k2a * u2 * u2) + ab * k2a * u3;
            let next = carried + dropped;
            let floor = abs(n1) * u - abs(n2) * u2;
            if floor <= FloatExp::ZERO || next > floor.mul_f64(limit) {
                break;
            }
            // d(δ')/d(δ) = A + 2 A2 δ + AB u = A + (2 A2 K1 + AB) u + O(u^2).
            let slope = cadd(cmul([q.a2[0].ldexp(1), q.a2[1].ldexp(1)], k1), q.ab);
            (d1, d2) = (cmul(f.a, d1), cadd(cmul(f.a, d2), cmul(slope, d1)));
            (k1, k2, rem) = (n1, n2, next);
            bound = abs(k1) * u + abs(k2) * u2 + rem;
            m += len;
            steps += 1;
        }
        (steps > 0).then_some(Skip { m, k: [k1, k2], d: [d1, d2], steps })
    }
}
