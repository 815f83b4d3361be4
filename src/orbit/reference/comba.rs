//! The high part of the square of a multi-limb magnitude on 64-bit limbs, column by column
//! (product scanning, after Comba): the kernel of the fixed-point reference orbit
//! ([`super::fixed`]) up to [`MAX_LIMBS`] limbs, where it beats the 26-bit digits of
//! [`super::square`].
//!
//! Each column k is the sum of the products a_i a_(k-i), i < k - i, doubled, plus a_(k/2)^2
//! when k is even: the off-diagonal products run through a u128 accumulator with a carry
//! counter (so a column of any length is exact in 192 bits), which the compiler turns into
//! one 64 x 64 -> 128-bit multiply and three additions with carry per product. Columns are
//! taken two at a time (2m and 2m + 1 multiply the same a_i by neighbouring limbs): two
//! independent chains in flight, each limb loaded once for two products, and half the
//! per-column bookkeeping, which on the short columns of a 60-limb square was a third of
//! the instructions. There are (64 / 26)^2, about six, times fewer
//! products than with 26-bit digits, no conversion to digits and back, and no vector
//! instructions: the same bits on every CPU. The digits' vector multiplies overtake it past
//! about 10000 bits on AVX2 (`cargo bench --bench reference`).
//!
//! Only the columns from n - 3 up are computed (a short product): the products of the
//! columns below add less than n units of limb n - 2 of the square, so limbs n - 1 and up
//! are exact to one unit of limb n - 1 (tested against malachite's exact square). The
//! columns can be split between threads: each part's carry is added into the limbs above
//! it afterwards, which gives exactly the bits of one pass.

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

/// The limb of `out` (as [`columns`] indexes it) that column `column` of an n-limb square
/// writes: columns below it fill the limbs below, and a carry out of them enters here.
pub fn limb_of_column(n: usize, column: usize) -> usize {
    column - (n - 2)
}

/// Adds a 128-bit product to a 192-bit sum kept as a u128 and a count of its carries.
#[inline(always)]
fn accumulate(s: &mut (u128, u64), p: u128) {
    let (v, c) = s.0.overflowing_add(p);
    s.0 = v;
    s.1 += c as u64;
}

/// A sum from [`accumulate`] as 192 bits (low, middle, high).
#[inline(always)]
fn words(s: (u128, u64)) -> [u64; 3] {
    [s.0 as u64, (s.0 >> 64) as u64, s.1]
}

/// 2 s in 192 bits (the off-diagonal products count twice).
#[inline(always)]
fn doubled([s0, s1, s2]: [u64; 3]) -> [u64; 3] {
    [s0 << 1, (s1 << 1) | (s0 >> 63), (s2 << 1) | (s1 >> 63)]
}

/// a + b in 192 bits (mod 2^192).
#[inline(always)]
fn add3(a: [u64; 3], b: [u64; 3]) -> [u64; 3] {
    let (v0, c0) = a[0].overflowing_add(b[0]);
    let (v1, c1) = a[1].overflowing_add(b[1]);
    let (v1, c2) = v1.overflowing_add(c0 as u64);
    [v0, v1, a[2].wrapping_add(b[2]).wrapping_add((c1 | c2) as u64)]
}

/// The diagonal product a_i^2 as 192 bits.
#[inline(always)]
fn diagonal(a: &[u64], i: usize) -> [u64; 3] {
    let d = a[i] as u128 * a[i] as u128;
    [d as u64, (d >> 64) as u64, 0]
}

/// Columns 2m and 2m + 1 of a^2 together, each as 192 bits. They pair the same a_i with
/// neighbouring limbs (a_(2m-i) and a_(2m+1-i)), so one pass over i loads each limb once
/// for two products and keeps two independent carry chains in flight; column 2m + 1 has
/// one more pair (a_m a_(m+1)), and column 2m one more where it reaches the top limb.
#[inline(always)]
fn pair(a: &[u64], m: usize) -> ([u64; 3], [u64; 3]) {
    let n = a.len();
    // Column 2m + 1's first i (its partner a_(2m+1-i) is at most a_(n-1)).
    let lo = (2 * m + 2).saturating_sub(n);
    let (mut even, mut odd) = ((0u128, 0u64), (0u128, 0u64));
    for (&x, y) in a[lo..m].iter().zip(a[m + 1..=2 * m + 1 - lo].windows(2).rev()) {
        accumulate(&mut even, x as u128 * y[0] as u128);
        accumulate(&mut odd, x as u128 * y[1] as u128);
    }
    accumulate(&mut odd, a[m] as u128 * a[m + 1] as u128);
    if lo > 0 {
        accumulate(&mut even, a[lo - 1] as u128 * a[n - 1] as u128);
    }
    (add3(doubled(words(even)), diagonal(a, m)), doubled(words(odd)))
}

/// Column k of a^2 alone (where a range starts or ends between pairs), as 192 bits.
#[inline(always)]
fn column(a: &[u64], k: usize) -> [u64; 3] {
    let n = a.len();
    let mut s = (0u128, 0u64);
    for i in k.saturating_sub(n - 1)..k.div_ceil(2) {
        accumulate(&mut s, a[i] as u128 * a[k - i] as u128);
    }
    let s = doubled(words(s));
    if k % 2 == 1 { s } else { add3(s, diagonal(a, k / 2)) }
}

