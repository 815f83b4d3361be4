//! The high part of the square of a multi-limb magnitude, in vector lanes: the kernel of the
//! fixed-point reference orbit ([`super::fixed`]).
//!
//! A 64 x 64-bit product per instruction, with a carry chain through every addition, runs at
//! about three cycles a product on Zen 3 in portable code. Here the magnitude is cut into
//! 26-bit digits instead, so that every digit product (52 bits) and every column of them
//! (fewer than 2^12 products) fits in a u64 with no carry at all: each row of the schoolbook
//! square is a plain multiply-add of one digit into a run of column sums, which the compiler
//! turns into 32 x 32 -> 64-bit vector multiplies (4 lanes with AVX2, 8 with AVX-512, 2 with
//! NEON) under the instruction set the caller chose. Rows are taken four at a time, so each
//! column sum is loaded and stored once per four products. Carries are resolved once, at the
//! end, while the digits are packed back into 64-bit limbs. All of it is integer
//! arithmetic: every instruction set gives the same bits.
//!
//! Only the columns that reach the kept limbs are computed (a short product): columns below
//! `k0` would change the lowest kept limb by less than 2^-16 of a unit, and rows split
//! between threads sum to exactly what one thread computes.

use std::ops::Range;

use pulp::{Simd, WithSimd};

use crate::simd_level::SimdLevel;

/// Bits per digit.
const DIGIT: usize = 26;
/// Most digits a magnitude may have: column sums of 2^52 products stay below 2^64.
pub const MAX_DIGITS: usize = 4094;

/// Where the digits of an n-limb square lie: m digits, columns from `k0` kept, and the row
/// index `h` where the lower rows (whose columns start at k0) end and the upper rows (whose
/// columns start after the diagonal) begin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// 64-bit limbs of the magnitude.
    pub n: usize,
    /// Its 26-bit digits.
    pub m: usize,
    /// The first column computed.
    pub k0: usize,
    /// The first upper row: ceil(k0 / 2).
    pub h: usize,
}

/// Rows taken together: each column sum is loaded and stored once per this many products.
const BLOCK: usize = 4;
/// Zero digits after the last: blocks run past the end of the rows without tests.
pub const PAD: usize = 8;
/// Zero digits before the first (digit j is stored at j + FRONT): a lower block's rows whose
/// multiplier is zero may reach below digit 0.
const FRONT: usize = BLOCK - 1;

impl Layout {
    /// The layout for n-limb magnitudes (n >= 2), or None beyond [`MAX_DIGITS`].
    pub fn new(n: usize) -> Option<Layout> {
        let m = (64 * n).div_ceil(DIGIT);
        // Columns below k0 add less than m 2^(52 + 26 k0) < 2^(64 (n - 1) - 16): 1/65536 of
        // the lowest kept limb's unit (the kept limbs are n - 1 .. 2n - 2 of the square).
        let k0 = (64 * (n - 1)).saturating_sub(16 + 52 + 12) / DIGIT;
        (m <= MAX_DIGITS && n >= 2).then_some(Layout { n, m, k0, h: k0.div_ceil(2) })
    }

    /// Column sums kept (columns k0 .. 2m - 1), plus room for the blocks' padding.
    pub fn columns(&self) -> usize {
        2 * self.m - 1 - self.k0 + 2 * PAD
    }

    /// Digits a digit buffer holds: a few zeros, m digits, then [`PAD`] zeros.
    pub fn digit_len(&self) -> usize {
        FRONT + self.m + PAD
    }

    /// The blocks of rows, in order: lower blocks from 0 below h, upper blocks from h below
    /// m (each row belongs to exactly one).
    fn blocks(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.h).step_by(BLOCK).chain((self.h..self.m).step_by(BLOCK))
    }

    /// Products of the block starting at row i (for balancing threads).
    fn block_cost(&self, i: usize) -> usize {
        (i..(i + BLOCK).min(self.m))
            .map(|r| if r < self.h { self.m.saturating_sub(self.k0 - r) } else { self.m - r - 1 })
            .sum()
    }

    /// Where the rows may be cut between threads ([`super::team`]): every block's start,
    /// with the products before it, and the end (m, all of them).
    pub fn cuts(&self) -> Vec<(usize, usize)> {
        let mut sum = 0;
        let mut out: Vec<(usize, usize)> = self
            .blocks()
            .map(|i| {
                let at = (i, sum);
                sum += self.block_cost(i);
                at
            })
            .collect();
        out.push((self.m, sum));
        out
    }
}

