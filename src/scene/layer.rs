//! Validation of `[[layer]]` tables into colouring layers (and the traps they need), and
//! the one table of what each kind uses for a key the layer leaves out.
//!
//! Each kind accepts a fixed set of keys ([`LAYER_KINDS`]); a key that does not apply to the
//! kind is an error that names it and lists what the kind takes, so a typo never silently
//! does nothing. The value used for an absent key comes from [`default_value`], which the
//! viewer's layer panel reads too, so each default is written once.

use std::path::Path;
use std::sync::Arc;

use toml::Spanned;

use super::context::{BitmapLoader, Ctx, linear_colour};
use super::raw::{LayerRaw, MaskRaw};
use crate::coloring::{Coloring, DistanceStyle, InteriorFill, Light, MASK_FEATHER, Mask, MaskQuantity, Transfer};
use crate::compose::{BlendMode, Layer};
use crate::palette::{self, Palette};
use crate::source::SourceError;
use crate::trap::ifs::IfsParams;
use crate::trap::{BitmapTrap, Frame, Shape, Stripe, Trap};

/// True when a palette given for every layer (`--palette`, the viewer's palette menu) applies
/// to `l`: its kind takes a palette and it uses one, written or by default. Distance,
/// interior and IFS layers without a palette are grey, solid or white by design and keep
/// that.
pub fn uses_palette(l: &LayerRaw) -> bool {
    let takes = kind_keys(l.kind.get_ref()).is_some_and(|keys| keys.contains(&"palette"));
    takes && (l.palette.is_some() || matches!(default_value(l, "palette"), Some(DefaultValue::Text(_))))
}

/// Every layer kind, with the keys it takes beyond `kind` and the [`COMMON_KEYS`].
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

/// The keys every kind takes.
pub const COMMON_KEYS: [&str; 3] = ["blend", "opacity", "mask"];

/// The names of the layer kinds, quoted and comma-separated (for messages).
pub fn kind_list() -> String {
    LAYER_KINDS.iter().map(|(k, _)| format!("\"{k}\"")).collect::<Vec<_>>().join(", ")
}

/// The keys `kind` takes beyond `kind` and the [`COMMON_KEYS`], or None for an unknown kind.
pub fn kind_keys(kind: &str) -> Option<&'static [&'static str]> {
    LAYER_KINDS.iter().find(|(k, _)| *k == kind).map(|(_, keys)| *keys)
}

