//! Bilinear approximation (BLA), carried to second order: tables of steps that skip runs of
//! iterations.
//!
//! One perturbed step z -> 2 Z_m z + z^2 + c is itself a quadratic in (z, c). A run of
//! steps is kept as the quadratic part of its composition,
//! z -> A z + B c + A2 z^2 + AB z c + B2 c^2, and is valid while the terms this drops are
//! below a relative accuracy ε. Two consecutive runs x then y compose exactly to second
//! order (A = A_y A_x, B = A_y B_x + B_y, A2 = A_y A2_x + A2_y A_x^2, ...); what the
//! composition drops is Q (2 A2_y L + A2_y Q + AB_y c), with L and Q the linear and
//! quadratic parts of x's image. The composite is valid for |z| up to the largest radius at
//! which (bounding every coefficient by its modulus and |c| by the largest pixel offset)
//! z is valid for x, x's image is valid for y, |Q| <= ε |A_y| / (4 |A2_y|) (the main dropped
//! term is then ε/2 of y's linear term), |Q| <= |L| and |AB_y| |c| |Q| <= ε/4 |A_y| |L|. Each of
//! these is a quadratic inequality in |z|, solved in closed form. A single step is exact; its
//! radius only keeps the sample away from what a run must not skip: |z| <= |Z_m| / 2 (the
//! sample cannot come nearer to 0 than to the reference inside a run, so no rebase or glitch
//! is skipped) and |z| <= max(R - |Z_m|, ε |Z_m|) (no escape is skipped, but for samples
//! within ε of the escape circle).
//!
//! First order, the same tables would be Zhuoran's BLA, valid while |z| < ε |Z_m|: at the
//! default ε = 1e-14 a sample drifting away from the reference at depth leaves them at
//! |z| ~ 1e-14 and takes single steps for the thousands of iterations its delta needs to grow
//! to |Z|. The second-order terms are valid to |z| ~ sqrt(ε |Z|) ~ 1e-7 for short runs, which
//! covers most of that drift (bench-e50: see docs/engine-notes.md).
//!
//! Merging pairs level by level gives a binary tree: level k holds steps of 2^k iterations
//! starting at origin + i 2^k, so at any index the loop tries the longest aligned step
//! first. Tables are built with wide exponents (radii below 1e-300 and products above 1e300
//! are normal at depth): radii in `FloatExp`, and coefficients, while merging, as complex
//! numbers sharing one exponent ([`Scaled`]: a third less time for the e1086 benchmark's
//! tables than `FloatExp` parts, the same image). They are converted to f64 for the f64
//! phase of the loop, where entries f64 cannot hold are marked unusable. Level 0 (single
//! steps) is not stored: the loop takes those as perturbation steps.

use rayon::prelude::*;

use super::reference::Reference;
use crate::num::real::{cadd, cmul};
use crate::num::{FloatExp, Real, Scaled};

/// The first-order part of a step over 2^level iterations, z -> a z + b c, which is valid on
/// its own while |z|^2 < lin2. Kept apart from the second-order part: most steps at shallow
/// depths and near the start of an orbit need only this, and read 40 bytes.
#[derive(Debug, Clone, Copy)]
pub struct Bla<T> {
    /// Multiplier of the delta.
    pub a: [T; 2],
    /// Multiplier of the pixel offset.
    pub b: [T; 2],
    /// Squared radius of the first-order step (negative: never valid).
    pub lin2: T,
}

/// The second-order part of the same step: z -> ... + a2 z^2 + ab z c + b2 c^2, valid with
/// the first-order part while |z|^2 < r2.
#[derive(Debug, Clone, Copy)]
pub struct Second<T> {
    /// Multiplier of the delta squared.
    pub a2: [T; 2],
    /// Multiplier of delta times offset.
    pub ab: [T; 2],
    /// Multiplier of the offset squared.
    pub b2: [T; 2],
    /// Squared validity radius (negative: never valid).
    pub r2: T,
}

