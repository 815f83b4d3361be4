//! Flags as typed by the user: parsed and checked, no I/O.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use deepfield::field::{Channel, ChannelSet};
use deepfield::num::Decimal;

/// Escape-time and distance-estimate renderer for the Mandelbrot and Julia sets.
#[derive(Debug, Parser)]
#[command(name = "deepfield", version, about, propagate_version = true)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render a scene to PNG (and optionally its raw data to EXR).
    Render(Box<RenderArgs>),
    /// Render a scene with every engine that can address it and measure each against a
    /// direct big-float ground truth on a sample of pixels.
    Compare(Box<CompareArgs>),
    /// Recolour raw data (an EXR written by `render --exr`) without recomputing the fractal.
    Recolor(Box<RecolorArgs>),
    /// Lay the same raw data out in a grid, one labelled cell per colouring or palette.
    Sheet(Box<SheetArgs>),
    /// List, preview and import palettes.
    Palettes(PalettesArgs),
    /// List the formula families, their powers, Kalles Fraktaler type numbers and maps.
    Formulas,
    /// Explore interactively (egui window; wgpu renderer).
    View(ViewArgs),
    /// Search a view for the lowest-period minibrot (or the simplest Misiurewicz point) and
    /// print it as a scene framed on it, centre in full precision.
    Find(Box<FindArgs>),
    /// Join the work units of `render --tile K/N` into the whole PNG (streamed, one row in
    /// memory at a time), or their raw data into the whole EXR.
    Assemble(AssembleArgs),
    /// Compute a deep view's reference orbit(s) once and write them to a file that
    /// `render --reference` reads (work units, frames of a zoom: no recomputing).
    Reference(Box<ReferenceArgs>),
    /// Write a zoom-out sequence of EXR keyframes (00000.exr outermost .. the scene's view),
    /// each a factor shallower than the next, from the deepest frame's one reference orbit.
    Zoom(Box<ZoomArgs>),
    /// Turn the keyframes of `deepfield zoom` into the frames of a zoom video: coloured by
    /// the scene's layers, resampled between keyframes, written as PNG or piped to ffmpeg.
    Frames(Box<FramesArgs>),
}

/// `deepfield frames`.
#[derive(Debug, Args)]
pub struct FramesArgs {
    /// Folder of keyframes written by `deepfield zoom` (00000.exr the outermost).
    #[arg(value_name = "DIR")]
    pub keyframes: PathBuf,
    /// Frames per second.
    #[arg(long, value_name = "F", default_value_t = 30.0)]
    pub fps: f64,
    /// Length of the video in seconds (default: one second per keyframe step).
    #[arg(long, value_name = "S")]
    pub seconds: Option<f64>,
    /// Frame size (default: the keyframes' size; the aspect ratio must be theirs).
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Zoom out from the deepest keyframe instead of in towards it.
    #[arg(long)]
    pub zoom_out: bool,
    /// Colour with this scene's layers (default: the scene stored in each keyframe).
    #[arg(long, value_name = "SCENE")]
    pub scene: Option<PathBuf>,
    /// Palette for every layer that uses one: a built-in name or a palette file.
    #[arg(long, value_name = "NAME|FILE")]
    pub palette: Option<String>,
    /// Replace the layers: KIND[:key=value,...] (repeat for a stack, bottom first).
    #[arg(long = "layer", value_name = "SPEC")]
    pub layers: Vec<String>,
    /// Only frames A..B (0-based, B excluded): one work unit of the video.
    #[arg(long, value_name = "A..B", value_parser = parse_units)]
    pub units: Option<(u32, u32)>,
    /// Folder for the frames as PNG (frame-00000.png, ...; created if missing).
    #[arg(short, long, value_name = "DIR", required_unless_present = "video")]
    pub output: Option<PathBuf>,
    /// Encode the frames into this video with ffmpeg (H.264, yuv420p), which must be on
    /// the PATH; the file appears only when ffmpeg has finished.
    #[arg(long, value_name = "FILE")]
    pub video: Option<PathBuf>,
    /// Worker threads (default: one per core). Output does not depend on it.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// No line per frame.
    #[arg(short, long)]
    pub quiet: bool,
}

