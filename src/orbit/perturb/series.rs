//! The view-wide series: every sample's delta at a reference index m as one polynomial of
//! high degree in its offset, computed from the reference orbit directly, with a bound on
//! what it leaves out; samples whose own bound passes start at m.
//!
//! This is the series approximation of Kalles Fraktaler and rust-fractal-core, where
//! δ_n = Σ A_(n,k) δc^k is carried to a fixed degree and its reach is judged by probe
//! samples. Here the reach is bounded instead. With u = δc / s (s a little more than the
//! view's largest offset, so every sample has |u| <= 0.8) the truncated polynomial
//! P_n(u) = Σ_(k=1..K) B_(n,k) u^k steps as δ does, δ -> 2 Z_n δ + δ^2 + s u (no s u for
//! Julia sets, whose delta lives in z_0), each product cut back to degree K. Two bounds go
//! with it, on the unit disk |u| <= 1, in the sum of the coefficients' moduli (a norm that
//! products respect):
//! - r, on what the cuts dropped, a power series in u whose terms all have degree above
//!   K, so |dropped(u)| <= r |u|^(K+1);
//! - g, on what rounding changed (the f64 coefficients and the f64 reference values), terms
//!   of any degree from 1, so |rounded(u)| <= g |u|.
//!
//! A step maps the error e = (true δ) - P through 2 Z e + 2 P e + e^2, so each bound grows
//! by 2 |Z| + 2 |P| + (the other bound) and takes in what the step drops or rounds anew.
//!
//! What a sample needs is that the delta it starts with stands for an offset within a tiny
//! fraction `tol` of its own spacing: |P(u) - δ_m| <= tol · h · |δ_m'(u)| (h: the spacing
//! in units of u; δ_m' = dδ_m/du), and, with a distance estimate, the derivative within
//! `tol` of itself. `tol` holds the truncation; the rounding bound, a worst case that adds
//! every rounding the same way, is held to a looser fraction ([`ROUNDED`]), as the engine's
//! single steps and BLA tables round in f64 without one. Both are tested at each sample's start (about 2K complex multiply-adds
//! beside the 2K of evaluating P and P'); a sample that fails starts from the BLA skip
//! ([`super::Skip`]) as before. The series goes on while a sample at the disk's edge with
//! the centre's slope |P'| = |B_1| would pass (the last such index is the stop `far`), and
//! keeps a second, earlier stop where every sample of the disk passes by a lower bound on
//! |P'| over it (`safe`), for samples `far` leaves out. At most [`MAX_STEPS`] iterations
//! are composed: past them the BLA skip and the tables serve.
//!
//! The bounds make the reach certain where probe samples can miss a sample that fails.
//! Where the BLA tables cannot merge steps (deltas far above their radii, from zoom 1e6 to
//! 1e15) the series still holds, since it keeps the nonlinear terms the tables' radii
//! exclude; docs/performance.md gives its reach along the seahorse descent and at the
//! benchmark locations. The series is not used without BLA (`compare`'s exact rows).

use crate::num::FloatExp;
use crate::num::real::{cadd, cmul};
use crate::orbit::reference::Reference;

