//! Single perturbation steps on AVX-512: eight samples to a vector, each at its own place in
//! the reference orbit.
//!
//! A deep view spends most of its time where BLA no longer helps a sample: once its delta
//! is above a tenth of the largest BLA radius it takes nothing but single steps until it
//! escapes or rebases (on the 1e50 benchmark ~11600 of them per sample). The scalar loop is
//! a chain of dependent multiplies (about 16 cycles of latency per step) that it can overlap
//! for two samples at most; here sixteen samples advance together, two vectors of eight.
//!
//! The lanes do only that one thing. A sample enters when the scalar loop
//! ([`Perturbation::begin`]) reaches a single step in single-step mode, and from then on
//! each step reads every lane's own Z_m (there is no common m: samples rebase and took BLA
//! steps of different lengths) with one 16-byte load per lane (a pair of gathers costs more
//! on Zen 4; while no lane is within two steps of its stop, one 32-byte load per lane serves
//! two steps), tests for anything that is not a plain step, and steps. A rebase that keeps
//! the sample in single steps happens in the lane. A lane that meets an escape, the
//! iteration limit, the reference's end, a rebase into FloatExp range or back to BLA steps,
//! or a derivative that leaves its exponent window hands its sample back to the scalar loop
//! ([`Perturbation::resume`]), which handles the event with its own code and returns the
//! sample (when it is again in single steps) or the next one. Nothing else leaves a lane,
//! so no lane idles while its neighbours run long. Positions are addresses kept per lane
//! in scalars (`at0[i] + t16`), and the iteration limit and the reference's end are a
//! per-lane stop on the same clock, tested once per step for the whole vector.
//!
//! The arithmetic is [`Perturbation::op`]'s, operation for operation and in the same order
//! (separate multiplies and adds, no fused multiply-add), so every sample ends bit for bit
//! as in the scalar loop; a test holds it to that.
//!
//! `unsafe` is confined to this file for two reasons: the loads and gathers read memory
//! through addresses (each lane reads inside its own reference orbit: its address is that
//! orbit's Z_0 plus 16 m bytes with m at most the orbit's last index, exposed by
//! [`Refs::new`]), and the kernel is compiled for AVX-512 and must be entered only after
//! run-time detection ([`available`]).
#![allow(unsafe_code)]

use std::arch::x86_64::*;

use super::{Counters, DER_HI, DER_LO, DER_TINY_Z2, DOWN, Held, Numbers, Perturbation};
use crate::field::Orbit;

/// Samples per vector.
const W: usize = 8;
/// Vectors in flight (their dependency chains overlap).
const G: usize = 2;

/// True when this CPU runs the kernel (AVX-512 F).
pub(super) fn available() -> bool {
    is_x86_feature_detected!("avx512f")
}

/// Iterates every sample as [`Perturbation::orbits`] promises, single steps above
/// `single_d2` in the lanes and everything else in the scalar loop.
pub(super) fn orbits(p: &Perturbation, offsets: &[[f64; 2]], out: &mut [Orbit], counters: &mut Counters) {
    let mut next = 0;
    let mut feed = |back: Option<Held>, counters: &mut Counters| -> Option<Held> {
        if let Some(h) = back
            && let Some(h) = p.resume(h, out, counters)
        {
            return Some(h);
        }
        while next < offsets.len() {
            let k = next;
            next += 1;
            if let Some(h) = p.begin(k, offsets[k], out, counters) {
                return Some(h);
            }
        }
        None
    };
    // SAFETY: `orbits` is reached only when `available()` found AVX-512 F.
    unsafe {
        if p.derivative {
            run::<true>(p, &mut feed, counters);
        } else {
            run::<false>(p, &mut feed, counters);
        }
    }
}

/// Where the reference orbits lie: each one's Z_0 as an address. Lane positions are
/// addresses, so one lane can read the Mandelbrot reference while its neighbour reads a
/// Julia set's orbit of 0 (another allocation); the addresses are exposed here and turned
/// back into pointers with `with_exposed_provenance` where they are read.
struct Refs {
    start: [i64; 2],
}

impl Refs {
    fn new(p: &Perturbation) -> Refs {
        let mut start = [0; 2];
        for (w, r) in p.refs.iter().enumerate() {
            start[w] = r.words().as_ptr().expose_provenance() as i64;
        }
        Refs { start }
    }
}

