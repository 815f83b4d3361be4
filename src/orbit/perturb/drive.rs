//! The drivers: where samples enter the loop and how they move between its parts. One
//! sample ([`Perturbation::orbit`]) or a batch ([`Perturbation::orbits`]: interior
//! detection's certified disks and models first, then each sample), each begun in the
//! number type its offset needs, handed to the vector lanes at single steps and back, and
//! switched between FloatExp and f64 as its delta crosses the range where every term of
//! the step is a normal f64 ([`Perturbation::drive`]).

use std::sync::atomic::AtomicBool;

use super::start::Given;
use super::*;

impl Perturbation {
    /// Iterates the sample at `offset` (in units of the spacing, from the reference point),
    /// letting traps observe every z_k, k >= 1. Returns the orbit's end; z_n is exact to f64
    /// and dz_n is the derivative times the spacing. `cancel`: the render's flag; once it is
    /// raised the orbit may be cut short (a cancelled render keeps no sample), though only
    /// where the steps of whole blocks past the BLA tree were to be built for it.
    pub fn orbit(
        &self,
        offset: [f64; 2],
        traps: &[Trap],
        states: &mut [TrapState],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) -> Orbit {
        let (start, mut der, add_fe) = self.start(offset, None, traps.is_empty(), counters);
        let fe = self.starts_in_floatexp(&start);
        let phase = if fe { Phase::Fe(start) } else { Phase::F64(start.convert()) };
        self.finish(phase, start.dc, &mut der, add_fe, traps, states, counters, cancel)
    }

    /// Iterates many samples without traps. Same results as [`Perturbation::orbit`], bit for
    /// bit, whatever `simd` is: with vectors (AVX2, AVX-512, NEON), single steps above
    /// `single_d2` run several samples to a vector (`perturb/lanes.rs`); with `scalar`,
    /// `LANES` samples at a time in the f64 phase (samples in their FloatExp phase run one at
    /// a time).
    ///
    /// In a view centred on a nucleus with interior detection on, groups of samples that lie
    /// in the minibrot's cardioid or bulbs are first found interior together
    /// (`Perturbation::certified_disks`): the same N as iterating them, since each is
    /// interior.
    ///
    /// `cancel` as for [`Perturbation::orbit`].
    pub fn orbits(
        &self,
        offsets: &[[f64; 2]],
        out: &mut [Orbit],
        counters: &mut Counters,
        simd: SimdLevel,
        cancel: &AtomicBool,
    ) {
        let models = self.sample_models(offsets, simd);
        let Some(done) = self.certified_disks(offsets, models.as_deref(), counters) else {
            return self.orbits_each(offsets, models.as_deref(), out, counters, simd, cancel);
        };
        let rest: Vec<usize> = (0..offsets.len()).filter(|&k| !done[k]).collect();
        let at: Vec<[f64; 2]> = rest.iter().map(|&k| offsets[k]).collect();
        let known: Option<Vec<Model>> = models.map(|m| rest.iter().map(|&k| m[k]).collect());
        let mut each = vec![Orbit::interior(); at.len()];
        self.orbits_each(&at, known.as_deref(), &mut each, counters, simd, cancel);
        for (k, d) in done.iter().enumerate() {
            if *d {
                out[k] = Orbit::interior();
            }
        }
        for (&k, o) in rest.iter().zip(each) {
            out[k] = o;
        }
    }

    /// [`Perturbation::orbits`] for samples each iterated; `known`: their
    /// [`Perturbation::start_model`]s where the batch worked them out.
    pub(super) fn orbits_each(
        &self,
        offsets: &[[f64; 2]],
        known: Option<&[Model]>,
        out: &mut [Orbit],
        counters: &mut Counters,
        simd: SimdLevel,
        cancel: &AtomicBool,
    ) {
        if lanes::orbits(self, offsets, known, out, counters, simd, cancel) {
            return;
        }
        match (self.derivative, self.interior.is_some()) {
            (false, false) => self.orbits_with::<false, false>(offsets, known, out, counters, cancel),
            (true, false) => self.orbits_with::<true, false>(offsets, known, out, counters, cancel),
            (false, true) => self.orbits_with::<false, true>(offsets, known, out, counters, cancel),
            (true, true) => self.orbits_with::<true, true>(offsets, known, out, counters, cancel),
        }
    }

