//! Bilinear approximation (BLA) for every formula: steps that skip runs of iterations,
//! δ -> A δ + B δc with real 2×2 matrices A and B, merged in a binary tree over the
//! reference's indices (Zhuoran's BLA, as Claude Heiland-Allen's "Deep zoom theory and
//! practice (again)" writes it for formulas with folds).
//!
//! One perturbed step at reference index m is δ' = f_m(Z_m + δ) - f_m(Z_m) + δc. Its
//! linear part is A = Jf_m(Z_m) (the real Jacobian: a fold flips the sign of a row or a
//! column of the power's conformal derivative p W^(p-1)) and B = I for the Mandelbrot form
//! (δc enters every step), B = 0 for a Julia set. The step is valid for |δ| below a radius
//! that respects:
//!
//! 1. the nonlinear terms: |f(Z + δ) - f(Z) - A δ| <= Σ_(k>=2) C(p,k) |Z|^(p-k) |δ|^k, and
//!    |A δ| = p |Z|^(p-1) |δ| exactly (folds and negations are reflections, so A is p W^(p-1)
//!    times orthogonal matrices), so the dropped terms stay below ε of the linear one for
//!    |δ| < ε |Z| / (p - 1) (the quadratic term is (p-1)/2 |δ|/|Z| of it; half of that
//!    allowance is left for the higher ones);
//! 2. the fold lines: a fold of x before the power is linear only while X + δx keeps the
//!    sign of X, so |δ| < |X| (likewise y, and the sign of x or y that a signed fold of the
//!    imaginary part reads after the power); a fold of Re U after the power (U = W^p) needs
//!    |δU| < |Re U|, and |δU| <= (|Z| + |δ|)^p - |Z|^p, so |δ| < |Z| ((1 + |Re U|/|Z|^p)^(1/p) - 1);
//! 3. escape: |δ| <= R - |Z|, so that no escape is skipped (the loop tests a sample at the
//!    index it looks a step up from).
//!
//! Two consecutive steps x then y merge into A = A_y A_x, B = A_y B_x + B_y, valid for
//! |δ| < min(r_x, (r_y - ‖B_x‖ |δc|max) / ‖A_x‖), ‖·‖ the operator norm (the largest
//! singular value, exact for 2×2 matrices: a Frobenius norm would lose up to √2 per level of
//! the tree). Level k of the tree holds steps of 2^k iterations starting at
//! origin + i 2^k; the loop climbs from a step of 2 iterations while the next level's
//! radius still holds the sample (radii never grow with the level at one start index).
//! Orbits of 0 start the tree at index 1 (from Z_0 = 0 nothing is linear: A = 0 and the
//! radius is 0), which is where every rebased sample goes on from.
//!
//! Beside the tree, steps from just after one dip of the reference towards 0 to the next
//! dips ([`Dips`], in stages of deeper dips, as the z^2 engine's stages after Zhuoran's
//! "LA v2"): a sample that rebases at every dip (or passes it: a nucleus's orbit repeats
//! every period) goes on from the index after it and would climb the tree again, taking
//! as many steps to the next dip as its distance has binary digits; a step that crosses
//! no deeper dip keeps the orbit's large radius between them and takes it there in one.
//! Around the power-3 minibrot of `scenes/bench-mandelbrot3-e80.toml` (period 338) that
//! cut the BLA steps from 39 to 10 million and the render's time by half.
//!
//! Hybrids need no more: each reference orbit has its own tree, and a reference's index
//! fixes the phase of each step it covers (orbit k steps index j with phase k + j), which
//! is the sample's phase while it follows that orbit. Steps from wide values (see
//! [`super::reference`]) get radius 0: their f64 value may have lost a sign a fold reads.
//!
//! Tables are built with FloatExp entries (products over long runs leave f64's range at
//! depth) and kept twice: in f64 for the f64 phase of the loop (entries f64 cannot hold made
//! unusable) and in FloatExp for deltas below f64's range.

use rayon::prelude::*;

