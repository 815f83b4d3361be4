//! Kalles Fraktaler `.kfr` locations, converted to deepfield scene text.
//!
//! A `.kfr` is what Kalles Fraktaler 2+ (KF) writes with "Save location": one `Key: value`
//! pair per line, CRLF line ends, keys case-sensitive, no sections and no comments. KF 2.15
//! writes, in this order, `Re`, `Im`, `Zoom`, `Iterations`, `IterDiv`, `SmoothMethod`,
//! `SmoothingMethod`, `BailoutRadiusPreset`, `BailoutRadiusCustom`, `BailoutNormPreset`,
//! `BailoutNormCustom`, `ColorMethod`, `Differences`, `ColorOffset`, `ColorPhaseStrength`,
//! `Colors`, `InteriorColor`, `Smooth`, `Flat`, `MultiColor`, `BlendMC`, `MultiColors`,
//! `Power`, `FractalType`, `Slopes`, `SlopePower`, `SlopeRatio`, `SlopeAngle`, `real`,
//! `imag`, `SeedR`, `SeedI`, `FactorAR`, `FactorAI`, `Period`, `Texture*`,
//! (`UseHybridFormula`, `HybridFormula`), `RotateAngle`, `StretchAngle`, `StretchAmount`,
//! `ImagPointsUp`, (`UseOpenGL`, `GLSL`, `UseSRGB`), `TriangleInequalityAverage`, `Version`.
//! Older files carry `Rotate` and `Ratio` instead of the transform keys. (Source: KF's
//! `CFraktalSFT::ToText` / `OpenString` in `fraktal_sft/Parameter.cpp`, old and 2.15 versions;
//! the reflection convention of `ImagPointsUp` as Fraktaler-3's `.kfr` import reads it.)
//!
//! What is mapped:
//!
//! | `.kfr` | scene | notes |
//! |---|---|---|
//! | `Re`, `Im` | `[view] center` | the decimal text is copied verbatim, every digit kept; absent: 0 |
//! | `Zoom` | `[view] zoom` | same convention: the image height spans `4 / Zoom` (KF: half-height `2 / Zoom`); absent: 1 |
//! | `FractalType`, `Power` | `[formula] kind`, `power` | through the table of families ([`crate::formula::kind::KINDS`]); see `scene::kfr_formula` |
//! | `UseHybridFormula`, `HybridFormula` | `[formula] kind = "a,b^3,..."` | when each group is one family; see `scene::kfr_hybrid` |
//! | `Iterations` | `[iteration] max` | optional (KF keeps its current value when absent); 1 ..= 2^32 - 2 |
//! | `TargetWidth`, `TargetHeight` | `[view] width`, `height` | KF 2.15 output size; these are `.kfs` keys, present when settings and location were saved together (PNG/EXR metadata) |
//! | `ImageWidth`, `ImageHeight` | `[view] width`, `height` | used when no `Target*` key is given (older KF); otherwise 800 x 600 |
//!
//! A file without `Re`, `Im` or `Zoom` (KF's formula presets have none) opens where KF would
//! open it: KF keeps its current view for a missing key (`OpenString` starts from `GetRe`,
//! `GetIm`, `GetZoom`), and the view it starts with is 0 + 0i at zoom 1 (`WM_CREATE` in
//! `fraktal_sft/main.cpp`: `SetPosition(0, 0, 2, 640, 360)`, radius 2; its "Reset" is
//! `SetPosition("0", "0", "1")`). The generated text says which keys were missing.
//!
//! What is checked, because deepfield cannot draw it and silently dropping it would give a
//! different picture: the formula must be one of deepfield's families (a `FractalType` KF
//! 2.15 has but deepfield does not is refused by KF's name, e.g. "FractalType 52
//! (General Quadratic Minus) is not one deepfield draws"), at a power the
//! family comes in; a hybrid must be a cycle of whole families; `SeedR`/`SeedI` must be 0
//! (KF's seed is the starting z_0 of the orbit, not a Julia parameter).
//!
//! The view's rotation and stretch are the scene's own keys, with KF 2.15's meaning
//! (`field::transform`): `RotateAngle`, `StretchAngle`, `StretchAmount` become `[view]
//! rotate`, `stretch_angle`, `stretch_amount` as written. Files from before KF 2.14 carry
//! `Rotate` (degrees) and `Ratio` (360 for square pixels) instead; they convert as KF's own
//! compatibility code read them: a stretch by sqrt(360 / Ratio) at angle `Rotate`, turned
//! back by `Rotate` (rotate = −Rotate, stretch_angle = Rotate, stretch_amount =
//! log2(360 / Ratio) / 2).
//!
//! KF 2.15 has no Julia mode: no key, formula or hybrid holds a fixed c (every reference and
//! perturbation loop adds the pixel's c; `SeedR + i SeedI` is only the orbit's z_0, and
//! `FactorAR`/`FactorAI` the coefficient a of some families). So a `.kfr` never converts to
//! `[formula] c`: it is always the Mandelbrot-type form of its family.
//!
//! Colours come with the location, near enough to open looking as its author saved it: a
//! `Colors` line becomes one `smooth` layer whose `palette` is the `.kfr` file itself (its
//! file name, resolved in its own folder: the palette importer reads `Colors` and
//! `ColorOffset` as for a `.kfp`, see `palette::import`), at `density = 1 / (1024 IterDiv)`
//! (KF spreads its keys over a table of 1024 entries indexed by iterations / `IterDiv`),
//! with `ColorMethod` 0, 1, 2, 3, 9 as the transfers `linear`, `sqrt`, `cbrt`, `log`,
//! `log-log`, and `InteriorColor` (B,G,R bytes like the keys) as the layer's `interior`.
//! KF's other colour methods (distance, stretched, atan, fourth root) fall back to `linear`,
//! and the generated text says so.
//!
//! What is ignored: the rest of KF's colouring (`Differences`, `MultiColors`, `Slopes*`,
//! `Texture*`, `Flat`, `GLSL`, ...), smoothing and bailout choices (deepfield's escape radius
//! is its own; `real`/`imag` are the bailout norm's weights), `Period`, `FactorAR`/`FactorAI`
//! for the families without a coefficient (the TheRedshiftRider families, `redshift-rider-*`,
//! take them as `[formula] a`, 1 + 0i where missing, as KF reads them),
//! `Version`, and any key this module does not know. A file without `Colors` gets deepfield's default colouring.
//!
//! Two differences remain (the first is stated in the generated text): without
//! `ImagPointsUp: 1` (KF 2.15.4 and later) KF draws the imaginary axis pointing down, so
//! deepfield's image (axis up) is KF's mirrored top to bottom; and KF's sample grid may sit
//! half a pixel from deepfield's pixel centres (invisible at any zoom).
//!
//! KF turns no formula over by itself. Its one pixel-to-plane map serves every formula
//! (`CFraktalSFT::GetPixelCoordinates` in `fraktal_sft/fraktal_sft.cpp`, Karl Runmo and
//! Claude Heiland-Allen, Kalles Fraktaler 2: x = centre + scale (m00 u + m01 v), y = centre +
//! scale (m10 u + m11 v), with v the row counted downwards from the middle and m the view's
//! transform, whose only reflection is `ImagPointsUp`'s: `OpenString` sets
//! `polar2(ImagPointsUp ? -1 : 1, ...)`, whatever the `FractalType`); the formulas add that
//! c unchanged (`formula/formula.xml`, e.g. Burning Ship: `Xin = abs(2 * Xr * Xi) + Ci`;
//! nothing in `formula.xsl`, `hybrid.cpp` or the reference code negates `Ci`). So the Burning
//! Ship's ship stands upright in KF because of the axis convention alone, and the centre a
//! `.kfr` names is the same point of the plane here. For families symmetric about the real
//! axis (no fold of the imaginary part) deepfield's mirror image is KF's picture of the
//! conjugate centre; for the others (Burning Ship, Buffalo, the partial folds of y, and
//! hybrids using them) no centre gives KF's picture, since deepfield's view turns and
//! stretches but does not reflect, and the generated text says that it is KF's upside down.
//!
//! The lines are read by [`crate::kf_text`] (shared with the palette importer): CRLF or LF
//! line ends, a leading byte-order mark, blank lines and spaces around keys and values are
//! allowed; a line without a `:` is an error, and so is a key given twice among those this
//! module reads (KF would silently take the first).

