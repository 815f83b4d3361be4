//! The vectorised f64 escape-time kernel: many orbits in flight, lanes refilled as they finish.
//!
//! Built for throughput on views with no interior (the target is 6e9 iterations per second
//! on two cores), so the inner loop does nothing but iterate:
//!
//! * `V` independent vectors are interleaved so that the multiply/add latency chain of one
//!   orbit is hidden behind the others; each vector holds `S::F64_LANES` orbits (8 with
//!   AVX-512, 4 with AVX2, 1 in the portable fallback), chosen at run time by pulp.
//! * Iterations run in blocks of `K` with no branch. When |z| > R implies the orbit stays
//!   escaped (R^2 - R >= |c|, nearly always) |z|^2 is tested once, at the block's end;
//!   otherwise each step ORs "|z|^2 > R^2" into a mask. The state is checkpointed every
//!   `STRIDE` steps. After a block, a vector with escaped lanes finds every lane's escape at
//!   once (`find_escapes`): blends pick each lane's last checkpoint inside the circle and
//!   at most `STRIDE` vector steps from there find the first value outside. This has no
//!   per-lane loop and no unpredictable branch, which matters because on a typical view a
//!   sample ends every ~15 iterations per vector (it replaced a scalar replay per lane and
//!   made the seahorse benchmark 20% faster). Traps and the every-step test keep the scalar
//!   replay of [`crate::formula`]'s step. All use the same IEEE operations in the same order,
//!   so the escape index, z_n and dz_n are bit-identical to the scalar kernel.
//! * A finished lane is refilled with the next sample at once, so no lane idles while
//!   another runs long (the classic waste of "run the vector until all lanes escape").
//! * Interior orbits are cut short exactly: a lane whose z equals, bit for bit, a value it
//!   held earlier is periodic in f64 and can never escape (Brent's scheme: the saved value is
//!   refreshed at power-of-two ages). The main cardioid and period-2 bulb never enter a lane.
//!
//! All bookkeeping that is not per-iteration (max-iteration deadlines, periodicity saves)
//! is scheduled by block count so that the common block costs one mask test per vector.

use std::sync::atomic::{AtomicBool, Ordering};

use pulp::{Simd, WithSimd};

use super::OrbitParams;
use crate::cancel::Cancelled;
use crate::formula::end::Orbit;
use crate::formula::{self, Family};
use crate::trap::Shape;

/// Vectors in flight per thread.
const V: usize = 4;
/// Iterations per branch-free block.
const K: u32 = 32;
/// Iterations between checkpoints inside a block (a replay never runs longer than this).
const STRIDE: u32 = 4;
/// Checkpoints per block.
const C: usize = (K / STRIDE) as usize;
/// Most lanes any backend has (AVX-512: 8 f64 lanes).
const MAX_LANES: usize = 8;
/// Age in blocks of the first periodicity reference: orbits that escape sooner never pay
/// for cycle detection (Brent's doubling then continues from here).
const FIRST_SAVE: u64 = 16;
/// Blocks between two looks at the cancel flag.
const CANCEL_EVERY: u64 = 1 << 12;

/// Iterates every point, writing one [`Orbit`] per point; returns the iterations performed.
/// With `final_z` false only N is wanted: escaped orbits may then carry z = dz = 0, which
/// spares the kernel selecting them (the derivative implies `final_z`).
pub fn iterate(
    params: &OrbitParams,
    points: &[[f64; 2]],
    out: &mut [Orbit],
    final_z: bool,
    cancel: &AtomicBool,
) -> Result<u64, Cancelled> {
    assert_eq!(points.len(), out.len());
    let final_z = final_z || params.derivative;
    params.simd.arch().dispatch(Job { params, points, out, shape: None, trap_out: &mut [], final_z, cancel })
}

/// As [`iterate`] when only N is wanted (no derivative), writing each point's N straight
/// into `n`: no [`Orbit`] records to fill and read back.
pub fn iterate_n(
    params: &OrbitParams,
    points: &[[f64; 2]],
    n: &mut [u32],
    cancel: &AtomicBool,
) -> Result<u64, Cancelled> {
    assert_eq!(points.len(), n.len());
    assert!(!params.derivative, "iterate_n is for N alone");
    let out = &mut NOnly(n);
    params.simd.arch().dispatch(Job { params, points, out, shape: None, trap_out: &mut [], final_z: false, cancel })
}

/// Where the kernel writes each sample's result.
trait Sink {
    fn put(&mut self, k: usize, orbit: Orbit);
}

impl Sink for [Orbit] {
    #[inline(always)]
    fn put(&mut self, k: usize, orbit: Orbit) {
        self[k] = orbit;
    }
}

/// N alone, into a plane.
struct NOnly<'a>(&'a mut [u32]);

impl Sink for NOnly<'_> {
    #[inline(always)]
    fn put(&mut self, k: usize, orbit: Orbit) {
        self.0[k] = orbit.n;
    }
}

