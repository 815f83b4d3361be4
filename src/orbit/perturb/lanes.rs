//! Single perturbation steps in vector lanes: several samples to a vector, each at its own
//! place in the reference orbit, on every instruction set with vectors of f64 (AVX2: 4
//! lanes, AVX-512: 8, NEON: 2).
//!
//! A deep view spends most of its time where BLA no longer helps a sample: once its delta is
//! above the single-step threshold it takes nothing but single steps until it escapes or
//! rebases (thousands per sample on the 1e50 benchmark). The scalar loop is a chain of
//! dependent multiplies (about 16 cycles of latency per step) that it can overlap for two
//! samples at most; here two vectors of samples advance together.
//!
//! The lanes do only that one thing. A sample enters when the scalar loop
//! ([`Perturbation::begin`]) reaches a single step in single-step mode, and from then on
//! each step reads every lane's own Z_m (there is no common m: samples rebase and took BLA
//! steps of different lengths), tests for anything that is not a plain step, and steps. A
//! rebase that keeps the sample in single steps happens in the lane. A lane that meets an
//! escape, the iteration limit, the reference's end, a rebase into FloatExp range or back to
//! BLA steps, or a derivative or |dz/dz|^2 (interior detection) that leaves its exponent
//! window hands its sample back to the scalar loop ([`Perturbation::resume`]), which handles the event with its own code and
//! returns the sample (when it is again in single steps) or the next one. Nothing else
//! leaves a lane, so no lane idles while its neighbours run long. Positions are addresses
//! kept per lane in scalars (`at0[i] + t16`), and the iteration limit and the reference's
//! end are a per-lane stop on the same clock, tested once per step for the whole vector.
//!
//! While every lane of every vector holds a sample and none is near its stop, the loop runs
//! in bursts ([`burst`]): the deltas (and derivatives) stay in registers, each lane reads its
//! Z_m at its start address plus the bytes stepped, and the only test per step is for an
//! event, before which the burst ends and hands the vectors to the general step. With
//! interior detection, bursts run while every lane's sample has left it (`Probe::plain`:
//! most samples outside a minibrot, from their start); such a lane carries no |dz/dz|^2.
//!
//! The loop is written once, generic over pulp's [`Simd`] (the vector width and the
//! arithmetic). What differs between instruction sets is only how every lane's Z_m is
//! brought into two vectors (re, im) and how a comparison becomes a bit mask: the
//! [`Unit`] trait, implemented for AVX2 (x86-64-v3), AVX-512 (x86-64-v4) and NEON. Each
//! lane's (re, im) pair is one 16-byte load; while no lane is within two steps of its stop
//! one 32-byte load per lane serves two steps (x86), and shuffles split the pairs (cheaper
//! than gathers on Zen 3 and Zen 4). The arithmetic is [`Perturbation::op`]'s, operation for
//! operation and in the same order (separate multiplies and adds, no fused multiply-add),
//! so every sample ends bit for bit as in the scalar loop on every instruction set; a test
//! holds each one the CPU has to that.
//!
//! `unsafe` is confined to this file for two reasons: the loads read memory through
//! addresses (each active lane reads inside its own reference orbit: its address is that
//! orbit's Z_0 plus 16 m bytes with m at most the orbit's last index, exposed by
//! [`Refs::new`]; an empty lane reads a static block of zeros), and the intrinsics of the
//! load routines need their instruction set, which the pulp token each [`Unit`] is
//! implemented for proves present.
#![allow(unsafe_code)]

use std::sync::atomic::AtomicBool;

use pulp::Simd;

use super::start::Given;
use super::{Counters, DER_HI, DER_LO, DER_TINY_Z2, DOWN, Held, Numbers, Perturbation};
use crate::orbit::interior;
use crate::orbit::interior::model::Model;

// The lanes hand a step back for either reason with one comparison.
const _: () = assert!(DER_TINY_Z2 == interior::TINY2);
use crate::formula::end::Orbit;
use crate::simd_level::SimdLevel;

/// Most lanes any instruction set has (AVX-512: 8 f64 lanes).
const MAX_W: usize = 8;
/// Vectors in flight (their dependency chains overlap).
const G: usize = 2;
/// Samples whose series starts are worked out together ([`Perturbation::series_starts`]).
const STARTS: usize = 8;

/// `[e(0), e(1)]` for an expression `e` of the vector's index `g`: what
/// `std::array::from_fn` (or an iterator over the vectors) would build, written out. The
/// compiler does not always inline such closures into the instruction set's function: once
/// both settings of interior detection ran bursts, they had two call sites each, and their
/// intrinsics ran as calls (twice the time on every view; an AVX-512 `and` in the
/// derivative's test kept liiiines 8% slower).
macro_rules! per_vector {
    (|$g:ident| $e:expr) => {{
        const _: () = assert!(G == 2);
        [
            {
                let $g = 0;
                $e
            },
            {
                let $g = 1;
                $e
            },
        ]
    }};
}

