//! Raw planes of the escape-time field on the GPU, shaped exactly like the CPU's.
//!
//! [`compute_planes`] is the GPU counterpart of [`crate::field::compute_strip`]: the same
//! [`FieldParams`], the same [`Planes`] back (N always; NF, T, DEX/DEY and trap planes as
//! `needs` asks), so colouring and file output work unchanged. What the GPU leaves out:
//! geometric traps, the stripe average and several traps at once (refused with
//! [`GpuError::Unsupported`]), the periodicity check (interior samples outside the main
//! cardioid and bulb iterate to the limit), and views the chosen precision cannot resolve
//! (the caller checks [`Precision::exhausted`]; the scene's engine choice does).
//! The deep engine's data (`params.deep`) is ignored: the GPU iterates directly.

use std::ops::Range;

#[cfg(feature = "gpu")]
use super::MAX_ESCAPE_RADIUS;
#[cfg(feature = "gpu")]
use super::runner::{self, Job};
#[cfg(feature = "gpu")]
use super::shaders;
use super::uniforms::{self, Uniforms};
use super::{GpuContext, GpuError, Precision};
#[cfg(feature = "gpu")]
use crate::field::TrapPlane;
use crate::field::{FieldParams, Planes};
use crate::formula::Family;
use crate::trap::{BitmapTrap, Trap};

/// Largest grid side the shaders address exactly (sample offsets are f32 halves).
pub const MAX_GRID_SIDE: u32 = 1 << 22;

/// The bitmap trap of a field's needs, when it is the only trap; an error naming the
/// problem for anything the GPU does not implement.
pub fn supported_trap(traps: &[Trap]) -> Result<Option<&BitmapTrap>, GpuError> {
    match traps {
        [] => Ok(None),
        [Trap::Bitmap(b)] => Ok(Some(b)),
        [Trap::Geometric(_)] => Err(GpuError::Unsupported(
            "geometric orbit traps (point, line, cross, circle) run only on the CPU engines".into(),
        )),
        [Trap::Stripe(_)] => Err(GpuError::Unsupported("the stripe average runs only on the CPU engines".into())),
        [Trap::Ifs(_)] => Err(GpuError::Unsupported(
            "the IFS layer is computed with the CPU engines (its shader runs headless and in tests)".into(),
        )),
        _ => Err(GpuError::Unsupported(format!(
            "the scene uses {} orbit traps; the GPU runs at most one, a bitmap trap",
            traps.len()
        ))),
    }
}

/// Checks what the uniforms cannot carry: grid size, escape radius, coordinates in the
/// f32 range.
#[cfg(feature = "gpu")]
fn check(params: &FieldParams) -> Result<(), GpuError> {
    let g = &params.grid;
    if !g.transform.is_identity() {
        return Err(GpuError::Unsupported("the GPU paths do not rotate or stretch the view".into()));
    }
    if g.width > MAX_GRID_SIDE || g.height > MAX_GRID_SIDE {
        return Err(GpuError::Unsupported(format!(
            "a {}x{} sample grid is larger than the GPU's {MAX_GRID_SIDE} samples per side",
            g.width, g.height
        )));
    }
    let r = params.orbit.escape_radius;
    if !(r > 1.0 && r <= MAX_ESCAPE_RADIUS) {
        return Err(GpuError::Unsupported(format!(
            "escape radius {r:e} is above the GPU's limit of 2^60 (|z|^2 must stay finite in f32)"
        )));
    }
    let spacing = g.spacing();
    let finite = |x: f64| x.is_finite() && x.abs() < 1e30;
    let julia_ok = match params.orbit.family {
        Family::Mandelbrot => true,
        Family::Julia { c } => finite(c[0]) && finite(c[1]),
    };
    if !(finite(g.center[0]) && finite(g.center[1]) && julia_ok && spacing > 1e-30 && spacing < 1e30) {
        return Err(GpuError::Unsupported(format!(
            "the view (centre {:e}, {:e}, spacing {spacing:e}) is outside the range of f32 numbers",
            g.center[0], g.center[1]
        )));
    }
    Ok(())
}

/// The uniform block of a field computation (row offset and count are set per chunk).
pub fn field_uniforms(params: &FieldParams, trap: Option<&BitmapTrap>) -> Uniforms {
    let g = &params.grid;
    let mut u = Uniforms::default();
    u.set_view(g.center, g.spacing(), g.width, g.height);
    let julia = match params.orbit.family {
        Family::Mandelbrot => None,
        Family::Julia { c } => Some(c),
    };
    u.set_orbit(julia, params.orbit.max_iter, params.orbit.escape_radius);
    let needs = &params.needs;
    if params.orbit.derivative || needs.de {
        u.flags |= uniforms::FLAG_DERIVATIVE;
    }
    let mut planes = 1;
    let mut next = |on: bool, n: u32| {
        if on {
            planes += n;
            planes - n
        } else {
            uniforms::NO_PLANE
        }
    };
    u.plane_nf = next(needs.nf, 1);
    u.plane_t = next(needs.t, 1);
    u.plane_de = next(needs.de, 2);
    u.plane_trap = next(trap.is_some(), 4);
    u.planes = planes;
    if let Some(t) = trap {
        u.flags |= uniforms::FLAG_TRAP;
        let (first, cols) = match t.frame {
            Some(f) => ((f.index % f.count) * f.width, f.width),
            None => (0, t.bitmap.width as u32),
        };
        u.trap_center_x = t.center[0] as f32;
        u.trap_center_y = t.center[1] as f32;
        u.trap_width = t.size as f32;
        u.trap_height = (t.size * t.bitmap.height as f64 / cols as f64) as f32;
        u.trap_cos = t.rotation[0] as f32;
        u.trap_sin = t.rotation[1] as f32;
        u.trap_threshold = t.threshold;
        u.trap_first_column = first;
        u.trap_columns = cols;
        u.trap_texture_width = t.bitmap.width as u32;
        u.trap_texture_height = t.bitmap.height as u32;
    }
    u
}