/// As [`iterate`], also keeping each orbit's distance to one geometric trap `shape`
/// (observing z_k for k >= 1 up to the escaping value, exactly as [`super::scalar`] does);
/// `trap_out[k]` receives the distance for point k. The cardioid/bulb skip is off, since
/// interior orbits have trap values too.
pub fn iterate_with_trap(
    params: &OrbitParams,
    shape: Shape,
    points: &[[f64; 2]],
    out: &mut [Orbit],
    trap_out: &mut [f64],
    cancel: &AtomicBool,
) -> Result<u64, Cancelled> {
    assert_eq!(points.len(), out.len());
    assert_eq!(points.len(), trap_out.len());
    params.simd.arch().dispatch(Job { params, points, out, shape: Some(shape), trap_out, final_z: true, cancel })
}

struct Job<'a, O: Sink + ?Sized> {
    params: &'a OrbitParams,
    points: &'a [[f64; 2]],
    out: &'a mut O,
    shape: Option<Shape>,
    trap_out: &'a mut [f64],
    final_z: bool,
    cancel: &'a AtomicBool,
}

impl<O: Sink + ?Sized> WithSimd for Job<'_, O> {
    type Output = Result<u64, Cancelled>;

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> Self::Output {
        match (self.params.derivative, self.shape.is_some(), self.final_z) {
            (false, false, false) => run::<S, false, false, false, O>(simd, self),
            (false, false, true) => run::<S, false, false, true, O>(simd, self),
            (true, false, _) => run::<S, true, false, true, O>(simd, self),
            (false, true, _) => run::<S, false, true, true, O>(simd, self),
            (true, true, _) => run::<S, true, true, true, O>(simd, self),
        }
    }
}

/// Per-lane bookkeeping that stays in scalar registers/memory.
#[derive(Clone, Copy)]
struct LaneInfo {
    /// Index of the sample in this lane, or `usize::MAX` when the lane is idle.
    pixel: usize,
    /// Iteration index of the orbit when it was loaded.
    start: u32,
    /// Global block count when it was loaded.
    loaded_at: u64,
    /// Age (blocks since load) at which the periodicity reference is next refreshed.
    next_save: u64,
    /// Global block count at which this lane must be looked at even without an event.
    deadline: u64,
}

const IDLE: usize = usize::MAX;

/// Writes `value` into the lane of `v` selected by `mask`.
#[inline(always)]
fn set_lane<S: Simd>(simd: S, v: &mut S::f64s, mask: S::m64s, value: f64) {
    *v = simd.select_f64s(mask, simd.splat_f64s(value), *v);
}

/// The lanes of a mask as bits (bit l = lane l). Backends store masks either as bitmasks
/// (AVX-512 and the scalar fallback: one byte) or as full-width lanes (AVX2: all-ones or
/// zero per 64-bit lane); both layouts are read through their bytes.
#[inline(always)]
fn mask_bits<S: Simd>(m: S::m64s) -> u32 {
    let bytes = bytemuck::bytes_of(&m);
    if bytes.len() == 1 {
        bytes[0] as u32
    } else {
        let mut bits = 0;
        for l in 0..S::F64_LANES {
            bits |= ((bytes[8 * l] != 0) as u32) << l;
        }
        bits
    }
}

#[inline(always)]
fn lanes<S: Simd>(v: &S::f64s) -> &[f64] {
    bytemuck::cast_slice(std::slice::from_ref(v))
}

/// The vector state of all orbits in flight.
struct State<S: Simd> {
    x: [S::f64s; V],
    y: [S::f64s; V],
    cx: [S::f64s; V],
    cy: [S::f64s; V],
    dx: [S::f64s; V],
    dy: [S::f64s; V],
    px: [S::f64s; V],
    py: [S::f64s; V],
    /// Running trap metric (see [`Shape::metric`]).
    tm: [S::f64s; V],
}

