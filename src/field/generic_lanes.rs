//! The direct f64 kernel of every single family but z² + c in vector lanes: `L` orbits in
//! flight as `[f64; L]` arrays ([`Num`]), compiled per family and per instruction set
//! (pulp's dispatch enables AVX2 or AVX-512 and the lane loops become vector
//! instructions), a finished lane refilled with the next sample at once.
//!
//! Every lane runs the operations of [`super::generic::orbit`] in the same order (the map's
//! [`Map::apply_n`] and [`Map::jacobian_n`] are the scalar map's code over lanes, the
//! escape test and the Jacobian's products likewise), so N, z_n and the derivative are the
//! scalar kernel's bits on every level; a test checks it on each level this CPU has. The
//! per-step bookkeeping (escape, iteration limit, Brent's cycle check) is one vector test;
//! only a lane that ends takes a scalar path. Hybrids, whose lanes would be at different
//! phases, and orbit traps run in the scalar kernel.

use std::sync::atomic::{AtomicBool, Ordering};

use pulp::{Simd, WithSimd};

use super::OrbitParams;
use crate::cancel::Cancelled;
use crate::formula::Family;
use crate::formula::end::Orbit;
use crate::formula::map::{Map, Mat2, Num, gradient_dz};
use crate::simd_level::SimdLevel;

/// Steps between two looks at the cancel flag.
const CANCEL_EVERY: u64 = 1 << 16;

/// Iterates every point with family `M`, writing one [`Orbit`] per point; returns the
/// iterations performed.
pub fn iterate<M: Map>(
    params: &OrbitParams,
    points: &[[f64; 2]],
    out: &mut [Orbit],
    cancel: &AtomicBool,
) -> Result<u64, Cancelled> {
    assert_eq!(points.len(), out.len());
    match (params.simd, params.derivative) {
        (SimdLevel::Scalar, false) => run::<M, 1, false>(params, points, out, cancel),
        (SimdLevel::Scalar, true) => run::<M, 1, true>(params, points, out, cancel),
        // Two vectors' worth of lanes, interleaved to hide the latency of each step.
        (level, _) => level.arch().dispatch(Job::<M> {
            params,
            points,
            out,
            cancel,
            lanes: level.f64_lanes() * 2,
            _map: M::default(),
        }),
    }
}

/// One call of the kernel, run by pulp under the level's target features (`with_simd`
/// is inlined into pulp's feature-enabled entry, and everything below it into that).
struct Job<'a, M: Map> {
    params: &'a OrbitParams,
    points: &'a [[f64; 2]],
    out: &'a mut [Orbit],
    cancel: &'a AtomicBool,
    lanes: usize,
    _map: M,
}

impl<M: Map> WithSimd for Job<'_, M> {
    type Output = Result<u64, Cancelled>;

    #[inline(always)]
    fn with_simd<S: Simd>(self, _: S) -> Self::Output {
        let Job { params, points, out, cancel, lanes, .. } = self;
        match (lanes, params.derivative) {
            (16, false) => run::<M, 16, false>(params, points, out, cancel),
            (16, true) => run::<M, 16, true>(params, points, out, cancel),
            (8, false) => run::<M, 8, false>(params, points, out, cancel),
            (8, true) => run::<M, 8, true>(params, points, out, cancel),
            (_, false) => run::<M, 4, false>(params, points, out, cancel),
            (_, true) => run::<M, 4, true>(params, points, out, cancel),
        }
    }
}

/// The lanes' state.
struct Lanes<const L: usize> {
    x: [f64; L],
    y: [f64; L],
    cx: [f64; L],
    cy: [f64; L],
    /// The Jacobian in the sample's parameter, by entry.
    j: [[[f64; L]; 2]; 2],
    /// Iteration index of z.
    n: [u32; L],
    /// The iteration limit (u32::MAX in an idle lane, which then never ends).
    limit: [u32; L],
    /// Brent's saved value and when it was saved; the next index to save at.
    sx: [f64; L],
    sy: [f64; L],
    save_at: [u32; L],
    /// The sample in each lane (usize::MAX: idle).
    pixel: [usize; L],
}