/// Eight lanes' state: the delta and offset, the derivative's mantissa and what a step
/// adds to it, and which lanes hold a sample. Positions are kept per lane in scalars, since
/// every lane advances one step at a time: `t16` counts the bytes stepped (16 per step),
/// lane i's Z_m lies at address `at0[i] + t16` and its iteration count is
/// `n0[i] + t16 / 16`, and the lane must leave when `t16` reaches `stop[i]` (the iteration
/// limit or the reference's end, whichever comes first).
#[derive(Clone, Copy)]
struct Lanes {
    dzr: __m512d,
    dzi: __m512d,
    dcr: __m512d,
    dci: __m512d,
    der_r: __m512d,
    der_i: __m512d,
    add: __m512d,
    act: __mmask8,
    /// Lanes that rebased in the lane and have not yet taken their first step from Z_0.
    fresh: __mmask8,
    t16: i64,
    at0: [i64; W],
    n0: [i64; W],
    stop: [i64; W],
    /// The earliest stop of an active lane.
    next_stop: i64,
}

impl Lanes {
    #[target_feature(enable = "avx512f")]
    fn empty() -> Lanes {
        let z = _mm512_setzero_pd();
        Lanes {
            dzr: z,
            dzi: z,
            dcr: z,
            dci: z,
            der_r: z,
            der_i: z,
            add: z,
            act: 0,
            fresh: 0,
            t16: 0,
            at0: [0; W],
            n0: [0; W],
            stop: [i64::MAX; W],
            next_stop: i64::MAX,
        }
    }

    /// Puts `h` into lane `i`.
    #[target_feature(enable = "avx512f")]
    fn put(&mut self, i: usize, h: &Held, p: &Perturbation, refs: &Refs) {
        let k = 1u8 << i;
        let f = |v: __m512d, x: f64| _mm512_mask_mov_pd(v, k, _mm512_set1_pd(x));
        self.dzr = f(self.dzr, h.s.dz[0]);
        self.dzi = f(self.dzi, h.s.dz[1]);
        self.dcr = f(self.dcr, h.s.dc[0]);
        self.dci = f(self.dci, h.s.dc[1]);
        self.der_r = f(self.der_r, h.der.mant[0]);
        self.der_i = f(self.der_i, h.der.mant[1]);
        self.add = f(self.add, h.der.add);
        self.place(i, h.s.which, h.s.m, h.s.n, p, refs);
        self.act |= k;
    }

    /// Writes lane `i`'s state back into `h` and empties the lane; returns the steps the
    /// sample took in it.
    #[target_feature(enable = "avx512f")]
    fn take(&mut self, i: usize, h: &mut Held, refs: &Refs) -> u32 {
        let k = 1u8 << i;
        let f = |v: __m512d| _mm512_cvtsd_f64(_mm512_maskz_compress_pd(k, v));
        h.s.dz = [f(self.dzr), f(self.dzi)];
        h.der.mant = [f(self.der_r), f(self.der_i)];
        h.s.m = ((self.at0[i] + self.t16 - refs.start[h.s.which]) / 16) as u32;
        let n = (self.n0[i] + self.t16 / 16) as u32;
        let steps = n - h.s.n;
        h.s.n = n;
        self.act &= !k;
        self.fresh &= !k;
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

    /// Lanes whose stop has come.
    fn stopped(&self) -> __mmask8 {
        let mut m = 0;
        for (i, &s) in self.stop.iter().enumerate() {
            m |= ((s <= self.t16) as u8) << i;
        }
        m & self.act
    }

    /// Byte offsets of every lane's Z_m, as a vector (for the gathers).
    #[target_feature(enable = "avx512f")]
    fn at(&self) -> __m512i {
        let a = self.at0.map(|x| x + self.t16);
        _mm512_setr_epi64(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7])
    }
}