#[inline(always)]
fn run<S: Simd, const DE: bool, const TRAP: bool, const Z: bool, O: Sink + ?Sized>(
    simd: S,
    job: Job<'_, O>,
) -> Result<u64, Cancelled> {
    let Job { params, points, out, shape, trap_out, cancel, .. } = job;
    let shape = shape.unwrap_or(Shape::Point { at: [0.0, 0.0] });
    let tv = TrapV::<S>::new(simd, &shape);
    let nl = S::F64_LANES;
    debug_assert!(nl <= MAX_LANES);
    let r2 = params.escape_radius * params.escape_radius;
    let max_iter = params.max_iter;
    let family = params.family;
    let dz_add = family.start([0.0, 0.0]).dz_add;

    let zero = simd.splat_f64s(0.0);
    let nan = simd.splat_f64s(f64::NAN);
    let mut st = State::<S> {
        x: [zero; V],
        y: [zero; V],
        cx: [zero; V],
        cy: [zero; V],
        dx: [zero; V],
        dy: [zero; V],
        px: [nan; V],
        py: [nan; V],
        tm: [zero; V],
    };
    let idle = LaneInfo { pixel: IDLE, start: 0, loaded_at: 0, next_save: 1, deadline: u64::MAX };
    let mut info = [idle; V * MAX_LANES];
    let mut cursor = 0usize;
    let mut block: u64 = 0;
    let mut iterations: u64 = 0;

    // One mask per lane, for writing single lanes with a blend: scalar stores into vectors
    // that are reloaded whole stall store forwarding, a blend of whole vectors does not.
    let iota = simd.partial_load_f64s(&[0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0][..nl]);
    let masks: [S::m64s; MAX_LANES] = std::array::from_fn(|l| simd.equal_f64s(iota, simd.splat_f64s(l as f64)));

    let ctx = RefillCtx { points, family, max_iter, masks, idle, shape };
    for v in 0..V {
        for l in 0..nl {
            refill::<S, DE, TRAP, O>(simd, &ctx, &mut st, &mut info[v * MAX_LANES + l], v, l, block, &mut cursor, out);
        }
    }
    let mut ck = Checkpoints::<S> {
        x: [[zero; V]; C],
        y: [[zero; V]; C],
        dx: [[zero; V]; C],
        dy: [[zero; V]; C],
        tm: [[zero; V]; C],
    };
    let mut deadline = info.iter().map(|i| i.deadline).min().unwrap_or(u64::MAX);

    // Largest |c| any orbit uses decides whether escape can be tested once per block.
    let max_c = match family {
        Family::Julia { c } => c[0] * c[0] + c[1] * c[1],
        Family::Mandelbrot => points.iter().map(|p| p[0] * p[0] + p[1] * p[1]).fold(0.0, f64::max),
    }
    .sqrt();
    let radius = params.escape_radius;
    // (With a margin far above rounding, so that the orbit stays escaped in f64 too.)
    let check_each = !(radius >= 2.0 && radius * radius - radius >= max_c + 1e-9 * radius * radius);
    let r2v = simd.splat_f64s(r2);
    let addv = simd.splat_f64s(dz_add);
    loop {
        if cursor >= points.len() && info.iter().all(|i| i.pixel == IDLE) {
            break;
        }
        let esc = if check_each {
            run_block::<S, DE, true, TRAP>(simd, &mut st, &mut ck, r2v, addv, &tv)
        } else {
            run_block::<S, DE, false, TRAP>(simd, &mut st, &mut ck, r2v, addv, &tv)
        };
        block += 1;
        if block.is_multiple_of(CANCEL_EVERY) && cancel.load(Ordering::Relaxed) {
            return Err(Cancelled);
        }

        let due = block >= deadline;
        for v in 0..V {
            let periodic = simd.and_m64s(simd.equal_f64s(st.x[v], st.px[v]), simd.equal_f64s(st.y[v], st.py[v]));
            let esc_bits = mask_bits::<S>(esc[v]);
            let per_bits = mask_bits::<S>(periodic);
            let mut todo = esc_bits | per_bits;
            if due {
                // Only the lanes whose own deadline has come (a periodicity save or the
                // max-iteration block), not every lane.
                for l in 0..nl {
                    todo |= ((info[v * MAX_LANES + l].deadline <= block) as u32) << l;
                }
            }
            if todo == 0 {
                continue;
            }
            // Monotone escapes (no traps) are located for the whole vector at once.
            let found = (esc_bits != 0 && !check_each && !TRAP)
                .then(|| find_escapes::<S, DE, Z>(simd, &ck, v, st.cx[v], st.cy[v], r2v, addv));
            while todo != 0 {
                let l = todo.trailing_zeros() as usize;
                todo &= todo - 1;
                let g = v * MAX_LANES + l;
                let li = info[g];
                if li.pixel == IDLE {
                    continue;
                }
                let age = block - li.loaded_at;
                let i0 = li.start as u64 + K as u64 * (age - 1);
                let overshoot = i0 + K as u64 > max_iter as u64;
                if let (true, false, Some(f)) = (esc_bits & (1 << l) != 0, overshoot, &found) {
                    let (n, orbit) = f.lane(l, i0);
                    iterations += n - li.start as u64;
                    out.put(li.pixel, orbit);
                    refill::<S, DE, TRAP, O>(simd, &ctx, &mut st, &mut info[g], v, l, block, &mut cursor, out);
                    deadline = deadline.min(info[g].deadline);
                } else if esc_bits & (1 << l) != 0 || overshoot {
                    let c = [lanes::<S>(&st.cx[v])[l], lanes::<S>(&st.cy[v])[l]];
                    let at = |k: usize| {
                        let z = [lanes::<S>(&ck.x[k][v])[l], lanes::<S>(&ck.y[k][v])[l]];
                        let dz = if DE { [lanes::<S>(&ck.dx[k][v])[l], lanes::<S>(&ck.dy[k][v])[l]] } else { [0.0; 2] };
                        let tm = if TRAP { lanes::<S>(&ck.tm[k][v])[l] } else { 0.0 };
                        (z, dz, tm)
                    };
                    // With the once-per-block test an escaped orbit stays escaped, so the escape
                    // lies after the last checkpoint still inside the circle; otherwise scan.
                    let first = if check_each || overshoot {
                        0
                    } else {
                        // Checkpoint 0 is inside (tested at the previous block's end) and the
                        // inside ones form a prefix, so the last one is their count minus one;
                        // counted without branches, the tests overlap.
                        (1..C).map(|k| (formula::step(at(k).0, c).1 <= r2) as usize).sum::<usize>()
                    };
                    let mut orbit = Orbit::interior();
                    let mut tm = f64::INFINITY;
                    for k in first..C {
                        let (z, dz, tm0) = at(k);
                        let i = i0 + k as u64 * STRIDE as u64;
                        if let Some((o, t)) = replay::<DE, TRAP>(z, dz, tm0, &shape, c, dz_add, i, max_iter, r2) {
                            (orbit, tm) = (o, t);
                            break;
                        }
                    }
                    iterations += orbit.iterations_from(li.start, max_iter);
                    out.put(li.pixel, orbit);
                    if TRAP {
                        trap_out[li.pixel] = shape.distance_from_metric(tm);
                    }
                    refill::<S, DE, TRAP, O>(simd, &ctx, &mut st, &mut info[g], v, l, block, &mut cursor, out);
                    deadline = deadline.min(info[g].deadline);
                } else if per_bits & (1 << l) != 0 {
                    iterations += i0 + K as u64 - li.start as u64;
                    out.put(li.pixel, Orbit::interior());
                    if TRAP {
                        trap_out[li.pixel] = shape.distance_from_metric(lanes::<S>(&st.tm[v])[l]);
                    }
                    refill::<S, DE, TRAP, O>(simd, &ctx, &mut st, &mut info[g], v, l, block, &mut cursor, out);
                    deadline = deadline.min(info[g].deadline);
                } else if block >= li.deadline {
                    // Refresh the periodicity reference (Brent: at ages 1, 2, 4, 8, ...).
                    let xs = lanes::<S>(&st.x[v])[l];
                    let ys = lanes::<S>(&st.y[v])[l];
                    set_lane(simd, &mut st.px[v], masks[l], xs);
                    set_lane(simd, &mut st.py[v], masks[l], ys);
                    let e = &mut info[g];
                    e.next_save = age * 2;
                    e.deadline = lane_deadline(e, max_iter);
                }
            }
        }
        if due {
            deadline = info.iter().map(|i| i.deadline).min().unwrap_or(u64::MAX);
        }
    }
    Ok(iterations)
}

