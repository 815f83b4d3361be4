//! The iterated maps, written once as small pure functions that every kernel calls.
//!
//! z² + c, the map most views use, has its exact operation sequence here ([`step`],
//! [`deriv_step`]) for its own kernels; every other family of maps is a row of
//! [`kind::KINDS`], composed by [`map`] (or a product of two maps, [`product`], or a sum of two powers with
//! a coefficient, [`sum`]) and chosen, alone or in hybrids, as a
//! [`phase::Formula`].
//!
//! Every f64 path (scalar, SIMD, traps) must produce bit-identical orbits, so the exact
//! sequence of IEEE operations lives here and the SIMD kernel mirrors it lane for lane.
//! Fused multiply-adds are part of that sequence: they are correctly rounded by definition
//! (so every backend, including a software `fma`, gives the same bits), they are slightly
//! more accurate, and on the machines we target they move work from the saturated add
//! pipes to the multiply pipes.

#[cfg(test)]
mod checks;
pub mod end;
pub mod kind;
pub mod map;
pub mod phase;
pub mod product;
pub mod sum;

pub use kind::Kind;
pub use phase::{Cycle, Formula, FormulaError, Phase, Single, Stepper};

/// Which family of maps z -> z^2 + c is iterated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Family {
    /// c is the pixel, z_0 = 0; the derivative is taken with respect to c.
    Mandelbrot,
    /// c is fixed, z_0 is the pixel; the derivative is taken with respect to z_0.
    Julia {
        /// The Julia parameter c = re + i im.
        c: [f64; 2],
    },
}

/// Start of an orbit at a sample point: (first iteration index, z, dz, c, dz increment).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitStart {
    /// Iteration index of `z`.
    pub n: u32,
    /// z_n.
    pub z: [f64; 2],
    /// dz_n (d z_n / d c for Mandelbrot, d z_n / d z_0 for Julia).
    pub dz: [f64; 2],
    /// The additive parameter c.
    pub c: [f64; 2],
    /// What the derivative step adds: 1 for Mandelbrot, 0 for Julia.
    pub dz_add: f64,
}

impl Family {
    /// The orbit start for a sample point. Mandelbrot starts at z_1 = c (z_0 = 0 never
    /// escapes), dz_1 = 1; Julia at z_0 = point, dz_0 = 1.
    #[inline]
    pub fn start(self, point: [f64; 2]) -> OrbitStart {
        match self {
            Family::Mandelbrot => OrbitStart { n: 1, z: point, dz: [1.0, 0.0], c: point, dz_add: 1.0 },
            Family::Julia { c } => OrbitStart { n: 0, z: point, dz: [1.0, 0.0], c, dz_add: 0.0 },
        }
    }
}

/// One step z -> z^2 + c; also returns |z|^2 of the input, which decides escape.
#[inline(always)]
pub fn step(z: [f64; 2], c: [f64; 2]) -> ([f64; 2], f64) {
    let [x, y] = z;
    let yy = y * y;
    let r2 = x.mul_add(x, yy);
    let re = x.mul_add(x, -yy) + c[0];
    let im = (x + x).mul_add(y, c[1]);
    ([re, im], r2)
}

/// One derivative step dz -> 2 z dz + add (add = 1 for Mandelbrot, 0 for Julia).
#[inline(always)]
pub fn deriv_step(z: [f64; 2], dz: [f64; 2], add: f64) -> [f64; 2] {
    let re = z[0].mul_add(dz[0], -(z[1] * dz[1]));
    let im = z[0].mul_add(dz[1], z[1] * dz[0]);
    [re.mul_add(2.0, add), im + im]
}

/// True when c lies in the main cardioid or the period-2 bulb of the Mandelbrot set, so
/// its orbit never escapes. The tests are exact in the sense that matters: a point they
/// accept is inside the set; points within rounding of the boundary take forever to escape
/// in any arithmetic.
#[inline]
pub fn in_main_components(c: [f64; 2]) -> bool {
    let [x, y] = c;
    let y2 = y * y;
    let xq = x - 0.25;
    let q = xq * xq + y2;
    if q * (q + xq) <= 0.25 * y2 {
        return true;
    }
    let xb = x + 1.0;
    xb * xb + y2 <= 0.0625
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cardioid_and_bulb() {
        assert!(in_main_components([0.0, 0.0]));
        assert!(in_main_components([-1.0, 0.0]));
        assert!(in_main_components([0.2, 0.3]));
        assert!(!in_main_components([0.3, 0.0]));
        assert!(!in_main_components([-0.75, 0.1]));
        assert!(!in_main_components([-2.0, 0.0]));
    }

    #[test]
    fn derivative_matches_finite_difference() {
        // Mandelbrot: d z_n / d c after a few steps, against a central difference.
        let c = [-0.7, 0.3];
        let h = 1e-7;
        let orbit = |c: [f64; 2]| {
            let mut z = c;
            for _ in 0..5 {
                z = step(z, c).0;
            }
            z
        };
        let (mut z, mut dz) = (c, [1.0, 0.0]);
        for _ in 0..5 {
            dz = deriv_step(z, dz, 1.0);
            z = step(z, c).0;
        }
        let zp = orbit([c[0] + h, c[1]]);
        let zm = orbit([c[0] - h, c[1]]);
        let fd = [(zp[0] - zm[0]) / (2.0 * h), (zp[1] - zm[1]) / (2.0 * h)];
        assert!((fd[0] - dz[0]).abs() < 1e-5 * dz[0].abs().max(1.0));
        assert!((fd[1] - dz[1]).abs() < 1e-5 * dz[1].abs().max(1.0));
    }
}