/// Hands the samples of `lanes` in `mask` back to the scalar loop (`renorm`: for their
/// derivative's renormalisation) and refills those lanes from `feed`.
#[target_feature(enable = "avx512f")]
#[inline(never)]
fn hand_back(
    lanes: &mut Lanes,
    meta: &mut [Option<Held>; W],
    mask: __mmask8,
    renorm: bool,
    p: &Perturbation,
    refs: &Refs,
    feed: &mut impl FnMut(Option<Held>, &mut Counters) -> Option<Held>,
    counters: &mut Counters,
) {
    for (i, slot) in meta.iter_mut().enumerate() {
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
    lanes.next_stop = lanes.stop.iter().copied().min().unwrap_or(i64::MAX);
}

/// Rebases the lanes of `mask` where they are, as `op` does: δ becomes the full value
/// (`fr`, `fi`) and the sample continues from Z_0 of the orbit of 0, leaving single-step
/// mode; the lane's next step is the one `op` takes after its rebase, and after it the
/// sample stays in the lane only if `op` would again choose a single step (see `fresh`).
#[target_feature(enable = "avx512f")]
#[inline(never)]
fn rebase(
    lanes: &mut Lanes,
    meta: &mut [Option<Held>; W],
    mask: __mmask8,
    full: (__m512d, __m512d),
    p: &Perturbation,
    refs: &Refs,
    counters: &mut Counters,
) {
    lanes.dzr = _mm512_mask_mov_pd(lanes.dzr, mask, full.0);
    lanes.dzi = _mm512_mask_mov_pd(lanes.dzi, mask, full.1);
    let which = p.refs.len() - 1;
    for (i, slot) in meta.iter_mut().enumerate() {
        if mask & (1 << i) == 0 {
            continue;
        }
        let Some(h) = slot else { continue };
        h.s.which = which;
        h.s.single = false;
        let n = (lanes.n0[i] + lanes.t16 / 16) as u32;
        lanes.place(i, which, 0, n, p, refs);
        counters.rebases += 1;
    }
    lanes.fresh |= mask;
}

/// Z_m of all eight lanes, as (re, im) vectors: one 16-byte load per lane at address
/// `at0[i] + t16`, paired into two vectors and split by two permutes (cheaper than two
/// gathers).
///
/// # Safety
/// Every `at0[i] + t16` must be the address of a Z_m inside a reference orbit.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn load_full(at0: &[i64; W], t16: i64, even: __m512i, odd: __m512i) -> (__m512d, __m512d) {
    // SAFETY: the caller's promise; the address was exposed by `Refs::new`.
    let q = |i: usize| unsafe { _mm_loadu_pd(std::ptr::with_exposed_provenance::<f64>((at0[i] + t16) as usize)) };
    let lo =
        _mm512_insertf64x4::<1>(_mm512_castpd256_pd512(_mm256_set_m128d(q(1), q(0))), _mm256_set_m128d(q(3), q(2)));
    let hi =
        _mm512_insertf64x4::<1>(_mm512_castpd256_pd512(_mm256_set_m128d(q(5), q(4))), _mm256_set_m128d(q(7), q(6)));
    (_mm512_permutex2var_pd(lo, even, hi), _mm512_permutex2var_pd(lo, odd, hi))
}

