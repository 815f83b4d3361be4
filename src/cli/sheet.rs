//! `deepfield sheet`: one field, many colourings, side by side.
//!
//! The field is computed once for the union of what every cell needs (all cells' layers are
//! validated together as one stack, so trap indices are shared), then each cell recolours
//! the same planes with its own layers.

use std::io::Write;
use std::path::PathBuf;
use std::sync::Mutex;

use anyhow::anyhow;
use deepfield::compose::sheet::{self, Cell, Overlays};
use deepfield::compose::{Layer, Stack};
use deepfield::field::ChannelSet;
use deepfield::io;
use deepfield::render::{self, Options};
use deepfield::scene::presets::{PRESETS, preset, preset_names};
use deepfield::scene::raw::LayerRaw;
use deepfield::scene::{FamilySpec, Scene};
use toml::Spanned;

use super::Failure;
use super::args::SheetArgs;

/// Runs `deepfield sheet`.
pub fn run(args: SheetArgs) -> Result<(), Failure> {
    if args.list {
        let mut out = String::from("scene                 the scene's own layers\n");
        for (name, what, _) in PRESETS {
            out += &format!("{name:<21} {what}\n");
        }
        return std::io::stdout().lock().write_all(out.as_bytes()).map_err(|e| Failure::Runtime(e.into()));
    }
    if args.colorings.is_empty() && args.palettes.is_empty() {
        return Err(Failure::Input(anyhow!(
            "name the cells with --colorings A,B,... ({}, scene) and/or --palettes A,B,...",
            preset_names()
        )));
    }
    let cancel = super::terminal::install_ctrlc();
    let base = super::scene::load(&args.scene)?;
    let colorings: Vec<String> = if args.colorings.is_empty() { vec!["scene".into()] } else { args.colorings.clone() };
    // `--palette` colours every cell; `--palettes` makes one cell per palette.
    let palettes: Vec<Option<String>> = if args.palettes.is_empty() {
        vec![args.scene.palette.clone()]
    } else {
        args.palettes.iter().cloned().map(Some).collect()
    };

    // Every cell's layers, one after another, validated as one scene.
    let mut cells: Vec<(String, usize)> = Vec::new();
    let mut all: Vec<Spanned<LayerRaw>> = Vec::new();
    for c in &colorings {
        let layers = if c == "scene" {
            base.file.layers.clone()
        } else {
            preset(c).ok_or_else(|| {
                Failure::Input(anyhow!("unknown colouring `{c}`; expected one of {}, scene", preset_names()))
            })?
        };
        for p in &palettes {
            let mut file = base.file.clone();
            file.layers = layers.clone();
            if let Some(p) = p {
                super::scene::apply_palette(&mut file, p);
            }
            let label = match p {
                Some(p) if !args.palettes.is_empty() && colorings.len() > 1 => format!("{c} / {p}"),
                Some(p) if !args.palettes.is_empty() => p.clone(),
                _ => c.clone(),
            };
            if file.layers.is_empty() {
                file.layers.push(Spanned::new(0..0, LayerRaw::of_kind("smooth")));
            }
            cells.push((label, file.layers.len()));
            all.extend(file.layers);
        }
    }
    let text = base.to_toml();
    let scene = super::scene::load_text(&base.origin, &text, &base.base_dir, |file| file.layers = all)?;

    let planes = Mutex::new(Vec::new());
    let bar = super::terminal::bar(args.quiet, scene.height as u64);
    let progress = |p: render::Progress| super::terminal::show(&bar, p);
    let plan = super::engine_plan(&scene)?;
    let result = render::render(
        &scene,
        &plan,
        Options {
            threads: args.threads.unwrap_or(0) as usize,
            exr_channels: ChannelSet::default(),
            simd: super::simd_level(args.simd.as_deref())?,
            ..Options::default()
        },
        &cancel,
        &progress,
        &|_| Ok(()),
        |strip, ()| {
            planes.lock().unwrap_or_else(|e| e.into_inner()).push(strip.planes);
            Ok(())
        },
    );
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    result?;
    let planes = planes.into_inner().unwrap_or_else(|e| e.into_inner());

    let mut images = Vec::with_capacity(cells.len());
    let mut layers = scene.stack.layers.iter().cloned();
    for (label, count) in cells {
        let stack =
            Stack { layers: layers.by_ref().take(count).collect::<Vec<Layer>>(), background: scene.stack.background };
        let rgb = render::recolor(&stack, &planes, scene.aa).map_err(|e| Failure::Runtime(e.into()))?.concat();
        images.push(Cell { label, rgb });
    }
    let overlays = Overlays {
        scale_bar: args.scale_bar.then(|| sheet::scale_bar(pixel_log10(&scene), scene.width)),
        marker: marker(&args, &scene)?,
    };
    let columns = args.columns.unwrap_or_else(|| (images.len() as f64).sqrt().ceil() as u32);
    let pix = sheet::sheet(&images, scene.width, scene.height, columns, &overlays)
        .ok_or_else(|| Failure::Input(anyhow!("the sheet would be too large")))?;
    let rgb: Vec<u8> = pix.pixels().iter().flat_map(|p| [p.red(), p.green(), p.blue()]).collect();
    let out = args.output.clone().unwrap_or_else(|| {
        let stem =
            args.scene.path.as_ref().and_then(|p| p.file_stem()).map_or("deepfield".into(), |s| s.to_string_lossy());
        PathBuf::from(format!("{stem}-sheet.png"))
    });
    io::write_png_rgb8(&out, pix.width(), pix.height(), &rgb, &base.to_toml()).map_err(Failure::input)
}

/// The marker's pixel position, from `--marker RE,IM` or `c` (positions use f64).
fn marker(args: &SheetArgs, scene: &Scene) -> Result<Option<[f32; 2]>, Failure> {
    let Some(m) = &args.marker else { return Ok(None) };
    let point = if m == "c" {
        match &scene.family {
            FamilySpec::Julia { c } => [c[0].to_f64(), c[1].to_f64()],
            FamilySpec::Mandelbrot => {
                return Err(Failure::Input(anyhow!("--marker c needs a Julia scene; give RE,IM for a point")));
            }
        }
    } else {
        let parse = |s: &str| s.trim().parse::<f64>().ok().filter(|v| v.is_finite());
        match m.split_once(',').and_then(|(a, b)| Some([parse(a)?, parse(b)?])) {
            Some(p) => p,
            None => return Err(Failure::Input(anyhow!("--marker `{m}` is not RE,IM or c"))),
        }
    };
    let [cx, cy] = scene.center_f64();
    let spacing = 10f64.powf(pixel_log10(scene));
    let x = (point[0] - cx) / spacing + scene.width as f64 / 2.0;
    let y = (cy - point[1]) / spacing + scene.height as f64 / 2.0;
    Ok(Some([x as f32, y as f32]))
}

/// log10 of the distance between output pixels in the plane.
fn pixel_log10(scene: &Scene) -> f64 {
    scene.log10_spacing() + (scene.aa as f64).log10()
}
