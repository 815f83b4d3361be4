//! What one orbit ended with: the record every kernel (direct, SIMD, perturbation) returns,
//! defined with the maps so that the deep engine and the per-sample planes both use it
//! without depending on each other.

/// N of a sample that never escaped within the iteration limit.
pub const INTERIOR: u32 = u32::MAX;

/// What one orbit ended with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    /// Escape index, or [`INTERIOR`].
    pub n: u32,
    /// z_n (zero for interior orbits).
    pub z: [f64; 2],
    /// dz_n when the derivative was tracked (zero otherwise and for interior orbits).
    pub dz: [f64; 2],
}

impl Orbit {
    /// The record of an orbit that never escaped.
    pub fn interior() -> Self {
        Self { n: INTERIOR, z: [0.0; 2], dz: [0.0; 2] }
    }

    /// Iterations a loop started at index `start` performed to reach this end.
    pub fn iterations_from(&self, start: u32, max_iter: u32) -> u64 {
        let end = if self.n == INTERIOR { max_iter } else { self.n };
        end.saturating_sub(start) as u64
    }
}
