//! `deepfield render`: scene + flags -> PNG (+ EXR), with progress, cancel and statistics.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::{Context, anyhow};
use deepfield::field::ChannelSet;
use deepfield::io::{self, ExrLayout, ExrWriter, PngEncoder, PngWriter};
use deepfield::render::{self, Options, RenderError, Stats};
use deepfield::scene::raw::{LayerRaw, cli};
use deepfield::scene::{Scene, SceneFile};
use indicatif::{ProgressBar, ProgressStyle};

use super::Failure;
use super::args::RenderArgs;

/// Runs `deepfield render`.
pub fn run(args: RenderArgs) -> Result<(), Failure> {
    // Ctrl-C sets a flag the kernels poll; installed first so that no output file can
    // exist before the handler does. Failing to install it only loses Ctrl-C handling.
    let cancel = Arc::new(AtomicBool::new(false));
    {
        let cancel = cancel.clone();
        let _ = ctrlc::set_handler(move || cancel.store(true, Ordering::Relaxed));
    }
    let scene = load_scene(&args)?;
    let plan = scene.engine().map_err(|e| Failure::Input(anyhow!(e)))?;
    let png_path = args.output.clone().unwrap_or_else(|| default_output(args.scene.as_deref()));
    check_distinct(&args, &png_path)?;
    let exr_channels = if args.exr.is_some() { scene.channels } else { ChannelSet::default() };
    let toml = scene.to_toml();

    // Open every output before computing anything: an unwritable path fails at once.
    let stats_file = match &args.stats_json {
        Some(path) => Some(io::AtomicFile::create(path).map_err(Failure::input)?),
        None => None,
    };
    let png = PngWriter::create(&png_path, scene.width, scene.height, scene.png_bits, &toml).map_err(Failure::input)?;
    let png_enc = PngEncoder::new(scene.png_bits);
    let exr = match &args.exr {
        Some(path) => {
            let layout = ExrLayout::new(exr_channels, &scene.traps);
            let (w, h) = (scene.width * scene.aa, scene.height * scene.aa);
            let engine = format!("{}: {}", plan.name, plan.reason);
            Some(ExrWriter::create(path, w, h, layout, &toml, &engine).map_err(Failure::input)?)
        }
        None => None,
    };
    let (mut exr_writer, exr_enc) = match exr {
        Some((w, e)) => (Some(w), Some(e)),
        None => (None, None),
    };

    let bar = progress_bar(&args, scene.height as u64);
    let progress = |rows: u64| {
        if let Some(b) = &bar {
            b.set_position(rows);
        }
    };
    let aa = scene.aa as usize;
    let prepare = |strip: &render::RenderedStrip| -> Result<_, String> {
        let bytes = png_enc.encode(&strip.rgb);
        let chunks = match &exr_enc {
            Some(e) => Some(e.encode(strip.row as usize * aa, &strip.planes, strip.samples.as_deref())?),
            None => None,
        };
        Ok((bytes, chunks))
    };
    let mut png = Some(png);
    let result = {
        let png = &mut png;
        let exr_writer = &mut exr_writer;
        let options = Options { threads: args.threads.unwrap_or(0) as usize, exr_channels };
        render::render(&scene, options, &cancel, &progress, &prepare, move |_strip, (bytes, chunks)| {
            png.as_mut().expect("open until finished").write_encoded(&bytes).map_err(|e| e.to_string())?;
            if let (Some(w), Some(c)) = (exr_writer.as_mut(), chunks) {
                w.write(c)?;
            }
            Ok(())
        })
    };
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let stats = match result {
        Ok(s) => s,
        Err(RenderError::Cancelled) => return Err(Failure::Cancelled),
        Err(RenderError::Engine(e)) => return Err(Failure::Input(anyhow!(e))),
        Err(e) => return Err(Failure::Runtime(anyhow!(e))),
    };
    png.take().expect("still open").finish().map_err(|e| Failure::Runtime(e.into()))?;
    if let Some(w) = exr_writer.take() {
        w.finish().map_err(|e| Failure::Runtime(e.into()))?;
    }
    report(&args, &stats, stats_file)
}

