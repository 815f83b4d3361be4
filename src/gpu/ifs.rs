//! The minimal IFS density field (p ← abs(p)/dot(p,p) + offset, weighted accumulation) on
//! the GPU ([`compute_ifs`], `ifs.wgsl`); its parameters and CPU version ([`density`]) live
//! in `trap::ifs` and are re-exported here.
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

pub use crate::trap::ifs::{IfsParams, MAX_STEP, MIN_MAG, MIN_STEP, density};

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
    let pipeline = ctx.compute_pipeline("ifs", shaders::ifs_module, shaders::IFS_ENTRY)?;
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
