//! The quadratic models of a batch of samples, worked out together
//! (`Perturbation::sample_models`): what [`model::fixed_point`] and
//! [`model::settled_cycle`] say of each sample, at a fraction of their cost one sample at a
//! time.
//!
//! Interior detection asks every sample's model before the disks and the iteration, so
//! the models are paid for on the exterior too, where they only tell a sample to leave
//! detection. One sample at a time they cost the 1e102 minibrot view about a tenth of its
//! time (43 ms of 338 on one thread): a dependent chain of multiplies per orbit, a
//! mispredicted branch where it escapes, Newton's searches from 0 for every sample in a
//! bulb, and 8192 iterations for each that never settles. Here:
//!
//! - **The cardioid in closed form, in vectors.** [`cardioid`] computes every sample's
//!   attracting fixed point ([`model::fixed_point_of`], branch-free) in a loop under the
//!   level's features; those samples need no orbit.
//! - **Orbits in lanes.** [`follow`] iterates [`LANES`] parameters at once, plain
//!   arithmetic on arrays under the level's features (pulp's dispatch, [`SimdLevel`]),
//!   which the compiler turns into vectors; a lane whose orbit escapes, or comes back
//!   within [`SETTLE2`] of a point it passed (Brent's test, with anchors at powers of two),
//!   or reaches the cap, takes the next parameter. The same IEEE operations in the same
//!   order on every level, so every level says the same. A first pass of
//!   [`FIRST_ITERATIONS`] decides most samples outside the minibrot; a second, as long as
//!   the model's own search, the ones left.
//! - **Bulbs from their neighbours.** Samples of a batch come row by row, so a sample's left
//!   neighbour, or the one above it, usually lies in the same component of the model.
//!   Where the neighbour's model has a cycle of period k >= 2, Newton's method starts from
//!   its cycle point ([`model::attractor_from`], a few steps). A settled orbit's point
//!   starts it too ([`resolve`]). A quadratic map has at most one attracting cycle, so the
//!   cycle found is the one the sample's own search would find.
//!
//! What is left (a settled orbit not near a cycle, as in a parabolic gate) goes through
//! [`model::settled_cycle`] as before; an orbit neither escaped nor settled after the
//! second pass is left unsettled. A model only decides where detection spends its time,
//! never a sample's result, so a verdict that differs from the sample's own search (a cycle
//! found where that search gave up) changes no pixel.

use super::model::{self, Model};
use crate::num::real::norm2;
use crate::simd_level::SimdLevel;

/// Parameters followed together in [`follow`]: two AVX-512 vectors, whose dependency
/// chains overlap.
const LANES: usize = 16;
/// Iterations of the first pass: most samples outside the minibrot escape within it, and
/// most inside it are decided without lanes (closed form, or a neighbour's cycle).
const FIRST_ITERATIONS: u32 = 128;
/// Iterations of the second pass, for the samples the first left undecided: as many as
/// [`model::settled_cycle`] would follow.
const LONG_ITERATIONS: u32 = model::ITERATIONS;
/// Newton's steps from a neighbour's cycle point ([`model::attractor_from`]): it converges
/// in three or four where the neighbour lies in the same component; more would be spent
/// where it does not.
const NEIGHBOUR_STEPS: u32 = 6;
/// Newton's steps from a point an orbit settled near ([`resolve`]).
const SETTLED_STEPS: u32 = 12;
/// A lane's orbit has settled once it comes back within this squared distance of its
/// anchor (`follow`): close enough to the cycle for Newton's method to converge from it
/// in a few steps.
const SETTLE2: f64 = 1e-8;
/// [`resolve`] takes the first return of a settled point within this squared distance as
/// the cycle's period (a multiple of it at worst, which Newton's method reduces).
const RETURN2: f64 = 1e-6;
/// Steps between looks at the lanes in [`stream`]: a decided lane runs on harmlessly (to
/// infinity or NaN) until the next look, its verdict kept.
const LOOK: u32 = 8;
/// A lane holding no parameter.
const EMPTY: usize = usize::MAX;