use super::kfr_formula;
pub use super::kfr_formula::{REFUSED, kf_type_name};
use crate::kf_text::{Entry, KfText};
use crate::num::Decimal;
use crate::scene::{MAX_ITER_LIMIT, MAX_SIDE};
use crate::source::SourceError;

/// Width used when the file names none.
const DEFAULT_WIDTH: u64 = 800;
/// Height used when the file names none.
const DEFAULT_HEIGHT: u64 = 600;
/// KF's opening view (`Re`, `Im`, `Zoom`), used for keys a file leaves out.
const DEFAULT_VIEW: [&str; 3] = ["0", "0", "1"];

/// Keys this module reads (each may appear once).
const KNOWN: &[&str] = &[
    "Re",
    "Im",
    "Zoom",
    "Iterations",
    "FractalType",
    "Power",
    "UseHybridFormula",
    "HybridFormula",
    "SeedR",
    "SeedI",
    "RotateAngle",
    "Rotate",
    "StretchAngle",
    "StretchAmount",
    "Ratio",
    "ImagPointsUp",
    "TargetWidth",
    "TargetHeight",
    "ImageWidth",
    "ImageHeight",
    "Colors",
    "IterDiv",
    "ColorMethod",
    "InteriorColor",
];

/// The parsed lines, with error construction bound to the source.
pub(super) struct Kfr<'a> {
    origin: &'a str,
    text: &'a str,
    lines: KfText<'a>,
}

impl<'a> Kfr<'a> {
    fn parse(origin: &'a str, text: &'a str) -> Result<Self, SourceError> {
        let lines = KfText::parse(text, KNOWN).map_err(|e| {
            let at = e.at();
            SourceError::at(origin, text, Some(at..at), e.to_string())
        })?;
        Ok(Self { origin, text, lines })
    }

    pub(super) fn get(&self, key: &str) -> Option<&Entry<'a>> {
        self.lines.get(key)
    }

    pub(super) fn error_at(&self, at: usize, message: impl Into<String>) -> SourceError {
        SourceError::at(self.origin, self.text, Some(at..at), message)
    }

    /// A decimal key, or `default` (KF's opening view) when the file has none.
    fn decimal_or(&self, key: &str, what: &str, default: &str) -> Result<(Decimal, Option<&Entry<'a>>), SourceError> {
        let Some(e) = self.get(key) else {
            return Ok((Decimal::parse(default).expect("a decimal default"), None));
        };
        let d = Decimal::parse(e.value).map_err(|err| self.error_at(e.value_at, format!("`{key}` ({what}): {err}")))?;
        Ok((d, Some(e)))
    }

    /// An optional decimal key that must be zero if given.
    fn must_be_zero(&self, key: &str, why: &str) -> Result<(), SourceError> {
        let Some(e) = self.get(key) else { return Ok(()) };
        let d = Decimal::parse(e.value).map_err(|err| self.error_at(e.value_at, format!("`{key}`: {err}")))?;
        if d.is_zero() {
            Ok(())
        } else {
            Err(self.error_at(e.value_at, format!("`{key}: {}` {why}; expected 0", e.value)))
        }
    }

    /// An optional integer key, within `lo ..= hi`.
    pub(super) fn integer(&self, key: &str, lo: u64, hi: u64, what: &str) -> Result<Option<u64>, SourceError> {
        let Some(e) = self.get(key) else { return Ok(None) };
        let digits = e.value.strip_prefix('+').unwrap_or(e.value);
        if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return Err(self.error_at(
                e.value_at,
                format!("`{key}` ({what}) must be a whole number from {lo} to {hi}, found `{}`", e.value),
            ));
        }
        match digits.parse::<u64>() {
            Ok(n) if (lo..=hi).contains(&n) => Ok(Some(n)),
            _ => {
                Err(self.error_at(e.value_at, format!("`{key}` ({what}) must be from {lo} to {hi}, found {}", e.value)))
            }
        }
    }
}