/// Degree of the series.
pub const DEGREE: usize = 32;
/// The series' unit disk is this much wider than the view's largest offset: every sample
/// has |u| <= 1 / MARGIN = 0.8, where the bounds on derivatives below hold.
const MARGIN: f64 = 1.25;
/// The most iterations the series composes (at DEGREE^2 complex operations each).
pub const MAX_STEPS: u32 = 4096;
/// What a term of the series costs each sample's start, in the iterations it skips (a
/// step of Horner's rule for P and P' takes about as long as two or three single steps
/// in the vector lanes, by the profile of the seahorse descent at zoom 1e8): the stop is
/// the one that skips the most iterations less this times the terms it keeps.
const TERM_COST: f64 = 3.0;
/// Unit roundoff of f64.
const UNIT: f64 = f64::EPSILON / 2.0;
/// Absolute rounding floor per operation for values near f64's bottom (reference values
/// stored as subnormals or zero, coefficients that underflow).
const FLOOR: f64 = f64::MIN_POSITIVE;
/// max over k >= 1 of k t^(k-1) at t = 0.8 (k = 4 and 5 give 2.048): bounds the derivative
/// of a series of degree >= 1 with coefficient sum 1 at |u| <= 0.8.
const SLOPE: f64 = 2.05;
/// The series' tolerance on its truncation relative to the BLA tolerance ε: at ε = 1e-14
/// a sample's start stands for an offset within 1e-10 of its spacing, and its derivative
/// is within 1e-10 of itself. (At 1e-6 the deep tests found samples within 1e-9 to 1e-5
/// spacings of the boundary moved across it.)
const TOL_PER_EPS: f64 = 1e4;
/// What the rounding bound may reach, in spacings (and relative to the derivative). The
/// bound adds every rounding as if all went the same way, compounded by the coefficient
/// norm's growth; the engine's single steps and BLA tables round in f64 without a bound at
/// all. Held to the truncation's tolerance it would stop the series within a few dozen
/// iterations, so it only guards against a polynomial whose evaluation cancels badly.
const ROUNDED: f64 = 1e-6;

/// Error bounds at one |u| (see [`Checkpoint::errors`]): the truncation's on the value and
/// the slope, and the rounding's.
#[derive(Debug, Clone, Copy)]
struct Bounds {
    value: f64,
    slope: f64,
    rounded: f64,
    rounded_slope: f64,
}

impl Bounds {
    /// Whether a start with these bounds and slope |P'| = `slope` stands for an offset
    /// within `tol` of a spacing `h` (truncation) and within [`ROUNDED`] of it (rounding), and,
    /// with a `derivative`, has P' within the same fractions of itself.
    #[inline]
    fn hold(&self, slope: f64, tol: f64, h: f64, derivative: bool) -> bool {
        let low = slope - self.slope - self.rounded_slope;
        low > 0.0
            && self.value <= tol * h * low
            && self.rounded <= ROUNDED * h * low
            && (!derivative || (self.slope <= tol * low && self.rounded_slope <= ROUNDED * low))
    }
}

/// One stop of the series: the polynomial at reference index `m` and its bounds.
#[derive(Debug, Clone, Copy)]
pub struct Checkpoint {
    /// Reference index (and iteration) the samples continue from.
    pub m: u32,
    /// Terms kept: coefficients of u^1 ..= u^degree (the rest was moved into `r`).
    degree: usize,
    /// B_1 ..= B_degree.
    coef: [[f64; 2]; DEGREE],
    /// Sum of the coefficients' moduli.
    norm: f64,
    /// Bound on the rounding part (degree >= 1).
    g: f64,
    /// Bound on the dropped part (degree > `degree`).
    r: f64,
    /// d(δ_m)/d(δ_start) = D1 + D2 δc to first order (interior detection's derivative).
    pub d: [[FloatExp; 2]; 2],
}

/// The series of a view: its scale s and tolerance, and up to two stops.
#[derive(Debug, Clone, Copy)]
pub struct Series {
    /// u = δ / s.
    inv_scale: FloatExp,
    /// The tolerance `tol` (module docs).
    tol: f64,
    /// Where a sample at the view's centre would still pass.
    pub far: Checkpoint,
    /// Where every sample of the disk passes, if earlier than `far`.
    pub safe: Option<Checkpoint>,
}

/// A sample's start from the series: δ_m, dδ_m/dδc times the spacing, and the stop used.
pub struct Start {
    /// δ_m (plane units).
    pub dz: [FloatExp; 2],
    /// d(δ_m)/d(δc) times the spacing.
    pub der: [FloatExp; 2],
    /// The reference index it starts at.
    pub m: u32,
    /// Interior detection's derivative there ([`Checkpoint::d`]).
    pub d: [[FloatExp; 2]; 2],
}

