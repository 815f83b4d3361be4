//! Layer masks: a layer's opacity at each sample, from a quantity of the raw planes.
//!
//! A mask keeps the samples whose quantity lies in [below, above] (either end open), with a
//! linear ramp `feather` wide on each side, and may be inverted. Typical uses: lighting
//! only near the boundary (distance <= 8 px), a palette only on late bands (iteration >=
//! 500), a colouring only inside the set.

use crate::field::Planes;
use crate::formula::end::INTERIOR;

/// A mask's feather where the scene gives none: hard edges.
pub const MASK_FEATHER: f64 = 0.0;

/// The quantity a mask reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MaskQuantity {
    /// Distance estimate in image pixels (0 inside the set).
    Distance,
    /// Smooth iteration count nu = N + NF (infinite inside).
    Iteration,
    /// Final phase T in turns.
    Phase,
    /// 1 inside the set, 0 outside.
    Interior,
}

impl MaskQuantity {
    /// Every quantity with its scene-file name.
    pub const ALL: [(MaskQuantity, &'static str); 4] = [
        (MaskQuantity::Distance, "distance"),
        (MaskQuantity::Iteration, "iteration"),
        (MaskQuantity::Phase, "phase"),
        (MaskQuantity::Interior, "interior"),
    ];
}

/// A mask on a layer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mask {
    /// What it reads.
    pub quantity: MaskQuantity,
    /// Lower end of the kept range.
    pub above: f64,
    /// Upper end of the kept range.
    pub below: f64,
    /// Width of the ramps at each end (0: hard edges).
    pub feather: f64,
    /// Keep the complement instead.
    pub invert: bool,
}

impl Mask {
    /// The planes the mask reads: (nf, t, de).
    pub fn needs(&self) -> (bool, bool, bool) {
        match self.quantity {
            MaskQuantity::Distance => (false, false, true),
            MaskQuantity::Iteration => (true, false, false),
            MaskQuantity::Phase => (false, true, false),
            MaskQuantity::Interior => (false, false, false),
        }
    }

    /// The quantity at sample `k`; `px` converts sample-raster pixels to image pixels.
    #[inline]
    fn quantity(&self, planes: &Planes, k: usize, px: f64) -> f64 {
        let inside = planes.n[k] == INTERIOR;
        match self.quantity {
            MaskQuantity::Interior => f64::from(u8::from(inside)),
            MaskQuantity::Distance if inside => 0.0,
            MaskQuantity::Distance => {
                let (x, y) = (planes.dex[k] as f64, planes.dey[k] as f64);
                (x * x + y * y).sqrt() * px
            }
            MaskQuantity::Iteration if inside => f64::INFINITY,
            MaskQuantity::Iteration => planes.n[k] as f64 + planes.nf[k] as f64,
            MaskQuantity::Phase => planes.t[k] as f64,
        }
    }

    /// Opacity factor in [0, 1] for value `q`.
    #[inline]
    pub fn weight(&self, q: f64) -> f32 {
        let ramp = |excess: f64| {
            if excess <= 0.0 {
                1.0
            } else if self.feather > 0.0 {
                (1.0 - excess / self.feather).max(0.0)
            } else {
                0.0
            }
        };
        let w = ramp(self.above - q).min(ramp(q - self.below));
        let w = if q.is_nan() { 0.0 } else { w };
        (if self.invert { 1.0 - w } else { w }) as f32
    }

    /// Opacity factor at sample `k`.
    #[inline]
    pub fn at(&self, planes: &Planes, k: usize, px: f64) -> f32 {
        self.weight(self.quantity(planes, k, px))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_and_feather() {
        let m = Mask {
            quantity: MaskQuantity::Distance,
            above: f64::NEG_INFINITY,
            below: 4.0,
            feather: 2.0,
            invert: false,
        };
        assert_eq!(m.weight(0.0), 1.0);
        assert_eq!(m.weight(4.0), 1.0);
        assert_eq!(m.weight(5.0), 0.5);
        assert_eq!(m.weight(6.5), 0.0);
        let band = Mask { above: 10.0, below: 20.0, feather: 0.0, invert: true, ..m };
        assert_eq!(band.weight(15.0), 0.0);
        assert_eq!(band.weight(9.0), 1.0);
        assert_eq!(band.weight(f64::INFINITY), 1.0);
    }
}