/// Orbit states saved every `STRIDE` iterations of a block, for replays.
struct Checkpoints<S: Simd> {
    x: [[S::f64s; V]; C],
    y: [[S::f64s; V]; C],
    dx: [[S::f64s; V]; C],
    dy: [[S::f64s; V]; C],
    tm: [[S::f64s; V]; C],
}

/// What refilling a lane needs besides the lane itself.
struct RefillCtx<'a, S: Simd> {
    points: &'a [[f64; 2]],
    family: Family,
    max_iter: u32,
    masks: [S::m64s; MAX_LANES],
    idle: LaneInfo,
    shape: Shape,
}

/// Loads the next sample that needs iterating into lane (v, l), or idles the lane when
/// none is left. Samples in the main cardioid or period-2 bulb are written as interior
/// without ever entering a lane. (A function, not a closure: closures do not inherit the
/// SIMD target features of the function they are written in.)
#[inline(always)]
fn refill<S: Simd, const DE: bool, const TRAP: bool, O: Sink + ?Sized>(
    simd: S,
    ctx: &RefillCtx<'_, S>,
    st: &mut State<S>,
    info: &mut LaneInfo,
    v: usize,
    l: usize,
    block: u64,
    cursor: &mut usize,
    out: &mut O,
) {
    let masks = &ctx.masks;
    loop {
        if *cursor >= ctx.points.len() {
            *info = ctx.idle;
            set_lane(simd, &mut st.x[v], masks[l], 0.0);
            set_lane(simd, &mut st.y[v], masks[l], 0.0);
            set_lane(simd, &mut st.cx[v], masks[l], 0.0);
            set_lane(simd, &mut st.cy[v], masks[l], 0.0);
            set_lane(simd, &mut st.px[v], masks[l], f64::NAN);
            return;
        }
        let p = *cursor;
        *cursor += 1;
        let point = ctx.points[p];
        if !TRAP && matches!(ctx.family, Family::Mandelbrot) && formula::in_main_components(point) {
            out.put(p, Orbit::interior());
            continue;
        }
        let s = ctx.family.start(point);
        set_lane(simd, &mut st.x[v], masks[l], s.z[0]);
        set_lane(simd, &mut st.y[v], masks[l], s.z[1]);
        set_lane(simd, &mut st.cx[v], masks[l], s.c[0]);
        set_lane(simd, &mut st.cy[v], masks[l], s.c[1]);
        if DE {
            set_lane(simd, &mut st.dx[v], masks[l], s.dz[0]);
            set_lane(simd, &mut st.dy[v], masks[l], s.dz[1]);
        }
        set_lane(simd, &mut st.px[v], masks[l], f64::NAN);
        set_lane(simd, &mut st.py[v], masks[l], f64::NAN);
        if TRAP {
            // Traps observe z_k for k >= 1: Mandelbrot's first value z_1 now, Julia's z_0 never.
            let tm = if s.n >= 1 { ctx.shape.metric(s.z) } else { f64::INFINITY };
            set_lane(simd, &mut st.tm[v], masks[l], tm);
        }
        *info = LaneInfo { pixel: p, start: s.n, loaded_at: block, next_save: FIRST_SAVE, deadline: 0 };
        info.deadline = lane_deadline(info, ctx.max_iter);
        return;
    }
}

