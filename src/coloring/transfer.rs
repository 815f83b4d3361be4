//! Transfer functions: how smooth iteration nu maps to a palette position before density
//! and offset. Deep views have nu in the millions with bands that widen geometrically;
//! compressive transfers (sqrt, cube root, log, log-log) keep the palette cycling at a
//! steady rate across such a range.

use crate::num::fastmath;

/// Map from smooth iteration to palette position, before density and offset.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Transfer {
    /// nu.
    #[default]
    Linear,
    /// sqrt(nu).
    Sqrt,
    /// nu^(1/3).
    Cbrt,
    /// ln(1 + nu).
    Log,
    /// ln(1 + ln(1 + nu)).
    LogLog,
}

impl Transfer {
    /// Every transfer with its scene-file name.
    pub const ALL: [(Transfer, &'static str); 5] = [
        (Transfer::Linear, "linear"),
        (Transfer::Sqrt, "sqrt"),
        (Transfer::Cbrt, "cbrt"),
        (Transfer::Log, "log"),
        (Transfer::LogLog, "log-log"),
    ];

    /// Applies the transfer to nu (negative values count as 0).
    #[inline]
    pub fn apply(self, nu: f64) -> f64 {
        let nu = nu.max(0.0);
        match self {
            Transfer::Linear => nu,
            Transfer::Sqrt => nu.sqrt(),
            Transfer::Cbrt => nu.cbrt(),
            Transfer::Log => fastmath::ln_1p(nu),
            Transfer::LogLog => fastmath::ln_1p(fastmath::ln_1p(nu)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transfers_are_monotone_and_start_at_zero() {
        for (t, name) in Transfer::ALL {
            assert_eq!(t.apply(0.0), 0.0, "{name}");
            assert_eq!(t.apply(-5.0), 0.0, "{name}");
            let mut last = 0.0;
            for k in 1..100 {
                let v = t.apply(k as f64 * 37.5);
                assert!(v > last, "{name}");
                last = v;
            }
        }
        assert_eq!(Transfer::Cbrt.apply(27.0), 3.0);
        assert!((Transfer::LogLog.apply(std::f64::consts::E - 1.0) - 2f64.ln()).abs() < 1e-12);
    }
}
