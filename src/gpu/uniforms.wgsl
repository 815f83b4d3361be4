// The uniform block every pipeline reads (mirror of `Uniforms` in uniforms.rs: same
// fields, same order, all 4-byte scalars, so the WGSL layout equals the #[repr(C)] one),
// and the sample raster it describes.

struct Params {
    center_x_hi: f32, center_x_lo: f32, center_y_hi: f32, center_y_lo: f32,
    spacing_hi: f32, spacing_lo: f32, width: u32, height: u32,
    row_offset: u32, count: u32, max_iter: u32, escape_r2: f32,
    family: u32, flags: u32, ln_escape: f32, one: f32,
    julia_x_hi: f32, julia_x_lo: f32, julia_y_hi: f32, julia_y_lo: f32,
    trap_center_x: f32, trap_center_y: f32, trap_width: f32, trap_height: f32,
    trap_cos: f32, trap_sin: f32, trap_threshold: f32, trap_first_column: u32,
    trap_columns: u32, trap_texture_width: u32, trap_texture_height: u32, planes: u32,
    plane_nf: u32, plane_t: u32, plane_de: u32, plane_trap: u32,
    ifs_offset_x: f32, ifs_offset_y: f32, ifs_offset_z: f32, ifs_z: f32,
    ifs_iterations: u32, ifs_strength: f32, ifs_decay: f32, ifs_scale: f32,
    palette_len: u32, palette_density: f32, palette_offset: f32, distance_k: f32,
    origin_x: f32, origin_y: f32, encode_srgb: u32, reserved: u32,
    interior_r: f32, interior_g: f32, interior_b: f32, interior_a: f32,
}

@group(0) @binding(0) var<uniform> P: Params;

const FAMILY_JULIA: u32 = 1u;
const FLAG_DERIVATIVE: u32 = 1u;
const FLAG_TRAP: u32 = 2u;
const FLAG_DISTANCE_SHADE: u32 = 4u;

// The point of sample (i, j) as (x_hi, x_lo, y_hi, y_lo): the docs/design.md convention
// x = cx + spacing (i + 0.5 - W/2), y = cy - spacing (j + 0.5 - H/2). The offsets are
// exact halves in f32 (W, H < 2^22); the product and the sum are double-float.
fn sample_point(i: u32, j: u32) -> vec4<f32> {
    let ox = (f32(i) + 0.5) - 0.5 * f32(P.width);
    let oy = (f32(j) + 0.5) - 0.5 * f32(P.height);
    let s = vec2<f32>(P.spacing_hi, P.spacing_lo);
    let x = df_add(vec2<f32>(P.center_x_hi, P.center_x_lo), df_mul_f(s, ox));
    let y = df_add(vec2<f32>(P.center_y_hi, P.center_y_lo), df_mul_f(s, -oy));
    return vec4<f32>(x, y);
}
