//! The turn loop: where the reference is one period of a nucleus, samples near the minibrot
//! go round it turn after turn (a rebase at Z_p, a single step to Z_1, one period-aligned
//! BLA step back to Z_p), and those passes run here without the table search at Z_1 that
//! `Perturbation::op` would make each time, in the same operations and order (so the same
//! bits).

use super::{Counters, Ctx, DOWN, Der, Exit, GLITCH2, Perturbation, Sample, found_interior, reference_value};
use crate::num::Real;
use crate::num::real::{cadd, cto_f64, norm2};

impl Perturbation {
    /// The passes of [`Perturbation::op`] through the turns of a nucleus's reference, for a
    /// sample (f64 phase, no traps) that a BLA step has just brought to the reference's end
    /// Z_p: there it rebases to Z_0 = 0 and takes the single step to Z_1, from where one
    /// period-aligned step reaches Z_p again, turn after turn while it stays near the
    /// minibrot (tens to thousands of turns at a minibrot-centred view). The same operations
    /// in the same order as `op`'s passes, so the same bits; what it saves is the search
    /// for the step at Z_1 (the step [`BlaTable::fixed_step`] says the search would find,
    /// taken while |δ|^2 is below its bound) and the tests for what cannot happen at these
    /// two indices. Returns None, to go on in `op`, at the start of a pass at Z_1 that would
    /// do anything else (rebase, single steps, another step); the tests it has done there
    /// give the same answers again.
    #[inline(never)]
    pub(super) fn turns<D: Real, const DER: bool, const INT: bool>(
        &self,
        s: &mut Sample<D>,
        der: &mut Der,
        ctx: Ctx<'_, D>,
        local: &mut Counters,
    ) -> Option<Exit<D>> {
        if INT && s.probe.plain {
            return self.turns::<D, DER, false>(s, der, ctx, local);
        }
        let r = &self.refs[s.which];
        let table = ctx.tables[self.refs.len() - 1]?;
        let (step, len, bound) = table.fixed_step(1)?;
        let last = r.last();
        if s.which != self.refs.len() - 1 || len == 0 || 1 + len != last {
            return None;
        }
        let at = |m: u32| reference_value::<D>(|| r.get(m), || r.get_fe(m));
        let (z_end, z_one) = (at(last), at(1));
        let glitch2 = norm2(z_one).mul_f64(GLITCH2);
        loop {
            // The pass at Z_p: end tests, the rebase, Newton's test, the step to Z_1.
            if INT && s.shrink.interior(self.check()) {
                return found_interior(local, false);
            }
            let full = cadd(z_end, s.dz);
            let z = cto_f64(full);
            if let Some(exit) = self.ends::<D, DER>(s, z, der, &[], &mut []) {
                return Some(exit);
            }
            let f2 = norm2(full);
            self.rebase(s, full, false, local);
            if INT && self.newton_probe(s) {
                return found_interior(local, true);
            }
            if ctx.hybrid && z[0].abs().max(z[1].abs()) < DOWN {
                return Some(Exit::Switch(*s));
            }
            if let Some(exit) = self.perturb_step::<D, DER, INT>(s, der, ctx, ([D::ZERO; 2], full, z, f2), local) {
                return Some(exit);
            }
            // The pass at Z_1, while it takes the step back to Z_p.
            if INT && s.shrink.interior(self.check()) {
                return found_interior(local, false);
            }
            let full = cadd(z_one, s.dz);
            if let Some(exit) = self.ends::<D, DER>(s, cto_f64(full), der, &[], &mut []) {
                return Some(exit);
            }
            let (d2, f2) = (norm2(s.dz), norm2(full));
            // `op`'s rebase, glitch and single-step tests, then the bound and budget under
            // which its search finds `step` (a NaN fails the bound, as it fails the search).
            let elsewhere = f2 < d2 || f2 < glitch2 || s.single || d2.to_f64() > self.single_d2;
            let found = d2.partial_cmp(&bound) == Some(std::cmp::Ordering::Less) && self.max_iter - s.n >= len;
            if elsewhere || !found {
                return None;
            }
            self.apply_bla::<D, DER, INT>((step, len), s, d2, der, ctx.add_fe, local);
        }
    }
}