use super::der::{MatFe, to_fe};
use super::reference::Track;
use crate::formula::map::{FOLD_IM, FOLD_RE, IM_BY_X, IM_BY_Y};
use crate::formula::{Formula, Stepper, sum};
use crate::num::{FloatExp, Real};
use crate::orbit::bla::dips;

/// The tree covers at most this many indices from its origin: it takes about 220 bytes per
/// index (f64 and FloatExp), 0.9 GB here.
const TREE_END: u32 = 1 << 22;

/// Fold radii are kept this much inside the fold lines (the linear steps' own error is
/// far smaller).
const SAFE: f64 = 0.999;

/// A step over 2^k iterations: δ -> A δ + B δc for |δ|^2 < r2.
#[derive(Debug, Clone, Copy)]
pub(super) struct Step<T> {
    /// Multiplier of the delta.
    pub(super) a: [[T; 2]; 2],
    /// Multiplier of the sample's offset δc.
    pub(super) b: [[T; 2]; 2],
    /// Squared validity radius (negative: never valid).
    pub(super) r2: T,
}

/// The tree of one reference orbit in number type T.
#[derive(Debug, Clone)]
pub(super) struct Table<T> {
    origin: u32,
    /// levels[k] holds steps of 2^(k+1) iterations.
    levels: Vec<Vec<Step<T>>>,
    /// Steps from dip to dip.
    dips: Dips<Step<T>>,
    /// The largest squared radius (of the shortest steps and the dips' steps): a sample
    /// above it looks nothing up.
    max_r2: T,
}

/// Steps that run from just after one dip of the reference towards 0 to later dips, in
/// stages (the z^2 engine's stages after Zhuoran's "LA v2", in short). A dip is an index
/// where |Z| falls below 1/64 of the least |Z| since the previous dip (stage 0, found by
/// the z^2 engine's [`dips`]); the dips of stage k + 1 are those of stage k where the same
/// holds among stage k's. A sample
/// stands at a dip when it rebases there or passes it with a small delta (a reference
/// that repeats, a nucleus's, is passed at every period); from the next index (the origin,
/// after a rebase) one step takes it to the next dip of each stage, the longest whose
/// radius holds it taken, and the loop tests it for a rebase there.
#[derive(Debug, Clone)]
struct Dips<S> {
    /// One bit per index from the origin: set where steps start.
    marked: Vec<u64>,
    /// The indices from the origin where steps start, ascending; start k's steps are
    /// `steps[first[k]..first[k + 1]]`, shortest first, each the one before merged with
    /// more (so their radii never grow).
    starts: Vec<u32>,
    first: Vec<u32>,
    steps: Vec<(S, u32)>,
    /// How many stages the dips have (0 without dips).
    stages: usize,
}

impl<S> Dips<S> {
    /// The same dips with each step converted by `f`.
    fn map<U>(&self, f: impl Fn(&S) -> U) -> Dips<U> {
        let steps = self.steps.iter().map(|(s, n)| (f(s), *n)).collect();
        let (marked, starts, first, stages) =
            (self.marked.clone(), self.starts.clone(), self.first.clone(), self.stages);
        Dips { marked, starts, first, steps, stages }
    }

    /// The steps that start `i` indices from the origin, shortest first.
    #[inline(always)]
    fn at(&self, i: u32) -> &[(S, u32)] {
        match self.marked.get((i / 64) as usize) {
            Some(word) if word >> (i % 64) & 1 != 0 => match self.starts.binary_search(&i) {
                Ok(k) => &self.steps[self.first[k] as usize..self.first[k + 1] as usize],
                Err(_) => &[],
            },
            _ => &[],
        }
    }

    /// The longest step from `i` that `valid` holds, no longer than `left`.
    #[inline(always)]
    fn longest(&self, i: u32, left: u32, valid: impl Fn(&S) -> bool) -> Option<&(S, u32)> {
        let steps = self.at(i);
        let n = steps.partition_point(|(s, len)| *len <= left && valid(s));
        n.checked_sub(1).map(|k| &steps[k])
    }
}

