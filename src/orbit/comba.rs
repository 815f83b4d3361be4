//! The high part of the square of a multi-limb magnitude on 64-bit limbs, column by column
//! (product scanning, after Comba): the kernel of the fixed-point reference orbit
//! ([`super::fixed`]) up to [`MAX_LIMBS`] limbs, where it beats the 26-bit digits of
//! [`super::square`].
//!
//! Each column k is the sum of the products a_i a_(k-i), i < k - i, doubled, plus a_(k/2)^2
//! when k is even: the off-diagonal products run through two u128 accumulators, each with
//! a carry counter (so a column of any length is exact in 192 bits), which the compiler
//! turns into one 64 x 64 -> 128-bit multiply and three additions with carry per product,
//! two independent chains in flight. There are (64 / 26)^2, about six, times fewer
//! products than with 26-bit digits, no conversion to digits and back, and no vector
//! instructions: the same bits on every CPU. The digits' vector multiplies overtake it past
//! about 10000 bits on AVX2 (`cargo bench --bench reference`).
//!
//! Only the columns from n - 3 up are computed (a short product): the products of the
//! columns below add less than n units of limb n - 2 of the square, so limbs n - 1 and up
//! are exact to one unit of limb n - 1 (tested against malachite's exact square). The
//! columns can be split between two threads: the lower part's carry is added into the upper
//! part's limbs afterwards, which gives exactly the bits of one pass.

use std::ops::Range;

/// Most limbs this kernel is used for (beyond, [`super::square`]'s vector digits are faster).
pub const MAX_LIMBS: usize = 160;

/// The first column computed for an n-limb magnitude.
pub fn first_column(n: usize) -> usize {
    n.saturating_sub(3)
}

/// One past the last column of an n-limb square's kept limbs (limb 2n - 2: the magnitudes
/// squared stay below 2^(64 (n - 1) + 62), so limb 2n - 1 is zero).
pub fn end_column(n: usize) -> usize {
    2 * n - 1
}

/// The sum of x_q y_(len-1-q) over q: the products of one column's off-diagonal pairs, as
/// 192 bits (low, middle, high).
#[inline(always)]
fn dot(x: &[u64], y: &[u64]) -> [u64; 3] {
    let (mut s0, mut s1) = (0u128, 0u128);
    let (mut t0, mut t1) = (0u64, 0u64);
    for (xa, ya) in x.chunks_exact(2).zip(y.rchunks_exact(2)) {
        let (v0, c0) = s0.overflowing_add(xa[0] as u128 * ya[1] as u128);
        let (v1, c1) = s1.overflowing_add(xa[1] as u128 * ya[0] as u128);
        (s0, s1) = (v0, v1);
        t0 += c0 as u64;
        t1 += c1 as u64;
    }
    if x.len() % 2 == 1 {
        let (v, c) = s0.overflowing_add(x[x.len() - 1] as u128 * y[0] as u128);
        s0 = v;
        t0 += c as u64;
    }
    let (s, c) = s0.overflowing_add(s1);
    [s as u64, (s >> 64) as u64, t0 + t1 + c as u64]
}

/// Column k of a^2: twice its off-diagonal products plus the diagonal one, in 192 bits.
#[inline(always)]
fn column(a: &[u64], k: usize) -> [u64; 3] {
    let n = a.len();
    let lo = k.saturating_sub(n - 1);
    let hi = k.div_ceil(2);
    let [s0, s1, s2] = if hi > lo { dot(&a[lo..hi], &a[k + 1 - hi..=k - lo]) } else { [0; 3] };
    let doubled = [s0 << 1, (s1 << 1) | (s0 >> 63), (s2 << 1) | (s1 >> 63)];
    if k % 2 == 1 {
        return doubled;
    }
    let d = a[k / 2] as u128 * a[k / 2] as u128;
    add3(doubled, [d as u64, (d >> 64) as u64, 0])
}

/// a + b in 192 bits (mod 2^192).
#[inline(always)]
fn add3(a: [u64; 3], b: [u64; 3]) -> [u64; 3] {
    let (v0, c0) = a[0].overflowing_add(b[0]);
    let (v1, c1) = a[1].overflowing_add(b[1]);
    let (v1, c2) = v1.overflowing_add(c0 as u64);
    [v0, v1, a[2].wrapping_add(b[2]).wrapping_add((c1 | c2) as u64)]
}

