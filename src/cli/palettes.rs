//! `deepfield palettes`: list the built-in palettes, preview one (or all) as PNG, and
//! convert palette files of other programs to our TOML format.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::anyhow;
use deepfield::compose::text::{draw_text, text_width};
use deepfield::io;
use deepfield::palette::{self, Palette, color, import};
use tiny_skia::{Color, Pixmap, PremultipliedColorU8};

use super::Failure;
use super::args::{PalettesAction, PalettesArgs};

/// Runs `deepfield palettes`.
pub fn run(args: PalettesArgs) -> Result<(), Failure> {
    match args.action {
        PalettesAction::List => {
            let mut out = String::new();
            for name in palette::builtin_names() {
                let p =
                    palette::builtin(name).ok_or_else(|| Failure::Runtime(anyhow!("built-in {name} is invalid")))?;
                out += &format!("{name:<14} {}\n", p.description);
            }
            print(&out)
        }
        PalettesAction::Show { name, all, output, size } => {
            let (w, h) = size;
            if all {
                let palettes: Vec<Palette> =
                    palette::builtin_names().into_iter().filter_map(palette::builtin).collect();
                let pix = catalogue(&palettes, w, h).ok_or_else(|| Failure::Input(anyhow!("size too large")))?;
                let out = output.unwrap_or_else(|| PathBuf::from("palettes.png"));
                return save(&out, &pix);
            }
            let name = name.unwrap_or_default();
            let p = load_any(&name)?;
            let mut pix = Pixmap::new(w, h).ok_or_else(|| Failure::Input(anyhow!("size too large")))?;
            strip(&mut pix, &p, 0, w, 0, h);
            let out = output.unwrap_or_else(|| PathBuf::from(format!("{}.png", p.name)));
            save(&out, &pix)
        }
        PalettesAction::Import { file, output } => {
            let palettes = import::import_file(&file).map_err(Failure::input)?;
            match output {
                None => {
                    let text: Vec<String> = palettes.iter().map(palette::to_toml).collect();
                    print(&text.join("\n# ---\n"))
                }
                Some(dir) if dir.is_dir() || palettes.len() > 1 => {
                    std::fs::create_dir_all(&dir).map_err(|e| Failure::Input(anyhow!("{}: {e}", dir.display())))?;
                    for p in &palettes {
                        write_toml(&dir.join(format!("{}.toml", p.name)), p)?;
                    }
                    Ok(())
                }
                Some(path) => write_toml(&path, &palettes[0]),
            }
        }
    }
}

fn print(text: &str) -> Result<(), Failure> {
    std::io::stdout().lock().write_all(text.as_bytes()).map_err(|e| Failure::Runtime(e.into()))
}

/// A built-in name, a TOML palette file, or any file `import` reads (its first palette).
fn load_any(name: &str) -> Result<Palette, Failure> {
    let path = Path::new(name);
    if path.is_file() && import::Format::from_path(path).is_some() {
        let mut v = import::import_file(path).map_err(Failure::input)?;
        return Ok(v.remove(0));
    }
    palette::load(name, None).map_err(Failure::input)
}

fn write_toml(path: &Path, p: &Palette) -> Result<(), Failure> {
    let opened = io::AtomicFile::create(path).map_err(Failure::input)?;
    super::commit_text(opened, &palette::to_toml(p))
}

fn save(path: &Path, pix: &Pixmap) -> Result<(), Failure> {
    let rgb: Vec<u8> = pix.pixels().iter().flat_map(|p| [p.red(), p.green(), p.blue()]).collect();
    io::write_png_rgb8(path, pix.width(), pix.height(), &rgb, "").map_err(Failure::input)
}

/// Paints one period of `p` across columns x0..x1, rows y0..y1, over a checkerboard where
/// the palette is translucent.
fn strip(pix: &mut Pixmap, p: &Palette, x0: u32, x1: u32, y0: u32, y1: u32) {
    let width = pix.width() as usize;
    let plain = p.clone().adjusted(0.0, 1.0);
    for x in x0..x1 {
        let t = (x - x0) as f64 / (x1 - x0).max(1) as f64;
        let c = plain.at(t);
        for y in y0..y1 {
            let check = if ((x / 8) + (y / 8)) % 2 == 0 { 0.8 } else { 0.55 };
            let mix = |v: f32| color::linear_to_srgb8(v * c[3] + check * (1.0 - c[3]));
            pix.pixels_mut()[y as usize * width + x as usize] =
                PremultipliedColorU8::from_rgba(mix(c[0]), mix(c[1]), mix(c[2]), 255)
                    .unwrap_or(PremultipliedColorU8::TRANSPARENT);
        }
    }
}

/// Every palette as a labelled strip, one per row, names on the left.
fn catalogue(palettes: &[Palette], w: u32, h: u32) -> Option<Pixmap> {
    let size = (h as f32 * 0.42).clamp(10.0, 24.0);
    let label_w = palettes.iter().map(|p| text_width(&p.name, size)).fold(0.0, f32::max).ceil() as u32 + 16;
    let gap = 4;
    let mut pix = Pixmap::new(label_w + w + gap, palettes.len() as u32 * (h + gap) + gap)?;
    pix.fill(Color::from_rgba8(24, 24, 28, 255));
    for (i, p) in palettes.iter().enumerate() {
        let y = gap + i as u32 * (h + gap);
        draw_text(&mut pix, &p.name, 8.0, y as f32 + (h as f32 - size * 1.15) / 2.0, size, [235, 235, 235]);
        strip(&mut pix, p, label_w, label_w + w, y, y + h);
    }
    Some(pix)
}
