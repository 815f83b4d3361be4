//! Named colourings: small layer stacks that `deepfield sheet --colorings` and
//! `recolor` can refer to by name, for side-by-side comparisons of the same raw data.

use toml::Spanned;

use super::Scene;
use super::raw::LayerRaw;

/// (name, what it shows, layers in scene-file TOML).
pub const PRESETS: &[(&str, &str, &str)] = &[
    ("smooth", "smooth iteration, linear transfer", "[[layer]]\nkind = \"smooth\"\n"),
    (
        "smooth-sqrt",
        "smooth iteration, square-root transfer",
        "[[layer]]\nkind = \"smooth\"\ntransfer = \"sqrt\"\ndensity = 0.3\n",
    ),
    (
        "smooth-log",
        "smooth iteration, log transfer",
        "[[layer]]\nkind = \"smooth\"\ntransfer = \"log\"\ndensity = 1.0\n",
    ),
    ("histogram", "histogram-equalised iteration", "[[layer]]\nkind = \"histogram\"\n"),
    ("soft-distance", "Inigo Quilez's soft distance colouring, grey", "[[layer]]\nkind = \"distance\"\n"),
    (
        "distance-linear",
        "distance estimate, linear, through a palette",
        "[[layer]]\nkind = \"distance\"\nstyle = \"linear\"\npalette = \"classic\"\n",
    ),
    (
        "distance-log",
        "distance estimate, log, through a palette",
        "[[layer]]\nkind = \"distance\"\nstyle = \"log\"\npalette = \"classic\"\n",
    ),
    (
        "boundary",
        "smooth iteration with 1.5-pixel boundary lines",
        "[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"boundary\"\nwidth = 1.5\n",
    ),
    (
        "slope",
        "smooth iteration lit from the DE vector (multiply)",
        "[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"slope\"\nblend = \"multiply\"\n",
    ),
    (
        "slope-near-boundary",
        "lighting masked to 8 pixels from the set",
        "[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"slope\"\nblend = \"multiply\"\n[layer.mask]\nquantity = \"distance\"\nbelow = 8.0\nfeather = 8.0\n",
    ),
    ("binary", "binary decomposition (sign of Im z_n)", "[[layer]]\nkind = \"binary\"\n"),
    ("angle", "final angle through a palette", "[[layer]]\nkind = \"angle\"\n"),
    (
        "stripe",
        "stripe average, 5 stripes per turn, [0.25, 0.75] spread over the palette",
        "[[layer]]\nkind = \"stripe\"\ndensity = 2.0\noffset = -0.5\n",
    ),
    ("trap", "distance to a point trap at 0", "[[layer]]\nkind = \"trap\"\n"),
    (
        "interior",
        "smooth outside, point-trap palette inside",
        "[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"interior\"\npalette = \"ocean\"\ndensity = 2.0\n",
    ),
];

/// The layers of a named colouring, or None for an unknown name.
pub fn preset(name: &str) -> Option<Vec<Spanned<LayerRaw>>> {
    let (_, _, text) = PRESETS.iter().find(|(n, _, _)| *n == name)?;
    // The presets are fixed text checked by the tests: a parse failure is a build defect.
    Scene::parse_file(name, &format!("version = 1\n{text}")).ok().map(|f| f.layers)
}

/// The preset names, comma-separated (for messages).
pub fn preset_names() -> String {
    PRESETS.iter().map(|(n, _, _)| *n).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_validates() {
        for (name, _, text) in PRESETS {
            let text = format!("version = 1\n{text}");
            let file = Scene::parse_file(name, &text).unwrap();
            let loader = |_: &std::path::Path| {
                Err(std::io::Error::new(std::io::ErrorKind::Unsupported, "the presets have no bitmap layers"))
            };
            Scene::validate(file, name, &text, std::path::Path::new("."), loader).unwrap();
            assert!(preset(name).is_some_and(|l| !l.is_empty()));
        }
        assert!(preset("nope").is_none());
    }
}
