//! Interior detection's Newton test, in a view centred on a nucleus: what a sample
//! remembers for it ([`Probe`]), when it is tried at the end of a turn
//! (`Perturbation::newton_probe`), the return map of k turns with its derivatives that
//! Newton's method and the disks' certificate iterate (`Perturbation::return_map`), and the
//! one-period quadratic model that gives the test its start (`Perturbation::model_cycle`,
//! `Perturbation::sample_models`). The criterion and the certificates themselves are in
//! [`crate::orbit::interior`]; this file is how the loop reaches them.

use super::batch_models;
use super::model::{self, Model};
use crate::num::real::{cadd, cconv, cmul, cto_f64, norm2};
use crate::num::{FloatExp, Real, Scaled};
use crate::orbit::interior;
use crate::orbit::perturb::der::Der;
use crate::orbit::perturb::{MAX_CYCLE_PERIODS, MODEL_TURNS_SPARE, NEVER, Perturbation, Sample};
use crate::simd_level::SimdLevel;

/// What a sample remembers for interior detection's Newton test, at the ends of the periods
/// of a nucleus's reference: the iteration from which it may run, and an anchor (an end
/// earlier, its full value, the binary exponent of |dz/dz|^2 there, and the squared distance
/// from its value to the next end's); and whether it has left interior detection
/// altogether (`plain`: its quadratic model escaped, and its |dz/dz|^2 is
/// [`Contraction::dropped`]); and the period in turns of the attracting cycle the quadratic
/// model has at its offset ([`Perturbation::start_model`]; 0 where it has none).
#[derive(Debug, Clone, Copy)]
pub(in crate::orbit) struct Probe {
    pub(in crate::orbit) at: u32,
    pub(in crate::orbit) anchor_n: u32,
    pub(in crate::orbit) anchor_exp: i32,
    pub(in crate::orbit) anchor: [f64; 2],
    pub(in crate::orbit) first2: f64,
    pub(in crate::orbit) plain: bool,
    pub(in crate::orbit) period: u32,
}

impl Probe {
    /// Whether a sample at full value `w`, `turns` turns after its anchor, may try Newton's
    /// test: one turn after it always (and the distance it went away is kept), later where
    /// it has come back four times closer than that; never without an anchor (0 turns).
    #[inline(always)]
    pub(in crate::orbit) fn candidate(&mut self, turns: u32, w: [f64; 2]) -> bool {
        let away2 = norm2([w[0] - self.anchor[0], w[1] - self.anchor[1]]);
        match turns {
            0 => false,
            1 => {
                self.first2 = away2;
                true
            }
            _ => away2 * 16.0 < self.first2,
        }
    }
}

/// The quadratic model's parameter c' = K origin + K spacing × offset of the sample at
/// `offset`, from [`Perturbation::model_map`]'s `(ko, ks)`.
pub(in crate::orbit) fn model_parameter((ko, ks): ([f64; 2], [f64; 2]), offset: [f64; 2]) -> [f64; 2] {
    let d = cmul(ks, offset);
    [ko[0] + d[0], ko[1] + d[1]]
}

/// A point z of the quadratic model's coordinate z = Λ w as the full value w near 0 at a
/// period end (`Perturbation::model_cycle`); None where it is not a finite f64.
pub(in crate::orbit) fn from_model(lam: [FloatExp; 2], z: [f64; 2]) -> Option<[f64; 2]> {
    let w = cto_f64(cmul(cconv::<f64, FloatExp>(z), interior::cinv(lam)));
    (w[0].is_finite() && w[1].is_finite()).then_some(w)
}

impl Perturbation {
    /// The period of the reference when interior detection may use Newton's test: a
    /// Mandelbrot view centred on a nucleus (its reference is one period, stored densely).
    pub(in crate::orbit) fn newton_period(&self) -> Option<u32> {
        self.refs[0].period().filter(|&p| self.mandelbrot && self.interior.is_some() && p <= self.refs[0].last())
    }

