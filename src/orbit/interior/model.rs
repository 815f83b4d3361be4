//! The quadratic model of a minibrot: near the nucleus of a period-p reference, one turn of
//! the orbit is close to w -> f^p(0) + Λ w^2, which the coordinate z = Λ w makes the
//! standard z -> z^2 + c' (Douady and Hubbard's renormalisation; a minibrot is a small
//! distorted copy of the whole set). Interior detection asks the model what a sample's orbit
//! will do before iterating it: escape (the sample leaves detection), or settle on an
//! attracting cycle of k turns, whose point near 0 starts Newton's test of period k p; the
//! certified disks ask it which parts of a batch lie well inside the cardioid or a bulb.
//!
//! Everything here is plain f64 on z^2 + c: the model only decides where to spend the
//! certificates' time, never a sample's result (a wrong verdict costs time, not a pixel).

use crate::num::real::{cmul, norm2};

/// The longest cycle the quadratic model's orbit is searched for, in periods: bulbs of the
/// minibrot, and the minibrots embedded near its edge, whose samples Newton's test from an
/// anchor (`Perturbation::newton_probe`) would reach only after many turns and the
/// contraction criterion only after thousands (their multiplier per turn is near 1). A
/// Newton test of k turns is tried only where the iteration limit holds
/// [`super::MODEL_TURNS_SPARE`] such tests.
pub(in crate::orbit) const MAX_PERIODS: u32 = 1024;
/// Iterations of the quadratic model's orbit at most ([`super::Perturbation::model_cycle`]).
pub(in crate::orbit) const ITERATIONS: u32 = 8192;
/// The Newton search for a period n found at a new minimum of |z_n| waits until iteration
/// n times this, for an orbit that escapes by then (most outside the set) to cost nothing.
const NEWTON_DELAY: u32 = 4;
/// Newton's steps at most in [`attractor`].
const NEWTON_STEPS: u32 = 24;
/// [`attractor`] has converged once a Newton step's squared length is below this.
const NEWTON_CLOSE2: f64 = 1e-26;
/// Newton's squared step below which [`attractor`] judges the multiplier: known then to
/// about 10^-5, and a cycle nearer neutral than that is no start the certificate could use
/// (its bound needs the multiplier 10^-5 below 1:
/// [`crate::orbit::interior::newton_attracting`]).
const NEWTON_JUDGE2: f64 = 1e-10;
/// A cycle point that comes back within this squared distance after a divisor of the period
/// has that period (well above the rounding of k steps, far below any two points of a cycle
/// the model's start can use).
const NEWTON_BACK2: f64 = 1e-18;

/// The attracting fixed point of z -> z^2 + c, (1 - sqrt(1 - 4c)) / 2, whose multiplier is
/// 1 - sqrt(1 - 4c); None where that is not below 1 in modulus (c outside the main cardioid)
/// or not a number (an overflowed c).
pub(in crate::orbit) fn fixed_point(c: [f64; 2]) -> Option<[f64; 2]> {
    let (z, mult2) = fixed_point_of(c);
    // Not a number compares false: refused.
    (mult2 < 1.0).then_some(z)
}

/// [`fixed_point`] as a point and its multiplier's squared modulus, branch-free (a loop of
/// these is vectorised).
#[inline(always)]
pub(in crate::orbit) fn fixed_point_of(c: [f64; 2]) -> ([f64; 2], f64) {
    let (x, y) = (1.0 - 4.0 * c[0], -4.0 * c[1]);
    // Not hypot (a libm call): an |x| or |y| past 1e154 makes r infinite and the multiplier
    // not a number, which is refused below as it should be.
    let r = (x * x + y * y).sqrt();
    let sq = [((r + x) / 2.0).sqrt(), ((r - x) / 2.0).sqrt().copysign(y)];
    let mult = [1.0 - sq[0], -sq[1]];
    ([mult[0] / 2.0, mult[1] / 2.0], mult[0] * mult[0] + mult[1] * mult[1])
}

/// What the orbit of 0 under the quadratic model z -> z^2 + c does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::orbit) enum Model {
    /// It settles on a cycle: a point of it, and its period.
    Cycle([f64; 2], u32),
    /// It escapes (|z| > 2): c is outside the model's Mandelbrot set.
    Escapes,
    /// Neither within [`ITERATIONS`], or its cycle is longer than [`MAX_PERIODS`].
    Unsettled,
}