pub(super) mod burst;

use burst::{Rate, burst, settle};

/// Where an empty lane reads: two steps' worth of zeros.
static PARK: [f64; 4] = [0.0; 4];

/// Z_m of every lane as (re, im) vectors.
type Z<S> = (<S as Simd>::f64s, <S as Simd>::f64s);

/// What the lanes' loop needs of an instruction set beyond pulp's arithmetic.
trait Unit: Simd {
    /// Z_m of every lane, as (re, im) vectors; `at[i]` is lane i's address of Z_m.
    ///
    /// # Safety
    /// Each of the first `F64_LANES` addresses must point at two readable f64.
    unsafe fn load_z(self, at: &[usize; MAX_W]) -> Z<Self>;

    /// Z_m and Z_m+1 of every lane.
    ///
    /// # Safety
    /// Each of the first `F64_LANES` addresses must point at four readable f64.
    unsafe fn load_pair(self, at: &[usize; MAX_W]) -> (Z<Self>, Z<Self>) {
        // SAFETY: the caller's promise covers both halves.
        unsafe { (self.load_z(at), self.load_z(&at.map(|a| a + 16))) }
    }

    /// The mask as bits, lane i at bit i.
    fn bits(self, m: Self::m64s) -> u32;
}

/// A pointer to the f64 at an exposed address.
#[inline(always)]
fn at_ptr(addr: usize) -> *const f64 {
    std::ptr::with_exposed_provenance::<f64>(addr)
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use pulp::x86::{V3, V4};
    use pulp::{b8, cast};

    use super::{MAX_W, Unit, Z, at_ptr};

    impl Unit for V3 {
        #[inline(always)]
        unsafe fn load_z(self, at: &[usize; MAX_W]) -> Z<Self> {
            // SAFETY: V3 proves AVX2; the caller promises the addresses.
            unsafe {
                let q = |i: usize| _mm_loadu_pd(at_ptr(at[i]));
                // [re0 im0 | re2 im2] and [re1 im1 | re3 im3], then interleave.
                let a = _mm256_set_m128d(q(2), q(0));
                let b = _mm256_set_m128d(q(3), q(1));
                (cast(_mm256_unpacklo_pd(a, b)), cast(_mm256_unpackhi_pd(a, b)))
            }
        }

        #[inline(always)]
        unsafe fn load_pair(self, at: &[usize; MAX_W]) -> (Z<Self>, Z<Self>) {
            // SAFETY: V3 proves AVX2; the caller promises the addresses.
            unsafe {
                let q = |i: usize| _mm256_loadu_pd(at_ptr(at[i]));
                // Lane i: [re_m im_m re_m+1 im_m+1].
                let (q0, q1, q2, q3) = (q(0), q(1), q(2), q(3));
                let re01 = _mm256_unpacklo_pd(q0, q1); // [re0 re1 | re0' re1']
                let im01 = _mm256_unpackhi_pd(q0, q1);
                let re23 = _mm256_unpacklo_pd(q2, q3);
                let im23 = _mm256_unpackhi_pd(q2, q3);
                let now = |x, y| _mm256_permute2f128_pd::<0x20>(x, y);
                let next = |x, y| _mm256_permute2f128_pd::<0x31>(x, y);
                ((cast(now(re01, re23)), cast(now(im01, im23))), (cast(next(re01, re23)), cast(next(im01, im23))))
            }
        }

        #[inline(always)]
        fn bits(self, m: Self::m64s) -> u32 {
            self.avx._mm256_movemask_pd(cast(m)) as u32
        }
    }

    impl Unit for V4 {
        #[inline(always)]
        unsafe fn load_z(self, at: &[usize; MAX_W]) -> Z<Self> {
            // SAFETY: V4 proves AVX-512 F; the caller promises the addresses.
            unsafe {
                let q = |i: usize| _mm_loadu_pd(at_ptr(at[i]));
                let half = |i: usize| _mm256_set_m128d(q(i + 1), q(i));
                let lo = _mm512_insertf64x4::<1>(_mm512_castpd256_pd512(half(0)), half(2));
                let hi = _mm512_insertf64x4::<1>(_mm512_castpd256_pd512(half(4)), half(6));
                let even = _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14);
                let odd = _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15);
                (cast(_mm512_permutex2var_pd(lo, even, hi)), cast(_mm512_permutex2var_pd(lo, odd, hi)))
            }
        }

        #[inline(always)]
        unsafe fn load_pair(self, at: &[usize; MAX_W]) -> (Z<Self>, Z<Self>) {
            // SAFETY: V4 proves AVX-512 F; the caller promises the addresses.
            unsafe {
                let q = |i: usize| _mm256_loadu_pd(at_ptr(at[i]));
                // Lanes i, i + 1: [re_m, im_m, re_m+1, im_m+1] of each.
                let pair = |i: usize| _mm512_insertf64x4::<1>(_mm512_castpd256_pd512(q(i)), q(i + 1));
                let (p01, p23, p45, p67) = (pair(0), pair(2), pair(4), pair(6));
                // a = [re_m of lanes 0..3 | im_m of lanes 0..3], b the same for m + 1; c, d
                // lanes 4..7.
                let now = _mm512_setr_epi64(0, 4, 8, 12, 1, 5, 9, 13);
                let next = _mm512_setr_epi64(2, 6, 10, 14, 3, 7, 11, 15);
                let a = _mm512_permutex2var_pd(p01, now, p23);
                let b = _mm512_permutex2var_pd(p01, next, p23);
                let c = _mm512_permutex2var_pd(p45, now, p67);
                let d = _mm512_permutex2var_pd(p45, next, p67);
                let lo = |x, y| _mm512_shuffle_f64x2::<0x44>(x, y);
                let hi = |x, y| _mm512_shuffle_f64x2::<0xee>(x, y);
                ((cast(lo(a, c)), cast(hi(a, c))), (cast(lo(b, d)), cast(hi(b, d))))
            }
        }

        #[inline(always)]
        fn bits(self, m: Self::m64s) -> u32 {
            let b8(bits) = m;
            bits as u32
        }
    }
}