    /// Interior detection's Newton test, at the end of a period of a nucleus's reference
    /// (the sample has just rebased to Z_0 = 0 with δ its full value, near 0).
    ///
    /// A sample inside the minibrot's cardioid is attracted by a cycle of the reference's
    /// period p; inside one of its bulbs, by a cycle of period k p, whose point near 0 the
    /// sample comes back to every k ends. So the sample keeps an anchor (an earlier end):
    /// one end after it, it may be a cycle of period p; later, k ends after it, one of
    /// period k p where its value has come back to the anchor's four times closer than it
    /// went away at the first end. Where that holds, |dz/dz|^2 shrank since the anchor, and
    /// the iteration count has reached the sample's `at`, Newton's method looks for an
    /// attracting cycle of period k p from the value ([`interior::newton_attracting`]). At
    /// the first end, before any anchor, a test of period k p starts from a point of the
    /// attracting cycle of the one-period quadratic model ([`Perturbation::model_cycle`])
    /// wherever the model has one: inside the minibrot's cardioid (k = 1) and its bulbs that
    /// start is close enough for Newton to certify within a few turns, without waiting for
    /// the orbit.
    /// Found, the sample is interior (its parameter lies in a hyperbolic component); else
    /// the next test waits until the iteration count has doubled, from a new anchor. This
    /// finds most interior samples within a few periods, where the contraction criterion
    /// needs log(threshold) / log|λ| of them (hundreds, and more than the limit allows near
    /// a component's edge); the contraction criterion still decides everywhere else.
    ///
    /// Called at every turn's end, and at most ends it only waits for the anchor's next
    /// turns: that case is decided here, inline in the loop; the rest, out of line, in
    /// [`Perturbation::newton_probe_at`] (a call per end cost an exterior sample a tenth of
    /// its time on the 1e102 minibrot view).
    #[inline(always)]
    pub(in crate::orbit) fn newton_probe<D: Real>(&self, s: &mut Sample<D>) -> bool {
        let Some(p) = self.newton_period() else { return false };
        let pr = &mut s.probe;
        if pr.at == NEVER {
            return false;
        }
        let since = s.n.wrapping_sub(pr.anchor_n);
        if pr.anchor_n != 0 && since >= p && since < p.saturating_mul(MAX_CYCLE_PERIODS) {
            // Turns 1 to MAX_CYCLE_PERIODS - 1 after the anchor: as below, but for a sample
            // that does not try Newton's test now, which keeps its anchor. (Only whether it
            // is one turn or more matters to the candidate test.)
            let turns = if since < p.saturating_mul(2) { 1 } else { 2 };
            let candidate = pr.candidate(turns, cto_f64(s.dz));
            if !(candidate && s.n >= pr.at && s.shrink.value().exponent() < pr.anchor_exp) {
                return false;
            }
        }
        self.newton_probe_at(s, p)
    }

    /// [`Perturbation::newton_probe`] where the sample has no anchor, has gone past its
    /// reach, or tries Newton's test: `p` is the reference's period.
    #[inline(never)]
    pub(in crate::orbit) fn newton_probe_at<D: Real>(&self, s: &mut Sample<D>, p: u32) -> bool {
        let exp = s.shrink.value().exponent();
        let (w, dc) = (cto_f64(s.dz), cto_f64(s.dc));
        let pr = &mut s.probe;
        let k = if pr.anchor_n == 0 { 0 } else { (s.n - pr.anchor_n) / p };
        let candidate = pr.candidate(k, w);
        // At the first end, a start from the quadratic model's attracting cycle, where the
        // model has one: no need to wait for the orbit to settle.
        if pr.anchor_n == 0
            && let Some((w0, turns)) = self.model_cycle(w, pr.period)
            && u64::from(turns) * u64::from(p) * MODEL_TURNS_SPARE <= u64::from(self.max_iter)
            && interior::newton_attracting(w0, |w, second| self.return_map(w, dc, p, turns, second))
        {
            return true;
        }
        if candidate && exp < pr.anchor_exp && s.n >= pr.at {
            pr.at = s.n.saturating_mul(2);
            if interior::newton_attracting(w, |w, second| self.return_map(w, dc, p, k, second)) {
                return true;
            }
        } else if k != 0 && k < MAX_CYCLE_PERIODS {
            return false;
        }
        *pr = Probe { anchor_n: s.n, anchor_exp: exp, anchor: w, ..*pr };
        false
    }

    /// K = Λ ∂Z_p/∂c of a nucleus's reference, which the engine keeps in its `model_scale`
    /// field: the sensitivity of one turn from w = 0 at the nucleus, times Λ. None where the
    /// view has no Newton test.
    pub(in crate::orbit) fn compute_model_scale(&self) -> Option<[FloatExp; 2]> {
        let (p, lam) = (self.newton_period()?, self.renormal?);
        let (_, sens) = self.return_map_with::<true>([0.0; 2], [0.0; 2], p, 1, false)?;
        Some(cmul(lam, sens?.dc))
    }

