//! Ground truth for `deepfield compare`: direct iteration of single pixels in big floats.
//!
//! No perturbation, no BLA, no f64 anywhere in the orbit: z and dz are iterated from the
//! exact pixel coordinates at a precision well beyond the view's depth, and only the end
//! (z_n, and dz_n times the sample spacing) is rounded. It shares nothing with the engines
//! but the big-float crate; the test suite checks the engines against a second,
//! independent implementation (astro-float).
//!
//! z² + c has its own loop ([`orbit`]). Every other formula ([`orbit_formula`]) steps by
//! Kalles Fraktaler's own expansions ([`super::kf_maps`], not the engines' composed maps),
//! in dual numbers that carry the real 2×2 Jacobian J of z_n in the pixel's parameter (c,
//! or z_0 for a Julia set); the distance estimate's derivative is then
//! `formula::map::gradient_dz(z_n, J)` (J itself where the map is conformal).

use malachite_float::Float;

use super::kf_maps::{self, Dual};
use crate::formula::Formula;
use crate::formula::map::gradient_dz;
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
    /// About log2 of the largest |dz_k / d(parameter)| times the sample spacing while
    /// |z_k| <= 2 (the binary exponent of the largest entry of the Jacobian; `i32::MIN`
    /// where it stayed 0): how far the orbit spreads a neighbourhood of the pixel, in units
    /// of the spacing, before it leaves the disk the bounded orbits live in
    /// ([`Truth::spreads`]).
    pub spread_log2: i32,
    /// N changes when the point moves 1e-9 sample spacings, or the orbit spreads that
    /// distance to a unit ([`Truth::spreads`]) (set by [`super::mark_ill_conditioned`], only
    /// on pixels some engine got wrong).
    pub ill_conditioned: bool,
    /// N holds but NF changes by more than [`super::NF_CONDITION`] when the point moves 1e-9
    /// sample spacings (set likewise, only where some engine's NF is that far off).
    pub nf_ill_conditioned: bool,
    /// N holds but the distance-estimate vector changes by more than
    /// [`super::DE_CONDITION`] of its length when the point moves 1e-9 sample spacings (set
    /// likewise, only where some engine's distance estimate is more than
    /// [`super::DE_SUSPECT`] off).
    pub de_ill_conditioned: bool,
    /// ln of the escape rate of the formula iterated (ln 2 for z^2 + c): the base of the
    /// true NF's logarithm, as the engines' smooth fraction takes it.
    pub ln_degree: f64,
}

impl Truth {
    /// An orbit's end as a big-float loop finds it: escaped at `n` with z_n and dz_n, or
    /// (None) interior; the conditioning flags are set later, where some engine disagrees
    /// ([`super::mark_ill_conditioned`]).
    fn found(n: Option<u32>, z: [f64; 2], dz: [f64; 2], near_circle: bool, spread_log2: i32, ln_degree: f64) -> Truth {
        Truth {
            n,
            z,
            dz,
            near_circle,
            spread_log2,
            ill_conditioned: false,
            nf_ill_conditioned: false,
            de_ill_conditioned: false,
            ln_degree,
        }
    }

    /// Whether the orbit spreads a disk of `shift` sample spacings around the pixel to a
    /// size of 1 or more while |z| <= 2: some z_k of the points in that disk lie a whole unit
    /// apart, so the disk covers a macroscopic part of the bounded dynamics and which of its
    /// points escape, and when, is decided by digits finer than `shift` of a spacing. A
    /// chaotic orbit does that (the Burning Ship's and Celtic's miniship neighbourhoods are
    /// full of them): its growth of about e^(λk) turns any rounding, f64's at each step or
    /// the truth's own at its precision, into an unrelated orbit, so the truth at the pixel's
    /// centre is one draw among its neighbours and N is ill-conditioned.
    pub fn spreads(&self, shift: f64) -> bool {
        self.spread_log2 != i32::MIN && f64::from(self.spread_log2) + shift.log2() >= 0.0
    }
}

/// The largest binary exponent among `parts` (entries of d z / d parameter), `i32::MIN`
/// where all are zero.
fn max_exponent<'a>(parts: impl IntoIterator<Item = &'a Float>) -> i32 {
    parts.into_iter().filter_map(Float::get_exponent).max().unwrap_or(i32::MIN)
}

