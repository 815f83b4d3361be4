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
mod layer;
pub mod presets;
pub mod raw;
mod validate;

use std::path::{Path, PathBuf};

pub use build::layer_key;
pub use context::BitmapLoader;
pub use inputs::RenderInputs;
pub use layer::{COMMON_KEYS, DefaultValue, LAYER_KINDS, default_value, kind_keys, kind_list, uses_palette};
pub use raw::SceneFile;

use crate::compose::Stack;
use crate::field::ChannelSet;
use crate::gpu::Precision;
use crate::num::Decimal;
use crate::orbit::{Numbers, Scale};
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
/// The f64 engine needs the pixel spacing to be at least this many ulps of the largest
/// coordinate magnitude the orbits meet. Measured (`cargo run --release --example f64_loss`,
/// table in docs/engine-notes.md): at ~3700 ulps per pixel (zoom 1e10, 480 rows) the median NF error
/// is 7e-6; at ~370 (zoom 1e11) it is 1.5e-3 and a quarter of N values are wrong.
pub const F64_MIN_ULPS_PER_PIXEL: f64 = 1024.0;
/// `auto` chooses direct f64 only down to zoom 10^this; deeper it chooses perturbation,
/// whose deltas carry the pixel's offset with full relative precision, while a forced
/// `f64` stays available down to [`F64_MIN_ULPS_PER_PIXEL`] as a speed-for-accuracy trade.
/// Direct f64 rounds every step at the orbit's own scale, so its error relative to the
/// view grows with the zoom whatever the sample count. Measured with the deep-view fuzzer
/// (`cargo run --release --example deep_fuzz -- --min-depth 3 --max-depth 12 --seconds
/// 300 --seed 7 --kinds descent,misiurewicz,early-escape,julia,minibrot`): of 11863
/// generated views, direct f64 broke the accuracy bar (mostly NF p99 above 1e-4) on none of 4707
/// below zoom 1e5.5, on 1 of 958 between 1e5.5 and 1e6, on 6 of 815 from 1e6 to 1e6.5 and on
/// most views past 1e9; no perturbation configuration broke it anywhere.
pub const F64_AUTO_MAX_LOG10_ZOOM: f64 = 5.0;

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

/// How an engine iterates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EngineKind {
    /// Direct f64 iteration of every sample (SIMD kernels).
    Direct,
    /// Perturbation against an arbitrary-precision reference.
    Perturb {
        /// Delta number types.
        numbers: Numbers,
        /// BLA tolerance (None: no BLA).
        bla: Option<f64>,
    },
    /// Direct iteration on the GPU ([`crate::gpu`]) in the given precision.
    Gpu(Precision),
}

/// The engine that will run, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct EnginePlan {
    /// Short name ("f64", "perturb-f64", "perturb-floatexp", "gpu", "gpu-df").
    pub name: &'static str,
    /// How it iterates.
    pub kind: EngineKind,
    /// Why it was chosen.
    pub reason: String,
}