    /// The quadratic model's parameter as a function of a sample's offset, to first order:
    /// c' = K δc = K origin + K spacing × offset (K the engine's `model_scale`), as the two
    /// complex numbers K origin and K spacing in f64 (in the model's coordinate, where the
    /// minibrot is the whole Mandelbrot set: K spacing is a sample's step there, and both
    /// terms are a few units at most where the samples lie near the minibrot). None where
    /// the view has no model, or no interior detection to use it.
    pub(in crate::orbit) fn model_map(&self) -> Option<([f64; 2], [f64; 2])> {
        self.interior?;
        let k = self.model_scale?;
        Some((cto_f64(cmul(k, self.origin)), [(k[0] * self.spacing).to_f64(), (k[1] * self.spacing).to_f64()]))
    }

    /// What the quadratic model does at a sample's `offset`, its parameter c' by
    /// [`Perturbation::model_map`] `(ko, ks)`: its attracting fixed point inside the main
    /// cardioid, else [`model::settled_cycle`].
    ///
    /// A sample whose model escapes lies outside the minibrot and leaves interior detection
    /// from its start, so that its first turn (in which most such samples escape) runs as
    /// without detection, vector lanes' bursts included. One whose model has an attracting
    /// cycle keeps its period, and at its first period end Newton's method finds the cycle
    /// of the model at its own value ([`Perturbation::model_cycle`]), a start for the test.
    pub(in crate::orbit) fn start_model(&self, map: ([f64; 2], [f64; 2]), offset: [f64; 2]) -> Option<Model> {
        let c = model_parameter(map, offset);
        Some(model::fixed_point(c).map_or_else(|| model::settled_cycle(c), |z| Model::Cycle(z, 1)))
    }

    /// [`Perturbation::start_model`] of every sample of a batch (None where the view has no
    /// model): worked out before the disks, which then look only among the samples whose
    /// model has a short attracting cycle.
    pub(in crate::orbit) fn sample_models(&self, offsets: &[[f64; 2]], simd: SimdLevel) -> Option<Vec<Model>> {
        let map = self.model_map()?;
        let cs: Vec<[f64; 2]> = offsets.iter().map(|&o| model_parameter(map, o)).collect();
        // A batch is whole rows: the first sample of the second row ends the first. (On a
        // rotated grid every sample's y differs: the "row" is then one sample, and the one
        // before serves as the one above; the models only ever cost time.)
        let width = offsets.iter().position(|o| o[1] != offsets[0][1]).unwrap_or(offsets.len());
        Some(batch_models::models(&cs, width, simd))
    }

    /// A point of the attracting cycle of period k turns of the quadratic model
    /// w -> a + Λ w^2 of one period near 0 (a the sample's value at its first period end,
    /// f^p(0)), and its exact period, where the model has one: in the renormalised
    /// coordinate z = Λ w the model is z -> z^2 + c' with c' = Λ a, whose attracting fixed
    /// point is [`model::fixed_point`]'s (the minibrot's cardioid, k = 1) and whose k-cycle
    /// Newton's method finds ([`model::attractor`]) where c' lies in a bulb of the standard
    /// Mandelbrot set of period k, so that samples in the minibrot's bulbs get Newton's test of
    /// period k p at their first period end too, rather than after waiting for their orbit to
    /// come back to an anchor. `k` is the period the model had at the sample's offset
    /// ([`Perturbation::start_model`]; 0: none, and so None here, as where Λ is unknown or
    /// Newton's method finds no attracting cycle at the sample's own value).
    pub(in crate::orbit) fn model_cycle(&self, a: [f64; 2], k: u32) -> Option<([f64; 2], u32)> {
        let lam = self.renormal?;
        let c = cto_f64(cmul(lam, cconv::<f64, FloatExp>(a)));
        let (z, k) = match k {
            0 => return None,
            1 => (model::fixed_point(c)?, 1),
            k => model::attractor(c, k)?,
        };
        Some((from_model(lam, z)?, k))
    }

