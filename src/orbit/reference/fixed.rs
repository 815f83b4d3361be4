//! The reference orbit's step z -> z^2 + c in fixed point on machine words: no allocation per
//! step, squarings that compute only the high half of their products, and the three
//! squarings of a step shared among a team of threads where the precision makes it pay.
//!
//! A reference orbit never leaves a small disc: it stops once |z| passes the escape radius R,
//! so every value it squares is below R and every value it stores below R^2 + |c|. Fixed
//! point with one 64-bit integer limb (two's complement) then holds the whole orbit, with
//! R up to 2^30 and |c|, |z_0| up to 2^30 ([`FixedOrbit::new`] refuses anything else, and
//! the reference falls back to malachite's floats). Absolute precision is what perturbation
//! needs: rounding Z_m by 2^-F changes the orbit as moving c by about 2^-F would, so F =
//! the view's bits plus a guard limb keeps the reference exact to far below a sample's
//! spacing, wherever the orbit passes (near 0 included, where a float would keep relative
//! precision that nothing downstream uses).
//!
//! One step is x' = x^2 - y^2 + cx, y' = (x + y)^2 - x^2 - y^2 + cy: three squarings of
//! magnitudes, each a short product (only the columns that reach the kept limbs; the
//! dropped ones change them by less than a unit of the lowest, far inside the guard limb).
//! Up to [`comba::MAX_LIMBS`] limbs the squares run on 64-bit limbs column by column
//! ([`comba`]); beyond, on 26-bit digits in vector lanes ([`square`]), which overtake it
//! there. The choice depends on the limb count only, so every instruction set gives the
//! same bits. With helper threads (a team, [`super::team`]), each thread keeps its own copy
//! of the orbit and computes its pieces of the three squares (columns, or rows of digits:
//! with two threads, the caller squares x and the lower part of (x + y)^2, the helper y and
//! the upper part), each publishes what it computed and takes everyone else's, and all join
//! the pieces exactly and finish the same step: the same bits as one thread, with one
//! hand-over each way per step, made at the same moment (a request and an answer would put
//! two cross-core latencies, ~0.2 µs each on a 2-core machine, in every step). Where the
//! machine is busier than its cores, a helper is often descheduled and every step would
//! wait for it: there the caller steps alone for stretches ([`super::handover`]).
//! `cargo bench --bench reference` compares this with malachite-float (and MPFR through
//! rug with the `mpfr` feature) at 1000, 2000, 4000 and 16000 bits. Below the widths where
//! sharing a step pays, a helper thread instead steps the orbit ahead in batches while the
//! caller keeps the values ([`FixedOrbit::for_each_value`]): the same values, in order.

use std::ops::Range;
use std::sync::atomic::Ordering;

use malachite_base::num::conversion::traits::RoundingFrom;
use malachite_base::rounding_modes::RoundingMode;
use malachite_float::Float;
use malachite_nz::integer::Integer;

use super::comba;
use super::cycle::Brent;
use super::handover::{self, Contention, Shared, StopOnDrop};
use super::square::{self, Layout};
use super::team::{self, Piece};
use crate::num::FloatExp;
use crate::simd_level::SimdLevel;

/// Largest escape radius, |c| and |z_0| fixed point takes: squares of values below 2^30 and
/// sums of a few of them stay below 2^63, the integer limb's range.
pub const MAX_MAGNITUDE: f64 = (1u64 << 30) as f64;

/// Limb count from which two threads share a step (below, handing the work over costs more
/// than it saves; `cargo bench --bench reference`).
pub const THREADED_LIMBS: usize = 24;

/// Most threads that share one orbit's steps. Each step hands every thread's pieces to every
/// other, so the hand-over grows with the team while each share shrinks; on the 2-core
/// machines here only a team of two could be timed, and this bound is a guess at where more
/// threads stop paying at the depths measured (docs/performance.md models it).
pub const MAX_TEAM: usize = 8;

/// Values per batch a pipelined orbit's helper hands over ([`FixedOrbit::for_each_value`]),
/// and batches it may run ahead.
const PIPELINE_BATCH: usize = 2048;
const PIPELINE_BATCHES: usize = 4;

/// An orbit z_0, z_1, ... of z -> z^2 + c in fixed point: n 64-bit limbs per real, little
/// endian, two's complement, value = X / 2^(64 (n - 1)).
#[derive(Debug, Clone)]
pub struct FixedOrbit {
    n: usize,
    x: Vec<u64>,
    y: Vec<u64>,
    cx: Vec<u64>,
    cy: Vec<u64>,
    /// How the squares are computed.
    kernel: Kernel,
    /// The instruction set the squares run with.
    simd: SimdLevel,
    /// Work space of a step, allocated once.
    w: Work,
}

/// How an n-limb square is computed.
#[derive(Debug, Clone, Copy)]
enum Kernel {
    /// 64-bit limbs, column by column ([`comba`]).
    Limbs { n: usize },
    /// 26-bit digits in vector lanes ([`square`]).
    Digits { layout: Layout },
}

/// A squaring's scratch: the digits and column sums of a square in progress.
#[derive(Debug, Clone)]
struct Scratch {
    digits: Vec<u32>,
    acc: Vec<u64>,
}

