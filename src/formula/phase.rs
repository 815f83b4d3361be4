//! A formula as users choose it: one family at one power, or a hybrid, a cycle of such
//! phases (what Kalles Fraktaler's hybrid designer and Fraktaler-3's formula lines express:
//! Burning Ship then Mandelbrot³ alternately is `burning-ship,mandelbrot^3`).
//!
//! [`Stepper`] is what the generic kernels iterate. A single family is [`Single`], a
//! zero-sized type per family and power, so those kernels are compiled per family; a
//! hybrid is [`Cycle`], which picks the phase of each iteration by its index (one
//! predictable branch per step; each phase's arithmetic is still the family's compiled
//! code). [`with_stepper!`](crate::with_stepper) turns a [`Formula`] into one of them.

use std::fmt;

use super::kind::Kind;
use super::map::{Map, Mat2};
use crate::num::bigcomplex::BigC;
use crate::num::real::Real;

/// The most phases a hybrid may have.
pub const MAX_PHASES: usize = 8;

/// A family's complex coefficient a (Kalles Fraktaler's `FactorAR` + i `FactorAI`), held as
/// the bits of its parts so that phases compare and hash exactly. Families without one
/// hold 1.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Coef([u64; 2]);

impl Coef {
    /// 1 + 0i, Kalles Fraktaler's default a.
    pub const ONE: Coef = Coef([1f64.to_bits(), 0f64.to_bits()]);

    /// The coefficient re + i im (a zero of either sign is kept as +0, so that equal
    /// values are equal phases).
    pub fn new([re, im]: [f64; 2]) -> Coef {
        Coef([(re + 0.0).to_bits(), (im + 0.0).to_bits()])
    }

    /// re, im.
    #[inline(always)]
    pub fn get(self) -> [f64; 2] {
        [f64::from_bits(self.0[0]), f64::from_bits(self.0[1])]
    }
}

impl fmt::Debug for Coef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [re, im] = self.get();
        write!(f, "{re:?}{im:+?}i")
    }
}

/// One family at one power, with its coefficient where the family has one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Phase {
    /// The family.
    pub kind: Kind,
    /// Its power.
    pub power: u32,
    /// Its coefficient a: the user's for a family that takes one ([`Kind::takes_a`]), the
    /// family's own constant for the others.
    pub a: Coef,
}

impl Phase {
    /// z² + c.
    pub const QUADRATIC: Phase = Phase { kind: Kind::Mandelbrot, power: 2, a: Coef::ONE };

    /// `kind` at `power`, with the family's own coefficient (1 where the user may set one).
    pub fn new(kind: Kind, power: u32) -> Phase {
        Phase { kind, power, a: Coef::new(kind.info().coef.default()) }
    }

    /// This phase with coefficient `a`, where the family takes one; unchanged otherwise.
    pub fn with_a(self, a: [f64; 2]) -> Phase {
        if self.kind.takes_a() { Phase { a: Coef::new(a), ..self } } else { self }
    }
}

impl fmt::Display for Phase {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.power == self.kind.default_power() {
            write!(f, "{}", self.kind.name())
        } else {
            write!(f, "{}^{}", self.kind.name(), self.power)
        }
    }
}

/// The map a scene iterates: a cycle of one to [`MAX_PHASES`] phases (iteration n, from
/// z_n to z_(n+1), uses phase n mod the cycle's length).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Formula {
    phases: [Phase; MAX_PHASES],
    len: u8,
}

impl Default for Formula {
    fn default() -> Self {
        Formula::single(Phase::QUADRATIC)
    }
}

/// Why a formula's text was refused.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FormulaError(pub String);

impl fmt::Display for FormulaError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for FormulaError {}

impl Formula {
    /// One phase.
    pub fn single(phase: Phase) -> Formula {
        Formula { phases: [phase; MAX_PHASES], len: 1 }
    }

    /// A cycle of phases; None when there are none or more than [`MAX_PHASES`].
    pub fn cycle(phases: &[Phase]) -> Option<Formula> {
        if phases.is_empty() || phases.len() > MAX_PHASES {
            return None;
        }
        let mut all = [phases[0]; MAX_PHASES];
        all[..phases.len()].copy_from_slice(phases);
        Some(Formula { phases: all, len: phases.len() as u8 })
    }

    /// This formula with coefficient `a` on every phase whose family takes one (one a for
    /// the whole formula, as Kalles Fraktaler has one `FactorAR`, `FactorAI`).
    pub fn with_a(mut self, a: [f64; 2]) -> Formula {
        // Every slot, the unused ones too: they hold copies of the first phase, and equal
        // formulas must hold equal slots.
        for p in &mut self.phases {
            *p = p.with_a(a);
        }
        self
    }