/// Runs `K` iterations on every vector; returns, per vector, the lanes that escaped.
///
/// The state is copied into locals first so that it lives in registers for the whole block
/// (the struct itself is borrowed by the refill logic and would otherwise be reloaded).
///
/// With `EACH` false the escape test runs once, at the end of the block. That is exact when
/// `R^2 - R >= |c|` for every orbit: then |z| > R implies |z^2 + c| > R, an escaped orbit stays
/// escaped (growing to infinity or NaN, which the `!(|z|^2 <= R^2)` test also catches), and
/// the scalar replay finds the first escaping index. Otherwise the test runs every step.
#[inline(always)]
fn run_block<S: Simd, const DE: bool, const EACH: bool, const TRAP: bool>(
    simd: S,
    st: &mut State<S>,
    ck: &mut Checkpoints<S>,
    r2v: S::f64s,
    addv: S::f64s,
    tv: &TrapV<S>,
) -> [S::m64s; V] {
    let (mut x, mut y, cx, cy) = (st.x, st.y, st.cx, st.cy);
    let (mut dx, mut dy) = (st.dx, st.dy);
    let mut tm = st.tm;
    let zero = simd.splat_f64s(0.0);
    let mut esc = [simd.less_than_f64s(zero, zero); V];
    for c in 0..C {
        ck.x[c] = x;
        ck.y[c] = y;
        if DE {
            ck.dx[c] = dx;
            ck.dy[c] = dy;
        }
        if TRAP {
            ck.tm[c] = tm;
        }
        // The stretch between checkpoints is unrolled: no loop control or register moves
        // between steps.
        for _ in 0..STRIDE {
            for v in 0..V {
                if EACH {
                    let rr = simd.mul_add_f64s(x[v], x[v], simd.mul_f64s(y[v], y[v]));
                    esc[v] = simd.or_m64s(esc[v], simd.greater_than_f64s(rr, r2v));
                }
                (x[v], y[v], dx[v], dy[v]) = step_v::<S, DE>(simd, x[v], y[v], dx[v], dy[v], cx[v], cy[v], addv);
                if TRAP {
                    tm[v] = simd.min_f64s(tm[v], tv.metric(simd, x[v], y[v]));
                }
            }
        }
    }
    if !EACH {
        for v in 0..V {
            let rr = simd.mul_add_f64s(x[v], x[v], simd.mul_f64s(y[v], y[v]));
            esc[v] = simd.not_m64s(simd.less_than_or_equal_f64s(rr, r2v));
        }
    }
    st.x = x;
    st.y = y;
    if DE {
        st.dx = dx;
        st.dy = dy;
    }
    if TRAP {
        st.tm = tm;
    }
    esc
}

/// One step of z and (with `DE`) dz on every lane, with the operations of
/// [`formula::step`] and [`formula::deriv_step`] in the same order, so that lanes and the
/// scalar kernel agree bit for bit.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn step_v<S: Simd, const DE: bool>(
    simd: S,
    x: S::f64s,
    y: S::f64s,
    dx: S::f64s,
    dy: S::f64s,
    cx: S::f64s,
    cy: S::f64s,
    addv: S::f64s,
) -> (S::f64s, S::f64s, S::f64s, S::f64s) {
    let yy = simd.mul_f64s(y, y);
    let (ndx, ndy) = if DE {
        let re = simd.mul_add_f64s(x, dx, simd.neg_f64s(simd.mul_f64s(y, dy)));
        let im = simd.mul_add_f64s(x, dy, simd.mul_f64s(y, dx));
        (simd.mul_add_f64s(re, simd.splat_f64s(2.0), addv), simd.add_f64s(im, im))
    } else {
        (dx, dy)
    };
    let nx = simd.add_f64s(simd.mul_add_f64s(x, x, simd.neg_f64s(yy)), cx);
    let ny = simd.mul_add_f64s(simd.add_f64s(x, x), y, cy);
    (nx, ny, ndx, ndy)
}

