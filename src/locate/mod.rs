//! Finding locations: the minibrot nearest a point (its period by the ball method, its
//! nucleus by Newton's method in big floats, its size and orientation for framing) and
//! Misiurewicz points (preperiod and period, by Newton's method), and the search of a view
//! for either ([`search`], behind `deepfield find` and the viewer's Newton zoom).
//!
//! These are what explorers use to reach deep views in a few steps (Kalles Fraktaler's and
//! Fraktaler-3's Newton zooming, after Claude Heiland-Allen's notes on atom domains, nucleus
//! finding and size estimates), and what the deep-view fuzzer uses to generate locations
//! nobody tuned the engine to. Every computation runs in malachite's floats at a precision
//! the caller chooses from the depth; the results keep it, so a centre found at 1e-2000 is
//! exact to its last digit.

pub mod family;
pub mod misiurewicz;
pub mod nucleus;
pub mod period;
pub mod search;

pub use nucleus::Minibrot;
