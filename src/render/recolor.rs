//! Recolouring: raw planes already computed (read from an EXR, or held by the viewer) to
//! output pixels, without touching the fractal. Strips are coloured in parallel; layers that
//! need the whole image (histograms) get their [`Context`] from every strip first, exactly
//! as a render builds it, so a recolour of a render's raw data reproduces its pixels.

use rayon::prelude::*;

use crate::coloring::Context;
use crate::compose::{self, Stack};
use crate::field::Planes;

/// Colours every strip (sample rows a multiple of `aa`) and downsamples it: linear RGB
/// output pixels per strip, in order.
pub fn recolor(stack: &Stack, strips: &[Planes], aa: u32) -> Vec<Vec<[f32; 3]>> {
    let ctx = if stack.is_global() { stack.context(strips.iter()) } else { Context::default() };
    strips
        .par_iter()
        .map(|planes| {
            let samples = stack.composite(planes, aa, &ctx);
            compose::downsample(samples, planes.width, aa as usize)
        })
        .collect()
}
