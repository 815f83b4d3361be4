//! Disks of parameters certified interior together: before a batch of samples is iterated
//! in a view centred on a nucleus, the parts of it that lie in the minibrot's cardioid or
//! its bulbs are found interior whole, each disk by one certificate
//! ([`interior::disk_attracting`]: Newton's method at the disk's centre, then Kantorovich's
//! theorem over every parameter of the disk), rather than sample by sample.
//!
//! The batch is halved across its bounding box's longer side while its disk fails; the
//! quadratic model ([`super::model`]) gates each try, so that a certificate is computed only
//! where the model puts the disk well inside a component, and the halving stops where its
//! distance estimate puts a disk far outside. A part whose samples' own models
//! (`Perturbation::sample_models`) do not all have the same period lies across a
//! component's edge: it is halved without a try (on the 1e102 minibrot view, the tries at
//! such parts had cost as much as all the certificates). A certified sample gets the value
//! of one that reached the iteration limit, so the disks change no pixel, only the time.

use super::model::{self, Model};
use super::probe::from_model;
use crate::num::FloatExp;
use crate::num::real::{cmul, cto_f64, norm2};
use crate::orbit::interior;
use crate::orbit::perturb::start::delta_c;
use crate::orbit::perturb::{Counters, MAX_CYCLE_PERIODS, Numbers, Perturbation};

/// Iterations of the quadratic model's orbit at most in a disk's gate (the cycles of bulbs
/// of period up to [`MAX_CYCLE_PERIODS`] are found within this where a disk can be
/// certified).
const DISK_MODEL_ITERATIONS: u32 = 256;
/// Newton's steps for the model's cycle at a disk's centre from a sample's, and at its edge
/// from the centre's ([`model::attractor_from`]), before the search from 0.
const HINT_STEPS: u32 = 8;
/// The fewest samples `Perturbation::certified_disks` tries a disk for.
const DISK_MIN: usize = 4;

/// What a disk of parameters was found to be ([`Perturbation::disk_interior`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Disk {
    /// Certified interior.
    Interior,
    /// Not certified; smaller disks inside it may be.
    Failed,
    /// Far outside the model's Mandelbrot set, it and every smaller disk of its parts: not
    /// worth halving.
    Outside,
}

impl Perturbation {
    /// The samples of a batch that lie in disks of parameters certified interior
    /// ([`interior::disk_attracting`]), marked, and counted into `counters`; None where
    /// there are none, or the view is not one where they are looked for: a Mandelbrot view
    /// centred on a nucleus, with interior detection on and f64 deltas (the Newton test's
    /// arithmetic).
    ///
    /// The batch is tried as one disk, the one around its samples' bounding box, and halved
    /// across the box's longer side (so that the parts tend to squares) while it fails, down
    /// to [`DISK_MIN`] samples. A disk is tried where every sample's model has a cycle of the
    /// same period, and where the quadratic model puts the disk well inside the minibrot's
    /// cardioid or one of its bulbs (`Perturbation::disk_interior`); then
    /// Newton's method finds the cycle at the disk's centre from the model's, and the disk
    /// certificate decides. What no disk covers is iterated as before.
    pub(in crate::orbit) fn certified_disks(
        &self,
        offsets: &[[f64; 2]],
        models: Option<&[Model]>,
        counters: &mut Counters,
    ) -> Option<Vec<bool>> {
        let (p, lam) = (self.newton_period()?, self.renormal?);
        if !self.disks || self.numbers != Numbers::F64 || offsets.len() < DISK_MIN {
            return None;
        }
        let scale = self.model_scale?;
        let mut done = vec![false; offsets.len()];
        // Disks are tried among the samples whose model has a short attracting cycle.
        let models = models?;
        let mut idx: Vec<usize> =
            (0..offsets.len()).filter(|&k| matches!(models[k], Model::Cycle(_, n) if n <= MAX_CYCLE_PERIODS)).collect();
        let found = self.disks_in(offsets, models, &mut idx, &mut done, (p, lam, scale));
        counters.interior += found;
        counters.newton += found;
        counters.disks += found;
        (found > 0).then_some(done)
    }

