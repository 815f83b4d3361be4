//! ln(1 + x) for colouring transfers, several times faster than libm's `log1p`.
//!
//! glibc's `log` is table-driven and fast (~4 ns), but its `log1p` takes a slower general
//! path (measured ~4x the time), and the log transfers call it for every sample of every
//! recolour. Goldberg's identity gives log1p to within a few ulps from `log` alone.
//! (Hand-written ln/exp/pow polynomials were tried and were slower than glibc's.)

/// ln(1 + x) for x >= -1.
#[inline]
pub fn ln_1p(x: f64) -> f64 {
    // u = 1 + x is rounded; x / (u - 1) undoes the rounding to first order.
    let u = 1.0 + x;
    if u == 1.0 { x } else { u.ln() * (x / (u - 1.0)) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agrees_with_libm() {
        for v in [0.0, 1e-300, 1e-9, 1e-4, 0.3, 1.0, 2.5, 100.0, 1e6, 4.3e9, 1e300] {
            let (a, b) = (ln_1p(v), v.ln_1p());
            assert!((a - b).abs() <= 4.0 * f64::EPSILON * b.abs(), "ln_1p {v}: {a} vs {b}");
        }
    }
}
