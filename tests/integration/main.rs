//! Integration tests: the engine against an arbitrary-precision reference, golden images,
//! the command line, determinism and round trips. One binary, as tiny-skia does.

mod accuracy;
mod cli;
mod coloring;
mod deep;
mod formula_kf;
mod fuzz;
mod golden;
#[cfg(feature = "gpu")]
mod gpu;
mod import;
mod interior;
mod kfr_presets;
mod layout;
mod locate;
mod peer;
mod reference;
mod sink;
mod units;
mod util;
#[cfg(feature = "viewer")]
mod viewer;