impl Kernel {
    /// The kernel for n-limb magnitudes, or None beyond [`square::MAX_DIGITS`].
    fn new(n: usize) -> Option<Kernel> {
        if (2..=comba::MAX_LIMBS).contains(&n) {
            return Some(Kernel::Limbs { n });
        }
        Some(Kernel::Digits { layout: Layout::new(n)? })
    }

    fn scratch(self) -> Scratch {
        let (digits, acc) = match self {
            Kernel::Limbs { .. } => (Vec::new(), Vec::new()),
            Kernel::Digits { layout } => (vec![0; layout.digit_len()], vec![0; layout.columns()]),
        };
        Scratch { digits, acc }
    }

    /// Where a square may be cut between threads, with the products before each cut
    /// ([`team::plan`]): columns, or starts of blocks of rows.
    fn cuts(self) -> Vec<(usize, usize)> {
        match self {
            Kernel::Limbs { n } => comba::cuts(n),
            Kernel::Digits { layout } => layout.cuts(),
        }
    }

    /// Words of a piece of a square ([`Kernel::piece`]).
    fn piece_len(self) -> usize {
        match self {
            // n + 1 limbs, and room for a carry after the last.
            Kernel::Limbs { n } => n + 3,
            Kernel::Digits { layout } => layout.columns(),
        }
    }

    /// The words of a piece over `range` that hold something: what a shared step hands
    /// over.
    fn piece_words(self, range: &Range<usize>) -> Range<usize> {
        match self {
            // The columns' limbs, and the carry out of the last after them.
            Kernel::Limbs { n } => {
                let from = comba::limb_of_column(n, range.start.max(n - 2));
                from..comba::limb_of_column(n, range.end) + 2
            }
            Kernel::Digits { layout } => 0..layout.columns(),
        }
    }

    /// Limbs n - 2 .. 2n - 2 of a^2 into `out`.
    fn square(self, a: &[u64], w: &mut Scratch, out: &mut [u64], simd: SimdLevel) {
        match self {
            Kernel::Limbs { .. } => comba::square(a, out),
            Kernel::Digits { layout } => square::square(layout, a, &mut w.digits, &mut w.acc, out, simd),
        }
    }

    /// One piece of a square of `a` shared between threads, into `piece` ([`Kernel::piece_len`]
    /// words): the limbs of the columns in `range` and the carry out of them (after their
    /// limbs), or the column sums of the blocks of rows starting in `range`.
    fn piece(self, range: Range<usize>, a: &[u64], w: &mut Scratch, piece: &mut [u64], simd: SimdLevel) {
        match self {
            Kernel::Limbs { n } => {
                let end = range.end;
                let carry = comba::columns(a, range, piece);
                let at = comba::limb_of_column(n, end);
                piece[at..at + 2].copy_from_slice(&carry);
            }
            Kernel::Digits { layout } => {
                square::digits(a, &mut w.digits);
                piece.fill(0);
                square::rows(layout, &w.digits, range, piece, simd);
            }
        }
    }

    /// Joins the pieces of a shared square of `a` (every range of its cuts once, in order)
    /// into `out`: the square, exactly as [`Kernel::square`] gives it.
    fn join<'p>(
        self,
        pieces: impl Iterator<Item = (&'p Range<usize>, &'p [u64])> + Clone,
        a: &[u64],
        w: &mut Scratch,
        out: &mut [u64],
    ) {
        match self {
            Kernel::Limbs { n } => {
                // Every piece's limbs first, then the carries, each into the limbs above it.
                for (range, piece) in pieces.clone() {
                    let words = self.piece_words(range);
                    let limbs = words.start..words.end - 2;
                    out[limbs.clone()].copy_from_slice(&piece[limbs]);
                }
                for (range, piece) in pieces {
                    let at = comba::limb_of_column(n, range.end);
                    if range.end < comba::end_column(n) {
                        comba::add_carry(n, range.end, [piece[at], piece[at + 1]], out);
                    }
                }
            }
            Kernel::Digits { layout } => {
                square::digits(a, &mut w.digits);
                w.acc.fill(0);
                for (_, piece) in pieces {
                    for (v, &p) in w.acc.iter_mut().zip(piece) {
                        *v += p;
                    }
                }
                square::finish(layout, &w.digits, &mut w.acc);
                square::pack(layout, &w.acc, out);
            }
        }
    }
}

/// A step's work space: the magnitudes |x|, |y|, |x + y| it squares (n limbs) and
/// their squares (n + 1 limbs, from limb n - 2 of the full product), and the squaring's
/// scratch.
#[derive(Debug, Clone)]
struct Work {
    ax: Vec<u64>,
    ay: Vec<u64>,
    asum: Vec<u64>,
    x2: Vec<u64>,
    y2: Vec<u64>,
    s2: Vec<u64>,
    scratch: Scratch,
}

impl Work {
    fn new(n: usize, kernel: Kernel) -> Work {
        let v = |k: usize| vec![0; k];
        Work { ax: v(n), ay: v(n), asum: v(n), x2: v(n + 1), y2: v(n + 1), s2: v(n + 1), scratch: kernel.scratch() }
    }
}

