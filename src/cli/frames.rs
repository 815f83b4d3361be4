//! `deepfield frames`: the keyframes of `deepfield zoom` into the frames of a zoom video.
//!
//! Each keyframe's raw data is coloured by the layers of its stored scene (or of `--scene`,
//! `--layer`, `--palette`) through the recolour path, then every frame is resampled from
//! the keyframes around its depth ([`deepfield::render::frames`]) at constant zoom speed.
//! Frames go to numbered PNG files or, with `--video`, straight into ffmpeg's standard
//! input as raw RGB; the video file appears only once ffmpeg has finished. Only the
//! keyframes a frame can reach are held in memory (the current one and the few deeper
//! ones whose centres it shows), so a sequence of any length streams.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::Ordering;

use anyhow::anyhow;
use deepfield::io;
use deepfield::palette::color::Srgb8Encoder;
use deepfield::render::frames::{self, Keyframe};
use deepfield::scene::Scene;
use deepfield::scene::raw::{LayerRaw, cli};

use super::Failure;
use super::args::FramesArgs;

/// Runs `deepfield frames`.
pub fn run(args: FramesArgs) -> Result<(), Failure> {
    let cancel = super::terminal::install_ctrlc();
    if !(args.fps.is_finite() && (0.1..=1000.0).contains(&args.fps)) {
        return Err(Failure::Input(anyhow!("--fps must be between 0.1 and 1000, got {}", args.fps)));
    }
    let files = keyframe_files(&args.keyframes)?;
    let count = files.len();
    let scenes = files.iter().map(|f| stored_scene(f)).collect::<Result<Vec<_>, _>>()?;
    let factor = factor_of(&scenes, &files)?;
    let (kw, kh) = (scenes[0].width as usize, scenes[0].height as usize);
    let is_map = !scenes[0].projection.is_flat();
    let (w, h) = match args.size {
        Some((w, h)) => (w as usize, h as usize),
        None if is_map => {
            return Err(Failure::Input(anyhow!(
                "{}: an exponential map has no frame size of its own; give --size WxH",
                args.keyframes.display()
            )));
        }
        None => (kw, kh),
    };
    if !is_map && ((w * kh) as f64 / (h * kw) as f64 - 1.0).abs() > 0.01 {
        return Err(Failure::Input(anyhow!(
            "--size {w}x{h} has another aspect ratio than the keyframes ({kw}x{kh}); frames keep the keyframes' shape"
        )));
    }
    if args.video.is_some() && (w % 2 == 1 || h % 2 == 1) {
        return Err(Failure::Input(anyhow!("a video needs an even frame width and height (yuv420p), not {w}x{h}")));
    }
    let seconds = args.seconds.unwrap_or((count - 1) as f64);
    if !(seconds.is_finite() && seconds > 0.0 && seconds * args.fps <= 1e7) {
        return Err(Failure::Input(anyhow!("--seconds must be positive and give at most 10 million frames")));
    }
    let total = ((seconds * args.fps).round() as usize).max(2);
    let units = match args.units {
        Some((a, b)) if a < b && b as usize <= total => a as usize..b as usize,
        Some((a, b)) => {
            return Err(Failure::Input(anyhow!("--units {a}..{b}: the frames are 0..{total}, and A must be below B")));
        }
        None => 0..total,
    };
    let colours = Colouring::from_args(&args)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0) as usize)
        .build()
        .map_err(|e| Failure::Runtime(e.into()))?;
    let mut sink = match (&args.video, &args.output) {
        (Some(video), _) => Sink::video(video, w, h, args.fps)?,
        (None, Some(dir)) => {
            std::fs::create_dir_all(dir).map_err(|e| Failure::Input(anyhow!("{}: {e}", dir.display())))?;
            Sink::Pngs(dir.clone())
        }
        (None, None) => return Err(Failure::Input(anyhow!("give -o DIR for PNG frames or --video FILE"))),
    };
    // The flat view inside an exponential map's deepest ring.
    let center = match is_map {
        true => Some(colours.keyframe(&args.keyframes.join(super::zoom::CENTER), &pool)?),
        false => None,
    };
    // Keyframes a frame at keyframe k can show: k and the deeper ones whose area is still
    // at least a pixel wide in it.
    let side = if is_map { (w as f64).hypot(h as f64) } else { kw.max(kh) as f64 };
    let reach = (side.ln() / factor.ln()).ceil() as usize + 1;
    let mut window: Vec<Option<Keyframe>> = vec![None; count];
    let taps = center.as_ref().map(|_| frames::MapTaps::new(w, h, kw, factor));
    let enc = Srgb8Encoder::get();
    for f in units.clone() {
        if cancel.load(Ordering::Relaxed) {
            return Err(Failure::Cancelled);
        }
        let z = frames::depth(f, total, count, args.zoom_out);
        let (k, _) = frames::locate(z, count);
        let keep = k..(k + reach + 1).min(count);
        for (d, slot) in window.iter_mut().enumerate() {
            if !keep.contains(&d) {
                *slot = None;
            } else if slot.is_none() {
                *slot = Some(colours.keyframe(&files[d], &pool)?);
            }
        }
        let rgb = pool.install(|| {
            let key = |d: usize| window[d].as_ref().unwrap_or_else(|| unreachable!("keyframe {d} is loaded"));
            match (&center, &taps) {
                (Some(center), Some(taps)) => {
                    let map = frames::Map { strip: &key, count, held: keep.clone(), factor, center };
                    frames::frame_from_map(&map, taps, z)
                }
                _ => frames::frame(&key, count, factor, z, w, h),
            }
        });
        let bytes: Vec<u8> = rgb.iter().flat_map(|p| p.map(|v| enc.encode(v))).collect();
        sink.write(f, w, h, &bytes)?;
        if !args.quiet {
            eprint!("\rframe {} of {total} (depth {z:.3} of {})", f + 1, count - 1);
        }
    }
    if !args.quiet {
        eprintln!();
    }
    sink.finish()
}

