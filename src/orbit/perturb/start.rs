//! Where a sample starts: its delta u = origin + spacing × offset, and after the view's
//! series ([`super::Series`], where its bounds hold for the sample) or common BLA steps
//! ([`super::Skip`]) the polynomial in u that stands for them, computed in
//! f64 where that gives FloatExp's bits and in FloatExp elsewhere; its derivative; and its
//! interior detection's state (the quadratic model's verdict, which may leave the sample
//! out of detection from its first step).

use super::series::Start;
use super::{Counters, DOWN, Der, NEVER, Numbers, Perturbation, Sample};
use crate::num::real::{cadd, cconv, cmul, norm2};
use crate::num::{FloatExp, Real};
use crate::orbit::interior::Contraction;
use crate::orbit::interior::model::Model;
use crate::orbit::interior::probe::Probe;

/// A sample's δc in `T`: the origin plus the spacing times its offset (a zero origin is
/// not added, which is exact either way: a render of its own is unchanged bit for bit).
pub(in crate::orbit) fn delta_c<T: Real>(spacing: FloatExp, origin: [FloatExp; 2], offset: [f64; 2]) -> [T; 2] {
    let sp = T::from_fe(spacing);
    let d = [sp.mul_f64(offset[0]), sp.mul_f64(offset[1])];
    if origin == [FloatExp::ZERO; 2] { d } else { cadd(cconv(origin), d) }
}

/// A sample's delta at the start, u = origin + spacing × offset, and, when the view's
/// common BLA steps are taken (`common` = their K1, K2), δ_m = K1 u + K2 u² with the scaled
/// derivative (K1 + 2 K2 u) × spacing where `derivative` asks for it (else zero): computed
/// in `T` (f64 where [`Perturbation::start_in_f64`] allows, which gives FloatExp's bits
/// sooner), returned in FloatExp.
#[allow(clippy::type_complexity)] // three complex values, named in the doc
pub(in crate::orbit) fn start_arithmetic<T: Real>(
    spacing: FloatExp,
    origin: [FloatExp; 2],
    offset: [f64; 2],
    common: Option<[[FloatExp; 2]; 2]>,
    derivative: bool,
) -> ([FloatExp; 2], Option<([FloatExp; 2], [FloatExp; 2])>) {
    let fe = |v: [FloatExp; 2]| -> [T; 2] { cconv(v) };
    let sp = T::from_fe(spacing);
    let d = delta_c::<T>(spacing, origin, offset);
    let moved = common.map(|[k1, k2]| {
        let (k1, k2) = (fe(k1), fe(k2));
        let dz = cadd(cmul(k1, d), cmul(cmul(k2, d), d));
        let der = if derivative {
            let k2d = cmul(k2, d);
            cconv(cmul(cadd(k1, [k2d[0].mul_f64(2.0), k2d[1].mul_f64(2.0)]), [sp, T::from_f64(0.0)]))
        } else {
            [FloatExp::ZERO; 2]
        };
        (cconv(dz), der)
    });
    (cconv(d), moved)
}

/// True when a sample's start at `offset` may be computed in f64 ([`start_arithmetic`]):
/// the spacing, the origin, the common steps' coefficients and the offset are zero or
/// within exponents that keep every product and sum the start forms a normal f64, where
/// FloatExp's operations give the bits f64's give (its mantissa products and sums are f64
/// operations, rounded alike; its alignment by powers of two is exact).
///
/// Without an origin or a derivative (a render of its own, no distance layer) the window
/// follows the view: δc = spacing · offset has an exponent within the spacing's plus
/// [-60, 41], and each product the start forms (K δc, K δc δc) must lie within 2^±900, so
/// that each sum of two of them (cancelling at most 53 bits) stays normal too. Otherwise
/// fixed windows cover the origin's sum and the derivative's products.
pub(in crate::orbit) fn start_fits_f64(
    spacing: FloatExp,
    origin: [FloatExp; 2],
    common: Option<&[[FloatExp; 2]; 2]>,
    derivative: bool,
    offset: [f64; 2],
) -> bool {
    let o = |x: f64| x == 0.0 || (2f64.powi(-60)..=2f64.powi(40)).contains(&x.abs());
    if !(o(offset[0]) && o(offset[1])) {
        return false;
    }
    let coefficients = || common.into_iter().flatten().flatten().filter(|v| !v.is_zero());
    if origin == [FloatExp::ZERO; 2] && !derivative && !spacing.is_zero() {
        let within = |lo: i32, hi: i32| lo >= -900 && hi <= 900;
        let d = (spacing.exponent() - 60, spacing.exponent() + 41);
        return within(d.0, d.1)
            && coefficients().all(|v| {
                let e = v.exponent();
                within(e + d.0, e + d.1) && within(e + 2 * d.0, e + 2 * d.1)
            });
    }
    let fits = |v: FloatExp, lo: i32, hi: i32| v.is_zero() || (lo..=hi).contains(&v.exponent());
    fits(spacing, -250, 0) && origin.iter().all(|&v| fits(v, -250, 40)) && coefficients().all(|&v| fits(v, -250, 250))
}