/// `deepfield zoom`.
#[derive(Debug, Args)]
pub struct ZoomArgs {
    /// The deepest view and flags that override it.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Number of keyframes.
    #[arg(long, value_name = "N", conflicts_with = "to_zoom")]
    pub frames: Option<u32>,
    /// Or: keyframes out to this zoom (the outermost is at most this deep).
    #[arg(long, value_name = "Z")]
    pub to_zoom: Option<String>,
    /// Zoom factor between keyframes (a decimal, taken exactly; default 2). With
    /// `--exponential-map F` the keyframes are the strips of an exponential map instead,
    /// one per factor F: rings from each keyframe's circumscribed circle inwards, sized for
    /// video frames of the scene's size and supersampling, plus `center.exr`, the flat view
    /// inside the deepest ring.
    #[arg(long, value_name = "F", value_parser = parse_decimal)]
    pub factor: Option<String>,
    /// Only keyframes A..B (0-based, B excluded): one work unit of the sequence.
    #[arg(long, value_name = "A..B", value_parser = parse_units)]
    pub units: Option<(u32, u32)>,
    /// Read the deepest frame's reference orbit(s) from FILE instead of computing them.
    #[arg(long, value_name = "FILE")]
    pub reference: Option<PathBuf>,
    /// Folder for the keyframes (created if missing).
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,
    /// Vector instruction set (output does not depend on it).
    #[arg(long, value_name = "LEVEL", value_parser = deepfield::simd_level::CHOICES)]
    pub simd: Option<String>,
    /// Print the time of the reference and of the frames.
    #[arg(long)]
    pub stats: bool,
    /// No line per keyframe.
    #[arg(short, long)]
    pub quiet: bool,
}

fn parse_units(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("`{s}` is not A..B (keyframe indices, B excluded), like 0..25");
    let (a, b) = s.split_once("..").ok_or_else(bad)?;
    Ok((a.trim().parse().map_err(|_| bad())?, b.trim().parse().map_err(|_| bad())?))
}

/// `deepfield reference`.
#[derive(Debug, Args)]
pub struct ReferenceArgs {
    /// The scene and flags that override it.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The reference file to write.
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// Store at most N iterations densely and pack the rest, as `render --dense-orbit`
    /// does (default: all of them up to 2^25, else 2^20).
    #[arg(long, value_name = "N")]
    pub dense_orbit: Option<u32>,
    /// Vector instruction set (the orbit's bits do not depend on it).
    #[arg(long, value_name = "LEVEL", value_parser = deepfield::simd_level::CHOICES)]
    pub simd: Option<String>,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
}

/// `deepfield assemble`.
#[derive(Debug, Args)]
pub struct AssembleArgs {
    /// The units' PNG files, or their EXR files (`render --tile K/N --exr`), in any order
    /// (all N of them).
    #[arg(value_name = "UNIT", required = true)]
    pub units: Vec<PathBuf>,
    /// The whole image: a PNG, or with a `.exr` name the whole raw data (recolour it for
    /// layers that colour from the whole image, like histogram equalisation).
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
}

