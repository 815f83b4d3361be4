//! Boundary descents for any formula, for the deep-view fuzzer ([`super::views`]).
//!
//! The minibrot and Misiurewicz searches of [`crate::locate`] are z² + c's (ball periods,
//! complex Newton); a Burning Ship, a Buffalo or a hybrid has neither. What every escape-time
//! set has is a boundary where escaping and non-escaping points meet, and that can be
//! followed down by sampling alone: a grid over the view, a cell whose corners disagree
//! (some escape within the limit, some do not), a new view about a random point of that
//! cell a few times smaller, again until the target zoom. The limit grows with the
//! escape counts seen (a grid where everything escapes raises it; one where nothing does
//! zooms back out). The same works for a Julia set (z_0 the point, c fixed) and along the
//! real axis, which every family's Mandelbrot form maps to itself, where the folds of the
//! Burning Ship and its relatives meet (|y| is not differentiable at y = 0).
//!
//! [`periodic_point`] then finds, near a descent's end, a point whose orbit returns to 0
//! after p steps (the centre of a minibrot or "miniship") by Newton's method on
//! z_p(c) = 0 with the real 2×2 Jacobian, where it is invertible.
//!
//! Past zoom 1e9 a grid is sampled by perturbation about a big-float orbit of a point near
//! it ([`escape_times_about`]: one orbit for the grids of four decades, not one a sample),
//! with f64 deltas down to 1e-250 and FloatExp ones below: that is what takes the descents
//! to 1e300 and beyond in seconds to minutes.
//!
//! The orbits here use the engines' maps (`formula::Stepper`): this only chooses where to
//! look; the truth the views are checked against is [`super::kf_maps`].

use rayon::prelude::*;

use super::views::Rng;
use crate::formula::{Cycle, Formula, Stepper};
use crate::num::bigcomplex::BigC;
use crate::num::{FloatExp, Real};

/// |z|² beyond which the descent counts an orbit escaped (every family's set lies in |c| <= 2).
const ESCAPE2: f64 = 16.0;
/// Samples per side of the descent's grid.
pub const GRID: usize = 8;
/// Samples along the real axis in [`descend_real`].
const LINE: usize = 33;
/// The first iteration limit of a descent.
const FIRST_LIMIT: u32 = 200;
/// Views shallower than this (log10 of the zoom) are sampled in f64.
const F64_DEPTH: f64 = 9.0;

/// Where a descent ended.
#[derive(Debug, Clone)]
pub struct Found {
    /// The view's centre.
    pub center: BigC,
    /// The view's radius.
    pub radius: FloatExp,
    /// The largest escape index among the last grid's samples.
    pub max_n: u32,
}

/// Bits that place a point exactly at zoom 10^log10_zoom, with a margin.
fn bits_for(log10_zoom: f64) -> u64 {
    crate::num::bigfloat::precision_for(-log10_zoom)
}

/// log10 of 1 / `radius`.
fn depth(radius: FloatExp) -> f64 {
    -radius.log2() * std::f64::consts::LOG10_2
}

/// p + d, at p's precision.
pub fn shifted(p: &BigC, d: [FloatExp; 2]) -> BigC {
    let big = |x: FloatExp| BigC::from_f64(x.mantissa(), 0.0, p.bits).ldexp(x.exponent()).re;
    p.add(&BigC { re: big(d[0]), im: big(d[1]), bits: p.bits })
}

/// z_0 and c of `point`'s orbit in big floats at its precision: (0, point) in the
/// Mandelbrot form, (point, `julia`) in the Julia form.
fn orbit_start(julia: Option<&BigC>, point: &BigC) -> (BigC, BigC) {
    match julia {
        Some(c) => (point.clone(), c.with_bits(point.bits)),
        None => (BigC::zero(point.bits), point.clone()),
    }
}

/// The escape index of `point`'s orbit under `formula` within `limit` (Mandelbrot form:
/// c = point, z_0 = 0; Julia form: z_0 = point), or None; in f64 where `shallow`.
pub fn escape_time(formula: Formula, julia: Option<&BigC>, point: &BigC, limit: u32, shallow: bool) -> Option<u32> {
    let s = Cycle(formula);
    if shallow {
        let f = |b: &BigC| b.to_fe().map(FloatExp::to_f64);
        let p = f(point);
        let (mut z, c) = match julia {
            Some(c) => (p, f(c)),
            None => ([0.0; 2], p),
        };
        for n in 0..limit {
            if z[0] * z[0] + z[1] * z[1] > ESCAPE2 {
                return Some(n);
            }
            let w = s.apply(n, z);
            z = [w[0] + c[0], w[1] + c[1]];
        }
        return None;
    }
    let (mut z, c) = orbit_start(julia, point);
    for n in 0..limit {
        let [x, y] = z.to_fe();
        if (x * x + y * y).to_f64() > ESCAPE2 {
            return Some(n);
        }
        z = s.apply_big(n, &z).add(&c);
    }
    None
}