    /// The coefficient a of the phases that take one; None when no phase does.
    pub fn a(&self) -> Option<[f64; 2]> {
        self.phases().iter().find(|p| p.kind.takes_a()).map(|p| p.a.get())
    }

    /// The phases, in order.
    pub fn phases(&self) -> &[Phase] {
        &self.phases[..self.len as usize]
    }

    /// The phase iteration `n` uses.
    #[inline(always)]
    pub fn phase(&self, n: u32) -> Phase {
        self.phases[(n % self.len as u32) as usize]
    }

    /// True for z² + c alone, which has engines of its own (fixed-point references,
    /// interior detection, the GPU paths).
    pub fn is_quadratic(&self) -> bool {
        self.len == 1 && self.phases[0] == Phase::QUADRATIC
    }

    /// True when every phase is complex-analytic (one complex derivative).
    pub fn is_conformal(&self) -> bool {
        self.phases().iter().all(|p| crate::with_map!(*p, M => <M as Map>::CONFORMAL, false))
    }

    /// ln of the escape rate: the mean of ln p over the cycle (smooth iteration divides by
    /// it, so a hybrid's bands are as smooth as its phases' mean degree makes them).
    pub fn ln_degree(&self) -> f64 {
        self.phases().iter().map(|p| (p.power as f64).ln()).sum::<f64>() / self.len as f64
    }

    /// The formula written `text`: `NAME`, `NAME^P`, or phases joined by `,` (a hybrid).
    /// `power` (from `--power` or the scene's `power`) sets the power of a single family
    /// written without one.
    pub fn parse(text: &str, power: Option<u32>) -> Result<Formula, FormulaError> {
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        if parts.len() > MAX_PHASES {
            return Err(FormulaError(format!(
                "a hybrid has at most {MAX_PHASES} phases; `{text}` has {}",
                parts.len()
            )));
        }
        if parts.len() > 1 && power.is_some() {
            return Err(FormulaError(
                "a hybrid gives each phase its power (`burning-ship,mandelbrot^3`), not one `power`".into(),
            ));
        }
        let mut phases = Vec::with_capacity(parts.len());
        for part in parts {
            let (name, p) = match part.split_once('^') {
                Some((n, p)) => {
                    let p: u32 = p.trim().parse().map_err(|_| {
                        FormulaError(format!("`{part}`: the power after `^` must be an integer from 2 to 10"))
                    })?;
                    (n.trim(), Some(p))
                }
                None => (part, None),
            };
            let kind = Kind::from_name(name).ok_or_else(|| {
                FormulaError(format!("unknown formula `{name}`; expected one of: julia, {}", Kind::names()))
            })?;
            let p = p.or(power).unwrap_or(kind.default_power());
            if !kind.has_power(p) {
                let i = kind.info();
                let range = if i.min_power == i.max_power {
                    format!("only power {}", i.min_power)
                } else {
                    format!("powers {} to {}", i.min_power, i.max_power)
                };
                return Err(FormulaError(format!("`{name}` comes in {range}, not {p}")));
            }
            phases.push(Phase::new(kind, p));
        }
        Formula::cycle(&phases).ok_or_else(|| FormulaError("a formula needs a family".into()))
    }
}

impl fmt::Display for Formula {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (k, p) in self.phases().iter().enumerate() {
            if k > 0 {
                f.write_str(",")?;
            }
            write!(f, "{p}")?;
        }
        Ok(())
    }
}

/// What the generic kernels iterate: the map of iteration `n` in every arithmetic.
pub trait Stepper: Copy + Send + Sync + 'static {
    /// f_n(z) (c not added).
    fn apply(&self, n: u32, z: [f64; 2]) -> [f64; 2];
    /// f_n(Z + d) - f_n(Z).
    fn delta<R: Real>(&self, n: u32, z: [f64; 2], d: [R; 2]) -> [R; 2];
    /// The Jacobian of f_n at z.
    fn jacobian(&self, n: u32, z: [f64; 2]) -> Mat2;
    /// f_n(z) in big floats.
    fn apply_big(&self, n: u32, z: &BigC) -> BigC;
    /// The length of the cycle of maps (1 for a single family).
    fn period(&self) -> u32;
}

/// One family at one power, as a type.
#[derive(Debug, Clone, Copy)]
pub struct Single<M: Map>(pub M);

impl<M: Map> Stepper for Single<M> {
    #[inline(always)]
    fn apply(&self, _: u32, z: [f64; 2]) -> [f64; 2] {
        self.0.apply(z)
    }
    #[inline(always)]
    fn delta<R: Real>(&self, _: u32, z: [f64; 2], d: [R; 2]) -> [R; 2] {
        self.0.delta(z, d)
    }
    #[inline(always)]
    fn jacobian(&self, _: u32, z: [f64; 2]) -> Mat2 {
        self.0.jacobian(z)
    }
    fn apply_big(&self, _: u32, z: &BigC) -> BigC {
        self.0.apply_big(z)
    }
    #[inline(always)]
    fn period(&self) -> u32 {
        1
    }
}