/// `deepfield find`.
#[derive(Debug, Args)]
pub struct FindArgs {
    /// The view to search (a scene and flags that override it: --center, --zoom).
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Find a Misiurewicz point (preperiod and period) instead of a minibrot.
    #[arg(long)]
    pub misiurewicz: bool,
    /// Largest period searched (default: 100000 for minibrots; for Misiurewicz points the
    /// view's lowest minibrot period, between 64 and 4096).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=100_000_000))]
    pub max_period: Option<u32>,
    /// Largest preperiod searched (Misiurewicz points; default: twice the view's lowest
    /// minibrot period, between 5000 and 8192).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub max_preperiod: Option<u32>,
    /// Write the scene here instead of printing it.
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `deepfield view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// Scene to open: TOML, .kfr, or a PNG/EXR written by deepfield (default: the last
    /// session's scene, or the whole Mandelbrot set).
    #[arg(value_name = "SCENE")]
    pub scene: Option<PathBuf>,
    /// Once the render is complete, save a screenshot of the whole window here and exit.
    #[arg(long, value_name = "FILE")]
    pub screenshot: Option<PathBuf>,
    /// Window size (inner, in points).
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Read the scene's reference orbit(s) from FILE (written by `deepfield reference`)
    /// instead of computing them; refused with the reason when it does not serve the scene.
    /// Views navigated to later use it where it still serves (same centre, no deeper).
    #[arg(long, value_name = "FILE", requires = "scene")]
    pub reference: Option<PathBuf>,
}

/// `deepfield recolor`.
#[derive(Debug, Args)]
pub struct RecolorArgs {
    /// Raw data: an OpenEXR file written by `deepfield render --exr`.
    #[arg(value_name = "DATA.exr")]
    pub data: PathBuf,
    /// Colour with this scene's layers (default: the scene stored in the EXR).
    #[arg(long, value_name = "SCENE")]
    pub scene: Option<PathBuf>,
    /// Palette for every layer that uses one: a built-in name or a palette file.
    #[arg(long, value_name = "NAME|FILE")]
    pub palette: Option<String>,
    /// Replace the layers: KIND[:key=value,...] (repeat for a stack, bottom first), e.g.
    /// `--layer smooth:palette=fire,density=0.02 --layer slope:blend=multiply`.
    #[arg(long = "layer", value_name = "SPEC")]
    pub layers: Vec<String>,
    /// Palette cycling: shift every palette by this many cycles.
    #[arg(long, value_name = "CYCLES", allow_hyphen_values = true)]
    pub cycle: Option<f64>,
    /// Output PNG (default: the data file's name with .png).
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// PNG bits per channel.
    #[arg(long, value_parser = ["8", "16"])]
    pub bits: Option<String>,
    /// Worker threads (default: one per core). Output does not depend on it.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Vector instruction set of the colouring's arithmetic (output does not depend on it).
    #[arg(long, value_name = "LEVEL", value_parser = deepfield::simd_level::CHOICES)]
    pub simd: Option<String>,
    /// Print the time spent reading, colouring and writing.
    #[arg(long)]
    pub stats: bool,
}

/// `deepfield sheet`.
#[derive(Debug, Args)]
pub struct SheetArgs {
    /// The scene and flags that override it.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Colourings, one cell each (see `deepfield sheet --list`); `scene` is the scene's own layers.
    #[arg(long, value_name = "A,B,...", value_delimiter = ',')]
    pub colorings: Vec<String>,
    /// Palettes, one cell each, applied to the scene's layers (or to each colouring).
    #[arg(long, value_name = "A,B,...", value_delimiter = ',')]
    pub palettes: Vec<String>,
    /// Cells per row (default: about square).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=64))]
    pub columns: Option<u32>,
    /// Output PNG (default: the scene's name with -sheet.png).
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Draw a scale bar with the length it spans in the complex plane.
    #[arg(long)]
    pub scale_bar: bool,
    /// Mark a point of the plane: RE,IM, or `c` for a Julia scene's parameter.
    #[arg(long, value_name = "RE,IM|c", allow_hyphen_values = true)]
    pub marker: Option<String>,
    /// List the colourings a sheet can show, and exit.
    #[arg(long)]
    pub list: bool,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Vector instruction set of the CPU kernels: auto (the widest this CPU has), scalar,
    /// avx2, avx512 or neon; refused where the CPU lacks it. Output does not depend on it.
    #[arg(long, value_name = "LEVEL", value_parser = deepfield::simd_level::CHOICES)]
    pub simd: Option<String>,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
}

/// `deepfield palettes`.
#[derive(Debug, Args)]
pub struct PalettesArgs {
    /// What to do.
    #[command(subcommand)]
    pub action: PalettesAction,
}

/// `deepfield palettes` subcommands.
#[derive(Debug, Subcommand)]
pub enum PalettesAction {
    /// List the built-in palettes.
    List,
    /// Write a preview strip of a palette (built-in name or file) as PNG.
    Show {
        /// Palette name or file (.toml, or any format `import` reads); omit with --all.
        #[arg(value_name = "NAME|FILE", required_unless_present = "all")]
        name: Option<String>,
        /// Every built-in palette, one labelled strip each.
        #[arg(long, conflicts_with = "name")]
        all: bool,
        /// Output PNG (default: NAME.png).
        #[arg(short, long, value_name = "FILE")]
        output: Option<PathBuf>,
        /// Strip size in pixels.
        #[arg(long, value_name = "WxH", value_parser = parse_size, default_value = "512x48")]
        size: (u32, u32),
    },
    /// Convert a palette file (.map, .ggr, .ugr, .kfp/.kfr, .cpt) to deepfield's TOML format.
    Import {
        /// The file to convert.
        #[arg(value_name = "FILE")]
        file: PathBuf,
        /// Output .toml file, or a folder (one file per palette; a .ugr holds several).
        /// Default: print to standard output.
        #[arg(short, long, value_name = "PATH")]
        output: Option<PathBuf>,
    },
}

/// `deepfield render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// The scene and flags that override it.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output PNG (default: the scene's name with .png, in the current folder).
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Also write the raw per-pixel data as OpenEXR (channels: see --channels).
    #[arg(long, value_name = "FILE")]
    pub exr: Option<PathBuf>,
    /// Render only work unit K of N (0-based): rows K·H/N .. (K+1)·H/N, as a PNG that
    /// `deepfield assemble` joins with the others into the whole image, byte for byte (and
    /// with --exr its raw data, which assemble joins into the whole EXR).
    #[arg(long, value_name = "K/N", value_parser = parse_tile)]
    pub tile: Option<(u32, u32)>,
    /// Read the reference orbit(s) from FILE (written by `deepfield reference`) instead of
    /// computing them; refused, with the reason, when the file does not serve the scene.
    #[arg(long, value_name = "FILE")]
    pub reference: Option<PathBuf>,
    /// Worker threads (default: one per core). Output does not depend on it.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Vector instruction set of the CPU kernels: auto (the widest this CPU has), scalar,
    /// avx2, avx512 or neon; refused where the CPU lacks it. Output does not depend on it.
    #[arg(long, value_name = "LEVEL", value_parser = deepfield::simd_level::CHOICES)]
    pub simd: Option<String>,
    /// Store at most N reference iterations densely (16 bytes each, with BLA tables) and
    /// the rest packed (1.0–1.4 bytes each, single steps). Default: all of them up to 2^25,
    /// else 2^20 (at least 1). The values are the same either way. With --reference the
    /// file's split is used.
    #[arg(long, value_name = "N")]
    pub dense_orbit: Option<u32>,
    /// Print engine, precision, pixels, iterations, time and speed when done.
    #[arg(long)]
    pub stats: bool,
    /// Write the same statistics as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    pub stats_json: Option<PathBuf>,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
}