/// Converts the text of a Kalles Fraktaler `.kfr` location into deepfield scene TOML.
///
/// `origin` names the file in errors and in the generated header comment. Errors carry the
/// line and column of the offending value (or the end of the text for a missing key) and say
/// what was expected. The result parses as a `version = 1` scene: a Mandelbrot view with the
/// centre and zoom copied digit for digit, `[iteration] max` from `Iterations`, and, when
/// the file has `Colors`, a `smooth` layer coloured by the file itself (the last component
/// of `origin` names it, so `origin` is the file's path; see the module documentation).
pub fn kfr_to_toml(origin: &str, text: &str) -> Result<String, SourceError> {
    let kfr = Kfr::parse(origin, text)?;

    if kfr.lines.entries().is_empty() {
        return Err(kfr.error_at(0, "not a Kalles Fraktaler location: the file has no `Key: value` lines"));
    }
    let (re, re_entry) = kfr.decimal_or("Re", "the real part of the view centre", DEFAULT_VIEW[0])?;
    let (im, im_entry) = kfr.decimal_or("Im", "the imaginary part of the view centre", DEFAULT_VIEW[1])?;
    let (zoom, zoom_entry) = kfr.decimal_or("Zoom", "the zoom: the image height spans 4 / Zoom", DEFAULT_VIEW[2])?;
    if let Some(e) = zoom_entry.filter(|_| zoom.is_zero() || zoom.is_negative()) {
        return Err(kfr.error_at(e.value_at, format!("`Zoom` must be positive, found {}", e.value)));
    }
    let missing: Vec<&str> = [("Re", re_entry), ("Im", im_entry), ("Zoom", zoom_entry)]
        .iter()
        .filter(|(_, e)| e.is_none())
        .map(|(k, _)| *k)
        .collect();
    let max_iter = kfr.integer("Iterations", 1, MAX_ITER_LIMIT, "the maximum iteration count")?;

    let chosen = kfr_formula::formula(&kfr)?;
    let seed_why =
        "starts every orbit at a non-zero z_0 (KF's seed is not a Julia parameter; deepfield's Mandelbrot starts at 0)";
    kfr.must_be_zero("SeedR", seed_why)?;
    kfr.must_be_zero("SeedI", seed_why)?;
    let transform = view_transform(&kfr)?;
    let imag_up = kfr.integer("ImagPointsUp", 0, 1, "1 when the imaginary axis points up")? == Some(1);

    let side = |target: &str, image: &str, default: u64| -> Result<u64, SourceError> {
        let what = "the image size in pixels";
        Ok(match kfr.integer(target, 1, MAX_SIDE as u64, what)? {
            Some(n) => n,
            None => kfr.integer(image, 1, MAX_SIDE as u64, what)?.unwrap_or(default),
        })
    };
    let width = side("TargetWidth", "ImageWidth", DEFAULT_WIDTH)?;
    let height = side("TargetHeight", "ImageHeight", DEFAULT_HEIGHT)?;

    let name: String = origin.chars().map(|c| if c.is_control() { '?' } else { c }).collect();
    let mut out = String::new();
    out.push_str(&format!("# Converted from the Kalles Fraktaler location {name}.\n"));
    if !imag_up {
        out.push_str(
            "# The file has no `ImagPointsUp: 1`, so KF draws it with the imaginary axis pointing down;\n\
             # deepfield's points up, so this image is KF's mirrored top to bottom.\n",
        );
        if !kfr_formula::symmetric(&chosen.formula) {
            out.push_str(&format!(
                "# `{}` is not symmetric about the real axis and deepfield's view cannot be reflected,\n\
                 # so no centre shows KF's picture: this one is KF's upside down.\n",
                chosen.formula
            ));
        }
    }
    if !missing.is_empty() {
        out.push_str(&format!(
            "# The file has no `{}` (a formula preset): KF's opening view, centre {} + {}i, zoom {}.\n",
            missing.join("`, `"),
            DEFAULT_VIEW[0],
            DEFAULT_VIEW[1],
            DEFAULT_VIEW[2]
        ));
    }
    for note in &chosen.notes {
        out.push_str(&format!("# {}\n", note.replace(['\n', '\r'], " ")));
    }
    let layer = colour_layer(&kfr, &name)?;
    if layer.is_none() {
        out.push_str("# The file has no `Colors`: deepfield's default colouring.\n");
    }
    out.push_str("version = 1\n\n[formula]\n");
    match chosen.formula.phases() {
        [single] => {
            out.push_str(&format!("kind = \"{}\"\n", single.kind.name()));
            if single.power != single.kind.default_power() {
                out.push_str(&format!("power = {}\n", single.power));
            }
        }
        _ => out.push_str(&format!("kind = \"{}\"\n", chosen.formula)),
    }
    if let Some([re, im]) = chosen.formula.a() {
        out.push_str(&format!("a = [{re:?}, {im:?}]\n"));
    }
    out.push_str("\n[view]\n");
    // Decimal texts hold only digits, signs, '.', 'e' and 'E': safe inside TOML strings.
    out.push_str(&format!("center = [\"{}\", \"{}\"]\n", re.text(), im.text()));
    out.push_str(&format!("zoom = \"{}\"\n", zoom.text()));
    out.push_str(&format!("width = {width}\nheight = {height}\n"));
    for (key, value) in ["rotate", "stretch_angle", "stretch_amount"].iter().zip(transform) {
        if value != 0.0 {
            out.push_str(&format!("{key} = {value:?}\n"));
        }
    }
    if let Some(n) = max_iter {
        out.push_str(&format!("\n[iteration]\nmax = {n}\n"));
    }
    if let Some(layer) = layer {
        out.push_str(&layer);
    }
    Ok(out)
}