/// What became of the orbit of 0 under z -> z^2 + c in [`follow`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::orbit) enum Fate {
    /// It left |z| <= 2.
    Escaped,
    /// It came back near an earlier point (Brent's test, anchors at powers of two): it has
    /// settled on a cycle near this point, or lingers where it moves slowly.
    Settled([f64; 2]),
    /// Neither within the requested iterations (nor ever, for a c that is not a number):
    /// where the orbit was then.
    Open([f64; 2]),
}

/// For each parameter c of `cs` at the indices `which`, what the orbit of 0 under
/// z -> z^2 + c does within `cap` iterations (a multiple of [`LOOK`]), computed in lanes
/// under `level`'s features and written into `out`. A lane whose parameter is decided
/// takes the next one, so no lane waits on a slow neighbour.
pub(in crate::orbit) fn follow(cs: &[[f64; 2]], which: &[usize], cap: u32, level: SimdLevel, out: &mut [Fate]) {
    level.arch().dispatch(Stream { cs, which, cap, out });
}

/// [`stream`]'s arguments, for pulp's dispatch: its `with_simd` is inlined into the
/// function that each instruction set's features are enabled for (a closure was not, and
/// ran in baseline SSE2 on every level).
struct Stream<'a> {
    cs: &'a [[f64; 2]],
    which: &'a [usize],
    cap: u32,
    out: &'a mut [Fate],
}

impl pulp::WithSimd for Stream<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        stream(self.cs, self.which, self.cap, self.out);
    }
}

/// Each parameter's attracting fixed point where it has one ([`model::fixed_point`]: the
/// main cardioid), in a loop under `level`'s features: those parameters need no orbit.
fn cardioid(cs: &[[f64; 2]], level: SimdLevel) -> Vec<Option<[f64; 2]>> {
    let (mut z, mut mult2) = (vec![[0.0; 2]; cs.len()], vec![0.0; cs.len()]);
    level.arch().dispatch(Cardioid { cs, z: &mut z, mult2: &mut mult2 });
    // Not a number compares false: refused.
    z.into_iter().zip(mult2).map(|(z, m)| (m < 1.0).then_some(z)).collect()
}

/// [`cardioid`]'s arguments, for pulp's dispatch (as [`Stream`]).
struct Cardioid<'a> {
    cs: &'a [[f64; 2]],
    z: &'a mut [[f64; 2]],
    mult2: &'a mut [f64],
}

impl pulp::WithSimd for Cardioid<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        for ((c, z), m) in self.cs.iter().zip(self.z.iter_mut()).zip(self.mult2.iter_mut()) {
            (*z, *m) = model::fixed_point_of(*c);
        }
    }
}

/// One lane's orbit, a field per quantity and an array element per lane (the form the
/// compiler vectorises).
struct Lanes {
    /// The parameter.
    c: [[f64; LANES]; 2],
    /// z_n.
    z: [[f64; LANES]; 2],
    /// x^2, y^2 and x y of z_n, as [`model::settled_cycle`] takes them: they serve the
    /// escape test and the next step.
    sq: [[f64; LANES]; 3],
    /// z at the latest power of two (Brent's anchor).
    anchor: [[f64; LANES]; 2],
    /// The largest |z|^2 since the lane took its parameter (escaped where above 4; f64 and
    /// `max` rather than a flag, which the vectors would convert at every step).
    top: [f64; LANES],
    /// The least squared distance from the anchor since the last look (settled where
    /// below [`SETTLE2`]).
    least: [f64; LANES],
    /// The index into `cs` each lane holds, or [`EMPTY`].
    held: [usize; LANES],
    /// n.
    n: [u32; LANES],
}

