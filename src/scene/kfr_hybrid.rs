//! Kalles Fraktaler's hybrid formulas (a `.kfr`'s `HybridFormula`), read as deepfield's
//! cycles of phases where they are one.
//!
//! KF 2.15's "hybrid formula designer" saves `UseHybridFormula: 1` and `HybridFormula:
//! L/G/G...` (KF's `to_string` / `hybrid_formula_from_string` in `fraktal_sft/hybrid.cpp`,
//! the types in `hybrid.h`, Claude Heiland-Allen, Kalles Fraktaler 2):
//!
//! - `L` is the group the loop returns to (0-based); each group `G` is `R|LINE|LINE...`:
//!   applied `R` times, one iteration each, before the next group; after the last group
//!   the loop goes back to group `L`.
//! - One iteration of a group applies its lines in order and then adds c:
//!   z -> LINE_k(... LINE_1(z)) + c.
//! - A line is `OP;OP;MODE`: the two operators combined by MODE (0 `+`, 1 `-`, 2 `*`); a
//!   second operator of power 0 and factor 0 with `+` or `-` is absent.
//! - An operator is `absx,absy,negx,negy,pow,are,aim`: x and y folded (absolute value)
//!   where asked, then negated where asked, raised to `pow`, multiplied by `are + i aim`
//!   (power 0 is the constant `are + i aim`).
//!
//! A group is one of deepfield's families when its lines, each a single operator with
//! factor 1, amount to exactly one power p ≥ 2 with folds and negations around it: the
//! folds and negations before the power become the family's fold in and a final negation
//! (a negated y before the power conjugates the result; a negated x conjugates and, for
//! odd p, negates it), those after it its fold out and negation, and the result must be a
//! row of [`crate::formula::kind::KINDS`] at that power. KF's formula presets write every
//! built-in family this way (Buffalo is `z^p` then a line `|x| + i|y|` of power 1).
//! A group whose last line multiplies z^a by (|x| + i|y|)^b, after nothing or after z^2
//! alone, is a product family (`formula::product`: Mothbrot, SimonBrot, SimonBrot2).
//! A group of one line A z² + z^q or A z² - z^q (q = 3 to 6) is a sum family
//! (`formula::sum`: TheRedshiftRider) with a = A; a formula has one a, so a hybrid whose
//! sums have different factors is refused. The line (|x| + i|y|)² - (|x| + i|y|) is HPDZ
//! Buffalo (a sum with its W folded).
//! Anything else is refused with what it is: a line combining two operators otherwise
//! (z³ + z²), a factor other than 1, a constant, two
//! powers in one iteration, or a map no family has. The sequence of groups must repeat
//! from the first iteration with at most [`MAX_PHASES`] iterations per cycle (groups
//! before the loop start are allowed when they equal the loop's end).
//!
//! A hybrid KF itself rejects (its `valid`: no groups, a group without lines or with
//! fewer than 1 repeat, a loop start outside the groups) is drawn by KF as the file's
//! `FractalType`; [`Hybrid::Invalid`] says so.

use std::fmt;

use crate::formula::kind::{KINDS, SumShape};
use crate::formula::map::{SIGN_IM, SIGN_RE};
use crate::formula::phase::MAX_PHASES;
use crate::formula::{Formula, Phase};

/// The real part (x), as a bit of a mask.
const RE: u8 = 1;
/// The imaginary part (y), as a bit of a mask.
const IM: u8 = 2;

/// The most iterations a hybrid may spell out before it repeats (a guard on `repeats`).
const MAX_SPELLED: usize = 4096;

/// What a `HybridFormula` value is.
#[derive(Debug, Clone, PartialEq)]
pub enum Hybrid {
    /// A cycle of deepfield's phases.
    Formula(Formula),
    /// KF's own check refuses it (KF then draws `FractalType`): why.
    Invalid(&'static str),
}

/// Why a `HybridFormula` value is not one deepfield draws.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HybridError {
    /// Byte offset in the value of the part the message is about.
    pub at: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for HybridError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for HybridError {}

fn err<T>(at: usize, message: impl Into<String>) -> Result<T, HybridError> {
    Err(HybridError { at, message: message.into() })
}

/// `s` split at `sep`, each piece with its offset (`base` is the offset of `s`).
fn pieces(s: &str, base: usize, sep: char) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut at = 0;
    for p in s.split(sep) {
        out.push((base + at, p));
        at += p.len() + sep.len_utf8();
    }
    out
}