/// The 26-bit digits of the magnitude `a` (little endian) into `d` (m digits after the
/// front padding; the padding stays zero).
pub fn digits(a: &[u64], d: &mut [u32]) {
    let m = (64 * a.len()).div_ceil(DIGIT);
    // A bit buffer: `have` bits of `buf` not yet taken, refilled a limb at a time.
    let (mut buf, mut have) = (0u128, 0u32);
    let mut limbs = a.iter();
    for v in d[FRONT..FRONT + m].iter_mut() {
        if have < DIGIT as u32 {
            buf |= (limbs.next().copied().unwrap_or(0) as u128) << have;
            have += 64;
        }
        *v = (buf as u32) & ((1 << DIGIT) - 1);
        buf >>= DIGIT;
        have -= DIGIT as u32;
    }
}

/// Adds the off-diagonal products d_i d_j (i < j, column i + j >= k0) of the rows in the
/// blocks starting in `rows` into the column sums `acc` (acc[k - k0]), with instruction set
/// `simd`. `rows` is a range of block starts (or m, [`Layout::cuts`]).
pub fn rows(layout: Layout, d: &[u32], rows: Range<usize>, acc: &mut [u64], simd: SimdLevel) {
    simd.arch().dispatch(Rows { layout, d, rows, acc });
}

struct Rows<'a> {
    layout: Layout,
    d: &'a [u32],
    rows: Range<usize>,
    acc: &'a mut [u64],
}

impl WithSimd for Rows<'_> {
    type Output = ();

    /// Four rows i .. i + 3 at a time, acc[k] += sum_t d_(i+t) d_(k-i-t), over a run of
    /// columns where every product belongs: no test inside the loop, and none at its ends
    /// (the digits after m are zero, and a lower block's rows past h multiply by zero).
    /// Lower rows (i + t < h) start at column k0 together. Upper rows start after the
    /// diagonal (j > i + t): the six products of their first six columns (2i + 1 ..
    /// 2i + 6), where the four rows have not all begun, are added one by one.
    #[inline(always)]
    fn with_simd<S: Simd>(self, _: S) {
        let Rows { layout, d, rows, acc } = self;
        let Layout { m, k0, h, .. } = layout;
        // Digit j of the magnitude.
        let dig = |j: usize| d[j + FRONT] as u64;
        for i in layout.blocks().filter(|i| rows.contains(i)) {
            let lower = i < h;
            let a = |t: usize| if i + t < m && (!lower || i + t < h) { dig(i + t) } else { 0 };
            let [a0, a1, a2, a3] = [a(0), a(1), a(2), a(3)];
            let first = if lower {
                k0
            } else {
                // Columns 2i + 1 .. 2i + 6: the products with j > i + t there.
                let p = |x: usize, y: usize| dig(x) * dig(y);
                let c = 2 * i + 1 - k0;
                acc[c] += p(i, i + 1);
                acc[c + 1] += p(i, i + 2);
                acc[c + 2] += p(i, i + 3) + p(i + 1, i + 2);
                acc[c + 3] += p(i, i + 4) + p(i + 1, i + 3);
                acc[c + 4] += p(i, i + 5) + p(i + 1, i + 4) + p(i + 2, i + 3);
                acc[c + 5] += p(i, i + 6) + p(i + 1, i + 5) + p(i + 2, i + 4);
                2 * i + 7
            };
            // Through column i + m + 2: row t's last digit is j = m - 1 (zeros beyond).
            let last = i + m + 3;
            if first >= last {
                continue;
            }
            let len = last - first;
            let out = &mut acc[first - k0..last - k0];
            // w[q + 3 - t] is digit first + q - i - t.
            let w = &d[first + FRONT - i - 3..first + FRONT - i + len];
            for (q, o) in out.iter_mut().enumerate() {
                *o += a0 * w[q + 3] as u64 + a1 * w[q + 2] as u64 + a2 * w[q + 1] as u64 + a3 * w[q] as u64;
            }
        }
    }
}

/// Turns the off-diagonal column sums into the square's: doubles them and adds the
/// diagonal products d_i^2 of columns k0 and up.
pub fn finish(layout: Layout, d: &[u32], acc: &mut [u64]) {
    for v in acc.iter_mut() {
        *v <<= 1;
    }
    for i in layout.k0.div_ceil(2)..layout.m {
        let v = d[i + FRONT] as u64;
        acc[2 * i - layout.k0] += v * v;
    }
}