/// `[rotate, stretch_angle, stretch_amount]` from KF 2.15's keys or, failing those, the old
/// `Rotate` and `Ratio` (see the module documentation).
fn view_transform(kfr: &Kfr<'_>) -> Result<[f64; 3], SourceError> {
    let number = |key: &str| -> Result<Option<(f64, usize)>, SourceError> {
        let Some(e) = kfr.get(key) else { return Ok(None) };
        let d = Decimal::parse(e.value).map_err(|err| kfr.error_at(e.value_at, format!("`{key}`: {err}")))?;
        let v = d.to_f64();
        if !(v.is_finite() && v.abs() <= 1e6) {
            return Err(kfr.error_at(e.value_at, format!("`{key}: {}` is out of range; expected at most 1e6", e.value)));
        }
        Ok(Some((v, e.value_at)))
    };
    let new_style = ["RotateAngle", "StretchAngle", "StretchAmount"].iter().any(|k| kfr.get(k).is_some());
    let out = if new_style {
        let v = |k| number(k).map(|x| x.map_or(0.0, |(v, _)| v));
        let (rotate, angle, amount) = (v("RotateAngle")?, v("StretchAngle")?, v("StretchAmount")?);
        // Without a stretch its angle means nothing (KF 2.15 writes one anyway).
        [rotate, if amount == 0.0 { 0.0 } else { angle }, amount]
    } else {
        let rotate = number("Rotate")?.map_or(0.0, |(v, _)| v);
        let amount = match number("Ratio")? {
            None => 0.0,
            // Ratio 360.000000 (square pixels) is exactly no stretch.
            Some((r, _)) if r > 0.0 => (360.0 / r).log2() / 2.0,
            Some((_, at)) => {
                return Err(kfr.error_at(at, "`Ratio` must be positive (360 is square pixels)"));
            }
        };
        [-rotate, if amount == 0.0 { 0.0 } else { rotate }, amount]
    };
    if out[2].abs() > crate::field::transform::MAX_STRETCH_AMOUNT {
        let at = kfr.get("StretchAmount").or(kfr.get("Ratio")).map_or(0, |e| e.value_at);
        return Err(kfr.error_at(
            at,
            format!(
                "the stretch 2^{} is beyond deepfield's limit of 2^{}",
                out[2],
                crate::field::transform::MAX_STRETCH_AMOUNT
            ),
        ));
    }
    // Negative zero reads as zero.
    Ok(out.map(|v| if v == 0.0 { 0.0 } else { v }))
}

/// KF's `ColorMethod` numbers that are one of deepfield's transfers.
const COLOR_METHODS: &[(u64, &str)] = &[(0, "linear"), (1, "sqrt"), (2, "cbrt"), (3, "log"), (9, "log-log")];

