//! Logarithm, cube root and fifth root for colouring, written with nothing but IEEE additions,
//! multiplications, divisions and bit operations: the same bits on every platform and
//! instruction set, and no branches, so that a loop over a run of samples vectorises.
//!
//! Colouring calls these for every sample of every recolour. The platform's libm is not used
//! for two reasons. Its results are the platform's: glibc, macOS and Windows round some
//! inputs differently, and a colour byte computed from them would then depend on the
//! machine. And it is one call per sample that no loop around it can vectorise (glibc's
//! `log` is fast, ~4 ns, but its `powf` ~10 ns and `log1p` ~4x `log`). Here the logarithm is
//! the series ln m = 2 atanh s, s = (m - 1) / (m + 1), on a mantissa m in [√½, √2), and
//! the fifth and cube roots are Newton's iteration for x^(-1/5) and x^(-1/3), which needs
//! no division, from a first guess read off the exponent bits.

/// ln 2, split so that e · LN2_HI is exact for |e| < 2^11.
const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
/// ln 2 - LN2_HI.
const LN2_LO: f64 = 1.9082149292705877e-10;

/// Natural logarithm of a positive normal x (to within a few ulps). Zero gives a large
/// negative number rather than -inf, subnormals are not treated apart (colouring takes
/// logarithms of 1 + x, x >= 0), and infinity and NaN give NaN or a large number: callers
/// keep x finite.
#[inline(always)]
pub fn ln(x: f64) -> f64 {
    // x = m 2^e with m in [√½, √2): shift the mantissa bits by 0x95f62 (the top of
    // 1/√2's mantissa) before reading the exponent, so the exponent rounds instead of
    // truncating. Only the high 32 bits take part, in i32 arithmetic (which vectorises).
    let bits = x.to_bits();
    let hi = (bits >> 32) as u32;
    let shifted = hi.wrapping_add(0x3ff0_0000 - 0x3fe6_a09e);
    let e = (shifted >> 20) as i32 - 1023;
    let m_hi = (shifted & 0x000f_ffff) + 0x3fe6_a09e;
    let m = f64::from_bits(((m_hi as u64) << 32) | (bits & 0xffff_ffff));
    let f = m - 1.0;
    let s = f / (2.0 + f);
    let s2 = s * s;
    // 2 atanh s = 2 (s + s^3/3 + s^5/5 + ...): |s| <= 0.1716, s^2 <= 0.0295, so eleven
    // terms leave a remainder below 2^-56 of the first.
    let mut p = 1.0 / 23.0;
    p = p * s2 + 1.0 / 21.0;
    p = p * s2 + 1.0 / 19.0;
    p = p * s2 + 1.0 / 17.0;
    p = p * s2 + 1.0 / 15.0;
    p = p * s2 + 1.0 / 13.0;
    p = p * s2 + 1.0 / 11.0;
    p = p * s2 + 1.0 / 9.0;
    p = p * s2 + 1.0 / 7.0;
    p = p * s2 + 1.0 / 5.0;
    p = p * s2 + 1.0 / 3.0;
    // ln m = f - (f - 2 atanh s) = f - s (f - s^2 p 2): computed as f - hf + s (hf + R)
    // with hf = f^2/2 (the form whose rounding errors stay below an ulp of the result).
    let hf = 0.5 * f * f;
    let r = s2 * p * 2.0;
    let de = e as f64;
    de * LN2_HI - ((hf - (s * (hf + r) + de * LN2_LO)) - f)
}

/// ln(1 + x) for x >= 0 (within a few ulps), from [`ln`] and Goldberg's identity.
#[inline(always)]
pub fn ln_1p(x: f64) -> f64 {
    // u = 1 + x is rounded; x / (u - 1) undoes the rounding to first order. Where u == 1
    // (x below half an ulp of 1), ln(1 + x) = x to within an ulp. The division by u - 1 = 0
    // there is discarded by the select, not taken.
    let u = 1.0 + x;
    let d = u - 1.0;
    let scaled = ln(u) * (x / if d == 0.0 { 1.0 } else { d });
    if d == 0.0 { x } else { scaled }
}

/// x^(1/5) for f32 x in [0, 1] (and above, to 2^127), correctly rounded for all but a
/// rare few inputs, where it is one ulp off. NaN gives NaN.
#[inline(always)]
pub fn fifth_root(x: f32) -> f32 {
    // In f64 every f32 (subnormals included) is normal, so the exponent bits give the
    // first guess: r0 = 2^(-e/5) in bits, within 11% of x^(-1/5).
    let xd = f64::from(x);
    let hi = (xd.to_bits() >> 32) as i32;
    const ONE: i32 = 0x3ff0_0000;
    let r0_hi = ONE - (hi - ONE) / 5;
    let mut r = f64::from_bits((r0_hi as u32 as u64) << 32);
    // Newton for r = x^(-1/5): r <- r + r (1 - x r^5) / 5; the error e goes to ~3 e^2, so
    // 0.11 -> 0.04 -> 4e-3 -> 5e-5 -> 7e-9 -> 2e-16 in five steps.
    for _ in 0..5 {
        let r2 = r * r;
        let r5 = r2 * r2 * r;
        r += r * (1.0 - xd * r5) * 0.2;
    }
    // x^(1/5) = x r^4.
    let r2 = r * r;
    let y = xd * (r2 * r2);
    // 0 gives 0 (its guess is huge and the steps overflow); NaN stays NaN.
    if x == 0.0 { 0.0 } else { y as f32 }
}

