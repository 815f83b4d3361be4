//! The formula a `.kfr` names: its `FractalType` and `Power`, or its hybrid formula.
//!
//! KF 2.15 draws the hybrid when `UseHybridFormula` is non-zero and `HybridFormula` passes
//! its check, and `FractalType` at `Power` otherwise (`CFraktalSFT::OpenString` in
//! `fraktal_sft/Parameter.cpp`: absent keys mean type 0, power 2, no hybrid). A type that is
//! a row of [`KINDS`] becomes that family, at `Power` if the family comes in it; every other
//! type of KF 2.15 (the `<group type=...>` entries of its `formula/formula.xml`, 0 to 71) is
//! refused by its KF name, from [`REFUSED`], the one list of them. A hybrid is read by
//! [`super::kfr_hybrid`]; KF's formula presets are all hybrids, and their `FractalType` is
//! only named in messages.

use super::kfr::Kfr;
use super::kfr_hybrid::{self, Hybrid};
use crate::formula::kind::KINDS;
use crate::formula::map::{FOLD_IM, IM_BY_Y};
use crate::formula::{Formula, Kind, Phase};
use crate::source::SourceError;

/// KF 2.15's formula types that are none of deepfield's families, with KF's names.
pub const REFUSED: [(u32, &str); 5] = [
    (52, "General Quadratic Minus"),
    (53, "General Quadratic Plus"),
    (69, "General Abs Quadratic Minus"),
    (70, "General Abs Quadratic Plus"),
    (71, "z^2 exp(2 a / z) + c"),
];

/// KF's name for its formula type `t`, if KF 2.15 has one.
pub fn kf_type_name(t: u64) -> Option<&'static str> {
    let t = u32::try_from(t).ok()?;
    KINDS.iter().find(|k| k.kf_type == t).map(|k| k.kf_name).or_else(|| REFUSED.iter().find(|r| r.0 == t).map(|r| r.1))
}

/// The formula a file names, and what its generated text should say about it.
pub(super) struct Chosen {
    /// The map.
    pub formula: Formula,
    /// Comment lines for the generated text (each without `#`).
    pub notes: Vec<String>,
}

/// The file's formula (see the module documentation).
pub(super) fn formula(kfr: &Kfr<'_>) -> Result<Chosen, SourceError> {
    let fractal_type = kfr.integer("FractalType", 0, u32::MAX as u64, "KF's formula number")?.unwrap_or(0);
    let mut notes = vec![];
    if kfr.integer("UseHybridFormula", 0, u32::MAX as u64, "1 when KF draws the hybrid formula")?.unwrap_or(0) != 0 {
        let also = || match kf_type_name(fractal_type) {
            Some(name) => format!(" (the file's FractalType {fractal_type} is KF's {name})"),
            None => String::new(),
        };
        match kfr.get("HybridFormula") {
            None => notes.push("The file turns on a hybrid formula but gives none: KF draws `FractalType`.".into()),
            Some(e) => match kfr_hybrid::parse(e.value) {
                Ok(Hybrid::Formula(formula)) => {
                    notes.push(format!("KF's hybrid formula `{}` is `{formula}`.", e.value));
                    return Ok(Chosen { formula, notes });
                }
                Ok(Hybrid::Invalid(why)) => {
                    notes.push(format!("KF does not draw the file's hybrid formula ({why}): it draws `FractalType`."));
                }
                Err(err) => {
                    return Err(
                        kfr.error_at(e.value_at + err.at, format!("`HybridFormula`: {}{}", err.message, also()))
                    );
                }
            },
        }
    }
    let type_at = kfr.get("FractalType").map_or(0, |e| e.value_at);
    let Some(kind) = u32::try_from(fractal_type).ok().and_then(Kind::from_kf_type) else {
        let message = match kf_type_name(fractal_type) {
            Some(name) => format!("FractalType {fractal_type} ({name}) is not one deepfield draws"),
            None => format!("FractalType {fractal_type} is not one of Kalles Fraktaler 2.15's formulas (0 to 71)"),
        };
        return Err(kfr.error_at(type_at, message));
    };
    let power = kfr.integer("Power", 0, u32::MAX as u64, "the formula's power")?.unwrap_or(2);
    let power = match u32::try_from(power) {
        Ok(p) if kind.has_power(p) => p,
        _ => {
            let i = kind.info();
            let at = kfr.get("Power").map_or(type_at, |e| e.value_at);
            return Err(kfr.error_at(
                at,
                format!(
                    "KF's {} (FractalType {}) at power {power} is not one deepfield draws: its `{}` comes in powers {} to {}",
                    i.kf_name, i.kf_type, i.name, i.min_power, i.max_power
                ),
            ));
        }
    };
    let mut formula = Formula::single(Phase::new(kind, power));
    if kind.takes_a() {
        // KF's a: `FactorAR` + i `FactorAI`, 1 + 0i where a key is missing.
        let part = |key: &str, default: f64| -> Result<f64, SourceError> {
            let Some(e) = kfr.get(key) else { return Ok(default) };
            let v = crate::num::Decimal::parse(e.value)
                .map(|d| d.to_f64())
                .map_err(|err| kfr.error_at(e.value_at, format!("`{key}` (the formula's coefficient a): {err}")))?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(kfr.error_at(e.value_at, format!("`{key}: {}` is out of range for the coefficient a", e.value)))
            }
        };
        formula = formula.with_a([part("FactorAR", 1.0)?, part("FactorAI", 0.0)?]);
    }
    Ok(Chosen { formula, notes })
}

