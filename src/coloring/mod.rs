//! Colourings: pure functions from raw planes to linear-light, premultiplied RGBA.
//!
//! Each colouring reads only the planes it declares in [`Coloring::needs`], which is how a
//! scene decides what the field computes: smooth iteration needs NF, distance and slope
//! need the DE vector, phase colourings need T, and the orbit statistics (traps, stripe
//! average) are computed only when a layer names them. Distances arrive in sample-raster
//! pixels and are converted to image pixels (divided by the supersampling factor) so a
//! look does not change with supersampling.
//!
//! Colourings that need the whole image (histogram equalisation) read a [`Context`] built
//! once from every strip; the others are local, sample by sample.

mod histogram;
pub mod mask;
pub mod shading;
mod transfer;

pub use histogram::Histogram;
pub use mask::{MASK_FEATHER, Mask, MaskQuantity};
pub use shading::{DistanceStyle, Light};
pub use transfer::Transfer;

use crate::field::{Needs, Planes, TrapPlane};
use crate::formula::end::INTERIOR;
use crate::palette::{Palette, color};
use crate::simd_level::SimdLevel;
use crate::trap::TrapKind;

/// Image-wide data some colourings need, built once from every strip of the image, and how
/// the colouring runs.
#[derive(Debug, Clone, Default)]
pub struct Context {
    /// Distribution of escape counts (for histogram colouring).
    pub histogram: Option<Histogram>,
    /// The instruction set the arithmetic passes (transfers, distance styles, palette
    /// coordinates) run with: the same bits at every level (default: the widest this CPU
    /// has).
    pub simd: SimdLevel,
}

/// One way of turning raw data into colour.
#[derive(Debug, Clone, PartialEq)]
pub enum Coloring {
    /// Smooth iteration nu = N + NF through a palette: position = transfer(nu) * density + offset.
    Smooth {
        /// The palette.
        palette: Palette,
        /// Palette cycles per unit of transfer(nu).
        density: f64,
        /// Palette offset in cycles.
        offset: f64,
        /// The transfer function.
        transfer: Transfer,
        /// Colour of interior samples (linear RGBA).
        interior: [f32; 4],
    },
    /// Histogram-equalised iteration: position = fraction of the image's exterior samples
    /// that escaped earlier (continuous in NF), times `cycles`, plus offset.
    Histogram {
        /// The palette.
        palette: Palette,
        /// Palette cycles over the whole distribution.
        cycles: f64,
        /// Palette offset in cycles.
        offset: f64,
        /// Colour of interior samples (linear RGBA).
        interior: [f32; 4],
    },
    /// Distance estimate through a palette (clamped at the ends for the soft style), or as
    /// an sRGB grey level when no palette is given (the look of Inigo Quilez's Mandelbrot distance shader).
    Distance {
        /// Distance to value.
        style: DistanceStyle,
        /// Optional palette.
        palette: Option<Palette>,
        /// Palette offset in cycles.
        offset: f64,
    },
    /// Boundary lines: the set and everything closer than `width / 2` pixels, antialiased.
    Boundary {
        /// Line width in image pixels.
        width: f64,
        /// Line colour (linear RGBA).
        color: [f32; 4],
    },
    /// Slope lighting from the DE vector: a grey level (1 = fully lit), meant to be blended
    /// (multiply, overlay, soft light) over a colour layer. Interior samples are transparent.
    Slope {
        /// The light.
        light: Light,
    },
    /// Binary decomposition: one colour where Im z_n >= 0 (T < 1/2), the other elsewhere.
    Binary {
        /// Colours for the upper and lower half-planes (linear RGBA).
        colors: [[f32; 4]; 2],
    },
    /// Final angle through a palette: position = T * density + offset.
    Angle {
        /// The palette.
        palette: Palette,
        /// Palette cycles per turn (whole numbers are seamless).
        density: f64,
        /// Palette offset in cycles.
        offset: f64,
    },
    /// Stripe average through a palette: position = stripe * density + offset.
    Stripe {
        /// Index of the stripe statistic in the field's trap list.
        trap: usize,
        /// The palette.
        palette: Palette,
        /// Palette cycles per unit of stripe value.
        density: f64,
        /// Palette offset in cycles.
        offset: f64,
    },
    /// Distance of the orbit to a geometric trap: palette at d * density + offset.
    TrapDistance {
        /// Index of the trap in the field's trap list.
        trap: usize,
        /// The palette.
        palette: Palette,
        /// Palette cycles per unit of distance in the plane.
        density: f64,
        /// Offset in cycles.
        offset: f64,
    },
    /// The colour of the first bitmap-trap hit; transparent where nothing hit.
    BitmapTrap {
        /// Index of the trap in the field's trap list.
        trap: usize,
    },
    /// The minimal IFS density field (a 2D layer independent of the fractal): through a
    /// palette at `v * density + offset`, or as white with opacity v when there is none.
    Ifs {
        /// Index of the field's plane in the trap list.
        trap: usize,
        /// Optional palette.
        palette: Option<Palette>,
        /// Palette cycles per unit of density.
        density: f64,
        /// Palette offset in cycles.
        offset: f64,
    },
    /// Interior colouring: only samples inside the set, by a solid colour or by the
    /// orbit's closest approach to a geometric trap through a palette.
    Interior {
        /// How the interior is filled.
        fill: InteriorFill,
    },
}