/// A scene and the flags that build or override it (shared by `render` and `compare`).
#[derive(Debug, Args)]
pub struct SceneArgs {
    /// Scene: a TOML scene file, a Kalles Fraktaler .kfr location, or a PNG written by deepfield
    /// (its embedded scene).
    /// Without one, flags alone describe the scene (default: the whole Mandelbrot set).
    #[arg(value_name = "SCENE")]
    pub path: Option<PathBuf>,
    /// Formula: a family (mandelbrot, burning-ship, buffalo, celtic, mandelbar,
    /// perpendicular-burning-ship, ...), NAME^P for its
    /// power, a hybrid (phases joined by `,`: burning-ship,mandelbrot^3), or julia (z^2 + c's
    /// Julia set; needs --julia-c). `deepfield formulas` lists the families.
    #[arg(long, value_name = "NAME")]
    pub formula: Option<String>,
    /// The power of a single family (2 to 10 for mandelbrot, 2 to 5 for burning-ship,
    /// buffalo, celtic and mandelbar).
    #[arg(long, value_name = "P")]
    pub power: Option<u32>,
    /// Julia parameter c, as RE,IM (decimal strings): the formula's Julia form (z_0 the
    /// pixel, c fixed).
    #[arg(long, value_name = "RE,IM", value_parser = parse_pair, allow_hyphen_values = true)]
    pub julia_c: Option<[String; 2]>,
    /// The coefficient a of the families that take one (redshift-rider-*: a z² ± z^p + c),
    /// as RE,IM (default 1,0, as in Kalles Fraktaler).
    #[arg(long, value_name = "RE,IM", value_parser = parse_coefficient, allow_hyphen_values = true)]
    pub formula_a: Option<[f64; 2]>,
    /// View centre, as RE,IM (decimal strings, any precision).
    #[arg(long, value_name = "RE,IM", value_parser = parse_pair, allow_hyphen_values = true)]
    pub center: Option<[String; 2]>,
    /// Zoom: the image height spans 4/ZOOM of the plane.
    #[arg(long, value_name = "Z", value_parser = parse_decimal, conflicts_with = "radius")]
    pub zoom: Option<String>,
    /// Half the image height in the plane (= 2/zoom).
    #[arg(long, value_name = "R", value_parser = parse_decimal)]
    pub radius: Option<String>,
    /// Image size in pixels, WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Turn the picture counter-clockwise by DEG degrees (view.rotate).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub rotate: Option<f64>,
    /// Stretch the view: the plane is covered 2^AMOUNT times faster along ANGLE degrees than
    /// across it (view.stretch_amount, view.stretch_angle; ANGLE defaults to 0).
    #[arg(long, value_name = "AMOUNT[@ANGLE]", value_parser = parse_stretch, allow_hyphen_values = true)]
    pub stretch: Option<(f64, f64)>,
    /// Render a strip of an exponential map instead of a flat image: columns go round the
    /// centre, rows from the view's radius inwards to radius / F (view.exponential_map).
    #[arg(long, value_name = "F")]
    pub exponential_map: Option<f64>,
    /// Maximum iterations (1 ..= 4294967294).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=u32::MAX as u64 - 1))]
    pub max_iter: Option<u64>,
    /// Escape radius (>= 2).
    #[arg(long, value_name = "R", value_parser = parse_escape)]
    pub escape_radius: Option<f64>,
    /// Supersampling: N x N samples per pixel, averaged in linear light (1 ..= 16).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=16))]
    pub aa: Option<u64>,
    /// Engine: auto picks the cheapest exact enough for the view (f64 direct, then
    /// perturbation with f64 deltas, then with FloatExp deltas); the others force one:
    /// f64, perturb-f64, perturb-floatexp, or the GPU (never picked by auto; any Vulkan,
    /// Metal, DX12 or GL adapter, lavapipe will do): gpu (f32) or gpu-df (double-float),
    /// refused where neighbouring pixels stop being distinct numbers (zoom ~3e4 and ~3e11
    /// at 1080 rows) and close to exact to about zoom 50 and 5e8.
    #[arg(long, value_parser = ["auto", "f64", "perturb-f64", "perturb-floatexp", "gpu", "gpu-df"])]
    pub engine: Option<String>,
    /// Turn off bilinear approximation in the perturbation engines.
    #[arg(long)]
    pub no_bla: bool,
    /// BLA tolerance ε (relative size of the dropped term per step; default 1e-14).
    #[arg(long, value_name = "EPS", value_parser = parse_tolerance)]
    pub bla_tolerance: Option<f64>,
    /// Interior detection in the perturbation engines: stop samples whose orbit contracts
    /// onto an attracting cycle (render.interior_detection). auto (the default): where the
    /// view's centre is interior; on; off (samples inside a minibrot run to the limit).
    #[arg(long, value_name = "WHEN", value_parser = ["auto", "on", "off"])]
    pub interior_detection: Option<String>,
    /// Palette for every layer that uses one: a built-in name or a palette file.
    #[arg(long, value_name = "NAME|FILE")]
    pub palette: Option<String>,
    /// Palette cycling: shift every palette by this many cycles (frames of an animation).
    #[arg(long, value_name = "CYCLES", allow_hyphen_values = true)]
    pub cycle: Option<f64>,
    /// EXR channels, comma-separated: N, NF, T, DEX, DEY, TRAPS (default N,NF,T,DEX,DEY).
    #[arg(long, value_name = "LIST", value_parser = parse_channels)]
    pub channels: Option<ChannelSet>,
    /// PNG bits per channel.
    #[arg(long, value_parser = ["8", "16"])]
    pub bits: Option<String>,
}

