//! Validation of `[[layer]]` tables into colouring layers (and the traps they need).
//!
//! Each kind accepts a fixed set of keys; a key that does not apply to the kind is an error
//! that names it and lists what the kind takes, so a typo never silently does nothing.

use std::path::Path;
use std::sync::Arc;

use toml::Spanned;

use super::context::{BitmapLoader, Ctx};
use super::raw::{LayerRaw, MaskRaw};
use crate::coloring::{Coloring, DistanceStyle, InteriorFill, Light, Mask, MaskQuantity};
use crate::compose::Layer;
use crate::palette::{self, Palette};
use crate::source::SourceError;
use crate::trap::{BitmapTrap, Frame, Shape, Stripe, Trap};

/// Every layer kind, with the keys it takes beyond `kind`, `blend`, `opacity` and `mask`.
pub const LAYER_KINDS: [(&str, &[&str]); 12] = [
    ("smooth", &["palette", "density", "offset", "transfer", "interior"]),
    ("histogram", &["palette", "density", "offset", "interior"]),
    ("distance", &["style", "k", "density", "palette", "offset"]),
    ("boundary", &["width", "color"]),
    ("slope", &["angle", "height", "strength"]),
    ("binary", &["colors"]),
    ("angle", &["palette", "density", "offset"]),
    ("stripe", &["frequency", "palette", "density", "offset"]),
    ("trap", &["shape", "center", "angle", "radius", "palette", "density", "offset"]),
    ("bitmap", &["image", "center", "size", "angle", "threshold", "frames", "frame", "frame_width"]),
    ("interior", &["color", "shape", "center", "angle", "radius", "palette", "density", "offset"]),
    ("ifs", &["fold_offset", "slice", "iterations", "strength", "decay", "scale", "palette", "density", "offset"]),
];

/// The names of the layer kinds, quoted and comma-separated (for messages).
pub fn kind_list() -> String {
    LAYER_KINDS.iter().map(|(k, _)| format!("\"{k}\"")).collect::<Vec<_>>().join(", ")
}

/// The layer used when a scene names none: smooth iteration through `classic`.
pub(super) fn default_layer() -> LayerRaw {
    LayerRaw::of_kind("smooth")
}