/// Where each lane of one vector escaped inside the last block, found for all lanes at once
/// (valid for the lanes that escaped; the others carry garbage).
struct Found<S: Simd> {
    /// Byte k-1 holds the lanes whose checkpoint k is inside the circle.
    checkpoints: u64,
    /// Byte s holds the lanes whose value s steps after their last inside checkpoint is inside.
    steps: u64,
    x: S::f64s,
    y: S::f64s,
    dx: S::f64s,
    dy: S::f64s,
}

impl<S: Simd> Found<S> {
    /// Lane `l`'s escape index (the block began at iteration `i0`) and its orbit record.
    #[inline(always)]
    fn lane(&self, l: usize, i0: u64) -> (u64, Orbit) {
        const BYTES: u64 = 0x0101_0101_0101_0101;
        let m = ((self.checkpoints >> l) & BYTES).count_ones() as u64;
        let j = ((self.steps >> l) & BYTES).count_ones() as u64;
        let n = i0 + STRIDE as u64 * m + j;
        let z = [lanes::<S>(&self.x)[l], lanes::<S>(&self.y)[l]];
        let dz = [lanes::<S>(&self.dx)[l], lanes::<S>(&self.dy)[l]];
        // n <= max_iter (blocks that reach max_iter take the scalar path), so it fits N's u32.
        (n, Orbit { n: n as u32, z, dz })
    }
}

/// The vector form of the scalar replay, for escapes that stay escaped (no `EACH` test, no
/// traps): the last checkpoint still inside the circle is picked per lane with blends, then
/// `STRIDE` steps from it find the first value outside, with the same operations as the
/// block, so the results are bit-identical to the scalar replay's. One pass serves every lane
/// of the vector: no per-lane loop, no unpredictable branch.
///
/// Because an escaped orbit stays escaped, "inside" holds for a prefix of the checkpoints and
/// of the steps, so neither needs a running AND: the last inside checkpoint is the last one
/// a forward chain of blends keeps, and the first value outside is the one a backward chain
/// keeps.
#[inline(always)]
fn find_escapes<S: Simd, const DE: bool, const Z: bool>(
    simd: S,
    ck: &Checkpoints<S>,
    v: usize,
    cx: S::f64s,
    cy: S::f64s,
    r2v: S::f64s,
    addv: S::f64s,
) -> Found<S> {
    let inside =
        |x: S::f64s, y: S::f64s| simd.less_than_or_equal_f64s(simd.mul_add_f64s(x, x, simd.mul_f64s(y, y)), r2v);
    let (mut x, mut y, mut dx, mut dy) = (ck.x[0][v], ck.y[0][v], ck.dx[0][v], ck.dy[0][v]);
    let mut checkpoints = 0u64;
    for k in 1..C {
        let ins = inside(ck.x[k][v], ck.y[k][v]);
        x = simd.select_f64s(ins, ck.x[k][v], x);
        y = simd.select_f64s(ins, ck.y[k][v], y);
        if DE {
            dx = simd.select_f64s(ins, ck.dx[k][v], dx);
            dy = simd.select_f64s(ins, ck.dy[k][v], dy);
        }
        checkpoints |= (mask_bits::<S>(ins) as u64) << (8 * (k - 1));
    }
    let mut z = [(x, y, dx, dy); STRIDE as usize + 1];
    let mut ins = [simd.equal_f64s(x, x); STRIDE as usize];
    let mut steps = 0u64;
    for s in 0..STRIDE as usize {
        let (x, y, dx, dy) = z[s];
        ins[s] = inside(x, y);
        steps |= (mask_bits::<S>(ins[s]) as u64) << (8 * s);
        // Without Z the value after the last test is never looked at.
        if Z || s + 1 < STRIDE as usize {
            z[s + 1] = step_v::<S, DE>(simd, x, y, dx, dy, cx, cy, addv);
        }
    }
    if !Z {
        let zero = simd.splat_f64s(0.0);
        return Found { checkpoints, steps, x: zero, y: zero, dx: zero, dy: zero };
    }
    let (mut x, mut y, mut dx, mut dy) = z[STRIDE as usize];
    for s in (0..STRIDE as usize).rev() {
        x = simd.select_f64s(ins[s], x, z[s].0);
        y = simd.select_f64s(ins[s], y, z[s].1);
        if DE {
            dx = simd.select_f64s(ins[s], dx, z[s].2);
            dy = simd.select_f64s(ins[s], dy, z[s].3);
        }
    }
    Found { checkpoints, steps, x, y, dx, dy }
}

