//! The direct f64 kernel of every formula but z² + c (single families and hybrids) in vector
//! lanes: `L` orbits in flight as `[f64; L]` arrays ([`Num`]), compiled per family and per
//! instruction set (pulp's dispatch enables AVX2 or AVX-512 and the lane loops become
//! vector instructions), a finished lane refilled with the next sample at once.
//!
//! Every lane runs the operations of [`super::generic::orbit`] in the same order (the map's
//! [`Map::apply_n`] and [`Map::jacobian_n`] are the scalar map's code over lanes, the
//! escape test and the Jacobian's products likewise), so N, z_n and the derivative are the
//! scalar kernel's bits on every level; a test checks it on each level this CPU has. The
//! per-step bookkeeping (escape, iteration limit, Brent's cycle check) is one vector test;
//! only a lane that ends takes a scalar path. Orbit traps run in the scalar kernel.
//!
//! A hybrid's lanes run in step: every lane's iteration index has the same phase (index mod
//! the cycle's length), so a pass applies one family to all of them. A lane that ends waits,
//! idle, until the pass's phase is a sample's first (at most the cycle's length less one
//! pass) before it takes the next sample. Each phase's pass is its family's compiled code
//! in a function of its own, called through a table built before the loop (`Phases`):
//! one indirect call a pass, not every family's code in one loop (the deep engine's lanes
//! tried that, and spilled their state around it: docs/performance.md).

use std::sync::atomic::{AtomicBool, Ordering};

use pulp::{Simd, WithSimd};

use super::OrbitParams;
use crate::cancel::Cancelled;
use crate::formula::end::Orbit;
use crate::formula::map::{Map, Mat2, Num, Ops, gradient_dz};
use crate::formula::phase::MAX_PHASES;
use crate::formula::{Family, Formula, Phase};
use crate::simd_level::LaneJob;

/// Steps between two looks at the cancel flag.
const CANCEL_EVERY: u64 = 1 << 16;

/// Iterates every point with family `M`, writing one [`Orbit`] per point; returns the
/// iterations performed.
pub fn iterate<M: Map>(
    map: M,
    params: &OrbitParams,
    points: &[[f64; 2]],
    out: &mut [Orbit],
    cancel: &AtomicBool,
) -> Result<u64, Cancelled> {
    assert_eq!(points.len(), out.len());
    // Two vectors' worth of lanes, interleaved to hide the latency of each step; one lane
    // at the scalar level (or a level this CPU lacks).
    match params.simd.run_lanes(Job::<M> { params, points, out, cancel, map }) {
        Ok(done) => done,
        Err(Job { params, points, out, cancel, map }) => match params.derivative {
            false => run::<M, 1, false>(map, params, points, out, cancel),
            true => run::<M, 1, true>(map, params, points, out, cancel),
        },
    }
}

/// One call of the kernel, run by pulp under the level's target features (`run` is
/// inlined into pulp's feature-enabled entry, and everything below it into that), at the
/// level's one width.
struct Job<'a, M: Map> {
    params: &'a OrbitParams,
    points: &'a [[f64; 2]],
    out: &'a mut [Orbit],
    cancel: &'a AtomicBool,
    map: M,
}

impl<M: Map> LaneJob for Job<'_, M> {
    type Output = Result<u64, Cancelled>;

    #[inline(always)]
    fn run<S: Simd, const L: usize>(self, _: S) -> Self::Output {
        let Job { params, points, out, cancel, map } = self;
        match params.derivative {
            false => run::<M, L, false>(map, params, points, out, cancel),
            true => run::<M, L, true>(map, params, points, out, cancel),
        }
    }
}

/// Iterates every point with the hybrid `formula` (two phases or more) in vector lanes,
/// writing one [`Orbit`] per point; returns the iterations performed. The scalar level has
/// no lanes to fill: there [`super::generic::iterate`] runs the hybrid.
pub fn iterate_cycle(
    params: &OrbitParams,
    formula: Formula,
    points: &[[f64; 2]],
    out: &mut [Orbit],
    cancel: &AtomicBool,
) -> Result<u64, Cancelled> {
    assert_eq!(points.len(), out.len());
    assert!(formula.phases().len() > 1, "a single family runs `iterate`");
    let job = CycleJob { params, formula, points, out, cancel };
    match params.simd.run_lanes(job) {
        Ok(done) => done,
        Err(CycleJob { params, formula, points, out, cancel }) => {
            crate::with_stepper!(formula, s => super::generic::iterate(s, params, &[], points, out, &mut [], cancel))
        }
    }
}