const IDLE: usize = usize::MAX;

#[inline(always)]
fn run<M: Map, const L: usize, const DE: bool>(
    params: &OrbitParams,
    points: &[[f64; 2]],
    out: &mut [Orbit],
    cancel: &AtomicBool,
) -> Result<u64, Cancelled> {
    let (n0, julia_c, add) = match params.family {
        Family::Mandelbrot => (1u32, None, 1.0),
        Family::Julia { c } => (0u32, Some(c), 0.0),
    };
    let r2 = params.escape_radius * params.escape_radius;
    let max_iter = params.max_iter;
    let mut s = Lanes::<L> {
        x: [0.0; L],
        y: [0.0; L],
        cx: [0.0; L],
        cy: [0.0; L],
        j: [[[1.0; L], [0.0; L]], [[0.0; L], [1.0; L]]],
        n: [0; L],
        limit: [u32::MAX; L],
        sx: [f64::NAN; L],
        sy: [f64::NAN; L],
        save_at: [u32::MAX; L],
        pixel: [IDLE; L],
    };
    let mut next = 0usize;
    let mut active = 0usize;
    let mut iterations = 0u64;
    // Loads the next sample into lane k (or idles it).
    let load = |s: &mut Lanes<L>, k: usize, next: &mut usize| -> bool {
        if *next >= points.len() {
            s.pixel[k] = IDLE;
            // An idle lane iterates a harmless value that never ends anything.
            s.x[k] = 0.0;
            s.y[k] = 0.0;
            s.cx[k] = 0.0;
            s.cy[k] = 0.0;
            s.n[k] = 0;
            s.limit[k] = u32::MAX;
            s.save_at[k] = u32::MAX;
            return false;
        }
        let p = points[*next];
        s.pixel[k] = *next;
        *next += 1;
        let c = julia_c.unwrap_or(p);
        (s.x[k], s.y[k], s.cx[k], s.cy[k]) = (p[0], p[1], c[0], c[1]);
        s.j[0][0][k] = 1.0;
        s.j[0][1][k] = 0.0;
        s.j[1][0][k] = 0.0;
        s.j[1][1][k] = 1.0;
        s.n[k] = n0;
        s.limit[k] = max_iter;
        s.sx[k] = f64::NAN;
        s.sy[k] = f64::NAN;
        s.save_at[k] = n0 + 1;
        true
    };
    for k in 0..L {
        active += load(&mut s, k, &mut next) as usize;
    }
    let mut steps = 0u64;
    while active > 0 {
        // The end tests of z_n, one vector test: escaped, at the limit, or repeating a
        // value saved earlier.
        let rr = s.x.mul_add(s.x, s.y.mul(s.y));
        let mut any = false;
        for k in 0..L {
            let repeat = (s.x[k] == s.sx[k]) & (s.y[k] == s.sy[k]);
            any |= (rr[k] > r2) | (s.n[k] >= s.limit[k]) | repeat;
        }
        if any {
            let mut ended = 0;
            for k in 0..L {
                let repeat = s.x[k] == s.sx[k] && s.y[k] == s.sy[k];
                let escaped = rr[k] > r2;
                if !(escaped || s.n[k] >= s.limit[k] || repeat) {
                    continue;
                }
                let z = [s.x[k], s.y[k]];
                out[s.pixel[k]] = if escaped {
                    let dz = if DE {
                        let j: Mat2 = [[s.j[0][0][k], s.j[0][1][k]], [s.j[1][0][k], s.j[1][1][k]]];
                        gradient_dz(z, j)
                    } else {
                        [0.0; 2]
                    };
                    Orbit { n: s.n[k], z, dz }
                } else {
                    Orbit::interior()
                };
                iterations += (s.n[k] - n0) as u64;
                active -= 1;
                ended += 1;
                active += load(&mut s, k, &mut next) as usize;
            }
            if ended > 0 {
                // Reloaded lanes are tested before they step (a sample may start escaped).
                continue;
            }
        }
        // Brent's saves at power-of-two ages (each lane's own schedule), after the test.
        // (Selects, not branches: the loop stays a few vector instructions.)
        for k in 0..L {
            let save = s.n[k] == s.save_at[k];
            s.sx[k] = if save { s.x[k] } else { s.sx[k] };
            s.sy[k] = if save { s.y[k] } else { s.sy[k] };
            let later = s.save_at[k].saturating_mul(2).saturating_sub(n0);
            s.save_at[k] = if save { later } else { s.save_at[k] };
        }
        if DE {
            let z = [s.x, s.y];
            let a = M::jacobian_n(z);
            let b = s.j;
            // The scalar kernel's `mat_mul`, then the identity added (Mandelbrot form).
            let m00 = a[0][0].mul(b[0][0]).add(a[0][1].mul(b[1][0]));
            let m01 = a[0][0].mul(b[0][1]).add(a[0][1].mul(b[1][1]));
            let m10 = a[1][0].mul(b[0][0]).add(a[1][1].mul(b[1][0]));
            let m11 = a[1][0].mul(b[0][1]).add(a[1][1].mul(b[1][1]));
            if add != 0.0 {
                s.j = [[m00.add(<[f64; L]>::splat(add)), m01], [m10, m11.add(<[f64; L]>::splat(add))]];
            } else {
                s.j = [[m00, m01], [m10, m11]];
            }
        }
        let f = M::apply_n([s.x, s.y]);
        s.x = f[0].add(s.cx);
        s.y = f[1].add(s.cy);
        for k in 0..L {
            s.n[k] = s.n[k].wrapping_add(1);
        }
        steps += 1;
        if steps.is_multiple_of(CANCEL_EVERY) && cancel.load(Ordering::Relaxed) {
            return Err(Cancelled);
        }
    }
    Ok(iterations)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::map::Ops;
    use crate::formula::{Formula, Single};

    fn check<M: Map>(family: Family, center: [f64; 2], radius: f64) {
        let points: Vec<[f64; 2]> = (0..1500)
            .map(|k| {
                [
                    center[0] + radius * ((k % 50) as f64 / 25.0 - 1.0),
                    center[1] + radius * ((k / 50) as f64 / 15.0 - 1.0),
                ]
            })
            .collect();
        for derivative in [false, true] {
            let base = OrbitParams {
                family,
                formula: Formula::default(),
                max_iter: 300,
                escape_radius: 1e4,
                derivative,
                simd: SimdLevel::Scalar,
            };
            let want: Vec<Orbit> = points
                .iter()
                .map(|&p| super::super::generic::orbit(Single(M::default()), &base, p, &[], &mut []).0)
                .collect();
            for simd in SimdLevel::usable() {
                let params = OrbitParams { simd, ..base };
                let mut got = vec![Orbit::interior(); points.len()];
                iterate::<M>(&params, &points, &mut got, &AtomicBool::new(false)).unwrap();
                for (k, (a, b)) in got.iter().zip(&want).enumerate() {
                    assert_eq!(a.n, b.n, "{simd:?} de={derivative} point {:?}", points[k]);
                    assert_eq!(a.z.map(f64::to_bits), b.z.map(f64::to_bits), "{simd:?} point {:?}", points[k]);
                    assert_eq!(a.dz.map(f64::to_bits), b.dz.map(f64::to_bits), "{simd:?} point {:?}", points[k]);
                }
            }
        }
    }

    /// Every level this CPU has gives the scalar kernel's bits (N, z_n, the derivative), for
    /// conformal and folded families, Mandelbrot and Julia forms.
    #[test]
    fn lanes_give_the_scalar_kernels_bits_on_every_level() {
        check::<Ops<3, 2, 0, 0>>(Family::Mandelbrot, [-0.5, -0.5], 1.2);
        check::<Ops<0, 3, 0, 0>>(Family::Mandelbrot, [0.0, 0.0], 1.2);
        check::<Ops<1, 2, 1, 1>>(Family::Mandelbrot, [-0.3, 0.0], 1.5);
        check::<Ops<0, 5, 3, 0>>(Family::Julia { c: [-0.5, 0.3] }, [0.0, 0.0], 1.3);
        check::<Ops<0, 3, 0, 2>>(Family::Mandelbrot, [0.0, 0.0], 1.2);
    }
}