/// The lanes' loop: fills every lane, steps them, hands samples back at events, until
/// `feed` has no more samples and every lane is empty.
///
/// # Safety
/// The CPU must have AVX-512 F.
#[target_feature(enable = "avx512f")]
unsafe fn run<const DER: bool>(
    p: &Perturbation,
    feed: &mut impl FnMut(Option<Held>, &mut Counters) -> Option<Held>,
    counters: &mut Counters,
) {
    let refs = Refs::new(p);
    let mut meta: [[Option<Held>; W]; G] = [[None; W]; G];
    let mut lanes = [Lanes::empty(); G];
    for (l, m) in lanes.iter_mut().zip(meta.iter_mut()) {
        for (i, slot) in m.iter_mut().enumerate() {
            if let Some(h) = feed(None, counters) {
                l.put(i, &h, p, &refs);
                *slot = Some(h);
            }
        }
    }
    let k = Consts {
        esc2: _mm512_set1_pd(p.escape2),
        two: _mm512_set1_pd(2.0),
        single_d2: _mm512_set1_pd(p.single_d2),
        down: _mm512_set1_pd(DOWN),
        lo: _mm512_set1_pd(DER_LO),
        hi: _mm512_set1_pd(DER_HI),
        zero: _mm512_setzero_pd(),
        tiny: _mm512_set1_pd(DER_TINY_Z2),
    };
    let even = _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14);
    let odd = _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15);
    let eight = _mm512_set1_epi64(8);
    while lanes.iter().any(|l| l.act != 0) {
        for (l, m) in lanes.iter_mut().zip(meta.iter_mut()) {
            if l.act == 0 {
                continue;
            }
            if l.act == 0xff && l.t16 + 32 <= l.next_stop {
                // Two steps from one 32-byte load per lane: every lane has at least two
                // steps before its stop, so Z_m+1 exists. The second step is skipped when
                // the first changed any lane (an event, a rebase, a hand-back).
                // SAFETY: every lane is active, at0[i] + t16 is its Z_m's address, and
                // Z_m+1 follows it in the same reference (m + 1 <= last, see above).
                let (z0, z1) = unsafe { load_pair(&l.at0, l.t16) };
                if step::<DER, _>(l, m, z0, &k, p, &refs, feed, counters) {
                    step::<DER, _>(l, m, z1, &k, p, &refs, feed, counters);
                }
                continue;
            }
            let z = if l.act == 0xff {
                // SAFETY: every lane is active, and at0[i] + t16 is its Z_m's address.
                unsafe { load_full(&l.at0, l.t16, even, odd) }
            } else {
                let at = l.at();
                // SAFETY: active lanes' addresses point at Z_m inside their own reference
                // (see the module docs; the base is 0, so the gathers read those addresses);
                // inactive lanes are masked off and read nothing.
                unsafe {
                    (
                        _mm512_mask_i64gather_pd::<1>(k.zero, l.act, at, std::ptr::null()),
                        _mm512_mask_i64gather_pd::<1>(k.zero, l.act, _mm512_add_epi64(at, eight), std::ptr::null()),
                    )
                }
            };
            step::<DER, _>(l, m, z, &k, p, &refs, feed, counters);
        }
    }
}

/// The constants a step uses.
struct Consts {
    esc2: __m512d,
    two: __m512d,
    single_d2: __m512d,
    down: __m512d,
    lo: __m512d,
    hi: __m512d,
    zero: __m512d,
    tiny: __m512d,
}

/// Z_m and Z_m+1 of all eight lanes, as ((re, im), (re, im)) vectors: one 32-byte load per
/// lane, paired, then split by four two-source permutes and four 128-bit shuffles.
///
/// # Safety
/// Every `at0[i] + t16` must be the address of a Z_m, and Z_m+1 must exist in the same
/// reference orbit.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn load_pair(at0: &[i64; W], t16: i64) -> ((__m512d, __m512d), (__m512d, __m512d)) {
    // SAFETY: the caller's promise; the address was exposed by `Refs::new`.
    let q = |i: usize| unsafe { _mm256_loadu_pd(std::ptr::with_exposed_provenance::<f64>((at0[i] + t16) as usize)) };
    // Lanes i, i + 1: [re_m, im_m, re_m+1, im_m+1] of each.
    let pair = |i: usize| _mm512_insertf64x4::<1>(_mm512_castpd256_pd512(q(i)), q(i + 1));
    let (p01, p23, p45, p67) = (pair(0), pair(2), pair(4), pair(6));
    // a = [re_m of lanes 0..3 | im_m of lanes 0..3], b the same for m + 1; c, d lanes 4..7.
    let now = _mm512_setr_epi64(0, 4, 8, 12, 1, 5, 9, 13);
    let next = _mm512_setr_epi64(2, 6, 10, 14, 3, 7, 11, 15);
    let a = _mm512_permutex2var_pd(p01, now, p23);
    let b = _mm512_permutex2var_pd(p01, next, p23);
    let c = _mm512_permutex2var_pd(p45, now, p67);
    let d = _mm512_permutex2var_pd(p45, next, p67);
    let lo = |x, y| _mm512_shuffle_f64x2::<0x44>(x, y);
    let hi = |x, y| _mm512_shuffle_f64x2::<0xee>(x, y);
    ((lo(a, c), hi(a, c)), (lo(b, d), hi(b, d)))
}