/// `deepfield compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// The scene and flags that override it.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Pixels compared against the big-float ground truth (a deterministic random sample).
    #[arg(long, value_name = "N", default_value_t = 200, value_parser = clap::value_parser!(u32).range(1..=100000))]
    pub samples: u32,
    /// Render only these sampled pixels with each engine instead of the whole image.
    #[arg(long)]
    pub sample_only: bool,
    /// Run only the engines whose row name contains one of these comma-separated strings
    /// (e.g. `bla` leaves out the slow engines without BLA at depth)
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub only: Vec<String>,
    /// Also score another program's raw data, NAME=FILE: an EXR with one sample per pixel of
    /// this view (top row first) holding N as a u32 (its IterationsBias attribute taken off;
    /// u32::MAX where the sample did not escape) and NF, as Fraktaler-3, fractall-rust and
    /// Kalles Fraktaler write them. Read at the same sampled pixels as the engines; its row
    /// has no time and no distance errors. Repeatable
    #[arg(long, value_name = "NAME=FILE")]
    pub peer: Vec<String>,
    /// Also write one CSV line per sampled pixel to FILE: position, the truth's N and NF
    /// (and whether N is ill-conditioned), and every engine's N and NF
    #[arg(long, value_name = "FILE")]
    pub pixels: Option<std::path::PathBuf>,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Vector instruction set of the CPU kernels: auto (the widest this CPU has), scalar,
    /// avx2, avx512 or neon; refused where the CPU lacks it. Output does not depend on it.
    #[arg(long, value_name = "LEVEL", value_parser = deepfield::simd_level::CHOICES)]
    pub simd: Option<String>,
    /// Print the rows as JSON.
    #[arg(long, conflicts_with = "csv")]
    pub json: bool,
    /// Print the rows as CSV.
    #[arg(long)]
    pub csv: bool,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
}

