//! The reference orbit: one orbit iterated in arbitrary precision, stored compactly.
//!
//! Every sample of a deep view is iterated as a small delta against this orbit. The orbit
//! is computed once per scene (all tiles share it) at a precision chosen from the view's
//! depth, and stored as f64 pairs (16 bytes per iteration). Values whose exponent falls
//! below the f64 range (|Z| < 2^-1000, which happens when the orbit passes very close to 0
//! near a deep minibrot's nucleus) are also kept, sparsely, as `FloatExp`, because deep
//! deltas must not be stepped against a Z that f64 rounded to zero.
//!
//! An orbit longer than the dense store's limit ([`Stepping::dense_limit`]) keeps the rest
//! predictively coded ([`Packed`], 1.0–1.4 bytes per iteration, the same values exactly):
//! the loop reads the dense part by index, with BLA, and the tail in order by single steps.

pub mod comba;
pub mod cycle;
pub mod fixed;
pub mod handover;
#[cfg(feature = "mpfr")]
pub mod mpfr;
pub mod packed;
pub mod square;
pub mod team;

use std::sync::atomic::{AtomicBool, Ordering};

use malachite_float::Float;

use crate::cancel::Cancelled;
use crate::num::FloatExp;
use crate::num::bigfloat::{self, BigComplex};
use crate::simd_level::SimdLevel;
use cycle::Brent;
use fixed::FixedOrbit;
use packed::{Cursor, Packed, TINY};

/// Iterations between progress reports and cancellation checks.
const REPORT_EVERY: u32 = 4096;

/// How a reference orbit's steps run: shared with a helper thread where that pays (see
/// [`FixedOrbit::with_stepper`]), and with which instruction set.
#[derive(Debug, Clone, Copy, Default)]
pub struct Stepping {
    /// Share wide steps with a helper thread.
    pub share: bool,
    /// Instruction set of the fixed-point squares.
    pub simd: SimdLevel,
    /// Stop at the first n >= 1 where |Z_n| < `periodic_below` |dZ_n/dC| (a Mandelbrot
    /// reference from 0): C is then a nucleus of period n to far below a sample's reach,
    /// and the orbit from there is the orbit from 0 again. Samples continue through the
    /// end of the stored period by the ordinary rebase (z = Z_n + δ becomes the delta
    /// against Z_0 = 0), so one period serves any iteration limit.
    pub periodic_below: Option<FloatExp>,
    /// Store Z_0 .. Z_(dense_limit) densely and the rest packed (None: all densely).
    pub dense_limit: Option<u32>,
    /// Keep every value densely up to this index before packing what lies past
    /// `dense_limit`: an orbit that turns out periodic by then (a nucleus's) stays dense,
    /// with BLA and Newton's test over its whole period.
    pub hold: Option<u32>,
    /// Stop where the orbit repeats itself exactly ([`Reference::cycle`]); false computes
    /// it to the limit (the same values, for tests and measurements).
    pub cut_cycles: bool,
}

/// A stored value too small for f64: its index and value.
pub type Tiny = packed::Tiny;

/// Moves the values after index `d` of a dense store into a packed tail seeded with Z_d.
fn pack_after(z: &mut Vec<[f64; 2]>, tiny: &mut Vec<Tiny>, d: u32, c: [f64; 2]) -> Packed {
    let mut p = Packed::new(c, d, z[d as usize]);
    let split = tiny.partition_point(|t| t.0 <= d);
    let mut later = tiny.drain(split..).peekable();
    for (k, v) in z.iter().enumerate().skip(d as usize + 1) {
        let fe = later.next_if(|t| t.0 as usize == k).map(|t| t.1);
        p.push(*v, fe);
    }
    z.truncate(d as usize + 1);
    // The values held dense while a period might end the orbit go back now, not when it
    // ends: the packed tail grows in their place.
    z.shrink_to_fit();
    p
}

/// An orbit Z_0 .. Z_end of z -> z^2 + C: Z_0 .. Z_last densely, the rest packed.
#[derive(Debug, Clone)]
pub struct Reference {
    z: Vec<[f64; 2]>,
    tiny: Vec<Tiny>,
    packed: Option<Packed>,
    escaped: bool,
    bits: u64,
    period: Option<u32>,
    cycle: Option<u32>,
}

