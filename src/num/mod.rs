//! Numbers: exact decimal inputs.
//!
//! View coordinates arrive as decimal strings so that any depth is exact. The f64 engine
//! only needs them rounded once, but the scene keeps the text (and a wide-exponent summary
//! of its value) so that deeper engines, error messages and the PNG metadata see exactly
//! what the user wrote. (`FloatExp`, the extended-exponent type of the deep-zoom engine,
//! will live here too.)

mod decimal;

pub use decimal::{Decimal, DecimalError};