fn int(at: usize, s: &str, what: &str) -> Result<i64, HybridError> {
    s.trim().parse().or_else(|_| err(at, format!("{what}: expected a whole number, found `{s}`")))
}

fn real(at: usize, s: &str, what: &str) -> Result<f64, HybridError> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => err(at, format!("{what}: expected a number, found `{s}`")),
    }
}

/// One operator: `absx,absy,negx,negy,pow,are,aim`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Operator {
    abs: u8,
    neg: u8,
    pow: i64,
    mul: [f64; 2],
}

impl Operator {
    /// KF's defaults for fields a file leaves out.
    const ZERO: Operator = Operator { abs: 0, neg: 0, pow: 0, mul: [0.0, 0.0] };

    fn parse(at: usize, s: &str) -> Result<Operator, HybridError> {
        let mut op = Operator::ZERO;
        let fields = pieces(s, at, ',');
        if fields.len() > 7 {
            return err(at, format!("an operator has 7 fields (absx,absy,negx,negy,pow,are,aim), found `{s}`"));
        }
        for (k, &(a, f)) in fields.iter().enumerate() {
            if s.is_empty() {
                break;
            }
            match k {
                0..=3 => {
                    let on = int(a, f, "an operator's abs/neg flag")? != 0;
                    let bit = if k % 2 == 0 { RE } else { IM };
                    let mask = if k < 2 { &mut op.abs } else { &mut op.neg };
                    if on {
                        *mask |= bit;
                    }
                }
                4 => op.pow = int(a, f, "an operator's power")?,
                5 => op.mul[0] = real(a, f, "an operator's factor (real part)")?,
                _ => op.mul[1] = real(a, f, "an operator's factor (imaginary part)")?,
            }
        }
        Ok(op)
    }

    /// As KF's designer would show it, for messages: `2 (|x| + i|y|)^3`.
    fn text(&self) -> String {
        if self.pow == 0 {
            return format!("the constant {}", complex_text(self.mul));
        }
        let x = match (self.abs & RE != 0, self.neg & RE != 0) {
            (false, false) => "x",
            (true, false) => "|x|",
            (false, true) => "-x",
            (true, true) => "-|x|",
        };
        let y = match (self.abs & IM != 0, self.neg & IM != 0) {
            (false, false) => "+ iy",
            (true, false) => "+ i|y|",
            (false, true) => "- iy",
            (true, true) => "- i|y|",
        };
        let factor = if self.mul == [1.0, 0.0] { String::new() } else { format!("{} ", complex_text(self.mul)) };
        format!("{factor}({x} {y})^{}", self.pow)
    }
}

fn complex_text(z: [f64; 2]) -> String {
    match z {
        [re, 0.0] => format!("{re}"),
        [0.0, im] => format!("{im}i"),
        [re, im] => format!("({re} {} {}i)", if im < 0.0 { '-' } else { '+' }, im.abs()),
    }
}

/// A group's lines folded into one family's steps: fold in, power, fold out, negation
/// (masks of [`RE`] and [`IM`]).
#[derive(Debug, Default)]
struct Steps {
    fold_in: u8,
    neg_in: u8,
    power: Option<u32>,
    fold_out: u8,
    sign: u8,
}

impl Steps {
    /// Folds `abs`, then negates `neg`, at the current place (before or after the power).
    fn fold_and_negate(&mut self, abs: u8, neg: u8) {
        let (fold, sign) = if self.power.is_none() {
            (&mut self.fold_in, &mut self.neg_in)
        } else {
            (&mut self.fold_out, &mut self.sign)
        };
        // |±x| = |x|: a fold swallows the negation before it; folds and negations of
        // different parts commute.
        *fold |= abs;
        *sign &= !abs;
        *sign ^= neg;
    }

    /// Raises to `p` ≥ 2: a negation before the power becomes one after it.
    fn power(&mut self, p: u32) {
        // (x - iy)^p = conj(z^p); (-x + iy)^p = (-1)^p conj(z^p).
        let mut sign = 0;
        if self.neg_in & IM != 0 {
            sign ^= IM;
        }
        if self.neg_in & RE != 0 {
            sign ^= if p % 2 == 1 { RE } else { IM };
        }
        self.neg_in = 0;
        self.power = Some(p);
        self.sign = sign;
    }