impl Series {
    /// The series of the primary reference `r` from index `start` (1 for the Mandelbrot
    /// set, where δ_1 = δc, 0 for Julia sets, where δ_0 is the offset) for offsets up to
    /// `extent` and samples `spacing` apart, within `max_iter`, at BLA tolerance `eps`.
    /// None where it would not reach past `beyond` (the BLA skip's stop) or the view is too
    /// deep for f64 coefficients.
    #[allow(clippy::too_many_arguments)] // the view's numbers, each named in the doc
    pub fn find(
        r: &Reference,
        start: u32,
        mandelbrot: bool,
        extent: FloatExp,
        spacing: FloatExp,
        escape_radius: f64,
        max_iter: u32,
        eps: f64,
        derivative: bool,
        beyond: u32,
    ) -> Option<Series> {
        let scale = extent.mul_f64(MARGIN);
        // Products of two coefficients (about s^2) stay normal f64.
        if extent.is_zero() || scale.exponent() < -480 || scale.exponent() > 0 {
            return None;
        }
        let s = scale.to_f64();
        let h = (spacing / scale).to_f64();
        let tol = (eps * TOL_PER_EPS).min(1e-3);
        // One short of the dense part's last value: a sample that reaches it goes on through
        // the packed tail or rebases at a nucleus's period, which a start there would skip.
        let limit = r.last().saturating_sub(1).min(max_iter.saturating_sub(1)).min(start + MAX_STEPS);
        let abs = |v: [f64; 2]| (v[0] * v[0] + v[1] * v[1]).sqrt();
        let mut b = [[0.0; 2]; DEGREE];
        b[0] = [s, 0.0];
        let (mut g, mut rem) = (0.0f64, 0.0f64);
        let (mut d0, mut d1) = ([FloatExp::ONE, FloatExp::ZERO], [FloatExp::ZERO; 2]);
        // The best stops so far by their worth (iterations skipped less the terms' cost).
        let (mut far, mut safe) = (None::<(f64, Checkpoint)>, None::<(f64, Checkpoint)>);
        let mut n = start;
        let inv = FloatExp::ONE / scale;
        let t = 1.0 / MARGIN;
        // The coefficients' moduli and their sum, carried from one iteration to the next.
        let mut a: [f64; DEGREE] = std::array::from_fn(|k| abs(b[k]));
        let mut norm: f64 = a.iter().sum();
        while n < limit {
            let z = r.get(n);
            let za = abs(z);
            // Every sample stays inside the escape circle at n (the loop would stop it).
            if za + norm + g + rem >= escape_radius {
                break;
            }
            let z2 = [2.0 * z[0], 2.0 * z[1]];
            let mut next = [[0.0; 2]; DEGREE];
            let mut rounding = 0.0;
            for k in 0..DEGREE {
                // Coefficient of u^(k+1): 2 Z B_(k+1) + Σ B_(i+1) B_(j+1) over i + j = k - 1.
                let mut acc = cmul(z2, b[k]);
                let mut size = 2.0 * za * a[k];
                for i in 0..k {
                    acc = cadd(acc, cmul(b[i], b[k - 1 - i]));
                    size += a[i] * a[k - 1 - i];
                }
                if k == 0 && mandelbrot {
                    acc[0] += s;
                    size += s;
                }
                next[k] = acc;
                rounding += (k as f64 + 4.0) * UNIT * size + 4.0 * (k as f64 + 2.0) * FLOOR;
            }
            // What the cut drops: the products B_(i+1) B_(j+1) of degree i + j + 2 > DEGREE.
            let mut dropped = 0.0;
            let mut upper = 0.0;
            for i in 0..DEGREE {
                // upper = a[DEGREE - 1 - i] + ... + a[DEGREE - 1].
                upper += a[DEGREE - 1 - i];
                dropped += a[i] * upper;
            }
            // The reference value's own rounding to f64 (2 Z δ with |ΔZ| <= UNIT |Z|).
            rounding += 2.0 * UNIT * za * norm + 2.0 * FLOOR * norm;
            let grow = 2.0 * za + 2.0 * norm;
            let new_rem = grow * rem + 2.0 * g * rem + rem * rem + dropped;
            let new_g = grow * g + g * g + rounding;
            // Interior detection's derivative: D' = 2 (Z + δ) D to first order in u.
            let zf = [FloatExp::from(z2[0]), FloatExp::from(z2[1])];
            let b1 = [FloatExp::from(2.0 * b[0][0]), FloatExp::from(2.0 * b[0][1])];
            (d0, d1) = (cmul(zf, d0), cadd(cmul(zf, d1), cmul(b1, d0)));
            b = next;
            g = new_g;
            rem = new_rem;
            n += 1;
            if !(g.is_finite() && rem.is_finite()) {
                break;
            }
            a = std::array::from_fn(|k| abs(b[k]));
            norm = a.iter().sum();
            let stop =
                Checkpoint { m: n, degree: DEGREE, coef: b, norm, g, r: rem, d: [d0, [d1[0] * inv, d1[1] * inv]] };
            let lead = a[0];
            let e = stop.errors(t);
            // A sample at the disk's edge whose slope were the centre's (|P'| = |B_1|) fails
            // from here on: stop.
            if !e.hold(lead, tol, h, derivative) {
                break;
            }
            let worth = |c: &Checkpoint| {
                let kept = c.fewest_terms(&a, tol, h, derivative);
                (f64::from(c.m) - TERM_COST * kept as f64, kept)
            };
            let (w, kept) = worth(&stop);
            if far.as_ref().is_none_or(|f| w > f.0) {
                far = Some((w, stop.trimmed(kept, &a)));
            }
            // A lower bound on |P'| over |u| <= 0.8.
            let spread: f64 = (1..DEGREE).map(|k| (k + 1) as f64 * a[k] * t.powi(k as i32)).sum();
            if e.hold(lead - spread, tol, h, derivative) && safe.as_ref().is_none_or(|f| w > f.0) {
                safe = Some((w, stop.trimmed(kept, &a)));
            }
        }
        let far = far.map(|f| f.1).filter(|f| f.m > beyond)?;
        let safe = safe.map(|s| s.1).filter(|s| s.m > beyond && s.m < far.m);
        Some(Series { inv_scale: inv, tol, far, safe })
    }