/// |x|, |y| and x + y (mod 2^(64 n)) of two's complement numbers, in one pass: three
/// independent carry chains per limb rather than a pass each (as nine passes, a step's
/// bookkeeping took about a tenth of a 60-limb step in a profile: docs/engine-notes.md).
fn magnitudes_and_sum(x: &[u64], y: &[u64], ax: &mut [u64], ay: &mut [u64], sum: &mut [u64]) {
    let negative = |a: &[u64]| a.last().is_some_and(|&t| t >> 63 == 1);
    // Negation is the complement plus one: xor with the mask, and the mask's 1 as carry in.
    let (mx, my) = (0u64.wrapping_sub(negative(x) as u64), 0u64.wrapping_sub(negative(y) as u64));
    let (mut cx, mut cy, mut cs) = (mx & 1 == 1, my & 1 == 1, false);
    for ((((&a, &b), ox), oy), os) in x.iter().zip(y).zip(ax).zip(ay).zip(sum) {
        (*ox, cx) = (a ^ mx).carrying_add(0, cx);
        (*oy, cy) = (b ^ my).carrying_add(0, cy);
        (*os, cs) = a.carrying_add(b, cs);
    }
}

/// |a| of a two's complement number, in place.
fn magnitude_in_place(a: &mut [u64]) {
    if a.last().is_some_and(|&t| t >> 63 == 1) {
        let mut carry = true;
        for x in a.iter_mut() {
            (*x, carry) = (!*x).carrying_add(0, carry);
        }
    }
}

/// a - b + c (mod 2^(64 n)) into `out`, in one pass.
fn sub_add(a: &[u64], b: &[u64], c: &[u64], out: &mut [u64]) {
    let (mut borrow, mut carry) = (false, false);
    for (((&a, &b), &c), o) in a.iter().zip(b).zip(c).zip(out) {
        let t;
        (t, borrow) = a.borrowing_sub(b, borrow);
        (*o, carry) = t.carrying_add(c, carry);
    }
}

/// a - b - c + d (mod 2^(64 n)) into `out`, in one pass.
fn sub_sub_add(a: &[u64], b: &[u64], c: &[u64], d: &[u64], out: &mut [u64]) {
    let (mut b1, mut b2, mut carry) = (false, false, false);
    for ((((&a, &b), &c), &d), o) in a.iter().zip(b).zip(c).zip(d).zip(out) {
        let (t, u);
        (t, b1) = a.borrowing_sub(b, b1);
        (u, b2) = t.borrowing_sub(c, b2);
        (*o, carry) = u.carrying_add(d, carry);
    }
}

impl FixedOrbit {
    /// Limbs for `bits` of precision: the fractional limbs cover `bits` plus 8 guard bits
    /// (the truncated squares lose fewer than log2(n) bits at the bottom, and `bits`
    /// already holds the view's margin), and one integer limb.
    pub fn limbs_for(bits: u64) -> usize {
        (bits as usize + 8).div_ceil(64) + 1
    }

    /// The orbit from `start` with parameter `c` at `bits` of precision, its squares run
    /// with instruction set `simd` (the same bits with every one); None when a value or
    /// `escape` is beyond [`MAX_MAGNITUDE`] (or not finite), or the precision beyond the
    /// squaring's ([`square::MAX_DIGITS`], about 100000 bits).
    pub fn new(start: &[Float; 2], c: &[Float; 2], bits: u64, escape: f64, simd: SimdLevel) -> Option<FixedOrbit> {
        if escape.is_nan() || escape > MAX_MAGNITUDE {
            return None;
        }
        let n = Self::limbs_for(bits);
        let kernel = Kernel::new(n)?;
        let conv = |v: &Float| to_fixed(v, n);
        let (x, y, cx, cy) = (conv(&start[0])?, conv(&start[1])?, conv(&c[0])?, conv(&c[1])?);
        Some(FixedOrbit { n, x, y, cx, cy, kernel, simd, w: Work::new(n, kernel) })
    }

    /// Limbs per real.
    pub fn limbs(&self) -> usize {
        self.n
    }

    /// The current z.
    pub fn get(&self) -> [FloatExp; 2] {
        [to_floatexp(&self.x), to_floatexp(&self.y)]
    }

    /// Whether z is exactly `saved` (words of x, then of y, as [`FixedOrbit::save`] wrote).
    fn is(&self, saved: &[u64]) -> bool {
        saved.len() == 2 * self.n && saved[..self.n] == self.x[..] && saved[self.n..] == self.y[..]
    }

    /// Writes z's words into `saved` (x, then y).
    fn save(&self, saved: &mut Vec<u64>) {
        saved.clear();
        saved.extend_from_slice(&self.x);
        saved.extend_from_slice(&self.y);
    }

    /// |x|, |y| and |x + y| into the work space.
    fn inputs(&mut self) {
        let w = &mut self.w;
        magnitudes_and_sum(&self.x, &self.y, &mut w.ax, &mut w.ay, &mut w.asum);
        magnitude_in_place(&mut w.asum);
    }