/// A step found by [`BlaTable::lookup`]: both parts.
#[derive(Debug, Clone, Copy)]
pub struct Step<'a, T> {
    /// First-order part.
    pub first: &'a Bla<T>,
    /// Second-order part.
    pub second: &'a Second<T>,
}

impl<T: Real> Step<'_, T> {
    /// True when the first-order step is valid for |z|^2 = `z2`.
    #[inline]
    pub fn linear(&self, z2: T) -> bool {
        z2 < self.first.lin2
    }

    /// The second-order step applied to `z` with offset `c`.
    #[inline]
    pub fn apply(&self, z: [T; 2], c: [T; 2]) -> [T; 2] {
        let q = self.second;
        self.finish(z, c, cadd(cmul(q.a2, z), cmul(q.ab, c)), cmul(q.b2, c))
    }

    /// The second-order step at (z, c), and its Jacobian (m, n): d(out) = m d(z) + n d(c).
    /// Shares the products A2 z, AB c and B2 c between the two.
    #[inline]
    pub fn apply_with_jacobian(&self, z: [T; 2], c: [T; 2]) -> ([T; 2], [T; 2], [T; 2]) {
        let (f, q) = (self.first, self.second);
        let twice = |v: [T; 2]| [v[0] + v[0], v[1] + v[1]];
        let (a2z, abc, b2c) = (cmul(q.a2, z), cmul(q.ab, c), cmul(q.b2, c));
        let m = cadd(cadd(f.a, twice(a2z)), abc);
        let n = cadd(cadd(f.b, cmul(q.ab, z)), twice(b2c));
        (self.finish(z, c, cadd(a2z, abc), b2c), m, n)
    }

    /// a z + b c + z (a2 z + ab c) + c (b2 c), given `zz` = a2 z + ab c and `b2c` = b2 c.
    #[inline]
    fn finish(&self, z: [T; 2], c: [T; 2], zz: [T; 2], b2c: [T; 2]) -> [T; 2] {
        let f = self.first;
        let lin = cadd(cmul(f.a, z), cmul(f.b, c));
        cadd(cadd(lin, cmul(zz, z)), cmul(b2c, c))
    }
}

/// Levels 1.. of the tree for one reference orbit.
#[derive(Debug, Clone)]
pub struct BlaTable<T> {
    origin: u32,
    /// levels[k] holds steps of 2^(k+1) iterations: first-order parts.
    levels: Vec<Vec<Bla<T>>>,
    /// Their second-order parts, alike.
    seconds: Vec<Vec<Second<T>>>,
    /// The squared radii again, by start index: for index i (from the origin) the radii of
    /// its steps of every level, shortest first, side by side (see [`column`]). A lookup then
    /// reads one cache line instead of one per level.
    radii: Vec<T>,
}

/// Where index i's radii start in `radii` and how many there are, for `top` levels. Index
/// i starts steps of levels k < tz(i) (index 0 of all `top`), and sum_{j=1}^{n} tz(j) =
/// n - popcount(n) (Legendre), so the columns before i's take top + (i - 1) - popcount(i - 1).
#[inline]
fn column(i: u32, top: usize) -> (usize, usize) {
    if i == 0 {
        (0, top)
    } else {
        let before = top + (i - 1) as usize - (i - 1).count_ones() as usize;
        (before, (i.trailing_zeros() as usize).min(top))
    }
}

/// The column layout of `levels`' radii; `never` marks a step past a level's end.
fn columns<T: Real>(levels: &[Vec<Second<T>>], never: T) -> Vec<T> {
    let top = levels.len();
    let count = levels.first().map_or(0, |l| 2 * l.len() as u32);
    let mut radii = Vec::with_capacity(count as usize + top);
    for i in 0..count {
        let (start, n) = column(i, top);
        debug_assert_eq!(start, radii.len());
        radii.extend((0..n).map(|k| levels[k].get((i >> (k + 1)) as usize).map_or(never, |e| e.r2)));
    }
    radii
}

