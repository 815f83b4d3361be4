//! Cancellation: the error of work stopped before it finished (Ctrl-C, a newer view in the
//! viewer). Its own module, below everything that can be cancelled, so the deep engine and
//! the per-sample planes share it without depending on each other.

use std::sync::atomic::AtomicBool;

/// The work was cancelled before it finished.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("cancelled")]
pub struct Cancelled;

/// A flag nobody raises: for work requested outside any job that can be cancelled (the
/// engine's own set-up, the Newton tests' return maps, tests and benchmarks).
pub static NEVER: AtomicBool = AtomicBool::new(false);