#[cfg(target_arch = "aarch64")]
mod arm {
    use std::arch::aarch64::*;

    use pulp::aarch64::Neon;
    use pulp::{cast, m64x2};

    use super::{MAX_W, Unit, Z, at_ptr};

    impl Unit for Neon {
        #[inline(always)]
        unsafe fn load_z(self, at: &[usize; MAX_W]) -> Z<Self> {
            // SAFETY: Neon proves NEON; the caller promises the addresses.
            unsafe {
                let (a, b) = (vld1q_f64(at_ptr(at[0])), vld1q_f64(at_ptr(at[1])));
                (cast(vzip1q_f64(a, b)), cast(vzip2q_f64(a, b)))
            }
        }

        #[inline(always)]
        fn bits(self, m: Self::m64s) -> u32 {
            let m: m64x2 = m;
            let [a, b]: [u64; 2] = cast(m);
            (a & 1) as u32 | ((b & 1) as u32) << 1
        }
    }
}

/// Runs [`orbits`] with the unit's target features enabled (pulp's `vectorize` compiles the
/// inlined loop for them).
struct Job<'a, 'b, U, F> {
    unit: U,
    p: &'a Perturbation,
    feed: &'b mut F,
    counters: &'b mut Counters,
}

impl<U: Unit, F: FnMut(Option<Held>, &mut Counters) -> Option<Held>> pulp::WithSimd for Job<'_, '_, U, F> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, _: S) {
        // `vectorize` passes the unit itself; its typed token is the one kept here.
        let (u, p, feed, c) = (self.unit, self.p, self.feed, self.counters);
        match (p.derivative, p.interior.is_some()) {
            (false, false) => run::<U, false, false, F>(u, p, feed, c),
            (true, false) => run::<U, true, false, F>(u, p, feed, c),
            (false, true) => run::<U, false, true, F>(u, p, feed, c),
            (true, true) => run::<U, true, true, F>(u, p, feed, c),
        }
    }
}

/// Iterates every sample as [`Perturbation::orbits`] promises, single steps above
/// `single_d2` in vector lanes of `level` and everything else in the scalar loop. Returns
/// false (doing nothing) where `level` has no vector lanes (scalar) or the CPU lacks it.
pub(super) fn orbits(
    p: &Perturbation,
    offsets: &[[f64; 2]],
    known: Option<&[Model]>,
    out: &mut [Orbit],
    counters: &mut Counters,
    level: SimdLevel,
    cancel: &AtomicBool,
) -> bool {
    let mut next = 0;
    // The series starts of the samples from `batch` on, worked out together (each sample's
    // alone is a chain of dependent operations: Series::starts).
    let mut batch = 0;
    let mut starts: Option<[Given; STARTS]> = None;
    let mut feed = |back: Option<Held>, counters: &mut Counters| -> Option<Held> {
        if let Some(h) = back
            && let Some(h) = p.resume(h, out, counters, cancel)
        {
            return Some(h);
        }
        while next < offsets.len() {
            let k = next;
            next += 1;
            if k % STARTS == 0 {
                batch = k;
                starts = p.series_starts::<STARTS>(&offsets[k..]);
            }
            let given = starts.as_mut().map(|s| (s[k - batch].0, s[k - batch].1.take()));
            if let Some(h) = p.begin(k, offsets[k], known.map(|m| m[k]), given, out, counters, cancel) {
                return Some(h);
            }
        }
        None
    };
    let feed = &mut feed;
    match level {
        #[cfg(target_arch = "x86_64")]
        SimdLevel::Avx2 => pulp::x86::V3::try_new().map(|unit| Simd::vectorize(unit, Job { unit, p, feed, counters })),
        #[cfg(target_arch = "x86_64")]
        SimdLevel::Avx512 => {
            pulp::x86::V4::try_new().map(|unit| Simd::vectorize(unit, Job { unit, p, feed, counters }))
        }
        #[cfg(target_arch = "aarch64")]
        SimdLevel::Neon => {
            pulp::aarch64::Neon::try_new().map(|unit| Simd::vectorize(unit, Job { unit, p, feed, counters }))
        }
        _ => None,
    }
    .is_some()
}