/// An entry under construction: radius kept unsquared for merging. The coefficients are
/// complex numbers with one exponent ([`Scaled`]): a complex product is then one f64
/// complex product and one renormalisation, where FloatExp parts take four products, two
/// sums and six renormalisations; the error is relative to each coefficient as a whole,
/// which is how a step uses it.
#[derive(Clone, Copy)]
struct Node {
    a: Scaled,
    b: Scaled,
    a2: Scaled,
    ab: Scaled,
    b2: Scaled,
    r: FloatExp,
    /// Radius of the first-order step (Zhuoran's BLA).
    lin: FloatExp,
}

/// The largest ρ >= 0 such that p ρ^2 + q ρ + s <= 0 holds on all of [0, ρ], for p >= 0;
/// None when it holds for every ρ, zero when it fails at 0.
fn largest_root(p: FloatExp, q: FloatExp, s: FloatExp) -> Option<FloatExp> {
    let zero = FloatExp::ZERO;
    if s > zero {
        return Some(zero);
    }
    if p.is_zero() {
        return (q > zero).then(|| -s / q);
    }
    // Roots of p ρ^2 + q ρ + s with s <= 0: one is >= 0; the form without cancellation.
    let disc = (q * q - (p * s).ldexp(2)).sqrt();
    Some(if q > zero { (-s).ldexp(1) / (q + disc) } else { (disc - q) / p.ldexp(1) })
}

/// x then y, with the radius of the composite (see the module docs); `gamma` is the largest
/// |c|, `eps` the tolerance.
fn merge(x: &Node, y: &Node, gamma: FloatExp, eps: f64) -> Node {
    let a = y.a * x.a;
    let b = y.a * x.b + y.b;
    let a2 = y.a * x.a2 + y.a2 * x.a.square();
    let ab = y.a * x.ab + (y.a2 * (x.a * x.b)).ldexp(1) + y.ab * x.a;
    let b2 = y.a * x.b2 + y.a2 * x.b.square() + (y.ab * x.b + y.b2);
    let [ax, bx, a2x, abx, b2x] = [x.a, x.b, x.a2, x.ab, x.b2].map(Scaled::abs);
    let [ay, a2y, aby] = [y.a, y.a2, y.ab].map(Scaled::abs);
    let g = gamma;
    // |Q| <= a2x ρ^2 + abx g ρ + b2x g^2, |L| <= ax ρ + bx g.
    let (qp, qq, qs) = (a2x, abx * g, b2x * g * g);
    let quarter = FloatExp::from(eps / 4.0);
    let bounds = [
        // x's image within y's radius.
        largest_root(qp, ax + qq, bx * g + qs - y.r),
        // |Q| <= |L|.
        largest_root(qp, qq - ax, qs - bx * g),
        // |AB_y| g |Q| <= ε/4 |A_y| |L|.
        largest_root(aby * g * qp, aby * g * qq - quarter * ay * ax, aby * g * qs - quarter * ay * bx * g),
        // |Q| <= ε |A_y| / (4 |A2_y|) (no bound where y has no quadratic term).
        if a2y.is_zero() { None } else { largest_root(qp, qq, qs - quarter * ay / a2y) },
    ];
    let r = bounds.into_iter().flatten().fold(x.r, FloatExp::min);
    // First order: z valid for x and A_x z + B_x c valid for y.
    let through = (y.lin - bx * g).max(FloatExp::ZERO);
    let lin = x.lin.min(if ax.is_zero() { y.lin.max(FloatExp::ZERO) } else { through / ax });
    Node { a, b, a2, ab, b2, r, lin }
}