/// Global block count at which a lane needs attention without an escape or a cycle: when
/// its periodicity reference is due, or when the block that reaches `max_iter` completes.
#[inline(always)]
fn lane_deadline(info: &LaneInfo, max_iter: u32) -> u64 {
    let remaining = max_iter as u64 + 1 - info.start as u64;
    let overshoot_age = remaining.div_ceil(K as u64);
    info.loaded_at + info.next_save.min(overshoot_age)
}

/// Scalar replay from a checkpoint (z_i0, dz_i0), testing z_i0 ..= z_(i0+STRIDE) (the last
/// one is the next checkpoint, or the block's end value that the once-per-block test saw):
/// the escape, or interior at `max_iter`, or `None` if neither happens in the stretch.
#[inline(always)]
fn replay<const DE: bool, const TRAP: bool>(
    mut z: [f64; 2],
    mut dz: [f64; 2],
    mut tm: f64,
    shape: &Shape,
    c: [f64; 2],
    dz_add: f64,
    i0: u64,
    max_iter: u32,
    r2: f64,
) -> Option<(Orbit, f64)> {
    for n in i0..=i0 + STRIDE as u64 {
        let (next, rr) = formula::step(z, c);
        if rr > r2 {
            // n <= max_iter here, so it fits the u32 of N.
            return Some((Orbit { n: n as u32, z, dz }, tm));
        }
        if n >= max_iter as u64 {
            return Some((Orbit::interior(), tm));
        }
        if DE {
            dz = formula::deriv_step(z, dz, dz_add);
        }
        z = next;
        if TRAP {
            let m = shape.metric(z);
            if m < tm {
                tm = m;
            }
        }
    }
    None
}

/// A shape's parameters as vectors, for [`Shape::metric`] on every lane.
struct TrapV<S: Simd> {
    kind: u8,
    ax: S::f64s,
    ay: S::f64s,
    d0: S::f64s,
    d1: S::f64s,
    r: S::f64s,
}

impl<S: Simd> TrapV<S> {
    #[inline(always)]
    fn new(simd: S, shape: &Shape) -> Self {
        let (kind, at, dir, r) = match *shape {
            Shape::Point { at } => (0, at, [0.0; 2], 0.0),
            Shape::Line { at, dir } => (1, at, dir, 0.0),
            Shape::Cross { at, dir } => (2, at, dir, 0.0),
            Shape::Circle { at, radius } => (3, at, [0.0; 2], radius),
        };
        let sp = |v: f64| simd.splat_f64s(v);
        Self { kind, ax: sp(at[0]), ay: sp(at[1]), d0: sp(dir[0]), d1: sp(dir[1]), r: sp(r) }
    }