/// How far (in grid radii) from the point of a [`Reference`] a grid may lie and still be
/// sampled about it: an offset that large keeps 16 - 4 digits of a grid step in f64.
const REUSE: f64 = 1e4;

/// A big-float orbit of one point, rounded to f64, that grids near it are sampled about
/// ([`escape_times_about`]); a descent keeps one for the grids of the next four decades of zoom,
/// which spares a big-float orbit a grid.
pub struct Reference {
    /// The orbit's point (its z_0 in the Julia form, its c in the Mandelbrot form).
    center: BigC,
    /// Z_0 .. Z_last: up to the orbit's escape (that value included) or the limit.
    orbit: Vec<[f64; 2]>,
    /// Whether the orbit escaped (else it holds the limit's iterations).
    escaped: bool,
}

impl Reference {
    /// `center`'s orbit to `limit` iterations, at precision `bits`.
    pub fn new(formula: Formula, julia: Option<&BigC>, center: &BigC, bits: u64, limit: u32) -> Reference {
        let s = Cycle(formula);
        let center = center.with_bits(bits);
        let (mut z, c) = orbit_start(julia, &center);
        let mut orbit = Vec::new();
        for n in 0..limit {
            let zf = z.to_fe().map(FloatExp::to_f64);
            orbit.push(zf);
            if zf[0] * zf[0] + zf[1] * zf[1] > ESCAPE2 {
                return Reference { center, orbit, escaped: true };
            }
            z = s.apply_big(n, &z).add(&c);
        }
        Reference { center, orbit, escaped: false }
    }

    /// Whether grids about `center` of radius `radius` can be sampled about this orbit to
    /// `limit` iterations.
    fn serves(&self, center: &BigC, radius: FloatExp, limit: u32) -> bool {
        let far = center.sub(&self.center).to_fe().iter().fold(FloatExp::ZERO, |m, x| m.max(x.abs()));
        (self.escaped || self.orbit.len() >= limit as usize) && far <= radius.mul_f64(REUSE)
    }
}

/// Offsets this small or smaller (log10) are iterated as FloatExp deltas, larger ones as
/// f64: the f64 range then holds every offset, and the deltas that shrink from one where
/// the orbit passes near a critical point, with 50 decades to spare.
const FLOATEXP_DEPTH: f64 = 250.0;

/// The escape indices (as [`escape_time`]) of the points `center` + `offsets[k]`, by
/// perturbation about `reference` (an orbit to `limit` at least, or to its escape): the
/// points' orbits are iterated as deltas from it (f64 where the offsets are larger than
/// 1e-250, FloatExp where they are not), and a delta is moved onto the
/// orbit's start where the point's orbit comes nearer 0 than the delta is large, or where
/// the reference ended (Zhuoran's rebasing; on a hybrid, onto the start of the phase the
/// point is in). A descent only chooses where to look, so this need not be exact; it
/// takes the descents to 1e300 and beyond.
pub fn escape_times_about(
    formula: Formula,
    julia: Option<&BigC>,
    reference: &Reference,
    center: &BigC,
    offsets: &[[FloatExp; 2]],
    limit: u32,
) -> Vec<Option<u32>> {
    let period = formula.phases().len();
    if reference.orbit.len() <= period {
        // Too short an orbit to rebase onto (a Julia centre that escapes at once).
        return offsets.iter().map(|&o| escape_time(formula, julia, &shifted(center, o), limit, false)).collect();
    }
    let from = center.sub(&reference.center).to_fe();
    let offsets: Vec<[FloatExp; 2]> = offsets.iter().map(|o| [from[0] + o[0], from[1] + o[1]]).collect();
    let largest = offsets.iter().flatten().fold(FloatExp::ZERO, |m, x| m.max(x.abs()));
    if largest.log2() * std::f64::consts::LOG10_2 > -FLOATEXP_DEPTH {
        perturbed::<f64>(formula, julia, &reference.orbit, &offsets, limit)
    } else {
        perturbed::<FloatExp>(formula, julia, &reference.orbit, &offsets, limit)
    }
}