/// One step of the eight lanes of `l` from Z_m = `z`: the end tests, then the step. Returns
/// false when it changed any lane's sample or position other than by the step (an event,
/// a rebase, a hand-back): values loaded ahead are then stale.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn step<const DER: bool, F: FnMut(Option<Held>, &mut Counters) -> Option<Held>>(
    l: &mut Lanes,
    m: &mut [Option<Held>; W],
    z: (__m512d, __m512d),
    k: &Consts,
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
    // SAFETY: `step` is inlined into `run`, its only caller, which has AVX-512 F enabled.
    unsafe {
        let fr = _mm512_add_pd(zr, l.dzr);
        let fi = _mm512_add_pd(zi, l.dzi);
        let f2 = _mm512_add_pd(_mm512_mul_pd(fr, fr), _mm512_mul_pd(fi, fi));
        let d2 = _mm512_add_pd(_mm512_mul_pd(l.dzr, l.dzr), _mm512_mul_pd(l.dzi, l.dzi));
        let esc = _mm512_mask_cmp_pd_mask::<_CMP_GT_OQ>(l.act, f2, k.esc2);
        let reb = _mm512_mask_cmp_pd_mask::<_CMP_LT_OQ>(l.act, f2, d2);
        let stopped = if l.t16 >= l.next_stop { l.stopped() } else { 0 };
        // With the derivative, a step from |z|^2 below DER_TINY_Z2 is the scalar loop's (it
        // updates the derivative in FloatExp).
        let tiny = if DER { _mm512_mask_cmp_pd_mask::<_CMP_LT_OQ>(l.act, f2, k.tiny) } else { 0 };
        if esc | reb | stopped | tiny != 0 {
            // A plain rebase stays in the lane, unless it brings an f64 delta below the
            // range where FloatExp takes over (`op`'s switch).
            let mut here = reb & !esc & !stopped & !tiny;
            if p.numbers == Numbers::FloatExp {
                let big = _mm512_max_pd(_mm512_abs_pd(fr), _mm512_abs_pd(fi));
                here &= !_mm512_cmp_pd_mask::<_CMP_LT_OQ>(big, k.down);
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
            let (a, b) = (l.der_r, l.der_i);
            let re = _mm512_sub_pd(_mm512_mul_pd(fr, a), _mm512_mul_pd(fi, b));
            let im = _mm512_add_pd(_mm512_mul_pd(fr, b), _mm512_mul_pd(fi, a));
            l.der_r = _mm512_add_pd(_mm512_mul_pd(k.two, re), l.add);
            l.der_i = _mm512_mul_pd(k.two, im);
        }
        // δ <- (2 Z_m + δ) δ + δc.
        let ar = _mm512_add_pd(_mm512_mul_pd(zr, k.two), l.dzr);
        let ai = _mm512_add_pd(_mm512_mul_pd(zi, k.two), l.dzi);
        let nr = _mm512_sub_pd(_mm512_mul_pd(ar, l.dzr), _mm512_mul_pd(ai, l.dzi));
        let ni = _mm512_add_pd(_mm512_mul_pd(ar, l.dzi), _mm512_mul_pd(ai, l.dzr));
        l.dzr = _mm512_add_pd(nr, l.dcr);
        l.dzi = _mm512_add_pd(ni, l.dci);
        l.t16 += 16;
        let mut renorm = 0;
        if DER {
            // `Der::renormalise`'s test: the larger part outside [DER_LO, DER_HI], not 0.
            let big = _mm512_max_pd(_mm512_abs_pd(l.der_r), _mm512_abs_pd(l.der_i));
            let inside = _mm512_mask_cmp_pd_mask::<_CMP_GE_OQ>(l.act, big, k.lo)
                & _mm512_mask_cmp_pd_mask::<_CMP_LE_OQ>(l.act, big, k.hi);
            renorm = _mm512_mask_cmp_pd_mask::<_CMP_NEQ_UQ>(l.act, big, k.zero) & !inside;
        }
        let mut calm = true;
        if l.fresh != 0 {
            // After a rebase `op` takes a single step only if |δ|^2 > single_d2 (else it looks
            // for a BLA step): lanes below go back to the scalar loop.
            let d2 = _mm512_add_pd(_mm512_mul_pd(l.dzr, l.dzr), _mm512_mul_pd(l.dzi, l.dzi));
            let leave = _mm512_mask_cmp_pd_mask::<_CMP_NGT_UQ>(l.fresh, d2, k.single_d2);
            for (i, slot) in m.iter_mut().enumerate() {
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
}
