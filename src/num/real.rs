//! `Real`: what the perturbation loop needs of its delta number type, for f64 and FloatExp.
//!
//! The perturbation loop is written once, generic over this trait; f64 runs where the
//! deltas' exponents are safe, `FloatExp` below 1e-300. Complex values are plain `[T; 2]`
//! with the small helpers here, so the same code serves both types without wrappers.

use std::fmt::Debug;
use std::ops::{Add, Mul, Neg, Sub};

use super::FloatExp;

/// A real number type the perturbation loop can run on.
pub trait Real:
    Copy
    + Send
    + Sync
    + Debug
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Neg<Output = Self>
{
    /// Zero.
    const ZERO: Self;
    /// Short name for statistics ("f64", "floatexp").
    const NAME: &'static str;
    /// From an f64.
    fn from_f64(x: f64) -> Self;
    /// From a FloatExp (f64 rounds to 0 or infinity outside its range).
    fn from_fe(x: FloatExp) -> Self;
    /// To the nearest f64.
    fn to_f64(self) -> f64;
    /// To FloatExp (exact).
    fn to_fe(self) -> FloatExp;
    /// self * k.
    fn mul_f64(self, k: f64) -> Self;
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const NAME: &'static str = "f64";
    #[inline(always)]
    fn from_f64(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn from_fe(x: FloatExp) -> Self {
        x.to_f64()
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline(always)]
    fn to_fe(self) -> FloatExp {
        FloatExp::from(self)
    }
    #[inline(always)]
    fn mul_f64(self, k: f64) -> Self {
        self * k
    }
}

impl Real for FloatExp {
    const ZERO: Self = FloatExp::ZERO;
    const NAME: &'static str = "floatexp";
    #[inline(always)]
    fn from_f64(x: f64) -> Self {
        FloatExp::from(x)
    }
    #[inline(always)]
    fn from_fe(x: FloatExp) -> Self {
        x
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        FloatExp::to_f64(self)
    }
    #[inline(always)]
    fn to_fe(self) -> FloatExp {
        self
    }
    #[inline(always)]
    fn mul_f64(self, k: f64) -> Self {
        FloatExp::mul_f64(self, k)
    }
}

/// a + b.
#[inline(always)]
pub fn cadd<T: Real>(a: [T; 2], b: [T; 2]) -> [T; 2] {
    [a[0] + b[0], a[1] + b[1]]
}

/// a * b.
#[inline(always)]
pub fn cmul<T: Real>(a: [T; 2], b: [T; 2]) -> [T; 2] {
    [a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0]]
}

/// |a|^2.
#[inline(always)]
pub fn norm2<T: Real>(a: [T; 2]) -> T {
    a[0] * a[0] + a[1] * a[1]
}

/// Converts each part.
#[inline(always)]
pub fn cconv<A: Real, B: Real>(a: [A; 2]) -> [B; 2] {
    [B::from_fe(a[0].to_fe()), B::from_fe(a[1].to_fe())]
}

/// The f64 parts.
#[inline(always)]
pub fn cto_f64<T: Real>(a: [T; 2]) -> [f64; 2] {
    [a[0].to_f64(), a[1].to_f64()]
}