/// The value a layer uses for a key it leaves out ([`default_value`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DefaultValue {
    /// A number.
    Number(f64),
    /// An integer.
    Integer(i64),
    /// A word, a colour "#rrggbb" or a built-in palette's name.
    Text(&'static str),
    /// Two colours "#rrggbb".
    Colors([&'static str; 2]),
    /// A point in the plane.
    Point([f64; 2]),
    /// Three numbers.
    Triple([f64; 3]),
    /// A transfer function.
    Transfer(Transfer),
    /// A blend mode.
    Blend(BlendMode),
    /// No value stands in for the key: leaving it out means what the text says (a distance
    /// layer without a palette is grey; a soft distance layer takes no density).
    Unset(&'static str),
}

impl DefaultValue {
    /// The number, if this is one.
    pub fn number(self) -> Option<f64> {
        if let DefaultValue::Number(x) = self { Some(x) } else { None }
    }

    /// The integer, if this is one.
    pub fn integer(self) -> Option<i64> {
        if let DefaultValue::Integer(x) = self { Some(x) } else { None }
    }

    /// The text, if this is one.
    pub fn text(self) -> Option<&'static str> {
        if let DefaultValue::Text(x) = self { Some(x) } else { None }
    }

    /// The two colours, if this is them.
    pub fn colors(self) -> Option<[&'static str; 2]> {
        if let DefaultValue::Colors(x) = self { Some(x) } else { None }
    }

    /// The point, if this is one.
    pub fn point(self) -> Option<[f64; 2]> {
        if let DefaultValue::Point(x) = self { Some(x) } else { None }
    }

    /// The three numbers, if this is them.
    pub fn triple(self) -> Option<[f64; 3]> {
        if let DefaultValue::Triple(x) = self { Some(x) } else { None }
    }

    /// The transfer function, if this is one.
    pub fn transfer(self) -> Option<Transfer> {
        if let DefaultValue::Transfer(x) = self { Some(x) } else { None }
    }

    /// The blend mode, if this is one.
    pub fn blend(self) -> Option<BlendMode> {
        if let DefaultValue::Blend(x) = self { Some(x) } else { None }
    }
}

/// The distance layer's style when it names none.
const DISTANCE_STYLE: &str = "soft";

/// What validation uses for `key` when layer `l` leaves it out: by the layer's kind, and for
/// a distance layer by its style (the soft style takes `k`, the others `density`). None when
/// the kind does not take the key, or is unknown.
pub fn default_value(l: &LayerRaw, key: &str) -> Option<DefaultValue> {
    use DefaultValue::{Blend, Colors, Integer, Number, Point, Text, Triple, Unset};
    let kind = l.kind.get_ref().as_str();
    let keys = kind_keys(kind)?;
    if !COMMON_KEYS.contains(&key) && !keys.contains(&key) {
        return None;
    }
    let style = l.style.as_ref().map_or(DISTANCE_STYLE, |s| s.get_ref().as_str());
    let ifs = IfsParams::default();
    Some(match (kind, key) {
        (_, "blend") => Blend(BlendMode::default()),
        (_, "opacity") => Number(1.0),
        (_, "mask") => Unset("none: the layer applies everywhere"),
        ("distance", "style") => Text(DISTANCE_STYLE),
        ("distance", "k") if style == "soft" => Number(0.25),
        ("distance", "k") => Unset("only with style = \"soft\""),
        ("distance", "density") => match style {
            "linear" => Number(0.05),
            "log" => Number(0.25),
            _ => Unset("only with style = \"linear\" or \"log\""),
        },
        ("distance", "palette") => Unset("none: grey"),
        ("interior", "palette") => Unset("none: a solid `color`"),
        ("ifs", "palette") => Unset("none: white, as opaque as the field is dense"),
        ("trap", "palette") => Text("fire"),
        (_, "palette") => Text("classic"),
        ("smooth", "density") => Number(0.05),
        (_, "density") => Number(1.0),
        (_, "offset") => Number(0.0),
        (_, "transfer") => DefaultValue::Transfer(Transfer::default()),
        (_, "interior" | "color") => Text("#000000"),
        (_, "width") => Number(1.0),
        ("slope", "angle") => Number(45.0),
        (_, "angle") => Number(0.0),
        (_, "height") => Number(1.5),
        ("slope", "strength") => Number(1.0),
        (_, "colors") => Colors(["#ffffff", "#000000"]),
        (_, "frequency") => Number(5.0),
        (_, "shape") => Text("point"),
        (_, "center") => Point([0.0, 0.0]),
        (_, "radius") => Number(1.0),
        (_, "image") => Unset("required: a PNG, relative to the scene file"),
        (_, "size") => Number(1.0),
        (_, "threshold") => Number(0.1),
        (_, "frames") => Unset("none: the whole image is one picture"),
        (_, "frame") => Integer(0),
        (_, "frame_width") => Unset("the image's width divided by `frames`"),
        (_, "fold_offset") => Triple(ifs.offset.map(f64::from)),
        (_, "slice") => Number(ifs.z.into()),
        (_, "iterations") => Integer(ifs.iterations.into()),
        (_, "strength") => Number(ifs.strength.into()),
        (_, "decay") => Number(ifs.decay.into()),
        (_, "scale") => Number(ifs.scale.into()),
        _ => return None,
    })
}

/// The default of `key` for layer `l`, read as `pick` expects. The table's tests make a
/// missing or mistyped entry impossible; should one slip through, it is reported as an
/// error rather than a panic.
fn expect_default<T>(
    cx: &Ctx<'_>,
    l: &LayerRaw,
    key: &str,
    pick: impl FnOnce(DefaultValue) -> Option<T>,
) -> Result<T, SourceError> {
    match default_value(l, key).and_then(pick) {
        Some(v) => Ok(v),
        None => cx.err(
            l.kind.span(),
            format!(
                "deepfield has no default for `{key}` in a `{}` layer (a defect: please report it)",
                l.kind.get_ref()
            ),
        ),
    }
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
    let Some(allowed) = kind_keys(kind) else {
        return cx.err(l.kind.span(), format!("unknown layer kind `{kind}`; expected one of {}", kind_list()));
    };
    for (key, span) in l.present() {
        if !allowed.contains(&key) && !COMMON_KEYS.contains(&key) {
            return cx.err(
                span,
                format!(
                    "`{key}` does not apply to a `{kind}` layer (it takes: {}, {})",
                    allowed.join(", "),
                    COMMON_KEYS.join(", ")
                ),
            );
        }
    }
    let num = |v: &Option<Spanned<f64>>, key: &str, lo: f64, hi: f64, what: &str| match v {
        Some(v) => cx.finite(v, lo, hi, what),
        None => expect_default(cx, l, key, DefaultValue::number),
    };
    let text = |v: &Option<Spanned<String>>, key: &str| -> Result<String, SourceError> {
        match v {
            Some(v) => Ok(v.get_ref().clone()),
            None => expect_default(cx, l, key, DefaultValue::text).map(str::to_string),
        }
    };
    let load = |name: &str, span: std::ops::Range<usize>| -> Result<Palette, SourceError> {
        let p = palette::load(name, Some(base_dir)).or_else(|e| cx.err(span, e.to_string()))?;
        // Cycling moves every palette along by the same phase.
        let (offset, density) = (p.offset + cycle, p.density);
        Ok(p.adjusted(offset, density))
    };
    // The layer's palette; None where the kind's default is to have none.
    let pal = || -> Result<Option<Palette>, SourceError> {
        match &l.palette {
            Some(n) => load(n.get_ref(), n.span()).map(Some),
            None => match default_value(l, "palette") {
                Some(DefaultValue::Unset(_)) => Ok(None),
                _ => load(expect_default(cx, l, "palette", DefaultValue::text)?, 0..0).map(Some),
            },
        }
    };
    let required_pal = || -> Result<Palette, SourceError> {
        match pal()? {
            Some(p) => Ok(p),
            None => expect_default(cx, l, "palette", |_| None),
        }
    };
    let colour = |v: &Option<Spanned<String>>, key: &str| match v {
        Some(c) => cx.colour(c),
        None => expect_default(cx, l, key, |d| d.text().and_then(linear_colour)),
    };
    // Checked before anything else, whichever kind reads them, so that of several problems
    // the same one is reported first.
    if let Some(c) = &l.center
        && !c.get_ref().iter().all(|v| v.is_finite())
    {
        return cx.err(c.span(), "center must be two finite numbers");
    }
    if let Some(a) = &l.angle {
        cx.finite(a, -1e6, 1e6, "angle (degrees)")?;
    }
    let center = || match &l.center {
        Some(c) => Ok(*c.get_ref()),
        None => expect_default(cx, l, "center", DefaultValue::point),
    };
    let angle = || num(&l.angle, "angle", -1e6, 1e6, "angle (degrees)");
    let density = || num(&l.density, "density", -1e9, 1e9, "density");
    let offset = || num(&l.offset, "offset", -1e9, 1e9, "offset");
    let shape = || -> Result<Shape, SourceError> {
        let dir = Shape::direction(angle()?);
        let at = center()?;
        match text(&l.shape, "shape")?.as_str() {
            "point" => Ok(Shape::Point { at }),
            "line" => Ok(Shape::Line { at, dir }),
            "cross" => Ok(Shape::Cross { at, dir }),
            "circle" => Ok(Shape::Circle { at, radius: num(&l.radius, "radius", 0.0, 1e6, "radius")? }),
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
            palette: required_pal()?,
            density: density()?,
            offset: offset()?,
            transfer: match &l.transfer {
                Some(t) => *t.get_ref(),
                None => expect_default(cx, l, "transfer", DefaultValue::transfer)?,
            },
            interior: colour(&l.interior, "interior")?,
        },
        "histogram" => Coloring::Histogram {
            palette: required_pal()?,
            cycles: density()?,
            offset: offset()?,
            interior: colour(&l.interior, "interior")?,
        },
        "distance" => {
            let style = match text(&l.style, "style")?.as_str() {
                "soft" => DistanceStyle::Soft { k: num(&l.k, "k", 0.0, 1e12, "k")? },
                "linear" => DistanceStyle::Linear { density: density()? },
                "log" => DistanceStyle::Log { density: density()? },
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
            Coloring::Distance { style, palette: pal()?, offset: offset()? }
        }
        "boundary" => Coloring::Boundary {
            width: num(&l.width, "width", 0.0, 1e6, "width (pixels)")?,
            color: colour(&l.color, "color")?,
        },
        "slope" => Coloring::Slope {
            light: Light::new(
                angle()?,
                num(&l.height, "height", 0.0, 1e6, "height")?,
                num(&l.strength, "strength", 0.0, 1.0, "strength")?,
            ),
        },
        "binary" => Coloring::Binary {
            colors: match &l.colors {
                None => {
                    let [a, b] = expect_default(cx, l, "colors", DefaultValue::colors)?;
                    let one = |s: &str| expect_default(cx, l, "colors", |_| linear_colour(s));
                    [one(a)?, one(b)?]
                }
                Some(c) => {
                    let [a, b] = c.get_ref();
                    let one = |s: &String| cx.colour(&Spanned::new(c.span(), s.clone()));
                    [one(a)?, one(b)?]
                }
            },
        },
        "angle" => Coloring::Angle { palette: required_pal()?, density: density()?, offset: offset()? },
        "stripe" => {
            let frequency = num(&l.frequency, "frequency", -1e6, 1e6, "frequency")?;
            Coloring::Stripe {
                trap: push(Trap::Stripe(Stripe { frequency })),
                palette: required_pal()?,
                density: density()?,
                offset: offset()?,
            }
        }
        "trap" => {
            let s = shape()?;
            Coloring::TrapDistance {
                trap: push(Trap::Geometric(s)),
                palette: required_pal()?,
                density: density()?,
                offset: offset()?,
            }
        }
        "ifs" => {
            let fold = match &l.fold_offset {
                Some(f) if f.get_ref().iter().all(|v| v.is_finite() && v.abs() <= 100.0) => *f.get_ref(),
                Some(f) => return cx.err(f.span(), "fold_offset must be three numbers in [-100, 100]"),
                None => expect_default(cx, l, "fold_offset", DefaultValue::triple)?,
            };
            let params = IfsParams {
                offset: fold.map(|v| v as f32),
                z: num(&l.slice, "slice", -100.0, 100.0, "slice")? as f32,
                iterations: match &l.iterations {
                    Some(n) => cx.range_i(n, 1, 1000, "iterations")?,
                    None => expect_default(cx, l, "iterations", DefaultValue::integer)?,
                } as u32,
                strength: num(&l.strength, "strength", 0.0, 1e6, "strength")? as f32,
                decay: num(&l.decay, "decay", 1e-3, 1e6, "decay")? as f32,
                scale: num(&l.scale, "scale", 1e-12, 1e12, "scale")? as f32,
            };
            Coloring::Ifs { trap: push(Trap::Ifs(params)), palette: pal()?, density: density()?, offset: offset()? }
        }
        "interior" => {
            let fill = if l.palette.is_some() {
                let s = shape()?;
                InteriorFill::Trap {
                    trap: push(Trap::Geometric(s)),
                    palette: required_pal()?,
                    density: density()?,
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
                InteriorFill::Solid(colour(&l.color, "color")?)
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
            let bitmap = bitmaps(&path).or_else(|e| cx.err(image.span(), format!("cannot load bitmap: {e}")))?;
            let size = num(&l.size, "size", 1e-300, 1e6, "size")?;
            let frame = frame(cx, l, bitmap.width)?;
            let a = angle()?.to_radians();
            Coloring::BitmapTrap {
                trap: push(Trap::Bitmap(BitmapTrap {
                    bitmap: Arc::new(bitmap),
                    center: center()?,
                    size,
                    rotation: [a.cos(), a.sin()],
                    threshold: num(&l.threshold, "threshold", 0.0, 1.0, "threshold")? as f32,
                    frame,
                })),
            }
        }
    };
    let opacity = num(&l.opacity, "opacity", 0.0, 1.0, "opacity")? as f32;
    let blend = match &l.blend {
        Some(b) => *b.get_ref(),
        None => expect_default(cx, l, "blend", DefaultValue::blend)?,
    };
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
        Some(f) => cx.range_i(f, 0, i64::from(u32::MAX), "frame")?,
        None => expect_default(cx, l, "frame", DefaultValue::integer)?,
    } as u32;
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
        None => MASK_FEATHER,
    };
    Ok(Mask { quantity: *quantity, above, below, feather, invert: raw.invert.as_ref().is_some_and(|v| *v.get_ref()) })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::raw::KeyValueMut;
    use crate::trap::Bitmap;

    /// `--palette` and the viewer's palette menu reach the layers that use a palette: the
    /// kinds that have one by default, and any layer that names one (IFS and distance
    /// included); not the layers that are grey, solid or white without one.
    #[test]
    fn a_palette_for_every_layer_reaches_the_layers_that_use_one() {
        let with = |kind: &str, palette: Option<&str>| {
            let mut l = LayerRaw::of_kind(kind);
            l.palette = palette.map(|p| Spanned::new(0..0, p.to_string()));
            uses_palette(&l)
        };
        for kind in ["smooth", "histogram", "angle", "stripe", "trap"] {
            assert!(with(kind, None), "{kind}");
        }
        for kind in ["distance", "interior", "ifs"] {
            assert!(!with(kind, None), "{kind} without a palette");
            assert!(with(kind, Some("ice")), "{kind} with a palette");
        }
        for kind in ["boundary", "slope", "binary"] {
            assert!(!with(kind, None), "{kind}");
        }
    }

    #[test]
    fn every_kind_key_is_declared_and_every_declared_key_is_taken() {
        for (kind, keys) in LAYER_KINDS {
            for key in keys {
                assert!(LayerRaw::KEYS.contains(key), "`{key}` of `{kind}` is not a declared layer key");
                assert!(!COMMON_KEYS.contains(key), "`{key}` is listed for `{kind}` but every kind takes it");
            }
        }
        for key in LayerRaw::KEYS {
            assert!(
                COMMON_KEYS.contains(key) || LAYER_KINDS.iter().any(|(_, keys)| keys.contains(key)),
                "declared key `{key}` is taken by no kind"
            );
        }
        for key in COMMON_KEYS {
            assert!(LayerRaw::KEYS.contains(&key), "`{key}` is not a declared layer key");
        }
    }

    fn with(mut l: LayerRaw, edit: impl FnOnce(&mut LayerRaw)) -> LayerRaw {
        edit(&mut l);
        l
    }

    fn at<T>(v: T) -> Option<Spanned<T>> {
        Some(Spanned::new(0..0, v))
    }

    fn text(s: &str) -> Option<Spanned<String>> {
        at(s.to_string())
    }

    /// A layer of every kind, and of every distance style (whose defaults differ).
    fn every_kind() -> Vec<LayerRaw> {
        let mut all: Vec<LayerRaw> = LAYER_KINDS.iter().map(|(kind, _)| LayerRaw::of_kind(kind)).collect();
        for style in ["soft", "linear", "log"] {
            all.push(with(LayerRaw::of_kind("distance"), |l| l.style = text(style)));
        }
        all
    }

    /// Every key a kind takes (what an editor shows for it) has a default of the key's type
    /// or says what leaving it out means; keys the kind does not take have none.
    #[test]
    fn every_key_a_kind_takes_has_a_default_of_its_type() {
        for l in every_kind() {
            let kind = l.kind.get_ref().clone();
            let takes = kind_keys(&kind).expect("a known kind");
            let mut probe = l.clone();
            for (key, field) in probe.fields_mut() {
                let default = default_value(&l, key);
                if !COMMON_KEYS.contains(&key) && !takes.contains(&key) {
                    assert_eq!(default, None, "`{kind}` does not take `{key}`");
                    continue;
                }
                let Some(default) = default else { panic!("no default for `{key}` of `{kind}`") };
                use DefaultValue as D;
                use KeyValueMut as K;
                let same_type = matches!(
                    (field, default),
                    (_, D::Unset(_))
                        | (K::Number(_), D::Number(_))
                        | (K::Integer(_), D::Integer(_))
                        | (K::Text(_), D::Text(_))
                        | (K::Colors(_), D::Colors(_))
                        | (K::Point(_), D::Point(_))
                        | (K::Triple(_), D::Triple(_))
                        | (K::Transfer(_), D::Transfer(_))
                        | (K::Blend(_), D::Blend(_))
                );
                assert!(same_type, "the default of `{key}` for `{kind}` is {default:?}, not of the key's type");
                match (key, default) {
                    ("interior" | "color", D::Text(c)) => assert!(linear_colour(c).is_some(), "{c}"),
                    (_, D::Colors(cs)) => assert!(cs.iter().all(|c| linear_colour(c).is_some()), "{cs:?}"),
                    ("palette", D::Text(p)) => assert!(palette::builtin_names().contains(&p), "{p}"),
                    _ => {}
                }
            }
        }
        // The colours written as text are exactly the ones validation once wrote as numbers.
        assert_eq!(linear_colour("#000000"), Some([0.0, 0.0, 0.0, 1.0]));
        assert_eq!(linear_colour("#ffffff"), Some([1.0; 4]));
    }

    /// `default_value`'s word for a key whose absence depends on the layer's other keys.
    #[test]
    fn distance_defaults_follow_the_style() {
        let d = |style: Option<&str>, key| {
            let mut l = LayerRaw::of_kind("distance");
            l.style = style.and_then(text);
            default_value(&l, key)
        };
        assert_eq!(d(None, "k"), Some(DefaultValue::Number(0.25)));
        assert!(matches!(d(None, "density"), Some(DefaultValue::Unset(_))));
        assert_eq!(d(Some("linear"), "density"), Some(DefaultValue::Number(0.05)));
        assert_eq!(d(Some("log"), "density"), Some(DefaultValue::Number(0.25)));
        assert!(matches!(d(Some("log"), "k"), Some(DefaultValue::Unset(_))));
        assert_eq!(default_value(&LayerRaw::of_kind("nope"), "blend"), None);
    }

    /// Validation reads its defaults from the table: a layer that leaves every key out gives
    /// the same layer and traps as one that writes out each default the table has.
    #[test]
    fn validation_uses_the_table() {
        let bitmap = |_: &Path| Ok(Bitmap { width: 4, height: 2, texels: vec![[1.0; 4]; 8] });
        let cx = Ctx::new("test", "");
        let mut layers = every_kind();
        // With the keys that switch the rest on: an interior layer's trap needs a palette,
        // a bitmap needs its image, and `frame` needs `frames`.
        for l in &mut layers {
            match l.kind.get_ref().as_str() {
                "interior" => l.palette = text("ocean"),
                "bitmap" => {
                    l.image = text("sheet.png");
                    l.frames = at(2);
                }
                _ => {}
            }
        }
        for l in layers {
            let mut explicit = l.clone();
            let mut written = 0;
            for (key, field) in explicit.fields_mut() {
                let Some(default) = default_value(&l, key) else { continue };
                match (field, default) {
                    (KeyValueMut::Number(v), DefaultValue::Number(x)) if v.is_none() => *v = at(x),
                    (KeyValueMut::Integer(v), DefaultValue::Integer(x)) if v.is_none() => *v = at(x),
                    (KeyValueMut::Text(v), DefaultValue::Text(x)) if v.is_none() => *v = at(x.to_string()),
                    (KeyValueMut::Colors(v), DefaultValue::Colors(x)) if v.is_none() => *v = at(x.map(str::to_string)),
                    (KeyValueMut::Point(v), DefaultValue::Point(x)) if v.is_none() => *v = at(x),
                    (KeyValueMut::Triple(v), DefaultValue::Triple(x)) if v.is_none() => *v = at(x),
                    (KeyValueMut::Transfer(v), DefaultValue::Transfer(x)) if v.is_none() => *v = at(x),
                    (KeyValueMut::Blend(v), DefaultValue::Blend(x)) if v.is_none() => *v = at(x),
                    _ => continue,
                }
                written += 1;
            }
            assert!(written >= 2, "{:?} wrote {written} defaults", l.kind.get_ref());
            let run = |l: LayerRaw| {
                let mut traps = Vec::new();
                let layer = layer(&cx, &Spanned::new(0..0, l), Path::new("."), &bitmap, 0.0, &mut traps)
                    .unwrap_or_else(|e| panic!("{e}"));
                (layer, format!("{traps:?}"))
            };
            assert_eq!(run(l.clone()), run(explicit), "{:?}", l.kind.get_ref());
        }
    }
}