/// Where the reference orbits lie: each one's Z_0 as an address. Lane positions are
/// addresses, so one lane can read the Mandelbrot reference while its neighbour reads a
/// Julia set's orbit of 0 (another allocation); the addresses are exposed here and turned
/// back into pointers with `with_exposed_provenance` where they are read.
struct Refs {
    start: [i64; 2],
    park: usize,
}

impl Refs {
    fn new(p: &Perturbation) -> Refs {
        let mut start = [0; 2];
        for (w, r) in p.refs.iter().enumerate() {
            start[w] = r.words().as_ptr().expose_provenance() as i64;
        }
        Refs { start, park: PARK.as_ptr().expose_provenance() }
    }
}

/// One vector of lanes: the delta and offset, the derivative's mantissa and what a step
/// adds to it, the mantissa of |dz/dz|^2 and the bottom of its window, and which lanes hold
/// a sample. Positions are kept per lane in scalars, since
/// every lane advances one step at a time: `t16` counts the bytes stepped (16 per step),
/// lane i's Z_m lies at address `at0[i] + t16` and its iteration count is
/// `n0[i] + t16 / 16`, and the lane must leave when `t16` reaches `stop[i]` (the iteration
/// limit or the reference's end, whichever comes first).
#[derive(Clone, Copy)]
struct Lanes<S: Simd> {
    dzr: S::f64s,
    dzi: S::f64s,
    dcr: S::f64s,
    dci: S::f64s,
    der_r: S::f64s,
    der_i: S::f64s,
    add: S::f64s,
    shrink: S::f64s,
    shrink_lo: S::f64s,
    act: u32,
    /// Lanes whose samples have left interior detection ([`Lanes::put`]).
    plain: u32,
    /// Lanes that rebased in the lane and have not yet taken their first step from Z_0.
    fresh: u32,
    t16: i64,
    at0: [i64; MAX_W],
    n0: [i64; MAX_W],
    stop: [i64; MAX_W],
    /// The earliest stop of an active lane.
    next_stop: i64,
}

/// Lane `i` of a vector, for writing.
#[inline(always)]
fn lane<S: Simd>(v: &mut S::f64s, i: usize) -> &mut f64 {
    &mut bytemuck::cast_slice_mut::<S::f64s, f64>(std::slice::from_mut(v))[i]
}

impl<S: Simd> Lanes<S> {
    /// All lanes set: every active bit of a full vector.
    const FULL: u32 = (1 << S::F64_LANES) - 1;

    #[inline(always)]
    fn empty(simd: S) -> Lanes<S> {
        let z = simd.splat_f64s(0.0);
        Lanes {
            dzr: z,
            dzi: z,
            dcr: z,
            dci: z,
            der_r: z,
            der_i: z,
            add: z,
            shrink: z,
            shrink_lo: z,
            act: 0,
            plain: 0,
            fresh: 0,
            t16: 0,
            at0: [0; MAX_W],
            n0: [0; MAX_W],
            stop: [i64::MAX; MAX_W],
            next_stop: i64::MAX,
        }
    }

    /// Puts `h` into lane `i`.
    fn put(&mut self, i: usize, h: &Held, p: &Perturbation, refs: &Refs) {
        *lane::<S>(&mut self.dzr, i) = h.s.dz[0];
        *lane::<S>(&mut self.dzi, i) = h.s.dz[1];
        *lane::<S>(&mut self.dcr, i) = h.s.dc[0];
        *lane::<S>(&mut self.dci, i) = h.s.dc[1];
        *lane::<S>(&mut self.der_r, i) = h.der.mant[0];
        *lane::<S>(&mut self.der_i, i) = h.der.mant[1];
        *lane::<S>(&mut self.add, i) = h.der.add;
        // A sample that has left interior detection (`Probe::plain`) carries no |dz/dz|^2:
        // 0 times any step stays 0 (or NaN), which the window below -inf never lets out.
        let plain = h.s.probe.plain;
        *lane::<S>(&mut self.shrink, i) = if plain { 0.0 } else { h.s.shrink.mant };
        *lane::<S>(&mut self.shrink_lo, i) = if plain { f64::NEG_INFINITY } else { h.s.shrink.lo };
        self.place(i, h.s.which, h.s.m, h.s.n, p, refs);
        self.act |= 1 << i;
        self.plain = (self.plain & !(1 << i)) | (u32::from(plain) << i);
    }

