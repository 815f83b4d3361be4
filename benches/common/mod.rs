//! What the benchmarks share: whether a run measures, or only checks that each benchmark
//! runs.
//!
//! `cargo bench` passes `--bench` and measures. `cargo test --all-targets` (the test suite)
//! runs every benchmark once without it: that checks each runs and what it asserts, not its
//! speed, so there the views shrink to an eighth per side and the check takes a second, not
//! half a minute.

/// True when this run measures (`cargo bench`), false when it only checks (`cargo test`).
pub fn measuring() -> bool {
    std::env::args().any(|a| a == "--bench")
}

/// `n` pixels per side for this run: `n` when measuring, else an eighth of it (at least 8).
pub fn side(n: u32) -> u32 {
    if measuring() { n } else { (n / 8).max(8) }
}