impl<T: Real> Dips<Step<T>> {
    /// Each start's radii made non-increasing with the length (as the merges make them,
    /// but for a longer step's f64 form that f64 cannot hold), which
    /// [`Dips::longest`]'s search needs.
    fn monotone(mut self) -> Self {
        for w in self.first.windows(2) {
            let run = &mut self.steps[w[0] as usize..w[1] as usize];
            for k in 1..run.len() {
                if run[k - 1].0.r2 < run[k].0.r2 {
                    run[k].0.r2 = run[k - 1].0.r2;
                }
            }
        }
        self
    }
}

/// A step while the tree is built: matrices and radius in FloatExp.
#[derive(Debug, Clone, Copy)]
struct Wide {
    a: MatFe,
    b: MatFe,
    r: FloatExp,
}

/// What the tables of a view are built for.
#[derive(Debug, Clone, Copy)]
pub(super) struct Build {
    /// The tolerance ε.
    pub(super) eps: f64,
    /// The largest |δc| (plane units); zero for Julia sets.
    pub(super) dc_max: FloatExp,
    /// The escape radius.
    pub(super) escape_radius: f64,
    /// Mandelbrot form (B = I) or Julia (B = 0).
    pub(super) mandelbrot: bool,
    /// Also keep the FloatExp tables.
    pub(super) floatexp: bool,
}

impl Table<f64> {
    /// The first look of [`Table::can_step`]: no |δ|² at or above this (or NaN) finds a
    /// step.
    #[inline(always)]
    pub(super) fn gate(&self) -> f64 {
        self.max_r2
    }
}

impl<T: Real> Table<T> {
    /// The longest step from index `m` whose radius holds |δ|^2 = `d2`, no longer than
    /// `left` iterations; with its length.
    #[inline(always)]
    pub(super) fn lookup(&self, m: u32, d2: T, left: u32) -> Option<(&Step<T>, u32)> {
        if d2.partial_cmp(&self.max_r2) != Some(std::cmp::Ordering::Less) || m < self.origin {
            return None;
        }
        let i = m - self.origin;
        let mut best = None;
        for (k, level) in self.levels.iter().enumerate() {
            let len = 2u32 << k;
            if i & (len - 1) != 0 || len > left {
                break;
            }
            match level.get((i >> (k + 1)) as usize) {
                Some(s) if d2 < s.r2 => best = Some((s, len)),
                _ => break,
            }
        }
        if let Some((s, len)) = self.dips.longest(i, left, |s| d2 < s.r2)
            && best.is_none_or(|(_, n)| n < *len)
        {
            best = Some((s, *len));
        }
        best
    }

    /// True when [`Table::lookup`] finds a step: the shortest step of the tree from `m`
    /// holds `d2` (every longer one is looked at only if it does), or the dips' step from
    /// `m` does. The lanes' test for a BLA event.
    #[inline(always)]
    pub(super) fn can_step(&self, m: u32, d2: T, left: u32) -> bool {
        if d2.partial_cmp(&self.max_r2) != Some(std::cmp::Ordering::Less) || m < self.origin {
            return false;
        }
        let i = m - self.origin;
        let tree = left >= 2
            && i & 1 == 0
            && self.levels.first().and_then(|l| l.get((i >> 1) as usize)).is_some_and(|s| d2 < s.r2);
        tree || self.dips.at(i).first().is_some_and(|(s, len)| d2 < s.r2 && *len <= left)
    }

    /// Steps from dip to dip, and the dips' stages.
    pub(super) fn dip_steps(&self) -> (usize, usize) {
        (self.dips.steps.len(), self.dips.stages)
    }

    /// Steps stored, over all levels.
    pub(super) fn len(&self) -> usize {
        self.levels.iter().map(Vec::len).sum()
    }

    /// Levels of the tree.
    pub(super) fn depth(&self) -> usize {
        self.levels.len()
    }
}

/// The operator norm (largest singular value) of a FloatExp matrix.
fn norm(a: &MatFe) -> FloatExp {
    let e = a.iter().flatten().filter(|x| !x.is_zero()).map(|x| x.exponent()).max();
    let Some(e) = e else { return FloatExp::ZERO };
    let m = a.map(|row| row.map(|x| x.ldexp(-e).to_f64()));
    let f2 = m.iter().flatten().map(|x| x * x).sum::<f64>();
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let s2 = 0.5 * (f2 + (f2 * f2 - 4.0 * det * det).max(0.0).sqrt());
    FloatExp::new(s2.sqrt(), e)
}