/// The `[[layer]]` text that colours the view as the file's `Colors` do, or `None` when it
/// has none. `name` is the file's path (its last component is what the layer names).
fn colour_layer(kfr: &Kfr<'_>, name: &str) -> Result<Option<String>, SourceError> {
    match kfr.get("Colors") {
        Some(e) if !e.value.trim().trim_end_matches(',').trim().is_empty() => {}
        _ => return Ok(None),
    }
    let file = std::path::Path::new(name).file_name().map_or_else(|| name.to_string(), |f| f.to_string_lossy().into());
    let iter_div = match kfr.get("IterDiv") {
        None => 1.0,
        Some(e) => {
            let d =
                Decimal::parse(e.value).map_err(|err| kfr.error_at(e.value_at, format!("`IterDiv`: {err}")))?.to_f64();
            if !(d.is_finite() && d > 0.0) {
                return Err(kfr.error_at(
                    e.value_at,
                    format!("`IterDiv: {}` must be a positive number (iterations per colour table entry)", e.value),
                ));
            }
            d
        }
    };
    let method = kfr.integer("ColorMethod", 0, u32::MAX as u64, "KF's colour method")?.unwrap_or(0);
    let mut out =
        String::from("\n# Colours from the file: its `Colors` and `ColorOffset` (the palette is the file itself),\n");
    out.push_str("# one cycle per 1024 x `IterDiv` iterations as in KF.\n");
    let transfer = match COLOR_METHODS.iter().find(|(m, _)| *m == method) {
        Some((_, t)) => t,
        None => {
            out.push_str(&format!(
                "# KF's `ColorMethod: {method}` (a distance, stretched, atan or fourth-root method) is drawn as linear iterations.\n"
            ));
            "linear"
        }
    };
    out.push_str("[[layer]]\nkind = \"smooth\"\n");
    out.push_str(&format!("palette = {}\n", toml::Value::String(file)));
    out.push_str(&format!("density = {:e}\n", 1.0 / (1024.0 * iter_div)));
    out.push_str(&format!("transfer = \"{transfer}\"\n"));
    if let Some(e) = kfr.get("InteriorColor") {
        let bytes: Vec<&str> = e.value.split(',').map(str::trim).filter(|w| !w.is_empty()).collect();
        let parsed: Option<Vec<u8>> = bytes.iter().map(|w| w.parse::<u8>().ok()).collect();
        match parsed.as_deref() {
            Some([b, g, r]) => out.push_str(&format!("interior = \"#{r:02x}{g:02x}{b:02x}\"\n")),
            _ => {
                return Err(kfr.error_at(
                    e.value_at,
                    format!("`InteriorColor: {}`: expected three colour values 0-255 (B,G,R)", e.value),
                ));
            }
        }
    }
    Ok(Some(out))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A location as KF 2.15 saves it: CRLF, every key, colour data included.
    const KF_215: &str = "Re: -1.759817130804847813610825010561798238243999999999999999999800\r\n\
Im: -0.012593310799749865383746631843264858450340000000000000000000\r\n\
Zoom: 1.00000000000E14\r\n\
Iterations: 4036\r\n\
IterDiv: 0.010000\r\n\
SmoothMethod: 0\r\n\
SmoothingMethod: 0\r\n\
BailoutRadiusPreset: 0\r\n\
BailoutRadiusCustom: 2\r\n\
BailoutNormPreset: 1\r\n\
BailoutNormCustom: 2\r\n\
ColorMethod: 7\r\n\
Differences: 3\r\n\
ColorOffset: 0\r\n\
ColorPhaseStrength: 0\r\n\
Colors: 255,255,255,128,0,64,160,0,0,192,128,0,\r\n\
InteriorColor: 0,0,0,\r\n\
Smooth: 1\r\n\
Flat: 0\r\n\
MultiColor: 0\r\n\
BlendMC: 0\r\n\
MultiColors: \r\n\
Power: 2\r\n\
FractalType: 0\r\n\
Slopes: 1\r\n\
SlopePower: 50\r\n\
SlopeRatio: 20\r\n\
SlopeAngle: 45\r\n\
real: 1\r\n\
imag: 1\r\n\
SeedR: 0\r\n\
SeedI: 0\r\n\
FactorAR: 1\r\n\
FactorAI: 0\r\n\
Period: 0\r\n\
TextureEnabled: 0\r\n\
TextureMerge: 1\r\n\
TexturePower: 200\r\n\
TextureRatio: 100\r\n\
TextureFile: \r\n\
TextureResize: 1\r\n\
RotateAngle: 0\r\n\
StretchAngle: 0\r\n\
StretchAmount: 0\r\n\
ImagPointsUp: 1\r\n\
TriangleInequalityAverage: 0\r\n\
Version: 2150500\r\n";

    fn table(toml_text: &str) -> toml::Table {
        toml_text.parse::<toml::Table>().unwrap_or_else(|e| panic!("{e}\n{toml_text}"))
    }

    fn err(text: &str) -> SourceError {
        kfr_to_toml("loc.kfr", text).expect_err("should fail")
    }

    #[test]
    fn mandelbrot_as_kf_writes_it() {
        let out = kfr_to_toml("e14.kfr", KF_215).unwrap();
        let t = table(&out);
        assert_eq!(t["version"].as_integer(), Some(1));
        assert_eq!(t["formula"]["kind"].as_str(), Some("mandelbrot"));
        assert!(t["formula"].get("c").is_none());
        let view = &t["view"];
        assert_eq!(view["center"][0].as_str(), Some("-1.759817130804847813610825010561798238243999999999999999999800"));
        assert_eq!(view["center"][1].as_str(), Some("-0.012593310799749865383746631843264858450340000000000000000000"));
        assert_eq!(view["zoom"].as_str(), Some("1.00000000000E14"));
        assert_eq!(view["width"].as_integer(), Some(800));
        assert_eq!(view["height"].as_integer(), Some(600));
        assert_eq!(t["iteration"]["max"].as_integer(), Some(4036));
        let layer = &t["layer"][0];
        assert_eq!(layer["kind"].as_str(), Some("smooth"));
        assert_eq!(layer["palette"].as_str(), Some("e14.kfr"), "the file is its own palette");
        assert_eq!(layer["density"].as_float(), Some(1.0 / (1024.0 * 0.01)), "IterDiv 0.01");
        assert_eq!(layer["interior"].as_str(), Some("#000000"));
        assert!(out.contains("ColorMethod: 7"), "the distance method is named as not reproduced");
        assert!(out.starts_with("# Converted from the Kalles Fraktaler location e14.kfr."));
        assert!(!out.contains("mirrored"), "ImagPointsUp: 1 matches deepfield's orientation");
        // It is a scene file deepfield reads.
        crate::scene::Scene::parse_file("e14.kfr", &out).unwrap();
    }

    #[test]
    fn old_style_lf_file_with_bom_deep_zoom_and_size() {
        let text = "\u{feff}Re: -1.768610493014677074503175653270226520239677907588665494837677257575304640978808475\n\
                    Im: 0.001266613503868717702066411192242601576193940560471409817185010171762524792588903\n\
                    Zoom: 1E1086\n\
                    Iterations: 600100\n\
                    Colors: 0,0,0,\n\
                    Rotate: 0.000000\n\
                    Ratio: 360.000000\n\
                    \n\
                    SomeFutureKey: whatever\n\
                    TargetWidth: 1920\n\
                    TargetHeight: 1080\n\
                    ImageWidth: 3840\n\
                    ImageHeight: 2160\n";
        let out = kfr_to_toml("old.kfr", text).unwrap();
        let t = table(&out);
        assert_eq!(t["view"]["zoom"].as_str(), Some("1E1086"));
        assert!(t["view"]["center"][0].as_str().unwrap().ends_with("808475"));
        assert_eq!(t["view"]["width"].as_integer(), Some(1920));
        assert_eq!(t["view"]["height"].as_integer(), Some(1080));
        assert_eq!(t["iteration"]["max"].as_integer(), Some(600100));
        assert!(out.contains("mirrored top to bottom"), "no ImagPointsUp: KF's axis points down");
    }

    #[test]
    fn image_size_without_target_and_no_iterations() {
        let out = kfr_to_toml("x.kfr", "Re: 0\nIm: 0\nZoom: 1\nImageWidth: 640\nImageHeight: 360\n").unwrap();
        let t = table(&out);
        assert_eq!(t["view"]["width"].as_integer(), Some(640));
        assert_eq!(t["view"]["height"].as_integer(), Some(360));
        assert!(t.get("iteration").is_none(), "absent Iterations keeps the scene default");
    }

    /// KF has no Julia mode: its seed is z_0 of a Mandelbrot-family orbit. A file with a
    /// non-zero seed (what a KF "Julia" attempt looks like) is refused with that explanation,
    /// rather than converted into a Julia scene that KF never drew.
    #[test]
    fn seed_is_not_a_julia_parameter() {
        let text =
            "Re: 0.1\r\nIm: 0.2\r\nZoom: 2\r\nIterations: 500\r\nSeedR: -0.7436447860\r\nSeedI: 0.1318252536\r\n";
        let e = err(text);
        assert_eq!(e.origin, "loc.kfr");
        let p = e.position.unwrap();
        assert_eq!((p.line, p.column), (5, 8));
        assert!(e.message.contains("SeedR") && e.message.contains("not a Julia parameter"), "{e}");
        // A zero seed written as KF writes doubles is fine.
        kfr_to_toml("z.kfr", "Re: 0\nIm: 0\nZoom: 1\nSeedR: 0\nSeedI: -0\n").unwrap();
    }

    /// KF's formula presets have no location: KF keeps its view, which is 0 + 0i at zoom 1
    /// when it starts. Each missing key takes its part of that view.
    #[test]
    fn missing_location_is_kfs_opening_view() {
        let out = kfr_to_toml("p.kfr", "Power: 3\r\nFractalType: 1\r\n").unwrap();
        let t = table(&out);
        assert_eq!(t["view"]["center"][0].as_str(), Some("0"));
        assert_eq!(t["view"]["center"][1].as_str(), Some("0"));
        assert_eq!(t["view"]["zoom"].as_str(), Some("1"));
        assert!(out.contains("no `Re`, `Im`, `Zoom` (a formula preset)"), "{out}");
        let t = table(&kfr_to_toml("p.kfr", "Re: -0.75\r\nIm: 0.1\r\nIterations: 100\r\n").unwrap());
        assert_eq!(t["view"]["center"][0].as_str(), Some("-0.75"));
        assert_eq!(t["view"]["zoom"].as_str(), Some("1"));
        let e = err("");
        assert!(e.message.contains("no `Key: value` lines"), "{e}");
    }

    fn formula_of(text: &str) -> (String, Option<i64>) {
        let t = table(&kfr_to_toml("f.kfr", text).unwrap_or_else(|e| panic!("{text}: {e}")));
        (t["formula"]["kind"].as_str().unwrap().to_string(), t["formula"].get("power").and_then(|p| p.as_integer()))
    }

    /// Every family of the table at every power it comes in, from `FractalType` and `Power`.
    #[test]
    fn fractal_type_and_power_map_through_the_table() {
        for k in crate::formula::kind::KINDS {
            for p in k.min_power..=k.max_power {
                let (kind, power) =
                    formula_of(&format!("Re: 0\nIm: 0\nZoom: 1\nPower: {p}\nFractalType: {}\n", k.kf_type));
                assert_eq!(kind, k.name);
                assert_eq!(power, (p != k.min_power).then_some(p as i64), "{}^{p}", k.name);
                let f = crate::formula::Formula::parse(&kind, power.map(|p| p as u32)).unwrap();
                assert_eq!(f.phases(), [crate::formula::Phase::new(k.kind, p)]);
            }
        }
        // KF's coefficient a of the sums, 1 + 0i where the file has none.
        let a = |text: &str| {
            let t = table(&kfr_to_toml("f.kfr", text).unwrap_or_else(|e| panic!("{text}: {e}")));
            let a = t["formula"].get("a").map(|a| [a[0].as_float().unwrap(), a[1].as_float().unwrap()]);
            (t["formula"]["kind"].as_str().unwrap().to_string(), a)
        };
        let base = "Re: 0\nIm: 0\nZoom: 1\n";
        assert_eq!(a(&format!("{base}Power: 3\nFractalType: 43\n")), ("redshift-rider-2".into(), Some([1.0, 0.0])));
        assert_eq!(
            a(&format!("{base}Power: 5\nFractalType: 47\nFactorAR: -0.25\nFactorAI: 1.5\n")),
            ("redshift-rider-6".into(), Some([-0.25, 1.5]))
        );
        assert_eq!(
            a(&format!("{base}Power: 3\nFractalType: 44\nFactorAR: 3\n")),
            ("redshift-rider-3".into(), None),
            "a fixed 2"
        );
        assert_eq!(a(&format!("{base}FractalType: 1\nFactorAR: 3\n")), ("burning-ship".into(), None));
        // No keys: KF's type 0 at power 2, written as before (no `power`).
        assert_eq!(formula_of("Re: 0\nIm: 0\nZoom: 1\n"), ("mandelbrot".into(), None));
    }

    #[test]
    fn refused_types_and_powers_are_named() {
        let e = err("Re: 0\nIm: 0\nZoom: 1\nPower: 3\nFractalType: 52\n");
        assert_eq!(e.message, "FractalType 52 (General Quadratic Minus) is not one deepfield draws");
        assert_eq!(e.position.map(|p| (p.line, p.column)), Some((5, 14)));
        for (t, name) in
            [(53, "General Quadratic Plus"), (69, "General Abs Quadratic Minus"), (71, "z^2 exp(2 a / z) + c")]
        {
            let e = err(&format!("Re: 0\nIm: 0\nZoom: 1\nFractalType: {t}\n"));
            assert!(e.message.contains(name), "{t}: {e}");
        }
        let e = err("Re: 0\nIm: 0\nZoom: 1\nFractalType: 99\n");
        assert!(e.message.contains("FractalType 99 is not one of Kalles Fraktaler 2.15's formulas"), "{e}");
        let e = err("Re: 0\nIm: 0\nZoom: 1\nPower: 7\nFractalType: 1\n");
        assert!(e.message.contains("Burning Ship (FractalType 1) at power 7") && e.message.contains("2 to 5"), "{e}");
        assert_eq!(e.position.map(|p| p.line), Some(4), "points at `Power`");
        let e = err("Re: 0\nIm: 0\nZoom: 1\nPower: 11\n");
        assert!(e.message.contains("powers 2 to 10"), "{e}");
    }

    #[test]
    fn hybrid_formulas_map_to_phases() {
        let base = "Re: 0\nIm: 0\nZoom: 1\nPower: 2\nFractalType: 0\nUseHybridFormula: 1\n";
        let none = "0,0,0,0,0,0,0";
        let (kind, power) =
            formula_of(&format!("{base}HybridFormula: 0/1|1,1,0,0,2,1,0;{none};0/1|0,0,0,0,3,1,0;{none};0\n"));
        assert_eq!((kind.as_str(), power), ("burning-ship,mandelbrot^3", None));
        let (kind, power) = formula_of(&format!("{base}HybridFormula: 0/1|1,1,0,0,4,1,0;{none};0\n"));
        assert_eq!((kind.as_str(), power), ("burning-ship", Some(4)), "one phase is a single family");
        // An operator, pointed at where it is; the FractalType's name comes with it.
        let e = err(&format!("{base}FractalType: 52\nHybridFormula: 0/1|0,0,0,0,3,1,0;0,0,0,0,2,1,0;0\n")
            .replace("FractalType: 0\n", ""));
        assert!(e.message.contains("combines two operators") && e.message.contains("General Quadratic Minus"), "{e}");
        assert_eq!(e.position.map(|p| (p.line, p.column)), Some((7, 20)));
        // KF draws FractalType when the hybrid is missing or fails its own check.
        let (kind, _) =
            formula_of(&format!("{base}HybridFormula: 0/0|1,1,0,0,2,1,0;{none};0\n").replace("Type: 0", "Type: 1"));
        assert_eq!(kind, "burning-ship");
        // A product: Mothbrot 2×1's lines, the family of that FractalType.
        let moth = format!("{base}HybridFormula: 0/1|0,0,0,0,2,1,0;1,1,0,0,1,1,0;2\n").replace("Type: 0", "Type: 56");
        assert_eq!(formula_of(&moth), ("mothbrot-2x1".into(), None));
        let out = kfr_to_toml("h.kfr", base).unwrap();
        assert!(out.contains("gives none"), "{out}");
        // Off means off, whatever the hybrid says.
        let off = format!("{base}HybridFormula: 0/1|1,1,0,0,2,1,0;{none};0\n")
            .replace("UseHybridFormula: 1", "UseHybridFormula: 0");
        assert_eq!(formula_of(&off).0, "mandelbrot");
    }

    /// KF turns no formula's picture over: every family is drawn with the same pixel-to-plane
    /// map (`CFraktalSFT::GetPixelCoordinates`), so a Burning Ship location keeps its centre
    /// and, without `ImagPointsUp: 1`, its text says the ship shows upside down here.
    #[test]
    fn burning_ship_keeps_its_centre_and_says_how_it_is_drawn() {
        let text = "Re: -1.7626\r\nIm: -0.0281\r\nZoom: 50\r\nPower: 2\r\nFractalType: 1\r\n";
        let out = kfr_to_toml("bs.kfr", text).unwrap();
        let t = table(&out);
        assert_eq!(t["formula"]["kind"].as_str(), Some("burning-ship"));
        assert_eq!(t["view"]["center"][1].as_str(), Some("-0.0281"), "the same point of the plane");
        assert!(out.contains("mirrored top to bottom") && out.contains("`burning-ship` is not symmetric"), "{out}");
        let up = kfr_to_toml("bs.kfr", &format!("{text}ImagPointsUp: 1\r\n")).unwrap();
        assert!(!up.contains("mirrored") && !up.contains("symmetric"), "{up}");
        // A family symmetric about the real axis gets only the mirror note.
        let celtic = kfr_to_toml("c.kfr", &text.replace("Type: 1", "Type: 3")).unwrap();
        assert!(celtic.contains("mirrored") && !celtic.contains("symmetric"), "{celtic}");
    }

    #[test]
    fn bad_number_points_at_the_value() {
        let e = err("Re: -0.75\r\nIm:   0.1x5\r\nZoom: 1E5\r\n");
        let p = e.position.unwrap();
        assert_eq!((p.line, p.column), (2, 7));
        assert!(e.message.contains("`Im`") && e.message.contains("not a decimal number"), "{e}");
        assert_eq!(e.to_string().split(": ").next(), Some("loc.kfr:2:7"));

        let e = err("Re: -0.75\nIm: 0\nZoom: 1,5E5\n");
        assert_eq!(e.position.map(|p| (p.line, p.column)), Some((3, 7)));

        let e = err("Re: -0.75\nIm: 0\nZoom: -3\n");
        assert!(e.message.contains("positive"), "{e}");
        let e = err("Re: -0.75\nIm: 0\nZoom: 0.0\n");
        assert!(e.message.contains("positive"), "{e}");
    }

    #[test]
    fn iterations_range() {
        for bad in ["0", "4294967295", "99999999999999999999999", "1e6", "-5", "12.5"] {
            let e = err(&format!("Re: 0\nIm: 0\nZoom: 1\nIterations: {bad}\n"));
            assert_eq!(e.position.map(|p| (p.line, p.column)), Some((4, 13)), "{bad}: {e}");
            assert!(e.message.contains("Iterations") && e.message.contains("4294967294"), "{e}");
        }
        let out = kfr_to_toml("x.kfr", "Re: 0\nIm: 0\nZoom: 1\nIterations: 4294967294\n").unwrap();
        assert_eq!(table(&out)["iteration"]["max"].as_integer(), Some(4294967294));
    }

    #[test]
    fn unsupported_keys_are_refused() {
        let base = "Re: 0\nIm: 0\nZoom: 1\n";
        for (line, needle) in [
            ("FractalType: 70", "General Abs Quadratic Plus"),
            ("Power: 3\nFractalType: 42\nFactorAI: 1e999", "FactorAI"),
            ("Power: 11", "powers 2 to 10"),
            ("FractalType: x", "whole number"),
            ("UseHybridFormula: 1\nHybridFormula: 0/1|0,0,0,0,2,3,0;0,0,0,0,0,0,0;0", "multiplies by 3"),
            ("ImagPointsUp: 2", "ImagPointsUp"),
            ("StretchAmount: 21", "limit"),
            ("Ratio: -3", "positive"),
            ("RotateAngle: 1e7", "range"),
        ] {
            let e = err(&format!("{base}{line}\n"));
            assert_eq!(e.position.map(|p| p.line), Some(3 + line.lines().count()), "{line}");
            assert!(e.message.contains(needle), "{line}: {e}");
        }
    }

    #[test]
    fn rotation_and_stretch_become_view_keys() {
        let base = "Re: 0\nIm: 0\nZoom: 1\n";
        let view = |text: &str| table(&kfr_to_toml("x.kfr", &format!("{base}{text}")).unwrap())["view"].clone();
        let v = view("RotateAngle: 30.5\nStretchAngle: 45\nStretchAmount: 0.25\n");
        assert_eq!(v["rotate"].as_float(), Some(30.5));
        assert_eq!(v["stretch_angle"].as_float(), Some(45.0));
        assert_eq!(v["stretch_amount"].as_float(), Some(0.25));
        // KF 2.15 writes zeros: no keys.
        let v = view("RotateAngle: 0\nStretchAngle: 45\nStretchAmount: 0\n");
        assert!(v.get("rotate").is_none() && v.get("stretch_angle").is_none() && v.get("stretch_amount").is_none());
        // Old style: square pixels are no stretch; 381.176471 (KF's 1e1086 benchmark) a slight one.
        let v = view("Rotate: 0.000000\nRatio: 360.000000\n");
        assert!(v.get("stretch_amount").is_none());
        let v = view("Rotate: 12\nRatio: 381.176471\n");
        assert_eq!(v["rotate"].as_float(), Some(-12.0));
        assert_eq!(v["stretch_angle"].as_float(), Some(12.0));
        let a = v["stretch_amount"].as_float().unwrap();
        assert!((a - (360.0f64 / 381.176471).log2() / 2.0).abs() < 1e-15, "{a}");
    }

    #[test]
    fn malformed_lines_and_duplicates() {
        let e = err("Re: 0\n  this is not a kfr line\nIm: 0\nZoom: 1\n");
        assert_eq!(e.position.map(|p| (p.line, p.column)), Some((2, 3)));
        assert!(e.message.contains("Key: value"), "{e}");
        let e = err("Re: 0\n: 5\nIm: 0\nZoom: 1\n");
        assert_eq!(e.position.map(|p| (p.line, p.column)), Some((2, 1)));
        let e = err("Re: 0\nIm: 0\nZoom: 1\nRe: 1\n");
        assert_eq!(e.position.map(|p| (p.line, p.column)), Some((4, 1)));
        assert!(e.message.contains("twice") && e.message.contains("line 1"), "{e}");
        // Unknown keys may repeat freely.
        kfr_to_toml("x.kfr", "Re: 0\nIm: 0\nZoom: 1\nFoo: 1\nFoo: 2\n").unwrap();
    }

    /// `scenes/bench-e14.kfr` (KF's format) and `scenes/bench-e14.toml` describe the same view.
    #[test]
    fn shipped_example_matches_its_scene() {
        let out = kfr_to_toml("scenes/bench-e14.kfr", include_str!("../../scenes/bench-e14.kfr")).unwrap();
        let t = table(&out);
        let scene = table(include_str!("../../scenes/bench-e14.toml"));
        assert_eq!(t["formula"]["kind"], scene["formula"]["kind"]);
        for key in ["center", "zoom", "width", "height"] {
            assert_eq!(t["view"][key], scene["view"][key], "{key}");
        }
        assert_eq!(t["iteration"]["max"], scene["iteration"]["max"]);
        assert!(!out.contains("mirrored"), "the example sets ImagPointsUp: 1");
    }

    #[test]
    fn exponent_forms_are_kept_verbatim() {
        let out = kfr_to_toml(
            "x.kfr",
            "Re: -1.99999999999999999999999999837485e+00\nIm: 1.3717805209060941414e-211\nZoom: 3.16254E321\n",
        )
        .unwrap();
        let t = table(&out);
        assert_eq!(t["view"]["center"][0].as_str(), Some("-1.99999999999999999999999999837485e+00"));
        assert_eq!(t["view"]["center"][1].as_str(), Some("1.3717805209060941414e-211"));
        assert_eq!(t["view"]["zoom"].as_str(), Some("3.16254E321"));
    }
}