/// The keyframes `00000.exr`, `00001.exr`, ... of a folder, in order, with none missing.
fn keyframe_files(dir: &Path) -> Result<Vec<PathBuf>, Failure> {
    let entries = std::fs::read_dir(dir).map_err(|e| Failure::Input(anyhow!("{}: {e}", dir.display())))?;
    let mut indices = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if let Some(stem) = name.strip_suffix(".exr")
            && stem.len() == 5
            && let Ok(k) = stem.parse::<usize>()
        {
            indices.push(k);
        }
    }
    indices.sort_unstable();
    if indices.len() < 2 {
        return Err(Failure::Input(anyhow!(
            "{}: needs at least two keyframes 00000.exr, 00001.exr, ... (written by deepfield zoom)",
            dir.display()
        )));
    }
    if let Some(gap) = indices.iter().enumerate().find(|(i, k)| *i != **k) {
        return Err(Failure::Input(anyhow!("{}: keyframe {:05}.exr is missing", dir.display(), gap.0)));
    }
    Ok(indices.iter().map(|k| dir.join(format!("{k:05}.exr"))).collect())
}

/// The scene stored in a keyframe's header.
fn stored_scene(path: &Path) -> Result<Scene, Failure> {
    let text = io::read_exr_scene(path)
        .map_err(Failure::input)?
        .ok_or_else(|| Failure::Input(anyhow!("{}: the keyframe carries no scene", path.display())))?;
    super::scene::load_text(&format!("{} (stored scene)", path.display()), &text, Path::new("."), |_| {})
}

/// The zoom factor between consecutive keyframes, checked to be the same throughout, and
/// every keyframe of one size.
fn factor_of(scenes: &[Scene], files: &[PathBuf]) -> Result<f64, Failure> {
    let steps: Vec<f64> = scenes.windows(2).map(|p| p[0].log10_radius - p[1].log10_radius).collect();
    let step = steps[0];
    for (k, (s, scene)) in steps.iter().zip(&scenes[1..]).enumerate() {
        if !(*s > 0.0 && (s - step).abs() <= 1e-6 * step.max(1.0)) {
            return Err(Failure::Input(anyhow!(
                "{}: not one constant zoom factor deeper than {} (keyframes must come from one deepfield zoom)",
                files[k + 1].display(),
                files[k].display()
            )));
        }
        if (scene.width, scene.height) != (scenes[0].width, scenes[0].height) {
            return Err(Failure::Input(anyhow!(
                "{}: {}x{} pixels, but {} has {}x{}",
                files[k + 1].display(),
                scene.width,
                scene.height,
                files[0].display(),
                scenes[0].width,
                scenes[0].height
            )));
        }
    }
    Ok(10f64.powf(step))
}

/// How keyframes are coloured: their stored scene with the layers replaced as asked.
struct Colouring {
    /// Layers from `--scene` or `--layer`, if given.
    layers: Option<Vec<LayerRaw>>,
    /// `--palette`.
    palette: Option<String>,
    /// Where palette and bitmap files named by the layers are found.
    base: PathBuf,
}

impl Colouring {
    fn from_args(args: &FramesArgs) -> Result<Colouring, Failure> {
        let mut layers = None;
        let mut base = PathBuf::from(".");
        if let Some(path) = &args.scene {
            let (origin, text, dir) = super::scene::read_source(path)?;
            let file = Scene::parse_file(&origin, &text).map_err(Failure::input)?;
            layers = Some(file.layers.into_iter().map(|l| l.into_inner()).collect());
            base = dir;
        }
        if !args.layers.is_empty() {
            let specs = args.layers.iter().enumerate().map(|(i, s)| super::scene::layer_spec(s, i + 1));
            layers = Some(specs.collect::<Result<_, _>>()?);
        }
        Ok(Colouring { layers, palette: args.palette.clone(), base })
    }