/// True when every phase commutes with complex conjugation (no fold of the imaginary part,
/// or one after the power that takes back the sign of y, which conjugation flips), so the
/// picture about conj(c) is the mirror image of the picture about c.
pub(super) fn symmetric(formula: &Formula) -> bool {
    formula.phases().iter().all(|p| {
        if let Some(s) = p.kind.sum() {
            // a W² ± W^p at conj(z) is conj(conj(a) W² ± W^p) when W(conj z) = conj W, which
            // a fold of y breaks: the mirror image for real a and no such fold.
            return p.a.get()[1] == 0.0 && s.fold_in & FOLD_IM == 0;
        }
        if p.kind.factors().is_some() {
            // z^a (|x| + i|y|)^b at conj(z) is conj(z^a) (|x| + i|y|)^b.
            return false;
        }
        let (fold_in, _, fold_out, _) = p.kind.shape(p.power);
        fold_in & FOLD_IM == 0 && (fold_out & FOLD_IM == 0 || fold_out & IM_BY_Y != 0)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::phase::apply;

    #[test]
    fn every_type_of_kf_2_15_is_a_family_or_refused_by_name() {
        for t in 0..=71u32 {
            let family = Kind::from_kf_type(t).is_some();
            let refused = REFUSED.iter().any(|r| r.0 == t);
            assert!(family != refused, "type {t}: family {family}, refused {refused}");
            assert!(kf_type_name(t as u64).is_some());
        }
        assert_eq!(kf_type_name(72), None);
        assert_eq!(kf_type_name(1), Some("Burning Ship"));
    }

    /// The finding about KF's imaginary axis, checked against the maps: conjugating the
    /// plane maps a family's picture onto its mirror image exactly when it folds no
    /// imaginary part (or signs the fold by y). The Burning Ship does, so its mirror image (deepfield's axis up
    /// against KF's down) is upside down, not another part of the ship.
    #[test]
    fn symmetry_about_the_real_axis() {
        let conj = |z: [f64; 2]| [z[0], -z[1]];
        for k in KINDS {
            for p in k.min_power..=k.max_power {
                let phase = Phase::new(k.kind, p);
                let commutes = [[0.3, 0.7], [-0.6, 0.2], [0.45, -0.85], [-0.25, -0.35]]
                    .iter()
                    .all(|&z| apply(phase, conj(z)) == conj(apply(phase, z)));
                assert_eq!(symmetric(&Formula::single(phase)), commutes, "{phase}");
            }
        }
        assert!(!symmetric(&Formula::single(Phase::new(Kind::BurningShip, 2))));
        assert!(symmetric(&Formula::default()));
    }
}