/// Validates one layer (its palettes cycled by `cycle`); traps it needs are appended to `traps`.
pub(super) fn layer(
    cx: &Ctx<'_>,
    spanned: &Spanned<LayerRaw>,
    base_dir: &Path,
    bitmaps: &BitmapLoader<'_>,
    cycle: f64,
    traps: &mut Vec<Trap>,
) -> Result<Layer, SourceError> {
    let l = spanned.get_ref();
    let kind = l.kind.get_ref().as_str();
    let Some((_, allowed)) = LAYER_KINDS.iter().find(|(k, _)| *k == kind) else {
        return cx.err(l.kind.span(), format!("unknown layer kind `{kind}`; expected one of {}", kind_list()));
    };
    for (key, span) in l.present() {
        if !allowed.contains(&key) && !["blend", "opacity", "mask"].contains(&key) {
            return cx.err(
                span,
                format!(
                    "`{key}` does not apply to a `{kind}` layer (it takes: {}, blend, opacity, mask)",
                    allowed.join(", ")
                ),
            );
        }
    }
    let num = |v: &Option<Spanned<f64>>, default: f64, lo: f64, hi: f64, what: &str| match v {
        Some(v) => cx.finite(v, lo, hi, what),
        None => Ok(default),
    };
    let pal = |name: Option<&Spanned<String>>, default: &str| -> Result<Palette, SourceError> {
        let (text, span) = match name {
            Some(n) => (n.get_ref().as_str(), n.span()),
            None => (default, 0..0),
        };
        let p = palette::load(text, Some(base_dir)).or_else(|e| cx.err(span, e.to_string()))?;
        // Cycling moves every palette along by the same phase.
        let (offset, density) = (p.offset + cycle, p.density);
        Ok(p.adjusted(offset, density))
    };
    let colour = |v: &Option<Spanned<String>>, default: [f32; 4]| match v {
        Some(c) => cx.colour(c),
        None => Ok(default),
    };
    let center = l.center.as_ref().map_or([0.0, 0.0], |c| *c.get_ref());
    if let Some(c) = &l.center
        && !c.get_ref().iter().all(|v| v.is_finite())
    {
        return cx.err(c.span(), "center must be two finite numbers");
    }
    let angle = num(&l.angle, 0.0, -1e6, 1e6, "angle (degrees)")?;
    let density = |default: f64| num(&l.density, default, -1e9, 1e9, "density");
    let offset = || num(&l.offset, 0.0, -1e9, 1e9, "offset");
    let black = [0.0, 0.0, 0.0, 1.0];
    let shape = || -> Result<Shape, SourceError> {
        let dir = Shape::direction(angle);
        match l.shape.as_ref().map_or("point", |s| s.get_ref().as_str()) {
            "point" => Ok(Shape::Point { at: center }),
            "line" => Ok(Shape::Line { at: center, dir }),
            "cross" => Ok(Shape::Cross { at: center, dir }),
            "circle" => Ok(Shape::Circle { at: center, radius: num(&l.radius, 1.0, 0.0, 1e6, "radius")? }),
            other => cx.err(
                l.shape.as_ref().map_or(0..0, |s| s.span()),
                format!("unknown trap shape `{other}`; expected \"point\", \"line\", \"cross\" or \"circle\""),
            ),
        }
    };
    let mut push = |t: Trap| {
        traps.push(t);
        traps.len() - 1
    };

    let coloring = match kind {
        "smooth" => Coloring::Smooth {
            palette: pal(l.palette.as_ref(), "classic")?,
            density: density(0.05)?,
            offset: offset()?,
            transfer: l.transfer.as_ref().map_or(Default::default(), |t| *t.get_ref()),
            interior: colour(&l.interior, black)?,
        },
        "histogram" => Coloring::Histogram {
            palette: pal(l.palette.as_ref(), "classic")?,
            cycles: density(1.0)?,
            offset: offset()?,
            interior: colour(&l.interior, black)?,
        },
        "distance" => {
            let style = match l.style.as_ref().map_or("soft", |s| s.get_ref().as_str()) {
                "soft" => DistanceStyle::Soft { k: num(&l.k, 0.25, 0.0, 1e12, "k")? },
                "linear" => DistanceStyle::Linear { density: density(0.05)? },
                "log" => DistanceStyle::Log { density: density(0.25)? },
                other => {
                    return cx.err(
                        l.style.as_ref().map_or(0..0, |s| s.span()),
                        format!("unknown distance style `{other}`; expected \"soft\", \"linear\" or \"log\""),
                    );
                }
            };
            if let (DistanceStyle::Soft { .. }, Some(d)) = (style, &l.density) {
                return cx.err(d.span(), "`density` applies to the linear and log styles; the soft style takes `k`");
            }
            if let (DistanceStyle::Linear { .. } | DistanceStyle::Log { .. }, Some(k)) = (style, &l.k) {
                return cx.err(k.span(), "`k` applies to the soft style; the linear and log styles take `density`");
            }
            Coloring::Distance {
                style,
                palette: l.palette.as_ref().map(|p| pal(Some(p), "")).transpose()?,
                offset: offset()?,
            }
        }
        "boundary" => Coloring::Boundary {
            width: num(&l.width, 1.0, 0.0, 1e6, "width (pixels)")?,
            color: colour(&l.color, black)?,
        },
        "slope" => Coloring::Slope {
            light: Light::new(
                num(&l.angle, 45.0, -1e6, 1e6, "angle (degrees)")?,
                num(&l.height, 1.5, 0.0, 1e6, "height")?,
                num(&l.strength, 1.0, 0.0, 1.0, "strength")?,
            ),
        },
        "binary" => Coloring::Binary {
            colors: match &l.colors {
                None => [[1.0; 4], black],
                Some(c) => {
                    let [a, b] = c.get_ref();
                    let one = |s: &String| cx.colour(&Spanned::new(c.span(), s.clone()));
                    [one(a)?, one(b)?]
                }
            },
        },
        "angle" => {
            Coloring::Angle { palette: pal(l.palette.as_ref(), "classic")?, density: density(1.0)?, offset: offset()? }
        }
        "stripe" => {
            let frequency = num(&l.frequency, 5.0, -1e6, 1e6, "frequency")?;
            Coloring::Stripe {
                trap: push(Trap::Stripe(Stripe { frequency })),
                palette: pal(l.palette.as_ref(), "classic")?,
                density: density(1.0)?,
                offset: offset()?,
            }
        }
        "trap" => {
            let s = shape()?;
            Coloring::TrapDistance {
                trap: push(Trap::Geometric(s)),
                palette: pal(l.palette.as_ref(), "fire")?,
                density: density(1.0)?,
                offset: offset()?,
            }
        }
        "ifs" => {
            let d = crate::trap::ifs::IfsParams::default();
            let fold = match &l.fold_offset {
                Some(f) if f.get_ref().iter().all(|v| v.is_finite() && v.abs() <= 100.0) => {
                    f.get_ref().map(|v| v as f32)
                }
                Some(f) => return cx.err(f.span(), "fold_offset must be three numbers in [-100, 100]"),
                None => d.offset,
            };
            let params = crate::trap::ifs::IfsParams {
                offset: fold,
                z: num(&l.slice, d.z as f64, -100.0, 100.0, "slice")? as f32,
                iterations: match &l.iterations {
                    Some(n) => cx.range_i(n, 1, 1000, "iterations")? as u32,
                    None => d.iterations,
                },
                strength: num(&l.strength, d.strength as f64, 0.0, 1e6, "strength")? as f32,
                decay: num(&l.decay, d.decay as f64, 1e-3, 1e6, "decay")? as f32,
                scale: num(&l.scale, d.scale as f64, 1e-12, 1e12, "scale")? as f32,
            };
            Coloring::Ifs {
                trap: push(Trap::Ifs(params)),
                palette: l.palette.as_ref().map(|p| pal(Some(p), "")).transpose()?,
                density: density(1.0)?,
                offset: offset()?,
            }
        }
        "interior" => {
            let fill = if l.palette.is_some() {
                let s = shape()?;
                InteriorFill::Trap {
                    trap: push(Trap::Geometric(s)),
                    palette: pal(l.palette.as_ref(), "")?,
                    density: density(1.0)?,
                    offset: offset()?,
                }
            } else {
                if let Some((key, span)) = l
                    .present()
                    .into_iter()
                    .find(|(k, _)| ["shape", "center", "angle", "radius", "density", "offset"].contains(k))
                {
                    return cx.err(
                        span,
                        format!("`{key}` needs `palette` (an interior layer without one is a solid `color`)"),
                    );
                }
                InteriorFill::Solid(colour(&l.color, black)?)
            };
            Coloring::Interior { fill }
        }
        _ => {
            let Some(image) = &l.image else {
                return cx.err(
                    l.kind.span(),
                    "a bitmap layer needs `image`, the path of a PNG (relative to the scene file)",
                );
            };
            let path = base_dir.join(image.get_ref());
            let bitmap = bitmaps(&path)
                .or_else(|e| cx.err(image.span(), format!("cannot load bitmap {}: {e}", path.display())))?;
            let size = num(&l.size, 1.0, 1e-300, 1e6, "size")?;
            let frame = frame(cx, l, bitmap.width)?;
            let a = angle.to_radians();
            Coloring::BitmapTrap {
                trap: push(Trap::Bitmap(BitmapTrap {
                    bitmap: Arc::new(bitmap),
                    center,
                    size,
                    rotation: [a.cos(), a.sin()],
                    threshold: num(&l.threshold, 0.1, 0.0, 1.0, "threshold")? as f32,
                    frame,
                })),
            }
        }
    };
    let opacity = num(&l.opacity, 1.0, 0.0, 1.0, "opacity")? as f32;
    let blend = l.blend.as_ref().map_or(Default::default(), |b| *b.get_ref());
    let mask = l.mask.as_ref().map(|m| mask(cx, m)).transpose()?;
    Ok(Layer { coloring, blend, opacity, mask })
}