fn mul(a: &MatFe, b: &MatFe) -> MatFe {
    let e = |i: usize, j: usize| a[i][0] * b[0][j] + a[i][1] * b[1][j];
    [[e(0, 0), e(0, 1)], [e(1, 0), e(1, 1)]]
}

fn add(a: &MatFe, b: &MatFe) -> MatFe {
    [[a[0][0] + b[0][0], a[0][1] + b[0][1]], [a[1][0] + b[1][0], a[1][1] + b[1][1]]]
}

/// x then y.
fn merge(x: &Wide, y: &Wide, dc_max: FloatExp) -> Wide {
    let na = norm(&x.a);
    let r = if na.is_zero() {
        x.r
    } else {
        let reach = y.r - norm(&x.b) * dc_max;
        if reach > FloatExp::ZERO { x.r.min(reach / na) } else { FloatExp::ZERO }
    };
    Wide { a: mul(&y.a, &x.a), b: add(&mul(&y.a, &x.b), &y.b), r }
}

/// The radius of the single step from Z = `z` with the map of iteration `n`.
fn single_radius<S: Stepper>(stepper: &S, formula: &Formula, n: u32, z: [f64; 2], how: &Build) -> f64 {
    let ph = formula.phase(n);
    let az = z[0].hypot(z[1]);
    let (fin, p, fout, _) = ph.kind.shape(ph.power);
    // The nonlinear terms: a power's stay below ε of the linear one for |δ| < ε |Z| / (p - 1);
    // a sum of two powers has its own bound (`formula::sum`), against |g| |δ|, g the
    // complex derivative (the modulus of a column of the Jacobian), and folds only before.
    let (fin, fout, mut r) = match ph.kind.sum() {
        Some(s) => {
            let j = stepper.jacobian(n, z);
            (s.fold_in, 0, sum::bla_radius(s.q, ph.a.get(), az, j[0][0].hypot(j[1][0]), how.eps))
        }
        None => (fin, fout, how.eps * az / (p - 1) as f64),
    };
    // A fold before the power, or the sign of x or y that a signed fold after it reads,
    // stays put while the delta does not reach that part's zero line.
    if (fin & FOLD_RE != 0) || (fout & IM_BY_X != 0) {
        r = r.min(z[0].abs() * SAFE);
    }
    if (fin & FOLD_IM != 0) || (fout & IM_BY_Y != 0) {
        r = r.min(z[1].abs() * SAFE);
    }
    if let Some((pre, _, _)) = formula.phase(n).kind.factors() {
        // A product folds u = Z^PRE: each part of it keeps its sign while |δ| stays below
        // |Z| ((1 + |part| / |Z|^PRE)^(1/PRE) - 1), as (|Z| + |δ|)^PRE - |Z|^PRE bounds
        // the change of u (|x| and |y| for PRE = 1).
        let u = if pre == 1 { z } else { [z[0] * z[0] - z[1] * z[1], 2.0 * z[0] * z[1]] };
        let zp = az.powi(pre as i32);
        for part in u {
            let q = part.abs() / zp;
            let t = if q.is_finite() { (q.ln_1p() / pre as f64).exp_m1() } else { 0.0 };
            r = r.min(az * t * SAFE);
        }
    } else if fout != 0 {
        // |Re U| and |Im U| are those of f(Z): a fold or a negation keeps magnitudes.
        let u = stepper.apply(n, z);
        let zp = az.powi(p as i32);
        for (bit, part) in [(FOLD_RE, u[0]), (FOLD_IM, u[1])] {
            if fout & bit != 0 {
                let q = part.abs() / zp;
                let t = if q.is_finite() { (q.ln_1p() / p as f64).exp_m1() } else { 0.0 };
                r = r.min(az * t * SAFE);
            }
        }
    }
    r.min((how.escape_radius - az).max(0.0)).max(0.0)
}

