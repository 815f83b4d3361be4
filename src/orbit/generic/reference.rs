//! The reference orbits of the generic engine: orbits of the view's centre and of 0 in big
//! floats, stored as f64 pairs, with the few values f64 cannot stand for kept in FloatExp.
//!
//! A sample is iterated as a delta against one of these ([`super::perturb`]). Rebasing
//! (Zhuoran's, as the quadratic engine does) moves a sample that came nearer to 0 than to
//! its reference onto an orbit of 0, with its full value as the new delta. For a hybrid
//! (a cycle of P phases, iteration n using phase n mod P) an orbit of 0 is only the right
//! target if it steps with the phases the sample steps with from there: a sample rebased
//! at iteration n takes phase n mod P next. So there is one orbit of 0 per phase offset k,
//! W_0 = 0, W_(j+1) = f_(k+j)(W_j) + C, and a rebase at iteration n goes to the orbit of
//! offset n mod P (Fraktaler-3 keeps one reference per phase for its hybrids likewise).
//! Then a sample on orbit k at index j always has n ≡ k + j (mod P), so the phase of a
//! step follows from the sample's own iteration index.
//!
//! The Mandelbrot form's primary reference is the orbit of 0 with offset 0 (the centre's
//! orbit starts at 0). A Julia set's primary reference starts at the centre, Z_0 = centre,
//! and its P orbits of 0 (the critical orbits under the Julia parameter) are the rebase
//! targets.
//!
//! An orbit is stored to its first value beyond [`reference_radius`] (larger than the
//! escape radius, so that samples near a reference that escapes escape before it ends) or
//! to the iteration limit. Values whose parts are nonzero but below [`TINY`], or whose
//! powers leave f64's range, or whose power U = W^p (before a fold after the power) has a
//! folded part so near 0 that U computed from the f64 value could have it with the wrong
//! sign (below 2^-45 of |U|: a preperiodic orbit may sit on such a fold line for good), are
//! *wide*: the loop takes the step from them in FloatExp ([`super::wide`]), with U from
//! the big floats, rather than from their f64 rounding, which may have lost a sign a fold
//! depends on.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use crate::cancel::Cancelled;
use crate::formula::map::{FOLD_IM, FOLD_RE, fold_big};
use crate::formula::{Formula, Stepper};
use crate::num::FloatExp;
use crate::num::bigcomplex::BigC;

/// Parts (nonzero) below this make a value wide: f64 holds them without all their bits,
/// or not at all.
pub(super) const TINY: f64 = f64::from_bits((1023 - 960) << 52);

/// A folded part of U below this fraction of |U| makes a value wide.
const NEAR_FOLD: f64 = f64::from_bits((1023 - 45) << 52);

/// A wide value: its index, Z and U = W^p (the power's value before any fold after it,
/// with the signs the big floats give), in FloatExp.
#[derive(Debug, Clone, Copy)]
pub(super) struct Wide {
    pub(super) m: u32,
    pub(super) z: [FloatExp; 2],
    pub(super) u: [FloatExp; 2],
}

/// Reference iterations between looks at the cancel flag (and progress reports).
const REPORT_EVERY: u32 = 1 << 12;

/// One reference orbit.
#[derive(Debug, Clone)]
pub struct Track {
    /// Z_0 ..= Z_last, rounded to f64.
    pub(super) z: Vec<[f64; 2]>,
    /// The orbit's phase offset: Z_j steps with phase k + j.
    pub(super) phase: u32,
    /// The wide indices, ascending, with their values.
    pub(super) wide: Vec<Wide>,
    /// True when the orbit ended by escaping (else at the iteration limit).
    pub(super) escaped: bool,
}

impl Track {
    /// The last index stored.
    #[inline(always)]
    pub(super) fn last(&self) -> u32 {
        self.z.len() as u32 - 1
    }

    /// The first index from `m` on where the fast loop must stop: a wide index, or the last.
    pub(super) fn stop(&self, m: u32) -> u32 {
        let k = self.wide.partition_point(|w| w.m < m);
        self.wide.get(k).map_or(self.last(), |w| w.m.min(self.last()))
    }

    /// Z_m in FloatExp, and U_m where m is wide.
    pub(super) fn value_fe(&self, m: u32) -> ([FloatExp; 2], Option<[FloatExp; 2]>) {
        match self.wide.binary_search_by_key(&m, |w| w.m) {
            Ok(k) => (self.wide[k].z, Some(self.wide[k].u)),
            Err(_) => {
                let z = self.z[m as usize];
                ([FloatExp::from(z[0]), FloatExp::from(z[1])], None)
            }
        }
    }

    /// True where m is wide.
    pub(super) fn is_wide(&self, m: u32) -> bool {
        self.wide.binary_search_by_key(&m, |w| w.m).is_ok()
    }
}

/// The radius past which a reference orbit stops: larger than the escape radius, so that a
/// sample following an escaping reference escapes (its own test) before the reference ends.
pub(super) fn reference_radius(escape_radius: f64) -> f64 {
    escape_radius.max(1024.0)
}

/// True when an f64 pair stands for `v` well enough for the fast loop's step: no part is
/// nonzero below [`TINY`], and `v`'s powers up to `power` stay in f64's range.
fn narrow(v: [FloatExp; 2], power: u32) -> bool {
    let part = |x: FloatExp| x.is_zero() || x.abs().to_f64() >= TINY;
    if !(part(v[0]) && part(v[1])) {
        return false;
    }
    let big = v[0].abs().max(v[1].abs());
    big.is_zero() || big.log2() * power as f64 > -960.0
}

