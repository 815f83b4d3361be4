//! The validation context shared by the scene and layer checks: [`Ctx`], which turns a
//! value's span into a located error (file, line, column, or "command line"), with the small
//! typed readers built on it, and [`BitmapLoader`], the I/O layer's bitmap reader that
//! validation is handed.
//!
//! They live apart from `validate` (the whole scene) and `layer` (one `[[layer]]`) so that
//! both depend on this module and neither on the other: `validate` uses `layer`, and `layer`
//! never reaches back.

use std::path::Path;

use toml::Spanned;

use super::MAX_LOG10_COORDINATE;
use super::raw::CLI;
use crate::num::Decimal;
use crate::palette::color;
use crate::source::SourceError;
use crate::trap::Bitmap;

/// Loads a bitmap for a bitmap trap (provided by the I/O layer, whose error names the file
/// and keeps the system's or the codec's failure beneath).
pub type BitmapLoader<'a> = dyn Fn(&Path) -> Result<Bitmap, BitmapLoadError> + 'a;

/// Why a [`BitmapLoader`] could not load a bitmap: the loader's own error, whole.
pub type BitmapLoadError = Box<dyn std::error::Error + Send + Sync>;

/// Where the scene being validated came from, so that every error can name the file, line
/// and column of the offending value (or say it came from the command line), or, for a scene
/// built in code, the key path of the value.
pub(super) struct Ctx<'a> {
    origin: &'a str,
    source: Source<'a>,
}

/// What a value's span points into.
enum Source<'a> {
    /// The scene's text: spans are byte ranges.
    Text(&'a str),
    /// No text: a span's start `k` (from 1) names the value at `keys[k - 1]`, as
    /// `build::label` numbers them.
    Keys(&'a [String]),
}

impl<'a> Ctx<'a> {
    /// Errors will name `origin` and locate spans in `text`.
    pub(super) fn new(origin: &'a str, text: &'a str) -> Self {
        Self { origin, source: Source::Text(text) }
    }

    /// Errors will name `origin` and the key path a span numbers in `keys`.
    pub(super) fn keyed(origin: &'a str, keys: &'a [String]) -> Self {
        Self { origin, source: Source::Keys(keys) }
    }

    /// An error at `span` (or on the command line, for the [`CLI`] span).
    pub(super) fn err<T>(&self, span: std::ops::Range<usize>, message: impl Into<String>) -> Result<T, SourceError> {
        let message = message.into();
        if span == CLI {
            return Err(SourceError::at_key("command line", None, message));
        }
        Err(match self.source {
            Source::Text(text) => SourceError::at(self.origin, text, Some(span), message),
            Source::Keys(keys) => {
                let key = span.start.checked_sub(1).and_then(|k| keys.get(k));
                SourceError::at_key(self.origin, key.map(String::as_str), message)
            }
        })
    }

    /// An exact decimal, or an error naming `what`.
    pub(super) fn decimal(&self, s: &Spanned<String>, what: &str) -> Result<Decimal, SourceError> {
        Decimal::parse(s.get_ref()).or_else(|e| self.err(s.span(), format!("{what}: {e}")))
    }

    /// Two exact decimals [re, im] within [`MAX_LOG10_COORDINATE`] of the origin.
    pub(super) fn pair(&self, s: &Spanned<[String; 2]>, what: &str) -> Result<[Decimal; 2], SourceError> {
        let [re, im] = s.get_ref();
        let p = |t: &String| {
            let d = Decimal::parse(t).or_else(|e| self.err(s.span(), format!("{what}: {e}")))?;
            // Everything past a few units from the origin escapes at once, and a value of
            // 1e100000 would cost a 330000-bit reference for nothing: refused before any
            // big number is built from it.
            if !d.is_zero() && d.log10_abs() > MAX_LOG10_COORDINATE {
                return self.err(
                    s.span(),
                    format!(
                        "{what}: {d} is too far from the origin; each part must lie within 1e{MAX_LOG10_COORDINATE:.0} (every sample beyond a few units escapes at the first iteration)"
                    ),
                );
            }
            Ok(d)
        };
        Ok([p(re)?, p(im)?])
    }

    /// A "#rrggbb" colour as linear RGBA.
    pub(super) fn colour(&self, s: &Spanned<String>) -> Result<[f32; 4], SourceError> {
        match linear_colour(s.get_ref()) {
            Some(c) => Ok(c),
            None => self.err(s.span(), format!("colour `{}` is not of the form \"#rrggbb\"", s.get_ref())),
        }
    }

    /// An integer in `lo ..= hi`.
    pub(super) fn range_i(&self, v: &Spanned<i64>, lo: i64, hi: i64, what: &str) -> Result<i64, SourceError> {
        let x = *v.get_ref();
        if x < lo || x > hi {
            return self.err(v.span(), format!("{what} must be in {lo} ..= {hi}, got {x}"));
        }
        Ok(x)
    }

    /// A finite number in `[lo, hi]`.
    pub(super) fn finite(&self, v: &Spanned<f64>, lo: f64, hi: f64, what: &str) -> Result<f64, SourceError> {
        let x = *v.get_ref();
        if !(x.is_finite() && x >= lo && x <= hi) {
            return self.err(v.span(), format!("{what} must be a finite number in [{lo}, {hi}], got {x}"));
        }
        Ok(x)
    }
}

/// A "#rrggbb" colour as opaque linear RGBA, or None when the text is not of that form.
pub(super) fn linear_colour(text: &str) -> Option<[f32; 4]> {
    let c = color::parse_hex(text)?;
    Some([color::srgb_to_linear(c[0]), color::srgb_to_linear(c[1]), color::srgb_to_linear(c[2]), 1.0])
}