fn parse_tile(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("`{s}` is not K/N with 0 <= K < N (a work unit and the number of units), like 3/8");
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let (k, n): (u32, u32) = (k.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
    if k >= n {
        return Err(bad());
    }
    Ok((k, n))
}

fn parse_decimal(s: &str) -> Result<String, String> {
    Decimal::parse(s).map(|d| d.text().to_string()).map_err(|e| e.to_string())
}

fn parse_pair(s: &str) -> Result<[String; 2], String> {
    let (re, im) = s.split_once(',').ok_or_else(|| format!("`{s}` is not RE,IM (two numbers separated by a comma)"))?;
    Ok([parse_decimal(re)?, parse_decimal(im)?])
}

fn parse_coefficient(s: &str) -> Result<[f64; 2], String> {
    let bad = || format!("`{s}` is not RE,IM (two finite numbers separated by a comma)");
    let (re, im) = s.split_once(',').ok_or_else(bad)?;
    let re: f64 = re.trim().parse().map_err(|_| bad())?;
    let im: f64 = im.trim().parse().map_err(|_| bad())?;
    if re.is_finite() && im.is_finite() { Ok([re, im]) } else { Err(bad()) }
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("`{s}` is not WIDTHxHEIGHT with both between 1 and {}", deepfield::scene::MAX_SIDE);
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    let max = deepfield::scene::MAX_SIDE as u32;
    if w == 0 || h == 0 || w > max || h > max {
        return Err(bad());
    }
    Ok((w, h))
}

fn parse_stretch(s: &str) -> Result<(f64, f64), String> {
    let bad = || format!("`{s}` is not AMOUNT or AMOUNT@ANGLE (log2 of the stretch factor, and degrees)");
    let (amount, angle) = s.split_once('@').unwrap_or((s, "0"));
    let amount: f64 = amount.trim().parse().map_err(|_| bad())?;
    let angle: f64 = angle.trim().parse().map_err(|_| bad())?;
    Ok((amount, angle))
}

fn parse_escape(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(r) if r.is_finite() && (2.0..=1e150).contains(&r) => Ok(r),
        _ => Err(format!("`{s}` is not an escape radius between 2 and 1e150")),
    }
}

fn parse_tolerance(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(t) if t.is_finite() && (1e-300..=0.1).contains(&t) => Ok(t),
        _ => Err(format!("`{s}` is not a BLA tolerance between 1e-300 and 0.1")),
    }
}

fn parse_channels(s: &str) -> Result<ChannelSet, String> {
    s.split(',').filter(|p| !p.trim().is_empty()).map(|p| p.parse::<Channel>().map_err(|e| e.to_string())).collect()
}