/// Iterations a repeating orbit is stored for at least (copies of its cycle): samples read
/// it by index, with BLA steps up to this long, and wrap back by this many iterations at
/// its end. 2^16 values take 1 MiB.
pub const CYCLE_SPAN: u32 = 1 << 16;

impl Reference {
    /// Iterates from `start` with parameter `c` until |Z| > `escape_radius` or `max_iter`.
    /// `progress` receives the iterations done so far; `cancel` stops the work. `steps` says
    /// how the steps run (the same bits whichever way).
    ///
    /// The orbit is iterated in fixed point ([`FixedOrbit`]) wherever its values fit (escape
    /// radius, |c| and |z_0| up to 2^30: every view of the Mandelbrot set, and Julia sets
    /// near theirs), else in malachite's floats; the choice depends on the scene alone, so
    /// the same scene gives the same orbit everywhere.
    #[allow(clippy::too_many_arguments)]
    pub fn compute(
        start: &BigComplex,
        c: &BigComplex,
        max_iter: u32,
        escape_radius: f64,
        bits: u64,
        steps: Stepping,
        progress: &dyn Fn(u32),
        cancel: &AtomicBool,
    ) -> Result<Reference, Cancelled> {
        let mut out = Reference {
            z: Vec::new(),
            tiny: Vec::new(),
            packed: None,
            escaped: false,
            bits,
            period: None,
            cycle: None,
        };
        let c64 = [bigfloat::to_floatexp(&c[0]).to_f64(), bigfloat::to_floatexp(&c[1]).to_f64()];
        let pack_at = steps.dense_limit.map(|d| steps.hold.map_or(d, |h| h.max(d)));
        let r2 = escape_radius * escape_radius;
        // dZ_n/dC, in FloatExp, for the period test.
        let (mut prev, mut dz) = ([FloatExp::ZERO; 2], [FloatExp::ZERO; 2]);
        // Stores Z_n; true when the orbit ends there.
        let mut keep = |n: u32, fe: [FloatExp; 2]| -> Result<bool, Cancelled> {
            let mut periodic = false;
            if let Some(scale) = steps.periodic_below
                && n >= 1
            {
                // dZ_n = 2 Z_(n-1) dZ_(n-1) + 1.
                let t = [prev[0] * dz[0] - prev[1] * dz[1], prev[0] * dz[1] + prev[1] * dz[0]];
                dz = [t[0].ldexp(1) + FloatExp::ONE, t[1].ldexp(1)];
                prev = fe;
                periodic = fe[0].abs().max(fe[1].abs()) < scale * dz[0].abs().max(dz[1].abs());
            }
            let f = [fe[0].to_f64(), fe[1].to_f64()];
            let tiny = f[0].abs().max(f[1].abs()) < TINY && !(fe[0].is_zero() && fe[1].is_zero());
            if let Some(p) = &mut out.packed {
                p.push(f, tiny.then_some(fe));
            } else {
                if tiny {
                    out.tiny.push((n, fe));
                }
                out.z.push(f);
                if pack_at == Some(n)
                    && let Some(d) = steps.dense_limit
                {
                    out.packed = Some(pack_after(&mut out.z, &mut out.tiny, d, c64));
                }
            }
            if periodic {
                out.period = Some(n);
                return Ok(true);
            }
            if f[0] * f[0] + f[1] * f[1] > r2 {
                out.escaped = true;
                return Ok(true);
            }
            if n >= max_iter {
                return Ok(true);
            }
            if n.is_multiple_of(REPORT_EVERY) {
                if cancel.load(Ordering::Relaxed) {
                    return Err(Cancelled);
                }
                progress(n);
            }
            Ok(false)
        };
        // Cycles are looked for while the orbit is stored densely.
        let detect_until = if steps.cut_cycles { pack_at.unwrap_or(u32::MAX) } else { 0 };
        let repeats = if let Some(mut orbit) = FixedOrbit::new(start, c, bits, escape_radius, steps.simd) {
            orbit.for_each_value(steps.share, r2, max_iter, detect_until, &mut keep)?
        } else {
            let mut z: BigComplex =
                [Float::from_float_prec_ref(&start[0], bits).0, Float::from_float_prec_ref(&start[1], bits).0];
            let mut n = 0u32;
            let mut cycle = Brent::new(z.clone());
            let mut found = None;
            loop {
                if keep(n, [bigfloat::to_floatexp(&z[0]), bigfloat::to_floatexp(&z[1])])? {
                    break None;
                }
                if found.is_some() {
                    // Z_n, kept, repeats the value `found` steps back.
                    break found;
                }
                bigfloat::step_assign(&mut z, c, bits);
                n += 1;
                if n <= detect_until {
                    found = cycle.found(|saved| *saved == z, |saved| saved.clone_from(&z));
                }
            }
        };
        if let Some(q) = repeats
            && out.packed.is_none()
        {
            out.repeat(q, max_iter);
        }
        out.z.shrink_to_fit();
        if let Some(p) = &mut out.packed {
            p.shrink_to_fit();
            if p.is_empty() {
                out.packed = None;
            }
        }
        Ok(out)
    }

