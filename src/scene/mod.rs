//! Scenes: what to render, from a TOML file, a PNG's metadata, or command-line flags.
//!
//! [`raw`] mirrors the file; `validate` turns it into a typed [`Scene`] and reports every
//! problem with the file, line and column of the offending value and what was expected
//! (`layer` validates each `[[layer]]`; both locate their errors through `context`).
//! The scene also decides which engine can address the view ([`Scene::engine`]).
//! `build` validates scenes built in code (errors name key paths) and changes one part of a
//! validated scene; `inputs` says what its planes depend on ([`RenderInputs`]).

mod build;
mod context;
mod inputs;
pub mod kfr;
mod kfr_formula;
mod kfr_hybrid;
mod layer;
pub mod presets;
pub mod raw;
mod validate;

use std::path::{Path, PathBuf};

pub use build::layer_key;
pub use context::{BitmapLoadError, BitmapLoader};
pub use inputs::RenderInputs;
pub use layer::{COMMON_KEYS, DefaultValue, LAYER_KINDS, default_value, kind_keys, kind_list, uses_palette};
pub use raw::SceneFile;

use crate::compose::Stack;
use crate::field::ChannelSet;
use crate::num::Decimal;
use crate::orbit::Scale;
use crate::source::SourceError;
use crate::trap::Trap;

/// Largest accepted max iteration count (2^32 - 2; 2^32 - 1 marks interior samples).
pub const MAX_ITER_LIMIT: u64 = u32::MAX as u64 - 1;
/// Largest accepted width or height in pixels.
pub const MAX_SIDE: i64 = 1 << 17;
/// Deepest accepted view, as a decimal exponent: zoom up to 1e100000000. A reference orbit
/// there takes 332 million bits per number (about 40 MB, each square seconds long), and much
/// deeper spacings (past 1e-600000000) leave the range of `FloatExp`'s 32-bit exponent.
pub const MAX_LOG10_ZOOM: f64 = 1e8;
/// Largest accepted magnitude of a centre or Julia parameter component, as a decimal
/// exponent (1e6).
pub const MAX_LOG10_COORDINATE: f64 = 6.0;
/// Largest accepted supersampling factor.
pub const MAX_AA: i64 = 16;
/// Largest accepted number of samples (width * height * aa^2).
pub const MAX_SAMPLES: u64 = 1 << 36;
/// The Mandelbrot form of the scene's formula or its Julia form, with Julia's parameter
/// kept exact.
#[derive(Debug, Clone, PartialEq)]
pub enum FamilySpec {
    /// z -> f(z) + c, c the pixel, z_0 = 0.
    Mandelbrot,
    /// z -> f(z) + c, z_0 the pixel.
    Julia {
        /// The parameter [re, im].
        c: [Decimal; 2],
    },
}

/// The engine the user requested (`render.engine`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EngineChoice {
    /// The cheapest engine that is exact enough for the view.
    Auto,
    /// Direct f64 iteration.
    F64,
    /// Perturbation with f64 deltas.
    PerturbF64,
    /// Perturbation with FloatExp deltas where f64 would underflow.
    PerturbFloatExp,
    /// Direct iteration on the GPU in f32 (never chosen by `auto`).
    Gpu,
    /// Direct iteration on the GPU in double-float, two f32s (never chosen by `auto`).
    GpuDf,
}

impl EngineChoice {
    /// Every accepted spelling, for messages.
    pub const NAMES: &'static str = "\"auto\", \"f64\", \"perturb-f64\", \"perturb-floatexp\", \"gpu\" or \"gpu-df\"";

    /// Parses an engine name.
    pub fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "auto" => EngineChoice::Auto,
            "f64" => EngineChoice::F64,
            "perturb-f64" => EngineChoice::PerturbF64,
            "perturb-floatexp" => EngineChoice::PerturbFloatExp,
            "gpu" => EngineChoice::Gpu,
            "gpu-df" => EngineChoice::GpuDf,
            _ => return None,
        })
    }
}

