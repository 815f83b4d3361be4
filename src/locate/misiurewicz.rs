//! Misiurewicz points: parameters whose critical orbit is eventually periodic, z_(k+p) =
//! z_k with preperiod k and period p. They lie on the boundary of the Mandelbrot set, and the
//! set looks the same at every depth around them (spirals and branches), so views of any
//! depth can be centred on one.
//!
//! Newton's method solves z_(k+p)(c) - z_k(c) = 0, with the derivatives carried alongside
//! (z_(n+1)' = 2 z_n z_n' + 1). Its roots also include points of lower preperiod or period
//! (and nuclei), so a root found is checked for the preperiod and period its orbit really
//! has ([`orbit_type`]).

use crate::num::FloatExp;

use crate::num::bigcomplex::BigC;

/// Newton's method for a root of z_(k+p) - z_k from `start`, at `start`'s precision;
/// None unless the steps converge within `max_steps`.
pub fn newton(start: &BigC, preperiod: u32, period: u32, max_steps: u32) -> Option<BigC> {
    let bits = start.bits;
    let one = BigC::from_f64(1.0, 0.0, bits);
    let tolerance = FloatExp::new(1.0, 16 - bits as i32);
    let mut c = start.clone();
    for _ in 0..max_steps {
        let (mut z, mut dz) = (BigC::zero(bits), BigC::zero(bits));
        let (mut zk, mut dzk) = (BigC::zero(bits), BigC::zero(bits));
        for n in 1..=preperiod + period {
            (z, dz) = c.orbit_step((&z, &dz), &one);
            if n == preperiod {
                (zk, dzk) = (z.clone(), dz.clone());
            }
        }
        let f = z.sub(&zk);
        let df = dz.sub(&dzk);
        if df.abs().is_zero() {
            return None;
        }
        let step = f.div(&df);
        c = c.sub(&step);
        if step.abs() <= tolerance * FloatExp::ONE.max(c.abs()) {
            return Some(c);
        }
        // Diverged (or NaN: then the comparison is false too).
        if c.abs().partial_cmp(&FloatExp::from(4.0)) != Some(std::cmp::Ordering::Less) {
            return None;
        }
    }
    None
}

/// The smallest preperiod k <= `max_preperiod` and period p <= `max_period` for which `c` is
/// a root of z_(k+p) = z_k to its precision: the first-order distance from `c` to that
/// root, |z_(k+p) - z_k| / |z'_(k+p) - z'_k|, is below 2^(24 - bits) (relative to |c| or 1).
/// What the orbit of `c` really is. Measured as a distance in the parameter rather than as
/// |z_(k+p) - z_k| itself, because a deep point's orbit amplifies its own rounding by the
/// derivative (2^100 and more at depth 1e-30): the difference left at a root found to the
/// last bit is that large, its distance is not. None when nothing repeats that soon; a
/// nucleus (z_p = 0, so preperiod 0) is reported as (0, p).
pub fn orbit_type(c: &BigC, max_preperiod: u32, max_period: u32) -> Option<(u32, u32)> {
    classify(c, &Orbit::of(c, (max_preperiod + max_period) as usize, None), max_preperiod, max_period)
}

/// [`orbit_type`] for `c` from its orbit (at least `max_preperiod + max_period` steps, with
/// the derivative in c), under whichever map made it.
pub fn classify(c: &BigC, orbit: &Orbit, max_preperiod: u32, max_period: u32) -> Option<(u32, u32)> {
    let tolerance = FloatExp::new(1.0, 24 - c.bits as i32) * FloatExp::ONE.max(c.abs());
    for k in 0..=max_preperiod as usize {
        for p in 1..=max_period as usize {
            if k + p >= orbit.len() {
                break;
            }
            if orbit.gap(k + p, k) <= orbit.slope(k + p, k) * tolerance {
                return Some((k as u32, p as u32));
            }
        }
    }
    None
}

/// The orbit of a parameter c from z_0 = 0, with the derivative in c, for comparing its
/// points: each z_n in big floats and, for speed, in 53 bits beside z'_n.
pub struct Orbit(Vec<(BigC, [FloatExp; 2], [FloatExp; 2])>);

