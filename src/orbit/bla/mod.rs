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
//! first. The tree covers an orbit's first 2^20 iterations (about 100 bytes per iteration
//! in f64, 450 in FloatExp); past them, steps of whole blocks ([`TailSteps`], built when a
//! sample first gets there). Beside the tree, steps aligned to the reference's near-periods run from one dip of
//! the orbit towards 0 to the next, in stages of longer near-periods (`Stages`, after
//! Zhuoran's "LA v2"): a sample that rebases at every dip crosses from dip to dip in one
//! step where the tree needs as many as the distance has binary digits.
//!
//! The loop tests a sample for rebase and escape at the index it looks up a step from, so a
//! step's own first index needs neither guard: every step keeps a second radius without
//! them (the start radius), which [`BlaTable::lookup`] tests. At a dip the first step is
//! then valid for deltas as large as the reference there (the sample passes the dip without
//! rebasing), where the guarded radius, |Z_m| / 2, would leave it to single steps.
//!
//! Tables are built with wide exponents (radii below 1e-300 and products above 1e300
//! are normal at depth): radii in `FloatExp`, and coefficients, while merging, as complex
//! numbers sharing one exponent ([`Scaled`]: a third less time for the e1086 benchmark's
//! tables than `FloatExp` parts, the same image). They are converted to f64 for the f64
//! phase of the loop, where entries f64 cannot hold are marked unusable. Level 0 (single
//! steps) is not stored: the loop takes those as perturbation steps.

mod tail;

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use rayon::prelude::*;

pub use tail::{Blocks, Parts, TailSteps};

use super::reference::Reference;
use crate::cancel::{self, Cancelled};
use crate::num::real::{cadd, cmul, norm2};
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
/// the first-order part while |z|^2 < r2 (for a delta tested at the step's first index, up
/// to the larger start radius kept beside the table: [`BlaTable::lookup`]).
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
    /// The squared start radii (for a delta tested at the step's first index, see
    /// [`BlaTable::lookup`]; at least `r2`), by start index: for index i (from the origin)
    /// the radii of its steps of every level, shortest first, side by side (see [`column`]).
    /// A lookup then reads one cache line instead of one per level.
    radii: Vec<T>,
    /// Steps aligned to the reference's near-periods (see [`Stages`]).
    stages: Stages<T>,
    /// How many indices from the origin the tree and the stages cover.
    tree_len: u32,
    /// What builds the tree's parts of a table: kept for the blocks past it.
    how: tail::Build,
    /// Steps of whole blocks past the tree (through the rest of a dense orbit and through a
    /// packed tail), built when first needed ([`BlaTable::with_blocks`]), and this number
    /// type's of them.
    blocks: Option<Arc<Blocks>>,
    pick: for<'a> fn(&'a Parts) -> &'a [Option<TailSteps<T>>; 2],
}

/// The tree and the stages end at this index of a reference at the latest: where a long
/// orbit's dense part ends ([`super::DENSE_PART`]), so that the blocks past it begin at the
/// same index whether the rest is stored densely or packed, and give the same steps. The
/// tree takes about 100 bytes per iteration in f64 and 450 in FloatExp: 2^25 dense
/// iterations would take 3.4 or 15 GB of it. Past it, steps of whole blocks ([`TailSteps`]).
const TREE_END: u32 = super::DENSE_PART;