/// The f64 and (with `how.floatexp`) FloatExp tables of one reference orbit, starting at
/// `origin`.
pub(super) fn build<S: Stepper>(
    stepper: &S,
    formula: &Formula,
    track: &Track,
    origin: u32,
    how: &Build,
) -> (Table<f64>, Option<Table<FloatExp>>) {
    let zero = FloatExp::ZERO;
    let one = FloatExp::ONE;
    let end = track.last().min(origin.saturating_add(TREE_END));
    let b = if how.mandelbrot { [[one, zero], [zero, one]] } else { [[zero; 2]; 2] };
    // Single steps from origin .. end (each lands at most at `end`).
    let mut level: Vec<Wide> = (origin..end)
        .into_par_iter()
        .map(|j| {
            let z = track.z[j as usize];
            let n = track.phase.wrapping_add(j);
            let wide = track.is_wide(j);
            let r = if wide { 0.0 } else { single_radius(stepper, formula, n, z, how) };
            Wide { a: to_fe(&stepper.jacobian(n, z)), b, r: FloatExp::from(r) }
        })
        .collect();
    let dips = dip_steps(&level, track, origin, how.dc_max);
    let mut f64_levels = Vec::new();
    let mut fe_levels = Vec::new();
    while level.len() >= 2 {
        level = level.par_chunks_exact(2).map(|p| merge(&p[0], &p[1], how.dc_max)).collect();
        f64_levels.push(level.par_iter().map(to_f64_step).collect::<Vec<_>>());
        if how.floatexp {
            fe_levels.push(level.par_iter().map(|w| Step { a: w.a, b: w.b, r2: w.r * w.r }).collect::<Vec<_>>());
        }
    }
    let dips64 = dips.map(to_f64_step).monotone();
    let dipsfe = dips.map(|w: &Wide| Step { a: w.a, b: w.b, r2: w.r * w.r }).monotone();
    let max64 = f64_levels.first().map_or(-1.0, |l: &Vec<Step<f64>>| l.iter().map(|s| s.r2).fold(-1.0, f64::max));
    let max64 = dips64.steps.iter().map(|(s, _)| s.r2).fold(max64, f64::max);
    let maxfe = fe_levels
        .first()
        .map_or(-FloatExp::ONE, |l: &Vec<Step<FloatExp>>| l.iter().map(|s| s.r2).fold(-FloatExp::ONE, FloatExp::max));
    let maxfe = dipsfe.steps.iter().map(|(s, _)| s.r2).fold(maxfe, FloatExp::max);
    let t64 = Table { origin, levels: f64_levels, dips: dips64, max_r2: max64 };
    let tfe = how.floatexp.then_some(Table { origin, levels: fe_levels, dips: dipsfe, max_r2: maxfe });
    (t64, tfe)
}

