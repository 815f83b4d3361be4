//! The direct f64 kernel of every formula but z² + c: one orbit at a time, compiled per
//! family ([`Stepper`]), with the derivative as the real 2×2 Jacobian and orbit traps.
//!
//! z² + c keeps its own kernels ([`super::scalar`], [`super::simd`]); this one serves the
//! other families and hybrids. The Jacobian J of z_n in the sample's parameter (c for the
//! Mandelbrot form, z₀ for the Julia form) becomes the distance estimate's derivative by
//! [`gradient_dz`]: for a conformal family that is dz itself. Interior orbits stop early
//! only where exact: Brent's check (z equal, bit for bit, to a value it held earlier).

use std::sync::atomic::{AtomicBool, Ordering};

use super::{OrbitParams, TrapPlane};
use crate::cancel::Cancelled;
use crate::formula::end::{INTERIOR, Orbit};
use crate::formula::map::{Mat2, gradient_dz, mat_mul};
use crate::formula::{Family, Stepper};
use crate::trap::{Trap, TrapState};

/// The identity matrix.
const I: Mat2 = [[1.0, 0.0], [0.0, 1.0]];

/// Iterates one orbit of `s` from `point`, letting each trap observe z_k for k >= 1.
/// Returns the orbit's end and the iterations performed.
#[inline]
pub fn orbit<S: Stepper>(
    s: S,
    params: &OrbitParams,
    point: [f64; 2],
    traps: &[Trap],
    states: &mut [TrapState],
) -> (Orbit, u64) {
    // Mandelbrot form: z_0 = 0 maps to c for every family, so start at z_1 = c, J_1 = I.
    let (n0, c, add) = match params.family {
        Family::Mandelbrot => (1u32, point, 1.0),
        Family::Julia { c } => (0u32, c, 0.0),
    };
    let r2 = params.escape_radius * params.escape_radius;
    let (mut z, mut j, mut n) = (point, I, n0);
    let (mut saved, mut saved_at) = ([f64::NAN; 2], 0u32);
    let mut next_save = n as u64 + 1;
    loop {
        if n >= 1 {
            for (trap, state) in traps.iter().zip(states.iter_mut()) {
                trap.observe(state, z);
            }
        }
        let rr = z[0].mul_add(z[0], z[1] * z[1]);
        if rr > r2 {
            let dz = if params.derivative { gradient_dz(z, j) } else { [0.0; 2] };
            return (Orbit { n, z, dz }, (n - n0) as u64);
        }
        if n >= params.max_iter {
            return (Orbit::interior(), (n - n0) as u64);
        }
        if params.derivative {
            let mut m = mat_mul(s.jacobian(n, z), j);
            m[0][0] += add;
            m[1][1] += add;
            j = m;
        }
        let f = s.apply(n, z);
        z = [f[0] + c[0], f[1] + c[1]];
        n += 1;
        // A hybrid's orbit repeats only when its phase does too.
        if z == saved && (n - saved_at) % s.period() == 0 {
            return (Orbit::interior(), (n - n0) as u64);
        }
        if n as u64 == next_save {
            (saved, saved_at) = (z, n);
            next_save = 2 * next_save - n0 as u64;
        }
    }
}

