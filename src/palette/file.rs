//! Reading palette files (`palettes/README.md` documents the format) and the built-in set.

use std::path::Path;

use serde::Deserialize;

use super::{Cosine, Definition, Mode, Palette, Space, Stop, color};
use crate::source::SourceError;

/// Why a palette could not be had.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PaletteError {
    /// Neither a built-in name nor a readable file.
    #[error("unknown palette `{name}`: not a built-in palette ({}) and no such file", builtin_names().join(", "))]
    Unknown {
        /// What was requested.
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
    /// Another program's palette file that could not be imported.
    #[error(transparent)]
    Import(#[from] super::import::ImportError),
    /// An imported file holds several palettes (a `.ugr` collection): which one is meant?
    #[error(
        "{path} holds {count} palettes ({names}); a scene names one palette: convert them with `deepfield palettes import {path} -o DIR` and name one file"
    )]
    Several {
        /// The file.
        path: String,
        /// How many it holds.
        count: usize,
        /// Their names, comma-separated.
        names: String,
    },
}

macro_rules! builtin {
    ($($name:literal),* $(,)?) => {
        const BUILTIN: &[(&str, &str)] = &[$(($name, include_str!(concat!("../../palettes/", $name, ".toml")))),*];
    };
}

builtin!(
    "aurora",
    "blueprint",
    "candy",
    "classic",
    "copper",
    "desert",
    "earth",
    "electric",
    "emerald",
    "fire",
    "forest",
    "gold",
    "grayscale",
    "ice",
    "iq-rainbow",
    "iq-sunrise",
    "iq-teal",
    "lava",
    "magma",
    "mono-blue",
    "neon-noir",
    "ocean",
    "pastel",
    "rainbow",
    "sepia",
    "sunset",
    "twilight",
);

/// Names of the palettes compiled into the binary.
pub fn builtin_names() -> Vec<&'static str> {
    BUILTIN.iter().map(|(n, _)| *n).collect()
}

/// A built-in palette by name.
pub fn builtin(name: &str) -> Option<Palette> {
    let (name, text) = BUILTIN.iter().find(|(n, _)| *n == name)?;
    // The built-in files are checked by the tests: a parse error here is a build defect.
    parse(&format!("palettes/{name}.toml"), text).ok()
}

