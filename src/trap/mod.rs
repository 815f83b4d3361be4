//! Orbit traps: shapes and bitmaps the orbit is tested against while it iterates.
//!
//! A trap observes every z_k the kernel computes for k >= 1, up to and including the
//! escaping value (or z_max_iter). Geometric traps keep the minimum distance of the orbit
//! to their shape; the bitmap trap (Inigo Quilez's technique) maps z to texture coordinates
//! and stops at the first sample whose alpha exceeds its threshold, keeping that colour.
//! Traps cost a scalar pass per sample, so the field only runs them when a layer asks.

mod bitmap;
mod geometric;
pub mod ifs;
mod kind;
pub mod stripe;

pub use bitmap::{Bitmap, BitmapTrap, Frame};
pub use geometric::Shape;
pub use kind::TrapKind;
pub use stripe::Stripe;

/// A trap the kernel evaluates along each orbit.
#[derive(Debug, Clone, PartialEq)]
pub enum Trap {
    /// Minimum distance of the orbit to a shape.
    Geometric(Shape),
    /// First bitmap sample whose alpha exceeds the threshold.
    Bitmap(BitmapTrap),
    /// Stripe average of the orbit's arguments (not a trap, but observed the same way).
    Stripe(Stripe),
    /// The minimal IFS density field at the sample's point: not an orbit statistic (it
    /// observes nothing), kept in the trap list so that its plane travels with the others
    /// (EXR channel, recolouring).
    Ifs(ifs::IfsParams),
}

impl Trap {
    /// What the trap's plane holds.
    pub fn plane_kind(&self) -> TrapKind {
        match self {
            Trap::Geometric(_) => TrapKind::Distance,
            Trap::Stripe(_) => TrapKind::Stripe,
            Trap::Bitmap(_) => TrapKind::Color,
            Trap::Ifs(_) => TrapKind::Density,
        }
    }

    /// True when the trap observes the orbit (every kind but the IFS field).
    pub fn observes_orbit(&self) -> bool {
        !matches!(self, Trap::Ifs(_))
    }
}

/// Per-orbit running state of one trap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TrapState {
    /// Smallest distance so far (infinite before the first observation).
    Distance(f64),
    /// Colour of the first hit (linear, premultiplied RGBA), or zero while nothing hit.
    Color {
        /// The colour.
        rgba: [f32; 4],
        /// True once a sample exceeded the threshold.
        hit: bool,
    },
    /// Running sum of the stripe function, its last term and the number of terms.
    Stripe {
        /// Sum of the terms so far.
        sum: f64,
        /// The latest term.
        last: f64,
        /// Terms so far.
        count: u32,
    },
}

impl Trap {
    /// State before the first observation.
    pub fn initial(&self) -> TrapState {
        match self {
            Trap::Geometric(_) => TrapState::Distance(f64::INFINITY),
            Trap::Bitmap(_) => TrapState::Color { rgba: [0.0; 4], hit: false },
            Trap::Stripe(_) => TrapState::Stripe { sum: 0.0, last: 0.0, count: 0 },
            Trap::Ifs(_) => TrapState::Distance(f64::NAN),
        }
    }

    /// Records z_k.
    #[inline]
    pub fn observe(&self, state: &mut TrapState, z: [f64; 2]) {
        match (self, state) {
            (Trap::Geometric(shape), TrapState::Distance(d)) => {
                let e = shape.distance(z);
                if e < *d {
                    *d = e;
                }
            }
            (Trap::Bitmap(trap), TrapState::Color { rgba, hit }) if !*hit => {
                let s = trap.sample(z);
                if s[3] > trap.threshold {
                    *rgba = s;
                    *hit = true;
                }
            }
            (Trap::Stripe(s), TrapState::Stripe { sum, last, count }) => {
                *last = s.term(z);
                *sum += *last;
                *count += 1;
            }
            _ => {}
        }
    }
}
