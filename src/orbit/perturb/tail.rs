//! The loop through a reference's packed tail ([`crate::orbit::reference::packed::Packed`]): values
//! read in order rather than by index, and steps of whole blocks at the blocks' boundaries.

use super::{Counters, Ctx, DOWN, Der, Exit, GLITCH2, Perturbation, Sample, found_interior, reference_value};
use crate::cancel::Cancelled;
use crate::formula::end::Orbit;
use crate::num::real::{cadd, cto_f64, norm2};
use crate::num::{FloatExp, Real};
use crate::orbit::reference::packed::Packed;
use crate::trap::{Trap, TrapState};

impl Perturbation {
    /// The loop through a reference's packed tail ([`Packed`]), entered at Z_last (the end
    /// of the dense part) with that pass's end tests done and (Z_last, z, z in f64) in
    /// `at`: single steps, the values read in order, and at each block boundary the
    /// longest valid step of whole blocks (`bla::TailSteps`, after which the sample reads
    /// on from the table's cursor where the step ends), until the sample rebases (and takes
    /// the rebase's step, as [`Perturbation::op`] does), escapes, is found interior or
    /// reaches the limit. The passes are `op`'s, in its order, and the blocks begin where
    /// a dense orbit's blocks past the tree would (`bla::TailSteps`), so a sample steps
    /// through the same bits as through the same orbit stored densely. It keeps its number
    /// type and leaves the vector lanes aside until it is back in the dense part, which is
    /// the only part they read by index.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn tail<D: Real, const DER: bool, const INT: bool>(
        &self,
        s: &mut Sample<D>,
        der: &mut Der,
        ctx: Ctx<'_, D>,
        at: ([D; 2], [D; 2], [f64; 2]),
        traps: &[Trap],
        states: &mut [TrapState],
        local: &mut Counters,
        packed: &Packed,
    ) -> Option<Exit<D>> {
        let full_range = D::NAME == FloatExp::NAME;
        let (mut zm, mut full, mut z) = at;
        // Entered at the seed only: the cursor starts there.
        debug_assert_eq!(s.m, packed.seed_index());
        let mut cursor = packed.cursor();
        let steps = match ctx.tables[s.which].map(|t| t.tail(ctx.cancel)) {
            Some(Err(Cancelled)) => return Some(Exit::Done(Orbit::interior())),
            Some(Ok(steps)) => steps,
            None => None,
        };
        loop {
            let d2 = norm2(s.dz);
            let f2 = norm2(full);
            let end = s.m >= packed.last();
            let rebase = f2 < d2 || end;
            let glitch = !rebase && f2 < norm2(zm).mul_f64(GLITCH2);
            if rebase || glitch {
                self.rebase(s, full, glitch, local);
                if ctx.hybrid && !full_range && z[0].abs().max(z[1].abs()) < DOWN {
                    return Some(Exit::Switch(*s));
                }
                zm = [D::ZERO; 2];
            }
            // A block's step where one starts here and is valid (in the f64 phase, for a
            // delta that `op` would still look a step up for).
            let bla = !(rebase || glitch || self.goes_single(s, d2));
            if let Some(t) = steps.filter(|_| bla)
                && let Some((e, len, at)) = t.lookup(s.m, d2, self.max_iter - s.n)
                && let Some(reader) = t.reader(at)
            {
                self.apply_step::<D, DER, INT>((e, len), s, d2, der, ctx.add_fe, local);
                local.tail_steps += 1;
                cursor = reader;
            } else {
                let switch = self.perturb_step::<D, DER, INT>(s, der, ctx, (zm, full, z, f2), local);
                if rebase || glitch {
                    // Back in the dense part: the switch `op` takes after a step. Within the
                    // tail the sample keeps its number type.
                    return switch;
                }
                let more = cursor.advance(packed);
                debug_assert!(more, "the tail's end was tested before the step");
            }
            debug_assert_eq!(cursor.index(), s.m, "the reader stands at the sample's index");
            if INT && s.shrink.interior(self.check()) {
                return found_interior(local, false);
            }
            zm = reference_value(|| cursor.get(), || cursor.get_fe(packed));
            full = cadd(zm, s.dz);
            z = cto_f64(full);
            if let Some(exit) = self.ends::<D, DER>(s, z, der, traps, states) {
                return Some(exit);
            }
        }
    }
}