    /// Stores copies of the orbit's last `q` values (Z_last = Z_(last - q), exactly) until
    /// it holds [`CYCLE_SPAN`] iterations past the first repeat or reaches `max_iter`, and
    /// records how far back a sample at its end continues ([`Reference::cycle`]).
    fn repeat(&mut self, q: u32, max_iter: u32) {
        let first = self.last() - q;
        let copies = CYCLE_SPAN.div_ceil(q).max(1);
        let end = (u64::from(self.last()) + u64::from(copies) * u64::from(q)).min(u64::from(max_iter)) as u32;
        let tiny: Vec<Tiny> = self.tiny.iter().filter(|t| t.0 > first).copied().collect();
        for m in self.last() + 1..=end {
            let from = m - q;
            self.z.push(self.z[from as usize]);
            // Values too small for f64 repeat with the rest (rare: a cycle through 0 itself
            // is a nucleus's, which the period test ends first).
            if let Some(t) = tiny.iter().find(|t| (m - t.0).is_multiple_of(q) && t.0 <= m) {
                self.tiny.push((m, t.1));
            }
        }
        // Past the limit nothing repeats that a sample could reach.
        let wrap = end - (first + q);
        self.cycle = (end < max_iter && wrap > 0).then_some(wrap);
    }

    /// How far back a sample that reaches [`Reference::last`] continues, where the orbit
    /// repeats itself exactly: Z_last = Z_(last - w), so the sample's index goes back by w
    /// and its delta stays as it is. None: the orbit escaped, reached the limit, or is one
    /// period of a nucleus (samples rebase at its end).
    #[inline]
    pub fn cycle(&self) -> Option<u32> {
        self.cycle
    }

    /// Index of the last value stored densely (read by index, [`Reference::get`]).
    #[inline]
    pub fn last(&self) -> u32 {
        (self.z.len() - 1) as u32
    }

    /// Index of the orbit's last value: [`Reference::last`], or the packed tail's last.
    #[inline]
    pub fn end(&self) -> u32 {
        self.packed.as_ref().map_or(self.last(), Packed::last)
    }

    /// The packed tail after Z_last, if the orbit is longer than its dense part.
    #[inline]
    pub fn packed(&self) -> Option<&Packed> {
        self.packed.as_ref()
    }

    /// A cursor at Z_last, from which the packed tail is read in order; None without one.
    #[inline]
    pub fn tail(&self) -> Option<Cursor> {
        self.packed.as_ref().map(Packed::cursor)
    }