    /// Writes lane `i`'s state back into `h` and empties the lane; returns the steps the
    /// sample took in it.
    fn take(&mut self, i: usize, h: &mut Held, refs: &Refs) -> u32 {
        h.s.dz = [*lane::<S>(&mut self.dzr, i), *lane::<S>(&mut self.dzi, i)];
        h.der.mant = [*lane::<S>(&mut self.der_r, i), *lane::<S>(&mut self.der_i, i)];
        if !h.s.probe.plain {
            h.s.shrink.mant = *lane::<S>(&mut self.shrink, i);
        }
        h.s.m = ((self.at0[i] + self.t16 - refs.start[h.s.which]) / 16) as u32;
        let n = (self.n0[i] + self.t16 / 16) as u32;
        let steps = n - h.s.n;
        h.s.n = n;
        self.act &= !(1 << i);
        self.fresh &= !(1 << i);
        self.plain &= !(1 << i);
        self.stop[i] = i64::MAX;
        steps
    }

    /// Sets lane i's position to Z_m of reference `which` with `n` iterations done, and its
    /// stop.
    fn place(&mut self, i: usize, which: usize, m: u32, n: u32, p: &Perturbation, refs: &Refs) {
        self.at0[i] = refs.start[which] + 16 * m as i64 - self.t16;
        self.n0[i] = n as i64 - self.t16 / 16;
        let left = (p.max_iter.saturating_sub(n)).min(p.refs[which].last().saturating_sub(m));
        self.stop[i] = self.t16 + 16 * left as i64;
        self.next_stop = self.next_stop.min(self.stop[i]);
    }

    /// Sets `next_stop` from every lane's stop, after stops moved later (a lane emptied
    /// or moved to another reference).
    fn restop(&mut self) {
        self.next_stop = self.stop.iter().copied().min().unwrap_or(i64::MAX);
    }

    /// Lanes whose stop has come.
    #[inline(always)]
    fn stopped(&self) -> u32 {
        let mut m = 0;
        for i in 0..S::F64_LANES {
            m |= ((self.stop[i] <= self.t16) as u32) << i;
        }
        m & self.act
    }

    /// Every lane's address of Z_m (empty lanes: the parking block).
    #[inline(always)]
    fn addresses(&self, refs: &Refs) -> [usize; MAX_W] {
        let mut at = [refs.park; MAX_W];
        for (i, a) in at.iter_mut().enumerate().take(S::F64_LANES) {
            if self.act & (1 << i) != 0 {
                *a = (self.at0[i] + self.t16) as usize;
            }
        }
        at
    }
}

/// Hands the samples of `lanes` in `mask` back to the scalar loop (`renorm`: for their
/// derivative's or |dz/dz|^2's renormalisation, or the interior verdict) and refills those
/// lanes from `feed`.
#[inline(never)]
fn hand_back<S: Simd>(
    lanes: &mut Lanes<S>,
    meta: &mut [Option<Held>; MAX_W],
    mask: u32,
    renorm: bool,
    p: &Perturbation,
    refs: &Refs,
    feed: &mut impl FnMut(Option<Held>, &mut Counters) -> Option<Held>,
    counters: &mut Counters,
) {
    for (i, slot) in meta.iter_mut().enumerate().take(S::F64_LANES) {
        if mask & (1 << i) == 0 {
            continue;
        }
        let Some(mut h) = slot.take() else { continue };
        let steps = lanes.take(i, &mut h, refs) as u64;
        counters.steps += steps;
        counters.iterations += steps;
        h.renorm = renorm;
        if let Some(h) = feed(Some(h), counters) {
            lanes.put(i, &h, p, refs);
            *slot = Some(h);
        }
    }
    lanes.restop();
}

