//! Validation: raw scene data to a typed [`Scene`], with located, explicit errors.

use std::path::Path;

use toml::Spanned;

use super::context::{BitmapLoader, Ctx};
use super::layer::{default_layer, layer};
use super::raw::{FormulaRaw, SceneFile, ViewRaw};
use super::{EngineChoice, FamilySpec, MAX_AA, MAX_ITER_LIMIT, MAX_LOG10_ZOOM, MAX_SAMPLES, MAX_SIDE, Scene};
use crate::compose::Stack;
use crate::field::transform::MAX_STRETCH_AMOUNT;
use crate::field::{Channel, ChannelSet};
use crate::formula::Formula;
use crate::num::Decimal;
use crate::orbit::interior::Detection;
use crate::orbit::{DEFAULT_BLA_TOLERANCE, Scale};
use crate::palette;
use crate::source::SourceError;

pub(super) fn validate(
    file: SceneFile,
    origin: &str,
    text: &str,
    base_dir: &Path,
    bitmaps: &BitmapLoader<'_>,
) -> Result<Scene, SourceError> {
    validate_in(file, &Ctx::new(origin, text), origin, base_dir, bitmaps)
}

/// [`validate`] with errors located by `cx` (in text, or by key path for a scene built in
/// code).
pub(super) fn validate_in(
    file: SceneFile,
    cx: &Ctx<'_>,
    origin: &str,
    base_dir: &Path,
    bitmaps: &BitmapLoader<'_>,
) -> Result<Scene, SourceError> {
    if *file.version.get_ref() != 1 {
        return cx
            .err(file.version.span(), format!("unsupported scene version {}; expected 1", file.version.get_ref()));
    }
    let (family, formula) = family(cx, &file.formula)?;
    let View { center, log10_radius, radius, scale, transform, projection } = view(cx, &file.view)?;
    let (width, height, aa) = size(cx, &file.view, &file.render.aa)?;
    let max_iter = max_iter(cx, &file.iteration.max)?;
    let escape_radius = cx.finite(&file.iteration.escape_radius, 2.0, 1e150, "iteration.escape_radius")?;
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
    let interior_detection = match file.render.interior_detection.as_ref().map(|b| *b.get_ref()) {
        None => Detection::Auto,
        Some(true) => Detection::On,
        Some(false) => Detection::Off,
    };
    let bg = cx.colour(&file.render.background)?;
    let cycle = match &file.render.cycle {
        Some(c) => cx.finite(c, -1e9, 1e9, "render.cycle")?,
        None => 0.0,
    };

    let mut traps = Vec::new();
    let mut layers = Vec::new();
    let raw_layers =
        if file.layers.is_empty() { vec![Spanned::new(0..0, default_layer())] } else { file.layers.clone() };
    for l in &raw_layers {
        layers.push(layer(cx, l, base_dir, bitmaps, cycle, &mut traps)?);
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
        // By default an EXR holds everything the layers read, so it recolours as rendered.
        None if traps.is_empty() => ChannelSet::default_exr(),
        None => {
            let mut set = ChannelSet::default_exr();
            set.insert(Channel::Traps);
            set
        }
        Some(list) => {
            let mut set = ChannelSet::default();
            for name in list.get_ref() {
                set.insert(name.parse::<Channel>().or_else(|e| cx.err(list.span(), e.to_string()))?);
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
        formula,
        center,
        log10_radius,
        radius,
        width,
        height,
        transform,
        projection,
        max_iter,
        escape_radius,
        aa,
        engine,
        bla,
        interior_detection,
        scale,
        stack: Stack { layers, background: [bg[0], bg[1], bg[2]] },
        traps,
        png_bits,
        channels,
        file,
    })
}

/// `[formula]`: the map, and whether the pixel is its parameter or its starting point.
pub(super) fn family(cx: &Ctx<'_>, formula: &FormulaRaw) -> Result<(FamilySpec, Formula), SourceError> {
    let kind = formula.kind.get_ref().as_str();
    let power = match &formula.power {
        Some(p) => match u32::try_from(*p.get_ref()) {
            Ok(v) if (2..=crate::formula::map::MAX_POWER).contains(&v) => Some(v),
            _ => {
                return cx
                    .err(p.span(), format!("`power` must be an integer from 2 to {}", crate::formula::map::MAX_POWER));
            }
        },
        None => None,
    };
    let at_power = |e: String| match &formula.power {
        Some(p) if e.contains("comes in") || e.contains("each phase") => cx.err(p.span(), e),
        _ => cx.err(formula.kind.span(), e),
    };
    let parsed = if kind == "julia" {
        if power.is_some_and(|p| p != 2) {
            return at_power("kind = \"julia\" is z² + c's Julia set; for another power write the family, e.g. kind = \"mandelbrot\", power = 3, and its c".into());
        }
        Formula::default()
    } else {
        match Formula::parse(kind, power) {
            Ok(f) => f,
            Err(e) => return at_power(e.0),
        }
    };
    let parsed = match &formula.a {
        None => parsed,
        Some(a) if !parsed.phases().iter().any(|p| p.kind.takes_a()) => {
            return cx.err(
                a.span(),
                format!(
                    "`a` is the coefficient of the families that take one (redshift-rider-1, ...); `{parsed}` has none"
                ),
            );
        }
        Some(a) => match *a.get_ref() {
            [re, im] if re.is_finite() && im.is_finite() => parsed.with_a([re, im]),
            _ => return cx.err(a.span(), "`a` must be two finite numbers [re, im]"),
        },
    };
    let family = match (&formula.c, kind) {
        (Some(c), _) => FamilySpec::Julia { c: cx.pair(c, "Julia parameter c")? },
        (None, "julia") => {
            return cx.err(formula.kind.span(), "a Julia set needs its parameter: c = [\"re\", \"im\"]");
        }
        (None, _) => FamilySpec::Mandelbrot,
    };
    Ok((family, parsed))
}

/// The `[view]` keys other than the size, validated.
pub(super) struct View {
    pub(super) center: [Decimal; 2],
    pub(super) log10_radius: f64,
    pub(super) radius: f64,
    pub(super) scale: Scale,
    pub(super) transform: crate::field::Transform,
    pub(super) projection: crate::field::Projection,
}

/// `[view]`: centre, scale, rotation, stretch and projection.
pub(super) fn view(cx: &Ctx<'_>, view: &ViewRaw) -> Result<View, SourceError> {
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
    if log10_radius < -MAX_LOG10_ZOOM {
        return cx.err(
            view.zoom.as_ref().or(view.radius.as_ref()).map_or(0..0, |s| s.span()),
            format!(
                "the view is deeper than deepfield renders: zoom is limited to 1e{MAX_LOG10_ZOOM:.0} (a reference orbit there needs {:.0} million bits per number, and deeper spacings leave the exponent range of the extended floats)",
                MAX_LOG10_ZOOM * std::f64::consts::LOG2_10 / 1e6
            ),
        );
    }
    if log10_radius > 3.0 {
        return cx.err(
            view.zoom.as_ref().or(view.radius.as_ref()).map_or(0..0, |s| s.span()),
            "the view is wider than 1000 units; zoom must be at least 0.002",
        );
    }
    if let Some(a) = &view.rotate {
        cx.finite(a, -1e6, 1e6, "view.rotate (degrees)")?;
    }
    if let Some(a) = &view.stretch_angle {
        cx.finite(a, -1e6, 1e6, "view.stretch_angle (degrees)")?;
    }
    if let Some(a) = &view.stretch_amount {
        cx.finite(a, -MAX_STRETCH_AMOUNT, MAX_STRETCH_AMOUNT, "view.stretch_amount (log2 of the factor)")?;
    }
    let transform = view.transform();
    let projection = match &view.exponential_map {
        None => crate::field::Projection::Flat,
        Some(f) => {
            let factor = cx.finite(f, 1.0, 1e6, "view.exponential_map (zoom factor per strip)")?;
            if factor <= 1.0 {
                return cx.err(f.span(), "view.exponential_map must be above 1 (the zoom factor from a strip's outer edge to its inner edge)");
            }
            if view.stretch_amount.as_ref().is_some_and(|a| *a.get_ref() != 0.0) {
                return cx.err(
                    f.span(),
                    "an exponential map cannot be stretched (view.stretch_amount); rotate it if needed",
                );
            }
            crate::field::Projection::Exponential { ln_factor: factor.ln() }
        }
    };
    Ok(View { center, log10_radius, radius, scale, transform, projection })
}

/// The image size and supersampling: width, height and aa, within the sample limit.
pub(super) fn size(cx: &Ctx<'_>, view: &ViewRaw, aa: &Spanned<i64>) -> Result<(u32, u32, u32), SourceError> {
    let width = cx.range_i(&view.width, 1, MAX_SIDE, "width")? as u32;
    let height = cx.range_i(&view.height, 1, MAX_SIDE, "height")? as u32;
    let aa = cx.range_i(aa, 1, MAX_AA, "render.aa")? as u32;
    let samples = width as u64 * height as u64 * (aa as u64).pow(2);
    if samples > MAX_SAMPLES {
        return cx.err(view.width.span(), format!("{width}x{height} with {aa}x{aa} supersampling is {samples} samples; at most {MAX_SAMPLES} are supported"));
    }
    Ok((width, height, aa))
}

/// `iteration.max`.
pub(super) fn max_iter(cx: &Ctx<'_>, max: &Spanned<i64>) -> Result<u32, SourceError> {
    Ok(cx.range_i(max, 1, MAX_ITER_LIMIT as i64, "iteration.max")? as u32)
}

/// Rewrites the files a valid scene refers to (bitmaps, palette files) as absolute paths,
/// so the scene embedded in an output re-renders from any folder. Built-in palette names
/// stay names.
pub(super) fn anchor_paths(file: &mut SceneFile, base_dir: &Path) {
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