/// Resolves the carries of the column sums and writes limbs n - 2 .. 2n - 2 of the square
/// (n + 1 limbs) into `out`.
pub fn pack(layout: Layout, acc: &[u64], out: &mut [u64]) {
    let acc = &acc[..2 * layout.m - 1 - layout.k0];
    // Bit position of column k0's digit relative to out[0] (negative: below it).
    let start = (DIGIT * layout.k0) as i64 - 64 * (layout.n as i64 - 2);
    let mask = (1u128 << DIGIT) - 1;
    let mut carry: u128 = 0;
    let mut sums = acc.iter();
    // Digits below out[0]: only their carries matter, and the bits that reach into it.
    let mut at = start;
    let (mut buf, mut have) = (0u128, start.max(0));
    while at < 0 {
        let v = sums.next().copied().unwrap_or(0) as u128 + carry;
        carry = v >> DIGIT;
        let digit = v & mask;
        if at + DIGIT as i64 > 0 {
            buf = digit >> (-at);
            have = at + DIGIT as i64;
        }
        at += DIGIT as i64;
    }
    // Then a bit buffer: digits in, whole limbs out.
    for o in out.iter_mut() {
        while have < 64 {
            let v = sums.next().copied().unwrap_or(0) as u128 + carry;
            carry = v >> DIGIT;
            buf |= (v & mask) << have;
            have += DIGIT as i64;
        }
        *o = buf as u64;
        buf >>= 64;
        have -= 64;
    }
}

/// The square of the magnitude `a` (n limbs), limbs n - 2 .. 2n - 2, into `out`; `d` and
/// `acc` are work space of the layout's sizes.
pub fn square(layout: Layout, a: &[u64], d: &mut [u32], acc: &mut [u64], out: &mut [u64], simd: SimdLevel) {
    digits(a, d);
    acc.fill(0);
    rows(layout, d, 0..layout.m, acc, simd);
    finish(layout, d, acc);
    pack(layout, acc, out);
}

#[cfg(test)]
mod tests {
    use malachite_nz::integer::Integer;

    use super::*;

    /// Against malachite's exact square: every kept limb but the lowest agrees (the
    /// dropped columns are worth less than 2^-16 of it), with every instruction set, and
    /// rows cut in three give the same sums as one pass.
    #[test]
    fn high_limbs_of_the_square_are_exact() {
        for n in [2usize, 3, 5, 17, 59, 61, 130] {
            let a: Vec<u64> = (0..n).map(|i| (i as u64 + 7).wrapping_mul(0x9e37_79b9_7f4a_7c15)).collect();
            let layout = Layout::new(n).expect("small");
            let exact = Integer::from_twos_complement_limbs_asc(&[a.clone(), vec![0]].concat());
            let exact = (&exact * &exact).to_twos_complement_limbs_asc();
            let mut d = vec![0; layout.digit_len()];
            let mut acc = vec![0; layout.columns()];
            let mut first = None;
            for simd in SimdLevel::usable() {
                let mut out = vec![0; n + 1];
                square(layout, &a, &mut d, &mut acc, &mut out, simd);
                assert_eq!(out[2..], exact[n..2 * n - 1], "{n} limbs, {simd}");
                let diff = out[1].abs_diff(exact[n - 1]);
                assert!(diff <= 1, "{n} limbs, {simd}: lowest kept limb off by {diff}");
                assert_eq!(*first.get_or_insert(out.clone()), out, "{n} limbs: {simd} differs");
                // The rows cut in three at block starts, their column sums added.
                let cuts = layout.cuts();
                let (a1, a2) = (cuts[cuts.len() / 3].0, cuts[2 * cuts.len() / 3].0);
                assert!(a1 <= a2 && a2 <= layout.m, "{n} limbs: cut at {a1}, {a2} of {}", layout.m);
                let mut lo = vec![0; layout.columns()];
                for range in [0..a1, a1..a2, a2..layout.m] {
                    let mut part = vec![0; layout.columns()];
                    rows(layout, &d, range, &mut part, simd);
                    for (l, p) in lo.iter_mut().zip(&part) {
                        *l += p;
                    }
                }
                finish(layout, &d, &mut lo);
                let mut parts = vec![0; n + 1];
                pack(layout, &lo, &mut parts);
                assert_eq!(parts, out, "{n} limbs, {simd}: rows in three parts");
            }
        }
    }

    #[test]
    fn digits_cover_every_bit() {
        let a = [u64::MAX, 0x8000_0000_0000_0001, 0x0123_4567_89ab_cdef];
        let layout = Layout::new(3).expect("small");
        let mut d = vec![0; layout.digit_len()];
        digits(&a, &mut d);
        let mut back = [0u64; 3];
        for (k, &v) in d[FRONT..FRONT + layout.m].iter().enumerate() {
            for b in 0..DIGIT {
                let bit = k * DIGIT + b;
                if bit < 192 {
                    back[bit / 64] |= ((v as u64 >> b) & 1) << (bit % 64);
                }
            }
        }
        assert_eq!(back, a);
    }
}
