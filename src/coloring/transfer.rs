//! Transfer functions: how smooth iteration nu maps to a palette position before density
//! and offset. Deep views have nu in the millions with bands that widen geometrically;
//! compressive transfers (sqrt, cube root, log, log-log) keep the palette cycling at a
//! steady rate across such a range.

use crate::num::fastmath;
use crate::simd_level::SimdLevel;

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
    #[inline(always)]
    pub fn apply(self, nu: f64) -> f64 {
        let mut v = [nu];
        self.apply_all(SimdLevel::Scalar, &mut v);
        v[0]
    }

    /// [`Transfer::apply`] to every value of a run, in place, under `simd`'s instruction set
    /// ([`SimdLevel::map`]): a loop with no branch inside, which vectorises at that width.
    /// The functions are IEEE operations in a fixed order, so every width gives the same
    /// bits.
    pub fn apply_all(self, simd: SimdLevel, v: &mut [f64]) {
        match self {
            Transfer::Linear => simd.map(v, |x| x.max(0.0)),
            Transfer::Sqrt => simd.map(v, |x| x.max(0.0).sqrt()),
            Transfer::Cbrt => simd.map(v, |x| fastmath::cbrt(x.max(0.0))),
            Transfer::Log => simd.map(v, |x| fastmath::ln_1p(x.max(0.0))),
            Transfer::LogLog => simd.map(v, |x| fastmath::ln_1p(fastmath::ln_1p(x.max(0.0)))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd_level::testing::{every_level_matches, uniform};

    #[test]
    fn every_instruction_set_gives_the_values_of_one_sample_at_a_time() {
        // Smooth iteration counts from 1e-3 to 4e9, and the edges.
        let mut nu: Vec<f64> = uniform(11, 1000).into_iter().map(|u| 10f64.powf(u * 12.6 - 3.0)).collect();
        nu.extend([0.0, -1.0, 1.0, 4294967295.0, 1e-17, f64::NAN]);
        for (t, name) in Transfer::ALL {
            every_level_matches(&nu, |x| t.apply(x), |l, v| t.apply_all(l, v), name);
        }
    }

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