/// Steps that end where the reference dips towards 0, in stages (after Zhuoran's "LA v2").
///
/// A sample rebases where the reference passes near 0 (|Z_m + δ| < |δ|), and a run of
/// steps that crosses such a dip is valid only for deltas below the dip's |Z_m| / 2, so the
/// binary tree's aligned steps reach a dip in as many steps as its distance has binary
/// digits, and after every rebase (back to index 1) a sample climbs the tree again. Steps
/// that start at one dip and end at the next cross no dip: they keep the large radius of
/// the orbit between, and take a sample from one dip to the next in one step.
///
/// Stage 0's marks are the indices where |Z_m| falls below [`DIP`] times the least |Z| since
/// the previous mark (the origin is always a mark): the reference's near-periods. Stage k + 1
/// keeps those of stage k's marks where the same holds among stage k's marks: the deeper
/// returns of a longer near-period. The stages end when a stage keeps every mark of the one
/// before.
///
/// Steps start at every stage-0 mark, and at the index after it (a sample that passes a dip
/// with a delta too large for a step from there takes one exact single step and goes on
/// from the next index). From each, a step runs to the next mark of every stage whose next
/// mark lies further on: to stage 0's next mark, then on to stage 1's, and so on, shortest
/// first. A sample that left the stage-k marks (its delta grew) still reaches the next
/// stage-(k+1) mark in one step, rather than going from mark to mark of stage k. Each is
/// composed from the binary tree's steps and the stages' own by the same merge, so its
/// radii are computed as theirs are, and each longer step from an index is the shorter one
/// merged with more, so its radii are no larger: a lookup climbs them as it climbs the
/// levels. Built in one pass per stage (each stage-k mark's step on to the next stage-(k+1)
/// mark is folded from the right), and stored for a few indices only (`--stats` prints how
/// many: bench-e1086 has 36920, in 10 stages, beside 538506 reference iterations).
#[derive(Debug, Clone)]
struct Stages<T> {
    /// One bit per index from the origin: set where steps start.
    marked: Vec<u64>,
    /// For each index from the origin (and one past the last), where its steps start in the
    /// arrays below: index i's are `at[i]..at[i + 1]`, shortest (stage 0) first.
    at: Vec<u32>,
    /// First-order parts.
    first: Vec<Bla<T>>,
    /// Second-order parts.
    second: Vec<Second<T>>,
    /// Squared start radii (see [`BlaTable::lookup`]).
    start2: Vec<T>,
    /// Lengths in iterations.
    len: Vec<u32>,
    /// How many stages there are.
    count: usize,
}

/// How far below the least |Z| since the previous mark the reference must dip for a new
/// mark (stage 0), or a mark below the least of its stage's marks since the previous one of
/// the next stage.
const DIP: f64 = 1.0 / 64.0;

