//! deepfield: escape-time and distance-estimate rasters of the Mandelbrot and Julia sets.
//!
//! The library is layered as docs/design.md describes: numbers and maps at the bottom
//! ([`num`], [`formula`]), raw per-sample data above them ([`field`], [`trap`]), colour on top
//! of raw data ([`palette`], [`coloring`], [`compose`]), and scenes, rendering and files
//! around it all ([`scene`], [`render`], [`io`]); [`gpu`] runs the 2D paths on a GPU through
//! wgpu. The command line lives in the binary. The viewer and the GPU device code are cargo
//! features (`viewer`, `gpu`), on by default; see [`gpu`] for what a headless build keeps.

pub mod cancel;
pub mod coloring;
pub mod compare;
pub mod compose;
pub mod field;
pub mod formula;
pub mod gpu;
pub mod io;
pub mod kf_text;
pub mod locate;
pub mod num;
pub mod orbit;
pub mod palette;
pub mod render;
pub mod scene;
pub mod simd_level;
pub mod source;
pub mod trap;
#[cfg(feature = "viewer")]
pub mod viewer;