/// Rebases the lanes of `mask` where they are, as `op` does: δ becomes the full value
/// (`fr`, `fi`) and the sample continues from Z_0 of the orbit of 0, leaving single-step
/// mode; the lane's next step is the one `op` takes after its rebase, and after it the
/// sample stays in the lane only if `op` would again choose a single step (see `fresh`).
#[inline(never)]
fn rebase<S: Simd>(
    lanes: &mut Lanes<S>,
    meta: &mut [Option<Held>; MAX_W],
    mask: u32,
    full: (S::f64s, S::f64s),
    p: &Perturbation,
    refs: &Refs,
    counters: &mut Counters,
) {
    let (mut fr, mut fi) = full;
    let which = p.refs.len() - 1;
    for (i, slot) in meta.iter_mut().enumerate().take(S::F64_LANES) {
        if mask & (1 << i) == 0 {
            continue;
        }
        let Some(h) = slot else { continue };
        *lane::<S>(&mut lanes.dzr, i) = *lane::<S>(&mut fr, i);
        *lane::<S>(&mut lanes.dzi, i) = *lane::<S>(&mut fi, i);
        h.s.which = which;
        h.s.single = false;
        let n = (lanes.n0[i] + lanes.t16 / 16) as u32;
        lanes.place(i, which, 0, n, p, refs);
        counters.rebases += 1;
    }
    lanes.fresh |= mask;
}

/// The constants a step uses.
#[derive(Clone, Copy)]
struct Consts<S: Simd> {
    esc2: S::f64s,
    two: S::f64s,
    single_d2: S::f64s,
    down: S::f64s,
    lo: S::f64s,
    hi: S::f64s,
    zero: S::f64s,
    tiny: S::f64s,
    four: S::f64s,
    shrink_hi: S::f64s,
}

/// The lanes' loop: fills every lane, steps them, hands samples back at events, until
/// `feed` has no more samples and every lane is empty.
#[inline(always)]
fn run<U: Unit, const DER: bool, const INT: bool, F: FnMut(Option<Held>, &mut Counters) -> Option<Held>>(
    unit: U,
    p: &Perturbation,
    feed: &mut F,
    counters: &mut Counters,
) {
    let refs = Refs::new(p);
    let mut meta: [[Option<Held>; MAX_W]; G] = [[None; MAX_W]; G];
    let mut lanes = [Lanes::<U>::empty(unit); G];
    for (l, m) in lanes.iter_mut().zip(meta.iter_mut()) {
        for (i, slot) in m.iter_mut().enumerate().take(U::F64_LANES) {
            if let Some(h) = feed(None, counters) {
                l.put(i, &h, p, &refs);
                *slot = Some(h);
            }
        }
    }
    let s = |x: f64| unit.splat_f64s(x);
    let k = Consts::<U> {
        esc2: s(p.escape2),
        two: s(2.0),
        single_d2: s(p.single_d2),
        down: s(DOWN),
        lo: s(DER_LO),
        hi: s(DER_HI),
        zero: s(0.0),
        tiny: s(DER_TINY_Z2),
        four: s(4.0),
        shrink_hi: s(p.interior.map_or(0.0, |c| c.hi)),
    };
    let full = Lanes::<U>::FULL;
    // Rebases inside bursts (see [`burst`]): f64 deltas only (a FloatExp view checks each
    // rebased delta against its range), and an orbit of 0 long enough that a rebased lane
    // has its two steps of a pair. With interior detection bursts run only while every
    // lane's sample has left it, and such a sample rebases as any other.
    let rebase_in_burst = p.numbers != Numbers::FloatExp && p.refs[p.refs.len() - 1].last() >= 2;
    // Where the bursts hold the lanes' addresses follows how often they rebase (speed only:
    // both give the same bits).
    let mut rate = Rate::new();
    while lanes.iter().any(|l| l.act != 0) {
        // With interior detection, bursts only while every lane's sample has left it (its
        // |dz/dz|^2 is not followed; the bursts' steps are then exactly `step`'s).
        if !INT || per_vector!(|g| lanes[g].act & !lanes[g].plain) == [0; G] {
            let moved = match (rebase_in_burst, rate.often()) {
                (true, true) => burst::<U, DER, true, true>(unit, &mut lanes, &k, &refs, p),
                (true, false) => burst::<U, DER, true, false>(unit, &mut lanes, &k, &refs, p),
                (false, _) => burst::<U, DER, false, false>(unit, &mut lanes, &k, &refs, p),
            };
            rate.add(&moved, U::F64_LANES);
            if moved.count != 0 {
                settle(&mut lanes, &mut meta, &moved, p, &refs, feed, counters);
            }
        }
        for (l, m) in lanes.iter_mut().zip(meta.iter_mut()) {
            if l.act == 0 {
                continue;
            }
            let at = l.addresses(&refs);
            if l.act == full && l.t16 + 32 <= l.next_stop {
                // Two steps from one 32-byte load per lane: every lane has at least two
                // steps before its stop, so Z_m+1 exists. The second step is skipped when
                // the first changed any lane (an event, a rebase, a hand-back).
                // SAFETY: every lane is active, `at[i]` is its Z_m's address, and Z_m+1
                // follows it in the same reference (m + 1 <= last, see above).
                let (z0, z1) = unsafe { unit.load_pair(&at) };
                if step::<U, DER, INT, F>(unit, l, m, z0, &k, p, &refs, feed, counters) {
                    step::<U, DER, INT, F>(unit, l, m, z1, &k, p, &refs, feed, counters);
                }
                continue;
            }
            // SAFETY: an active lane's address is its Z_m inside its reference (module
            // docs); an empty lane's is the parking block.
            let z = unsafe { unit.load_z(&at) };
            step::<U, DER, INT, F>(unit, l, m, z, &k, p, &refs, feed, counters);
        }
    }
}