    /// A sample's start at δc (Mandelbrot) or δ_0 (Julia) `dc` for samples `spacing` apart:
    /// from the farthest stop whose bounds hold for it, or None.
    pub fn start(&self, dc: [FloatExp; 2], spacing: FloatExp, derivative: bool) -> Option<Start> {
        let [s] = self.starts(&[dc], spacing, derivative);
        s
    }

    /// [`Series::start`] of `N` samples at once. Horner's rule for one sample is a chain of
    /// dependent multiplies and adds; here the `N` chains run in one loop and overlap. Each
    /// sample's operations are the ones it would take alone, in the same order, so each
    /// start has the same bits.
    pub fn starts<const N: usize>(
        &self,
        dc: &[[FloatExp; 2]; N],
        spacing: FloatExp,
        derivative: bool,
    ) -> [Option<Start>; N] {
        let u: [[f64; 2]; N] =
            std::array::from_fn(|j| [(dc[j][0] * self.inv_scale).to_f64(), (dc[j][1] * self.inv_scale).to_f64()]);
        // (Moduli by square roots here, not `hypot`: every value is far from f64's limits.)
        let t: [f64; N] = std::array::from_fn(|j| (u[j][0] * u[j][0] + u[j][1] * u[j][1]).sqrt());
        let h = (spacing * self.inv_scale).to_f64();
        let from = |at: &Checkpoint, (p, dp): ([f64; 2], [f64; 2]), t: f64| -> Option<Start> {
            let slope = (dp[0] * dp[0] + dp[1] * dp[1]).sqrt();
            at.errors(t).hold(slope, self.tol, h, derivative).then(|| Start {
                dz: [FloatExp::from(p[0]), FloatExp::from(p[1])],
                der: [FloatExp::from(dp[0] * h), FloatExp::from(dp[1] * h)],
                m: at.m,
                d: at.d,
            })
        };
        let far = self.far.eval(&u);
        std::array::from_fn(|j| {
            // (A NaN offset fails too.)
            if t[j].is_nan() || t[j] > 1.0 / MARGIN {
                return None;
            }
            from(&self.far, (far.0[j], far.1[j]), t[j]).or_else(|| {
                let safe = self.safe.as_ref()?;
                let ([p], [dp]) = safe.eval(&[u[j]]);
                from(safe, (p, dp), t[j])
            })
        })
    }