    /// The map in words, for messages.
    fn text(&self, p: u32) -> String {
        let base = ["z", "(|x| + iy)", "(x + i|y|)", "(|x| + i|y|)"][self.fold_in as usize];
        let mut after = vec![];
        if self.fold_out & RE != 0 {
            after.push("|Re w|");
        }
        if self.fold_out & IM != 0 {
            after.push("|Im w|");
        }
        if self.sign & RE != 0 {
            after.push("-Re w");
        }
        if self.sign & IM != 0 {
            after.push("-Im w");
        }
        if after.is_empty() {
            format!("w + c, w = {base}^{p}")
        } else {
            format!("w = {base}^{p} then {}", after.join(", "))
        }
    }
}

/// The product family a `*` line is, after the steps so far: z^A times (|x| + i|y|)^B (in
/// either order, factors 1), on z itself or on u = z^PRE from a power line before it with
/// no fold or negation (KF's SimonBrot2 is `z^2`, then `z * (|x| + i|y|)`). Where two rows
/// are one map (Mothbrot 2×2 is SimonBrot 4th), the general family's row, Mothbrot (KF's
/// higher type number).
fn product_phase(steps: &Steps, one: Operator, two: Operator) -> Option<Phase> {
    let factor_one = |o: &Operator| o.neg == 0 && o.mul == [1.0, 0.0] && o.pow >= 1;
    let (a, b) = match (one.abs, two.abs) {
        (0, 3) if factor_one(&one) && factor_one(&two) => (one.pow, two.pow),
        (3, 0) if factor_one(&one) && factor_one(&two) => (two.pow, one.pow),
        _ => return None,
    };
    if steps.fold_in != 0 || steps.neg_in != 0 || steps.fold_out != 0 || steps.sign != 0 {
        return None;
    }
    let factors = (steps.power.unwrap_or(1), u32::try_from(a).ok()?, u32::try_from(b).ok()?);
    KINDS
        .iter()
        .filter(|k| k.factors == Some(factors))
        .max_by_key(|k| k.kf_type)
        .map(|k| Phase::new(k.kind, k.min_power))
}

/// The sum family a `+` or `-` line is, as the only line of its group: A W² then W^q, the
/// same folds on both and no negation, the second operator's factor 1. KF's TheRedshiftRider
/// presets are W = z, `redshift-rider-*` with a = A (KF's type 44, 2 z² - z³, is then the
/// row of a z² - z³ with a = 2: the same map); its HPDZ Buffalo preset is W = |x| + i|y|,
/// W² - W, whose A must be its fixed 1.
fn sum_phase(one: Operator, two: Operator, minus: bool) -> Option<Phase> {
    if one.abs != two.abs || one.neg != 0 || two.neg != 0 || one.pow != 2 || two.mul != [1.0, 0.0] {
        return None;
    }
    let shape = SumShape { fold_in: one.abs, q: u32::try_from(two.pow).ok()?, neg: minus };
    let rows = || KINDS.iter().filter(|k| k.sum == Some(shape));
    match rows().find(|k| k.kind.takes_a()) {
        Some(k) => Some(Phase::new(k.kind, k.min_power).with_a(one.mul)),
        None => rows().map(|k| Phase::new(k.kind, k.min_power)).find(|p| p.a.get() == one.mul),
    }
}