    /// z <- z^2 + c from the three squares in the work space (the kept n limbs are 1..=n).
    fn finish(&mut self) {
        let w = &self.w;
        let (x2, y2, s2) = (&w.x2[1..], &w.y2[1..], &w.s2[1..]);
        // x' = x^2 - y^2 + cx
        sub_add(x2, y2, &self.cx, &mut self.x);
        // y' = (x + y)^2 - x^2 - y^2 + cy
        sub_sub_add(s2, x2, y2, &self.cy, &mut self.y);
    }

    /// One step, z <- z^2 + c, on this thread.
    pub fn step(&mut self) {
        self.inputs();
        let (k, simd, w) = (self.kernel, self.simd, &mut self.w);
        k.square(&w.ax, &mut w.scratch, &mut w.x2, simd);
        k.square(&w.ay, &mut w.scratch, &mut w.y2, simd);
        k.square(&w.asum, &mut w.scratch, &mut w.s2, simd);
        self.finish();
    }

    /// Runs `body` with a stepper that shares each step with helper threads where the orbit
    /// is wide enough for that to pay ([`THREADED_LIMBS`]) and `share` allows it (a team of
    /// [`FixedOrbit::team_size`] threads), else steps on this thread alone. The results are
    /// the same bits either way.
    pub fn with_stepper<R>(&mut self, share: bool, body: impl FnOnce(&mut Stepper<'_>) -> R) -> R {
        // The team's size (a query of the machine's cores) only where sharing is possible.
        let team = if share && self.n >= THREADED_LIMBS { self.team_size() } else { 1 };
        if team >= 2 {
            self.with_team(team, Policy::Adaptive(Contention::default()), body)
        } else {
            body(&mut Stepper { orbit: self, sharing: None })
        }
    }

    /// Threads that share this orbit's steps: the threads free (the caller's thread pool,
    /// a render's `--threads`, and the machine's cores), at most [`MAX_TEAM`], and at most
    /// as many as leave each thread as many products of a step as two threads have at
    /// [`THREADED_LIMBS`] limbs (where sharing starts to pay).
    pub fn team_size(&self) -> usize {
        let cores = std::thread::available_parallelism().map_or(1, |p| p.get());
        let free = cores.min(rayon::current_num_threads()).min(MAX_TEAM);
        let products = |k: Kernel| k.cuts().last().map_or(0, |c| c.1);
        let least = Kernel::new(THREADED_LIMBS).map_or(1, products) * team::SQUARES / 2;
        let most = products(self.kernel) * team::SQUARES / least.max(1);
        free.min(most.max(1))
    }

    /// Hands Z_0, Z_1, ... to `keep` in order until it returns true (or an error);
    /// `escape2` and `max_iter` are where the orbit ends in any case (|Z_n|^2 above it in
    /// f64, n at it), so no step runs past an escape. On one thread it steps only as far as
    /// `keep` asks; pipelined, up to a few batches further, which changes nothing kept.
    ///
    /// Up to index `detect_until` each z is also compared with one remembered value (Brent's
    /// cycle detection: the value is renewed at indices 1, 2, 4, 8, ...): once z_n is
    /// exactly z_(n-q), every bit of the orbit from there repeats with period q, so the
    /// orbit stops there with `Some(q)` after `keep` saw z_n. An orbit that only comes close
    /// to repeating (slow escapes, repelling cycles) is never cut: equality is of every
    /// word of the fixed-point state.
    ///
    /// Where a step is too narrow to share ([`THREADED_LIMBS`]) but two threads are free
    /// and `share` allows it, a helper thread steps the orbit ahead in batches while this
    /// one keeps the values: keeping (the period test, rounding to f64, storing) costs
    /// about half as much as a narrow step, and the two then overlap. A helper that ran
    /// ahead of the end stops at the next batch. The values, and so the orbit kept, are the
    /// same bits either way.
    pub fn for_each_value<E>(
        &mut self,
        share: bool,
        escape2: f64,
        max_iter: u32,
        detect_until: u32,
        mut keep: impl FnMut(u32, [FloatExp; 2]) -> Result<bool, E>,
    ) -> Result<Option<u32>, E> {
        if !(share && self.n < THREADED_LIMBS && two_threads()) {
            return self.with_stepper(share, |s| {
                let mut n = 0u32;
                let mut cycle = Watch::new(s.orbit);
                while !keep(n, s.get())? {
                    s.step();
                    n += 1;
                    if n <= detect_until
                        && let Some(q) = cycle.found(s.orbit)
                    {
                        return Ok((!keep(n, s.get())?).then_some(q));
                    }
                }
                Ok(None)
            });
        }
        let ends = |n: u32, v: [FloatExp; 2]| {
            let f = [v[0].to_f64(), v[1].to_f64()];
            n >= max_iter || f[0] * f[0] + f[1] * f[1] > escape2
        };
        let (tx, rx) = std::sync::mpsc::sync_channel::<Vec<[FloatExp; 2]>>(PIPELINE_BATCHES);
        let orbit = &mut *self;
        let repeats = std::sync::atomic::AtomicU32::new(0);
        std::thread::scope(|scope| {
            let repeats = &repeats;
            scope.spawn(move || {
                let mut n = 0u32;
                let mut cycle = Watch::new(orbit);
                loop {
                    let mut batch = Vec::with_capacity(PIPELINE_BATCH);
                    let mut last = false;
                    while batch.len() < PIPELINE_BATCH && !last {
                        let v = orbit.get();
                        batch.push(v);
                        last = ends(n, v);
                        if !last {
                            orbit.step();
                            n += 1;
                            if n <= detect_until
                                && let Some(q) = cycle.found(orbit)
                            {
                                // z_n is the last value: send it, and say why the orbit ends.
                                batch.push(orbit.get());
                                repeats.store(q, Ordering::Relaxed);
                                last = true;
                            }
                        }
                    }
                    // A closed channel: the keeper has what it needs.
                    if tx.send(batch).is_err() || last {
                        return;
                    }
                }
            });
            let mut n = 0u32;
            // Dropping the receiver when this returns (or unwinds) stops the helper.
            for batch in rx {
                for v in batch {
                    if keep(n, v)? {
                        return Ok(None);
                    }
                    n += 1;
                }
            }
            // The channel closed without `keep` ending the orbit: the helper found it
            // repeating (the scope joined the helper, so its store is seen).
            let q = repeats.load(Ordering::Relaxed);
            assert!(q > 0, "the helper stops at the orbit's end, which `keep` ends at, or at a repeat");
            Ok(Some(q))
        })
    }

    /// Runs `body` with a stepper that shares each step with a helper thread, except while
    /// the machine is too busy for that to pay ([`super::handover`]).
    pub fn with_helper<R>(&mut self, body: impl FnOnce(&mut Stepper<'_>) -> R) -> R {
        self.with_team(2, Policy::Adaptive(Contention::default()), body)
    }

    /// Runs `body` with a stepper that shares each step among `threads` threads: this one
    /// and `threads - 1` helpers, each with its own copy of the orbit and its share of the
    /// squares ([`team::plan`]); `policy` says when the caller steps alone.
    fn with_team<R>(&mut self, threads: usize, policy: Policy, body: impl FnOnce(&mut Stepper<'_>) -> R) -> R {
        let k = self.kernel;
        let plan = team::plan(&k.cuts(), threads);
        let words = plan.iter().map(|ps| ps.iter().map(|p| k.piece_words(&p.range).len()).sum()).max().unwrap_or(0);
        let shared = Shared::new(threads, words);
        let twins: Vec<FixedOrbit> = (1..threads).map(|_| self.clone()).collect();
        let (plan, shared) = (&plan, &shared);
        std::thread::scope(|s| {
            for (t, mut twin) in twins.into_iter().enumerate() {
                s.spawn(move || {
                    let mut seat = Seat::new(t + 1, plan, k);
                    let (mut epoch, mut seq) = (0, 0);
                    loop {
                        seq += 1;
                        if twin.shared_step(shared, &mut seat, epoch, seq).is_none() {
                            // The caller paused or stopped: sleep until it resumes, from its value.
                            let Some(e) = shared.rejoin(epoch, |r| {
                                twin.x.copy_from_slice(&r.x);
                                twin.y.copy_from_slice(&r.y);
                                seq = r.seq;
                            }) else {
                                return;
                            };
                            epoch = e;
                        }
                    }
                });
            }
            let _stop = StopOnDrop(shared);
            let seat = Seat::new(0, plan, k);
            let sharing = Sharing { shared, seat, seq: 0, epoch: 0, alone: 0, policy };
            body(&mut Stepper { orbit: self, sharing: Some(sharing) })
        })
    }

    /// Step `seq` (from 1) shared with the team, every thread running the same step on its
    /// own copy of the orbit: this thread computes its pieces of the squares ([`Seat`]),
    /// publishes them, takes everyone else's, and every thread finishes the step from the
    /// same squares, so the copies stay the same bits. One hand-over each way per step, all
    /// at once: no thread waits for a request before it starts. Returns whether the wait for
    /// the others was slow ([`super::handover::wait`]); None for a helper whose caller has
    /// paused or stopped meanwhile (`epoch` is no longer the caller's).
    fn shared_step(&mut self, sh: &Shared, seat: &mut Seat<'_>, epoch: u64, seq: u64) -> Option<bool> {
        self.inputs();
        let (k, simd, w) = (self.kernel, self.simd, &mut self.w);
        let me = seat.me;
        let magnitudes = [&w.ax, &w.asum, &w.ay];
        // Each thread's words alternate between two boxes by the step's parity: a box is
        // written again two steps later, after all its readers have answered the step between.
        let slot = (seq % 2) as usize;
        let mut at = 0;
        for (p, piece) in seat.plan[me].iter().zip(&mut seat.pieces[me]) {
            k.piece(p.range.clone(), magnitudes[p.square], &mut w.scratch, piece, simd);
            let words = &piece[k.piece_words(&p.range)];
            for (b, &v) in sh.boxes[me][slot][at..].iter().zip(words) {
                b.store(v, Ordering::Relaxed);
            }
            at += words.len();
        }
        sh.publish(me, epoch, seq);
        let helper = me != 0;
        let slow = handover::wait(|| sh.others_have(me, epoch, seq) || (helper && sh.left(epoch)));
        if !sh.others_have(me, epoch, seq) || (helper && sh.left(epoch)) {
            return None;
        }
        for (t, (plan, pieces)) in seat.plan.iter().zip(&mut seat.pieces).enumerate().filter(|(t, _)| *t != me) {
            let mut at = 0;
            for (p, piece) in plan.iter().zip(pieces) {
                let words = k.piece_words(&p.range);
                let len = words.len();
                for (v, b) in piece[words].iter_mut().zip(&sh.boxes[t][slot][at..at + len]) {
                    *v = b.load(Ordering::Relaxed);
                }
                at += len;
            }
        }
        let outs = [&mut w.x2, &mut w.s2, &mut w.y2];
        for (q, out) in outs.into_iter().enumerate() {
            let pieces = seat
                .plan
                .iter()
                .flatten()
                .zip(seat.pieces.iter().flatten())
                .filter(move |(p, _)| p.square == q)
                .map(|(p, piece)| (&p.range, piece.as_slice()));
            k.join(pieces, magnitudes[q], &mut w.scratch, out);
        }
        self.finish();
        Some(slow)
    }
}

/// One thread's place in a team: its index (0 the caller), the team's plan, and a buffer
/// for every piece of every thread (its own computed, the others' taken from their boxes).
struct Seat<'p> {
    me: usize,
    plan: &'p [Vec<Piece>],
    pieces: Vec<Vec<Vec<u64>>>,
}

impl<'p> Seat<'p> {
    fn new(me: usize, plan: &'p [Vec<Piece>], k: Kernel) -> Seat<'p> {
        let pieces = plan.iter().map(|ps| ps.iter().map(|_| vec![0; k.piece_len()]).collect()).collect();
        Seat { me, plan, pieces }
    }
}

/// Steps a [`FixedOrbit`], on one thread or a team.
pub struct Stepper<'a> {
    orbit: &'a mut FixedOrbit,
    /// Where a helper thread shares the steps.
    sharing: Option<Sharing<'a>>,
}

/// The caller's side of steps shared with a team.
struct Sharing<'a> {
    shared: &'a Shared,
    /// The caller's place in the team.
    seat: Seat<'a>,
    /// Steps taken.
    seq: u64,
    /// The sharing's epoch ([`super::handover`]).
    epoch: u64,
    /// Steps still to take alone before sharing again.
    alone: u32,
    policy: Policy,
}

/// When a shared stepper steps alone.
#[derive(Debug, Clone, Copy)]
enum Policy {
    /// While the machine is busy ([`Contention`]).
    Adaptive(Contention),
    /// A fixed rhythm: `shared` steps shared, then `alone` alone, and again (tests).
    #[cfg(test)]
    Rhythm { shared: u32, alone: u32, count: u32 },
}

impl Policy {
    /// After a shared step: the steps to take alone now, if any.
    fn after(&mut self, slow: bool) -> Option<u32> {
        match self {
            Policy::Adaptive(c) => c.after(slow),
            #[cfg(test)]
            Policy::Rhythm { shared, alone, count } => {
                *count += 1;
                (*count % *shared == 0).then_some(*alone)
            }
        }
    }
}

impl Stepper<'_> {
    /// The current z.
    pub fn get(&self) -> [FloatExp; 2] {
        self.orbit.get()
    }

