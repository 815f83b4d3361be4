//! Ground truth for `deepfield compare`: direct iteration of single pixels in big floats.
//!
//! No perturbation, no BLA, no f64 anywhere in the orbit: z and dz are iterated from the
//! exact pixel coordinates at a precision well beyond the view's depth, and only the end
//! (z_n, and dz_n times the sample spacing) is rounded. It shares nothing with the engines
//! but the big-float crate; the test suite checks the engines against a second,
//! independent implementation (astro-float).

use malachite_float::Float;

use crate::num::FloatExp;
use crate::num::bigfloat;

/// The true end of one orbit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Escape index, or None (interior within max_iter).
    pub n: Option<u32>,
    /// z_n.
    pub z: [f64; 2],
    /// dz_n times the sample spacing.
    pub dz: [f64; 2],
    /// Some |z_k| came within 1e-9 relative of the escape radius: N is ill-conditioned.
    pub near_circle: bool,
    /// N changes when the point moves 1e-9 sample spacings (set by
    /// [`super::mark_ill_conditioned`], only on pixels some engine got wrong).
    pub ill_conditioned: bool,
    /// N holds but NF changes by more than [`super::NF_CONDITION`] when the point moves 1e-9
    /// sample spacings (set likewise, only where some engine's NF is that far off).
    pub nf_ill_conditioned: bool,
}

/// Iterates the orbit of `point` (Mandelbrot: c = point, z_0 = 0; Julia: z_0 = point).
pub fn orbit(
    point: &[Float; 2],
    julia: Option<&[Float; 2]>,
    max_iter: u32,
    escape: f64,
    spacing: &Float,
    bits: u64,
) -> Truth {
    let zero = || Float::from(0u32);
    let (mut x, mut y, cx, cy, mut dx, mut dy, add) = match julia {
        Some(c) => (point[0].clone(), point[1].clone(), c[0].clone(), c[1].clone(), Float::from(1u32), zero(), false),
        None => (zero(), zero(), point[0].clone(), point[1].clone(), zero(), zero(), true),
    };
    let r2 = escape * escape;
    let mut near = false;
    let f = |v: &Float| bigfloat::to_floatexp(v).to_f64();
    for n in 0..=max_iter {
        let xx = x.square_prec_ref(bits).0;
        let yy = y.square_prec_ref(bits).0;
        let m2 = f(&xx) + f(&yy);
        if ((m2 / r2).sqrt() - 1.0).abs() < 1e-9 {
            near = true;
        }
        if m2 > r2 {
            let scaled = |d: &Float| -> f64 {
                let v: FloatExp = bigfloat::to_floatexp(d) * bigfloat::to_floatexp(spacing);
                v.to_f64()
            };
            let (z, dz) = ([f(&x), f(&y)], [scaled(&dx), scaled(&dy)]);
            return Truth { n: Some(n), z, dz, near_circle: near, ill_conditioned: false, nf_ill_conditioned: false };
        }
        if n == max_iter {
            break;
        }
        // dz <- 2 z dz + (1 for Mandelbrot); z <- z^2 + c.
        let a = x.mul_prec_ref_ref(&dx, bits).0.sub_prec(y.mul_prec_ref_ref(&dy, bits).0, bits).0;
        let b = x.mul_prec_ref_ref(&dy, bits).0.add_prec(y.mul_prec_ref_ref(&dx, bits).0, bits).0;
        dx = a << 1u32;
        if add {
            dx = dx.add_prec(Float::from(1u32), bits).0;
        }
        dy = b << 1u32;
        let xy = x.mul_prec_ref_ref(&y, bits).0;
        x = xx.sub_prec(yy, bits).0.add_prec_ref_ref(&cx, bits).0;
        y = (xy << 1u32).add_prec_ref_ref(&cy, bits).0;
    }
    Truth { n: None, z: [0.0; 2], dz: [0.0; 2], near_circle: near, ill_conditioned: false, nf_ill_conditioned: false }
}
