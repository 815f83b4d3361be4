//! The WGSL sources and how the shader modules are assembled from them.
//!
//! WGSL has neither `#include` nor generics, so modules are built by concatenating shared
//! text: the double-float helpers (`df.wgsl`), the uniform block and sample raster
//! (`uniforms.wgsl`), a number prelude that gives the orbit its arithmetic
//! (`num_f32.wgsl` or `num_df.wgsl`: the type `Num` and the same few functions on it,
//! [`number_wgsl`]), and the orbit loop and its compute entry point (`escape.wgsl`,
//! written once against those functions); or, for the IFS field, the first two and
//! `ifs.wgsl`. The viewer's paint shader (`src/viewer/paint.wgsl`) is appended to
//! [`escape_module`], so the compute image and the viewer iterate with the very same
//! text, in either precision.

use super::Precision;

/// Double-float arithmetic (two-sum, Dekker's two-product).
pub const DF_WGSL: &str = include_str!("df.wgsl");
/// The uniform block (mirror of [`super::uniforms::Uniforms`]) and the sample raster.
pub const UNIFORMS_WGSL: &str = include_str!("uniforms.wgsl");
/// The orbit's numbers in plain f32.
pub const NUM_F32_WGSL: &str = include_str!("num_f32.wgsl");
/// The orbit's numbers in double-float.
pub const NUM_DF_WGSL: &str = include_str!("num_df.wgsl");
/// Escape-time orbits, per-sample quantities, bitmap trap; the compute entry point.
pub const ESCAPE_WGSL: &str = include_str!("escape.wgsl");
/// The IFS density field.
pub const IFS_WGSL: &str = include_str!("ifs.wgsl");

/// Compute entry point of the escape-time kernel (either precision's module).
pub const ESCAPE_ENTRY: &str = "escape_main";
/// Compute entry point of the IFS field.
pub const IFS_ENTRY: &str = "ifs_main";

/// The number prelude of `precision`: the orbit loop's arithmetic.
pub fn number_wgsl(precision: Precision) -> &'static str {
    match precision {
        Precision::F32 => NUM_F32_WGSL,
        Precision::DoubleFloat => NUM_DF_WGSL,
    }
}

/// The escape-time compute module, iterating in `precision`.
pub fn escape_module(precision: Precision) -> String {
    [DF_WGSL, UNIFORMS_WGSL, number_wgsl(precision), ESCAPE_WGSL].concat()
}

/// The IFS compute module.
pub fn ifs_module() -> String {
    [DF_WGSL, UNIFORMS_WGSL, IFS_WGSL].concat()
}