/// The escape indices of the points `offsets` away from the point of `orbit` (longer than
/// the formula's cycle), with deltas in `R`, the points shared among the threads.
fn perturbed<R: Real>(
    formula: Formula,
    julia: Option<&BigC>,
    orbit: &[[f64; 2]],
    offsets: &[[FloatExp; 2]],
    limit: u32,
) -> Vec<Option<u32>> {
    let s = Cycle(formula);
    let period = s.period() as usize;
    offsets
        .par_iter()
        .map(|&o| {
            let o = o.map(R::from_fe);
            let dc = if julia.is_some() { [R::ZERO; 2] } else { o };
            let mut d = if julia.is_some() { o } else { [R::ZERO; 2] };
            let mut m = 0usize;
            for n in 0..limit as usize {
                let zm = orbit[m];
                let full = [zm[0] + d[0].to_f64(), zm[1] + d[1].to_f64()];
                let r2 = full[0] * full[0] + full[1] * full[1];
                if r2 > ESCAPE2 {
                    return Some(n as u32);
                }
                if m + 1 == orbit.len() || r2 < (d[0] * d[0] + d[1] * d[1]).to_f64() {
                    // Onto Z_k, k the phase of iteration n (0 for a single family), which
                    // leaves the orbit room for a step (it is longer than the cycle).
                    let k = n % period;
                    let zk = orbit[k];
                    d = [R::from_f64(zm[0] - zk[0]) + d[0], R::from_f64(zm[1] - zk[1]) + d[1]];
                    m = k;
                }
                let step = s.delta(m as u32, orbit[m], d);
                d = [step[0] + dc[0], step[1] + dc[1]];
                m += 1;
            }
            None
        })
        .collect()
}

/// The escape indices of `center` + `offsets[k]` for a grid of radius `radius`: each in f64
/// where `shallow`, else by perturbation about `reference`, replaced by an orbit of `center`
/// (at precision `bits`) where it does not serve the grid.
#[allow(clippy::too_many_arguments)]
fn sample(
    formula: Formula,
    julia: Option<&BigC>,
    reference: &mut Option<Reference>,
    center: &BigC,
    radius: FloatExp,
    offsets: &[[FloatExp; 2]],
    limit: u32,
    shallow: bool,
) -> Vec<Option<u32>> {
    if shallow {
        return offsets.iter().map(|&o| escape_time(formula, julia, &shifted(center, o), limit, true)).collect();
    }
    let r = match reference.take() {
        Some(r) if r.serves(center, radius, limit) => r,
        _ => {
            let bits = bits_for(depth(radius) + 10.0 + REUSE.log10()).max(center.bits);
            Reference::new(formula, julia, center, bits, limit)
        }
    };
    let n = escape_times_about(formula, julia, &r, center, offsets, limit);
    *reference = Some(r);
    n
}

