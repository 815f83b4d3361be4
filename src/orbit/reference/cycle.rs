//! Brent's cycle detection, as both ways of stepping a reference orbit (fixed point, big
//! floats) run it on their exact state: one remembered value, renewed each time the steps
//! since it reach a power of two (1, 2, 4, ...), and one comparison per step. Once the
//! orbit is inside a cycle of period q, the remembered value is in it too within a power of
//! two past q, and the orbit meets it again q steps later: the repeat is found within about
//! three times the steps it takes the orbit to enter the cycle and go round it once.

/// The detector's state around a remembered value of type `S`.
#[derive(Debug, Clone)]
pub struct Brent<S> {
    saved: S,
    since: u32,
    power: u32,
}

impl<S> Brent<S> {
    /// A detector that remembers `start`, the orbit's first value.
    pub fn new(start: S) -> Self {
        Brent { saved: start, since: 0, power: 1 }
    }

    /// After a step: `is_saved` tells whether the new value is exactly the remembered one,
    /// `remember` stores the new value in its place. Returns the period q when the value is
    /// the one q steps back.
    pub fn found(&mut self, is_saved: impl FnOnce(&S) -> bool, remember: impl FnOnce(&mut S)) -> Option<u32> {
        self.since += 1;
        if is_saved(&self.saved) {
            return Some(self.since);
        }
        if self.since == self.power {
            remember(&mut self.saved);
            self.since = 0;
            self.power = self.power.saturating_mul(2);
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On the orbit of k -> k^2 + 1 mod 1000 from 3 (a preperiod and then a cycle), the
    /// period found is the cycle's, by direct search.
    #[test]
    fn finds_the_period_of_a_sequence_that_enters_a_cycle() {
        let f = |k: u64| (k * k + 1) % 1000;
        let mut seen = std::collections::HashMap::new();
        let (mut k, mut n) = (3u64, 0u32);
        let period = loop {
            if let Some(m) = seen.insert(k, n) {
                break n - m;
            }
            k = f(k);
            n += 1;
        };
        let (mut k, mut b) = (3u64, Brent::new(3u64));
        let found = loop {
            k = f(k);
            if let Some(q) = b.found(|s| *s == k, |s| *s = k) {
                break q;
            }
        };
        assert_eq!(found, period);
    }
}