/// [`follow`]'s loop.
#[inline(always)]
fn stream(cs: &[[f64; 2]], which: &[usize], cap: u32, out: &mut [Fate]) {
    let zero = [0.0; LANES];
    let mut l = Lanes {
        c: [zero; 2],
        z: [zero; 2],
        sq: [zero; 3],
        anchor: [zero; 2],
        top: zero,
        least: [f64::INFINITY; LANES],
        held: [EMPTY; LANES],
        n: [0; LANES],
    };
    let mut next = which.iter();
    loop {
        let mut busy = false;
        for i in 0..LANES {
            if l.held[i] != EMPTY {
                let fate = if l.top[i] > 4.0 {
                    Some(Fate::Escaped)
                } else if l.least[i] < SETTLE2 {
                    Some(Fate::Settled([l.z[0][i], l.z[1][i]]))
                } else {
                    (l.n[i] >= cap).then_some(Fate::Open([l.z[0][i], l.z[1][i]]))
                };
                match fate {
                    Some(f) => {
                        out[l.held[i]] = f;
                        l.held[i] = EMPTY;
                    }
                    None if l.n[i].is_power_of_two() => (l.anchor[0][i], l.anchor[1][i]) = (l.z[0][i], l.z[1][i]),
                    None => {}
                }
            }
            l.least[i] = f64::INFINITY;
            if l.held[i] == EMPTY
                && let Some(&k) = next.next()
            {
                (l.held[i], l.n[i], l.top[i]) = (k, 0, 0.0);
                [l.c[0][i], l.c[1][i]] = cs[k];
                (l.z[0][i], l.z[1][i], l.anchor[0][i], l.anchor[1][i]) = (0.0, 0.0, f64::NAN, f64::NAN);
                (l.sq[0][i], l.sq[1][i], l.sq[2][i]) = (0.0, 0.0, 0.0);
            }
            busy |= l.held[i] != EMPTY;
        }
        if !busy {
            return;
        }
        for _ in 0..LOOK {
            for i in 0..LANES {
                let (x, y) = (l.sq[0][i] - l.sq[1][i] + l.c[0][i], l.sq[2][i] + l.sq[2][i] + l.c[1][i]);
                (l.z[0][i], l.z[1][i]) = (x, y);
                (l.sq[0][i], l.sq[1][i], l.sq[2][i]) = (x * x, y * y, x * y);
                l.top[i] = l.top[i].max(l.sq[0][i] + l.sq[1][i]);
                let (dx, dy) = (x - l.anchor[0][i], y - l.anchor[1][i]);
                l.least[i] = l.least[i].min(dx * dx + dy * dy);
            }
        }
        for n in l.n.iter_mut() {
            *n += LOOK;
        }
    }
}

/// The models of parameters `cs` in the order a batch's samples come, row by row in rows
/// of `width`: the verdicts of [`model::fixed_point`] and [`model::settled_cycle`] (module
/// docs).
pub(in crate::orbit) fn models(cs: &[[f64; 2]], width: usize, level: SimdLevel) -> Vec<Model> {
    let fixed = cardioid(cs, level);
    let all: Vec<usize> = (0..cs.len()).filter(|&k| fixed[k].is_none()).collect();
    let mut fates = vec![Fate::Escaped; cs.len()];
    follow(cs, &all, FIRST_ITERATIONS, level, &mut fates);
    let mut out = vec![Model::Unsettled; cs.len()];
    let mut pending = Vec::new();
    for (k, &c) in cs.iter().enumerate() {
        let found = match fates[k] {
            _ if let Some(z) = fixed[k] => Some(Model::Cycle(z, 1)),
            // As the model's own search says of a parameter that is not a number.
            _ if !(c[0].is_finite() && c[1].is_finite()) => Some(Model::Escapes),
            Fate::Escaped => Some(Model::Escapes),
            fate => from_neighbours(c, k, width, &out)
                .or_else(|| if let Fate::Settled(z) = fate { resolve(c, z) } else { None }),
        };
        match found {
            Some(m) => out[k] = m,
            None => pending.push(k),
        }
    }
    // The samples left: most outside the minibrot, escaping later, and the first of each
    // bulb's samples; their orbits in lanes again, as long as the model's own search would
    // follow them.
    follow(cs, &pending, LONG_ITERATIONS, level, &mut fates);
    for k in pending {
        let c = cs[k];
        // An orbit still open after as many iterations as the model's own search follows
        // is left unsettled where it is not near a cycle then: that search would find
        // one rarely, after all its iterations again.
        out[k] = match fates[k] {
            Fate::Escaped => Model::Escapes,
            Fate::Settled(z) => {
                from_neighbours(c, k, width, &out).or_else(|| resolve(c, z)).unwrap_or_else(|| model::settled_cycle(c))
            }
            Fate::Open(z) => from_neighbours(c, k, width, &out).or_else(|| resolve(c, z)).unwrap_or(Model::Unsettled),
        };
    }
    out
}

