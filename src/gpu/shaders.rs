//! The WGSL sources and how the shader modules are assembled from them.
//!
//! WGSL has no `#include`, so modules are built by concatenating shared text: the
//! double-float helpers (`df.wgsl`), the uniform block and sample raster
//! (`uniforms.wgsl`), the orbit code and its compute entry points (`escape.wgsl`), and
//! on top of those either the paint callback's vertex and fragment shaders (`paint.wgsl`)
//! or the IFS field (`ifs.wgsl`). The compute image and the viewer therefore iterate with
//! the very same text.

/// Double-float arithmetic (two-sum, Dekker's two-product).
pub const DF_WGSL: &str = include_str!("df.wgsl");
/// The uniform block (mirror of [`super::uniforms::Uniforms`]) and the sample raster.
pub const UNIFORMS_WGSL: &str = include_str!("uniforms.wgsl");
/// Escape-time orbits, per-sample quantities, bitmap trap; compute entry points.
pub const ESCAPE_WGSL: &str = include_str!("escape.wgsl");
/// The viewer's paint callback: full-viewport triangle, palette, distance shading.
pub const PAINT_WGSL: &str = include_str!("paint.wgsl");
/// The IFS density field.
pub const IFS_WGSL: &str = include_str!("ifs.wgsl");

/// Compute entry point of the f32 escape-time kernel.
pub const ESCAPE_F32_ENTRY: &str = "escape_f32_main";
/// Compute entry point of the double-float escape-time kernel.
pub const ESCAPE_DF_ENTRY: &str = "escape_df_main";
/// Compute entry point of the IFS field.
pub const IFS_ENTRY: &str = "ifs_main";
/// Vertex entry point of the paint callback.
pub const PAINT_VS_ENTRY: &str = "paint_vs";
/// Fragment entry point of the paint callback, f32 orbits.
pub const PAINT_F32_ENTRY: &str = "paint_f32_fs";
/// Fragment entry point of the paint callback, double-float orbits.
pub const PAINT_DF_ENTRY: &str = "paint_df_fs";

/// The escape-time compute module.
pub fn escape_module() -> String {
    [DF_WGSL, UNIFORMS_WGSL, ESCAPE_WGSL].concat()
}

/// The paint module: the escape-time module plus the vertex and fragment shaders.
pub fn paint_module() -> String {
    [DF_WGSL, UNIFORMS_WGSL, ESCAPE_WGSL, PAINT_WGSL].concat()
}

/// The IFS compute module.
pub fn ifs_module() -> String {
    [DF_WGSL, UNIFORMS_WGSL, IFS_WGSL].concat()
}