/// Where the orbit of 0 under z -> z^2 + c goes within [`ITERATIONS`]: a point of the
/// attracting cycle it settles on, of period 2 to [`MAX_PERIODS`], and its period; or
/// that it escapes.
///
/// The cycle is solved for, not waited for: at each iteration n where |z_n| reaches a new
/// minimum (n is then the period of an atom domain that holds c, after Claude
/// Heiland-Allen's notes on atom domains; a hyperbolic component lies inside the domain of
/// its own period), Newton's method looks for an n-cycle from 0 ([`attractor`]), and
/// an attracting one ends the search; the search waits [`NEWTON_DELAY`] times n
/// iterations, and an orbit that escapes meanwhile (most outside the set) costs none.
/// Waiting instead for the orbit to come back to itself (Brent's cycle detection, as this
/// did before) takes log(accuracy) / log|λ| turns of the cycle, hundreds near a bulb's edge
/// where |λ| is near 1 (on the 1e-102 minibrot view: 579 iterations a sample on average,
/// and 621 samples not settled within [`ITERATIONS`]); Newton's method takes a few
/// times the period there too.
pub(in crate::orbit) fn settled_cycle(c: [f64; 2]) -> Model {
    cycle_within(c, ITERATIONS)
}

/// [`settled_cycle`] within `iterations`.
pub(in crate::orbit) fn cycle_within(c: [f64; 2], iterations: u32) -> Model {
    // A parameter that is not a number escapes at once; from a finite one the orbit stays
    // finite until it escapes, so the loop tests |z|^2 > 4 alone.
    if !(c[0].is_finite() && c[1].is_finite()) {
        return Model::Escapes;
    }
    // The products of z that the escape test takes are those the next step needs: x^2 - y^2
    // and 2 x y (as xy + xy, the same bits).
    let (mut x2, mut y2, mut xy) = (0.0, 0.0, 0.0);
    // The latest new minimum's iteration, and when its Newton search is due.
    let (mut least, mut period, mut due) = (f64::INFINITY, 0, 0);
    for n in 1..=iterations {
        let z = [x2 - y2 + c[0], xy + xy + c[1]];
        (x2, y2, xy) = (z[0] * z[0], z[1] * z[1], z[0] * z[1]);
        let r2 = x2 + y2;
        if r2 > 4.0 {
            return Model::Escapes;
        }
        if r2 < least {
            (least, period, due) = (r2, n, n.saturating_mul(NEWTON_DELAY));
        }
        if n == due
            && (2..=MAX_PERIODS).contains(&period)
            && let Some((w, k)) = attractor(c, period)
        {
            return Model::Cycle(w, k);
        }
    }
    Model::Unsettled
}

/// An attracting cycle of z -> z^2 + c whose period divides `n`, by Newton's method on
/// f^n(w) - w from w = 0 (whose first step lands on z_n): its point near 0 and its exact
/// period. None where Newton's method leaves |w| <= 2 (every cycle lies inside), has not
/// converged within [`NEWTON_STEPS`], or converges on a repelling cycle, which it
/// takes for one as soon as a step is below [`NEWTON_JUDGE2`] with |f^n'| >= 1.
pub(in crate::orbit) fn attractor(c: [f64; 2], n: u32) -> Option<([f64; 2], u32)> {
    attractor_from(c, n, [0.0, 0.0], NEWTON_STEPS)
}