    /// [`Perturbation::orbits`] with the derivative carried or not (`DER`) and interior
    /// detection on or off (`INT`), compiled apart so that the common case has no branches of
    /// either in its loop.
    pub(super) fn orbits_with<const DER: bool, const INT: bool>(
        &self,
        offsets: &[[f64; 2]],
        known: Option<&[Model]>,
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) {
        let add_fe = self.add_fe();
        let c64 = self.ctx(&self.bla_f64, true, add_fe, cancel);
        let mut lanes: [Option<Lane>; LANES] = [None; LANES];
        let mut next = 0;
        let mut local = Counters::default();
        loop {
            for slot in lanes.iter_mut() {
                while slot.is_none() && next < offsets.len() {
                    let k = next;
                    next += 1;
                    let (start, mut der, _) = self.start(offsets[k], known.map(|m| m[k]), true, counters);
                    let s = if self.starts_in_floatexp(&start) {
                        let cfe = self.ctx(&self.bla_fe, true, add_fe, cancel);
                        match self.run::<FloatExp>(start, &mut der, cfe, &[], &mut [], counters) {
                            Exit::Done(o) => {
                                out[k] = o;
                                continue;
                            }
                            Exit::Switch(s) | Exit::Vector(s) => s.convert(),
                        }
                    } else {
                        start.convert()
                    };
                    *slot = Some(Lane { k, s, der, start_n: s.n, dc_fe: start.dc });
                }
            }
            if lanes.iter().all(Option::is_none) {
                break;
            }
            // Round robin until a lane finishes; then refill. With both lanes busy they are
            // stepped as two locals, so that their state stays in registers.
            let (l, exit) = match &mut lanes {
                [Some(a), Some(b)] => {
                    let (mut a2, mut b2) = (*a, *b);
                    let r = loop {
                        if let Some(e) = self.op::<f64, DER, INT>(&mut a2.s, &mut a2.der, c64, &[], &mut [], &mut local)
                        {
                            break (0, e);
                        }
                        if let Some(e) = self.op::<f64, DER, INT>(&mut b2.s, &mut b2.der, c64, &[], &mut [], &mut local)
                        {
                            break (1, e);
                        }
                    };
                    (*a, *b) = (a2, b2);
                    r
                }
                _ => {
                    let l = lanes.iter().position(Option::is_some).unwrap_or(0);
                    let Some(lane) = &mut lanes[l] else { continue };
                    (l, self.steps::<f64, DER, INT>(&mut lane.s, &mut lane.der, c64, &[], &mut [], &mut local))
                }
            };
            if let Some(lane) = &mut lanes[l] {
                local.iterations += (lane.s.n - lane.start_n) as u64;
                out[lane.k] = match exit {
                    Exit::Done(o) => o,
                    Exit::Switch(s) => {
                        let fe = Sample { dc: lane.dc_fe, ..s.convert() };
                        self.finish(Phase::Fe(fe), lane.dc_fe, &mut lane.der, add_fe, &[], &mut [], counters, cancel)
                    }
                    Exit::Vector(_) => unreachable!("the two-lane loop never asks for the vector lanes"),
                };
            }
            lanes[l] = None;
        }
        counters.add(&local);
    }

    /// What the derivative adds per step (the spacing for the Mandelbrot set).
    pub(super) fn add_fe(&self) -> FloatExp {
        if self.mandelbrot { self.spacing } else { FloatExp::ZERO }
    }

    /// Runs sample `k` from its start until it ends (written to `out`) or reaches a single
    /// step in single-step mode, where it is returned for the vector lanes. `given`: its
    /// series start where the lanes' feed worked it out beside its neighbours'
    /// ([`Perturbation::series_starts`]).
    #[allow(clippy::too_many_arguments)] // the sample, its series start, and where it goes
    pub(super) fn begin(
        &self,
        k: usize,
        offset: [f64; 2],
        known: Option<Model>,
        given: Option<Given>,
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) -> Option<Held> {
        let (start, der, _) = self.start_given(offset, known, true, given, counters);
        let phase = if self.starts_in_floatexp(&start) { Phase::Fe(start) } else { Phase::F64(start.convert()) };
        self.hand_over(phase, k, start.dc, der, out, counters, cancel)
    }

