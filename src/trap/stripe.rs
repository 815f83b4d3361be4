//! Stripe average colouring's orbit statistic (Jussi Härkönen, 2007): the mean over the
//! orbit of 0.5 + 0.5 sin(s arg z_k). Observed along the orbit like a trap (it needs every
//! z_k, so it runs in the scalar and per-sample deep paths, and only when a layer asks).
//!
//! The raw plane holds the average smoothed across iteration bands: with A_n the mean of
//! the terms up to the escaping z_n and A_{n-1} the mean without it, the value is
//! A_{n-1} + (A_n - A_{n-1}) NF, which is continuous where N changes (NF -> 1 on one side
//! meets NF = 0 on the other with the same set of terms).

/// The stripe statistic's parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stripe {
    /// Stripes per turn of arg z (s); whole numbers give seamless stripes.
    pub frequency: f64,
}

impl Stripe {
    /// The term for one orbit value.
    #[inline]
    pub fn term(&self, z: [f64; 2]) -> f64 {
        0.5 + 0.5 * (self.frequency * z[1].atan2(z[0])).sin()
    }
}

/// The means with and without the last term, from the running state.
#[inline]
pub fn means(sum: f64, last: f64, count: u32) -> (f64, f64) {
    match count {
        0 => (0.0, 0.0),
        1 => (sum, sum),
        n => ((sum - last) / (n - 1) as f64, sum / n as f64),
    }
}

/// The band-smoothed stripe value: mean without the last term, moved towards the full mean
/// by the smooth iteration fraction `nf`.
#[inline]
pub fn smoothed(prev: f32, full: f32, nf: f32) -> f32 {
    prev + (full - prev) * nf
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn means_and_smoothing() {
        let s = Stripe { frequency: 1.0 };
        assert!((s.term([0.0, 1.0]) - 1.0).abs() < 1e-15);
        assert!((s.term([1.0, 0.0]) - 0.5).abs() < 1e-15);
        assert_eq!(means(3.0, 1.0, 3), (1.0, 1.0));
        assert_eq!(means(2.0, 2.0, 2), (0.0, 1.0));
        assert_eq!(smoothed(0.0, 1.0, 0.25), 0.25);
    }
}
