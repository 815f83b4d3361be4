//! Files: PNG images carrying their scene, EXR raw data, bitmaps for traps, safe writes.
//!
//! Every output is written to a temporary file beside its destination and renamed into
//! place only when complete ([`AtomicFile`]), so a failed or cancelled render never leaves
//! a half-written file and never clobbers an existing one. Writers stream: they accept
//! strips of rows in order and hold nothing more.

mod atomic;
mod bitmap;
mod error;
mod exr;
mod exr_blocks;
mod exr_fault;
mod exr_lines;
mod exr_plain;
mod exr_raw;
mod exr_read;
#[cfg(test)]
mod exr_test_file;
pub mod output;
mod png;
mod scene_source;
mod tile;
mod tile_exr;

pub use atomic::AtomicFile;
pub use bitmap::load_bitmap;
pub use error::{Cause, IoError};
pub use exr::{ExrEncoder, ExrLayout, ExrWriter, TILE_ATTRIBUTE, read_exr_iteration_bias, read_exr_scene};
pub use exr_read::{ExrStrips, RawData, RawHeader, read_exr_planes};
pub use png::{PngEncoder, PngWriter, SCENE_KEYWORD, read_png_scene, write_png_rgb8};
pub use scene_source::{SceneSource, read_scene_source};
pub use tile::{TILE_KEYWORD, assemble_png, band_rows, tile_text};
pub use tile_exr::assemble_exr;
