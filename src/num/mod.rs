//! Numbers: exact decimal inputs, the extended-exponent `FloatExp`, and the `Real` trait
//! the perturbation loop is generic over.
//!
//! View coordinates arrive as decimal strings so that any depth is exact; the scene keeps
//! the text (and a wide-exponent summary of its value) so that deep engines, error messages
//! and the PNG metadata see exactly what the user wrote. `FloatExp` carries pixel offsets
//! and deltas below the f64 range; `Scaled` is a complex pair with one shared exponent,
//! for quantities whose size as a whole is what counts; `Real` lets one loop run on f64 or
//! `FloatExp`.

pub mod bigcomplex;
pub mod bigfloat;
mod decimal;
pub mod fastmath;
mod floatexp;
pub mod real;
mod scaled;

pub use decimal::{Decimal, DecimalError, scientific};
pub use floatexp::FloatExp;
pub use real::Real;
pub use scaled::Scaled;
