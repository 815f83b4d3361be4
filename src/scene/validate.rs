//! Validation: raw scene data to a typed [`Scene`], with located, explicit errors.

use std::path::Path;
use std::sync::Arc;

use toml::Spanned;

use super::raw::{CLI, LayerRaw, SceneFile};
use super::{EngineChoice, FamilySpec, MAX_AA, MAX_ITER_LIMIT, MAX_SAMPLES, MAX_SIDE, Scene};
use crate::coloring::Coloring;
use crate::compose::{Layer, Stack};
use crate::field::{Channel, ChannelSet};
use crate::num::Decimal;
use crate::orbit::{DEFAULT_BLA_TOLERANCE, Scale};
use crate::palette::{self, Palette, color};
use crate::source::SourceError;
use crate::trap::{Bitmap, BitmapTrap, Shape, Trap};

/// Loads a bitmap for a bitmap trap (provided by the I/O layer).
pub type BitmapLoader<'a> = dyn Fn(&Path) -> Result<Bitmap, String> + 'a;

struct Ctx<'a> {
    origin: &'a str,
    text: &'a str,
}

impl Ctx<'_> {
    fn err<T>(&self, span: std::ops::Range<usize>, message: impl Into<String>) -> Result<T, SourceError> {
        let message = message.into();
        if span == CLI {
            return Err(SourceError { origin: "command line".into(), position: None, message });
        }
        Err(SourceError::at(self.origin, self.text, Some(span), message))
    }

    fn decimal(&self, s: &Spanned<String>, what: &str) -> Result<Decimal, SourceError> {
        Decimal::parse(s.get_ref()).or_else(|e| self.err(s.span(), format!("{what}: {e}")))
    }

    fn pair(&self, s: &Spanned<[String; 2]>, what: &str) -> Result<[Decimal; 2], SourceError> {
        let [re, im] = s.get_ref();
        let p = |t: &String| Decimal::parse(t).or_else(|e| self.err(s.span(), format!("{what}: {e}")));
        Ok([p(re)?, p(im)?])
    }

    fn colour(&self, s: &Spanned<String>) -> Result<[f32; 4], SourceError> {
        match color::parse_hex(s.get_ref()) {
            Some(c) => Ok([color::srgb_to_linear(c[0]), color::srgb_to_linear(c[1]), color::srgb_to_linear(c[2]), 1.0]),
            None => self.err(s.span(), format!("colour `{}` is not of the form \"#rrggbb\"", s.get_ref())),
        }
    }

    fn range_i(&self, v: &Spanned<i64>, lo: i64, hi: i64, what: &str) -> Result<i64, SourceError> {
        let x = *v.get_ref();
        if x < lo || x > hi {
            return self.err(v.span(), format!("{what} must be in {lo} ..= {hi}, got {x}"));
        }
        Ok(x)
    }

    fn finite(&self, v: &Spanned<f64>, lo: f64, hi: f64, what: &str) -> Result<f64, SourceError> {
        let x = *v.get_ref();
        if !(x.is_finite() && x >= lo && x <= hi) {
            return self.err(v.span(), format!("{what} must be a finite number in [{lo}, {hi}], got {x}"));
        }
        Ok(x)
    }
}

