//! What a trap's plane holds: the kind of per-sample data a trap produces, by which a
//! layer's colouring and a plane read back from a file are matched.

/// What one trap's plane holds (and its EXR channels: `trapK.D`, `trapK.STRIPE`,
/// `trapK.R/G/B/A`, `trapK.IFS`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrapKind {
    /// Distances (`field::TrapPlane::Distance`).
    Distance,
    /// Stripe averages (`field::TrapPlane::Stripe`).
    Stripe,
    /// Colours (`field::TrapPlane::Color`).
    Color,
    /// IFS densities (`field::TrapPlane::Density`).
    Density,
}

impl TrapKind {
    /// The kind in words, for messages.
    pub fn name(self) -> &'static str {
        match self {
            TrapKind::Distance => "distance",
            TrapKind::Stripe => "stripe",
            TrapKind::Color => "colour",
            TrapKind::Density => "density",
        }
    }
}