/// Computes sample rows `rows` of `params.grid` on the GPU in `precision`, returning planes
/// shaped as [`crate::field::compute_strip`]'s (`Planes::new(width, rows, &params.needs)`).
#[cfg(feature = "gpu")]
pub fn compute_planes(
    ctx: &GpuContext,
    params: &FieldParams,
    precision: Precision,
    rows: Range<u32>,
) -> Result<Planes, GpuError> {
    let trap = supported_trap(&params.needs.traps)?;
    check(params)?;
    let width = params.grid.width;
    let mut planes = Planes::new(width as usize, rows.len(), &params.needs);
    if planes.is_empty() {
        return Ok(planes);
    }
    let uniforms = field_uniforms(params, trap);
    let name = match precision {
        Precision::F32 => "escape f32",
        Precision::DoubleFloat => "escape double-float",
    };
    let pipeline = ctx.compute_pipeline(name, || shaders::escape_module(precision), shaders::ESCAPE_ENTRY)?;
    let dummy = [[0.0f32; 4]];
    let texels = match trap {
        Some(t) if !t.bitmap.texels.is_empty() => t.bitmap.texels.as_slice(),
        _ => &dummy,
    };
    let job = Job { pipeline: &pipeline, uniforms, texels, width, rows, words: uniforms.planes };
    runner::run(ctx, &job, |first, n, words| {
        let at = first as usize * width as usize;
        let count = n as usize * width as usize;
        let plane = |p: u32| &words[p as usize * count..(p as usize + 1) * count];
        planes.n[at..at + count].copy_from_slice(plane(0));
        let floats = |dst: &mut [f32], p: u32| {
            for (d, w) in dst.iter_mut().zip(plane(p)) {
                *d = f32::from_bits(*w);
            }
        };
        if uniforms.plane_nf != uniforms::NO_PLANE {
            floats(&mut planes.nf[at..at + count], uniforms.plane_nf);
        }
        if uniforms.plane_t != uniforms::NO_PLANE {
            floats(&mut planes.t[at..at + count], uniforms.plane_t);
        }
        if uniforms.plane_de != uniforms::NO_PLANE {
            floats(&mut planes.dex[at..at + count], uniforms.plane_de);
            floats(&mut planes.dey[at..at + count], uniforms.plane_de + 1);
        }
        if uniforms.plane_trap != uniforms::NO_PLANE
            && let Some(TrapPlane::Color(colors)) = planes.traps.first_mut()
        {
            let p = uniforms.plane_trap;
            let (r, g, b, a) = (plane(p), plane(p + 1), plane(p + 2), plane(p + 3));
            for (k, c) in colors[at..at + count].iter_mut().enumerate() {
                *c = [r[k], g[k], b[k], a[k]].map(f32::from_bits);
            }
        }
    })?;
    Ok(planes)
}

/// Without the `gpu` feature no [`GpuContext`] exists, so this is never called.
#[cfg(not(feature = "gpu"))]
pub fn compute_planes(
    ctx: &GpuContext,
    _params: &FieldParams,
    _precision: Precision,
    _rows: Range<u32>,
) -> Result<Planes, GpuError> {
    match *ctx {}
}

/// Iterations the orbit loops performed on sample rows `rows`, estimated from N: an
/// escaped sample counts N - N_0 (N_0 = 1 for Mandelbrot, 0 for Julia), an interior one
/// max_iter - N_0 (the GPU has no periodicity check, so interior samples really run to the
/// limit), except Mandelbrot samples in the main cardioid or period-2 bulb when no trap
/// runs, which the shader skips (zero).
pub fn estimated_iterations(params: &FieldParams, rows: Range<u32>, planes: &Planes) -> u64 {
    let (start, skips) = match params.orbit.family {
        Family::Mandelbrot => (1, params.needs.traps.is_empty()),
        Family::Julia { .. } => (0, false),
    };
    let max = params.orbit.max_iter;
    let width = planes.width.max(1);
    planes
        .n
        .iter()
        .enumerate()
        .map(|(k, &n)| {
            if n != crate::formula::end::INTERIOR {
                return n.saturating_sub(start) as u64;
            }
            let j = rows.start + (k / width) as u32;
            if skips && crate::formula::in_main_components(params.grid.point((k % width) as u32, j)) {
                return 0;
            }
            max.saturating_sub(start) as u64
        })
        .sum()
}