/// Columns `cols` of the square of `a` (n limbs), with no carry coming in from below:
/// writes limb k - (n - 2) of `out` (limbs n - 2 .. 2n - 2 of the square, n + 1 of them) for
/// every column k >= n - 2 in the range, and returns the carry out of the range's last
/// column, worth units of limb `cols.end` (and the next).
pub fn columns(a: &[u64], cols: Range<usize>, out: &mut [u64]) -> [u64; 2] {
    columns_inline(a, cols, out)
}

/// [`columns`], inlined where the limb count is known at compile time ([`square`]).
#[inline(always)]
fn columns_inline(a: &[u64], cols: Range<usize>, out: &mut [u64]) -> [u64; 2] {
    let base = a.len() - 2;
    let mut carry = [0u64; 2];
    let mut put = |k: usize, v: [u64; 3]| {
        let [v0, v1, v2] = add3(v, [carry[0], carry[1], 0]);
        if k >= base {
            out[k - base] = v0;
        }
        carry = [v1, v2];
    };
    let mut k = cols.start;
    if k % 2 == 1 && k < cols.end {
        put(k, column(a, k));
        k += 1;
    }
    while k + 1 < cols.end {
        let (even, odd) = pair(a, k / 2);
        put(k, even);
        put(k + 1, odd);
        k += 2;
    }
    if k < cols.end {
        put(k, column(a, k));
    }
    carry
}

/// Adds a carry returned by [`columns`] for the range ending at column `at` into the limbs
/// of `out` (indexed as there) from that column up.
pub fn add_carry(n: usize, at: usize, carry: [u64; 2], out: &mut [u64]) {
    let from = limb_of_column(n, at);
    let mut c = 0u64;
    for (k, o) in out.iter_mut().enumerate().skip(from) {
        let add = carry.get(k - from).copied().unwrap_or(0);
        let (v, c1) = o.overflowing_add(add);
        let (v, c2) = v.overflowing_add(c);
        *o = v;
        c = (c1 | c2) as u64;
    }
}

/// Where the columns of an n-limb square may be cut between threads ([`super::team`]): every
/// column from n - 2 on (so that a carry lands in `out`), with the products before it,
/// from the first column (none before it) to the end (all of them).
pub fn cuts(n: usize) -> Vec<(usize, usize)> {
    let cost = |k: usize| k.div_ceil(2).saturating_sub(k.saturating_sub(n - 1)) + 1;
    let (first, end) = (first_column(n), end_column(n));
    let mut out = vec![(first, 0)];
    let mut sum = 0;
    for k in first..end {
        sum += cost(k);
        if k + 1 >= n - 2 {
            out.push((k + 1, sum));
        }
    }
    out
}

/// Limbs n - 2 .. 2n - 2 of a^2 (n + 1 of them) into `out`, for a magnitude `a` of n >= 2
/// limbs below 2^(64 (n - 1) + 62).
///
/// Up to [`UNROLLED_LIMBS`] limbs (views down to about 1e-100) the limb count is a
/// constant of the code: the loops over a column's products unroll and their bounds checks
/// go, which at 3 to 8 limbs was most of a square's time. The same columns, the same bits.
pub fn square(a: &[u64], out: &mut [u64]) {
    match a.len() {
        2 => square_n::<2>(a, out),
        3 => square_n::<3>(a, out),
        4 => square_n::<4>(a, out),
        5 => square_n::<5>(a, out),
        6 => square_n::<6>(a, out),
        7 => square_n::<7>(a, out),
        8 => square_n::<8>(a, out),
        n => {
            columns(a, first_column(n)..end_column(n), out);
        }
    }
}

/// Most limbs [`square`] runs with the limb count known at compile time.
pub const UNROLLED_LIMBS: usize = 8;

/// [`square`] for N limbs.
#[inline(never)]
fn square_n<const N: usize>(a: &[u64], out: &mut [u64]) {
    let a: &[u64; N] = a.try_into().expect("N limbs");
    let out = &mut out[..N + 1];
    columns_inline(a, first_column(N)..end_column(N), out);
}

#[cfg(test)]
mod tests {
    use malachite_nz::natural::Natural;

    use super::*;

    /// Against malachite's exact square: every kept limb but the lowest two agree exactly,
    /// limb n - 1 to one unit, and two threads' parts joined give the bits of one pass, wherever
    /// they split (odd and even columns: the columns run in pairs).
    #[test]
    fn high_limbs_of_the_square_are_exact() {
        for n in [2usize, 3, 4, 5, 6, 7, 8, 9, 17, 59, 60, 61, 130, MAX_LIMBS] {
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
                for mid in (n - 2).max(first_column(n))..end_column(n) {
                    let mut halves = vec![0; n + 1];
                    let carry = columns(&a, first_column(n)..mid, &mut halves);
                    let mut upper = vec![0; n + 1];
                    columns(&a, mid..end_column(n), &mut upper);
                    let from = limb_of_column(n, mid);
                    halves[from..].copy_from_slice(&upper[from..]);
                    add_carry(n, mid, carry, &mut halves);
                    assert_eq!(halves, out, "{n} limbs: split at column {mid}");
                }
            }
        }
    }
}