/// One step of the lanes of `l` from Z_m = `z`: the end tests, then the step. Returns false
/// when it changed any lane's sample or position other than by the step (an event, a
/// rebase, a hand-back): values loaded ahead are then stale.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn step<U: Unit, const DER: bool, const INT: bool, F: FnMut(Option<Held>, &mut Counters) -> Option<Held>>(
    u: U,
    l: &mut Lanes<U>,
    m: &mut [Option<Held>; MAX_W],
    z: (U::f64s, U::f64s),
    k: &Consts<U>,
    p: &Perturbation,
    refs: &Refs,
    feed: &mut F,
    counters: &mut Counters,
) -> bool {
    let (zr, zi) = z;
    // The end tests of `op`: escape; rebase (|Z_m + δ| < |δ|); and, by the scalar clock, the
    // iteration limit and the reference's end. Pauldelbrot's glitch test needs no test of
    // its own: |Z_m + δ| < 10^-3 |Z_m| implies |δ| > 0.999 |Z_m| > |Z_m + δ|, a rebase (by a
    // margin no rounding can undo).
    let (fr, fi) = plus(u, (zr, zi), (l.dzr, l.dzi));
    let f2 = norm(u, (fr, fi));
    let d2 = norm(u, (l.dzr, l.dzi));
    let esc_m = u.greater_than_f64s(f2, k.esc2);
    let reb_m = u.less_than_f64s(f2, d2);
    // With the derivative or interior detection, a step from |z|^2 below DER_TINY_Z2 (the
    // same as `interior::TINY2`) is the scalar loop's (it updates both in FloatExp); with
    // interior detection, so is a pass that begins with |dz/dz|^2 out of its window (the
    // test at the top of `op`). All of them rare: one mask, and the parts only when it fires.
    let tiny_m = u.less_than_f64s(f2, k.tiny);
    let window_m = u.or_m64s(u.less_than_f64s(l.shrink, l.shrink_lo), u.greater_than_f64s(l.shrink, k.shrink_hi));
    let ev = match (DER || INT, INT) {
        (false, _) => u.or_m64s(esc_m, reb_m),
        // f2 < max(d2, TINY) is a rebase or a tiny step.
        (true, false) => u.or_m64s(esc_m, u.less_than_f64s(f2, u.max_f64s(d2, k.tiny))),
        (true, true) => u.or_m64s(u.or_m64s(esc_m, u.less_than_f64s(f2, u.max_f64s(d2, k.tiny))), window_m),
    };
    let stopped = if l.t16 >= l.next_stop { l.stopped() } else { 0 };
    if (u.bits(ev) & l.act) | stopped != 0 {
        let esc = u.bits(esc_m) & l.act;
        let reb = u.bits(reb_m) & l.act;
        // Steps for the scalar loop: tiny ones, and passes that begin unsettled.
        let tiny = if DER || INT { u.bits(tiny_m) & l.act } else { 0 };
        let tiny = if INT { tiny | (u.bits(window_m) & l.act) } else { tiny };
        // A plain rebase stays in the lane, unless it brings an f64 delta below the range
        // where FloatExp takes over (`op`'s switch).
        let mut here = reb & !esc & !stopped & !tiny;
        if p.numbers == Numbers::FloatExp {
            let big = u.max_f64s(u.abs_f64s(fr), u.abs_f64s(fi));
            here &= !u.bits(u.less_than_f64s(big, k.down));
        }
        let away = (esc | reb | stopped | tiny) & !here;
        if away != 0 {
            hand_back(l, m, away, false, p, refs, feed, counters);
        }
        if here != 0 {
            rebase(l, m, here, (fr, fi), p, refs, counters);
        }
        return false;
    }
    if DER {
        (l.der_r, l.der_i) = der_step(u, k, (fr, fi), (l.der_r, l.der_i), l.add);
    }
    if INT {
        // `Contraction::step`: the mantissa times 4 |z|^2.
        l.shrink = u.mul_f64s(l.shrink, u.mul_f64s(f2, k.four));
    }
    (l.dzr, l.dzi) = plain(u, k, (zr, zi), (l.dzr, l.dzi), (l.dcr, l.dci));
    l.t16 += 16;
    let mut renorm = 0;
    if DER {
        renorm = renorm_bits(u, k, (l.der_r, l.der_i)) & l.act;
    }

    let mut calm = true;
    if l.fresh != 0 {
        // After a rebase `op` takes a single step only if |δ|^2 > single_d2 (else it looks
        // for a BLA step): lanes below go back to the scalar loop.
        let d2 = norm(u, (l.dzr, l.dzi));
        let leave = !u.bits(u.greater_than_f64s(d2, k.single_d2)) & l.fresh;
        for (i, slot) in m.iter_mut().enumerate().take(U::F64_LANES) {
            if let Some(h) = slot
                && (l.fresh & !leave) & (1 << i) != 0
            {
                h.s.single = true;
            }
        }
        l.fresh = 0;
        if leave & !renorm != 0 {
            hand_back(l, m, leave & !renorm, false, p, refs, feed, counters);
            calm = false;
        }
    }
    if renorm != 0 {
        hand_back(l, m, renorm, true, p, refs, feed, counters);
        calm = false;
    }
    calm
}