pub(super) fn validate(
    file: SceneFile,
    origin: &str,
    text: &str,
    base_dir: &Path,
    bitmaps: &BitmapLoader<'_>,
) -> Result<Scene, SourceError> {
    let cx = Ctx { origin, text };
    if *file.version.get_ref() != 1 {
        return cx
            .err(file.version.span(), format!("unsupported scene version {}; expected 1", file.version.get_ref()));
    }

    let family = match file.formula.kind.get_ref().as_str() {
        "mandelbrot" => {
            if let Some(c) = &file.formula.c {
                return cx.err(c.span(), "`c` applies only to kind = \"julia\"");
            }
            FamilySpec::Mandelbrot
        }
        "julia" => match &file.formula.c {
            Some(c) => FamilySpec::Julia { c: cx.pair(c, "Julia parameter c")? },
            None => return cx.err(file.formula.kind.span(), "a Julia set needs its parameter: c = [\"re\", \"im\"]"),
        },
        other => {
            return cx.err(
                file.formula.kind.span(),
                format!("unknown formula `{other}`; expected \"mandelbrot\" or \"julia\""),
            );
        }
    };

    let view = &file.view;
    let center = cx.pair(&view.center, "view centre")?;
    let (log10_radius, radius, scale) = match (&view.zoom, &view.radius) {
        (Some(_), Some(r)) => return cx.err(r.span(), "give either `zoom` or `radius`, not both"),
        (Some(z), None) => {
            let d = cx.decimal(z, "zoom")?;
            if d.is_zero() || d.is_negative() {
                return cx.err(z.span(), format!("zoom must be positive, got {d}"));
            }
            (2f64.log10() - d.log10_abs(), 2.0 / d.to_f64(), Scale::Zoom(d))
        }
        (None, Some(r)) => {
            let d = cx.decimal(r, "radius")?;
            if d.is_zero() || d.is_negative() {
                return cx.err(r.span(), format!("radius must be positive, got {d}"));
            }
            (d.log10_abs(), d.to_f64(), Scale::Radius(d))
        }
        // The whole set.
        (None, None) => (1.25f64.log10(), 1.25, Scale::Radius(Decimal::parse("1.25").expect("valid literal"))),
    };
    if log10_radius > 3.0 {
        return cx.err(
            view.zoom.as_ref().or(view.radius.as_ref()).map_or(0..0, |s| s.span()),
            "the view is wider than 1000 units; zoom must be at least 0.002",
        );
    }
    let width = cx.range_i(&view.width, 1, MAX_SIDE, "width")? as u32;
    let height = cx.range_i(&view.height, 1, MAX_SIDE, "height")? as u32;
    let max_iter = cx.range_i(&file.iteration.max, 1, MAX_ITER_LIMIT as i64, "iteration.max")? as u32;
    let escape_radius = cx.finite(&file.iteration.escape_radius, 2.0, 1e150, "iteration.escape_radius")?;
    let aa = cx.range_i(&file.render.aa, 1, MAX_AA, "render.aa")? as u32;
    let samples = width as u64 * height as u64 * (aa as u64).pow(2);
    if samples > MAX_SAMPLES {
        return cx.err(view.width.span(), format!("{width}x{height} with {aa}x{aa} supersampling is {samples} samples; at most {MAX_SAMPLES} are supported"));
    }
    let engine = match EngineChoice::parse(file.render.engine.get_ref()) {
        Some(e) => e,
        None => {
            let other = file.render.engine.get_ref();
            let names = EngineChoice::NAMES;
            return cx.err(file.render.engine.span(), format!("unknown engine `{other}`; expected {names}"));
        }
    };
    let bla_on = file.render.bla.as_ref().is_none_or(|b| *b.get_ref());
    let tolerance = match &file.render.bla_tolerance {
        Some(t) => cx.finite(t, 1e-300, 0.1, "render.bla_tolerance")?,
        None => DEFAULT_BLA_TOLERANCE,
    };
    let bla = bla_on.then_some(tolerance);
    let bg = cx.colour(&file.render.background)?;

    let mut traps = Vec::new();
    let mut layers = Vec::new();
    let raw_layers =
        if file.layers.is_empty() { vec![Spanned::new(0..0, default_layer())] } else { file.layers.clone() };
    for l in &raw_layers {
        layers.push(layer(&cx, l, base_dir, bitmaps, &mut traps)?);
    }

    let png_bits = match &file.output.bits {
        None => 8,
        Some(b) => match b.get_ref() {
            8 => 8,
            16 => 16,
            other => return cx.err(b.span(), format!("output.bits must be 8 or 16, got {other}")),
        },
    };
    let channels = match &file.output.channels {
        None => ChannelSet::default_exr(),
        Some(list) => {
            let mut set = ChannelSet::default();
            for name in list.get_ref() {
                set.insert(name.parse::<Channel>().or_else(|e| cx.err(list.span(), e))?);
            }
            set
        }
    };

    let mut file = file;
    anchor_paths(&mut file, base_dir);
    Ok(Scene {
        origin: origin.to_string(),
        base_dir: base_dir.to_path_buf(),
        family,
        center,
        log10_radius,
        radius,
        width,
        height,
        max_iter,
        escape_radius,
        aa,
        engine,
        bla,
        scale,
        stack: Stack { layers, background: [bg[0], bg[1], bg[2]] },
        traps,
        png_bits,
        channels,
        file,
    })
}

/// Rewrites the files a valid scene refers to (bitmaps, palette files) as absolute paths,
/// so the scene embedded in an output re-renders from any folder. Built-in palette names
/// stay names.
fn anchor_paths(file: &mut SceneFile, base_dir: &Path) {
    let absolute = |p: &str| -> Option<String> {
        let path = base_dir.join(p);
        path.is_file().then(|| std::fs::canonicalize(&path).unwrap_or(path).display().to_string())
    };
    for l in &mut file.layers {
        let l = l.get_mut();
        if let Some(img) = &mut l.image
            && let Some(abs) = absolute(img.get_ref())
        {
            *img.get_mut() = abs;
        }
        if let Some(pal) = &mut l.palette
            && !palette::builtin_names().contains(&pal.get_ref().as_str())
            && let Some(abs) = absolute(pal.get_ref())
        {
            *pal.get_mut() = abs;
        }
    }
}

/// The layer used when a scene names none: smooth iteration through `classic`.
fn default_layer() -> LayerRaw {
    LayerRaw::of_kind("smooth")
}

