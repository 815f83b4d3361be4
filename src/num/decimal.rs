//! `Decimal`: a validated decimal string with a wide-exponent summary of its value.
//!
//! The text is kept verbatim (it is the contract with the user and with deeper engines);
//! `mantissa * 10^exp10` summarises it for decisions that must work beyond the f64
//! exponent range, such as "is this zoom too deep for f64?".

use std::fmt;

use malachite_base::num::arithmetic::traits::{Pow, RoundToMultiple};
use malachite_base::num::conversion::traits::{FromSciString, RoundingFrom};
use malachite_base::rounding_modes::RoundingMode;
use malachite_nz::integer::Integer;
use malachite_q::Rational;

/// Why a string is not a decimal number.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "`{text}` is not a decimal number ({reason}); expected digits with an optional sign, point and exponent, like \"-0.75\" or \"1.5e-20\""
)]
pub struct DecimalError {
    /// The offending text.
    pub text: String,
    /// What is wrong with it.
    pub reason: &'static str,
}

/// A decimal number as written, plus `mantissa * 10^exp10` (mantissa in [1, 10), or 0).
#[derive(Debug, Clone, PartialEq)]
pub struct Decimal {
    text: String,
    mantissa: f64,
    exp10: i64,
}

impl Decimal {
    /// Parses `text` (surrounding whitespace ignored).
    pub fn parse(text: &str) -> Result<Self, DecimalError> {
        let t = text.trim();
        let err = |reason| DecimalError { text: text.to_string(), reason };
        let (negative, body) = match t.as_bytes().first() {
            Some(b'-') => (true, &t[1..]),
            Some(b'+') => (false, &t[1..]),
            Some(_) => (false, t),
            None => return Err(err("it is empty")),
        };
        let (significand, exponent) = match body.find(['e', 'E']) {
            Some(i) => (&body[..i], Some(&body[i + 1..])),
            None => (body, None),
        };
        let (int_part, frac_part) = match significand.find('.') {
            Some(i) => (&significand[..i], &significand[i + 1..]),
            None => (significand, ""),
        };
        if int_part.is_empty() && frac_part.is_empty() {
            return Err(err("it has no digits"));
        }
        if !int_part.bytes().chain(frac_part.bytes()).all(|b| b.is_ascii_digit()) {
            return Err(err("it contains a character that is not a digit"));
        }
        let exp: i64 = match exponent {
            None => 0,
            Some(e) => {
                let digits = e.strip_prefix(['+', '-']).unwrap_or(e);
                if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
                    return Err(err("its exponent is not an integer"));
                }
                if digits.len() > 15 {
                    return Err(err("its exponent is absurdly large"));
                }
                e.parse().map_err(|_| err("its exponent is not an integer"))?
            }
        };
        // Position of the first significant digit decides the decimal exponent.
        let all: Vec<u8> = int_part.bytes().chain(frac_part.bytes()).collect();
        let (mantissa, exp10) = match all.iter().position(|&b| b != b'0') {
            None => (0.0, 0),
            Some(first) => {
                let sig: String = all[first..].iter().take(17).map(|&b| b as char).collect();
                let m: f64 = format!("{}.{}", &sig[..1], &sig[1..]).parse().unwrap_or(1.0);
                let e = int_part.len() as i64 - 1 - first as i64 + exp;
                (m, e)
            }
        };
        Ok(Self { text: t.to_string(), mantissa: if negative { -mantissa } else { mantissa }, exp10 })
    }

    /// The text as written (trimmed).
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Nearest f64 (correctly rounded; may be infinite or zero outside the f64 range).
    pub fn to_f64(&self) -> f64 {
        self.text.parse().unwrap_or(f64::NAN)
    }

    /// log10(|value|); negative infinity for zero.
    pub fn log10_abs(&self) -> f64 {
        if self.mantissa == 0.0 { f64::NEG_INFINITY } else { self.mantissa.abs().log10() + self.exp10 as f64 }
    }

    /// True when the value is exactly zero.
    pub fn is_zero(&self) -> bool {
        self.mantissa == 0.0
    }

    /// True when the value is negative.
    pub fn is_negative(&self) -> bool {
        self.mantissa < 0.0
    }
}

impl Decimal {
    /// `r` rounded to `digits` digits after the point (trailing zeros dropped): the exact
    /// text of a value computed in rationals or big floats, e.g. a view centre found by
    /// Newton's method.
    pub fn from_rational(r: &Rational, digits: u64) -> Decimal {
        let scale = Rational::from(10u32).pow(digits);
        let scaled = (r * &scale).round_to_multiple(Rational::from(1u32), RoundingMode::Nearest).0;
        let int: Integer = Integer::rounding_from(&scaled, RoundingMode::Exact).0;
        let full = int.to_string();
        let neg = full.starts_with('-');
        let mut s = full.trim_start_matches('-').to_string();
        while s.len() <= digits as usize {
            s.insert(0, '0');
        }
        s.insert(s.len() - digits as usize, '.');
        let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
        let text = if neg && s != "0" { format!("-{s}") } else { s };
        // Digits, a point and a sign: always a valid decimal.
        Decimal::parse(&text).unwrap_or_else(|_| Decimal { text: "0".into(), mantissa: 0.0, exp10: 0 })
    }

    /// The exact value as a rational (zero if the text were somehow unreadable).
    pub fn to_rational(&self) -> Rational {
        let t = self.text.strip_prefix('+').unwrap_or(&self.text);
        Rational::from_sci_string(t).unwrap_or_default()
    }
}

/// A positive number given by its decimal logarithm, as text `m.mmme±N` with `digits`
/// digits after the point: depths, zooms and sizes far outside the f64 range (zoom 1e1086
/// is `1.000000e1086`).
pub fn scientific(log10: f64, digits: usize) -> String {
    let e = log10.floor();
    format!("{:.digits$}e{e}", 10f64.powf(log10 - e))
}

impl fmt::Display for Decimal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_summarises() {
        let d = Decimal::parse("-0.000123e-5").unwrap();
        assert!((d.log10_abs() - (1.23f64.log10() - 9.0)).abs() < 1e-12);
        assert!(d.is_negative());
        assert_eq!(d.to_f64(), -0.000123e-5);
        let deep = Decimal::parse("1e1000").unwrap();
        assert_eq!(deep.log10_abs(), 1000.0);
        assert!(deep.to_f64().is_infinite());
        assert!(Decimal::parse("0.000").unwrap().is_zero());
    }

    #[test]
    fn rationals_round_to_decimal_text() {
        let third = Rational::from(1u32) / Rational::from(3u32);
        assert_eq!(Decimal::from_rational(&third, 5).text(), "0.33333");
        assert_eq!(Decimal::from_rational(&-(Rational::from(7u32) / Rational::from(4u32)), 1).text(), "-1.8");
        assert_eq!(Decimal::from_rational(&Rational::from(0u32), 3).text(), "0");
        let d = Decimal::parse("-1.25e-3").unwrap();
        assert_eq!(Decimal::from_rational(&d.to_rational(), 10).text(), "-0.00125");
    }

    #[test]
    fn rejects_garbage() {
        for bad in ["", "-", "1.2.3", "abc", "1e", "1e+-2", "0x10", "1,5", "nan", "inf"] {
            assert!(Decimal::parse(bad).is_err(), "{bad}");
        }
    }
}