/// A validated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The scene as written, with overrides applied (serialised into outputs).
    pub file: SceneFile,
    /// Where it came from, for messages.
    pub origin: String,
    /// Folder that relative paths in the scene are resolved against.
    pub base_dir: PathBuf,
    /// Whether the pixel is the map's parameter (Mandelbrot form) or its start (Julia form).
    pub family: FamilySpec,
    /// The map: a family at a power, or a hybrid ([`crate::formula::Formula::default`] is z² + c).
    pub formula: crate::formula::Formula,
    /// View centre.
    pub center: [Decimal; 2],
    /// log10 of the view's half-height (works beyond the f64 range).
    pub log10_radius: f64,
    /// The half-height correctly rounded to f64 from the decimal written (zero or infinite
    /// outside the f64 range).
    pub radius: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Rotation and stretch of the view (`[view] rotate`, `stretch_angle`, `stretch_amount`).
    pub transform: crate::field::Transform,
    /// A flat image, or a strip of an exponential map (`[view] exponential_map`).
    pub projection: crate::field::Projection,
    /// Maximum iterations.
    pub max_iter: u32,
    /// Escape radius.
    pub escape_radius: f64,
    /// Supersampling factor.
    pub aa: u32,
    /// Requested engine.
    pub engine: EngineChoice,
    /// BLA tolerance for the perturbation engines (None: BLA off).
    pub bla: Option<f64>,
    /// Interior detection in the perturbation engines (`[render] interior_detection`:
    /// true, false, or absent for the default).
    pub interior_detection: crate::orbit::interior::Detection,
    /// The view's scale as written (exact, for deep engines).
    pub scale: Scale,
    /// Colouring layers.
    pub stack: Stack,
    /// Orbit traps the layers use.
    pub traps: Vec<Trap>,
    /// PNG bit depth.
    pub png_bits: u8,
    /// Channels for EXR output.
    pub channels: ChannelSet,
}

impl Scene {
    /// Parses scene text. `origin` names it in errors; `base_dir` resolves relative paths.
    pub fn parse_file(origin: &str, text: &str) -> Result<SceneFile, SourceError> {
        toml::from_str(text).map_err(|e| SourceError::from_toml(origin, text, &e))
    }

    /// Validates a scene file (possibly with command-line overrides written into it).
    /// `text` is the file's text, used to turn spans into lines and columns; `bitmaps`
    /// loads bitmap traps' images (the I/O layer's `load_bitmap`), its error quoted in the
    /// scene's.
    pub fn validate<E: Into<BitmapLoadError>>(
        file: SceneFile,
        origin: &str,
        text: &str,
        base_dir: &Path,
        bitmaps: impl Fn(&Path) -> Result<crate::trap::Bitmap, E>,
    ) -> Result<Scene, SourceError> {
        let load = |path: &Path| bitmaps(path).map_err(Into::into);
        validate::validate(file, origin, text, base_dir, &load)
    }

    /// The scene as TOML text (what PNG and EXR metadata carry).
    pub fn to_toml(&self) -> String {
        toml::to_string(&self.file).unwrap_or_default()
    }

    /// View half-height as an f64 (zero or infinite outside the f64 range).
    pub fn radius_f64(&self) -> f64 {
        self.radius
    }

    /// The centre rounded to f64.
    pub fn center_f64(&self) -> [f64; 2] {
        [self.center[0].to_f64(), self.center[1].to_f64()]
    }

    /// Distance between samples in the plane, as log10.
    pub fn log10_spacing(&self) -> f64 {
        self.log10_radius + 2f64.log10() - ((self.height * self.aa) as f64).log10()
    }

    /// f64 ulps of the orbit's coordinates per sample: how well direct f64 iteration
    /// resolves the view.
    pub fn ulps_per_sample(&self) -> f64 {
        // The orbits meet values of magnitude up to ~2 whatever the view; the centre and
        // the Julia parameter may be larger.
        let mut magnitude = 1.0f64.log10();
        for d in self.center.iter().chain(match &self.family {
            FamilySpec::Julia { c } => c.iter(),
            FamilySpec::Mandelbrot => [].iter(),
        }) {
            magnitude = magnitude.max(d.log10_abs());
        }
        let ulp_log10 = magnitude - 52.0 * 2f64.log10();
        10f64.powf(self.log10_spacing() - ulp_log10)
    }
}
