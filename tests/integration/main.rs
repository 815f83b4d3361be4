//! Integration tests: the engine against an arbitrary-precision reference, golden images,
//! the command line, determinism and round trips. One binary, as tiny-skia does.

mod accuracy;
mod cli;
mod coloring;
mod deep;
mod fuzz;
mod golden;
mod gpu;
mod import;
mod reference;
mod units;
mod util;
mod viewer;
