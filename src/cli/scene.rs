//! The scene a command works on: a file (TOML, .kfr or PNG) plus command-line overrides.

use std::path::{Path, PathBuf};

use anyhow::{Context, anyhow};
use deepfield::io;
use deepfield::scene::raw::{LayerRaw, cli};
use deepfield::scene::{Scene, SceneFile, kfr};

use super::Failure;
use super::args::SceneArgs;

/// Loads the scene named by `args` (or the default one) and applies the flags.
pub fn load(args: &SceneArgs) -> Result<Scene, Failure> {
    let (origin, text, base_dir) = match &args.path {
        None => ("command line".to_string(), "version = 1\n".to_string(), PathBuf::from(".")),
        Some(path) => {
            let origin = path.display().to_string();
            if !path.exists() {
                return Err(Failure::Input(anyhow!("{origin}: no such scene file")));
            }
            let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
            let is_png = std::fs::File::open(path)
                .and_then(|mut f| {
                    let mut magic = [0u8; 8];
                    std::io::Read::read(&mut f, &mut magic).map(|n| n == 8 && magic == *b"\x89PNG\r\n\x1a\n")
                })
                .unwrap_or(false);
            let text = if is_png {
                io::read_png_scene(path)
                    .map_err(Failure::input)?
                    .ok_or_else(|| Failure::Input(anyhow!("{origin}: this PNG carries no deepfield scene")))?
            } else {
                std::fs::read_to_string(path)
                    .with_context(|| format!("{origin}: cannot read scene"))
                    .map_err(Failure::Input)?
            };
            let is_kfr = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("kfr"));
            if is_kfr {
                // Validated as the scene it converts to; the converter checked what it read.
                let toml = kfr::kfr_to_toml(&origin, &text).map_err(Failure::input)?;
                (format!("{origin} (as a scene)"), toml, base)
            } else {
                (origin, text, base)
            }
        }
    };
    let mut file = Scene::parse_file(&origin, &text).map_err(Failure::input)?;
    apply_flags(&mut file, args);
    Scene::validate(file, &origin, &text, &base_dir, &io::load_bitmap).map_err(Failure::input)
}

/// Writes the flags into the scene, so the PNG's embedded scene reproduces the render.
fn apply_flags(file: &mut SceneFile, a: &SceneArgs) {
    if let Some(f) = &a.formula {
        file.formula.kind = cli(f.clone());
        if f == "mandelbrot" {
            file.formula.c = None;
        }
    }
    if let Some(c) = &a.julia_c {
        file.formula.kind = cli("julia".into());
        file.formula.c = Some(cli(c.clone()));
    }
    if let Some(c) = &a.center {
        file.view.center = cli(c.clone());
    }
    if let Some(z) = &a.zoom {
        file.view.zoom = Some(cli(z.clone()));
        file.view.radius = None;
    }
    if let Some(r) = &a.radius {
        file.view.radius = Some(cli(r.clone()));
        file.view.zoom = None;
    }
    if let Some((w, h)) = a.size {
        file.view.width = cli(w as i64);
        file.view.height = cli(h as i64);
    }
    if let Some(n) = a.max_iter {
        file.iteration.max = cli(n as i64);
    }
    if let Some(r) = a.escape_radius {
        file.iteration.escape_radius = cli(r);
    }
    if let Some(n) = a.aa {
        file.render.aa = cli(n as i64);
    }
    if a.no_bla {
        file.render.bla = Some(cli(false));
    }
    if let Some(t) = a.bla_tolerance {
        file.render.bla_tolerance = Some(cli(t));
    }
    if let Some(e) = &a.engine {
        file.render.engine = cli(e.clone());
    }
    if let Some(p) = &a.palette {
        // A palette file named on the command line is relative to the current folder.
        let p = match std::fs::canonicalize(p) {
            Ok(abs) if Path::new(p).is_file() => abs.display().to_string(),
            _ => p.clone(),
        };
        if file.layers.is_empty() {
            file.layers.push(toml::Spanned::new(0..0, LayerRaw::of_kind("smooth")));
        }
        for l in &mut file.layers {
            let l = l.get_mut();
            // Distance layers without a palette are grey by design; they keep that look.
            let uses_palette = match l.kind.get_ref().as_str() {
                "smooth" | "histogram" | "angle" | "stripe" | "trap" => true,
                "distance" | "interior" => l.palette.is_some(),
                _ => false,
            };
            if uses_palette {
                l.palette = Some(cli(p.clone()));
            }
        }
    }
    if let Some(set) = a.channels {
        file.output.channels = Some(cli(set.iter().map(|c| c.name().to_string()).collect()));
    }
    if let Some(b) = &a.bits {
        file.output.bits = Some(cli(b.parse().unwrap_or(8)));
    }
}
