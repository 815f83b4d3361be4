//! The scalar f64 kernel: one orbit at a time, with every option (derivative, traps).
//!
//! It runs orbits with a bitmap trap (a texture lookup per step) or several traps, and it is
//! the plain reference the vectorised kernel is tested against: both call the same step
//! functions, so their results agree bit for bit.
//!
//! Interior orbits stop early only where that is exact: Brent's periodicity check (z equal,
//! bit for bit, to a value it held earlier) proves the f64 orbit cycles forever, and traps
//! have by then seen every value the cycle holds. The cardioid/bulb skip is used only when
//! no trap needs the orbit.

use std::sync::atomic::{AtomicBool, Ordering};

use super::{OrbitParams, TrapPlane};
use crate::cancel::Cancelled;
use crate::formula::end::{INTERIOR, Orbit};
use crate::formula::{self, Family};
use crate::trap::{Trap, TrapState};

/// Iterates one orbit, letting each trap observe z_k for k >= 1. Returns the orbit's end and
/// the iterations performed.
pub fn orbit(params: &OrbitParams, point: [f64; 2], traps: &[Trap], states: &mut [TrapState]) -> (Orbit, u64) {
    if traps.is_empty() && matches!(params.family, Family::Mandelbrot) && formula::in_main_components(point) {
        return (Orbit::interior(), 0);
    }
    let s = params.family.start(point);
    let r2 = params.escape_radius * params.escape_radius;
    let dz0 = if params.derivative { s.dz } else { [0.0; 2] };
    let (mut z, mut dz, mut n) = (s.z, dz0, s.n);
    let mut saved = [f64::NAN; 2];
    let mut next_save = n as u64 + 1;
    loop {
        if n >= 1 {
            for (trap, state) in traps.iter().zip(states.iter_mut()) {
                trap.observe(state, z);
            }
        }
        let (next, rr) = formula::step(z, s.c);
        if rr > r2 {
            return (Orbit { n, z, dz }, (n - s.n) as u64);
        }
        if n >= params.max_iter {
            return (Orbit::interior(), (n - s.n) as u64);
        }
        if params.derivative {
            dz = formula::deriv_step(z, dz, s.dz_add);
        }
        z = next;
        n += 1;
        if z == saved {
            return (Orbit::interior(), (n - s.n) as u64);
        }
        if n as u64 == next_save {
            saved = z;
            next_save = 2 * next_save - s.n as u64;
        }
    }
}

/// Iterates every point with traps, writing orbits and trap planes; returns iterations.
pub fn iterate_with_traps(
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
        if k % 1024 == 0 && cancel.load(Ordering::Relaxed) {
            return Err(Cancelled);
        }
        for (state, trap) in states.iter_mut().zip(traps) {
            *state = trap.initial();
        }
        let (orbit, its) = orbit(params, p, traps, &mut states);
        out[k] = orbit;
        iterations += its;
        for (plane, state) in planes.iter_mut().zip(&states) {
            plane.store(k, state);
        }
    }
    debug_assert!(out.iter().all(|o| o.n == INTERIOR || o.n <= params.max_iter));
    Ok(iterations)
}
