//! Recolouring: raw planes already computed (read from an EXR, or held by the viewer) to
//! output pixels, without touching the fractal. Strips are coloured in parallel; layers that
//! need the whole image (histograms) get their [`Context`] from every strip first, exactly
//! as a render builds it, so a recolour of a render's raw data reproduces its pixels.

use rayon::prelude::*;

use crate::coloring::Context;
use crate::compose::{self, Stack, TrapMismatch};
use crate::field::{Planes, TrapPlane};
use crate::palette::color::linear_to_srgb8;
use crate::trap::TrapKind;

/// Colours every strip (sample rows a multiple of `aa`) and downsamples it: linear RGB
/// output pixels per strip, in order. Refuses strips whose trap planes do not serve the
/// layers ([`Stack::check_traps`]).
pub fn recolor(stack: &Stack, strips: &[Planes], aa: u32) -> Result<Vec<Vec<[f32; 3]>>, TrapMismatch> {
    check(stack, strips)?;
    let ctx = context(stack, strips);
    Ok(strips.par_iter().map(|planes| strip_linear(stack, planes, aa, &ctx)).collect())
}

/// Like [`recolor`], for 8-bit output: sRGB bytes per strip, identical to encoding
/// [`recolor`]'s pixels, and faster at one sample per pixel (no round trip through linear
/// light where the compositor already holds sRGB bytes).
pub fn recolor_rgb8(stack: &Stack, strips: &[Planes], aa: u32) -> Result<Vec<Vec<u8>>, TrapMismatch> {
    check(stack, strips)?;
    let ctx = context(stack, strips);
    Ok(strips.par_iter().map(|planes| strip_rgb8(stack, planes, aa, &ctx)).collect())
}

/// [`Stack::check_traps`] on every strip's trap planes.
fn check(stack: &Stack, strips: &[Planes]) -> Result<(), TrapMismatch> {
    for planes in strips {
        let kinds: Vec<TrapKind> = planes.traps.iter().map(TrapPlane::kind).collect();
        stack.check_traps(&kinds)?;
    }
    Ok(())
}

/// The image-wide data the layers need ([`Stack::context`]), built once from every strip;
/// empty when no layer needs any.
pub fn context(stack: &Stack, strips: &[Planes]) -> Context {
    if stack.is_global() { stack.context(strips.iter()) } else { Context::default() }
}

/// One strip of [`recolor`]: its output pixels in linear RGB.
pub fn strip_linear(stack: &Stack, planes: &Planes, aa: u32, ctx: &Context) -> Vec<[f32; 3]> {
    compose::downsample(stack.composite(planes, aa, ctx), planes.width, aa as usize)
}

/// One strip of [`recolor_rgb8`]: its output pixels as sRGB bytes.
pub fn strip_rgb8(stack: &Stack, planes: &Planes, aa: u32, ctx: &Context) -> Vec<u8> {
    if aa == 1 {
        return stack.composite_rgb8(planes, ctx);
    }
    strip_linear(stack, planes, aa, ctx).iter().flat_map(|p| p.map(linear_to_srgb8)).collect()
}