/// A hybrid: the phase of each iteration picked by its index.
#[derive(Debug, Clone, Copy)]
pub struct Cycle(pub Formula);

impl Stepper for Cycle {
    #[inline(always)]
    fn apply(&self, n: u32, z: [f64; 2]) -> [f64; 2] {
        crate::with_map!(self.0.phase(n), m: M => m.apply(z), unreachable!("validated phase"))
    }
    #[inline(always)]
    fn delta<R: Real>(&self, n: u32, z: [f64; 2], d: [R; 2]) -> [R; 2] {
        crate::with_map!(self.0.phase(n), m: M => m.delta(z, d), unreachable!("validated phase"))
    }
    #[inline(always)]
    fn jacobian(&self, n: u32, z: [f64; 2]) -> Mat2 {
        crate::with_map!(self.0.phase(n), m: M => m.jacobian(z), unreachable!("validated phase"))
    }
    fn apply_big(&self, n: u32, z: &BigC) -> BigC {
        crate::with_map!(self.0.phase(n), m: M => m.apply_big(z), unreachable!("validated phase"))
    }
    #[inline(always)]
    fn period(&self) -> u32 {
        self.0.len as u32
    }
}

/// Runs `$body` with `$M` the [`Map`] type of `$phase` (a [`Phase`]; with `m: M =>`, `m`
/// its map, [`Map::of`] the phase), or `$none` when the
/// phase is not one the table of families holds (a test checks none is missing). The list
/// is every (fold in, Q, negated) of a sum, every (PRE, A, B) of a product family and every (fold in,
/// power, fold out, sign) of a composition that the table of families uses.
#[macro_export]
macro_rules! with_map {
    ($phase:expr, $m:ident : $M:ident => $body:expr, $none:expr) => {{
        let phase_of_map: $crate::formula::Phase = $phase;
        $crate::with_map!(phase_of_map, $M => {
            #[allow(unused_imports)]
            use $crate::formula::map::Map as _;
            let $m = <$M as $crate::formula::map::Map>::of(&phase_of_map);
            $body
        }, $none)
    }};
    ($phase:expr, $M:ident => $body:expr, $none:expr) => {
        $crate::__map_arms!($phase, $M, $body, $none;
            // the sums a W^2 ± W^Q: (fold in, Q, negated)
            [(0, 3, false), (0, 3, true), (0, 4, false), (0, 4, true), (0, 5, false), (0, 5, true), (0, 6, false),
             (0, 6, true), (3, 1, true)];
            // the products u^A (|Re u| + i|Im u|)^B, u = z^PRE: (PRE, A, B)
            [(1, 2, 2), (1, 3, 3), (2, 1, 1), (1, 1, 1), (1, 1, 2), (1, 2, 1), (1, 1, 3), (1, 3, 1),
             (1, 1, 4), (1, 2, 3), (1, 3, 2), (1, 4, 1), (1, 1, 5), (1, 2, 4), (1, 4, 2), (1, 5, 1)];
            // mandelbrot
            (0, 2, 0, 0), (0, 3, 0, 0), (0, 4, 0, 0), (0, 5, 0, 0), (0, 6, 0, 0), (0, 7, 0, 0),
            (0, 8, 0, 0), (0, 9, 0, 0), (0, 10, 0, 0),
            // burning-ship
            (3, 2, 0, 0), (3, 3, 0, 0), (3, 4, 0, 0), (3, 5, 0, 0),
            // buffalo
            (0, 2, 3, 0), (0, 3, 3, 0), (0, 4, 3, 0), (0, 5, 3, 0),
            // celtic
            (0, 2, 1, 0), (0, 3, 1, 0), (0, 4, 1, 0), (0, 5, 1, 0),
            // mandelbar
            (0, 2, 0, 1), (0, 3, 0, 2), (0, 4, 0, 1), (0, 5, 0, 1),
            // types 5 to 9
            (0, 2, 1, 1), (1, 2, 0, 1), (2, 2, 0, 1), (1, 2, 1, 1), (2, 2, 1, 1),
            // the partial folds of powers 3 to 5
            (1, 3, 2, 1), (1, 3, 0, 0), (2, 3, 0, 0), (0, 3, 2, 0),
            (2, 4, 0, 0), (1, 4, 0, 0), (1, 4, 0, 1), (2, 4, 1, 0), (1, 4, 1, 0), (1, 4, 1, 1),
            (0, 4, 2, 0), (0, 4, 1, 1),
            (1, 5, 0, 0), (1, 5, 0, 1), (0, 5, 1, 1), (1, 5, 2, 1),
            // the quasi families: the imaginary part folded and signed by x (6), y (10) or
            // xy (14), the real part folded too (+ 1)
            (1, 3, 10, 1), (0, 4, 14, 1), (0, 4, 14, 0), (0, 4, 15, 1), (0, 4, 15, 0),
            (1, 5, 10, 1), (1, 5, 10, 0), (0, 4, 6, 0), (0, 4, 10, 1), (0, 4, 10, 0),
            (0, 4, 7, 0), (0, 4, 11, 1), (0, 4, 11, 0)
        )
    };
}