    /// Reads one keyframe and colours it: linear RGB pixels.
    fn keyframe(&self, path: &Path, pool: &rayon::ThreadPool) -> Result<Keyframe, Failure> {
        let raw = io::read_exr_planes(path, 32).map_err(Failure::input)?;
        let text = raw
            .header
            .scene
            .clone()
            .ok_or_else(|| Failure::Input(anyhow!("{}: the keyframe carries no scene", path.display())))?;
        let scene =
            super::scene::load_text(&format!("{} (stored scene)", path.display()), &text, &self.base, |file| {
                if let Some(layers) = &self.layers {
                    file.layers = layers.iter().cloned().map(cli).collect();
                }
                if let Some(p) = &self.palette {
                    super::scene::apply_palette(file, p);
                }
            })?;
        super::recolor::check_fits(&scene, &raw.header, path)?;
        let strips =
            pool.install(|| deepfield::render::recolor(&scene.stack, &raw.strips, scene.aa)).map_err(Failure::input)?;
        Ok(Keyframe { width: scene.width as usize, height: scene.height as usize, rgb: strips.concat() })
    }
}

/// Where frames go.
enum Sink {
    /// `DIR/frame-NNNNN.png`.
    Pngs(PathBuf),
    /// ffmpeg reading raw RGB on its standard input.
    Video(Video),
}

/// A running ffmpeg writing a temporary file beside the video's destination (with its
/// extension, which chooses the container); the file is renamed into place only when
/// ffmpeg succeeds, and removed otherwise.
struct Video {
    child: Child,
    temp: PathBuf,
    dest: PathBuf,
    done: bool,
}

impl Sink {
    /// Starts ffmpeg.
    fn video(dest: &Path, w: usize, h: usize, fps: f64) -> Result<Sink, Failure> {
        let dir = match dest.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if !dir.is_dir() || dest.is_dir() {
            return Err(Failure::Input(anyhow!("{}: cannot write a video there", dest.display())));
        }
        let name = dest.file_stem().map_or("video".into(), |n| n.to_string_lossy().into_owned());
        let ext = dest.extension().map_or("mp4".into(), |e| e.to_string_lossy().into_owned());
        let temp = dir.join(format!(".{name}.{}.partial.{ext}", std::process::id()));
        let child = Command::new("ffmpeg")
            .args(["-hide_banner", "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24"])
            .args(["-s", &format!("{w}x{h}"), "-r", &format!("{fps}"), "-i", "-"])
            .args(["-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "18"])
            .arg(&temp)
            .stdin(Stdio::piped())
            .spawn()
            .map_err(|e| match e.kind() {
                std::io::ErrorKind::NotFound => Failure::Input(anyhow!(
                    "ffmpeg is not on the PATH: install it for --video, or write PNG frames with -o DIR"
                )),
                _ => Failure::Runtime(anyhow!("cannot start ffmpeg: {e}")),
            })?;
        Ok(Sink::Video(Video { child, temp, dest: dest.to_path_buf(), done: false }))
    }

    fn write(&mut self, f: usize, w: usize, h: usize, rgb: &[u8]) -> Result<(), Failure> {
        match self {
            Sink::Pngs(dir) => io::write_png_rgb8(&dir.join(format!("frame-{f:05}.png")), w as u32, h as u32, rgb, "")
                .map_err(|e| Failure::Runtime(e.into())),
            Sink::Video(v) => {
                let stdin = v.child.stdin.as_mut().ok_or_else(|| Failure::Runtime(anyhow!("ffmpeg has no input")))?;
                stdin.write_all(rgb).map_err(|e| Failure::Runtime(anyhow!("ffmpeg stopped reading frames: {e}")))
            }
        }
    }

    fn finish(self) -> Result<(), Failure> {
        match self {
            Sink::Pngs(_) => Ok(()),
            Sink::Video(mut v) => {
                drop(v.child.stdin.take());
                let status = v.child.wait().map_err(|e| Failure::Runtime(e.into()))?;
                if !status.success() {
                    return Err(Failure::Runtime(anyhow!("ffmpeg failed ({status}); no video written")));
                }
                std::fs::rename(&v.temp, &v.dest)
                    .map_err(|e| Failure::Runtime(anyhow!("{}: {e}", v.dest.display())))?;
                v.done = true;
                Ok(())
            }
        }
    }
}

impl Drop for Video {
    /// A video left unfinished (an error, Ctrl-C) stops its encoder and leaves no file.
    fn drop(&mut self) {
        if !self.done {
            let _ = self.child.kill();
            let _ = self.child.wait();
            let _ = std::fs::remove_file(&self.temp);
        }
    }
}
