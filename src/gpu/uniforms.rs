//! The one uniform block every GPU pipeline reads (escape-time compute, IFS compute, the
//! viewer's paint callback), mirrored field for field by `Params` in `uniforms.wgsl`.
//!
//! Every field is a 4-byte scalar, so the WGSL uniform layout rules (members aligned to
//! their size, vec2/vec3/arrays with 8/16-byte alignment and strides) never insert
//! padding: the `#[repr(C)]` layout and the shader's are the same by construction, and the
//! size is a multiple of 16 as uniform bindings want. That is checked three ways: a
//! compile-time size assertion here, the binding's `min_binding_size` (wgpu refuses a
//! pipeline whose shader struct is larger than the Rust one), and an integration test in
//! which the device echoes every field back.
//!
//! Double precision values (view centre, pixel spacing, Julia parameter) travel as
//! double-float pairs: `hi = x as f32`, `lo = (x - hi) as f32`, so hi + lo holds x to about
//! 2^-48 relative ([`split`]).

/// Flag: track the derivative for distance estimates.
pub const FLAG_DERIVATIVE: u32 = 1;
/// Flag: run the bitmap orbit trap.
pub const FLAG_TRAP: u32 = 2;
/// Flag (paint): multiply the soft distance shading over the palette colour.
pub const FLAG_DISTANCE_SHADE: u32 = 4;
/// Plane index meaning "not computed".
pub const NO_PLANE: u32 = u32::MAX;
/// `family` of the Mandelbrot set.
pub const FAMILY_MANDELBROT: u32 = 0;
/// `family` of Julia sets.
pub const FAMILY_JULIA: u32 = 1;

/// The uniform block (see the module docs for the layout contract).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Uniforms {
    /// View centre x, high part.
    pub center_x_hi: f32,
    /// View centre x, low part.
    pub center_x_lo: f32,
    /// View centre y, high part.
    pub center_y_hi: f32,
    /// View centre y, low part.
    pub center_y_lo: f32,
    /// Distance between samples, high part.
    pub spacing_hi: f32,
    /// Distance between samples, low part.
    pub spacing_lo: f32,
    /// Samples per row of the whole grid.
    pub width: u32,
    /// Rows of the whole grid.
    pub height: u32,
    /// First grid row of this dispatch.
    pub row_offset: u32,
    /// Samples in this dispatch (whole rows).
    pub count: u32,
    /// Largest iteration index examined.
    pub max_iter: u32,
    /// R^2, rounded to f32.
    pub escape_r2: f32,
    /// [`FAMILY_MANDELBROT`] or [`FAMILY_JULIA`].
    pub family: u32,
    /// `FLAG_*` bits.
    pub flags: u32,
    /// ln R.
    pub ln_escape: f32,
    /// Always 1.0: the double-float code multiplies by it to stop the shader compiler from
    /// simplifying error terms away (see `df.wgsl`).
    pub one: f32,
    /// Julia parameter re, high part.
    pub julia_x_hi: f32,
    /// Julia parameter re, low part.
    pub julia_x_lo: f32,
    /// Julia parameter im, high part.
    pub julia_y_hi: f32,
    /// Julia parameter im, low part.
    pub julia_y_lo: f32,
    /// Bitmap trap: point of the plane at the image centre, x.
    pub trap_center_x: f32,
    /// Bitmap trap: point of the plane at the image centre, y.
    pub trap_center_y: f32,
    /// Bitmap trap: width of the image (one frame) in the plane.
    pub trap_width: f32,
    /// Bitmap trap: height of the image in the plane.
    pub trap_height: f32,
    /// Bitmap trap: cosine of the rotation.
    pub trap_cos: f32,
    /// Bitmap trap: sine of the rotation.
    pub trap_sin: f32,
    /// Bitmap trap: alpha a sample must exceed.
    pub trap_threshold: f32,
    /// Bitmap trap: first texel column of the frame.
    pub trap_first_column: u32,
    /// Bitmap trap: texel columns of the frame.
    pub trap_columns: u32,
    /// Bitmap trap: texels per row of the whole image.
    pub trap_texture_width: u32,
    /// Bitmap trap: texel rows.
    pub trap_texture_height: u32,
    /// Output planes per sample (compute).
    pub planes: u32,
    /// Plane of NF, or [`NO_PLANE`].
    pub plane_nf: u32,
    /// Plane of T, or [`NO_PLANE`].
    pub plane_t: u32,
    /// Plane of DEX (DEY follows), or [`NO_PLANE`].
    pub plane_de: u32,
    /// First of the four trap colour planes (R, G, B, A), or [`NO_PLANE`].
    pub plane_trap: u32,
    /// IFS: offset added after each fold, x.
    pub ifs_offset_x: f32,
    /// IFS: offset, y.
    pub ifs_offset_y: f32,
    /// IFS: offset, z.
    pub ifs_offset_z: f32,
    /// IFS: the slice of the 3D field.
    pub ifs_z: f32,
    /// IFS: iterations.
    pub ifs_iterations: u32,
    /// IFS: strength of the exp(-strength |d|^2.3) term.
    pub ifs_strength: f32,
    /// IFS: weight decay, w_i = exp(-i / decay).
    pub ifs_decay: f32,
    /// IFS: plane units to field units.
    pub ifs_scale: f32,
    /// Paint: entries in the palette table.
    pub palette_len: u32,
    /// Paint: palette cycles per iteration.
    pub palette_density: f32,
    /// Paint: palette offset in cycles.
    pub palette_offset: f32,
    /// Paint: k of the soft distance shading.
    pub distance_k: f32,
    /// Paint: x of the image's top-left corner in target pixels.
    pub origin_x: f32,
    /// Paint: y of the image's top-left corner in target pixels.
    pub origin_y: f32,
    /// Paint: 1 when the shader must sRGB-encode (the target format does not).
    pub encode_srgb: u32,
    /// Unused (keeps the paint fields in whole 16-byte rows).
    pub reserved: u32,
    /// Paint: interior colour, linear red.
    pub interior_r: f32,
    /// Paint: interior colour, linear green.
    pub interior_g: f32,
    /// Paint: interior colour, linear blue.
    pub interior_b: f32,
    /// Paint: interior opacity.
    pub interior_a: f32,
}