/// One group's iteration as a phase.
fn group_phase(at: usize, lines: &[(usize, &str)]) -> Result<Phase, HybridError> {
    let mut steps = Steps::default();
    for &(line_at, line) in lines {
        let parts = pieces(line, line_at, ';');
        if parts.len() > 3 {
            return err(line_at, format!("a line is `OPERATOR;OPERATOR;MODE`, found `{line}`"));
        }
        let one = Operator::parse(parts[0].0, parts[0].1)?;
        let two = match parts.get(1) {
            Some(&(a, s)) => Operator::parse(a, s)?,
            None => Operator::ZERO,
        };
        let mode = match parts.get(2) {
            Some(&(a, s)) => int(a, s, "a line's operator (0 +, 1 -, 2 *)")?,
            None => 0,
        };
        // KF's `hybrid_combine_from_string`: anything but 1 and 2 is `+`.
        let symbol = match mode {
            1 => '-',
            2 => '*',
            _ => '+',
        };
        let alone = two.pow == 0 && two.mul == [0.0, 0.0] && symbol != '*';
        if symbol != '*'
            && lines.len() == 1
            && let Some(phase) = sum_phase(one, two, symbol == '-')
        {
            return Ok(phase);
        }
        if symbol == '*'
            && let Some(phase) = product_phase(&steps, one, two)
        {
            if line_at != lines[lines.len() - 1].0 {
                return err(line_at, "a line after a product (Mothbrot, SimonBrot), which no deepfield family has");
            }
            return Ok(phase);
        }
        if !alone {
            return err(
                line_at,
                format!(
                    "the line `{} {symbol} {}` combines two operators, which no deepfield family does \
                     (deepfield draws lines of one operator: folds, negations and a power)",
                    one.text(),
                    two.text()
                ),
            );
        }
        if one.pow == 0 {
            return err(line_at, format!("the line `{}` is a constant, which no deepfield family is", one.text()));
        }
        if one.mul != [1.0, 0.0] {
            return err(
                line_at,
                format!(
                    "the line `{}` multiplies by {}: deepfield's families have no factors",
                    one.text(),
                    complex_text(one.mul)
                ),
            );
        }
        let p = match u32::try_from(one.pow) {
            Ok(p) if p >= 1 => p,
            _ => return err(line_at, format!("the line `{}`: the power must be 1 or more", one.text())),
        };
        steps.fold_and_negate(one.abs, one.neg);
        if p >= 2 {
            if steps.power.is_some() {
                return err(
                    line_at,
                    format!(
                        "the line `{}` is a second power in one iteration, which no deepfield family has",
                        one.text()
                    ),
                );
            }
            steps.power(p);
        }
    }
    let Some(p) = steps.power else {
        return err(at, "a group without a power above 1 (z -> ±|z| + c) is not a fractal family deepfield draws");
    };
    let sign = if steps.sign & IM != 0 { SIGN_IM } else { 0 } | if steps.sign & RE != 0 { SIGN_RE } else { 0 };
    let shape = (steps.fold_in, p, steps.fold_out, sign);
    KINDS.iter().find(|k| k.kind.has_power(p) && k.kind.shape(p) == shape).map(|k| Phase::new(k.kind, p)).ok_or_else(
        || HybridError { at, message: format!("the iteration {} is none of deepfield's families", steps.text(p)) },
    )
}