/// The positions of `at` (ascending) kept as marks: the first, and each whose squared
/// magnitude `mag2` is below DIP^2 times the least since the last kept one (not counting
/// that one itself).
pub(in crate::orbit) fn dips(at: impl IntoIterator<Item = u32>, mag2: impl Fn(u32) -> FloatExp) -> Vec<u32> {
    let mut at = at.into_iter();
    let mut keep: Vec<u32> = at.next().into_iter().collect();
    let mut low: Option<FloatExp> = None;
    for i in at {
        let v = mag2(i);
        match low {
            Some(l) if v < l.mul_f64(DIP * DIP) => {
                keep.push(i);
                low = None;
            }
            _ => low = Some(low.map_or(v, |l| l.min(v))),
        }
    }
    keep
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

/// The column layout of the radii `radius(k, j)` of `top` levels whose first holds
/// `shortest` steps; `never` marks a step past a level's end (None).
fn columns<T: Real>(top: usize, shortest: usize, radius: impl Fn(usize, usize) -> Option<T>, never: T) -> Vec<T> {
    let count = 2 * shortest as u32;
    let mut radii = Vec::with_capacity(count as usize + top);
    for i in 0..count {
        let (start, n) = column(i, top);
        debug_assert_eq!(start, radii.len());
        radii.extend((0..n).map(|k| radius(k, (i >> (k + 1)) as usize).unwrap_or(never)));
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
    /// The radius without the first index's own guards (see [`BlaTable::lookup`]).
    r0: FloatExp,
    /// Radius of the first-order step (Zhuoran's BLA).
    lin: FloatExp,
}

impl Node {
    /// The single step at Z = `z`: exact, with the radius of the module docs.
    fn single(z: [FloatExp; 2], one: Scaled, epsilon: f64, escape: FloatExp) -> Node {
        let z = Scaled::from_fe(z);
        let size = z.abs();
        let lin = size.mul_f64(epsilon);
        let r = size.ldexp(-1).min((escape - size).max(lin));
        // The step itself is exact: with rebase and escape ruled out at its index, only
        // the size of a delta that has not escaped (|δ| <= |Z + δ| + |Z| <= 2 R) bounds it.
        let r0 = escape.ldexp(2);
        let a2 = Scaled::from_f64([1.0, 0.0]);
        Node { a: z.ldexp(1), b: one, a2, ab: Scaled::ZERO, b2: Scaled::ZERO, r, r0, lin }
    }

    /// A stored step (with its squared start radius `r02`), back in the form merges take.
    fn stored(f: &Bla<FloatExp>, q: &Second<FloatExp>, r02: FloatExp) -> Node {
        let s = Scaled::from_fe;
        let (r, r0, lin) = (q.r2.sqrt(), r02.sqrt(), f.lin2.sqrt());
        Node { a: s(f.a), b: s(f.b), a2: s(q.a2), ab: s(q.ab), b2: s(q.b2), r, r0, lin }
    }

    /// The parts a table stores.
    fn parts(&self) -> (Bla<FloatExp>, Second<FloatExp>) {
        (
            Bla { a: self.a.to_fe(), b: self.b.to_fe(), lin2: self.lin * self.lin },
            Second { a2: self.a2.to_fe(), ab: self.ab.to_fe(), b2: self.b2.to_fe(), r2: self.r * self.r },
        )
    }
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
    compose::<false>(x, y, gamma, eps)
}

/// [`merge`] of `x` then `y`, a single step ([`Node::single`]: A2 = 1, AB = B2 = 0): the
/// same composite, with those coefficients' products left out, for the steps of whole
/// blocks folded one iteration at a time ([`TailSteps`], whose whole cost this is).
fn then_single(x: &Node, y: &Node, gamma: FloatExp, eps: f64) -> Node {
    compose::<true>(x, y, gamma, eps)
}

/// [`merge`], and where `SINGLE` says y is a single step, [`then_single`].
#[inline(always)]
fn compose<const SINGLE: bool>(x: &Node, y: &Node, gamma: FloatExp, eps: f64) -> Node {
    let a = y.a * x.a;
    let b = y.a * x.b + y.b;
    let (a2, ab, b2) = if SINGLE {
        (y.a * x.a2 + x.a.square(), y.a * x.ab + (x.a * x.b).ldexp(1), y.a * x.b2 + x.b.square())
    } else {
        (
            y.a * x.a2 + y.a2 * x.a.square(),
            y.a * x.ab + (y.a2 * (x.a * x.b)).ldexp(1) + y.ab * x.a,
            y.a * x.b2 + y.a2 * x.b.square() + (y.ab * x.b + y.b2),
        )
    };
    let [ax, bx, a2x, abx, b2x] = [x.a, x.b, x.a2, x.ab, x.b2].map(Scaled::abs);
    let g = gamma;
    // |Q| <= a2x ρ^2 + abx g ρ + b2x g^2, |L| <= ax ρ + bx g.
    let (qp, qq, qs) = (a2x, abx * g, b2x * g * g);
    let quarter = FloatExp::from(eps / 4.0);
    let gap = if SINGLE {
        // The third bound holds everywhere where AB_y = 0, and |A2_y| = 1 in the fourth.
        [None, largest_root(qp, qq, qs - quarter * y.a.abs())]
    } else {
        let [ay, a2y, aby] = [y.a, y.a2, y.ab].map(Scaled::abs);
        [
            // |AB_y| g |Q| <= ε/4 |A_y| |L|.
            largest_root(aby * g * qp, aby * g * qq - quarter * ay * ax, aby * g * qs - quarter * ay * bx * g),
            // |Q| <= ε |A_y| / (4 |A2_y|) (no bound where y has no quadratic term).
            if a2y.is_zero() { None } else { largest_root(qp, qq, qs - quarter * ay / a2y) },
        ]
    };
    let bounds = [
        // x's image within y's radius.
        largest_root(qp, ax + qq, bx * g + qs - y.r),
        // |Q| <= |L|.
        largest_root(qp, qq - ax, qs - bx * g),
        gap[0],
        gap[1],
    ];
    let r = bounds.into_iter().flatten().fold(x.r, FloatExp::min);
    let r0 = bounds.into_iter().flatten().fold(x.r0, FloatExp::min);
    // First order: z valid for x and A_x z + B_x c valid for y.
    let through = (y.lin - bx * g).max(FloatExp::ZERO);
    let lin = x.lin.min(if ax.is_zero() { y.lin.max(FloatExp::ZERO) } else { through / ax });
    Node { a, b, a2, ab, b2, r, r0, lin }
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
        Self::build_with_tree(orbit, origin, tail::Build::new(mandelbrot, epsilon, dc_max, escape), TREE_END)
    }

    /// [`BlaTable::build`] with the tree ending at index `tree_end` at the latest (tests
    /// reach the blocks past it on short orbits).
    fn build_with_tree(orbit: &Reference, origin: u32, how: tail::Build, tree_end: u32) -> Self {
        let tail::Build { one, epsilon, dc_max, escape } = how;
        let single = |i: u32| Node::single(orbit.get_fe(origin + i), one, epsilon, escape);
        let all = orbit.last().saturating_sub(origin);
        // The whole tree over the first part; whole blocks past it.
        let tree_len = all.min(tree_end.saturating_sub(origin));
        let mut level: Vec<Node> = (0..tree_len).into_par_iter().map(single).collect();
        let count = tree_len;
        let (mut levels, mut seconds, mut starts) = (Vec::new(), Vec::new(), Vec::new());
        while level.len() >= 2 {
            level = level.par_chunks_exact(2).map(|p| merge(&p[0], &p[1], dc_max, epsilon)).collect();
            let (l, q): (Vec<_>, Vec<_>) = level.par_iter().map(Node::parts).unzip();
            levels.push(l);
            seconds.push(q);
            starts.push(level.par_iter().map(|n| n.r0 * n.r0).collect::<Vec<FloatExp>>());
        }
        let (top, shortest) = (levels.len(), levels.first().map_or(0, Vec::len));
        let radii = columns(top, shortest, |k, j| starts[k].get(j).copied(), FloatExp::ZERO);
        // Index i's step of 2^k iterations (k = 0: the single step).
        let tree = |i: u32, k: usize| {
            if k == 0 {
                single(i)
            } else {
                let j = (i >> k) as usize;
                Node::stored(&levels[k - 1][j], &seconds[k - 1][j], starts[k - 1][j])
            }
        };
        let mag2 = |i| norm2(orbit.get_fe(origin + i));
        let stages = Stages::build(count, top, mag2, tree, |x, y| merge(x, y, dc_max, epsilon));
        BlaTable { origin, tree_len, levels, seconds, radii, stages, how, blocks: None, pick: |p| &p.fe }
    }

    /// The same table with steps of whole blocks past its tree, through the rest of
    /// `refs[k]`, the orbit it was built for (densely stored or packed), built the first
    /// time a sample needs them ([`Blocks`]); `floatexp`: keep their FloatExp steps (a view
    /// with FloatExp deltas), not only the f64 ones.
    pub fn with_blocks(self, refs: Arc<Vec<Reference>>, k: usize, floatexp: bool) -> Self {
        let from = self.origin + self.tree_len;
        let blocks = Blocks::new(refs, k, from, self.how, floatexp).map(Arc::new);
        BlaTable { blocks, ..self }
    }

    /// The same table for the f64 loop; entries f64 cannot hold are never valid.
    pub fn to_f64(&self) -> BlaTable<f64> {
        let mut levels = Vec::new();
        let mut seconds = Vec::new();
        for (l, q) in self.levels.iter().zip(&self.seconds) {
            let (l, q): (Vec<_>, Vec<_>) = l.par_iter().zip(q.par_iter()).map(|(e, q)| entry_to_f64(e, q)).unzip();
            levels.push(l);
            seconds.push(q);
        }
        // A start radius where the step's parts are finite in f64 (r2 is negative where not).
        let (top, shortest) = (levels.len(), levels.first().map_or(0, Vec::len));
        let start2 = |k: usize, j: usize| {
            let q: &Second<f64> = seconds[k].get(j)?;
            let i = (j as u32) << (k + 1);
            Some(if q.r2 < 0.0 { -1.0 } else { self.radii[column(i, top).0 + k].to_f64() })
        };
        let radii = columns(top, shortest, start2, -1.0);
        let s = &self.stages;
        let (first, second): (Vec<_>, Vec<_>) =
            s.first.par_iter().zip(s.second.par_iter()).map(|(e, q)| entry_to_f64(e, q)).unzip();
        let start2: Vec<f64> =
            second.iter().zip(&s.start2).map(|(q, r)| if q.r2 < 0.0 { -1.0 } else { r.to_f64() }).collect();
        let (marked, at, len, count) = (s.marked.clone(), s.at.clone(), s.len.clone(), s.count);
        let stages = Stages { marked, at, first, second, start2, len, count };
        let (origin, tree_len, how, blocks) = (self.origin, self.tree_len, self.how, self.blocks.clone());
        BlaTable { origin, tree_len, levels, seconds, radii, stages, how, blocks, pick: |p| &p.f64 }
    }
}

/// One step for the f64 loop; parts f64 cannot hold make it never valid.
fn entry_to_f64(e: &Bla<FloatExp>, q: &Second<FloatExp>) -> (Bla<f64>, Second<f64>) {
    let f = |v: [FloatExp; 2]| [v[0].to_f64(), v[1].to_f64()];
    let finite = |vs: &[[f64; 2]]| vs.iter().flatten().all(|v| v.is_finite());
    let (a, b, a2, ab, b2) = (f(e.a), f(e.b), f(q.a2), f(q.ab), f(q.b2));
    let lin2 = if finite(&[a, b]) { e.lin2.to_f64() } else { -1.0 };
    let r2 = if finite(&[a, b, a2, ab, b2]) { q.r2.to_f64() } else { -1.0 };
    (Bla { a, b, lin2 }, Second { a2, ab, b2, r2 })
}

impl Stages<FloatExp> {
    /// The stages for `count` indices from the origin, given each index's |Z|^2 (`mag2`),
    /// the binary tree's step of 2^k iterations at an index (`tree`, k = 0 the single step,
    /// up to `top`) and the merge.
    fn build(
        count: u32,
        top: usize,
        mag2: impl Fn(u32) -> FloatExp,
        tree: impl Fn(u32, usize) -> Node + Sync,
        merge: impl Fn(&Node, &Node) -> Node + Sync,
    ) -> Stages<FloatExp> {
        // The longest aligned step of the tree from i that ends by b (i < b), and its length.
        let aligned = |i: u32, b: u32| {
            let mut k = 0;
            while k < top && i.trailing_zeros() > k as u32 && i + (2 << k) <= b {
                k += 1;
            }
            (tree(i, k), 1u32 << k)
        };
        // From a to b (a < b), through those steps.
        let span = |a: u32, b: u32| {
            let (mut acc, n) = aligned(a, b);
            let mut i = a + n;
            while i < b {
                let (step, n) = aligned(i, b);
                acc = merge(&acc, &step);
                i += n;
            }
            acc
        };
        let mut marks = vec![dips(0..count, &mag2)];
        loop {
            let last = &marks[marks.len() - 1];
            let next = dips(last.iter().copied(), &mag2);
            if next.len() == last.len() {
                break;
            }
            marks.push(next);
        }
        let end = |k: usize, j: usize| marks[k].get(j + 1).copied().unwrap_or(count);
        // tails[k][j]: from stage k's mark j to the next mark of stage k + 1 (or the end),
        // folded from the right through stage k's steps; steps[k][j], stage k's step from its
        // mark j, is tails[k - 1] at that mark.
        let first: Vec<Node> = (0..marks[0].len()).into_par_iter().map(|j| span(marks[0][j], end(0, j))).collect();
        let mut steps = vec![first];
        let mut tails: Vec<Vec<Node>> = Vec::new();
        for k in 0..marks.len() - 1 {
            let (below, above) = (&marks[k], &marks[k + 1]);
            // Stage k's marks cut at stage k + 1's: each run folds from its right end.
            let mut cuts: Vec<usize> = Vec::with_capacity(above.len() + 1);
            let mut j = 0;
            for &m in above {
                while below[j] != m {
                    j += 1;
                }
                cuts.push(j);
            }
            cuts.push(below.len());
            let own = &steps[k];
            let runs: Vec<Vec<Node>> = cuts
                .par_windows(2)
                .map(|w| {
                    let mut run: Vec<Node> = Vec::with_capacity(w[1] - w[0]);
                    for j in (w[0]..w[1]).rev() {
                        let t = run.last().map_or(own[j], |after| merge(&own[j], after));
                        run.push(t);
                    }
                    run.reverse();
                    run
                })
                .collect();
            let tail: Vec<Node> = runs.into_iter().flatten().collect();
            steps.push(cuts[..cuts.len() - 1].iter().map(|&j| tail[j]).collect());
            tails.push(tail);
        }
        // The indices with steps: every stage-0 mark and the index after it (never a mark).
        // Each gets a step to the next mark of every stage whose next mark lies further on,
        // shortest first: to stage 0's next mark, then on through the tails.
        let starts: Vec<u32> = marks[0].iter().flat_map(|&b| [b, b + 1]).filter(|&i| i < count).collect();
        let chains: Vec<Vec<(Node, u32)>> = starts
            .par_iter()
            .map(|&i| {
                // Stage 0's next mark after i (i is below count, so it lies further on).
                let mut at = marks[0].partition_point(|&m| m <= i);
                let mut to = marks[0].get(at).copied().unwrap_or(count);
                let mut step = span(i, to);
                let mut chain = vec![(step, to - i)];
                for k in 0..marks.len() - 1 {
                    // `to` is stage k's mark `at` (or the end); on to stage k + 1's next one.
                    if to == count {
                        break;
                    }
                    let next = marks[k + 1].partition_point(|&m| m <= i);
                    let goal = marks[k + 1].get(next).copied().unwrap_or(count);
                    if goal > to {
                        step = merge(&step, &tails[k][at]);
                        to = goal;
                        chain.push((step, to - i));
                    }
                    at = next;
                }
                chain
            })
            .collect();
        // Side by side by start index, shortest first. Steps of one iteration (a last mark
        // just before the end) are left out: the loop's single step is the same.
        let mut s = Stages {
            marked: vec![0; (count as usize).div_ceil(64)],
            at: vec![0; count as usize + 1],
            first: Vec::new(),
            second: Vec::new(),
            start2: Vec::new(),
            len: Vec::new(),
            count: marks.len(),
        };
        for (&i, chain) in starts.iter().zip(&chains) {
            for (node, len) in chain.iter().filter(|(_, len)| *len >= 2) {
                let (f, q) = node.parts();
                s.first.push(f);
                s.second.push(q);
                s.start2.push(node.r0 * node.r0);
                s.len.push(*len);
                s.at[i as usize + 1] += 1;
                s.marked[i as usize / 64] |= 1 << (i % 64);
            }
        }
        for i in 0..count as usize {
            s.at[i + 1] += s.at[i];
        }
        s
    }
}

impl<T: Real> BlaTable<T> {
    /// The longest valid step at index `m` for a delta with |z|^2 = `z2`, at most `budget`
    /// iterations long; returns the step and its length. The caller must have tested the
    /// delta at `m` itself, as the loop does before it looks for a step: no rebase
    /// (|Z_m + z| >= |z|) and no escape. The step's radius then leaves out what guards its
    /// first index (|z| <= |Z_m| / 2 and the escape circle): from a dip of the reference
    /// that a sample passes without rebasing, the first step is exact and the rest must hold
    /// its image, so steps are valid there for deltas up to the dip's size and beyond.
    ///
    /// A longer step starting at the same index is valid on a subset of where a shorter one
    /// is (its radius is a minimum over more steps), so the search climbs from the shortest
    /// step and stops at the first that fails: one probe where nothing is valid, which is
    /// the common case.
    #[inline(always)]
    pub fn lookup(&self, m: u32, z2: T, budget: u32) -> Option<(Step<'_, T>, u32)> {
        self.lookup_in(m, z2, budget, &cancel::NEVER).and_then(Result::ok)
    }

    /// [`BlaTable::lookup`] for a sample of a render that `cancel` may stop: past the tree,
    /// where the steps of whole blocks are built when first needed ([`Blocks::parts`]),
    /// `Err(Cancelled)` where their build was cancelled (the sample is then abandoned: a
    /// cancelled render keeps none of its samples).
    #[inline(always)]
    pub fn lookup_in(
        &self,
        m: u32,
        z2: T,
        budget: u32,
        cancel: &AtomicBool,
    ) -> Option<Result<(Step<'_, T>, u32), Cancelled>> {
        let i = m.checked_sub(self.origin)?;
        if i >= self.tree_len {
            return match self.blocks(cancel) {
                Ok(b) => b?.lookup(m, z2, budget).map(|(step, len, _)| Ok((step, len))),
                Err(e) => Some(Err(e)),
            };
        }
        let (start, n) = column(i, self.levels.len());
        let mut best = None;
        if let Some(radii) = self.radii.get(start..start + n) {
            let mut k = 0;
            while k < n && z2 < radii[k] && (2u32 << k) <= budget {
                k += 1;
            }
            // Steps past a level's end have radius "never", so levels[k - 1] holds this one.
            // An `if`, not `bool::then` with a closure: the closure was compiled out of
            // line, a call per lookup on the loop's hottest path.
            if k > 0 {
                let j = (i >> k) as usize;
                best = Some((Step { first: &self.levels[k - 1][j], second: &self.seconds[k - 1][j] }, 1u32 << k));
            }
        }
        let step = if self.stages.marked(i) {
            self.stages.climb(i, z2, budget, best, |s| self.stages.start2[s])
        } else {
            best
        };
        step.map(Ok)
    }

    /// [`BlaTable::lookup`] for a delta not tested at `m` (steps composed for every sample
    /// at once): the radii with every guard.
    pub fn lookup_untested(&self, m: u32, z2: T, budget: u32) -> Option<(Step<'_, T>, u32)> {
        let i = m.checked_sub(self.origin)?;
        let mut best = None;
        for (k, level) in self.seconds.iter().enumerate() {
            let len = 2u32 << k;
            if i % len != 0 || len > budget {
                break;
            }
            let j = (i / len) as usize;
            match level.get(j) {
                Some(q) if z2 < q.r2 => best = Some((Step { first: &self.levels[k][j], second: q }, len)),
                _ => break,
            }
        }
        if self.stages.marked(i) { self.stages.climb(i, z2, budget, best, |s| self.stages.second[s].r2) } else { best }
    }

    /// The step [`BlaTable::lookup`] returns at index `m` for every |z|^2 below the bound
    /// returned beside it and a budget of at least its length: the longest period-aligned
    /// step from `m`. The bound is the least start radius of the aligned steps the search
    /// climbs through on the way (it stops at the first that fails); the tree's steps at `m`
    /// are shorter, or never valid, so the search keeps the aligned one. None where no
    /// aligned step starts at `m`, a tree step there as long as it could be taken, or the
    /// steps are not in the order the search assumes (lengths rising, radii numbers). A
    /// loop that comes back to `m` again and again (the turns of a nucleus's reference)
    /// tests the bound instead of searching, and takes the same step.
    pub fn fixed_step(&self, m: u32) -> Option<(Step<'_, T>, u32, T)> {
        let i = m.checked_sub(self.origin)?;
        let s = &self.stages;
        if !s.marked(i) {
            return None;
        }
        let (from, to) = (s.at[i as usize] as usize, s.at[i as usize + 1] as usize);
        let last = to.checked_sub(1).filter(|&l| l >= from)?;
        let (start, n) = column(i, self.levels.len());
        let tree = self.radii.get(start..start + n)?;
        let longer = |k: usize| (2u64 << k) >= u64::from(s.len[last]);
        // A radius that is not above zero holds no |z|^2 (and a NaN none either).
        if tree.iter().enumerate().any(|(k, r)| longer(k) && T::ZERO < *r) {
            return None;
        }
        let mut bound = s.start2[from];
        for k in from..to {
            let rising = k == from || s.len[k] > s.len[k - 1];
            // A NaN radius fails every test in the search (and here, any comparison).
            match s.start2[k].partial_cmp(&bound) {
                Some(order) if rising => {
                    if order == std::cmp::Ordering::Less {
                        bound = s.start2[k];
                    }
                }
                _ => return None,
            }
        }
        Some((Step { first: &s.first[last], second: &s.second[last] }, s.len[last], bound))
    }

    /// The squared radii of the steps of `level` (2^(level+1) iterations), or of the
    /// longest steps when the table has fewer levels.
    pub fn radii2(&self, level: usize) -> impl Iterator<Item = T> + '_ {
        let k = level.min(self.seconds.len().saturating_sub(1));
        self.seconds.get(k).into_iter().flatten().map(|e| e.r2)
    }

    /// Bytes of memory the table uses.
    pub fn bytes(&self) -> usize {
        let s = &self.stages;
        self.levels.iter().map(|l| l.capacity() * std::mem::size_of::<Bla<T>>()).sum::<usize>()
            + self.seconds.iter().map(|l| l.capacity() * std::mem::size_of::<Second<T>>()).sum::<usize>()
            + self.radii.capacity() * std::mem::size_of::<T>()
            + s.first.capacity() * std::mem::size_of::<Bla<T>>()
            + s.second.capacity() * std::mem::size_of::<Second<T>>()
            + s.start2.capacity() * std::mem::size_of::<T>()
            + (s.len.capacity() + s.at.capacity()) * 4
            + s.marked.capacity() * 8
            + self.built().map_or(0, |b| b.iter().flatten().map(TailSteps::bytes).sum())
    }

    /// The steps of whole blocks through the dense orbit past the tree, if it is longer
    /// (built now if they have not been: [`Blocks::parts`], which `cancel` may stop).
    #[inline]
    pub fn blocks(&self, cancel: &AtomicBool) -> Result<Option<&TailSteps<T>>, Cancelled> {
        self.part(0, cancel)
    }

    /// The steps through the reference's packed tail, if it has one (built now if they
    /// have not been).
    #[inline]
    pub fn tail(&self, cancel: &AtomicBool) -> Result<Option<&TailSteps<T>>, Cancelled> {
        self.part(1, cancel)
    }

    fn part(&self, k: usize, cancel: &AtomicBool) -> Result<Option<&TailSteps<T>>, Cancelled> {
        match &self.blocks {
            Some(b) => Ok((self.pick)(b.parts(cancel)?)[k].as_ref()),
            None => Ok(None),
        }
    }

    /// The steps of whole blocks past the tree if a sample has needed them, [dense, packed]
    /// (for statistics); None where they have not been built.
    pub fn built(&self) -> Option<&[Option<TailSteps<T>>; 2]> {
        self.blocks.as_ref().and_then(|b| b.built()).map(self.pick)
    }

    /// Whether the table has steps of whole blocks to build (an orbit past the tree).
    pub fn has_blocks(&self) -> bool {
        self.blocks.is_some()
    }

    /// While the steps of whole blocks are being built, the iterations folded so far and of
    /// how many ([`Blocks::progress`]).
    pub fn blocks_progress(&self) -> Option<(u64, u64)> {
        self.blocks.as_ref().and_then(|b| b.progress())
    }

    /// Seconds the steps of whole blocks took to build, where a sample needed them.
    pub fn blocks_seconds(&self) -> f64 {
        self.blocks.as_ref().and_then(|b| b.built()).map_or(0.0, |p| p.seconds)
    }

    /// How many period-aligned steps the table holds.
    pub fn aligned_steps(&self) -> usize {
        self.stages.len.len()
    }

    /// How many stages of near-periods they reach.
    pub fn stage_count(&self) -> usize {
        self.stages.count
    }
}