/// How an interior layer fills the set.
#[derive(Debug, Clone, PartialEq)]
pub enum InteriorFill {
    /// One colour (linear RGBA).
    Solid([f32; 4]),
    /// Palette at trap distance * density + offset.
    Trap {
        /// Index of the trap in the field's trap list.
        trap: usize,
        /// The palette.
        palette: Palette,
        /// Palette cycles per unit of distance in the plane.
        density: f64,
        /// Offset in cycles.
        offset: f64,
    },
}

impl Coloring {
    /// The raw planes this colouring reads (trap planes come from the scene's trap list).
    pub fn needs(&self) -> Needs {
        match self {
            Coloring::Smooth { .. } | Coloring::Histogram { .. } => Needs { nf: true, ..Needs::default() },
            Coloring::Distance { .. } | Coloring::Boundary { .. } | Coloring::Slope { .. } => {
                Needs { de: true, ..Needs::default() }
            }
            Coloring::Binary { .. } | Coloring::Angle { .. } => Needs { t: true, ..Needs::default() },
            Coloring::Stripe { .. }
            | Coloring::TrapDistance { .. }
            | Coloring::BitmapTrap { .. }
            | Coloring::Ifs { .. }
            | Coloring::Interior { .. } => Needs::default(),
        }
    }

    /// The trap plane the colouring reads, if any: the trap's index and what its plane
    /// must hold (a plane of another kind would paint nothing; [`crate::compose::Stack::check_traps`]
    /// refuses it first).
    pub fn trap_plane(&self) -> Option<(usize, TrapKind)> {
        match self {
            Coloring::Stripe { trap, .. } => Some((*trap, TrapKind::Stripe)),
            Coloring::TrapDistance { trap, .. } | Coloring::Interior { fill: InteriorFill::Trap { trap, .. } } => {
                Some((*trap, TrapKind::Distance))
            }
            Coloring::BitmapTrap { trap } => Some((*trap, TrapKind::Color)),
            Coloring::Ifs { trap, .. } => Some((*trap, TrapKind::Density)),
            _ => None,
        }
    }

    /// The palette the colouring uses, if it has one.
    pub fn palette(&self) -> Option<&Palette> {
        match self {
            Coloring::Smooth { palette, .. }
            | Coloring::Histogram { palette, .. }
            | Coloring::Angle { palette, .. }
            | Coloring::Stripe { palette, .. }
            | Coloring::TrapDistance { palette, .. }
            | Coloring::Interior { fill: InteriorFill::Trap { palette, .. } } => Some(palette),
            Coloring::Distance { palette, .. } | Coloring::Ifs { palette, .. } => palette.as_ref(),
            _ => None,
        }
    }

    /// The palette the colouring uses, for replacing (the viewer's palette editor).
    pub fn palette_mut(&mut self) -> Option<&mut Palette> {
        match self {
            Coloring::Smooth { palette, .. }
            | Coloring::Histogram { palette, .. }
            | Coloring::Angle { palette, .. }
            | Coloring::Stripe { palette, .. }
            | Coloring::TrapDistance { palette, .. }
            | Coloring::Interior { fill: InteriorFill::Trap { palette, .. } } => Some(palette),
            Coloring::Distance { palette, .. } | Coloring::Ifs { palette, .. } => palette.as_mut(),
            _ => None,
        }
    }

    /// True when the colouring reads image-wide data from a [`Context`].
    pub fn is_global(&self) -> bool {
        matches!(self, Coloring::Histogram { .. })
    }

    /// Colours every sample of `planes`; `aa` is the supersampling factor and `mask` scales
    /// each sample's opacity. Output is linear light, premultiplied by alpha.
    pub fn paint(&self, planes: &Planes, aa: u32, ctx: &Context, mask: Option<&Mask>) -> Vec<[f32; 4]> {
        let mut out = vec![[0.0f32; 4]; planes.len()];
        self.paint_runs(planes, aa, ctx, mask, &mut |start, run| out[start..start + run.len()].copy_from_slice(run));
        out
    }