impl BlaTable<FloatExp> {
    /// Builds the table for steps from index `origin` of `orbit`. `epsilon` is the relative
    /// tolerance, `dc_max` the largest |c offset| (zero for Julia), `mandelbrot` sets B = 1,
    /// `escape` is the escape radius.
    pub fn build(
        orbit: &Reference,
        origin: u32,
        mandelbrot: bool,
        epsilon: f64,
        dc_max: FloatExp,
        escape: f64,
    ) -> Self {
        let one = Scaled::from_f64([if mandelbrot { 1.0 } else { 0.0 }, 0.0]);
        let escape = FloatExp::from(escape);
        let mut level: Vec<Node> = (origin..orbit.last())
            .into_par_iter()
            .map(|m| {
                let z = Scaled::from_fe(orbit.get_fe(m));
                let size = z.abs();
                let lin = size.mul_f64(epsilon);
                let r = size.ldexp(-1).min((escape - size).max(lin));
                let a2 = Scaled::from_f64([1.0, 0.0]);
                Node { a: z.ldexp(1), b: one, a2, ab: Scaled::ZERO, b2: Scaled::ZERO, r, lin }
            })
            .collect();
        let (mut levels, mut seconds) = (Vec::new(), Vec::new());
        while level.len() >= 2 {
            level = level.par_chunks_exact(2).map(|p| merge(&p[0], &p[1], dc_max, epsilon)).collect();
            levels
                .push(level.par_iter().map(|n| Bla { a: n.a.to_fe(), b: n.b.to_fe(), lin2: n.lin * n.lin }).collect());
            seconds.push(
                level
                    .par_iter()
                    .map(|n| Second { a2: n.a2.to_fe(), ab: n.ab.to_fe(), b2: n.b2.to_fe(), r2: n.r * n.r })
                    .collect(),
            );
        }
        let radii = columns(&seconds, FloatExp::ZERO);
        BlaTable { origin, levels, seconds, radii }
    }

    /// The same table for the f64 loop; entries f64 cannot hold are never valid.
    pub fn to_f64(&self) -> BlaTable<f64> {
        let f = |v: [FloatExp; 2]| [v[0].to_f64(), v[1].to_f64()];
        let finite = |vs: &[[f64; 2]]| vs.iter().flatten().all(|v| v.is_finite());
        let mut levels = Vec::new();
        let mut seconds = Vec::new();
        for (l, q) in self.levels.iter().zip(&self.seconds) {
            let pairs = l.par_iter().zip(q.par_iter()).map(|(e, q)| {
                let (a, b, a2, ab, b2) = (f(e.a), f(e.b), f(q.a2), f(q.ab), f(q.b2));
                let lin2 = if finite(&[a, b]) { e.lin2.to_f64() } else { -1.0 };
                let r2 = if finite(&[a, b, a2, ab, b2]) { q.r2.to_f64() } else { -1.0 };
                (Bla { a, b, lin2 }, Second { a2, ab, b2, r2 })
            });
            let (l, q): (Vec<_>, Vec<_>) = pairs.unzip();
            levels.push(l);
            seconds.push(q);
        }
        let radii = columns(&seconds, -1.0);
        BlaTable { origin: self.origin, levels, seconds, radii }
    }
}

impl<T: Real> BlaTable<T> {
    /// The longest valid step at index `m` for a delta with |z|^2 = `z2`, at most `budget`
    /// iterations long; returns the step and its length. A longer step starting at the same
    /// index is valid on a subset of where a shorter one is (its radius is a minimum over
    /// more steps), so the search climbs from the shortest step and stops at the first that
    /// fails: one probe where nothing is valid, which is the common case.
    #[inline(always)]
    pub fn lookup(&self, m: u32, z2: T, budget: u32) -> Option<(Step<'_, T>, u32)> {
        let i = m.checked_sub(self.origin)?;
        let (start, n) = column(i, self.levels.len());
        let radii = self.radii.get(start..start + n)?;
        let mut k = 0;
        while k < n && z2 < radii[k] && (2u32 << k) <= budget {
            k += 1;
        }
        // Steps past a level's end have radius "never", so levels[k - 1] holds this one.
        let j = (i >> k) as usize;
        // An `if`, not `bool::then` with a closure: the closure was compiled out of line, a
        // call per lookup on the loop's hottest path.
        if k == 0 {
            return None;
        }
        Some((Step { first: &self.levels[k - 1][j], second: &self.seconds[k - 1][j] }, 1u32 << k))
    }