/// Follows the boundary of `formula`'s set (Julia set of `julia` where given) down from
/// the view (`center`, `radius`) to zoom 10^`log10_zoom`, with iteration limits up to
/// `max_iter`; None when the boundary is lost (a Julia set that is dust, a limit too low).
pub fn descend(
    rng: &mut Rng,
    formula: Formula,
    julia: Option<&BigC>,
    center: BigC,
    radius: FloatExp,
    log10_zoom: f64,
    max_iter: u32,
) -> Option<Found> {
    let (mut center, mut radius) = (center, radius);
    let mut limit = FIRST_LIMIT.min(max_iter);
    let mut misses = 0;
    let mut reference = None;
    for _ in 0..(60.0 + 4.0 * log10_zoom) as usize {
        let d = depth(radius);
        let bits = bits_for(d + 10.0).max(center.bits);
        center = center.with_bits(bits);
        let step = radius.mul_f64(2.0 / (GRID - 1) as f64);
        let at = |i: usize, j: usize| [step.mul_f64(i as f64) - radius, step.mul_f64(j as f64) - radius];
        let offsets: Vec<[FloatExp; 2]> = (0..GRID * GRID).map(|k| at(k / GRID, k % GRID)).collect();
        let flat = sample(formula, julia, &mut reference, &center, radius, &offsets, limit, d < F64_DEPTH);
        let mut n = [[None; GRID]; GRID];
        for (k, v) in flat.into_iter().enumerate() {
            n[k / GRID][k % GRID] = v;
        }
        let max_n = n.iter().flatten().flatten().copied().max();
        if d >= log10_zoom {
            return Some(Found { center, radius, max_n: max_n.unwrap_or(limit) });
        }
        let mut mixed = Vec::new();
        for i in 0..GRID - 1 {
            for j in 0..GRID - 1 {
                let corners = [n[i][j], n[i + 1][j], n[i][j + 1], n[i + 1][j + 1]];
                if corners.iter().any(Option::is_some) && corners.iter().any(Option::is_none) {
                    mixed.push((i, j));
                }
            }
        }
        if mixed.is_empty() {
            misses += 1;
            if misses > 8 {
                return None;
            }
            if n.iter().flatten().all(Option::is_some) && limit < max_iter {
                // Everything escaped: the set's points here need a higher limit.
                limit = limit.saturating_mul(2).min(max_iter);
            } else {
                radius = radius.mul_f64(2.0);
            }
            continue;
        }
        misses = 0;
        if let Some(m) = max_n {
            limit = limit.max(m.saturating_mul(2).saturating_add(100)).min(max_iter);
        }
        let (i, j) = mixed[rng.next_u64() as usize % mixed.len()];
        let [x, y] = at(i, j);
        let to = [x + step.mul_f64(rng.uniform(0.0, 1.0)), y + step.mul_f64(rng.uniform(0.0, 1.0))];
        center = shifted(&center, to);
        radius = step.mul_f64(rng.uniform(0.6, 1.5));
    }
    None
}

/// The first sample, row by row, of the [`GRID`] × [`GRID`] grid of radius `radius` about
/// `center` (the grid a descent ending there sampled last) whose orbit in `formula`'s
/// Mandelbrot form does not escape within `limit`; None when every sample escapes.
pub fn inside_sample(formula: Formula, center: &BigC, radius: FloatExp, limit: u32) -> Option<BigC> {
    let step = radius.mul_f64(2.0 / (GRID - 1) as f64);
    let shallow = depth(radius) < F64_DEPTH;
    (0..GRID * GRID)
        .map(|k| shifted(center, [step.mul_f64((k / GRID) as f64) - radius, step.mul_f64((k % GRID) as f64) - radius]))
        .find(|p| escape_time(formula, None, p, limit, shallow).is_none())
}

/// [`descend`] along the real axis of `formula`'s Mandelbrot form, from the segment
/// [-2.5, 2.5]: every centre has imaginary part exactly 0.
pub fn descend_real(rng: &mut Rng, formula: Formula, log10_zoom: f64, max_iter: u32) -> Option<Found> {
    let mut center = BigC::zero(64);
    let mut radius = FloatExp::from(2.5);
    let mut limit = FIRST_LIMIT.min(max_iter);
    let mut misses = 0;
    let mut reference = None;
    for _ in 0..(60.0 + 4.0 * log10_zoom) as usize {
        let d = depth(radius);
        center = center.with_bits(bits_for(d + 10.0).max(center.bits));
        let step = radius.mul_f64(2.0 / (LINE - 1) as f64);
        let at = |i: usize| [step.mul_f64(i as f64) - radius, FloatExp::ZERO];
        let offsets: Vec<[FloatExp; 2]> = (0..LINE).map(at).collect();
        let n = sample(formula, None, &mut reference, &center, radius, &offsets, limit, d < F64_DEPTH);
        let max_n = n.iter().flatten().copied().max();
        if d >= log10_zoom {
            return Some(Found { center, radius, max_n: max_n.unwrap_or(limit) });
        }
        let mixed: Vec<usize> = (0..LINE - 1).filter(|&i| n[i].is_some() != n[i + 1].is_some()).collect();
        if mixed.is_empty() {
            misses += 1;
            if misses > 8 {
                return None;
            }
            if n.iter().all(Option::is_some) && limit < max_iter {
                limit = limit.saturating_mul(2).min(max_iter);
            } else {
                radius = radius.mul_f64(2.0);
            }
            continue;
        }
        misses = 0;
        if let Some(m) = max_n {
            limit = limit.max(m.saturating_mul(2).saturating_add(100)).min(max_iter);
        }
        let i = mixed[rng.next_u64() as usize % mixed.len()];
        center = shifted(&center, [at(i)[0] + step.mul_f64(rng.uniform(0.0, 1.0)), FloatExp::ZERO]);
        radius = step.mul_f64(rng.uniform(1.0, 4.0));
    }
    None
}