/// The arms of [`with_map!`](crate::with_map).
#[doc(hidden)]
#[macro_export]
macro_rules! __map_arms {
    ($phase:expr, $M:ident, $body:expr, $none:expr;
     [ $( ($fi:literal, $q:literal, $neg:literal) ),* ];
     [ $( ($pre:literal, $a:literal, $b:literal) ),* ];
     $( ($i:literal, $p:literal, $o:literal, $s:literal) ),* ) => {{
        let phase: $crate::formula::Phase = $phase;
        match (phase.kind.sum(), phase.kind.factors()) {
            $( (Some($crate::formula::kind::SumShape { fold_in: $fi, q: $q, neg: $neg }), _) => {
                type $M = $crate::formula::sum::Sum<$fi, $q, $neg>;
                $body
            } )*
            (Some(_), _) => $none,
            (None, None) => match phase.kind.shape(phase.power) {
                $( ($i, $p, $o, $s) => {
                    type $M = $crate::formula::map::Ops<$i, $p, $o, $s>;
                    $body
                } )*
                _ => $none,
            },
            $( (None, Some(($pre, $a, $b))) => {
                type $M = $crate::formula::product::Product<$pre, $a, $b>;
                $body
            } )*
            (None, Some(_)) => $none,
        }
    }};
}

/// Runs `$body` with `$s` a [`Stepper`] for `$formula`: a [`Single`] per family and power,
/// or a [`Cycle`] for hybrids.
#[macro_export]
macro_rules! with_stepper {
    ($formula:expr, $s:ident => $body:expr) => {{
        let formula: $crate::formula::Formula = $formula;
        if formula.phases().len() == 1 {
            $crate::with_map!(formula.phases()[0], m: M => {
                let $s = $crate::formula::Single::<M>(m);
                $body
            }, {
                let $s = $crate::formula::Cycle(formula);
                $body
            })
        } else {
            let $s = $crate::formula::Cycle(formula);
            $body
        }
    }};
}

/// The map of `phase` in f64 (c not added): the one-off uses (seeds, tests) that need no
/// compiled loop.
pub fn apply(phase: Phase, z: [f64; 2]) -> [f64; 2] {
    crate::with_map!(phase, m: M => m.apply(z), [f64::NAN; 2])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::kind::KINDS;

    #[test]
    fn every_family_at_every_power_has_compiled_code() {
        for k in KINDS {
            for p in k.min_power..=k.max_power {
                let phase = Phase::new(k.kind, p);
                let known = crate::with_map!(phase, M => M::POWER == p, false);
                assert!(known, "{phase} has no arm in with_map!");
            }
        }
    }

    #[test]
    fn parse_and_display_round_trip() {
        for text in ["mandelbrot", "burning-ship^3", "burning-ship,mandelbrot^3", "celtic^5,buffalo,mandelbar^3"] {
            let f = Formula::parse(text, None).unwrap();
            assert_eq!(f.to_string(), text);
        }
        assert_eq!(Formula::parse("mandelbrot", Some(2)).unwrap(), Formula::default());
        assert!(Formula::parse("mandelbrot", None).unwrap().is_quadratic());
        assert_eq!(Formula::parse("buffalo", Some(4)).unwrap().to_string(), "buffalo^4");
    }

    #[test]
    fn bad_formulas_say_what_was_expected() {
        let e = |t: &str, p| Formula::parse(t, p).unwrap_err().0;
        assert!(e("burning-boat", None).contains("unknown formula `burning-boat`"));
        assert!(e("burning-ship^7", None).contains("powers 2 to 5, not 7"));
        assert!(e("perpendicular-celtic", Some(3)).contains("only power 2"));
        assert!(e("mandelbrot^x", None).contains("integer"));
        assert!(e("mandelbrot,celtic", Some(3)).contains("each phase its power"));
        assert!(e(&["mandelbrot"; 9].join(","), None).contains("at most 8"));
    }

    #[test]
    fn a_cycle_steps_through_its_phases() {
        let f = Formula::parse("burning-ship,mandelbrot^3", None).unwrap();
        let s = Cycle(f);
        let z = [0.3, -0.4];
        assert_eq!(s.apply(0, z), apply(f.phases()[0], z));
        assert_eq!(s.apply(1, z), apply(f.phases()[1], z));
        assert_eq!(s.apply(2, z), apply(f.phases()[0], z));
        assert_eq!(s.period(), 2);
    }
}