    /// [`Shape::metric`] on every lane, with the same operations.
    #[inline(always)]
    fn metric(&self, simd: S, x: S::f64s, y: S::f64s) -> S::f64s {
        let a = simd.sub_f64s(x, self.ax);
        let b = simd.sub_f64s(y, self.ay);
        let sq = || simd.add_f64s(simd.mul_f64s(a, a), simd.mul_f64s(b, b));
        let cross = || simd.abs_f64s(simd.sub_f64s(simd.mul_f64s(a, self.d1), simd.mul_f64s(b, self.d0)));
        match self.kind {
            0 => sq(),
            1 => cross(),
            2 => simd
                .min_f64s(cross(), simd.abs_f64s(simd.add_f64s(simd.mul_f64s(a, self.d0), simd.mul_f64s(b, self.d1)))),
            _ => simd.abs_f64s(simd.sub_f64s(simd.sqrt_f64s(sq()), self.r)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{SampleGrid, scalar};
    use crate::simd_level::SimdLevel;
    use crate::trap::Shape;

    fn check(family: Family, center: [f64; 2], radius: f64, max_iter: u32, derivative: bool) {
        check_with(family, center, radius, max_iter, derivative, 1024.0);
    }

    /// The sample points of a `width` x `height` grid over the view.
    fn grid_points(center: [f64; 2], radius: f64, width: u32, height: u32) -> Vec<[f64; 2]> {
        let grid =
            SampleGrid { center, radius, width, height, transform: Default::default(), projection: Default::default() };
        (0..height).flat_map(|j| (0..width).map(move |i| grid.point(i, j))).collect()
    }

    /// Every instruction set this CPU runs (scalar included) against the scalar kernel.
    fn check_with(family: Family, center: [f64; 2], radius: f64, max_iter: u32, derivative: bool, escape_radius: f64) {
        for simd in SimdLevel::usable() {
            check_level(family, center, radius, max_iter, derivative, escape_radius, simd);
        }
    }

    fn check_level(
        family: Family,
        center: [f64; 2],
        radius: f64,
        max_iter: u32,
        derivative: bool,
        escape_radius: f64,
        simd: SimdLevel,
    ) {
        let points = grid_points(center, radius, 67, 31);
        let params = OrbitParams { family, formula: Default::default(), max_iter, escape_radius, derivative, simd };
        let mut out = vec![Orbit::interior(); points.len()];
        let its = iterate(&params, &points, &mut out, true, &AtomicBool::new(false)).unwrap();
        let mut total = 0;
        for (p, o) in points.iter().zip(&out) {
            let (want, n) = scalar::orbit(&params, *p, &[], &mut []);
            total += n;
            assert_eq!(*o, want, "{simd} at {p:?}");
        }
        // Periodicity detection may stop interior orbits at different points; escapes agree.
        if out.iter().all(|o| o.n != crate::formula::end::INTERIOR) {
            assert_eq!(its, total);
        }
        // Asking for N alone gives the same N (and the same work).
        let mut n_only = vec![Orbit::interior(); points.len()];
        let its_n = iterate(&params, &points, &mut n_only, false, &AtomicBool::new(false)).unwrap();
        assert_eq!(its_n, its);
        for (a, b) in n_only.iter().zip(&out) {
            assert_eq!(a.n, b.n);
        }
        // And written straight into a plane.
        if !derivative {
            let mut plane = vec![0u32; points.len()];
            let its_plane = iterate_n(&params, &points, &mut plane, &AtomicBool::new(false)).unwrap();
            assert_eq!(its_plane, its);
            assert!(plane.iter().zip(&out).all(|(n, o)| *n == o.n));
        }
    }

    /// The vectorised trap path against the scalar kernel: same orbits, same trap distance.
    fn check_trap(family: Family, center: [f64; 2], radius: f64, max_iter: u32, derivative: bool, shape: Shape) {
        for simd in SimdLevel::usable() {
            check_trap_level(family, center, radius, max_iter, derivative, shape, simd);
        }
    }

    fn check_trap_level(
        family: Family,
        center: [f64; 2],
        radius: f64,
        max_iter: u32,
        derivative: bool,
        shape: Shape,
        simd: SimdLevel,
    ) {
        let points = grid_points(center, radius, 53, 29);
        let params =
            OrbitParams { family, formula: Default::default(), max_iter, escape_radius: 1024.0, derivative, simd };
        let mut out = vec![Orbit::interior(); points.len()];
        let mut dist = vec![0.0; points.len()];
        iterate_with_trap(&params, shape, &points, &mut out, &mut dist, &AtomicBool::new(false)).unwrap();
        let trap = crate::trap::Trap::Geometric(shape);
        for (k, p) in points.iter().enumerate() {
            let mut state = [trap.initial()];
            let (want, _) = scalar::orbit(&params, *p, std::slice::from_ref(&trap), &mut state);
            assert_eq!(out[k], want, "{simd} {shape:?} at {p:?}");
            let crate::trap::TrapState::Distance(d) = state[0] else { unreachable!() };
            assert_eq!(dist[k].to_bits(), d.to_bits(), "{shape:?} at {p:?}: {} vs {d}", dist[k]);
        }
    }

    #[test]
    fn trap_path_agrees_bit_for_bit_with_the_scalar_kernel() {
        let dir = Shape::direction(30.0);
        let shapes = [
            Shape::Point { at: [0.1, -0.2] },
            Shape::Line { at: [0.0, 0.3], dir },
            Shape::Cross { at: [-0.5, 0.0], dir },
            Shape::Circle { at: [0.0, 0.0], radius: 0.7 },
        ];
        for shape in shapes {
            for de in [false, true] {
                check_trap(Family::Mandelbrot, [-0.75, 0.0], 1.5, 400, de, shape);
                check_trap(Family::Julia { c: [-0.8, 0.156] }, [0.0, 0.0], 1.5, 300, de, shape);
            }
        }
    }

    #[test]
    fn agrees_bit_for_bit_with_the_scalar_kernel() {
        for de in [false, true] {
            check(Family::Mandelbrot, [-0.75, 0.0], 1.5, 500, de);
            check(Family::Mandelbrot, [-0.7436438870, 0.1318259042], 1e-6, 3000, de);
            check(Family::Mandelbrot, [-0.75, 0.0], 1.5, 3, de);
            check(Family::Julia { c: [-0.8, 0.156] }, [0.0, 0.0], 1.5, 700, de);
            check(Family::Julia { c: [0.0, 1.0] }, [0.0, 0.0], 1.6, 10_001, de);
            // |c| > R^2 - R: the escape test runs at every step instead of once per block.
            check_with(Family::Mandelbrot, [-0.5, 0.0], 2.5, 300, de, 2.0);
            check_with(Family::Julia { c: [3.0, 1.5] }, [0.0, 0.0], 2.0, 100, de, 2.0);
            check_with(Family::Julia { c: [-0.8, 0.156] }, [0.0, 0.0], 1.5, u32::MAX - 1, de, 2.0);
        }
    }
}