/// The cycle at `c` found by Newton's method from the cycle of the sample's left
/// neighbour or, failing that, of the one above it (index `k` in rows of `width`; their
/// models in `out`), where either lies in a bulb.
fn from_neighbours(c: [f64; 2], k: usize, width: usize, out: &[Model]) -> Option<Model> {
    let left = (!k.is_multiple_of(width.max(1))).then(|| k - 1);
    let above = k.checked_sub(width.max(1));
    [left, above].into_iter().flatten().find_map(|j| match out[j] {
        Model::Cycle(w, n) if n >= 2 => {
            model::attractor_from(c, n, w, NEIGHBOUR_STEPS).map(|(w, n)| Model::Cycle(w, n))
        }
        _ => None,
    })
}

/// The attracting cycle at `c` near `z`, a point its orbit settled near ([`Fate::Settled`]):
/// the period is the first return of z within [`RETURN2`] (at most
/// [`model::MAX_PERIODS`]), and Newton's method from z finds the cycle.
fn resolve(c: [f64; 2], z: [f64; 2]) -> Option<Model> {
    let mut y = z;
    let period = (1..=model::MAX_PERIODS).find(|_| {
        y = [y[0] * y[0] - y[1] * y[1] + c[0], 2.0 * y[0] * y[1] + c[1]];
        norm2([y[0] - z[0], y[1] - z[1]]) < RETURN2
    })?;
    let (w, k) = model::attractor_from(c, period, z, SETTLED_STEPS)?;
    Some(Model::Cycle(w, k))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parameters over the whole Mandelbrot set and around it, row by row as a batch's
    /// samples come, some not numbers.
    fn grid() -> Vec<[f64; 2]> {
        let mut cs: Vec<[f64; 2]> = (0..150)
            .flat_map(|j| (0..200).map(move |i| [-2.2 + 2.8 * i as f64 / 200.0, -1.2 + 2.4 * j as f64 / 150.0]))
            .collect();
        cs.extend([[f64::NAN, 0.0], [0.0, f64::INFINITY], [1e300, -1e300]]);
        cs
    }

    /// The lanes say what each orbit does, within a short and a long cap, and the same on
    /// every level this CPU has: an orbit they call escaped escapes within the cap, one
    /// they call open does not, and one they call settled passes exactly through the point
    /// they give before it escapes (if it does).
    #[test]
    fn follow_agrees_with_each_orbit_on_every_level() {
        let cs = grid();
        for cap in [FIRST_ITERATIONS, LONG_ITERATIONS] {
            // Two of every three parameters, so that the lanes also skip some.
            let which: Vec<usize> = (0..cs.len()).filter(|k| k % 3 != 1).collect();
            let mut scalar = vec![Fate::Escaped; cs.len()];
            follow(&cs, &which, cap, SimdLevel::Scalar, &mut scalar);
            let mut counts = [0; 3];
            for &k in &which {
                let c = cs[k];
                let (mut z, mut escaped_at, mut passes) = ([0.0f64, 0.0], None, false);
                for n in 1..=cap {
                    z = [z[0] * z[0] - z[1] * z[1] + c[0], 2.0 * z[0] * z[1] + c[1]];
                    passes |= Fate::Settled(z) == scalar[k] && escaped_at.is_none();
                    if escaped_at.is_none() && z[0] * z[0] + z[1] * z[1] > 4.0 {
                        escaped_at = Some(n);
                    }
                }
                match scalar[k] {
                    Fate::Escaped => assert!(escaped_at.is_some(), "{c:?} within {cap}"),
                    Fate::Open(_) => assert!(escaped_at.is_none(), "{c:?} within {cap}"),
                    Fate::Settled(_) => assert!(passes, "{c:?} within {cap}"),
                }
                counts[match scalar[k] {
                    Fate::Escaped => 0,
                    Fate::Settled(_) => 1,
                    Fate::Open(_) => 2,
                }] += 1;
            }
            // (Open within the long cap: the near-neutral and the parameters not numbers.)
            let open = if cap == FIRST_ITERATIONS { 200 } else { 3 };
            assert!(counts[0] > 1000 && counts[1] > 1000 && counts[2] >= open, "{counts:?} within {cap}");
            assert!((0..cs.len()).filter(|k| k % 3 == 1).all(|k| scalar[k] == Fate::Escaped));
            for level in SimdLevel::usable() {
                let mut v = vec![Fate::Escaped; cs.len()];
                follow(&cs, &which, cap, level, &mut v);
                // Bit for bit (the points' shortest round-trip decimals; NaN as NaN).
                let first = (0..cs.len()).find(|&k| format!("{:?}", v[k]) != format!("{:?}", scalar[k]));
                assert_eq!(first, None, "{level} differs from scalar within {cap}");
            }
        }
    }

    /// A batch's models say what each sample's own does: escape where its orbit escapes, a
    /// cycle of the same period where its own search finds one (from a neighbour's cycle
    /// or not), and none where it neither escapes nor settles (or its cycle is all but
    /// neutral); the same on every level.
    #[test]
    fn a_batchs_models_are_each_samples_own() {
        let cs = grid();
        let batch = models(&cs, 200, SimdLevel::Scalar);
        let (mut cycles, mut bulbs, mut near_neutral) = (0, 0, 0);
        for (c, m) in cs.iter().zip(&batch) {
            let own = model::fixed_point(*c).map_or_else(|| model::settled_cycle(*c), |z| Model::Cycle(z, 1));
            match (own, *m) {
                // The neighbour's start may find a cycle too near neutral for the sample's
                // own search to settle on within its iterations.
                (Model::Cycle(_, _) | Model::Unsettled, Model::Cycle(w, b)) => {
                    if let Model::Cycle(_, a) = own {
                        assert_eq!(a, b, "{c:?}");
                    }
                    // w lies on an attracting cycle of period b.
                    let mut y = w;
                    for _ in 0..b {
                        y = [y[0] * y[0] - y[1] * y[1] + c[0], 2.0 * y[0] * y[1] + c[1]];
                    }
                    assert!((y[0] - w[0]).hypot(y[1] - w[1]) < 1e-9, "{c:?}");
                    let mu = model::multiplier(*c, w, b);
                    assert!(mu[0].hypot(mu[1]) < 1.0, "{c:?}");
                    cycles += 1;
                    bulbs += usize::from(b > 1);
                }
                // An orbit that has not settled within the second pass is left unsettled:
                // only where its cycle is all but neutral.
                (Model::Cycle(z, a), Model::Unsettled) => {
                    let mu = model::multiplier(*c, z, a);
                    assert!(mu[0].hypot(mu[1]) > 0.99, "{c:?}: {mu:?}");
                    near_neutral += 1;
                }
                (own, m) => assert_eq!(own, m, "{c:?}"),
            }
        }
        assert!(cycles > 2000 && bulbs > 500, "{cycles} cycles, {bulbs} in bulbs");
        assert!(near_neutral < 20, "{near_neutral} cycles left unsettled");
        for level in SimdLevel::usable() {
            let other = models(&cs, 200, level);
            let first = (0..cs.len()).find(|&k| format!("{:?}", other[k]) != format!("{:?}", batch[k]));
            assert_eq!(first, None, "{level} differs from scalar");
        }
    }
}