/// Whether a step with delta `d` and full value `f` = Z_m + δ would be anything but a plain
/// step: [`step`]'s events without interior detection (escape, rebase, and with the
/// derivative a step from a tiny |z|).
#[inline(always)]
fn event<U: Unit, const DER: bool>(u: U, k: &Consts<U>, f: Z<U>, d: Z<U>) -> U::m64s {
    let f2 = norm(u, f);
    let d2 = norm(u, d);
    let low = if DER { u.max_f64s(d2, k.tiny) } else { d2 };
    u.or_m64s(u.greater_than_f64s(f2, k.esc2), u.less_than_f64s(f2, low))
}

/// Z_m + δ (the full value) from Z_m = `z` and δ = `d`.
#[inline(always)]
fn plus<U: Unit>(u: U, z: Z<U>, d: Z<U>) -> Z<U> {
    (u.add_f64s(z.0, d.0), u.add_f64s(z.1, d.1))
}

/// |v|^2, re^2 + im^2 in that order (the scalar loop's `norm2`).
#[inline(always)]
fn norm<U: Unit>(u: U, v: Z<U>) -> U::f64s {
    u.add_f64s(u.mul_f64s(v.0, v.0), u.mul_f64s(v.1, v.1))
}

/// The derivative's mantissa after a step from z = `f` (Z_m + δ): 2 z der + add.
#[inline(always)]
fn der_step<U: Unit>(u: U, k: &Consts<U>, f: Z<U>, der: Z<U>, add: U::f64s) -> Z<U> {
    let (a, b) = der;
    let re = u.sub_f64s(u.mul_f64s(f.0, a), u.mul_f64s(f.1, b));
    let im = u.add_f64s(u.mul_f64s(f.0, b), u.mul_f64s(f.1, a));
    (u.add_f64s(u.mul_f64s(k.two, re), add), u.mul_f64s(k.two, im))
}

/// `Der::renormalise`'s test of every lane: the larger part outside [DER_LO, DER_HI], not 0
/// (lane i at bit i; no bits beyond the lanes).
#[inline(always)]
fn renorm_bits<U: Unit>(u: U, k: &Consts<U>, der: Z<U>) -> u32 {
    let big = u.max_f64s(u.abs_f64s(der.0), u.abs_f64s(der.1));
    let inside = u.bits(u.greater_than_or_equal_f64s(big, k.lo)) & u.bits(u.less_than_or_equal_f64s(big, k.hi));
    let nonzero = !u.bits(u.equal_f64s(big, k.zero));
    nonzero & !inside & Lanes::<U>::FULL
}

/// δ <- (2 Z_m + δ) δ + δc, as [`step`] computes it. 2 Z_m + δ is one fused multiply-add:
/// 2 Z_m is exact, so fused or not it is the one rounding of the exact sum, the scalar
/// loop's bits, and the add ports (the busier ones) have one operation less.
#[inline(always)]
fn plain<U: Unit>(u: U, k: &Consts<U>, z: Z<U>, d: Z<U>, c: Z<U>) -> Z<U> {
    let xr = u.mul_add_e_f64s(z.0, k.two, d.0);
    let xi = u.mul_add_e_f64s(z.1, k.two, d.1);
    let nr = u.sub_f64s(u.mul_f64s(xr, d.0), u.mul_f64s(xi, d.1));
    let ni = u.add_f64s(u.mul_f64s(xr, d.1), u.mul_f64s(xi, d.0));
    (u.add_f64s(nr, c.0), u.add_f64s(ni, c.1))
}