/// U = W^p for the phase `n` of `formula` at `z`: its fold before the power, then the
/// power, in big floats.
fn power_big(formula: &Formula, n: u32, z: &BigC) -> BigC {
    let phase = formula.phase(n);
    if let Some((pre, _, _)) = phase.kind.factors() {
        // A product folds u = Z^PRE.
        return z.pow(pre);
    }
    if phase.kind.sum().is_some() {
        // A sum folds nothing: its highest power, which no step reads.
        return z.pow(phase.power);
    }
    let (fin, p, _, _) = phase.kind.shape(phase.power);
    fold_big(fin, z.clone()).pow(p)
}

/// True when U = f(Z) before its fold (|parts| those of `fz`) has a folded part near 0;
/// for a product, when u = Z^PRE (from `z`) has, for PRE > 1 (u = Z itself keeps its signs
/// in f64).
fn near_fold(formula: &Formula, n: u32, z: [FloatExp; 2], fz: [FloatExp; 2]) -> bool {
    let phase = formula.phase(n);
    if phase.kind.sum().is_some() {
        return false;
    }
    if let Some((pre, _, _)) = phase.kind.factors() {
        if pre == 1 {
            return false;
        }
        let u = [z[0] * z[0] - z[1] * z[1], (z[0] * z[1]).ldexp(1)];
        let size = u[0].abs().max(u[1].abs()).mul_f64(NEAR_FOLD);
        return u[0].abs() < size || u[1].abs() < size;
    }
    let (_, _, fout, _) = phase.kind.shape(phase.power);
    let size = fz[0].abs().max(fz[1].abs()).mul_f64(NEAR_FOLD);
    (fout & FOLD_RE != 0 && fz[0].abs() < size) || (fout & FOLD_IM != 0 && fz[1].abs() < size)
}

/// Iterates W_0 = `start`, W_(j+1) = f_(phase+j)(W_j) + `c` at `c.bits` until |W| passes
/// `radius` or j reaches `max_iter`. `progress` gets the iterations done; the cancel flag is
/// read every few thousand.
#[allow(clippy::too_many_arguments)]
pub(super) fn compute<S: Stepper>(
    stepper: &S,
    formula: &Formula,
    start: &BigC,
    c: &BigC,
    phase: u32,
    max_iter: u32,
    radius: f64,
    max_power: u32,
    progress: &(dyn Fn(u32) + Sync),
    cancel: &AtomicBool,
) -> Result<Track, Cancelled> {
    let mut out = Track { z: Vec::new(), phase, wide: Vec::new(), escaped: false };
    let r2 = radius * radius;
    let mut z = start.with_bits(c.bits);
    let mut j = 0u32;
    loop {
        if j.is_multiple_of(REPORT_EVERY) {
            if cancel.load(Ordering::Relaxed) {
                return Err(Cancelled);
            }
            progress(j);
        }
        let fe = z.to_fe();
        let f = [fe[0].to_f64(), fe[1].to_f64()];
        out.z.push(f);
        let escaped = f[0] * f[0] + f[1] * f[1] > r2;
        if escaped || j >= max_iter {
            out.escaped = escaped;
            if !narrow(fe, max_power) {
                out.wide.push(Wide { m: j, z: fe, u: [FloatExp::ZERO; 2] });
            }
            break;
        }
        let n = phase.wrapping_add(j);
        let fz = stepper.apply_big(n, &z);
        // The map's own parts decide a fold after the power: they must be f64 too.
        let ffe = fz.to_fe();
        if !narrow(fe, max_power) || !narrow(ffe, 1) || near_fold(formula, n, fe, ffe) {
            out.wide.push(Wide { m: j, z: fe, u: power_big(formula, n, &z).to_fe() });
        }
        z = fz.add(c);
        j += 1;
    }
    progress(max_iter);
    Ok(out)
}

/// The orbits of a view, computed side by side (one thread each): for the Mandelbrot form
/// the P orbits of 0 under C (phase offsets 0..P, the first the primary reference); for a
/// Julia set the centre's orbit and then the P orbits of 0. `progress` gets (iterations
/// done, of this many) summed over the orbits.
#[allow(clippy::too_many_arguments)]
pub(super) fn compute_all<S: Stepper>(
    stepper: &S,
    formula: &Formula,
    center: &BigC,
    julia: Option<&BigC>,
    max_iter: u32,
    radius: f64,
    max_power: u32,
    progress: &(dyn Fn(u64, u64) + Sync),
    cancel: &AtomicBool,
) -> Result<Vec<Track>, Cancelled> {
    use rayon::prelude::*;
    let period = stepper.period();
    let bits = center.bits;
    let zero = BigC::zero(bits);
    // (start, c, phase) of each orbit.
    let mut jobs: Vec<(&BigC, &BigC, u32)> = Vec::new();
    let c = julia.unwrap_or(center);
    if julia.is_some() {
        jobs.push((center, c, 0));
    }
    jobs.extend((0..period).map(|k| (&zero, c, k)));
    let total = max_iter as u64 * jobs.len() as u64;
    let done: Vec<AtomicU64> = jobs.iter().map(|_| AtomicU64::new(0)).collect();
    let tracks: Vec<Result<Track, Cancelled>> = jobs
        .par_iter()
        .enumerate()
        .map(|(k, &(start, c, phase))| {
            let report = |j: u32| {
                done[k].store(j as u64, Ordering::Relaxed);
                progress(done.iter().map(|d| d.load(Ordering::Relaxed)).sum(), total);
            };
            compute(stepper, formula, start, c, phase, max_iter, radius, max_power, &report, cancel)
        })
        .collect();
    tracks.into_iter().collect()
}