/// One call of the hybrid kernel under a level's target features.
struct CycleJob<'a> {
    params: &'a OrbitParams,
    formula: Formula,
    points: &'a [[f64; 2]],
    out: &'a mut [Orbit],
    cancel: &'a AtomicBool,
}

impl LaneJob for CycleJob<'_> {
    type Output = Result<u64, Cancelled>;

    #[inline(always)]
    fn run<S: Simd, const L: usize>(self, simd: S) -> Self::Output {
        match self.params.derivative {
            false => self.cycle::<S, L, false>(simd),
            true => self.cycle::<S, L, true>(simd),
        }
    }
}

impl CycleJob<'_> {
    #[inline(always)]
    fn cycle<S: Simd, const L: usize, const DE: bool>(self, simd: S) -> Result<u64, Cancelled> {
        let CycleJob { params, formula, points, out, cancel } = self;
        // The table of passes, one per phase, chosen once.
        let mut steps = [pass::<S, Ops<0, 2, 0, 0>, L, DE> as PassFn<S, L>; MAX_PHASES];
        for (step, &phase) in steps.iter_mut().zip(formula.phases()) {
            *step = crate::with_map!(phase, M => pass::<S, M, L, DE> as PassFn<S, L>,
                unreachable!("a validated formula has compiled code"));
        }
        let phases = Phases { simd, steps, formula, len: formula.phases().len() as u32 };
        run_cycle::<S, L, DE>(phases, params, points, out, cancel)
    }
}

/// A pass of one phase over the lanes: z and the Jacobian stepped by that phase's map.
type PassFn<S, const L: usize> = fn(S, &Phase, &mut Lanes<L>, f64);

/// One phase's pass, out of line (one function per family in the table), its body compiled
/// under the level's target features by pulp's `vectorize`.
#[inline(never)]
fn pass<S: Simd, M: Map, const L: usize, const DE: bool>(simd: S, phase: &Phase, s: &mut Lanes<L>, add: f64) {
    struct Op<'a, M, const L: usize, const DE: bool>(&'a mut Lanes<L>, f64, M);
    impl<M: Map, const L: usize, const DE: bool> WithSimd for Op<'_, M, L, DE> {
        type Output = ();
        #[inline(always)]
        fn with_simd<S: Simd>(self, _: S) {
            step_lanes::<M, L, DE>(&self.2, self.0, self.1);
        }
    }
    simd.vectorize(Op::<M, L, DE>(s, add, M::of(phase)));
}

/// A hybrid: the pass of each phase, by phase.
struct Phases<S, const L: usize> {
    simd: S,
    steps: [PassFn<S, L>; MAX_PHASES],
    formula: Formula,
    len: u32,
}

impl<S: Simd, const L: usize> Phases<S, L> {
    /// Steps every lane by the map of phase `g`.
    #[inline(always)]
    fn step(&self, g: u32, s: &mut Lanes<L>, add: f64) {
        (self.steps[g as usize])(self.simd, &self.formula.phases()[g as usize], s, add);
    }
}

/// One step of every lane by family `M`: the Jacobian (with `DE`), then z ← f(z) + c.
#[inline(always)]
fn step_lanes<M: Map, const L: usize, const DE: bool>(map: &M, s: &mut Lanes<L>, add: f64) {
    if DE {
        let z = [s.x, s.y];
        let a = map.jacobian_n(z);
        let b = s.j;
        // The scalar kernel's `mat_mul`, then the identity added (Mandelbrot form).
        let m00 = a[0][0].mul(b[0][0]).add(a[0][1].mul(b[1][0]));
        let m01 = a[0][0].mul(b[0][1]).add(a[0][1].mul(b[1][1]));
        let m10 = a[1][0].mul(b[0][0]).add(a[1][1].mul(b[1][0]));
        let m11 = a[1][0].mul(b[0][1]).add(a[1][1].mul(b[1][1]));
        if add != 0.0 {
            s.j = [[m00.add(<[f64; L]>::splat(add)), m01], [m10, m11.add(<[f64; L]>::splat(add))]];
        } else {
            s.j = [[m00, m01], [m10, m11]];
        }
    }
    let f = map.apply_n([s.x, s.y]);
    s.x = f[0].add(s.cx);
    s.y = f[1].add(s.cy);
}