/// The cube root of x >= 0 (to within an ulp or two) for x up to 2^900, subnormals
/// included; NaN gives NaN. Newton's iteration for x^(-1/3) from a bit-level guess, as in
/// [`fifth_root`], then one Newton step on the root itself for the last bits.
#[inline(always)]
pub fn cbrt(x: f64) -> f64 {
    // Below 2^-1000 the exponent bits no longer give a guess: scale by 2^1002 = (2^334)^3.
    let tiny = x < f64::from_bits((1023 - 1000) << 52);
    let xs = if tiny { x * f64::from_bits((1023 + 1002) << 52) } else { x };
    const ONE: i32 = 0x3ff0_0000;
    let hi = (xs.to_bits() >> 32) as i32;
    let mut r = f64::from_bits(((ONE - (hi - ONE) / 3) as u32 as u64) << 32);
    // The error e of r goes to ~2 e^2 a step: 0.1 -> 0.02 -> 8e-4 -> 1.3e-6 -> 3e-12 -> 2e-23.
    for _ in 0..5 {
        let r3 = r * r * r;
        r += r * (1.0 - xs * r3) * (1.0 / 3.0);
    }
    let y = xs * (r * r);
    let y = y - (y * y * y - xs) / (3.0 * (y * y));
    let y = if tiny { y * f64::from_bits((1023 - 334) << 52) } else { y };
    // 0 gives 0 (its guess is huge and the steps overflow); NaN stays NaN.
    if x == 0.0 { 0.0 } else { y }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Inputs spread over many binades, their neighbours, and a pseudo-random sweep.
    fn inputs() -> Vec<f64> {
        let mut v = vec![1.0, 2.0, 0.5, std::f64::consts::E, 1.0 + f64::EPSILON, 1.0 - f64::EPSILON / 2.0];
        // Either side of the mantissa split at √½ and √2.
        let (h, r) = (std::f64::consts::FRAC_1_SQRT_2, std::f64::consts::SQRT_2);
        v.extend([h, h.next_down(), h.next_up(), r, r.next_down(), r.next_up()]);
        v.extend([f64::MIN_POSITIVE, f64::MAX, 1e-300, 1e300, 4.3e9, 1e6, 0.3]);
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..200_000 {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            // Exponents over the normal range, random mantissas.
            let e = (state >> 53) % 2000;
            let m = state & ((1 << 52) - 1);
            v.push(f64::from_bits(((e + 20) << 52) | m));
        }
        v
    }

    #[test]
    fn ln_is_within_a_few_ulps_of_libm() {
        for x in inputs() {
            let (a, b) = (ln(x), x.ln());
            // Relative to the result, or to ln's natural scale near 1 (where the result is
            // small and its ulps tiny).
            let tol = 2.0 * f64::EPSILON * b.abs().max(((x - 1.0) / x).abs());
            assert!((a - b).abs() <= tol, "ln {x:e}: {a:e} vs {b:e}");
        }
    }

    #[test]
    fn ln_1p_is_within_a_few_ulps_of_libm() {
        let mut xs = inputs();
        xs.extend([0.0, 1e-300, 1e-18, 1e-16, 1.1e-16, 2.3e-16, 1e-9, 1e-4]);
        for x in xs.into_iter().filter(|x| *x < 1e300) {
            let (a, b) = (ln_1p(x), x.ln_1p());
            assert!((a - b).abs() <= 4.0 * f64::EPSILON * b.abs(), "ln_1p {x:e}: {a:e} vs {b:e}");
        }
    }

    #[test]
    fn cbrt_is_within_two_ulps_of_libm() {
        let mut xs: Vec<f64> = inputs().into_iter().filter(|x| *x < 2f64.powi(900)).collect();
        xs.extend([0.0, 1.0, 8.0, 27.0, 1e-310, f64::from_bits(1), 4.3e9, 0.001]);
        for x in xs {
            let (a, b) = (cbrt(x), x.cbrt());
            assert!((a - b).abs() <= 2.0 * f64::EPSILON * b, "cbrt {x:e}: {a:e} vs {b:e}");
        }
        assert_eq!(cbrt(0.0), 0.0);
        assert!(cbrt(f64::NAN).is_nan());
    }

    #[test]
    fn fifth_root_is_correctly_rounded_but_for_a_few() {
        // Every f32 of a wide sweep, against the f64 root rounded once to f32 (f64's pow is
        // accurate to far below f32's half ulp, so that is the correctly rounded value but
        // where the two roundings meet).
        let (mut total, mut off) = (0u32, 0u32);
        let mut bits = 0u32;
        while bits < 0x3f80_0001 {
            let x = f32::from_bits(bits);
            let want = f64::from(x).powf(0.2) as f32;
            let got = fifth_root(x);
            total += 1;
            if got != want {
                off += 1;
                assert!((got.to_bits() as i64 - want.to_bits() as i64).abs() <= 1, "{x:e}: {got:e} vs {want:e}");
            }
            bits += 997;
        }
        assert!(off * 10_000 < total, "{off} of {total} off by an ulp");
        assert_eq!(fifth_root(0.0), 0.0);
        assert_eq!(fifth_root(1.0), 1.0);
        assert_eq!(fifth_root(32.0), 2.0);
        assert!(fifth_root(f32::NAN).is_nan());
        assert_eq!(fifth_root(f32::from_bits(1)), (f64::from(f32::from_bits(1)).powf(0.2)) as f32);
    }
}