    /// `Perturbation::certified_disks` on a part of the batch, the samples `idx` (reordered here).
    fn disks_in(
        &self,
        offsets: &[[f64; 2]],
        models: &[Model],
        idx: &mut [usize],
        done: &mut [bool],
        model: (u32, [FloatExp; 2], [FloatExp; 2]),
    ) -> u64 {
        if idx.len() < DISK_MIN {
            return 0;
        }
        let (lo, hi) = idx.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), &k| {
            let o = offsets[k];
            ([lo[0].min(o[0]), lo[1].min(o[1])], [hi[0].max(o[0]), hi[1].max(o[1])])
        });
        let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
        // Half the box's diagonal, a little more for the rounding of the centre.
        let r = ((hi[0] - lo[0]) / 2.0).hypot((hi[1] - lo[1]) / 2.0) * (1.0 + 1e-9);
        let Model::Cycle(hint, period) = models[idx[0]] else { return 0 };
        let uniform = idx.iter().all(|&k| matches!(models[k], Model::Cycle(_, n) if n == period));
        let verdict = if uniform { self.disk_interior(centre, r, (hint, period), model) } else { Disk::Failed };
        match verdict {
            Disk::Interior => {
                for &k in idx.iter() {
                    done[k] = true;
                }
                return idx.len() as u64;
            }
            // Every part's disk lies within twice this one's radius of its centre.
            Disk::Outside => return 0,
            Disk::Failed => {}
        }
        if idx.len() < 2 * DISK_MIN {
            return 0;
        }
        // Halved across the box's longer side, so that the parts tend to squares.
        let axis = usize::from(hi[1] - lo[1] > hi[0] - lo[0]);
        let h = idx.len() / 2;
        idx.select_nth_unstable_by(h, |&a, &b| offsets[a][axis].total_cmp(&offsets[b][axis]));
        let (a, b) = idx.split_at_mut(h);
        self.disks_in(offsets, models, a, done, model) + self.disks_in(offsets, models, b, done, model)
    }

    /// Whether the disk of radius `r` about `centre` (offsets, in spacings) is certified
    /// interior (`Perturbation::certified_disks`). The gate: the model's parameter
    /// c' = K δc (K = Λ ∂Z_p/∂c at the nucleus) and the disk's radius there r' = |K| rho. In
    /// the cardioid the model's multiplier is μ = 1 - sqrt(1 - 4 c') and the certificate's
    /// bounds come to what is tested below; in a bulb of period k up to
    /// [`MAX_CYCLE_PERIODS`], the multiplier of the model's k-cycle at the centre and at the
    /// disk's edge stand in for them. `hint`: a point of a sample's model cycle, of period
    /// `period`, where Newton's method looks for the centre's first.
    fn disk_interior(
        &self,
        centre: [f64; 2],
        r: f64,
        (hint, period): ([f64; 2], u32),
        (p, lam, scale): (u32, [FloatExp; 2], [FloatExp; 2]),
    ) -> Disk {
        let dc_fe = delta_c::<FloatExp>(self.spacing, self.origin, centre);
        let dc = cto_f64(dc_fe);
        let rho = self.spacing.mul_f64(r).to_f64();
        let normal = |x: f64| x == 0.0 || x.is_normal();
        if !(normal(dc[0]) && normal(dc[1]) && rho.is_normal()) {
            return Disk::Failed;
        }
        // The model's gate.
        let cm = cto_f64(cmul(scale, dc_fe));
        let rm = norm2(scale).sqrt().mul_f64(rho).to_f64();
        let (z, k) = if let Some(z) = model::fixed_point(cm) {
            // In the model the certificate's bounds come to about |μ| + 6 r' / |1 - μ| for
            // the multiplier and 5 r' / |1 - μ|^2 for Kantorovich's h (r' the disk's radius
            // there).
            let mu = [2.0 * z[0], 2.0 * z[1]];
            let gap = norm2([1.0 - mu[0], -mu[1]]).sqrt();
            let fits = norm2(mu).sqrt() + 6.3 * rm / gap < 1.0 && 5.3 * rm < 0.25 * gap * gap;
            if !fits {
                return Disk::Failed;
            }
            (z, 1)
        } else {
            // A bulb's k-cycle: its multiplier at the centre, and its change across the disk
            // as the model's cycle at the disk's edge has it, taken 4.5 times (as the
            // cardioid's bounds take theirs about 3 times, with room for Kantorovich's h).
            let near = |c: [f64; 2], z: [f64; 2], k: u32| {
                model::attractor_from(c, k, z, HINT_STEPS)
                    .map_or_else(|| model::cycle_within(c, DISK_MODEL_ITERATIONS), |(z, k)| Model::Cycle(z, k))
            };
            let (z, k) = match near(cm, hint, period) {
                Model::Cycle(z, k) => (z, k),
                Model::Escapes if model::far(cm, 2.0 * rm, DISK_MODEL_ITERATIONS) => return Disk::Outside,
                _ => return Disk::Failed,
            };
            let edge = [cm[0] + rm, cm[1]];
            let Model::Cycle(z_edge, k_edge) = near(edge, z, k) else {
                return Disk::Failed;
            };
            if k > MAX_CYCLE_PERIODS || k_edge != k {
                return Disk::Failed;
            }
            let (mu, mu_edge) = (model::multiplier(cm, z, k), model::multiplier(edge, z_edge, k));
            let change = norm2([mu_edge[0] - mu[0], mu_edge[1] - mu[1]]).sqrt();
            if norm2(mu).sqrt() + 4.5 * change >= 1.0 {
                return Disk::Failed;
            }
            (z, k)
        };
        let Some(w0) = from_model(lam, z) else { return Disk::Failed };
        let Some(w) = interior::newton_cycle(w0, |w, second| self.return_map(w, dc, p, k, second)) else {
            return Disk::Failed;
        };
        let certified = interior::disk_attracting(w, rho, |w, shift| {
            let (t, s) = self.return_map_with::<true>(w, [dc[0] + shift[0], dc[1] + shift[1]], p, k, true)?;
            Some((t, s?))
        });
        if certified { Disk::Interior } else { Disk::Failed }
    }
}