/// The sprite-sheet frame of a bitmap layer, if it names one.
fn frame(cx: &Ctx<'_>, l: &LayerRaw, image_width: usize) -> Result<Option<Frame>, SourceError> {
    let Some(frames) = &l.frames else {
        if let Some(f) = l.frame.as_ref().or(l.frame_width.as_ref()) {
            return cx.err(f.span(), "`frame` and `frame_width` need `frames` (the number of frames in the sheet)");
        }
        return Ok(None);
    };
    let count = cx.range_i(frames, 1, 4096, "frames")? as u32;
    let width = match &l.frame_width {
        Some(w) => cx.range_i(w, 1, image_width as i64, "frame_width (texels)")? as u32,
        None => (image_width / count as usize).max(1) as u32,
    };
    if (count as usize) * (width as usize) > image_width {
        return cx.err(
            frames.span(),
            format!("{count} frames of {width} texels do not fit in an image {image_width} texels wide"),
        );
    }
    let index = match &l.frame {
        Some(f) => cx.range_i(f, 0, i64::from(u32::MAX), "frame")? as u32,
        None => 0,
    };
    Ok(Some(Frame { index, count, width }))
}

fn mask(cx: &Ctx<'_>, m: &Spanned<MaskRaw>) -> Result<Mask, SourceError> {
    let raw = m.get_ref();
    let name = raw.quantity.get_ref().as_str();
    let Some((quantity, _)) = MaskQuantity::ALL.iter().find(|(_, n)| *n == name) else {
        let names: Vec<String> = MaskQuantity::ALL.iter().map(|(_, n)| format!("\"{n}\"")).collect();
        return cx.err(raw.quantity.span(), format!("unknown mask quantity `{name}`; expected {}", names.join(", ")));
    };
    let bound = |v: &Option<Spanned<f64>>, default: f64, what: &str| match v {
        Some(v) if v.get_ref().is_nan() => cx.err(v.span(), format!("mask.{what} must be a number")),
        Some(v) => Ok(*v.get_ref()),
        None => Ok(default),
    };
    let above = bound(&raw.above, f64::NEG_INFINITY, "above")?;
    let below = bound(&raw.below, f64::INFINITY, "below")?;
    if above > below {
        return cx.err(m.span(), format!("mask.above ({above}) is greater than mask.below ({below}): nothing is kept"));
    }
    let feather = match &raw.feather {
        Some(f) => cx.finite(f, 0.0, 1e12, "mask.feather")?,
        None => 0.0,
    };
    Ok(Mask { quantity: *quantity, above, below, feather, invert: raw.invert.as_ref().is_some_and(|v| *v.get_ref()) })
}