impl Orbit {
    /// z_0 .. z_n of `c` (n steps), at `c`'s precision; it ends before the first z_n with
    /// |z_n| above `bound`, if one is given.
    pub fn of(c: &BigC, n: usize, bound: Option<FloatExp>) -> Orbit {
        let one = BigC::from_f64(1.0, 0.0, c.bits);
        Orbit::by(c, n, bound, |_, z, dz| c.orbit_step((z, dz), &one))
    }

    /// [`Orbit::of`] under another map: `step` takes (n, z_n, z'_n) to (z_(n+1), z'_(n+1)).
    pub fn by(
        c: &BigC,
        n: usize,
        bound: Option<FloatExp>,
        mut step: impl FnMut(u32, &BigC, &BigC) -> (BigC, BigC),
    ) -> Orbit {
        let (mut z, mut dz) = (BigC::zero(c.bits), BigC::zero(c.bits));
        let mut orbit = Vec::with_capacity(n + 1);
        orbit.push((z.clone(), z.to_fe(), dz.to_fe()));
        for i in 0..n {
            (z, dz) = step(i as u32, &z, &dz);
            if bound.is_some_and(|b| z.abs() > b) {
                break;
            }
            orbit.push((z.clone(), z.to_fe(), dz.to_fe()));
        }
        Orbit(orbit)
    }

    /// Points held (n + 1 unless the orbit left the bound).
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Never: z_0 is always there.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// z_i to 53 bits.
    pub fn point(&self, i: usize) -> [FloatExp; 2] {
        self.0[i].1
    }

    /// |z_i - z_j|: in 53 bits unless the difference cancels there (near a root of
    /// z_i = z_j, where it is small compared with z), then in big floats.
    pub fn gap(&self, i: usize, j: usize) -> FloatExp {
        let ((zi, a, _), (zj, b, _)) = (&self.0[i], &self.0[j]);
        let rough = norm(a[0] - b[0], a[1] - b[1]);
        let scale = FloatExp::ONE.max(b[0].abs().max(b[1].abs()));
        if rough > scale.mul_f64(1e-9) { rough } else { zi.sub(zj).abs() }
    }

    /// |z'_i - z'_j|: the derivative of z_i - z_j in c.
    pub fn slope(&self, i: usize, j: usize) -> FloatExp {
        let (a, b) = (self.0[i].2, self.0[j].2);
        norm(a[0] - b[0], a[1] - b[1])
    }
}

/// |re + i im|.
pub fn norm(re: FloatExp, im: FloatExp) -> FloatExp {
    (re * re + im * im).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Published Misiurewicz points: c = -2 (0, -2, 2, 2, ...: preperiod 2, period 1), c = i
    /// (0, i, -1 + i, -i, -1 + i: preperiod 2, period 2), and the tip of the spiral at
    /// -0.77568377 + 0.13646737i (preperiod 23, period 2: the main spiral of seahorse
    /// valley's neighbour, as listed in the Mandelbrot encyclopedia).
    #[test]
    fn misiurewicz_points_agree_with_published_coordinates() {
        let found = |re: f64, im: f64, k: u32, p: u32| {
            let c = newton(&BigC::from_f64(re, im, 200), k, p, 100).expect("converges");
            (c.to_fe().map(|v| v.to_f64()), orbit_type(&c, 40, 8))
        };
        assert_eq!(found(-1.98, 0.01, 2, 1), ([-2.0, 0.0], Some((2, 1))));
        let (c, t) = found(0.02, 0.98, 2, 2);
        assert!((c[0]).abs() < 1e-15 && (c[1] - 1.0).abs() < 1e-15, "{c:?}");
        assert_eq!(t, Some((2, 2)));
    }

    #[test]
    fn a_nucleus_is_preperiod_zero() {
        let c = super::super::nucleus::newton(&BigC::from_f64(-1.75, 0.0, 200), 3, 100).expect("converges");
        assert_eq!(orbit_type(&c, 10, 10), Some((0, 3)));
    }
}
