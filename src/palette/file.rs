//! Reading palette files (`palettes/README.md` documents the format) and the built-in set.

use std::path::Path;

use serde::Deserialize;

use super::{Mode, Palette, Space, Stop, color};
use crate::source::SourceError;

/// Why a palette could not be had.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PaletteError {
    /// Neither a built-in name nor a readable file.
    #[error("unknown palette `{name}`: not a built-in palette ({}) and no such file", builtin_names().join(", "))]
    Unknown {
        /// What was asked for.
        name: String,
    },
    /// The file could not be read.
    #[error("cannot read palette file {path}: {reason}")]
    Io {
        /// The file.
        path: String,
        /// The OS error.
        reason: String,
    },
    /// The file is not a valid palette.
    #[error(transparent)]
    Invalid(#[from] SourceError),
}

macro_rules! builtin {
    ($($name:literal),* $(,)?) => {
        const BUILTIN: &[(&str, &str)] = &[$(($name, include_str!(concat!("../../palettes/", $name, ".toml")))),*];
    };
}

builtin!("classic", "electric", "fire", "forest", "grayscale", "ocean", "pastel", "twilight");

/// Names of the palettes compiled into the binary.
pub fn builtin_names() -> Vec<&'static str> {
    BUILTIN.iter().map(|(n, _)| *n).collect()
}

/// A built-in palette by name, or a palette file by path (relative paths are resolved
/// against `base`, the folder of the scene that names it).
pub fn load(name_or_path: &str, base: Option<&Path>) -> Result<Palette, PaletteError> {
    if let Some((name, text)) = BUILTIN.iter().find(|(n, _)| *n == name_or_path) {
        return Ok(parse(&format!("palettes/{name}.toml"), text)?);
    }
    let path = Path::new(name_or_path);
    let path = match base {
        Some(b) if path.is_relative() => b.join(path),
        _ => path.to_path_buf(),
    };
    if !path.exists() {
        return Err(PaletteError::Unknown { name: name_or_path.to_string() });
    }
    let text = std::fs::read_to_string(&path)
        .map_err(|e| PaletteError::Io { path: path.display().to_string(), reason: e.to_string() })?;
    Ok(parse(&path.display().to_string(), &text)?)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPalette {
    name: String,
    #[serde(default)]
    #[allow(dead_code)]
    description: String,
    #[serde(default)]
    space: Space,
    #[serde(default)]
    mode: Mode,
    #[serde(rename = "stop")]
    stops: Vec<toml::Spanned<RawStop>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStop {
    pos: f64,
    color: String,
    #[serde(default = "one")]
    opacity: f64,
}

fn one() -> f64 {
    1.0
}

/// Parses and validates palette text; `origin` names it in errors.
pub fn parse(origin: &str, text: &str) -> Result<Palette, SourceError> {
    let raw: RawPalette = toml::from_str(text).map_err(|e| SourceError::from_toml(origin, text, &e))?;
    let err = |span: std::ops::Range<usize>, msg: String| SourceError::at(origin, text, Some(span), msg);
    if raw.stops.len() < 2 {
        return Err(SourceError::at(origin, text, None, "a palette needs at least 2 [[stop]] tables"));
    }
    let mut stops = Vec::with_capacity(raw.stops.len());
    for (k, s) in raw.stops.iter().enumerate() {
        let span = s.span();
        let s = s.get_ref();
        if !(0.0..=1.0).contains(&s.pos) {
            return Err(err(span, format!("stop position {} is outside [0, 1]", s.pos)));
        }
        if k == 0 && s.pos != 0.0 {
            return Err(err(span, "the first stop must be at pos = 0.0".into()));
        }
        if let Some(prev) = stops.last().map(|p: &Stop| p.pos)
            && s.pos <= prev
        {
            return Err(err(span, format!("stop positions must increase strictly ({} follows {prev})", s.pos)));
        }
        let srgb = color::parse_hex(&s.color)
            .ok_or_else(|| err(span.clone(), format!("colour `{}` is not of the form \"#rrggbb\"", s.color)))?;
        if !(0.0..=1.0).contains(&s.opacity) {
            return Err(err(span, format!("opacity {} is outside [0, 1]", s.opacity)));
        }
        stops.push(Stop { pos: s.pos, srgb, opacity: s.opacity as f32 });
    }
    Ok(Palette::new(raw.name, raw.space, raw.mode, stops))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_line_and_column() {
        let text = "name = \"x\"\n[[stop]]\npos = 0.0\ncolor = \"#000000\"\n[[stop]]\npos = 1.0\ncolor = \"red\"\n";
        let e = parse("x.toml", text).unwrap_err();
        assert_eq!(e.position.unwrap().line, 5, "{e}");
        assert!(e.to_string().contains("#rrggbb"), "{e}");
        let e = parse("x.toml", "name = \"x\"\nbogus = 1\n").unwrap_err();
        assert_eq!(e.position.unwrap().line, 2, "{e}");
        assert!(matches!(load("no-such-palette", None), Err(PaletteError::Unknown { .. })));
    }
}
