//! The minimal IFS density field, a shader idiom (p ← abs(p)/dot(p,p) + offset, weighted accumulation), as a 2D layer
//! quantity, on the CPU ([`density`]) and on the GPU ([`compute_ifs`], `ifs.wgsl`).
//!
//! The field folds a 3D point again and again, p -> |p| / (p . p) + offset (the "kali"
//! fold), and measures how much successive squared radii differ: steps that barely change
//! |p|^2 contribute exp(-strength |mag - prev|^2.3), weighted by exp(-i / decay). The
//! density is max(0, 5 accum / total weight - 0.7): bright filaments where the fold
//! settles, dark elsewhere. A plane point (x, y) is the 3D point (x scale, y scale, z), so
//! `z` picks a slice of the 3D field and `scale` how much of it the view shows.
//!
//! Both versions run the same f32 operations in the same order, so they differ only by
//! the device's exp/pow (a few ulps) and any fused multiply-adds the shader compiler
//! forms; the fold is chaotic, so those ulps can grow along the 32 iterations where |p|
//! gets small (the tests bound the difference).

use std::ops::Range;

use super::runner::{self, Job};
use super::shaders;
use super::uniforms::Uniforms;
use super::{GpuContext, GpuError};
use crate::field::SampleGrid;

/// Smallest p . p divided by (the seed divided by zero at p = 0).
pub const MIN_MAG: f32 = 1e-20;
/// |mag - prev| is clamped into [MIN_STEP, MAX_STEP] before pow(.., 2.3): pow(0, y) and
/// infinities are undefined in WGSL, and exp(-strength MAX_STEP^2.3) is already zero.
pub const MIN_STEP: f32 = 1e-30;
/// See [`MIN_STEP`].
pub const MAX_STEP: f32 = 1e4;

/// Parameters of the IFS field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IfsParams {
    /// Added after each fold (the seed's tunable vec3(-0.5, -0.4, -1.5)).
    pub offset: [f32; 3],
    /// The slice of the 3D field shown.
    pub z: f32,
    /// Folds.
    pub iterations: u32,
    /// Sharpness of the exp(-strength |d|^2.3) term.
    pub strength: f32,
    /// Weight of fold i: exp(-i / decay).
    pub decay: f32,
    /// Plane units to field units.
    pub scale: f32,
}

impl Default for IfsParams {
    fn default() -> Self {
        Self { offset: [-0.5, -0.4, -1.5], z: 0.0, iterations: 32, strength: 7.0, decay: 7.0, scale: 1.0 }
    }
}

/// The density at plane point (x, y), in f32, with the shader's operations in its order.
pub fn density(params: &IfsParams, x: f32, y: f32) -> f32 {
    let mut p = [x * params.scale, y * params.scale, params.z];
    let (mut accum, mut prev, mut total) = (0.0f32, 0.0f32, 0.0f32);
    for i in 0..params.iterations {
        let mag = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        let m = mag.max(MIN_MAG);
        for k in 0..3 {
            p[k] = p[k].abs() / m + params.offset[k];
        }
        let w = (-(i as f32) / params.decay).exp();
        let step = (mag - prev).abs().clamp(MIN_STEP, MAX_STEP);
        accum += w * (-params.strength * step.powf(2.3)).exp();
        total += w;
        prev = mag;
    }
    if total <= 0.0 {
        return 0.0;
    }
    (5.0 * accum / total - 0.7).max(0.0)
}

/// The plane point the GPU uses for sample (i, j) of `grid`: the f64 point rounded to f32
/// (the shader computes it in double-float and keeps the high part, which agrees except,
/// rarely, at a rounding tie).
pub fn sample_point(grid: &SampleGrid, i: u32, j: u32) -> [f32; 2] {
    let p = grid.point(i, j);
    [p[0] as f32, p[1] as f32]
}

/// The density at every sample of rows `rows` of `grid`, row-major, on the GPU.
pub fn compute_ifs(
    ctx: &GpuContext,
    params: &IfsParams,
    grid: &SampleGrid,
    rows: Range<u32>,
) -> Result<Vec<f32>, GpuError> {
    if grid.width > super::field::MAX_GRID_SIDE || grid.height > super::field::MAX_GRID_SIDE {
        return Err(GpuError::Unsupported(format!("a {}x{} grid is too large for the GPU", grid.width, grid.height)));
    }
    let mut u = Uniforms::default();
    u.set_view(grid.center, grid.spacing(), grid.width, grid.height);
    u.ifs_offset_x = params.offset[0];
    u.ifs_offset_y = params.offset[1];
    u.ifs_offset_z = params.offset[2];
    u.ifs_z = params.z;
    u.ifs_iterations = params.iterations;
    u.ifs_strength = params.strength;
    u.ifs_decay = params.decay;
    u.ifs_scale = params.scale;
    let pipeline = ctx.compute_pipeline(shaders::ifs_module, shaders::IFS_ENTRY)?;
    let width = grid.width as usize;
    let mut out = vec![0.0f32; width * rows.len()];
    let job = Job { pipeline: &pipeline, uniforms: u, texels: &[[0.0; 4]], width: grid.width, rows, words: 1 };
    runner::run(ctx, &job, |first, n, words| {
        let at = first as usize * width;
        for (d, w) in out[at..at + n as usize * width].iter_mut().zip(words) {
            *d = f32::from_bits(*w);
        }
    })?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn density_is_finite_and_in_range_everywhere_including_the_origin() {
        let p = IfsParams::default();
        for (x, y) in [(0.0, 0.0), (0.3, -0.2), (1e-30, 0.0), (5.0, 5.0), (-1.0, 0.7)] {
            let d = density(&p, x, y);
            assert!(d.is_finite() && (0.0..=4.3).contains(&d), "({x}, {y}): {d}");
        }
        let zero = IfsParams { z: 0.0, offset: [0.0; 3], ..p };
        assert!(density(&zero, 0.0, 0.0).is_finite());
    }
}
