//! The scene a command works on: a file (TOML, .kfr or PNG) plus command-line overrides.

use std::path::{Path, PathBuf};

use anyhow::anyhow;
use deepfield::io;
use deepfield::scene::raw::{LayerRaw, cli};
use deepfield::scene::{Scene, SceneFile};

use super::Failure;
use super::args::SceneArgs;

/// Loads the scene named by `args` (or the default one) and applies the flags.
pub fn load(args: &SceneArgs) -> Result<Scene, Failure> {
    load_edited(args, |_| {})
}

/// [`load`], with `edit` applied after the flags (a keyframe's zoom, say).
pub fn load_edited(args: &SceneArgs, edit: impl FnOnce(&mut SceneFile)) -> Result<Scene, Failure> {
    let (origin, text, base_dir) = match &args.path {
        None => ("command line".to_string(), "version = 1\n".to_string(), PathBuf::from(".")),
        Some(path) => read_source(path)?,
    };
    load_text(&origin, &text, &base_dir, |file| {
        apply_flags(file, args);
        edit(file);
    })
}

/// Parses scene text, lets `edit` change the raw scene, and validates it.
pub fn load_text(
    origin: &str,
    text: &str,
    base_dir: &Path,
    edit: impl FnOnce(&mut SceneFile),
) -> Result<Scene, Failure> {
    let mut file = Scene::parse_file(origin, text).map_err(Failure::input)?;
    edit(&mut file);
    Scene::validate(file, origin, text, base_dir, io::load_bitmap).map_err(Failure::input)
}

/// The scene text of a file: a TOML scene, a .kfr location (converted), or the scene
/// embedded in a PNG or EXR written by deepfield. Returns (origin, text, folder).
pub fn read_source(path: &Path) -> Result<(String, String, PathBuf), Failure> {
    let s = io::read_scene_source(path).map_err(Failure::input)?;
    Ok((s.origin, s.text, s.base_dir))
}

/// Parses a `--layer` specification `KIND[:key=value,...]` (values in TOML syntax, bare
/// words taken as strings; `mask.quantity=distance` sets a mask key).
pub fn layer_spec(spec: &str, index: usize) -> Result<LayerRaw, Failure> {
    let origin = format!("--layer {index} ({spec})");
    let (kind, rest) = spec.split_once(':').unwrap_or((spec, ""));
    let mut text = format!("kind = {}\n", toml::Value::String(kind.trim().to_string()));
    for pair in split_top_level(rest) {
        let Some((key, value)) = pair.split_once('=') else {
            return Err(Failure::Input(anyhow!("{origin}: `{pair}` is not key=value")));
        };
        let (key, value) = (key.trim(), value.trim());
        let literal = toml::from_str::<toml::Table>(&format!("v = {value}")).is_ok();
        let value = if literal { value.to_string() } else { toml::Value::String(value.to_string()).to_string() };
        text += &format!("{key} = {value}\n");
    }
    toml::from_str::<LayerRaw>(&text).map_err(|e| Failure::Input(anyhow!("{origin}: {}", e.message())))
}

/// Splits on commas outside brackets and quotes.
fn split_top_level(s: &str) -> Vec<&str> {
    let (mut out, mut depth, mut quoted, mut start) = (Vec::new(), 0i32, false, 0);
    for (i, ch) in s.char_indices() {
        match ch {
            '"' => quoted = !quoted,
            '[' if !quoted => depth += 1,
            ']' if !quoted => depth -= 1,
            ',' if !quoted && depth == 0 => {
                out.push(&s[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    out.push(&s[start..]);
    out.into_iter().filter(|p| !p.trim().is_empty()).collect()
}

/// Sets `palette` on every layer that uses one (adding the default layer to a scene that
/// has none); a palette file named on the command line is relative to the current folder.
pub fn apply_palette(file: &mut SceneFile, p: &str) {
    let p = match std::fs::canonicalize(p) {
        Ok(abs) if Path::new(p).is_file() => abs.display().to_string(),
        _ => p.to_string(),
    };
    if file.layers.is_empty() {
        file.layers.push(toml::Spanned::new(0..0, LayerRaw::of_kind("smooth")));
    }
    for l in &mut file.layers {
        let l = l.get_mut();
        if deepfield::scene::uses_palette(l) {
            l.palette = Some(cli(p.clone()));
        }
    }
}

/// Writes the flags into the scene, so the PNG's embedded scene reproduces the render.
fn apply_flags(file: &mut SceneFile, a: &SceneArgs) {
    if let Some(f) = &a.formula {
        file.formula.kind = cli(f.clone());
        file.formula.power = None;
        if f != "julia" {
            // A family named on the command line is its Mandelbrot form unless --julia-c
            // says otherwise.
            file.formula.c = None;
        }
        // The scene's coefficient stays only with a formula that takes one.
        if deepfield::formula::Formula::parse(f, None).map_or(true, |f| f.a().is_none()) {
            file.formula.a = None;
        }
    }
    if let Some(p) = a.power {
        file.formula.power = Some(cli(i64::from(p)));
    }
    if let Some(v) = a.formula_a {
        file.formula.a = Some(cli(v));
    }
    if let Some(c) = &a.julia_c {
        // z² + c's Julia set keeps its name; any other formula takes c as its Julia form.
        if file.formula.kind.get_ref() == "mandelbrot" && file.formula.power.as_ref().is_none_or(|p| *p.get_ref() == 2)
        {
            file.formula.kind = cli("julia".into());
            file.formula.power = None;
        }
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
    if let Some(r) = a.rotate {
        file.view.rotate = Some(cli(r));
    }
    if let Some((amount, angle)) = a.stretch {
        file.view.stretch_amount = Some(cli(amount));
        file.view.stretch_angle = Some(cli(angle));
    }
    if let Some(f) = a.exponential_map {
        file.view.exponential_map = Some(cli(f));
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
    if let Some(c) = a.cycle {
        file.render.cycle = Some(cli(c));
    }
    if let Some(t) = a.bla_tolerance {
        file.render.bla_tolerance = Some(cli(t));
    }
    if let Some(w) = &a.interior_detection {
        file.render.interior_detection = match w.as_str() {
            "on" => Some(cli(true)),
            "off" => Some(cli(false)),
            _ => None,
        };
    }
    if let Some(e) = &a.engine {
        file.render.engine = cli(e.clone());
    }
    if let Some(p) = &a.palette {
        apply_palette(file, p);
    }
    if let Some(set) = a.channels {
        file.output.channels = Some(cli(set.iter().map(|c| c.name().to_string()).collect()));
    }
    if let Some(b) = &a.bits {
        file.output.bits = Some(cli(b.parse().unwrap_or(8)));
    }
}