fn layer(
    cx: &Ctx<'_>,
    spanned: &Spanned<LayerRaw>,
    base_dir: &Path,
    bitmaps: &BitmapLoader<'_>,
    traps: &mut Vec<Trap>,
) -> Result<Layer, SourceError> {
    let l = spanned.get_ref();
    let kind = l.kind.get_ref().as_str();
    // Keys each kind accepts, beyond kind/blend/opacity.
    let allowed: &[&str] = match kind {
        "smooth" => &["palette", "density", "offset", "transfer", "interior"],
        "distance" => &["k", "palette"],
        "boundary" => &["width", "color"],
        "trap" => &["shape", "center", "angle", "radius", "palette", "density", "offset"],
        "bitmap" => &["image", "center", "size", "angle", "threshold"],
        other => {
            return cx.err(l.kind.span(), format!(
                "unknown layer kind `{other}`; expected one of \"smooth\", \"distance\", \"boundary\", \"trap\", \"bitmap\""
            ));
        }
    };
    let present: [(&str, Option<std::ops::Range<usize>>); 16] = [
        ("palette", l.palette.as_ref().map(|s| s.span())),
        ("density", l.density.as_ref().map(|s| s.span())),
        ("offset", l.offset.as_ref().map(|s| s.span())),
        ("transfer", l.transfer.as_ref().map(|s| s.span())),
        ("interior", l.interior.as_ref().map(|s| s.span())),
        ("k", l.k.as_ref().map(|s| s.span())),
        ("width", l.width.as_ref().map(|s| s.span())),
        ("color", l.color.as_ref().map(|s| s.span())),
        ("shape", l.shape.as_ref().map(|s| s.span())),
        ("center", l.center.as_ref().map(|s| s.span())),
        ("angle", l.angle.as_ref().map(|s| s.span())),
        ("radius", l.radius.as_ref().map(|s| s.span())),
        ("image", l.image.as_ref().map(|s| s.span())),
        ("size", l.size.as_ref().map(|s| s.span())),
        ("threshold", l.threshold.as_ref().map(|s| s.span())),
        ("blend", None),
    ];
    for (key, span) in present {
        if let Some(span) = span
            && !allowed.contains(&key)
        {
            return cx
                .err(span, format!("`{key}` does not apply to a `{kind}` layer (it takes: {})", allowed.join(", ")));
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
        palette::load(text, Some(base_dir)).or_else(|e| cx.err(span, e.to_string()))
    };
    let center = l.center.as_ref().map_or([0.0, 0.0], |c| *c.get_ref());
    if let Some(c) = &l.center
        && !c.get_ref().iter().all(|v| v.is_finite())
    {
        return cx.err(c.span(), "center must be two finite numbers");
    }
    let angle = num(&l.angle, 0.0, -1e6, 1e6, "angle (degrees)")?;

    let coloring = match kind {
        "smooth" => Coloring::Smooth {
            palette: pal(l.palette.as_ref(), "classic")?,
            density: num(&l.density, 0.05, -1e9, 1e9, "density")?,
            offset: num(&l.offset, 0.0, -1e9, 1e9, "offset")?,
            transfer: l.transfer.as_ref().map_or(Default::default(), |t| *t.get_ref()),
            interior: match &l.interior {
                Some(c) => cx.colour(c)?,
                None => [0.0, 0.0, 0.0, 1.0],
            },
        },
        "distance" => Coloring::SoftDistance {
            k: num(&l.k, 0.25, 0.0, 1e12, "k")?,
            palette: l.palette.as_ref().map(|p| pal(Some(p), "")).transpose()?,
        },
        "boundary" => Coloring::Boundary {
            width: num(&l.width, 1.0, 0.0, 1e6, "width (pixels)")?,
            color: match &l.color {
                Some(c) => cx.colour(c)?,
                None => [0.0, 0.0, 0.0, 1.0],
            },
        },
        "trap" => {
            let dir = Shape::direction(angle);
            let shape_name = l.shape.as_ref().map_or("point", |s| s.get_ref().as_str());
            let shape = match shape_name {
                "point" => Shape::Point { at: center },
                "line" => Shape::Line { at: center, dir },
                "cross" => Shape::Cross { at: center, dir },
                "circle" => Shape::Circle { at: center, radius: num(&l.radius, 1.0, 0.0, 1e6, "radius")? },
                other => {
                    let span = l.shape.as_ref().map_or(0..0, |s| s.span());
                    return cx.err(
                        span,
                        format!("unknown trap shape `{other}`; expected \"point\", \"line\", \"cross\" or \"circle\""),
                    );
                }
            };
            traps.push(Trap::Geometric(shape));
            Coloring::TrapDistance {
                trap: traps.len() - 1,
                palette: pal(l.palette.as_ref(), "fire")?,
                density: num(&l.density, 1.0, -1e9, 1e9, "density")?,
                offset: num(&l.offset, 0.0, -1e9, 1e9, "offset")?,
            }
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
            if size <= 0.0 {
                return cx.err(l.size.as_ref().map_or(0..0, |s| s.span()), "size must be positive");
            }
            let a = angle.to_radians();
            traps.push(Trap::Bitmap(BitmapTrap {
                bitmap: Arc::new(bitmap),
                center,
                size,
                rotation: [a.cos(), a.sin()],
                threshold: num(&l.threshold, 0.1, 0.0, 1.0, "threshold")? as f32,
            }));
            Coloring::BitmapTrap { trap: traps.len() - 1 }
        }
    };
    let opacity = num(&l.opacity, 1.0, 0.0, 1.0, "opacity")? as f32;
    let blend = l.blend.as_ref().map_or(Default::default(), |b| *b.get_ref());
    Ok(Layer { coloring, blend, opacity })
}