/// A sample's δc and its series start, worked out beside its neighbours'
/// ([`Perturbation::series_starts`]) for [`Perturbation::start_given`].
pub(in crate::orbit) type Given = ([FloatExp; 2], Option<Start>);

impl Perturbation {
    /// A sample's starting state (FloatExp), its derivative, and what the derivative adds;
    /// when `skip`, after the view's series where it holds for the sample, else after the
    /// common BLA steps (counted into `counters`).
    /// `known`: the sample's [`Perturbation::start_model`] where the batch has worked it out
    /// (`Perturbation::sample_models`).
    pub(in crate::orbit) fn start(
        &self,
        offset: [f64; 2],
        known: Option<Model>,
        skip: bool,
        counters: &mut Counters,
    ) -> (Sample<FloatExp>, Der, FloatExp) {
        self.start_given(offset, known, skip, None, counters)
    }

    /// [`Perturbation::start`] with the sample's series start `given` where it was worked out
    /// already ([`Perturbation::series_starts`], which gives the same start).
    pub(in crate::orbit) fn start_given(
        &self,
        offset: [f64; 2],
        known: Option<Model>,
        skip: bool,
        given: Option<Given>,
        counters: &mut Counters,
    ) -> (Sample<FloatExp>, Der, FloatExp) {
        let zero = FloatExp::ZERO;
        let arithmetic = |common| self.start_arithmetic(offset, common);
        let common = self.skip.as_ref().filter(|_| skip).map(|k| k.k);
        // The series first where the view has one; the common steps' polynomial only for a
        // sample whose series bounds fail.
        let series_on = self.series.as_ref().filter(|_| skip);
        let (d, mut moved, series) = match given {
            Some((d, series)) if series_on.is_some() => (d, None, series),
            _ => {
                let (d, moved) = arithmetic(if series_on.is_some() { None } else { common });
                (d, moved, series_on.and_then(|s| s.start(d, self.spacing, self.derivative)))
            }
        };
        if series_on.is_some() && series.is_none() && common.is_some() {
            moved = arithmetic(common).1;
        }
        // A sample whose quadratic model escapes leaves interior detection here.
        let model = known.or_else(|| self.start_model(self.model_map()?, offset));
        let plain = model == Some(Model::Escapes);
        let period = if let Some(Model::Cycle(_, k)) = model { k } else { 0 };
        let shrink = match self.interior {
            None => Contraction::IDLE,
            Some(c) if plain => Contraction::dropped(c),
            Some(c) => Contraction::new(FloatExp::ONE, c),
        };
        // The first Newton test at the end of the second period, if the first contracted.
        let at = if plain { NEVER } else { self.newton_period().map_or(u32::MAX, |p| p.saturating_mul(2)) };
        let probe = Probe { at, anchor_n: 0, anchor_exp: i32::MAX, anchor: [0.0; 2], first2: 0.0, plain, period };
        let (mut start, add_fe) = if self.mandelbrot {
            (Sample { dz: d, dc: d, m: 1, which: 0, n: 1, single: false, shrink, probe }, self.spacing)
        } else {
            (Sample { dz: d, dc: [zero; 2], m: 0, which: 0, n: 0, single: false, shrink, probe }, zero)
        };
        let mut der = [self.spacing, zero];
        if let Some(s) = series {
            let skipped = (s.m - start.m) as u64;
            counters.iterations += skipped;
            counters.series += 1;
            counters.series_iterations += skipped;
            start.dz = s.dz;
            start.m = s.m;
            start.n = s.m;
            der = s.der;
            if let Some(c) = self.interior.filter(|_| !plain) {
                let [d1, d2] = s.d;
                start.shrink = Contraction::new(norm2(cadd(d1, cmul(d2, d))), c);
            }
        } else if let (true, Some(k), Some((dz, scaled))) = (skip, &self.skip, moved) {
            counters.iterations += (k.m - start.m) as u64;
            counters.bla_iterations += (k.m - start.m) as u64;
            counters.bla_steps += k.steps as u64;
            start.dz = dz;
            start.m = k.m;
            start.n = k.m;
            der = scaled;
            if let Some(c) = self.interior.filter(|_| !plain) {
                let [d1, d2] = k.d;
                start.shrink = Contraction::new(norm2(cadd(d1, cmul(d2, d))), c);
            }
        }
        // Without a derivative the loop never reads it (its DER parameter is false).
        let der = if self.derivative { Der::from_fe(der, add_fe) } else { Der::UNUSED };
        (start, der, add_fe)
    }