    /// One step, z <- z^2 + c.
    pub fn step(&mut self) {
        let Some(sh) = &mut self.sharing else {
            return self.orbit.step();
        };
        sh.seq += 1;
        if sh.alone > 0 {
            self.orbit.step();
            sh.alone -= 1;
            if sh.alone == 0 {
                sh.epoch = sh.shared.resume(sh.seq, &self.orbit.x, &self.orbit.y);
            }
            return;
        }
        let slow = self.orbit.shared_step(sh.shared, &mut sh.seat, sh.epoch, sh.seq);
        debug_assert!(slow.is_some(), "only the caller pauses or stops the helper");
        if let Some(alone) = sh.policy.after(slow.unwrap_or(false)) {
            sh.epoch = sh.shared.pause();
            sh.alone = alone.max(1);
        }
    }
}

/// v in fixed point with n limbs (round to nearest), or None beyond [`MAX_MAGNITUDE`].
fn to_fixed(v: &Float, n: usize) -> Option<Vec<u64>> {
    if !v.is_finite() {
        return None;
    }
    if v.is_zero() {
        return Some(vec![0; n]);
    }
    if crate::num::bigfloat::to_floatexp(v).abs() > FloatExp::from(MAX_MAGNITUDE) {
        return None;
    }
    let scaled = v.clone() << (64 * (n as u64 - 1));
    let (int, _) = Integer::rounding_from(scaled, RoundingMode::Nearest);
    let mut limbs = int.to_twos_complement_limbs_asc();
    let fill = if int < 0 { u64::MAX } else { 0 };
    limbs.resize(n, fill);
    Some(limbs)
}