/// Refuses runs whose outputs would collide with each other or overwrite the input scene.
fn check_distinct(args: &RenderArgs, png: &Path) -> Result<(), Failure> {
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut named: Vec<(&str, PathBuf)> = vec![("-o", abs(png))];
    if let Some(p) = &args.exr {
        named.push(("--exr", abs(p)));
    }
    if let Some(p) = &args.stats_json {
        named.push(("--stats-json", abs(p)));
    }
    for (i, (a, pa)) in named.iter().enumerate() {
        for (b, pb) in &named[i + 1..] {
            if pa == pb {
                return Err(Failure::Input(anyhow!("{a} and {b} name the same file {}", pa.display())));
            }
        }
        if let Some(scene) = &args.scene
            && abs(scene) == *pa
        {
            return Err(Failure::Input(anyhow!(
                "{a} would overwrite the input {}; give another output name with {a}",
                scene.display()
            )));
        }
    }
    Ok(())
}

fn progress_bar(args: &RenderArgs, rows: u64) -> Option<ProgressBar> {
    if args.quiet || !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = ProgressBar::new(rows);
    let style = ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} rows, ETA {eta}")
        .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    Some(bar)
}

fn report(
    args: &RenderArgs,
    stats: &Stats,
    stats_file: Option<(io::AtomicFile, std::io::BufWriter<std::fs::File>)>,
) -> Result<(), Failure> {
    if args.stats {
        let mut out = std::io::stdout().lock();
        let text = format!(
            "engine      {}\n  why       {}\nprecision   {}\nsimd        {}\nthreads     {}\npixels      {}\nsamples     {}\niterations  {}\nwall time   {:.3} s\nspeed       {:.3e} iterations/s\n",
            stats.engine,
            stats.engine_reason,
            stats.precision,
            stats.simd,
            stats.threads,
            stats.pixels,
            stats.samples,
            stats.iterations,
            stats.wall_seconds,
            stats.iterations_per_second
        );
        out.write_all(text.as_bytes()).map_err(|e| Failure::Runtime(e.into()))?;
    }
    if let (Some(path), Some((file, mut w))) = (&args.stats_json, stats_file) {
        let json = serde_json::to_string_pretty(stats).map_err(|e| Failure::Runtime(e.into()))?;
        w.write_all(json.as_bytes()).and_then(|_| w.write_all(b"\n")).map_err(|e| Failure::Runtime(e.into()))?;
        let inner = w.into_inner().map_err(|e| Failure::Runtime(anyhow!("{}: {}", path.display(), e.error())))?;
        drop(inner);
        file.commit_written().map_err(|e| Failure::Runtime(e.into()))?;
    }
    Ok(())
}

fn default_output(scene: Option<&Path>) -> PathBuf {
    let stem = scene
        .and_then(|p| p.file_stem())
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "deepfield".into());
    PathBuf::from(format!("{stem}.png"))
}

/// Reads the scene named on the command line (TOML or PNG), applies the flags, validates.
fn load_scene(args: &RenderArgs) -> Result<Scene, Failure> {
    let (origin, text, base_dir) = match &args.scene {
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
            (origin, text, base)
        }
    };
    let mut file = Scene::parse_file(&origin, &text).map_err(Failure::input)?;
    apply_flags(&mut file, args);
    Scene::validate(file, &origin, &text, &base_dir, &io::load_bitmap).map_err(Failure::input)
}

/// Writes the flags into the scene, so the PNG's embedded scene reproduces the render.
fn apply_flags(file: &mut SceneFile, a: &RenderArgs) {
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
                "smooth" | "trap" => true,
                "distance" => l.palette.is_some(),
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
