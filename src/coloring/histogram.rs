//! Histogram equalisation of iteration counts: the palette position of a sample is the
//! fraction of exterior samples that escaped before it, so every colour of the palette
//! covers the same area of the image whatever the depth or the iteration spread.
//!
//! The cumulative distribution is taken over the whole image (every sample of every strip),
//! never per strip, so a render and a recolour of its raw data agree. Between the counts at
//! N and N + 1 the position moves linearly with NF, which makes it continuous across
//! iteration bands exactly as the smooth iteration count is.

use crate::field::Planes;
use crate::formula::end::INTERIOR;

/// Cumulative distribution of escape counts over an image.
#[derive(Debug, Clone, PartialEq)]
pub struct Histogram {
    /// Distinct escape counts, increasing.
    counts: Vec<u32>,
    /// `below[i]`: fraction of exterior samples with N < counts[i]; one more entry (1.0).
    below: Vec<f64>,
}

impl Histogram {
    /// Builds the distribution from every exterior sample of `strips`.
    pub fn build<'a>(strips: impl IntoIterator<Item = &'a Planes>) -> Self {
        let mut ns: Vec<u32> = Vec::new();
        for p in strips {
            ns.extend(p.n.iter().copied().filter(|&n| n != INTERIOR));
        }
        rayon::slice::ParallelSliceMut::par_sort_unstable(&mut ns[..]);
        let total = ns.len().max(1) as f64;
        let mut counts = Vec::new();
        let mut below = Vec::new();
        for (i, &n) in ns.iter().enumerate() {
            if counts.last() != Some(&n) {
                counts.push(n);
                below.push(i as f64 / total);
            }
        }
        below.push(1.0);
        Self { counts, below }
    }

    /// Position in [0, 1] of a sample with escape count `n` and fraction `nf`.
    #[inline]
    pub fn position(&self, n: u32, nf: f32) -> f64 {
        let i = self.counts.partition_point(|&c| c < n);
        let lo = self.below.get(i).copied().unwrap_or(1.0);
        // The fraction below n + 1: the next entry when it is n + 1's own, else the same
        // as below the next larger count.
        let j = if self.counts.get(i) == Some(&n) { i + 1 } else { i };
        let hi = self.below.get(j).copied().unwrap_or(1.0);
        lo + (hi - lo) * nf as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::Needs;

    fn planes(n: &[u32]) -> Planes {
        let mut p = Planes::new(n.len(), 1, &Needs::default());
        p.n.copy_from_slice(n);
        p
    }

    #[test]
    fn equalises_and_is_continuous() {
        let a = planes(&[3, 3, 5, INTERIOR]);
        let b = planes(&[5, 9]);
        let h = Histogram::build([&a, &b]);
        // 5 exterior samples: N=3 twice, 5 twice, 9 once.
        assert_eq!(h.position(3, 0.0), 0.0);
        assert_eq!(h.position(5, 0.0), 0.4);
        assert_eq!(h.position(9, 0.0), 0.8);
        // Continuity: (n, nf -> 1) meets (n + 1, 0).
        assert_eq!(h.position(3, 1.0), h.position(4, 0.0));
        assert_eq!(h.position(4, 0.5), 0.4);
        assert_eq!(h.position(9, 1.0), 1.0);
        assert_eq!(h.position(2, 0.5), 0.0);
        assert_eq!(h.position(100, 0.5), 1.0);
    }
}