/// Size of the block in bytes (56 four-byte fields).
pub const UNIFORMS_SIZE: usize = 224;
const _: () = assert!(std::mem::size_of::<Uniforms>() == UNIFORMS_SIZE && UNIFORMS_SIZE.is_multiple_of(16));

/// Splits an f64 into a double-float pair (hi, lo): hi is x rounded to f32, lo the
/// rest rounded to f32. Values beyond the f32 range give (±inf, NaN); callers check.
pub fn split(x: f64) -> (f32, f32) {
    let hi = x as f32;
    let lo = (x - hi as f64) as f32;
    (hi, lo)
}

impl Default for Uniforms {
    fn default() -> Self {
        Self {
            one: 1.0,
            plane_nf: NO_PLANE,
            plane_t: NO_PLANE,
            plane_de: NO_PLANE,
            plane_trap: NO_PLANE,
            trap_columns: 1,
            trap_texture_width: 1,
            trap_texture_height: 1,
            trap_width: 1.0,
            trap_height: 1.0,
            trap_cos: 1.0,
            ..bytemuck::Zeroable::zeroed()
        }
    }
}

impl Uniforms {
    /// Sets the view: centre, sample spacing and the grid's size.
    pub fn set_view(&mut self, center: [f64; 2], spacing: f64, width: u32, height: u32) {
        (self.center_x_hi, self.center_x_lo) = split(center[0]);
        (self.center_y_hi, self.center_y_lo) = split(center[1]);
        (self.spacing_hi, self.spacing_lo) = split(spacing);
        self.width = width;
        self.height = height;
    }

    /// Sets the iteration: family (Julia parameter or Mandelbrot), limit, escape radius.
    pub fn set_orbit(&mut self, julia: Option<[f64; 2]>, max_iter: u32, escape_radius: f64) {
        match julia {
            Some(c) => {
                self.family = FAMILY_JULIA;
                (self.julia_x_hi, self.julia_x_lo) = split(c[0]);
                (self.julia_y_hi, self.julia_y_lo) = split(c[1]);
            }
            None => self.family = FAMILY_MANDELBROT,
        }
        self.max_iter = max_iter;
        self.escape_r2 = (escape_radius * escape_radius) as f32;
        self.ln_escape = escape_radius.ln() as f32;
    }

    /// The block as bytes, for `Queue::write_buffer`.
    pub fn bytes(&self) -> &[u8] {
        bytemuck::bytes_of(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_holds_an_f64_to_48_bits() {
        for x in [std::f64::consts::PI, -0.743_644_786_013_1, 1e-12 / 3.0, 0.1] {
            let (hi, lo) = split(x);
            assert_eq!(hi, x as f32);
            let back = hi as f64 + lo as f64;
            assert!((back - x).abs() <= x.abs() * 2f64.powi(-48), "{x}: {back}");
        }
    }

    #[test]
    fn fields_are_in_16_byte_rows() {
        use std::mem::offset_of;
        assert_eq!(offset_of!(Uniforms, spacing_hi), 16);
        assert_eq!(offset_of!(Uniforms, julia_x_hi), 64);
        assert_eq!(offset_of!(Uniforms, ifs_offset_x), 144);
        assert_eq!(offset_of!(Uniforms, interior_r), 208);
        assert_eq!(Uniforms::default().one, 1.0);
    }
}