    /// Every value Z_k for k in `from..=to` (at most [`Reference::end`]) at full range, in
    /// order: the dense part by index, the tail through a cursor.
    pub fn values_fe(&self, from: u32, to: u32) -> impl Iterator<Item = [FloatExp; 2]> + '_ {
        let to = to.min(self.end());
        let dense = (from..=to.min(self.last())).map(|k| self.get_fe(k));
        let mut cursor = self.tail().filter(|_| to > self.last());
        let packed = std::iter::from_fn(move || {
            let (c, p) = (cursor.as_mut()?, self.packed.as_ref()?);
            while c.index() < to && c.advance(p) {
                if c.index() >= from {
                    return Some(c.get_fe(p));
                }
            }
            None
        });
        dense.chain(packed)
    }

    /// [`Reference::values_fe`] from `from` to `to`, going on through the cycle of an
    /// orbit that repeats ([`Reference::cycle`]) past its end, as a sample would read it.
    pub fn values_through_cycle(&self, from: u32, to: u32) -> impl Iterator<Item = [FloatExp; 2]> + '_ {
        let stored = self.values_fe(from, to);
        let rest = self.cycle.filter(|_| to > self.end()).map(|w| {
            let first = self.end() - w + 1;
            let start = from.max(self.end() + 1);
            let turns = (first..=self.end()).cycle().skip(((start - self.end() - 1) % w) as usize);
            turns.take((to - start + 1) as usize).map(|m| self.get_fe(m))
        });
        stored.chain(rest.into_iter().flatten())
    }

    /// True when the orbit escaped (at index [`Reference::end`]).
    pub fn escaped(&self) -> bool {
        self.escaped
    }

    /// The densely stored values: Z_n as f64, and those too small for f64 with their
    /// exponents.
    pub fn parts(&self) -> (&[[f64; 2]], &[Tiny]) {
        (&self.z, &self.tiny)
    }

    /// An orbit from stored parts (a reference file's); `z` must not be empty, and a packed
    /// tail's seed must be the last of `z`.
    pub fn from_parts(
        z: Vec<[f64; 2]>,
        tiny: Vec<Tiny>,
        packed: Option<Packed>,
        escaped: bool,
        bits: u64,
        period: Option<u32>,
        cycle: Option<u32>,
    ) -> Reference {
        Reference { z, tiny, packed, escaped, bits, period, cycle }
    }

    /// The period found (see [`Stepping::periodic_below`]): the orbit stored is one period.
    pub fn period(&self) -> Option<u32> {
        self.period
    }

    /// Precision it was computed with, in bits.
    pub fn bits(&self) -> u64 {
        self.bits
    }

    /// Z_m rounded to f64 (zero or subnormal for tiny values).
    #[inline(always)]
    pub fn get(&self, m: u32) -> [f64; 2] {
        self.z[m as usize]
    }

    /// Z_m at full range.
    #[inline]
    pub fn get_fe(&self, m: u32) -> [FloatExp; 2] {
        let f = self.z[m as usize];
        if f[0].abs().max(f[1].abs()) < TINY
            && let Ok(i) = self.tiny.binary_search_by_key(&m, |t| t.0)
        {
            return self.tiny[i].1;
        }
        [FloatExp::from(f[0]), FloatExp::from(f[1])]
    }

    /// The stored values as f64 words, re and im interleaved (Z_m at words 2m, 2m + 1).
    #[inline]
    pub fn words(&self) -> &[f64] {
        bytemuck::cast_slice(&self.z)
    }

    /// Bytes of memory the stored orbit uses.
    pub fn bytes(&self) -> usize {
        self.z.capacity() * 16
            + self.tiny.capacity() * std::mem::size_of::<Tiny>()
            + self.packed.as_ref().map_or(0, Packed::bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orbit_of_minus_two_stays_on_two() {
        let c = [Float::from(-2.0), Float::from(0.0)];
        let z0 = [Float::from(0.0), Float::from(0.0)];
        let r = Reference::compute(&z0, &c, 50, 1024.0, 128, Stepping::default(), &|_| {}, &AtomicBool::new(false))
            .unwrap();
        assert_eq!(r.last(), 50);
        assert!(!r.escaped());
        assert_eq!(r.get(1), [-2.0, 0.0]);
        assert_eq!(r.get(50), [2.0, 0.0]);
    }

    /// c = -1 is the period-2 nucleus (0, -1, 0, ...): with a period test the orbit stops
    /// at Z_2 = 0; c = -1 + 1e-30 stops only with a test loose enough to let it through.
    #[test]
    fn periods() {
        let z0 = [Float::from(0.0), Float::from(0.0)];
        let run = |c: [Float; 2], steps: Stepping| {
            Reference::compute(&z0, &c, 1_000_000, 1024.0, 256, steps, &|_| {}, &AtomicBool::new(false)).unwrap()
        };
        let periodic = |t: f64| Stepping { periodic_below: Some(FloatExp::from(t)), ..Stepping::default() };
        let r = run([Float::from(-1.0), Float::from(0.0)], periodic(1e-40));
        assert_eq!((r.period(), r.last(), r.end()), (Some(2), 2, 2));
        let near =
            bigfloat::from_decimal(&crate::num::Decimal::parse("-0.999999999999999999999999999999").unwrap(), 256);
        // |Z_2| = |c^2 + c| ~ 1e-30 and |dZ_2/dc| = |2c + 1| ~ 1: caught at 1e-20, not at 1e-40.
        assert_eq!(run([near.clone(), Float::from(0.0)], periodic(1e-20)).period(), Some(2));
        assert_eq!(run([near.clone(), Float::from(0.0)], periodic(1e-40)).period(), None);
        // Packed after 1 unless a period ends the orbit by 1000: the nucleus stays dense,
        // the other is packed after 1 (and holds the same values).
        let held = |t: f64| Stepping { dense_limit: Some(1), hold: Some(1000), ..periodic(t) };
        let r = run([Float::from(-1.0), Float::from(0.0)], held(1e-40));
        assert_eq!((r.period(), r.last(), r.end()), (Some(2), 2, 2));
        let r = run([near.clone(), Float::from(0.0)], held(1e-40));
        assert_eq!((r.last(), r.end()), (1, 1_000_000));
        let dense = run([near, Float::from(0.0)], periodic(1e-40));
        let all = |r: &Reference| r.values_fe(0, u32::MAX).map(|v| v.map(|x| x.to_f64().to_bits())).collect::<Vec<_>>();
        assert_eq!(all(&r), all(&dense));
    }

    /// An orbit that repeats itself exactly (a centre whose orbit settles on an attracting
    /// cycle, once the rounding at the working precision repeats) is cut at the repeat, and
    /// read through its cycle it holds every value of the orbit computed to the limit, bit
    /// for bit, on one thread and pipelined; an orbit that only comes close to repeating
    /// (crawling past the cusp, near a Misiurewicz point, escaping) is never cut.
    #[test]
    fn an_orbit_is_cut_where_it_repeats_exactly_and_nowhere_else() {
        let z0 = [Float::from(0.0), Float::from(0.0)];
        let big = |re: &str, im: &str, bits: u64| {
            let d = |t: &str| bigfloat::from_decimal(&crate::num::Decimal::parse(t).unwrap(), bits);
            [d(re), d(im)]
        };
        let run = |c: &BigComplex, max_iter: u32, cut_cycles: bool, share: bool| {
            let steps = Stepping { cut_cycles, share, ..Stepping::default() };
            Reference::compute(
                &z0,
                c,
                max_iter,
                1e10,
                c[0].get_prec().unwrap_or(64),
                steps,
                &|_| {},
                &AtomicBool::new(false),
            )
            .unwrap()
        };
        let bits = |v: [FloatExp; 2]| v.map(|x| (x.mantissa().to_bits(), x.exponent()));
        // (centre, precision, limit, cut?)
        let cases = [
            // Inside the main cardioid: the fixed point attracts by 0.28 a step.
            (big("-0.1", "0.1", 200), 200_000, true),
            // Inside the period-2 bulb, near its edge (multiplier about 0.9).
            (big("-0.77", "0.05", 130), 300_000, true),
            // Inside the period-3 bulb (the rabbit's parameter).
            (big("-0.12256116687665", "0.74486176661974", 100), 200_000, true),
            // Past the cusp: the orbit crawls past 1/2 for about 10^9 iterations.
            (big("0.25000000000000001", "0", 200), 300_000, false),
            // Close to the Misiurewicz point -0.10109636384562 + 0.95628651080914i.
            (big("-0.10109636384562", "0.95628651080914", 200), 200_000, false),
            // A chaotic orbit that escapes (the 1e14 benchmark's neighbourhood).
            (big("-1.7490", "0.00003", 100), 200_000, false),
        ];
        for (c, max_iter, cuts) in cases {
            let whole = run(&c, max_iter, false, false);
            assert_eq!(whole.cycle(), None);
            let want: Vec<_> = whole.values_fe(0, max_iter).map(bits).collect();
            for share in [false, true] {
                let cut = run(&c, max_iter, true, share);
                let at = c[0].to_string();
                assert_eq!(cut.cycle().is_some(), cuts, "{at}: cut at {} with {:?}", cut.end(), cut.cycle());
                if cuts {
                    assert!(cut.end() < max_iter / 2, "{at}: {} values kept", cut.end());
                }
                let got: Vec<_> = cut.values_through_cycle(0, max_iter).map(bits).collect();
                assert!(got == want, "{at} (share {share}): the orbit read through its cycle differs");
            }
        }
    }

    /// An orbit stored densely up to a limit and packed after it holds the same values, bit
    /// for bit, as one stored densely throughout, and so does one stepped ahead by a helper
    /// thread (`share`: [`FixedOrbit::for_each_value`]): a deep view's chaotic orbit (the
    /// 1e50 benchmark's centre, at that view's precision) and a slowly escaping one near
    /// the cusp. The packed part takes under 2.5 bytes per iteration.
    #[test]
    fn packed_tail_holds_the_dense_values() {
        let z0 = [Float::from(0.0), Float::from(0.0)];
        let centres = [
            [
                "-0.04947002906310409375169222672735363011874571248822487931810494023264219477268690",
                "-0.67478757584467536401139205313059765633477070682240348069799979479099419834548451",
            ],
            ["0.25000000000000000000000000000001", "0.00000000000000000000000000000000000001"],
        ];
        for [re, im] in centres {
            let c = [re, im].map(|t| bigfloat::from_decimal(&crate::num::Decimal::parse(t).unwrap(), 300));
            let run = |dense_limit, share| {
                let steps = Stepping { dense_limit, share, ..Stepping::default() };
                Reference::compute(&z0, &c, 200_000, 2.0, 300, steps, &|_| {}, &AtomicBool::new(false)).unwrap()
            };
            let (dense, packed) = (run(None, false), run(Some(1000), true));
            assert_eq!(run(None, true).parts(), dense.parts(), "{re}: stepped ahead by a helper");
            assert!(dense.end() > 2000 && packed.packed().is_some(), "{re}: {}", dense.end());
            assert_eq!((packed.last(), packed.end(), packed.escaped()), (1000, dense.end(), dense.escaped()));
            let all =
                |r: &Reference| r.values_fe(0, u32::MAX).map(|v| v.map(|x| x.to_f64().to_bits())).collect::<Vec<_>>();
            assert_eq!(all(&packed), all(&dense), "{re}");
            let middle = |r: &Reference| r.values_fe(1500, 1600).collect::<Vec<_>>();
            assert_eq!(middle(&packed), middle(&dense));
            let per = packed.packed().unwrap().bytes() as f64 / (packed.end() - 1000) as f64;
            assert!(per < 2.5, "{re}: {per} bytes per iteration");
        }
    }

    #[test]
    fn tiny_values_keep_their_exponent() {
        // Z_0 = 1e-400 (beyond f64) at the precision of a view of that depth: stored as
        // FloatExp, to its 53 bits.
        let d = crate::num::Decimal::parse("1e-400").unwrap();
        let z0 = [bigfloat::from_decimal(&d, 1500), Float::from(0.0)];
        let c = [Float::from(0.25), Float::from(0.0)];
        let r =
            Reference::compute(&z0, &c, 3, 4.0, 1500, Stepping::default(), &|_| {}, &AtomicBool::new(false)).unwrap();
        assert_eq!(r.get(0), [0.0, 0.0]);
        let fe = r.get_fe(0);
        assert!((fe[0].log2() / std::f64::consts::LOG2_10 + 400.0).abs() < 1e-9);
        assert_eq!(r.get_fe(1)[0].to_f64(), 0.25);
        // Tiny values in a packed tail: c = 1e-400 from 0 stays near 1e-400.
        let steps = Stepping { dense_limit: Some(0), ..Stepping::default() };
        let zero = [Float::from(0.0), Float::from(0.0)];
        let c = [bigfloat::from_decimal(&d, 1500), Float::from(0.0)];
        let r = Reference::compute(&zero, &c, 3, 4.0, 1500, steps, &|_| {}, &AtomicBool::new(false)).unwrap();
        assert_eq!((r.last(), r.end()), (0, 3));
        for v in r.values_fe(1, 3) {
            assert!((v[0].log2() / std::f64::consts::LOG2_10 + 400.0).abs() < 1e-9);
        }
    }
}