/// A built-in palette by name, or a palette file by path (relative paths are resolved
/// against `base`, the folder of the scene that names it). A path whose extension names
/// another program's format ([`super::import::Format::from_path`]: `.ggr`, `.cpt`, `.map`,
/// `.ugr`, `.kfp`, `.kfr`) is imported as `deepfield palettes import` would, so a scene
/// converted from a Kalles Fraktaler location can name the location file as its palette.
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
    if super::import::Format::from_path(&path).is_some() {
        let mut found = super::import::import_file(&path)?;
        return match found.len() {
            1 => Ok(found.remove(0)),
            count => Err(PaletteError::Several {
                path: path.display().to_string(),
                count,
                names: found.iter().map(|p| p.name.as_str()).collect::<Vec<_>>().join(", "),
            }),
        };
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
    description: String,
    #[serde(default)]
    space: Space,
    #[serde(default)]
    mode: Mode,
    #[serde(default)]
    offset: Option<toml::Spanned<f64>>,
    #[serde(default)]
    density: Option<toml::Spanned<f64>>,
    #[serde(default)]
    cosine: Option<toml::Spanned<RawCosine>>,
    #[serde(default, rename = "stop")]
    stops: Vec<toml::Spanned<RawStop>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCosine {
    a: [f64; 3],
    b: [f64; 3],
    c: [f64; 3],
    d: [f64; 3],
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
    let definition = match (&raw.cosine, raw.stops.is_empty()) {
        (Some(c), true) => {
            let v = c.get_ref();
            if [v.a, v.b, v.c, v.d].iter().flatten().any(|x| !x.is_finite()) {
                return Err(err(c.span(), "cosine coefficients must be finite numbers".into()));
            }
            Definition::Cosine(Cosine { a: v.a, b: v.b, c: v.c, d: v.d })
        }
        (Some(c), false) => {
            return Err(err(c.span(), "a palette has either [cosine] or [[stop]] tables, not both".into()));
        }
        (None, _) => Definition::Stops(stops(&raw.stops, &err)?),
    };
    let number = |v: &Option<toml::Spanned<f64>>, default: f64, what: &str| match v {
        None => Ok(default),
        Some(v) if v.get_ref().is_finite() && (what == "offset" || *v.get_ref() > 0.0) => Ok(*v.get_ref()),
        Some(v) => Err(err(
            v.span(),
            format!("`{what}` must be a finite number{}", if what == "offset" { "" } else { " > 0" }),
        )),
    };
    let offset = number(&raw.offset, 0.0, "offset")?;
    let density = number(&raw.density, 1.0, "density")?;
    Ok(Palette::with(raw.name, raw.description, raw.space, raw.mode, definition).adjusted(offset, density))
}

fn stops(
    raw: &[toml::Spanned<RawStop>],
    err: &dyn Fn(std::ops::Range<usize>, String) -> SourceError,
) -> Result<Vec<Stop>, SourceError> {
    if raw.len() < 2 {
        return Err(err(0..0, "a palette needs at least 2 [[stop]] tables (or one [cosine] table)".into()));
    }
    let mut stops = Vec::with_capacity(raw.len());
    for (k, s) in raw.iter().enumerate() {
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
    Ok(stops)
}

/// The palette in our TOML format (what `deepfield palettes import` writes); parsing the
/// text gives the same palette back (colours rounded to 8 bits).
pub fn to_toml(p: &Palette) -> String {
    let mut out = String::new();
    let q = |s: &str| toml::Value::String(s.to_string()).to_string();
    out += &format!("name = {}\n", q(&p.name));
    out += &format!("description = {}\n", q(&p.description));
    out += &format!("space = \"{}\"\nmode = \"{}\"\n", p.space.name(), p.mode.name());
    if p.offset != 0.0 {
        out += &format!("offset = {:?}\n", p.offset);
    }
    if p.density != 1.0 {
        out += &format!("density = {:?}\n", p.density);
    }
    match &p.definition {
        Definition::Cosine(c) => {
            out += &format!("\n[cosine]\na = {:?}\nb = {:?}\nc = {:?}\nd = {:?}\n", c.a, c.b, c.c, c.d);
        }
        Definition::Stops(stops) => {
            for s in stops {
                out += &format!("\n[[stop]]\npos = {:?}\ncolor = \"{}\"\n", s.pos, color::to_hex(s.srgb));
                if s.opacity != 1.0 {
                    out += &format!("opacity = {:?}\n", s.opacity as f64);
                }
            }
        }
    }
    out
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
        let e = parse(
            "x.toml",
            "name = \"x\"\ndensity = -1.0\n[cosine]\na=[0.5,0.5,0.5]\nb=[0.5,0.5,0.5]\nc=[1,1,1]\nd=[0,0.1,0.2]\n",
        )
        .unwrap_err();
        assert_eq!(e.position.unwrap().line, 2, "{e}");
    }

    #[test]
    fn toml_round_trip() {
        for name in builtin_names() {
            let p = builtin(name).unwrap();
            let back = parse("back.toml", &to_toml(&p)).unwrap();
            assert_eq!(back, p, "{name}");
        }
        let text = "name = \"c\"\noffset = 0.25\ndensity = 2.0\n[cosine]\na=[0.5,0.5,0.5]\nb=[0.5,0.5,0.5]\nc=[1,1,1]\nd=[0,0.1,0.2]\n";
        let p = parse("c.toml", text).unwrap();
        assert_eq!(parse("c2.toml", &to_toml(&p)).unwrap(), p);
        // density and offset act before the mode: t = 0.1 samples the palette at 0.45.
        let plain = p.clone().adjusted(0.0, 1.0);
        assert_eq!(p.at(0.1), plain.at(0.45));
    }
}