impl<T: Real> Stages<T> {
    /// True when steps start at index `i` (from the origin).
    #[inline(always)]
    fn marked(&self, i: u32) -> bool {
        self.marked.get(i as usize / 64).is_some_and(|w| w & (1 << (i % 64)) != 0)
    }

    /// The longest valid step at marked index `i` for |z|^2 = `z2` within `budget`, or
    /// `best` (the tree's) when that is longer. Climbs from stage 0 and stops at the first
    /// step that is not valid (a longer step from the same index is valid on a subset).
    #[inline(always)]
    fn climb<'a>(
        &'a self,
        i: u32,
        z2: T,
        budget: u32,
        best: Option<(Step<'a, T>, u32)>,
        radius2: impl Fn(usize) -> T,
    ) -> Option<(Step<'a, T>, u32)> {
        let mut best = best;
        let from = self.at[i as usize] as usize;
        let to = self.at[i as usize + 1] as usize;
        for s in from..to {
            let len = self.len[s];
            // Written so that a NaN radius fails as "not valid", as the tree's test does.
            let valid = z2 < radius2(s);
            if len > budget || !valid {
                break;
            }
            if best.as_ref().is_none_or(|b| b.1 < len) {
                best = Some((Step { first: &self.first[s], second: &self.second[s] }, len));
            }
        }
        best
    }
}

#[cfg(test)]
mod tests;