    /// The series' degree.
    pub fn degree(&self) -> usize {
        self.far.degree
    }
}

impl Checkpoint {
    /// The fewest terms (at least 4) that keep this stop's error bounds at a sample of the
    /// disk's edge within a quarter of what one at the centre may have, the terms left out
    /// moving into the bound r (they have degree above those kept). `a`: the coefficients'
    /// moduli.
    fn fewest_terms(&self, a: &[f64; DEGREE], tol: f64, h: f64, derivative: bool) -> usize {
        let lead = a[0];
        let e = self.errors(1.0 / MARGIN);
        let (val_room, der_room) = (e.value.max(0.25 * tol * h * lead), e.slope.max(0.25 * tol * lead));
        let mut tail = 0.0;
        let mut kept = self.degree;
        for k in (4..self.degree).rev() {
            // Keep u^1 ..= u^k; u^(k+1) ..= u^degree join the dropped part.
            tail += a[k];
            let c = Checkpoint { degree: k, norm: self.norm - tail, r: self.r + tail, ..*self };
            let e = c.errors(1.0 / MARGIN);
            if e.value > val_room || (derivative && e.slope > der_room) {
                break;
            }
            kept = k;
        }
        kept
    }

    /// This stop with its first `kept` terms, the rest moved into the bound r.
    fn trimmed(&self, kept: usize, a: &[f64; DEGREE]) -> Checkpoint {
        let tail: f64 = a[kept..].iter().sum();
        let mut c = Checkpoint { degree: kept, norm: self.norm - tail, r: self.r + tail, ..*self };
        c.coef[kept..].fill([0.0; 2]);
        c
    }

    /// P(u) and P'(u) by Horner's rule at each of `N` points, the points' chains in one loop.
    #[inline]
    fn eval<const N: usize>(&self, u: &[[f64; 2]; N]) -> ([[f64; 2]; N], [[f64; 2]; N]) {
        // Q(u) = Σ B_k u^(k-1): P = u Q, P' = Q + u Q'.
        let (mut q, mut dq) = ([self.coef[self.degree - 1]; N], [[0.0; 2]; N]);
        for k in (0..self.degree - 1).rev() {
            for j in 0..N {
                dq[j] = cadd(cmul(dq[j], u[j]), q[j]);
                q[j] = cadd(cmul(q[j], u[j]), self.coef[k]);
            }
        }
        (std::array::from_fn(|j| cmul(u[j], q[j])), std::array::from_fn(|j| cadd(q[j], cmul(u[j], dq[j]))))
    }

    /// Bounds on |P(u) - δ(u)| and |P'(u) - δ'(u)| at |u| = t <= 0.8, the truncation's and
    /// the rounding's apart (with the rounding of evaluating P and P' by Horner's rule, 2
    /// degree complex operations).
    #[inline]
    fn errors(&self, t: f64) -> Bounds {
        let k = self.degree as f64;
        // Horner's rounding: (4 degree + 4) UNIT Σ |B_k| t^k for P, the same with k |B_k|
        // t^(k-1) (at most SLOPE Σ |B_k|) for P': both within g's terms.
        let g = self.g + (4.0 * k + 4.0) * UNIT * self.norm;
        let tk = t.powi(self.degree as i32);
        Bounds { value: self.r * tk * t, slope: (k + 1.0) * self.r * tk, rounded: g * t, rounded_slope: SLOPE * g }
    }
}