/// Columns `cols` of the square of `a` (n limbs), with no carry coming in from below:
/// writes limb k - (n - 2) of `out` (limbs n - 2 .. 2n - 2 of the square, n + 1 of them) for
/// every column k >= n - 2 in the range, and returns the carry out of the range's last
/// column, worth units of limb `cols.end` (and the next).
pub fn columns(a: &[u64], cols: Range<usize>, out: &mut [u64]) -> [u64; 2] {
    let base = a.len() - 2;
    let mut carry = [0u64; 2];
    for k in cols {
        let [v0, v1, v2] = add3(column(a, k), [carry[0], carry[1], 0]);
        if k >= base {
            out[k - base] = v0;
        }
        carry = [v1, v2];
    }
    carry
}

/// Adds a carry returned by [`columns`] for the range ending at column `at` into the limbs
/// of `out` (indexed as there) from that column up.
pub fn add_carry(n: usize, at: usize, carry: [u64; 2], out: &mut [u64]) {
    let mut c = 0u64;
    for (k, o) in out.iter_mut().enumerate().skip(at - (n - 2)) {
        let add = carry.get(k - (at - (n - 2))).copied().unwrap_or(0);
        let (v, c1) = o.overflowing_add(add);
        let (v, c2) = v.overflowing_add(c);
        *o = v;
        c = (c1 | c2) as u64;
    }
}

/// Where the columns of an n-limb square split between two threads: 60% of the products
/// below, 40% above (the caller's thread, which takes the lower part, is also the one that
/// runs the step's additions and stores the orbit; on the e1086 benchmark's 60 limbs 60/40
/// beat 50/50 and 70/30), and at or above column n - 2 so that the carry lands in `out`.
pub fn split(n: usize) -> usize {
    let cost = |k: usize| k.div_ceil(2).saturating_sub(k.saturating_sub(n - 1)) + 1;
    let cols = first_column(n)..end_column(n);
    let total: usize = cols.clone().map(cost).sum();
    let mut sum = 0;
    for k in cols {
        if 5 * sum >= 3 * total {
            return k.max(n - 2);
        }
        sum += cost(k);
    }
    end_column(n)
}

/// Limbs n - 2 .. 2n - 2 of a^2 (n + 1 of them) into `out`, for a magnitude `a` of n >= 2
/// limbs below 2^(64 (n - 1) + 62).
pub fn square(a: &[u64], out: &mut [u64]) {
    let n = a.len();
    columns(a, first_column(n)..end_column(n), out);
}

#[cfg(test)]
mod tests {
    use malachite_nz::natural::Natural;

    use super::*;

    /// Against malachite's exact square: every kept limb but the lowest two agree exactly,
    /// limb n - 1 to one unit, and two threads' halves joined give the bits of one pass.
    #[test]
    fn high_limbs_of_the_square_are_exact() {
        for n in [2usize, 3, 4, 5, 17, 59, 60, 61, 130, MAX_LIMBS] {
            for seed in [0x9e37_79b9_7f4a_7c15u64, u64::MAX] {
                let mut a: Vec<u64> = (0..n).map(|i| (i as u64 + 7).wrapping_mul(seed)).collect();
                a[n - 1] >>= 2;
                let exact = Natural::from_limbs_asc(&a);
                let mut exact = (&exact * &exact).to_limbs_asc();
                exact.resize(2 * n, 0);
                let mut out = vec![0; n + 1];
                square(&a, &mut out);
                assert_eq!(out[2..], exact[n..2 * n - 1], "{n} limbs");
                let diff = out[1].abs_diff(exact[n - 1]);
                assert!(diff <= 1, "{n} limbs: limb n - 1 off by {diff}");
                let mid = split(n);
                let mut halves = vec![0; n + 1];
                let carry = columns(&a, first_column(n)..mid, &mut halves);
                let mut upper = vec![0; n + 1];
                columns(&a, mid..end_column(n), &mut upper);
                let from = mid - (n - 2);
                halves[from..].copy_from_slice(&upper[from..]);
                add_carry(n, mid, carry, &mut halves);
                assert_eq!(halves, out, "{n} limbs: split at column {mid}");
            }
        }
    }
}