    /// Colours every sample of `planes`, handing them to `sink` in order, in runs of up to
    /// [`RUN`] samples (the index of the run's first sample, its premultiplied linear RGBA
    /// colours): no image-sized buffer, as the compositor writes its output directly, and
    /// one call per run, whose loop the sink's own code is compiled into (a call per sample
    /// was not inlined where many colourings share one sink).
    pub fn paint_runs(
        &self,
        planes: &Planes,
        aa: u32,
        ctx: &Context,
        mask: Option<&Mask>,
        sink: &mut impl FnMut(usize, &[[f32; 4]]),
    ) {
        let px = 1.0 / aa as f64;
        match mask {
            None => self.paint_unmasked(planes, px, ctx, sink),
            Some(m) => self.paint_unmasked(planes, px, ctx, &mut |start, run: &[[f32; 4]]| {
                let mut masked = [[0.0f32; 4]; RUN];
                for ((out, c), k) in masked.iter_mut().zip(run).zip(start..) {
                    let w = m.at(planes, k, px);
                    *out = c.map(|v| v * w);
                }
                sink(start, &masked[..run.len()])
            }),
        }
    }

    fn paint_unmasked(&self, planes: &Planes, px: f64, ctx: &Context, sink: &mut impl FnMut(usize, &[[f32; 4]])) {
        let len = planes.len();
        // The planes cut to `len` once: the passes index them with k < len, and the compiler
        // then drops the bounds check per sample (an eighth of a 4K recolour's instructions).
        // A plane the colouring needs and the planes lack still panics, here instead.
        fn cut(p: &[f32], len: usize) -> &[f32] {
            if p.is_empty() { p } else { &p[..len] }
        }
        let (n, nf, dex, dey) = (&planes.n[..len], cut(&planes.nf, len), cut(&planes.dex, len), cut(&planes.dey, len));
        let inside = |k: usize| n[k] == INTERIOR;
        let distance = |k: usize| {
            let (x, y) = (dex[k] as f64, dey[k] as f64);
            (x * x + y * y).sqrt() * px
        };
        // Statically dispatched per colouring: the closures inline into the passes. `each!`
        // colours a sample in one go; `staged!` first takes the number a palette is read at
        // (a transfer, a distance style, a histogram position) for a whole run.
        macro_rules! staged {
            (|$k:pat_param| $value:expr, $then:expr, |$k2:pat_param, $v:pat_param| $colour:expr) => {
                in_runs(len, |$k: usize| -> f64 { $value }, $then, |$k2: usize, $v: f64| -> [f32; 4] { $colour }, sink)
            };
            (|$k:pat_param| $value:expr, |$k2:pat_param, $v:pat_param| $colour:expr) => {
                staged!(|$k| $value, |_: &mut [f64]| (), |$k2, $v| $colour)
            };
        }
        macro_rules! each {
            (|$k:pat_param| $body:expr) => {
                in_runs(len, |_| 0.0, |_: &mut [f64]| (), |$k: usize, _| -> [f32; 4] { $body }, sink)
            };
        }
        match self {
            Coloring::Smooth { palette, density, offset, transfer, interior } => {
                staged!(
                    |k| n[k] as f64 + nf[k] as f64,
                    |v: &mut [f64]| {
                        transfer.apply_all(ctx.simd, v);
                        v.iter_mut().for_each(|t| *t = *t * density + offset);
                        palette.coordinates(ctx.simd, v);
                    },
                    |k, f| if inside(k) { premul(*interior) } else { premul(palette.at_coordinate(f)) }
                )
            }
            Coloring::Histogram { palette, cycles, offset, interior } => {
                let fallback;
                let hist = match &ctx.histogram {
                    Some(h) => h,
                    None => {
                        fallback = Histogram::build([planes]);
                        &fallback
                    }
                };
                staged!(
                    |k| hist.position(n[k], nf[k]) * cycles + offset,
                    |v: &mut [f64]| palette.coordinates(ctx.simd, v),
                    |k, f| if inside(k) { premul(*interior) } else { premul(palette.at_coordinate(f)) }
                )
            }
            Coloring::Distance { style, palette, offset } => {
                staged!(
                    |k| if inside(k) { 0.0 } else { distance(k) },
                    |v: &mut [f64]| style.values(ctx.simd, v),
                    |_, v| match palette {
                        // The soft style spans [0, 1]: keep 1 off the wrap-around point.
                        Some(p) if matches!(style, DistanceStyle::Soft { .. }) =>
                            premul(p.at(v.min(1.0 - 1e-9) + offset)),
                        Some(p) => premul(p.at(v + offset)),
                        None => {
                            let g = color::srgb_to_linear_lut(v as f32);
                            [g, g, g, 1.0]
                        }
                    }
                )
            }
            Coloring::Boundary { width, color } => each!(|k| {
                let cover = if inside(k) { 1.0 } else { shading::boundary_cover(distance(k), *width) };
                premul([color[0], color[1], color[2], color[3] * cover])
            }),
            Coloring::Slope { light } => each!(|k| {
                if inside(k) {
                    return [0.0; 4];
                }
                let g = light.shade(dex[k], dey[k]);
                [g, g, g, 1.0]
            }),
            Coloring::Binary { colors } => each!(|k| {
                if inside(k) {
                    return [0.0; 4];
                }
                premul(colors[usize::from(planes.t[k] >= 0.5)])
            }),
            Coloring::Angle { palette, density, offset } => {
                staged!(
                    |k| planes.t[k] as f64 * density + offset,
                    |v: &mut [f64]| palette.coordinates(ctx.simd, v),
                    |k, f| if inside(k) { [0.0; 4] } else { premul(palette.at_coordinate(f)) }
                )
            }
            Coloring::Stripe { trap, palette, density, offset } => match &planes.traps[*trap] {
                TrapPlane::Stripe { value, .. } => {
                    staged!(
                        |k| value[k] as f64 * density + offset,
                        |v: &mut [f64]| palette.coordinates(ctx.simd, v),
                        |k, f| if inside(k) { [0.0; 4] } else { premul(palette.at_coordinate(f)) }
                    )
                }
                _ => each!(|_| [0.0; 4]),
            },
            Coloring::TrapDistance { trap, palette, density, offset } => match &planes.traps[*trap] {
                TrapPlane::Distance(d) => staged!(
                    |k| d[k] as f64 * density + offset,
                    |v: &mut [f64]| palette.coordinates(ctx.simd, v),
                    |_, f| premul(palette.at_coordinate(f))
                ),
                _ => each!(|_| [0.0; 4]),
            },
            Coloring::BitmapTrap { trap } => match &planes.traps[*trap] {
                TrapPlane::Color(c) => each!(|k| c[k]),
                _ => each!(|_| [0.0; 4]),
            },
            Coloring::Ifs { trap, palette, density, offset } => match &planes.traps[*trap] {
                TrapPlane::Density(d) => each!(|k| match palette {
                    Some(p) => premul(p.at(d[k] as f64 * density + offset)),
                    None => {
                        let a = d[k].clamp(0.0, 1.0);
                        [a, a, a, a]
                    }
                }),
                _ => each!(|_| [0.0; 4]),
            },
            Coloring::Interior { fill } => match fill {
                InteriorFill::Solid(c) => each!(|k| if inside(k) { premul(*c) } else { [0.0; 4] }),
                InteriorFill::Trap { trap, palette, density, offset } => match &planes.traps[*trap] {
                    TrapPlane::Distance(d) => each!(|k| {
                        if !inside(k) {
                            return [0.0; 4];
                        }
                        premul(palette.at(d[k] as f64 * density + offset))
                    }),
                    _ => each!(|_| [0.0; 4]),
                },
            },
        }
    }
}