/// The lanes' state.
struct Lanes<const L: usize> {
    x: [f64; L],
    y: [f64; L],
    cx: [f64; L],
    cy: [f64; L],
    /// The Jacobian in the sample's parameter, by entry.
    j: [[[f64; L]; 2]; 2],
    /// Iteration index of z.
    n: [u32; L],
    /// The iteration limit (u32::MAX in an idle lane, which then never ends).
    limit: [u32; L],
    /// Brent's saved value and when it was saved; the next index to save at.
    sx: [f64; L],
    sy: [f64; L],
    save_at: [u32; L],
    /// The phase at the save (a hybrid's orbit repeats only where its phase does too).
    sg: [u32; L],
    /// The sample in each lane (usize::MAX: idle).
    pixel: [usize; L],
}

const IDLE: usize = usize::MAX;

/// What every sample's orbit starts from: its first index, the Julia parameter (None: c is
/// the sample), what the Jacobian's step adds, and the iteration limit.
struct Start {
    n0: u32,
    julia_c: Option<[f64; 2]>,
    add: f64,
    max_iter: u32,
}

impl Start {
    fn of(params: &OrbitParams) -> Start {
        let (n0, julia_c, add) = match params.family {
            Family::Mandelbrot => (1u32, None, 1.0),
            Family::Julia { c } => (0u32, Some(c), 0.0),
        };
        Start { n0, julia_c, add, max_iter: params.max_iter }
    }
}

impl<const L: usize> Lanes<L> {
    /// Every lane idle.
    #[inline(always)]
    fn new() -> Self {
        Lanes {
            x: [0.0; L],
            y: [0.0; L],
            cx: [0.0; L],
            cy: [0.0; L],
            j: [[[1.0; L], [0.0; L]], [[0.0; L], [1.0; L]]],
            n: [0; L],
            limit: [u32::MAX; L],
            sx: [f64::NAN; L],
            sy: [f64::NAN; L],
            save_at: [u32::MAX; L],
            sg: [0; L],
            pixel: [IDLE; L],
        }
    }

    /// Loads the sample `points[*next]` into lane `k` and moves `next` on; with none left,
    /// idles the lane and returns false.
    #[inline(always)]
    fn load(&mut self, k: usize, points: &[[f64; 2]], next: &mut usize, st: &Start) -> bool {
        if *next >= points.len() {
            self.pixel[k] = IDLE;
            // An idle lane iterates a harmless value that never ends anything.
            self.x[k] = 0.0;
            self.y[k] = 0.0;
            self.cx[k] = 0.0;
            self.cy[k] = 0.0;
            self.n[k] = 0;
            self.limit[k] = u32::MAX;
            self.save_at[k] = u32::MAX;
            return false;
        }
        let p = points[*next];
        self.pixel[k] = *next;
        *next += 1;
        let c = st.julia_c.unwrap_or(p);
        (self.x[k], self.y[k], self.cx[k], self.cy[k]) = (p[0], p[1], c[0], c[1]);
        self.j[0][0][k] = 1.0;
        self.j[0][1][k] = 0.0;
        self.j[1][0][k] = 0.0;
        self.j[1][1][k] = 1.0;
        self.n[k] = st.n0;
        self.limit[k] = st.max_iter;
        self.sx[k] = f64::NAN;
        self.sy[k] = f64::NAN;
        self.save_at[k] = st.n0 + 1;
        true
    }

    /// The orbit lane `k` ends with: escaped (with the derivative where `DE`), or interior.
    #[inline(always)]
    fn end<const DE: bool>(&self, k: usize, escaped: bool) -> Orbit {
        if !escaped {
            return Orbit::interior();
        }
        let z = [self.x[k], self.y[k]];
        let dz = if DE {
            let j: Mat2 = [[self.j[0][0][k], self.j[0][1][k]], [self.j[1][0][k], self.j[1][1][k]]];
            gradient_dz(z, j)
        } else {
            [0.0; 2]
        };
        Orbit { n: self.n[k], z, dz }
    }
}