    /// Runs a sample (output index `k`) from `phase` with the lanes in use: writes its orbit
    /// to `out` when it ends, or returns it for the lanes.
    pub(super) fn hand_over(
        &self,
        phase: Phase,
        k: usize,
        dc_fe: [FloatExp; 2],
        mut der: Der,
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) -> Option<Held> {
        match self.drive(phase, dc_fe, &mut der, self.add_fe(), &[], &mut [], true, counters, cancel) {
            Ended::Done(o) => {
                out[k] = o;
                None
            }
            Ended::Vector(s) => Some(Held { k, s, der, dc_fe, renorm: false }),
        }
    }

    /// Runs a sample from `phase` to its end without the lanes.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn finish(
        &self,
        phase: Phase,
        dc_fe: [FloatExp; 2],
        der: &mut Der,
        add_fe: FloatExp,
        traps: &[Trap],
        states: &mut [TrapState],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) -> Orbit {
        match self.drive(phase, dc_fe, der, add_fe, traps, states, false, counters, cancel) {
            Ended::Done(o) => o,
            Ended::Vector(_) => unreachable!("drive hands samples to the lanes only when asked"),
        }
    }

    /// Continues a sample the vector lanes handed back: after a renormalisation of its
    /// derivative (`renorm`), or else at an event the lanes do not handle (escape, the
    /// iteration limit, a rebase or glitch, the reference's end, |dz/dz|^2 out of its
    /// window or below the threshold), which one full pass of the scalar loop takes care of
    /// before the sample runs on as [`Perturbation::begin`]'s do.
    pub(super) fn resume(
        &self,
        mut h: Held,
        out: &mut [Orbit],
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) -> Option<Held> {
        let add_fe = self.add_fe();
        let phase = if h.renorm {
            h.der.renormalise(add_fe);
            Phase::F64(h.s)
        } else {
            let c64 = self.ctx(&self.bla_f64, true, add_fe, cancel);
            let n0 = h.s.n;
            let mut local = Counters::default();
            let (s, der, l) = (&mut h.s, &mut h.der, &mut local);
            let exit = match (self.derivative, self.interior.is_some()) {
                (false, false) => self.op::<f64, false, false>(s, der, c64, &[], &mut [], l),
                (true, false) => self.op::<f64, true, false>(s, der, c64, &[], &mut [], l),
                (false, true) => self.op::<f64, false, true>(s, der, c64, &[], &mut [], l),
                (true, true) => self.op::<f64, true, true>(s, der, c64, &[], &mut [], l),
            };
            local.iterations = (h.s.n - n0) as u64;
            counters.add(&local);
            match exit {
                None => Phase::F64(h.s),
                Some(Exit::Done(o)) => {
                    out[h.k] = o;
                    return None;
                }
                Some(Exit::Switch(s)) => Phase::Fe(Sample { dc: h.dc_fe, ..s.convert() }),
                Some(Exit::Vector(s)) => Phase::F64(s),
            }
        };
        self.hand_over(phase, h.k, h.dc_fe, h.der, out, counters, cancel)
    }

    /// Runs a sample from `phase` to its end, switching number types as its delta asks (with
    /// `vector`, until it reaches a single step in single-step mode in its f64 phase).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn drive(
        &self,
        mut phase: Phase,
        dc_fe: [FloatExp; 2],
        der: &mut Der,
        add_fe: FloatExp,
        traps: &[Trap],
        states: &mut [TrapState],
        vector: bool,
        counters: &mut Counters,
        cancel: &AtomicBool,
    ) -> Ended {
        let bla = traps.is_empty();
        let cfe = self.ctx(&self.bla_fe, bla, add_fe, cancel);
        let c64 = Ctx { vector, ..self.ctx(&self.bla_f64, bla, add_fe, cancel) };
        loop {
            phase = match phase {
                Phase::Fe(s) => match self.run::<FloatExp>(s, der, cfe, traps, states, counters) {
                    Exit::Done(o) => return Ended::Done(o),
                    Exit::Switch(s) | Exit::Vector(s) => Phase::F64(s.convert()),
                },
                Phase::F64(s) => match self.run::<f64>(s, der, c64, traps, states, counters) {
                    Exit::Done(o) => return Ended::Done(o),
                    Exit::Vector(s) => return Ended::Vector(s),
                    // The offset goes back to FloatExp from the original, never from its
                    // f64 rounding: below 2^-1022 that keeps only a few bits.
                    Exit::Switch(s) => Phase::Fe(Sample { dc: dc_fe, ..s.convert() }),
                },
            }
        }
    }
}