/// [`attractor`] from `w` rather than 0, within `steps` Newton steps: from a point of a
/// neighbouring parameter's attracting n-cycle, a few steps reach this parameter's, where
/// it has one of that period.
pub(in crate::orbit) fn attractor_from(c: [f64; 2], n: u32, mut w: [f64; 2], steps: u32) -> Option<([f64; 2], u32)> {
    for _ in 0..steps {
        let (mut z, mut d) = (w, [1.0, 0.0]);
        for _ in 0..n {
            d = cmul([2.0 * z[0], 2.0 * z[1]], d);
            z = step(z, c);
        }
        // (f^n(w) - w) / (f^n'(w) - 1), as g conj(g') / |g'|^2.
        let (g, gd) = ([z[0] - w[0], z[1] - w[1]], [d[0] - 1.0, d[1]]);
        let q = cmul(g, [gd[0], -gd[1]]);
        let newton = [q[0] / norm2(gd), q[1] / norm2(gd)];
        w = [w[0] - newton[0], w[1] - newton[1]];
        let r2 = norm2(w);
        if r2 > 4.0 || r2.is_nan() {
            return None;
        }
        let (moved2, mult2) = (norm2(newton), norm2(d));
        if moved2 <= NEWTON_JUDGE2 && mult2 >= 1.0 {
            return None;
        }
        if moved2 <= NEWTON_CLOSE2 {
            // The exact period: the first divisor of n after which w comes back.
            let mut y = w;
            for k in 1..n {
                y = step(y, c);
                if n.is_multiple_of(k) && norm2([y[0] - w[0], y[1] - w[1]]) <= NEWTON_BACK2 {
                    return Some((w, k));
                }
            }
            return Some((w, n));
        }
    }
    None
}

/// One step of the quadratic model, z^2 + c.
#[inline(always)]
fn step(z: [f64; 2], c: [f64; 2]) -> [f64; 2] {
    [z[0] * z[0] - z[1] * z[1] + c[0], 2.0 * z[0] * z[1] + c[1]]
}

/// True when the orbit of 0 under z -> z^2 + c escapes within `iterations` and the
/// distance estimate puts c farther than `r` from the Mandelbrot set: with the estimate
/// d = 2 |z| ln|z| / |dz/dc| taken where |z| has passed 1e4, Koebe's quarter theorem keeps
/// the true distance above d / 4 (as |z| grows), so c is taken as far where d / 4 > r.
pub(in crate::orbit) fn far(c: [f64; 2], r: f64, iterations: u32) -> bool {
    let (mut z, mut dz) = ([0.0, 0.0], [0.0, 0.0]);
    for _ in 0..iterations {
        dz = [2.0 * (z[0] * dz[0] - z[1] * dz[1]) + 1.0, 2.0 * (z[0] * dz[1] + z[1] * dz[0])];
        z = step(z, c);
        let r2 = norm2(z);
        if r2 > 1e8 {
            let size = r2.sqrt();
            return 2.0 * size * size.ln() / norm2(dz).sqrt() > 4.0 * r;
        }
        if r2.is_nan() {
            return false;
        }
    }
    false
}

