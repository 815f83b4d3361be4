//! Numbers: exact decimal inputs and the small complex helpers the kernels share.
//!
//! View coordinates arrive as decimal strings so that any depth is exact. The f64 engine
//! only needs them rounded once, but the scene keeps the text (and a wide-exponent summary
//! of its value) so that deeper engines, error messages and the PNG metadata see exactly
//! what the user wrote.

mod decimal;

pub use decimal::{Decimal, DecimalError};

/// Distance from `x` to the next representable f64 away from zero (one unit in the last place).
pub fn ulp(x: f64) -> f64 {
    let a = x.abs();
    if a == 0.0 || !a.is_finite() {
        return f64::MIN_POSITIVE;
    }
    f64::from_bits(a.to_bits() + 1) - a
}

/// Squared magnitude of a complex number given as `[re, im]`.
#[inline]
pub fn norm2(z: [f64; 2]) -> f64 {
    z[0] * z[0] + z[1] * z[1]
}