    /// The squared radii of the steps of `level` (2^(level+1) iterations), or of the
    /// longest steps when the table has fewer levels.
    pub fn radii2(&self, level: usize) -> impl Iterator<Item = T> + '_ {
        let k = level.min(self.seconds.len().saturating_sub(1));
        self.seconds.get(k).into_iter().flatten().map(|e| e.r2)
    }

    /// Bytes of memory the table uses.
    pub fn bytes(&self) -> usize {
        self.levels.iter().map(|l| l.capacity() * std::mem::size_of::<Bla<T>>()).sum::<usize>()
            + self.seconds.iter().map(|l| l.capacity() * std::mem::size_of::<Second<T>>()).sum::<usize>()
            + self.radii.capacity() * std::mem::size_of::<T>()
    }
}

#[cfg(test)]
mod tests {
    use malachite_float::Float;
    use std::sync::atomic::AtomicBool;

    use super::*;
    use crate::num::real::norm2;

    fn cabs(v: [FloatExp; 2]) -> FloatExp {
        norm2(v).sqrt()
    }

    #[test]
    fn merged_step_matches_iterated_steps_to_second_order() {
        // Reference at c = -0.75 + 0.1i; one merged step over 4 iterations equals four exact
        // perturbed steps, at a delta where the linear terms alone would be far off.
        let c = [Float::from(-0.75), Float::from(0.1)];
        let z0 = [Float::from(0.0), Float::from(0.0)];
        let r =
            Reference::compute(&z0, &c, 64, 1e10, 128, Default::default(), &|_| {}, &AtomicBool::new(false)).unwrap();
        let dc = [FloatExp::from(1e-9), FloatExp::from(-2e-9)];
        let eps = 1e-6;
        let t = BlaTable::build(&r, 1, true, eps, cabs(dc), 2.0);
        let start = [FloatExp::from(3e-5), FloatExp::from(1e-5)];
        let (e, len) = t.lookup(1, norm2(start), 4).expect("valid");
        assert_eq!(len, 4);
        // Exact steps, with the derivative d(z)/d(c) carried from 0.
        let (mut z, mut dz) = (start, [FloatExp::ZERO; 2]);
        for m in 1..5 {
            let zm = r.get_fe(m);
            let two_z = [zm[0].ldexp(1), zm[1].ldexp(1)];
            let w = cadd(two_z, z);
            dz = cadd(cmul(cadd(two_z, [z[0].ldexp(1), z[1].ldexp(1)]), dz), [FloatExp::ONE, FloatExp::ZERO]);
            z = cadd(cmul(w, z), dc);
        }
        let err = |v: [FloatExp; 2], w: [FloatExp; 2]| cabs(cadd(v, [-w[0], -w[1]])).to_f64() / cabs(w).to_f64();
        let step = e.apply(start, dc);
        assert!(err(step, z) <= 4.0 * eps, "second order: relative error {}", err(step, z));
        let linear = cadd(cmul(e.first.a, start), cmul(e.first.b, dc));
        assert!(err(linear, z) > 100.0 * eps, "the delta must be past first order: {}", err(linear, z));
        // The Jacobian's offset column is the derivative from a zero one.
        let (_, _, n) = e.apply_with_jacobian(start, dc);
        assert!(err(n, dz) <= 4.0 * eps, "derivative: relative error {}", err(n, dz));
        // Too large a delta gets no step; an unaligned index gets none longer than allowed.
        assert!(t.lookup(1, FloatExp::from(1.0), 64).is_none());
        assert_eq!(t.lookup(3, FloatExp::from(1e-24), 64).map(|x| x.1), Some(2));
        assert!(t.lookup(2, FloatExp::from(1e-24), 64).is_none());
    }
}
