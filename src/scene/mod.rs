//! Scenes: what to render, from a TOML file, a PNG's metadata, or command-line flags.
//!
//! [`raw`] mirrors the file; [`validate`] turns it into a typed [`Scene`] and reports every
//! problem with the file, line and column of the offending value and what was expected.
//! The scene also decides which engine can address the view ([`Scene::engine`]).

pub mod raw;
mod validate;

use std::path::{Path, PathBuf};

pub use raw::SceneFile;
pub use validate::BitmapLoader;

use crate::compose::Stack;
use crate::field::ChannelSet;
use crate::num::Decimal;
use crate::source::SourceError;
use crate::trap::Trap;

/// Largest accepted max iteration count (2^32 - 2; 2^32 - 1 marks interior samples).
pub const MAX_ITER_LIMIT: u64 = u32::MAX as u64 - 1;
/// Largest accepted width or height in pixels.
pub const MAX_SIDE: i64 = 1 << 17;
/// Largest accepted supersampling factor.
pub const MAX_AA: i64 = 16;
/// Largest accepted number of samples (width * height * aa^2).
pub const MAX_SAMPLES: u64 = 1 << 36;
/// The f64 engine needs the pixel spacing to be at least this many ulps of the largest
/// coordinate magnitude the orbits meet. Measured (`cargo run --release --example f64_loss`,
/// table in the README): at ~3700 ulps per pixel (zoom 1e10, 480 rows) the median NF error
/// is 7e-6; at ~370 (zoom 1e11) it is 1.5e-3 and a quarter of N values are wrong.
pub const F64_MIN_ULPS_PER_PIXEL: f64 = 1024.0;

/// Mandelbrot or Julia, with Julia's parameter kept exact.
#[derive(Debug, Clone, PartialEq)]
pub enum FamilySpec {
    /// z -> z^2 + c, c the pixel.
    Mandelbrot,
    /// z -> z^2 + c, z_0 the pixel.
    Julia {
        /// The parameter [re, im].
        c: [Decimal; 2],
    },
}

/// The engine the user asked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EngineChoice {
    /// The cheapest engine that is exact enough for the view.
    Auto,
    /// Direct f64 iteration.
    F64,
}

/// The engine that will run, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct EnginePlan {
    /// Short name ("f64").
    pub name: &'static str,
    /// Why it was chosen.
    pub reason: String,
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
    /// The map.
    pub family: FamilySpec,
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
    /// Maximum iterations.
    pub max_iter: u32,
    /// Escape radius.
    pub escape_radius: f64,
    /// Supersampling factor.
    pub aa: u32,
    /// Requested engine.
    pub engine: EngineChoice,
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
    /// `text` is the file's text, used to turn spans into lines and columns.
    pub fn validate(
        file: SceneFile,
        origin: &str,
        text: &str,
        base_dir: &Path,
        bitmaps: &BitmapLoader<'_>,
    ) -> Result<Scene, SourceError> {
        validate::validate(file, origin, text, base_dir, bitmaps)
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

    /// Chooses the engine for this view, or explains why none available can render it.
    pub fn engine(&self) -> Result<EnginePlan, String> {
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
        let ulps_per_pixel = 10f64.powf(self.log10_spacing() - ulp_log10);
        let depth = -self.log10_radius + 2f64.log10();
        if ulps_per_pixel >= F64_MIN_ULPS_PER_PIXEL {
            let reason = format!(
                "zoom 1e{depth:.1}: a pixel spans {ulps_per_pixel:.3e} f64 ulps (>= {F64_MIN_ULPS_PER_PIXEL}), so direct f64 iteration is exact enough",
            );
            Ok(EnginePlan { name: "f64", reason })
        } else {
            Err(format!(
                "the view is too deep for f64: at zoom 1e{depth:.1} a pixel spans only {ulps_per_pixel:.3e} f64 ulps of the coordinates \
                 (at least {F64_MIN_ULPS_PER_PIXEL} are needed); rendering it needs the perturbation engine, which this build does not have yet"
            ))
        }
    }
}