/// [`run`] for a hybrid: the same loop, its lanes in step (see the module doc). A loop of
/// its own, so that the phases' bookkeeping (the pass's phase, the phase of each save, lanes
/// waiting for a first phase) is not in the single families' loop at all; the two share
/// the lanes' loads, ends and steps ([`Lanes`], [`step_lanes`]).
#[inline(always)]
fn run_cycle<S: Simd, const L: usize, const DE: bool>(
    t: Phases<S, L>,
    params: &OrbitParams,
    points: &[[f64; 2]],
    out: &mut [Orbit],
    cancel: &AtomicBool,
) -> Result<u64, Cancelled> {
    let st = Start::of(params);
    let (n0, add) = (st.n0, st.add);
    let r2 = params.escape_radius * params.escape_radius;
    let mut s = Lanes::<L>::new();
    // The cycle's length, the phase of every live lane's index, and that of a sample's
    // first index (a lane takes a sample only when the two agree).
    let period = t.len;
    let first = n0 % period;
    let mut g = first;
    let mut next = 0usize;
    let mut active = 0usize;
    let mut iterations = 0u64;
    let load = |s: &mut Lanes<L>, k: usize, next: &mut usize| s.load(k, points, next, &st);
    for k in 0..L {
        active += load(&mut s, k, &mut next) as usize;
    }
    let mut steps = 0u64;
    // (Every lane may be idle, waiting for the first phase, while samples remain.)
    while active > 0 || next < points.len() {
        if g == first && active < L && next < points.len() {
            // Idle lanes take samples at their first phase.
            for k in 0..L {
                if s.pixel[k] == IDLE {
                    active += load(&mut s, k, &mut next) as usize;
                }
            }
        }
        // The end tests of z_n, one vector test: escaped, at the limit, or repeating a
        // value saved earlier (at the same phase).
        let rr = s.x.mul_add(s.x, s.y.mul(s.y));
        let mut any = false;
        for k in 0..L {
            let repeat = (s.x[k] == s.sx[k]) & (s.y[k] == s.sy[k]) & (s.sg[k] == g);
            any |= (rr[k] > r2) | (s.n[k] >= s.limit[k]) | repeat;
        }
        if any {
            let mut ended = 0;
            for k in 0..L {
                let repeat = s.x[k] == s.sx[k] && s.y[k] == s.sy[k] && s.sg[k] == g;
                let escaped = rr[k] > r2;
                if !(escaped || s.n[k] >= s.limit[k] || repeat) {
                    continue;
                }
                out[s.pixel[k]] = s.end::<DE>(k, escaped);
                iterations += (s.n[k] - n0) as u64;
                active -= 1;
                ended += 1;
                if g == first {
                    active += load(&mut s, k, &mut next) as usize;
                } else {
                    // Idle (loading past the last sample idles a lane) until the passes
                    // reach a sample's first phase.
                    load(&mut s, k, &mut points.len());
                }
            }
            if ended > 0 {
                // Reloaded lanes are tested before they step (a sample may start escaped).
                continue;
            }
        }
        // Brent's saves at power-of-two ages (each lane's own schedule), after the test.
        // (Selects, not branches: the loop stays a few vector instructions.)
        for k in 0..L {
            let save = s.n[k] == s.save_at[k];
            s.sx[k] = if save { s.x[k] } else { s.sx[k] };
            s.sy[k] = if save { s.y[k] } else { s.sy[k] };
            let later = s.save_at[k].saturating_mul(2).saturating_sub(n0);
            s.save_at[k] = if save { later } else { s.save_at[k] };
            s.sg[k] = if save { g } else { s.sg[k] };
        }
        t.step(g, &mut s, add);
        g = if g + 1 == period { 0 } else { g + 1 };
        for k in 0..L {
            s.n[k] = s.n[k].wrapping_add(1);
        }
        steps += 1;
        if steps.is_multiple_of(CANCEL_EVERY) && cancel.load(Ordering::Relaxed) {
            return Err(Cancelled);
        }
    }
    Ok(iterations)
}