/// The multiplier of the k-cycle of z -> z^2 + c through `z`: the product of 2 z_i round it.
pub(in crate::orbit) fn multiplier(c: [f64; 2], mut z: [f64; 2], k: u32) -> [f64; 2] {
    let mut mu = [1.0, 0.0];
    for _ in 0..k {
        mu = cmul(mu, [2.0 * z[0], 2.0 * z[1]]);
        z = step(z, c);
    }
    mu
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The model's cycle finder on parameters of known period: the period-2 bulb, the
    /// airplane and the rabbit (3), nuclei of the 1/q bulbs of the main cardioid for q up
    /// to [`MAX_PERIODS`] (the longest cycle the search tries), each found here by Newton's
    /// method on f_c^q(0) = 0 from the bulb's estimated centre, and parameters near the edge
    /// of the period-2 bulb whose 2-cycle attracts slowly (multiplier 0.999 and 0.9999 in
    /// modulus: an orbit waited for would take 10^4 to 10^5 turns to settle, past
    /// [`ITERATIONS`]). The point returned must lie on a cycle of exactly the period
    /// returned. Outside the set (beside the cusp, past the tip) there is no cycle; at the
    /// Feigenbaum point none settles.
    #[test]
    fn model_settled_cycle_finds_cycles_of_every_period_to_its_limit() {
        let step = |z: [f64; 2], c: [f64; 2]| [z[0] * z[0] - z[1] * z[1] + c[0], 2.0 * z[0] * z[1] + c[1]];
        let far2 = |a: [f64; 2], b: [f64; 2]| norm2([a[0] - b[0], a[1] - b[1]]);
        let check = |c: [f64; 2], want: u32| {
            let Model::Cycle(z, k) = settled_cycle(c) else { panic!("{c:?}: no cycle found") };
            assert_eq!(k, want, "{c:?}");
            let mut y = z;
            for j in 1..=k {
                y = step(y, c);
                if j < k {
                    assert!(far2(y, z) > NEWTON_BACK2, "{c:?}: back after {j} of {k}");
                }
            }
            assert!(far2(y, z) < 1e-10, "{c:?}: not a {k}-cycle");
        };
        check([-1.0, 0.0], 2);
        // The period-2 bulb is |c + 1| < 1/4, its 2-cycle's multiplier 4 (c + 1).
        for (m, t) in [(0.999, 1.0f64), (0.9999, 2.5), (0.9999, -0.3)] {
            check([-1.0 + m / 4.0 * t.cos(), m / 4.0 * t.sin()], 2);
        }
        check([-1.754877666246693, 0.0], 3);
        check([-0.12256116687665362, 0.7448617666197442], 3);
        // The 1/q bulb touches the cardioid c = μ/2 - μ^2/4 at μ = e^(2πi/q); its centre lies
        // outward, about sin(π/q)/q^2 from there.
        let nucleus = |q: u32| {
            let t = std::f64::consts::TAU / q as f64;
            let mu = [t.cos(), t.sin()];
            let mu2 = [mu[0] * mu[0] - mu[1] * mu[1], 2.0 * mu[0] * mu[1]];
            let root = [mu[0] / 2.0 - mu2[0] / 4.0, mu[1] / 2.0 - mu2[1] / 4.0];
            let out = [mu[0] - mu2[0], mu[1] - mu2[1]];
            let (n, r) = (out[0].hypot(out[1]), (std::f64::consts::PI / q as f64).sin() / (q * q) as f64);
            let mut c = [root[0] + out[0] / n * r, root[1] + out[1] / n * r];
            for _ in 0..60 {
                let (mut z, mut dz) = ([0.0, 0.0], [0.0, 0.0]);
                for _ in 0..q {
                    dz = [2.0 * (z[0] * dz[0] - z[1] * dz[1]) + 1.0, 2.0 * (z[0] * dz[1] + z[1] * dz[0])];
                    z = step(z, c);
                }
                let d2 = dz[0] * dz[0] + dz[1] * dz[1];
                c = [c[0] - (z[0] * dz[0] + z[1] * dz[1]) / d2, c[1] - (z[1] * dz[0] - z[0] * dz[1]) / d2];
            }
            c
        };
        for q in [5, 17, 65, 100, 200, MAX_PERIODS] {
            check(nucleus(q), q);
        }
        assert_eq!(settled_cycle([0.26, 0.0]), Model::Escapes);
        assert_eq!(settled_cycle([-2.01, 0.0]), Model::Escapes);
        assert_eq!(settled_cycle([f64::NAN, 0.0]), Model::Escapes);
        // The Feigenbaum point: its orbit neither escapes nor settles on a short cycle.
        assert_eq!(settled_cycle([-1.401155189092051, 0.0]), Model::Unsettled);
    }

    /// A parameter the distance estimate calls far from the Mandelbrot set is: every point
    /// of a sweep of disks it calls far escapes (none is in the set), and parameters inside
    /// the set or beside it are never far.
    #[test]
    fn model_far_is_far() {
        let escapes = |c: [f64; 2]| {
            let mut z = [0.0f64, 0.0];
            (0..20000).any(|_| {
                z = [z[0] * z[0] - z[1] * z[1] + c[0], 2.0 * z[0] * z[1] + c[1]];
                norm2(z) > 4.0
            })
        };
        assert!(far([3.0, 0.0], 0.5, 256));
        assert!(!far([0.0, 0.0], 1e-9, 256));
        assert!(!far([-0.75, 0.1], 0.01, 256));
        assert!(!far([0.26, 0.0], 0.1, 256));
        let mut called = 0;
        for i in 0..60 {
            for j in 0..60 {
                let c = [-2.5 + 3.5 * i as f64 / 60.0, -1.5 + 3.0 * j as f64 / 60.0];
                for r in [0.01, 0.05, 0.2] {
                    if !far(c, r, 256) {
                        continue;
                    }
                    called += 1;
                    for k in 0..16 {
                        for t in [0.5, 1.0] {
                            let a = std::f64::consts::TAU * k as f64 / 16.0;
                            let e = [c[0] + t * r * a.cos(), c[1] + t * r * a.sin()];
                            assert!(escapes(e), "{c:?} called farther than {r} from the set, but {e:?} is in it");
                        }
                    }
                }
            }
        }
        assert!(called > 1000, "only {called} disks called far");
    }
}