/// Sample spacings below 10^this put deltas too close to the f64 underflow for f64 deltas.
pub const PERTURB_F64_MIN_LOG10_SPACING: f64 = -290.0;
/// Why no engine (or not the forced one) can address a scene's view.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EngineError {
    /// `--engine f64` on a view too deep for it.
    #[error(
        "the view is too deep for the f64 engine: at zoom 1e{log10_zoom:.1} a sample spans only {ulps:.3e} f64 ulps of the coordinates (at least {F64_MIN_ULPS_PER_PIXEL} are needed); use --engine auto, perturb-f64 or perturb-floatexp"
    )]
    F64TooDeep {
        /// log10 of the zoom.
        log10_zoom: f64,
        /// f64 ulps per sample.
        ulps: f64,
    },
    /// `--engine perturb-f64` where f64 deltas underflow.
    #[error(
        "the view is too deep for perturbation with f64 deltas: the sample spacing 1e{log10_spacing:.1} is below 1e{min_log10_spacing}, where f64 deltas underflow; use --engine auto or perturb-floatexp"
    )]
    DeltasUnderflow {
        /// log10 of the sample spacing.
        log10_spacing: f64,
        /// The smallest spacing f64 deltas take.
        min_log10_spacing: f64,
    },
    /// A GPU engine cannot draw the scene's traps.
    #[error("--engine {engine}: {reason}; use --engine auto")]
    GpuTraps {
        /// The engine's name.
        engine: &'static str,
        /// What the GPU paths lack.
        reason: String,
    },
    /// The GPU paths draw unrotated, unstretched views only.
    #[error(
        "--engine {engine}: the GPU paths draw only flat views without rotation or stretch (view.rotate, view.stretch_amount, view.exponential_map); use --engine auto"
    )]
    GpuTransform {
        /// The engine's name.
        engine: &'static str,
    },
    /// A GPU engine's escape radius limit.
    #[error(
        "--engine {engine}: iteration.escape_radius = {escape_radius:e} is above the GPU's limit of 2^60 (|z|^2 must stay finite in f32)"
    )]
    GpuEscapeRadius {
        /// The engine's name.
        engine: &'static str,
        /// The scene's escape radius.
        escape_radius: f64,
    },
    /// A GPU engine on a view past the f64 range.
    #[error(
        "--engine {engine}: the view is too deep for direct iteration (zoom 1e{log10_zoom:.1} is past the f64 range); use --engine auto"
    )]
    GpuPastF64 {
        /// The engine's name.
        engine: &'static str,
        /// log10 of the zoom.
        log10_zoom: f64,
    },
    /// A GPU engine on a view deeper than its precision resolves.
    #[error(
        "--engine {engine}: the view is too deep for {precision}: at zoom 1e{log10_zoom:.1} neighbouring samples are {ulps:.2} rounding units apart (at least 1 is needed); use {better}"
    )]
    GpuPrecision {
        /// The engine's name.
        engine: &'static str,
        /// The precision's description.
        precision: &'static str,
        /// log10 of the zoom.
        log10_zoom: f64,
        /// Rounding units per sample.
        ulps: f64,
        /// What to use instead.
        better: &'static str,
    },
}