    /// [`start_arithmetic`] for the sample at `offset`, in f64 where that gives FloatExp's bits.
    #[allow(clippy::type_complexity)] // start_arithmetic's
    fn start_arithmetic(
        &self,
        offset: [f64; 2],
        common: Option<[[FloatExp; 2]; 2]>,
    ) -> ([FloatExp; 2], Option<([FloatExp; 2], [FloatExp; 2])>) {
        if self.start_in_f64(offset) {
            start_arithmetic::<f64>(self.spacing, self.origin, offset, common, self.derivative)
        } else {
            start_arithmetic::<FloatExp>(self.spacing, self.origin, offset, common, self.derivative)
        }
    }

    /// The δc and series starts of up to `N` samples at `offsets` (the rest of the `N` unused), for
    /// [`Perturbation::start_given`]: the view's series evaluated for all of them at once
    /// ([`super::Series::starts`]), or None where the view has no series.
    pub(in crate::orbit) fn series_starts<const N: usize>(&self, offsets: &[[f64; 2]]) -> Option<[Given; N]> {
        let series = self.series.as_ref()?;
        let dc: [[FloatExp; 2]; N] =
            std::array::from_fn(|j| offsets.get(j).map_or([FloatExp::ZERO; 2], |&o| self.start_arithmetic(o, None).0));
        let starts = series.starts(&dc, self.spacing, self.derivative);
        let mut starts = starts.into_iter();
        Some(dc.map(|d| (d, starts.next().flatten())))
    }

    /// True when a sample's start at `offset` may be computed in f64 ([`start_arithmetic`],
    /// [`start_fits_f64`]).
    pub(in crate::orbit) fn start_in_f64(&self, offset: [f64; 2]) -> bool {
        start_fits_f64(self.spacing, self.origin, self.skip.as_ref().map(|k| &k.k), self.derivative, offset)
    }

    /// True when a sample starting at `s` must begin in FloatExp.
    pub(in crate::orbit) fn starts_in_floatexp(&self, s: &Sample<FloatExp>) -> bool {
        let big = s.dz[0].abs().max(s.dz[1].abs());
        self.numbers == Numbers::FloatExp && big < FloatExp::from(DOWN)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where [`start_fits_f64`] allows it, a start computed in f64 has FloatExp's bits: over
    /// a grid of spacings from 2^-1000 to 2^-10, coefficients K1 and K2 each from 2^-600 to
    /// 2^600 and offsets over their whole range (mantissas and signs drawn at random), with and
    /// without a derivative and an origin, so that products reach both edges of the window.
    /// The view-dependent window takes in a 1e-102 view's starts (spacing 2^-349).
    #[test]
    fn a_start_in_f64_has_floatexps_bits() {
        let mut seed = 12345u64;
        let mut u = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut allowed, mut deep) = (0, 0);
        for es in (-1000..=-10).step_by(15) {
            for (ek, ek2) in (-600..=600).step_by(40).flat_map(|a| (-600..=600).step_by(40).map(move |b| (a, b))) {
                for (eo, variant) in [-59, -20, 0, 39].into_iter().flat_map(|eo| (0..4).map(move |v| (eo, v))) {
                    let mut fe = |e: i32| {
                        let m = 1.0 + u();
                        FloatExp::new(if u() < 0.5 { -m } else { m }, e)
                    };
                    let spacing = fe(es).abs();
                    let k = [[fe(ek), fe(ek - 3)], [fe(ek2), fe(ek2 - 2)]];
                    let origin = if variant == 1 { [fe(-120), fe(-130)] } else { [FloatExp::ZERO; 2] };
                    let derivative = variant == 2;
                    let offset = [(1.0 + u()) * 2f64.powi(eo), -(1.0 + u()) * 2f64.powi(eo)];
                    // Variant 3: no common steps.
                    let common = (variant != 3).then_some(k);
                    if !start_fits_f64(spacing, origin, common.as_ref(), derivative, offset) {
                        continue;
                    }
                    allowed += 1;
                    deep += usize::from(es < -300);
                    let bits = |v: [FloatExp; 2]| v.map(|x| (x.mantissa().to_bits(), x.exponent()));
                    let a = start_arithmetic::<f64>(spacing, origin, offset, common, derivative);
                    let b = start_arithmetic::<FloatExp>(spacing, origin, offset, common, derivative);
                    let what =
                        format!("spacing 2^{es}, coefficients 2^{ek} and 2^{ek2}, offset 2^{eo}, variant {variant}");
                    assert_eq!(bits(a.0), bits(b.0), "δc: {what}");
                    if let (Some(ma), Some(mb)) = (a.1, b.1) {
                        assert_eq!((bits(ma.0), bits(ma.1)), (bits(mb.0), bits(mb.1)), "start: {what}");
                    }
                }
            }
        }
        assert!(allowed > 1000 && deep > 100, "{allowed} starts in f64, {deep} of them past 2^-300");
        let k = [[FloatExp::new(1.3, 40), FloatExp::new(-1.1, 38)], [FloatExp::new(1.7, 300), FloatExp::ZERO]];
        assert!(start_fits_f64(FloatExp::new(1.2, -349), [FloatExp::ZERO; 2], Some(&k), false, [123.5, -7.25]));
    }
}