/// A point near `near` whose orbit under `formula` (Mandelbrot form) returns to 0 after p
/// steps, with p. The candidates for p are the steps at which the orbit of `near` comes
/// closer to 0 than ever before (before escape or `limit`), tried from the smallest: for
/// each, Newton's method on z_p(c) = 0 with the real Jacobian of z_p in c, which fails
/// where the Jacobian is singular, the iterate leaves a few `radius` of `near`, or it does
/// not settle within 60 steps.
pub fn periodic_point(formula: Formula, near: &BigC, radius: FloatExp, limit: u32) -> Option<(BigC, u32)> {
    let s = Cycle(formula);
    let mut z = BigC::zero(near.bits);
    let mut closest: Option<FloatExp> = None;
    let mut candidates = Vec::new();
    for n in 1..=limit {
        z = s.apply_big(n - 1, &z).add(near);
        let [x, y] = z.to_fe();
        let m = x * x + y * y;
        if m.to_f64() > ESCAPE2 {
            break;
        }
        if closest.is_none_or(|b| m < b) {
            closest = Some(m);
            candidates.push(n);
        }
    }
    candidates.into_iter().take(12).find_map(|p| newton(s, near, radius, p).map(|c| (c, p)))
}

/// Newton's method for a zero of z_p(c) from `near`, kept within 4 `radius` of it.
fn newton(s: Cycle, near: &BigC, radius: FloatExp, period: u32) -> Option<BigC> {
    let bits = near.bits;
    let mut c = near.clone();
    let small = radius.mul_f64(1e-10);
    for _ in 0..60 {
        let mut z = BigC::zero(bits);
        // J = j 2^e: the Jacobian of z_n in c, J_(n+1) = Df(z_n) J_n + I.
        let (mut j, mut e) = ([[0.0f64; 2]; 2], 0i32);
        for n in 0..period {
            let df = s.jacobian(n, z.to_fe().map(FloatExp::to_f64));
            let one = 2f64.powi(-e);
            j = [
                [df[0][0] * j[0][0] + df[0][1] * j[1][0] + one, df[0][0] * j[0][1] + df[0][1] * j[1][1]],
                [df[1][0] * j[0][0] + df[1][1] * j[1][0], df[1][0] * j[0][1] + df[1][1] * j[1][1] + one],
            ];
            if j.iter().flatten().any(|v| v.abs() > 2f64.powi(100)) {
                j = j.map(|r| r.map(|v| v * 2f64.powi(-100)));
                e += 100;
            }
            z = s.apply_big(n, &z).add(&c);
        }
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        // δ = -J⁻¹ z_p.
        let [fx, fy] = z.to_fe();
        let k = -1.0 / det;
        let dx = (fx.mul_f64(j[1][1]) - fy.mul_f64(j[0][1])).mul_f64(k).ldexp(-e);
        let dy = (fy.mul_f64(j[0][0]) - fx.mul_f64(j[1][0])).mul_f64(k).ldexp(-e);
        c = shifted(&c, [dx, dy]);
        let [ox, oy] = c.sub(near).to_fe();
        if (ox * ox + oy * oy).sqrt() > radius.mul_f64(4.0) {
            return None;
        }
        if (dx * dx + dy * dy).sqrt() < small {
            return Some(c);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::{Kind, Phase};

    fn ship() -> Formula {
        Formula::single(Phase::new(Kind::BurningShip, 2))
    }

    #[test]
    fn a_descent_ends_on_the_boundary() {
        let mut rng = Rng::new(5);
        let f = descend(&mut rng, ship(), None, BigC::zero(64), FloatExp::from(2.5), 6.0, 20_000).expect("found");
        assert!(depth(f.radius) >= 6.0);
        // Some sample of the final view escapes and some does not (within a generous limit).
        let limit = 4 * f.max_n + 1000;
        let step = f.radius.mul_f64(0.25);
        let ns: Vec<Option<u32>> = (0..81)
            .map(|k| {
                let d = [step.mul_f64((k % 9) as f64 - 4.0), step.mul_f64((k / 9) as f64 - 4.0)];
                escape_time(ship(), None, &shifted(&f.center, d), limit, true)
            })
            .collect();
        assert!(ns.iter().any(Option::is_some) && ns.iter().any(Option::is_none), "{ns:?}");
    }

    #[test]
    fn a_real_descent_stays_on_the_axis() {
        let mut rng = Rng::new(9);
        let f = descend_real(&mut rng, ship(), 12.0, 20_000).expect("found");
        assert!(f.center.im.is_zero());
        assert!(depth(f.radius) >= 12.0);
    }

    /// The perturbed grid, with f64 deltas and with FloatExp ones, about its centre and
    /// about a point hundreds of radii away, gives direct big-float iteration's escape
    /// indices on the views descents end at past f64's depth, for a single family, its
    /// Julia form and a hybrid:
    /// every sample of the 9×9 grid whose index is the same at the view's precision and 64
    /// bits above it (the others are ill-conditioned) agrees.
    #[test]
    fn the_perturbed_grid_agrees_with_big_float_iteration() {
        let julia_c = BigC::from_f64(-0.2, -0.5, 128);
        let hybrid = Formula::parse("burning-ship,mandelbrot^3", None).expect("a hybrid");
        for (formula, julia, zoom) in [(ship(), None, 40.0), (ship(), Some(&julia_c), 18.0), (hybrid, None, 14.0)] {
            let mut checked = 0;
            for seed in 1..=6 {
                let mut rng = Rng::new(seed);
                let start = (BigC::zero(64), FloatExp::from(2.5));
                let Some(f) = descend(&mut rng, formula, julia, start.0, start.1, zoom, 5000) else { continue };
                let limit = 2 * f.max_n + 100;
                let step = f.radius.mul_f64(0.25);
                let offsets: Vec<[FloatExp; 2]> =
                    (0..81).map(|k| [step.mul_f64((k % 9) as f64 - 4.0), step.mul_f64((k / 9) as f64 - 4.0)]).collect();
                let at_center = Reference::new(formula, julia, &f.center, f.center.bits, limit);
                let fast = perturbed::<f64>(formula, julia, &at_center.orbit, &offsets, limit);
                let wide = perturbed::<FloatExp>(formula, julia, &at_center.orbit, &offsets, limit);
                // About a point 760 radii away, as a descent reuses an orbit.
                let away = shifted(&f.center, [f.radius.mul_f64(-700.0), f.radius.mul_f64(300.0)]);
                let far = Reference::new(formula, julia, &away, bits_for(depth(f.radius) + 14.0), limit);
                assert!(far.serves(&f.center, f.radius, limit));
                let reused = escape_times_about(formula, julia, &far, &f.center, &offsets, limit);
                let tiny = step.mul_f64(1e-9);
                let direct = |by: FloatExp| -> Vec<Option<u32>> {
                    let at = |o: [FloatExp; 2]| shifted(&f.center, [o[0] + by, o[1] + by]);
                    offsets.iter().map(|&o| escape_time(formula, julia, &at(o), limit, false)).collect()
                };
                let (slow, finer) = (direct(FloatExp::ZERO), direct(tiny));
                if slow != finer {
                    // A chaotic view (neighbours a billionth of a step apart disagree): no
                    // sample in it is a test of the perturbation.
                    continue;
                }
                for (name, got) in [("f64", &fast), ("floatexp", &wide), ("reused", &reused)] {
                    let differ: Vec<usize> = (0..81).filter(|&k| got[k] != slow[k]).collect();
                    assert!(differ.is_empty(), "{formula} seed {seed}, {name}: {differ:?} differ\n{got:?}\n{slow:?}");
                }
                if slow.iter().any(Option::is_some) && slow.iter().any(Option::is_none) {
                    checked += 1;
                    if checked == 2 {
                        break;
                    }
                }
            }
            assert!(checked > 0, "{formula}: no descent ended on a view with both kinds of sample");
        }
    }

    /// The Burning Ship's period-3 miniship on the real axis near c = -1.7549 (the real
    /// slice is z² + c's: c³ + 2c² + c + 1 = 0 gives -1.75487766624669...).
    #[test]
    fn newton_finds_the_period_3_miniship() {
        let near = BigC::from_f64(-1.755, 1e-4, 128);
        let (c, p) = periodic_point(ship(), &near, FloatExp::from(0.01), 1000).expect("converges");
        assert_eq!(p, 3);
        let [x, y] = c.to_fe().map(FloatExp::to_f64);
        assert!((x + 1.754_877_666_246_69).abs() < 1e-12 && y.abs() < 1e-12, "{x} {y}");
    }
}