/// The dips' steps (see [`Dips`]) over the single steps `singles` (index `origin + j` at
/// `j`). With the dips d_0 < d_1 < ..., leg j is the single steps from d_j up to d_(j+1)
/// (the step at the dip included) and start j's first leg those from d_j + 1 (from the
/// origin for the first start); a start's step to the next dip of stage k is its first leg
/// merged with the legs up to that dip, which a right fold over each stage gives in one
/// merge per leg.
fn dip_steps(singles: &[Wide], track: &Track, origin: u32, dc_max: FloatExp) -> Dips<Wide> {
    let count = singles.len() as u32;
    let mag2 = |j: u32| {
        let z = track.z[(origin + j) as usize];
        FloatExp::from(z[0] * z[0] + z[1] * z[1])
    };
    // The z^2 engine's marks keep their first index; here the origin is no dip, and the
    // first index only sets the least |Z| (a placeholder first, dropped after).
    let find = |at: &mut dyn Iterator<Item = u32>| dips(std::iter::once(0).chain(at), mag2).split_off(1);
    let d = find(&mut (1..count));
    // Each dip's highest stage: stage k + 1's dips are found among stage k's the same way.
    let mut stage = vec![0usize; d.len()];
    let mut marks = d.clone();
    let mut stages = 1;
    loop {
        let next = find(&mut marks.iter().copied());
        if next.is_empty() || next.len() + 1 == marks.len() {
            break;
        }
        for &m in &next {
            stage[d.binary_search(&m).unwrap_or_default()] = stages;
        }
        marks = next;
        stages += 1;
    }
    // The single steps of [a, b) merged (a < b).
    let fold = |a: u32, b: u32| {
        let run = &singles[a as usize..b as usize];
        run[1..].iter().fold(run[0], |acc, s| merge(&acc, s, dc_max))
    };
    let legs: Vec<Wide> = d.par_windows(2).map(|w| fold(w[0], w[1])).collect();
    // Starts: the origin (before d_0), then after every dip that has a next one.
    let start_at = |j: usize| if j == 0 { 0 } else { d[j - 1] + 1 };
    let starts: Vec<usize> = (0..d.len()).filter(|&j| start_at(j) < d[j]).collect();
    let heads: Vec<Wide> = starts.par_iter().map(|&j| fold(start_at(j), d[j])).collect();
    // tails[k][j]: legs j, j + 1, ... merged up to the next dip of stage k or higher.
    let mut per_start: Vec<Vec<(Wide, u32)>> =
        heads.iter().zip(&starts).map(|(h, &j)| vec![(*h, d[j] - start_at(j))]).collect();
    for k in 0..stages {
        // From dip j: legs j, j + 1, ... merged up to the next dip of stage k or higher,
        // and that dip's place in `d` (none where no such dip follows).
        let mut tails: Vec<Option<(Wide, usize)>> = vec![None; legs.len() + 1];
        for j in (0..legs.len()).rev() {
            tails[j] = if stage[j + 1] >= k {
                Some((legs[j], j + 1))
            } else {
                tails[j + 1].map(|(after, end)| (merge(&legs[j], &after, dc_max), end))
            };
        }
        for (steps, &j) in per_start.iter_mut().zip(&starts) {
            // Start j's head ends at d_j: on to the next dip of stage k, unless d_j is one.
            if stage[j] >= k {
                continue;
            }
            let Some((tail, end)) = tails[j] else { continue };
            let (head, len) = steps[0];
            let len = len + (d[end] - d[j]);
            if steps.last().is_none_or(|(_, n)| *n < len) {
                steps.push((merge(&head, &tail, dc_max), len));
            }
        }
    }
    let mut marked = vec![0u64; count.div_ceil(64) as usize];
    let mut first = vec![0u32];
    let mut flat = Vec::new();
    let mut at = Vec::new();
    for (steps, &j) in per_start.into_iter().zip(&starts) {
        let s = start_at(j);
        marked[(s / 64) as usize] |= 1 << (s % 64);
        at.push(s);
        flat.extend(steps);
        first.push(flat.len() as u32);
    }
    let stages = if d.is_empty() { 0 } else { stages };
    Dips { marked, starts: at, first, steps: flat, stages }
}

/// A step's f64 form: unusable (negative radius) where an entry leaves f64's range.
fn to_f64_step(w: &Wide) -> Step<f64> {
    let a = w.a.map(|row| row.map(FloatExp::to_f64));
    let b = w.b.map(|row| row.map(FloatExp::to_f64));
    let finite = a.iter().chain(&b).flatten().all(|x| x.is_finite());
    let r = w.r.to_f64();
    Step { a, b, r2: if finite && r > 0.0 { r * r } else { -1.0 } }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_operator_norm_of_a_rotation_and_of_a_shear() {
        let m = |a: [[f64; 2]; 2]| a.map(|r| r.map(FloatExp::from));
        // 3 + 4i as a matrix: norm 5.
        assert!((norm(&m([[3.0, -4.0], [4.0, 3.0]])).to_f64() - 5.0).abs() < 1e-14);
        // A reflection of it: still 5.
        assert!((norm(&m([[3.0, 4.0], [4.0, -3.0]])).to_f64() - 5.0).abs() < 1e-14);
        // [[1, 1], [0, 1]]: the golden ratio.
        let phi = (1.0 + 5f64.sqrt()) / 2.0;
        assert!((norm(&m([[1.0, 1.0], [0.0, 1.0]])).to_f64() - phi).abs() < 1e-14);
    }
}