/// Iterates every point, writing orbits and, with traps, their planes; returns the
/// iterations performed.
pub fn iterate<S: Stepper>(
    s: S,
    params: &OrbitParams,
    traps: &[Trap],
    points: &[[f64; 2]],
    out: &mut [Orbit],
    planes: &mut [TrapPlane],
    cancel: &AtomicBool,
) -> Result<u64, Cancelled> {
    let mut states: Vec<TrapState> = traps.iter().map(Trap::initial).collect();
    let mut iterations = 0;
    for (k, &p) in points.iter().enumerate() {
        if k % 256 == 0 && cancel.load(Ordering::Relaxed) {
            return Err(Cancelled);
        }
        for (state, trap) in states.iter_mut().zip(traps) {
            *state = trap.initial();
        }
        let (o, its) = orbit(s, params, p, traps, &mut states);
        out[k] = o;
        iterations += its;
        for (plane, state) in planes.iter_mut().zip(&states) {
            plane.store(k, state);
        }
    }
    debug_assert!(out.iter().all(|o| o.n == INTERIOR || o.n <= params.max_iter));
    Ok(iterations)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::map::Ops;
    use crate::formula::{Formula, Phase, Single};
    use crate::simd_level::SimdLevel;

    fn params(family: Family, derivative: bool) -> OrbitParams {
        OrbitParams {
            family,
            formula: Formula::default(),
            max_iter: 500,
            escape_radius: 1e3,
            derivative,
            simd: SimdLevel::Scalar,
        }
    }

    /// The generic kernel at z² + c is the z² + c kernel up to rounding (z² + c's kernel
    /// fuses the addition of c into its last product, the generic map adds c after the
    /// map): near the boundary the difference grows along the orbit, so N may differ on a
    /// few samples and z by a little; a wrong map would differ everywhere, by O(1).
    #[test]
    fn quadratic_through_the_generic_kernel_matches_its_own_kernel() {
        let s = Single(Ops::<0, 2, 0, 0>);
        for family in [Family::Mandelbrot, Family::Julia { c: [-0.8, 0.156] }] {
            let p = params(family, true);
            let mut differ = 0;
            for k in 0..400 {
                let point = [-2.0 + (k % 20) as f64 * 0.13, -1.2 + (k / 20) as f64 * 0.12];
                let (a, _) = orbit(s, &p, point, &[], &mut []);
                let (b, _) = super::super::scalar::orbit(&p, point, &[], &mut []);
                if a.n != b.n {
                    differ += 1;
                    continue;
                }
                // Short orbits amplify rounding little.
                if a.n != INTERIOR && a.n < 12 {
                    let dz = (a.z[0] - b.z[0]).hypot(a.z[1] - b.z[1]) / b.z[0].hypot(b.z[1]);
                    assert!(dz < 1e-9, "{point:?}: {:?} {:?}", a.z, b.z);
                    let rel = ((a.dz[0] - b.dz[0]).hypot(a.dz[1] - b.dz[1])) / b.dz[0].hypot(b.dz[1]);
                    assert!(rel < 1e-9, "{point:?}: {:?} {:?}", a.dz, b.dz);
                }
            }
            assert!(differ <= 4, "{differ} of 400 samples escape at another N");
        }
    }

    /// A hybrid's cycle detection never stops an orbit that escapes: the same points
    /// through the kernel with and without Brent's check (a huge iteration limit vs. the
    /// escape found).
    #[test]
    fn hybrids_escape_where_they_escape() {
        let f = Formula::cycle(&[
            Phase::new(crate::formula::Kind::BurningShip, 2),
            Phase::new(crate::formula::Kind::Mandelbrot, 3),
        ])
        .unwrap();
        let s = crate::formula::Cycle(f);
        let p = params(Family::Mandelbrot, false);
        let mut escaped = 0;
        for k in 0..400 {
            let point = [-2.0 + (k % 20) as f64 * 0.13, -1.2 + (k / 20) as f64 * 0.12];
            let (a, _) = orbit(s, &p, point, &[], &mut []);
            // Direct iteration without any shortcut.
            let mut z = point;
            let mut n = 1;
            let want = loop {
                if z[0] * z[0] + z[1] * z[1] > 1e6 {
                    break n;
                }
                if n >= 500 {
                    break INTERIOR;
                }
                let w = s.apply(n, z);
                z = [w[0] + point[0], w[1] + point[1]];
                n += 1;
            };
            assert_eq!(a.n, want, "{point:?}");
            escaped += (want != INTERIOR) as u32;
        }
        assert!(escaped > 100 && escaped < 400, "{escaped}");
    }
}
