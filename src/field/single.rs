//! The f32 kernel: direct iteration in single precision, the cheapest and least exact way
//! to compute a view. It exists so that `deepfield compare` can show what 24-bit arithmetic
//! costs in accuracy (it is what a plain GPU shader does); renders never choose it.

use super::OrbitParams;
use crate::formula::Family;
use crate::formula::end::{INTERIOR, Orbit};

/// Iterates one sample in f32; returns the orbit's end (z and dz widened to f64) and the
/// iterations performed.
pub fn orbit(params: &OrbitParams, point: [f64; 2]) -> (Orbit, u64) {
    let p = [point[0] as f32, point[1] as f32];
    let (mut z, c, mut dz, add, mut n) = match params.family {
        Family::Mandelbrot => (p, p, [1.0f32, 0.0], 1.0f32, 1u32),
        Family::Julia { c } => (p, [c[0] as f32, c[1] as f32], [1.0, 0.0], 0.0, 0),
    };
    let start = n;
    let r2 = (params.escape_radius * params.escape_radius) as f32;
    loop {
        let (x, y) = (z[0], z[1]);
        if x * x + y * y > r2 {
            let orbit = Orbit { n, z: [x as f64, y as f64], dz: [dz[0] as f64, dz[1] as f64] };
            return (orbit, (n - start) as u64);
        }
        if n >= params.max_iter {
            return (Orbit { n: INTERIOR, z: [0.0; 2], dz: [0.0; 2] }, (n - start) as u64);
        }
        if params.derivative {
            dz = [2.0 * (x * dz[0] - y * dz[1]) + add, 2.0 * (x * dz[1] + y * dz[0])];
        }
        z = [x * x - y * y + c[0], 2.0 * x * y + c[1]];
        n += 1;
    }
}
