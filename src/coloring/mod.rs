//! Colourings: pure functions from raw planes to linear-light, premultiplied RGBA.
//!
//! Each colouring reads only the planes it declares in [`Coloring::needs`], which is how a
//! scene decides what the field computes. Distances arrive in sample-raster pixels and are
//! converted to image pixels (divided by the supersampling factor) so a look does not
//! change with supersampling.

use crate::field::{INTERIOR, Needs, Planes, TrapPlane};
use crate::palette::{Palette, color};
use crate::trap::Trap;

/// Map from smooth iteration to palette position, before density and offset.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Transfer {
    /// nu.
    #[default]
    Linear,
    /// sqrt(nu).
    Sqrt,
    /// ln(1 + nu).
    Log,
}

impl Transfer {
    #[inline]
    fn apply(self, nu: f64) -> f64 {
        match self {
            Transfer::Linear => nu,
            Transfer::Sqrt => nu.max(0.0).sqrt(),
            Transfer::Log => nu.max(0.0).ln_1p(),
        }
    }
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
    /// The seeds' soft distance colouring v = clamp((k d)^0.2, 0, 1), d in image pixels;
    /// through a palette (clamped) when one is given, else as an sRGB grey level.
    SoftDistance {
        /// Scale k (per pixel).
        k: f64,
        /// Optional palette.
        palette: Option<Palette>,
    },
    /// Boundary lines: the set and everything closer than `width / 2` pixels, antialiased.
    Boundary {
        /// Line width in image pixels.
        width: f64,
        /// Line colour (linear RGBA).
        color: [f32; 4],
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
}

impl Coloring {
    /// The raw planes this colouring reads (`traps` is the scene's trap list).
    pub fn needs(&self, traps: &[Trap]) -> Needs {
        match self {
            Coloring::Smooth { .. } => Needs { nf: true, ..Needs::default() },
            Coloring::SoftDistance { .. } | Coloring::Boundary { .. } => Needs { de: true, ..Needs::default() },
            Coloring::TrapDistance { trap, .. } | Coloring::BitmapTrap { trap } => {
                Needs { traps: vec![traps[*trap].clone()], ..Needs::default() }
            }
        }
    }

    /// Colours every sample of `planes`; `aa` is the supersampling factor. Output is linear
    /// light, premultiplied by alpha.
    pub fn paint(&self, planes: &Planes, aa: u32) -> Vec<[f32; 4]> {
        let len = planes.len();
        let px = 1.0 / aa as f64;
        let distance = |k: usize| {
            let (x, y) = (planes.dex[k] as f64, planes.dey[k] as f64);
            (x * x + y * y).sqrt() * px
        };
        let premul = |c: [f32; 4]| [c[0] * c[3], c[1] * c[3], c[2] * c[3], c[3]];
        match self {
            Coloring::Smooth { palette, density, offset, transfer, interior } => (0..len)
                .map(|k| {
                    let n = planes.n[k];
                    if n == INTERIOR {
                        return premul(*interior);
                    }
                    let nu = n as f64 + planes.nf[k] as f64;
                    premul(palette.at(transfer.apply(nu) * density + offset))
                })
                .collect(),
            Coloring::SoftDistance { k, palette } => (0..len)
                .map(|i| {
                    let d = if planes.n[i] == INTERIOR { 0.0 } else { distance(i) };
                    let v = (k * d).powf(0.2).clamp(0.0, 1.0);
                    match palette {
                        Some(p) => premul(p.at(v.min(1.0 - 1e-9))),
                        None => {
                            let g = color::srgb_to_linear(v as f32);
                            [g, g, g, 1.0]
                        }
                    }
                })
                .collect(),
            Coloring::Boundary { width, color } => (0..len)
                .map(|i| {
                    let cover = if planes.n[i] == INTERIOR {
                        1.0
                    } else {
                        (width * 0.5 + 0.5 - distance(i)).clamp(0.0, 1.0) as f32
                    };
                    premul([color[0], color[1], color[2], color[3] * cover])
                })
                .collect(),
            Coloring::TrapDistance { trap, palette, density, offset } => match &planes.traps[*trap] {
                TrapPlane::Distance(d) => d.iter().map(|&d| premul(palette.at(d as f64 * density + offset))).collect(),
                TrapPlane::Color(_) => vec![[0.0; 4]; len],
            },
            Coloring::BitmapTrap { trap } => match &planes.traps[*trap] {
                TrapPlane::Color(c) => c.clone(),
                TrapPlane::Distance(_) => vec![[0.0; 4]; len],
            },
        }
    }
}