/// Reads a `HybridFormula` value.
pub fn parse(text: &str) -> Result<Hybrid, HybridError> {
    let groups = pieces(text, 0, '/');
    let loop_start = int(0, groups[0].1, "the loop start (the first field)")?;
    let mut phases: Vec<(Phase, i64)> = vec![];
    for &(at, group) in &groups[1..] {
        let fields = pieces(group, at, '|');
        let repeats = int(fields[0].0, fields[0].1, "a group's repeat count")?;
        if repeats <= 0 {
            return Ok(Hybrid::Invalid("a group repeats fewer than once"));
        }
        if fields.len() < 2 {
            return Ok(Hybrid::Invalid("a group has no lines"));
        }
        phases.push((group_phase(at, &fields[1..])?, repeats));
    }
    if phases.is_empty() {
        return Ok(Hybrid::Invalid("it has no groups"));
    }
    if loop_start < 0 || loop_start as usize >= phases.len() {
        return Ok(Hybrid::Invalid("its loop starts outside its groups"));
    }
    let loop_start = loop_start as usize;

    // The phase of each iteration, as KF steps through the groups.
    let count = |range: &[(Phase, i64)]| range.iter().map(|&(_, r)| r as u128).sum::<u128>();
    let (head, cycle) = (count(&phases[..loop_start]), count(&phases[loop_start..]));
    if head + cycle + MAX_PHASES as u128 > MAX_SPELLED as u128 {
        return err(
            0,
            format!(
                "the hybrid runs {} iterations before repeating; deepfield's hybrids have at most {MAX_PHASES} phases",
                head + cycle
            ),
        );
    }
    let (head, cycle) = (head as usize, cycle as usize);
    let mut seq = Vec::with_capacity(head + cycle + MAX_PHASES);
    let mut group = 0;
    while seq.len() < head + cycle + MAX_PHASES {
        let (phase, repeats) = phases[group];
        seq.extend(std::iter::repeat_n(phase, repeats as usize));
        group = if group + 1 == phases.len() { loop_start } else { group + 1 };
    }
    // One coefficient a for the formula, as KF has one (`FactorAR`, `FactorAI`) and scenes
    // have one `a`.
    let coefs = || seq.iter().filter(|p| p.kind.takes_a()).map(|p| p.a);
    if let Some(first) = coefs().next()
        && coefs().any(|a| a != first)
    {
        return err(0, "the hybrid's lines a z^2 ± z^q have different factors a; deepfield's formulas have one a");
    }
    // The shortest period of the whole sequence (iterations before the loop included).
    let period = (1..=MAX_PHASES).find(|&d| (0..head + cycle).all(|n| seq[n] == seq[n + d]));
    match period {
        Some(d) => Ok(Hybrid::Formula(Formula::cycle(&seq[..d]).expect("1 to MAX_PHASES phases"))),
        None if head > 0 && (1..=MAX_PHASES).any(|d| (head..head + cycle).all(|n| seq[n] == seq[n + d])) => err(
            0,
            "the groups before the loop start are not a part of the loop, and deepfield's hybrids repeat from the first iteration",
        ),
        None => err(
            0,
            format!(
                "the hybrid repeats every {cycle} iterations; deepfield's hybrids have at most {MAX_PHASES} phases"
            ),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::Kind;

    fn formula(text: &str) -> String {
        match parse(text) {
            Ok(Hybrid::Formula(f)) => f.to_string(),
            other => panic!("{text}: {other:?}"),
        }
    }

    fn refused(text: &str) -> HybridError {
        match parse(text) {
            Err(e) => e,
            other => panic!("{text}: {other:?}"),
        }
    }

    const NONE: &str = "0,0,0,0,0,0,0";

    /// The hybrids KF's formula presets write for its built-in families.
    #[test]
    fn kf_presets_of_the_families() {
        let one = |op: &str| format!("0/1|{op};{NONE};0");
        let two = |a: &str, b: &str| format!("0/1|{a};{NONE};0|{b};{NONE};0");
        assert_eq!(formula(&one("0,0,0,0,2,1,0")), "mandelbrot");
        assert_eq!(formula(&one("0,0,0,0,10,1,0")), "mandelbrot^10");
        assert_eq!(formula(&one("1,1,0,0,3,1,0")), "burning-ship^3");
        assert_eq!(formula(&two("0,0,0,0,4,1,0", "1,1,0,0,1,1,0")), "buffalo^4");
        assert_eq!(formula(&two("0,0,0,0,2,1,0", "1,0,0,0,1,1,0")), "celtic");
        assert_eq!(formula(&one("0,0,0,1,2,1,0")), "mandelbar");
        assert_eq!(formula(&one("0,0,0,1,5,1,0")), "mandelbar^5");
        assert_eq!(formula(&one("1,0,0,1,2,1,0")), "perpendicular-mandelbrot");
        assert_eq!(formula(&one("0,1,0,1,2,1,0")), "perpendicular-burning-ship");
        assert_eq!(formula(&two("0,1,0,1,2,1,0", "1,0,0,0,1,1,0")), "perpendicular-buffalo");
        assert_eq!(formula(&two("1,0,0,0,3,1,0", "0,1,0,1,1,1,0")), "cubic-quasi-burning-ship");
        assert_eq!(formula(&two("0,0,0,1,5,1,0", "1,0,0,0,1,1,0")), "5th-celtic-mbar");
        assert_eq!(formula(&two("1,0,0,0,5,1,0", "0,1,0,1,1,1,0")), "5th-quasi-burning-ship");
    }

    /// KF's TheRedshiftRider presets: one line A z² ± z^q, with A the formula's a.
    #[test]
    fn kf_presets_of_the_sums() {
        let a = |text: &str| match parse(text) {
            Ok(Hybrid::Formula(f)) => (f.to_string(), f.a()),
            other => panic!("{text}: {other:?}"),
        };
        assert_eq!(a("0/1|0,0,0,0,2,1,0;0,0,0,0,3,1,0;0"), ("redshift-rider-1".into(), Some([1.0, 0.0])));
        assert_eq!(a("0/1|0,0,0,0,2,2,0;0,0,0,0,3,1,0;1"), ("redshift-rider-2".into(), Some([2.0, 0.0])));
        assert_eq!(a("0/1|0,0,0,0,2,1,0;0,0,0,0,6,1,0;1"), ("redshift-rider-9".into(), Some([1.0, 0.0])));
        assert_eq!(
            a(&format!("0/1|0,0,0,0,2,-0.5,0.25;0,0,0,0,4,1,0;0/1|1,1,0,0,2,1,0;{NONE};0")),
            ("redshift-rider-4,burning-ship".into(), Some([-0.5, 0.25]))
        );
        // Two factors a, a sum after another line, a power the family lacks.
        let e = refused("0/1|0,0,0,0,2,1,0;0,0,0,0,3,1,0;0/1|0,0,0,0,2,3,0;0,0,0,0,3,1,0;0");
        assert!(e.message.contains("different factors a"), "{e}");
        assert!(
            refused(&format!("0/1|1,1,0,0,1,1,0;{NONE};0|0,0,0,0,2,1,0;0,0,0,0,3,1,0;0")).message.contains("combines")
        );
        assert!(refused("0/1|0,0,0,0,2,1,0;0,0,0,0,7,1,0;0").message.contains("combines two operators"));
        // HPDZ Buffalo: (|x| + i|y|)^2 - (|x| + i|y|), whose factor is its fixed 1.
        assert_eq!(a("0/1|1,1,0,0,2,1,0;1,1,0,0,1,1,0;1"), ("hpdz-buffalo".into(), None));
        assert!(refused("0/1|1,1,0,0,2,2,0;1,1,0,0,1,1,0;1").message.contains("combines two operators"));
    }

    /// KF's Mothbrot and SimonBrot presets: a line multiplying z^a by (|x| + i|y|)^b, on z or
    /// on z² from a line before it.
    #[test]
    fn kf_presets_of_the_products() {
        assert_eq!(formula("0/1|0,0,0,0,2,1,0;1,1,0,0,3,1,0;2"), "mothbrot-2x3");
        assert_eq!(formula("0/1|1,1,0,0,3,1,0;0,0,0,0,2,1,0;2"), "mothbrot-2x3", "either order");
        assert_eq!(formula("0/1|0,0,0,0,1,1,0;1,1,0,0,1,1,0;2"), "mothbrot-1x1");
        assert_eq!(formula("0/1|0,0,0,0,3,1,0;1,1,0,0,3,1,0;2"), "mothbrot-3x3", "SimonBrot 6th's lines");
        let simon2 = format!("0/1|0,0,0,0,2,1,0;{NONE};0|0,0,0,0,1,1,0;1,1,0,0,1,1,0;2");
        assert_eq!(formula(&simon2), "simonbrot2-4th");
        assert_eq!(
            formula(&format!("0/1|0,0,0,0,2,1,0;1,1,0,0,2,1,0;2/1|1,1,0,0,2,1,0;{NONE};0")),
            "mothbrot-2x2,burning-ship"
        );
        // No row: z^3 (|x| + i|y|)^4, a product after a fold, a line after a product.
        assert!(refused("0/1|0,0,0,0,3,1,0;1,1,0,0,4,1,0;2").message.contains("combines two operators"));
        assert!(
            refused(&format!("0/1|1,1,0,0,1,1,0;{NONE};0|0,0,0,0,1,1,0;1,1,0,0,1,1,0;2")).message.contains("combines")
        );
        let e = refused(&format!("0/1|0,0,0,0,1,1,0;1,1,0,0,1,1,0;2|0,0,0,0,2,1,0;{NONE};0"));
        assert!(e.message.contains("after a product"), "{e}");
    }

    /// KF's Mandelbar of power 3 is -Re z³ + i Im z³, which is (-x + iy)³; its preset's
    /// hybrid, (x - iy)³ = conj(z³), is a different map that no family is.
    #[test]
    fn negations_before_the_power() {
        assert_eq!(formula(&format!("0/1|0,0,1,0,3,1,0;{NONE};0")), "mandelbar^3");
        let e = refused(&format!("0/1|0,0,0,1,3,1,0;{NONE};0"));
        assert!(e.message.contains("-Im w") && e.message.contains("none of deepfield's families"), "{e}");
        // (-z)^2 = z^2; a negation folded away is no negation.
        assert_eq!(formula(&format!("0/1|0,0,1,1,2,1,0;{NONE};0")), "mandelbrot");
        assert_eq!(formula(&format!("0/1|0,0,1,1,1,1,0;{NONE};0|1,1,0,0,2,1,0;{NONE};0")), "burning-ship");
    }

    #[test]
    fn groups_repeat_and_loop() {
        let bs = format!("1,1,0,0,2,1,0;{NONE};0");
        let m3 = format!("0,0,0,0,3,1,0;{NONE};0");
        assert_eq!(formula(&format!("0/1|{bs}/1|{m3}")), "burning-ship,mandelbrot^3");
        assert_eq!(formula(&format!("0/2|{bs}/1|{m3}")), "burning-ship,burning-ship,mandelbrot^3");
        // The same group twice is one phase; a loop back to a group equal to the first.
        assert_eq!(formula(&format!("0/3|{bs}")), "burning-ship");
        assert_eq!(formula(&format!("1/1|{bs}/1|{bs}")), "burning-ship");
        // A head that is not part of the loop, and a cycle too long.
        let e = refused(&format!("1/1|{m3}/1|{bs}"));
        assert!(e.message.contains("before the loop start"), "{e}");
        let e = refused(&format!("0/9|{bs}/1|{m3}"));
        assert!(e.message.contains("every 10 iterations"), "{e}");
        let e = refused(&format!("0/2000000000|{bs}/1|{m3}"));
        assert!(e.message.contains("at most 8"), "{e}");
        let f = match parse(&format!("0/1|{bs}/1|{m3}")).unwrap() {
            Hybrid::Formula(f) => f,
            h => panic!("{h:?}"),
        };
        assert_eq!(f.phases()[0].kind, Kind::BurningShip);
    }

    #[test]
    fn what_kf_rejects_is_invalid() {
        assert!(matches!(parse("0"), Ok(Hybrid::Invalid(_))));
        assert!(matches!(parse("0/1"), Ok(Hybrid::Invalid(_))));
        assert!(matches!(parse(&format!("0/0|0,0,0,0,2,1,0;{NONE};0")), Ok(Hybrid::Invalid(_))));
        assert!(matches!(parse(&format!("1/1|0,0,0,0,2,1,0;{NONE};0")), Ok(Hybrid::Invalid(_))));
    }

    #[test]
    fn operators_factors_and_constants_are_refused_by_what_they_are() {
        // z^3 + z^2 (the order of TheRedshiftRider's terms turned), a product of a partial
        // fold, HPDZ Buffalo's line with one fold taken away.
        let e = refused("0/1|0,0,0,0,3,1,0;0,0,0,0,2,1,0;0");
        assert!(e.message.contains("`(x + iy)^3 + (x + iy)^2` combines two operators"), "{e}");
        let e = refused("0/1|0,0,0,0,2,1,0;1,0,0,0,2,1,0;2");
        assert!(e.message.contains("(x + iy)^2 * (|x| + iy)^2"), "{e}");
        let e = refused("0/1|1,1,0,0,2,1,0;1,0,0,0,1,1,0;1");
        assert!(e.message.contains(" - "), "{e}");
        let e = refused("0/1|0,0,0,0,2,2,0;0,0,0,0,0,0,0;0");
        assert!(e.message.contains("multiplies by 2"), "{e}");
        assert_eq!(e.at, 4, "points at the line");
        let e = refused("0/1|0,0,0,0,0,1,0;0,0,0,0,0,0,0;0");
        assert!(e.message.contains("constant"), "{e}");
        let e = refused(&format!("0/1|0,0,0,0,2,1,0;{NONE};0|0,0,0,0,2,1,0;{NONE};0"));
        assert!(e.message.contains("second power"), "{e}");
        let e = refused(&format!("0/1|1,1,0,0,1,1,0;{NONE};0"));
        assert!(e.message.contains("without a power"), "{e}");
        let e = refused("0/1|0,0,0,0,x,1,0;0,0,0,0,0,0,0;0");
        assert!(e.message.contains("whole number") && e.at == 12, "{e:?}");
    }
}