/// The same for Julia sets, whose rebased step is δ -> δ^2 with nothing added: δ^2 must
/// stay a normal f64 for deltas down to the sample spacing.
pub const PERTURB_F64_MIN_LOG10_SPACING_JULIA: f64 = -150.0;

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

    /// Chooses the engine for this view (or checks the forced one), and says why.
    pub fn engine(&self) -> Result<EnginePlan, EngineError> {
        self.engine_for(self.engine)
    }

    /// Like [`Scene::engine`] for a given choice.
    pub fn engine_for(&self, choice: EngineChoice) -> Result<EnginePlan, EngineError> {
        let ulps = self.ulps_per_sample();
        let depth = -self.log10_radius + 2f64.log10();
        let spacing = self.log10_spacing();
        let f64_ok = ulps >= F64_MIN_ULPS_PER_PIXEL;
        let f64_exact = f64_ok && depth <= F64_AUTO_MAX_LOG10_ZOOM;
        let min_spacing = match self.family {
            FamilySpec::Mandelbrot => PERTURB_F64_MIN_LOG10_SPACING,
            FamilySpec::Julia { .. } => PERTURB_F64_MIN_LOG10_SPACING_JULIA,
        };
        let deltas_ok = spacing > min_spacing;
        let bla = if self.traps.iter().all(|t| !t.observes_orbit()) { self.bla } else { None };
        let bla_note = match (self.bla, bla) {
            (Some(e), Some(_)) => format!("; BLA tolerance {e:e}"),
            (Some(_), None) => "; BLA off (traps must see every iteration)".into(),
            (None, _) => "; BLA off".into(),
        };
        let perturb = |numbers| EngineKind::Perturb { numbers, bla };
        match choice {
            EngineChoice::Auto if f64_exact => Ok(EnginePlan {
                name: "f64",
                kind: EngineKind::Direct,
                reason: format!(
                    "zoom 1e{depth:.1} (<= 1e{F64_AUTO_MAX_LOG10_ZOOM}): a sample spans {ulps:.3e} f64 ulps (>= {F64_MIN_ULPS_PER_PIXEL}), so direct f64 iteration is exact enough"
                ),
            }),
            EngineChoice::Auto if deltas_ok => Ok(EnginePlan {
                name: "perturb-f64",
                kind: perturb(Numbers::F64),
                reason: if f64_ok {
                    format!(
                        "zoom 1e{depth:.1} is past 1e{F64_AUTO_MAX_LOG10_ZOOM}, where direct f64's rounding starts to show in the smooth iteration (--engine f64 still renders it, faster and less exact), so perturbation with f64 deltas{bla_note}"
                    )
                } else {
                    format!(
                        "zoom 1e{depth:.1}: a sample spans only {ulps:.3e} f64 ulps (< {F64_MIN_ULPS_PER_PIXEL}), but the sample spacing 1e{spacing:.1} is inside the f64 range, so perturbation with f64 deltas{bla_note}"
                    )
                },
            }),
            EngineChoice::Auto => Ok(EnginePlan {
                name: "perturb-floatexp",
                kind: perturb(Numbers::FloatExp),
                reason: format!(
                    "zoom 1e{depth:.1}: the sample spacing 1e{spacing:.1} is below the f64-safe 1e{min_spacing}, so perturbation with FloatExp deltas (f64 once a delta grows past 2^-480){bla_note}"
                ),
            }),
            EngineChoice::F64 if f64_ok => Ok(EnginePlan {
                name: "f64",
                kind: EngineKind::Direct,
                reason: format!("forced; a sample spans {ulps:.3e} f64 ulps"),
            }),
            EngineChoice::F64 => Err(EngineError::F64TooDeep { log10_zoom: depth, ulps }),
            EngineChoice::PerturbF64 if deltas_ok => {
                Ok(EnginePlan { name: "perturb-f64", kind: perturb(Numbers::F64), reason: format!("forced{bla_note}") })
            }
            EngineChoice::PerturbF64 => {
                Err(EngineError::DeltasUnderflow { log10_spacing: spacing, min_log10_spacing: min_spacing })
            }
            EngineChoice::PerturbFloatExp => Ok(EnginePlan {
                name: "perturb-floatexp",
                kind: perturb(Numbers::FloatExp),
                reason: format!("forced{bla_note}"),
            }),
            EngineChoice::Gpu => self.gpu_plan(Precision::F32),
            EngineChoice::GpuDf => self.gpu_plan(Precision::DoubleFloat),
        }
    }

    /// The GPU engine in `precision`, or why it cannot address the scene: traps other than
    /// one bitmap trap, the stripe average, a rotated or stretched view, an escape radius past 2^60, a view past the f64
    /// range, or a view deeper than the precision resolves ([`Precision::exhausted`]).
    fn gpu_plan(&self, precision: Precision) -> Result<EnginePlan, EngineError> {
        let name = precision.name();
        crate::gpu::field::supported_trap(&self.traps)
            .map_err(|e| EngineError::GpuTraps { engine: name, reason: e.to_string() })?;
        if !self.transform.is_identity() || !self.projection.is_flat() {
            return Err(EngineError::GpuTransform { engine: name });
        }
        if self.escape_radius > crate::gpu::MAX_ESCAPE_RADIUS {
            return Err(EngineError::GpuEscapeRadius { engine: name, escape_radius: self.escape_radius });
        }
        let depth = -self.log10_radius + 2f64.log10();
        let spacing = 2.0 * self.radius / (self.height * self.aa) as f64;
        if !(self.radius.is_normal() && spacing.is_normal()) {
            return Err(EngineError::GpuPastF64 { engine: name, log10_zoom: depth });
        }
        let center = self.center_f64();
        let ulps = precision.ulps_per_sample(spacing, center);
        if precision.exhausted(spacing, center) {
            let better = match precision {
                Precision::F32 => "--engine gpu-df, f64 or auto",
                Precision::DoubleFloat => "--engine auto",
            };
            return Err(EngineError::GpuPrecision {
                engine: name,
                precision: precision.describe(),
                log10_zoom: depth,
                ulps,
                better,
            });
        }
        Ok(EnginePlan {
            name,
            kind: EngineKind::Gpu(precision),
            reason: if ulps >= crate::gpu::AGREEMENT_ULPS {
                format!("forced; a sample spans {ulps:.3e} {} rounding units", precision.describe())
            } else {
                format!(
                    "forced; a sample spans only {ulps:.3e} {} rounding units: below ~{} expect N to differ from exact \
                     arithmetic on more than 1% of pixels near the boundary",
                    precision.describe(),
                    crate::gpu::AGREEMENT_ULPS
                )
            },
        })
    }
}