/// True where a second thread can run beside this one: the caller's thread pool has two
/// (a render's `--threads`) and the machine two cores.
fn two_threads() -> bool {
    let cores = std::thread::available_parallelism().map_or(1, |p| p.get());
    cores >= 2 && rayon::current_num_threads() >= 2
}

/// t / 2^64 rounded to the nearest f64 (ties to even), for t with its top bit set: its top
/// 64 bits converted with the rest as a sticky bit. Bit 0 lies below the rounding position
/// (bit 10 of the 64), so that is t's own rounding, without the slow 128-bit conversion.
#[inline]
fn high_to_f64(t: u128) -> f64 {
    ((t >> 64) as u64 | (t as u64 != 0) as u64) as f64
}

/// The nearest FloatExp to a fixed-point value (to within the rounding of its top 128 bits).
fn to_floatexp(a: &[u64]) -> FloatExp {
    let n = a.len();
    let negative = a[n - 1] >> 63 == 1;
    // Limb i of |a|, without writing it out: -a = !a + 1, whose carry stops at the lowest
    // nonzero limb of a.
    let lowest = a.iter().position(|&l| l != 0).unwrap_or(n);
    let mag = |i: usize| -> u64 {
        if !negative {
            a[i]
        } else if i < lowest {
            0
        } else if i == lowest {
            (!a[i]).wrapping_add(1)
        } else {
            !a[i]
        }
    };
    let Some(h) = (0..n).rev().find(|&i| mag(i) != 0) else {
        return FloatExp::ZERO;
    };
    let lz = mag(h).leading_zeros();
    // The 128 bits from the leading one down.
    let top = ((mag(h) as u128) << 64) | if h >= 1 { mag(h - 1) as u128 } else { 0 };
    let low = if h >= 2 { mag(h - 2) } else { 0 };
    let t = if lz == 0 { top } else { (top << lz) | (low >> (64 - lz)) as u128 };
    // Value = t * 2^(64 (h - 1) - lz - 64 (n - 1)) = (t / 2^64) * 2^(64 h - lz - 64 (n - 1)).
    let exp = 64 * h as i64 - lz as i64 - 64 * (n as i64 - 1);
    let f = FloatExp::new(high_to_f64(t), exp as i32);
    if negative { -f } else { f }
}