#[inline(always)]
fn run<M: Map, const L: usize, const DE: bool>(
    map: M,
    params: &OrbitParams,
    points: &[[f64; 2]],
    out: &mut [Orbit],
    cancel: &AtomicBool,
) -> Result<u64, Cancelled> {
    let st = Start::of(params);
    let (n0, add) = (st.n0, st.add);
    let r2 = params.escape_radius * params.escape_radius;
    let mut s = Lanes::<L>::new();
    let mut next = 0usize;
    let mut active = 0usize;
    let mut iterations = 0u64;
    let load = |s: &mut Lanes<L>, k: usize, next: &mut usize| s.load(k, points, next, &st);
    for k in 0..L {
        active += load(&mut s, k, &mut next) as usize;
    }
    let mut steps = 0u64;
    while active > 0 {
        // The end tests of z_n, one vector test: escaped, at the limit, or repeating a
        // value saved earlier.
        let rr = s.x.mul_add(s.x, s.y.mul(s.y));
        let mut any = false;
        for k in 0..L {
            let repeat = (s.x[k] == s.sx[k]) & (s.y[k] == s.sy[k]);
            any |= (rr[k] > r2) | (s.n[k] >= s.limit[k]) | repeat;
        }
        if any {
            let mut ended = 0;
            for k in 0..L {
                let repeat = s.x[k] == s.sx[k] && s.y[k] == s.sy[k];
                let escaped = rr[k] > r2;
                if !(escaped || s.n[k] >= s.limit[k] || repeat) {
                    continue;
                }
                out[s.pixel[k]] = s.end::<DE>(k, escaped);
                iterations += (s.n[k] - n0) as u64;
                active -= 1;
                ended += 1;
                active += load(&mut s, k, &mut next) as usize;
            }
            if ended > 0 {
                // Reloaded lanes are tested before they step (a sample may start escaped).
                continue;
            }
        }
        // Brent's saves at power-of-two ages (each lane's own schedule), after the test.
        // (Selects, not branches: the loop stays a few vector instructions.)
        for k in 0..L {
            let save = s.n[k] == s.save_at[k];
            s.sx[k] = if save { s.x[k] } else { s.sx[k] };
            s.sy[k] = if save { s.y[k] } else { s.sy[k] };
            let later = s.save_at[k].saturating_mul(2).saturating_sub(n0);
            s.save_at[k] = if save { later } else { s.save_at[k] };
        }
        step_lanes::<M, L, DE>(&map, &mut s, add);
        for k in 0..L {
            s.n[k] = s.n[k].wrapping_add(1);
        }
        steps += 1;
        if steps.is_multiple_of(CANCEL_EVERY) && cancel.load(Ordering::Relaxed) {
            return Err(Cancelled);
        }
    }
    Ok(iterations)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::{Cycle, Single};
    use crate::simd_level::SimdLevel;

    fn check<M: Map + Default>(family: Family, center: [f64; 2], radius: f64) {
        let points: Vec<[f64; 2]> = (0..1500)
            .map(|k| {
                [
                    center[0] + radius * ((k % 50) as f64 / 25.0 - 1.0),
                    center[1] + radius * ((k / 50) as f64 / 15.0 - 1.0),
                ]
            })
            .collect();
        for derivative in [false, true] {
            let base = OrbitParams {
                family,
                formula: Formula::default(),
                max_iter: 300,
                escape_radius: 1e4,
                derivative,
                simd: SimdLevel::Scalar,
            };
            let want: Vec<Orbit> = points
                .iter()
                .map(|&p| super::super::generic::orbit(Single(M::default()), &base, p, &[], &mut []).0)
                .collect();
            for simd in SimdLevel::usable() {
                let params = OrbitParams { simd, ..base };
                let mut got = vec![Orbit::interior(); points.len()];
                iterate::<M>(M::default(), &params, &points, &mut got, &AtomicBool::new(false)).unwrap();
                for (k, (a, b)) in got.iter().zip(&want).enumerate() {
                    assert_eq!(a.n, b.n, "{simd:?} de={derivative} point {:?}", points[k]);
                    assert_eq!(a.z.map(f64::to_bits), b.z.map(f64::to_bits), "{simd:?} point {:?}", points[k]);
                    assert_eq!(a.dz.map(f64::to_bits), b.dz.map(f64::to_bits), "{simd:?} point {:?}", points[k]);
                }
            }
        }
    }

    /// A hybrid through [`iterate_cycle`] against the scalar kernel's [`Cycle`] on every
    /// level: N, z_n and the derivative, bit for bit, and the iterations counted.
    fn check_cycle(text: &str, family: Family, center: [f64; 2], radius: f64) {
        let formula = Formula::parse(text, None).unwrap();
        // An odd count, so that the last lanes run idle beside others.
        let points: Vec<[f64; 2]> = (0..1499)
            .map(|k| {
                [
                    center[0] + radius * ((k % 50) as f64 / 25.0 - 1.0),
                    center[1] + radius * ((k / 50) as f64 / 15.0 - 1.0),
                ]
            })
            .collect();
        for derivative in [false, true] {
            let base =
                OrbitParams { family, formula, max_iter: 300, escape_radius: 1e4, derivative, simd: SimdLevel::Scalar };
            let mut want_its = 0;
            let want: Vec<Orbit> = points
                .iter()
                .map(|&p| {
                    let (o, its) = super::super::generic::orbit(Cycle(formula), &base, p, &[], &mut []);
                    want_its += its;
                    o
                })
                .collect();
            let (mut escaped, mut repeated) = (0, 0);
            for o in &want {
                escaped += (o.n != crate::formula::end::INTERIOR) as u32;
                repeated += (o.n == crate::formula::end::INTERIOR) as u32;
            }
            // Both kinds of end occur, so both paths of a lane's end are held.
            assert!(escaped > 100 && repeated > 100, "{text}: {escaped} escaped, {repeated} not");
            for simd in SimdLevel::usable() {
                let params = OrbitParams { simd, ..base };
                let mut got = vec![Orbit::interior(); points.len()];
                let its = iterate_cycle(&params, formula, &points, &mut got, &AtomicBool::new(false)).unwrap();
                assert_eq!(its, want_its, "{text} {simd:?} de={derivative}");
                for (k, (a, b)) in got.iter().zip(&want).enumerate() {
                    assert_eq!(a.n, b.n, "{text} {simd:?} de={derivative} point {:?}", points[k]);
                    assert_eq!(a.z.map(f64::to_bits), b.z.map(f64::to_bits), "{text} {simd:?} point {:?}", points[k]);
                    assert_eq!(a.dz.map(f64::to_bits), b.dz.map(f64::to_bits), "{text} {simd:?} point {:?}", points[k]);
                }
            }
        }
    }

    /// Hybrids of two and three phases, Mandelbrot form (first index 1) and Julia form
    /// (first index 0): lanes that end at every phase wait for a sample's first.
    #[test]
    fn hybrid_lanes_give_the_scalar_kernels_bits_on_every_level() {
        check_cycle("burning-ship,mandelbrot^3", Family::Mandelbrot, [-0.5, -0.3], 1.5);
        check_cycle("celtic^3,buffalo,mandelbar", Family::Mandelbrot, [-0.4, 0.0], 1.4);
        check_cycle("mandelbrot,perpendicular-burning-ship", Family::Julia { c: [-0.1, 0.1] }, [0.0, 0.0], 1.3);
    }

    /// Every level this CPU has gives the scalar kernel's bits (N, z_n, the derivative), for
    /// conformal and folded families, Mandelbrot and Julia forms, and the quasi families'
    /// imaginary parts signed by y (type 14) and by xy with the real part folded (type 26).
    #[test]
    fn lanes_give_the_scalar_kernels_bits_on_every_level() {
        check::<Ops<3, 2, 0, 0>>(Family::Mandelbrot, [-0.5, -0.5], 1.2);
        check::<Ops<0, 3, 0, 0>>(Family::Mandelbrot, [0.0, 0.0], 1.2);
        check::<Ops<1, 2, 1, 1>>(Family::Mandelbrot, [-0.3, 0.0], 1.5);
        check::<Ops<0, 5, 3, 0>>(Family::Julia { c: [-0.5, 0.3] }, [0.0, 0.0], 1.3);
        check::<Ops<0, 3, 0, 2>>(Family::Mandelbrot, [0.0, 0.0], 1.2);
        check::<Ops<1, 3, 10, 1>>(Family::Mandelbrot, [-0.2, 0.0], 1.3);
        check::<Ops<0, 4, 15, 0>>(Family::Julia { c: [-0.4, 0.2] }, [0.0, 0.0], 1.2);
    }
}