/// Samples per run in which colourings paint (the most [`Coloring::paint_runs`] hands over
/// at once).
pub const RUN: usize = 64;

/// Paints samples 0..len in runs of [`RUN`], in passes over each: `value` of every sample
/// of the run, `then` over those values as a whole, `colour` from each, then `sink` with
/// the run's colours. Each pass is a short loop of independent iterations, so the core
/// overlaps many samples' palette lookups, and the arithmetic passes (a transfer, a
/// distance style, palette coordinates: branch-free loops over the run) vectorise; one pass per sample chains
/// everything and waits on each (two-layer 4K recolour, one thread: colour and write
/// 0.88–0.95 s in one pass, 0.63–0.71 s with the transfer and the sink in passes of their
/// own). The bytes do not change.
#[inline(always)]
fn in_runs(
    len: usize,
    value: impl Fn(usize) -> f64,
    then: impl Fn(&mut [f64]),
    colour: impl Fn(usize, f64) -> [f32; 4],
    sink: &mut impl FnMut(usize, &[[f32; 4]]),
) {
    let (mut v, mut c) = ([0.0f64; RUN], [[0.0f32; 4]; RUN]);
    for start in (0..len).step_by(RUN) {
        let run = start..len.min(start + RUN);
        for (vj, k) in v.iter_mut().zip(run.clone()) {
            *vj = value(k);
        }
        then(&mut v[..run.len()]);
        for ((cj, &vj), k) in c.iter_mut().zip(&v).zip(run.clone()) {
            *cj = colour(k, vj);
        }
        sink(start, &c[..run.len()]);
    }
}

/// Premultiplies a linear RGBA colour by its alpha.
#[inline]
pub fn premul(c: [f32; 4]) -> [f32; 4] {
    [c[0] * c[3], c[1] * c[3], c[2] * c[3], c[3]]
}