/// Brent's cycle detection ([`super::cycle`]) on the fixed-point state: the words of x,
/// then of y (a comparison of a few words per step, against a step's squares of them).
struct Watch(Brent<Vec<u64>>);

impl Watch {
    fn new(orbit: &FixedOrbit) -> Watch {
        let mut saved = Vec::new();
        orbit.save(&mut saved);
        Watch(Brent::new(saved))
    }

    /// After a step: the period q when z is now exactly the value q steps back.
    fn found(&mut self, orbit: &FixedOrbit) -> Option<u32> {
        self.0.found(|saved| orbit.is(saved), |saved| orbit.save(saved))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::num::bigfloat;

    fn big(x: f64, prec: u64) -> Float {
        Float::from_primitive_float_prec(x, prec).0
    }

    /// Iterates c from 0 in fixed point at `bits` and in malachite's floats at `bits` + 64,
    /// until escape or `steps`; returns the stored values, asserting that the two agree to
    /// two ulps at every step for the first `strict` steps (a chaotic orbit amplifies the
    /// last bits of both afterwards) and escape together.
    fn against_big_floats(c: [&str; 2], bits: u64, steps: usize, strict: usize, simd: SimdLevel) -> Vec<[f64; 2]> {
        let c = c.map(|t| bigfloat::from_decimal(&crate::num::Decimal::parse(t).unwrap(), bits));
        let z0 = [big(0.0, bits), big(0.0, bits)];
        let mut fixed = FixedOrbit::new(&z0, &c, bits, 65536.0, simd).expect("in range");
        let mut z = z0.clone();
        let mut out = Vec::new();
        let escaped = |v: [f64; 2]| v[0].hypot(v[1]) > 65536.0;
        while out.len() < steps {
            fixed.step();
            bigfloat::step_assign(&mut z, &c, bits + 64);
            let a = fixed.get().map(FloatExp::to_f64);
            let b = [bigfloat::to_floatexp(&z[0]).to_f64(), bigfloat::to_floatexp(&z[1]).to_f64()];
            if out.len() < strict {
                for k in 0..2 {
                    let (x, y) = (a[k], b[k]);
                    assert!((x - y).abs() <= 2.0 * f64::EPSILON * x.abs().max(y.abs()), "{bits} bits: {x} vs {y}");
                }
            }
            assert_eq!(escaped(a), escaped(b), "{bits} bits: escape at step {}", out.len());
            out.push(a);
            if escaped(a) {
                break;
            }
        }
        out
    }

    /// Fixed point against malachite's floats with 64 more bits: at the period-3 rabbit's
    /// centre (an attracting cycle, where rounding errors shrink: every step agrees), and
    /// near the e1086 location's minibrot (truncated to 250 digits: the orbit lingers for
    /// hundreds of steps and escapes; the steps agree until chaos amplifies the last bits,
    /// and the escape is the same), with both squaring kernels. Every instruction set gives
    /// the same bits, and so do the steps shared with a helper thread.
    #[test]
    fn fixed_point_orbit_matches_big_floats() {
        let rabbit = ["-0.12256116687665361237", "0.74486176661974423659"];
        let e1086 = [
            "-1.768610493014677074503175653270226520239677907588665494837677257575304640978808475274635707362464044253014370289948538552508877464736415873052958422861932774670165994201643419934807500290056179906392909880374230601661671965436663874506006355684",
            "0.001266613503868717702066411192242601576193940560471409817185010171762524792588903616691501346028502452530417599269384116816237002586460261272462170615382790262110756215389780859682964779212455295242650488799024701023353984576434859496345393442867",
        ];
        // 200 and 1700 bits run on 64-bit limbs, 10300 bits on vector digits.
        for (bits, steps) in [(200u64, 20000), (1700, 20000), (10300, 1500)] {
            let limbs = FixedOrbit::limbs_for(bits) <= comba::MAX_LIMBS;
            assert_eq!(limbs, bits < 10000, "{bits} bits: kernel");
            against_big_floats(rabbit, bits, steps.min(3000), steps.min(3000), SimdLevel::Scalar);
            let mine = against_big_floats(e1086, bits, steps, 100, SimdLevel::Scalar);
            assert!(mine.len() > 200, "{bits} bits: escaped after {} steps", mine.len());
            for simd in SimdLevel::usable() {
                assert_eq!(against_big_floats(e1086, bits, steps, 0, simd), mine, "{bits} bits, {simd}");
            }
            let c = e1086.map(|t| bigfloat::from_decimal(&crate::num::Decimal::parse(t).unwrap(), bits));
            let fresh = || {
                FixedOrbit::new(&[big(0.0, bits), big(0.0, bits)], &c, bits, 65536.0, SimdLevel::detect())
                    .expect("in range")
            };
            // Teams of two to five threads (on a 2-core machine more than two take turns, so
            // they run fewer steps): every value the same bits as one thread's, sharing all
            // the time or paused and resumed (as on a busy machine) in rhythms that put every
            // step parity at a switch; and the last state the same words.
            for threads in 2..=5 {
                let count = if threads == 2 { mine.len() } else { mine.len().min(300) };
                let mut alone = fresh();
                (0..count).for_each(|_| alone.step());
                let rhythms: &[(u32, u32)] = if threads == 2 { &[(1, 1), (3, 2), (7, 5)] } else { &[(3, 2)] };
                let policies = std::iter::once(Policy::Adaptive(Contention::default()))
                    .chain(rhythms.iter().map(|&(shared, alone)| Policy::Rhythm { shared, alone, count: 0 }));
                for policy in policies {
                    let mut orbit = fresh();
                    orbit.with_team(threads, policy, |s| {
                        for (k, want) in mine.iter().take(count).enumerate() {
                            s.step();
                            let what = format!("{bits} bits: step {k} of {threads} threads, {policy:?}");
                            assert_eq!(s.get().map(FloatExp::to_f64), *want, "{what}");
                        }
                    });
                    assert!(orbit.x == alone.x && orbit.y == alone.y, "{bits} bits, {threads} threads: last state");
                }
            }
        }
    }

    /// A caller that panics between shared steps does not leave the helper waiting (the
    /// scope would then never end): the panic reaches the caller.
    #[test]
    fn a_panic_between_shared_steps_stops_the_helper() {
        let bits = 2000;
        let c = [big(-0.75, bits), big(0.1, bits)];
        let mut orbit =
            FixedOrbit::new(&[big(0.0, bits), big(0.0, bits)], &c, bits, 65536.0, SimdLevel::Scalar).expect("in range");
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            orbit.with_helper(|s| {
                s.step();
                panic!("the caller's work failed");
            })
        }));
        assert!(outcome.is_err());
    }

    #[test]
    fn high_bits_round_as_the_whole_does() {
        let top = 1u128 << 127;
        // Exact, below, at and above a tie (bit 74 of t is the rounding bit), and with the
        // tie broken only by the low 64 bits; odd and even mantissas; the carry to 2^128.
        let ties = [0u128, 1, 1 << 63, 1 << 64, (1 << 74) - 1, 1 << 74, (1 << 74) + 1, (1 << 74) | (1 << 3)];
        for base in [top, top | (1 << 75), u128::MAX >> 1 | top] {
            for d in ties {
                let t = base.wrapping_add(d).max(top);
                assert_eq!(high_to_f64(t) * 2f64.powi(64), t as f64, "{t:#x}");
            }
        }
        let mut t = 0x9e37_79b9_7f4a_7c15_f39c_c060_5ced_c834u128 | top;
        for _ in 0..10000 {
            t = t.wrapping_mul(0x2360_ed05_1fc6_5da4_4385_df64_9fcc_f645) | top;
            assert_eq!(high_to_f64(t) * 2f64.powi(64), t as f64, "{t:#x}");
        }
    }

    #[test]
    fn conversions_round_trip() {
        for x in [0.0, 1.0, -1.0, 0.75, -1.768_610_493_014_677, 2.5e-200, -3.0e-250, 1e9] {
            let f = to_fixed(&big(x, 1000), FixedOrbit::limbs_for(1000)).expect("in range");
            assert_eq!(to_floatexp(&f).to_f64(), x, "{x}");
        }
        assert!(to_fixed(&big(2e9, 100), 4).is_none());
        let zero = [big(0.0, 64), big(0.0, 64)];
        assert!(FixedOrbit::new(&zero, &zero, 64, 1e10, SimdLevel::Scalar).is_none());
    }
}