/// [`Truth::spread_log2`] from the largest exponent of the Jacobian's entries and the
/// spacing's.
fn spread(max_exp: i32, spacing: &Float) -> i32 {
    match (max_exp, spacing.get_exponent()) {
        (i32::MIN, _) | (_, None) => i32::MIN,
        (e, Some(s)) => e.saturating_add(s),
    }
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
    let mut widest = i32::MIN;
    let f = |v: &Float| bigfloat::to_floatexp(v).to_f64();
    for n in 0..=max_iter {
        let xx = x.square_prec_ref(bits).0;
        let yy = y.square_prec_ref(bits).0;
        let m2 = f(&xx) + f(&yy);
        if ((m2 / r2).sqrt() - 1.0).abs() < 1e-9 {
            near = true;
        }
        if m2 <= 4.0 {
            widest = widest.max(max_exponent([&dx, &dy]));
        }
        if m2 > r2 {
            let scaled = |d: &Float| -> f64 {
                let v: FloatExp = bigfloat::to_floatexp(d) * bigfloat::to_floatexp(spacing);
                v.to_f64()
            };
            let (z, dz) = ([f(&x), f(&y)], [scaled(&dx), scaled(&dy)]);
            return Truth::found(Some(n), z, dz, near, spread(widest, spacing), std::f64::consts::LN_2);
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
    Truth::found(None, [0.0; 2], [0.0; 2], near, spread(widest, spacing), std::f64::consts::LN_2)
}

/// Iterates the orbit of `point` under `formula` (Mandelbrot form: c = point, z_0 = 0;
/// Julia form: z_0 = point, c = `julia`); iteration n steps by phase n mod the cycle's
/// length. z² + c goes through [`orbit`], its own loop, unchanged.
///
/// # Panics
///
/// When a phase is none of `KINDS`' rows, which [`Formula::parse`] never admits.
pub fn orbit_formula(
    point: &[Float; 2],
    julia: Option<&[Float; 2]>,
    formula: Formula,
    max_iter: u32,
    escape: f64,
    spacing: &Float,
    bits: u64,
) -> Truth {
    if formula.is_quadratic() {
        return orbit(point, julia, max_iter, escape, spacing, bits);
    }
    // The parameter the derivative is taken in carries the tangents.
    let (mut z, c) = match julia {
        Some(c) => (
            [Dual::variable(point[0].clone(), 0), Dual::variable(point[1].clone(), 1)],
            [Dual::constant(c[0].clone()), Dual::constant(c[1].clone())],
        ),
        None => (
            [Dual::constant(Float::from(0u32)), Dual::constant(Float::from(0u32))],
            [Dual::variable(point[0].clone(), 0), Dual::variable(point[1].clone(), 1)],
        ),
    };
    let r2 = escape * escape;
    let mut near = false;
    let mut widest = i32::MIN;
    let f = |v: &Float| bigfloat::to_floatexp(v).to_f64();
    for n in 0..=max_iter {
        let m2 = f(&z[0].v.square_prec_ref(bits).0) + f(&z[1].v.square_prec_ref(bits).0);
        if ((m2 / r2).sqrt() - 1.0).abs() < 1e-9 {
            near = true;
        }
        if m2 <= 4.0 {
            widest = widest.max(max_exponent(z.iter().flat_map(|p| p.d.iter())));
        }
        if m2 > r2 {
            let scaled = |d: &Float| -> f64 {
                let v: FloatExp = bigfloat::to_floatexp(d) * bigfloat::to_floatexp(spacing);
                v.to_f64()
            };
            let zf = [f(&z[0].v), f(&z[1].v)];
            // J times the spacing, rows first, then the derivative a distance estimate uses.
            let j = [[scaled(&z[0].d[0]), scaled(&z[0].d[1])], [scaled(&z[1].d[0]), scaled(&z[1].d[1])]];
            let dz = gradient_dz(zf, j);
            return Truth::found(Some(n), zf, dz, near, spread(widest, spacing), formula.ln_degree());
        }
        if n == max_iter {
            break;
        }
        let step = kf_maps::kf_step_dual(formula.phase(n), &z, &c, bits);
        z = step.expect("every phase of a validated formula is a row of KINDS").z;
    }
    Truth::found(None, [0.0; 2], [0.0; 2], near, spread(widest, spacing), formula.ln_degree())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::Phase;

    fn f(x: f64) -> Float {
        Float::from_primitive_float_prec(x, 64).0
    }

    /// z² + c written as a one-phase formula is [`orbit`] itself.
    #[test]
    fn the_quadratic_formula_keeps_its_loop() {
        let (p, s) = ([f(-0.7453), f(0.1127)], f(1e-6));
        let a = orbit(&p, None, 5000, 2.0, &s, 128);
        let b = orbit_formula(&p, None, Formula::default(), 5000, 2.0, &s, 128);
        assert_eq!(a, b);
    }

    /// Mandelbrot power 2 as a hybrid of two identical phases (not `is_quadratic`, so it
    /// takes the dual-number loop through KF's expansion) ends where z² + c's loop does,
    /// with the same derivative: the map is conformal, so `gradient_dz` of J is dz.
    #[test]
    fn kfs_expansion_and_the_quadratic_loop_agree() {
        let hybrid = Formula::cycle(&[Phase::QUADRATIC, Phase::QUADRATIC]).unwrap();
        let s = f(1e-3);
        for (p, julia) in
            [([f(-0.7453), f(0.1127)], None), ([f(0.3), f(-0.5)], Some([f(-0.8), f(0.156)])), ([f(-1.8), f(0.0)], None)]
        {
            let a = orbit(&p, julia.as_ref(), 3000, 1e3, &s, 160);
            let b = orbit_formula(&p, julia.as_ref(), hybrid, 3000, 1e3, &s, 160);
            assert_eq!(a.n, b.n, "{p:?}");
            for k in 0..2 {
                assert!((a.z[k] - b.z[k]).abs() <= 1e-12 * a.z[0].hypot(a.z[1]), "{a:?} {b:?}");
                assert!((a.dz[k] - b.dz[k]).abs() <= 1e-12 * a.dz[0].hypot(a.dz[1]), "{a:?} {b:?}");
            }
        }
    }

    /// The Burning Ship's dz against a finite difference of its escaped orbit: the real
    /// Jacobian J of z_n in c, by central differences, then `gradient_dz`.
    #[test]
    fn a_non_conformal_derivative_is_the_gradient_of_the_jacobian() {
        let formula = Formula::single(Phase::new(crate::formula::Kind::BurningShip, 2));
        let bits = 200;
        let c = [-1.7602, -0.0282];
        let one = f(1.0);
        let t = orbit_formula(&[f(c[0]), f(c[1])], None, formula, 1000, 1e10, &one, bits);
        let n = t.n.expect("escapes");
        assert!(n >= 8, "escapes after {n} steps: too few to test the chain of Jacobians");
        // z_n at c moved by h along x and y, iterating KF's expansion directly.
        let zn = |dx: f64, dy: f64| {
            let cx = f(c[0]).add_prec(f(dx), bits).0;
            let cy = f(c[1]).add_prec(f(dy), bits).0;
            let (mut x, mut y) = (f(0.0), f(0.0));
            for _ in 0..n {
                [x, y] = kf_maps::kf_step(formula.phase(0), [&x, &y], [&cx, &cy], bits).unwrap();
            }
            [x, y]
        };
        let h = 1e-30;
        let mut j = [[0.0; 2]; 2];
        for (col, (dx, dy)) in [(h, 0.0), (0.0, h)].into_iter().enumerate() {
            let (a, b) = (zn(dx, dy), zn(-dx, -dy));
            for row in 0..2 {
                let d = a[row].sub_prec_ref_ref(&b[row], bits).0;
                j[row][col] = bigfloat::to_floatexp(&d).to_f64() / (2.0 * h);
            }
        }
        let want = gradient_dz(t.z, j);
        let size = want[0].hypot(want[1]);
        assert!((t.dz[0] - want[0]).abs() <= 1e-6 * size && (t.dz[1] - want[1]).abs() <= 1e-6 * size, "{t:?} {want:?}");
    }

    /// A pixel of a Burning Ship miniship's neighbourhood (zoom 1.6e12, 64×48) whose
    /// big-float orbit stays bounded in a chaotic set that a few percent of its neighbours
    /// leave: its Jacobian spreads 1e-9 of a spacing to a unit within the limit, so its N is
    /// ill-conditioned although two shifted orbits stay bounded too. Points on attracting
    /// cycles, the Burning Ship's (c = -0.2 + 0.01i, the real quadratic's fixed point) and
    /// z² + c's (-0.1 + 0.1i), do not spread at any depth a view has.
    #[test]
    fn chaotic_bounded_orbits_spread_and_attracted_ones_do_not() {
        let ship = Formula::single(Phase::new(crate::formula::Kind::BurningShip, 2));
        let bits = 160;
        let dec = |t: &str| bigfloat::from_decimal(&crate::num::Decimal::parse(t).unwrap(), bits);
        let spacing = dec("1.284336128e-12").mul_prec(f(2.0 / 48.0), bits).0;
        let at = |centre: &Float, k: f64| centre.add_prec_ref_ref(&f(k).mul_prec_ref_ref(&spacing, bits).0, bits).0;
        let point = [
            at(&dec("-0.962730847674877211587188843374065790131981540325592592438619377"), -17.5),
            at(&dec("-0.5562060518186959832065133561785838685815563879120244049347743243"), 18.5),
        ];
        let t = orbit_formula(&point, None, ship, 3000, 65536.0, &spacing, bits);
        assert_eq!(t.n, None, "{t:?}");
        assert!(t.spreads(1e-9), "{t:?}");
        for (formula, c) in [(ship, [-0.2, 0.01]), (Formula::default(), [-0.1, 0.1])] {
            for spacing in [1e-3, 1e-12, 1e-300] {
                let t = orbit_formula(&[f(c[0]), f(c[1])], None, formula, 3000, 65536.0, &f(spacing), bits);
                assert_eq!(t.n, None, "{c:?}");
                assert!(t.spread_log2 > i32::MIN && !t.spreads(1e-9), "{c:?} {spacing}: {t:?}");
            }
        }
    }
}