    /// f^(k p)(w) and its first and second derivatives in w, for a full value w near 0 and
    /// the sample offset `dc`, by perturbation against k turns of one period p of a
    /// nucleus's reference from Z_0 = 0 (each turn ending at Z_p, near 0, where the next
    /// begins from Z_0 with δ the full value): BLA steps where the f64 tables have them
    /// (δ' = A δ + B δc + A2 δ^2 + AB δ δc + B2 δc^2, so d1' = m d1 with m = A + 2 A2 δ +
    /// AB δc and d2' = m d2 + 2 A2 d1^2), single steps elsewhere (d1' = 2 z d1,
    /// d2' = 2 (d1^2 + z d2)); d2 only when `second` asks. None where the orbit of w escapes
    /// or leaves the reference within a turn (it would rebase elsewhere than at Z_p).
    #[inline(always)]
    pub(in crate::orbit) fn return_map(
        &self,
        w: [f64; 2],
        dc: [f64; 2],
        p: u32,
        k: u32,
        second: bool,
    ) -> Option<interior::Turn> {
        self.return_map_with::<false>(w, dc, p, k, second).map(|(t, _)| t)
    }

    /// [`Perturbation::return_map`], with its [`interior::Sensitivity`] to the parameter
    /// when `C`: e = ∂z/∂c and f = ∂²z/∂w∂c, through a BLA step e' = m e + n (n = B + AB δ +
    /// 2 B2 δc, the step's derivative in δc) and f' = m f + d1 (2 A2 e + AB), through a
    /// single step e' = 2 z e + 1 and f' = 2 (d1 e + z f).
    pub(in crate::orbit) fn return_map_with<const C: bool>(
        &self,
        w: [f64; 2],
        dc: [f64; 2],
        p: u32,
        k: u32,
        second: bool,
    ) -> Option<(interior::Turn, Option<interior::Sensitivity>)> {
        let r = &self.refs[0];
        let table = self.bla_f64[0].as_ref();
        let mut z = w;
        // d1 as an f64 pair with its own exponent (FloatExp for each product would double
        // the cost of the turn); d2 likewise ([`Scaled`]: only its size enters Newton's
        // bound), and only when requested; e and f likewise.
        let mut d1 = Der { mant: [1.0, 0.0], exp: 0, add: 0.0 };
        let (mut d2, mut e, mut f) = (Scaled::ZERO, Scaled::ZERO, Scaled::ZERO);
        for _ in 0..k {
            let (mut dz, mut m) = (z, 0u32);
            while m < p {
                let zm = r.get(m);
                let full = cadd(zm, dz);
                let (f2, d2z) = (norm2(full), norm2(dz));
                if f2 > self.escape2 || (m > 0 && f2 < d2z) {
                    return None;
                }
                let d = || Scaled::new(d1.mant, d1.exp);
                if let Some(t) = table
                    && let Some((s, len)) = t.lookup(m, d2z, p - m)
                {
                    let linear = s.linear(d2z);
                    let (next, jac, jc) = if linear {
                        (cadd(cmul(s.first.a, dz), cmul(s.first.b, dc)), s.first.a, s.first.b)
                    } else {
                        s.apply_with_jacobian(dz, dc)
                    };
                    // 2 A2 (as d, made only where it is used: on the plain turn of Newton's
                    // first steps, neither asks for it).
                    let a2 = || Scaled::from_f64(s.second.a2).ldexp(1);
                    if C {
                        let mix = if linear { Scaled::ZERO } else { a2() * e + Scaled::from_f64(s.second.ab) };
                        f = Scaled::from_f64(jac) * f + d() * mix;
                        e = Scaled::from_f64(jac) * e + Scaled::from_f64(jc);
                    }
                    if second {
                        d2 = Scaled::from_f64(jac) * d2 + a2() * d().square();
                    }
                    d1.mul(jac);
                    (dz, m) = (next, m + len);
                    continue;
                }
                if C {
                    f = (d() * e + Scaled::from_f64(full) * f).ldexp(1);
                    e = (Scaled::from_f64(full) * e).ldexp(1) + Scaled::from_f64([1.0, 0.0]);
                }
                if second {
                    d2 = (d().square() + Scaled::from_f64(full) * d2).ldexp(1);
                }
                d1.mul([full[0] * 2.0, full[1] * 2.0]);
                dz = cadd(cmul([zm[0] * 2.0 + dz[0], zm[1] * 2.0 + dz[1]], dz), dc);
                m += 1;
            }
            z = cadd(r.get(p), dz);
        }
        let turn = interior::Turn { z, d1: d1.to_fe(), d2: second.then_some(d2.to_fe()) };
        Some((turn, C.then(|| interior::Sensitivity { dc: e.to_fe(), dwc: f.to_fe() })))
    }
}
